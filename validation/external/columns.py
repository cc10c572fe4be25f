"""The columns of a trajectory file, declared once: name, unit, frame, meaning, group.

A trajectory file (``docs/trajectory-format.md``) is a table with one row per output sample and
one column per scalar below. Columns come in groups: the four required groups give the motion in
the paper's coordinates ``q = [R, u, p]`` (Eq. 44) and the time; each optional group is given whole
or not at all. Per-mass columns are numbered 1 … n along the scene's masses (1-based, as in the
scene files and the paper, ``docs/errata.md`` C6), without leading zeros: ``p_1``, ``p_2``, ….

Everything here is data about names; nothing reads a file. :func:`header` lists the columns of a
file for a scene's n and a set of groups; :func:`parse_header` maps a file's header to the groups
it holds, refusing unknown, duplicate and missing names and a mass count other than the scene's.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum

from validation.external.errors import TrajectoryFileError


class TrajectoryFormat(StrEnum):
    """The file formats of a trajectory; the value is the file name's suffix (without the dot)."""

    CSV = "csv"
    PARQUET = "parquet"


class ColumnGroup(StrEnum):
    """A group of columns given together; the value is how messages name it ("no omega columns")."""

    TIME = "t"
    POSITION = "R"
    ATTITUDE = "u"
    ROD_POSITIONS = "p"
    VELOCITY = "v"
    ANGULAR_VELOCITY = "omega"
    ROD_VELOCITIES = "pdot"
    TORQUE = "tau"
    ROD_FORCES = "F"
    WORK = "work"

    @property
    def required(self) -> bool:
        return self in REQUIRED_GROUPS

    @property
    def per_mass(self) -> bool:
        return self in (ColumnGroup.ROD_POSITIONS, ColumnGroup.ROD_VELOCITIES, ColumnGroup.ROD_FORCES)


REQUIRED_GROUPS = frozenset(
    {ColumnGroup.TIME, ColumnGroup.POSITION, ColumnGroup.ATTITUDE, ColumnGroup.ROD_POSITIONS}
)
"""Every file holds these: the time and the coordinates ``q = [R, u, p]``."""
OPTIONAL_GROUPS = frozenset(ColumnGroup) - REQUIRED_GROUPS
"""A file may hold any of these, each whole; a check that needs an absent one is not judged."""


@dataclass(frozen=True)
class Column:
    """One column, or (``per_mass``) the template of one column per mass.

    Attributes:
        name: the header name; for a per-mass column the prefix, the header names being
            ``f"{name}_{i}"`` for i = 1 … n.
        group: the group it belongs to.
        unit: SI unit ("1" for a dimensionless quaternion component).
        frame: "inertial", "body axes" (BR's principal axes at C), "along the rod" or "".
        meaning: one sentence, as ``docs/trajectory-format.md`` shows it.
    """

    name: str
    group: ColumnGroup
    unit: str
    frame: str
    meaning: str

    @property
    def per_mass(self) -> bool:
        return self.group.per_mass

    def names(self, n: int) -> tuple[str, ...]:
        """The header names of this column for n masses (one, or n for a per-mass column)."""
        return tuple(f"{self.name}_{i}" for i in range(1, n + 1)) if self.per_mass else (self.name,)


_G = ColumnGroup
_ANGULAR_IMPULSE = (
    "angular impulse since t = 0 of the external moments about the system centre of mass c, "
    "∫ S(u)(τ + τ_given) + (R − c) × F_C dt, x"
)
_LINEAR_IMPULSE = "impulse since t = 0 of the control force at C, ∫ F_C dt (zero for the paper's cost), x"
COLUMNS: tuple[Column, ...] = (
    Column("t", _G.TIME, "s", "", "sample time, on the scene's output grid 0, 1/rate, …, t_end"),
    Column("R_x", _G.POSITION, "m", "inertial", "position of C, the centre of mass of BR, x"),
    Column("R_y", _G.POSITION, "m", "inertial", "position of C, y"),
    Column("R_z", _G.POSITION, "m", "inertial", "position of C, z"),
    Column("u_w", _G.ATTITUDE, "1", "body → inertial", "attitude quaternion, scalar part (w first)"),
    Column("u_x", _G.ATTITUDE, "1", "body → inertial", "attitude quaternion, x"),
    Column("u_y", _G.ATTITUDE, "1", "body → inertial", "attitude quaternion, y"),
    Column("u_z", _G.ATTITUDE, "1", "body → inertial", "attitude quaternion, z"),
    Column("p", _G.ROD_POSITIONS, "m", "along the rod", "position of mass i along the rod from O′"),
    Column("v_x", _G.VELOCITY, "m/s", "inertial", "velocity of C, x"),
    Column("v_y", _G.VELOCITY, "m/s", "inertial", "velocity of C, y"),
    Column("v_z", _G.VELOCITY, "m/s", "inertial", "velocity of C, z"),
    Column("omega_x", _G.ANGULAR_VELOCITY, "rad/s", "body axes", "angular velocity of BR, x"),
    Column("omega_y", _G.ANGULAR_VELOCITY, "rad/s", "body axes", "angular velocity of BR, y"),
    Column("omega_z", _G.ANGULAR_VELOCITY, "rad/s", "body axes", "angular velocity of BR, z"),
    Column("pdot", _G.ROD_VELOCITIES, "m/s", "along the rod", "velocity of mass i along the rod"),
    Column("tau_x", _G.TORQUE, "N·m", "body axes", "control torque on BR, x"),
    Column("tau_y", _G.TORQUE, "N·m", "body axes", "control torque on BR, y"),
    Column("tau_z", _G.TORQUE, "N·m", "body axes", "control torque on BR, z"),
    Column(
        "F",
        _G.ROD_FORCES,
        "N",
        "along the rod",
        "control force on mass i along the rod (between the rod and the mass)",
    ),
    Column(
        "W",
        _G.WORK,
        "J",
        "",
        "work done since t = 0 by the control (τ·ω + F·ṗ + F_C·Ṙ) and the scene's given torque",
    ),
    Column("I_L_x", _G.WORK, "N·m·s", "inertial", _ANGULAR_IMPULSE),
    Column("I_L_y", _G.WORK, "N·m·s", "inertial", "angular impulse, y"),
    Column("I_L_z", _G.WORK, "N·m·s", "inertial", "angular impulse, z"),
    Column("I_P_x", _G.WORK, "N·s", "inertial", _LINEAR_IMPULSE),
    Column("I_P_y", _G.WORK, "N·s", "inertial", "impulse of the force at C, y"),
    Column("I_P_z", _G.WORK, "N·s", "inertial", "impulse of the force at C, z"),
)
"""Every column, in the order a file written by this project has them (any order is read)."""

_PER_MASS = re.compile(r"(?P<prefix>[A-Za-z]+)_(?P<index>[1-9][0-9]{0,8})\Z")
_BY_NAME = {c.name: c for c in COLUMNS if not c.per_mass}
_BY_PREFIX = {c.name: c for c in COLUMNS if c.per_mass}


def header(n: int, groups: frozenset[ColumnGroup] | None = None) -> tuple[str, ...]:
    """The header names of a file for n masses holding ``groups`` (default: every group), in the
    order of :data:`COLUMNS`."""
    chosen = frozenset(ColumnGroup) if groups is None else REQUIRED_GROUPS | groups
    return tuple(name for c in COLUMNS if c.group in chosen for name in c.names(n))


def group_names(group: ColumnGroup, n: int) -> tuple[str, ...]:
    """The header names of one group for n masses, in order (``p_1 … p_n``, ``omega_x …``)."""
    return tuple(name for c in COLUMNS if c.group is group for name in c.names(n))


def _show(name: str) -> str:
    """A header name as a message quotes it: ``repr``, cut to 40 characters (a file's text)."""
    return repr(name if len(name) <= 40 else name[:37] + "...")


@dataclass(frozen=True)
class HeaderLayout:
    """Where each group's columns are in a file.

    Attributes:
        index: header name -> 0-based column position in the file.
        present: the optional groups the file holds (each whole).
    """

    index: dict[str, int]
    present: frozenset[ColumnGroup]

    def columns(self, group: ColumnGroup, n: int) -> list[int]:
        """0-based file positions of ``group``'s columns, in the group's order."""
        return [self.index[name] for name in group_names(group, n)]


def columns_text(n: int) -> str:
    """Every column name for n masses, a per-mass group as a range: ``"t, R_x, …, p_1 … p_3, …"``."""
    parts = []
    for group in ColumnGroup:
        names = group_names(group, n)
        if group.per_mass and len(names) > 1:
            parts.append(f"{names[0]} … {names[-1]}")
        else:
            parts.extend(names)
    return ", ".join(parts)


def _check_mass_indices(group: ColumnGroup, found: set[int], n: int, where: str) -> None:
    """Refuse a per-mass group whose mass numbers are not 1 … n: a file for another mass count
    (numbers 1 … k, k ≠ n), a gap, or a number beyond n."""
    if found == set(range(1, n + 1)):
        return
    k = max(found)
    if found == set(range(1, k + 1)):
        names = f"{group.value}_1" + (f" … {group.value}_{k}" if k > 1 else "")
        masses = "1 mass" if k == 1 else f"{k} masses"
        raise TrajectoryFileError(
            f"{where}: the file has {masses} ({names}), the scene n = {n}"
        )
    gaps = set(range(1, min(k, n) + 1)) - found
    if gaps:
        raise TrajectoryFileError(f"{where}: column '{group.value}_{min(gaps)}' missing")
    beyond = min(i for i in found if i > n)
    raise TrajectoryFileError(
        f"{where}: column '{group.value}_{beyond}' is beyond the scene's n = {n} masses"
    )


def parse_header(names: Sequence[str], n: int, where: str) -> HeaderLayout:
    """Map a file's header to its groups, for a scene with n masses.

    Args:
        names: the header names in file order (already stripped of surrounding blanks).
        n: the scene's number of masses.
        where: how messages name the file and the header (``"trajectory file 'x.csv', header"``).

    Raises:
        TrajectoryFileError: an empty, unknown or duplicate name; a per-mass group whose masses are
            not 1 … n (naming the file's mass count and the scene's); a required column missing; an
            optional group given in part.
    """
    index: dict[str, int] = {}
    masses: dict[ColumnGroup, set[int]] = {}
    for pos, name in enumerate(names):
        col = f"column {pos + 1}"
        if not name:
            raise TrajectoryFileError(f"{where}, {col}: empty column name")
        if name in index:
            raise TrajectoryFileError(
                f"{where}, {col}: duplicate column {_show(name)} (also column {index[name] + 1})"
            )
        m = _PER_MASS.match(name)
        if name in _BY_NAME:
            pass
        elif m and m["prefix"] in _BY_PREFIX:
            masses.setdefault(_BY_PREFIX[m["prefix"]].group, set()).add(int(m["index"]))
        else:
            raise TrajectoryFileError(
                f"{where}, {col}: unknown column {_show(name)} (the columns are "
                f"{columns_text(n)}; docs/trajectory-format.md)"
            )
        index[name] = pos
    for group, found in masses.items():
        _check_mass_indices(group, found, n, where)
    present: set[ColumnGroup] = set()
    for group in ColumnGroup:
        wanted = group_names(group, n)
        have = [name for name in wanted if name in index]
        if group in REQUIRED_GROUPS:
            if len(have) < len(wanted):
                missing = next(name for name in wanted if name not in index)
                raise TrajectoryFileError(f"{where}: required column {missing!r} missing")
        elif have and len(have) < len(wanted):
            missing = next(name for name in wanted if name not in index)
            raise TrajectoryFileError(
                f"{where}: column {missing!r} missing: the {group.value} columns "
                f"({', '.join(wanted)}) are given together or not at all"
            )
        elif have or (group.per_mass and n == 0):
            present.add(group)
    return HeaderLayout(index=index, present=frozenset(present) & OPTIONAL_GROUPS)


__all__ = [
    "COLUMNS",
    "OPTIONAL_GROUPS",
    "REQUIRED_GROUPS",
    "Column",
    "ColumnGroup",
    "HeaderLayout",
    "TrajectoryFormat",
    "columns_text",
    "group_names",
    "header",
    "parse_header",
]
