"""Batched throughput: scenes per second against batch size, for each batched plant, as a ratio to
the C plant's loop over the same scenes (an entry of :data:`validation.bench.goals.GOALS`, and
``tumble bench --batched``).

**The work.** :func:`batch_scenes` makes ``size`` scenes of one structure (the same ``n`` and
effects): the built-in :data:`BASE_SCENE` with each scene's initial spin, the masses' initial
rates and the spin targets drawn apart (seeded), every scene over the same horizon at the same
MuJoCo step (:data:`HORIZON_S`, :data:`DT_S`: short, for CPUs; MuJoCo Warp costs ~19 ms per step
and call on the CPU here). For each batch size (:data:`BATCH_SIZES`), a batched plant
(``batched = True``, ``docs/plugins.md`` §14: ``mjx``, ``mjwarp``) runs the first ``size`` scenes
in **one** ``simulate_batch`` call, and the C plant (``mujoco``) runs the same scenes in its loop
(``simulate_batch`` of a plant that is not batched: one ``simulate`` per scene), at their default
settings.

**What is timed.** The wall clock of each whole call (``call``): for an accelerated plant it
includes its fresh process, the engine's import and its compilation (each of its calls runs in a
process of its own), so it is what a user waits for; and the engine's own stepping time
(``stepping``), ``info["wall_time_s"]`` of the trajectories (for a batch, the largest of them:
its worlds step together; for the loop, their sum), NaN where a plant does not report it. Each
plant runs once first (size 1, not counted: the first compilation, the kernels' disk caches). One
measurement per size, not rounds: a batch of 256 on a CPU takes tens of seconds. Wall time, not
thread CPU time: the work runs in other processes (the load average is printed beside it).

**The devices.** :func:`accelerator_devices` asks JAX and Warp, each in a new process (neither is
imported here: ``docs/plugins.md`` §9), which device they would use; the trajectories' own
``info["device"]`` is printed too. On a machine with a GPU both pick it by default; nothing here
chooses the CPU.

**The goal.** Per plant: at the largest batch size, the time per scene of the batched call over the
C loop's, ``≤`` :data:`THROUGHPUT_LIMIT` (a batch is worth it when it costs less per scene than the
C engine's loop). Measured once (no spread); skipped, with the reason, when no batched plant is
installed or the plant refuses the scene. The figures: ``docs/performance.md``, Batched runs.
"""

from __future__ import annotations

import copy
import importlib.util
import math
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from analytic.plant import Plant
from analytic.scene import Scene, scene_from_dict
from analytic.scene.dump import scene_to_dict
from validation.bench.goal import Goal
from validation.scenes import resolve_scene

BASE_SCENE = "paper_example1_controlled"
"""The scene every batch is drawn around (two masses, springs, gravity, every control channel)."""
BATCH_SIZES = (1, 16, 256)
"""The batch sizes measured by default."""
HORIZON_S = 0.01
"""Each scene's horizon, s: 40 steps at :data:`DT_S` (MuJoCo Warp on a CPU: ~19 ms per step)."""
DT_S = 2.5e-4
"""MuJoCo's step of every scene (the scene's ``[mujoco] timestep``, which the C plant and both
accelerated plants take by default), s."""
C_PLANT = "mujoco"
"""The plant whose loop is the reference: MuJoCo's C engine."""
THROUGHPUT_LIMIT = 1.0
"""A batched plant's time per scene at the largest batch size, over the C plant's loop's: at most
1, a batch no costlier per scene than the loop it replaces."""
PROBE_TIMEOUT_S = 300.0
"""How long asking a library for its device may take, s (importing JAX or Warp, initialising a
GPU's driver)."""

DEVICE_PROBES = {
    "JAX": (
        "jax",
        "import jax; d = jax.devices()[0]; "
        "print(f'{d.platform}:{d.id} ({d.device_kind}; {len(jax.devices())} device(s))')",
    ),
    "Warp": (
        "warp",
        "import warp as wp; wp.config.quiet = True; wp.init(); d = wp.get_preferred_device(); "
        "print(f'{d.alias} ({d.name})')",
    ),
}
"""library -> (module, the code that prints its default device), run in a new process."""

Progress = Callable[[str], None]


def batch_scenes(
    count: int, seed: int = 0, base: str = BASE_SCENE, dt: float = DT_S
) -> list[Scene]:
    """``count`` scenes of ``base``'s structure at MuJoCo step ``dt``: scene 0 is ``base`` itself,
    each other one its initial spin scaled per axis by ``U(0.5, 1.5)``, the masses' initial rates
    shifted by ``U(-0.2, 0.2)`` m/s and its spin targets scaled by ``U(0.8, 1.2)`` (seeded by
    ``seed``); named ``<base>_batch<i>``, ``i`` zero-padded to one width (a name is part of a
    twin: MJX stacks only models whose name tables have one layout)."""
    if isinstance(count, bool) or not isinstance(count, int) or count < 1:
        raise ValueError(f"count: must be a whole number ≥ 1 (got {count!r})")
    data = scene_to_dict(resolve_scene(base))
    data["mujoco"]["timestep"] = float(dt)
    rng = np.random.default_rng(seed)
    width = len(str(count - 1))
    out = []
    for i in range(count):
        d = copy.deepcopy(data)
        d["scene"]["name"] = f"{base}_batch{i:0{width}d}"  # one length: the twins' name tables
        if i:
            init = d["initial"]
            init["omega"] = [float(w * rng.uniform(0.5, 1.5)) for w in init["omega"]]
            init["pdot"] = [float(v + rng.uniform(-0.2, 0.2)) for v in init["pdot"]]
            target = d.get("control", {}).get("omega")
            if target and "b" in target:
                target["b"] = [float(b * rng.uniform(0.8, 1.2)) for b in target["b"]]
        out.append(scene_from_dict(d))
    return out


def accelerator_devices(timeout_s: float = PROBE_TIMEOUT_S) -> dict[str, str]:
    """library (``JAX``, ``Warp``) -> the device it uses by default (``"cpu:0 (cpu; 1
    device(s))"``, ``"cuda:0 (NVIDIA A100 ...)"``), each asked in a new process; a library that is
    not installed is left out, one that fails says why."""
    out: dict[str, str] = {}
    for lib, (module, code) in DEVICE_PROBES.items():
        if importlib.util.find_spec(module) is None:
            continue
        try:
            done = subprocess.run(
                [sys.executable, "-c", code],
                capture_output=True,
                text=True,
                timeout=timeout_s,
                check=False,
            )
        except subprocess.TimeoutExpired:
            out[lib] = f"unknown (no answer in {timeout_s:g} s)"
            continue
        lines = done.stdout.strip().splitlines()
        if done.returncode == 0 and lines:
            out[lib] = lines[-1]
        else:
            err = done.stderr.strip().splitlines()
            out[lib] = f"unknown ({err[-1] if err else f'exit {done.returncode}'})"
    return out


def batched_plants() -> list[Plant]:
    """Every registered plant with ``batched = True`` that can run here, in report order."""
    from mj_bridge.plants import plant, registered

    return [plant(n) for n, cls in registered().items() if cls.batched and not cls.unavailable()]


@dataclass(frozen=True)
class Timed:
    """One ``simulate_batch`` call: its wall (s), its engine's stepping time (s; NaN: not
    reported), the devices its trajectories name and how many of them did not finish."""

    wall_s: float
    stepping_s: float
    devices: tuple[str, ...]
    failed: int


def timed_call(pl: Plant, scenes: Sequence[Scene], horizon: float) -> Timed:
    """``pl.simulate_batch(scenes, t_end=horizon)`` at its default settings, timed (module
    docstring: stepping is the batch's largest ``info["wall_time_s"]`` for a batched plant, the
    sum for a loop)."""
    t0 = time.perf_counter()
    trajs = pl.simulate_batch(list(scenes), t_end=horizon)
    wall = time.perf_counter() - t0
    steps = [tr.info.get("wall_time_s") for tr in trajs]
    if all(isinstance(s, int | float) for s in steps) and steps:
        stepping = float(max(steps) if pl.batched else sum(steps))
    else:
        stepping = math.nan
    devices = tuple(sorted({str(tr.info["device"]) for tr in trajs if "device" in tr.info}))
    failed = sum(1 for tr in trajs if tr.status.value != "ok")
    return Timed(wall, stepping, devices, failed)


@dataclass(frozen=True)
class BatchPoint:
    """One batch size: the batched plant's call and the C plant's loop over the same scenes."""

    size: int
    batched: Timed
    loop: Timed

    @property
    def scenes_per_s(self) -> float:
        return self.size / self.batched.wall_s

    @property
    def loop_scenes_per_s(self) -> float:
        return self.size / self.loop.wall_s

    @property
    def speedup(self) -> float:
        """The batched call's scenes per second over the C loop's (> 1: the batch is faster)."""
        return self.loop.wall_s / self.batched.wall_s

    @property
    def stepping_speedup(self) -> float:
        """The same, of the engines' stepping times (NaN where either is not reported)."""
        return self.loop.stepping_s / self.batched.stepping_s

    def to_dict(self) -> dict[str, Any]:
        return {
            "size": self.size,
            "wall_s": self.batched.wall_s,
            "stepping_s": self.batched.stepping_s,
            "scenes_per_s": self.scenes_per_s,
            "failed": self.batched.failed,
            "c_loop_wall_s": self.loop.wall_s,
            "c_loop_stepping_s": self.loop.stepping_s,
            "c_loop_scenes_per_s": self.loop_scenes_per_s,
            "speedup": self.speedup,
            "stepping_speedup": self.stepping_speedup,
        }


def _rate(size: int, seconds: float) -> str:
    return f"{size / seconds:10.3g}" if seconds > 0 and math.isfinite(seconds) else f"{'-':>10}"


def table_lines(points: Sequence[BatchPoint]) -> list[str]:
    """The printed table under a plant's line: per batch size, the batched call's seconds,
    its scenes per second (whole call; engine stepping), the C loop's, and the batched one's
    multiple of the loop's (whole calls; stepping)."""
    head = (
        f"    {'batch':>6} {'call s':>14} {'scenes/s':>10} {'stepping':>10} "
        f"{'C loop s':>10} {'scenes/s':>10} {'stepping':>10} {'x C loop':>9} {'(stepping)':>10}"
    )
    rows = [head]
    for p in points:
        rows.append(
            f"    {p.size:>6} {p.batched.wall_s:14.3g} {_rate(p.size, p.batched.wall_s)} "
            f"{_rate(p.size, p.batched.stepping_s)} {p.loop.wall_s:10.3g} "
            f"{_rate(p.size, p.loop.wall_s)} {_rate(p.size, p.loop.stepping_s)} "
            f"{p.speedup:9.3g} {p.stepping_speedup:10.3g}"
            + (f"  ({p.batched.failed} of {p.size} did not finish)" if p.batched.failed else "")
        )
    return rows


def goal_name(label: str, largest: int) -> str:
    return f"{label} batched: {largest} scenes in one call, time per scene / MuJoCo C loop's"


def goal_batched_throughput(
    plants: Sequence[Plant] | None = None,
    sizes: Sequence[int] = BATCH_SIZES,
    horizon: float = HORIZON_S,
    dt: float = DT_S,
    base: str = BASE_SCENE,
    progress: Progress = print,
    devices: dict[str, str] | None = None,
) -> tuple[Goal, ...]:
    """One :class:`Goal` per batched plant (default :func:`batched_plants`), its table printed to
    ``progress`` as it is measured (module docstring); ``devices`` as :func:`accelerator_devices`
    gives (asked when None)."""
    from mj_bridge.plants import plant

    sizes = sorted({int(s) for s in sizes})
    if not sizes or sizes[0] < 1:
        raise ValueError(f"sizes: batch sizes must be whole numbers ≥ 1 (got {list(sizes)!r})")
    chosen = list(batched_plants() if plants is None else plants)
    largest = sizes[-1]
    if not chosen:
        return (
            Goal(
                "batched throughput",
                math.nan,
                THROUGHPUT_LIMIT,
                skipped="no batched plant is installed (mjx: the [mjx] extra; mjwarp: [warp])",
            ),
        )
    scenes = batch_scenes(largest, base=base, dt=dt)
    steps = round(horizon / dt)
    progress(
        f"  batched throughput: {largest} scenes of {base}'s structure (initial spins, mass rates "
        f"and spin targets drawn apart), {horizon:g} s at dt {dt:g} s ({steps} steps) each"
    )
    devices = accelerator_devices() if devices is None else devices
    progress(
        "  devices: "
        + ("; ".join(f"{lib} {d}" for lib, d in devices.items()) or "neither JAX nor Warp")
    )
    c = plant(C_PLANT)
    timed_call(c, scenes[:1], horizon)  # its first run: MuJoCo's and the controller's set-up
    loops = {size: timed_call(c, scenes[:size], horizon) for size in sizes}
    out = []
    for pl in chosen:
        out.append(_plant_goal(pl, scenes, sizes, horizon, loops, progress))
    return tuple(out)


def _plant_goal(
    pl: Plant,
    scenes: list[Scene],
    sizes: list[int],
    horizon: float,
    loops: dict[int, Timed],
    progress: Progress,
) -> Goal:
    """The goal of one batched plant (:func:`goal_batched_throughput`)."""
    name = goal_name(pl.label, sizes[-1])
    try:
        pl.check_scene(scenes[0])
    except ValueError as exc:
        return Goal(name, math.nan, THROUGHPUT_LIMIT, skipped=f"it refuses the scene: {exc}")
    failure = ""
    points: list[BatchPoint] = []
    try:
        first = timed_call(pl, scenes[:1], horizon)
        for s in sizes:
            points.append(BatchPoint(s, timed_call(pl, scenes[:s], horizon), loops[s]))
    except Exception as exc:  # a plant's failure is its goal's, never the benchmark's
        if not points:
            return Goal(name, math.inf, THROUGHPUT_LIMIT, f"a run failed: {exc}")
        failure = f"the batch of {sizes[len(points)]} failed: {exc}"
    settings = pl.describe(pl.default_settings(scenes[0]))
    where = ", ".join(sorted({d for p in points for d in p.batched.devices})) or "not reported"
    progress(
        f"  {pl.label} ({settings}; device {where}): first call {first.wall_s:.3g} s "
        "(compilation, not counted)"
    )
    for line in table_lines(points):
        progress(line)
    if failure:
        progress(f"    {failure}")
    top = points[-1]
    value = 1.0 / top.speedup if not failure else math.inf
    return Goal(
        name,
        value,
        THROUGHPUT_LIMIT,
        f"{top.scenes_per_s:.3g} scenes/s in one call of {top.size} against "
        f"{top.loop_scenes_per_s:.3g} in the C loop (whole calls; the engines' stepping alone: "
        f"{top.stepping_speedup:.3g}x the loop's); device {where}"
        + (f"; {failure}" if failure else ""),
        data={
            "plant": pl.engine,
            "settings": settings,
            "device": where,
            "horizon_s": horizon,
            "first_call_s": first.wall_s,
            "points": [p.to_dict() for p in points],
            "failure": failure,
        },
    )


__all__ = [
    "BASE_SCENE",
    "BATCH_SIZES",
    "C_PLANT",
    "DT_S",
    "HORIZON_S",
    "THROUGHPUT_LIMIT",
    "BatchPoint",
    "Timed",
    "accelerator_devices",
    "batch_scenes",
    "batched_plants",
    "goal_batched_throughput",
    "table_lines",
    "timed_call",
]
