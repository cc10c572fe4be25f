"""The horizon a trajectory file is judged over: the scene's, a ``t_end`` given, or the file's own.

Another engine's run may cover less than the scene's ``[output] t_end`` (a faithful 2 s run of a
20 s scene). It is judged over the horizon it covers when the user says so:

* ``t_end`` (``tumble judge --t-end T``, ``[judge] t_end``): the scene judged as if its ``t_end``
  were T; T must be in (0, the scene's t_end] and on the scene's output grid (a multiple of
  1/rate, or the scene's t_end itself), so the shortened grid is the scene's grid up to T;
* ``up_to_file_end`` (``--up-to-file-end``, ``[judge] up_to_file_end = true``): a file that stops
  on the grid before the (possibly shortened) end is judged up to its last row.

:class:`JudgedHorizon` is what the report states ("judged over 0-2 s of the scene's 20 s").
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import numpy as np

from analytic.scene import Scene
from validation.external.table import GRID_TOL


class HorizonSource(StrEnum):
    """Where the judged horizon came from."""

    SCENE = "scene"
    """The scene's own ``[output] t_end``."""
    T_END = "t_end"
    """A ``t_end`` given (``--t-end``)."""
    FILE_END = "file_end"
    """The file's last row (``--up-to-file-end``)."""


@dataclass(frozen=True)
class JudgedHorizon:
    """The horizon a file was judged over.

    Attributes:
        t_end: the judged horizon, s (the last sample judged).
        scene_t_end: the scene's own ``[output] t_end``, s.
        samples: the samples judged (rows of the file compared).
        source: where ``t_end`` came from.
    """

    t_end: float
    scene_t_end: float
    samples: int
    source: HorizonSource

    @property
    def whole(self) -> bool:
        """Whether the scene's whole horizon is judged."""
        return self.t_end == self.scene_t_end

    @property
    def sentence(self) -> str:
        """``"judged over 0-2 s of the scene's 20 s (201 samples, up to the file's last row)"``."""
        why = {
            HorizonSource.SCENE: "the scene's horizon",
            HorizonSource.T_END: "t_end given",
            HorizonSource.FILE_END: "up to the file's last row",
        }[self.source]
        return (
            f"judged over 0-{self.t_end:g} s of the scene's {self.scene_t_end:g} s "
            f"({self.samples} samples, {why})"
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "t_end_s": self.t_end,
            "scene_t_end_s": self.scene_t_end,
            "samples": self.samples,
            "source": self.source.value,
            "whole": self.whole,
            "text": self.sentence,
        }


def horizon_on_grid(scene: Scene, t_end: Any, field: str = "t_end") -> float:
    """``t_end`` checked as a horizon to judge ``scene`` over: the grid point it names.

    Raises:
        ValueError: naming ``field`` and the value: not a number, not in (0, the scene's t_end],
            or not on the scene's output grid (within :data:`GRID_TOL` sample intervals).
    """
    top = scene.output.t_end
    if isinstance(t_end, bool) or not isinstance(t_end, (int, float)):
        raise ValueError(f"{field}: must be a time in s (got {t_end!r:.60})")
    t = float(t_end)
    if not math.isfinite(t) or not 0.0 < t <= top * (1.0 + 1e-12):
        raise ValueError(
            f"{field}: {t!r} s is not in (0, {top:g}] s, the horizon of the scene {scene.name!r}"
        )
    grid = scene.output.times()
    k = int(np.argmin(np.abs(grid - t)))
    if k == 0 or abs(float(grid[k]) - t) > GRID_TOL / scene.output.rate:
        raise ValueError(
            f"{field}: {t!r} s is not on the output grid of the scene {scene.name!r} (a multiple "
            f"of 1/rate = {1.0 / scene.output.rate!r} s, or its t_end {top:g} s)"
        )
    return float(grid[k])


def shortened(scene: Scene, t_end: float) -> Scene:
    """``scene`` with its horizon ``t_end``, a point of its grid (:func:`horizon_on_grid`): its
    grid is the scene's up to ``t_end``."""
    if t_end == scene.output.t_end:
        return scene
    return scene.replace(output=scene.output.with_t_end(t_end, "t_end"))


__all__ = ["HorizonSource", "JudgedHorizon", "horizon_on_grid", "shortened"]
