"""The analytic side: the paper's tumbling multibody model and its closed-form control.

Koganti & Udwadia, "Dynamics and Precision Control of Tumbling Multibody Systems", J. Guidance,
Control, and Dynamics 40(3), 2017. Notation and equation numbers as in the paper.
"""

from analytic.builtin_scenes import builtin_scene_names
from analytic.effects import Effect, SolverMethod, Weighting
from analytic.model import ControlOutput, TumblingModel
from analytic.scene import Scene, load_scene, scene_from_dict
from analytic.simulate import simulate
from analytic.trajectory import Engine, Invariants, RunStatus, Tracking, Trajectory

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
