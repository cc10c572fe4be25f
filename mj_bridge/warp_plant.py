"""The MuJoCo Warp plant's engine: scenes of one structure as the worlds of one Warp model.

Runs only in the process that owns Warp (:func:`run_batch`, :func:`pointwise_qddot`, called
through an isolated process by :class:`mj_bridge.warp_plugin.WarpPlant`; Warp and a CUDA context
do not survive a fork). Everything here imports ``warp`` and ``mujoco_warp`` lazily, inside the
functions.

The engine is MuJoCo Warp's own: ``mjw.step`` with the twin's integrator (RK4 by default, Warp's
``rungekutta4``), state in **float32** (Warp's ``Data``), the model the C plant runs (its twin,
with only the energy flag off, :func:`twin_for`). The project's controller runs in every
integrator stage through Warp's control callback (``Model.callback.control``, called by every
forward evaluation, four per RK4 step, as ``mjcb_control`` in MuJoCo's C engine): it reads the
stage's ``qpos``, ``qvel`` of all worlds, evaluates the controller on the host for all of them
(:class:`mj_bridge.warp_control.HostController`) and writes the same channels as the C plant
(:mod:`mj_bridge.stages`): ``ctrl = τ / gear`` on the torque motors, ``F / gear`` on the rod
motors, the force at C into ``xfrc_applied[BR, :3]``. The stage's time is ``t₀ + c_k h`` with
RK4's nodes ``c = (0, ½, ½, 1)`` (Warp's Data does not move its clock inside a step); the
callback also sums the control's work and impulses with the stage weights
(:data:`mj_bridge.accumulator.STAGE_WEIGHTS`), as the C plant's stages do.

Batches: N scenes become the N worlds of one model. Per-world parameters ride on Warp's batched
model fields (leading dimension ``*``: masses, inertias, joint axes, body positions, tendon
stiffness and rest lengths, gravity, ...): :func:`batched_model` puts each scene's twin on the
device and stacks every field that differs; scenes whose twins differ in a field Warp cannot batch
(or in their step or output grid) run as separate groups of worlds, one ``nworld`` call each.

Shapes: ``qpos`` (N, n+7), ``qvel``/``qacc`` (N, n+6) per world; the paper's coordinates
(Eq. 44) by :mod:`model_xml.coordinates` (BR's body frame at C); times in s, SI units.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Sequence

import numpy as np

from analytic.effects import MjIntegrator
from analytic.scene import Scene
from analytic.trajectory import RunStatus, Trajectory
from mj_bridge.warp_settings import ENGINE

STAGE_NODES: dict[MjIntegrator, tuple[float, ...]] = {
    MjIntegrator.RK4: (0.0, 0.5, 0.5, 1.0),
    MjIntegrator.EULER: (0.0,),
    MjIntegrator.IMPLICIT: (0.0,),
    MjIntegrator.IMPLICITFAST: (0.0,),
}
"""Where in the step (fraction of h) each controller call of one step sits: Warp's ``step`` runs
a forward evaluation at the step's start, and RK4 three more at the tableau's nodes."""

IGNORED_FIELDS = frozenset({"key_time", "key_qpos", "key_qvel", "key_act", "key_mpos", "key_mquat",
                            "key_ctrl", "key_plastic", "callback"})  # fmt: skip
"""Model fields no forward evaluation reads (keyframes) and the callbacks: a batch may differ in
them (each scene's initial state is its own)."""


def import_warp(device: str = ""):
    """``(wp, mjw, device)``: Warp initialised quietly, the device chosen (``""``: Warp's
    preferred device, CUDA when it sees one, else ``"cpu"``). Warp's kernel cache is its default
    (``WARP_CACHE_PATH``, else the user's cache directory): compiled kernels are reused by every
    later process."""
    import warp as wp

    wp.config.log_level = wp.LOG_WARNING  # no greeting, no line per kernel module loaded
    import mujoco_warp as mjw

    wp.init()
    dev = wp.get_device(device or None)
    return wp, mjw, str(dev)


def twin_for(scene: Scene, dt: float | None):
    """``(TwinModel, MjModel handed to Warp, changed)``: the C plant's twin of ``scene`` with the
    step ``dt`` (None: the scene's), the energy flag off (Warp refuses it), nothing else changed."""
    from mj_bridge.accelerated import accelerated_twin

    tw = accelerated_twin(scene, dt)
    return tw.tm, tw.model, tw.changed


# ----------------------------------------------------------------------------------------------
# The batched model
# ----------------------------------------------------------------------------------------------


class Unbatchable(Exception):
    """Two twins differ in a model field Warp cannot batch (``field``)."""

    def __init__(self, field: str):
        super().__init__(field)
        self.field = field


def _values(x) -> np.ndarray | object:
    import warp as wp

    if isinstance(x, tuple | list):
        return type(x)(_values(v) for v in x)
    return x.numpy() if isinstance(x, wp.array) else x


def _same(a, b) -> bool:
    if isinstance(a, tuple | list) or isinstance(b, tuple | list):
        return (type(a) is type(b) and len(a) == len(b)
                and all(_same(x, y) for x, y in zip(a, b, strict=True)))  # fmt: skip
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return a.shape == b.shape and a.dtype == b.dtype and np.array_equal(a, b, equal_nan=True)
    try:
        return bool(a == b)
    except Exception:  # an object without equality: the same object only
        return a is b


def _merge(base, others: list, prefix: str = "") -> None:
    """Stack into ``base`` (a Warp ``Model`` or one of its sub-records) every batched field in
    which ``others`` differ; :class:`Unbatchable` naming the first field that differs and cannot
    be batched."""
    import warp as wp
    from mujoco_warp._src import warp_util

    for f in dataclasses.fields(base):
        if f.name in IGNORED_FIELDS:
            continue
        name = prefix + f.name
        val = getattr(base, f.name)
        rest = [getattr(o, f.name) for o in others]
        if dataclasses.is_dataclass(val) and not isinstance(val, type):
            _merge(val, rest, name + ".")
            continue
        a = _values(val)
        vs = [_values(r) for r in rest]
        if all(_same(a, v) for v in vs):
            continue
        spec = getattr(f.type, "shape", ())
        if not (isinstance(val, wp.array) and warp_util.is_array_spec(f.type) and spec
                and spec[0] == "*" and all(v.shape == a.shape for v in vs)):  # fmt: skip
            raise Unbatchable(name)
        stacked = np.concatenate([a, *vs], axis=0)
        arr = wp.array(stacked, dtype=val.dtype, device=val.device)
        arr._is_batched = True
        setattr(base, f.name, arr)


def batched_model(mjw, models: Sequence):
    """One Warp model whose worlds are ``models`` (MjModels of one structure), in order: their
    own values in every batched field in which they differ. Raises :class:`Unbatchable`.

    ``put_model`` refusing a twin raises ``NotImplementedError``/``ValueError`` (the feature it
    names), re-raised by the caller as a ``ValueError``."""
    base = mjw.put_model(models[0])
    others = [m for m in models[1:] if m is not models[0]]
    if others:
        _merge(base, [mjw.put_model(m) for m in models[1:]])
    return base


# ----------------------------------------------------------------------------------------------
# The worlds and the controller callback
# ----------------------------------------------------------------------------------------------


class Worlds:
    """N scenes of one structure (same twin layout, one step ``dt``) as the worlds of one model.

    Attributes:
        scenes, tms (their TwinModels), n, nworld, dt, integrator; mw, d (Warp's Model, Data);
        ctl (the host controller of all worlds); acc (N, 7) the quadratures
        ``[W, I_L (3), I_P (3)]`` summed at the stages; calls: stages run since the last reset.
    """

    def __init__(self, mjw, wp, device: str, scenes: Sequence[Scene], dt: float | None):
        import mujoco

        from mj_bridge.accumulator import STAGE_WEIGHTS
        from mj_bridge.warp_control import HostController

        self.wp, self.mjw = wp, mjw
        self.scenes = list(scenes)
        one = {}  # a scene given for several worlds is built once (its worlds share the model)
        twins = [one.setdefault(id(s), twin_for(s, dt)) for s in self.scenes]
        self.tms = [t[0] for t in twins]
        self.changed = twins[0][2]
        tm0 = self.tms[0]
        self.n = self.scenes[0].n
        self.nworld = len(self.scenes)
        self.dt = float(tm0.dt)
        self.integrator = tm0.integrator
        self.nodes = STAGE_NODES[self.integrator]
        self.weights = STAGE_WEIGHTS[self.integrator]
        m0 = twins[0][1]
        self.nu, self.nbody = m0.nu, m0.nbody
        with wp.ScopedDevice(device):
            self.mw = batched_model(mjw, [t[1] for t in twins])
            self.d = mjw.put_data(m0, mujoco.MjData(m0), nworld=self.nworld)
        self.device = device
        self.ctl = HostController(self.scenes)
        self.active = bool(self.nu)  # the callback has channels to write
        self.body_id = tm0.body_id
        self.torque_ids = tm0.torque_ids
        self.force_ids = tm0.force_ids
        self._ctrl = np.zeros((self.nworld, self.nu), dtype=np.float32)
        self._xfrc = np.zeros((self.nworld, self.nbody, 6), dtype=np.float32)
        self.acc = np.zeros((self.nworld, 7))
        self.calls = 0
        self.stepping = False
        self.t0: np.ndarray = np.zeros(self.nworld)
        if self.active:
            self.mw.callback.control = self._control

    # -- state ----------------------------------------------------------------------------------

    def set_state(self, qpos: np.ndarray, qvel: np.ndarray) -> None:
        """MuJoCo states of every world, (N, nq) and (N, nv); controls cleared."""
        self.d.qpos.assign(np.asarray(qpos, dtype=np.float32))
        self.d.qvel.assign(np.asarray(qvel, dtype=np.float32))
        self.d.ctrl.zero_()
        self.d.xfrc_applied.zero_()

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(qpos, qvel, qacc)`` of every world, float64 copies of Warp's float32 state."""
        self.wp.synchronize()
        d = self.d
        return (d.qpos.numpy().astype(float), d.qvel.numpy().astype(float),
                d.qacc.numpy().astype(float))  # fmt: skip

    # -- the controller, in every stage ---------------------------------------------------------

    def _control(self, m, d) -> None:
        """Warp's control callback: the controller at this stage's time and state, all worlds."""
        from mj_bridge.stages import INV_GEAR
        from model_xml.coordinates import mujoco_to_paper_state

        self.wp.synchronize()
        qpos = d.qpos.numpy()
        qvel = d.qvel.numpy()
        k = self.calls % len(self.nodes)
        t = self.t0 + (self.nodes[k] * self.dt if self.stepping else 0.0)
        q, qd = mujoco_to_paper_state(qpos.astype(float), qvel.astype(float))
        tau, rod, fC = self.ctl.forces(t, q, qd)
        if self.torque_ids is not None:
            self._ctrl[:, self.torque_ids] = tau * INV_GEAR
        if self.force_ids is not None:
            self._ctrl[:, self.force_ids] = rod * INV_GEAR
            self._xfrc[:, self.body_id, :3] = fC
            d.xfrc_applied.assign(self._xfrc)
        d.ctrl.assign(self._ctrl)
        if self.stepping:
            w = self.dt * self.weights[k]
            self.acc += w * self.ctl.rates(q, qd, qvel[:, 3:6].astype(float), tau, rod, fC)
            self.calls += 1

    def forward(self, t: np.ndarray | float) -> None:
        """Forward dynamics of every world at its current state, the controller at time(s) t."""
        self.stepping = False
        self.t0 = np.broadcast_to(np.asarray(t, dtype=float), (self.nworld,)).copy()
        self.mjw.forward(self.mw, self.d)

    def step(self, t: float, k: int) -> None:
        """``k`` steps of every world from time t (s), the controller in every stage."""
        self.stepping = True
        self.calls = 0
        for j in range(k):
            self.t0 = np.full(self.nworld, t + j * self.dt)
            self.mjw.step(self.mw, self.d)
        self.stepping = False
        if self.active and self.calls != len(self.nodes) * k:
            raise RuntimeError(
                f"controller called {self.calls} times in {k} steps; expected "
                f"{len(self.nodes)} per step for {self.integrator.value}"
            )


# ----------------------------------------------------------------------------------------------
# The runs
# ----------------------------------------------------------------------------------------------


def _group_key(scene: Scene, dt: float | None, t_end: float | None) -> tuple:
    from mj_bridge.plan import plan_steps

    integ, h, times, _ = plan_steps(scene, None, dt, t_end)
    return (integ, h, tuple(times.tolist()))


def run_worlds(
    mjw, wp, device: str, scenes: Sequence[Scene], dt: float | None, t_end: float | None,
    progress: Callable[[float], None] | None,
) -> list[Trajectory]:  # fmt: skip
    """One ``nworld`` run of ``scenes`` (one structure, one step and output grid)."""
    import mujoco_warp

    from analytic.assemble import assemble
    from analytic.fast import FastModel
    from mj_bridge.plan import plan_steps

    scene0 = scenes[0]
    integ, h, times, ksteps = plan_steps(scene0, None, dt, t_end)
    c0 = time.perf_counter()
    W = Worlds(mjw, wp, device, scenes, h)
    states = [W.tms[i].to_mujoco(s.initial.q0(), s.initial.qdot0()) for i, s in enumerate(scenes)]
    W.set_state(np.array([s[0] for s in states]), np.array([s[1] for s in states]))
    rec = {k: [] for k in ("t", "qpos", "qvel", "qacc", "aux")}
    status, message = RunStatus.OK, ""

    def sample(t: float) -> None:
        W.forward(t)
        qpos, qvel, qacc = W.arrays()
        rec["t"].append(t)
        rec["qpos"].append(qpos)
        rec["qvel"].append(qvel)
        rec["qacc"].append(qacc)
        rec["aux"].append(W.acc.copy())

    sample(float(times[0]))
    compile_s = time.perf_counter() - c0  # the first forward compiles (or loads) the kernels
    wall0 = time.perf_counter()
    nsteps = 0
    try:
        for i, k in enumerate(ksteps, start=1):
            W.step(float(times[i - 1]), int(k))
            nsteps += int(k)
            sample(float(times[i]))
            last = rec["qpos"][-1], rec["qvel"][-1]
            if not (np.all(np.isfinite(last[0])) and np.all(np.isfinite(last[1]))):
                status, message = RunStatus.FAILED, f"non-finite state at t = {times[i]:.6g} s"
                break
            if progress is not None:
                progress(float(times[i]))
    except KeyboardInterrupt:
        status, message = RunStatus.INTERRUPTED, f"interrupted at t = {rec['t'][-1]:.6g} s"
    wall = time.perf_counter() - wall0

    t = np.array(rec["t"])
    qpos_all, qvel_all, qacc_all = (np.array(rec[k]) for k in ("qpos", "qvel", "qacc"))
    aux_all = np.array(rec["aux"])
    out = []
    for w, (scene, tm) in enumerate(zip(scenes, W.tms, strict=True)):
        q, qd, qdd, omega = tm.to_paper_batch(qpos_all[:, w], qvel_all[:, w], qacc_all[:, w])
        ok = np.all(np.isfinite(q), axis=1) & np.all(np.isfinite(qd), axis=1)
        st, msg = status, message
        if st is RunStatus.FAILED and np.all(ok):
            st, msg = RunStatus.OK, ""  # another world of the batch failed; this one did not
        if st is RunStatus.OK and not np.all(ok):
            st, msg = RunStatus.FAILED, f"non-finite state at t = {t[np.argmin(ok)]:.6g} s"
        keep = np.ones(len(t), bool) if np.all(ok) else (np.arange(len(t)) < np.argmin(ok))
        fast = FastModel(scene)
        controls = [
            fast.acceleration(ti, qi, qdi)[1] if scene.controlled else None
            for ti, qi, qdi in zip(t[keep], q[keep], qd[keep], strict=True)
        ]
        out.append(
            assemble(
                fast.model,
                ENGINE,
                t[keep],
                q[keep],
                qd[keep],
                qdd[keep],
                controls,
                aux_all[keep, w],
                st,
                msg,
                {
                    "integrator": integ.value,
                    "dt": h,
                    "nsteps": nsteps,
                    "precision": "float32",
                    "device": device,
                    "nworld": len(scenes),
                    "controller": "host (numpy, every stage, Warp's control callback)",
                    "changed": list(W.changed),
                    "wall_time_s": wall,
                    "compile_s": compile_s,
                    "mujoco_warp_version": mujoco_warp.__version__,
                    "warp_version": wp.__version__,
                },
                omega=omega[keep],
            )
        )
    return out


def run_batch(
    scenes: Sequence[Scene], dt: float | None, device: str, t_end: float | None,
    progress: Callable[[float], None] | None = None,
) -> list[Trajectory]:  # fmt: skip
    """Every scene's trajectory, in order: scenes grouped into ``nworld`` runs (one structure,
    one step, one output grid and one batchable model each). ``progress(t)`` per output sample of
    each group. ``ValueError`` naming the field when Warp refuses a scene's twin."""
    wp, mjw, dev = import_warp(device)
    groups: dict[tuple, list[int]] = {}
    for i, s in enumerate(scenes):
        groups.setdefault(_group_key(s, dt, t_end), []).append(i)
    out: list[Trajectory | None] = [None] * len(scenes)
    pending = list(groups.values())
    longest = max(t_end or s.output.t_end for s in scenes)
    done = 0  # worlds run so far: a later group's progress starts where the last one ended

    def share(ix: list[int]):
        if progress is None or len(ix) == len(scenes):
            return progress
        horizon, before = t_end or scenes[ix[0]].output.t_end, done
        return lambda t: progress(
            longest * (before + len(ix) * min(t / horizon, 1.0)) / len(scenes)
        )

    while pending:
        idx = pending.pop(0)
        try:
            trajs = _guarded(lambda ix=idx: run_worlds(
                mjw, wp, dev, [scenes[i] for i in ix], dt, t_end, share(ix)))  # fmt: skip
        except Unbatchable:
            if len(idx) == 1:
                raise
            pending[:0] = [idx[: len(idx) // 2], idx[len(idx) // 2 :]]  # halve and retry
            continue
        for i, tr in zip(idx, trajs, strict=True):
            out[i] = tr
        done += len(idx)
    return out  # type: ignore[return-value]


def _guarded(fn):
    """``fn()``, Warp's refusal of a twin (``NotImplementedError``) as a ``ValueError``."""
    try:
        return fn()
    except NotImplementedError as exc:
        raise ValueError(f"model: MuJoCo Warp refuses the twin: {exc}") from None


def pointwise_qddot(
    scene: Scene, dt: float | None, device: str, t: np.ndarray, q: np.ndarray, qdot: np.ndarray
) -> np.ndarray:
    """Warp's q̈ (N, n+7), paper coordinates, at N given states (one world each): the scene's
    controller (and given torque) applied, as in every stage of a run."""
    wp, mjw, dev = import_warp(device)
    t = np.atleast_1d(np.asarray(t, dtype=float))
    q, qdot = np.atleast_2d(q), np.atleast_2d(qdot)
    W = _guarded(lambda: Worlds(mjw, wp, dev, [scene] * len(t), dt))
    tm = W.tms[0]
    qpos, qvel = tm.to_mujoco(q, qdot)
    W.set_state(qpos, qvel)
    W.forward(t)
    qp, qv, qa = W.arrays()
    return tm.to_paper_acc(qp, qv, qa)


__all__ = [
    "ENGINE",
    "STAGE_NODES",
    "Unbatchable",
    "Worlds",
    "batched_model",
    "import_warp",
    "pointwise_qddot",
    "run_batch",
    "run_worlds",
    "twin_for",
]
