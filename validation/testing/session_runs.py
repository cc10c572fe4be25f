"""The pytest plugin's runs: each scene file (or judge file, or scene given to the fixture) run
once per session, whatever the distribution between pytest-xdist workers.

:class:`SessionRuns` caches a run by the scene's content and the plant settings (a judge by the
judge file's and the trajectory file's contents). Under pytest-xdist a run is shared between the
session's workers through the session's temporary directory: under a file lock, the first worker
runs it and stores it signed with the session's secret (HMAC-SHA256, :func:`_store_signed`), the
others load it; a stored run whose signature does not match (planted, altered, another session's)
is never unpickled (:func:`_load_signed`) and the worker runs the scene itself. Output goes to
``--tumble-out DIR/<slug of the file's path>`` or to the session's temporary directory.

A run has BLAS on one thread for the run only (:func:`validation.runs.environment.one_blas_thread`,
the pools given back as they were). A run that cannot be made is its one-line reason (a ``str``),
not an exception. Like the plugin, this module imports pytest and the standard library only; the
plants are imported when the first run is made. Files are read with :func:`read_head`, which never
blocks on a FIFO or a device.
"""

from __future__ import annotations

import errno
import hashlib
import hmac
import os
import stat
import tempfile
from pathlib import Path
from typing import Any

import pytest

SHARE_KEY = "tumble_share_key"
"""The ``workerinput`` entry that carries the session's secret for shared runs (hex)."""


def read_head(path: Path, limit: int) -> bytes:
    """At most ``limit`` bytes of the regular file at ``path``: opened without blocking (a FIFO
    or a device), ``OSError`` for anything that is not a regular file."""
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise OSError(errno.EINVAL, "not a regular file", str(path))
        return os.read(fd, limit)
    finally:
        os.close(fd)


def _store_signed(store: Path, secret: bytes, data: bytes) -> None:
    """``data`` at ``store`` behind its HMAC-SHA256 under ``secret`` (a temporary file, renamed)."""
    tmp = store.with_suffix(f".{os.getpid()}.tmp")
    tmp.write_bytes(hmac.new(secret, data, hashlib.sha256).digest() + data)
    os.replace(tmp, store)


def _load_signed(store: Path, secret: bytes) -> Any:
    """The run another worker of this session stored at ``store``, or None when there is none, it
    is not a regular file, or its signature does not match (never unpickled then: a pickle
    planted by anyone without the session's secret is not trusted)."""
    # deferred: ~2 ms (python -X importtime) in every pytest session; only xdist's shared runs
    import pickle

    if not secret:
        return None
    try:
        blob = read_head(store, 1 << 30)
    except OSError:
        return None
    mac, data = blob[:32], blob[32:]
    if len(mac) < 32 or not hmac.compare_digest(
        mac, hmac.new(secret, data, hashlib.sha256).digest()
    ):
        return None
    return pickle.loads(data)


class SessionRuns:
    """Runs of scene files for one pytest session, cached by scene content and plant settings;
    the cache key of each run made is appended to ``runs`` (the plugin's ``RUNS``)."""

    def __init__(self, config: pytest.Config, runs: list[str]) -> None:
        self.config = config
        self.runs = runs
        self._plants: tuple[str, ...] | None = None
        self._memo: dict[str, Any] = {}
        self._dirs: dict[str, str] = {}
        self.keep: list[Any] = []

    def plants(self) -> tuple[str, ...]:
        """The chosen plants, checked (``ValueError`` naming ``--tumble-plants``)."""
        if self._plants is None:
            import warnings

            from mj_bridge.plants import installed_plants, parse_plants, plugin_errors

            for err in plugin_errors():  # one line each in pytest's warnings summary; others run
                warnings.warn(f"tumble: {err}", pytest.PytestWarning, stacklevel=1)
            text = self.config.getoption("tumble_plants")
            try:
                chosen = parse_plants(text) if text else installed_plants()
            except ValueError as exc:
                raise ValueError(f"--tumble-plants: {exc}") from None
            if len(chosen) < 2:
                raise ValueError(
                    f"--tumble-plants: give at least two plants to compare (got {text!r})"
                )
            self._plants = tuple(chosen)
        return self._plants

    def key(self, content: bytes, plants: tuple[str, ...], t_end: float | None) -> str:
        h = hashlib.sha256(content)
        h.update(repr((plants, t_end, self.config.getoption("tumble_out"))).encode())
        return h.hexdigest()

    def _out_dir(self, path: Path | None, key: str, label: str) -> Path:
        if path is not None:
            try:
                rel = path.resolve().relative_to(Path(self.config.rootpath).resolve())
            except ValueError:
                rel = Path(path.name)
            label = rel.with_suffix("").as_posix()
        from validation.runs.outputs import slug

        name = slug(label, "scene file")
        if self._dirs.get(name, key) != key:
            name = f"{name}-{key[:8]}"
        self._dirs[name] = key
        out = self.config.getoption("tumble_out")
        if out:
            return Path(out) / name
        return self._basetemp() / "tumble" / name

    def _basetemp(self) -> Path:
        factory = getattr(self.config, "_tmp_path_factory", None)
        if factory is not None:
            return Path(factory.getbasetemp())

        return Path(tempfile.mkdtemp(prefix="tumble-"))

    def _shared_dir(self) -> Path | None:
        """Under pytest-xdist: a directory every worker of this session sees."""
        if not hasattr(self.config, "workerinput"):
            return None
        d = self._basetemp().parent / "tumble-runs"
        d.mkdir(parents=True, exist_ok=True)
        return d

    def outcome(self, path: Path) -> Any:
        """The run of the scene file ``path`` on the session's plants (ValidationResult, or the
        one-line reason it could not run)."""
        plants = self.plants()
        try:
            content = read_head(path, 1 << 20)
        except OSError as exc:  # not a regular file (a FIFO is never opened to block)
            return f"ValueError: scene: cannot read {str(path)!r} ({exc.strerror or exc})"
        return self.run(content, plants, None, path=path, scene=None)

    def judged(self, path: Path, spec: Any) -> Any:
        """The judge of the ``[judge]`` file ``path`` (its checked ``spec``): a ValidationResult,
        or the one-line reason it could not run; once per session per file content and
        trajectory file content."""
        try:
            h = hashlib.sha256(read_head(path, 1 << 20))
            h.update(read_head(spec.trajectory, 1 << 30))
        except OSError as exc:
            return f"ValueError: judge: cannot read {str(path)!r} ({exc.strerror or exc})"
        key = h.hexdigest()
        if key in self._memo:
            return self._memo[key]
        from validation.external.judge import judge
        from validation.runs.environment import one_blas_thread

        self.runs.append(key)
        out = self._out_dir(path, key, "judge")
        try:
            with one_blas_thread():  # the session's pools as they were after (module docstring)
                res = judge(
                    str(spec.scene),
                    spec.trajectory,
                    out,
                    label=spec.label,
                    plants=None if spec.reference is not None else (spec.plants or self.plants()),
                    reference=spec.reference,
                    t_end=spec.t_end,
                    up_to_file_end=spec.up_to_file_end,
                )
        except (ValueError, OSError) as exc:
            res = f"{type(exc).__name__}: {exc}".splitlines()[0]
        self._memo[key] = res
        return res

    def run(
        self,
        content: bytes,
        plants: tuple[str, ...],
        t_end: float | None,
        path: Path | None,
        scene: Any,
        label: str = "scene",
    ) -> Any:
        key = self.key(content, plants, t_end)
        if key in self._memo:
            return self._memo[key]
        shared = self._shared_dir()
        if shared is None:
            res = self._run(key, plants, t_end, path, scene, label)
        else:
            res = self._run_shared(shared, key, plants, t_end, path, scene, label)
        self._memo[key] = res
        return res

    def _run_shared(self, shared: Path, key: str, *args: Any) -> Any:
        store = shared / f"{key}.pickle"
        try:
            import fcntl
        except ImportError:  # pragma: no cover - not POSIX: each worker runs what it is given
            return self._run(key, *args)
        secret = bytes.fromhex(self.config.workerinput.get(SHARE_KEY, ""))
        import pickle

        with open(shared / f"{key}.lock", "wb") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            try:
                shared_res = _load_signed(store, secret)
                if shared_res is not None:
                    return shared_res
                res = self._run(key, *args)
                _store_signed(store, secret, pickle.dumps(res))
                return res
            finally:
                fcntl.flock(lock, fcntl.LOCK_UN)

    def _run(
        self,
        key: str,
        plants: tuple[str, ...],
        t_end: float | None,
        path: Path | None,
        scene: Any,
        label: str,
    ) -> Any:
        from validation.runs.environment import one_blas_thread
        from validation.validate import run_validation

        self.runs.append(key)
        out = self._out_dir(path, key, label)
        try:
            with one_blas_thread():  # the session's pools as they were after (module docstring)
                return run_validation(
                    scene if scene is not None else path, out, t_end=t_end, plants=",".join(plants)
                )
        except (ValueError, OSError) as exc:
            return f"{type(exc).__name__}: {exc}".splitlines()[0]
