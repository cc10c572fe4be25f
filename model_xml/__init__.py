"""MJCF twin of a scene: :func:`build_spec` (MuJoCo's ``MjSpec``), :func:`to_mjcf` (full-precision
text), the geometry-primitive description of BR (:mod:`model_xml.primitives`) and the checked-in
MJCF files of the four paper scenes (:mod:`model_xml.regenerate`)."""

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
