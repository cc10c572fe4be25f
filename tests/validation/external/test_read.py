"""read_trajectory (validation/external/read.py): a hand-written file read to known values, either
quaternion sign to one attitude, columns in any order, and every bad file refused in one line
naming its data row (1-based; CSV: and its line) and column (docs/trajectory-format.md)."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pytest

from analytic.scene import load_scene
from analytic.trajectory import Engine
from tests.support import tolerances as tol
from validation.compare.differences import attitude_angle
from validation.external import ColumnGroup, TrajectoryFileError, read_trajectory
from validation.external.columns import OPTIONAL_GROUPS
from validation.external.write import trajectory_table

ROUND_TRIP = tol.TRAJECTORY_FILE_ROUND_TRIP_REL.value


def _scene(name: str, t_end: float):
    sc = load_scene(name)
    return sc.replace(output=sc.output.with_t_end(t_end))


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))

DOC = Path(__file__).resolve().parents[3] / "docs" / "trajectory-format.md"


def test_columns_in_any_order_read_the_same(controlled_run, tmp_path):
    scene, tr = controlled_run
    names, values = trajectory_table(tr, scene)
    order = np.random.default_rng(7).permutation(len(names))
    text = ",".join(names[i] for i in order) + "\n"
    text += "".join(",".join(repr(float(x)) for x in row[order]) + "\n" for row in values)
    (tmp_path / "shuffled.csv").write_text(text)
    back = read_trajectory(tmp_path / "shuffled.csv", scene, engine=Engine.MUJOCO).trajectory
    np.testing.assert_array_equal(back.q, tr.q)
    np.testing.assert_array_equal(back.torque, tr.torque)
    assert back.engine == Engine.MUJOCO


@pytest.mark.parametrize("flip", ["every_row", "alternate_rows"])
def test_either_quaternion_sign_reads_to_the_same_attitude(controlled_run, tmp_path, flip):
    scene, tr = controlled_run
    names, values = trajectory_table(tr, scene)
    cols = [names.index(c) for c in ("u_w", "u_x", "u_y", "u_z")]
    rows = slice(None) if flip == "every_row" else slice(1, None, 2)
    values[rows, cols] *= -1.0
    text = ",".join(names) + "\n" + "".join(",".join(map(repr, r)) + "\n" for r in values.tolist())
    (tmp_path / "flipped.csv").write_text(text)
    back = read_trajectory(tmp_path / "flipped.csv", scene, engine=Engine.ANALYTIC).trajectory
    assert float(np.max(attitude_angle(back.u, tr.u))) <= ROUND_TRIP
    # one convention: the sign continuing the scene's u(0), whatever the file chose
    np.testing.assert_array_equal(back.u, tr.u)
    # ω is a property of the attitude's motion, not of the sign: u̇ flips with u
    assert _rel(back.omega, tr.omega) <= ROUND_TRIP


# ---- a hand-written file read to known values -----------------------------------------------------

# Paper Example 1 (n = 2) for 0.02 s at 100 Hz: grid 0, 0.01, 0.02. Rotation about body z by
# 2θ with cos θ = 0.6, sin θ = 0.8 at the last row; the masses' positions; ω about z.
HAND = """t,R_x,R_y,R_z,u_w,u_x,u_y,u_z,p_1,p_2,omega_x,omega_y,omega_z
0,0,0,0,1,0,0,0,5,11,0,0,2
0.01, 0.25 ,-1.5e-1,2.5e+1,-1,0,0,0,4.5,11.25,0,0,2
0.02,1,2,3,0.6,0,0,0.8,4,12,1,-1,0.5
"""


def _quat_mul(a, b):
    """Hamilton product, w first, written out here (not the project's)."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return np.array(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ]
    )


def test_hand_written_csv_reads_to_known_values(tmp_path):
    scene = _scene("paper_example1", 0.02)
    path = tmp_path / "hand.csv"
    path.write_text(HAND)
    ext = read_trajectory(path, scene, engine=Engine.ANALYTIC)
    tr = ext.trajectory
    np.testing.assert_array_equal(tr.t, [0.0, 0.01, 0.02])
    np.testing.assert_array_equal(tr.R, [[0, 0, 0], [0.25, -0.15, 25.0], [1, 2, 3]])
    np.testing.assert_array_equal(tr.p, [[5, 11], [4.5, 11.25], [4, 12]])
    # the scene's u(0) has w > 0, so the second row's -1 reads as +1 (the same attitude)
    np.testing.assert_array_equal(tr.u, [[1, 0, 0, 0], [1, 0, 0, 0], [0.6, 0, 0, 0.8]])
    # u̇ = ½ u ⊗ (0, ω) for body-axis ω
    for k, w in enumerate([(0, 0, 2), (0, 0, 2), (1, -1, 0.5)]):
        expected = 0.5 * _quat_mul(tr.u[k], np.array([0.0, *w]))
        np.testing.assert_allclose(tr.qdot[k, 3:7], expected, rtol=0, atol=1e-15)
        np.testing.assert_allclose(tr.omega[k], w, rtol=0, atol=1e-15)
    assert ext.present == {ColumnGroup.ANGULAR_VELOCITY}
    assert ext.absent == OPTIONAL_GROUPS - {ColumnGroup.ANGULAR_VELOCITY}
    assert np.isnan(tr.qdot[:, :3]).all() and np.isnan(tr.qdot[:, 7:]).all()
    assert np.isnan(tr.torque).all() and np.isnan(tr.rod_forces).all()
    np.testing.assert_allclose(tr.invariants.quat_norm_error, 0.0, atol=1e-15)
    # momentum and energy need every velocity: absent, so NaN; uncontrolled: no work is done
    assert np.isnan(tr.invariants.energy).all() and np.isnan(tr.invariants.linear_momentum).all()
    np.testing.assert_array_equal(tr.invariants.work, 0.0)
    assert tr.info["file"] == str(path) and tr.info["format"] == "csv"


# ---- bad files: one line naming the row (1-based data row; CSV: and line) and the column ----------

HEAD, ROW0, ROW1, ROW2 = HAND.splitlines()


def _csv(*lines: str) -> str:
    return "\n".join(lines) + "\n"


BAD_CSV = {
    "nan": (
        _csv(HEAD, ROW0, ROW1.replace("-1.5e-1", "nan"), ROW2),
        r"data row 2 \(line 3\), column 'R_y': NaN",
    ),
    "inf": (
        _csv(HEAD, ROW0, ROW1, ROW2.replace(",0.5", ",-inf")),
        r"data row 3 \(line 4\), column 'omega_z': infinite \(-inf\)",
    ),
    "overflow": (
        _csv(HEAD, ROW0, ROW1, "0.02,1e999" + ROW2[6:]),
        r"data row 3 \(line 4\), column 'R_x': infinite \(inf\)",
    ),
    "non_unit_quaternion": (
        _csv(HEAD, ROW0, ROW1, ROW2.replace("0.6,0,0,0.8", "0.6,0,0,0.8002")),
        r"data row 3 \(line 4\), columns 'u_w' … 'u_z': \|u\| − 1 = 0\.00016, beyond 1e-06",
    ),
    "too_few_values": (
        _csv(HEAD, ROW0, ROW1.rsplit(",", 1)[0], ROW2),
        r"data row 2 \(line 3\): 12 values, but the header has 13 columns",
    ),
    "too_many_values": (
        _csv(HEAD, ROW0, ROW1, ROW2 + ",7"),
        r"data row 3 \(line 4\): 14 values, but the header has 13 columns",
    ),
    "unknown_column": (
        _csv(HEAD.replace("u_w", "q_w"), ROW0, ROW1, ROW2),
        r"header, column 5: unknown column 'q_w'",
    ),
    "missing_required_column": (
        _csv(*(",".join(x.split(",")[:3] + x.split(",")[4:]) for x in (HEAD, ROW0, ROW1, ROW2))),
        r"header: required column 'R_z' missing",
    ),
    "duplicate_column": (
        _csv(HEAD.replace("p_2", "p_1"), ROW0, ROW1, ROW2),
        r"header, column 10: duplicate column 'p_1' \(also column 9\)",
    ),
    "partial_optional_group": (
        _csv(*(",".join(x.split(",")[:-1]) for x in (HEAD, ROW0, ROW1, ROW2))),
        r"header: column 'omega_z' missing: the omega columns",
    ),
    "mass_count": (
        _csv(HEAD.replace("p_2", "p_2,p_3"), *(r.replace(",11", ",11,0") for r in (ROW0,)),
             ROW1.replace(",11.25", ",11.25,0"), ROW2.replace(",12", ",12,0")),
        r"header: the file has 3 masses \(p_1 … p_3\), the scene n = 2",
    ),
    "fewer_masses": (
        _csv(*(",".join(x.split(",")[:9] + x.split(",")[10:]) for x in (HEAD, ROW0, ROW1, ROW2))),
        r"header: the file has 1 mass \(p_1\), the scene n = 2",
    ),
    "gap_in_masses": (
        _csv(HEAD.replace("p_2", "p_3"), ROW0, ROW1, ROW2),
        r"header: column 'p_2' missing",
    ),
    "non_monotone_t": (
        _csv(HEAD, ROW0, ROW1, ROW2.replace("0.02", "0.01", 1)),
        r"data row 3 \(line 4\), column 't': 0\.01 s is not after the previous row's 0\.01 s",
    ),
    "off_grid_t": (
        _csv(HEAD, ROW0, ROW1.replace("0.01", "0.011", 1), ROW2),
        r"data row 2 \(line 3\), column 't': 0\.011 s, expected 0\.01 s .*first 0 s, step "
        r"1/rate = 0\.01 s, last t_end = 0\.02 s, 3 samples",
    ),
    "too_few_rows": (
        _csv(HEAD, ROW0, ROW1),
        r"column 't': 2 data rows, not the scene's output grid \(first 0 s, step 1/rate = "
        r"0\.01 s, last t_end = 0\.02 s, 3 samples\)",
    ),
    "not_a_number": (
        _csv(HEAD, ROW0, ROW1.replace("4.5", "__import__('os')"), ROW2),
        r"data row 2 \(line 3\), column 'p_1': not a number: \"__import__\('os'\)\"",
    ),
    "underscore_digits": (
        _csv(HEAD, ROW0, ROW1.replace("4.5", "4_5"), ROW2),
        r"data row 2 \(line 3\), column 'p_1': not a number: '4_5'",
    ),
    "empty_value": (
        _csv(HEAD, ROW0, ROW1.replace("4.5", " "), ROW2),
        r"data row 2 \(line 3\), column 'p_1': empty value",
    ),
    "blank_line": (
        _csv(HEAD, ROW0, "", ROW1, ROW2),
        r"data row 2 \(line 3\): empty line",
    ),
    "no_data_rows": (_csv(HEAD), r"no data rows, expected the scene's output grid"),
    "semicolons": (
        _csv(HEAD.replace(",", ";"), ROW0.replace(",", ";")),
        r"header: one column .*; columns are separated by commas",
    ),
}


@pytest.mark.parametrize("case", sorted(BAD_CSV))
def test_bad_csv_refused_in_one_line_naming_row_and_column(tmp_path, case):
    text, pattern = BAD_CSV[case]
    scene = _scene("paper_example1", 0.02)
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(TrajectoryFileError) as err:
        read_trajectory(path, scene, engine=Engine.ANALYTIC)
    message = str(err.value)
    assert "\n" not in message
    assert message.startswith(f"trajectory file {str(path)!r}")
    assert re.search(pattern, message), message


def test_the_base_of_the_bad_files_is_good(tmp_path):
    """Each bad case differs from HAND by its one defect."""
    (tmp_path / "good.csv").write_text(_csv(HEAD, ROW0, ROW1, ROW2))
    read_trajectory(tmp_path / "good.csv", _scene("paper_example1", 0.02), engine=Engine.ANALYTIC)


def _parquet(tmp_path: Path, columns: dict, name: str = "bad.parquet") -> Path:
    pa = pytest.importorskip("pyarrow")
    pq = pytest.importorskip("pyarrow.parquet")
    path = tmp_path / name
    pq.write_table(pa.table(columns), path)
    return path


def _hand_columns() -> dict:
    rows = [[float(x) for x in r.split(",")] for r in (ROW0, ROW1, ROW2)]
    return {name: [r[c] for r in rows] for c, name in enumerate(HEAD.split(","))}


@pytest.mark.parametrize(
    "change, pattern",
    [
        ({"u_w": [1.0, None, 0.6]}, r"bad\.parquet', data row 2, column 'u_w': missing value \(null\)"),
        ({"R_x": [0.0, float("nan"), 1.0]}, r"bad\.parquet', data row 2, column 'R_x': NaN"),
        ({"R_x": ["0", "0.25", "1"]}, r"column 'R_x': of type string, not numbers"),
        ({"u_z": [0.0, 0.0, 0.9]}, r"data row 3, columns 'u_w' … 'u_z': \|u\| − 1"),
        ({"x": [1.0, 2.0, 3.0]}, r"header, column 14: unknown column 'x'"),
    ],
)
def test_bad_parquet_refused_naming_row_and_column(tmp_path, change, pattern):
    path = _parquet(tmp_path, {**_hand_columns(), **change})
    with pytest.raises(TrajectoryFileError, match=pattern) as err:
        read_trajectory(path, _scene("paper_example1", 0.02), engine=Engine.ANALYTIC)
    assert "\n" not in str(err.value)


def test_parquet_with_more_rows_than_the_grid_refused_before_reading(tmp_path):
    cols = {k: v * 1000 for k, v in _hand_columns().items()}
    path = _parquet(tmp_path, cols)
    with pytest.raises(TrajectoryFileError, match=r"3000 rows, more than the scene's output grid"):
        read_trajectory(path, _scene("paper_example1", 0.02), engine=Engine.ANALYTIC)


@pytest.mark.faults
def test_fifo_and_oversized_file_refused_without_reading_a_link_followed(tmp_path):
    scene = _scene("paper_example1", 0.02)
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)  # no writer: reading would block; the reader must not wait
    with pytest.raises(TrajectoryFileError, match=r"'.*pipe\.csv': a FIFO, not a regular file"):
        read_trajectory(fifo, scene, engine=Engine.ANALYTIC)
    good = tmp_path / "good.csv"
    good.write_text(HAND)
    link = tmp_path / "link.csv"
    link.symlink_to(good)  # a file the user names: a link is followed to a regular file ...
    assert read_trajectory(link, scene, engine=Engine.ANALYTIC).source == str(link)
    link_to_fifo = tmp_path / "link_to_pipe.csv"
    link_to_fifo.symlink_to(fifo)  # ... and never to a FIFO
    with pytest.raises(TrajectoryFileError, match=r"link_to_pipe\.csv': a FIFO, not a regular"):
        read_trajectory(link_to_fifo, scene, engine=Engine.ANALYTIC)
    big = tmp_path / "big.csv"
    big.write_text(HAND + " " * 200_000)
    with pytest.raises(TrajectoryFileError, match=r"'.*big\.csv': larger than [0-9,]+ bytes"):
        read_trajectory(big, scene, engine=Engine.ANALYTIC)
    with pytest.raises(TrajectoryFileError, match=r"no such file"):
        read_trajectory(tmp_path / "absent.csv", scene, engine=Engine.ANALYTIC)


def test_suffix_names_the_format(tmp_path):
    scene = _scene("paper_example1", 0.02)
    (tmp_path / "run.txt").write_text(HAND)
    with pytest.raises(TrajectoryFileError, match=r"unknown format \(suffix '\.txt'\)"):
        read_trajectory(tmp_path / "run.txt", scene, engine=Engine.ANALYTIC)
    parquet = _parquet(tmp_path, _hand_columns(), "run.parquet")
    (tmp_path / "named.csv").write_bytes(parquet.read_bytes())
    with pytest.raises(TrajectoryFileError, match=r"a Parquet file, not CSV text"):
        read_trajectory(tmp_path / "named.csv", scene, engine=Engine.ANALYTIC)
    ok = read_trajectory(tmp_path / "named.csv", scene, engine=Engine.ANALYTIC, format="parquet")
    np.testing.assert_array_equal(ok.trajectory.p, [[5, 11], [4.5, 11.25], [4, 12]])


def test_docs_example_is_a_valid_file(tmp_path):
    text = DOC.read_text(encoding="utf-8")
    example = re.search(r"```csv\n(.*?)```", text, re.S)
    assert example is not None
    (tmp_path / "example.csv").write_text(example.group(1))
    ext = read_trajectory(
        tmp_path / "example.csv", _scene("paper_example1", 0.02), engine=Engine.ANALYTIC
    )
    assert ext.present == {ColumnGroup.ANGULAR_VELOCITY}
