"""A fork-server preload that takes a minute (as compiling numba's kernels into a cold cache
can): ``tests/cross/test_fault_processes.py`` kills the server's client meanwhile."""

import time

time.sleep(60)
