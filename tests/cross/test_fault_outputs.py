"""What the output directory survives: planted links, other people's files, odd places.

Each test plants one fault around an output directory (a symbolic link where the lock, the target
or a staging directory goes; a user's hidden files, look-alike names or edits; a mount point; the
working directory itself) and checks the rule: a directory is replaced only when its
``manifest.json`` proves it is a tumble run, nothing the tool did not create is opened for
writing, replaced or deleted, and a refusal is one line before any plant runs.

Read as a table: each test's docstring is "<fault> -> <what the tool does>".
"""

from __future__ import annotations

import errno
import hashlib
import json
import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.trees import tree as _tree
from validation.cli import EXIT_USAGE, main
from validation.runs import staging as outputs_mod  # the commit's renames and mount test
from validation.runs.atomic import OutputError, write_bytes, write_text
from validation.runs.outputs import MANIFEST, OutputBusy, output_run

pytestmark = pytest.mark.faults

SCENE = "paper_example1_controlled"
T_END = "0.2"
VICTIM = b"precious: do not touch\n"


@pytest.fixture(autouse=True)
def _one_process(monkeypatch):
    monkeypatch.setenv("TUMBLE_WORKERS", "0")


def _fake_run(target: Path, files: dict[str, bytes] | None = None):
    """A quick run through the output machinery alone (no plant)."""
    files = {"report.md": b"# run\n", "run.rrd": b"rrd"} if files is None else files
    with output_run(target, "test") as run:
        for name, data in files.items():
            write_bytes(run.path / name, data)
    return run


def _validate(out: Path, capsys) -> tuple[int, list[str]]:
    """Exit status and the error lines of ``tumble validate`` (the numba cache's own notes about
    compiling or rebuilding kernels are not this module's and are left out)."""
    rc = main(["validate", SCENE, "--t-end", T_END, "--out", str(out)])
    err = capsys.readouterr().err
    assert "Traceback" not in err, err
    lines = err.strip().splitlines()
    notes = ("tumble: warning:", "tumble: compiling", "tumble:   ")
    return rc, [ln for ln in lines if not ln.startswith(notes)]


def _no_plant_may_run(monkeypatch) -> None:
    """Make any plant run fail the test: a refusal must come before the work."""
    import validation.validate as validate_mod

    def forbidden(*args, **kwargs):
        pytest.fail("a plant ran before the output directory was checked")

    monkeypatch.setattr(validate_mod, "_validate_into", forbidden)


# ---------------------------------------------------------------------------------------------
# The lock file
# ---------------------------------------------------------------------------------------------


def test_lock_symlink_to_a_file_is_refused(tmp_path, capsys, monkeypatch):
    """A symlink planted at the lock path -> refused in one line, exit 2; the file it points to
    is neither truncated nor written."""
    victim = tmp_path / "victim.txt"
    victim.write_bytes(VICTIM)
    (tmp_path / ".o.lock").symlink_to(victim)
    _no_plant_may_run(monkeypatch)
    rc, err = _validate(tmp_path / "o", capsys)
    assert rc == EXIT_USAGE and len(err) == 1 and ".o.lock" in err[0], err
    assert victim.read_bytes() == VICTIM
    assert not (tmp_path / "o").exists()


def test_dangling_lock_symlink_creates_nothing(tmp_path):
    """A dangling symlink at the lock path -> refused; no file appears where it points."""
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (tmp_path / ".o.lock").symlink_to(elsewhere / "created.txt")
    with pytest.raises(ValueError, match=r"\.o\.lock"):
        _fake_run(tmp_path / "o")
    assert list(elsewhere.iterdir()) == [] and not (tmp_path / "o").exists()


def test_lock_hard_link_is_refused(tmp_path):
    """The lock path hard-linked to a user's file -> refused; the file is not written."""
    victim = tmp_path / "victim.txt"
    victim.write_bytes(VICTIM)
    os.link(victim, tmp_path / ".o.lock")
    with pytest.raises(ValueError, match=r"\.o\.lock"):
        _fake_run(tmp_path / "o")
    assert victim.read_bytes() == VICTIM


def test_lock_fifo_is_refused_without_blocking(tmp_path):
    """A FIFO at the lock path -> refused at once (never opened for a blocking read or write)."""
    os.mkfifo(tmp_path / ".o.lock")
    with pytest.raises(ValueError, match=r"\.o\.lock"):
        _fake_run(tmp_path / "o")


def test_old_lock_file_is_used_not_rewritten(tmp_path):
    """A regular lock file left by a killed run -> the run goes ahead, the file is left as found."""
    lock = tmp_path / ".o.lock"
    lock.write_bytes(b"12345\n")
    _fake_run(tmp_path / "o")
    assert (tmp_path / "o" / MANIFEST).is_file()
    assert lock.read_bytes() == b"12345\n"


def test_lock_is_held_while_an_old_lock_file_is_reused(tmp_path):
    """A second run while the first holds a reused lock file -> the second is refused (busy)."""
    (tmp_path / ".o.lock").write_bytes(b"")
    with output_run(tmp_path / "o", "first"):
        with pytest.raises(OutputBusy):
            _fake_run(tmp_path / "o")


# ---------------------------------------------------------------------------------------------
# The target directory: ownership is proven by the manifest
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("hidden", [".notes", ".gitkeep", ".gitignore"])
def test_directory_of_hidden_files_is_not_replaced(tmp_path, capsys, monkeypatch, hidden):
    """A directory holding only the user's dot-file -> refused in one line naming it; kept."""
    r = tmp_path / "r"
    r.mkdir()
    (r / hidden).write_bytes(VICTIM)
    _no_plant_may_run(monkeypatch)
    rc, err = _validate(r, capsys)
    assert rc == EXIT_USAGE and len(err) == 1 and hidden in err[0], err
    assert _tree(r) == {hidden: VICTIM}


def test_users_own_report_md_is_not_replaced(tmp_path, capsys, monkeypatch):
    """A user's report.md (no manifest) -> refused, kept byte for byte."""
    d = tmp_path / "d"
    d.mkdir()
    (d / "report.md").write_bytes(VICTIM)
    _no_plant_may_run(monkeypatch)
    rc, err = _validate(d, capsys)
    assert rc == EXIT_USAGE and len(err) == 1, err
    assert _tree(d) == {"report.md": VICTIM}


def test_users_directory_named_like_an_output_is_not_deleted(tmp_path):
    """A user's directory called report.md/ -> refused, it and its contents kept."""
    d = tmp_path / "d"
    (d / "report.md").mkdir(parents=True)
    (d / "report.md" / "chapter.txt").write_bytes(VICTIM)
    with pytest.raises(ValueError, match=r"report\.md"):
        _fake_run(d)
    assert _tree(d) == {"report.md": "dir", "report.md/chapter.txt": VICTIM}


def test_older_run_without_manifest_is_refused(tmp_path):
    """Only tumble's file names but no manifest -> refused, telling the user to remove it."""
    d = tmp_path / "d"
    d.mkdir()
    (d / "report.md").write_bytes(VICTIM)
    (d / "run.rrd").write_bytes(b"rrd")
    before = _tree(d)
    with pytest.raises(ValueError, match="remove it or choose another"):
        _fake_run(d)
    assert _tree(d) == before


def test_file_added_to_a_run_is_not_deleted(tmp_path):
    """A run directory the user added a hidden file to -> refused naming it; nothing deleted."""
    d = tmp_path / "d"
    _fake_run(d)
    (d / ".notes").write_bytes(VICTIM)
    before = _tree(d)
    with pytest.raises(ValueError, match=r"\.notes"):
        _fake_run(d)
    assert _tree(d) == before


def test_subdirectory_added_to_a_run_is_not_deleted(tmp_path):
    """A run directory the user added a subdirectory to -> refused; the subdirectory kept."""
    d = tmp_path / "d"
    _fake_run(d)
    (d / "mine").mkdir()
    (d / "mine" / "data.csv").write_bytes(VICTIM)
    before = _tree(d)
    with pytest.raises(ValueError, match="mine"):
        _fake_run(d)
    assert _tree(d) == before


def test_output_edited_after_the_run_is_not_replaced(tmp_path):
    """A run's report.md edited by the user (its hash no longer the manifest's) -> refused."""
    d = tmp_path / "d"
    _fake_run(d)
    (d / "report.md").write_bytes(b"# run\nmy notes on it\n")
    before = _tree(d)
    with pytest.raises(ValueError, match=r"report\.md"):
        _fake_run(d)
    assert _tree(d) == before


def test_listed_name_of_another_kind_is_not_replaced(tmp_path):
    """A name the manifest lists as a file is now the user's directory -> refused, kept."""
    d = tmp_path / "d"
    _fake_run(d)
    (d / "run.rrd").unlink()
    (d / "run.rrd").mkdir()
    (d / "run.rrd" / "keep.txt").write_bytes(VICTIM)
    before = _tree(d)
    with pytest.raises(ValueError, match=r"run\.rrd"):
        _fake_run(d)
    assert _tree(d) == before


def test_file_added_while_the_run_goes_on_is_kept(tmp_path):
    """The user saves a file into the run directory while a new run is writing -> the new run is
    not put in (one OutputError), the user's file and the previous run are kept."""
    d = tmp_path / "d"
    _fake_run(d, {"report.md": b"one"})
    with pytest.raises(OutputError, match="changed during the run"):
        with output_run(d, "test") as run:
            write_bytes(run.path / "report.md", b"two")
            (d / "notes.txt").write_bytes(VICTIM)
    assert (d / "notes.txt").read_bytes() == VICTIM and (d / "report.md").read_bytes() == b"one"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d"]


@pytest.mark.parametrize(
    "manifest",
    [
        b"{}",
        b"not json",
        json.dumps({"files": {"notes.txt": {}}}).encode(),
        json.dumps(
            {
                "schema": "tumble-manifest/1",
                "run_id": "../../x",
                "command": "validate",
                "state": "complete",
                "files": {"notes.txt": {"bytes": 0, "sha256": "0" * 64}},
            }
        ).encode(),
    ],
    ids=["empty", "garbage", "no-run-id", "bad-run-id"],
)
def test_forged_manifest_does_not_prove_ownership(tmp_path, manifest):
    """A manifest.json tumble did not write (wrong schema or run id) -> refused, all kept."""
    d = tmp_path / "d"
    d.mkdir()
    (d / MANIFEST).write_bytes(manifest)
    (d / "notes.txt").write_bytes(b"")
    before = _tree(d)
    with pytest.raises(ValueError, match=re.escape(MANIFEST)):
        _fake_run(d)
    assert _tree(d) == before


def test_manifest_that_is_a_symlink_does_not_prove_ownership(tmp_path):
    """manifest.json as a link to a real run's manifest -> refused, nothing followed or kept."""
    real = tmp_path / "real"
    _fake_run(real, {"report.md": b"x"})
    d = tmp_path / "d"
    d.mkdir()
    (d / "report.md").write_bytes(b"x")
    (d / MANIFEST).symlink_to(real / MANIFEST)
    before = _tree(d)
    with pytest.raises(ValueError, match=re.escape(MANIFEST)):
        _fake_run(d)
    assert _tree(d) == before


def test_target_symlink_to_a_directory_is_refused(tmp_path):
    """--out naming a symlink to a directory -> refused; the link and its directory unchanged."""
    real = tmp_path / "real"
    real.mkdir()
    (tmp_path / "o").symlink_to(real)
    with pytest.raises(ValueError, match="symbolic link"):
        _fake_run(tmp_path / "o")
    assert list(real.iterdir()) == [] and (tmp_path / "o").is_symlink()


def test_dangling_target_symlink_is_refused(tmp_path):
    """--out naming a dangling symlink -> refused; the link stays, nothing created."""
    (tmp_path / "o").symlink_to(tmp_path / "nowhere")
    with pytest.raises(ValueError, match="symbolic link"):
        _fake_run(tmp_path / "o")
    assert (tmp_path / "o").is_symlink() and not (tmp_path / "nowhere").exists()


def test_a_run_replaces_its_own_previous_run(tmp_path):
    """A directory holding a complete earlier run -> replaced whole by the new run."""
    d = tmp_path / "d"
    _fake_run(d, {"report.md": b"one", "tracking.png": b"png"})
    run = _fake_run(d, {"report.md": b"two"})
    assert sorted(p.name for p in d.iterdir()) == [MANIFEST, "report.md"]
    man = json.loads((d / MANIFEST).read_text())
    assert man["run_id"] == run.run_id
    assert man["files"]["report.md"]["sha256"] == hashlib.sha256(b"two").hexdigest()


# ---------------------------------------------------------------------------------------------
# Siblings: stale staging directories
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "name",
    [".o.backup.old", ".o.2024.partial", ".o.20000101T000000Z-deadbeef.partial"],
)
def test_user_directories_named_like_staging_are_kept(tmp_path, name):
    """A user's directory named like a staging sibling -> left alone, contents kept."""
    mine = tmp_path / name
    mine.mkdir()
    (mine / "keep.txt").write_bytes(VICTIM)
    _fake_run(tmp_path / "o")
    assert (mine / "keep.txt").read_bytes() == VICTIM


def test_symlink_named_like_staging_is_not_followed(tmp_path):
    """A symlink named like a stale staging sibling -> left alone; what it points to kept."""
    real = tmp_path / "real"
    real.mkdir()
    (real / "keep.txt").write_bytes(VICTIM)
    link = tmp_path / ".o.20000101T000000Z-deadbeef.partial"
    link.symlink_to(real)
    _fake_run(tmp_path / "o")
    assert link.is_symlink() and (real / "keep.txt").read_bytes() == VICTIM


_KILLED_RUN = """
import os, signal, sys
from validation.runs.atomic import write_bytes
from validation.runs.outputs import output_run
with output_run(sys.argv[1], "killed") as run:
    write_bytes(run.path / "run.rrd", b"half")
    os.kill(os.getpid(), signal.SIGKILL)
"""


def test_staging_left_by_a_killed_run_is_cleaned(tmp_path):
    """A run killed with SIGKILL mid-way -> its staging directory is removed by the next run,
    which commits normally."""
    out = tmp_path / "o"
    proc = subprocess.run([sys.executable, "-c", _KILLED_RUN, str(out)], check=False)
    assert proc.returncode == -signal.SIGKILL
    assert list(tmp_path.glob(".o.*.partial")), "the killed run left no staging directory"
    _fake_run(out)
    assert not list(tmp_path.glob(".o.*.partial")) and (out / MANIFEST).is_file()


# ---------------------------------------------------------------------------------------------
# Places a directory cannot be swapped: mount points, the working directory
# ---------------------------------------------------------------------------------------------


@pytest.fixture
def mount_point(tmp_path):
    """A tmpfs mounted at ``tmp_path/vol`` (skipped where mounting is not allowed)."""
    vol = tmp_path / "vol"
    vol.mkdir()
    r = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=20m", "tmpfs", str(vol)],
        capture_output=True,
        check=False,
    )
    if r.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {r.stderr.decode().strip()}")
    try:
        yield vol
    finally:
        subprocess.run(["umount", "-l", str(vol)], check=False)


def test_validate_into_a_mount_point(mount_point, capsys):
    """--out naming a mount point (a container volume) -> the whole run is put there, and a
    second run replaces it; nothing is left beside or inside but the run."""
    rc, err = _validate(mount_point, capsys)
    assert rc == 0, err
    man = json.loads((mount_point / MANIFEST).read_text())
    assert set(man["files"]) | {MANIFEST} == {p.name for p in mount_point.iterdir()}
    assert (mount_point / "run.rrd").stat().st_size == man["files"]["run.rrd"]["bytes"]
    run = _fake_run(mount_point, {"report.md": b"second"})
    assert sorted(p.name for p in mount_point.iterdir()) == [MANIFEST, "report.md"]
    assert json.loads((mount_point / MANIFEST).read_text())["run_id"] == run.run_id
    assert not [p for p in mount_point.parent.iterdir() if p.name.startswith(".vol")]


def test_foreign_mount_point_is_refused_before_the_run(mount_point, capsys, monkeypatch):
    """A mount point holding the user's files -> refused in one line before any plant runs."""
    (mount_point / "data.csv").write_bytes(VICTIM)
    _no_plant_may_run(monkeypatch)
    rc, err = _validate(mount_point, capsys)
    assert rc == EXIT_USAGE and len(err) == 1 and "data.csv" in err[0], err
    assert _tree(mount_point) == {"data.csv": VICTIM}


def test_mount_point_found_without_mounting(tmp_path, monkeypatch):
    """A directory seen as a mount point (simulated) -> files committed by per-file renames into
    the same directory inode, the manifest last."""
    out = tmp_path / "o"
    out.mkdir()
    inode = out.stat().st_ino
    monkeypatch.setattr(outputs_mod, "_is_mount_point", lambda p: Path(p) == out)
    _fake_run(out, {"report.md": b"one", "x.png": b"png"})
    _fake_run(out, {"report.md": b"two"})
    assert out.stat().st_ino == inode
    assert sorted(p.name for p in out.iterdir()) == [MANIFEST, "report.md"]
    assert (out / "report.md").read_bytes() == b"two"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["o"]


def test_lost_and_found_of_a_mounted_filesystem_is_left_alone(tmp_path, monkeypatch):
    """A mount point holding only the filesystem's lost+found -> the run goes in beside it, and
    lost+found and its contents are kept through a second run."""
    out = tmp_path / "o"
    (out / "lost+found").mkdir(parents=True)
    (out / "lost+found" / "#1234").write_bytes(VICTIM)
    monkeypatch.setattr(outputs_mod, "_is_mount_point", lambda p: Path(p) == out)
    _fake_run(out, {"report.md": b"one"})
    _fake_run(out, {"report.md": b"two"})
    assert sorted(p.name for p in out.iterdir()) == ["lost+found", MANIFEST, "report.md"]
    assert (out / "lost+found" / "#1234").read_bytes() == VICTIM


def test_rename_refused_with_ebusy_falls_back_to_per_file(tmp_path, monkeypatch):
    """The directory swap refused with EBUSY (a mount point not found up front) -> the run is
    still put there, file by file; the previous run's files are replaced."""
    out = tmp_path / "o"
    _fake_run(out, {"report.md": b"one", "x.png": b"png"})

    def busy(a, b):
        raise OSError(errno.EBUSY, os.strerror(errno.EBUSY), str(b))

    monkeypatch.setattr(outputs_mod, "_renameat2_exchange", busy)
    _fake_run(out, {"report.md": b"two"})
    assert sorted(p.name for p in out.iterdir()) == [MANIFEST, "report.md"]
    assert (out / "report.md").read_bytes() == b"two"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["o"]


def test_full_disk_while_copying_into_a_mount_point_keeps_the_previous_run(tmp_path, monkeypatch):
    """ENOSPC while the files are copied onto a mounted filesystem -> one OutputError, the
    previous run there byte for byte, no temporary file left."""
    out = tmp_path / "o"
    monkeypatch.setattr(outputs_mod, "_is_mount_point", lambda p: Path(p) == out)
    out.mkdir()
    _fake_run(out, {"report.md": b"one", "run.rrd": b"rrd one"})
    before = _tree(out)
    real_rename, real_write = outputs_mod._rename_noreplace, os.write

    def across_filesystems(a, b):
        if Path(b).parent == out:
            raise OSError(errno.EXDEV, os.strerror(errno.EXDEV), str(b))
        return real_rename(a, b)

    def full(fd, data):
        if Path(os.readlink(f"/proc/self/fd/{fd}")).parent == out:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real_write(fd, data)

    monkeypatch.setattr(outputs_mod, "_rename_noreplace", across_filesystems)
    monkeypatch.setattr(os, "write", full)
    with pytest.raises(OutputError, match="No space left on device") as info:
        _fake_run(out, {"report.md": b"two", "run.rrd": b"rrd two"})
    monkeypatch.undo()
    assert "\n" not in str(info.value) and "unchanged" in str(info.value)
    assert _tree(out) == before


def test_out_dot_keeps_the_working_directory(tmp_path, capsys, monkeypatch):
    """--out . from an empty working directory -> the files land in it; the shell's directory is
    the same directory afterwards (not swapped away and deleted)."""
    cwd = tmp_path / "here"
    cwd.mkdir()
    monkeypatch.chdir(cwd)
    inode = os.stat(".").st_ino
    rc, err = _validate(Path("."), capsys)
    assert rc == 0, err
    assert os.stat(".").st_ino == inode and os.stat(cwd).st_ino == inode
    assert (cwd / MANIFEST).is_file() and (cwd / "report.md").is_file()
    _fake_run(Path("."), {"report.md": b"again"})
    assert os.stat(cwd).st_ino == inode and (cwd / "report.md").read_bytes() == b"again"


def test_ancestor_of_the_working_directory_is_refused(tmp_path, monkeypatch):
    """--out naming a directory that holds the working directory -> refused, nothing moved."""
    cwd = tmp_path / "top" / "sub"
    cwd.mkdir(parents=True)
    monkeypatch.chdir(cwd)
    with pytest.raises(ValueError, match="working directory"):
        _fake_run(Path(".."))
    assert Path.cwd() == cwd and os.path.isdir(cwd)


# ---------------------------------------------------------------------------------------------
# Single files (atomic writes)
# ---------------------------------------------------------------------------------------------


def test_atomic_write_over_a_symlink_does_not_write_through(tmp_path):
    """A file path that is a symlink to a user's file -> refused; the linked file unchanged."""
    victim = tmp_path / "victim.txt"
    victim.write_bytes(VICTIM)
    (tmp_path / "f.md").symlink_to(victim)
    with pytest.raises(OutputError, match="symbolic link"):
        write_text(tmp_path / "f.md", "new")
    assert victim.read_bytes() == VICTIM and (tmp_path / "f.md").is_symlink()


def test_atomic_write_to_a_device_writes_into_it(tmp_path):
    """A file path that is a character device (like /dev/null) -> written into, never replaced
    by a regular file."""
    dev = tmp_path / "null"
    try:
        os.mknod(dev, 0o666 | 0o020000, os.makedev(1, 3))
    except OSError as exc:
        pytest.skip(f"cannot create a device node here: {exc}")
    write_text(dev, "discarded")
    assert dev.is_char_device()


def test_atomic_write_to_a_fifo_does_not_block(tmp_path):
    """A file path that is a FIFO nobody reads -> an OutputError at once, no hang."""
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    with pytest.raises(OutputError):
        write_text(fifo, "x")
    assert fifo.is_fifo()
