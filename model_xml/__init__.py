"""MJCF twin of a scene: :func:`build_spec` (MuJoCo's ``MjSpec``), :func:`to_mjcf` (full-precision
text), the geometry-primitive description of BR (:mod:`model_xml.primitives`) and the checked-in
MJCF files of the four paper scenes (:mod:`model_xml.regenerate`)."""

from typing import TYPE_CHECKING

from analytic.runtime.lazy import lazy_exports

_PUBLIC = {
    "BODY": "model_xml.builder",
    "KEY_INITIAL": "model_xml.builder",
    "ROOT": "model_xml.builder",
    "TORQUE_ACTUATORS": "model_xml.builder",
    "BodyFrame": "model_xml.builder",
    "SpringTendon": "model_xml.builder",
    "build_spec": "model_xml.builder",
    "compile_scene": "model_xml.builder",
    "force_actuator_name": "model_xml.builder",
    "joint_name": "model_xml.builder",
    "mass_name": "model_xml.builder",
    "spring_actuator_name": "model_xml.builder",
    "spring_tendons": "model_xml.builder",
    "tendon_name": "model_xml.builder",
    "spec_to_mjcf": "model_xml.mjcf_text",
    "to_mjcf": "model_xml.mjcf_text",
    "MassProperties": "model_xml.primitives",
    "Primitive": "model_xml.primitives",
    "PrimitiveKind": "model_xml.primitives",
    "mass_properties": "model_xml.primitives",
    "match_axes": "model_xml.primitives",
    "paper_example1_primitives": "model_xml.primitives",
    "primitive_spec": "model_xml.primitives",
    "rod_in_principal": "model_xml.primitives",
}
"""Public name -> its module, imported on first use: a light module of the package
(:mod:`model_xml.tendon_terms`, read when the plants are listed) is imported without MuJoCo."""

if TYPE_CHECKING:  # the same names, typed for a type checker (never run: imports stay lazy)
    from model_xml.builder import BODY as BODY
    from model_xml.builder import KEY_INITIAL as KEY_INITIAL
    from model_xml.builder import ROOT as ROOT
    from model_xml.builder import TORQUE_ACTUATORS as TORQUE_ACTUATORS
    from model_xml.builder import BodyFrame as BodyFrame
    from model_xml.builder import SpringTendon as SpringTendon
    from model_xml.builder import build_spec as build_spec
    from model_xml.builder import compile_scene as compile_scene
    from model_xml.builder import force_actuator_name as force_actuator_name
    from model_xml.builder import joint_name as joint_name
    from model_xml.builder import mass_name as mass_name
    from model_xml.builder import spring_actuator_name as spring_actuator_name
    from model_xml.builder import spring_tendons as spring_tendons
    from model_xml.builder import tendon_name as tendon_name
    from model_xml.mjcf_text import spec_to_mjcf as spec_to_mjcf
    from model_xml.mjcf_text import to_mjcf as to_mjcf
    from model_xml.primitives import MassProperties as MassProperties
    from model_xml.primitives import Primitive as Primitive
    from model_xml.primitives import PrimitiveKind as PrimitiveKind
    from model_xml.primitives import mass_properties as mass_properties
    from model_xml.primitives import match_axes as match_axes
    from model_xml.primitives import paper_example1_primitives as paper_example1_primitives
    from model_xml.primitives import primitive_spec as primitive_spec
    from model_xml.primitives import rod_in_principal as rod_in_principal

__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())

__all__ = [
    "BODY",
    "KEY_INITIAL",
    "ROOT",
    "TORQUE_ACTUATORS",
    "BodyFrame",
    "MassProperties",
    "Primitive",
    "PrimitiveKind",
    "SpringTendon",
    "build_spec",
    "compile_scene",
    "force_actuator_name",
    "joint_name",
    "mass_name",
    "mass_properties",
    "match_axes",
    "paper_example1_primitives",
    "primitive_spec",
    "rod_in_principal",
    "spec_to_mjcf",
    "spring_actuator_name",
    "spring_tendons",
    "tendon_name",
    "to_mjcf",
]
