"""The project's loggers: one root, a child per module, a NullHandler and nothing else."""

from __future__ import annotations

import logging
import subprocess
import sys

import pytest

from analytic.runtime.log import ROOT, get_logger


def test_every_module_logs_under_the_one_root():
    assert (
        get_logger("validation.studies.sweep.study").name
        == f"{ROOT}.validation.studies.sweep.study"
    )
    assert get_logger(ROOT).name == ROOT
    assert get_logger(f"{ROOT}.x").name == f"{ROOT}.x"


@pytest.mark.parametrize("name", ["", ".", None, 3])
def test_a_bad_name_is_refused_naming_it(name):
    with pytest.raises(ValueError, match="name"):
        get_logger(name)


def test_the_library_adds_only_a_null_handler():
    handlers = logging.getLogger(ROOT).handlers
    assert any(isinstance(h, logging.NullHandler) for h in handlers)


def test_a_program_that_configures_nothing_sees_no_message():
    """Not even Python's last-resort output of a warning (the NullHandler)."""
    code = (
        "from analytic.runtime.log import get_logger\n"
        "get_logger('x').warning('careful')\n"
        "get_logger('x').info('notice')\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and proc.stderr == ""


def test_a_program_that_configures_logging_gets_the_messages():
    code = (
        "import logging\n"
        "logging.basicConfig(level=logging.INFO, format='%(name)s %(levelname)s %(message)s')\n"
        "from analytic.runtime.log import get_logger\n"
        "get_logger('validation.x').info('notice')\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.stderr.strip() == f"{ROOT}.validation.x INFO notice"
