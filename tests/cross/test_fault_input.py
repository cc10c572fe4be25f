"""Faults in the input: what the tool does with hostile scene files and options.

Each test is one row of the table: a hostile input, and what the tool does with it. A hostile
input is refused before any work, by a ``ValueError`` naming the field (and the file or line where
that helps) and the value; the command line prints one line ``tumble: error: ...`` (or
``tumble <command>: error: ...`` for an option) and exits 2. A plant that runs out of memory says
so in one line. Nothing here runs a plant: every refusal comes before one would start.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

from analytic.scene import MAX_SCENE_NESTING, load_scene, scene_from_dict
from analytic.scene import reading as scene_reading
from analytic.scene.random_scenes import chain_scene
from analytic.trajectory import Engine
from tests.support.guards import forbid_plant_runs
from validation.cli import EXIT_FAILED, EXIT_USAGE, main

pytestmark = pytest.mark.faults

SCENE = Path(__file__).resolve().parents[2] / "analytic" / "scenes" / "paper_example1_controlled.toml"


def _scene_text(replace=(), append="", prepend="") -> str:
    text = SCENE.read_text(encoding="utf-8")
    for old, new in replace:
        assert old in text, old
        text = text.replace(old, new, 1)
    return prepend + text + append


def _write(tmp_path, text: str) -> Path:
    path = tmp_path / "s.toml"
    path.write_text(text, encoding="utf-8")
    return path




def _validate_refuses(tmp_path, monkeypatch, capsys, path, *args) -> str:
    """``tumble validate`` on ``path``: exit 2, one stderr line (returned), no plant, no output."""
    forbid_plant_runs(monkeypatch)
    out = tmp_path / "out"
    rc = main(["validate", str(path), "--out", str(out), *args])
    err = capsys.readouterr().err.splitlines()
    assert rc == EXIT_USAGE, err
    assert len(err) == 1 and err[0].startswith("tumble: error: "), err
    assert "Traceback" not in err[0]
    assert not out.exists()
    return err[0]


# ------------------------------------------------------------------------------------------------
# Nesting: refused before the recursive TOML parser (or any later walk) can overflow the stack
# ------------------------------------------------------------------------------------------------


def test_array_nested_3000_deep_is_one_line_naming_the_key(tmp_path, monkeypatch, capsys):
    """An array nested 3,000 levels deep -> exit 2, one line naming the key, its line and the file."""
    path = _write(tmp_path, _scene_text(append="\n[extra]\nx = " + "[" * 3000 + "]" * 3000 + "\n"))
    line = _validate_refuses(tmp_path, monkeypatch, capsys, path)
    assert line.startswith(f"tumble: error: extra.x: nested deeper than {MAX_SCENE_NESTING} levels")
    assert str(path) in line and "line " in line


def test_inline_tables_2000_deep_are_refused_naming_the_key(tmp_path):
    """Inline tables nested 2,000 deep -> ValueError naming the key and the file, no RecursionError."""
    path = _write(tmp_path, _scene_text(prepend="x = " + "{a = " * 2000 + "1" + "}" * 2000 + "\n"))
    with pytest.raises(ValueError, match=r"^x: nested deeper than") as exc:
        load_scene(path)
    assert str(path) in str(exc.value) and "\n" not in str(exc.value)


def test_dotted_keys_5000_deep_are_refused_naming_the_path(tmp_path):
    """A dotted key of 5,000 parts (deep tables without brackets) -> ValueError naming its path."""
    path = _write(tmp_path, _scene_text(prepend=".".join(["a"] * 5000) + " = 1\n"))
    tomllib.loads(path.read_text())  # the parser itself follows it: the loader's walk refuses it
    with pytest.raises(ValueError, match=r"^a\.a\.a.*: nested deeper than") as exc:
        load_scene(path)
    assert str(path) in str(exc.value)


def test_a_parser_recursion_error_becomes_a_value_error(tmp_path, monkeypatch):
    """The TOML parser's RecursionError (should the scan miss a case) -> ValueError naming the file."""
    path = _write(tmp_path, _scene_text())
    monkeypatch.setattr(scene_reading, "check_text_nesting", lambda text, given: None)

    def recursing(text):
        raise RecursionError("maximum recursion depth exceeded")

    monkeypatch.setattr(scene_reading.tomllib, "loads", recursing)
    with pytest.raises(ValueError, match=r"^scene: nested deeper than .*s\.toml"):
        load_scene(path)


def test_a_document_that_holds_itself_is_refused_not_walked_forever():
    """A dict that contains itself (given to the API) -> ValueError naming the path, no hang."""
    data: dict = {}
    data["scene"] = data
    with pytest.raises(ValueError, match=r"^scene\.scene.*: nested deeper than"):
        scene_from_dict(data)


def test_brackets_inside_strings_and_comments_are_not_nesting(tmp_path):
    """Brackets inside strings and comments -> not counted: the scene loads (the strings are
    refused only as what they are, here an unknown key)."""
    junk = '"""' + "[" * 100 + '"""'
    path = _write(
        tmp_path,
        _scene_text(append=f"\n# {'[' * 100}\n[thresholds]\nposition_C = {{ value = 1e-6, "
        f'reason = "{"{" * 100}" }}\n'),
    )
    assert load_scene(path).extra["thresholds"]["position_C"]["value"] == 1e-6
    path = _write(tmp_path, _scene_text(prepend=f"junk = {junk}\n"))
    with pytest.raises(ValueError, match=r"^junk: unknown key"):
        load_scene(path)


# ------------------------------------------------------------------------------------------------
# Overflow: every field finite, a quantity derived from them not -> refused at load, field named
# ------------------------------------------------------------------------------------------------


def test_huge_initial_omega_is_refused_at_load_naming_the_field(tmp_path, monkeypatch, capsys):
    """initial.omega = [1e308, 1e308, 1e308] -> exit 2 before any plant, one line naming the field
    and the value (not scipy's "y0 must be finite" after the plants ran)."""
    path = _write(
        tmp_path,
        _scene_text(
            replace=[("omega = [1.0, -1.0, 0.5]", "omega = [1e308, 1e308, 1e308]")],
        ),
    )
    line = _validate_refuses(tmp_path, monkeypatch, capsys, path)
    assert line.startswith("tumble: error: initial.omega: makes the initial")
    assert "overflow" in line and "1e+308" in line


@pytest.mark.parametrize(
    ("replace", "field"),
    [
        (("omega = [1.0, -1.0, 0.5]", "omega = [1e160, 0.0, 0.0]"), "initial.omega"),  # J ω²
        (("Rdot = [1.0, 2.0, 20.0]", "Rdot = [1e200, 2.0, 20.0]"), "initial.Rdot"),  # m v²
        (("p = [5.0, 11.0]", "p = [5.0, 1e100]"), "initial.p"),  # k^n x⁴
        (("gamma = 0.6", "gamma = 1e308"), "control.omega.gamma"),  # γ (ω - b)
        (("lambda = [6.283185307179586", "lambda = [1e200"), "control.masses.lambda"),  # l λ²
        (("[0.0, 0.0, -9.81]", "[0.0, 0.0, -1e305]"), "gravity.vector"),  # m_T g
        (("beta = [12.0, 12.0]", "beta = [12.0, 1.7e308]"), "control.masses.beta"),  # β e
    ],
)
def test_a_finite_field_whose_derived_quantity_overflows_is_named(replace, field):
    """A finite field that makes an initial energy, force, acceleration or requirement overflow ->
    ValueError at load naming that field."""
    text = _scene_text(replace=[replace])
    with pytest.raises(ValueError) as exc:
        scene_from_dict(tomllib.loads(text))
    msg = str(exc.value)
    assert msg.startswith(f"{field}: makes the initial ") and "overflow" in msg, msg
    assert "\n" not in msg


def test_switching_on_an_effect_checks_the_derived_quantities_again():
    """An effect switched on later (Scene.with_effects) whose data overflows -> ValueError too."""
    text = _scene_text(replace=[("[0.0, 0.0, -9.81]", "[0.0, 0.0, -1e305]")])
    data = tomllib.loads(text)
    data["scene"]["effects"] = [e for e in data["scene"]["effects"] if e != "gravity"]
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # [gravity] given while the effect is off
        sc = scene_from_dict(data)
    from analytic.effects import Effect

    with pytest.raises(ValueError, match=r"^gravity\.vector: makes the initial"):
        sc.with_effects(sc.effects | {Effect.GRAVITY})


# ------------------------------------------------------------------------------------------------
# Size: a scene the Pinocchio plant cannot hold, and a plant out of memory
# ------------------------------------------------------------------------------------------------


def test_pinocchio_refuses_more_masses_than_it_holds_up_front():
    """More masses than Pinocchio's data can hold (n³ memory) -> ValueError naming masses.mass, the
    value and the limit, before Pinocchio allocates; the other plants accept the scene."""
    from mj_bridge.plants import PINOCCHIO_MAX_MASSES, plant, plants_for_scene

    sc = chain_scene(PINOCCHIO_MAX_MASSES + 1)
    with pytest.raises(ValueError) as exc:
        plant(Engine.PINOCCHIO).check_scene(sc)
    msg = str(exc.value)
    assert msg.startswith(f"masses.mass: the pinocchio plant holds at most {PINOCCHIO_MAX_MASSES}")
    assert f"(got {PINOCCHIO_MAX_MASSES + 1} masses)" in msg and "n³" in msg
    for e in (Engine.ANALYTIC, Engine.MUJOCO):
        plant(e).check_scene(sc)
    everything = (Engine.ANALYTIC, Engine.MUJOCO, Engine.PINOCCHIO)
    assert plants_for_scene(sc, everything) == (Engine.ANALYTIC, Engine.MUJOCO)
    pytest.importorskip("pinocchio")
    from mj_bridge.pinocchio_plant import PinocchioDynamics

    with pytest.raises(ValueError, match=r"^masses\.mass: the pinocchio plant holds at most"):
        PinocchioDynamics(sc)


def test_default_plants_leave_out_a_plant_that_cannot_run_the_scene(monkeypatch):
    """A scene beyond Pinocchio's size with the default plants -> the others run, one warning and
    the report's referee note say why Pinocchio is left out."""
    from mj_bridge.plants import PINOCCHIO_MAX_MASSES, PinocchioPlant
    from validation.preflight import validation_plants
    from validation.validate import _referee_note

    monkeypatch.setattr(PinocchioPlant, "unavailable", classmethod(lambda cls: ""))  # installed
    sc = chain_scene(PINOCCHIO_MAX_MASSES + 1)
    with pytest.warns(UserWarning, match=r"^pinocchio plant left out: masses\.mass: "):
        chosen = validation_plants(None, sc)
    assert chosen == (Engine.ANALYTIC, Engine.MUJOCO)
    assert _referee_note(sc).startswith("the referee (Pinocchio) cannot run this scene: masses.mass")


def test_a_plant_out_of_memory_says_so_in_one_line(monkeypatch):
    """A MemoryError without a message inside a plant -> MemoryError "out of memory (plant, n)"."""
    from mj_bridge.plants import plant

    pl = plant(Engine.MUJOCO)

    def no_memory(*a, **k):
        raise MemoryError()

    monkeypatch.setattr(type(pl), "_simulate", no_memory)
    sc = load_scene(SCENE)
    with pytest.raises(MemoryError) as exc:
        pl.simulate(sc, t_end=0.2)
    assert str(exc.value) == f"out of memory (MuJoCo with {sc.n} masses)"


def test_out_of_memory_on_the_command_line_is_one_line(monkeypatch, capsys):
    """A MemoryError without a message reaching the command line -> "tumble: error: out of memory",
    exit 1, no traceback."""
    import validation.commands.export_mjcf as cli

    def no_memory(args):
        raise MemoryError()

    monkeypatch.setattr(cli, "run", no_memory)
    rc = main(["export-mjcf", "paper_example1"])
    err = capsys.readouterr().err.splitlines()
    assert rc == EXIT_FAILED and err == ["tumble: error: out of memory"]


# ------------------------------------------------------------------------------------------------
# Options: argparse's refusals are one line, like every other bad input
# ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("argv", "line"),
    [
        (["validate", "--dt", "0"], "tumble validate: error: --dt: must be a positive finite number (got '0')"),
        (["validate", "--dt", "-1"], "tumble validate: error: --dt: must be a positive finite number (got '-1')"),
        (["validate", "--t-end", "nan"], "tumble validate: error: --t-end: must be a positive finite number (got 'nan')"),
        (["validate", "--t-end", "inf"], "tumble validate: error: --t-end: must be a positive finite number (got 'inf')"),
        (["validate", "--dt", "x"], "tumble validate: error: --dt: must be a number (got 'x')"),
        (["validate", "--integrator", "foo"], "tumble validate: error: --integrator: invalid choice: 'foo'"),
        (["validate", "--dt"], "tumble validate: error: --dt: expected one argument"),
        (["simulate", "--rtol", "0"], "tumble simulate: error: --rtol: must be a positive finite number (got '0')"),
        (["simulate", "--atol", "-1"], "tumble simulate: error: --atol: must be a positive finite number (got '-1')"),
        (["simulate", "--method", "foo"], "tumble simulate: error: --method: invalid choice: 'foo'"),
        (["simulate", "--backend", "foo"], "tumble simulate: error: --backend: invalid choice: 'foo'"),
        (["sweep", "--t-end", "-1"], "tumble sweep: error: --t-end: must be a positive finite number (got '-1')"),
        (["validate", "--no-such-option"], "tumble: error: unrecognized arguments: --no-such-option"),
        (["no-such-command"], "tumble: error: COMMAND: invalid choice: 'no-such-command'"),
        ([], "tumble: error: the following arguments are required: COMMAND"),
    ],
)  # fmt: skip
def test_a_bad_option_is_one_line_and_exit_2(argv, line, monkeypatch, capsys):
    """A bad option value (zero, negative, NaN, an unknown choice, a missing value) -> one line
    ``tumble <command>: error: --option: ... (got ...)``, exit 2, no usage block."""
    forbid_plant_runs(monkeypatch)
    with pytest.raises(SystemExit) as exc:
        main(argv)
    captured = capsys.readouterr()
    err = captured.err.splitlines()
    assert exc.value.code == EXIT_USAGE
    assert len(err) == 1 and err[0].startswith(line), err
    assert "usage:" not in captured.err and captured.out == ""


def test_help_is_unchanged(capsys):
    """``--help`` -> the usage and every option on stdout, exit 0 (not shortened to one line)."""
    with pytest.raises(SystemExit) as exc:
        main(["validate", "--help"])
    out = capsys.readouterr().out
    assert exc.value.code == 0
    assert out.startswith("usage: tumble validate") and "--dt DT" in out and "--t-end" in out
