"""The plant contract: the scene a plant is given, and what it must return before it is compared."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from analytic.plant import AnalyticPlant
from analytic.trajectory import RunStatus
from validation.runs.contract import ContractError, check_trajectory, contract_problem, plant_scene
from validation.scenes import DEFAULT_SCENE, resolve_scene

T_END = 0.1


@pytest.fixture(scope="module")
def scene():
    return resolve_scene(DEFAULT_SCENE)


@pytest.fixture(scope="module")
def run(scene):
    return AnalyticPlant().simulate(plant_scene(scene), t_end=T_END)


def test_a_plants_scene_is_an_equal_copy_it_cannot_change_for_anyone_else(scene):
    mine = plant_scene(scene)
    assert mine.name == scene.name and np.array_equal(mine.body.inertia, scene.body.inertia)
    assert not np.shares_memory(mine.body.inertia, scene.body.inertia)
    assert not mine.masses.mass.flags.writeable and not mine.initial.omega.flags.writeable
    before = scene.body.inertia.copy()
    with pytest.raises(ValueError, match="read-only"):
        mine.body.inertia[0] = 0.0
    inertia = mine.body.inertia
    inertia.setflags(write=True)  # numpy allows it on an array that owns its memory
    inertia *= 2.0
    object.__setattr__(mine, "name", "changed")
    object.__setattr__(mine.output, "t_end", 99.0)
    assert np.array_equal(scene.body.inertia, before)
    assert scene.name == DEFAULT_SCENE and scene.output.t_end != 99.0


def test_a_built_in_run_keeps_the_contract(scene, run):
    assert contract_problem(run, "analytic", scene, T_END) == ""
    assert check_trajectory(run, "analytic", scene, T_END) is run


def test_each_breach_of_the_contract_is_named(scene, run):
    n = run.t.size
    bad = np.array(run.qdot)
    bad[3, 0] = np.nan
    breaches = {
        "NoneType, not a Trajectory": None,
        "named 'mujoco', not its own name 'analytic'": dataclasses.replace(run, engine="mujoco"),
        "q has shape": dataclasses.replace(run, q=run.q[:, :3]),
        "qdot has non-finite values": dataclasses.replace(run, qdot=bad),
        f"t has {n - 2} samples": dataclasses.replace(
            run, t=run.t[:-2], q=run.q[:-2]
        ),  # a run that says ok stops short
        "t[1] is": dataclasses.replace(run, t=run.t + np.r_[0.0, 1e-3, np.zeros(n - 2)]),
        "rod_forces has shape": dataclasses.replace(run, rod_forces=run.rod_forces[:, :1]),
    }
    for words, out in breaches.items():
        why = contract_problem(out, "analytic", scene, T_END)
        assert words in why, (words, why)
        with pytest.raises(ContractError, match="broke the plant contract"):
            check_trajectory(out, "analytic", scene, T_END)


def test_a_failed_run_may_stop_short_on_the_grid(scene, run):
    k = 5
    short = dataclasses.replace(
        run,
        t=run.t[:k], q=run.q[:k], qdot=run.qdot[:k], qddot=run.qddot[:k], QC=run.QC[:k],
        torque=run.torque[:k], rod_forces=run.rod_forces[:k], force_at_C=run.force_at_C[:k],
        residual_norm=run.residual_norm[:k],
        invariants=type(run.invariants)(
            **{f.name: getattr(run.invariants, f.name)[:k] for f in dataclasses.fields(run.invariants)}
        ),
        tracking=dataclasses.replace(
            run.tracking, e_omega=run.tracking.e_omega[:k], e_p=run.tracking.e_p[:k]
        ),
        status=RunStatus.FAILED,
        message="gave up",
    )
    assert contract_problem(short, "analytic", scene, T_END) == ""
    assert "t has 5 samples" in contract_problem(
        dataclasses.replace(short, status=RunStatus.OK), "analytic", scene, T_END
    )


def test_the_fuzzer_takes_a_contract_breach_as_the_plant_raising(scene):
    """A plant returning its run under another plant's name -> the fuzzer's run of it is the
    plant raising ``ContractError``: no trajectory to compare."""
    from tests.support.hostile_plugins import LiarPlant
    from validation.studies.fuzz import judge

    got = judge.run_one("liar", LiarPlant(), scene, T_END, budget_s=120.0)
    assert got.traj is None and got.raised == "ContractError"
    assert "not its own name 'liar'" in got.message
