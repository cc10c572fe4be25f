"""Run a scene in MuJoCo (the twin built by :mod:`model_xml`) in the paper's coordinates.

* :func:`simulate` -> :class:`analytic.trajectory.Trajectory` (engine ``mujoco``);
* :func:`acceleration`: MuJoCo's forward dynamics at a paper-coordinates state, as paper ``q̈``;
* :func:`to_mujoco` / :func:`to_paper` / :func:`to_paper_acc` for a compiled model, and the
  pure-array :func:`paper_to_mujoco_state` / :func:`mujoco_to_paper_state` / :func:`mujoco_to_paper_acc`
  (all from :mod:`model_xml.coordinates`, the one module of coordinate maps);
* :func:`mujoco_control`: the Udwadia–Kalaba control from MuJoCo's own ``M`` and forces;
* :class:`Twin`: a compiled model with all of the above and the in-integrator controller.
"""

from typing import TYPE_CHECKING

from analytic.runtime.lazy import lazy_exports
from mj_bridge.simulate import simulate  # bound here: the function, not its module's name (light)

_LAZY = {
    "installed": "mj_bridge.callbacks",
    "ControllerSource": "mj_bridge.mujoco_settings",
    "MjControl": "mj_bridge.twin",
    "Twin": "mj_bridge.twin",
    "acceleration": "mj_bridge.twin",
    "mujoco_control": "mj_bridge.twin",
    "to_mujoco": "mj_bridge.twin_model",
    "to_paper": "mj_bridge.twin_model",
    "to_paper_acc": "mj_bridge.twin_model",
    "mujoco_to_paper_acc": "model_xml.coordinates",
    "mujoco_to_paper_state": "model_xml.coordinates",
    "paper_to_mujoco_state": "model_xml.coordinates",
}
"""Public names imported on first use: importing this package (or :mod:`mj_bridge.plants`, to
choose plants) costs neither MuJoCo nor numba."""

if TYPE_CHECKING:  # the same names, typed for a type checker (never run: imports stay lazy)
    from mj_bridge.callbacks import installed as installed
    from mj_bridge.mujoco_settings import ControllerSource as ControllerSource
    from mj_bridge.twin import MjControl as MjControl
    from mj_bridge.twin import Twin as Twin
    from mj_bridge.twin import acceleration as acceleration
    from mj_bridge.twin import mujoco_control as mujoco_control
    from mj_bridge.twin_model import to_mujoco as to_mujoco
    from mj_bridge.twin_model import to_paper as to_paper
    from mj_bridge.twin_model import to_paper_acc as to_paper_acc
    from model_xml.coordinates import mujoco_to_paper_acc as mujoco_to_paper_acc
    from model_xml.coordinates import mujoco_to_paper_state as mujoco_to_paper_state
    from model_xml.coordinates import paper_to_mujoco_state as paper_to_mujoco_state

__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())

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
