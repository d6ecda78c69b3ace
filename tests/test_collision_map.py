"""The collision map as a double run applies it (events.working_map): double-double
constants with a_i + q a_j = 1 + k, exact products, outgoing rates rounded once."""

from __future__ import annotations

import random

import mpmath
import pytest

from heyroll.model.laws import ImpulseMap
from heyroll.simulation.events import working_map
from heyroll.simulation.precision import Precision


def law_map(q, a_j, k):
    q, a_j, k = mpmath.mpf(q), mpmath.mpf(a_j), mpmath.mpf(k)
    return ImpulseMap(q=q, a_i=(1 + k) - q * a_j, a_j=a_j, one_plus_k=1 + k)


def exact(pair) -> mpmath.mpf:
    return mpmath.mpf(pair[0]) + pair[1]


@pytest.mark.parametrize("seed", range(4))
def test_double_runs_apply_the_map_correctly_rounded(seed):
    rng = random.Random(seed)
    m = law_map(rng.uniform(0.2, 3), rng.uniform(0.1, 1.9), rng.choice(["1", "0.9", "0.5", "0"]))
    wm = working_map(m, Precision.parse("double"))
    with mpmath.workprec(300):
        q, a_i, a_j = exact(wm.q), exact(wm.a_i), exact(wm.a_j)
        assert abs(a_i + q * a_j - m.one_plus_k) < mpmath.mpf(2) ** -100  # the map's invariant, to ~106 bits
        for _ in range(500):
            vi = rng.uniform(-3, 3) * 10.0 ** rng.randint(-8, 2)
            vj = rng.uniform(-3, 3) * 10.0 ** rng.randint(-8, 2)
            d = vi - q * vj
            assert wm.apply(vi, vj) == (float(vi - a_i * d), float(vj + a_j * d))


def test_other_precisions_apply_the_map_in_their_own_type():
    wm = working_map(law_map("1.25", "0.5", "1"), Precision.parse("quad"))
    vi, vj = wm.q * 0 + 1, wm.q * 0 - 2  # real128 numbers
    out = wm.apply(vi, vj)
    assert all(type(v) is type(vi) for v in out)
    d = vi - wm.q * vj
    assert out == (vi - wm.a_i * d, vj + wm.a_j * d)
