"""``tumble fuzz``: a differential fuzzing campaign over the whole scene space.

Seeded scenes (:mod:`~validation.studies.fuzz.space`) run on every chosen plant and judged by the
comparison's checks and the referee (:mod:`~validation.studies.fuzz.judge`), through one
``concurrent.futures`` executor (a process pool, or Dask); every new disagreement shrunk to a
minimal scene (:mod:`~validation.studies.fuzz.shrink`) written as a scene file
(:mod:`~validation.studies.fuzz.toml`); known findings told apart
(:mod:`~validation.studies.fuzz.known`); the report (:mod:`~validation.studies.fuzz.report`).
:func:`fuzz` is the campaign (:mod:`~validation.studies.fuzz.campaign`). See ``docs/fuzzing.md``.
"""

from typing import TYPE_CHECKING

from validation._lazy import lazy_exports

_TABLE = {
    "CampaignResult": "validation.studies.fuzz.campaign",
    "Counterexample": "validation.studies.fuzz.campaign",
    "Disagreement": "validation.studies.fuzz.judge",
    "SerialExecutor": "validation.studies.fuzz.campaign",
    "draw_scene_dict": "validation.studies.fuzz.space",
    "fuzz": "validation.studies.fuzz.campaign",
    "judge_scene": "validation.studies.fuzz.judge",
    "shrink": "validation.studies.fuzz.shrink",
}

if TYPE_CHECKING:  # the same names, typed for a type checker (never run: imports stay lazy)
    from validation.studies.fuzz.campaign import CampaignResult as CampaignResult
    from validation.studies.fuzz.campaign import Counterexample as Counterexample
    from validation.studies.fuzz.campaign import SerialExecutor as SerialExecutor
    from validation.studies.fuzz.campaign import fuzz as fuzz
    from validation.studies.fuzz.judge import Disagreement as Disagreement
    from validation.studies.fuzz.judge import judge_scene as judge_scene
    from validation.studies.fuzz.shrink import shrink as shrink
    from validation.studies.fuzz.space import draw_scene_dict as draw_scene_dict
__getattr__, __dir__ = lazy_exports(__name__, _TABLE, globals())
__all__ = sorted(_TABLE)
