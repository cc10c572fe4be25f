"""Where a JSON output came from, and how it is written: the block every machine-read file carries
(``report.json``, ``sweep.json``, ``hard_cases.json``, ``bench.json``) and the one encoder for them.

* :func:`provenance` returns the block (the file's ``"provenance"`` key): the file's kind and schema
  version, the project version, the git commit when run from a git checkout, a UTC timestamp, the
  command line, the resolved scene and the versions of the libraries that produce the numbers.
* :func:`dumps` writes a document as JSON text: NaN and infinities become ``null``, numpy scalars and
  arrays become numbers and lists, enums their value, paths strings; a placeholder string (``"nan"``,
  ``"inf"``, ``"<2001 values>"``, ...) or an object of unknown type is refused with a ``ValueError``
  naming where it is in the document.

The schemas of the four files are ``validation/schemas/<kind>.schema.json`` (JSON Schema draft
2020-12, :func:`schema_path`), documented in ``docs/json-output.md``. A file kind's schema version
(:data:`SCHEMA_VERSIONS`) goes up when a field is removed, renamed or changes meaning or unit; added
fields keep it.

Nothing here imports numpy, the engines or the plotting libraries (versions are read with
:mod:`importlib.metadata`), so writing the block costs a ``git`` call at most.
"""

from __future__ import annotations

import enum
import json
import math
import re
import subprocess
import sys
from collections.abc import Mapping
from datetime import UTC, datetime
from importlib import metadata
from pathlib import Path, PurePath
from typing import Any

DISTRIBUTION = "tumbling-testbed"
"""The project's distribution name (its version is read from the installed metadata)."""

LIBRARIES = ("numba", "mujoco", "numpy", "scipy", "rerun-sdk", "pin")
"""Distributions whose versions the block records (None when not installed)."""

GIT_TIMEOUT_S = 2.0
"""How long the ``git rev-parse`` call may take before the commit is recorded as None."""

SCHEMA_DIR = Path(__file__).resolve().parent / "schemas"


class FileKind(enum.StrEnum):
    """The machine-read files, each with its own schema."""

    REPORT = "report"  # tumble validate: OUT/report.json
    SWEEP = "sweep"  # tumble sweep: OUT/sweep.json
    HARD_CASES = "hard_cases"  # tumble hard-cases: OUT/hard_cases.json
    BENCH = "bench"  # tumble bench --out / python -m validation.bench --out: bench.json


SCHEMA_VERSIONS: dict[FileKind, int] = {
    FileKind.REPORT: 1,
    FileKind.SWEEP: 1,
    FileKind.HARD_CASES: 1,
    FileKind.BENCH: 1,
}
"""The schema version of each file kind (the ``const`` of ``provenance.schema_version`` in its
schema; tests/test_schema.py checks both agree)."""


def schema_path(kind: FileKind | str) -> Path:
    """The JSON Schema of a file kind, ``validation/schemas/<kind>.schema.json``."""
    return SCHEMA_DIR / f"{FileKind(kind).value}.schema.json"


def project_version() -> str | None:
    """The installed project's version, or None (run from a checkout that was never installed)."""
    try:
        return metadata.version(DISTRIBUTION)
    except metadata.PackageNotFoundError:
        return None


def library_versions(names: tuple[str, ...] = LIBRARIES) -> dict[str, str | None]:
    """Distribution name -> installed version (None when not installed); nothing is imported."""
    out: dict[str, str | None] = {}
    for name in names:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = None
    return out


def git_commit(root: Path | None = None, timeout: float = GIT_TIMEOUT_S) -> str | None:
    """The commit checked out at ``root`` (default: the directory holding the project's packages),
    or None: not a git checkout, ``root`` inside some other repository (an installed copy in a
    user's project), ``git`` missing, slow or failing. Never raises."""
    root = Path(__file__).resolve().parent.parent if root is None else Path(root)
    try:
        done = subprocess.run(
            ["git", "-C", str(root), "rev-parse", "--show-toplevel", "HEAD"],
            capture_output=True,
            text=True,
            timeout=timeout,
            check=False,
        )
        lines = done.stdout.split()
        if done.returncode != 0 or len(lines) != 2:
            return None
        top, commit = lines
        if Path(top).resolve() != root.resolve() or not re.fullmatch(r"[0-9a-f]{40,64}", commit):
            return None
        return commit
    except (OSError, ValueError, subprocess.SubprocessError):
        return None


def utc_now() -> str:
    """The current UTC time, ISO 8601 with an explicit offset (``2026-01-31T12:00:00.123456+00:00``)."""
    return datetime.now(UTC).isoformat()


def provenance(
    kind: FileKind | str,
    scene: Any = None,
    argv: list[str] | None = None,
) -> dict[str, Any]:
    """The block a machine-read file carries under its ``"provenance"`` key.

    Args:
        kind: the file's kind (:class:`FileKind` or its value); a ``ValueError`` names an unknown one.
        scene: the resolved :class:`~analytic.scene.Scene` the file is about (dumped whole by
            :func:`analytic.scene_dump.scene_to_dict`), or None when the file covers several
            scenes or none (``hard_cases.json``, ``bench.json``).
        argv: the command line (default ``sys.argv``).

    Returns:
        ``{"kind", "schema_version", "project_version", "git_commit", "created_utc", "command",
        "scene", "versions"}``; see ``docs/json-output.md`` for each field.
    """
    try:
        kind = FileKind(kind)
    except ValueError:
        known = ", ".join(k.value for k in FileKind)
        raise ValueError(f"kind: unknown file kind {kind!r} (known: {known})") from None
    dumped = None
    if scene is not None:
        from analytic.scene_dump import scene_to_dict

        dumped = scene_to_dict(scene)
    return {
        "kind": kind.value,
        "schema_version": SCHEMA_VERSIONS[kind],
        "project_version": project_version(),
        "git_commit": git_commit(),
        "created_utc": utc_now(),
        "command": [str(a) for a in (sys.argv if argv is None else argv)],
        "scene": dumped,
        "versions": library_versions(),
    }


# ----------------------------------------------------------------------------------------------
# The encoder
# ----------------------------------------------------------------------------------------------

_PLACEHOLDER = re.compile(
    r"\s*([+-]?(nan|inf|infinity)|none|null|not installed|unknown|<[^<>]*>)\s*",
    re.IGNORECASE,
)
"""Strings that stand in for a missing or non-finite value (``"nan"``, ``"inf"``, ``"None"``,
``"<2001 values>"`` ...). A number that is not there is ``null`` in these files, never a string.
(``"N/A"`` is not among them: it is a hard case's verdict for a plant it does not apply to.)"""


class PlaceholderError(ValueError):
    """A value that JSON output must not carry (a placeholder string, an unknown type)."""


def to_json_value(x: Any, where: str = "$") -> Any:
    """``x`` as JSON-ready data (see the module docstring); ``where`` names it in errors.

    Raises:
        PlaceholderError: a placeholder string, a non-string mapping key that is not a plain
            scalar, or a value of a type JSON cannot carry, named by its path (``$.run.t_max``).
    """
    if x is None or isinstance(x, bool):
        return x
    if isinstance(x, enum.Enum):  # before str/int: a StrEnum is a str
        value = x.value  # a declared value (a shape kind "none"), never a placeholder
        return value if isinstance(value, str) else to_json_value(value, where)
    if isinstance(x, str):
        if getattr(x, "verbatim_text", False):  # a scene file's own text (analytic.scene.SceneText)
            return str(x)
        if _PLACEHOLDER.fullmatch(x):
            raise PlaceholderError(
                f"{where}: the placeholder string {x!r} stands for a value; write the number, "
                "or null when there is none"
            )
        return x
    if isinstance(x, int):
        return int(x)
    if isinstance(x, float):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, Mapping):
        out = {}
        for k, v in x.items():
            if isinstance(k, enum.Enum):
                k = k.value
            if not isinstance(k, str | int | float | bool):
                raise PlaceholderError(f"{where}: a key of type {type(k).__name__} ({k!r})")
            out[str(k)] = to_json_value(v, f"{where}.{k}")
        return out
    if isinstance(x, list | tuple):
        return [to_json_value(v, f"{where}[{i}]") for i, v in enumerate(x)]
    if isinstance(x, PurePath):
        return str(x)
    # numpy, without importing it: scalars have .item(), arrays .tolist()
    module = type(x).__module__ or ""
    if module == "numpy" or module.startswith("numpy."):
        if hasattr(x, "tolist") and getattr(x, "ndim", 0) > 0:
            return to_json_value(x.tolist(), where)
        if hasattr(x, "item"):
            return to_json_value(x.item(), where)
    raise PlaceholderError(
        f"{where}: a value of type {type(x).__name__} has no JSON form here ({x!r:.60}); "
        "convert it to numbers, strings, lists or dicts first"
    )


def dumps(doc: Any, indent: int | None = 2) -> str:
    """``doc`` as JSON text ending in a newline, through :func:`to_json_value` (strict JSON: no
    NaN or Infinity tokens, UTF-8 text kept as it is)."""
    return json.dumps(to_json_value(doc), indent=indent, allow_nan=False, ensure_ascii=False) + "\n"


__all__ = [
    "LIBRARIES",
    "SCHEMA_VERSIONS",
    "FileKind",
    "PlaceholderError",
    "dumps",
    "git_commit",
    "library_versions",
    "project_version",
    "provenance",
    "schema_path",
    "to_json_value",
]
