"""Effects cost time too: one dynamics evaluation with each of the scene's effects switched off.

For the scene as given and for each effect it lists, the scene without that effect
(``scene.with_effects(...)``; a combination the scene validation refuses is reported as such), the
median cost in µs of one evaluation, with the fastest and slowest of the rounds (``<column>_min``,
``<column>_max``; ``<column>_resolved``: the variant's range and the full scene's do not meet, so
their ratio ``<column>_rel`` is a difference the timings support), of:

* ``analytic_numpy``: ``TumblingModel.acceleration`` (the reference numpy path);
* ``analytic_fast``: the analytic engine's default evaluator (compiled kernel when numba is
  installed: what ``analytic.simulate`` calls per right-hand side);
* ``mj_forward``: MuJoCo's ``mj_forward`` on ``model_xml.build_spec(scene).compile()`` at the
  scene's initial state (no Python callback: controls stay zero);
* ``mj_forward_ctrl``: ``mj_forward`` with the twin's callbacks installed (installing and removing
  them included) (the analytic controller
  in ``mjcb_control`` for controlled scenes; the spring user bias when the scene needs it), i.e. one
  stage of the controlled MuJoCo plant.

Run alone: ``python -m validation.studies.effects_cost [SCENE]``.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from typing import Any

from analytic.model import TumblingModel
from analytic.scene import Scene
from analytic.simulate import evaluator
from validation.scenes import DEFAULT_SCENE, resolve_scene

COST_COLUMNS = ("analytic_numpy", "analytic_fast", "mj_forward", "mj_forward_ctrl")


def _batch(fn) -> int:
    """Calls per timed batch (~10 ms)."""
    t0 = time.perf_counter()
    fn()
    one = max(time.perf_counter() - t0, 1e-7)
    return max(1, int(0.01 / one))


def evaluation_callables(scene: Scene) -> dict[str, Callable[[], Any]]:
    """One zero-argument callable per column of :data:`COST_COLUMNS`, warmed up."""
    # deferred: MuJoCo ~0.2 s (python -X importtime); the sweep's markdown imports this module
    import mujoco

    from mj_bridge.twin import Twin
    from model_xml import build_spec

    q, qd = scene.initial.q0(), scene.initial.qdot0()
    model = TumblingModel(scene)
    fast = evaluator(model, "auto")
    m = build_spec(scene).compile()
    d = mujoco.MjData(m)
    tw = Twin(scene, integrator="RK4")
    tw.set_state(0.3, q, qd)

    def mj_ctrl() -> None:
        with tw.callbacks():
            mujoco.mj_forward(tw.m, tw.d)

    fns = {
        "analytic_numpy": lambda: model.acceleration(0.3, q, qd),
        "analytic_fast": lambda: fast(0.3, q, qd),
        "mj_forward": lambda: mujoco.mj_forward(m, d),
        "mj_forward_ctrl": mj_ctrl,
    }
    for fn in fns.values():
        fn()  # JIT compile or cache load, first-call allocations
    return fns


def effects_cost(scene: Scene, repeats: int = 15) -> list[dict[str, Any]]:
    """One row for the full scene and one per effect switched off (``off`` = effect name).

    Costs in µs per evaluation: the median over ``repeats`` rounds, each round timing one batch of
    every (variant, column) in turn, so that a slow spell of a shared machine spreads over all
    variants instead of biasing one.
    """
    rows: list[dict[str, Any]] = []
    variants: list[tuple[str, Any]] = [("", scene.effects)]
    variants += [(str(e.value), scene.effects - {e}) for e in sorted(scene.effects)]
    fns: dict[tuple[int, str], Callable[[], Any]] = {}
    for off, effects in variants:
        row: dict[str, Any] = {"off": off or "(none: full scene)", "note": ""}
        row.update(dict.fromkeys(COST_COLUMNS))
        rows.append(row)
        try:
            sc = scene.with_effects(effects)
        except ValueError as exc:
            row["note"] = f"refused by the scene validation: {exc}"
            continue
        try:
            for c, fn in evaluation_callables(sc).items():
                fns[(len(rows) - 1, c)] = fn
        except Exception as exc:  # an engine that cannot build this variant is a result
            row["note"] = f"{type(exc).__name__}: {exc}"
    numbers = {k: _batch(fn) for k, fn in fns.items()}
    samples: dict[tuple[int, str], list[float]] = {k: [] for k in fns}
    for _ in range(repeats):
        for k, fn in fns.items():
            n = numbers[k]
            t0 = time.perf_counter()
            for _ in range(n):
                fn()
            samples[k].append((time.perf_counter() - t0) / n * 1e6)
    for (i, c), v in samples.items():
        rows[i][c] = statistics.median(v)
        rows[i][f"{c}_min"] = min(v)
        rows[i][f"{c}_max"] = max(v)
    full = rows[0]
    for row in rows:
        row["repeats"] = repeats
        for c in COST_COLUMNS:
            v, f = row[c], full[c]
            row[f"{c}_rel"] = (v / f) if (v is not None and f) else None
            row[f"{c}_resolved"] = resolved(row, full, c)
    return rows


def resolved(row: dict[str, Any], full: dict[str, Any], column: str) -> bool | None:
    """Whether a variant's cost differs from the full scene's beyond the timings' spread: their
    ranges [fastest, slowest] over the rounds do not meet. None when either was not timed; the
    full scene's own row is never resolved from itself."""
    lo, hi = row.get(f"{column}_min"), row.get(f"{column}_max")
    flo, fhi = full.get(f"{column}_min"), full.get(f"{column}_max")
    if None in (lo, hi, flo, fhi):
        return None
    if row is full:
        return False
    return bool(hi < flo or lo > fhi)


def effects_markdown(rows: list[dict[str, Any]]) -> list[str]:
    """Markdown table lines: µs with the spread over the rounds, and the ratio to the full scene's
    cost only where the spreads do not overlap (:func:`resolved`)."""

    def cell(r, c):
        v, rel = r[c], r.get(f"{c}_rel")
        if v is None:
            return "–"
        spread = ""
        if r.get(f"{c}_min") is not None:
            spread = f" [{r[f'{c}_min']:.3g}–{r[f'{c}_max']:.3g}]"
        if r is rows[0]:
            return f"{v:.3g}{spread}"
        if r.get(f"{c}_resolved"):
            return f"{v:.3g}{spread} (×{rel:.2f})"
        return f"{v:.3g}{spread} (≈ full: ranges overlap)"

    repeats = rows[0].get("repeats") if rows else None
    rounds = f"over {repeats} rounds" if repeats else "over the rounds"
    lines = [
        f"Median µs per evaluation {rounds}, [fastest–slowest]. A ratio to the full scene's cost "
        "(×) is given only where the two ranges do not meet; otherwise the timings do not tell "
        "the two costs apart (≈ full). analytic_fast is what the analytic engine calls per "
        "right-hand side; mj_forward_ctrl includes the analytic controller in MuJoCo's control "
        "callback.",
        "",
        "| effect off | " + " | ".join(COST_COLUMNS) + " | note |",
        "|---|" + "---|" * (len(COST_COLUMNS) + 1),
    ]
    for r in rows:
        note = r["note"].replace("|", "/").replace("\n", " ")
        lines.append(
            f"| {r['off']} | " + " | ".join(cell(r, c) for c in COST_COLUMNS) + f" | {note} |"
        )
    return lines


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m validation.studies.effects_cost")
    ap.add_argument("scene", nargs="?", default=DEFAULT_SCENE)
    ap.add_argument("--repeats", type=int, default=15)
    args = ap.parse_args(argv)
    rows = effects_cost(resolve_scene(args.scene), repeats=args.repeats)
    print("\n".join(effects_markdown(rows)))
    return 0


if __name__ == "__main__":
    from validation.runs.environment import as_program

    as_program()  # one BLAS thread, as `tumble` has
    raise SystemExit(main())
