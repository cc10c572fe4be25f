"""Default output paths: slugs of scene names, directories and files under ``out/``, run ids.

Rule 1 of :mod:`validation.runs.outputs`: paths never come from scene data. A scene's ``name`` only
ever becomes a *slug* (:func:`slug`) inside a default directory under :data:`DEFAULT_ROOT`; a name
that cannot be made safe is refused with a ``ValueError`` naming ``scene.name``.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import re
import uuid
from pathlib import Path

DEFAULT_ROOT = Path("out")
"""Where a command's default output directory goes, relative to the working directory."""

SLUG_MAX_LEN = 64
"""Longest slug kept verbatim. Longer names are cut and given a hash of the whole name (so two
long names stay distinct); 64 + prefix + hash stays far below NAME_MAX (255 bytes) on every
common filesystem."""

_SLUG_OK = re.compile(r"[^A-Za-z0-9._-]+")

RUN_ID_PATTERN = r"\d{8}T\d{6}Z-[0-9a-f]{8}"
"""Every run id (:func:`new_run_id`): UTC time to the second, a dash, 8 hex digits."""

_RUN_ID = re.compile(rf"^{RUN_ID_PATTERN}$")

def slug(name: str, field: str = "scene.name") -> str:
    """A file-name-safe form of a scene name: ``[A-Za-z0-9._-]`` only, no leading dot.

    Separators, ``..``, spaces and any other character become ``_`` runs; names longer than
    :data:`SLUG_MAX_LEN` are cut and end in 8 hex digits of the whole name's SHA-256.

    Raises:
        ValueError: naming ``field`` when the name is not a string, holds a NUL or another control
            character, or has nothing left to name a directory by (e.g. ``"../.."``).
    """
    if not isinstance(name, str):
        raise ValueError(f"{field}: must be a string (got {name!r})")
    if any(ord(c) < 32 or ord(c) == 127 for c in name):
        raise ValueError(f"{field}: must not contain control characters (got {name[:40]!r})")
    s = _SLUG_OK.sub("_", name).strip("._-")
    if not s or not any(c.isalnum() for c in s):
        raise ValueError(
            f"{field}: cannot name an output directory (got {name[:40]!r}); "
            "use letters, digits, '.', '_' or '-'"
        )
    if len(s) > SLUG_MAX_LEN:
        digest = hashlib.sha256(name.encode("utf-8", "surrogatepass")).hexdigest()[:8]
        s = f"{s[: SLUG_MAX_LEN - 9].rstrip('._-')}-{digest}"
    return s


def default_out_dir(prefix: str, scene_name: str) -> Path:
    """``out/<prefix><slug(scene_name)>``: a default output directory, always under ``out/``."""
    return DEFAULT_ROOT / f"{prefix}{slug(scene_name)}"


def default_out_file(scene_name: str, suffix: str) -> Path:
    """``out/<slug(scene_name)><suffix>``: a default output file, always under ``out/``."""
    return DEFAULT_ROOT / f"{slug(scene_name)}{suffix}"


def new_run_id() -> str:
    """A fresh run id: UTC time to the second and 8 random hex digits (sortable, unique)."""
    now = _dt.datetime.now(_dt.UTC).strftime("%Y%m%dT%H%M%SZ")
    return f"{now}-{uuid.uuid4().hex[:8]}"


def is_run_id(text: object) -> bool:
    """Whether ``text`` is a run id of :data:`RUN_ID_PATTERN` (a string, whole)."""
    return isinstance(text, str) and _RUN_ID.fullmatch(text) is not None


__all__ = [
    "DEFAULT_ROOT",
    "RUN_ID_PATTERN",
    "SLUG_MAX_LEN",
    "default_out_dir",
    "default_out_file",
    "is_run_id",
    "new_run_id",
    "slug",
]
