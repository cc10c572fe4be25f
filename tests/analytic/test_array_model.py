"""The array form of the model and controller (``analytic/array_model.py``, and
``analytic.fundamental.solve_array``) against the numpy reference ``TumblingModel.acceleration``.

The reference evaluates the same formulas through the same array form, but with scipy's Cholesky
of ``M_α`` and the branching ``pinv_psd``; the array path's defaults (an LU solve, the masked rank
decision) and JAX's XLA evaluation differ from it by round-off only, so every output (q̈, Q^C, τ,
rod forces, force at C, residual) must agree to ``ARRAY_VS_NUMPY_REL`` in float64: numpy in this
process, JAX (eager, ``jax.jit`` and ``jax.vmap``) in a subprocess that sets ``jax_enable_x64``
before any array exists (the flag is process-wide; this process may run other JAX tests).

Scenes: the one generator (:mod:`analytic.scene.random_scenes`), n = 0, 1, 2, 5, every weighting,
subsets of the ω components and of the masses (Remark 4), a gain matrix (Eq. B6), the given
torque, the masses' inertia (ring and body), damping. A rank-deficient requirement set (the
model's own rows never lose rank: ``analytic.fast``'s docstring) is given to the fundamental
equation directly, as duplicated rows, consistent and conflicting.
"""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from analytic import array_model as am
from analytic import fundamental
from analytic.effects import Effect, Weighting
from analytic.model import TumblingModel
from analytic.scene import scene_from_dict
from analytic.scene.random_scenes import PLANT_EFFECTS, random_scene_dict, random_state
from tests.support import tolerances as tol

TOL = tol.ARRAY_VS_NUMPY_REL.value
FIELDS = ("qddot", "QC", "torque", "rod_forces", "force_at_C", "residual")
ROOT = Path(__file__).resolve().parents[2]

# (name, n, options): the scenes of the pointwise comparison
CASES = (
    ("rigid_free", 0, dict(controlled=False)),
    ("rigid_omega_gauss", 0, dict(weighting="M^-1")),
    ("rigid_omega2_identity_torque", 0, dict(weighting="identity", omega=[2], torque=True)),
    ("rigid_minv2", 0, dict(weighting="M^-2", torque=True)),
    ("one_gauss_torque_damping", 1, dict(weighting="M^-1", torque=True, damping=True)),
    ("one_minv2", 1, dict(weighting="M^-2")),
    ("one_identity_body", 1, dict(weighting="identity", inertia="body")),
    ("two_masses_only", 2, dict(omega=[], masses=[2])),
    ("five_free_damping", 5, dict(controlled=False, damping=True, torque=True)),
    ("five_subset_gauss_gain", 5, dict(omega=[1, 3], masses=[2, 4], gain=True, inertia="body")),
    ("five_subset_minv2", 5, dict(weighting="M^-2", omega=[2], masses=[1, 5], damping=True)),
    ("five_all_identity", 5, dict(weighting="identity", torque=True, damping=True)),
)


def case_scene(seed: int, n: int, opts: dict):
    """One scene of :data:`CASES`, drawn by the generator and adjusted as its options say."""
    rng = np.random.default_rng(seed)
    effects = [*PLANT_EFFECTS, Effect.SPRINGS_DAMPING] if opts.get("damping") else PLANT_EFFECTS
    controlled = opts.get("controlled", True)
    data = random_scene_dict(
        rng,
        n,
        controlled=controlled,
        track_all=True,
        external_torque=bool(opts.get("torque")),
        effects=effects,
        mass_inertia=opts.get("inertia", "ring"),
    )
    if controlled:
        eff = [e for e in data["scene"]["effects"] if not e.startswith("control")]
        ctrl = data["control"]
        ctrl["weighting"] = opts.get("weighting", "M^-1")
        omega = opts.get("omega", [1, 2, 3])
        if omega:
            ctrl["omega"]["components"] = omega
            eff.append(Effect.CONTROL_OMEGA.value)
            if opts.get("gain"):
                B = rng.normal(size=(len(omega),) * 2)
                ctrl["omega"]["gain"] = (B @ B.T + np.eye(len(omega))).tolist()
                del ctrl["omega"]["gamma"]
        else:
            del ctrl["omega"]
        masses = opts.get("masses", list(range(1, n + 1)))
        if n and masses:
            mt = ctrl["masses"]
            pick = [i - 1 for i in masses]
            for key in ("l", "lambda", "alpha", "beta"):
                mt[key] = [mt[key][i] for i in pick]
            mt["indices"] = masses
            eff.append(Effect.CONTROL_MASSES.value)
        elif n:
            del ctrl["masses"]
        data["scene"]["effects"] = eff
    return scene_from_dict(data)


def rel(x, ref, scale=None) -> float:
    """``|x - ref| / scale`` (Euclidean), ``scale = |ref|`` by default; the difference itself
    where the scale is 0 (both empty or zero)."""
    x, ref = np.asarray(x, float), np.asarray(ref, float)
    d = float(np.linalg.norm(x - ref))
    s = float(np.linalg.norm(ref)) if scale is None else float(scale)
    return d / s if s > 0 else d


def reference(tm: TumblingModel, t, q, qd) -> dict[str, np.ndarray]:
    """The numpy reference's outputs, and the scale of the residual (``|b_c| + |A_c||q̈|``: the
    residual is a difference of those, ~0 when the requirements are met)."""
    qdd, c = tm.acceleration(t, q, qd)
    A, b = tm.control_constraints(t, q, qd)
    out = dict(
        qddot=qdd,
        QC=c.QC,
        torque=c.torque,
        rod_forces=c.rod_forces,
        force_at_C=c.force_at_C,
        residual=c.residual,
    )
    out["residual_scale"] = float(np.linalg.norm(b) + np.linalg.norm(A) * np.linalg.norm(qdd))
    return out


def worst(got, ref: dict) -> dict[str, float]:
    """Relative difference per output field of an :class:`ArrayControl` against :func:`reference`."""
    return {
        f: rel(getattr(got, f), ref[f], ref["residual_scale"] if f == "residual" else None)
        for f in FIELDS
    }


def states(scene, count: int, seed: int):
    rng = np.random.default_rng(seed)
    return [random_state(rng, scene) for _ in range(count)]


# --------------------------------------------------------------------------------------------------
# numpy
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name,n,opts", CASES, ids=[c[0] for c in CASES])
def test_numpy_matches_reference(name, n, opts):
    scene = case_scene(11, n, opts)
    tm = TumblingModel(scene)
    st = am.structure_of(scene)
    assert st == tm.structure and hash(st) == hash(am.structure_of(scene))
    P = am.parameters(scene, np, np.float64)
    for t, q, qd in states(scene, 3, 5):
        errs = worst(am.controlled_acceleration(np, st, P, t, q, qd), reference(tm, t, q, qd))
        assert max(errs.values()) <= TOL, errs
        torque, rod, fC = am.control_forces(np, st, P, t, q, qd)
        _, c = tm.acceleration(t, q, qd)
        if st.controlled:
            assert rel(torque, c.torque) <= TOL and rel(rod, c.rod_forces) <= TOL
            assert rel(fC, c.force_at_C) <= TOL
        else:
            assert not np.any(torque) and not np.any(rod) and not np.any(fC)
            assert rod.shape == (n,)
        assert np.array_equal(am.given_torque(np, st, P, t), tm.given_torque(t))


def test_numpy_batched_equals_per_sample():
    """Scenes of one structure stacked (parameters (N, ...), states (N, nq)) give what each gives
    alone, in float64 and float32; one set of parameters broadcasts over a batch of states."""
    n, opts = 5, dict(omega=[1, 3], masses=[2, 4], gain=True, damping=True, torque=True)
    scenes = [case_scene(seed, n, opts) for seed in range(4)]
    st = am.structure_of(scenes[0])
    assert all(am.structure_of(s) == st for s in scenes)
    draws = [states(s, 1, 30 + i)[0] for i, s in enumerate(scenes)]
    T = np.array([d[0] for d in draws])
    Q = np.stack([d[1] for d in draws])
    QD = np.stack([d[2] for d in draws])
    for dtype in (np.float64, np.float32):
        Ps = [am.parameters(s, np, dtype) for s in scenes]
        batch = am.controlled_acceleration(
            np, st, am.stack_parameters(Ps, np), T, Q.astype(dtype), QD.astype(dtype)
        )
        assert batch.qddot.shape == (4, n + 7) and batch.torque.shape == (4, 3)
        for f in FIELDS:
            assert getattr(batch, f).dtype == dtype, f
        for i in range(4):
            one = am.controlled_acceleration(
                np, st, Ps[i], T[i], Q[i].astype(dtype), QD[i].astype(dtype)
            )
            for f in FIELDS:
                ref = getattr(one, f)
                scale = 1.0 if f == "residual" else None
                assert rel(getattr(batch, f)[i], ref, scale) <= np.finfo(dtype).eps * 10, f
    P0 = am.parameters(scenes[0], np, np.float64)
    shared = am.control_forces(np, st, P0, T, Q, QD)
    for i in range(4):
        one = am.control_forces(np, st, P0, T[i], Q[i], QD[i])
        for a, b in zip(shared, one, strict=True):
            assert rel(a[i], b) <= TOL


def test_float32_close_to_float64():
    """float32 parameters and states: float32 outputs, within float32 round-off of float64."""
    scene = case_scene(3, 2, dict(weighting="M^-1", torque=True))
    st = am.structure_of(scene)
    P64, P32 = (am.parameters(scene, np, d) for d in (np.float64, np.float32))
    for t, q, qd in states(scene, 3, 8):
        q32, qd32 = q.astype(np.float32), qd.astype(np.float32)
        r32 = am.controlled_acceleration(np, st, P32, np.float32(t), q32, qd32)
        r64 = am.controlled_acceleration(
            np, st, P64, float(np.float32(t)), q32.astype(float), qd32.astype(float)
        )
        assert r32.qddot.dtype == np.float32
        assert rel(r32.qddot, r64.qddot) <= tol.ARRAY_FLOAT32_REL.value
        assert rel(r32.torque, r64.torque) <= tol.ARRAY_FLOAT32_REL.value


def rank_deficient_systems(seed: int = 0):
    """``(name, M, Q, a_m, b_m, A_c, b_c, weighting)`` with duplicated control rows: consistent
    (the same requirement twice) and conflicting (two values for one requirement)."""
    out = []
    for w in (Weighting.M_INV, Weighting.M_INV2, Weighting.IDENTITY):
        scene = case_scene(seed, 2, dict(weighting=w.value))
        tm = TumblingModel(scene)
        t, q, qd = states(scene, 1, 40)[0]
        M, Q = tm.mass_matrix(q), tm.generalized_force(t, q, qd)
        a_m, b_m = tm.modeling_constraint(q, qd)
        A, b = tm.control_constraints(t, q, qd)
        A2 = np.vstack([A, A[:2]])
        out.append((f"consistent_{w.name}", M, Q, a_m, b_m, A2, np.r_[b, b[:2]], w))
        out.append((f"conflicting_{w.name}", M, Q, a_m, b_m, A2, np.r_[b, b[:2] + 1.0], w))
    return out


def compare_solutions(sol, ref) -> dict[str, float]:
    scale = float(np.linalg.norm(ref.residual)) + 1.0
    return {
        "qddot": rel(sol.qddot, ref.qddot),
        "QC": rel(sol.constraint_force, ref.constraint_force),
        "control": rel(sol.control_force, ref.control_force),
        "residual": rel(sol.residual, ref.residual, scale),
    }


def test_rank_deficient_requirements_masked_equals_reference():
    for name, M, Q, a_m, b_m, A, b, w in rank_deficient_systems():
        ref = fundamental.solve(M, Q, a_m, b_m, A, b, w)
        assert ref.rank == A.shape[0] - 2, name
        sol = fundamental.solve_array(np, M, Q, a_m, np.float64(b_m), A, b, w)
        assert int(sol.rank) == ref.rank, name
        errs = compare_solutions(sol, ref)
        assert max(errs.values()) <= TOL, (name, errs)


def test_pinv_masked_equals_branching():
    """The masked Moore-Penrose inverse is pinv_psd's at every rank, one matrix or a batch."""
    rng = np.random.default_rng(4)
    Gs, refs = [], []
    for r in (4, 3, 1, 0):
        B = rng.normal(size=(4, r)) * 10.0 ** rng.uniform(-2, 2, r)
        G = B @ B.T
        Ginv, rank = fundamental.pinv_psd(G)
        assert rank == r
        got, got_rank = fundamental.pinv_psd_masked(np, G)
        assert int(got_rank) == r
        assert rel(got, Ginv, max(np.linalg.norm(Ginv), 1.0)) <= TOL
        Gs.append(G)
        refs.append(Ginv)
    got, ranks = fundamental.pinv_psd_masked(np, np.stack(Gs))
    assert ranks.tolist() == [4, 3, 1, 0]
    for g, ref in zip(got, refs, strict=True):
        assert rel(g, ref, max(np.linalg.norm(ref), 1.0)) <= TOL


def test_stack_parameters_refuses_mixed_structures():
    a = am.parameters(case_scene(0, 1, dict(controlled=False)), np, np.float64)
    b = am.parameters(case_scene(0, 1, dict(torque=True)), np, np.float64)
    with pytest.raises(ValueError, match=r"params\[1\]"):
        am.stack_parameters([a, b], np)
    with pytest.raises(ValueError, match="params"):
        am.stack_parameters([], np)


# --------------------------------------------------------------------------------------------------
# JAX, in a subprocess with x64 on
# --------------------------------------------------------------------------------------------------

JIT_CASES = ("rigid_omega2_identity_torque", "one_gauss_torque_damping", "five_subset_minv2")
"""The structures of the default run (each ``jax.jit`` compile takes 1-2 s of CPU here; eager
JAX costs more, compiling every operation); the slow test compiles every case."""


def jax_report(full: bool = False) -> dict:
    """Run in the subprocess: the worst relative difference per check (JSON-able), over
    :data:`JIT_CASES` or (``full``) every case of :data:`CASES`."""
    import functools

    import jax

    if not jax.config.jax_enable_x64:
        raise RuntimeError("jax_enable_x64 must be set before this runs")
    import jax.numpy as jnp

    report: dict[str, float] = {}

    def note(key, errs):
        report[key] = max(report.get(key, 0.0), *errs.values())

    for name, n, opts in CASES:
        if not (full or name in JIT_CASES):
            continue
        scene = case_scene(11, n, opts)
        tm = TumblingModel(scene)
        st = am.structure_of(scene)
        P = am.parameters(scene, jnp, jnp.float64)
        f = jax.jit(functools.partial(am.controlled_acceleration, jnp, st))
        cf = jax.jit(functools.partial(am.control_forces, jnp, st))
        for t, q, qd in states(scene, 3, 5):
            got = f(P, t, jnp.asarray(q), jnp.asarray(qd))
            ref = reference(tm, t, q, qd)
            note("jit", worst(got, ref))
            if st.controlled and (full or name == JIT_CASES[-1]):  # (one more compile each)
                torque, rod, fC = cf(P, t, jnp.asarray(q), jnp.asarray(qd))
                note(
                    "control_forces",
                    {
                        "torque": rel(torque, ref["torque"]),
                        "rod": rel(rod, ref["rod_forces"]),
                        "fC": rel(fC, ref["force_at_C"]),
                    },
                )
            gt = am.given_torque(jnp, st, P, t)
            note("given_torque", {"t": rel(gt, tm.given_torque(t), 1.0 + np.linalg.norm(gt))})
        if name == "five_subset_minv2":  # float32 in the x64 process: dtype from the parameters
            P32 = am.parameters(scene, jnp, jnp.float32)
            t, q, qd = states(scene, 1, 6)[0]
            r32 = f(P32, t, jnp.asarray(q, jnp.float32), jnp.asarray(qd, jnp.float32))
            report["float32_dtype_ok"] = float(all(x.dtype == jnp.float32 for x in r32))

    # vmap over scenes of one structure and their states, against each scene's reference
    n, opts = 5, dict(omega=[1, 3], masses=[2, 4], gain=True, damping=True, torque=True)
    scenes = [case_scene(seed, n, opts) for seed in range(4)]
    st = am.structure_of(scenes[0])
    draws = [states(s, 1, 30 + i)[0] for i, s in enumerate(scenes)]
    PB = am.stack_parameters([am.parameters(s, jnp, jnp.float64) for s in scenes], jnp)
    vf = jax.jit(jax.vmap(functools.partial(am.controlled_acceleration, jnp, st)))
    got = vf(
        PB,
        jnp.asarray([d[0] for d in draws]),
        jnp.asarray(np.stack([d[1] for d in draws])),
        jnp.asarray(np.stack([d[2] for d in draws])),
    )
    for i, s in enumerate(scenes):
        one = am.ArrayControl(*(x[i] for x in got))
        note("vmap", worst(one, reference(TumblingModel(s), *draws[i])))

    # the rank-deficient requirement sets, jit-compiled per weighting (masked rank decision)
    solvers = {
        w: jax.jit(functools.partial(fundamental.solve_array, jnp, weighting=w)) for w in Weighting
    }
    for _name, M, Q, a_m, b_m, A, b, w in rank_deficient_systems():
        if not (full or w is Weighting.M_INV):  # one compile by default: the same masked pinv
            continue
        ref = fundamental.solve(M, Q, a_m, b_m, A, b, w)
        sol = solvers[w](M, Q, a_m, jnp.float64(b_m), A, b)
        note("rank_deficient", compare_solutions(sol, ref))
        report["rank_mismatches"] = report.get("rank_mismatches", 0.0) + float(
            int(sol.rank) != ref.rank
        )
    return report


def run_jax_report(full: bool) -> dict:
    """:func:`jax_report` in a fresh interpreter with ``jax_enable_x64`` set first (CPU)."""
    if importlib.util.find_spec("jax") is None:
        pytest.skip("jax not installed")
    code = (
        "import jax; jax.config.update('jax_enable_x64', True); import json; "
        "from tests.analytic.test_array_model import jax_report; "
        f"print(json.dumps(jax_report(full={full!r})))"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT), "JAX_PLATFORMS": "cpu"}
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=900, cwd=ROOT, env=env
    )
    if proc.returncode:
        raise AssertionError(f"the JAX subprocess failed:\n{proc.stderr[-4000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def jax_results() -> dict:
    return run_jax_report(full=False)


@pytest.mark.parametrize(
    "check", ["jit", "control_forces", "given_torque", "vmap", "rank_deficient"]
)
def test_jax_matches_reference(jax_results, check):
    assert jax_results[check] <= TOL, jax_results


def test_jax_rank_and_dtype(jax_results):
    assert jax_results["rank_mismatches"] == 0.0
    assert jax_results["float32_dtype_ok"] == 1.0


@pytest.mark.slow
def test_jax_every_case_matches_reference():
    """Every structure of :data:`CASES` compiled (~20 s of compiles)."""
    report = run_jax_report(full=True)
    for check in ("jit", "control_forces", "given_torque", "vmap", "rank_deficient"):
        assert report[check] <= TOL, report
