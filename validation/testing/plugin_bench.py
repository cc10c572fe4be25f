"""What the pytest plugin costs a pytest run that collects no scene, measured:
``python -m validation.testing.pytest_plugin --bench`` (a measurement run by hand, never a test).

It prints the median time of importing :mod:`validation.testing.pytest_plugin` after pytest (and
which heavy modules, if any, that import loaded), then the median wall time of ``pytest -q`` on a
directory with one plain test and a ``.toml`` that is not a test file, with the plugin and without
it (``-p no:tumble``), their difference and the run-to-run spread.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def bench(repeats: int = 15) -> None:  # pragma: no cover - a measurement, run by hand
    import statistics  # deferred: ~3 ms (python -X importtime), for this measurement only

    py = sys.executable
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    subprocess.run(
        [py, "-c", "import validation.testing.pytest_plugin"], env=env, check=True
    )  # .pyc
    imp = (
        "import time, sys; import pytest; t0 = time.perf_counter(); "
        "import validation.testing.pytest_plugin; t1 = time.perf_counter(); "
        "heavy = [m for m in ('numpy', 'mujoco', 'numba', 'scipy') if m in sys.modules]; "
        "print(t1 - t0, ','.join(heavy))"
    )
    times, heavy = [], ""
    for _ in range(repeats):
        out = subprocess.run(
            [py, "-c", imp], capture_output=True, text=True, check=True, env=env
        ).stdout
        t, heavy = out.split(" ", 1)
        times.append(float(t))
    print(
        f"import validation.testing.pytest_plugin (after pytest): median {statistics.median(times) * 1e3:.2f} ms; "
        f"heavy modules imported: {heavy.strip() or 'none'}"
    )
    with tempfile.TemporaryDirectory() as d:
        Path(d, "test_plain.py").write_text("def test_one():\n    assert True\n")
        Path(d, "pyproject.toml").write_text("[tool.pytest.ini_options]\n")
        Path(d, "settings.toml").write_text("[scene]\nname = 'not a test file'\n")
        res: dict[str, list[float]] = {"with": [], "without": []}
        for i in range(2 * repeats):
            which = "with" if i % 2 == 0 else "without"
            args = [py, "-m", "pytest", "-q", "-p", "no:cacheprovider"]
            if which == "without":
                args += ["-p", "no:tumble"]
            t0 = time.perf_counter()
            subprocess.run(args, cwd=d, capture_output=True, check=True, env=env)
            res[which].append(time.perf_counter() - t0)
    w, wo = statistics.median(res["with"]), statistics.median(res["without"])
    spread = statistics.stdev(res["without"])
    print(
        f"pytest on a directory with no scene ({repeats} runs each, median): with the plugin "
        f"{w * 1e3:.0f} ms, without (-p no:tumble) {wo * 1e3:.0f} ms, difference "
        f"{(w - wo) * 1e3:+.0f} ms (run-to-run spread {spread * 1e3:.0f} ms)"
    )
