"""What the demo teaches, as text: its steps (:data:`STEPS`, in order: each a scene, its story and
what to look at), the learning goals, the exercises with the physics of their answers, and the
paper. A new chapter is one :class:`~validation.studies.demo.step.DemoStep` in :data:`STEPS`."""

from __future__ import annotations

from analytic.effects import Effect
from validation.studies.demo.plots import DRIFT_KEY, REQUIREMENT_HUE, WITH_HUE, WITHOUT_HUE, Plot
from validation.studies.demo.step import DemoStep

PAPER = (
    'P. B. Koganti and F. E. Udwadia, "Dynamics and Precision Control of Tumbling Multibody '
    'Systems", Journal of Guidance, Control, and Dynamics, Vol. 40, No. 3, 2017, '
    "doi:10.2514/1.G000633."
)
"""The paper the model, the controller and the equation numbers come from."""

STEPS = (
    DemoStep(
        "step1_uncontrolled",
        "1. Example 1 tumbling freely",
        "paper_example1",
        """# 1. Example 1 tumbling freely

A 10 × 6 × 2 m aluminium block with a 16 m rod at a corner; two masses slide on the rod between
linear + cubic springs. No control: the motion follows Lagrange's equations in the quaternion
coordinates `q = [R, u, p]` (Eq. 44), with the norm constraint `uᵀu = 1` stabilised (Eq. 58),

    M(q) q̈ = Q(q, q̇)        (Eqs. 50–53, solved with Udwadia–Kalaba)

Only gravity acts on the system as a whole, so its centre of mass falls on a parabola
(`Ṗ = m_T g`) and its angular momentum about that centre of mass is constant (Fig. 8); C, the centre
of mass of BR alone (the trail), wobbles about the parabola as the heavy masses slide.""",
        look_at=(
            "the 3D view: the block tumbles while the masses oscillate on the rod; the trail of C "
            "bends under gravity;",
            "the drift plot (the key plot): every balance holds to the integration error, about "
            "twelve decades below the size of what it balances, all the way: nothing but the "
            f"integrator disturbs them (one colour per quantity: {DRIFT_KEY}; MuJoCo's lighter; "
            f"{REQUIREMENT_HUE.name}: the thresholds);",
            "ω: the rates change although no torque acts — the body is asymmetric (Euler's "
            "equations) and the sliding masses shift its inertia;",
            "the analytic − MuJoCo plot: the two engines agree to round-off and integration error.",
        ),
        key=Plot.INVARIANTS,
        others=(Plot.OMEGA, Plot.ERRORS),
    ),
    DemoStep(
        "step2_controlled",
        "2. Example 1 under control",
        "paper_example1_controlled",
        """# 2. The same body under control

The controller is the explicit Udwadia–Kalaba force (Eq. 89)

    Q^C = M^{1/2} (A M^{-1/2})⁺ (b − A M⁻¹ Q)

that makes the motion satisfy the requirements exactly, with the least Gauss cost (Eq. 74):

* angular velocity `ω̄ = b cos(σ t)` (Eq. 76) with `b_x = −10 rad/s, σ_x = 0`: ω_x, which starts at
  +1 rad/s, **reverses** and settles at −10 rad/s (watch the green arrow), the tracking error decaying
  as `e_ω(t) = e_ω(0) exp(−γ t)` (Eq. 84, γ = 0.6 1/s);
* masses `p̄ = p_e + l cos(λ t)` (Eq. 75): they **oscillate**, the error obeying
  `ë + α ė + β e = 0` (Eq. 78).

The purple arrow is the control torque τ (body axes); the rod forces are in their own plot.
Angular momentum now changes exactly by the impulse of `S(u) τ`; energy by the control's work.""",
        look_at=(
            "ω (the key plot): each component leaves its initial value and joins its grey "
            "requirement ω̄ — ω_x reverses from +1 to −10 rad/s, ω_y and ω_z settle on cosines;",
            "the tracking errors: straight lines on the log10 plot, the slope of |e_ω| is "
            "−γ / ln 10 = −0.26 per second (Eq. 84); the mass errors decay as e^{−αt/2} with dips "
            "where they change sign (Eq. 78);",
            "the control torque and rod forces: up to ~1e10 N·m and ~6e8 N in the first second, "
            "while the errors are large, then what the requirements keep asking for;",
            "the drift plot: the balances still hold, now counting the control's impulse and work.",
        ),
        key=Plot.OMEGA,
        others=(Plot.TRACKING, Plot.TORQUE, Plot.ROD_FORCES, Plot.INVARIANTS),
    ),
    DemoStep(
        "step3_example2_subset",
        "3. Example 2: only masses 1, 2, 4 controlled",
        "paper_example2_controlled",
        """# 3. Example 2: a hollow cylinder, five masses, three of them controlled

Remark 4: the requirements can be any subset. Here only masses 1, 2 and 4 are asked to follow
`p̄_i = p_e,i + l_i cos(λ_i t)` (Eq. 75 with the rows of A in Eq. 80 kept for i = 1, 2, 4 only), and
the angular velocity tracks `ω̄` (Eq. 76). Masses 3 and 5 are left to the springs: their motion is
whatever the dynamics give, and the control leaves them no force of their own (their rod-force
plot stays at zero). Linear stiffnesses are this project's assumption (Eq. 64 is missing from the
paper; docs/errata.md, item 10).""",
        look_at=(
            "the mass positions (the key plot): masses 1, 2 and 4 join their grey requirements "
            "p̄_i; masses 3 and 5, which have none, move as their springs push them;",
            "the rod forces: F_3 and F_5 stay at zero — the least-cost control (Eq. 74) acts only "
            "where a requirement asks it to;",
            "the tracking errors: three mass errors and the ω error decay by Eqs. 78 and 84.",
        ),
        key=Plot.MASS_POSITIONS,
        others=(Plot.ROD_FORCES, Plot.TRACKING, Plot.OMEGA),
    ),
    DemoStep(
        "step4_no_cubic_springs",
        "4. Example 1 without the cubic springs",
        "paper_example1",
        """# 4. An effect switched off: the cubic springs

The spring potential of Eq. (38) is

    U_s = Σ ½ k_l,i Δ_i² + ¼ k_n,i Δ_i⁴,   Δ_i = extension of spring i

This step runs step 1's scene with `springs.cubic` switched off (`scene.with_effects(...)`): the
masses' oscillation about `p_e` changes (plot *mass positions*: """
        + f"{WITH_HUE.name} with, {WITHOUT_HUE.name} without"
        + """ the
cubic term), and with it the body's tumble. Energy is still conserved — the switched-off term is
removed from the model and from the energy alike.""",
        look_at=(
            f"the mass positions (the key plot): with the cubic term ({WITH_HUE.name}) the "
            "springs stiffen at large extension, so the masses turn back a little sooner and "
            f"oscillate a little faster than without it ({WITHOUT_HUE.name});",
            "the drift plot: the balances hold as well as in step 1 — removing a term from the "
            "model removes it from the energy too;",
            "the analytic − MuJoCo plot: MuJoCo runs the same reduced scene and still agrees.",
        ),
        key=Plot.MASS_POSITIONS,
        others=(Plot.INVARIANTS, Plot.ERRORS),
        switched_off=frozenset({Effect.SPRINGS_CUBIC}),
    ),
)

LEARNING_GOALS = (
    "describe a tumbling body with sliding masses in the paper's coordinates `q = [R, u, p]` "
    "(Eq. 44), and say why the quaternion's norm needs stabilising (Eqs. 55–58);",
    "read the balances of a free tumble — linear momentum against gravity, angular momentum about "
    "the system's centre of mass, energy — and tell integration error from physics;",
    "explain how the Udwadia–Kalaba control (Eq. 89) makes requirements exact: the error dynamics "
    "`e_ω(t) = e_ω(0) exp(−γ t)` (Eq. 84) and `ë + α ė + β e = 0` (Eq. 78) are properties of the "
    "controlled motion, predictable without integrating anything;",
    "see that the requirements may be any subset (Remark 4), and what switching an effect off "
    "changes (the motion) and does not (the balances);",
    "judge agreement between two engines (the analytic model and MuJoCo) under one controller.",
)

EXERCISES = (
    (
        "Change γ and predict e_ω(20)",
        """Copy `analytic/scenes/paper_example1_controlled.toml` (in this repository) to
`gamma.toml`, change `name` and, under `[control.omega]`, `gamma = 0.6` to `gamma = 0.3`, then run

    tumble simulate gamma.toml        # or: python -m validation simulate gamma.toml

and read the line `|e_omega| (x,y,z) rad/s` under `tracking at t = 20 s`.

*Prediction.* The requirement enters as the first-order stabilised constraint
`ė_ω + γ e_ω = 0` (Eq. 84; docs/errata.md, item 3), and the control (Eq. 89) makes it hold exactly,
whatever the body, the masses and the springs do. So `e_ω(20) = e_ω(0) exp(−20 γ)` with
`e_ω(0) = ω(0) − ω̄(0) = (1, −1, 0.5) − (−10, 8, 15) = (11, −9, −14.5)` rad/s: for γ = 0.3,
`exp(−6) = 2.48e-3` and `|e_ω(20)| = (2.73e-2, 2.23e-2, 3.59e-2)` rad/s; for the scene's γ = 0.6,
`(6.76e-5, 5.53e-5, 8.91e-5)` rad/s. Halving γ costs three decades at 20 s. The mass errors
(`|e_p|`) do not change: they obey their own law.""",
    ),
    (
        "Soften the mass requirement: change α and predict e_p(20)",
        """In the same copy set `alpha = [1.0, 1.0]` under `[control.masses]` (β stays 12 1/s²) and
run `tumble simulate` again; read `|e_p| (masses 1,2) m`.

*Prediction.* Each mass error obeys `ë + α ė + β e = 0` (Eq. 78): a damped oscillation at
`ω_d = √(β − α²/4)` (3.43 rad/s for α = 1) under the envelope `exp(−α t / 2)`. From
`e(0) = p(0) − p̄(0) = (5 − 3, 11 − 14) = (2, −3)` m and `ė(0) = (−0.4, 0.3)` m/s the closed form
gives `|e_p(20)| = (7.28e-5, 1.07e-4)` m for α = 1, against `(4.21e-9, 6.38e-9)` m for the scene's
α = 2: half the damping rate, the envelope at 20 s is `exp(−10)` instead of `exp(−20)`. Check the
numbers with `validation.compare.tracking_laws.mass_error_reference`.""",
    ),
    (
        "Switch off the cubic springs under control and predict what changes",
        """Remove `"springs.cubic"` from `effects` in the controlled scene (the loader warns that the
now unused `k_cubic` is ignored) and run `tumble simulate`.

*Prediction.* The tracking errors at 20 s do not change at all (`|e_ω|` and `|e_p|` as in the
original), because Eqs. 78 and 84 contain neither the springs nor the body: whatever force the
springs no longer give, the control supplies. What changes is the control: the summary's
`max |F_i|` moves from 6.161e8 N to 6.172e8 N — by the order of the cubic spring force
`k_n Δ³ ~ 1e6 N` for extensions Δ of a metre or two — and the motion of everything the
requirements leave free.""",
    ),
)


__all__ = ["EXERCISES", "LEARNING_GOALS", "PAPER", "STEPS"]
