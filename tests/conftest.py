"""Test-session setup.

BLAS is pinned to one thread by ``import validation`` (the one place that sets the process-wide
numerical environment, with the measurement behind it), imported here before numpy.
"""

import validation  # noqa: F401  (sets the numerical environment before numpy is imported)

# tests/validation/testing/test_pytest_plugin.py runs pytest inside pytest on scene files (the tumble plugin)
pytest_plugins = ["pytester"]
