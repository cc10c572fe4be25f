"""A scene file read: the path (or a built-in scene's name) to the TOML document, then to a
:class:`~analytic.scene.records.Scene` through :func:`analytic.scene.loading.scene_from_dict`.

The file is read by :mod:`analytic.runtime.safe_files` (a regular file only, never blocking, at most
:data:`~analytic.scene.limits.MAX_SCENE_BYTES`); its text is parsed with :mod:`tomllib` and
nothing in it is ever evaluated.
"""

from __future__ import annotations

import errno
import os
import stat
import tomllib
from pathlib import Path

from analytic.runtime import safe_files
from analytic.scene.builtin import builtin_scene_names, builtin_scene_path
from analytic.scene.limits import MAX_SCENE_BYTES, MAX_SCENE_NESTING
from analytic.scene.loading import Scene, scene_from_dict
from analytic.scene.nesting import check_text_nesting


def load_scene(path: str | Path) -> Scene:
    """Read and validate a scene file (TOML), or a built-in scene by name. Raises ``ValueError``
    naming the field on bad input.

    ``path`` is a file when one exists there, else the name of a built-in scene
    (``"paper_example1"``, see :func:`analytic.scene.builtin.builtin_scene_names`). Only a regular
    file of at most :data:`MAX_SCENE_BYTES` is read (a FIFO, a device such as ``/dev/zero`` or a
    directory is refused without reading it); messages name ``path`` as given.
    """
    p = Path(path)
    given = str(path)
    source = given
    try:
        st = os.stat(p)
    except FileNotFoundError:
        builtin = builtin_scene_path(given)
        if builtin is None:
            raise ValueError(
                f"scene: file not found and no built-in scene of that name (got {given!r}; "
                f"built-in: {', '.join(builtin_scene_names())})"
            ) from None
        p = builtin
        source = str(builtin)
        st = os.stat(p)
    except OSError as exc:
        raise ValueError(f"scene: cannot read {given!r} ({exc.strerror or exc})") from None
    except ValueError as exc:  # a NUL byte in the path
        raise ValueError(f"scene: cannot look up {given!r} ({exc})") from None
    if stat.S_ISDIR(st.st_mode):
        raise ValueError(f"scene: is a directory, not a scene file (got {given!r})")
    if not stat.S_ISREG(st.st_mode):
        raise ValueError(f"scene: not a regular file (got {given!r})")
    too_big = f"scene: file larger than {MAX_SCENE_BYTES:,} bytes (got {given!r})"
    if st.st_size > MAX_SCENE_BYTES:
        raise ValueError(too_big)
    try:  # (never blocks: should the path have become a FIFO since stat, it is refused)
        raw = safe_files.read_regular(p, MAX_SCENE_BYTES, follow_links=True)
    except safe_files.NotRegularFile:
        raise ValueError(f"scene: not a regular file (got {given!r})") from None
    except OSError as exc:
        if exc.errno == errno.EFBIG:  # (it grew past the limit since stat)
            raise ValueError(too_big) from None
        raise ValueError(f"scene: cannot read {given!r} ({exc.strerror or exc})") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise ValueError(f"scene: not UTF-8 text (got {given!r})") from None
    check_text_nesting(text, given)
    try:
        data = tomllib.loads(text)
    except RecursionError:  # (the scan above refuses such files first; kept as a safety net)
        raise ValueError(
            f"scene: nested deeper than {MAX_SCENE_NESTING} levels of lists and tables "
            f"(in {given!r})"
        ) from None
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"scene: not valid TOML in {given!r} ({exc})") from None
    except ValueError as exc:  # e.g. an integer literal of more than 4300 digits
        msg = str(exc).splitlines()[0].split(";")[0] if str(exc) else type(exc).__name__
        raise ValueError(f"scene: cannot parse {given!r} ({msg})") from None
    return scene_from_dict(data, source=source)


__all__ = ["load_scene"]
