"""Agreement as an assertion: :func:`assert_agree`, and the readable rows a failed check prints.

The same text serves the pytest plugin (:mod:`validation.testing.pytest_plugin`: one failed test item per
check) and plain tests (:func:`assert_agree` raises ``AssertionError`` with the table of failed
checks). Importing this module is cheap: numpy, MuJoCo and the plants are imported when a scene
runs, not before.
"""

from __future__ import annotations

import math
import shutil
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover - types only
    from analytic.scene import Scene
    from validation.compare.checks import Check
    from validation.validate import ValidationResult

PAIR_CHECKS = (
    "position_C",
    "attitude",
    "rod_positions",
    "velocity_C",
    "rod_velocities",
    "angular_velocity",
    "control_torque",
    "rod_forces",
)
"""Checks made on every pair of plants, in report order (``rod_forces`` only with masses): the
values of :class:`validation.compare.differences.Difference`, spelled out here so that importing the plugin
does not import numpy (``tests/validation/testing/test_pytest_plugin.py`` checks the two agree)."""


def _num(x: float) -> str:
    return "nan" if isinstance(x, float) and math.isnan(x) else f"{x:.4g}"


def _unit(u: str) -> str:
    return "" if u == "1" else f" {u}"


def plant_names(result: ValidationResult) -> tuple[str, ...]:
    """The plants of a result, in report order (from their ``completed`` checks)."""
    return tuple(c.subject.value for c in result.checks if c.name == "completed")


def _values_at(result: ValidationResult, check: Check) -> list[tuple[str, str, str]]:
    """``(whose, what, value)`` rows: every plant's (or pair's) value of the check's quantity at the
    time of its worst value, read from the comparison's series."""
    cmp = result.comparison
    if cmp is None or not check.series or not math.isfinite(check.t_max):
        return []
    # deferred: numpy ~50 ms, the plants ~0.1 s (python -X importtime); the plugin imports this
    import numpy as np

    own = check.series.split(".", 1)[1]  # position_C, e_omega_law, energy, ...
    if check.subject.is_pair:
        keys = [s.key for s in cmp.series if s.subject.is_pair and s.name == own]
        if check.name == "control_torque":
            keys += [s.key for s in cmp.series if not s.subject.is_pair and s.name == "torque"]
        elif check.name == "rod_forces":
            keys += [
                s.key
                for s in cmp.series
                if not s.subject.is_pair and s.name.startswith("rod_force_")
            ]
    else:
        keys = [s.key for s in cmp.series if not s.subject.is_pair and s.name == own]
    rows = []
    for key in keys:
        s = cmp.get(key)
        if not s.t.size:
            continue
        i = int(np.argmin(np.abs(s.t - check.t_max)))
        v = np.asarray(s.values[i], float)
        val = _num(float(v)) if v.ndim == 0 else "[" + ", ".join(_num(float(x)) for x in v) + "]"
        mark = "  <- this check" if key == check.series else ""
        rows.append((s.subject.value, s.label, f"{val}{_unit(s.unit)}{mark}"))
    return rows


def describe_check(check: Check, result: ValidationResult | None = None) -> str:
    """The report's row of one check, for people: value, threshold, unit, time of the worst value,
    the threshold's reason and (with ``result``) every plant's values at that time."""
    verdict = "<=" if check.passed else ">"
    if check.name == "completed":
        head = f"{check.label}: reached t = {_num(check.value)} s of {_num(check.threshold)} s"
    else:
        head = (
            f"{check.label}: {_num(check.value)}{_unit(check.unit)} {verdict} threshold "
            f"{_num(check.threshold)}{_unit(check.unit)} ({check.subject.value})"
        )
    lines = [head]
    if check.name != "completed":
        lines.append(f"  value      {_num(check.value)}{_unit(check.unit)}")
        lines.append(f"  threshold  {_num(check.threshold)}{_unit(check.unit)}")
        if check.scale != 1.0:
            lines.append(f"  scale      {_num(check.scale)} (the value is max over time / scale)")
        lines.append(f"  worst at   t = {_num(check.t_max)} s")
    lines.append(f"  reason     {check.reason}")
    if result is not None:
        rows = _values_at(result, check)
        if rows:
            lines.append(f"  at t = {_num(check.t_max)} s:")
            w1 = max(len(r[0]) for r in rows)
            w2 = max(len(r[1]) for r in rows)
            lines += [f"    {a:<{w1}}  {b:<{w2}}  {c}" for a, b, c in rows]
    return "\n".join(lines)


def failure_table(result: ValidationResult, where: str = "") -> str:
    """The failed checks of ``result`` as a table, then each one's row (:func:`describe_check`)."""
    failed = result.failed_checks
    plants = ", ".join(plant_names(result)) or "no plant"
    head = (
        f"{len(failed)} of {len(result.checks)} checks failed for scene {result.scene!r} ({plants})"
    )
    lines = [head + (f"; {where}" if where else "")]
    if result.failure:
        lines.append(f"run failed: {result.failure}")
    if failed:
        cols = [(c.label, _num(c.value), _num(c.threshold), c.unit, _num(c.t_max)) for c in failed]
        hdr = ("check", "value", "threshold", "unit", "worst at t (s)")
        widths = [max(len(r[i]) for r in [hdr, *cols]) for i in range(len(hdr))]
        for r in [hdr, *cols]:
            row = "  ".join(f"{x:<{w}}" for x, w in zip(r, widths, strict=True))
            lines.append(f"  {row}".rstrip())
        lines.append("")
        lines += [describe_check(c, result) for c in failed]
    return "\n".join(lines).rstrip()


def with_thresholds(scene: Scene, thresholds: Mapping[str, Any]) -> Scene:
    """``scene`` with ``thresholds`` laid over its ``[thresholds]`` table (checked first: a bad
    name or value raises the loader's one-line ``ValueError`` naming ``thresholds.<name>``)."""
    if not thresholds:
        return scene
    from validation.compare.thresholds import thresholds_for
    from validation.scenes import with_threshold_overrides

    laid = with_threshold_overrides(scene, thresholds)
    thresholds_for(laid)
    return laid


def load(scene: Scene | str | Path) -> Scene:
    """A :class:`Scene` as given, or loaded from a file or a built-in name (``resolve_scene``)."""
    from analytic.scene import Scene

    if isinstance(scene, Scene):
        return scene
    from validation.scenes import resolve_scene

    return resolve_scene(str(scene))


def assert_agree(
    scene: Scene | str | Path,
    plants: Sequence[str] | str | None = None,
    t_end: float | None = None,
    out_dir: str | Path | None = None,
    **thresholds: Any,
) -> ValidationResult:
    """Run ``scene`` on ``plants`` and assert that every agreement check passes.

    Args:
        scene: a :class:`~analytic.scene.Scene`, a scene file or a built-in scene name.
        plants: ``"analytic,mujoco"`` or a sequence of names; default every installed plant.
        t_end: horizon, s (default the scene's ``[output] t_end``).
        out_dir: keep the report and recording here (default: a temporary directory, removed).
        **thresholds: overrides of named thresholds (``position_C=1e-8`` or
            ``attitude={"value": 1e-8, "reason": "..."}``), laid over the scene's ``[thresholds]``.

    Returns:
        the :class:`~validation.validate.ValidationResult` when every check passed.

    Raises:
        AssertionError: a check failed or a plant could not run; the message is the table of the
            failed checks, each with its value, threshold, unit, time of the worst value, reason
            and the plants' values at that time.
        ValueError: bad input (scene, plants, thresholds, t_end), before any plant runs.
    """
    from validation.validate import run_request, validation_request

    # this boundary checks every input once (the scene, the overrides, plants, t_end): the run
    # trusts the request
    request = validation_request(scene, plants=plants, t_end=t_end, thresholds=thresholds)
    tmp = None
    if out_dir is None:
        tmp = tempfile.mkdtemp(prefix="tumble-agree-")
        target: Path = Path(tmp) / "run"
    else:
        target = Path(out_dir)
    try:
        result = run_request(request, target)
    finally:
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)
    if not result.passed:
        where = (
            f"report: {result.files.get('report.md', result.out_dir)}"
            if tmp is None
            else "pass out_dir= to keep the report"
        )
        raise AssertionError(failure_table(result, where))
    return result


__all__ = ["assert_agree", "describe_check", "failure_table", "with_thresholds"]
