"""Test-session setup.

BLAS on one thread for the test session, as the ``tumble`` program sets it for its own process
(:func:`validation.runs.environment.set_process_env`, with the measurement behind it), before
numpy is imported. ``import validation`` changes no environment: the suite sets it here, itself.
"""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
if "NO_COLOR" not in os.environ and not os.isatty(2):
    os.environ["NO_COLOR"] = "1"

# tests/validation/testing/test_pytest_plugin.py runs pytest inside pytest on scene files (the tumble plugin)
pytest_plugins = ["pytester"]
