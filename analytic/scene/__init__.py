"""Scene files: one TOML description drives every engine.

A scene is data only: it is parsed with :mod:`tomllib` and validated into frozen dataclasses; nothing
in it is ever evaluated. Every error is a :class:`ValueError` whose message starts with the dotted
name of the offending field and shows the offending value, e.g.
``masses.mass[1]: must be positive (got -3.0)``.

The package, one job per module:

* :mod:`~analytic.scene.schema`: every key of the format, declared once (type, unit, default,
  bounds, meaning, the effect that reads it; :mod:`~analytic.scene.key` says what a declaration
  is, ``keys_body``, ``keys_motion``, ``keys_run`` hold them); the loader reads keys only through
  it and ``docs/scene-format.md`` is rendered from it;
* :mod:`~analytic.scene.records`: the frozen dataclasses a scene loads to (:class:`Scene`, ...);
* :mod:`~analytic.scene.reading`: :func:`load_scene`, a file (or a built-in scene's name) read
  safely and parsed; :mod:`~analytic.scene.loading`: :func:`scene_from_dict`, the parsed document
  validated, table by table (:mod:`~analytic.scene.parsers`, through
  :mod:`~analytic.scene.table` and :mod:`~analytic.scene.values`);
* the checks across fields: :mod:`~analytic.scene.rules` (effects and their data),
  :mod:`~analytic.scene.twin` (what the MuJoCo twin can represent),
  :mod:`~analytic.scene.overflow` (initial quantities beyond the double range),
  :mod:`~analytic.scene.nesting`; the bounds in :mod:`~analytic.scene.limits`;
* :mod:`~analytic.scene.builtin` (the built-in scenes, ``analytic/scenes/*.toml``),
  :mod:`~analytic.scene.random_scenes` (random valid scenes), :mod:`~analytic.scene.dump` (a
  scene written back as TOML).

Units are SI; *body* vectors in BR's principal axes at C, *inertial* ones in XYZ with Z up;
quaternions w-first; mass and axis indices 1-based in files, 0-based in the records.
"""

from analytic.scene.builtin import BUILTIN_DIR, builtin_scene_names, builtin_scene_path
from analytic.scene.dump import modified_scene
from analytic.scene.limits import (
    AXIS_NORMALISE_TOL,
    AXIS_REFUSE_TOL,
    GRID_RTOL,
    MAX_INERTIA,
    MAX_MASS,
    MAX_MASSES,
    MAX_MUJOCO_STEPS,
    MAX_OUTPUT_SAMPLES,
    MAX_SCENE_BYTES,
    MAX_SCENE_NESTING,
    QUAT_NORMALISE_TOL,
    QUAT_REFUSE_TOL,
    ROTATION_EXACT_TOL,
    ROTATION_REFUSE_TOL,
)
from analytic.scene.loading import Scene, scene_from_dict
from analytic.scene.parsers import IDENTITY_QUATERNION
from analytic.scene.reading import load_scene
from analytic.scene.records import (
    Body,
    BodyShape,
    Control,
    ExternalTorque,
    InitialState,
    Masses,
    MassTrack,
    MujocoSettings,
    OmegaTrack,
    OutputSettings,
    Rod,
    SceneRecord,
    SolverSettings,
    Springs,
    Stabilization,
    output_times,
)
from analytic.scene.twin import (
    MJ_MINVAL,
    POINT_INERTIA_MIN,
    POINT_INERTIA_REL,
    TRIANGLE_RTOL,
    twin_point_inertia,
)
from analytic.scene.values import SceneText, as_enum

__all__ = [
    "AXIS_NORMALISE_TOL",
    "AXIS_REFUSE_TOL",
    "BUILTIN_DIR",
    "GRID_RTOL",
    "IDENTITY_QUATERNION",
    "MAX_INERTIA",
    "MAX_MASS",
    "MAX_MASSES",
    "MAX_MUJOCO_STEPS",
    "MAX_OUTPUT_SAMPLES",
    "MAX_SCENE_BYTES",
    "MAX_SCENE_NESTING",
    "MJ_MINVAL",
    "POINT_INERTIA_MIN",
    "POINT_INERTIA_REL",
    "QUAT_NORMALISE_TOL",
    "QUAT_REFUSE_TOL",
    "ROTATION_EXACT_TOL",
    "ROTATION_REFUSE_TOL",
    "TRIANGLE_RTOL",
    "Body",
    "BodyShape",
    "Control",
    "ExternalTorque",
    "InitialState",
    "MassTrack",
    "Masses",
    "MujocoSettings",
    "OmegaTrack",
    "OutputSettings",
    "Rod",
    "Scene",
    "SceneRecord",
    "SceneText",
    "SolverSettings",
    "Springs",
    "Stabilization",
    "as_enum",
    "builtin_scene_names",
    "builtin_scene_path",
    "load_scene",
    "modified_scene",
    "output_times",
    "scene_from_dict",
    "twin_point_inertia",
]
