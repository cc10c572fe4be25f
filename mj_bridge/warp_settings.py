"""The MuJoCo Warp plant's settings and what it needs installed: light (no Warp import), read by
the plugin (:mod:`mj_bridge.warp_plugin`) and by the engine (:mod:`mj_bridge.warp_plant`)."""

from __future__ import annotations

import importlib.util
from dataclasses import dataclass

from analytic.effects import Precision
from analytic.plant import check_positive

ENGINE = "mjwarp"

DEVICE_AUTO = ""
"""``WarpSettings.device`` for Warp's preferred device: CUDA when Warp sees one, else the CPU."""


def _valid_device(device: str) -> bool:
    if device in (DEVICE_AUTO, "cpu", "cuda"):
        return True
    head, _, index = device.partition(":")
    return head == "cuda" and index.isdigit()


@dataclass(frozen=True)
class WarpSettings:
    """How the MuJoCo Warp plant runs.

    Attributes:
        timestep: Warp's step, s (None: the scene's ``[mujoco] timestep``); the integrator is the
            scene's ``[mujoco] integrator`` (the twin's, RK4 by default).
        device: Warp's device: ``""`` (Warp's preferred: CUDA when present, else ``"cpu"``),
            ``"cpu"``, ``"cuda"`` or ``"cuda:N"``.
    """

    timestep: float | None = None
    device: str = DEVICE_AUTO

    def __post_init__(self) -> None:
        check_positive(self, "timestep", allow_none=True)
        if not (isinstance(self.device, str) and _valid_device(self.device)):
            raise ValueError(
                f"device: must be '' (Warp's default), 'cpu', 'cuda' or 'cuda:N' "
                f"(got {self.device!r})"
            )

    @property
    def precision(self) -> Precision:
        """MuJoCo Warp computes in float32 only."""
        return Precision.FLOAT32


def warp_unavailable() -> str:
    """Why the plant cannot run here ("" when it can): ``mujoco_warp`` or ``warp`` missing."""
    for module, dist in (("mujoco_warp", "mujoco-warp"), ("warp", "warp-lang")):
        if importlib.util.find_spec(module) is None:
            return (
                f"the MuJoCo Warp plant needs the '{dist}' package: "
                f"pip install mujoco-warp warp-lang (the [warp] extra)"
            )
    return ""


def warp_version() -> str:
    """The installed ``mujoco-warp`` distribution's version ("?" when unknown)."""
    from importlib import metadata

    try:
        return metadata.version("mujoco-warp")
    except metadata.PackageNotFoundError:
        return "?"


__all__ = ["DEVICE_AUTO", "ENGINE", "WarpSettings", "warp_unavailable", "warp_version"]
