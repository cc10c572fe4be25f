"""A scene given as nested dicts (the parsed TOML) validated into a
:class:`~analytic.scene.records.Scene`.

A scene is data only: every key is read through its declaration (:mod:`analytic.scene.schema`),
each table by its parser (:mod:`analytic.scene.parsers`), then the cross-field rules
(:mod:`analytic.scene.rules`, :mod:`~analytic.scene.twin`, :mod:`~analytic.scene.overflow`) are
checked. Every error is a :class:`ValueError` whose message starts with the dotted name of the
offending field and shows the offending value, e.g. ``masses.mass[1]: must be positive (got -3.0)``.

Units are SI. Frames: vectors marked *body* are in BR's principal axes at its centre of mass C
(the paper's xyz); vectors marked *inertial* are in XYZ with Z up. Quaternions are w-first.
Mass and control indices in files are 1-based, as in the paper (masses 1, 2, 4 of Example 2); the
loaded records hold 0-based indices.

Every key, with its type, unit, default and meaning, is declared in :mod:`analytic.scene.schema`
(rendered as ``docs/scene-format.md``); ``analytic/scenes/paper_example1.toml`` is a fully commented
example of every table, ``analytic/scenes/spacecraft_slosh.toml`` one of a system beyond the paper.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from analytic.effects import Effect
from analytic.scene.nesting import check_nesting
from analytic.scene.overflow import check_initial_quantities
from analytic.scene.parsers import (
    parse_body,
    parse_control,
    parse_external_torque,
    parse_initial,
    parse_masses,
    parse_mujoco,
    parse_output,
    parse_rod,
    parse_solver,
    parse_springs,
    parse_thresholds,
)
from analytic.scene.records import SceneRecord, Stabilization
from analytic.scene.rules import (
    check_effects_consistent,
    warn_masses_off_the_drawn_rod,
    warn_unused_tables,
)
from analytic.scene.schema import DEFAULT_GRAVITY, Kind
from analytic.scene.table import Table, refuse_unknown_keys
from analytic.scene.twin import check_horizon_fits_mujoco
from analytic.scene.values import frozen, show


@dataclass(frozen=True)
class Scene(SceneRecord):
    """A validated scene. Build one with :func:`~analytic.scene.load_scene` or
    :func:`scene_from_dict`."""

    def with_effects(self, effects: set[Effect] | frozenset[Effect]) -> Scene:
        """A copy with another effect set, validated like a loaded scene."""
        new = dataclasses.replace(self, effects=frozenset(effects))
        check_effects_consistent(new)
        check_initial_quantities(new)
        return new


def scene_from_dict(data: Mapping[str, Any], source: str = "") -> Scene:
    """Validate a scene given as nested dicts (the parsed TOML)."""
    check_nesting(data, source)
    if not isinstance(data, Mapping):
        raise ValueError(f"scene: must be a table (got {show(data)})")
    refuse_unknown_keys(data)
    top = Table(data, "")

    meta = top.required_table("scene")
    name = meta.string("name")
    description = meta.string("description")
    effects_raw = meta.raw("effects", kinds=(Kind.CHOICES,))
    if not isinstance(effects_raw, list):
        raise ValueError(
            f"scene.effects: must be a list of effect names (got {show(effects_raw)})"
        )
    effects = set()
    for i, e in enumerate(effects_raw):
        try:
            effects.add(Effect(e))
        except ValueError:
            allowed = ", ".join(repr(x.value) for x in Effect)
            raise ValueError(
                f"scene.effects[{i}]: unknown effect {show(e)} (allowed: {allowed})"
            ) from None
    meta.finish()

    body = parse_body(top.required_table("body"))
    rod = parse_rod(top.required_table("rod"))
    masses = parse_masses(top.table("masses"), rod.axis)
    n = masses.n
    springs = parse_springs(top.table("springs"), n)

    g_tab = top.table("gravity")
    gravity = frozen(np.array(DEFAULT_GRAVITY))
    if g_tab is not None:
        gravity = g_tab.vector("vector", 3)
        g_tab.finish()

    initial = parse_initial(top.table_or_empty("initial"), n)

    s_tab = top.table_or_empty("stabilization")
    stab = Stabilization(
        delta1=s_tab.number("delta1", nonneg=True), delta2=s_tab.number("delta2", nonneg=True)
    )
    s_tab.finish()

    control = parse_control(top.table_or_empty("control"), n)
    ext = parse_external_torque(top.table("external_torque"))
    solver = parse_solver(top.table_or_empty("solver"))
    output = parse_output(top.table_or_empty("output"))
    mj = parse_mujoco(top.table_or_empty("mujoco"))

    # [thresholds] belongs to later layers (the comparison's names are checked where they are
    # resolved, validation.compare.thresholds); here its shape: numbers, or {value, reason} tables.
    extra = {}
    th = top.table("thresholds")
    if th is not None:
        extra["thresholds"] = parse_thresholds(th)
    # [hard_case] belongs to the hard-case suite, which validates it (validation/studies/hard_cases/
    # criterion.py); here only that it is a table, kept verbatim.
    hc = top.table("hard_case")
    if hc is not None:
        extra["hard_case"] = dict(hc.data)
    # [mjx]: the MJX plant's settings (mj_bridge/mjx_settings.py validates them), kept verbatim.
    mx = top.table("mjx")
    if mx is not None:
        extra["mjx"] = dict(mx.data)
    top.finish()

    scene = Scene(
        name=name,
        description=description,
        effects=frozenset(effects),
        body=body,
        rod=rod,
        masses=masses,
        springs=springs,
        gravity=gravity,
        initial=initial,
        stabilization=stab,
        control=control,
        external_torque=ext,
        solver=solver,
        output=output,
        mujoco=mj,
        source=source,
        extra=extra,
    )
    check_effects_consistent(scene)
    check_initial_quantities(scene)
    check_horizon_fits_mujoco(scene)
    warn_unused_tables(data, scene)
    warn_masses_off_the_drawn_rod(scene)
    return scene


__all__ = ["Scene", "scene_from_dict"]
