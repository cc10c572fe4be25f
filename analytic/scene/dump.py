"""A resolved :class:`~analytic.scene.Scene` written back in the scene file's own conventions.

:func:`scene_to_dict` gives the scene as the tables of a scene file (:mod:`analytic.scene.schema`):
the same keys (``lambda``, ``k_linear``, ``[initial.attitude] quaternion``), 1-based mass and axis
indices, every default filled in. :func:`scene_to_toml` writes that as TOML text, which
:func:`analytic.scene.load_scene` reads back to an equal scene (every field, every array
bit for bit; ``source`` aside, which is where a scene was read from). It is the ``provenance.scene``
block of the JSON outputs (:mod:`validation.report.provenance`) and the ``scene.toml`` that ``tumble
validate`` writes beside its report: pasted into a scene file, it runs the same scene.

What the file gave in another form is written in the one the loader resolved it to: the attitude as
the unit quaternion ``u(0)`` (w first), the masses' own inertia as ``inertia_body`` (one 3×3
matrix per mass, body axes), ``control.omega.gain`` as ``gamma`` when it is ``γ I``. A table or key
the loader would fill in with the same value is written anyway (``[solver]``, ``[output]``,
``[mujoco]``, ``[stabilization]``), except the ones whose presence means something: ``[gravity]``
only when it is not the default, ``[springs]`` keys only when the scene gave them (an effect needs
its constants given), ``solver.max_step`` only when there is a limit, ``[body.shape]`` keys only
for the shape drawn. Units are SI, as in the file. ``extra`` (``[thresholds]``, ``[hard_case]``) is
written as the scene gave it.
"""

from __future__ import annotations

import datetime
import enum
import math
import re
from collections.abc import Mapping
from typing import Any

import numpy as np

from analytic.effects.registry import SPRING_LAWS
from analytic.scene.limits import QUAT_NORMALISE_TOL
from analytic.scene.loading import Scene, scene_from_dict
from analytic.scene.schema import DEFAULT_GRAVITY


def _floats(a: Any) -> Any:
    """An array (or a number) as nested lists of Python floats."""
    return np.asarray(a, dtype=float).tolist()


def _table_body(scene: Scene) -> dict[str, Any]:
    b = scene.body
    out: dict[str, Any] = {"mass": float(b.mass), "inertia": _floats(b.inertia)}
    s = b.shape
    shape: dict[str, Any] = {"kind": s.kind}
    if s.kind.value == "box_and_rod":
        shape |= {
            "box_half_sizes": _floats(s.box_half_sizes),
            "box_center": _floats(s.box_center),
            "box_rotation": _floats(s.box_rotation),
        }
    elif s.kind.value == "hollow_cylinder_and_rod":
        shape |= {
            "cylinder_radius": float(s.cylinder_radius),
            "cylinder_length": float(s.cylinder_length),
            "cylinder_thickness": float(s.cylinder_thickness),
            "cylinder_axis": _floats(s.cylinder_axis),
        }
    if s.kind.value != "none":
        shape |= {
            "rod_radius": float(s.rod_radius),
            "rod_start": float(s.rod_start),
            "rod_length": float(s.rod_length),
        }
    out["shape"] = shape
    return out


def _table_masses(scene: Scene) -> dict[str, Any] | None:
    m = scene.masses
    if m.n == 0:
        return None
    out: dict[str, Any] = {"mass": _floats(m.mass), "p_e": _floats(m.p_e)}
    if np.any(np.asarray(m.inertia) != 0.0):
        out["inertia_body"] = _floats(m.inertia)
    return out


def _table_springs(scene: Scene) -> dict[str, Any] | None:
    sp = scene.springs
    out = {law.key.key: _floats(sp.of(law)) for law in SPRING_LAWS if law.key.key in sp.given}
    return out or None


def _table_initial(scene: Scene) -> dict[str, Any]:
    i = scene.initial
    out: dict[str, Any] = {
        "R": _floats(i.R),
        "Rdot": _floats(i.Rdot),
        "omega": _floats(i.omega),
    }
    if scene.n:
        out["p"] = _floats(i.p)
        out["pdot"] = _floats(i.pdot)
    attitude: dict[str, Any] = {"quaternion": _floats(i.u)}
    if abs(float(np.linalg.norm(i.u)) - 1.0) > QUAT_NORMALISE_TOL:
        attitude["allow_off_manifold"] = True  # the scene started off the unit sphere on purpose
    out["attitude"] = attitude
    return out


def _table_control(scene: Scene) -> dict[str, Any]:
    c = scene.control
    out: dict[str, Any] = {"weighting": c.weighting}
    if c.omega is not None:
        w = c.omega
        gain = np.asarray(w.gain, dtype=float)
        omega: dict[str, Any] = {
            "components": [int(i) + 1 for i in w.components],
            "b": _floats(w.b),
            "sigma": _floats(w.sigma),
        }
        if np.array_equal(gain, gain[0, 0] * np.eye(len(gain))):
            omega["gamma"] = float(gain[0, 0])
        else:
            omega["gain"] = _floats(gain)
        out["omega"] = omega
    if c.masses is not None:
        mt = c.masses
        out["masses"] = {
            "indices": [int(i) + 1 for i in mt.indices],
            "l": _floats(mt.l),
            "lambda": _floats(mt.lam),
            "alpha": _floats(mt.alpha),
            "beta": _floats(mt.beta),
        }
    return out


def scene_to_dict(scene: Scene) -> dict[str, Any]:
    """The tables of a scene file that loads as ``scene``; see the module docstring.

    Returns:
        ``{"scene": {name, description, effects}, "body": {...}, "rod": ..., ...}`` in the order of
        the reference (``docs/scene-format.md``): plain dicts, lists, floats, ints, bools and
        strings (string enums stay themselves, a ``str``; the scene's own text stays
        :class:`~analytic.scene.SceneText`). Every number is finite.
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected an analytic.scene.Scene (got {type(scene).__name__})")
    out: dict[str, Any] = {
        "scene": {
            "name": scene.name,
            "description": scene.description,
            "effects": sorted(scene.effects, key=lambda e: e.value),
        },
        "body": _table_body(scene),
        "rod": {"axis": _floats(scene.rod.axis), "offset": _floats(scene.rod.offset)},
    }
    masses = _table_masses(scene)
    if masses is not None:
        out["masses"] = masses
    springs = _table_springs(scene)
    if springs is not None:
        out["springs"] = springs
    if not np.array_equal(np.asarray(scene.gravity, dtype=float), DEFAULT_GRAVITY):
        out["gravity"] = {"vector": _floats(scene.gravity)}
    out["initial"] = _table_initial(scene)
    st = scene.stabilization
    out["stabilization"] = {"delta1": float(st.delta1), "delta2": float(st.delta2)}
    out["control"] = _table_control(scene)
    if scene.external_torque is not None:
        et = scene.external_torque
        out["external_torque"] = {
            "constant": _floats(et.constant),
            "amplitude": _floats(et.amplitude),
            "frequency": float(et.frequency),
        }
    sv = scene.solver
    out["solver"] = {"method": sv.method, "rtol": float(sv.rtol), "atol": float(sv.atol)}
    if math.isfinite(sv.max_step):
        out["solver"]["max_step"] = float(sv.max_step)
    out["output"] = {"t_end": float(scene.output.t_end), "rate": float(scene.output.rate)}
    mj = scene.mujoco
    out["mujoco"] = {
        "integrator": mj.integrator,
        "timestep": float(mj.timestep),
        "spring_model": mj.spring_model,
    }
    for table in ("hard_case", "mjx", "thresholds"):
        if table in scene.extra:
            out[table] = _verbatim(scene.extra[table])
    return out


def modified_scene(scene: Scene, changes: Mapping[str, Any]) -> Scene:
    """``scene`` with some keys of its tables changed, validated again as a loaded scene is.

    ``changes`` is laid over :func:`scene_to_dict` of ``scene``, in the scene file's own keys
    (``docs/scene-format.md``): a table given as a dict is merged key by key, any other value
    replaces the key (``{"body": {"inertia": [1.0, 2.0, 3.0]}, "output": {"t_end": 5.0}}``;
    ``{"scene": {"effects": ["gravity"]}}`` sets the effects). Every cross-field rule is applied
    again (:func:`~analytic.scene.scene_from_dict`); ``dataclasses.replace`` and
    :meth:`~analytic.scene.SceneRecord.replace` check nothing.

    Raises:
        ValueError: naming the changed field that the loader refuses, and its value.
    """

    def merge(base: dict[str, Any], over: Mapping[str, Any]) -> dict[str, Any]:
        out = dict(base)
        for key, value in over.items():
            if isinstance(value, Mapping) and isinstance(out.get(key), Mapping):
                out[key] = merge(dict(out[key]), value)
            else:
                out[key] = value
        return out

    if not isinstance(changes, Mapping):
        raise ValueError(f"changes: must be a table of tables (got {type(changes).__name__})")
    return scene_from_dict(merge(scene_to_dict(scene), changes), source=scene.source)


def _verbatim(x: Any) -> Any:
    """A table the scene gave, as plain dicts and lists (the values themselves untouched)."""
    if isinstance(x, Mapping):
        return {str(k): _verbatim(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_verbatim(v) for v in x]
    return x


# ----------------------------------------------------------------------------------------------
# TOML text
# ----------------------------------------------------------------------------------------------

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
_ESCAPES = {
    '"': '\\"',
    "\\": "\\\\",
    "\b": "\\b",
    "\t": "\\t",
    "\n": "\\n",
    "\f": "\\f",
    "\r": "\\r",
}


def _toml_string(s: str) -> str:
    """A TOML basic string: quotes, backslashes and control characters escaped."""
    out = []
    for ch in s:
        if ch in _ESCAPES:
            out.append(_ESCAPES[ch])
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _toml_key(k: str) -> str:
    return k if _BARE_KEY.fullmatch(k) else _toml_string(k)


def _toml_value(v: Any) -> str:
    """One TOML value, inline (a table inside a list as an inline table). A float is written with
    Python's shortest round-trip repr, so it reads back bit for bit."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, enum.Enum):
        v = v.value
    if isinstance(v, str):
        return _toml_string(v)
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"scene: a non-finite number has no place in a scene file (got {v!r})")
        return repr(v)
    if isinstance(v, datetime.date | datetime.time):  # (tomllib reads these)
        return v.isoformat()
    if isinstance(v, Mapping):
        return (
            "{" + ", ".join(f"{_toml_key(str(k))} = {_toml_value(x)}" for k, x in v.items()) + "}"
        )
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"scene: no TOML form for a {type(v).__name__} (got {v!r})")


def _toml_table(path: list[str], table: Mapping[str, Any], out: list[str]) -> None:
    """``[path]`` with its plain keys, then each sub-table as its own ``[path.key]``."""
    plain = [(k, v) for k, v in table.items() if not isinstance(v, Mapping)]
    subs = [(k, v) for k, v in table.items() if isinstance(v, Mapping)]
    if path and (plain or not subs):
        out.append(f"[{'.'.join(_toml_key(p) for p in path)}]")
    for k, v in plain:
        out.append(f"{_toml_key(str(k))} = {_toml_value(v)}")
    if path and (plain or not subs):
        out.append("")
    for k, v in subs:
        _toml_table([*path, str(k)], v, out)


def _comment(text: str) -> list[str]:
    """``text`` as TOML comment lines, each control character escaped (a newline in a path given
    by the user cannot start a line of TOML)."""
    return [f"# {_toml_string(line)[1:-1]}".rstrip() for line in text.split("\n")]


def scene_to_toml(scene: Scene, header: str = "") -> str:
    """``scene`` as the text of a scene file (:func:`scene_to_dict`, written as TOML), which
    :func:`analytic.scene.load_scene` reads back to an equal scene.

    Args:
        scene: a loaded scene.
        header: comment lines to put first (each prefixed with ``# ``), e.g. where the scene came
            from; the scene's ``source`` is named there when it has one.
    """
    data = scene_to_dict(scene)
    lines = _comment(header) if header else []
    if scene.source:
        lines += _comment(f"Resolved from {scene.source}: every default filled in.")
    lines += _comment("Units SI; mass and axis indices 1-based (docs/scene-format.md).")
    lines.append("")
    _toml_table([], data, lines)
    return "\n".join(lines).rstrip("\n") + "\n"


__all__ = ["modified_scene", "scene_to_dict", "scene_to_toml"]
