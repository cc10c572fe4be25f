"""MJCF twin of a scene: :func:`build_spec` (MuJoCo's ``MjSpec``), :func:`to_mjcf` (full-precision
text), the geometry-primitive description of BR (:mod:`model_xml.primitives`) and the checked-in
MJCF files of the four paper scenes (:mod:`model_xml.regenerate`)."""

from model_xml.builder import (
    BODY,
    KEY_INITIAL,
    ROOT,
    TORQUE_ACTUATORS,
    BodyFrame,
    SpringTendon,
    build_spec,
    compile_scene,
    force_actuator_name,
    joint_name,
    mass_name,
    spring_actuator_name,
    spring_tendons,
    tendon_name,
)
from model_xml.mjcf_text import spec_to_mjcf, to_mjcf
from model_xml.primitives import (
    MassProperties,
    Primitive,
    PrimitiveKind,
    mass_properties,
    match_axes,
    paper_example1_primitives,
    primitive_spec,
    rod_in_principal,
)

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
