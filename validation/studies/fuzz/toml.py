"""A minimal counterexample as a commented scene file.

The file is :func:`analytic.scene.dump.scene_to_toml` of the minimal scene (every table the loader
resolves, so ``tumble validate FILE``, the pytest plugin and the hard-case runner read it as it
is), its header the disagreement, the referee's verdicts and the command that reproduces it (with
the campaign's per-run time limit, ``--time-limit SECONDS``), and a
``[hard_case]`` table: each plant but the analytic one against the analytic plant's run, bound
by the comparison's own threshold (``hard_<quantity>`` in ``[thresholds]``). The case fails while
the disagreement lasts and passes once it is fixed.
"""

from __future__ import annotations

import copy
import re
from typing import TYPE_CHECKING, Any

from analytic.scene import scene_from_dict
from analytic.scene.dump import scene_to_toml
from validation.compare.thresholds import thresholds_for

if TYPE_CHECKING:
    from validation.studies.fuzz.records import Counterexample, FuzzConfig

HARD_MEASURES = ("position_C", "attitude", "rod_positions")
"""The hard-case measures against the analytic plant a counterexample's case judges."""


def slug(key: str) -> str:
    """A file-name-safe form of a disagreement's key (``outlier-rod_positions-pinocchio``)."""
    return re.sub(r"[^A-Za-z0-9_.]+", "-", key).strip("-.") or "disagreement"


def with_hard_case(data: dict[str, Any], criterion: str) -> dict[str, Any]:
    """``data`` with a ``[hard_case]`` table (module docstring) and its bounds."""

    out = copy.deepcopy(data)
    th = thresholds_for(None)
    n = len(out.get("masses", {}).get("mass", []))
    measures = [m for m in HARD_MEASURES if m != "rod_positions" or n]
    out.setdefault("thresholds", {}).update({f"hard_{m}": th[m].value for m in measures})
    out["hard_case"] = {
        "criterion": criterion,
        "fast": True,
        "check": [
            {
                "what": m,
                "against": "analytic",
                "bound": f"hard_{m}",
                "why": f"the comparison's own {m} threshold (validation.compare.thresholds)",
            }
            for m in measures
        ],
    }
    return out


def _comment_lines(text: str) -> list[str]:
    return [f"# {line}".rstrip() for line in text.splitlines()]


def counterexample_toml(ex: Counterexample, cfg: FuzzConfig) -> str:
    """The counterexample's scene file (module docstring)."""
    d = ex.disagreement
    data = copy.deepcopy(ex.data)
    data["scene"]["name"] = f"fuzz/{slug(d.key)}"
    data.setdefault("output", {})["t_end"] = ex.horizon  # the shrunk horizon is the file's own
    data["scene"]["description"] = f"Minimal scene of a fuzzing campaign: {d.kind.value} {d.what}"
    data = with_hard_case(data, f"the plants agree on this scene (the campaign found: {d.key})")
    scene = scene_from_dict(data)
    plants = ",".join(cfg.plants)
    lines = [
        f"Minimal counterexample: {d.kind.value}: {d.what}" + (f" ({d.plant})" if d.plant else ""),
        f"Found in scene {ex.found_in} of the campaign with seed {cfg.seed} (plants {plants}, "
        f"horizon {cfg.horizon:g} s), shrunk in {ex.evaluations} evaluations to horizon "
        f"{ex.horizon:g} s.",
        f"Known finding: {ex.known}." if ex.known else "A new finding.",
        "Verdicts it reproduces (the referee):",
    ]
    lines += [f"  {v['quantity']}: {v['verdict']} {v['outlier']}".rstrip() for v in ex.outcome.verdicts]
    failed = [k for k, v in ex.outcome.checks.items() if v[2] == "FAIL"]
    lines.append(f"Failed checks: {', '.join(failed) if failed else 'none'}.")
    for name, msg in ex.outcome.messages.items():
        lines.append(f"{name}: {msg}")
    if ex.settlement is not None:
        lines.append(f"Cause: {ex.settlement.cause.value}: {ex.settlement.text}.")
    lines.append(
        f"Reproduce: tumble validate FILE --plants {plants} --t-end {ex.horizon:g} "
        f"--time-limit {cfg.time_limit_s:g}"
    )
    return scene_to_toml(scene, header="\n".join(lines))


__all__ = ["HARD_MEASURES", "counterexample_toml", "slug", "with_hard_case"]
