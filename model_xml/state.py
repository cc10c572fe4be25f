"""The paper <-> MuJoCo state maps under their earlier names; they live in
:mod:`model_xml.coordinates`."""

from model_xml.coordinates import (
    mujoco_to_paper_acc,
    mujoco_to_paper_batch,
    mujoco_to_paper_state,
    paper_to_frame_state,
    paper_to_mujoco_state,
)

__all__ = [
    "mujoco_to_paper_acc",
    "mujoco_to_paper_batch",
    "mujoco_to_paper_state",
    "paper_to_frame_state",
    "paper_to_mujoco_state",
]
