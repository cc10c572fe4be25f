"""The loader's bounds: tolerances of what it repairs, sizes it can hold, magnitudes it refuses.

Each constant with its reason; ``docs/scene-format.md`` quotes them (rendered from here). What the
MuJoCo twin can represent is in :mod:`analytic.scene.twin`.
"""

from __future__ import annotations

# Quaternion norm tolerances on load: silently exact below, renormalised with a warning up
# to the refusal bound, refused above it unless the scene asks to start off the manifold (Eq. 58).
QUAT_NORMALISE_TOL = 1e-12
QUAT_REFUSE_TOL = 1e-3
# A reference-frame matrix may be rounded (the paper prints Eq. 63 to 4 digits, orthogonal to ~1e-4);
# it is replaced by the nearest rotation, and refused when further than this from orthogonal.
ROTATION_REFUSE_TOL = 1e-2
# The rod axis a: a printed axis is rounded (Example 1's a has |a| = 0.99997); a norm within
# AXIS_REFUSE_TOL of 1 is normalised, with a one-line warning naming the norm when it is off 1 by
# more than AXIS_NORMALISE_TOL (round-off of a unit vector written with every digit, ~1e-16, is
# below it, so a normalised axis written back loads unchanged and without a warning); further off
# it is refused.
AXIS_REFUSE_TOL = 1e-3
AXIS_NORMALISE_TOL = 1e-12
# A rotation matrix orthonormal to this (max |MᵀM − I|, det > 0) is kept as given; otherwise the
# nearest rotation is taken. Round-off of a rotation written with every digit is ~1e-16, so a
# loaded matrix written back loads unchanged.
ROTATION_EXACT_TOL = 1e-12

# --- Sizes that can be held -------------------------------------------------------------------
# A scene file is a page of numbers: the largest built-in one (hard/many_masses, 200 masses) is
# about 10 KB. 1 MiB leaves a hundredfold margin and is still read at once; anything larger (a
# device such as /dev/zero, a log given by mistake) is refused before it is read.
MAX_SCENE_BYTES = 1 << 20
# The reference numpy model and MuJoCo's dense mass matrix hold (n+7)² doubles: 0.8 GB each at
# n = 10⁴ (ten times the largest benchmarked n = 1000); a longer list is a mistake, not a scene.
MAX_MASSES = 10_000
# Lists and tables nested in one another: the deepest value of the format is four levels below the
# document ([hard_case] checks, masses.inertia_body: a table, a list, a matrix, its rows). Python's
# TOML parser recurses once per level of brackets (its RecursionError comes near 300-1000 levels),
# and dotted keys build deeper tables without it (`a.a.a... = 1`), which every later walk of the
# document (repr, copies, JSON) would recurse through: deeper than this is refused at load.
MAX_SCENE_NESTING = 16
# Every output sample holds the state, accelerations, control and invariants of each plant (about
# 1 KB for the paper scenes, n + 7 ≤ 12): 10⁶ samples are ~1 GB per plant before the comparison,
# figures and recording, and a hundred times the largest built-in grid (1000 s at 10 Hz).
MAX_OUTPUT_SAMPLES = 1_000_000
# MuJoCo steps of one run: 10⁹ RK4 steps with the controller are three to five hours (its cost
# per step: docs/performance.md, The analytic layer's tolerances and limits); the longest
# built-in run is 2·10⁶ steps (hard/long_horizon).
MAX_MUJOCO_STEPS = 1_000_000_000
# t_end·rate within this distance of an integer (in sample intervals, so the last interval is never
# longer than 1/rate by more than this fraction) puts t_end on the output grid: decimal horizons
# and rates are not exact in binary (0.3 s x 10 Hz = 3.0000000000000004); the product's round-off,
# at most 2.2e-16 x MAX_OUTPUT_SAMPLES = 2.2e-10 intervals, stays below it. A sample interval must
# fit a whole number of MuJoCo steps to the same relative tolerance
# (mj_bridge.plan.STEP_FIT_RTOL).
GRID_RTOL = 1e-9
# Upper bounds on masses (kg) and moments of inertia (kg·m²): the model forms squares and fourth
# powers of them (the M⁻² weighting and its Schur complement, energies, momenta times lever arms);
# at 1e30 kg (the mass of the Sun) and 1e40 kg·m² their fourth powers (1e120, 1e160) stay far
# inside the double range (1e308), where 1e300 overflows at once.
MAX_MASS = 1e30
MAX_INERTIA = 1e40


__all__ = [
    "AXIS_NORMALISE_TOL",
    "AXIS_REFUSE_TOL",
    "GRID_RTOL",
    "MAX_INERTIA",
    "MAX_MASS",
    "MAX_MASSES",
    "MAX_MUJOCO_STEPS",
    "MAX_OUTPUT_SAMPLES",
    "MAX_SCENE_BYTES",
    "MAX_SCENE_NESTING",
    "QUAT_NORMALISE_TOL",
    "QUAT_REFUSE_TOL",
    "ROTATION_EXACT_TOL",
    "ROTATION_REFUSE_TOL",
]
