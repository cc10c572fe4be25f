"""Named tolerances of the tests, each an :class:`analytic.threshold.Threshold` with its unit and
the reason for its number.

Only the tests use these; the comparison's thresholds (which a scene may override) are
``validation/compare/thresholds.py``, in the same record type. Tests read a bound as ``tol.NAME.value``.

A relative tolerance has unit "1" and its reason says what it is relative to (``max|x - y| /
max|y|`` unless stated); the record's ``relative``/``floor`` fields belong to the comparison's
scale machinery and stay at their defaults here. Each record's ``name`` is its name in this module
(``tests/cross/test_tolerances.py`` checks it, and that every record has a unit and a reason).
"""

from __future__ import annotations

from collections.abc import Mapping

from analytic.threshold import Threshold

# =================================================================================================
# The analytic engine: the paper examples (test_paper_examples.py, test_spacecraft.py)
# =================================================================================================

QUAT_NORM_UNCONTROLLED = Threshold(
    "QUAT_NORM_UNCONTROLLED",
    1e-13,
    "1",
    "max ||u|² - 1| at the integrator's steps, the paper examples uncontrolled: 20 s at rtol 1e-12 "
    "/ atol 1e-13 (DOP853). The paper reports O(1e-15) for |u|² - 1 with ode113 at the "
    "integrator's steps; an 8th-order method at rtol 1e-12 makes local errors ~1e-13 in u, so "
    "1e-13 is the tolerance-level bound.",
)
DRIFT_UNCONTROLLED = Threshold(
    "DRIFT_UNCONTROLLED",
    1e-11,
    "1",
    "Relative drift of angular momentum and energy over 20 s, the paper examples uncontrolled: the "
    "balances are integrated quantities (q, q̇ at rtol 1e-12), so drift must stay within ten times "
    "the tolerance.",
)
BALANCE_CONTROLLED = Threshold(
    "BALANCE_CONTROLLED",
    1e-9,
    "1",
    "The paper examples controlled. The balances (L - L0 - ∫Sτ, E - E0 - W) close to a bound that "
    "reflects the integration tolerance times the amplification by the (large) control forces.",
)
_ERROR_DYNAMICS = (
    "e_ω(t) = e_ω(0) exp(-γ t) and e_p solves ë + α ė + β e = 0 exactly for the exact dynamics; "
    "the integrated solution follows them to within an absolute error set by the tolerance: the "
    "error state is a difference of O(10) rad/s and O(1) m quantities integrated at rtol 1e-12 -> "
    "1e-9."
)
ERROR_DYNAMICS_ABS_OMEGA = Threshold("ERROR_DYNAMICS_ABS_OMEGA", 1e-9, "rad/s", _ERROR_DYNAMICS)
ERROR_DYNAMICS_ABS_P = Threshold("ERROR_DYNAMICS_ABS_P", 1e-9, "m", _ERROR_DYNAMICS)
ORDER_FACTOR = Threshold(
    "ORDER_FACTOR",
    10.0,
    "1",
    'The paper\'s orders of magnitude (docs/errata.md, "What reproduced means"): "O(1e-k)" '
    "accepted as |e| < 10^(-k+1).",
)
FORCE_AT_C = Threshold(
    "FORCE_AT_C",
    0.0,
    "N",
    "Force at C for the Gauss cost: structurally zero (A has no R columns).",
)

# =================================================================================================
# The MuJoCo twin (test_mjcf.py, test_mj_bridge.py, test_coordinates.py).
# Relative errors are max|x - y| / max|y| unless stated.
# =================================================================================================

# --- model_xml -----------------------------------------------------------------------------------
XML_VS_SPEC_QACC_REL = Threshold(
    "XML_VS_SPEC_QACC_REL",
    1e-14,
    "1",
    "Compiling the full-precision MJCF and the spec must give the same qacc: repr() round-trips "
    "every double exactly, so only the parser's last-bit rounding is allowed.",
)
SPRING_ACTUATOR_VS_TENDON_REL = Threshold(
    "SPRING_ACTUATOR_VS_TENDON_REL",
    1e-12,
    "1",
    "Spring actuators vs native tendon springs: the same polynomial evaluated in a different order.",
)
PRIMITIVE_SIG_DIGITS_REL = Threshold(
    "PRIMITIVE_SIG_DIGITS_REL",
    5e-4,
    "1",
    "The paper prints Example 1's mass and moments to 4 significant digits (half a unit in the 4th).",
)
PRIMITIVE_ROD_ABS = Threshold(
    "PRIMITIVE_ROD_ABS",
    1e-3,
    "m (d), 1 (a)",
    "The paper prints a and d to 4 decimals (m / unit vector); they are checked to 1e-3.",
)

# --- pointwise dynamics and control --------------------------------------------------------------
FAST_VS_NUMPY_REL = Threshold(
    "FAST_VS_NUMPY_REL",
    1e-12,
    "1",
    "The compiled kernel vs the numpy model (analytic.model) at one state, relative to the "
    "largest entry: the same closed forms evaluated in a different order and with different "
    "solves (structured LDLᵀ against dense), so only round-off separates them; at the paper's "
    "conditioning (M entries up to ~1e8) that is ~1e-14 relative, 1e-12 leaves two decades.",
)
ARRAY_VS_NUMPY_REL = Threshold(
    "ARRAY_VS_NUMPY_REL",
    1e-12,
    "1",
    "The array form of the model and controller (analytic.array_model: numpy with an LU solve and "
    "the masked rank decision; JAX eager, jit and vmap) vs TumblingModel.acceleration (the same "
    "formulas with scipy's Cholesky and the branching pinv), float64, Euclidean norm relative to "
    "the reference's (the residual relative to |b_c| + |A_c||q̈|): only the order of operations "
    "and the factorisation differ, ~eps x cond(M_α) ~ 1e-14 for the generator's scenes (measured "
    "worst ~1e-14); 1e-12 leaves two decades.",
)
ARRAY_FLOAT32_REL = Threshold(
    "ARRAY_FLOAT32_REL",
    1e-3,
    "1",
    "The array form in float32 vs float64 at the same (float32-representable) state, q̈ and τ "
    "relative to float64's: float32 round-off eps32 = 1.19e-7 amplified by the solve, ~cond(M_α) "
    "(up to ~1e3 for the generator's scenes: J over three decades, masses J/10), and by the "
    "cancellation in Q^C = M q̈ - Q; 1e-3 is eps32 x ~1e4 (measured worst 3.5e-5 over the test's "
    "scene kinds, three seeds each).",
)
POINTWISE_QDDOT_REL = Threshold(
    "POINTWISE_QDDOT_REL",
    1e-9,
    "1",
    "Analytic vs MuJoCo q̈ at a state: two exact formulations of the same dynamics; round-off in M "
    "(entries up to ~1e8 for Example 1) and the dense solves stays well below this.",
)
POINTWISE_CONTROL_REL = Threshold(
    "POINTWISE_CONTROL_REL",
    1e-9,
    "1",
    "Analytic controller (paper coordinates + quaternion constraint) vs Udwadia–Kalaba from "
    "MuJoCo's M and forces (MuJoCo coordinates): same law, different algebra; round-off only.",
)
STATE_MAP_ROUNDTRIP = Threshold(
    "STATE_MAP_ROUNDTRIP",
    1e-13,
    "1",
    "paper -> MuJoCo -> paper state maps: a few rotations and cross products of O(1..100) values.",
)

# --- trajectories --------------------------------------------------------------------------------
EX1_POSITION_ABS_M = Threshold(
    "EX1_POSITION_ABS_M",
    1e-9,
    "m",
    "Example 1 uncontrolled, 20 s, RK4 dt = 2.5e-4 vs analytic rtol 1e-12 (position of C and of "
    "every mass, m).",
)
EX1_ATTITUDE_RAD = Threshold(
    "EX1_ATTITUDE_RAD",
    1e-9,
    "rad",
    "Same run (Example 1 uncontrolled, 20 s, RK4 dt = 2.5e-4 vs analytic rtol 1e-12): attitude "
    "angle between the two plants, rad.",
)
_CONVERGENCE = (
    "Observed RK4 order in a dt-halving test: 4 ± 0.3 (a controller held over the step gives 1)."
)
CONVERGENCE_ORDER = Threshold("CONVERGENCE_ORDER", 4.0, "1", _CONVERGENCE)
CONVERGENCE_ORDER_TOL = Threshold("CONVERGENCE_ORDER_TOL", 0.3, "1", _CONVERGENCE)
TRACKING_FACTOR = Threshold(
    "TRACKING_FACTOR",
    10.0,
    "1",
    "Controlled runs: MuJoCo's tracking error at 20 s within this factor of the analytic plant's.",
)
UNCONTROLLED_ROD_FORCE_REL = Threshold(
    "UNCONTROLLED_ROD_FORCE_REL",
    1e-12,
    "1",
    "Rod force on masses outside the tracked set, relative to the largest rod force: Gauss's "
    "weighting puts the control only on tracked coordinates (Q^C = A_cᵀ μ).",
)
RK4_INVARIANT_DRIFT_REL = Threshold(
    "RK4_INVARIANT_DRIFT_REL",
    1e-10,
    "1",
    "MuJoCo RK4 at dt = 1e-3, 20 s uncontrolled: energy and momentum conserved to this.",
)
BALANCE_REL_CONTROLLED = Threshold(
    "BALANCE_REL_CONTROLLED",
    1e-7,
    "1",
    "Controlled runs at dt = 1e-3: energy and angular-momentum balances with the work/impulse "
    "integrated by the same RK4 stages; RK4 truncation ~ (ω h)^4 over 20 s with ω up to ~15 rad/s.",
)
MJ_ENERGY_VS_PAPER_REL = Threshold(
    "MJ_ENERGY_VS_PAPER_REL",
    1e-12,
    "1",
    "MuJoCo's own d.energy (potential + kinetic) vs the paper-coordinate energy at the same state.",
)
MJ_ANGMOM_VS_PAPER_REL = Threshold(
    "MJ_ANGMOM_VS_PAPER_REL",
    1e-12,
    "1",
    "MuJoCo's subtree angular momentum about the system CoM vs the paper-coordinate one.",
)
CONTROLLER_SOURCES_TRAJ_REL = Threshold(
    "CONTROLLER_SOURCES_TRAJ_REL",
    1e-11,
    "1",
    "Compiled, numpy and MuJoCo-matrix controllers driving MuJoCo for 0.5 s: the same law "
    "evaluated three ways, so trajectories, torques and work differ by round-off (~1e-14 "
    "measured) only.",
)
CLOSED_FORM_ERROR_REL = Threshold(
    "CLOSED_FORM_ERROR_REL",
    1e-8,
    "1",
    "Controlled Example 2 at dt = 2e-3 over 1 s: tracking errors vs the closed-form error "
    "dynamics, relative to their largest value; RK4 truncation of the e^{-γt} / damped-oscillator "
    "solutions.",
)
KINEMATICS_REL = Threshold(
    "KINEMATICS_REL",
    1e-13,
    "1",
    "MuJoCo's own kinematics (xipos, ximat, object velocity) at a mapped state vs the paper's "
    "quantities: a few rotations of O(1..100) values.",
)
SPRING_CLOSED_FORM_REL = Threshold(
    "SPRING_CLOSED_FORM_REL",
    1e-13,
    "1",
    "Tendon spring forces and MuJoCo's spring energy vs Eq. (38) evaluated directly.",
)
INERTIA_SUM_REL = Threshold(
    "INERTIA_SUM_REL",
    1e-13,
    "1",
    "System inertia about C assembled from MuJoCo's bodies vs J + Σ m_i(|d|²I - d dᵀ).",
)
TUBE_MESH_REL = Threshold(
    "TUBE_MESH_REL",
    1e-6,
    "1",
    "Thick tube as a 256-gon mesh with equal-area polygons: moments off by O((2π/256)⁴) ≈ 4e-7.",
)
SHELL_CLOSED_FORM_REL = Threshold(
    "SHELL_CLOSED_FORM_REL",
    1e-9,
    "1",
    "MuJoCo's shell inertia of a closed cylinder vs the thin-shell closed forms (mass exact).",
)
FREE_MOTION_MOMENTUM_REL = Threshold(
    "FREE_MOTION_MOMENTUM_REL",
    1e-9,
    "1",
    "Without gravity the total linear momentum is constant; RK4 at dt = 2e-3 over 1 s with the "
    "stiff Example 2 springs leaves a truncation drift of the nonlinear momentum map well below "
    "this.",
)
ULP_REL = Threshold(
    "ULP_REL",
    4e-15,
    "1",
    "The same number through a handful of floating-point operations on both sides (a few ulps).",
)
MASS_FORMULA_REL = Threshold(
    "MASS_FORMULA_REL",
    1e-12,
    "1",
    "MuJoCo's geom volumes/masses vs ρ·V written out here (π and products rounded differently).",
)


# =================================================================================================
# The Drake plant (tests/mj_bridge/test_drake_plant.py): the agreement goals of the fourth engine
# =================================================================================================

DRAKE_QDDOT_REL = Threshold(
    "DRAKE_QDDOT_REL",
    1e-12,
    "1",
    "Drake's q̈ (MultibodyPlant.EvalTimeDerivatives, mapped to the paper's coordinates) against "
    "the analytic model's at one on-manifold state, |Δq̈|/|q̈|: two independent computations of "
    "the same dynamics in double precision under the same control forces, over random scenes "
    "n = 0…6 with every effect and each weighting. Seen (worst of 8 states per scene): 6.4e-15 "
    "uncontrolled, 6.7e-15 under M^-1, 4.2e-14 under M^-2 and 2.2e-14 under identity (there the "
    "analytic side's q̈ comes from its dense solve and loses cond(M) digits, as for Pinocchio); a "
    "missing or wrong term is O(1) relative.",
)
DRAKE_UNCONTROLLED_M = Threshold(
    "DRAKE_UNCONTROLLED_M",
    5e-11,
    "m",
    "Drake and analytic plants over 20 s uncontrolled, both DOP853 at rtol 1e-12 / atol 1e-13: "
    "largest distance of C and of the rod positions. Each plant's own integration error is what "
    "is left (seen: Example 1 4.5e-12 m in C, 1.2e-11 m in p; Example 2 8.1e-12 m, 9.7e-12 m); a "
    "model error (a wrong inertia, spring or gravity term) is O(1e-3) m or more after 20 s. The "
    "slow test holds random n = 3, 6 scenes (every force effect; C travels ~1 km, so each plant's "
    "own error at rtol 1e-12 is ~1.5e-9 m) and the spacecraft scene to it at rtol 2.5e-14 (seen "
    "9.1e-12, 1.9e-12 and 4.3e-14 m).",
)
DRAKE_CONTROLLED_EX1_M = Threshold(
    "DRAKE_CONTROLLED_EX1_M",
    2e-9,
    "m",
    "The controlled Example 1 over 20 s, both plants DOP853 at rtol 1e-12 / atol 1e-13, the "
    "analytic controller at Drake's state (u as integrated) in every evaluation: C, rod "
    "positions (m) and attitude angle (rad). C falls ~1.6 km while the body spins at up to "
    "~20 rad/s: each plant's integration error in C at rtol 1e-12 is ~1e-9 m (seen: Drake 1.1e-9 "
    "m, analytic 2.6e-9 m, each against its own rtol-2.5e-14 run, where the two agree to 1.9e-10 "
    "m); seen 1.7e-9 m between the plants. Handing the controller the normalised quaternion "
    "instead gives 8.0e-9 m (a closed loop that integrates less accurately), so this bound also "
    "guards that choice.",
)


# =================================================================================================
# Bounds of single tests that stood as bare numbers (test_balances.py, test_hard_cases.py)
# =================================================================================================

ERROR_DYNAMICS_ABS_OMEGA_QUICK = Threshold(
    "ERROR_DYNAMICS_ABS_OMEGA_QUICK",
    1e-7,
    "rad/s",
    "General controlled scenes (test_balances.py: random rod axis and masses, each weighting, "
    "γ = 0.8 1/s, 3 s at the quick tolerance rtol 1e-10): |e_ω(t) - e_ω(0) exp(-γ t)| (Eq. 84, "
    "docs/errata.md item 3) for |e_ω| up to 0.6 rad/s, on top of assert_allclose's default rtol "
    "1e-7. At rtol 1e-10 the integrated error follows its closed form to ~1e-10 (measured ≤ 8e-11 "
    "rad/s); 1e-7 keeps three decades for the random scenes, while a requirement stabilised at the "
    "wrong order departs by O(|e_ω|) ~ 0.1 rad/s.",
)
_EULER_REFERENCE = (
    "The hard cases' independent reference (validation.studies.hard_cases.euler_reference: Euler's "
    "equations and u̇ = ½ u ⊗ ω, DOP853 at rtol 1e-13) on an axisymmetric body whose precession is "
    "closed form (J = diag(2, 2, 3.5) kg·m², |ω| ≈ 2.2 rad/s, 10 s): its global error stays at the "
    "level of its tolerance (measured: ω 5e-14 rad/s, |u| 2e-14, L 6e-13 kg·m²/s of |L| ≈ 7.2); "
    "the bound leaves one to two decades and is far below the 1e-9 relative bounds "
    "(hard_reference_rel) by which the reference judges the plants."
)
EULER_REFERENCE_OMEGA_ABS = Threshold(
    "EULER_REFERENCE_OMEGA_ABS", 1e-11, "rad/s", "max |ω - ω_closed form|: " + _EULER_REFERENCE
)
EULER_REFERENCE_QUAT_NORM_ABS = Threshold(
    "EULER_REFERENCE_QUAT_NORM_ABS",
    1e-12,
    "1",
    "max ||u| - 1| (u is not renormalised): " + _EULER_REFERENCE,
)
EULER_REFERENCE_MOMENTUM_ABS = Threshold(
    "EULER_REFERENCE_MOMENTUM_ABS",
    1e-11,
    "kg·m²/s",
    "max |L(t) - L(0)|, L = S(u) J ω inertial (torque-free, so constant): " + _EULER_REFERENCE,
)
COM_PARABOLA_ABS_M = Threshold(
    "COM_PARABOLA_ABS_M",
    1e-9,
    "m",
    "Paper Example 1 uncontrolled, 2 s at its rtol 1e-12: the system centre of mass assembled from "
    "R, u and p against c(0) + ċ(0) t + ½ g t² (uniform gravity, internal rod and spring forces "
    "only). Integration error on a trajectory of ~20 m at rtol 1e-12 (measured 7e-13 m); a force "
    "that does not cancel between body and masses moves c by O(F t²/m_T), far above 1e-9 m.",
)

# --- trajectory files (tests/validation/external) ---------------------------------------------------
TRAJECTORY_FILE_ROUND_TRIP_REL = Threshold(
    "TRAJECTORY_FILE_ROUND_TRIP_REL",
    1e-15,
    "1",
    "A plant's trajectory written to a trajectory file (CSV: repr, the shortest text that reads "
    "back to the same double; Parquet: doubles) and read back: C, p, v, ṗ, τ, F come back bit for "
    "bit and the attitude angle is 0; ω is recomputed through u̇ = Hᵀω/(4|u|²) and H u̇, a few "
    "roundings (~2e-16 relative measured). Relative to the largest value of each quantity.",
)
JUDGED_FILE_CHECK_FRACTION = Threshold(
    "JUDGED_FILE_CHECK_FRACTION",
    1e-6,
    "1",
    "A plant's run written to a trajectory file and judged (tumble judge) against the same "
    "check of that run in run_validation, as a fraction of the check's threshold: the file holds "
    "the plant's doubles, so position, attitude, rod and velocity differences come out equal; "
    "only ω (through u̇ = Hᵀω/(4|u|²)) and the momenta and energy built from the velocities are "
    "recomputed, a few roundings (measured ≤ 1.2e-8 of the threshold, the energy balance of "
    "MuJoCo on paper_example2 over 1 s). A wrong column or frame moves a value by O(1) of it.",
)

# --- a plant's own error estimate (tests/cross/test_tightened.py) -----------------------------------
OWN_ERROR_ESTIMATE_REL = Threshold(
    "OWN_ERROR_ESTIMATE_REL",
    0.1,
    "1",
    "|estimate / true error - 1| of a plant's own error estimate (its run at the given settings "
    "against its run at Plant.tightened's settings), the true error taken against the closed-form "
    "torque-free precession of an axisymmetric body: the tightened run's own error is 1/256 of "
    "the given one for RK4 (dt / 4) and about 1/100 for an adaptive method (tolerances / 100, "
    "error about proportional to the tolerance), so the estimate is within ~1 %; 0.1 leaves a "
    "decade for an adaptive step control that is not exactly proportional (measured 0.3-0.9 %). "
    "An estimate that measured something else (a tightened run no better than the given one, or "
    "a different method) is off by O(1).",
)

# =================================================================================================
# Viscous damping of the spring elements (tests/analytic/effects/test_damping.py)
# =================================================================================================

DAMPED_OSCILLATOR_ABS = Threshold(
    "DAMPED_OSCILLATOR_ABS",
    1e-9,
    "m",
    "One mass between two damped springs, the body not rotating, no gravity: p(t) against the "
    "closed-form damped oscillator of the reduced mass (under-, critically and over-damped), "
    "amplitude O(0.1 m) over 3 s at rtol 1e-12 / atol 1e-14 (DOP853): the integrator's global "
    "error is O(1e-11), so 1e-9 leaves two decades and still fails a wrong rate or sign.",
)
DISSIPATED_ENERGY_ABS = Threshold(
    "DISSIPATED_ENERGY_ABS",
    1e-9,
    "J",
    "The same runs: the integrated D against E(0) - E(t) of the closed form (energies O(0.1 J)); "
    "and, for a plant that does not integrate D along its motion, D over its samples at 100 Hz by "
    "the fourth-order Hermite rule (error O(h⁴ D⁽⁵⁾) ~ 1e-10 for these rates).",
)

# =================================================================================================
# The accelerated plants: MuJoCo's RK4 written out, MJX (tests/mj_bridge/test_accelerated_scheme.py,
# test_mjx_plant.py)
# =================================================================================================
EPS32 = 2.0**-23
"""float32's machine epsilon, 1.19e-7: the relative spacing of float32 numbers at 1."""

RK4_MIRROR_ROUNDOFF = Threshold(
    "RK4_MIRROR_ROUNDOFF",
    1e-14,
    "SI (state units)",
    "One RK4 step of a free body with O(1) coordinates and velocities: the scheme written out and "
    "MuJoCo's mj_step on the same mj_forward differ only by the order of a few float64 "
    "operations, a few ε = 2.2e-16 of O(1) values; 1e-14 is ~45 ε, while a different position "
    "rule (the plain sum of the stage angular velocities) misses by ~1e-5 at that step.",
)
RK4_MIRROR_RUN = Threshold(
    "RK4_MIRROR_RUN",
    1e-12,
    "1",
    "200 steps (0.05 s) of Example 1: the scheme on the C engine against the C plant, relative to "
    "the run's largest coordinate (and to max(1 J, |W|) for the work): round-off of ~ε per step "
    "accumulated over 200 steps and amplified by the motion's sensitivity stays below 1e-13 "
    "(measured 1e-16); a scheme of another order or position rule differs by > 1e-9 there.",
)
MJX_F64_SHORT = Threshold(
    "MJX_F64_SHORT",
    1e-12,
    "m",
    "MJX float64 against the C plant on Example 1 with linear springs, 0.05 s: the same RK4, the "
    "same twin, the same controller, so only the two engines' forward dynamics differ by "
    "round-off (measured 6e-17 m controlled, 2e-15 m uncontrolled on positions of O(10 m)); "
    "1e-12 m is ~500 ε of the 16 m rod.",
)
MJX_F64_GOAL = Threshold(
    "MJX_F64_GOAL",
    1e-7,
    "m",
    "The goal for MJX float64 against the C plant and the analytic plant, Example 1 with linear "
    "springs, 2 s, uncontrolled and controlled: the C plant's own RK4 error at 2.5e-4 s is "
    "O(1e-9) m against the analytic plant, and MJX must not add more than a decade and a half.",
)
MJX_F32_FACTOR = Threshold(
    "MJX_F32_FACTOR",
    10.0,
    "1",
    "MJX float32 against the C plant (float64): the float32 floor is ε₃₂ = 1.19e-7 of the largest "
    "coordinate per operation, accumulating as a random walk over the run's steps; the bound is "
    "this factor × ε₃₂ × max|q| × √(steps) (0.05 s: 200 steps, max|q| ≈ 12 m -> 2e-4 m). Ten "
    "covers the systematic part of the rounding (the stage sums, the time in float32).",
)
MJX_POINTWISE_F64 = Threshold(
    "MJX_POINTWISE_F64",
    1e-12,
    "1",
    "MJX's q̈ (float64) against the C engine's at the initial and random states, relative to "
    "max|q̈|: the same model's forward dynamics in two implementations (measured 6e-15).",
)
JAX_CONTROLLER_F64 = Threshold(
    "JAX_CONTROLLER_F64",
    1e-12,
    "1",
    "The controller in JAX (analytic.array_model, float64, jit) against the numpy model's at the "
    "same states, relative to the largest force of each output: one set of formulas on two "
    "array libraries, differing by the order of float64 operations only.",
)

# =================================================================================================
# float32 drift of the accelerated plants (tests/cross/test_accelerated_drift.py)
# =================================================================================================


FLOAT32_DRIFT_FACTOR = Threshold(
    "FLOAT32_DRIFT_FACTOR",
    2.0,
    "1",
    "A float32 plant's largest difference from a float64 run of the same scene (the C plant, the "
    "analytic plant) after N steps is at most FACTOR x sqrt(N) x eps32 x S: each step rounds every "
    "state component once to eps32/2 of its magnitude, unbiased, so the roundings add as a random "
    "walk of sqrt(N) steps; S is the reach of the compared quantity, its magnitude plus what a "
    "velocity error integrates to over the run (C: max |R| + max |Ṙ| T, the rods: max |p| + "
    "max |ṗ| T, the attitude: 1 rad + max |ω| T). 2 = 4 x eps32/2 per step: RK4's four stages each "
    "round once, and a maximum over the run is about twice an rms. A larger difference is not "
    "round-off: the model or the integration differs (MJX's dropped cubic stiffness is 4 decades "
    "above it).",
)
FLOAT32_FLOOR_FRACTION = Threshold(
    "FLOAT32_FLOOR_FRACTION",
    0.1,
    "1",
    "A float32 plant's largest difference in the position of C from a float64 run is at least "
    "this fraction of eps32 x max |R|: storing R in float32 alone rounds it by up to eps32/2 x |R| "
    "at each of the ~200 samples compared, so the largest rounding over them is above eps32/4 x "
    "max |R| but for a vanishing chance; a smaller difference means the plant did not run in "
    "float32.",
)

# =================================================================================================
# MuJoCo Warp, float32 (tests/mj_bridge/test_warp_plant.py); eps32 = 2⁻²³ = 1.19e-7
# =================================================================================================

WARP_QDDOT_REL = Threshold(
    "WARP_QDDOT_REL",
    64 * EPS32,
    "1",
    "max|q̈_warp - q̈_ref| / max|q̈_ref| at a state, the reference MuJoCo's C engine or the analytic "
    "model (which agree to ~1e-15): 8 nv eps32 with nv = 8 (Example 1's twin). Warp rounds the "
    "state to float32 and solves M q̈ = f by a float32 LDLᵀ: each component is an nv-term back "
    "substitution whose terms carry ~eps32 each, and a factor 8 covers the rounded state feeding "
    "M and the bias forces, and the controller's own float32 solve. Measured ≤ 12 eps32 on the "
    "four paper scenes and the controlled slosh scene at the initial and random states, 5 eps32 on "
    "the spring-actuator twin at its initial state (39 eps32 at random states, where its affine "
    "bias b0 + b1 L cancels in float32) (the "
    "controller in float32); a model difference (a spring term or a channel left out) is ≥ 1e-3.",
)
WARP_BATCH_REL = Threshold(
    "WARP_BATCH_REL",
    EPS32,
    "1",
    "A scene as one world of a batch against the same scene alone, 8 steps: max|Δq| / max|q| (and "
    "q̇): the same kernels on the same world's data, so equal or one float32 rounding (eps32) apart; "
    "a world reading another's parameters is off by O(1).",
)
WARP_RUN_REL_PER_STEP = Threshold(
    "WARP_RUN_REL_PER_STEP",
    2 * EPS32,
    "1",
    "Per step, times the number of steps k: max|q_warp - q_C| / max|q_C| (and q̇; and the work "
    "against the energy scale) after a few steps of the same scene and controller in MuJoCo Warp "
    "(float32) and the C plant (float64). Each step rounds every updated coordinate and velocity "
    "to float32 (≤ eps32/2 of its magnitude) and moves it by h q̈ with q̈ off by ≤ WARP_QDDOT_REL, "
    "h² q̈ far below the coordinate itself: ≤ 2 eps32 of the scale per step, added at most linearly "
    "over a few steps (too few for the dynamics to grow a perturbation).",
)
WARP_DRIFT_REL_PER_SQRT_STEP = Threshold(
    "WARP_DRIFT_REL_PER_SQRT_STEP",
    8 * EPS32,
    "1",
    "Per sqrt(step), times sqrt(k) and max|q_C| of the group (R, p; u absolute): MuJoCo Warp "
    "against the C plant over 2 s of Example 1 (k = 8000 steps of 2.5e-4 s), the float32 floor. "
    "The roundings of k steps, ≤ eps32/2 each and independent, add up as a random walk (sqrt(k)); "
    "a factor 16 on eps32/2 covers the tumbling motion's growth of those perturbations over 2 s. "
    "Measured 7.1e-5 m on R uncontrolled (docs/performance.md); the C engine's own RK4 error "
    "there is ~1e-11 m, so the whole difference is Warp's float32.",
)

# =================================================================================================
# The state a plant's progress carries (tests/analytic/test_progress.py,
# tests/mj_bridge/test_plants.py, tests/validation/recording/test_live.py)
# =================================================================================================

PROGRESS_STATE_REL = Threshold(
    "PROGRESS_STATE_REL",
    1e-13,
    "1",
    "Relative to max(1, max|q|): the compiled loop's state where a call stops against its sample at "
    "that time, the same point once as the step's end and once through the dense output at its end "
    "(about ten terms h b_i k_i summed again): a few ulps of the state per term, 1e-13 leaving a "
    "decade above the ~1e-14 that ten terms at 2.2e-16 can reach. scipy's loop and MuJoCo hand over "
    "the sample itself (zero).",
)
LIVE_STATE_F32_REL = Threshold(
    "LIVE_STATE_F32_REL",
    2 * EPS32,
    "1",
    "Relative to max(1, |x|): a streamed state (float64 scalars) against the recording's pose of the "
    "body at the same time, which Rerun stores as float32 (translation; the normalised quaternion): "
    "one rounding to float32 is eps32/2 of the value, the normalisation before it a few ulps of "
    "float64; 2 eps32 bounds both with a factor 4 to spare.",
)


TOLERANCES: Mapping[str, Threshold] = {
    t.name: t for t in list(globals().values()) if isinstance(t, Threshold)
}
"""Every tolerance of this module by name (``tests/cross/test_tolerances.py`` checks them all)."""
