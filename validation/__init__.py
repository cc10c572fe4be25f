"""The side-by-side validation of the analytic plant and the MuJoCo twin, and the ``tumble`` CLI.

Importing this package pins BLAS to one thread (``OPENBLAS_NUM_THREADS``, ``OMP_NUM_THREADS``,
``MKL_NUM_THREADS``, unless set) and sets ``NO_COLOR=1`` when stderr is not a terminal (unless ``NO_COLOR`` is
set already): Rerun's logger otherwise writes ANSI colour codes into files and pipes. It reads the
variable once, when ``rerun`` is first imported, which in this project happens inside this package
(:mod:`validation.recording.recording`).

Public names (imported on first use, so ``import validation`` stays cheap: the pytest plugin
:mod:`validation.testing.pytest_plugin` imports this package in every pytest run):

* :func:`assert_agree`: run a scene and raise ``AssertionError`` with the table of failed checks;
* :func:`run_validation`, :class:`ValidationResult`: the ``tumble validate`` job;
* :func:`resolve_scene`: load a scene file or a built-in scene by name;
* :func:`thresholds_for`, :class:`Threshold`: the named agreement thresholds;
* :class:`Check`: one verdict of a run.
"""

import os as _os

# The process-wide numerical environment, set here once: every entry point (``tumble``,
# ``python -m validation.*``, the pytest plugin, ``import validation``) imports this package before
# numpy. The model works on small dense matrices (n + 7 up to a few hundred): multithreaded BLAS
# only adds synchronisation there, and on a loaded 2-core machine its spinning threads slowed one
# evaluation by up to 100x (measured: n = 50, 1.3 ms with one thread against 120 ms with two while
# another process ran). ``setdefault``: a user's explicit setting wins.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    _os.environ.setdefault(_var, "1")

if "NO_COLOR" not in _os.environ and not _os.isatty(2):
    _os.environ["NO_COLOR"] = "1"

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

__all__ = sorted(_LAZY)


def __getattr__(name: str):
    if name in _LAZY:
        import importlib  # deferred: `import validation` stays at ~1 ms (the pytest plugin imports it in every run)

        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'validation' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_LAZY])
