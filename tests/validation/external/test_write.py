"""write_trajectory (validation/external/write.py): a plant's run written as CSV and Parquet reads back
to full precision; absent groups stay absent; what the reader would refuse is never written."""

from __future__ import annotations

import numpy as np
import pytest

from analytic.invariants import Balance
from analytic.scene import load_scene
from analytic.trajectory import Engine
from tests.support import tolerances as tol
from validation.compare.balances import BalanceTerms, relative
from validation.compare.differences import attitude_angle
from validation.compare.thresholds import DEFAULTS
from validation.external import (
    ColumnGroup,
    ExternalTrajectory,
    TrajectoryFileError,
    TrajectoryFormat,
    read_trajectory,
    write_trajectory,
)
from validation.external.columns import OPTIONAL_GROUPS, header
from validation.external.write import trajectory_table

ROUND_TRIP = tol.TRAJECTORY_FILE_ROUND_TRIP_REL.value


def _scene(name: str, t_end: float):
    sc = load_scene(name)
    return sc.replace(output=sc.output.with_t_end(t_end))


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


@pytest.mark.parametrize("fmt", list(TrajectoryFormat))
def test_plant_trajectory_round_trip_full_precision(controlled_run, tmp_path, fmt):
    scene, tr = controlled_run
    path = write_trajectory(tmp_path / f"run.{fmt.value}", scene, tr)
    ext = read_trajectory(path, scene, engine=Engine.ANALYTIC)
    back = ext.trajectory
    assert ext.present == OPTIONAL_GROUPS and ext.format is fmt
    np.testing.assert_array_equal(back.t, scene.output.times())
    assert _rel(back.R, tr.R) <= ROUND_TRIP
    assert float(np.max(attitude_angle(back.u, tr.u))) <= ROUND_TRIP
    assert _rel(back.p, tr.p) <= ROUND_TRIP
    assert _rel(back.qdot[:, :3], tr.qdot[:, :3]) <= ROUND_TRIP
    assert _rel(back.omega, tr.omega) <= ROUND_TRIP
    assert _rel(back.qdot[:, 7:], tr.qdot[:, 7:]) <= ROUND_TRIP
    assert _rel(back.torque, tr.torque) <= ROUND_TRIP
    assert _rel(back.rod_forces, tr.rod_forces) <= ROUND_TRIP
    # the plant's q is continuous from the scene's u(0): it reads back with its own sign
    np.testing.assert_array_equal(back.u, tr.u)
    # the quadratures: each balance closes for the file's run as for the plant's (same verdict
    # under the comparison's threshold), and its residual is the plant's to that threshold
    assert _rel(back.invariants.work, tr.invariants.work) <= ROUND_TRIP
    assert _rel(back.invariants.angular_impulse, tr.invariants.angular_impulse) <= ROUND_TRIP
    for balance in Balance:
        th = DEFAULTS[balance.value]
        plants = relative(BalanceTerms.of(tr.invariants), balance, th.floor)
        mine = relative(BalanceTerms.of(back.invariants), balance, th.floor)
        assert plants <= th.value and mine <= th.value, (balance, plants, mine)
    # what no column holds is NaN, never a value a comparison could take for a result
    assert np.isnan(back.qddot).all() and np.isnan(back.force_at_C).all()
    assert np.isnan(back.residual_norm).all()
    # the tracking errors follow from the columns (Eqs. 77, 82)
    assert _rel(back.tracking.e_p, tr.tracking.e_p) <= ROUND_TRIP
    assert _rel(back.tracking.e_omega, tr.tracking.e_omega) <= ROUND_TRIP


def test_csv_values_are_written_with_repr(controlled_run, tmp_path):
    """Each value is the shortest text of its double: the text parses back to it exactly."""
    scene, tr = controlled_run
    path = write_trajectory(tmp_path / "run.csv", scene, tr)
    lines = path.read_text().splitlines()
    assert tuple(lines[0].split(",")) == header(scene.n)
    assert len(lines) == len(tr.t) + 1
    row = [float(x) for x in lines[5].split(",")]
    _, values = trajectory_table(tr, scene)
    assert row == values[4].tolist()


def test_missing_optional_groups_are_reported_absent(controlled_run, tmp_path):
    scene, tr = controlled_run
    bare = read_trajectory(
        write_trajectory(tmp_path / "bare.parquet", scene, tr, groups=frozenset()),
        scene,
        engine=Engine.ANALYTIC,
    )
    assert bare.present == frozenset() and bare.absent == OPTIONAL_GROUPS
    assert not bare.has(ColumnGroup.ANGULAR_VELOCITY) and bare.has(ColumnGroup.ROD_POSITIONS)
    assert ExternalTrajectory.not_judged(ColumnGroup.ANGULAR_VELOCITY) == (
        "not judged: no omega columns"
    )
    back = bare.trajectory
    assert np.isnan(back.qdot).all() and np.isnan(back.torque).all()
    assert np.isnan(back.tracking.e_omega).all()
    assert _rel(back.tracking.e_p, tr.tracking.e_p) <= ROUND_TRIP
    # controlled: the work of the control is not in the file, so the balances cannot close
    assert np.isnan(back.invariants.work).all()
    some = read_trajectory(
        write_trajectory(
            tmp_path / "some.csv", scene, tr, groups=frozenset({ColumnGroup.TORQUE})
        ),
        scene,
        engine=Engine.ANALYTIC,
    )
    assert some.present == {ColumnGroup.TORQUE}
    np.testing.assert_array_equal(some.trajectory.torque, tr.torque)
    assert np.isnan(some.trajectory.rod_forces).all()


def test_writer_refuses_another_scene_and_non_finite_values(controlled_run, tmp_path):
    scene, tr = controlled_run
    other = _scene("paper_example2_controlled", 0.2)
    with pytest.raises(TrajectoryFileError, match=r"n = 2 masses, the scene .* n = 5"):
        write_trajectory(tmp_path / "x.csv", other, tr)
    longer = scene.replace(output=scene.output.with_t_end(0.3))
    with pytest.raises(TrajectoryFileError, match=r"21 data rows, not the scene's output grid"):
        write_trajectory(tmp_path / "x.csv", longer, tr)
    torque = tr.torque.copy()
    torque[3, 1] = np.nan
    bad = tr.__class__(**{**tr.__dict__, "torque": torque})
    with pytest.raises(
        TrajectoryFileError,
        match=r"trajectory to write to '.*x\.csv', data row 4 \(line 5\), column 'tau_y': NaN",
    ):
        write_trajectory(tmp_path / "x.csv", scene, bad)
    assert list(tmp_path.iterdir()) == []
