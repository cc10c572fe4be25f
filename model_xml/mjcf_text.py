"""MJCF text with full floating-point precision.

``MjSpec.to_xml()`` writes about 6 significant digits (recompiling changes ``qacc`` by ~1e-9
relative) and, in MuJoCo 4.0.0, drops an explicit ``<inertial>`` whose ``pos`` is zero. The text is
therefore taken from ``to_xml()`` for its structure and every numeric attribute this project sets is
rewritten from the spec with ``repr`` precision (shortest round-tripping decimal), and each
explicit inertial is written in full.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from analytic.scene import Scene

if TYPE_CHECKING:
    from model_xml.builder import BodyFrame


def _num(values: Any) -> str:
    arr = np.atleast_1d(np.asarray(values, dtype=float))
    return " ".join(repr(float(x)) for x in arr)


def _named(spec_items: Iterable[Any]) -> dict[str, Any]:
    return {it.name: it for it in spec_items if it.name}


def spec_to_mjcf(spec: mujoco.MjSpec) -> str:
    """Full-precision MJCF for a spec built by :func:`model_xml.build_spec`."""
    root = ET.fromstring(spec.to_xml())

    opt = root.find("option")
    if opt is None:
        opt = ET.SubElement(root, "option")
    opt.set("timestep", _num(spec.option.timestep))
    opt.set("gravity", _num(spec.option.gravity))

    bodies = _named(spec.bodies)
    joints = _named(spec.joints)
    geoms = _named(spec.geoms)
    tendons = _named(spec.tendons)
    actuators = _named(spec.actuators)
    keys = _named(spec.keys)

    for el in root.iter("body"):
        b = bodies[el.attrib["name"]]
        el.set("pos", _num(b.pos))
        el.set("quat", _num(b.quat))
        if b.explicitinertial:
            inert = el.find("inertial")
            if inert is None:
                inert = ET.Element("inertial")
                el.insert(0, inert)
            inert.attrib.clear()
            inert.set("pos", _num(b.ipos))
            inert.set("quat", _num(b.iquat))
            inert.set("mass", _num(b.mass))
            inert.set("diaginertia", _num(b.inertia))
    for el in root.iter("joint"):
        name = el.get("name")
        if name in joints and el.get("type") != "free":
            el.set("axis", _num(joints[name].axis))
    for el in root.iter("geom"):
        g = geoms[el.attrib["name"]]
        el.set("size", _num(g.size[: _geom_nsize(g.type)]))
        el.set("pos", _num(g.pos))
        el.set("quat", _num(g.quat))
    tend = root.find("tendon")
    if tend is not None:
        for el in tend.iter("fixed"):
            t = tendons[el.attrib["name"]]
            el.set("stiffness", _num(t.stiffness))
            el.set("springlength", _num(t.springlength))
    act = root.find("actuator")
    if act is not None:
        for el in act:
            a = actuators[el.attrib["name"]]
            el.set("gear", _num(a.gear))
            if a.biastype != mujoco.mjtBias.mjBIAS_NONE:
                el.set("biasprm", _num(a.biasprm))
                el.set("gainprm", _num(a.gainprm))
    kf = root.find("keyframe")
    if kf is not None:
        for el in kf.iter("key"):
            k = keys[el.attrib["name"]]
            el.set("qpos", _num(k.qpos))
            el.set("qvel", _num(k.qvel))
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="unicode") + "\n"


def _geom_nsize(gtype: Any) -> int:
    return {
        mujoco.mjtGeom.mjGEOM_SPHERE: 1,
        mujoco.mjtGeom.mjGEOM_CYLINDER: 2,
        mujoco.mjtGeom.mjGEOM_CAPSULE: 2,
    }.get(gtype, 3)


def to_mjcf(scene: Scene, body_frame: BodyFrame | None = None) -> str:
    """The scene's MuJoCo twin as full-precision MJCF text (``body_frame`` as in ``build_spec``)."""
    from model_xml.builder import build_spec

    return spec_to_mjcf(build_spec(scene, body_frame))
