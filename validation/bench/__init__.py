"""The benchmark wing: every speed goal, as a ratio measured in one process.

* :mod:`.command`: ``tumble bench`` (= ``python -m validation.bench``);
* :mod:`.goals`: every speed goal (the registry, :data:`~.goals.GOALS`), each in its own module
  (``*_goal.py``, ``evaluation_goals``), each a ``Goal`` (:mod:`.goal`);
* :mod:`.verdicts`: a goal's spread over its rounds and its verdict (``Verdict``, ``SPREAD_BOUND``);
* :mod:`.timing`: the chain scene and the timing loop the goals share (thread CPU time);
* :mod:`.fast_bench`: the compiled kernel against the numpy reference and ``mj_forward``;
* :mod:`.mujoco_steps`: MuJoCo RK4's per-step cost with and without the controller.
"""

from typing import TYPE_CHECKING

from validation._lazy import lazy_exports

_PUBLIC = {
    "CpuMeter": "validation.bench.timing",
    "Goal": "validation.bench.goal",
    "SPREAD_BOUND": "validation.bench.verdicts",
    "Spread": "validation.bench.verdicts",
    "Verdict": "validation.bench.verdicts",
    "chain_scene": "validation.bench.timing",
    "time_call": "validation.bench.timing",
}

if TYPE_CHECKING:  # the same names, typed for a type checker (never run: imports stay lazy)
    from validation.bench.goal import Goal as Goal
    from validation.bench.timing import CpuMeter as CpuMeter
    from validation.bench.timing import chain_scene as chain_scene
    from validation.bench.timing import time_call as time_call
    from validation.bench.verdicts import SPREAD_BOUND as SPREAD_BOUND
    from validation.bench.verdicts import Spread as Spread
    from validation.bench.verdicts import Verdict as Verdict

__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
