"""The double cover: ``u`` and ``-u`` are the same attitude (``S(-u) = S(u)``), and the equations of
motion are odd in ``(u, u̇)``, so a scene started from ``-u(0)`` must move as its mirror started
from ``u(0)``, with ``u`` negated and everything else equal."""

from __future__ import annotations

import numpy as np

from analytic.scene import Scene
from validation.scenes import resolve_scene

SIGN_ATOL = 1e-15
"""How exactly the mirror's u(0) must be this scene's, negated (both are printed to 16 digits)."""


def mirror_scene(scene: Scene, name: str) -> Scene:
    """The built-in scene ``name`` (checked against the built-in names when the criterion was
    read), refused with a ValueError naming ``hard_case.mirror.scene`` unless its u(0) is
    ``-u(0)`` of ``scene``."""
    mirror = resolve_scene(name)
    if not np.allclose(mirror.initial.u, -scene.initial.u, rtol=0, atol=SIGN_ATOL):
        raise ValueError(
            f"hard_case.mirror.scene: {name!r} must start from -u(0) of this scene "
            f"(got u(0) {mirror.initial.u.tolist()!r} against {scene.initial.u.tolist()!r})"
        )
    return mirror


__all__ = ["SIGN_ATOL", "mirror_scene"]
