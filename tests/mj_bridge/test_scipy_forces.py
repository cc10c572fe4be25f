"""The force effects of the plants on scipy's loop: one function per effect, found by its name, and
compiled into one chain that applies those the packed scene switches on (Eq. 38's spring chain,
Remark 2's given torque).

References: the springs' tensions written out with numpy (``f = k_l e + k_n e³ + c ė`` on the
extensions ``e = diff([0, p - p_e, 0])`` and their rates ``ė = diff([0, ṗ, 0])``) and the
scene's own ``ExternalTorque.at``."""

from __future__ import annotations

import numpy as np
import pytest

from analytic.effects import Effect
from analytic.fast import FastModel
from analytic.kernel.layout import I_KP, tail_offsets
from analytic.scene.random_scenes import random_scene
from mj_bridge.scipy_forces import FORCE_EFFECTS, FORCES, force
from mj_bridge.scipy_stage import apply_forces


def test_one_function_per_force_effect():
    assert FORCE_EFFECTS == {
        Effect.SPRINGS_LINEAR,
        Effect.SPRINGS_CUBIC,
        Effect.SPRINGS_DAMPING,
        Effect.EXTERNAL_TORQUE,
    }
    assert all(callable(fn) and isinstance(flag, int) for flag, fn in FORCES.values())
    with pytest.raises(ValueError, match=r"^springs\.linear: a force is registered for it already"):
        force(Effect.SPRINGS_LINEAR, 0)(lambda *args: None)


@pytest.mark.parametrize("off", [(), (Effect.SPRINGS_CUBIC,), (Effect.SPRINGS_LINEAR,),
                                 (Effect.SPRINGS_DAMPING,), (Effect.EXTERNAL_TORQUE,)])  # fmt: skip
def test_the_chain_applies_the_scenes_forces(off):
    rng = np.random.default_rng(8)
    effects = ["springs.linear", "springs.cubic", "springs.damping"]
    sc = random_scene(rng, 3, external_torque=True, controlled=False, effects=effects)
    sc = sc.with_effects(sc.effects - set(off))
    fm = FastModel(sc)
    n = sc.n
    q = np.concatenate([rng.normal(size=3), [1.0, 0.0, 0.0, 0.0], rng.normal(size=n)])
    qd = rng.normal(size=n + 7)
    t = 0.37
    tt0 = np.array([0.1, -0.2, 0.3])
    tt, ten = tt0.copy(), np.zeros(n + 1)
    apply_forces(t, q, qd, fm.fp, fm.ip, tail_offsets(n, int(fm.ip[I_KP])), tt, ten)
    e = np.diff(np.concatenate([[0.0], q[7:] - sc.masses.p_e, [0.0]]))
    ref = np.zeros(n + 1)
    if sc.has(Effect.SPRINGS_LINEAR):
        ref += sc.springs.k_linear * e
    if sc.has(Effect.SPRINGS_CUBIC):
        ref += sc.springs.k_cubic * e**3
    if sc.has(Effect.SPRINGS_DAMPING):
        ref += sc.springs.c_damping * np.diff(np.concatenate([[0.0], qd[7:], [0.0]]))
    np.testing.assert_allclose(ten, ref, rtol=1e-14, atol=0)
    torque = sc.external_torque.at(t) if sc.has(Effect.EXTERNAL_TORQUE) else 0.0
    np.testing.assert_allclose(tt, tt0 + torque, rtol=1e-14, atol=1e-16)
