"""analytic.kernel.paste: inline stages pasted at the source level compute what numba's own
inlining computes.

The kernel's halves are compiled from pasted source (analytic.kernel.halves); here the same
halves are also compiled the way numba pastes them (its ``inline="always"``), and every output of
the kernel is compared bit for bit over random scenes, both weightings, full and q̈-only output.
The pasting rules themselves (early returns inside loops, a parameter the callee rebinds, tuple
results, folded constants) are checked on small functions against numba's compiled originals.
"""

from __future__ import annotations

import functools

import numba
import numpy as np

from analytic import fast
from analytic.kernel import gauss, halves, kinematics, minv2, paste, system
from analytic.kernel.abi import SOLVE_SIG, SYSTEM_SIG
from analytic.kernel.entry import Solver, solver_of
from analytic.kernel.jit import inline
from analytic.kernel.layout import (
    I_FN_SOLVE,
    I_FN_SYSTEM,
    STATUS_OK,
    W_GAUSS,
    W_MINV2,
    WS_LA,
)
from tests.random_scenes import FORCE_EFFECTS, random_state
from tests.test_fast import make_scene

STEP = 3  # a module-level number: pasted code reads it as a constant


@inline
def _first_at_least(xs, limit):
    """Early return inside a loop inside a loop, with a value; a fall-through return."""
    for i in range(xs.shape[0]):
        for j in range(2):
            if xs[i] + j >= limit:
                return i * 2 + j
    return -1


@inline
def _rebinds(x, xs):
    """Rebinds its parameter (the caller's variable must not change) and returns a tuple."""
    x += STEP
    xs[0] = x
    return x, x * 2.0


@inline
def _stage(xs, out):
    """A statement-level stage with an early bare return and a nested pasted call."""
    if xs.shape[0] == 0:
        return
    out[0], out[1] = _rebinds(xs[0], out)
    out[2] = xs[WS_LA - WS_LA + 1] if xs.shape[0] > 1 else 0.0


def _caller(xs, limit, out):
    x = xs[0]
    k = _first_at_least(xs, limit)
    if not _first_at_least(xs, limit) >= 0:
        out[3] = -5.0
    _stage(xs, out)
    a, b = _rebinds(x, out[4:])
    return k + a + b + x  # x: the caller's value, untouched by the callee's rebinding


def test_pasting_rules_match_numba_inlining():
    pasted = paste.flatten(_caller)
    assert pasted is not _caller
    compiled = numba.njit(_caller)
    compiled_pasted = numba.njit(pasted)
    for xs, limit in [
        (np.array([1.0, 5.0, 2.0]), 5.5),
        (np.array([1.0, 5.0, 2.0]), 9.0),  # never reached: the fall-through return
        (np.array([7.0]), 0.0),  # reached at once
        (np.array([0.5, 0.25]), 1.25),
    ]:
        results = []
        for fn in (compiled, compiled_pasted, pasted):  # pasted also runs as plain Python
            out = np.zeros(6)
            results.append((fn(xs.copy(), limit, out), out))
        for value, out in results[1:]:
            assert value == results[0][0]
            np.testing.assert_array_equal(out, results[0][1])


def test_pasted_code_reads_module_numbers_as_constants():
    """The layout offsets and other module-level numbers become literals (fewer statements for
    numba to type): the pasted caller refers to no such global."""
    pasted = paste.flatten(_caller)
    names = set(pasted.__code__.co_names)
    assert not names & {"STEP", "WS_LA"}
    assert "_rebinds" not in names and "_stage" not in names  # pasted, not called
    assert "_first_at_least" in names  # inside a comparison: left to numba's own inlining


def _calls_through_a_module(u):
    s = kinematics.rotation(u[0], u[1], u[2], u[3])  # an inline function of another module
    return s[0] * s[4] - s[8]


def test_an_inline_function_called_through_its_module_is_pasted():
    """``gauss.join(...)`` (how ``entry.evaluate_as`` calls a solve) is pasted like a call of a
    global name: numba's own inlining of it would run its front end again in every caller."""
    pasted = paste.flatten(_calls_through_a_module)
    assert not {"kinematics", "rotation"} & set(pasted.__code__.co_names)  # pasted, not called
    u = np.array([0.9, 0.1, -0.3, 0.2])
    want = numba.njit(_calls_through_a_module)(u)
    assert numba.njit(pasted)(u) == want and pasted(u) == want


def _scaler(k):
    """A factory: the inline function closes over ``k`` (a number)."""

    @inline
    def scale(x):
        if k == 2:
            return x * k
        return x + k

    return scale


def _closes_over_an_array():
    table = np.arange(3.0)

    @inline
    def look(i):
        return table[i]

    return look


_double, _plus_three, _look = _scaler(2), _scaler(3), _closes_over_an_array()


def _uses_closures(x):
    a = _double(x)
    b = _plus_three(x)
    c = _look(1)
    return a + b + c


def test_a_callees_closure_numbers_are_pasted_as_literals():
    """A factory's inline function (a solve chosen by a closure constant) is pasted with its
    closure numbers as literals; one closing over anything else is left to numba."""
    pasted = paste.flatten(_uses_closures)
    names = set(pasted.__code__.co_names)
    assert "_double" not in names and "_plus_three" not in names and "k" not in names
    assert "_look" in names
    assert pasted.__code__.co_freevars == ()
    for x in (0.5, -2.0, 7.0):
        expected = numba.njit(_uses_closures)(x)
        assert numba.njit(pasted)(x) == expected == pasted(x)
        assert expected == x * 2 + (x + 3) + 1.0


def _caller_of(k):
    """A factory of callers (one per solve in the kernel): its closure value stays a closure
    variable of the pasted function (numba's cache key hashes it)."""

    def call(x):
        y = _double(x)
        return y + k

    return call


def test_variants_of_one_factory_share_the_pasted_code_not_their_closures():
    first, second = _caller_of(1.0), _caller_of(10.0)
    one, two = paste.flatten(first), paste.flatten(second)
    assert one is not first and one.__code__ is two.__code__  # pasted, once
    assert one.__code__.co_freevars == ("k",) and "_double" not in one.__code__.co_names
    assert (one(2.0), two(2.0)) == (5.0, 14.0)
    assert numba.njit(two)(2.0) == 14.0


@functools.cache
def _inlined_halves() -> dict[str, object]:
    """The halves compiled from the unpasted factories (numba inlines the stages), in memory."""
    from numba.core import sigutils
    from numba.core.ccallback import CFunc

    made = {}
    for name, factory, sig in (
        ("system", system.make_build_system, SYSTEM_SIG),
        ("gauss", gauss.make_solve_gauss, SOLVE_SIG),
        ("minv2", minv2.make_solve_minv2, SOLVE_SIG),
    ):
        made[name] = CFunc(factory(halves._DEPS), sigutils.normalize_signature(sig), {}, {})
        made[name].compile()
    return made


def test_pasted_halves_compute_what_numba_inlined_halves_compute():
    """Every output of the kernel (q̈, Q^C, τ, residual; and q̈ alone under Gauss) from the pasted
    halves equals the output of the halves numba inlined itself, bit for bit, over random scenes
    of both weightings and uncontrolled ones: same operations in the same order, so the pasting
    changes how fast numba compiles, never a number."""
    inlined = _inlined_halves()
    rng = np.random.default_rng(1234)
    compared = {W_GAUSS: 0, W_MINV2: 0}
    for weighting in ("M^-1", "M^-2"):
        for n in (0, 1, 2, 5, 9):
            for omega, masses in ((True, True), (True, False), (False, True), (False, False)):
                if masses and n == 0:
                    continue
                effects = tuple(e for e in FORCE_EFFECTS if rng.random() < 0.7)
                sc = make_scene(rng, n, effects, omega=omega, masses=masses, weighting=weighting)
                fm = fast.FastModel(sc)
                by_minv2 = solver_of(fm.ip) is Solver.MINV2
                evaluate = minv2.evaluate if by_minv2 else gauss.evaluate
                ip = fm.ip.copy()
                ip[I_FN_SYSTEM] = inlined["system"].address
                ip[I_FN_SOLVE] = inlined["minv2" if by_minv2 else "gauss"].address
                lengths = [fm._nout] + ([] if by_minv2 else [sc.n + 7])
                for _ in range(3):
                    q, qd = random_state(rng, sc.n)
                    t = float(rng.uniform(0.0, 5.0))
                    for length in lengths:
                        want, got = np.empty(length), np.empty(length)
                        assert evaluate(t, q, qd, fm.fp, ip, want) == STATUS_OK
                        assert evaluate(t, q, qd, fm.fp, fm.ip, got) == STATUS_OK
                        np.testing.assert_array_equal(got, want)
                        compared[W_MINV2 if by_minv2 else W_GAUSS] += 1
    assert min(compared.values()) >= 30


def test_without_source_nothing_is_pasted(monkeypatch):
    """An install without ``.py`` files (or a file changed since import): the function is left
    as it is, and numba inlines its stages itself (the same numbers, see above)."""
    import linecache

    monkeypatch.setattr(linecache, "getlines", lambda *a, **k: [])
    monkeypatch.setattr(paste, "_factories", {})  # what this process pasted already
    paste._shape.cache_clear()
    try:
        assert paste.flatten(_caller) is _caller
    finally:
        paste._shape.cache_clear()
