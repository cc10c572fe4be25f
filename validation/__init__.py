"""The side-by-side validation of the analytic plant and the MuJoCo twin, and the ``tumble`` CLI.

Importing this package sets ``NO_COLOR=1`` when stderr is not a terminal (unless ``NO_COLOR`` is
set already): Rerun's logger otherwise writes ANSI colour codes into files and pipes. It reads the
variable once, when ``rerun`` is first imported, which in this project happens inside this package
(:mod:`validation.recording`).

Public names (imported on first use, so ``import validation`` stays cheap: the pytest plugin
:mod:`validation.pytest_plugin` imports this package in every pytest run):

* :func:`assert_agree`: run a scene and raise ``AssertionError`` with the table of failed checks;
* :func:`run_validation`, :class:`ValidationResult`: the ``tumble validate`` job;
* :func:`resolve_scene`: load a scene file or a built-in scene by name;
* :func:`thresholds_for`, :class:`Threshold`: the named agreement thresholds;
* :class:`Check`: one verdict of a run.
"""

import os as _os

if "NO_COLOR" not in _os.environ and not _os.isatty(2):
    _os.environ["NO_COLOR"] = "1"

_LAZY = {
    "assert_agree": "validation.agree",
    "Check": "validation.compare",
    "resolve_scene": "validation.scenes",
    "run_validation": "validation.validate",
    "Threshold": "validation.thresholds",
    "thresholds_for": "validation.thresholds",
    "ValidationResult": "validation.validate",
}

__all__ = sorted(_LAZY)


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'validation' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_LAZY])
