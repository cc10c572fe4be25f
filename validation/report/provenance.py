"""Where a JSON output came from, and how it is written: the block every machine-read file carries
(``report.json``, ``sweep.json``, ``hard_cases.json``, ``bench.json``) and the one encoder for them.

* :func:`provenance` returns the block (the file's ``"provenance"`` key): the file's kind and schema
  version, the project version, the commit of the code that ran (:func:`code_origin`), a UTC
  timestamp, the command line, the resolved scene and the versions of the libraries that produce
  the numbers.

Which code ran (:func:`code_origin`): an installed package knows the commit it was built from
(``validation/_version.py``, written by setuptools-scm when the wheel is built from a git checkout;
not in the repository); a package imported from a git checkout (an editable install, or run from
the checkout) is that checkout's ``HEAD``. Separately, the block records the tumbling-testbed
checkout the command runs in (the working directory), so that a run of an installed package
inside a checkout at another commit says both.
* :func:`dumps` writes a document as JSON text: NaN and infinities become ``null``, numpy scalars and
  arrays become numbers and lists, enums their value, paths strings; a placeholder string (``"nan"``,
  ``"inf"``, ``"<2001 values>"``, ...) or an object of unknown type is refused with a ``ValueError``
  naming where it is in the document.

The schemas of the four files are ``validation/report/schemas/<kind>.schema.json`` (JSON Schema draft
2020-12, :func:`schema_path`), documented in ``docs/json-output.md``. A file kind's schema version
(:data:`SCHEMA_VERSIONS`) goes up when a field is removed, renamed or changes meaning or unit; added
fields keep it.

Nothing here imports numpy, the engines or the plotting libraries (versions are read with
:mod:`importlib.metadata`), so writing the block costs a few ``git`` calls at most.
"""

from __future__ import annotations

import enum
import importlib
import json
import math
import re
import subprocess
import sys
from collections.abc import Mapping
from dataclasses import dataclass
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
    BENCH = "bench"  # tumble bench --out / python -m validation.bench.command --out: bench.json
    CAMPAIGN = "campaign"  # tumble fuzz: OUT/campaign.json


SCHEMA_VERSIONS: dict[FileKind, int] = {
    FileKind.REPORT: 2,  # 2: provenance.scene in the scene file's conventions (scene.toml's tables)
    FileKind.SWEEP: 2,  # 2: the same
    FileKind.HARD_CASES: 1,
    FileKind.BENCH: 1,
    FileKind.CAMPAIGN: 1,
}
"""The schema version of each file kind (the ``const`` of ``provenance.schema_version`` in its
schema; tests/validation/report/test_provenance.py checks both agree)."""


def schema_path(kind: FileKind | str) -> Path:
    """The JSON Schema of a file kind, ``validation/report/schemas/<kind>.schema.json``."""
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


PACKAGE_ROOT = Path(__file__).resolve().parents[2]
"""The directory holding the project's packages (a checkout's top, or ``site-packages``)."""

_COMMIT = re.compile(r"[0-9a-f]{7,64}")


def _git(root: Path, args: list[str], timeout: float) -> subprocess.CompletedProcess | None:
    """``git -C root <args>``, or None when git is missing, slow or cannot start."""
    try:
        return subprocess.run(
            ["git", "-C", str(root), *args],
            capture_output=True,
            text=True,
            timeout=timeout,
            check=False,
        )
    except (OSError, ValueError, subprocess.SubprocessError):
        return None


def _toplevel_and_head(root: Path, timeout: float) -> tuple[Path, str] | None:
    done = _git(root, ["rev-parse", "--show-toplevel", "HEAD"], timeout)
    if done is None or done.returncode != 0:
        return None
    lines = done.stdout.split()
    if len(lines) != 2 or not re.fullmatch(r"[0-9a-f]{40,64}", lines[1]):
        return None
    return Path(lines[0]).resolve(), lines[1]


def git_commit(root: Path | None = None, timeout: float = GIT_TIMEOUT_S) -> str | None:
    """The commit checked out at ``root`` (default: the directory holding the project's packages),
    or None: not a git checkout, ``root`` inside some other repository (an installed copy in a
    user's project), ``git`` missing, slow or failing. Never raises."""
    root = PACKAGE_ROOT if root is None else Path(root)
    found = _toplevel_and_head(root, timeout)
    if found is None or found[0] != root.resolve():
        return None
    return found[1]


def is_dirty(root: Path, timeout: float = GIT_TIMEOUT_S) -> bool | None:
    """Whether the checkout at ``root`` has uncommitted changes to tracked files (None: unknown)."""
    done = _git(root, ["status", "--porcelain", "--untracked-files=no"], timeout)
    if done is None or done.returncode != 0:
        return None
    return bool(done.stdout.strip())


def _is_project_checkout(top: Path) -> bool:
    """Whether the checkout at ``top`` is tumbling-testbed's (its pyproject names the project and
    it holds this module), not a user's project that happens to use the package."""
    try:
        text = (top / "pyproject.toml").read_text(encoding="utf-8")
    except OSError:
        return False
    return f'name = "{DISTRIBUTION}"' in text and (top / "validation" / "provenance.py").is_file()


def working_checkout(
    cwd: Path | None = None, timeout: float = GIT_TIMEOUT_S
) -> tuple[Path, str] | None:
    """The tumbling-testbed git checkout holding the working directory ``cwd`` (default: the
    process's): its top directory and ``HEAD`` commit, or None (not in a checkout, or a checkout
    of another project)."""
    found = _toplevel_and_head(Path.cwd() if cwd is None else Path(cwd), timeout)
    if found is None or not _is_project_checkout(found[0]):
        return None
    return found


@dataclass(frozen=True)
class BuildInfo:
    """What the build wrote into the package (``validation/_version.py``, setuptools-scm).

    Attributes:
        version: the version it computed (``0.1.1.dev12+g1a2b3c4``).
        commit: the commit built from, hex (abbreviated or full), or None (built from no git
            checkout).
        dirty: whether that checkout had uncommitted changes (None: unknown).
    """

    version: str
    commit: str | None
    dirty: bool | None


def parse_build_node(node: Any) -> str | None:
    """A setuptools-scm node (``g1a2b3c4``, a full hash, None) as a bare hex commit, or None."""
    if not isinstance(node, str):
        return None
    node = node.removeprefix("g").lower()
    return node if _COMMIT.fullmatch(node) else None


def build_info() -> BuildInfo | None:
    """The package's build record, or None when the package was never built by setuptools-scm
    (run from a checkout that was never installed, or an install before the record existed)."""
    try:  # written at build time, not in the repository; looked up in sys.modules first
        _version = importlib.import_module("validation._version")
    except ImportError:
        return None
    dirty = getattr(_version, "build_dirty", None)
    return BuildInfo(
        version=str(getattr(_version, "version", "")),
        commit=parse_build_node(getattr(_version, "build_node", None)),
        dirty=dirty if isinstance(dirty, bool) else None,
    )


def same_commit(a: str | None, b: str | None) -> bool:
    """Whether two commits (full or abbreviated, at least 7 hex digits) name the same one."""
    if not a or not b:
        return False
    n = min(len(a), len(b))
    return a[:n] == b[:n]


class CodeSource(enum.StrEnum):
    """Where the running packages were imported from."""

    CHECKOUT = "checkout"  # a git checkout of the project (editable install, or run from it)
    INSTALLED = "installed"  # an installed copy (site-packages), identified by its build record
    UNIDENTIFIED = "unidentified"  # neither: an install without a build record, no git


@dataclass(frozen=True)
class CodeOrigin:
    """Which code ran, and where (the block's code fields; ``docs/json-output.md``).

    Attributes:
        source: where the packages were imported from.
        commit: the commit of the code that ran: the checkout's ``HEAD`` (CHECKOUT) or the commit
            the package was built from (INSTALLED); None when unknown.
        dirty: uncommitted changes in that code (None: unknown).
        build: the package's build record (None: none).
        working_checkout: ``HEAD`` of the tumbling-testbed checkout the command runs in (the
            working directory); None when it runs in none.
    """

    source: CodeSource
    commit: str | None
    dirty: bool | None
    build: BuildInfo | None
    working_checkout: str | None

    @property
    def differs(self) -> bool:
        """The command runs in a checkout at another commit than the code that ran."""
        return self.working_checkout is not None and not same_commit(
            self.commit, self.working_checkout
        )

    def sentence(self) -> str:
        """The origin in words, for ``report.md``: the commit and where it comes from, and the
        working checkout's commit when it differs."""
        if self.commit is None:
            text = "Code: commit unknown (an installed package without a build record)"
        elif self.source is CodeSource.CHECKOUT:
            text = f"Code: the checkout at commit {self.commit}"
        else:
            text = f"Code: the installed package built from commit {self.commit}"
        if self.dirty:
            text += ", with uncommitted changes"
        if self.differs:
            text += (
                f". The command ran in a checkout at another commit, {self.working_checkout}: "
                "the results are those of the code named first"
            )
        return text + "."


def code_origin(timeout: float = GIT_TIMEOUT_S) -> CodeOrigin:
    """Which code is running (:class:`CodeOrigin`). Never raises."""
    build = build_info()
    here = git_commit(PACKAGE_ROOT, timeout)
    work = working_checkout(timeout=timeout)
    work_commit = work[1] if work else None
    if here is not None:
        return CodeOrigin(
            CodeSource.CHECKOUT, here, is_dirty(PACKAGE_ROOT, timeout), build, work_commit
        )
    if build is not None and build.commit is not None:
        return CodeOrigin(CodeSource.INSTALLED, build.commit, build.dirty, build, work_commit)
    return CodeOrigin(CodeSource.UNIDENTIFIED, None, None, build, work_commit)


def utc_now() -> str:
    """The current UTC time, ISO 8601 with an explicit offset (``2026-01-31T12:00:00.123456+00:00``)."""
    return datetime.now(UTC).isoformat()


def provenance(
    kind: FileKind | str,
    scene: Any = None,
    argv: list[str] | None = None,
    origin: CodeOrigin | None = None,
) -> dict[str, Any]:
    """The block a machine-read file carries under its ``"provenance"`` key.

    Args:
        kind: the file's kind (:class:`FileKind` or its value); a ``ValueError`` names an unknown one.
        scene: the resolved :class:`~analytic.scene.Scene` the file is about (dumped whole by
            :func:`analytic.scene.dump.scene_to_dict`), or None when the file covers several
            scenes or none (``hard_cases.json``, ``bench.json``).
        argv: the command line (default ``sys.argv``).
        origin: which code ran (default: :func:`code_origin`, found now).

    Returns:
        ``{"kind", "schema_version", "project_version", "git_commit", "code_source",
        "code_dirty", "build_commit", "working_checkout_commit", "created_utc", "command",
        "scene", "versions"}``; see ``docs/json-output.md`` for each field.
    """
    try:
        kind = FileKind(kind)
    except ValueError:
        known = ", ".join(k.value for k in FileKind)
        raise ValueError(f"kind: unknown file kind {kind!r} (known: {known})") from None
    origin = code_origin() if origin is None else origin
    dumped = None
    if scene is not None:
        # deferred: numpy ~80 ms (python -X importtime); this module is standard library only
        from analytic.scene.dump import scene_to_dict

        dumped = scene_to_dict(scene)
    return {
        "kind": kind.value,
        "schema_version": SCHEMA_VERSIONS[kind],
        "project_version": project_version(),
        "git_commit": origin.commit,
        "code_source": origin.source.value,
        "code_dirty": origin.dirty,
        "build_commit": origin.build.commit if origin.build else None,
        "working_checkout_commit": origin.working_checkout,
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
    "BuildInfo",
    "CodeOrigin",
    "CodeSource",
    "FileKind",
    "PlaceholderError",
    "build_info",
    "code_origin",
    "dumps",
    "git_commit",
    "library_versions",
    "project_version",
    "provenance",
    "schema_path",
    "to_json_value",
]
