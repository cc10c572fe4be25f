"""The benchmark wing: every speed goal, as a ratio measured in one process.

* :mod:`.command`: ``tumble bench`` (= ``python -m validation.bench``);
* :mod:`.goals`: the speed goals, each a ``Goal``;
* :mod:`.verdicts`: a goal's spread over its rounds and its verdict (``Verdict``, ``SPREAD_BOUND``);
* :mod:`.timing`: the chain scene and the timing loop the goals share (thread CPU time);
* :mod:`.fast_bench`: the compiled kernel against the numpy reference and ``mj_forward``;
* :mod:`.mujoco_steps`: MuJoCo RK4's per-step cost with and without the controller.
"""

from validation._lazy import lazy_exports

_PUBLIC = {
    "CpuMeter": "validation.bench.timing",
    "Goal": "validation.bench.goals",
    "SPREAD_BOUND": "validation.bench.verdicts",
    "Spread": "validation.bench.verdicts",
    "Verdict": "validation.bench.verdicts",
    "chain_scene": "validation.bench.timing",
    "time_call": "validation.bench.timing",
}

__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
