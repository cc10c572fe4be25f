"""The MJX plant's engine work, run in its own spawned process
(:func:`mj_bridge.accelerated.run_isolated`, from :class:`mj_bridge.mjx_plugin.MjxPlant`).

Each entry (:func:`simulate_runs`, :func:`pointwise`) first sets JAX's x64 mode for the
settings' precision and its persistent compilation cache (``<user cache>/tumbling-testbed/jax``,
so a second process loads what the first compiled), before any JAX array exists; then imports
MJX. The scenes' twins are the C plant's (:func:`mj_bridge.accelerated.accelerated_twin`, the
energy flag off), each handed to ``mjx.put_model`` (its ``NotImplementedError`` becomes a
``ValueError`` naming the field); scenes of one batch must give models of one structure, whose
differing leaves are stacked and ``jax.vmap``-ed over (``in_axes`` 0 for those, None for the
leaves every scene shares).

One step is MuJoCo's RK4 (:func:`mj_bridge.accelerated_scheme.rk4_step`) around
``mjx.forward``, the controller in each stage at the stage's state
(:func:`~mj_bridge.accelerated_scheme.controlled_stage`): in JAX from
:mod:`analytic.array_model` (``controller = "jax"``), or the compiled numpy controller through
``jax.pure_callback`` (``"host"``). A run is ``jax.lax.scan`` over the steps between two output
samples, one jit-compiled call per sample interval, so ``progress(t)`` is called on the host
after each (where a Ctrl-C is raised) and a run stops between samples with what it reached.
The data pytree is not carried through the scan (only ``qpos``, ``qvel``, the quadratures and
the time are): ``mjx.forward`` starts each stage from one template ``Data``.
"""

from __future__ import annotations

import dataclasses
import functools
import signal
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from analytic.effects import Effect, MjIntegrator, Precision
from analytic.runtime.cache_dir import user_cache_dir
from analytic.scene import Scene
from analytic.trajectory import RunStatus, Trajectory
from mj_bridge.accelerated import accelerated_trajectory, accelerated_twin, dropped_fields
from mj_bridge.accelerated_scheme import StageConstants, controlled_stage, rk4_step
from mj_bridge.mjx_settings import MjxController, MjxSettings
from mj_bridge.plan import plan_steps

ENGINE = "mjx"
"""The plant's name in its trajectories (:attr:`mj_bridge.mjx_plugin.MjxPlant.engine`)."""


def jax_cache_dir():
    """JAX's persistent compilation cache: beside numba's in the user's cache directory."""
    return user_cache_dir().parent / "jax"


def _jax(settings: MjxSettings):
    """JAX, configured for ``settings`` (x64 per precision, the persistent cache) before any
    array exists in this process."""
    import jax

    jax.config.update("jax_enable_x64", settings.precision is Precision.FLOAT64)
    jax.config.update("jax_compilation_cache_dir", str(jax_cache_dir()))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.5)
    return jax


def _device(jax, device: str):
    """The JAX device ``device`` names ("" the default); ValueError naming ``mjx.device``."""
    if not device:
        return jax.devices()[0]
    platform, _, index = device.partition(":")
    try:
        found = jax.devices(platform)
    except RuntimeError:
        found = []
    i = int(index or 0)
    if i >= len(found):
        have = ", ".join(sorted({f"{d.platform}:{d.id}" for d in jax.devices()}))
        raise ValueError(f"mjx.device: JAX has no device {device!r} here (it has {have})")
    return found[i]


def _refusal(exc: BaseException) -> str:
    """``mjx.put_model``'s refusal as one line naming the field."""
    what = " ".join(str(exc).split()) or type(exc).__name__
    field = what.split(".")[0] if what.startswith("mjt") else "scene"
    names = {
        "mjtIntegrator": "mujoco.integrator",
        "mjtGain": "mujoco.spring_model",
        "mjtBias": "mujoco.spring_model",
        "mjtEnableBit": "opt.enableflags",
        "mjtDisableBit": "opt.disableflags",
    }
    return f"{names.get(field, field)}: MJX cannot run this scene's twin ({what})"


def mjx_field_names() -> tuple[set[str], set[str]]:
    """The fields of ``mjx.Model`` and the names MJX's computation reads (every ``.<name>`` in
    its sources other than its type and conversion modules and tests), for
    :func:`mj_bridge.accelerated.dropped_fields`."""
    import dataclasses
    import pathlib
    import re

    from mujoco import mjx

    fields = {f.name for f in dataclasses.fields(mjx.Model)}
    src = pathlib.Path(mjx.__file__).parent / "_src"
    text = "\n".join(
        p.read_text(encoding="utf-8")
        for p in src.glob("*.py")
        if p.name not in ("types.py", "io.py") and not p.name.endswith("_test.py")
    )
    return fields, set(re.findall(r"\.([a-z_][a-z0-9_]*)\b", text))


NOT_READ = ("key_", "name", "nnames", "path", "npaths")
"""Prefixes of ``mjx.Model`` fields no forward evaluation reads (keyframes, names and their
addresses, paths): a batch's scenes may differ in them."""


class _Engine:
    """Scenes of one structure as MJX models (stacked where they differ) and their stages."""

    def __init__(self, scenes: Sequence[Scene], settings: MjxSettings):
        self.jax = jax = _jax(settings)
        import mujoco
        from mujoco import mjx

        self.jnp = jnp = jax.numpy
        self.mjx = mjx
        self.settings = settings
        self.scenes = list(scenes)
        self.dtype = jnp.float64 if settings.precision is Precision.FLOAT64 else jnp.float32
        dev = _device(jax, settings.device)
        self.device = f"{dev.platform}:{dev.id}"
        self.twins = [accelerated_twin(s, settings.timestep) for s in self.scenes]
        models = []
        for at in self.twins:
            try:
                models.append(mjx.put_model(at.model, device=dev))
            except NotImplementedError as exc:
                raise ValueError(_refusal(exc)) from None
        self.tm = tm = self.twins[0].tm
        self.h = tm.dt
        self.body = tm.body_id
        self.mx, self.mx_axes, self._axes = self._stack(models)
        self._chunks: dict[int, Callable] = {}
        self._stage_jit = jax.jit(self._stage_eval)
        self.d0 = mjx.put_data(self.twins[0].model, mujoco.MjData(self.twins[0].model), device=dev)
        consts = [
            StageConstants.of(s, at.tm).arrays(np, np.float64)
            for s, at in zip(self.scenes, self.twins, strict=True)
        ]
        self.c = {k: jnp.asarray(np.stack([c[k] for c in consts]), self.dtype) for k in consts[0]}
        self.fast = [self._fast(s) for s in self.scenes]
        self.controller = settings.controller
        self.params, self.structure = self._controller_params()
        self.widx = jnp.arange(len(self.scenes))
        fields, read = mjx_field_names()
        self.dropped = dropped_fields(self.twins[0].model, fields, read)

    # -- the models ---------------------------------------------------------------------------

    def _stack(self, models):
        """One model pytree for the batch: each leaf stacked over the scenes where they differ
        (vmapped, axis 0), else the first scene's (axis None)."""
        jax = self.jax
        # The keyframes (the twin records each scene's initial state as one) and the names (the
        # twin is named after its scene) are static numpy fields of mjx.Model, so they would make
        # the scenes' trees differ; forward dynamics never reads them: the batch's model carries
        # the first scene's.
        keys = [f.name for f in dataclasses.fields(models[0]) if f.name.startswith(NOT_READ)]
        models = [models[0]] + [
            mx.replace(**{k: getattr(models[0], k) for k in keys}) for mx in models[1:]
        ]
        leaves0, tree0 = jax.tree_util.tree_flatten(models[0])
        per = [leaves0]
        for i, mx in enumerate(models[1:], start=1):
            leaves, tree = jax.tree_util.tree_flatten(mx)
            if tree != tree0 or any(
                a.shape != b.shape for a, b in zip(leaves, leaves0, strict=True)
            ):
                raise ValueError(
                    f"scenes[{i}]: its twin's MJX model differs in structure from scenes[0]'s "
                    f"(a batch holds scenes whose twins differ in numbers only)"
                )
            per.append(leaves)
        out, axes = [], []
        for j, leaf in enumerate(leaves0):
            col = [p[j] for p in per]
            if all(np.array_equal(np.asarray(leaf), np.asarray(x)) for x in col[1:]):
                out.append(leaf)
                axes.append(None)
            else:
                out.append(self.jnp.stack(col))
                axes.append(0)
        return tree0.unflatten(out), tree0.unflatten(axes), (tree0, axes)

    @staticmethod
    def _fast(scene):
        from analytic.fast import FastModel

        return FastModel(scene)

    def _controller_params(self):
        if self.controller is MjxController.HOST:
            return {}, None
        from analytic import array_model as am

        structure = am.structure_of(self.scenes[0])
        for i, s in enumerate(self.scenes[1:], start=1):
            if am.structure_of(s) != structure:
                raise ValueError(
                    f"scenes[{i}]: its controller's structure differs from scenes[0]'s "
                    f"(tracked components, masses, weighting or spring laws)"
                )
        params = am.stack_parameters(
            [am.parameters(s, self.jnp, self.dtype) for s in self.scenes], self.jnp
        )
        return params, structure

    # -- one world ----------------------------------------------------------------------------

    def _host_control(self, widx, t, q, qd):
        """The compiled controller on the host, rows of any leading shape."""
        n = self.scenes[0].n
        w, t, q, qd = (np.asarray(x) for x in (widx, t, q, qd))
        shape = np.broadcast_shapes(w.shape, t.shape, q.shape[:-1])
        w, t = np.broadcast_to(w, shape).ravel(), np.broadcast_to(t, shape).ravel()
        q = np.broadcast_to(q, (*shape, q.shape[-1])).reshape(-1, q.shape[-1])
        qd = np.broadcast_to(qd, (*shape, qd.shape[-1])).reshape(-1, qd.shape[-1])
        tau, rod, fC = np.zeros((len(w), 3)), np.zeros((len(w), n)), np.zeros((len(w), 3))
        for r in range(len(w)):
            fm = self.fast[int(w[r])]
            _, tq, rf, fc, _ = fm.qddot_and_forces(
                float(t[r]), q[r].astype(float), qd[r].astype(float)
            )
            tau[r], rod[r], fC[r] = tq, rf, fc
        dt = np.dtype(self.dtype)
        return (
            tau.reshape(*shape, 3).astype(dt),
            rod.reshape(*shape, n).astype(dt),
            fC.reshape(*shape, 3).astype(dt),
        )

    def _host_given(self, widx, t):
        w, t = np.asarray(widx), np.asarray(t)
        shape = np.broadcast_shapes(w.shape, t.shape)
        w, t = np.broadcast_to(w, shape).ravel(), np.broadcast_to(t, shape).ravel()
        out = np.stack(
            [self.fast[int(w[r])].model.given_torque(float(t[r])) for r in range(len(w))]
        )
        return out.reshape(*shape, 3).astype(np.dtype(self.dtype))

    def _stage_eval(self, mx, c, p, widx, t, qpos, qvel):
        """The controlled stage of one world (:func:`controlled_stage`) on MJX's forward:
        ``(qacc, rates)`` at ``(t, qpos, qvel)``."""
        jax, jnp, mjx = self.jax, self.jnp, self.mjx
        scene = self.scenes[0]
        n, d0, body, dtype = scene.n, self.d0, self.body, self.dtype

        def forward(t, qpos, qvel, ctrl, fC):
            xfrc = d0.xfrc_applied.at[body, :3].set(fC)
            d = d0.replace(qpos=qpos, qvel=qvel, ctrl=ctrl, xfrc_applied=xfrc, time=t)
            return mjx.forward(mx, d).qacc

        if self.controller is MjxController.JAX:
            from analytic import array_model as am

            st = self.structure

            def control(t, q, qd):
                return am.control_forces(jnp, st, p, t, q, qd)

            def given(t):
                return am.given_torque(jnp, st, p, t)

        else:
            shapes = (
                jax.ShapeDtypeStruct((3,), dtype),
                jax.ShapeDtypeStruct((n,), dtype),
                jax.ShapeDtypeStruct((3,), dtype),
            )
            controlled = scene.controlled
            torque = scene.has(Effect.EXTERNAL_TORQUE)

            def control(t, q, qd):
                if not controlled:
                    z = jnp.zeros(3, dtype)
                    return z, jnp.zeros(n, dtype), z
                return jax.pure_callback(
                    self._host_control, shapes, widx, t, q, qd, vmap_method="expand_dims"
                )

            def given(t):
                if not torque:
                    return jnp.zeros(3, dtype)
                return jax.pure_callback(
                    self._host_given, shapes[0], widx, t, vmap_method="expand_dims"
                )

        return controlled_stage(jnp, forward, control, given, c)(t, qpos, qvel)

    def stage(self, mx, c, p, widx) -> Callable:
        """World ``widx``'s stage ``(t, qpos, qvel) -> (qacc, rates)``: one jit-compiled
        function (:attr:`_stage_jit`), so a step's five stages are traced once."""
        return lambda t, qpos, qvel: self._stage_jit(mx, c, p, widx, t, qpos, qvel)

    def _chunk_world(self, mx, c, p, widx, t0, t1, qpos, qvel, aux, *, k: int):
        """k RK4 steps of one world from ``t0``: ``(qpos, qvel, aux, qacc)`` at the sample ``t1``
        and the acceleration at the start (the previous sample's, computed once per run)."""
        jax = self.jax
        stage = self.stage(mx, c, p, widx)
        h = self.h

        def body(carry, _):
            t, qp, qv, ax = carry
            qp, qv, ax = rk4_step(self.jnp, stage, t, qp, qv, ax, h)
            return (t + h, qp, qv, ax), None

        qacc0, _ = stage(t0, qpos, qvel)
        (_, qpos, qvel, aux), _ = jax.lax.scan(body, (t0, qpos, qvel, aux), None, length=k)
        qacc, _ = stage(t1, qpos, qvel)
        return qpos, qvel, aux, qacc, qacc0

    def _qacc_world(self, mx, c, p, widx, t, qpos, qvel):
        return self.stage(mx, c, p, widx)(t, qpos, qvel)[0]

    def chunk(self, k: int):
        """The jit-compiled batch of k steps: every world at once (``jax.vmap``)."""
        if k not in self._chunks:
            f = functools.partial(self._chunk_world, k=k)
            ax = (self.mx_axes, 0, 0, 0, None, None, 0, 0, 0)
            self._chunks[k] = self.jax.jit(self.jax.vmap(f, in_axes=ax))
        return self._chunks[k]

    @functools.cached_property
    def qacc_states(self):
        """The jit-compiled accelerations of world 0 at N states (times, qpos, qvel batched)."""
        ax = (None, None, None, None, 0, 0, 0)
        return self.jax.jit(self.jax.vmap(self._qacc_world, in_axes=ax))

    def world(self, i: int):
        """World i's model, constants and parameters (unbatched)."""
        jax = self.jax
        tree, axes = self._axes
        leaves = jax.tree_util.tree_leaves(self.mx)
        mx = tree.unflatten([x if a is None else x[i] for x, a in zip(leaves, axes, strict=True)])
        take = functools.partial(jax.tree_util.tree_map, lambda x: x[i])
        return mx, take(self.c), take(self.params), self.widx[i]

    def asarray(self, x):
        return self.jnp.asarray(np.asarray(x), self.dtype)

    def info(self) -> dict[str, Any]:
        import jax
        import mujoco

        return {
            "integrator": MjIntegrator.RK4.value,
            "dt": self.h,
            "precision": self.settings.precision.value,
            "device": self.device,
            "controller": self.controller.value,
            "mjx_version": _version("mujoco-mjx"),
            "jax_version": jax.__version__,
            "mujoco_version": mujoco.__version__,
            "changed_fields": list(self.twins[0].changed),
            "dropped_fields": list(self.dropped),
        }


def _version(dist: str) -> str:
    import importlib.metadata

    try:
        return importlib.metadata.version(dist)
    except importlib.metadata.PackageNotFoundError:
        return "?"


def simulate_runs(
    scenes: Sequence[Scene],
    settings: MjxSettings,
    t_end: float | None,
    progress: Callable[[float], None] | None = None,
) -> list[Trajectory]:
    """Run ``scenes`` (one structure, one output grid and step) together; one trajectory each.

    A world that turns non-finite ends ``FAILED`` at its last finite sample while the others go
    on; a ``KeyboardInterrupt`` (SIGINT from the parent, between sample intervals) ends every
    world ``INTERRUPTED`` with the samples reached.
    """
    return run_engine(engine(scenes, settings), t_end, progress)


def engine(scenes: Sequence[Scene], settings: MjxSettings) -> _Engine:
    """The engine of ``scenes`` (one structure) at ``settings``, for :func:`run_engine` and
    :func:`pointwise_on` (one engine serves both, its stage traced once)."""
    return _Engine(scenes, settings)


def run_engine(
    eng: _Engine, t_end: float | None, progress: Callable[[float], None] | None = None
) -> list[Trajectory]:
    """:func:`simulate_runs` on an engine already built."""
    scenes, settings = eng.scenes, eng.settings
    _, h, times, ksteps = plan_steps(scenes[0], MjIntegrator.RK4, settings.timestep, t_end)
    for i, s in enumerate(scenes[1:], start=1):
        _, h_i, times_i, _ = plan_steps(s, MjIntegrator.RK4, settings.timestep, t_end)
        if (
            h_i != h
            or len(times_i) != len(times)
            or not np.allclose(times_i, times, rtol=0, atol=1e-12)
        ):
            raise ValueError(
                f"scenes[{i}]: a batch runs on one output grid and step: its [output] or "
                f"[mujoco] timestep differs from scenes[0]'s"
            )
    W = len(scenes)
    q0 = np.stack([s.initial.q0() for s in scenes])
    qd0 = np.stack([s.initial.qdot0() for s in scenes])
    qpos0, qvel0 = eng.tm.to_mujoco(q0, qd0)
    qpos, qvel = eng.asarray(qpos0), eng.asarray(qvel0)
    aux = eng.asarray(np.zeros((W, 7)))
    t0 = time.perf_counter()
    rec = [[np.asarray(x)] for x in (qpos, qvel, qpos[:, :-1], aux)]  # qacc: from the first call
    reached = np.full(W, 1)
    failed: dict[int, str] = {}
    status = RunStatus.OK
    first_chunk_s = None
    try:
        for i, k in enumerate(ksteps, start=1):
            c0 = time.perf_counter()
            out = eng.chunk(int(k))(
                eng.mx, eng.c, eng.params, eng.widx, eng.asarray(times[i - 1]),
                eng.asarray(times[i]), qpos, qvel, aux,
            )  # fmt: skip
            host = [np.asarray(out[j]) for j in (0, 1, 3, 2)]  # qpos, qvel, qacc, aux
            if first_chunk_s is None:
                first_chunk_s = time.perf_counter() - c0
                rec[2][0] = np.asarray(out[4])
            qpos, qvel, aux = out[0], out[1], out[2]
            for j in range(W):
                if j in failed:
                    continue
                if not all(np.all(np.isfinite(x[j])) for x in host):
                    failed[j] = f"non-finite state at t = {times[i]:.6g} s"
                    continue
                reached[j] = i + 1
            for r, x in zip(rec, host, strict=True):
                r.append(x)
            if len(failed) == W:
                break
            if progress is not None:
                progress(float(times[i]))
    except KeyboardInterrupt:
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # a second one would cut the record short
        status = RunStatus.INTERRUPTED
    if first_chunk_s is None:  # stopped before the first interval: sample 0's acceleration
        rec[2][0] = np.stack(
            [
                np.asarray(
                    eng.qacc_states(
                        *eng.world(j), eng.asarray(times[:1]), qpos[j : j + 1], qvel[j : j + 1]
                    )
                )[0]
                for j in range(W)
            ]
        )
    wall = time.perf_counter() - t0
    arrays = [np.stack(r, axis=1) for r in rec]  # (W, N, ·)
    info = eng.info() | {
        "wall_time_s": wall,
        "first_interval_s": first_chunk_s,
        "nworld": W,
        "nsteps": int(np.sum(ksteps[: max(0, arrays[0].shape[1] - 1)])),
    }
    out = []
    for j, scene in enumerate(scenes):
        N = int(reached[j])
        st, msg = status, ""
        if j in failed:
            st, msg = RunStatus.FAILED, failed[j]
        elif status is RunStatus.INTERRUPTED:
            N = min(N, arrays[0].shape[1])
            msg = f"interrupted at t = {times[N - 1]:.6g} s"
        qp, qv, qa, ax = (a[j, :N] for a in arrays)
        out.append(
            accelerated_trajectory(
                scene,
                eng.twins[j].tm,
                ENGINE,
                times[:N],
                qp,
                qv,
                qa,
                ax,
                st,
                msg,
                dict(info),
                fast=eng.fast[j],
            )
        )
    return out


def pointwise(
    scene: Scene, settings: MjxSettings, t: np.ndarray, q: np.ndarray, qdot: np.ndarray
) -> np.ndarray:
    """MJX's ``q̈`` (N, n+7), paper coordinates, at N given paper states (``t`` (N,), ``q``,
    ``q̇`` (N, n+7)), the scene's controller and given torque applied (as a stage applies them)."""
    return pointwise_on(_Engine([scene], settings), t, q, qdot)


def pointwise_on(eng: _Engine, t: np.ndarray, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
    """:func:`pointwise` on an engine already built (its first scene)."""
    qpos, qvel = eng.tm.to_mujoco(np.atleast_2d(q), np.atleast_2d(qdot))
    mx, c, p, w = eng.world(0)
    qacc = eng.qacc_states(
        mx, c, p, w, eng.asarray(np.atleast_1d(t)), eng.asarray(qpos), eng.asarray(qvel)
    )
    return eng.tm.to_paper_acc(qpos, qvel, np.asarray(qacc, np.float64))


__all__ = [
    "ENGINE",
    "engine",
    "jax_cache_dir",
    "mjx_field_names",
    "pointwise",
    "pointwise_on",
    "run_engine",
    "simulate_runs",
]
