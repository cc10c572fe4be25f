"""Named acceptance thresholds of the MuJoCo-twin tests, each with its reason.

Relative errors are ``max|x - y| / max|y|`` unless stated.
"""

# --- model_xml -----------------------------------------------------------------------------------
XML_VS_SPEC_QACC_REL = 1e-14
"""Compiling the full-precision MJCF and the spec must give the same qacc: repr() round-trips every
double exactly, so only the parser's last-bit rounding is allowed."""

SPRING_ACTUATOR_VS_TENDON_REL = 1e-12
"""Spring actuators vs native tendon springs: the same polynomial evaluated in a different order."""

PRIMITIVE_SIG_DIGITS_REL = 5e-4
"""The paper prints Example 1's mass and moments to 4 significant digits (half a unit in the 4th)."""

PRIMITIVE_ROD_ABS = 1e-3
"""The paper prints a and d to 4 decimals (m / unit vector); they are checked to 1e-3."""

# --- pointwise dynamics and control --------------------------------------------------------------
POINTWISE_QDDOT_REL = 1e-9
"""Analytic vs MuJoCo q̈ at a state: two exact formulations of the same dynamics; round-off in
M (entries up to ~1e8 for Example 1) and the dense solves stays well below this."""

POINTWISE_CONTROL_REL = 1e-9
"""Analytic controller (paper coordinates + quaternion constraint) vs Udwadia–Kalaba from MuJoCo's
M and forces (MuJoCo coordinates): same law, different algebra; round-off only."""

STATE_MAP_ROUNDTRIP = 1e-13
"""paper -> MuJoCo -> paper state maps: a few rotations and cross products of O(1..100) values."""

# --- trajectories --------------------------------------------------------------------------------
EX1_POSITION_ABS_M = 1e-9
"""Example 1 uncontrolled, 20 s, RK4 dt = 2.5e-4 vs analytic rtol 1e-12 (position of C and of
every mass, m)."""

EX1_ATTITUDE_RAD = 1e-9
"""Same run: attitude angle between the two plants, rad."""

CONVERGENCE_ORDER = 4.0
CONVERGENCE_ORDER_TOL = 0.3
"""Observed RK4 order in a dt-halving test: 4 ± 0.3 (a controller held over the step gives 1)."""

TRACKING_FACTOR = 10.0
"""Controlled runs: MuJoCo's tracking error at 20 s within this factor of the analytic plant's."""

UNCONTROLLED_ROD_FORCE_REL = 1e-12
"""Rod force on masses outside the tracked set, relative to the largest rod force: Gauss's
weighting puts the control only on tracked coordinates (Q^C = A_cᵀ μ)."""

RK4_INVARIANT_DRIFT_REL = 1e-10
"""MuJoCo RK4 at dt = 1e-3, 20 s uncontrolled: energy and momentum conserved to this."""

BALANCE_REL_CONTROLLED = 1e-7
"""Controlled runs at dt = 1e-3: energy and angular-momentum balances with the work/impulse
integrated by the same RK4 stages; RK4 truncation ~ (ω h)^4 over 20 s with ω up to ~15 rad/s."""

MJ_ENERGY_VS_PAPER_REL = 1e-12
"""MuJoCo's own d.energy (potential + kinetic) vs the paper-coordinate energy at the same state."""

MJ_ANGMOM_VS_PAPER_REL = 1e-12
"""MuJoCo's subtree angular momentum about the system CoM vs the paper-coordinate one."""

CONTROLLER_SOURCES_TRAJ_REL = 1e-11
"""Compiled, numpy and MuJoCo-matrix controllers driving MuJoCo for 0.5 s: the same law evaluated
three ways, so trajectories, torques and work differ by round-off (~1e-14 measured) only."""

CLOSED_FORM_ERROR_REL = 1e-8
"""Controlled Example 2 at dt = 2e-3 over 1 s: tracking errors vs the closed-form error dynamics,
relative to their largest value; RK4 truncation of the e^{-γt} / damped-oscillator solutions."""

KINEMATICS_REL = 1e-13
"""MuJoCo's own kinematics (xipos, ximat, object velocity) at a mapped state vs the paper's
quantities: a few rotations of O(1..100) values."""

SPRING_CLOSED_FORM_REL = 1e-13
"""Tendon spring forces and MuJoCo's spring energy vs Eq. (38) evaluated directly."""

INERTIA_SUM_REL = 1e-13
"""System inertia about C assembled from MuJoCo's bodies vs J + Σ m_i(|d|²I - d dᵀ)."""

TUBE_MESH_REL = 1e-6
"""Thick tube as a 256-gon mesh with equal-area polygons: moments off by O((2π/256)⁴) ≈ 4e-7."""

SHELL_CLOSED_FORM_REL = 1e-9
"""MuJoCo's shell inertia of a closed cylinder vs the thin-shell closed forms (mass exact)."""

FREE_MOTION_MOMENTUM_REL = 1e-9
"""Without gravity the total linear momentum is constant; RK4 at dt = 2e-3 over 1 s with the
stiff Example 2 springs leaves a truncation drift of the nonlinear momentum map well below this."""

ULP_REL = 4e-15
"""The same number through a handful of floating-point operations on both sides (a few ulps)."""

MASS_FORMULA_REL = 1e-12
"""MuJoCo's geom volumes/masses vs ρ·V written out here (π and products rounded differently)."""
