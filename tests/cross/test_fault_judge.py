"""Faults in what ``tumble judge`` reads: another engine's file over a shorter horizon, reference
packs, and Parquet and CSV files built to be expensive.

Each test is one row of the table at the end of ``docs/verdicts.md``. A file that covers less than
the scene's horizon is refused unless the user says which horizon to judge (``--t-end``,
``--up-to-file-end``), and then judged over that horizon, which the report states. A reference pack
judges any horizon up to its own, and not at all when it does not say it is accurate enough. A
Parquet file's metadata (rows, columns, types, declared sizes) is checked before any of its data is
decompressed; a file too large is refused naming its rows and the limit.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from analytic.scene import load_scene
from analytic.scene.dump import scene_to_toml
from analytic.trajectory import Engine
from mj_bridge.plants import plant
from tests.support.guards import forbid_plant_runs
from validation.cli import EXIT_USAGE, main
from validation.external import TrajectoryFileError, read_trajectory
from validation.external.judge import judge_request
from validation.external.reference_pack import write_pack
from validation.external.write import trajectory_table, write_trajectory

pytestmark = pytest.mark.faults


def _scene(name: str, t_end: float | None = None):
    sc = load_scene(name)
    return sc if t_end is None else sc.replace(output=sc.output.with_t_end(t_end))


def _refused(capsys, argv: list[str], out: Path) -> str:
    """``tumble`` with ``argv``: exit 2, one stderr line (returned), no traceback, no output."""
    try:
        rc = main([*argv, "--out", str(out)])
    except SystemExit as stop:  # an option's refusal, by the argument parser
        rc = stop.code
    err = capsys.readouterr().err.splitlines()
    assert rc == EXIT_USAGE, err
    assert len(err) == 1 and err[0].startswith("tumble"), err
    assert "Traceback" not in err[0]
    assert not out.exists()
    return err[0]


@pytest.fixture(scope="module")
def two_seconds(tmp_path_factory):
    """A faithful 2 s run of the 20 s scene paper_example1: the analytic plant at the scene's own
    settings over 0-2 s, every column, written with the CSV writer."""
    short = _scene("paper_example1", 2.0)
    path = tmp_path_factory.mktemp("short") / "theirs.csv"
    write_trajectory(path, short, plant("analytic").simulate(short))
    return path


def test_a_short_run_is_refused_naming_the_options_and_judged_over_its_horizon_when_asked(
    two_seconds, tmp_path, monkeypatch, capsys
):
    """A faithful 2 s run of a 20 s scene -> without an option, exit 2 before any plant, one line
    naming its 201 rows, the grid's 2001 and the options --t-end 2 and --up-to-file-end; with
    --up-to-file-end (or --t-end 2) judged over 0-2 s: it passes beside the analytic plant, the
    comparison holds 201 samples up to t = 2 s, and report.md's first note and report.json's
    run.judged_horizon say "judged over 0-2 s of the scene's 20 s"."""
    base = ["judge", "paper_example1", "--trajectory", str(two_seconds), "--plants", "analytic"]
    with monkeypatch.context() as m:
        forbid_plant_runs(m)
        line = _refused(capsys, base, tmp_path / "refused")
    assert "201 data rows" in line and "2001 samples" in line
    assert "--t-end 2" in line and "--up-to-file-end" in line
    request = judge_request("paper_example1", two_seconds, plants="analytic", t_end=2)
    assert request.validation.horizon == 2.0 and request.horizon.samples == 201
    assert "judged over 0-2 s of the scene's 20 s" in request.horizon.sentence
    out = tmp_path / "judged"
    rc = main([*base, "--up-to-file-end", "--out", str(out)])
    said = capsys.readouterr().out
    assert rc == 0, said
    assert "PASS" in said and "judged over 0-2 s of the scene's 20 s" in said
    report = json.loads((out / "report.json").read_text())
    assert report["passed"] is True
    assert report["samples"] == 201 and report["t_end"] == pytest.approx(2.0)
    horizon = report["run"]["judged_horizon"]
    assert (horizon["t_end_s"], horizon["scene_t_end_s"], horizon["source"]) == (2.0, 20.0, "file_end")
    notes = [line for line in (out / "report.md").read_text().splitlines() if line.startswith("> ")]
    assert notes[0].startswith("> judged over 0-2 s of the scene's 20 s")


@pytest.mark.parametrize(
    ("t_end", "said"),
    [
        ("30", "t_end: 30.0 s is not in (0, 20] s"),
        ("2.005", "t_end: 2.005 s is not on the output grid"),
        ("0", "--t-end: must be a positive finite number (got '0')"),
        ("nan", "--t-end: must be a positive finite number (got 'nan')"),
    ],
)
def test_a_t_end_beyond_the_scene_or_off_its_grid_is_one_line(
    two_seconds, tmp_path, monkeypatch, capsys, t_end, said
):
    """--t-end beyond the scene's t_end, off its output grid, zero or NaN -> exit 2 before any
    plant, one line naming t_end and the value."""
    forbid_plant_runs(monkeypatch)
    argv = ["judge", "paper_example1", "--trajectory", str(two_seconds), "--t-end", t_end]
    assert said in _refused(capsys, argv, tmp_path / "out")


def test_a_file_longer_than_t_end_or_of_one_row_is_refused(two_seconds, tmp_path, monkeypatch, capsys):
    """A 2 s file judged with --t-end 1, or a file of one row (t = 0) with --up-to-file-end ->
    exit 2 before any plant, one line: 201 data rows against the grid's 101; one row covers no
    horizon."""
    forbid_plant_runs(monkeypatch)
    argv = ["judge", "paper_example1", "--trajectory", str(two_seconds), "--t-end", "1"]
    line = _refused(capsys, argv, tmp_path / "a")
    assert "201 data rows" in line and "101 samples" in line
    one = tmp_path / "one.csv"
    one.write_text("".join(two_seconds.read_text().splitlines(keepends=True)[:2]))
    argv = ["judge", "paper_example1", "--trajectory", str(one), "--up-to-file-end"]
    assert "one data row (t = 0) covers no horizon" in _refused(capsys, argv, tmp_path / "b")


@pytest.fixture(scope="module")
def pack(tmp_path_factory):
    """The reference pack of paper_example1_controlled over 0.4 s (``pack/``, its scene beside it
    as ``scene.toml``), and the analytic plant's runs at the scene's own settings over 0.2 s
    (``theirs.csv``) and 0.8 s (``long.csv``), every column."""
    root = tmp_path_factory.mktemp("pack")
    scene = _scene("paper_example1_controlled", 0.4)
    (root / "scene.toml").write_text(scene_to_toml(scene))
    result = write_pack(scene, root / "pack")
    assert result.accurate_enough
    for name, t_end in (("theirs.csv", 0.2), ("long.csv", 0.8)):
        sc = _scene("paper_example1_controlled", t_end)
        write_trajectory(root / name, sc, plant("analytic").simulate(sc))
    (root / "long.toml").write_text(scene_to_toml(_scene("paper_example1_controlled", 0.8)))
    return root


def test_a_pack_judges_a_shorter_horizon_and_refuses_a_longer_one(pack, tmp_path, monkeypatch, capsys):
    """A reference pack of 0.4 s and a file of 0.2 s -> judged against the pack over 0-0.2 s
    (--t-end 0.2), no plant run, PASS for the analytic plant's own run; a file of 0.8 s of the
    same scene judged against that pack -> exit 2, one line: its reference covers 0-0.4 s,
    shorter than the 0-0.8 s judged."""
    forbid_plant_runs(monkeypatch)
    ref = ["--reference", str(pack / "pack")]
    out = tmp_path / "judged"
    argv = ["judge", str(pack / "scene.toml"), "--trajectory", str(pack / "theirs.csv"), *ref]
    rc = main([*argv, "--t-end", "0.2", "--out", str(out)])
    said = capsys.readouterr().out
    assert rc == 0, said
    report = json.loads((out / "report.json").read_text())
    assert report["passed"] is True and report["samples"] == 21
    assert [p["engine"] for p in report["plants"]] == ["reference", "theirs"]
    assert report["run"]["judged_horizon"]["scene_t_end_s"] == 0.4
    argv = ["judge", str(pack / "long.toml"), "--trajectory", str(pack / "long.csv"), *ref]
    line = _refused(capsys, argv, tmp_path / "refused")
    assert "its reference covers 0-0.4 s, shorter than the 0-0.8 s judged" in line


def test_a_pack_not_accurate_enough_is_refused(pack, tmp_path, monkeypatch, capsys):
    """A pack whose reference.json says accurate_enough = false -> exit 2 before any work, one
    line naming the pack, the quantity and "not accurate enough"; nothing is written (never a
    PASS against it)."""
    forbid_plant_runs(monkeypatch)
    bad = tmp_path / "bad"
    shutil.copytree(pack / "pack", bad)
    record = json.loads((bad / "reference.json").read_text())
    record["accurate_enough"] = False
    record["accuracy"][0]["ok"] = False
    (bad / "reference.json").write_text(json.dumps(record))
    argv = [
        "judge", str(pack / "scene.toml"), "--trajectory", str(pack / "theirs.csv"),
        "--reference", str(bad), "--t-end", "0.2",
    ]  # fmt: skip
    line = _refused(capsys, argv, tmp_path / "out")
    assert "not accurate enough" in line and str(bad) in line
    assert record["accuracy"][0]["quantity"] in line


def _parquet_table(scene, t_end: float) -> dict[str, np.ndarray]:
    """The analytic plant's run of ``scene`` over ``t_end`` as named columns."""
    sc = scene.replace(output=scene.output.with_t_end(t_end))
    names, values = trajectory_table(plant("analytic").simulate(sc), sc)
    return {name: values[:, c] for c, name in enumerate(names)}


_PEAK = textwrap.dedent(
    """
    import sys
    from analytic.scene import load_scene
    from validation.external import read_trajectory

    def peak():  # this process's peak resident memory, bytes (VmHWM: not inherited over exec)
        with open("/proc/self/status") as f:
            line = next(x for x in f if x.startswith("VmHWM:"))
        return int(line.split()[1]) * 1024

    sc = load_scene("paper_example1")
    sc = sc.replace(output=sc.output.with_t_end(0.02))
    before = peak()
    try:
        read_trajectory(sys.argv[1], sc, engine="x")
    except ValueError as exc:
        print(str(exc))
    print(peak() - before)
    """
)


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads VmHWM from /proc")
def test_a_small_parquet_file_with_a_huge_binary_column_is_refused_before_decompressing(tmp_path):
    """A Parquet file of a few KB whose binary column decompresses to 256 MiB -> refused from its
    metadata (the column's type), one line naming the column; the reading process's peak memory
    grows by less than 64 MiB (nothing was decompressed)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    huge = 256 << 20
    path = tmp_path / "bomb.parquet"
    table = pa.table({"t": [0.0, 0.01, 0.02], "R_x": pa.array([b"\0" * huge, b"", b""])})
    pq.write_table(table, path, compression="zstd")
    del table
    assert path.stat().st_size < 100_000
    done = subprocess.run(
        [sys.executable, "-c", _PEAK, str(path)], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr[-2000:]
    message, grown = done.stdout.strip().splitlines()
    assert "column 'R_x': of type binary, not numbers" in message
    assert int(grown) < 64 << 20, grown


def test_a_valid_parquet_file_of_one_row_row_groups_is_read(tmp_path):
    """A valid Parquet file of 21 one-row row groups (its bytes mostly row-group overhead) -> read,
    to the same trajectory as the same table in a CSV file (the bound is on rows × columns)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    scene = _scene("paper_example1", 0.2)
    columns = _parquet_table(scene, 0.2)
    path = tmp_path / "groups.parquet"
    pq.write_table(pa.table(columns), path, row_group_size=1)
    assert pq.ParquetFile(path).metadata.num_row_groups == 21
    csv = tmp_path / "same.csv"
    csv.write_text(
        ",".join(columns) + "\n"
        + "".join(",".join(repr(float(v[k])) for v in columns.values()) + "\n" for k in range(21))
    )  # fmt: skip
    got = read_trajectory(path, scene, engine=Engine.ANALYTIC).trajectory
    want = read_trajectory(csv, scene, engine=Engine.ANALYTIC).trajectory
    np.testing.assert_array_equal(got.q, want.q)
    np.testing.assert_array_equal(got.qdot, want.qdot)


def test_a_million_row_file_is_refused_naming_its_rows_and_the_limit(tmp_path):
    """A 10⁶-row file (CSV; Parquet, compressible or not) -> one line naming its 1000000 rows and
    the 21 samples of the scene's grid (and, when the bytes are beyond the bound, the bound), the
    data never parsed."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    scene = _scene("paper_example1", 0.2)
    rows = 1_000_000
    csv = tmp_path / "million.csv"
    csv.write_bytes(b"t\n" + b"0\n" * rows)
    with pytest.raises(TrajectoryFileError) as err:
        read_trajectory(csv, scene, engine="x")
    text = str(err.value)
    assert "1000000 data rows" in text and "21 samples" in text and "larger than" in text
    for name, t in (("varied.parquet", np.arange(rows) / 100.0), ("flat.parquet", np.zeros(rows))):
        path = tmp_path / name
        pq.write_table(pa.table({"t": t}), path)
        with pytest.raises(TrajectoryFileError) as err:
            read_trajectory(path, scene, engine="x")
        assert "1000000 rows" in str(err.value) and "21 samples" in str(err.value), name
        assert "\n" not in str(err.value)


@pytest.mark.slow
def test_a_judge_table_with_a_bad_horizon_is_a_collection_error_naming_the_key(
    pytester: pytest.Pytester,
) -> None:
    """A [judge] table with t_end off the scene's grid or beyond it, or up_to_file_end not a
    boolean -> a collection error naming judge.t_end or judge.up_to_file_end; a short file with
    up_to_file_end = true or the t_end it covers -> its checks pass; without either -> its run
    item fails naming the options."""
    sc = _scene("paper_example1_controlled", 0.1)
    (pytester.path / "s.toml").write_text(scene_to_toml(sc))
    short = _scene("paper_example1_controlled", 0.05)
    write_trajectory(pytester.path / "mine.csv", short, plant("analytic").simulate(short))
    head = '[judge]\nscene = "s.toml"\ntrajectory = "mine.csv"\nplants = "analytic"\n'
    pytester.makefile(
        ".toml",
        test_off=head + "t_end = 0.055\n",
        test_beyond=head + "t_end = 1.0\n",
        test_flag=head + 'up_to_file_end = "yes"\n',
        test_end=head + "up_to_file_end = true\n",
        test_t=head + "t_end = 0.05\n",
        test_short=head,
    )
    r = pytester.runpytest_subprocess("-p", "no:cacheprovider", "-rA", "--continue-on-collection-errors")
    text = r.stdout.str()
    assert "test_off.toml: judge.t_end: 0.055 s is not on the output grid" in text
    assert "test_beyond.toml: judge.t_end: 1.0 s is not in (0, 0.1] s" in text
    assert "test_flag.toml: judge.up_to_file_end: must be true or false" in text
    assert re.search(r"PASSED test_end\.toml::analytic_vs_mine\.attitude", text)
    assert re.search(r"PASSED test_t\.toml::analytic_vs_mine\.attitude", text)
    assert re.search(r"FAILED test_short\.toml::run", text)
    assert re.search(
        r"could not run: TrajectoryFileError: .*mine\.csv', column 't': 6 data rows, .* it stops "
        r"on the grid at t = 0\.05 s: .*--t-end 0\.05 or --up-to-file-end \(\[judge\] t_end or "
        r"up_to_file_end = true\)",
        text,
    )
    assert r.parseoutcomes()["errors"] == 3

