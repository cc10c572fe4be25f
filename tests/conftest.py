"""Test-session setup.

The model works on small dense matrices (n+7 ≤ a few hundred): multithreaded BLAS only adds
synchronisation cost there, and on a loaded 2-core machine its spinning threads slowed one
evaluation by up to 100x (measured: n = 50, 1.3 ms single-threaded vs 120 ms with 2 threads while
another process ran). Pin BLAS to one thread before numpy is imported.
"""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

# tests/test_plugin.py runs pytest inside pytest on scene files (the tumble plugin)
pytest_plugins = ["pytester"]
