"""The side-by-side validation of the analytic plant and the MuJoCo twin, and the ``tumble`` CLI.

Importing this package changes nothing in the process: no environment variable, no thread pool
(the ``tumble`` program sets its own numerical environment at start,
:mod:`validation.runs.environment`, which states why).

Public names (imported on first use, so ``import validation`` stays cheap: the pytest plugin
:mod:`validation.testing.pytest_plugin` imports this package in every pytest run):

* :func:`assert_agree`: run a scene and raise ``AssertionError`` with the table of failed checks;
* :func:`run_validation`, :class:`ValidationResult`: the ``tumble validate`` job;
* :func:`resolve_scene`: load a scene file or a built-in scene by name;
* :func:`thresholds_for`, :class:`Threshold`: the named agreement thresholds;
* :class:`Check`: one verdict of a run.
"""

TYPE_CHECKING = False  # typing.TYPE_CHECKING without importing typing (mypy reads it as that)

_LAZY = {
    "assert_agree": "validation.testing.agree",
    "Check": "validation.compare.checks",
    "fuzz": "validation.studies.fuzz.campaign",
    "judge": "validation.external.judge",
    "resolve_scene": "validation.scenes",
    "run_validation": "validation.validate",
    "Threshold": "validation.compare.thresholds",
    "thresholds_for": "validation.compare.thresholds",
    "ValidationResult": "validation.validate",
}

if TYPE_CHECKING:  # the same names, typed for a type checker (never run: imports stay lazy)
    from typing import Any

    from validation.compare.checks import Check as Check
    from validation.compare.thresholds import Threshold as Threshold
    from validation.compare.thresholds import thresholds_for as thresholds_for
    from validation.external.judge import judge as judge
    from validation.scenes import resolve_scene as resolve_scene
    from validation.studies.fuzz.campaign import fuzz as fuzz
    from validation.testing.agree import assert_agree as assert_agree
    from validation.validate import ValidationResult as ValidationResult
    from validation.validate import run_validation as run_validation

__all__ = sorted(_LAZY)


def __getattr__(name: str) -> "Any":
    if name in _LAZY:
        # deferred: `import validation` imports no submodule (the pytest plugin imports it in
        # every run; docs/performance.md, Import costs)
        import importlib

        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'validation' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_LAZY])
