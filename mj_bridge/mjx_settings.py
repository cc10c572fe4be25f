"""How the MJX plant runs (its settings record, read from a scene's optional ``[mjx]`` table) and
whether MJX is installed, apart from the plant: nothing here imports JAX or MJX.

The ``[mjx]`` table of a scene (kept verbatim by the loader in ``scene.extra``)::

    [mjx]
    precision = "float32"     # or "float64" (default): JAX's x64 mode in the engine's process
    device = "cpu"            # JAX's platform ("cpu", "gpu", "cuda:1"); "" (default) JAX's default
    timestep = 2.5e-4         # s; default the scene's [mujoco] timestep
    controller = "jax"        # "jax" (default): the controller in JAX in every stage;
                              # "host": the compiled numpy controller through a host callback
"""

from __future__ import annotations

import importlib.util
import re
from collections.abc import Mapping
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

from analytic.effects import Precision
from analytic.plant import check_positive, coerce_enum

MJX_MISSING = (
    "the mjx plant needs the 'mujoco-mjx' and 'jax' packages: "
    "pip install 'mujoco-mjx>=3.17' 'jax>=0.10' (the [mjx] extra)"
)
"""What :func:`mjx_unavailable` says when MJX or JAX cannot be imported."""

DEVICE_PATTERN = re.compile(r"(|[a-z]+(:[0-9]+)?)")
"""A JAX device: a platform name, optionally ``:index``; empty for JAX's default."""


class MjxController(StrEnum):
    """Where the MJX plant's controller is evaluated in each integrator stage."""

    JAX = "jax"
    """The project's array-API controller (:mod:`analytic.array_model`) in JAX, in the engine's
    precision, jit-compiled with the step: no host round trip per stage."""
    HOST = "host"
    """The compiled numpy controller (``analytic.fast.FastModel``, float64) through
    ``jax.pure_callback``: for cross-checking the JAX controller."""


def mjx_unavailable() -> str:
    """Why the MJX plant cannot run here (:data:`MJX_MISSING`), or "" (found without importing)."""
    try:
        found = importlib.util.find_spec("jax") is not None and (
            importlib.util.find_spec("mujoco.mjx") is not None
        )
    except (ImportError, ValueError):
        found = False
    return "" if found else MJX_MISSING


@dataclass(frozen=True)
class MjxSettings:
    """How the MJX plant runs.

    Attributes:
        precision: float32 or float64 (:class:`analytic.effects.Precision`).
        device: JAX's device (platform name, optionally ``:index``), "" for JAX's default.
        timestep: the step, s; None for the scene's ``[mujoco] timestep``.
        controller: :class:`MjxController`.
    """

    precision: Precision = Precision.FLOAT64
    device: str = ""
    timestep: float | None = None
    controller: MjxController = MjxController.JAX

    def __post_init__(self) -> None:
        coerce_enum(self, "precision", Precision)
        coerce_enum(self, "controller", MjxController)
        check_positive(self, "timestep", allow_none=True, what="positive finite time step in s")
        if not (isinstance(self.device, str) and DEVICE_PATTERN.fullmatch(self.device)):
            raise ValueError(
                f"device: must be a JAX platform name such as 'cpu' or 'cuda:0', or '' for "
                f"JAX's default (got {self.device!r})"
            )

    @classmethod
    def from_table(cls, table: Mapping[str, Any] | None, timestep: float) -> MjxSettings:
        """The settings of a scene's ``[mjx]`` table (``mjx.<key>`` named in a refusal), the
        step defaulting to ``timestep`` (the scene's ``[mujoco]`` one)."""
        table = dict(table or {})
        unknown = sorted(set(table) - {"precision", "device", "timestep", "controller"})
        if unknown:
            raise ValueError(
                f"mjx.{unknown[0]}: not a key of the [mjx] table (keys: precision, device, "
                f"timestep, controller)"
            )
        table.setdefault("timestep", timestep)
        try:
            return cls(**table)
        except ValueError as exc:
            raise ValueError(f"mjx.{exc}") from None


__all__ = ["MJX_MISSING", "MjxController", "MjxSettings", "mjx_unavailable"]
