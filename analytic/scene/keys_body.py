"""The scene format's keys of the body, rod, masses, springs and gravity: one :class:`~analytic.scene.key.Key` each (type, unit, default,
bounds, meaning, the effect that reads it), in the order of the reference.

Part of :data:`analytic.scene.schema.KEYS`, the one table the loader, its cross-field rules and
``docs/scene-format.md`` read.
"""

from __future__ import annotations

from analytic.effects import Effect, ShapeKind
from analytic.effects.registry import SPRING_LAWS
from analytic.scene.key import DEFAULT_GRAVITY, Key, Kind, Need

_R = Need.REQUIRED
_C = Need.CONDITIONAL

_SHAPE_ROD = 'kind is not "none"'
_BOX = 'kind = "box_and_rod"'
_CYL = 'kind = "hollow_cylinder_and_rod"'

BODY_KEYS: tuple[Key, ...] = (
    # ---- [scene] -------------------------------------------------------------------------------
    Key(
        "", "scene", Kind.TABLE, "", "What the scene is called and which effects it simulates.", _R
    ),
    Key(
        "scene",
        "name",
        Kind.STRING,
        "",
        "The scene's name, shown in reports; default output directories are named after it, "
        "reduced to `[A-Za-z0-9._-]` (a name never chooses a path).",
        _R,
    ),
    Key("scene", "description", Kind.STRING, "", "One line for reports.", default=""),
    Key(
        "scene",
        "effects",
        Kind.CHOICES,
        "",
        "What is simulated, from the effects listed above. An effect that is not listed is not "
        "computed at all, and data given for it is ignored with one warning.",
        _R,
        choices=Effect,
    ),
    # ---- [body] --------------------------------------------------------------------------------
    Key(
        "",
        "body",
        Kind.TABLE,
        "",
        "The rigid body BR (body B plus rod R): its mass and principal moments of inertia. Its "
        "principal axes at its centre of mass C are the body axes of every other table.",
        _R,
    ),
    Key(
        "body",
        "mass",
        Kind.NUMBER,
        "kg",
        "`m_BR`, the mass of BR.",
        _R,
        bounds="{MJ_MINVAL} … {MAX_MASS} kg",
    ),
    Key(
        "body",
        "inertia",
        Kind.VECTOR3,
        "kg·m²",
        "Principal moments `J = diag(J_x, J_y, J_z)` of BR about C.",
        _R,
        bounds="> 0, at most {MAX_INERTIA} kg·m²; A + B ≥ C",
    ),
    Key(
        "body",
        "shape",
        Kind.TABLE,
        "",
        "Pictures of BR for the viewers; massless, never used by the dynamics.",
        default_text="no picture",
    ),
    # ---- [body.shape] --------------------------------------------------------------------------
    Key("body.shape", "kind", Kind.CHOICE, "", "What to draw.", _R, choices=ShapeKind),
    Key(
        "body.shape",
        "box_half_sizes",
        Kind.VECTOR3,
        "m",
        "Half the box's edge lengths, along the box's own axes.",
        _C,
        when=f"required with {_BOX}",
        bounds="> 0",
    ),
    Key(
        "body.shape",
        "box_center",
        Kind.VECTOR3,
        "m",
        "The box's centre, body axes (from C).",
        _C,
        default=[0.0, 0.0, 0.0],
        when=f"only with {_BOX}",
    ),
    Key(
        "body.shape",
        "box_rotation",
        Kind.MATRIX3,
        "",
        "Body-from-box rotation (columns: the box's axes in body axes); the nearest rotation is "
        "taken.",
        _C,
        default_text="identity",
        when=f"only with {_BOX}",
        bounds="within {ROTATION_REFUSE_TOL} of a rotation",
    ),
    Key(
        "body.shape",
        "cylinder_radius",
        Kind.NUMBER,
        "m",
        "Outer radius of the hollow cylinder (centred on C).",
        _C,
        when=f"required with {_CYL}",
        bounds="> 0",
    ),
    Key(
        "body.shape",
        "cylinder_length",
        Kind.NUMBER,
        "m",
        "Outer length of the cylinder, end plates included.",
        _C,
        when=f"required with {_CYL}",
        bounds="> 0",
    ),
    Key(
        "body.shape",
        "cylinder_thickness",
        Kind.NUMBER,
        "m",
        "Thickness of the cylinder's wall and end plates.",
        _C,
        when=f"required with {_CYL}",
        bounds="> 0",
    ),
    Key(
        "body.shape",
        "cylinder_axis",
        Kind.VECTOR3,
        "",
        "Direction of the cylinder's axis, body axes (any nonzero length).",
        _C,
        when=f"required with {_CYL}",
    ),
    Key(
        "body.shape",
        "rod_radius",
        Kind.NUMBER,
        "m",
        "Radius of the drawn rod.",
        _C,
        default=0.05,
        when=f"only with {_SHAPE_ROD}",
        bounds="> 0",
    ),
    Key(
        "body.shape",
        "rod_start",
        Kind.NUMBER,
        "m",
        "Where the drawn rod starts, along `a` from O' (negative: behind O').",
        _C,
        default=0.0,
        when=f"only with {_SHAPE_ROD}",
    ),
    Key(
        "body.shape",
        "rod_length",
        Kind.NUMBER,
        "m",
        "Length of the drawn rod, from `rod_start` along `a`. A picture only: the masses slide on "
        "an unbounded line; a `masses.p_e` or `initial.p` off the drawn rod gets one warning.",
        _C,
        default=1.0,
        when=f"only with {_SHAPE_ROD}",
        bounds="> 0",
    ),
    # ---- [rod] ---------------------------------------------------------------------------------
    Key(
        "",
        "rod",
        Kind.TABLE,
        "",
        "The line fixed in BR along which the masses slide: through O' along `a`.",
        _R,
    ),
    Key(
        "rod",
        "axis",
        Kind.VECTOR3,
        "",
        "The unit vector `a` along the rod, body axes; positions `p` count along it from O'.",
        _R,
        bounds="unit length within {AXIS_REFUSE_TOL}; one off 1 by more than "
        "{AXIS_NORMALISE_TOL} is normalised with a one-line warning naming its norm",
    ),
    Key(
        "rod",
        "offset",
        Kind.VECTOR3,
        "m",
        "`d`, the vector from C to the rod's reference point O', body axes (zero: the rod passes "
        "through C).",
        _R,
    ),
    # ---- [masses] ------------------------------------------------------------------------------
    Key(
        "",
        "masses",
        Kind.TABLE,
        "",
        "The n masses sliding along the rod (mass i is `m_i` of the paper, 1-based).",
        default_text="no masses (n = 0)",
    ),
    Key(
        "masses",
        "mass",
        Kind.VECTOR_N,
        "kg",
        "`m_i`; the length of this list is n.",
        _R,
        bounds="each {MJ_MINVAL} … {MAX_MASS} kg; n ≤ {MAX_MASSES}",
    ),
    Key(
        "masses",
        "p_e",
        Kind.VECTOR_N,
        "m",
        "The springs' rest positions `p_e,i`: where each mass sits, along `a` from O', when every "
        "spring is at its rest length (Eq. 38). Any order; masses may pass each other.",
        _R,
    ),
    Key(
        "masses",
        "ring_radius",
        Kind.VECTOR_N,
        "m",
        "Each mass a thin ring of this radius about the rod: axial moment `m r²`, transverse "
        "`m r²/2` (Remark 1, Eq. 62). One of `ring_radius`, `inertia_axial` + "
        "`inertia_transverse`, `inertia_body`; used with the effect `mass_inertia`.",
        _C,
        when="optional; not with the other inertia keys",
        bounds="≥ 0",
        effect=Effect.MASS_INERTIA,
    ),
    Key(
        "masses",
        "inertia_axial",
        Kind.VECTOR_N,
        "kg·m²",
        "Each mass's moment of inertia about the rod through its own centre (axisymmetric mass); "
        "given with `inertia_transverse`.",
        _C,
        when="optional, with inertia_transverse; not with the other inertia keys",
        bounds="≥ 0, at most {MAX_INERTIA} kg·m², at most twice the transverse moment",
        effect=Effect.MASS_INERTIA,
    ),
    Key(
        "masses",
        "inertia_transverse",
        Kind.VECTOR_N,
        "kg·m²",
        "Each mass's moment of inertia about any axis perpendicular to the rod through its centre.",
        _C,
        when="optional, with inertia_axial; not with the other inertia keys",
        bounds="≥ 0, at most {MAX_INERTIA} kg·m²",
        effect=Effect.MASS_INERTIA,
    ),
    Key(
        "masses",
        "inertia_body",
        Kind.MATRICES_N,
        "kg·m²",
        "Each mass's full inertia matrix about its own centre, body axes (`P_iᵀ J_i P_i` of "
        "Remark 1, Eq. 54).",
        _C,
        when="optional; not with the other inertia keys",
        bounds="symmetric, positive semidefinite, A + B ≥ C; entries at most {MAX_INERTIA} kg·m² "
        "in magnitude",
        effect=Effect.MASS_INERTIA,
    ),
    # ---- [springs] -----------------------------------------------------------------------------
    Key(
        "",
        "springs",
        Kind.TABLE,
        "",
        "The n + 1 spring elements wall – m_1 – m_2 – … – m_n – wall (Eq. 38); see *Springs* above.",
        default_text="no springs",
    ),
    *(law.key for law in SPRING_LAWS),  # declared with their laws (analytic.effects)
    # ---- [gravity] -----------------------------------------------------------------------------
    Key(
        "",
        "gravity",
        Kind.TABLE,
        "",
        "Uniform gravity on BR and every mass (Eq. 46), acting only with the effect `gravity`.",
        default_text=f"vector = [{', '.join(f'{g:g}' for g in DEFAULT_GRAVITY)}]",
        effect=Effect.GRAVITY,
    ),
    Key("gravity", "vector", Kind.VECTOR3, "m/s²", "The acceleration of gravity, inertial.", _R),
)
"""``[scene]``, ``[body]``, ``[body.shape]``, ``[rod]``, ``[masses]``, ``[springs]``, ``[gravity]``."""
