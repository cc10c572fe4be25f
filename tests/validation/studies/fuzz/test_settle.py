"""Settling a fuzz finding: no model finding against a correct engine, and a cause sentence that
states only the comparisons made (each inequality it quotes recomputed here from the inputs).

Every settle input is built by hand: a minimal scene's outcome at default settings, the settling
task's result (own errors, tightened outcome, how each default run ended)."""

from __future__ import annotations

import math
import re

import pytest

from validation.studies.fuzz.judge import Disagreement, Kind, Outcome
from validation.studies.fuzz.settle import (
    CONDITIONING_FRACTION,
    SETTLE_MARGIN,
    Cause,
    settle,
)

PLANTS = ("analytic", "mujoco", "pinocchio")
TORQUE = Disagreement(Kind.OUTLIER, "control_torque", "mujoco")
STOP = Disagreement(Kind.STOPPED, "failed", "mujoco")
BADQACC = "unstable: bad qacc (MuJoCo reset the state)"
NUMBER = r"(-?(?:\d+(?:\.\d*)?|\.\d+)(?:e[+-]?\d+)?|inf)"


def _verdict(d: Disagreement, dist: float) -> dict:
    group = [p for p in PLANTS if p != d.plant]
    return {"quantity": d.what, "verdict": "outlier", "outlier": d.plant, "group": group,
            "outliers": [{"plant": d.plant, "distance": dist}]}


def _outcome(d: Disagreement, dist: float, checks=None, scales=None, stopped=False) -> Outcome:
    found = [d, STOP] if stopped else [d]
    return Outcome(
        ran=PLANTS, checks=dict(checks or {}), verdicts=(_verdict(d, dist),),
        disagreements=tuple(sorted(found)),
        messages={"mujoco": BADQACC} if stopped else {},
        reached={"mujoco": 0.41} if stopped else {},
        scales=dict(scales or {}),
    )


def _task(own, tightened: Outcome, runs=None, bounds=None, untightened=None) -> dict:
    return {
        "own_errors": own,
        "settings": {p: [f"{p} default", f"{p} tight"] for p in PLANTS},
        "untightened": untightened or {},
        "tightened": tightened.to_dict(),
        "default_runs": runs or {p: {"status": "ok", "reached": 2.0,
                                     "largest": {"coordinate": 1.0, "velocity": 1.0,
                                                 "acceleration": 1.0}} for p in PLANTS},
        "bounds": bounds or {"analytic": math.inf, "mujoco": 1e10, "pinocchio": math.inf},
        "interval": 0.01,
        "sensitivity": {},
    }


def _num(text: str) -> float:
    return float(text)


def _close(quoted: float, exact: float) -> bool:
    """A number quoted to 3 significant digits stands for ``exact``."""
    return math.isclose(quoted, exact, rel_tol=6e-3) or (quoted == exact == 0.0)


def margin_inequalities(text: str) -> list[tuple[float, str, float, list[float], float, float]]:
    """Every margin comparison a sentence quotes, ``V op M × (n1 e1 + n2 e2) [/ ... S] = B``:
    (V, op, M, [e1, e2], S (1 when absent), B)."""
    pat = re.compile(
        NUMBER + r" ([≤>]) " + NUMBER + r" × \(([^)]*)\)(?: / the check's scale " + NUMBER
        + r")? = " + NUMBER
    )
    out = []
    for m in pat.finditer(text):
        terms = [_num(x) for x in re.findall(r" " + NUMBER + r"(?= \+|$)", m.group(4))]
        scale = _num(m.group(5)) if m.group(5) else 1.0
        out.append((_num(m.group(1)), m.group(2), _num(m.group(3)), terms, scale,
                    _num(m.group(6))))
    return out


def check_quoted(text: str, value: float, errors: list[float], scale: float = 1.0) -> None:
    """The sentence quotes exactly one margin comparison, of ``value`` against ``errors`` (the
    outlier's own error and the group's largest, or the pair's), and it holds."""
    (got,) = margin_inequalities(text)
    v, op, m, terms, s, b = got
    assert m == SETTLE_MARGIN
    assert _close(v, value) and _close(s, scale)
    assert len(terms) == len(errors) and all(_close(a, e) for a, e in zip(terms, errors, strict=True))
    bound = SETTLE_MARGIN * sum(errors) / scale  # recomputed from the inputs
    assert _close(b, bound)
    assert (value <= bound) if op == "≤" else (value > bound), text


# -- a run its engine's guard cut short -------------------------------------------------------


def test_an_outlier_on_a_run_its_engine_cut_short_is_not_a_model_finding():
    """The seed-7 finding, as constructed inputs: MuJoCo stops at t = 0.41 s (bad qacc) and is
    the referee's outlier on the relative control torque up to there, at default and tightened
    settings; its own error is unknown (its run did not finish). Its stop is no range
    exceedance (the others stay far below mjMAXVAL): the outlier is unsettled, not a model
    finding, and the sentence says why."""
    out = _outcome(TORQUE, 2.2e-4, stopped=True)
    tight = _outcome(TORQUE, 2.1e-4, stopped=True)
    own = {"analytic": {"control_torque": 0.17}, "pinocchio": {"control_torque": 0.034}}
    runs = _task(own, tight)["default_runs"]
    runs["mujoco"] = {"status": "stopped", "reached": 0.41}
    st = settle(TORQUE, out, _task(own, tight, runs), PLANTS)
    assert st.cause is Cause.UNSETTLED, st.text
    assert "cut short" in st.text and "t = 0.41 s" in st.text and BADQACC in st.text
    assert "exceeds" not in st.text and not margin_inequalities(st.text)


def test_an_outlier_on_a_run_cut_short_takes_its_stops_range_cause():
    """The same run cut short where a finished plant reaches an acceleration beyond MuJoCo's
    bound: its stop is the motion leaving MuJoCo's range, and so is the outlier on its run up
    to there (a campaign is not failed by it)."""
    out = _outcome(TORQUE, 2.2e-4, stopped=True)
    tight = _outcome(TORQUE, 2.1e-4, stopped=True)
    task = _task({}, tight)
    task["default_runs"]["mujoco"] = {"status": "stopped", "reached": 0.41}
    task["default_runs"]["analytic"]["largest"] = {"coordinate": 3.2e3, "velocity": 5e6,
                                                   "acceleration": 3e10}
    st = settle(TORQUE, out, task, PLANTS)
    assert st.cause is Cause.RANGE, st.text
    assert "acceleration 3e+10" in st.text and "bound 1e+10" in st.text


def test_an_outlier_whose_tightened_run_was_cut_short_is_unsettled():
    out = _outcome(TORQUE, 2.2e-4)
    tight = _outcome(TORQUE, 2.1e-4, stopped=True)
    own = {p: {"control_torque": 1e-9} for p in PLANTS}
    st = settle(TORQUE, out, _task(own, tight), PLANTS)
    assert st.cause is Cause.UNSETTLED and "tightened settings" in st.text, st.text


def test_a_check_of_a_run_cut_short_is_not_a_model_finding():
    """A failed pair check against MuJoCo's run cut short, which its stop does not explain:
    unsettled, never the model."""
    d = Disagreement(Kind.CHECK, "rod_positions")  # the reference pair, analytic vs mujoco
    out = Outcome(ran=PLANTS, checks={"rod_positions": (3.0, 1e-6, "FAIL")},
                  disagreements=tuple(sorted((d, STOP))), messages={"mujoco": BADQACC},
                  reached={"mujoco": 0.41})
    task = _task({"analytic": {"rod_positions": 1e-9}}, out)
    task["default_runs"]["mujoco"] = {"status": "stopped", "reached": 0.41}
    st = settle(d, out, task, PLANTS)
    assert st.cause is Cause.UNSETTLED and "mujoco's run cut short" in st.text, st.text


# -- an unknown own error ---------------------------------------------------------------------


def test_an_outlier_whose_own_error_is_unknown_is_unsettled():
    """Persists at tightened settings, but the outlier's own error could not be estimated: no
    margin test can be made, so no model finding."""
    d = Disagreement(Kind.OUTLIER, "attitude", "mujoco")
    out, tight = _outcome(d, 1e-3), _outcome(d, 1e-3)
    own = {"analytic": {"attitude": 1e-12}, "pinocchio": {"attitude": 1e-12}}
    st = settle(d, out, _task(own, tight), PLANTS)
    assert st.cause is Cause.UNSETTLED and "no own error on attitude for mujoco" in st.text, st.text
    assert not margin_inequalities(st.text)


# -- a majority that disagrees with itself ----------------------------------------------------


@pytest.mark.parametrize("where", ["default", "tightened"])
def test_a_group_that_disagrees_with_itself_is_no_majority(where):
    """MuJoCo the outlier on the attitude, far beyond every own error, but analytic and
    Pinocchio, its group, fail their own pair check on the rod positions: unsettled (the
    sentence quotes that failed check, recomputed here), not the model."""
    d = Disagreement(Kind.OUTLIER, "attitude", "mujoco")
    failing = {"analytic_vs_pinocchio.rod_positions": (0.5, 1e-6, "FAIL")}
    out = _outcome(d, 1e-3, failing if where == "default" else {})
    tight = _outcome(d, 1e-3, failing if where == "tightened" else {})
    own = {p: {"attitude": 1e-12} for p in PLANTS}
    st = settle(d, out, _task(own, tight), PLANTS)
    assert st.cause is Cause.UNSETTLED and f"at the {where} settings" in st.text, st.text
    m = re.search(r"analytic_vs_pinocchio\.rod_positions " + NUMBER + " > threshold " + NUMBER,
                  st.text)
    assert m and _num(m.group(1)) > _num(m.group(2)) and _close(_num(m.group(1)), 0.5)
    # the same group agreeing with itself: the outlier is the model's
    passing = {"analytic_vs_pinocchio.rod_positions": (1e-9, 1e-6, "pass")}
    st = settle(d, _outcome(d, 1e-3, passing), _task(own, _outcome(d, 1e-3, passing)), PLANTS)
    assert st.cause is Cause.MODEL, st.text
    check_quoted(st.text, 1e-3, [1e-12, 1e-12])


# -- the margin, and the sentence --------------------------------------------------------------


@pytest.mark.parametrize(
    ("dist", "errors", "cause"),
    [(1e-3, (1e-12, 3e-12), Cause.MODEL), (1e-6, (2e-8, 9e-8), Cause.SETTINGS)],
)
def test_an_absolute_outlier_quotes_the_margin_it_tested(dist, errors, cause):
    d = Disagreement(Kind.OUTLIER, "rod_positions", "mujoco")
    own = {"mujoco": {"rod_positions": errors[0]}, "analytic": {"rod_positions": errors[1]},
           "pinocchio": {"rod_positions": errors[1] / 3}}
    st = settle(d, _outcome(d, dist), _task(own, _outcome(d, dist)), PLANTS)
    assert st.cause is cause, st.text
    check_quoted(st.text, dist, list(errors))  # the outlier's and the group's largest


@pytest.mark.parametrize(
    ("scale", "cause"), [(1e4, Cause.MODEL), (1e3, Cause.SETTINGS)]
)
def test_a_relative_outlier_is_tested_against_its_own_errors_over_the_checks_scale(scale, cause):
    """The control torque is relative (the check divides by the largest torque): the own
    errors, in N·m, are divided by the same scale before the margin test; the sentence quotes
    the scale. Distance 2.2e-4 against 10 × (0.001 + 0.17) N·m / scale."""
    own = {"mujoco": {"control_torque": 1e-3}, "analytic": {"control_torque": 0.17},
           "pinocchio": {"control_torque": 0.034}}
    scales = {"control_torque": scale, "mujoco_vs_pinocchio.control_torque": 2 * scale,
              "analytic_vs_pinocchio.control_torque": scale / 10}  # not the outlier's pair
    out = _outcome(TORQUE, 2.2e-4, scales=scales)
    st = settle(TORQUE, out, _task(own, _outcome(TORQUE, 2.2e-4, scales=scales)), PLANTS)
    assert st.cause is cause, st.text
    check_quoted(st.text, 2.2e-4, [1e-3, 0.17], scale)  # the smallest of mujoco's pairs


def test_a_relative_outlier_without_its_scale_is_unsettled():
    own = {p: {"control_torque": 1e-9} for p in PLANTS}
    st = settle(TORQUE, _outcome(TORQUE, 2.2e-4), _task(own, _outcome(TORQUE, 2.2e-4)), PLANTS)
    assert st.cause is Cause.UNSETTLED and "scale" in st.text, st.text


@pytest.mark.parametrize(("value", "cause"), [(5e-4, Cause.MODEL), (2e-10, Cause.SETTINGS)])
def test_a_failed_pair_check_is_tested_against_the_pairs_own_errors(value, cause):
    d = Disagreement(Kind.CHECK, "mujoco_vs_pinocchio.velocity_C")
    checks = {d.what: (value, 1e-10, "FAIL")}
    out = Outcome(ran=PLANTS, checks=checks, disagreements=(d,))
    own = {"mujoco": {"velocity_C": 2e-11}, "pinocchio": {"velocity_C": 1e-11},
           "analytic": {"velocity_C": 1.0}}  # not in the pair: not in the bound
    st = settle(d, out, _task(own, out), PLANTS)
    assert st.cause is cause, st.text
    check_quoted(st.text, value, [2e-11, 1e-11])


def test_the_conditioning_sentence_quotes_a_comparison_that_holds():
    d = Disagreement(Kind.CHECK, "velocity_C")  # the reference pair's, analytic vs mujoco
    out = Outcome(ran=PLANTS, checks={d.what: (164.6, 0.07, "FAIL")}, disagreements=(d,))
    task = _task({}, out)
    task["sensitivity"] = {"analytic": {"velocity_C": 40.0}}
    st = settle(d, out, task, PLANTS)
    assert st.cause is Cause.CONDITIONING, st.text
    m = re.search(NUMBER + r" on velocity_C, ≥ " + NUMBER + r" × the disagreement's " + NUMBER,
                  st.text)
    assert m and _num(m.group(2)) == CONDITIONING_FRACTION
    assert _close(_num(m.group(1)), 40.0) and _close(_num(m.group(3)), 164.6)
    assert 40.0 >= CONDITIONING_FRACTION * 164.6



def test_a_stop_against_plants_that_disagree_with_each_other_is_unsettled():
    """MuJoCo stops at tightened settings too, with no range or scene cause, while analytic and
    Pinocchio, the plants that finish, fail their pair check on the rod positions: no majority
    shows that the motion goes on, so the stop is unsettled; with the pair passing, the model."""
    failing = {"analytic_vs_pinocchio.rod_positions": (0.5, 1e-6, "FAIL")}
    out = Outcome(ran=PLANTS, checks=failing, disagreements=(STOP,))
    task = _task({}, out)
    task["default_runs"]["mujoco"] = {"status": "stopped", "reached": 0.41}
    st = settle(STOP, out, task, PLANTS)
    assert st.cause is Cause.UNSETTLED, st.text
    m = re.search(r"analytic_vs_pinocchio\.rod_positions " + NUMBER + " > threshold " + NUMBER,
                  st.text)
    assert m and _num(m.group(1)) > _num(m.group(2))
    passing = {"analytic_vs_pinocchio.rod_positions": (1e-9, 1e-6, "pass")}
    out = Outcome(ran=PLANTS, checks=passing, disagreements=(STOP,))
    task["tightened"] = out.to_dict()
    assert settle(STOP, out, task, PLANTS).cause is Cause.MODEL


ROUNDOFF = (
    "round-off limited at t = 1.2 s: a one-ulp change of the state moves ẏ[14] by 1.3e-08, so a "
    "step of 3.3e-05 s moves component 14 by 1.6 × its tolerance 2.7e-13"
)


def test_a_plant_stopped_round_off_limited_at_both_settings_is_conditioning_not_model():
    """The analytic plant stops round-off limited (its own probe: a one-ulp change of its state
    moves a step by its whole tolerance) at its default and its tightened settings, while the
    others finish and agree: beyond double precision, ``conditioning``, never ``model``; an
    outlier on its run up to the stop takes that cause. A stop for another reason keeps the
    rules it had (``model`` here), and a round-off stop at the default settings alone is the
    settings."""
    stop = Disagreement(Kind.STOPPED, "failed", "analytic")
    tight = Outcome(ran=PLANTS, disagreements=(stop,), messages={"analytic": ROUNDOFF})
    out = Outcome(ran=PLANTS, disagreements=(stop,), messages={"analytic": ROUNDOFF},
                  reached={"analytic": 1.2})
    st = settle(stop, out, _task({}, tight), PLANTS)
    assert st.cause is Cause.CONDITIONING, st.text
    assert "round-off limited" in st.text and "analytic" in st.text
    outlier = Disagreement(Kind.OUTLIER, "rod_positions", "analytic")
    both = Outcome(ran=PLANTS, disagreements=(outlier, stop), messages={"analytic": ROUNDOFF},
                   verdicts=(_verdict(outlier, 1.0),))
    assert settle(outlier, both, _task({}, tight), PLANTS).cause is Cause.CONDITIONING
    other = Outcome(ran=PLANTS, disagreements=(stop,), messages={"analytic": "LSODA failed"})
    assert settle(stop, other, _task({}, other), PLANTS).cause is Cause.MODEL
    finished = Outcome(ran=PLANTS)
    assert settle(stop, out, _task({}, finished), PLANTS).cause is Cause.SETTINGS
