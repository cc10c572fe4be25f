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

from typing import TYPE_CHECKING

from analytic.runtime.lazy import lazy_exports

_PUBLIC = {
    "BUILTIN_DIR": "analytic.scene.builtin",
    "builtin_scene_names": "analytic.scene.builtin",
    "builtin_scene_path": "analytic.scene.builtin",
    "modified_scene": "analytic.scene.dump",
    "AXIS_NORMALISE_TOL": "analytic.scene.limits",
    "AXIS_REFUSE_TOL": "analytic.scene.limits",
    "GRID_RTOL": "analytic.scene.limits",
    "MAX_INERTIA": "analytic.scene.limits",
    "MAX_MASS": "analytic.scene.limits",
    "MAX_MASSES": "analytic.scene.limits",
    "MAX_MUJOCO_STEPS": "analytic.scene.limits",
    "MAX_OUTPUT_SAMPLES": "analytic.scene.limits",
    "MAX_SCENE_BYTES": "analytic.scene.limits",
    "MAX_SCENE_NESTING": "analytic.scene.limits",
    "QUAT_NORMALISE_TOL": "analytic.scene.limits",
    "QUAT_REFUSE_TOL": "analytic.scene.limits",
    "ROTATION_EXACT_TOL": "analytic.scene.limits",
    "ROTATION_REFUSE_TOL": "analytic.scene.limits",
    "Scene": "analytic.scene.loading",
    "scene_from_dict": "analytic.scene.loading",
    "IDENTITY_QUATERNION": "analytic.scene.parsers",
    "load_scene": "analytic.scene.reading",
    "Body": "analytic.scene.records",
    "BodyShape": "analytic.scene.records",
    "Control": "analytic.scene.records",
    "ExternalTorque": "analytic.scene.records",
    "InitialState": "analytic.scene.records",
    "Masses": "analytic.scene.records",
    "MassTrack": "analytic.scene.records",
    "MujocoSettings": "analytic.scene.records",
    "OmegaTrack": "analytic.scene.records",
    "OutputSettings": "analytic.scene.records",
    "Rod": "analytic.scene.records",
    "SceneRecord": "analytic.scene.records",
    "SolverSettings": "analytic.scene.records",
    "Springs": "analytic.scene.records",
    "Stabilization": "analytic.scene.records",
    "output_times": "analytic.scene.records",
    "MJ_MINVAL": "analytic.scene.twin",
    "POINT_INERTIA_MIN": "analytic.scene.twin",
    "POINT_INERTIA_REL": "analytic.scene.twin",
    "TRIANGLE_RTOL": "analytic.scene.twin",
    "twin_point_inertia": "analytic.scene.twin",
    "SceneText": "analytic.scene.values",
    "as_enum": "analytic.scene.values",
}
"""Public name -> the module it lives in: imported on first use, so that a module of the package
(``analytic.scene.key``, which the effect declarations read) is imported without the loader."""

if TYPE_CHECKING:  # the same names, typed for a type checker (never run: imports stay lazy)
    from analytic.scene.builtin import BUILTIN_DIR as BUILTIN_DIR
    from analytic.scene.builtin import builtin_scene_names as builtin_scene_names
    from analytic.scene.builtin import builtin_scene_path as builtin_scene_path
    from analytic.scene.dump import modified_scene as modified_scene
    from analytic.scene.limits import AXIS_NORMALISE_TOL as AXIS_NORMALISE_TOL
    from analytic.scene.limits import AXIS_REFUSE_TOL as AXIS_REFUSE_TOL
    from analytic.scene.limits import GRID_RTOL as GRID_RTOL
    from analytic.scene.limits import MAX_INERTIA as MAX_INERTIA
    from analytic.scene.limits import MAX_MASS as MAX_MASS
    from analytic.scene.limits import MAX_MASSES as MAX_MASSES
    from analytic.scene.limits import MAX_MUJOCO_STEPS as MAX_MUJOCO_STEPS
    from analytic.scene.limits import MAX_OUTPUT_SAMPLES as MAX_OUTPUT_SAMPLES
    from analytic.scene.limits import MAX_SCENE_BYTES as MAX_SCENE_BYTES
    from analytic.scene.limits import MAX_SCENE_NESTING as MAX_SCENE_NESTING
    from analytic.scene.limits import QUAT_NORMALISE_TOL as QUAT_NORMALISE_TOL
    from analytic.scene.limits import QUAT_REFUSE_TOL as QUAT_REFUSE_TOL
    from analytic.scene.limits import ROTATION_EXACT_TOL as ROTATION_EXACT_TOL
    from analytic.scene.limits import ROTATION_REFUSE_TOL as ROTATION_REFUSE_TOL
    from analytic.scene.loading import Scene as Scene
    from analytic.scene.loading import scene_from_dict as scene_from_dict
    from analytic.scene.parsers import IDENTITY_QUATERNION as IDENTITY_QUATERNION
    from analytic.scene.reading import load_scene as load_scene
    from analytic.scene.records import Body as Body
    from analytic.scene.records import BodyShape as BodyShape
    from analytic.scene.records import Control as Control
    from analytic.scene.records import ExternalTorque as ExternalTorque
    from analytic.scene.records import InitialState as InitialState
    from analytic.scene.records import Masses as Masses
    from analytic.scene.records import MassTrack as MassTrack
    from analytic.scene.records import MujocoSettings as MujocoSettings
    from analytic.scene.records import OmegaTrack as OmegaTrack
    from analytic.scene.records import OutputSettings as OutputSettings
    from analytic.scene.records import Rod as Rod
    from analytic.scene.records import SceneRecord as SceneRecord
    from analytic.scene.records import SolverSettings as SolverSettings
    from analytic.scene.records import Springs as Springs
    from analytic.scene.records import Stabilization as Stabilization
    from analytic.scene.records import output_times as output_times
    from analytic.scene.twin import MJ_MINVAL as MJ_MINVAL
    from analytic.scene.twin import POINT_INERTIA_MIN as POINT_INERTIA_MIN
    from analytic.scene.twin import POINT_INERTIA_REL as POINT_INERTIA_REL
    from analytic.scene.twin import TRIANGLE_RTOL as TRIANGLE_RTOL
    from analytic.scene.twin import twin_point_inertia as twin_point_inertia
    from analytic.scene.values import SceneText as SceneText
    from analytic.scene.values import as_enum as as_enum

__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())

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
