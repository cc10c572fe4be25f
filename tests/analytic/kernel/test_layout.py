"""The packed layout: ``fp``'s tail blocks follow each other without gaps or overlaps, in the
order of :class:`~analytic.kernel.layout.FpTail`'s fields, and the packer fills each block with
the model's numbers (what a new block must keep true)."""

from __future__ import annotations

import numpy as np
import pytest

from analytic.effects.registry import SPRING_LAWS
from analytic.fast import pack
from analytic.kernel import layout as L
from analytic.model import TumblingModel
from analytic.scene.random_scenes import random_scene

LENGTHS = {
    "m": lambda n, kp: n,
    "p_e": lambda n, kp: n,
    "laws": lambda n, kp: L.N_LAWS * (n + 1),
    "l": lambda n, kp: kp,
    "lam": lambda n, kp: kp,
    "alpha": lambda n, kp: kp,
    "beta": lambda n, kp: kp,
    "a": lambda n, kp: 3,
    "d": lambda n, kp: 3,
}
"""The length of each block of the tail, for n masses and k_p tracked masses."""


@pytest.mark.parametrize(("n", "kp"), [(0, 0), (1, 0), (1, 1), (4, 2), (7, 7)])
def test_the_tail_blocks_follow_each_other(n, kp):
    o = L.tail_offsets(n, kp)
    assert o._fields[:-1] == tuple(LENGTHS) and o._fields[-1] == "end"
    at = L.F_ARR
    for name, length in LENGTHS.items():
        assert getattr(o, name) == at, name
        at += length(n, kp)
    assert o.end == at == L.fp_length(n, kp)
    assert L.ip_length(n, kp) == L.I_TRACK + n + kp


def test_the_packer_fills_every_block():
    sc = random_scene(np.random.default_rng(3), 4, controlled=True, track_all=True)
    model = TumblingModel(sc)
    fp, ip = pack(model)
    n, kp = model.n, len(model.mass_track.indices)
    o = L.tail_offsets(n, kp)
    assert fp.shape == (o.end,) and ip.shape == (L.ip_length(n, kp),)
    mt = model.mass_track
    want = {
        "m": model.m,
        "p_e": model.p_e,
        "laws": np.concatenate([model.spring_coefficients[law.effect] for law in SPRING_LAWS]),
        "l": mt.l,
        "lam": mt.lam,
        "alpha": mt.alpha,
        "beta": mt.beta,
        "a": model.a,
        "d": model.d,
    }
    for name, value in want.items():
        start = getattr(o, name)
        block = fp[start : start + LENGTHS[name](n, kp)]
        np.testing.assert_array_equal(block, np.broadcast_to(value, block.shape), err_msg=name)
    np.testing.assert_array_equal(ip[L.I_TRACK + n :], mt.indices)
    for law in SPRING_LAWS:  # each law's flag, in its slot
        assert ip[L.I_LAWS + L.LAW_INDEX[law.effect]] == sc.has(law.effect), law.effect
