"""The scene format's reference, rendered from the loader's own declarations.

``python -m validation scene-reference > docs/scene-format.md`` (or ``--out FILE``) writes it. Every
key, type, unit, default and meaning comes from :data:`analytic.scene.schema.KEYS` (which the loader
reads its keys through), the thresholds from :data:`validation.compare.thresholds.DEFAULTS`, the limits
from the constants of :mod:`analytic.scene` (its ``limits`` and ``twin``), the built-in scenes from their files; this module adds
only the prose that ties them together. ``tests/validation/report/test_scene_reference.py`` checks that the committed
``docs/scene-format.md`` is what this renders now.

Layered here, not in ``analytic``, because the ``[thresholds]`` names belong to the comparison.
"""

from __future__ import annotations

import os
import tomllib
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from analytic import scene as S
from analytic.scene.builtin import BUILTIN_DIR, builtin_scene_names
from analytic.scene.schema import CHOICE_MEANINGS, KEYS, NO_DEFAULT, Key, Kind, Need
from validation.compare.thresholds import DEFAULTS, HARD_CASE_PREFIX, SCALED
from validation.report import scene_schema

GENERATOR = "python -m validation scene-reference > docs/scene-format.md"

MINIMAL_SCENE = """\
# A 100 kg body spinning at 0.5 rad/s about its z axis, one 5 kg mass on a spring to each end
# of a rod along x that passes 0.1 m from C. Every key not given takes its default (here: the
# attitude is the identity, body axes along XYZ; no gravity effect; DOP853, MuJoCo RK4).
[scene]
name = "my_body"
effects = ["springs.linear"]

[body]
mass = 100.0                     # kg
inertia = [10.0, 12.0, 15.0]     # kg m^2, principal moments about C

[rod]
axis = [1.0, 0.0, 0.0]           # a, body axes
offset = [0.0, 0.0, 0.1]         # d = C -> O', m, body axes

[masses]
mass = [5.0]                     # kg
p_e = [0.5]                      # m from O' along a: where both springs are at rest

[springs]
k_linear = [200.0, 200.0]        # N/m: near wall - m1 - far wall

[initial]
omega = [0.0, 0.0, 0.5]          # rad/s, body axes
p = [0.6]                        # m: 0.1 m off its rest position

[output]
t_end = 2.0                      # s
"""


LIMIT_NAMES = (
    "AXIS_NORMALISE_TOL",
    "AXIS_REFUSE_TOL",
    "MAX_INERTIA",
    "MAX_MASS",
    "MAX_MASSES",
    "MAX_MUJOCO_STEPS",
    "MAX_OUTPUT_SAMPLES",
    "MAX_SCENE_BYTES",
    "MJ_MINVAL",
    "POINT_INERTIA_MIN",
    "POINT_INERTIA_REL",
    "QUAT_NORMALISE_TOL",
    "QUAT_REFUSE_TOL",
    "ROTATION_REFUSE_TOL",
)
"""The loader's bounds (constants of :mod:`analytic.scene`) that the reference quotes."""


def _num(x: float | int) -> str:
    """A bound as the reference prints it: ``1e-15``, ``1e30``, ``10,000``."""
    if isinstance(x, int):
        return f"{x:,}"
    return f"{x:g}".replace("e+", "e")


LIMITS = {name: _num(getattr(S, name)) for name in LIMIT_NAMES}


def _fill(text: str) -> str:
    """``text`` with each ``{NAME}`` replaced by the loader's constant of that name."""
    return text.format_map(LIMITS)


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return f'"{v}"'
    if isinstance(v, int | float):
        return f"{v:g}"
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"no TOML form for {v!r}")


def _default(k: Key) -> str:
    if k.default is not NO_DEFAULT:
        return f"`{_toml_value(k.default)}`"
    if k.default_text:
        return k.default_text
    return "—"


def _need(k: Key) -> str:
    if k.need is Need.CONDITIONAL:
        return _fill(k.when)
    return k.need.value


def _meaning(k: Key) -> str:
    text = _fill(k.meaning)
    if k.kind is Kind.CHOICE and k.choices is not None:
        text += " One of " + ", ".join(f'`"{c.value}"`' for c in k.choices) + " (below)."
    if k.bounds:
        text += f" Refused unless: {_fill(k.bounds)}."
    return text


def _key_table(keys: Iterable[Key]) -> list[str]:
    out = [
        "| key | type | unit | default | required | meaning |",
        "|---|---|---|---|---|---|",
    ]
    for k in keys:
        out.append(
            f"| `{k.key}` | {k.kind.value} | {k.unit or '—'} | {_cell(_default(k))} | "
            f"{_cell(_need(k))} | {_cell(_meaning(k))} |"
        )
    return out


def _choices(keys: Iterable[Key]) -> list[str]:
    out = []
    for k in keys:
        if k.kind is not Kind.CHOICE or k.choices is None:
            continue
        out.append(f"`{k.dotted}`:")
        out.append("")
        for c in k.choices:
            out.append(f'- `"{c.value}"`: {CHOICE_MEANINGS[c]}')
        out.append("")
    return out


def _tables() -> list[str]:
    out = []
    tables = [k for k in KEYS if k.kind is Kind.TABLE]
    for t in tables:
        keys = [k for k in KEYS if k.table == t.dotted]
        title = "[thresholds]" if t.dotted == "thresholds" else f"[{t.dotted}]"
        out.append(f"### `{title}`")
        out.append("")
        need = _need(t)
        absent = f" When absent: {t.default_text}." if t.default_text else ""
        out.append(f"*{need}.* {_fill(t.meaning)}{absent}")
        out.append("")
        plain = [k for k in keys if k.kind is not Kind.TABLE]
        if plain:
            out += _key_table(plain)
            out.append("")
        subs = [k for k in keys if k.kind is Kind.TABLE]
        if subs:
            out.append("Sub-tables: " + ", ".join(f"`[{k.dotted}]`" for k in subs) + ".")
            out.append("")
        out += _choices(plain)
        if t.dotted == "thresholds":
            out += _thresholds()
            sub = [k for k in KEYS if k.table == "thresholds.<name>"]
            out.append('An entry given as a table, `<name> = { value = …, reason = "…" }`:')
            out.append("")
            out += _key_table(sub)
            out.append("")
    return out


def _thresholds() -> list[str]:
    out = [
        "The names the comparison knows, with their defaults (`validation/compare/thresholds.py`). An "
        "absolute threshold bounds the maximum over time of a difference, in its unit; a relative "
        "one bounds that maximum divided by the reference signal's largest magnitude (at least "
        "its floor). An absolute threshold with an rtol bounds it by `value + rtol × scale`, "
        "scale the quantity's largest magnitude over the run across the compared plants (as "
        "scipy's `atol + rtol·|y|`; for C, its departure from the uniformly accelerated motion "
        "R(0) + Ṙ(0) t + ½ g t²); a scene may set the rtol of those names only. Entries "
        "starting with "
        f"`{HARD_CASE_PREFIX}` belong to the hard-case suite and are not checked here.",
        "",
        "| name | default | rtol | unit | kind | why this number |",
        "|---|---|---|---|---|---|",
    ]
    for name, t in DEFAULTS.items():
        kind = f"relative (floor {t.floor:g})" if t.relative else "absolute"
        rtol = f"`{t.rtol:g}`" if name in SCALED else "—"
        out.append(f"| `{name}` | `{t.value:g}` | {rtol} | {t.unit} | {kind} | {_cell(t.reason)} |")
    out.append("")
    return out


def _limits() -> list[str]:
    lines = [
        "Besides the bounds in the tables, the loader refuses what a plant could not hold or "
        "MuJoCo's compiler would refuse (constants of `analytic/scene/limits.py` and "
        "`analytic/scene/twin.py`, each with its reason there):",
        "",
        "- a scene file larger than {MAX_SCENE_BYTES} bytes, or not a regular file;",
        "- more than {MAX_MASSES} masses;",
        "- more than {MAX_OUTPUT_SAMPLES} output samples (`t_end · rate`);",
        "- more than {MAX_MUJOCO_STEPS} MuJoCo steps (`t_end / timestep`), or `t_end` shorter "
        "than one step;",
        "- a mass below MuJoCo's mjMINVAL = {MJ_MINVAL} kg or above {MAX_MASS} kg, a moment of "
        "inertia above {MAX_INERTIA} kg·m²;",
        "- principal moments that violate A + B ≥ C (BR's, each mass's), or that leave BR no room "
        "for the small inertia the MuJoCo twin lends each point mass "
        "(max({POINT_INERTIA_REL} · min J, {POINT_INERTIA_MIN}) kg·m²);",
        "- `rod.axis` off unit length by more than {AXIS_REFUSE_TOL}, a quaternion off by more "
        "than {QUAT_REFUSE_TOL} (without `allow_off_manifold`), a rotation matrix further than "
        "{ROTATION_REFUSE_TOL} from orthogonal;",
        "- an unknown table or key, first, before any other check: named, with the closest "
        "declared name at its level (`control.masses.lamda: unknown key (did you mean 'lambda'? "
        "known in [control.masses]: indices, l, lambda, alpha, beta) (got [6.28])`; a misspelt "
        "`[mass]` is named as such, not reported as the masses it leaves out);",
        "- a key given where it does not apply (`body.shape.box_center` without a box: `not used "
        "here`);",
        "- an effect listed without its data (`springs.k_cubic: required by effect "
        "springs.cubic`), a wrong type.",
        "",
        "It warns (one line each, and loads the scene) about:",
        "",
        "- data given for an effect that is not listed (`[external_torque]` without the effect "
        "`external_torque`): ignored;",
        "- a quaternion whose norm is off 1 by more than {QUAT_NORMALISE_TOL}: normalised;",
        "- a `rod.axis` whose norm is off 1 by more than {AXIS_NORMALISE_TOL} (a printed, rounded "
        "axis): normalised, the warning naming its norm (`rod.axis: norm 0.999971 normalised to "
        "1`);",
        "- a `masses.p_e` or `initial.p` beyond the drawn rod (`body.shape.rod_start`, "
        "`rod_length`): the drawing is a picture only, the masses slide on an unbounded line.",
        "",
    ]
    return [_fill(line) for line in lines]


DIRECTIVE_EXAMPLE = """\
#:schema ./scene.schema.json

[scene]
name = "my_body"
"""
"""The top of a scene file that names the schema written beside it (``docs/scene-format.md``)."""

TAPLO_CONFIG = """\
[[rule]]
include = ["scenes/**/*.toml"]

[rule.schema]
path = "./scene.schema.json"
"""
"""A ``.taplo.toml`` that gives every scene under ``scenes/`` the schema (Taplo, Even Better TOML)."""

TOMBI_CONFIG = """\
[[schemas]]
path = "./scene.schema.json"
include = ["scenes/**/*.toml"]
"""
"""A ``tombi.toml`` that gives every scene under ``scenes/`` the schema."""


def _indented(text: str) -> list[str]:
    """``text`` as a fenced block inside a list item (no language: not a scene)."""
    return ["   ```", *(f"   {line}" if line else "" for line in text.splitlines()), "   ```"]


def _editors() -> list[str]:
    """How editors pick up the scene format's JSON Schema, and what it leaves to the loader."""
    shipped = scene_schema.SHIPPED
    root = shipped.parents[2]
    relative = Path(os.path.relpath(shipped, BUILTIN_DIR)).as_posix()
    out = [
        f"`{shipped.relative_to(root).as_posix()}` is the scene format's JSON Schema, generated "
        "from the same declarations as this page (`tumble scene-reference --json-schema` prints "
        "it, `--out FILE` writes it; a test checks the shipped file is what the generator "
        "produces). It is **draft-07**, the draft both TOML language servers read: Taplo (and VS "
        "Code's Even Better TOML, which is Taplo) reads draft-04/06/07, Tombi draft-07 and "
        "2020-12. Each key has its type, its choices, its fixed length, its bounds, its meaning "
        "and its default, so an editor completes keys and values, shows the meaning on hover and "
        "marks an unknown key, a wrong type or a value out of range as you type.",
        "",
        "The built-in scenes and the hard cases name it in their first line (relative to the "
        f"file: `#:schema {relative}` in `analytic/scenes/`); the loader reads the line as the "
        "comment it is. For the scenes of your own project:",
        "",
        "1. write the schema of the version you have installed into the project: "
        "`tumble scene-reference --json-schema --out scene.schema.json`;",
        "2. either make `#:schema <path or URL>` the first line of each scene file, followed by a "
        "blank line (Tombi reads a directive only at the very top, set apart from what follows); "
        "a relative path is relative to the scene file:",
        "",
        *_indented(DIRECTIVE_EXAMPLE),
        "",
        "3. or give one rule for every scene in the editor's configuration at the project's root: "
        "Taplo's `.taplo.toml` (read by the `taplo` command and by Even Better TOML) and Tombi's "
        "`tombi.toml` (or `[tool.tombi]` in `pyproject.toml`); their `include` patterns are "
        "relative to the project's root:",
        "",
        *_indented(f"# .taplo.toml\n{TAPLO_CONFIG}\n# tombi.toml\n{TOMBI_CONFIG}"),
        "",
        "A directive in the file takes precedence over a configuration rule in both. The same "
        "schema checks the files in CI without an editor: `taplo check` or `tombi lint`.",
        "",
        "Every table the loader checks is closed (`additionalProperties: false`), so an unknown "
        "key is an error in the editor as it is at load; `[hard_case]` and `[mjx]` are open, as "
        "the loader keeps them verbatim for the layers that check them. `[thresholds]` lists the "
        "comparison's names (an unknown one is refused by every command that compares). A file "
        "the schema accepts can still be refused by the loader, which checks what a JSON Schema "
        "cannot express:",
        "",
    ]
    for clause, why in scene_schema.LOADER_ONLY.items():
        if why == scene_schema.WARNING_ONLY:
            continue
        keys = [k.dotted for k in KEYS if clause in scene_schema.bound_clauses(k)]
        out.append(f"- {', '.join(f'`{k}`' for k in keys)}: {clause}, {why};")
    out += [
        "- the keys required or allowed only in a case (the *required* column: `box_half_sizes` "
        "with a box, `angle` or `angle_deg`, `gamma` or `gain`, one of the inertia keys of "
        "`[masses]`, `[initial]` with masses): refused as missing or `not used here`;",
        "- lengths tied to n and k (the schema bounds them by {MAX_MASSES} masses only), and "
        "indices beyond n;",
        "- the rules across tables (`analytic/scene/rules.py`): an effect listed without its data "
        "(`[control.omega]`, a per-spring key) is refused, data of an effect not listed is ignored "
        "with a warning; BR's inertia as the MuJoCo twin compiles it; initial quantities whose "
        "products would overflow;",
        "- numbers that are not finite: TOML's `nan` passes any JSON Schema bound (and `inf` any "
        "key without one); an index written `1.0` is an integer to draft-07, not to the loader.",
        "",
    ]
    return [_fill(line) for line in out]


def _builtins() -> list[str]:
    out = [
        "`analytic.load_scene(name)`, `tumble validate NAME` and every other command accept these "
        "names (files in `analytic/scenes/`, each commented line by line):",
        "",
        "| name | what it is |",
        "|---|---|",
    ]
    for name in builtin_scene_names():
        with open(BUILTIN_DIR / f"{name}.toml", "rb") as f:
            description = tomllib.load(f)["scene"].get("description", "")
        out.append(f"| `{name}` | {_cell(description)} |")
    out += [
        "",
        "The command line also accepts the hard-case suite's scenes as `hard/<name>` "
        "(`validation/scenes/hard/`, run by `tumble hard-cases`).",
        "",
    ]
    return out


def render() -> str:
    """The markdown of ``docs/scene-format.md``."""
    out = [
        "# Scene format",
        "",
        f"<!-- Generated by `{GENERATOR}` from analytic/scene/keys_*.py (the keys the loader reads), "
        "validation/compare/thresholds.py and analytic/scenes/; do not edit by hand: "
        "tests/validation/report/test_scene_reference.py compares this file with what the generator renders. -->",
        "",
        "A scene is one TOML file that describes a body, its sliding masses, their springs, the "
        "initial state, what to simulate and how. It is data only, never evaluated. Load it with "
        '`analytic.load_scene("my_body.toml")` or run it with `tumble validate my_body.toml`; '
        "every bad value is refused when the scene is loaded, before any plant runs, with a "
        "`ValueError` that starts with the dotted key (`masses.mass[1]: must be positive (got "
        "-3.0)`).",
        "",
        "## Conventions",
        "",
        "- Units are SI: m, kg, s, rad (or degrees where a key says `_deg`), N.",
        "- **Body axes** are BR's principal axes at its centre of mass C (the paper's xyz); "
        "**inertial** axes are XYZ with Z up. Quaternions are w first and turn body into "
        "inertial vectors.",
        "- The rod is the line through O' = C + `d` along the unit vector `a` (both fixed in BR); "
        "a mass's position `p_i` is its distance from O' along `a` (negative: behind O').",
        "- `n` is the number of masses (the length of `masses.mass`); `k` the number of "
        "controlled masses or axes. Mass and axis indices are 1-based in files, as in the paper "
        "(error messages index lists from 0, as TOML arrays are indexed).",
        "",
        "## Springs",
        "",
        "The n masses are chained by n + 1 spring elements (Eq. 38), each a linear spring "
        "`k^l` in parallel with a cubic one `k^n`:",
        "",
        "```",
        "near wall ─k_1─ m_1 ─k_2─ m_2 ─ … ─k_n─ m_n ─k_(n+1)─ far wall",
        "```",
        "",
        "Spring i stretches by `x_i = (p_i − p_e,i) − (p_(i−1) − p_e,(i−1))` with "
        "`p_0 − p_e,0 = p_(n+1) − p_e,(n+1) = 0` (the walls are fixed to BR) and pushes with "
        "`k_i^l x_i + k_i^n x_i³`. So `masses.p_e` are the rest positions: every spring is at its "
        "rest length when each mass sits at its `p_e`, and where the walls are never enters. One "
        "mass between two walls feels the stiffness `k_1 + k_2`; a zero stiffness leaves two "
        "neighbours uncoupled. Masses may pass through each other (they are points on a line).",
        "",
        "## Effects",
        "",
        "`scene.effects` lists what is simulated; what is not listed is not computed at all "
        "(a plant never multiplies a term by zero).",
        "",
        "| effect | what it adds |",
        "|---|---|",
    ]
    effects_key = next(k for k in KEYS if k.dotted == "scene.effects")
    assert effects_key.choices is not None
    for e in effects_key.choices:
        out.append(f"| `{e.value}` | {_cell(CHOICE_MEANINGS[e])} |")
    out += [
        "",
        "## A minimal scene",
        "",
        "```toml",
        MINIMAL_SCENE.rstrip("\n"),
        "```",
        "",
        "## Built-in scenes",
        "",
        *_builtins(),
        "## The resolved scene",
        "",
        "`tumble validate` writes `scene.toml` beside its report: the scene as it ran, in this "
        "format, every default filled in (the attitude as its quaternion, the masses' own inertia "
        "as `inertia_body`); `tumble validate OUT/scene.toml` runs the same scene again. The "
        "`provenance.scene` block of `report.json` holds the same tables (1-based indices, "
        "`lambda`). From Python: `analytic.scene.dump.scene_to_toml(scene)`.",
        "",
        "## Keys, table by table",
        "",
        "*required*: the scene is refused without it; *optional*: the default applies when it "
        "is absent; otherwise the column says when the key is required or allowed. Every key not "
        "given takes its default; an unknown key or table is refused, by name. A list's length "
        "is in its type: *n* is the number of masses (the length of `masses.mass`), *k* the "
        "number of controlled masses (`control.masses.indices`, all n by default) or axes "
        "(`control.omega.components`).",
        "",
        *_tables(),
        "## What the loader refuses and warns about",
        "",
        *_limits(),
        "## Editors: the JSON Schema",
        "",
        *_editors(),
    ]
    return "\n".join(out).rstrip("\n") + "\n"


__all__ = [
    "DIRECTIVE_EXAMPLE",
    "GENERATOR",
    "MINIMAL_SCENE",
    "TAPLO_CONFIG",
    "TOMBI_CONFIG",
    "render",
]
