"""Where a campaign's records are in its directory, how they are written, and how a resumed
campaign reads them back.

``scenes/<i>.json`` is a scene's outcome; ``counterexamples/<key>.json`` (beside its ``.toml``) a
shrunk disagreement. Only a file whose size and SHA-256 the campaign's manifest lists is read
back (:class:`validation.studies.fuzz.directory.CampaignDir`); one that is listed but does not read
as a record is a :class:`~validation.studies.fuzz.directory.ChangedRecord` naming it.
"""

from __future__ import annotations

import json
from typing import Any

from validation.studies.fuzz.directory import (
    COUNTEREXAMPLES_DIR,
    SCENES_DIR,
    CampaignDir,
    ChangedRecord,
)
from validation.studies.fuzz.judge import Disagreement, Outcome
from validation.studies.fuzz.records import Counterexample, FuzzConfig, SceneRecord
from validation.studies.fuzz.settle import Settlement
from validation.studies.fuzz.space import draw_scene_dict
from validation.studies.fuzz.toml import slug


def json_bytes(doc: Any) -> bytes:
    """``doc`` as indented JSON, one trailing newline, UTF-8."""
    return (json.dumps(doc, indent=2) + "\n").encode("utf-8")


def scene_rel(index: int) -> str:
    """Scene ``index``'s record, relative to the campaign's directory."""
    return f"{SCENES_DIR}/{index:06d}.json"


def example_rel(key: str, suffix: str) -> str:
    """The counterexample of disagreement ``key`` (``.toml`` or ``.json``), relative."""
    return f"{COUNTEREXAMPLES_DIR}/{slug(key)}{suffix}"


def _malformed(cd: CampaignDir, rel: str, exc: BaseException) -> ChangedRecord:
    """A record whose bytes the manifest lists but which does not read as one (a forged pair)."""
    why = f"{type(exc).__name__}: {exc}".splitlines()[0][:120]
    return ChangedRecord(
        f"{cd.path(rel)}: not a record this campaign wrote ({why}); delete it to have the "
        "campaign redo it, or give a new output directory"
    )


def load_scene_record(cd: CampaignDir, cfg: FuzzConfig, index: int) -> SceneRecord | None:
    """Scene ``index``'s record as judged before an interruption (None: not judged yet)."""
    rel = scene_rel(index)
    d = cd.read_json(rel)
    if d is None:
        return None
    try:
        outcome = Outcome.from_dict(d)
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise _malformed(cd, rel, exc) from None
    return SceneRecord(index, draw_scene_dict(cfg.seed, index, cfg.horizon), outcome)


def load_counterexample(cd: CampaignDir, target: Disagreement) -> Counterexample | None:
    """The counterexample of ``target`` shrunk before an interruption (kept as it was written)."""
    rel = example_rel(target.key, ".json")
    done = cd.read_json(rel)
    if done is None:
        return None
    try:
        name = f"{slug(target.key)}.toml"
        if done["file"] != name:
            raise ValueError(f"file {str(done['file'])[:40]!r}, not {name!r}")
        return Counterexample(
            target,
            int(done["found_in"]),
            dict(done["scene"]),
            float(done["horizon"]),
            Outcome.from_dict(done["outcome"]),
            int(done["evaluations"]),
            str(done["known"]),
            cd.path(f"{COUNTEREXAMPLES_DIR}/{name}"),
            settlement=(
                Settlement.from_dict(done["settlement"]) if done.get("settlement") else None
            ),
        )
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise _malformed(cd, rel, exc) from None


__all__ = [
    "example_rel",
    "json_bytes",
    "load_counterexample",
    "load_scene_record",
    "scene_rel",
]
