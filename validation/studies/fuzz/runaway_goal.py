"""The runaway campaign: a campaign of violent scenes that must end in verdicts a maintainer keeps.

Seed :data:`RUNAWAY_SEED` with :data:`RUNAWAY_SCENES` scenes over :data:`RUNAWAY_HORIZON_S` s draws
runaways (masses flung kilometres along a rod, a controlled motion that blows up, spins of
hundreds of rad/s). Run as ``tumble fuzz`` runs it (the default plants, the default executor),
the campaign must hold four goals (:func:`runaway_campaign`):

1. no new finding whose cause is ``model`` (each minimal counterexample is settled,
   :mod:`validation.studies.fuzz.settle`): a correct engine is never blamed for a numerical limit;
2. no plant run reaches its time limit (the adaptive plants' error control follows the state's
   magnitude and stops a run round-off limited, :mod:`analytic.error_scale`, instead of grinding);
3. the whole campaign, shrinking and settling included, within :data:`RUNAWAY_WALL_LIMIT_S` s of
   wall on the machine it runs on (2 cores here);
4. every counterexample it writes reproduces what it reports under ``tumble validate``, run by
   the command its ``Reproduce:`` line gives (with the campaign's per-run time limit): an outlier
   is the referee's outlier on that quantity again, a plant that stopped stops again, a failed
   check fails again, and no plant run passes its time limit.

``python -m validation.studies.fuzz.bench --runaway`` prints them; the campaign's files stay in a
temporary directory unless ``out`` is given.
"""

from __future__ import annotations

import functools
import json
import os
import shlex
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from validation.runs.lifetime import die_with_parent

RUNAWAY_SEED = 7
"""The campaign's seed: its 40 scenes hold two runaways that ground the adaptive plants to their
time limit and a minimal scene once settled, wrongly, as a model difference of MuJoCo."""

RUNAWAY_SCENES = 40
RUNAWAY_HORIZON_S = 2.0

RUNAWAY_WALL_LIMIT_S = 150.0
"""The campaign's wall-time goal on 2 cores, s: 40 scenes of three plants with every finding
shrunk and settled; the runs that ground to their 30 s limits had taken it to 235 s."""

REPRODUCE_TIMEOUT_S = 600.0
"""How long one reproduction may take in all before it counts as not reproduced, s: its plants are
held to the campaign's per-run limit by ``--time-limit``; this only guards the measurement."""


@dataclass(frozen=True)
class Reproduction:
    """One counterexample run again by its ``Reproduce:`` command.

    Attributes:
        key: the finding's key (``outlier:rod_positions:mujoco``).
        reproduced: whether the report shows the finding again and no run passed its limit.
        why: one line: what the report showed.
        wall_s: the command's wall time, s.
    """

    key: str
    reproduced: bool
    why: str
    wall_s: float


@dataclass(frozen=True)
class RunawayResult:
    """The runaway campaign's figures (module docstring).

    Attributes:
        wall_s: the campaign's wall time, s.
        scenes: scenes judged.
        causes: finding key -> its settled cause (new findings and known ones).
        model: keys of new findings settled as ``model``.
        timeouts: plant -> the runs that passed the time limit.
        reproductions: one per counterexample.
    """

    wall_s: float
    scenes: int
    causes: dict[str, str]
    model: tuple[str, ...]
    timeouts: dict[str, int]
    reproductions: tuple[Reproduction, ...]

    def lines(self) -> list[str]:
        """The four goals, a line each, and a line per reproduction."""
        n_timeouts = sum(self.timeouts.values())
        bad = [r for r in self.reproductions if not r.reproduced]
        causes = ", ".join(f"{k} {v}" for k, v in sorted(self.causes.items())) or "none"
        out = [
            f"runaway campaign (seed {RUNAWAY_SEED}, {self.scenes} scenes, {RUNAWAY_HORIZON_S:g} s): "
            f"model findings {len(self.model)} (goal 0: {'holds' if not self.model else 'fails'}); "
            f"findings: {causes}",
            f"runaway campaign: runs over the time limit {n_timeouts} (goal 0: "
            f"{'holds' if not n_timeouts else 'fails'})",
            f"runaway campaign: wall {self.wall_s:.1f} s (goal ≤ {RUNAWAY_WALL_LIMIT_S:g} s: "
            f"{'holds' if self.wall_s <= RUNAWAY_WALL_LIMIT_S else 'fails'})",
            f"runaway campaign: counterexamples reproduced by their command "
            f"{len(self.reproductions) - len(bad)} / {len(self.reproductions)} "
            f"({'holds' if not bad else 'fails'})",
        ]
        out += [f"  {r.key}: {'reproduced' if r.reproduced else 'NOT reproduced'} in "
                f"{r.wall_s:.1f} s: {r.why}" for r in self.reproductions]
        return out


def _shows(key: str, report: dict) -> tuple[bool, str]:
    """Whether validate's ``report`` (report.json) shows the finding ``key`` again, and what it
    showed."""
    kind, _, rest = key.partition(":")
    over = [p["engine"] for p in report.get("plants", []) if "time limit" in p.get("message", "")]
    if over:
        return False, f"{', '.join(over)} passed the time limit"
    if kind == "outlier":
        quantity, _, plant = rest.rpartition(":")
        for v in report.get("referee", []):
            if v.get("quantity") == quantity:
                named = [o["plant"] for o in v.get("outliers", [])]
                return plant in named, f"the referee on {quantity}: {v.get('verdict')} {named}"
        return False, f"no referee verdict on {quantity}"
    if kind in ("stopped", "raised"):
        plant = rest.rpartition(":")[2]
        for p in report.get("plants", []):
            if p.get("engine") == plant:
                return p.get("status") != "ok", f"{plant} {p.get('status')} at t = {p.get('t_reached')} s"
        return False, f"{plant} did not run"
    passed = {f"{c.get('subject')}.{c.get('name')}": c.get("passed")
              for c in report.get("checks", []) if c.get("applicable", True)}
    label = rest.split(":")[0]
    if label in passed:
        return passed[label] is False, f"{label} {'passes' if passed[label] else 'fails'}"
    return False, f"no {label} in the report"


def reproduce(command: str, key: str, out: Path) -> Reproduction:
    """Run a counterexample's ``Reproduce:`` ``command`` (a ``tumble validate`` line) into ``out``
    and say whether it shows ``key`` again."""
    args = shlex.split(command)
    if args[:2] != ["tumble", "validate"]:
        raise ValueError(f"command: not a tumble validate line (got {command!r})")
    t0 = time.perf_counter()
    try:
        subprocess.run(
            [sys.executable, "-m", "validation", *args[1:], "--out", str(out)],
            capture_output=True, text=True, timeout=REPRODUCE_TIMEOUT_S, stdin=subprocess.DEVNULL,
            check=False, preexec_fn=functools.partial(die_with_parent, os.getpid()),
        )  # fmt: skip
    except subprocess.TimeoutExpired:
        return Reproduction(key, False, f"not done in {REPRODUCE_TIMEOUT_S:g} s",
                            time.perf_counter() - t0)
    wall = time.perf_counter() - t0
    try:
        report = json.loads((out / "report.json").read_text())
    except (OSError, ValueError) as exc:
        return Reproduction(key, False, f"no report: {exc}", wall)
    ok, why = _shows(key, report)
    return Reproduction(key, ok, why, wall)


def runaway_campaign(
    out: str | Path | None = None, progress: Callable[[str], None] = print
) -> RunawayResult:
    """Run the runaway campaign as ``tumble fuzz`` does, then each counterexample's command
    (module docstring)."""
    from validation.studies.fuzz.campaign import fuzz

    with tempfile.TemporaryDirectory(prefix="tumble-runaway-") as tmp:
        root = Path(out) if out is not None else Path(tmp) / "campaign"
        progress(f"  the runaway campaign (seed {RUNAWAY_SEED}, {RUNAWAY_SCENES} scenes) ...")
        t0 = time.perf_counter()
        fuzz(root, budget=RUNAWAY_SCENES, seed=RUNAWAY_SEED, horizon=RUNAWAY_HORIZON_S)
        wall = time.perf_counter() - t0
        summary = json.loads((root / "campaign.json").read_text())
        found = summary["counterexamples"]
        causes = {f["key"]: f["settlement"]["cause"] for f in found if f.get("settlement")}
        model = tuple(f["key"] for f in found
                      if not f.get("known") and f.get("settlement", {}).get("cause") == "model")
        reps = []
        for i, f in enumerate(found):
            progress(f"  reproducing {f['key']} ...")
            reps.append(reproduce(f["command"], f["key"], Path(tmp) / f"reproduce-{i}"))
    return RunawayResult(
        wall, int(summary["scenes"]), causes, model,
        {str(k): int(v) for k, v in summary.get("timeouts", {}).items()}, tuple(reps),
    )  # fmt: skip


__all__ = [
    "REPRODUCE_TIMEOUT_S",
    "RUNAWAY_HORIZON_S",
    "RUNAWAY_SCENES",
    "RUNAWAY_SEED",
    "RUNAWAY_WALL_LIMIT_S",
    "Reproduction",
    "RunawayResult",
    "reproduce",
    "runaway_campaign",
]
