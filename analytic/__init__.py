"""The analytic side: the paper's tumbling multibody model and its closed-form control.

Koganti & Udwadia, "Dynamics and Precision Control of Tumbling Multibody Systems", J. Guidance,
Control, and Dynamics 40(3), 2017. Notation and equation numbers as in the paper.
"""

from analytic.runtime.lazy import lazy_exports
from analytic.simulate import simulate  # bound here: the function, not its module's name

_LAZY = {
    "builtin_scene_names": "analytic.scene.builtin",
    "Effect": "analytic.effects",
    "SolverMethod": "analytic.effects",
    "Weighting": "analytic.effects",
    "ControlOutput": "analytic.model",
    "TumblingModel": "analytic.model",
    "Scene": "analytic.scene",
    "load_scene": "analytic.scene",
    "scene_from_dict": "analytic.scene",
    "Engine": "analytic.trajectory",
    "Invariants": "analytic.trajectory",
    "RunStatus": "analytic.trajectory",
    "Tracking": "analytic.trajectory",
    "Trajectory": "analytic.trajectory",
}
"""Public names imported on first use (``import analytic`` then costs numpy, not scipy or numba:
the command line starts its work sooner)."""


__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())


__all__ = [
    "ControlOutput",
    "Effect",
    "Engine",
    "Invariants",
    "RunStatus",
    "Scene",
    "SolverMethod",
    "Tracking",
    "Trajectory",
    "TumblingModel",
    "Weighting",
    "builtin_scene_names",
    "load_scene",
    "scene_from_dict",
    "simulate",
]
