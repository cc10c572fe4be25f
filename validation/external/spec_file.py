"""The ``[judge]`` table of a ``test_*.toml`` file: another engine's trajectory file as pytest items.

::

    # test_my_engine.toml
    [judge]
    scene = "paper_example1_controlled"  # a built-in scene name, or a scene file beside this one
    trajectory = "runs/my_engine.csv"    # the trajectory file (docs/trajectory-format.md)
    label = "my_engine"                  # optional: the file's plant name (default: its stem)
    plants = "analytic,mujoco"           # optional: the plants run beside it (default: installed)
    reference = "pack"                   # optional: a reference pack directory instead of plants
    t_end = 2.0                          # optional: the horizon judged, s (default the scene's)
    up_to_file_end = true                # optional: a file that stops early judged to its end

Every path is relative to the directory of the TOML file and stays inside it: no absolute path,
no ``..``, and nothing (a symbolic link included) that resolves outside that directory. Nothing in
the file is evaluated; an unknown key, a value of another type, or a table besides ``[judge]`` is
one collection error naming it. This module reads and checks the table only (standard library);
the pytest plugin (:mod:`validation.testing.pytest_plugin`) runs :func:`validation.external.judge.judge`.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path, PurePosixPath, PureWindowsPath

TABLE = "judge"
KEYS = ("scene", "trajectory", "label", "plants", "reference", "t_end", "up_to_file_end")
REQUIRED = ("scene", "trajectory")


@dataclass(frozen=True)
class JudgeSpec:
    """A checked ``[judge]`` table.

    Attributes:
        scene: a built-in scene name, or a scene file inside the TOML's directory.
        trajectory: the trajectory file, inside the TOML's directory.
        label: the file's plant name (None: from its stem).
        plants: the plants run beside it (None: the session's ``--tumble-plants``).
        reference: a reference pack directory inside the TOML's directory, or None.
        t_end: the horizon judged, s (None: the scene's; checked against the scene by the judge:
            in (0, its t_end], on its output grid).
        up_to_file_end: a file that stops on the grid early is judged up to its last row.
    """

    scene: str | Path
    trajectory: Path
    label: str | None = None
    plants: str | None = None
    reference: Path | None = None
    t_end: float | None = None
    up_to_file_end: bool = False


def inside(base: Path, value: object, key: str) -> Path:
    """``base / value`` for a relative path ``value`` that stays inside ``base`` once resolved.

    Raises:
        ValueError: naming ``judge.<key>``: not a non-empty string, absolute, with ``..`` or a
            NUL, or resolving (through a link) outside ``base``.
    """
    where = f"{TABLE}.{key}"
    if not isinstance(value, str) or not value.strip():
        raise ValueError(f"{where}: must be a non-empty path string (got {value!r:.60})")
    if "\0" in value:
        raise ValueError(f"{where}: a path cannot hold a NUL character")
    for flavour in (PurePosixPath(value), PureWindowsPath(value)):
        if flavour.is_absolute() or flavour.drive or flavour.root:
            raise ValueError(f"{where}: {value!r:.60} must be relative to the TOML file's directory")
        if ".." in flavour.parts:
            raise ValueError(f"{where}: {value!r:.60} must not contain '..'")
    root = base.resolve()
    path = (base / value).resolve()
    try:
        path.relative_to(root)
    except ValueError:
        raise ValueError(
            f"{where}: {value!r:.60} resolves outside the TOML file's directory (a link?)"
        ) from None
    return base / value


def parse_spec(text: bytes, base: Path, builtin: list[str]) -> JudgeSpec:
    """The ``[judge]`` table of a TOML file's bytes ``text``, paths relative to ``base``.

    Args:
        text: the TOML file's content.
        base: its directory.
        builtin: the built-in scene names (a ``scene`` value naming one is not a path).

    Raises:
        ValueError: one line naming the key: not TOML, a table besides ``[judge]``, an unknown
            or missing key, a value that is not a string (``t_end``: a positive number,
            ``up_to_file_end``: a boolean), a path outside ``base``.
    """
    try:
        data = tomllib.loads(text.decode("utf-8"))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise ValueError(f"not a TOML file: {exc}") from None
    extra = sorted(set(data) - {TABLE})
    if extra:
        raise ValueError(f"{extra[0]}: a judge file holds only a [{TABLE}] table")
    table = data.get(TABLE)
    if not isinstance(table, dict):
        raise ValueError(f"{TABLE}: must be a table")
    unknown = sorted(set(table) - set(KEYS))
    if unknown:
        raise ValueError(f"{TABLE}.{unknown[0]}: unknown key (the keys are {', '.join(KEYS)})")
    for key in REQUIRED:
        if key not in table:
            raise ValueError(f"{TABLE}.{key}: missing")
    for key in ("label", "plants"):
        if key in table and not isinstance(table[key], str):
            raise ValueError(f"{TABLE}.{key}: must be a string (got {table[key]!r:.60})")
    t_end = table.get("t_end")
    if t_end is not None and (
        isinstance(t_end, bool) or not isinstance(t_end, (int, float)) or not 0 < t_end < math.inf
    ):
        raise ValueError(f"{TABLE}.t_end: must be a positive number of seconds (got {t_end!r:.60})")
    up_to_file_end = table.get("up_to_file_end", False)
    if not isinstance(up_to_file_end, bool):
        raise ValueError(
            f"{TABLE}.up_to_file_end: must be true or false (got {up_to_file_end!r:.60})"
        )
    scene = table["scene"]
    if not isinstance(scene, str):
        raise ValueError(f"{TABLE}.scene: must be a string (got {scene!r:.60})")
    return JudgeSpec(
        scene=scene if scene in builtin else inside(base, scene, "scene"),
        trajectory=inside(base, table["trajectory"], "trajectory"),
        label=table.get("label"),
        plants=table.get("plants"),
        reference=inside(base, table["reference"], "reference") if "reference" in table else None,
        t_end=None if t_end is None else float(t_end),
        up_to_file_end=up_to_file_end,
    )


__all__ = ["KEYS", "TABLE", "JudgeSpec", "inside", "parse_spec"]
