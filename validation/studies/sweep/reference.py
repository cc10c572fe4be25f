"""The reference solution of a sweep, computed once per scene and cached.

**What it is.** The analytic engine (DOP853) at scipy's tightest tolerance (rtol 2.5e-14, below
every rtol of the sweep), its steps capped at half the mean step of the same run uncapped. Its
error is estimated by self-convergence: the difference between the capped and the uncapped run,
in the sweep's error measure (:mod:`validation.studies.sweep.metrics`). DOP853 is of order 8, so halving
the steps shrinks truncation error ~256x: the difference bounds the coarser run's error and hence
the reference's (what is left is round-off).

**The cache.** Both runs go through the sweep's executor; the result (the capped run's samples,
their scales, the error estimate and the runs' counts) is stored in ``reference-<key>.npz`` under
the cache directory (:func:`default_cache_dir`), written atomically (:mod:`validation.runs.atomic`).
The key is a SHA-256 of the resolved scene (every field but its name, description and source
path), the horizon, the reference's settings and the code that computes it (the source of
``analytic/`` and of the error measure, the versions of Python, numpy, scipy and numba). A file is
used only when it loads (no pickles), passes its content check, carries the same key and holds
finite samples on the expected output grid; anything else is refused, recomputed and overwritten
(atomically), with one line saying so.

**The content check.** Each file carries a SHA-256 (:func:`content_digest`) over its arrays (each
one's name, dtype, shape and bytes, in the fixed order of :data:`ARRAY_KEYS`) and its metadata
(the key, the layout version and how the reference was computed). A file whose bytes were changed
after it was written (a poisoned rotation sample, a flipped bit that leaves the zip readable) no
longer matches and is recomputed, never used.

**Never blocking.** A cache file is opened with ``O_NOFOLLOW | O_NONBLOCK`` and used only when the
descriptor is a regular file: a FIFO, a device, a directory or a symbolic link at its name is not
read (one line says so) and the reference is computed; the new entry is then stored only where
:func:`validation.runs.atomic.write_bytes` may write it, and otherwise not stored (one line says so):
what sits at the name, which the tool did not create, is left as it is.
"""

from __future__ import annotations

import dataclasses
import enum
import hashlib
import io
import json
import math
import os
import platform
import warnings
from collections.abc import Callable, Mapping
from concurrent.futures import Executor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import scipy

import analytic
from analytic.runtime import safe_files
from analytic.scene import Scene, SolverSettings
from validation.compare import checks as compare
from validation.compare import summary
from validation.runs.atomic import write_bytes
from validation.studies.sweep import metrics
from validation.studies.sweep.config import (
    REFERENCE_ATOL,
    REFERENCE_METHOD,
    REFERENCE_RTOL,
    REFERENCE_STEP_FRACTION,
)
from validation.studies.sweep.metrics import RefSamples

CACHE_ENV = "TUMBLE_CACHE_DIR"
"""Environment variable naming the cache directory (default: the user's cache directory)."""
CACHE_FORMAT = 2
"""Version of the cache file's layout; part of the key."""
ARRAY_KEYS = ("t", "R", "u", "p", "scales")
"""The sample arrays of a cache file, in the order :func:`content_digest` hashes them."""
DIGEST_MEMBER = "sha256"
"""The member of a cache file holding its :func:`content_digest` (hex)."""
SCENE_LABELS = frozenset({"name", "description", "source"})
"""Fields of a scene that name it without changing its motion: left out of the key."""


class CacheRefused(ValueError):
    """A cache file that is not a usable reference (unreadable, another key, bad samples)."""


class ReferenceCacheWarning(UserWarning):
    """One line about the reference cache: an entry not used (its content check failed, or not a
    regular file) or a reference that could not be stored. Shown by ``tumble`` whatever its
    progress output."""


def _warn(line: str) -> None:
    warnings.warn(line, ReferenceCacheWarning, stacklevel=3)


class ContentCheckFailed(CacheRefused):
    """A cache file whose arrays or metadata do not match the SHA-256 it carries."""


class NotRegularFile(CacheRefused):
    """Something other than a regular file (a FIFO, a device, a directory, a symbolic link) sits
    at a cache file's name: it is not read."""


@dataclass(frozen=True)
class Reference:
    """The reference of a sweep.

    Attributes:
        samples: the capped run's samples and the error scales.
        info: how it was computed (method, rtol, atol, max_step, nfev, nsteps, wall_time_s,
            uncapped_nsteps), its estimated error (``error_estimate`` and ``error_components``),
            the scales, the drifts, and ``cache`` (where it came from).
    """

    samples: RefSamples
    info: Mapping[str, Any]

    @property
    def error_estimate(self) -> float:
        return float(self.info["error_estimate"])


def reference_run(scene: Scene, t_end: float, max_step: float = math.inf):
    """The analytic engine at the reference tolerance (DOP853), steps capped at ``max_step``."""
    sc = scene.replace(
        solver=SolverSettings(
            method=REFERENCE_METHOD, rtol=REFERENCE_RTOL, atol=REFERENCE_ATOL, max_step=max_step
        )
    )
    return analytic.simulate(sc, t_end=t_end)


def reference_task(scene: Scene, t_end: float, max_step: float) -> dict[str, Any]:
    """:func:`reference_run` in a worker: what the sweep needs of it, small enough to send back."""
    tr = reference_run(scene, t_end, max_step)
    return {
        "samples": metrics.ref_samples(tr),
        "status": tr.status.value,
        "message": tr.message,
        "nfev": int(tr.info["nfev"]),
        "nsteps": int(tr.info["nsteps"]),
        "wall_time_s": float(tr.info["wall_time_s"]),
        "drift": metrics.drifts(tr),
    }


def compute_reference(scene: Scene, t_end: float, executor: Executor) -> Reference:
    """The uncapped run, then the capped one, in ``executor``; the estimate from the two."""
    coarse = executor.submit(reference_task, scene, t_end, math.inf).result()
    if coarse["status"] != "ok":
        raise RuntimeError(f"reference run failed: {coarse['message']}")
    max_step = REFERENCE_STEP_FRACTION * t_end / max(coarse["nsteps"], 1)
    fine = executor.submit(reference_task, scene, t_end, max_step).result()
    if fine["status"] != "ok":
        raise RuntimeError(f"reference run failed: {fine['message']}")
    ref: RefSamples = fine["samples"]
    est = metrics.errors_against(coarse["samples"], ref)
    info = {
        "method": REFERENCE_METHOD,
        "rtol": REFERENCE_RTOL,
        "atol": REFERENCE_ATOL,
        "max_step": max_step,
        "nfev": fine["nfev"],
        "nsteps": fine["nsteps"],
        "wall_time_s": fine["wall_time_s"],
        "uncapped_nsteps": coarse["nsteps"],
        "uncapped_wall_time_s": coarse["wall_time_s"],
        "error_estimate": est["error"],
        "error_components": {
            "pos": est["err_pos_max"],
            "att": est["err_att_max"],
            "rod": est["err_rod_max"],
        },
        "R_scale": ref.R_scale,
        "p_scale": ref.p_scale,
        "drift": fine["drift"],
    }
    return Reference(ref, info)


# ----------------------------------------------------------------------------------------------
# The cache
# ----------------------------------------------------------------------------------------------


def default_cache_dir() -> Path:
    """``$TUMBLE_CACHE_DIR``, else ``$XDG_CACHE_HOME/tumbling-testbed``, else
    ``~/.cache/tumbling-testbed``; the references go to its ``sweep-reference`` directory."""
    env = os.environ.get(CACHE_ENV)
    if env:
        base = Path(env)
    else:
        xdg = os.environ.get("XDG_CACHE_HOME")
        base = (Path(xdg) if xdg else Path.home() / ".cache") / "tumbling-testbed"
    return base / "sweep-reference"


def _canonical(x: Any) -> Any:
    """A JSON-ready form of a scene's value that two equal scenes share (floats exact)."""
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        return {f.name: _canonical(getattr(x, f.name)) for f in dataclasses.fields(x)}
    if isinstance(x, enum.Enum):
        return _canonical(x.value)
    if isinstance(x, np.ndarray):
        return {"shape": list(x.shape), "values": [_canonical(v) for v in x.ravel().tolist()]}
    if isinstance(x, np.generic):
        return _canonical(x.item())
    if isinstance(x, Mapping):
        return {str(k): _canonical(v) for k, v in sorted(x.items(), key=lambda kv: str(kv[0]))}
    if isinstance(x, frozenset | set):
        return sorted((_canonical(v) for v in x), key=repr)
    if isinstance(x, list | tuple):
        return [_canonical(v) for v in x]
    if isinstance(x, float):
        return repr(x)  # exact, and inf / nan as text
    if isinstance(x, str | int | bool) or x is None:
        return x
    raise TypeError(f"cannot fingerprint a {type(x).__name__} in a scene")


def scene_fingerprint(scene: Scene) -> Any:
    """The scene as :func:`_canonical` data, without the fields that only name it."""
    return {
        f.name: _canonical(getattr(scene, f.name))
        for f in dataclasses.fields(scene)
        if f.name not in SCENE_LABELS
    }


def code_fingerprint() -> str:
    """SHA-256 of the code the reference depends on: every module of ``analytic`` (its
    subpackages too: the scene format in ``analytic/scene/``, the kernel in ``analytic/kernel/``),
    the error measure and its helpers, and the versions of Python, numpy, scipy and numba."""
    h = hashlib.sha256()
    root = Path(analytic.__file__).parent
    files = sorted(root.rglob("*.py"))
    files += [Path(__file__), Path(metrics.__file__), Path(compare.__file__)]
    files += [Path(summary.__file__)]
    for f in files:
        h.update((f.relative_to(root).as_posix() if f.is_relative_to(root) else f.name).encode())
        h.update(f.read_bytes())
    try:
        # deferred: optional (absent: no version), and ~0.13 s (python -X importtime)
        import numba

        numba_version = numba.__version__
    except ImportError:
        numba_version = "none"
    versions = (platform.python_version(), np.__version__, scipy.__version__, numba_version)
    h.update(repr(versions).encode())
    return h.hexdigest()


def cache_key(scene: Scene, t_end: float) -> str:
    """The hex SHA-256 that names a reference: scene, horizon, reference settings, code."""
    doc = {
        "format": CACHE_FORMAT,
        "scene": scene_fingerprint(scene),
        "t_end": repr(float(t_end)),
        "reference": {
            "method": REFERENCE_METHOD,
            "rtol": repr(REFERENCE_RTOL),
            "atol": repr(REFERENCE_ATOL),
            "step_fraction": repr(REFERENCE_STEP_FRACTION),
        },
        "code": code_fingerprint(),
    }
    return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()


def cache_path(cache_dir: str | Path, key: str) -> Path:
    """The file of ``key`` (hex digits only: never a name from scene data)."""
    if not (len(key) == 64 and all(c in "0123456789abcdef" for c in key)):
        raise ValueError(f"key: not a SHA-256 hex digest (got {key!r})")
    return Path(cache_dir) / f"reference-{key}.npz"


def content_digest(meta_json: str, arrays: Mapping[str, np.ndarray]) -> str:
    """The hex SHA-256 a cache file carries: over ``meta_json`` (the metadata as stored, UTF-8)
    and, for each name of :data:`ARRAY_KEYS` in that order, the name, the array's dtype
    (``dtype.str``, byte order included), its shape and its bytes in C order."""
    h = hashlib.sha256()
    meta_bytes = meta_json.encode("utf-8")
    h.update(b"meta %d\n" % len(meta_bytes) + meta_bytes)
    for name in ARRAY_KEYS:
        a = np.ascontiguousarray(arrays[name])
        head = f"\n{name} {a.dtype.str} {list(a.shape)} {a.nbytes}\n"
        h.update(head.encode("ascii"))
        h.update(a.tobytes(order="C"))
    return h.hexdigest()


def _encode(ref: Reference, key: str) -> bytes:
    meta_json = json.dumps({"key": key, "format": CACHE_FORMAT, "info": dict(ref.info)})
    s = ref.samples
    arrays = {
        "t": np.asarray(s.t, dtype=float),
        "R": np.asarray(s.R, dtype=float),
        "u": np.asarray(s.u, dtype=float),
        "p": np.asarray(s.p, dtype=float),
        "scales": np.array([s.R_scale, s.p_scale], dtype=float),
    }
    buf = io.BytesIO()
    np.savez(
        buf,
        meta=np.array(meta_json),
        **{DIGEST_MEMBER: np.array(content_digest(meta_json, arrays))},
        **arrays,
    )
    return buf.getvalue()


def _open_regular(path: str | Path) -> int:
    """A read-only descriptor of the regular file at ``path``
    (:func:`analytic.runtime.safe_files.open_regular`: no link followed, never blocking).

    Raises:
        FileNotFoundError: nothing at ``path``.
        NotRegularFile: a FIFO, device, directory or symbolic link at ``path``.
        CacheRefused: any other failure to open it.
    """
    try:
        with safe_files.open_regular(path) as fd:
            return os.dup(fd)
    except FileNotFoundError:
        raise
    except safe_files.NotRegularFile as exc:
        raise NotRegularFile(str(exc)) from exc
    except OSError as exc:
        raise CacheRefused(f"{path}: cannot be opened ({exc.strerror or exc})") from exc


def _read_members(path: str | Path) -> tuple[str, str, dict[str, np.ndarray]]:
    """The metadata (JSON text), the stored digest and the arrays of the cache file at ``path``
    (:func:`_open_regular`; no pickles)."""
    fd = _open_regular(path)
    try:
        with os.fdopen(fd, "rb") as f, np.load(f, allow_pickle=False) as z:
            members = {k: np.array(z[k]) for k in ("meta", DIGEST_MEMBER, *ARRAY_KEYS)}
    except Exception as exc:  # a damaged file fails in many ways (zip, CRC, missing member)
        raise CacheRefused(f"{path}: unreadable ({type(exc).__name__}: {exc})") from exc
    meta_json, digest = str(members.pop("meta")), str(members.pop(DIGEST_MEMBER))
    return meta_json, digest, members


def load_cached(path: str | Path, key: str, times: np.ndarray) -> Reference:
    """The reference stored at ``path``; :class:`CacheRefused` unless it is a regular file
    (:class:`NotRegularFile`), whole, matches the SHA-256 it carries (:class:`ContentCheckFailed`),
    carries ``key`` and holds finite samples at ``times`` (s, the expected output grid)."""
    meta_json, digest, arrays = _read_members(path)
    if content_digest(meta_json, arrays) != digest:
        raise ContentCheckFailed(f"{path}: its arrays or metadata do not match its SHA-256")
    try:
        meta = json.loads(meta_json)
    except ValueError as exc:
        raise CacheRefused(f"{path}: unreadable metadata ({exc})") from exc
    if not isinstance(meta, dict) or meta.get("key") != key:
        raise CacheRefused(f"{path}: stored for another scene, horizon or code version")
    t, R, u, p, scales = (arrays[k] for k in ("t", "R", "u", "p", "scales"))
    n = len(times)
    shapes_ok = (
        t.shape == (n,) and R.shape == (n, 3) and u.shape == (n, 4) and p.ndim == 2
        and p.shape[0] == n and scales.shape == (2,)
    )  # fmt: skip
    if not shapes_ok:
        raise CacheRefused(f"{path}: samples of the wrong shape")
    if not all(np.all(np.isfinite(a)) for a in (t, R, u, p, scales)) or np.any(scales <= 0):
        raise CacheRefused(f"{path}: non-finite samples or scales")
    if not np.allclose(t, times, rtol=0, atol=metrics.SAMPLE_TIME_ATOL):
        raise CacheRefused(f"{path}: samples not on the output grid")
    info = meta.get("info")
    if not isinstance(info, dict) or not isinstance(info.get("error_estimate"), float):
        raise CacheRefused(f"{path}: no error estimate")
    samples = RefSamples(t, R, u, p, float(scales[0]), float(scales[1]))
    return Reference(samples, info)


def store_cached(path: str | Path, key: str, ref: Reference, times: np.ndarray) -> None:
    """Write ``ref`` to ``path`` atomically; the file is read back (:func:`load_cached`) before it
    replaces anything."""
    write_bytes(path, _encode(ref, key), check=lambda tmp: load_cached(tmp, key, times))


def obtain_reference(
    scene: Scene,
    t_end: float,
    executor: Executor,
    cache_dir: str | Path | None = None,
    say: Callable[[str], None] = lambda _msg: None,
) -> Reference:
    """The reference of ``scene`` over ``t_end``: from the cache when it holds it, else computed
    in ``executor`` and stored. ``info["cache"]`` says which (and why a file was refused)."""
    directory = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    key = cache_key(scene, t_end)
    path = cache_path(directory, key)
    times = scene.output.with_t_end(t_end).times()
    cache: dict[str, Any] = {"key": key, "path": str(path)}
    try:
        ref = load_cached(path, key, times)
    except FileNotFoundError:
        cache["status"] = "computed (not in the cache)"
    except ContentCheckFailed as exc:
        cache["status"] = f"computed (cache file refused: {exc})"
        _warn(f"sweep reference cache entry {path} failed its content check; recomputing")
    except NotRegularFile as exc:
        cache["status"] = f"computed (cache file refused: {exc})"
        _warn(f"sweep reference cache entry {exc}; not read, recomputing")
    except CacheRefused as exc:
        cache["status"] = f"computed (cache file refused: {exc})"
        say(f"  reference cache refused, recomputing: {exc}")
    else:
        say(f"  reference from the cache: {path}")
        return Reference(ref.samples, {**ref.info, "cache": {**cache, "status": "cached"}})
    say(f"reference: {REFERENCE_METHOD} rtol {REFERENCE_RTOL:g}, {t_end:g} s")
    ref = compute_reference(scene, t_end, executor)
    try:
        store_cached(path, key, ref, times)
    except OSError as exc:  # a read-only or full cache directory, a directory at the name
        cache["status"] += f"; not stored ({exc})"
        _warn(f"sweep reference not stored in the cache: {exc}")
    return Reference(ref.samples, {**ref.info, "cache": cache})


__all__ = [
    "CACHE_ENV",
    "CacheRefused",
    "ContentCheckFailed",
    "NotRegularFile",
    "Reference",
    "ReferenceCacheWarning",
    "cache_key",
    "cache_path",
    "code_fingerprint",
    "compute_reference",
    "content_digest",
    "default_cache_dir",
    "load_cached",
    "obtain_reference",
    "reference_run",
    "reference_task",
    "scene_fingerprint",
    "store_cached",
]
