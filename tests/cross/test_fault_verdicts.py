"""Faults a validation's verdict must survive: a verdict true to its files.

A run is PASSED only when every check passed and every file its report names exists, whole, in
the committed directory; anything else is FAILED or INTERRUPTED in the first line of report.md,
in report.json and in the exit status, and a run whose files cannot be written gives no verdict
at all (one line, exit 1, the previous run kept as it was). Each test below is one fault and
what the tool does about it:

* a full disk while a figure, its rendering, or the recording is written, here or in a worker,
  or on a real tiny filesystem -> OutputError, the previous run unchanged;
* a figure or the recording that cannot be made (a bug) -> FAILED, the file not named;
* SIGTERM while the plants run (in workers or here), Ctrl-C while a plant runs or while the
  report is written -> the job stops within seconds, exit 143, report.md INTERRUPTED;
* a plant worker killed (``kill -9``) -> the plant is redone here, and the report says so;
* a choice of plants with nothing to compare -> refused before any plant runs;
* hostile strings in a scene -> literal text in report.md, its structure intact.
"""

from __future__ import annotations

import errno
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from analytic.scene.builtin import builtin_scene_path
from validation import validate as V
from validation.cli import main
from validation.runs.atomic import OutputError

pytestmark = pytest.mark.faults

SCENE = "paper_example1_controlled"
T_END = 0.2
"""A short horizon: every stage runs, in a second or two."""
REPO = Path(__file__).resolve().parents[2]
ENOSPC = OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


def _report_schema():
    """report.json's JSON Schema, with the schemas it refers to."""
    jsonschema = pytest.importorskip("jsonschema")
    from referencing import Registry, Resource

    from validation.report import provenance as pv

    docs = [json.loads(p.read_text()) for p in pv.SCHEMA_DIR.glob("*.schema.json")]
    registry = Registry().with_resources((d["$id"], Resource.from_contents(d)) for d in docs)
    schema = json.loads(pv.schema_path("report").read_text())
    return jsonschema.Draft202012Validator(schema, registry=registry)


def _snapshot(d: Path) -> dict[str, bytes]:
    """Every entry of ``d`` (hidden ones too) with its bytes: what must not change."""
    return {p.name: p.read_bytes() for p in sorted(d.iterdir()) if p.is_file()}


def _siblings(d: Path) -> list[str]:
    """What the run left beside ``d`` (staging directories, locks)."""
    return sorted(p.name for p in d.parent.iterdir() if p.name != d.name)


@pytest.fixture(scope="module")
def previous_run(tmp_path_factory) -> Path:
    """A complete, passing run: what a later run must not lose."""
    out = tmp_path_factory.mktemp("previous") / "v"
    res = V.run_validation(SCENE, out, t_end=T_END, concurrent=False)
    assert res.passed
    return out


@pytest.fixture
def previous(previous_run, tmp_path) -> Path:
    """A copy of the previous run in a directory of its own."""
    out = tmp_path / "v"
    shutil.copytree(previous_run, out)
    return out


def _fail_writes_of(monkeypatch, pattern: str) -> None:
    """``os.write`` fails with ENOSPC on any file whose name matches ``pattern`` (the temporary
    file of a figure or the recording): the disk fills up exactly there."""
    fds = Path("/proc/self/fd")
    if not fds.is_dir():
        pytest.skip("needs /proc/self/fd to tell which file a write goes to")
    real = os.write

    def write(fd, data):
        try:
            name = os.readlink(fds / str(fd))
        except OSError:
            name = ""
        if re.search(pattern, Path(name).name):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(fd, data)

    monkeypatch.setattr(os, "write", write)


@pytest.mark.parametrize("pattern", [r"^\.errors\.png\.", r"^\.run\.rrd\."])
def test_full_disk_while_the_evidence_is_written(previous, monkeypatch, pattern):
    """ENOSPC writing a figure or the recording (here) -> OutputError, the previous run kept
    byte for byte, nothing left beside it."""
    before = _snapshot(previous)
    _fail_writes_of(monkeypatch, pattern)
    with pytest.raises(OutputError, match="No space left on device") as err:
        V.run_validation(SCENE, previous, t_end=T_END, concurrent=False)
    assert "keeps its previous contents" in str(err.value)
    assert _snapshot(previous) == before
    assert _siblings(previous) == []


def test_full_disk_while_matplotlib_renders(previous, monkeypatch):
    """ENOSPC raised inside a figure's rendering (savefig) -> OutputError, not a figure error."""
    from validation.report.figures import Drawing

    before = _snapshot(previous)

    def render(self, fmt="png"):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), "savefig")

    monkeypatch.setattr(Drawing, "render", render)
    with pytest.raises(OutputError, match="No space left on device"):
        V.run_validation(SCENE, previous, t_end=T_END, concurrent=False)
    assert _snapshot(previous) == before


FORKED = """
import errno, json, os, re, signal, sys
from pathlib import Path
from validation import validate as V
from validation.runs import workers
from validation.runs.atomic import OutputError

assert workers.can_fork(), "a fresh interpreter with one thread should fork"
mode, out = sys.argv[1], Path(sys.argv[2])
parent = os.getpid()
if mode == "enospc":  # the disk fills up while a worker writes errors.png
    real = os.write
    def write(fd, data):
        try:
            name = os.readlink(f"/proc/self/fd/{fd}")
        except OSError:
            name = ""
        if re.match(r"^\\.errors\\.png\\.", Path(name).name):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(fd, data)
    os.write = write
    try:
        V.run_validation("paper_example1_controlled", out, t_end=0.2)
        print(json.dumps({"raised": None}))
    except OutputError as exc:
        print(json.dumps({"raised": "OutputError", "message": str(exc)}))
elif mode == "kill":  # the MuJoCo plant's worker is killed on its first call
    real_task = V._plant_task
    def task(pl, *a, **k):
        if os.getpid() != parent and pl.engine == "mujoco":
            os.kill(os.getpid(), signal.SIGKILL)
        return real_task(pl, *a, **k)
    V._plant_task = task
    res = V.run_validation("paper_example1_controlled", out, t_end=0.2)
    print(json.dumps({"passed": res.passed, "failure": res.failure}))
"""


def _forked(mode: str, out: Path) -> dict:
    """Run :data:`FORKED` in a fresh interpreter (one thread, so the workers fork)."""
    from validation.runs import workers

    if not (sys.platform.startswith("linux") and workers.available_cpus() > 1):
        pytest.skip("workers fork only on Linux with more than one CPU")
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    env.pop(workers.ENV_SWITCH, None)
    proc = subprocess.run(
        [sys.executable, "-c", FORKED, mode, str(out)],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.splitlines()[-1])


def test_full_disk_inside_a_figure_worker(previous):
    """ENOSPC writing a figure in a forked evidence worker -> the same OutputError in this process,
    the previous run kept byte for byte."""
    before = _snapshot(previous)
    got = _forked("enospc", previous)
    assert got["raised"] == "OutputError", got
    assert "No space left on device" in got["message"]
    assert _snapshot(previous) == before
    assert _siblings(previous) == []


def _mount_tmpfs(where: Path, size_kb: int) -> None:
    where.mkdir()
    try:
        subprocess.run(
            ["mount", "-t", "tmpfs", "-o", f"size={size_kb}k", "tmpfs", str(where)],
            check=True,
            capture_output=True,
            timeout=30,
        )
    except (OSError, subprocess.SubprocessError):
        pytest.skip("mounting a tmpfs is not allowed here")


def _tumble(*args: str, env: dict | None = None, **kw) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "validation", *args],
        capture_output=True,
        text=True,
        env=env or os.environ,
        timeout=300,
        cwd=kw.get("cwd"),
    )


def test_full_disk_on_a_real_tiny_filesystem(previous, tmp_path):
    """A tmpfs with room for the previous run and a new report, not for a figure -> exit 1, one
    line, the previous run unchanged, nothing left beside it (TUMBLE_WORKERS=0 and workers)."""
    kb = {p.name: -(-p.stat().st_size // 4096) * 4 for p in previous.iterdir()}  # tmpfs pages
    report_kb = kb["report.json"] + kb["report.md"] + kb["manifest.json"]
    assert min(kb[n] for n in kb if n.endswith(".png")) > report_kb + 64
    mnt = tmp_path / "mnt"
    _mount_tmpfs(mnt, sum(kb.values()) + report_kb + 64)
    try:
        shutil.copytree(previous, mnt / "v")
        before = _snapshot(mnt / "v")
        for switch in ("0", "1"):
            env = dict(os.environ, TUMBLE_WORKERS=switch)
            proc = _tumble("validate", SCENE, "--t-end", str(T_END), "--out", str(mnt / "v"), env=env)
            assert proc.returncode == 1, proc.stderr
            errors = [x for x in proc.stderr.splitlines() if x.startswith("tumble: error:")]
            assert len(errors) == 1 and "No space left on device" in errors[0], proc.stderr
            assert "keeps its previous contents" in errors[0]
            assert "PASS" not in proc.stdout
            assert _snapshot(mnt / "v") == before
            assert _siblings(mnt / "v") == []
    finally:
        subprocess.run(["umount", "-l", str(mnt)], capture_output=True, timeout=30)


def test_a_figure_that_cannot_be_drawn_fails_the_run(tmp_path, monkeypatch):
    """A drawing bug in one figure -> FAILED first in report.md and report.json, the figure named
    as the cause, no file of it, and every file the report names exists."""
    import validation.report.report as R

    def broken(*a, **k):
        raise RuntimeError("a drawing bug")

    monkeypatch.setattr(R, "figure_tracking", broken)
    res = V.run_validation(SCENE, tmp_path / "v", t_end=T_END, concurrent=False)
    assert not res.passed and "tracking" in res.failure and "a drawing bug" in res.failure
    md = (tmp_path / "v" / "report.md").read_text()
    assert md.splitlines()[0] == f"# {SCENE}: FAILED"
    assert "a drawing bug" in md.split("##")[0]  # said before any section
    doc = json.loads((tmp_path / "v" / "report.json").read_text())
    assert doc["verdict"] == "FAILED" and doc["passed"] is False
    assert not list((tmp_path / "v").glob("tracking.*"))
    for name in doc["figures"]:
        assert (tmp_path / "v" / name).is_file()
    assert set(res.files) == {p.name for p in (tmp_path / "v").iterdir()}


def test_a_recording_that_cannot_be_made_fails_the_run(tmp_path, monkeypatch, capsys):
    """A recording bug -> exit 1, FAILED, and the closing line names no run.rrd (there is none)."""
    import validation.recording.recording as rec

    def broken(*a, **k):
        raise ValueError("a recording bug")

    monkeypatch.setattr(rec, "write_recording", broken)
    monkeypatch.setenv("TUMBLE_WORKERS", "0")
    out = tmp_path / "v"
    status = main(["validate", SCENE, "--t-end", str(T_END), "--out", str(out)])
    said = capsys.readouterr().out
    assert status == 1
    assert said.startswith("FAIL:") and "a recording bug" in said
    assert "run.rrd" not in said and not (out / "run.rrd").exists()
    assert (out / "report.md").read_text().splitlines()[0] == f"# {SCENE}: FAILED"


def test_a_plant_interrupted_part_way_makes_the_report_interrupted(tmp_path):
    """Ctrl-C while the analytic plant runs (here) -> KeyboardInterrupt, report.md INTERRUPTED
    first with how far each plant got, report.json passed false, manifest interrupted."""

    def progress(stage, t):
        if stage == "analytic" and t > 0.1:
            raise KeyboardInterrupt

    out = tmp_path / "v"
    with pytest.raises(KeyboardInterrupt):
        V.run_validation(SCENE, out, t_end=T_END, progress=progress, concurrent=False)
    lines = (out / "report.md").read_text().splitlines()
    assert lines[0] == f"# {SCENE}: INTERRUPTED"
    assert lines[2].startswith("**The run was interrupted:**") and "analytic reached t =" in lines[2]
    doc = json.loads((out / "report.json").read_text())
    assert doc["verdict"] == "INTERRUPTED" and doc["passed"] is False
    _report_schema().validate(doc)  # an interrupted report is still a report.json
    man = json.loads((out / "manifest.json").read_text())
    assert man["state"] == "interrupted"
    assert set(man["files"]) | {"manifest.json"} == {p.name for p in out.iterdir()}


def test_ctrl_c_while_the_report_is_written_makes_it_interrupted(tmp_path, monkeypatch):
    """Ctrl-C arriving while a passing run's report is written -> the report is written again,
    INTERRUPTED first, and the set is committed interrupted (never PASSED in an interrupted set)."""
    real = V.write_report
    calls = []

    def write_report(*a, **k):
        calls.append(k.get("interrupted"))
        if len(calls) == 1:
            os.kill(os.getpid(), signal.SIGINT)
        return real(*a, **k)

    monkeypatch.setattr(V, "write_report", write_report)
    out = tmp_path / "v"
    with pytest.raises(KeyboardInterrupt):
        V.run_validation(SCENE, out, t_end=T_END, concurrent=False)
    assert calls == [False, True]
    assert (out / "report.md").read_text().splitlines()[0] == f"# {SCENE}: INTERRUPTED"
    assert json.loads((out / "report.json").read_text())["passed"] is False
    assert json.loads((out / "manifest.json").read_text())["state"] == "interrupted"


@pytest.mark.parametrize("workers_switch", ["1", "0"], ids=["workers", "one-process"])
def test_sigterm_while_the_plants_run_stops_the_job(tmp_path, workers_switch):
    """SIGTERM to the command while the plants run a 200 s horizon -> exit 143 within a few
    seconds, report.md INTERRUPTED, report.json passed false, manifest interrupted."""
    out = tmp_path / "f"
    env = dict(os.environ, TUMBLE_WORKERS=workers_switch)
    proc = subprocess.Popen(
        [sys.executable, "-m", "validation", "validate", SCENE, "--t-end", "200", "--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        for line in proc.stderr:
            if ": mujoco plant, 0 -> 200 s" in line:
                break
        time.sleep(1.0)  # every plant is well inside its run
        assert proc.poll() is None, "the run ended before the signal"
        proc.send_signal(signal.SIGTERM)
        t0 = time.monotonic()
        proc.communicate(timeout=60)
        took = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 143
    assert took < 5.0, f"the job took {took:.1f} s to stop"
    first = (out / "report.md").read_text().splitlines()[0]
    assert first == f"# {SCENE}: INTERRUPTED"
    doc = json.loads((out / "report.json").read_text())
    assert doc["passed"] is False and doc["verdict"] == "INTERRUPTED"
    assert json.loads((out / "manifest.json").read_text())["state"] == "interrupted"
    mujoco = next(p for p in doc["plants"] if p["engine"] == "mujoco")  # running at the signal
    assert mujoco["status"] == "interrupted" and mujoco["t_reached"] < 200


def test_a_killed_plant_worker_is_redone_here(tmp_path):
    """The MuJoCo plant's worker killed (SIGKILL) -> the plant is run again in the main process,
    the run passes, and the report says which plant was redone and why."""
    got = _forked("kill", tmp_path / "v")
    assert got["passed"], got
    md = (tmp_path / "v" / "report.md").read_text()
    assert md.splitlines()[0] == f"# {SCENE}: PASSED"
    head = md.split("##")[0]
    assert "MuJoCo plant" in head and "exit -9" in head and "main process" in head
    doc = json.loads((tmp_path / "v" / "report.json").read_text())
    assert any("exit -9" in r for r in doc["run"]["redone"])


def test_a_plant_raising_value_error_part_way_fails_the_run_and_keeps_it(tmp_path, monkeypatch):
    """An engine raising ValueError after the plants started (bad input was refused before) ->
    the run is FAILED, naming the plant and the error; its files are kept, marked failed (not
    discarded as bad input)."""
    from mj_bridge.plants import MujocoPlant

    def engine_error(self, scene, settings, t_end, progress):
        raise ValueError("All components of the initial state `y0` must be finite.")

    monkeypatch.setattr(MujocoPlant, "_simulate", engine_error)
    res = V.run_validation(SCENE, tmp_path / "v", t_end=T_END, concurrent=False)
    assert not res.passed and "MuJoCo plant: ValueError: All components" in res.failure
    assert (tmp_path / "v" / "report.md").read_text().startswith(f"# {SCENE}: FAILED")
    manifest = json.loads((tmp_path / "v" / "manifest.json").read_text())
    assert manifest["state"] == "failed"


@pytest.mark.parametrize("plants", ["analytic", "analytic,analytic", "mujoco,analytic,mujoco"])
def test_plants_with_nothing_to_compare_are_refused_up_front(tmp_path, monkeypatch, plants):
    """One plant, or a plant named twice -> ValueError naming plants and the value before any
    plant runs; the command line says it in one line and exits 2."""

    def no_plant(*a, **k):
        raise AssertionError("a plant ran")

    monkeypatch.setattr(V, "_plant_task", no_plant)
    with pytest.raises(ValueError, match=r"^plants: .*" + re.escape(repr(plants))):
        V.run_validation(SCENE, tmp_path / "v", plants=plants, t_end=T_END, concurrent=False)
    assert not (tmp_path / "v").exists()
    proc = _tumble("validate", SCENE, "--plants", plants, "--out", str(tmp_path / "c"))
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and proc.stderr.startswith("tumble: error: plants:")
    assert proc.stdout == "" and not (tmp_path / "c").exists()


HOSTILE = [
    'see <img src=x onerror="alert(1)">',
    "line one\n# an added heading\n| a | fake | row |",
    "`code` and ``` a fence",
    "# leading hash",
    "<!-- an open comment",
    "[a link](javascript:alert(1)) ![an image](http://example.invalid/x.png)",
]


def test_hostile_scene_strings_are_literal_text_in_report_md(tmp_path):
    """HTML, newlines, headings, pipes, backticks and links in the scene's name, description and
    threshold reasons -> one literal line each in report.md: the same headings, the same table
    rows, no raw '<' outside the JSON block."""
    text = builtin_scene_path(SCENE).read_text()
    name = " ".join(HOSTILE)
    for key, value in (("name", name), ("description", HOSTILE[1])):
        line = f"{key} = {json.dumps(value)}"  # a TOML basic string: JSON's escapes are TOML's
        text = re.sub(rf'(?m)^{key} = ".*"$', lambda _m, line=line: line, text, count=1)
    reasons = {
        "attitude": HOSTILE[0],
        "position_C": HOSTILE[1],
        "angular_velocity": HOSTILE[2] + " " + HOSTILE[3],
    }
    table = "\n".join(
        f"{k} = {{ value = 1, reason = {json.dumps(r)} }}" for k, r in reasons.items()
    )
    scene = tmp_path / "s.toml"
    scene.write_text(f"{text}\n[thresholds]\n{table}\n")
    V.run_validation(scene, tmp_path / "v", t_end=T_END, concurrent=False)
    md = (tmp_path / "v" / "report.md").read_text()
    body, fenced = md.split("```json\n", 1)
    fenced, tail = fenced.split("\n```\n", 1)
    assert tail.strip() == ""  # the JSON block ends where the report ends it
    json.loads(fenced)  # and is still the JSON of the run
    headings = [x for x in body.splitlines() if x.startswith("#")]
    assert headings[0].endswith(": PASSED") and len(headings[0].split(": PASSED")) == 2
    assert [h for h in headings[1:] if not h.startswith("## ")] == []
    assert [h[3:] for h in headings[1:]] == [
        "Referee",
        "Checks",
        "Summaries over time",
        "Figures",
        "Thresholds",
        "Run",
    ]
    assert "<" not in body
    thresholds = body.split("## Thresholds\n\n", 1)[1].split("\n\n", 1)[0].splitlines()
    doc = json.loads((tmp_path / "v" / "report.json").read_text())
    assert len(thresholds) == 2 + len(doc["thresholds"])  # header, rule, one row each
    for row in thresholds:
        assert len(re.findall(r"(?<!\\)\|", row)) == 6  # five cells: no pipe from a reason
    assert doc["thresholds"]["attitude"]["reason"].startswith(HOSTILE[0])  # kept verbatim there


@pytest.mark.parametrize("placeholder", ["unknown", "nan", "None", "<an image>"])
def test_scene_text_that_reads_like_a_placeholder_is_written_as_it_is(tmp_path, placeholder):
    """A scene whose description or threshold reason reads "unknown", "nan" or "<...>" (words the
    JSON writers refuse from the code itself) -> the run completes and report.json carries the
    text verbatim."""
    text = builtin_scene_path(SCENE).read_text()
    line = f"description = {json.dumps(placeholder)}"
    text = re.sub(r'(?m)^description = ".*"$', lambda _m: line, text, count=1)
    scene = tmp_path / "s.toml"
    scene.write_text(f'{text}\n[thresholds]\nattitude = {{ value = 1, reason = "{placeholder}" }}\n')
    res = V.run_validation(scene, tmp_path / "v", t_end=T_END, concurrent=False)
    assert res.passed
    doc = json.loads((tmp_path / "v" / "report.json").read_text())
    assert doc["provenance"]["scene"]["scene"]["description"] == placeholder
    assert doc["thresholds"]["attitude"]["reason"].startswith(f"{placeholder} (default")


def test_a_file_missing_after_the_commit_gives_no_verdict(previous):
    """A file the result names missing, or not the size its manifest records, after the commit
    -> OutputError (the command says it in one line and exits 1), never PASS."""
    files = {p.name: p for p in previous.iterdir()}  # a committed run, as its result names it
    V._check_committed(previous, files)  # whole: no complaint
    rrd = files.pop("run.rrd")
    rrd.unlink()
    with pytest.raises(OutputError, match="missing after the commit"):
        V._check_committed(previous, {**files, "run.rrd": rrd})
    size = files["report.md"].stat().st_size
    files["report.md"].write_text("# x: PASSED, and more\n")
    with pytest.raises(OutputError, match=f"the manifest says {size}"):
        V._check_committed(previous, files)


def test_report_md_escaping_keeps_one_literal_line():
    """Every Markdown or HTML special in a scene string -> escaped on one line (a unit check of
    the escaping the report uses)."""
    from validation.report.report import _md

    for s in HOSTILE:
        out = _md(s)
        assert "\n" not in out and "<" not in out and not out.startswith("#")
        assert re.search(r"(?<!\\)[`|\[\]]", out) is None
    assert _md("1. first") == "1\\. first"
    assert _md("a_b c, 1e-7 m") == "a_b c, 1e-7 m"  # ordinary text stays as it is
