"""The analytic side: the paper's tumbling multibody model and its closed-form control.

Koganti & Udwadia, "Dynamics and Precision Control of Tumbling Multibody Systems", J. Guidance,
Control, and Dynamics 40(3), 2017. Notation and equation numbers as in the paper.
"""

from typing import TYPE_CHECKING

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

if TYPE_CHECKING:  # the same names, typed for a type checker (never run: imports stay lazy)
    from analytic.effects import Effect as Effect
    from analytic.effects import SolverMethod as SolverMethod
    from analytic.effects import Weighting as Weighting
    from analytic.model import ControlOutput as ControlOutput
    from analytic.model import TumblingModel as TumblingModel
    from analytic.scene import Scene as Scene
    from analytic.scene import load_scene as load_scene
    from analytic.scene import scene_from_dict as scene_from_dict
    from analytic.scene.builtin import builtin_scene_names as builtin_scene_names
    from analytic.trajectory import Engine as Engine
    from analytic.trajectory import Invariants as Invariants
    from analytic.trajectory import RunStatus as RunStatus
    from analytic.trajectory import Tracking as Tracking
    from analytic.trajectory import Trajectory as Trajectory


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
