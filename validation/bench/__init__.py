"""The benchmark wing: every speed goal, as a ratio measured in one process.

* :mod:`.command`: ``tumble bench`` (= ``python -m validation.bench``);
* :mod:`.goals`: the speed goals, each a ``Goal``;
* :mod:`.timing`: the chain scene and the timing loop the goals share;
* :mod:`.fast_bench`: the compiled kernel against the numpy reference and ``mj_forward``;
* :mod:`.mujoco_steps`: MuJoCo RK4's per-step cost with and without the controller.
"""

from validation._lazy import lazy_exports

_PUBLIC = {
    "Goal": "validation.bench.goals",
    "chain_scene": "validation.bench.timing",
    "time_call": "validation.bench.timing",
}

__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
