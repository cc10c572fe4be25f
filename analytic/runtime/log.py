"""The project's loggers: one root, :data:`ROOT`, and one child per module.

Contract:

* :func:`get_logger` ``(__name__)`` is ``logging.getLogger(f"{ROOT}.{__name__}")``: every module
  of every package logs under the one root, so a caller routes, filters or silences all of the
  tool's messages with one name (``logging.getLogger("tumbling_testbed").setLevel(...)``).
* The library never configures logging: importing this module adds a single
  :class:`logging.NullHandler` to the root (Python's convention for a library), so a program that
  never configures logging sees none of these messages, not even Python's last-resort output of
  warnings. Configure logging (``logging.basicConfig(level=logging.INFO)``) to see them.
* The ``tumble`` command line installs its own handler on the root for the command's duration
  (:mod:`validation.runs.messages`): ``tumble: warning: ...`` lines as the rest of its output.

What goes here and what stays a :func:`warnings.warn`: a warning the caller can act on (a scene
value that was corrected or ignored, a pointwise check left out) stays a Python warning, so that
``pytest.warns`` and ``-W error`` keep working; a notice about what the tool is doing (which
stage runs, a study's series done, a finding shrunk) is logged at ``INFO``.
"""

from __future__ import annotations

import logging

ROOT = "tumbling_testbed"
"""The name of the project's root logger (the distribution's name, as ``pip`` knows it)."""


def _root() -> logging.Logger:
    root = logging.getLogger(ROOT)
    if not any(isinstance(h, logging.NullHandler) for h in root.handlers):
        root.addHandler(logging.NullHandler())
    return root


ROOT_LOGGER = _root()
"""The root logger, with its one :class:`logging.NullHandler`."""


def get_logger(name: str) -> logging.Logger:
    """The logger of module ``name`` (pass ``__name__``), a child of :data:`ROOT`.

    Raises:
        ValueError: ``name`` empty or not a string.
    """
    if not isinstance(name, str) or not name.strip("."):
        raise ValueError(f"name: must be a module name (got {name!r})")
    if name == ROOT or name.startswith(f"{ROOT}."):
        return logging.getLogger(name)
    return logging.getLogger(f"{ROOT}.{name}")


__all__ = ["ROOT", "ROOT_LOGGER", "get_logger"]
