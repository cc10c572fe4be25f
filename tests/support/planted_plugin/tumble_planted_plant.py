"""A planted wrong plant: the analytic plant, with a modelling slip that shows only in some scenes.

In a scene with at least :data:`MIN_MASSES` masses whose initial spin ``|ω(0)|`` is over
:data:`MIN_SPIN` rad/s, the body's principal moments are taken :data:`INERTIA_ERROR` relative too
large (as an engine that rounds its inertia, or converts units once too often, would); everywhere
else it is the analytic plant itself. A differential fuzzer must find the slip in the scenes that
show it and shrink one of them to a scene with exactly ``MIN_MASSES`` masses that names this plant
the outlier.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from analytic.plant import AnalyticPlant

INERTIA_ERROR = 1e-6
"""Relative error of the body's principal moments where the slip shows."""

MIN_MASSES = 3
"""The slip shows only with at least this many masses."""

MIN_SPIN = 5.0
"""... and an initial spin over this, rad/s."""


def slipped(scene) -> bool:
    """Whether the slip shows in ``scene``."""
    return (
        len(scene.masses.mass) >= MIN_MASSES
        and float(np.linalg.norm(scene.initial.omega)) > MIN_SPIN
    )


class PlantedPlant(AnalyticPlant):
    """The analytic plant, reported as ``planted``, with the slip of the module docstring."""

    engine = "planted"
    label = "Planted"
    default = False  # asked for by name only

    def _simulate(self, scene, settings, t_end, progress):
        if slipped(scene):
            body = dataclasses.replace(
                scene.body, inertia=scene.body.inertia * (1.0 + INERTIA_ERROR)
            )
            scene = dataclasses.replace(scene, body=body)
        tr = super()._simulate(scene, settings, t_end, progress)
        return dataclasses.replace(tr, engine=self.engine)
