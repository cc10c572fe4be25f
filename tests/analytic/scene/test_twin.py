"""What the MuJoCo twin can represent: the loader's MuJoCo bounds are MuJoCo's.

Every bad input must raise ValueError whose message starts with the dotted field name.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

from analytic import scene as S
from analytic.scene import load_scene, scene_from_dict
from tests.analytic.scene.test_loading import PAPER, _raw
from validation.scenes import scene_path

# ------------------------------------------------------------------------------------------------
# The loader's MuJoCo bounds are MuJoCo's: accepted scenes compile, refused ones would not
# ------------------------------------------------------------------------------------------------


def test_loader_bounds_match_mujoco_and_the_builder():
    mujoco = pytest.importorskip("mujoco")
    from model_xml import builder

    assert S.MJ_MINVAL == mujoco.mjMINVAL
    for name in PAPER:
        sc = load_scene(scene_path(name))
        eps, count = S.twin_point_inertia(sc)
        assert builder.point_inertia(sc) == eps  # the one formula, not a copy of it
        _, pad = builder.mass_inertias(sc)
        assert pad == eps * count


def _compiles(sc) -> bool:
    from model_xml import build_spec

    try:
        build_spec(sc).compile()
    except ValueError:
        return False
    return True


def test_scenes_at_the_bounds_compile_and_beyond_them_mujoco_refuses():
    pytest.importorskip("mujoco")
    raw = _raw("paper_example1")
    raw["masses"]["mass"] = [S.MJ_MINVAL, S.MAX_MASS]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # MuJoCo: the inertia matrix is nearly singular
        assert _compiles(scene_from_dict(raw))
    # Example 2 has point masses: BR gives up 5 eps of each moment, so a flat BR needs that margin.
    raw = _raw("paper_example2")
    raw["body"]["inertia"] = [1.0, 1.0, 2.0]
    with pytest.raises(ValueError, match=r"^body\.inertia: principal moments"):
        scene_from_dict(raw)
    ok = scene_from_dict(_raw("paper_example2"))
    flat = ok.replace(body=dataclasses.replace(ok.body, inertia=np.array([1.0, 1.0, 2.0])))
    assert not _compiles(flat)  # what the loader refused, MuJoCo's compiler refuses too
    eps, count = S.twin_point_inertia(flat)
    raw["body"]["inertia"] = [1.0, 1.0, 2.0 - eps * count]
    assert _compiles(scene_from_dict(raw))
    # a mass's own inertia must satisfy A + B >= C
    raw = _raw("paper_example1")
    del raw["masses"]["ring_radius"]
    raw["masses"]["inertia_body"] = [np.diag([1.0, 1.0, 2.001]).tolist(), np.eye(3).tolist()]
    with pytest.raises(ValueError, match=r"^masses\.inertia_body\[0\]: principal moments"):
        scene_from_dict(raw)
    raw["masses"]["inertia_body"][0] = np.diag([1.0, 1.0, 2.0]).tolist()
    assert _compiles(scene_from_dict(raw))
