"""Compile the plants' numba kernels before a run, and say so: the first run on a machine.

numba compiles the compiled kernels on their first call and keeps the machine code in its on-disk
cache (``*.nbi`` / ``*.nbc`` files in ``__pycache__`` beside the sources, or ``$NUMBA_CACHE_DIR``);
later processes load it in well under a second. On a fresh install the first ``tumble validate``
would otherwise print nothing while it compiles and then sit at its first percent.

:func:`warm_up` (called by ``tumble validate`` before the plants run):

1. finds the kernels whose cache is cold: first the kernel's two halves
   (:func:`kernel_halves_state`, importing nothing but the kernel); when they are cold so is every
   plant (each embeds the kernel), otherwise numba's own index of each compiled function of the
   plants' modules is read (:func:`cold_engines`, :func:`cache_state`). Nothing is compiled to
   tell; when every one is cached it returns at once, silently;
2. otherwise says what it compiles and that it happens once per machine, then compiles each cold
   stage by calling the plants' public entry points (:class:`analytic.fast.FastModel`, each plant's
   ``simulate`` for one output interval), reporting each stage with its wall time:

   * the analytic kernel's two halves (:mod:`analytic.kernel.halves`) at the same time: stages
     1-6 in a *helper process*, the scene's solve here;
   * beside them, what calls the halves by address and so compiles without them
     (:mod:`analytic.kernel.abi`): in the helper, before stages 1-6, the MuJoCo plant's stage
     (:func:`compile_stage`), then here, after the solve, the MuJoCo native callback, which links
     that stage from disk; in the helper, after stages 1-6, the analytic plant's compiled
     right-hand side (its work and impulse rates pasted in); then the kernel's entry point, here;
   * then each plant for one output interval (the MuJoCo plant in the helper), which finds
     everything on disk and compiles whatever else its settings need.

   Around a run of both the MuJoCo and the analytic plant (:func:`warming`, what ``tumble
   validate`` uses) the analytic plant's own stages are left to the helper instead: it compiles
   the right-hand side after stages 1-6 while the plants already run, holding its
   compile lock (:mod:`analytic.kernel.compile_lock`) so that the analytic plant waits for them;
   with Pinocchio too, the helper then compiles the Pinocchio stage, holding its lock likewise.

   numba holds the GIL while it compiles, so threads would not overlap; a second process does, and
   it leaves its result in the on-disk cache, where this process loads it. Used when two CPUs are
   free to this process and the cache is writable (otherwise everything is compiled here, in
   order). The helper is forked from this process once numba is set up here (it inherits
   numba's registries and the imported kernel), or, where forking is not safe, spawned.

   Every compile goes through :class:`analytic.kernel.jit.LeanCompiler`, which leaves out numba
   passes the kernel does not need and resolves each scalar operation's type once per compile.

A failure while warming up is never fatal: the plant's own run compiles what is missing and
reports its own error.
"""

from __future__ import annotations

import contextlib
import dataclasses
import enum
import os
import sys
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from analytic.scene import Scene

ANALYTIC, MUJOCO, PINOCCHIO = "analytic", "mujoco", "pinocchio"

EXPECTED_COLD_S = 5
"""What the message announces: the compile time of every kernel on a 2-core machine, s (measured:
kernels ready 2.6-4.2 s after the start for two plants, the analytic plant's last kernels done
about 1.3 s later)."""

ENGINE_MODULES: dict[str, tuple[str, ...]] = {
    ANALYTIC: ("analytic.",),
    MUJOCO: ("mj_bridge.",),
    PINOCCHIO: ("mj_bridge.pinocchio",),
}
"""Module-name prefixes of each engine's compiled functions (the longest matching prefix wins:
``mj_bridge.pinocchio_plant`` belongs to Pinocchio, the rest of ``mj_bridge`` to MuJoCo)."""

ENTRY_MODULES: dict[str, tuple[str, ...]] = {
    ANALYTIC: ("analytic.fast", "analytic.simulate", "analytic.fast_rhs"),
    MUJOCO: ("mj_bridge.simulate", "mj_bridge.native"),
    PINOCCHIO: ("mj_bridge.pinocchio_plant",),
}
"""Imported before the caches are inspected, so that every compiled function of a plant exists
(some are imported lazily by the plants). A module that no longer exists is skipped."""

TITLES = {
    "system": "the analytic kernel's stages 1-6 (analytic.kernel.system)",
    "solve": "the analytic kernel's solve (analytic.kernel)",
    "rhs": "the analytic plant's compiled right-hand side (analytic.compiled_rhs)",
    "stage": "the MuJoCo plant's compiled stage (mj_bridge.fast_stage)",
    "native": "the MuJoCo native controller callback (mj_bridge.native)",
    "kernel": "the analytic kernel (analytic.fast)",
    ANALYTIC: "the analytic plant's right-hand side",
    MUJOCO: "the MuJoCo native controller stage (mj_bridge.native, fast_stage)",
    PINOCCHIO: "the Pinocchio stage (mj_bridge.pinocchio_plant)",
}


@dataclass(frozen=True)
class StageTime:
    """One compiled stage: its title, wall time (s), and where it ran ("here" or "helper")."""

    title: str
    seconds: float
    where: str = "here"
    error: str = ""


@dataclass(frozen=True)
class WarmupResult:
    """What :func:`warm_up` did.

    Attributes:
        cold: the engines whose kernels were not cached (empty: nothing was compiled).
        stages: each stage compiled, in the order it finished.
        seconds: wall time of the whole warm-up, s.
        concurrent: whether a helper process compiled a stage alongside this one.
        cached: whether numba can keep the result on disk (False: every process compiles).
    """

    cold: tuple[str, ...] = ()
    stages: tuple[StageTime, ...] = ()
    seconds: float = 0.0
    concurrent: bool = False
    cached: bool = True


# ----------------------------------------------------------------------------------------------
# Is the cache cold?
# ----------------------------------------------------------------------------------------------


def _dispatchers(prefixes: Iterable[str], exclude: Iterable[str] = ()) -> list[Any]:
    """numba dispatchers and C callbacks (``cfunc``) defined at module level in the loaded modules
    named by ``prefixes``."""
    try:
        from numba.core.ccallback import CFunc
        from numba.core.dispatcher import Dispatcher
    except ImportError:  # pragma: no cover - numba is a dependency
        return []
    prefixes, exclude = tuple(prefixes), tuple(exclude)
    found, seen = [], set()
    for name, mod in list(sys.modules.items()):
        if not name.startswith(prefixes) or (exclude and name.startswith(exclude)):
            continue
        for value in list(vars(mod).values()):
            if isinstance(value, CFunc):  # a C callback (the kernel's halves)
                pass
            elif not isinstance(value, Dispatcher) or value.targetoptions.get("inline") == "always":
                continue  # an inlined stage is compiled into its callers, never on its own
            if id(value) not in seen:
                seen.add(id(value))
                found.append(value)
    return found


class CacheState(enum.Enum):
    """What numba's disk cache holds for one compiled function."""

    CACHED = "cached"  # compiled code for this machine, this numba and this source
    STALE = "stale"  # an index, but no entry for them: the source, numba or the CPU changed
    ABSENT = "absent"  # no index: never compiled here (or a function no run calls)
    NO_CACHE = "no cache"  # no writable cache directory: compiled in every process
    UNKNOWN = "unknown"  # numba's cache layout is not the one read here


def cache_state(dispatcher: Any) -> CacheState:
    """What numba's on-disk cache holds for ``dispatcher`` (any signature).

    Reads the cache index the way numba does (its index key: the target machine, the bytecode and
    closure hashes; numba treats an index written for another source file or numba version as
    empty), without compiling or loading code."""
    try:
        from numba.core.caching import Cache

        cache = dispatcher._cache
        if not isinstance(cache, Cache):
            return CacheState.NO_CACHE
        index_file = cache._cache_file
        if not os.path.exists(index_file._index_path):
            return CacheState.ABSENT
        target = getattr(dispatcher, "targetctx", None)  # a C callback: its target descriptor's
        target = target or dispatcher._targetdescr.target_context
        want = cache._index_key(None, target.codegen())[1:]
        found = any(key[1:] == want for key in index_file._load_index())
        return CacheState.CACHED if found else CacheState.STALE
    except Exception:
        return CacheState.UNKNOWN


def engine_is_cold(states: Sequence[CacheState]) -> bool:
    """An engine's kernels must be compiled when any of its functions is stale, uncached or of
    unknown state, or when none of them was ever compiled here. A function without an index among
    cached ones is one no run calls (a public helper the plants do not use): it does not count."""
    if not states:
        return False
    if any(s in (CacheState.STALE, CacheState.NO_CACHE, CacheState.UNKNOWN) for s in states):
        return True
    return all(s is CacheState.ABSENT for s in states)


def _import_entries(engines: Iterable[str]) -> None:
    import importlib

    for e in engines:
        for name in ENTRY_MODULES.get(e, ()):
            try:
                importlib.import_module(name)
            except ModuleNotFoundError as exc:  # renamed or removed: its functions are elsewhere
                if exc.name != name:
                    raise


def _engine_dispatchers(engine: str) -> list[Any]:
    longer = [p for e, ps in ENGINE_MODULES.items() if e != engine for p in ps]
    own = ENGINE_MODULES[engine]
    exclude = [p for p in longer if any(p.startswith(o) and p != o for o in own)]
    return _dispatchers(own, exclude)


def cold_engines(engines: Sequence[str]) -> tuple[str, ...]:
    """The engines among ``engines`` with at least one compiled function not in numba's disk cache
    (or whose state cannot be told), in the order given. Imports the plants' modules."""
    try:
        import numba  # noqa: F401
    except ImportError:  # pragma: no cover - without numba nothing is compiled
        return ()
    _import_entries(engines)
    return tuple(e for e in engines if engine_is_cold(_grouped_states(_engine_dispatchers(e))))


def _grouped_states(dispatchers: Sequence[Any]) -> list[CacheState]:
    """One state per cache index file: the variants one factory makes (a compiled caller per
    solve, closing over different constants) share an index, and a run compiles only the variant
    its scene needs, so the index counts as cached when any variant is."""
    groups: dict[Any, list[CacheState]] = {}
    for d in dispatchers:
        try:
            key = d._cache._cache_file._index_path
        except AttributeError:
            key = id(d)
        groups.setdefault(key, []).append(cache_state(d))
    return [
        CacheState.CACHED if CacheState.CACHED in states else states[0]
        for states in groups.values()
    ]


WARM_STAMP = "tumble-kernels-warm.json"
"""A file beside numba's cache of the kernel (:func:`analytic.kernel.cache_dir.kernel_cache_dir`)
listing the :func:`warm_key` values for which every kernel a run needs is cached: written when
:func:`cold_engines` finds nothing cold, or after a warm-up whose every stage compiled (it runs the
plants' own entry points). A run whose key is listed skips the check, which imports numba, MuJoCo
and every compiled module (about half a second) in the process that then starts the plants, where
each plant imports what it needs side by side. Should the stamp outlive the cache (a deleted
``__pycache__`` of another package), the plants compile what is missing themselves, unannounced."""

STAMP_KEYS_KEPT = 16  # keys a stamp keeps (engines x weighting x interpreters sharing one tree)


def _cpu_identity() -> str:
    """What tells this machine's CPU from another for compiled code (numba keys its cache on the
    CPU's name and features): the model and feature flags from ``/proc/cpuinfo``, else
    :func:`platform.processor`."""
    import platform

    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            lines = f.read().split("\n\n", 1)[0].splitlines()
        wanted = ("model name", "flags", "Features", "CPU implementer", "CPU part")
        return "\n".join(line for line in lines if line.split(":", 1)[0].strip() in wanted)
    except OSError:
        return f"{platform.machine()} {platform.processor()}"


def _source_roots() -> list[Path]:
    """The directories of the packages that hold compiled code."""
    import analytic
    import mj_bridge

    return [Path(pkg.__file__).resolve().parent for pkg in (analytic, mj_bridge)]


def warm_key(engines: Sequence[str], scene: Scene) -> str:
    """The hash under which a warm cache is stamped: every source of the packages that hold
    compiled code (:mod:`analytic`, :mod:`mj_bridge`), the versions of numba, llvmlite and
    Python, the CPU, the ``NUMBA_*`` settings, the engines and the scene's weighting (which
    selects the compiled solve). Any change makes the next run check numba's cache again."""
    import hashlib
    import platform
    from importlib import metadata

    h = hashlib.sha256()
    for root in _source_roots():
        for path in sorted(root.rglob("*.py")):
            h.update(str(path.relative_to(root.parent)).encode())
            h.update(path.read_bytes())
    for dist in ("numba", "llvmlite"):
        try:
            h.update(f"{dist} {metadata.version(dist)}".encode())
        except metadata.PackageNotFoundError:
            h.update(f"{dist} absent".encode())
    h.update(f"{sys.version} {platform.machine()}".encode())
    h.update(_cpu_identity().encode())
    h.update(repr(sorted((k, v) for k, v in os.environ.items() if k.startswith("NUMBA_"))).encode())
    h.update(repr((sorted(engines), str(scene.control.weighting))).encode())
    return h.hexdigest()


def _stamp_path() -> Path | None:
    from analytic.kernel.cache_dir import kernel_cache_dir

    where = kernel_cache_dir()
    return where / WARM_STAMP if where is not None else None


def _stamped_keys() -> list[str]:
    import json

    path = _stamp_path()
    try:
        from analytic.safe_files import read_regular  # never blocks (a FIFO there)

        keys = json.loads(read_regular(path, 1 << 20))["warm_keys"] if path else []
    except (OSError, ValueError, KeyError, TypeError):
        return []
    return [k for k in keys if isinstance(k, str)] if isinstance(keys, list) else []


def is_stamped_warm(key: str) -> bool:
    """Whether a check of numba's cache found every kernel of ``key`` cached before."""
    return key in _stamped_keys()


def stamp_warm(key: str) -> None:
    """Record ``key`` as warm (atomically; a stamp that cannot be written is no error)."""
    import json

    from validation.atomic import write_text

    path = _stamp_path()
    if path is None:
        return
    from analytic.kernel import cache_check

    cache_check.record()  # the kernels on disk now are the ones numba wrote: their hashes kept
    kept = [k for k in _stamped_keys() if k != key][-(STAMP_KEYS_KEPT - 1) :]
    keys = [*kept, key]
    try:
        write_text(path, json.dumps({"warm_keys": keys}, indent=1) + "\n")
    except OSError:
        pass


def kernel_halves_state(scene: Scene) -> list[CacheState] | None:
    """What numba's disk cache holds for the two halves of the kernel ``scene`` evaluates
    (:mod:`analytic.kernel.halves`: stages 1-6 and the solve its :class:`analytic.fast.FastModel`
    uses), read without compiling; None when the kernel does not serve the scene (numba absent,
    or a weighting it does not compile). Imports only the analytic side."""
    from analytic.kernel.entry import Solver

    solver = _compiled_solver(scene)
    if solver is None:
        return None
    from analytic.kernel import halves

    minv2_solve = solver is Solver.MINV2
    return [cache_state(halves.callback(h, minv2_solve)) for h in halves.KernelHalf]


def cache_writable(engines: Sequence[str]) -> bool:
    """Whether numba keeps these engines' compiled code on disk (a writable cache directory)."""
    from numba.core.caching import Cache

    return all(isinstance(d._cache, Cache) for e in engines for d in _engine_dispatchers(e))


# ----------------------------------------------------------------------------------------------
# Compiling
# ----------------------------------------------------------------------------------------------


def compile_kernel(scene: Scene) -> None:
    """The analytic kernel through its public entry point (one evaluation of the dynamics)."""
    import numpy as np

    from analytic import fast

    if fast.available():
        q = np.ascontiguousarray(scene.initial.q0(), dtype=float)
        qd = np.ascontiguousarray(scene.initial.qdot0(), dtype=float)
        fast.FastModel(scene).acceleration(0.0, q, qd)


def compile_kernel_half(scene: Scene, half: str) -> None:
    """One half of the analytic kernel (:func:`analytic.fast.compile_half`): two processes
    compile one each at the same time, and :func:`compile_kernel` then only joins them."""
    from analytic import fast

    fast.compile_half(scene, half)


def _compiled_solver(scene: Scene) -> Any:
    """The solve (:class:`analytic.kernel.entry.Solver`) the scene's compiled kernel uses, read
    from its :class:`analytic.fast.FastModel` without compiling anything (``ip`` untouched); None
    when the kernel does not serve the scene (numba absent, or a weighting it does not compile)."""
    from analytic import fast

    if not fast.available():
        return None
    fm = fast.FastModel(scene)
    return fm.solver if fm.compiled else None


def compile_rhs(scene: Scene) -> None:
    """The analytic plant's compiled right-hand side (the stepping loop's C callback and the
    function it calls, :func:`analytic.compiled_stepping.prepare`) without running it: it calls
    the kernel's halves by address, so it compiles while they are still being compiled."""
    solver = _compiled_solver(scene)
    if solver is not None:
        from analytic import compiled_stepping

        compiled_stepping.prepare(int(solver))


def compile_stage(scene: Scene) -> None:
    """The MuJoCo plant's compiled stage for the scene's solve (:func:`mj_bridge.fast_stage.
    compile_for`), without running it: the native callback links it (compiled after it, it
    finds it on disk) and the Python callback calls it."""
    solver = _compiled_solver(scene)
    if solver is not None:
        from mj_bridge import fast_stage

        fast_stage.compile_for(solver)


def compile_native(scene: Scene) -> None:
    """The MuJoCo plant's native controller callback (:func:`mj_bridge.native.compiled`) for the
    scene's solve, without running it (it calls the kernel's halves by address)."""
    solver = _compiled_solver(scene)
    if solver is not None:
        from mj_bridge import native

        if native.available():
            native.compiled(solver)


def compile_plant(scene: Scene, engine: str) -> None:
    """One output interval of ``engine``'s plant (its default settings): what the run calls first,
    with the argument types the run uses, so every kernel it needs is compiled and cached."""
    from mj_bridge.plants import plant

    pl = plant(engine)
    pl.simulate(scene, pl.default_settings(scene), t_end=1.0 / scene.output.rate)


def _timed(title: str, fn: Callable[[], None], where: str = "here") -> StageTime:
    t0 = time.perf_counter()
    try:
        fn()
        error = ""
    except KeyboardInterrupt:
        raise
    except Exception as exc:  # the plant's own run will compile and report
        error = f"{type(exc).__name__}: {exc}".splitlines()[0]
    return StageTime(title, time.perf_counter() - t0, where, error)


HELPER_STAGES: dict[str, Callable[[Scene], None]] = {
    "stage": compile_stage,
    "system": lambda scene: compile_kernel_half(scene, "system"),
    "rhs": compile_rhs,
}
"""What the helper process can compile before the ``go`` line, by :data:`TITLES` key."""


def _helper_main() -> None:  # pragma: no cover - runs in the helper process
    """A spawned helper process (``python -c``): import the kernel's modules, read its job
    (pickled ``(scene, engine, first, held)``, after a line with its size; an empty line: nothing
    to do) from stdin, and run it (:func:`_run_job`): one JSON line per stage on stdout, the
    ``go`` line read from stdin."""
    import pickle
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent stops it; no second traceback
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    import importlib

    for name in ("analytic.aux_rates", "analytic.fast"):  # what every job compiles first,
        importlib.import_module(name)  # imported while the parent still checks numba's cache

    line = sys.stdin.buffer.readline()
    if not line.strip():  # no job: the cache was warm after all
        return
    size = int(line)
    job = pickle.loads(sys.stdin.buffer.read(size))
    _run_job(job, sys.stdout.buffer, sys.stdin.buffer)


def _forked_main(
    job: tuple, fds: dict[str, int], parents: Sequence[int]
) -> None:  # pragma: no cover
    """A forked helper process: close its copies of the parent's pipe ends (so that the ``go``
    pipe ends when the parent does), send stderr into its pipe, and run the job
    (:func:`_run_job`)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent stops it; no second traceback
    for fd in parents:
        os.close(fd)
    os.dup2(fds["stderr"], 2)
    with (
        open(fds["stdout"], "wb", buffering=0) as out,
        open(fds["stdin"], "rb") as inp,
    ):
        _run_job(job, out, inp)


def _run_job(job: tuple, out: Any, inp: Any) -> None:  # pragma: no cover - in the helper
    """The helper's job ``(scene, engine, first, held)``: take the compile locks named in
    ``held`` (lock name -> the stage after which it is let go), compile each stage named in
    ``first`` (:data:`HELPER_STAGES`) at once, writing each one's time as one JSON line to
    ``out``; then, for an engine, wait for the ``go`` line on ``inp`` (what the engine's plant
    embeds is on disk by then), run its plant for one interval (:func:`compile_plant`) and write
    its time."""
    import json

    scene, engine, first, held = job
    from analytic.kernel import compile_lock

    for lock in held:  # before anything else: a plant that needs one waits for it
        compile_lock.hold(lock)

    def compiled(name: str) -> None:  # what the locks held until ``name`` guard is on disk
        for lock, until in held.items():
            if until == name:
                compile_lock.release(lock)

    def say(st: StageTime) -> None:
        out.write(json.dumps(dataclasses.asdict(st)).encode() + b"\n")
        out.flush()

    for name in first:
        say(_timed(TITLES[name], lambda name=name: HELPER_STAGES[name](scene), "helper process"))
        compiled(name)
    if engine is None:
        return
    _import_entries([engine])  # the imports overlap the parent's compiling
    if inp.readline().strip() != b"go":
        return
    say(_timed(TITLES[engine], lambda: compile_plant(scene, engine), where="helper process"))
    compiled(engine)


def _numba_set_up() -> None:
    """numba's compiler set up in this process before a helper is forked from it: its registries
    of typing and lowering rules (numba's documented ``refresh``, done by the first compile of a
    process, about half a second), which the helper then inherits instead of loading again."""
    try:
        from numba.core.registry import cpu_target

        cpu_target.target_context.refresh()
    except Exception:  # pragma: no cover - another numba: the first compile does it
        pass


class _ForkedProcess:
    """The part of :class:`subprocess.Popen` a :class:`_Helper` uses, for a process forked with
    :mod:`multiprocessing` (its pipes made here)."""

    def __init__(self, process: Any, stdin: Any, stdout: Any, stderr: Any) -> None:
        self.process, self.stdin, self.stdout, self.stderr = process, stdin, stdout, stderr

    def poll(self) -> int | None:
        return self.process.exitcode

    def wait(self, timeout: float | None = None) -> int | None:
        self.process.join(timeout)
        return self.process.exitcode

    def kill(self) -> None:
        self.process.kill()


class _Helper:
    """A helper process that compiles into numba's disk cache; :meth:`send` gives it its job: the
    stages named in ``first`` at once (:meth:`next` waits for each in turn), then ``engine``'s
    plant after :meth:`go` (:meth:`result`).

    Forked from this process when :meth:`send` gives the job, where forking is safe
    (:func:`validation.workers.can_fork`): numba is imported and set up here by then (the cache
    check needs it, and this process compiles too), and the child inherits that instead of
    starting an interpreter, importing and setting numba up again (about a CPU-second, on a
    machine whose CPUs are all busy compiling). Elsewhere it is spawned at once (``python -c``, so
    no ``__main__`` of the caller is re-imported), its imports overlapping the cache check."""

    def __init__(self, fork: bool | None = None) -> None:
        from validation import workers

        self.engine: str | None = None
        self.first: list[str] = []
        self.fork = workers.can_fork() if fork is None else fork
        self.proc: Any = None if self.fork else self._spawn()

    @staticmethod
    def _spawn() -> Any:
        import subprocess

        code = "from validation.warmup import _helper_main; _helper_main()"
        env = dict(os.environ)  # this copy of the project first, wherever it was imported from
        root = str(Path(__file__).resolve().parents[1])
        env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
        # cwd: ``-c`` puts the working directory first on sys.path, and a source checkout there
        # (the README's ``pip install .`` in a clone) would be compiled instead of this copy.
        return subprocess.Popen(
            [sys.executable, "-c", code],
            env=env,
            cwd=root,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
        )

    def _forked(self, job: tuple) -> _ForkedProcess:
        import multiprocessing as mp

        _numba_set_up()
        from validation.workers import flush_std_streams

        (in_r, in_w), (out_r, out_w), (err_r, err_w) = os.pipe(), os.pipe(), os.pipe()
        child = {"stdin": in_r, "stdout": out_w, "stderr": err_w}
        parent = [in_w, out_r, err_r]
        flush_std_streams()  # the child must not print this buffer again
        process = mp.get_context("fork").Process(
            target=_forked_main, args=(job, child, parent), name="tumble-compile", daemon=True
        )
        try:
            process.start()
        finally:
            for fd in child.values():
                os.close(fd)
        ends = (open(parent[0], "wb"), open(parent[1], "rb"), open(parent[2], "rb"))
        return _ForkedProcess(process, *ends)  # stop() closes the ends

    def send(
        self,
        scene: Scene,
        engine: str | None,
        first: Sequence[str],
        held: dict[str, str] | None = None,
    ) -> None:
        """The job: compile the stages named in ``first`` now, then ``engine``'s plant after
        :meth:`go` (None: no plant); ``held``: compile locks (:mod:`analytic.kernel.
        compile_lock`) it takes at once, each kept until the stage (of ``first``, or the engine)
        it maps to is compiled."""
        import pickle

        from validation import workers

        self.engine, self.first = engine, list(first)
        job = (scene, engine, self.first, dict(held or {}))
        if self.fork and workers.can_fork():
            self.proc = self._forked(job)
            return
        if self.proc is None:  # forking stopped being safe since (a thread started): spawned
            self.fork, self.proc = False, self._spawn()
        data = pickle.dumps(job)
        try:
            self.proc.stdin.write(b"%d\n" % len(data) + data)
            self.proc.stdin.flush()
        except OSError:
            pass

    def next(self) -> StageTime:
        """The next stage of ``first``, once the helper has compiled it (waits for its line)."""
        import json

        title = TITLES[self.first.pop(0)]
        line = self.proc.stdout.readline()
        try:
            return StageTime(**json.loads(line.decode()))
        except (ValueError, TypeError):
            return StageTime(title, 0.0, "helper process", "helper failed")

    def go(self) -> None:
        try:
            self.proc.stdin.write(b"go\n")
            self.proc.stdin.close()
        except OSError:
            pass

    def result(self) -> StageTime:
        import json

        # read through the same buffered pipe as next(): a line the helper wrote early may
        # already sit in its buffer (communicate() would read past it, from the descriptor)
        line = self.proc.stdout.readline()
        err = b"" if line.strip() else self.proc.stderr.read()
        self.proc.wait()
        try:
            return StageTime(**json.loads(line.decode()))
        except (ValueError, TypeError):
            why = (err.decode(errors="replace").strip().splitlines() or ["no output"])[-1]
            title = TITLES[self.engine] if self.engine else TITLES["system"]
            return StageTime(title, 0.0, "helper process", f"helper failed: {why}")

    def stop(self) -> None:
        if self.proc is None:  # a forked helper never given a job
            return
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(timeout=5)
        for f in (self.proc.stdin, self.proc.stdout, self.proc.stderr):
            if f is not None:
                try:
                    f.close()
                except OSError:
                    pass


def free_cpus() -> int:
    """CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def warm_up(
    scene: Scene,
    plants: Sequence[Any],
    progress: Callable[[str], None] | None = None,
    concurrent: bool | None = None,
) -> WarmupResult:
    """Compile what ``plants`` need for ``scene`` when numba's cache is cold; silent when warm.

    Args:
        scene: the resolved scene the run will use (its constants do not change the machine
            code; its types do not either, but it is what the plants are called with).
        plants: engine names or :class:`~analytic.trajectory.Engine` members.
        progress: receives one line of text per event: what will be compiled (once), each stage
            done with its wall time, the total. Nothing is sent when the cache is warm.
        concurrent: compile in a helper process alongside this one (default: when at least two
            CPUs are free to this process and the cache is writable).

    Returns:
        a :class:`WarmupResult`.
    """
    with warming(scene, plants, progress, concurrent, overlap=False) as result:
        return result


@contextlib.contextmanager
def warming(
    scene: Scene,
    plants: Sequence[Any],
    progress: Callable[[str], None] | None = None,
    concurrent: bool | None = None,
    overlap: bool = True,
) -> Iterator[WarmupResult]:
    """:func:`warm_up` around the run that needs it: with ``overlap``, when the MuJoCo and the
    analytic plant both run, the body starts as soon as the MuJoCo plant's kernels are compiled,
    while the helper process still compiles the analytic plant's right-hand side (about a third
    of the whole; the MuJoCo plant's run takes longer than the analytic plant's) and, with
    Pinocchio, its stage. The helper holds that kernel's compile lock
    (:mod:`analytic.kernel.compile_lock`), so the analytic plant's run waits for it and loads it
    from disk rather than compiling it again. On leaving, the helper's last stages are reported
    (waited for when the body ended normally, stopped otherwise)."""
    engines = [str(getattr(p, "value", p)) for p in plants]
    engines = [e for e in (ANALYTIC, MUJOCO, PINOCCHIO) if e in engines]
    t0 = time.perf_counter()
    key = warm_key(engines, scene)
    from analytic.kernel import cache_check

    cache_check.ensure_checked()  # numba's cache files against their hashes (no numba import)
    if is_stamped_warm(key) and not cache_check.removed_any():  # nothing imports numba here
        yield WarmupResult()
        return
    if concurrent is None:
        concurrent = free_cpus() >= 2
    # not known warm: a helper starts importing now, in case the check below finds work for it
    helper = _Helper() if concurrent else None
    try:
        job = _Warmup(scene, engines, key, helper, progress, concurrent, t0)
        result = job.run(overlap)
        yield result
        job.finish()
    finally:
        if helper is not None:
            helper.stop()


class _Warmup:
    """:func:`warming` once the stamp did not answer; ``helper`` (started, no job yet) or None."""

    def __init__(
        self,
        scene: Scene,
        engines: list[str],
        key: str,
        helper: _Helper | None,
        progress: Callable[[str], None] | None,
        concurrent: bool,
        t0: float,
    ) -> None:
        self.scene, self.engines, self.key, self.helper = scene, engines, key, helper
        self.say = progress or (lambda _line: None)
        self.concurrent, self.t0 = concurrent, t0
        self.stages: list[StageTime] = []
        self.cached = True
        self.deferred = False  # the helper still compiles the analytic plant's stages

    def report(self, st: StageTime, after_run: bool = False) -> None:
        self.stages.append(st)
        where = "" if st.where == "here" else f" ({st.where})"
        instead = (
            "the run compiled it instead" if after_run else "it will compile in the run instead"
        )
        tail = f"; {instead} ({st.error})" if st.error else ""
        self.say(f"  {st.title}: {st.seconds:.1f} s{where}{tail}")

    def run(self, overlap: bool) -> WarmupResult:
        scene, helper, report = self.scene, self.helper, self.report
        # every plant embeds the analytic kernel: when its halves are cold, so is every plant
        # (each caller's cache key holds the kernel's fingerprint), and the full check, which
        # imports every plant's modules, would only delay the compile on the critical path
        halves_state = kernel_halves_state(scene)
        kernel_cold = halves_state is not None and engine_is_cold(halves_state)
        cold = tuple(self.engines) if kernel_cold else cold_engines(self.engines)
        if not cold:
            stamp_warm(self.key)
            return WarmupResult()
        if kernel_cold:
            cached = CacheState.NO_CACHE not in halves_state
        else:
            cached = cache_writable(cold)
            kernel_cold = ANALYTIC in cold or bool(cold_engines([ANALYTIC]))
        self.cached = cached
        rest = list(cold)
        concurrent = bool(self.concurrent and cached and helper is not None)
        split = concurrent and kernel_cold  # the kernel's two halves compiled at once
        # the analytic plant's own stages in the helper while the MuJoCo plant runs
        self.deferred = deferred = bool(overlap and split and {ANALYTIC, MUJOCO} <= set(rest))
        engine_beside = concurrent and not deferred and MUJOCO in rest and len(rest) >= 2
        concurrent = split or engine_beside
        names = [TITLES["kernel"]] if kernel_cold else []
        names += [TITLES[e] for e in rest]
        how = (
            "once per machine; later runs load them from numba's cache"
            if cached
            else "numba has no writable cache directory here (set NUMBA_CACHE_DIR), so every run "
            "compiles them"
        )
        # the MuJoCo stage first in the helper: the callback compiled here links it
        mj_stage = ["stage"] if split and MUJOCO in cold else []
        beside = ["the MuJoCo plant's stage"] if mj_stage else []
        beside += ["the kernel's stages 1-6"] if split else []
        # with Pinocchio too, its stage is the helper's last job, also while the plants start
        pin_beside = deferred and PINOCCHIO in rest
        if deferred:
            beside += ["the analytic plant's right-hand side"]
            beside += ["the Pinocchio stage"] if pin_beside else []
            beside[-1] += ", while the plants start"
        elif split and ANALYTIC in rest:
            beside += ["the analytic plant's right-hand side"]
        beside += ["the MuJoCo plant's first interval"] if engine_beside else []
        where = f" ({', '.join(beside)} in a helper process)" if beside else ""
        self.say(
            f"compiling the fast kernels ({how}; ~{EXPECTED_COLD_S} s): {', '.join(names)}{where}"
        )
        if concurrent:
            if deferred:  # locked at once: the plants' runs wait for the helper's results
                from analytic.kernel import compile_lock

                held = {compile_lock.RHS: "rhs"}
                if pin_beside:
                    held[compile_lock.PINOCCHIO] = PINOCCHIO
                engine = PINOCCHIO if pin_beside else None
                helper.send(scene, engine, [*mj_stage, "system", "rhs"], held=held)
            else:
                first = [*mj_stage, "system"] + (["rhs"] if ANALYTIC in rest else [])
                helper.send(scene, MUJOCO if engine_beside else None, first if split else [])
            if engine_beside:
                rest.remove(MUJOCO)
        if split:
            # Here the solve, then the MuJoCo native callback (it calls the kernel's halves by
            # address, so it compiles without them, and links the MuJoCo stage, which the helper
            # compiles meanwhile, first); the helper then compiles stages 1-6, then the analytic
            # plant's right-hand side (also calling the halves by address).
            report(_timed(TITLES["solve"], lambda: compile_kernel_half(scene, "solve")))
            if mj_stage:
                report(helper.next())  # the MuJoCo stage: on disk for the callback to link
                report(_timed(TITLES["native"], lambda: compile_native(scene)))
            report(helper.next())  # stages 1-6
            if pin_beside:  # the kernel's halves are on disk: the Pinocchio stage may start
                helper.go()
                rest.remove(PINOCCHIO)
            if not deferred:
                while helper.first:
                    report(helper.next())
        if kernel_cold:
            report(_timed(TITLES["kernel"], lambda: compile_kernel(scene)))
        if concurrent and engine_beside:
            helper.go()  # what its plant embeds is on disk: it loads rather than compiles
        if deferred:
            rest.remove(ANALYTIC)  # its own run loads what the helper leaves on disk
        for e in rest:
            report(_timed(TITLES[e], lambda e=e: compile_plant(scene, e)))
        if concurrent and engine_beside:
            report(helper.result())
        total = time.perf_counter() - self.t0
        if deferred:
            which = "the analytic plant's" + (" and the Pinocchio stage" if pin_beside else "")
            self.say(
                f"  kernels ready in {total:.1f} s but {which} (still compiling in the helper "
                "process; the runs that need them wait)"
            )
        else:
            self.say(f"  kernels ready in {total:.1f} s")
            self._stamp()
        return WarmupResult(tuple(cold), tuple(self.stages), total, concurrent, cached)

    def finish(self) -> None:
        """After the body of :func:`warming` ended normally: the helper's last stages, if any."""
        if not self.deferred:
            return
        while self.helper.first:
            self.report(self.helper.next(), after_run=True)
        if self.helper.engine is not None:
            self.report(self.helper.result(), after_run=True)
        self._stamp()

    def _stamp(self) -> None:
        if self.cached and not any(st.error for st in self.stages):
            # every stage ran the plants' own entry points: what a run of this key needs is on
            # disk (the cache check would still count variants no run of this scene uses)
            stamp_warm(self.key)


__all__ = [
    "CacheState",
    "StageTime",
    "WarmupResult",
    "cache_state",
    "cache_writable",
    "cold_engines",
    "compile_kernel",
    "compile_plant",
    "engine_is_cold",
    "is_stamped_warm",
    "kernel_halves_state",
    "stamp_warm",
    "warm_key",
    "warm_up",
    "warming",
]
