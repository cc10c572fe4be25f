"""State maps for a compiled twin (``MjModel``): the inertial frame of body ``BR`` is read from the
model (``body_ipos``, ``body_iquat``), so they hold for any placement of BR's body frame.

Pure-array versions with the inertial frame given explicitly: :mod:`model_xml.state`.
"""

from __future__ import annotations

import mujoco
import numpy as np

from model_xml import BODY
from model_xml.state import mujoco_to_paper_acc, mujoco_to_paper_state, paper_to_mujoco_state


def _inertial_frame(m: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray]:
    b = m.body(BODY).id
    return m.body_ipos[b], m.body_iquat[b]


def to_mujoco(m: mujoco.MjModel, q: np.ndarray, qdot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Paper ``(q (n+7), q̇ (n+7))`` -> ``(qpos (n+7), qvel (n+6))`` of model m."""
    return paper_to_mujoco_state(q, qdot, *_inertial_frame(m))


def to_paper(
    m: mujoco.MjModel, qpos: np.ndarray, qvel: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(qpos, qvel)`` of model m -> paper ``(q, q̇)`` (``u̇ = ¼ Hᵀ ω``)."""
    return mujoco_to_paper_state(qpos, qvel, *_inertial_frame(m))


def to_paper_acc(
    m: mujoco.MjModel, qpos: np.ndarray, qvel: np.ndarray, qacc: np.ndarray
) -> np.ndarray:
    """MuJoCo ``qacc (n+6)`` at ``(qpos, qvel)`` -> paper ``q̈ (n+7)``."""
    return mujoco_to_paper_acc(qpos, qvel, qacc, *_inertial_frame(m))
