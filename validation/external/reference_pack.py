"""Reference packs: what an engineer needs to test an engine in any language against a scene.

``tumble reference SCENE --out DIR`` (:func:`write_pack`) writes, in one output set
(:func:`validation.runs.outputs.output_run`):

* ``scene.toml``: the scene (:func:`analytic.scene.dump.scene_to_toml`), which loads back equal;
* ``reference.csv``: the analytic plant's run at :data:`REFERENCE_SETTINGS` in the trajectory
  format (``docs/trajectory-format.md``), every column: the motion, the velocities, the
  controller's outputs along it (``tau``, ``F``) and the work and impulse integrals;
* ``reference.json``: the settings, the SHA-256 of the two files above, and the reference's own
  error estimated by self-convergence: each difference quantity of the comparison between the
  reference and a run at :data:`CHECK_SETTINGS` (ten times tighter), beside its threshold; the
  estimate must be at most :data:`ACCURACY_MARGIN` × the threshold, and the pack says so when
  it is not (``accurate_enough``);
* ``README.md``: the problem, the controller's equations (for a controlled scene, with the paper's
  equation numbers), the error definitions and the acceptance thresholds
  (:mod:`validation.external.pack_readme`).

:func:`read_pack` reads a pack back for ``tumble judge --reference DIR``: the three files at their
fixed names in ``DIR`` (regular files, not links; nothing in the pack names a path), the pack's
scene compared with the scene judged (its horizon aside: a pack judges any horizon up to its own),
the CSV's SHA-256 with the one ``reference.json`` records. A pack whose ``reference.json`` does not
say ``accurate_enough = true`` is refused: a judge against it would not be a judge.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import stat
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from analytic.effects import SolverMethod
from analytic.plant import AnalyticSettings
from analytic.runtime.safe_files import read_regular
from analytic.scene import Scene, load_scene
from analytic.scene.dump import scene_to_dict, scene_to_toml
from analytic.trajectory import RunStatus
from mj_bridge.plants import plant
from validation.compare.checks import compare
from validation.compare.thresholds import thresholds_for
from validation.external.columns import OPTIONAL_GROUPS
from validation.external.pack_readme import render_readme
from validation.external.read import read_trajectory, size_limit
from validation.external.record import ExternalTrajectory
from validation.external.write import write_trajectory
from validation.runs.atomic import write_text
from validation.runs.outputs import output_run
from validation.runs.progress import RunsProgress
from validation.scenes import resolve_scene

SCENE_FILE = "scene.toml"
TRAJECTORY_FILE = "reference.csv"
RECORD_FILE = "reference.json"
README_FILE = "README.md"
PACK_FORMAT = 1
"""The version of the pack's layout (``reference.json``'s ``pack_format``)."""
REFERENCE_PLANT = "reference"
"""The plant name of a pack's trajectory when a file is judged against it."""

REFERENCE_SETTINGS = AnalyticSettings(SolverMethod.DOP853, rtol=1e-13, atol=1e-14)
"""The reference run: DOP853 (the compiled stepper where it applies) at rtol 1e-13, atol 1e-14,
a decade tighter than the scenes' own 1e-12 / 1e-13."""
CHECK_SETTINGS = AnalyticSettings(SolverMethod.DOP853, rtol=1e-14, atol=1e-15)
"""The self-convergence run the reference's error is estimated against (ten times tighter)."""
ACCURACY_MARGIN = 1e-2
"""The reference's estimated error must be at most this fraction of every threshold it judges, so
an engine's difference from it is its own error to within 1 %."""
RECORD_LIMIT = 1 << 20
"""Largest ``reference.json`` and ``scene.toml`` read back, bytes."""


@dataclass(frozen=True)
class Accuracy:
    """The reference's estimated error in one difference quantity.

    Attributes:
        quantity: the threshold's name (``position_C``).
        estimate: the largest difference between the reference and the tighter run, in the
            threshold's unit (relative for the forces), NaN when the quantity does not apply.
        threshold: the acceptance threshold in force.
        unit: the unit of both.
    """

    quantity: str
    estimate: float
    threshold: float
    unit: str

    @property
    def ok(self) -> bool:
        """Not applicable, or at most :data:`ACCURACY_MARGIN` × the threshold."""
        return math.isnan(self.estimate) or self.estimate <= ACCURACY_MARGIN * self.threshold

    def to_dict(self) -> dict[str, Any]:
        return {
            "quantity": self.quantity,
            "estimate": None if math.isnan(self.estimate) else self.estimate,
            "threshold": self.threshold,
            "unit": self.unit,
            "ratio": None if math.isnan(self.estimate) else self.estimate / self.threshold,
            "ok": self.ok,
        }


@dataclass(frozen=True)
class PackResult:
    """What :func:`write_pack` wrote.

    Attributes:
        out_dir: the pack's directory.
        files: name -> path of every file of the pack.
        accuracy: the reference's estimated error per difference quantity.
    """

    out_dir: Path
    files: Mapping[str, Path]
    accuracy: tuple[Accuracy, ...]

    @property
    def accurate_enough(self) -> bool:
        return all(a.ok for a in self.accuracy)


def _settings_dict(s: AnalyticSettings) -> dict[str, Any]:
    return {"method": s.method.value, "rtol": s.rtol, "atol": s.atol}


def estimate_accuracy(scene: Scene) -> tuple[Any, tuple[Accuracy, ...]]:
    """The reference run of ``scene`` and its estimated error (module docstring).

    Raises:
        RuntimeError: a run did not reach the scene's horizon.
    """
    analytic = plant("analytic")
    # an interrupted run stops the pack (its partial samples are no reference); a code swallowed stops the run at its next report
    # signal compiled code swallowed stops the run at its next report (RunsProgress's, shown
    # under the progress display in force)
    with RunsProgress(f"reference {scene.name}", scene.output.t_end, 2) as shown:
        ref = analytic.simulate(scene, REFERENCE_SETTINGS, progress=shown.run(0))
        ref = ref.raise_if_interrupted()
        tight = analytic.simulate(scene, CHECK_SETTINGS, progress=shown.run(1))
        tight = tight.raise_if_interrupted()
    for tr, s in ((ref, REFERENCE_SETTINGS), (tight, CHECK_SETTINGS)):
        if tr.status is not RunStatus.OK:
            raise RuntimeError(f"the analytic plant at rtol {s.rtol:g} stopped: {tr.message}")
    cmp = compare(tight, ref, scene)
    out = tuple(
        Accuracy(c.name, c.value if c.applicable else math.nan, c.threshold, c.unit)
        for c in cmp.checks
        if c.name in _PAIR_NAMES
    )
    return ref, out


_PAIR_NAMES = (
    "position_C",
    "attitude",
    "rod_positions",
    "velocity_C",
    "rod_velocities",
    "angular_velocity",
    "control_torque",
    "rod_forces",
)


def write_pack(scene: Scene | str | Path | None, out_dir: str | Path) -> PackResult:
    """Write the reference pack of ``scene`` (a :class:`Scene`, a scene file or a built-in name)
    into ``out_dir`` (module docstring).

    Raises:
        ValueError: a bad scene, naming its field; an output directory that is not the tool's.
        OutputError: a file could not be written (``out_dir`` keeps its previous contents).
    """

    sc = scene if isinstance(scene, Scene) else resolve_scene(scene)
    thresholds = thresholds_for(sc)
    scene_text = scene_to_toml(sc, header=f"reference pack of the scene {sc.name!r}")
    # the runs inside the output run: a signal during them leaves OUT marked interrupted
    with output_run(out_dir, "reference") as run:
        files = {SCENE_FILE: write_text(run.path / SCENE_FILE, scene_text)}
        ref, accuracy = estimate_accuracy(sc)
        files[TRAJECTORY_FILE] = write_trajectory(run.path / TRAJECTORY_FILE, sc, ref)
        record = {
            "pack_format": PACK_FORMAT,
            "scene": sc.name,
            "scene_sha256": _sha256(files[SCENE_FILE].read_bytes()),
            "reference_sha256": _sha256(files[TRAJECTORY_FILE].read_bytes()),
            "samples": int(ref.t.shape[0]),
            "t_end": float(ref.t[-1]),
            "output_rate_hz": sc.output.rate,
            "n": sc.n,
            "controlled": bool(sc.controlled),
            "reference_settings": _settings_dict(REFERENCE_SETTINGS),
            "check_settings": _settings_dict(CHECK_SETTINGS),
            "accuracy_margin": ACCURACY_MARGIN,
            "accuracy": [a.to_dict() for a in accuracy],
            "accurate_enough": all(a.ok for a in accuracy),
        }
        files[RECORD_FILE] = write_text(run.path / RECORD_FILE, json.dumps(record, indent=2) + "\n")
        files[README_FILE] = write_text(
            run.path / README_FILE, render_readme(sc, thresholds, accuracy, record)
        )
        names = list(files)
    return PackResult(
        out_dir=run.target,
        files={name: run.final(name) for name in names},
        accuracy=accuracy,
    )


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _pack_file(pack: Path, name: str, where: str) -> Path:
    """``pack/name``, a regular file and not a link (nothing in a pack points elsewhere)."""
    path = pack / name
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        raise ValueError(f"{where}: no {name} (not a reference pack: tumble reference)") from None
    except OSError as exc:
        raise ValueError(f"{where}: {name}: {exc.strerror or exc}") from None
    if not stat.S_ISREG(st.st_mode):
        raise ValueError(f"{where}: {name} is not a regular file (a link or another kind)")
    return path


def _first_difference(a: Any, b: Any, at: str = "") -> str:
    """The dotted key of the first place two scene dicts differ, with both values."""
    if isinstance(a, Mapping) and isinstance(b, Mapping):
        for k in list(a) + [k for k in b if k not in a]:
            key = f"{at}.{k}" if at else str(k)
            if k not in a or k not in b:
                return f"{key} only in the {'pack' if k in a else 'scene'}"
            found = _first_difference(a[k], b[k], key)
            if found:
                return found
        return ""
    if a != b:
        return f"{at}: {a!r:.60} in the pack, {b!r:.60} in the scene"
    return ""


def _comparable(sc: Scene) -> dict[str, Any]:
    """The scene as a dict, without the tables that judge rather than define the problem (its
    ``[thresholds]``, a hard case's criterion) and without its horizon (a pack's run judges any
    horizon up to its own, :func:`read_pack`)."""
    data = json.loads(json.dumps(scene_to_dict(sc), default=str))
    for table in ("thresholds", "hard_case"):
        data.pop(table, None)
    if isinstance(data.get("output"), dict):
        data["output"].pop("t_end", None)
    return data


def _check_accurate(record: Mapping[str, Any], where: str) -> None:
    """Refuse a pack whose record does not say its reference is accurate enough
    (``accurate_enough`` true): an engine judged against it would be judged against the
    reference's own error."""
    if record.get("accurate_enough") is True:
        return
    bad = [
        str(a.get("quantity"))
        for a in record.get("accuracy", ())
        if isinstance(a, Mapping) and a.get("ok") is False
    ]
    which = f" ({', '.join(bad)})" if bad else ""
    raise ValueError(
        f"{where}: {RECORD_FILE} says the reference is not accurate enough{which} "
        f"(accurate_enough = {json.dumps(record.get('accurate_enough'))}): it cannot judge an "
        "engine"
    )


def read_pack(pack: str | Path, scene: Scene) -> ExternalTrajectory:
    """The reference trajectory of the pack in ``pack`` for ``scene`` (plant ``reference``).

    ``scene``'s horizon may be shorter than the pack's (a pack of 20 s judges 2 s): the
    reference is read whole on the pack's grid and judged up to ``scene``'s t_end.

    Raises:
        ValueError: one line naming the pack and what is wrong: not a directory, a file missing,
            a link or not regular, ``reference.json`` unreadable or of another pack format, a
            pack that does not say it is accurate enough (``accurate_enough`` not true), the
            pack's scene not ``scene`` (naming the first field that differs; the horizon aside),
            a pack shorter than ``scene``'s horizon, ``reference.csv``
            not the file ``reference.json`` records (its SHA-256), or a bad ``reference.csv``
            (its row and column).
    """
    pack = Path(pack)
    where = f"reference pack {str(pack)!r}"
    if not pack.is_dir():
        raise ValueError(f"{where}: not a directory")
    raw = read_regular(_pack_file(pack, RECORD_FILE, where), RECORD_LIMIT, follow_links=False)
    try:
        record = json.loads(raw)
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{where}: {RECORD_FILE} is not JSON ({exc})") from None
    if not isinstance(record, dict) or record.get("pack_format") != PACK_FORMAT:
        raise ValueError(f"{where}: {RECORD_FILE} is not of pack format {PACK_FORMAT}")
    _check_accurate(record, where)
    try:
        theirs = load_scene(_pack_file(pack, SCENE_FILE, where))
    except ValueError as exc:
        raise ValueError(f"{where}: {SCENE_FILE}: {exc}") from None
    diff = _first_difference(_comparable(theirs), _comparable(scene))
    if diff:
        raise ValueError(f"{where}: its scene is not the scene {scene.name!r} ({diff})")
    covers, wanted = theirs.output.t_end, scene.output.t_end
    if covers < wanted:
        raise ValueError(
            f"{where}: its reference covers 0-{covers:g} s, shorter than the 0-{wanted:g} s "
            f"judged (write a pack of the scene's {wanted:g} s with tumble reference)"
        )
    grid = scene.replace(output=theirs.output)  # the pack's grid; judged up to the scene's t_end
    csv = _pack_file(pack, TRAJECTORY_FILE, where)
    digest = _sha256(read_regular(csv, size_limit(grid), follow_links=False))
    if digest != record.get("reference_sha256"):
        raise ValueError(
            f"{where}: {TRAJECTORY_FILE} is not the file {RECORD_FILE} records (SHA-256 {digest[:12]}…)"
        )
    ref = read_trajectory(csv, grid, engine=REFERENCE_PLANT, judged=scene)
    missing = sorted(g.value for g in OPTIONAL_GROUPS - ref.present)
    if missing:
        raise ValueError(f"{where}: {TRAJECTORY_FILE} lacks the {', '.join(missing)} columns")
    return ref


__all__ = [
    "ACCURACY_MARGIN",
    "CHECK_SETTINGS",
    "PACK_FORMAT",
    "REFERENCE_PLANT",
    "REFERENCE_SETTINGS",
    "Accuracy",
    "PackResult",
    "estimate_accuracy",
    "read_pack",
    "write_pack",
]
