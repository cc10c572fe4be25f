"""Faults in the caches the tool reads: numba's compiled kernels and the files beside them.

Every cache is checked against a content hash before it is trusted; a cache that fails is rebuilt
with one line saying so; nothing at a cache path can make the tool block. Read as a table:

* a truncated, bit-flipped or garbled numba cache file -> the kernel is deleted and recompiled,
  one line names its source file, the run gives the right numbers;
* numba data files swapped between kernels -> caught by the hash check before numba loads them
  (which would crash the process), recompiled;
* no manifest, or a manifest edited -> every kernel recompiled, said in one line;
* a file written by a sibling process after its parent's check -> left alone (the child trusts the
  check its parent made);
* a FIFO among the cache files, or at the warm stamp -> never opened; the cache is left alone and
  the kernels compiled in a private directory for the run;
* a FIFO or a symbolic link at a compile lock -> not opened, the kernel compiled without the lock;
* a full cache disk -> the kernels are compiled and used, one line says the cache could not be
  written, the full disk is not touched.

The fast tests use a two-function module written into ``tmp_path`` and compiled in a subprocess
with its own ``NUMBA_CACHE_DIR``; one end-to-end test damages the real kernels' cache.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import textwrap
import threading
from pathlib import Path

import pytest

from analytic.runtime import cache_check as cc

pytestmark = pytest.mark.faults

ROOT = Path(__file__).resolve().parents[2]

TINY = textwrap.dedent(
    """
    import numba


    @numba.njit(cache=True)
    def add(a, b):
        return a + b


    @numba.njit(cache=True)
    def triple_product(a, b):
        return 3.0 * a * b
    """
)
"""Two cached kernels of the same signature: ``add(2, 3) = 5``, ``triple_product(2, 3) = 18``."""
EXPECTED = {"add": 5.0, "triple_product": 18.0}

RUNNER = textwrap.dedent(
    """
    import json, sys
    from pathlib import Path
    src, cache, mode = Path(sys.argv[1]), Path(sys.argv[2]), sys.argv[3]
    sys.path.insert(0, str(src))
    from analytic.runtime import cache_check as cc
    lay = cc.Layout(cache / cc.MANIFEST_NAME, ((cache / cc.numba_subdir(src), src),))
    res = cc.check(lay) if mode == "check" else None
    import tiny
    out = {"add": tiny.add(2.0, 3.0), "triple_product": tiny.triple_product(2.0, 3.0)}
    if res is not None:
        out.update(lines=list(res.lines), removed=list(res.removed), problems=list(res.problems))
        cc.record(lay)
    print(json.dumps(out))
    """
)
"""Checks the tiny module's cache (``check``) or not (``plain``: numba alone), calls both kernels,
records the manifest, prints what it got as JSON."""


def _env(cache: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k != cc.ENV_MARK}
    env["NUMBA_CACHE_DIR"] = str(cache)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH")) if p)
    return env


def _run_tiny(src: Path, cache: Path, mode: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, str(src / "runner.py"), str(src), str(cache), mode],
        env=_env(cache),
        capture_output=True,
        text=True,
        timeout=120,
    )


def _answers(proc: subprocess.CompletedProcess) -> dict | None:
    """The JSON the runner printed (None when it failed)."""
    if proc.returncode != 0:
        return None
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    """``(source directory, a warm checked cache of the tiny module)``: copy the cache per test."""
    src = tmp_path_factory.mktemp("tiny_src")
    (src / "tiny.py").write_text(TINY)
    (src / "runner.py").write_text(RUNNER)
    cache = tmp_path_factory.mktemp("tiny_cache")
    got = _answers(_run_tiny(src, cache, "check"))
    assert got is not None and got["lines"] == []
    assert {k: got[k] for k in EXPECTED} == EXPECTED
    return src, cache


def _cache_copy(tiny, tmp_path) -> tuple[Path, Path, Path]:
    """``(source dir, a private copy of the warm cache, its numba directory)``."""
    src, proto = tiny
    cache = tmp_path / "cache"
    shutil.copytree(proto, cache)
    return src, cache, cache / cc.numba_subdir(src)


def _files(numba_dir: Path, kernel: str, suffix: str) -> list[Path]:
    return sorted(numba_dir.glob(f"tiny.{kernel}-*{suffix}"))


def _damage(numba_dir: Path, how: str) -> str:
    """Damage the tiny cache as ``how`` says; returns the kernel damaged (for the line)."""
    nbc = _files(numba_dir, "add", ".nbc")[0]
    nbi = _files(numba_dir, "add", ".nbi")[0]
    data = nbc.read_bytes()
    if how == "truncated data":
        nbc.write_bytes(data[: len(data) // 3])
    elif how == "halved data":
        nbc.write_bytes(data[: len(data) // 2])
    elif how == "flipped bit in data":
        k = len(data) // 2
        nbc.write_bytes(data[:k] + bytes([data[k] ^ 0x01]) + data[k + 1 :])
    elif how == "garbled index":
        raw = nbi.read_bytes()
        nbi.write_bytes(raw[:20] + b"\xff\xfe garbled \x80" + raw[40:])
    elif how == "swapped data":
        other = _files(numba_dir, "triple_product", ".nbc")[0]
        a, b = nbc.read_bytes(), other.read_bytes()
        nbc.write_bytes(b)
        other.write_bytes(a)
    return "add"


@pytest.mark.parametrize(
    "how", ["truncated data", "halved data", "flipped bit in data", "garbled index", "swapped data"]
)
def test_damaged_numba_cache_file_is_recompiled(tiny, tmp_path, how):
    """A damaged numba cache file (truncated, halved, bit-flipped, garbled index, data swapped
    between kernels) -> the kernel is deleted and recompiled with one line naming it, and the
    kernels give the right numbers (numba alone fails or answers wrongly on the same files)."""
    src, cache, numba_dir = _cache_copy(tiny, tmp_path)
    _damage(numba_dir, how)
    plain_copy = tmp_path / "plain"
    shutil.copytree(cache, plain_copy)
    plain = _answers(_run_tiny(src, plain_copy, "plain"))
    if how != "flipped bit in data":  # a flipped bit may land where numba never looks
        assert plain is None or {k: plain[k] for k in EXPECTED} != EXPECTED  # the fault is real
    checked = _run_tiny(src, cache, "check")
    got = _answers(checked)
    assert got is not None, checked.stderr
    assert {k: got[k] for k in EXPECTED} == EXPECTED
    named = [ln for ln in got["lines"] if "tiny.py" in ln and "recompiled" in ln]
    assert named and len(got["lines"]) == len(got["removed"])
    assert any("tiny.add-" in r for r in got["removed"]) and got["problems"] == []
    # rebuilt and recorded: the next run trusts it and says nothing
    again = _answers(_run_tiny(src, cache, "check"))
    assert again is not None and again["lines"] == [] and again["removed"] == []


def test_numba_cache_without_manifest_is_recompiled(tiny, tmp_path):
    """A cache with no manifest, or one whose entries were edited -> every kernel is deleted and
    recompiled, said in one line."""
    src, cache, _numba_dir = _cache_copy(tiny, tmp_path)
    manifest = cache / cc.MANIFEST_NAME
    doc = json.loads(manifest.read_text())
    doc["files"] = {k: "0" * 64 for k in doc["files"]}  # hashes edited, the manifest's own kept
    manifest.write_text(json.dumps(doc))
    got = _answers(_run_tiny(src, cache, "check"))
    assert got is not None and {k: got[k] for k in EXPECTED} == EXPECTED
    assert len(got["lines"]) == 1 and "manifest" in got["lines"][0]
    assert len(got["removed"]) == 2
    manifest.unlink()
    got = _answers(_run_tiny(src, cache, "check"))
    assert len(got["lines"]) == 1 and "no manifest" in got["lines"][0]


def test_file_written_after_the_parents_check_is_trusted_by_its_child(tmp_path):
    """A kernel a sibling wrote after the parent process checked the cache -> a child process
    trusts its parent's check and does not delete it; once the run is killed before recording it,
    the next run does not know it and deletes it (to be recompiled)."""
    cache = tmp_path / "cache"
    code = textwrap.dedent(
        """
        import os, subprocess, sys
        from analytic.runtime import cache_check as cc
        cc.ensure_checked()
        d = cc.layout().dirs[0][0]
        d.mkdir(parents=True, exist_ok=True)
        (d / "fresh.f-1.py311.nbi").write_bytes(b"written by a sibling")
        child = "from analytic.runtime import cache_check as cc; print(cc.ensure_checked())"
        out = subprocess.run([sys.executable, "-c", child], capture_output=True, text=True)
        print(out.stdout.strip(), (d / "fresh.f-1.py311.nbi").exists(), d, flush=True)
        os._exit(0)  # killed before it recorded the manifest
        """
    )
    proc = subprocess.run(
        [sys.executable, "-c", code], env=_env(cache), capture_output=True, text=True, timeout=60
    )
    trusted, exists, d = proc.stdout.split()
    assert (trusted, exists) == ("None", "True"), proc.stderr
    # the next run (not its child) checks for itself: the unrecorded file goes
    proc = subprocess.run(
        [sys.executable, "-c", "from analytic.runtime import cache_check as cc; cc.ensure_checked()"],
        env=_env(cache),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert not (Path(d) / "fresh.f-1.py311.nbi").exists()
    assert "no manifest" in proc.stderr and "recompiled" in proc.stderr


def _unblocked(fn, fifo: Path):
    """``fn()`` in a thread; should it block on ``fifo``, a writer releases it and the test
    fails."""
    box: dict = {}
    th = threading.Thread(target=lambda: box.setdefault("out", fn()), daemon=True)
    th.start()
    th.join(30)
    if th.is_alive():
        os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
        th.join(10)
        pytest.fail(f"blocked on the FIFO {fifo}")
    return box["out"]


def test_fifo_among_numba_cache_files_is_never_opened(tmp_path):
    """A FIFO named like a numba cache file, or at the warm stamp -> nothing blocks; the FIFO is
    left alone and the run goes to a private cache directory."""
    src = tmp_path / "src"
    src.mkdir()
    cache = tmp_path / "cache"
    numba_dir = cache / cc.numba_subdir(src)
    numba_dir.mkdir(parents=True)
    fifo = numba_dir / "tiny.add-3.py311.nbi"
    os.mkfifo(fifo)
    lay = cc.Layout(cache / cc.MANIFEST_NAME, ((numba_dir, src),))
    res = _unblocked(lambda: cc.check(lay), fifo)
    assert res.mode is cc.Mode.PRIVATE and any("FIFO" in p for p in res.problems)
    assert fifo.is_fifo()
    # the warm stamp beside the cache: read without blocking, as no stamp
    from validation.runs import warmup

    stamp = cache / warmup.WARM_STAMP
    os.mkfifo(stamp)
    original = warmup._stamp_path
    warmup._stamp_path = lambda: stamp
    try:
        assert _unblocked(warmup._stamped_keys, stamp) == []
    finally:
        warmup._stamp_path = original
    assert stamp.is_fifo()


def test_fifo_or_link_at_a_compile_lock_is_not_opened(tmp_path, monkeypatch):
    """A FIFO or a symbolic link at a kernel's compile lock in the cache directory -> nothing
    blocks or is created through the link; the kernel is compiled without the lock."""
    from analytic.runtime import compile_lock

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    fifo = tmp_path / f"tumble-compiling-{compile_lock.RHS}.lock"
    os.mkfifo(fifo)
    assert _unblocked(lambda: compile_lock.hold(compile_lock.RHS), fifo) is False
    assert fifo.is_fifo()
    target = tmp_path / "elsewhere" / "victim"
    link = tmp_path / f"tumble-compiling-{compile_lock.PINOCCHIO}.lock"
    link.symlink_to(target)
    with compile_lock.compiling(compile_lock.PINOCCHIO):
        pass
    assert link.is_symlink() and not target.exists()


FULL_DISK = textwrap.dedent(
    """
    import builtins, errno, os, sys
    from pathlib import Path
    src, cache, mode = Path(sys.argv[1]), os.environ["NUMBA_CACHE_DIR"], sys.argv[3]
    sys.path.insert(0, str(src))
    real_open = builtins.open

    def full_open(file, mode="r", *args, **kwargs):  # every write into the cache: no space
        if any(c in mode for c in "wax+") and str(file).startswith(cache):
            raise OSError(errno.ENOSPC, "No space left on device", str(file))
        return real_open(file, mode, *args, **kwargs)

    builtins.open = full_open
    real_statvfs = os.statvfs

    def full_statvfs(path):  # the cache's filesystem (the cache or a parent of it): no room
        st = real_statvfs(path)
        if not (str(path).startswith(cache) or cache.startswith(str(path))):
            return st
        return os.statvfs_result((st.f_bsize, st.f_frsize, st.f_blocks, 0, 0) + tuple(st)[5:])

    os.statvfs = full_statvfs
    if mode == "check":
        from analytic.runtime import cache_check
        cache_check.ensure_checked()
    import tiny
    print(tiny.add(2.0, 3.0), tiny.triple_product(2.0, 3.0))
    """
)


def test_full_numba_cache_disk_compiles_in_a_private_directory(tmp_path):
    """numba's cache directory on a full disk (simulated: no free blocks, every write ENOSPC) ->
    the kernels are compiled and used, one line says the cache could not be written, and nothing
    is written to the full disk (numba alone fails the call)."""
    src = tmp_path / "src"
    src.mkdir()
    (src / "tiny.py").write_text(TINY)
    (src / "full.py").write_text(FULL_DISK)
    cache = tmp_path / "cache"

    def run(mode):
        return subprocess.run(
            [sys.executable, str(src / "full.py"), str(src), str(cache), mode],
            env=_env(cache),
            capture_output=True,
            text=True,
            timeout=120,
        )

    plain = run("plain")
    assert plain.returncode != 0 and "No space left on device" in plain.stderr  # the fault
    shutil.rmtree(cache, ignore_errors=True)
    checked = run("check")
    assert checked.returncode == 0, checked.stderr
    assert [float(x) for x in checked.stdout.split()] == [5.0, 18.0]
    said = [ln for ln in checked.stderr.splitlines() if "could not be written" in ln]
    assert len(said) == 1 and "kB free" in said[0]
    nb = [p for p in cache.rglob("*") if p.suffix in (".nbi", ".nbc")] if cache.exists() else []
    assert nb == []


# ----------------------------------------------------------------------------------------------
# The real kernels
# ----------------------------------------------------------------------------------------------


def _validate(cache: Path, out: Path, extra_env: dict | None = None):
    env = {**_env(cache), "TUMBLE_WORKERS": "0", **(extra_env or {})}
    args = ["validate", "paper_example1_controlled", "--t-end", "0.2"]
    args += ["--plants", "analytic,mujoco", "--out", str(out)]
    return subprocess.run(
        [sys.executable, "-m", "validation", *args],
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
        cwd=out.parent,
    )


def test_swapped_kernel_data_files_are_recompiled_not_loaded(tmp_path):
    """The real kernels' numba data files swapped between two kernels, and a third truncated ->
    the hash check catches them before numba loads them (which crashed the plants), each is
    recompiled with one line, and the run passes."""
    cache = tmp_path / "numba"
    first = _validate(cache, tmp_path / "o1")
    assert first.returncode == 0, first.stderr[-2000:]
    nbc = sorted(cache.rglob("*.nbc"))
    by_module = {p.name.split(".", 1)[0]: p for p in nbc}
    a, b = by_module["system"], by_module["gauss"]  # the kernel's two halves
    da, db = a.read_bytes(), b.read_bytes()
    a.write_bytes(db)
    b.write_bytes(da)
    third = by_module["native"]
    third.write_bytes(third.read_bytes()[:100])
    second = _validate(cache, tmp_path / "o2")
    assert second.returncode == 0, second.stderr[-2000:]
    assert (tmp_path / "o2" / "report.md").read_text().startswith("# paper_example1_controlled: P")
    lines = [ln for ln in second.stderr.splitlines() if "differs from its recorded SHA-256" in ln]
    for source in ("kernel/system.py", "kernel/gauss.py", "mj_bridge/native.py"):
        assert sum(source in ln for ln in lines) == 1, (source, lines)


def test_full_tmpfs_numba_cache_dir_still_passes(tmp_path):
    """``NUMBA_CACHE_DIR`` on a real full filesystem (a 300 kB tmpfs, cold) -> the run passes, one
    line says the cache could not be written, and the filesystem is left as it was."""
    mnt = tmp_path / "full"
    mnt.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=300k", "tmpfs", str(mnt)]).returncode:
        pytest.skip("cannot mount a tmpfs here")
    try:
        res = _validate(mnt, tmp_path / "o")
        assert res.returncode == 0, res.stderr[-2000:]
        assert sum("could not be written" in ln for ln in res.stderr.splitlines()) == 1
        assert not [p for p in mnt.rglob("*") if p.suffix in (".nbi", ".nbc")]
    finally:
        subprocess.run(["umount", str(mnt)])
