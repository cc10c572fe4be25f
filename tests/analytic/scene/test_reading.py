"""Reading a scene file: a small regular file only, parser errors as one named line.

Every bad input must raise ValueError whose message starts with the dotted field name.
"""

from __future__ import annotations

import errno
import os
from pathlib import Path

import numpy as np
import pytest

from analytic import scene as S
from analytic.runtime import safe_files
from analytic.scene import load_scene


def test_missing_file_and_bad_toml(tmp_path):
    with pytest.raises(ValueError, match=r"^scene: file not found"):
        load_scene(tmp_path / "nope.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[scene\nname = 1")
    with pytest.raises(ValueError, match=r"^scene: not valid TOML"):
        load_scene(bad)


def test_scene_path_must_be_a_small_regular_file(tmp_path, monkeypatch):
    with pytest.raises(ValueError, match=r"^scene: is a directory, not a scene file \(got '"):
        load_scene(tmp_path)
    if Path("/dev/zero").exists():
        with pytest.raises(ValueError, match=r"^scene: not a regular file \(got '/dev/zero'\)$"):
            load_scene("/dev/zero")
    huge = tmp_path / "huge.toml"
    with open(huge, "wb") as f:  # sparse: no disk space used
        f.truncate(S.MAX_SCENE_BYTES + 1)
    with pytest.raises(ValueError, match=r"^scene: file larger than 1,048,576 bytes"):
        load_scene(huge)
    # the path is named as the user gave it
    monkeypatch.chdir(tmp_path)
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "bad.toml").write_text("[scene\n")
    with pytest.raises(ValueError, match=r"^scene: not valid TOML in './sub/../sub/bad.toml'"):
        load_scene("./sub/../sub/bad.toml")


def test_integer_beyond_the_toml_parser_is_one_named_line(tmp_path):
    p = tmp_path / "big.toml"
    p.write_text("x = " + "9" * 5000 + "\n")
    with pytest.raises(ValueError) as exc:
        load_scene(p)
    msg = str(exc.value)
    assert msg.startswith(f"scene: cannot parse {str(p)!r}") and "\n" not in msg
    assert "set_int_max_str_digits" not in msg


def test_a_scene_through_a_link_is_read_and_a_link_to_a_fifo_is_refused_without_blocking(tmp_path):
    """A scene file the user names is followed through a symbolic link (``safe_files`` with
    ``follow_links``) to the same scene; a link to a FIFO with no writer is refused, never opened
    for a blocking read."""
    target = tmp_path / "real.toml"
    target.write_bytes(S.builtin_scene_path("paper_example1").read_bytes())
    link = tmp_path / "link.toml"
    link.symlink_to(target)
    via_link, direct = load_scene(link), load_scene(target)
    assert via_link.name == direct.name == "paper_example1"
    assert np.array_equal(via_link.initial.u, direct.initial.u)
    fifo = tmp_path / "pipe.toml"
    os.mkfifo(fifo)
    fifo_link = tmp_path / "pipe_link.toml"
    fifo_link.symlink_to(fifo)
    for path in (fifo, fifo_link):
        with pytest.raises(ValueError, match=r"^scene: not a regular file \(got '.*pipe"):
            load_scene(path)


def test_read_regular_follows_a_link_only_when_asked(tmp_path):
    target = tmp_path / "a.txt"
    target.write_bytes(b"abc")
    link = tmp_path / "b.txt"
    link.symlink_to(target)
    assert safe_files.read_regular(link, 10, follow_links=True) == b"abc"
    with pytest.raises(safe_files.NotRegularFile, match="symbolic link"):
        safe_files.read_regular(link, 10)
    with pytest.raises(OSError) as exc:
        safe_files.read_regular(link, 2, follow_links=True)
    assert exc.value.errno == errno.EFBIG
