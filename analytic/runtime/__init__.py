"""How the project's code is run, none of it physics: the lowest layer. It imports nothing of the
rest of ``analytic`` (``tests/cross/test_layers.py``), and any module may import it.

* :mod:`~analytic.runtime.jit`: numba plumbing (compilation with numba's documented API, the disk
  cache's directory, source fingerprints in cache keys);
* :mod:`~analytic.runtime.abi`: the C signatures of the kernel's two halves and the calls by
  address compiled callers make;
* :mod:`~analytic.runtime.cache_dir`: where numba caches compiled code, decided without numba;
* :mod:`~analytic.runtime.cache_check`: numba's cache files checked against their recorded hashes;
* :mod:`~analytic.runtime.compile_lock`: one process compiles a kernel, the others wait for it;
* :mod:`~analytic.runtime.safe_files`: reading a file that must be a regular file, never blocking;
* :mod:`~analytic.runtime.lazy`: a package's public names imported on first use;
* :mod:`~analytic.runtime.log`: the project's loggers, one root (``tumbling_testbed``).
"""
