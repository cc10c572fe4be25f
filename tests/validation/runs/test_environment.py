"""The package changes nothing in other people's processes: the pytest plugin, loaded in every
pytest session of an environment that has the package, leaves the environment variables and the
BLAS thread pools of an unrelated test suite as they were, with or without a scene file in the
session; ``import validation`` leaves ``os.environ`` as it was. (The ``tumble`` program sets its
own: :mod:`validation.runs.environment`.)"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.validation.testing.test_pytest_plugin import short_scene

VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "NO_COLOR")

PROBE = """
import json, os
import numpy, scipy.linalg, threadpoolctl

def probe():
    return {
        "env": {v: os.environ.get(v) for v in VARS},
        "blas": sorted(
            (i["internal_api"], i["num_threads"])
            for i in threadpoolctl.threadpool_info()
            if i["user_api"] == "blas"
        ),
    }
"""


def _clean_env(monkeypatch: pytest.MonkeyPatch) -> None:
    """None of :data:`VARS` set (the test session's conftest sets them for itself)."""
    for var in VARS:
        monkeypatch.delenv(var, raising=False)


def _reference() -> dict:
    """What a plain interpreter without the package reports (the original thread counts)."""
    code = f"VARS = {VARS!r}\n{PROBE}\nprint(json.dumps(probe()))"
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    return json.loads(out.stdout)


def _unrelated_suite(pytester: pytest.Pytester, out: Path) -> None:
    pytester.makepyfile(
        test_z_unrelated=f"VARS = {VARS!r}\n{PROBE}\n"
        "import json\n"
        "def test_numbers(request):\n"
        "    got = probe()\n"
        "    got['plugin'] = request.config.pluginmanager.hasplugin('tumble')\n"
        "    from validation.testing import pytest_plugin\n"
        "    got['runs'] = len(pytest_plugin.RUNS)\n"
        f"    open({str(out)!r}, 'w').write(json.dumps(got))\n"
    )


@pytest.mark.parametrize(
    "with_scene",
    [False, pytest.param(True, marks=pytest.mark.slow)],  # a scene run in a fresh session: ~40 s
    ids=["no_scene", "after_a_scene"],
)
def test_an_unrelated_suite_keeps_its_environment_and_blas_threads(
    pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch, tmp_path: Path, with_scene: bool
) -> None:
    """An unrelated numerical test in a session with the plugin loaded sees none of the BLAS
    variables nor NO_COLOR set and its BLAS libraries on their original thread counts, also
    when a scene file of the session ran before it (the run's limit is given back)."""
    _clean_env(monkeypatch)
    expected = _reference()
    out = tmp_path / "seen.json"
    _unrelated_suite(pytester, out)
    if with_scene:
        pytester.makefile(".toml", test_a_scene=short_scene())
    r = pytester.runpytest_subprocess(
        "-p", "tumble", "--tumble-plants", "analytic,mujoco", "-p", "no:cacheprovider"
    )
    assert r.ret == 0, r.stdout.str()[-3000:]
    got = json.loads(out.read_text())
    assert got["plugin"]
    assert got["runs"] == (1 if with_scene else 0)
    assert got["env"] == {v: None for v in VARS}
    assert got["blas"] == [list(x) for x in expected["blas"]]


def test_import_validation_leaves_the_environment_unchanged(monkeypatch) -> None:
    """``import validation`` (and its public names, numpy with them, and the plugin module) in a
    fresh interpreter: os.environ is what it was."""
    _clean_env(monkeypatch)
    code = (
        "import json, os\n"
        "before = dict(os.environ)\n"
        "import validation, validation.testing.pytest_plugin\n"
        "validation.resolve_scene, validation.run_validation\n"
        "print(json.dumps([before, dict(os.environ)]))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    before, after = json.loads(out.stdout)
    assert after == before
    assert not set(VARS) & set(after)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="counts threads in /proc")
def test_a_measurement_program_starts_again_with_one_blas_thread(monkeypatch, tmp_path) -> None:
    """A ``python -m`` measurement program whose module imported numpy before its main block:
    :func:`validation.runs.environment.as_program` starts it again with the variables set, so
    its BLAS has one thread (one OS thread in the process) and its arguments are kept."""
    _clean_env(monkeypatch)
    prog = tmp_path / "prog.py"
    prog.write_text(
        "import json, os, sys\n"
        "import numpy\n"
        "from validation.runs.environment import as_program\n"
        "as_program()\n"
        "print(json.dumps([os.environ.get('OPENBLAS_NUM_THREADS'),"
        " len(os.listdir('/proc/self/task')), sys.argv[1:]]))\n"
    )
    out = subprocess.run(
        [sys.executable, str(prog), "--x", "1"], capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout) == ["1", 1, ["--x", "1"]]


POOL_BLAS = """
import json, threadpoolctl
from validation.studies.sweep.running import default_executor

def blas(info):
    return sorted(i["num_threads"] for i in info if i["user_api"] == "blas")

with default_executor() as ex:
    worker = blas(ex.submit(threadpoolctl.threadpool_info).result())
import numpy, scipy.linalg
print(json.dumps([worker, blas(threadpoolctl.threadpool_info())]))
"""


def test_the_tools_pool_workers_have_one_blas_thread_and_the_caller_keeps_its_own(
    monkeypatch,
) -> None:
    """A library user's process without the variables runs a study's process pool: each pool
    worker (the tool's own process) has its BLAS on one thread; the user's process keeps its
    original thread counts."""
    _clean_env(monkeypatch)
    expected = sorted(n for _, n in _reference()["blas"])
    out = subprocess.run(
        [sys.executable, "-c", POOL_BLAS], capture_output=True, text=True, timeout=300
    )
    assert out.returncode == 0, out.stderr
    worker, caller = json.loads(out.stdout)
    assert worker and all(n == 1 for n in worker)
    assert caller == expected
