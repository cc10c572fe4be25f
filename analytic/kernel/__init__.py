"""The compiled O(n) kernel of the controlled dynamics (Eqs. 51-53, 59, 80-89, B10-B13): the numba
side of :mod:`analytic.fast`.

Modules, in the order an evaluation runs through them:

* :mod:`~analytic.kernel.layout`: where every number lives (packed parameters, output, workspace);
* :mod:`~analytic.runtime.jit`: numba plumbing (compilation with numba's documented API, disk
  cache, source fingerprints);
* :mod:`~analytic.kernel.kinematics`: ``S(u)``, ``H(u)``, ``L_x(u)`` (Eqs. 11-34), stage 1;
* :mod:`~analytic.kernel.forces`: ``Q`` (Eq. 52, springs Eq. 38), stages 2 and 4;
* :mod:`~analytic.kernel.mass_matrix`: ``M`` (Eq. 51), stage 3;
* :mod:`~analytic.kernel.constraints`: ``b_m`` (Eq. 59) and ``b_c`` (Eqs. 81, 86), stages 5-6;
* :mod:`~analytic.kernel.system`: stages 1-6 together (the first half);
* Gauss (N = M⁻¹, Eq. 89): :mod:`~analytic.kernel.schur` (stage 7),
  :mod:`~analytic.kernel.bordered` (stage 8), :mod:`~analytic.kernel.gauss` (stage 9: the second
  half);
* :mod:`~analytic.kernel.norm_constrained`: what the two weightings solved through ``M_α`` share
  (everything but their control force);
* :mod:`~analytic.kernel.minv2`: N = M⁻² (Eq. B13), compiled only for scenes that ask for it;
* :mod:`~analytic.kernel.identity`: N = I (Eq. B10 with W = I), likewise;
* :mod:`~analytic.kernel.weighting`: a weighting's kernel as its callers reach it (``join``) and
  its entry points (``evaluate``, ``qddot_into``), built in one place for every weighting;
* :mod:`~analytic.runtime.abi`, :mod:`~analytic.kernel.halves`: the two halves as C callbacks, each
  compiled once and cached on its own, and how compiled callers call them by address;
* :mod:`~analytic.kernel.entry`: which solve a scene needs; ``evaluate`` for any scene.

Everything the kernel needs is packed by :func:`analytic.fast.pack` into one float array ``fp`` and
one int array ``ip``, so a call unboxes six arguments. ``evaluate(t, q, q̇, fp, ip, out)`` writes
``[q̈ (nq), Q^C (nq), τ (3), A_c q̈ - b_c (k)]`` into ``out`` and returns a status (0 = done).

Cost notes (an evaluation at small n is short, so constant factors matter; figures in
``docs/performance.md``): the stages are
compiled into two C callbacks, stages 1-6 and the solve (two, so that two processes compile a
first run's kernel at once), which every caller calls through addresses held in ``ip``
(:mod:`~analytic.runtime.abi`: a caller's compile then neither waits for nor repeats the kernel's);
no heap allocation on the Gauss path (one stack workspace carved
by ``layout.WS_*``; the rod rows of ``Q`` and ``b_c`` live in ``out``); closed forms for ``L_a(u)``,
``L̇_a u̇`` and ``H(u)ᵀx`` instead of the (3, 4, 4) tensor contractions; no square roots on the Gauss
path (LDLᵀ); cos and sin of one argument in one block (one ``sincos`` call) and reused while the
mass-track λ repeats; indices read from ``ip`` masked (``layout.IX``). Every weighting is compiled.
"""
