"""The machine-read files (``report.json``, ``sweep.json``, ``hard_cases.json``, ``bench.json``):
each, as the commands write it, validates against its JSON Schema (``validation/report/schemas``), carries
the provenance block, and holds strict JSON (no NaN tokens, no placeholder strings).

The schemas are checked with ``jsonschema`` (a test dependency, see pyproject.toml).
"""

from __future__ import annotations

import dataclasses
import json
import math
import subprocess
import sys
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
import pytest
from jsonschema import Draft202012Validator
from jsonschema.exceptions import ValidationError
from referencing import Registry, Resource

from analytic.effects import SolverMethod
from analytic.scene import load_scene, scene_from_dict
from analytic.scene.dump import scene_to_dict
from validation.report import provenance as pv
from validation.report.provenance import (
    FileKind,
    PlaceholderError,
    dumps,
    provenance,
    to_json_value,
)
from validation.scenes import SCENES_DIR, resolve_scene

ROOT = Path(__file__).resolve().parents[3]
SCHEMAS = sorted(pv.SCHEMA_DIR.glob("*.schema.json"))


def _registry() -> Registry:
    resources = []
    for p in SCHEMAS:
        doc = json.loads(p.read_text(encoding="utf-8"))
        resources.append((doc["$id"], Resource.from_contents(doc)))
    return Registry().with_resources(resources)


def validator(kind: FileKind | str) -> Draft202012Validator:
    schema = json.loads(pv.schema_path(kind).read_text(encoding="utf-8"))
    return Draft202012Validator(schema, registry=_registry())


def strict_load(path: Path):
    """JSON as the standard defines it: a NaN or Infinity token is an error here."""

    def refuse(token: str):
        raise AssertionError(f"{path.name}: non-standard JSON token {token}")

    return json.loads(path.read_text(encoding="utf-8"), parse_constant=refuse)


def check_file(path: Path, kind: FileKind) -> dict:
    doc = strict_load(path)
    validator(kind).validate(doc)
    return doc


def needs_block(path: Path, writer: str) -> None:
    """Skip (naming the writer) while a file's writer does not include the provenance block yet."""
    doc = json.loads(path.read_text(encoding="utf-8"))
    if "provenance" not in doc:
        pytest.skip(
            f"{path.name} has no provenance block yet: {writer} does not write it through "
            "validation.report.provenance (see docs/json-output.md, 'Writing a file')"
        )


# ------------------------------------------------------------------------------------------------
# The schemas themselves
# ------------------------------------------------------------------------------------------------


def test_every_file_kind_has_a_valid_schema():
    assert {p.name for p in SCHEMAS} == {f"{k.value}.schema.json" for k in FileKind} | {
        "provenance.schema.json"
    }
    for p in SCHEMAS:
        doc = json.loads(p.read_text(encoding="utf-8"))
        Draft202012Validator.check_schema(doc)
        assert doc["$schema"] == "https://json-schema.org/draft/2020-12/schema"


@pytest.mark.parametrize("kind", list(FileKind))
def test_schema_pins_the_kind_and_its_version(kind):
    schema = json.loads(pv.schema_path(kind).read_text(encoding="utf-8"))
    block = schema["properties"]["provenance"]
    assert block["$ref"] == "urn:tumbling-testbed:schema:provenance"
    assert block["properties"]["kind"] == {"const": kind.value}
    assert block["properties"]["schema_version"] == {"const": pv.SCHEMA_VERSIONS[kind]}
    assert "provenance" in schema["required"]


def test_every_field_of_every_schema_is_documented():
    """docs/json-output.md names every top-level field of every file and every provenance field."""
    doc = (ROOT / "docs" / "json-output.md").read_text(encoding="utf-8")
    for p in SCHEMAS:
        schema = json.loads(p.read_text(encoding="utf-8"))
        for name in schema.get("properties", {}):
            assert f"`{name}`" in doc, (p.name, name)


# ------------------------------------------------------------------------------------------------
# The provenance block
# ------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def scene():
    return resolve_scene("paper_example1_controlled")


def test_block_fields(scene):
    before = datetime.now(UTC)
    block = provenance(FileKind.SWEEP, scene, argv=["tumble", "sweep", "--quick"])
    after = datetime.now(UTC)
    reg = _registry()
    schema = reg.contents("urn:tumbling-testbed:schema:provenance")
    Draft202012Validator(schema, registry=reg).validate(json.loads(dumps(block)))
    assert block["kind"] == "sweep" and block["schema_version"] == pv.SCHEMA_VERSIONS["sweep"]
    assert block["command"] == ["tumble", "sweep", "--quick"]
    made = datetime.fromisoformat(block["created_utc"])
    assert made.utcoffset().total_seconds() == 0 and before <= made <= after
    assert set(block["versions"]) == {"numba", "mujoco", "numpy", "scipy", "rerun-sdk", "pin"}
    assert block["versions"]["numpy"] == np.__version__  # read from metadata, not imported
    assert provenance("bench")["command"] == sys.argv
    with pytest.raises(ValueError, match="kind: unknown file kind 'nope'"):
        provenance("nope")


def test_git_commit_is_the_checkout_or_none(tmp_path):
    """The commit of this checkout when it is one; None anywhere else (never raises)."""
    inside = subprocess.run(
        ["git", "-C", str(ROOT), "rev-parse", "--show-toplevel", "HEAD"],
        capture_output=True,
        text=True,
        check=False,
    )
    lines = inside.stdout.split()
    if inside.returncode == 0 and Path(lines[0]).resolve() == ROOT:
        assert pv.git_commit() == lines[1]
    else:
        assert pv.git_commit() is None
    assert pv.git_commit(tmp_path) is None  # not a repository
    assert pv.git_commit(ROOT / "validation") is None  # inside one, but not its top level
    assert pv.git_commit(tmp_path / "missing") is None


def test_library_versions_none_when_not_installed():
    assert pv.library_versions(("numpy", "no-such-distribution-xyz")) == {
        "numpy": np.__version__,
        "no-such-distribution-xyz": None,
    }


def test_scene_dump_fills_every_default(tmp_path):
    """A scene file without [solver], [output] or [mujoco] tables: the dump has the defaults the
    loader used, the attitude as a unit quaternion, the masses' inertia as matrices, in the scene
    file's own tables (tests/analytic/scene/test_dump.py: it loads back to the same scene)."""
    text = (SCENES_DIR / "paper_example1.toml").read_text(encoding="utf-8")
    kept, skip = [], False
    for line in text.splitlines():
        if line.startswith("["):
            skip = line.strip() in ("[solver]", "[output]", "[mujoco]")
        if not skip:
            kept.append(line)
    path = tmp_path / "bare.toml"
    path.write_text("\n".join(kept) + "\n", encoding="utf-8")
    sc = load_scene(path)
    d = scene_to_dict(sc)
    assert d["solver"]["method"] == SolverMethod.DOP853.value == sc.solver.method.value
    assert "max_step" not in d["solver"]  # no limit: absent, as in a scene file
    assert d["output"] == {"t_end": sc.output.t_end, "rate": sc.output.rate}
    assert d["mujoco"]["integrator"] == sc.mujoco.integrator.value
    u = d["initial"]["attitude"]["quaternion"]
    assert math.isclose(float(np.linalg.norm(u)), 1.0, rel_tol=1e-12)
    np.testing.assert_array_equal(d["masses"]["inertia_body"], sc.masses.inertia)
    assert d["scene"]["effects"] == sorted(e.value for e in sc.effects)
    written = json.loads(dumps(d))
    assert written == json.loads(dumps(scene_to_dict(scene_from_dict(written))))
    with pytest.raises(TypeError, match="scene: expected"):
        scene_to_dict({"name": "x"})


# ------------------------------------------------------------------------------------------------
# The encoder
# ------------------------------------------------------------------------------------------------


def test_encoder_turns_non_finite_and_numpy_into_json():
    doc = {
        "nan": math.nan,
        "inf": -math.inf,
        "np": np.float64(2.5),
        "npnan": np.float32("nan"),
        "i": np.int64(3),
        "b": np.bool_(True),
        "arr": np.array([[1.0, np.inf], [0.5, 2.0]]),
        "t": (1, 2),
        "enum": SolverMethod.RK45,
        "path": Path("a/b"),
        "verdict": "N/A",
    }
    text = dumps(doc)
    back = json.loads(text, parse_constant=lambda c: pytest.fail(f"token {c}"))
    assert back == {
        "nan": None,
        "inf": None,
        "np": 2.5,
        "npnan": None,
        "i": 3,
        "b": True,
        "arr": [[1.0, None], [0.5, 2.0]],
        "t": [1, 2],
        "enum": "RK45",
        "path": "a/b",
        "verdict": "N/A",
    }
    assert type(back["i"]) is int and type(back["b"]) is bool


@pytest.mark.parametrize("placeholder", ["nan", "inf", "-inf", "NaN", "None", "<2001 values>"])
def test_encoder_refuses_placeholder_strings(placeholder):
    with pytest.raises(PlaceholderError, match=r"\$\.run\.t_max"):
        to_json_value({"run": {"t_max": placeholder}})


def test_an_enum_value_that_reads_like_a_placeholder_is_data():
    """A scene without a picture of BR has ``shape.kind = "none"``: a declared enum value, written
    as it is (its report once failed to write); the bare string is still refused."""
    from analytic.effects import ShapeKind
    from analytic.scene import load_scene

    assert to_json_value({"kind": ShapeKind.NONE}) == {"kind": "none"}
    with pytest.raises(PlaceholderError):
        to_json_value({"kind": "none"})
    sc = load_scene(ROOT / "validation" / "scenes" / "hard" / "many_masses.toml")
    assert sc.body.shape.kind is ShapeKind.NONE
    doc = json.loads(dumps({"provenance": provenance(FileKind.REPORT, sc)}))
    assert doc["provenance"]["scene"]["body"]["shape"]["kind"] == "none"


def test_encoder_refuses_unknown_objects():
    @dataclasses.dataclass
    class Thing:
        x: float = 1.0

    with pytest.raises(PlaceholderError, match=r"\$\.rows\[1\]: a value of type Thing"):
        dumps({"rows": [1, Thing()]})


def test_schema_refuses_a_placeholder_and_a_missing_block():
    doc = {
        "provenance": json.loads(dumps(provenance(FileKind.BENCH))),
        "machine": {"cpus": 2, "load_average_1min": {"before": 0.1, "after": 1.9}},
        "spread_bound": 0.2,
        "evaluation_us": [{"n": 2, "numpy_us": 10.0, "compiled_us": 1.0, "mj_forward_us": None}],
        "goals": [],
    }
    v = validator(FileKind.BENCH)
    v.validate(doc)
    bad = json.loads(json.dumps(doc))
    bad["evaluation_us"][0]["mj_forward_us"] = "nan"
    with pytest.raises(ValidationError):
        v.validate(bad)
    with pytest.raises(ValidationError):
        v.validate({k: v for k, v in doc.items() if k != "provenance"})
    wrong = json.loads(json.dumps(doc))
    wrong["provenance"]["kind"] = "report"
    with pytest.raises(ValidationError):
        v.validate(wrong)


# ------------------------------------------------------------------------------------------------
# The files the commands write
# ------------------------------------------------------------------------------------------------


@pytest.fixture
def quick_bench(monkeypatch):
    """bench's measurements replaced by fixed numbers (the file's form is under test, not the
    speeds; tumble bench itself takes minutes)."""
    from validation.bench import command as bench
    from validation.bench import goals
    from validation.bench.goal import Goal
    from validation.bench.verdicts import Spread

    done = Goal("a measured goal", 0.5, 1.0, "detail", data={"runs_s": [0.1, 0.2]})
    busy = Goal("a busy goal", 0.6, 1.0, "", spread=Spread(0.2, 0.6, 1.1, 21, 0.4))
    skipped = Goal("a skipped goal", math.nan, 3.0, "", skipped="pin is not installed")
    monkeypatch.setattr(goals, "measure", lambda skip_long, progress: [done, busy, skipped])
    rows = [{"n": 2, "numpy_us": 20.0, "compiled_us": 0.6, "mj_forward_us": math.nan}]
    monkeypatch.setattr(bench, "evaluation_table", lambda: rows)


def test_tumble_bench_out_writes_a_valid_bench_json(tmp_path, quick_bench, capsys):
    from validation.cli import main

    assert main(["bench", "--skip-long", "--out", str(tmp_path / "b")]) == 0
    doc = check_file(tmp_path / "b" / "bench.json", FileKind.BENCH)
    assert doc["provenance"]["command"] == sys.argv
    assert doc["evaluation_us"][0]["mj_forward_us"] is None  # NaN written as null
    assert [g["verdict"] for g in doc["goals"]] == ["HOLDS", "TOO_BUSY", "SKIPPED"]
    assert doc["goals"][1]["spread"]["high"] == 1.1 and doc["goals"][0]["spread"] is None
    assert doc["machine"]["cpus"] >= 1 and doc["spread_bound"] > 0
    assert (tmp_path / "b" / "manifest.json").exists()
    out = capsys.readouterr().out
    assert "HOLDS  a measured goal" in out and f"written: {tmp_path / 'b' / 'bench.json'}" in out


def test_bench_module_out_is_the_same_option(tmp_path, quick_bench, capsys):
    """``python -m validation.bench.command --out DIR`` writes what ``tumble bench --out DIR`` writes; the
    old ``--json FILE`` still writes FILE, with a one-line deprecation warning."""
    from validation.bench import command as bench

    assert bench.main(["--skip-long", "--out", str(tmp_path / "m")]) == 0
    check_file(tmp_path / "m" / "bench.json", FileKind.BENCH)
    capsys.readouterr()
    assert bench.main(["--skip-long", "--json", str(tmp_path / "old.json")]) == 0
    check_file(tmp_path / "old.json", FileKind.BENCH)
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--json FILE is deprecated; use --out DIR" in err[0]


def test_report_json_validates(tmp_path):
    from validation.validate import run_validation

    res = run_validation("paper_example1_controlled", tmp_path / "v", t_end=0.2)
    path = res.out_dir / "report.json"
    needs_block(path, "validation/report/report.py (write_report)")
    doc = check_file(path, FileKind.REPORT)
    assert doc["provenance"]["scene"]["scene"]["name"] == "paper_example1_controlled"


def test_sweep_json_validates(tmp_path):
    from concurrent.futures import ThreadPoolExecutor

    from validation.studies import sweep

    cfg = dataclasses.replace(
        sweep.SweepConfig.quick(),
        t_end=0.2,
        solvers=("DOP853",),
        rtols=(1e-5, 1e-8),
        integrators=("RK4",),
        dts=(1e-2, 5e-3),
        deltas=((0.5, 8.0),),
        effects_repeats=1,
    )
    with ThreadPoolExecutor(max_workers=1) as ex:
        res = sweep.run_sweep("paper_example1_controlled", tmp_path / "s", executor=ex, config=cfg)
    path = res.files["json"]
    needs_block(path, "validation/sweep.py (run_sweep)")
    doc = check_file(path, FileKind.SWEEP)
    assert doc["provenance"]["scene"]["scene"]["name"] == "paper_example1_controlled"


def test_hard_cases_json_validates(tmp_path):
    from validation.studies.hard_cases import run_hard_cases

    run_hard_cases(tmp_path / "h", names=["pass_through"])
    path = tmp_path / "h" / "hard_cases.json"
    needs_block(path, "validation/hard_cases.py (write_table)")
    check_file(path, FileKind.HARD_CASES)


# ----------------------------------------------------------------------------------------------
# Which code ran: the build record, the checkout, the working directory's checkout
# ----------------------------------------------------------------------------------------------

HEX_A = "a" * 40
HEX_B = "b" * 40


def _git(cwd: Path, *args: str) -> str:
    done = subprocess.run(
        ["git", "-C", str(cwd), "-c", "user.email=t@example.org", "-c", "user.name=t", *args],
        capture_output=True,
        text=True,
        check=True,
    )
    return done.stdout.strip()


def _project_checkout(at: Path) -> str:
    """A minimal git repository that looks like a tumbling-testbed checkout; returns its HEAD."""
    (at / "validation").mkdir(parents=True)
    (at / "validation" / "provenance.py").write_text("# placeholder\n")
    (at / "pyproject.toml").write_text('[project]\nname = "tumbling-testbed"\n')
    _git(at, "init", "-q")
    _git(at, "add", "-A")
    _git(at, "commit", "-qm", "first")
    return _git(at, "rev-parse", "HEAD")


def test_build_node_and_commit_prefixes():
    """setuptools-scm's node is ``g`` + hex (abbreviated after a tag, full without one)."""
    assert pv.parse_build_node("g1a2b3c4") == "1a2b3c4"
    assert pv.parse_build_node("G" + HEX_A) is None  # not a node setuptools-scm writes
    assert pv.parse_build_node(HEX_A) == HEX_A
    assert pv.parse_build_node(None) is None
    assert pv.parse_build_node("gxyz") is None
    assert pv.same_commit("1a2b3c4", "1a2b3c4" + "0" * 33)
    assert not pv.same_commit("1a2b3c5", "1a2b3c4" + "0" * 33)
    assert not pv.same_commit(None, HEX_A)


def test_build_info_reads_the_build_record(monkeypatch):
    """The record the build writes (the template in pyproject.toml) is read back; none, None."""
    import types

    fake = types.ModuleType("validation._version")
    fake.version = "0.1.1.dev3+g" + HEX_A[:9]
    fake.build_node = "g" + HEX_A
    fake.build_dirty = True
    monkeypatch.setitem(sys.modules, "validation._version", fake)
    assert pv.build_info() == pv.BuildInfo(fake.version, HEX_A, True)
    monkeypatch.setitem(sys.modules, "validation._version", None)  # import fails
    assert pv.build_info() is None


def test_working_checkout_is_only_the_projects(tmp_path):
    """The working directory's checkout is recorded when it is tumbling-testbed's, not a user's
    project that uses the package."""
    head = _project_checkout(tmp_path / "ours")
    assert pv.working_checkout(tmp_path / "ours" / "validation") == (
        (tmp_path / "ours").resolve(),
        head,
    )
    other = tmp_path / "theirs"
    other.mkdir()
    (other / "pyproject.toml").write_text('[project]\nname = "someone-else"\n')
    _git(other, "init", "-q")
    _git(other, "add", "-A")
    _git(other, "commit", "-qm", "x")
    assert pv.working_checkout(other) is None
    assert pv.working_checkout(tmp_path) is None  # no repository at all


@pytest.mark.parametrize(
    ("here", "build", "work", "source", "commit", "differs"),
    [
        # an installed package, run outside any checkout: the build record names the code
        (None, pv.BuildInfo("v", HEX_A, False), None, "installed", HEX_A, False),
        # an installed package run inside a checkout at the commit it was built from
        (None, pv.BuildInfo("v", HEX_A[:9], False), HEX_A, "installed", HEX_A[:9], False),
        # ... inside a checkout that has moved on: both are reported
        (None, pv.BuildInfo("v", HEX_A, False), HEX_B, "installed", HEX_A, True),
        # the packages imported from a checkout: its HEAD, whatever a stale record says
        (HEX_B, pv.BuildInfo("v", HEX_A, False), HEX_B, "checkout", HEX_B, False),
        # an install without a record, outside a checkout: unknown, said as such
        (None, None, None, "unidentified", None, False),
    ],
)
def test_code_origin_names_the_code_that_ran(
    monkeypatch, here, build, work, source, commit, differs
):
    monkeypatch.setattr(pv, "build_info", lambda: build)
    monkeypatch.setattr(pv, "git_commit", lambda root=None, timeout=0: here)
    monkeypatch.setattr(pv, "is_dirty", lambda root, timeout=0: False)
    monkeypatch.setattr(pv, "working_checkout", lambda cwd=None, timeout=0: work and (ROOT, work))
    origin = pv.code_origin()
    assert (origin.source.value, origin.commit, origin.differs) == (source, commit, differs)
    block = provenance("bench", origin=origin)
    assert block["git_commit"] == commit and block["code_source"] == source
    assert block["build_commit"] == (build.commit if build else None)
    assert block["working_checkout_commit"] == work
    reg = _registry()
    schema = reg.contents("urn:tumbling-testbed:schema:provenance")
    Draft202012Validator(schema, registry=reg).validate(json.loads(dumps(block)))
    words = origin.sentence()
    assert (commit or "unknown") in words
    assert ("another commit" in words) == differs
    if differs:
        assert work in words


@pytest.mark.slow
def test_installed_package_knows_its_commit(tmp_path):
    """Built and installed as the README says (``pip install .``, not editable, from a git
    checkout) into a fresh venv: the provenance names the commit built from, outside the checkout
    and inside it, and both commits once the checkout has moved on."""
    src = tmp_path / "src"
    files = subprocess.run(
        ["git", "-C", str(ROOT), "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
        capture_output=True,
        check=True,
    ).stdout.split(b"\0")
    for name in filter(None, (f.decode() for f in files)):
        if (ROOT / name).is_file():
            (src / name).parent.mkdir(parents=True, exist_ok=True)
            (src / name).write_bytes((ROOT / name).read_bytes())
    _git(src, "init", "-q")
    _git(src, "add", "-A")
    _git(src, "commit", "-qm", "snapshot")
    built = _git(src, "rev-parse", "HEAD")
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    py = venv / "bin" / "python"
    done = subprocess.run(
        [sys.executable, "-m", "pip", "--python", str(py), "install", "-q", "--no-deps", str(src)],
        capture_output=True,
        text=True,
        check=False,
    )
    if done.returncode != 0 and "No matching distribution" in done.stdout + done.stderr:
        pytest.skip(f"the build backend could not be fetched: {done.stderr[-300:]}")
    assert done.returncode == 0, done.stderr
    probe = (
        "import json; from validation.report.provenance import provenance; "
        "b = provenance('bench'); print(json.dumps({k: b[k] for k in "
        "('project_version', 'git_commit', 'code_source', 'build_commit', "
        "'working_checkout_commit')}))"
    )

    def block(cwd: Path) -> dict:
        out = subprocess.run(
            [str(py), "-I", "-c", probe], cwd=cwd, capture_output=True, text=True, check=True
        )
        return json.loads(out.stdout)

    outside = block(tmp_path)
    assert outside["git_commit"] == built and outside["build_commit"] == built
    assert outside["code_source"] == "installed" and outside["working_checkout_commit"] is None
    node = outside["project_version"].partition("+g")[2]  # 0.1.1.dev1+g<abbreviated commit>
    assert len(node) >= 7 and built.startswith(node)
    assert block(src)["working_checkout_commit"] == built
    (src / "moved.txt").write_text("the checkout moves on\n")
    _git(src, "add", "moved.txt")
    _git(src, "commit", "-qm", "moved on")
    moved = block(src)
    assert moved["git_commit"] == built
    assert moved["working_checkout_commit"] == _git(src, "rev-parse", "HEAD") != built
