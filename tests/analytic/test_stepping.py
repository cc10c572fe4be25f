"""analytic.stepping (the scipy loop the analytic and Pinocchio plants share) and analytic.assemble
(the record every plant returns).

References: closed-form solutions of linear systems (scipy's own ``fun_linear`` / ``sol_linear``
idea), errors scaled by ``atol + rtol·|y|``; planted faults for the ways a run ends early.
"""

from __future__ import annotations

import numpy as np
import pytest

from analytic.assemble import N_AUX, assemble
from analytic.effects import SolverMethod
from analytic.kinematics import omega_of, udot_of
from analytic.model import TumblingModel
from analytic.stepping import NonFinite, step_and_sample
from analytic.trajectory import Engine, RunStatus
from tests.support.scene_strategies import random_scene

W = 2.0  # rad/s


def _oscillator(scale: float = 1.0):
    """``y[3:5] = (cos Wt, sin Wt)`` (so |y[3:7]| stays 1) and the quadrature ``scale ∫ y[3] dt``
    in the last component."""

    def f(t, y):
        out = np.zeros_like(y)
        out[3], out[4] = -W * y[4], W * y[3]
        out[-1] = scale * y[3]
        return out

    return f, np.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0])


@pytest.mark.parametrize("method", [SolverMethod.DOP853, SolverMethod.RK45, SolverMethod.RADAU])
def test_samples_follow_the_closed_form(method):
    f, y0 = _oscillator()
    t_eval = np.linspace(0.0, 3.0, 31)
    seen = []
    run = step_and_sample(
        f, t_eval, y0, method=method, rtol=1e-10, atol=1e-12, n_motion=7, progress=seen.append
    )
    assert run.status is RunStatus.OK and run.message == ""
    np.testing.assert_array_equal(run.t, t_eval)
    tol = 1e-12 + 1e-10 * 1.0
    np.testing.assert_allclose(run.y[:, 3], np.cos(W * t_eval), rtol=0, atol=100 * tol)
    np.testing.assert_allclose(run.y[:, 4], np.sin(W * t_eval), rtol=0, atol=100 * tol)
    np.testing.assert_allclose(run.y[:, -1], np.sin(W * t_eval) / W, rtol=0, atol=100 * tol)
    assert run.nsteps > 0 and run.wall_time_s >= 0.0
    assert run.max_quat_norm_error_at_steps <= 100 * tol
    assert seen == sorted(seen) and seen[-1] == pytest.approx(3.0)


def test_quadratures_are_left_out_of_the_error_control():
    """A quadrature 1e12 times larger takes the same steps: it rides along, never shrinks them."""
    t_eval = np.linspace(0.0, 2.0, 5)
    runs = []
    for scale in (1.0, 1e12):
        f, y0 = _oscillator(scale)
        runs.append(
            step_and_sample(
                f, t_eval, y0, method=SolverMethod.DOP853, rtol=1e-9, atol=1e-12, n_motion=7
            )
        )
    assert runs[0].nsteps == runs[1].nsteps
    np.testing.assert_array_equal(runs[0].y[:, :7], runs[1].y[:, :7])
    np.testing.assert_allclose(runs[1].y[:, -1], 1e12 * runs[0].y[:, -1], rtol=1e-13, atol=0)


@pytest.mark.parametrize(
    ("fault", "status", "words"),
    [
        (NonFinite("non-finite acceleration at t = 1 s"), RunStatus.FAILED, "non-finite"),
        (KeyboardInterrupt(), RunStatus.INTERRUPTED, "interrupted at t = "),
        (np.linalg.LinAlgError("not PD"), RunStatus.FAILED, "the matrix failed near t = "),
    ],
)
def test_a_run_that_ends_early_keeps_its_samples(fault, status, words):
    f0, y0 = _oscillator()

    def f(t, y):
        if t > 1.05:
            raise fault
        return f0(t, y)

    t_eval = np.linspace(0.0, 2.0, 21)
    run = step_and_sample(
        f, t_eval, y0, method=SolverMethod.DOP853, rtol=1e-10, atol=1e-12, n_motion=7,
        linalg_failure="the matrix failed",
    )  # fmt: skip
    assert run.status is status and words in run.message
    assert 1 <= len(run.t) < len(t_eval) and run.y.shape == (len(run.t), len(y0))
    np.testing.assert_array_equal(run.t, t_eval[: len(run.t)])
    np.testing.assert_allclose(run.y[:, 3], np.cos(W * run.t), rtol=0, atol=1e-8)


def test_assemble_fills_what_a_plant_leaves_out():
    """Samples without a control get zeros; ω defaults to H(u) u̇; the quadratures become the
    invariants' work and impulses; the record carries what it was given."""
    scene = random_scene(np.random.default_rng(4), 2)
    model = TumblingModel(scene)
    rng = np.random.default_rng(0)
    N, nq = 5, model.nq
    q = np.concatenate(
        [rng.normal(size=(N, 3)), rng.normal(size=(N, 4)), rng.normal(size=(N, 2))], 1
    )
    q[:, 3:7] /= np.linalg.norm(q[:, 3:7], axis=1, keepdims=True)
    qd = rng.normal(size=(N, nq))
    qd[:, 3:7] = udot_of(q[:, 3:7], rng.normal(size=(N, 3)))
    quad = rng.normal(size=(N, N_AUX))
    t = np.linspace(0.0, 1.0, N)
    tr = assemble(
        model, Engine.PINOCCHIO, t, q, qd, np.zeros((N, nq)), [None] * N, quad,
        RunStatus.FAILED, "why", {"k": 1},
    )  # fmt: skip
    assert tr.engine == Engine.PINOCCHIO and tr.status is RunStatus.FAILED
    assert tr.message == "why" and tr.info == {"k": 1} and tr.scene == scene.name
    for a in (tr.QC, tr.torque, tr.rod_forces, tr.force_at_C, tr.residual_norm):
        assert a.shape[0] == N and not a.any()
    np.testing.assert_array_equal(tr.invariants.work, quad[:, 0])
    np.testing.assert_array_equal(tr.invariants.angular_impulse, quad[:, 1:4])
    np.testing.assert_array_equal(tr.omega, omega_of(q[:, 3:7], qd[:, 3:7]))
