"""Run a scene in MuJoCo (the twin built by :mod:`model_xml`) in the paper's coordinates.

* :func:`simulate` -> :class:`analytic.trajectory.Trajectory` (engine ``mujoco``);
* :func:`acceleration`: MuJoCo's forward dynamics at a paper-coordinates state, as paper ``q̈``;
* :func:`to_mujoco` / :func:`to_paper` / :func:`to_paper_acc` for a compiled model, and the
  pure-array :func:`paper_to_mujoco_state` / :func:`mujoco_to_paper_state` / :func:`mujoco_to_paper_acc`
  (all from :mod:`model_xml.coordinates`, the one module of coordinate maps);
* :func:`mujoco_control`: the Udwadia–Kalaba control from MuJoCo's own ``M`` and forces;
* :class:`Twin`: a compiled model with all of the above and the in-integrator controller.
"""

from mj_bridge.callbacks import installed
from mj_bridge.simulate import simulate
from mj_bridge.twin import ControllerSource, MjControl, Twin, acceleration, mujoco_control
from mj_bridge.twin_model import to_mujoco, to_paper, to_paper_acc
from model_xml.coordinates import mujoco_to_paper_acc, mujoco_to_paper_state, paper_to_mujoco_state

__all__ = [
    "ControllerSource",
    "MjControl",
    "Twin",
    "acceleration",
    "installed",
    "mujoco_control",
    "mujoco_to_paper_acc",
    "mujoco_to_paper_state",
    "paper_to_mujoco_state",
    "simulate",
    "to_mujoco",
    "to_paper",
    "to_paper_acc",
]
