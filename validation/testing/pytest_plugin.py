"""The pytest plugin: scene files become tests, one test item per agreement check.

Registered as the ``pytest11`` entry point ``tumble`` (``pip install tumbling-testbed``). It does
nothing until a scene is collected:

* a file ``test_*.toml`` with a ``[scene]`` table, or any ``.toml`` file matching a glob of the ini
  option ``tumble_scenes``, is a scene file (every other ``.toml`` is left alone);
* each scene runs once per session on the plants of ``--tumble-plants`` (default every installed
  plant), and each of its checks is one item, ``test_slosh.toml::position_C``,
  ``test_slosh.toml::mujoco.energy``, ..., plus ``test_slosh.toml::run`` (the run itself: no plant
  failed, the report was written); every item carries the marker ``tumble``;
* runs are cached for the session by scene content and plant settings; under pytest-xdist the
  items of a scene carry ``xdist_group(<scene file>)`` (``--dist loadgroup`` sends a scene's items
  to one worker) and a run is shared between workers through the session's temporary directory
  under a file lock, so a scene never runs twice whatever the distribution mode;
* output goes to a temporary directory, or with ``--tumble-out DIR`` to ``DIR/<slug of the scene
  file's path>`` (the report, ``report.json``, figures and ``run.rrd``: CI artefacts).
* a ``test_*.toml`` with a ``[judge]`` table instead (:mod:`validation.external.spec_file`: a scene,
  a trajectory file beside it, optionally a label, plants or a reference pack) judges another
  engine's run (:class:`JudgeFile`): the judge's checks are its items, each check the file cannot
  support skipped as ``not judged: no ... columns``.

This module holds the hooks, the items and the fixture; the session's runs (the cache, the
sharing between xdist workers) are :mod:`validation.testing.session_runs`. It imports pytest and
the standard library only; the plants, numpy and MuJoCo are imported when the first scene file is
collected. Loading the plugin changes nothing in the session's process (no environment variable,
no thread pool); a scene's run has BLAS on one thread for the run only
(:func:`validation.runs.environment.one_blas_thread`), the pools given back as they were.
``python -m validation.testing.pytest_plugin --bench`` measures the plugin's cost on a pytest run
that collects no scene (:mod:`validation.testing.plugin_bench`).
"""

from __future__ import annotations

import fnmatch
import itertools
import os
import re
import secrets
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from validation.testing.session_runs import SHARE_KEY, SessionRuns, read_head

MARKER = "tumble"
RUN_ITEM = "run"
_SCENE_TABLE = re.compile(rb"^[ \t]*\[[ \t]*scene[ \t]*\][ \t]*(#.*)?\r?$", re.MULTILINE)
_JUDGE_TABLE = re.compile(rb"^[ \t]*\[[ \t]*judge[ \t]*\][ \t]*(#.*)?\r?$", re.MULTILINE)

RUNS: list[str] = []
"""Scene runs made by this process (one cache key each, in order): what tests count."""


# ----------------------------------------------------------------------------------------------
# Options
# ----------------------------------------------------------------------------------------------


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("tumble", "tumbling-testbed agreement checks (scene files as tests)")
    group.addoption(
        "--tumble-plants",
        default=None,
        metavar="PLANTS",
        help="plants to run each scene file on, e.g. 'analytic,mujoco' (default: every installed "
        "plant; at least two)",
    )
    group.addoption(
        "--tumble-out",
        default=None,
        metavar="DIR",
        help="keep each scene's report and recording in DIR/<scene file> (default: a temporary "
        "directory)",
    )
    parser.addini(
        "tumble_scenes",
        type="linelist",
        default=[],
        help="globs of further scene files to collect (relative to the rootdir), besides "
        "test_*.toml files with a [scene] table",
    )


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", f"{MARKER}: an agreement check of a scene file (tumbling-testbed)"
    )
    if not config.pluginmanager.hasplugin("xdist"):  # keep --strict-markers happy without xdist
        config.addinivalue_line("markers", "xdist_group(name): run in one pytest-xdist worker")
    config.stash[_SESSION] = SessionRuns(config, RUNS)


# ----------------------------------------------------------------------------------------------
# Collection
# ----------------------------------------------------------------------------------------------


def _matches_ini(config: pytest.Config, path: Path) -> bool:
    globs = config.getini("tumble_scenes")
    if not globs:
        return False
    root = Path(config.rootpath)
    try:
        rel = path.resolve().relative_to(root.resolve()).as_posix()
    except ValueError:
        rel = None
    for g in globs:
        g = g.strip()
        if not g:
            continue
        if fnmatch.fnmatch(path.as_posix(), g) or (rel is not None and fnmatch.fnmatch(rel, g)):
            return True
    return False


def pytest_collect_file(file_path: Path, parent: pytest.Collector) -> SceneFile | None:
    """A scene file (a ``[scene]`` table) or a judge file (a ``[judge]`` table: another engine's
    trajectory file judged, :class:`JudgeFile`)."""
    if file_path.suffix != ".toml":
        return None
    named = file_path.name.startswith("test_")
    listed = _matches_ini(parent.config, file_path)
    if not (named or listed):
        return None
    if named and not listed:
        try:
            head = read_head(file_path, 1 << 20)
        except OSError:  # also a FIFO or device named test_*.toml: never opened to block
            return None
        if not _SCENE_TABLE.search(head):
            if _JUDGE_TABLE.search(head):
                return JudgeFile.from_parent(parent, path=file_path)
            return None  # a test_*.toml that is not a scene: not ours
    return SceneFile.from_parent(parent, path=file_path)


@pytest.hookimpl(optionalhook=True)
def pytest_configure_node(node: Any) -> None:
    """pytest-xdist, in the controller: every worker of this session gets one random secret, with
    which the runs they share are signed (:mod:`validation.testing.session_runs`)."""
    key = node.config.stash.get(_SHARE_SECRET, None)
    if key is None:
        key = node.config.stash[_SHARE_SECRET] = secrets.token_hex(32)
    node.workerinput[SHARE_KEY] = key


_SHARE_SECRET = pytest.StashKey[str]()


class SceneFile(pytest.File):
    """A scene file: its checks are the items. A bad scene is one collection error naming the
    field (the loader's one-line ``ValueError``)."""

    labels: tuple[str, ...] = ()

    def collect(self) -> Iterator[pytest.Item]:
        sess = self.config.stash[_SESSION]
        try:
            plants = sess.plants()
            # deferred: numpy, the scenes, the plants: ~80 ms (python -X importtime)
            from validation.scenes import resolve_scene

            scene = resolve_scene(str(self.path))
            labels = expected_labels(scene, plants)
        except ValueError as exc:
            raise self.CollectError(f"{self.path.name}: {exc}") from None
        yield from self._items(labels)

    def _items(self, labels: list[str]) -> Iterator[pytest.Item]:
        self.labels = tuple(labels)
        group = pytest.mark.xdist_group(self.nodeid)
        for label in [*labels, RUN_ITEM]:
            item = CheckItem.from_parent(self, name=label)
            item.add_marker(MARKER)
            item.add_marker(group)
            yield item

    def outcome(self) -> Any:
        """This file's run (ValidationResult, or the one-line reason it could not run)."""
        return self.config.stash[_SESSION].outcome(self.path)


class JudgeFile(SceneFile):
    """A ``test_*.toml`` with a ``[judge]`` table (:mod:`validation.external.spec_file`): another
    engine's trajectory file of a scene, judged (:func:`validation.external.judge.judge`); the
    judge's checks are the items, a check the file cannot support skipped as ``not judged``. A
    bad table or path is one collection error naming the key."""

    spec: Any = None

    def collect(self) -> Iterator[pytest.Item]:
        sess = self.config.stash[_SESSION]
        try:
            # deferred: numpy, the scenes, the plants (as for a scene file)
            from validation.external.judge import REFERENCE_PLANT, plant_label
            from validation.external.spec_file import parse_spec
            from validation.scenes import builtin_names, resolve_scene

            spec = parse_spec(read_head(self.path, 1 << 20), self.path.parent, builtin_names())
            scene = resolve_scene(str(spec.scene))
            if spec.t_end is not None:  # the horizon judged: in the scene's, on its grid
                from validation.external.horizon import horizon_on_grid

                horizon_on_grid(scene, spec.t_end, "judge.t_end")
            if spec.reference is not None:
                plants: tuple[str, ...] = (REFERENCE_PLANT,)
            elif spec.plants is not None:
                from mj_bridge.plants import parse_plants

                plants = tuple(parse_plants(spec.plants))
            else:
                plants = sess.plants()
            label = plant_label(spec.label, spec.trajectory, plants)
            labels = expected_labels(scene, (*plants, label))
        except (ValueError, OSError) as exc:
            raise self.CollectError(f"{self.path.name}: {exc}") from None
        self.spec = spec
        yield from self._items(labels)

    def outcome(self) -> Any:
        return self.config.stash[_SESSION].judged(self.path, self.spec)


class CheckFailed(Exception):
    """A check of a scene file failed: ``args[0]`` is the row to print."""


class CheckItem(pytest.Item):
    """One agreement check of a scene file, read from the session's (cached) run."""

    parent: SceneFile

    def runtest(self) -> None:
        outcome = self.parent.outcome()
        if isinstance(outcome, str):
            raise CheckFailed(f"the scene could not run: {outcome}")
        # deferred: ~2.5 ms (python -X importtime) in every pytest session; only with scene files
        from validation.testing.agree import describe_check

        result = outcome
        where = f"report: {result.files.get('report.md', result.out_dir)}"
        if self.name == RUN_ITEM:
            expected = set(self.parent.labels)
            extra = [c for c in result.failed_checks if c.label not in expected]
            problems = [f"run failed: {result.failure}"] if result.failure else []
            problems += [describe_check(c, result) for c in extra]
            if problems:
                raise CheckFailed("\n".join([*problems, where]))
            return
        by = {c.label: c for c in result.checks}
        check = by.get(self.name)
        if check is None:
            why = f" ({result.failure})" if result.failure else ""
            raise CheckFailed(f"{self.name}: the run made no such check{why}\n{where}")
        if not check.applicable:  # nothing to compare (no control torque in either plant)
            pytest.skip(f"{self.name}: not applicable ({check.reason})")
        if not check.passed:
            raise CheckFailed(f"{describe_check(check, result)}\n  {where}")

    def repr_failure(self, excinfo: pytest.ExceptionInfo[BaseException], style: Any = None) -> Any:
        if isinstance(excinfo.value, CheckFailed):
            return str(excinfo.value.args[0])
        return super().repr_failure(excinfo, style=style)

    def reportinfo(self) -> tuple[Path, int | None, str]:
        return self.path, None, f"{self.path.name}::{self.name}"


def expected_labels(scene: Any, plants: tuple[str, ...]) -> list[str]:
    """The labels of the checks :func:`validation.validate.run_validation` makes for ``scene`` on
    ``plants`` (report order), known before it runs: what the items are named."""
    from analytic.effects import Effect
    from validation.compare.checks import Subject
    from validation.testing.agree import PAIR_CHECKS

    def own(p: str) -> list[str]:
        names = []
        if scene.has(Effect.CONTROL_OMEGA) and scene.control.omega is not None:
            if len(scene.control.omega.components):
                names.append("tracking_omega")
        if scene.has(Effect.CONTROL_MASSES) and scene.control.masses is not None:
            if len(scene.control.masses.indices):
                names.append("tracking_p")
        names += ["quat_norm", "linear_momentum", "angular_momentum", "energy"]
        return [f"{p}.{n}" for n in names]

    def pair(a: str, b: str) -> list[str]:
        s = Subject.pair(a, b)
        names = [n for n in PAIR_CHECKS if n != "rod_forces" or scene.n]
        return [n if s == Subject.BOTH else f"{s.slug}.{n}" for n in names]

    out = [f"{p}.completed" for p in plants[:2]]
    if len(plants) > 1:
        out += pair(plants[0], plants[1])
    out += [x for p in plants[:2] for x in own(p)]
    for i, j in itertools.combinations(range(len(plants)), 2):
        if (i, j) == (0, 1):
            continue
        out += pair(plants[i], plants[j])
        if i == 0:
            out += [f"{plants[j]}.completed", *own(plants[j])]
    return out


_SESSION = pytest.StashKey[SessionRuns]()


@pytest.fixture
def tumble_validation(request: pytest.FixtureRequest) -> Callable[..., Any]:
    """A function ``(scene, plants=None, t_end=None) -> ValidationResult``: the session's cached
    run of ``scene`` (a scene file, a built-in name or a Scene) on ``plants`` (default
    ``--tumble-plants``, else every installed plant). A scene file that is also collected as test
    items shares their run."""
    sess = request.config.stash[_SESSION]

    def get(scene: Any, plants: Any = None, t_end: float | None = None) -> Any:
        from validation.scenes import scene_path
        from validation.testing.agree import load

        if plants is None:
            chosen = sess.plants()
        else:
            from mj_bridge.plants import parse_plants

            text = plants if isinstance(plants, str) else ",".join(map(str, plants))
            chosen = tuple(parse_plants(text))
        if isinstance(scene, str | os.PathLike):
            path = scene_path(os.fspath(scene))
            sc = load(path) if t_end is not None else None
            res = sess.run(path.read_bytes(), chosen, t_end, path=path, scene=sc)
        else:
            sc = load(scene)
            sess.keep.append(sc)  # cached for this object: its id stays its own
            content = f"Scene object {id(sc)}".encode()
            res = sess.run(content, chosen, t_end, path=None, scene=sc, label=sc.name)
        if isinstance(res, str):
            raise ValueError(res)
        return res

    return get


if __name__ == "__main__":  # pragma: no cover
    if "--bench" in sys.argv[1:]:
        from validation.testing.plugin_bench import bench

        bench()
    else:
        print("usage: python -m validation.testing.pytest_plugin --bench")


__all__ = [
    "MARKER",
    "RUNS",
    "CheckItem",
    "JudgeFile",
    "SceneFile",
    "expected_labels",
    "tumble_validation",
]
