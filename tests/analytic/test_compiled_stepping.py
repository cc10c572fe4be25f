"""The compiled loop (:mod:`analytic.compiled_stepping`): CyRK's C++ Runge-Kutta loop stepping the
compiled right-hand side, against scipy's loop, the reference.

References: scipy's DOP853 at the same tolerance (the same method, stepped from Python); a tight run
(scipy's loop at the sweep's reference tolerance, rtol 2.5e-14) as an independent reference for
both; the steps CyRK keeps when asked to (for the step watch); planted faults (a right-hand side
that turns non-finite part way, Ctrl-C), as ``tests/cross/test_faults.py`` plants them on scipy's loop.
"""

from __future__ import annotations

import numpy as np
import pytest

from analytic import RunStatus, compiled_stepping, simulate
from analytic.effects import SolverMethod, Stepper
from analytic.fast import FastModel
from analytic.model import TumblingModel
from analytic.plant import AnalyticPlant, AnalyticSettings
from validation.scenes import resolve_scene
from validation.studies.sweep import REFERENCE_ATOL, REFERENCE_RTOL, errors_against, ref_samples

pytestmark = pytest.mark.skipif(
    bool(compiled_stepping.unavailable()),
    reason=f"compiled loop unavailable: {compiled_stepping.unavailable()}",
)

PAPER_SCENES = [
    "paper_example1",
    "paper_example2",
    "paper_example1_controlled",
    "paper_example2_controlled",
]
RTOL, ATOL = 1e-12, 1e-13  # the scenes' own tolerances (DOP853)

AGREE_2S = 10.0
"""|compiled - scipy| over 2 s, in the sweep's error measure, in units of rtol. Two runs that each
meet the tolerance differ by at most the sum of their global errors, which over 2 s are below
1e-11 (measured against the reference: 6e-13 to 8e-12 on the four scenes); the two loops take the
same steps (CyRK ports scipy's controller) and measure 1e-15 to 2e-13 apart."""

AGREE_60S = 100.0
"""The same over 60 s of the controlled Example 1: the global errors grow to ~1.1e-10 against the
reference (C travels ~16 km); the loops, whose steps part by round-off at each restart of a compiled
call (every 200 steps), measure ~3e-11 apart."""

AS_ACCURATE = 2.0
"""The compiled run's error against the reference is at most this times scipy's (plus rtol): the
same method at the same tolerance is as accurate, whichever loop steps it."""


def _pair(name: str, t_end: float, rtol: float = RTOL, atol: float = ATOL):
    sc = resolve_scene(name)
    kw = dict(method="DOP853", rtol=rtol, atol=atol, t_end=t_end)
    return sc, simulate(sc, stepper="compiled", **kw), simulate(sc, stepper="scipy", **kw)


def _reference(sc, t_end: float):
    return ref_samples(
        simulate(sc, rtol=REFERENCE_RTOL, atol=REFERENCE_ATOL, t_end=t_end, stepper="scipy")
    )


def _check_agreement(sc, c, s, t_end: float, factor: float) -> None:
    assert c.status is RunStatus.OK and s.status is RunStatus.OK
    assert c.info["stepper"] == "compiled" and s.info["stepper"] == "scipy"
    assert "scipy_from_t_s" not in c.info  # no hand-over
    np.testing.assert_array_equal(c.t, s.t)  # the same output grid, t = 0 and t_end included
    assert c.t[0] == 0.0 and c.t[-1] == t_end
    assert errors_against(c, ref_samples(s))["error"] <= factor * RTOL
    ref = _reference(sc, t_end)
    e_c, e_s = errors_against(c, ref)["error"], errors_against(s, ref)["error"]
    assert e_c <= AS_ACCURATE * e_s + RTOL
    # the same method and controller: the same work, counted the same way
    assert abs(c.info["nsteps"] - s.info["nsteps"]) <= 0.01 * s.info["nsteps"] + 2
    assert abs(c.info["nfev"] - s.info["nfev"]) <= 0.01 * s.info["nfev"] + 30


@pytest.mark.parametrize("name", PAPER_SCENES)
def test_agrees_with_scipys_loop(name):
    sc, c, s = _pair(name, 2.0)
    _check_agreement(sc, c, s, 2.0, AGREE_2S)


@pytest.mark.slow
def test_agrees_with_scipys_loop_over_60_s():
    sc, c, s = _pair("paper_example1_controlled", 60.0)
    _check_agreement(sc, c, s, 60.0, AGREE_60S)


def test_error_follows_the_tolerance():
    """Against the reference, the compiled DOP853's error falls at least tenfold for each hundredfold
    tighter rtol (tolerance proportionality would give a hundredfold)."""
    sc = resolve_scene("paper_example1_controlled")
    ref = _reference(sc, 2.0)
    errs = [
        errors_against(simulate(sc, rtol=r, atol=0.1 * r, t_end=2.0, stepper="compiled"), ref)[
            "error"
        ]
        for r in (1e-8, 1e-10, 1e-12)
    ]
    assert errs[1] <= errs[0] / 10 and errs[2] <= errs[1] / 10, errs


@pytest.mark.parametrize("method", ["DOP853", "RK45"])
def test_step_watch_counts_the_accepted_steps(method):
    """``max |u|² - 1`` at the steps, as the right-hand side finds them while CyRK keeps only the
    samples, equals the maximum over the steps CyRK keeps when asked to (the same steps: one call,
    the same settings)."""
    sc = resolve_scene("paper_example1_controlled")
    rt = compiled_stepping._runtime()
    fm = FastModel(sc)
    ny = 2 * fm.nq + 7
    y0 = np.concatenate([sc.initial.q0(), sc.initial.qdot0(), np.zeros(7)])
    atols = np.concatenate([np.full(2 * fm.nq, ATOL), np.full(7, 1e300)])
    rtol = np.array([RTOL])
    samples = sc.output.with_t_end(5.0).times()[1:].copy()
    m = rt.methods[SolverMethod(method)]

    def solve(kernel, t_eval):
        kernel.start_call(0.0)
        te = (t_eval.ctypes.data, t_eval.size) if t_eval is not None else (None, 0)
        ptr = rt.solve(
            rt.address, 0.0, 5.0, y0.ctypes.data, ny, m, 0, 0, kernel.args.ctypes.data,
            kernel.args.nbytes, 0, 2000, False, *te, None, None, 0, rtol.ctypes.data, 1,
            atols.ctypes.data, ny, np.inf, 0.0, True,
        )  # fmt: skip
        try:
            size, steps = int(rt.size(ptr)), int(rt.steps(ptr))
            y = np.ctypeslib.as_array(rt.y_ptr(ptr), (size * ny,)).reshape(size, ny).copy()
            y_now = np.ctypeslib.as_array(rt.y_now(ptr), (ny,)).copy()
        finally:
            rt.free(ptr)
        return steps, y, y_now

    k1 = compiled_stepping._Kernel(rt.layout, fm, ny)
    steps1, _, y_end = solve(k1, samples)
    watched = max(k1.steps_watched()[0], abs(y_end[3:7] @ y_end[3:7] - 1.0))
    steps2, y_steps, _ = solve(compiled_stepping._Kernel(rt.layout, fm, ny), None)
    assert steps1 == steps2 == len(y_steps) - 1 > 100
    u = y_steps[1:, 3:7]
    assert watched == np.max(np.abs(np.sum(u * u, axis=1) - 1.0))


# ------------------------------------------------------------------------------------------------
# Faults: a non-finite right-hand side, Ctrl-C
# ------------------------------------------------------------------------------------------------


def _poison_after(monkeypatch, t_fault: float):
    """From the first ``progress(t)`` with ``t > t_fault`` on (at once when ``t_fault`` < 0), every
    evaluation is non-finite: the compiled kernel's constants become NaN and the numpy model (which
    answers where the kernel declines) returns NaN. Returns the progress callback."""
    models: list[FastModel] = []
    original_init = FastModel.__init__
    poisoned = {"on": False}

    def init(self, *args, **kwargs):
        original_init(self, *args, **kwargs)
        models.append(self)
        if t_fault < 0:
            self.fp[:] = np.nan
            poisoned["on"] = True

    original_accel = TumblingModel.acceleration

    def accel(self, t, q, qdot):
        qdd, c = original_accel(self, t, q, qdot)
        return (qdd * np.nan if poisoned["on"] else qdd), c

    monkeypatch.setattr(FastModel, "__init__", init)
    monkeypatch.setattr(TumblingModel, "acceleration", accel)

    def progress(t):
        if t > t_fault and not poisoned["on"]:
            for fm in models:
                fm.fp[:] = np.nan
            poisoned["on"] = True

    return progress


def test_non_finite_part_way_keeps_the_samples_before_it(monkeypatch):
    sc = resolve_scene("paper_example1_controlled")
    clean = simulate(sc, t_end=3.0, stepper="compiled")
    progress = _poison_after(monkeypatch, 1.0)
    tr = simulate(sc, t_end=3.0, stepper="compiled", progress=progress)
    assert tr.status is RunStatus.FAILED and "non-finite acceleration at t =" in tr.message
    handed = tr.info["scipy_from_t_s"]  # scipy's loop took over and failed as on its own path
    assert 1.0 < handed < 3.0 and tr.t[-1] <= handed
    k = len(tr.t)
    assert 100 <= k < len(clean.t)
    assert np.all(np.isfinite(tr.q))
    np.testing.assert_array_equal(tr.q, clean.q[:k])  # what came before the fault is untouched


def test_non_finite_from_the_start_keeps_t0(monkeypatch):
    sc = resolve_scene("paper_example1_controlled")
    _poison_after(monkeypatch, -1.0)
    tr = simulate(sc, t_end=1.0, stepper="compiled")
    assert tr.status is RunStatus.FAILED and "non-finite acceleration at t = 0 s" in tr.message
    assert tr.info["scipy_from_t_s"] == 0.0
    np.testing.assert_array_equal(tr.t, [0.0])
    np.testing.assert_array_equal(tr.q[0], sc.initial.q0())


def test_ctrl_c_between_calls_keeps_the_samples():
    """Ctrl-C takes effect between calls into the C++ loop, at most CHUNK_STEPS steps or a second of
    simulated time apart (where ``progress`` is called); the run ends interrupted with the samples
    reached."""
    sc = resolve_scene("paper_example1_controlled")
    clean = simulate(sc, t_end=6.0, stepper="compiled")
    seen = []

    def progress(t):
        seen.append(t)
        if t > 3.0:
            raise KeyboardInterrupt

    tr = simulate(sc, t_end=6.0, stepper="compiled", progress=progress)
    assert tr.status is RunStatus.INTERRUPTED and tr.message.startswith("interrupted at t = ")
    k = len(tr.t)
    assert tr.t[-1] <= seen[-1] < 6.0 and tr.t[-1] > 3.0 - 0.1
    np.testing.assert_array_equal(tr.q, clean.q[:k])
    with pytest.raises(KeyboardInterrupt):
        tr.raise_if_interrupted()
    # progress came after every call: at least once per CHUNK_STEPS steps
    assert seen == sorted(seen)
    assert len(seen) >= tr.info["nsteps"] / compiled_stepping.CHUNK_STEPS


def test_progress_reaches_t_end():
    sc = resolve_scene("paper_example1_controlled")
    seen = []
    tr = simulate(sc, t_end=5.0, stepper="compiled", progress=seen.append)
    assert tr.status is RunStatus.OK and seen[-1] == 5.0
    assert len(seen) >= tr.info["nsteps"] / compiled_stepping.CHUNK_STEPS
    assert {1.0, 2.0, 3.0, 4.0, 5.0} <= set(seen)  # at least once per second simulated


def test_calls_that_pass_no_sample():
    """An output grid sparser than the calls (a sample every 2.5 s, calls ending each second):
    calls that reach no sample carry the state on, and the samples still agree with scipy's."""
    from analytic.scene import OutputSettings

    sc = resolve_scene("paper_example1_controlled").replace(output=OutputSettings(5.0, 0.4))
    seen = []
    c = simulate(sc, stepper="compiled", progress=seen.append)
    s = simulate(sc, stepper="scipy")
    assert c.status is RunStatus.OK and "scipy_from_t_s" not in c.info
    np.testing.assert_array_equal(c.t, [0.0, 2.5, 5.0])
    assert seen == [1.0, 2.0, 3.0, 4.0, 5.0]
    assert errors_against(c, ref_samples(s))["error"] <= AGREE_2S * RTOL


# ------------------------------------------------------------------------------------------------
# Choosing the loop, and bad settings
# ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "stepper"),
    [
        ({}, "compiled"),
        ({"method": "RK45"}, "compiled"),
        ({"method": "RK23"}, "scipy"),  # no stage at c = 1 for the step watch
        ({"method": "Radau"}, "scipy"),  # implicit methods stay on scipy's loop
        ({"backend": "numpy"}, "scipy"),  # the loop needs the compiled right-hand side
        ({"stepper": "scipy"}, "scipy"),
    ],
)
def test_auto_runs_the_compiled_loop_where_it_applies(kwargs, stepper):
    sc = resolve_scene("paper_example1")
    tr = simulate(sc, t_end=0.2, rtol=1e-8, atol=1e-9, **kwargs)
    assert tr.status is RunStatus.OK and tr.info["stepper"] == stepper


@pytest.mark.parametrize(
    ("kwargs", "needle"),
    [
        ({"stepper": "fast"}, "stepper: must be one of ['auto', 'compiled', 'scipy'] (got 'fast')"),
        ({"stepper": "compiled", "method": "Radau"}, "stepper: 'compiled' cannot run this case: "),
        ({"stepper": "compiled", "method": "RK23"}, "method 'RK23' is not one of DOP853, RK45"),
        ({"stepper": "compiled", "backend": "numpy"}, "not the compiled kernel"),
    ],
)
def test_bad_stepper_is_refused_naming_the_field(kwargs, needle):
    sc = resolve_scene("paper_example1")
    with pytest.raises(ValueError) as exc:
        simulate(sc, t_end=0.2, **kwargs)
    assert needle in str(exc.value) and str(exc.value).startswith("stepper: ")


def test_settings_take_the_stepper():
    with pytest.raises(ValueError, match=r"^stepper: must be one of .* \(got 'fast'\)"):
        AnalyticSettings(stepper="fast")
    assert AnalyticSettings(stepper="scipy").stepper is Stepper.SCIPY
    assert AnalyticSettings().stepper is Stepper.AUTO
    sc = resolve_scene("paper_example1")
    tr = AnalyticPlant().simulate(sc, AnalyticSettings(stepper="scipy"), t_end=0.2)
    assert tr.info["stepper"] == "scipy"


def test_cli_refuses_a_stepper_that_cannot_run_in_one_line(tmp_path, capsys):
    from validation.cli import EXIT_USAGE, main

    argv = ["simulate", "paper_example1", "--t-end", "0.2", "--out"]
    bad = ["--stepper", "compiled", "--method", "Radau"]
    assert main([*argv, str(tmp_path / "a"), *bad]) == EXIT_USAGE
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "stepper: 'compiled' cannot run this case" in err
    assert main([*argv, str(tmp_path / "b"), "--stepper", "scipy"]) == 0
