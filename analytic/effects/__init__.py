"""Named effects and option enums shared by every engine.

A scene lists the effects it simulates; each engine assembles its model from that list only, so an
effect that is off is never computed (not computed and multiplied by zero).
"""

from __future__ import annotations

from enum import StrEnum


class Effect(StrEnum):
    """One physical or control effect that a scene may switch on."""

    GRAVITY = "gravity"
    """Uniform gravity on BR and every mass (Eq. 46)."""
    SPRINGS_LINEAR = "springs.linear"
    """Linear spring elements ``k_l`` (Eq. 38, quadratic potential)."""
    SPRINGS_CUBIC = "springs.cubic"
    """Cubic spring elements ``k_n`` (Eq. 38, quartic potential)."""
    SPRINGS_DAMPING = "springs.damping"
    """Viscous damping ``c`` of the spring elements (:mod:`analytic.effects.damping`)."""
    MASS_INERTIA = "mass_inertia"
    """Rotational inertia of the sliding masses (Remark 1, Eq. 54)."""
    CONTROL_OMEGA = "control.omega"
    """Angular-velocity tracking constraint (Eqs. 82-86)."""
    CONTROL_MASSES = "control.masses"
    """Mass-position tracking constraint (Eqs. 77-81, subsets per Remark 4)."""
    EXTERNAL_TORQUE = "external_torque"
    """A given body-axis torque (Remark 2, Eq. 61)."""


CONTROL_EFFECTS = frozenset({Effect.CONTROL_OMEGA, Effect.CONTROL_MASSES})


class Weighting(StrEnum):
    """Cost weighting ``N`` of the control cost ``J = Q^C^T N Q^C`` (Appendix B, Eq. B10)."""

    M_INV = "M^-1"
    """Gauss's principle (Eq. 74, B12): the paper's default."""
    M_INV2 = "M^-2"
    """Eq. B13."""
    IDENTITY = "identity"
    """Plain Euclidean norm of the generalized control force."""


class SolverMethod(StrEnum):
    """scipy ``solve_ivp`` methods the analytic engine accepts."""

    DOP853 = "DOP853"
    RK45 = "RK45"
    RK23 = "RK23"
    RADAU = "Radau"
    BDF = "BDF"
    LSODA = "LSODA"


class Stepper(StrEnum):
    """Which loop steps the analytic plant's integrator (its right-hand side is :class:`Backend`'s)."""

    AUTO = "auto"
    """The compiled loop where it applies (DOP853, RK45 or RK23 on the compiled right-hand side, with
    CyRK installed), else scipy's."""
    COMPILED = "compiled"
    """CyRK's C++ Runge-Kutta loop over the compiled right-hand side
    (:mod:`analytic.compiled_stepping`); an error where it does not apply."""
    SCIPY = "scipy"
    """scipy's ``OdeSolver`` stepped from Python (:mod:`analytic.stepping`): the reference."""


class Backend(StrEnum):
    """How the analytic engine evaluates its right-hand side."""

    AUTO = "auto"
    """The compiled kernel when numba is installed and the case is structured, else numpy."""
    NUMPY = "numpy"
    """The reference implementation (:class:`analytic.model.TumblingModel`)."""
    NUMBA = "numba"
    """The compiled O(n) kernel (:mod:`analytic.fast`); an error when numba is missing."""


class MjIntegrator(StrEnum):
    """MuJoCo integrators (``mjtIntegrator``) by their MJCF names."""

    EULER = "Euler"
    RK4 = "RK4"
    IMPLICIT = "implicit"
    IMPLICITFAST = "implicitfast"


class Precision(StrEnum):
    """The floating-point format an accelerated engine (MJX, MuJoCo Warp) computes in."""

    FLOAT32 = "float32"
    """IEEE single precision (ε = 1.19e-7): what GPUs run fast, the accelerated engines' usual case."""
    FLOAT64 = "float64"
    """IEEE double precision (ε = 2.2e-16), as MuJoCo's C engine and the analytic plant."""


class SpringModel(StrEnum):
    """How the MuJoCo twin represents the rod springs."""

    TENDON = "tendon"
    """Fixed tendons with native polynomial stiffness (energy counted by MuJoCo)."""
    ACTUATOR = "actuator"
    """One general actuator per spring (affine bias plus a user-bias cubic term)."""


class ShapeKind(StrEnum):
    """Pictures of BR (massless, for viewers only)."""

    NONE = "none"
    BOX_AND_ROD = "box_and_rod"
    HOLLOW_CYLINDER_AND_ROD = "hollow_cylinder_and_rod"
