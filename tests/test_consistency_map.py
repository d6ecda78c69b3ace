"""validation/consistency_map.py: the analytic consistency condition against sampled rates.

The rolling law separates every approaching pair of rates iff r_i = r_j (any
k); the engine's own impulse map, applied to rates sampled on the
kinetic-energy circle, must agree sample by sample, and the sampled share of
inconsistent outcomes must match the analytic wedge.
"""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest

PATH = Path(__file__).resolve().parents[1] / "validation" / "consistency_map.py"


@pytest.fixture(scope="module")
def cmap():
    spec = importlib.util.spec_from_file_location("consistency_map", PATH)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize(
    "r_i, r_j, k",
    [(0.1, 0.1, 0.0), (0.1, 0.1, 0.7), (0.25, 0.25, 1.0), (0.1, 0.15, 0.8), (0.1, 0.15, 1.0), (0.15, 0.1, 0.0),
     (0.1, 0.102, 0.9), (0.3, 0.05, 0.4)],
)
def test_analytic_condition_matches_sampling(cmap, r_i, r_j, k):
    check = cmap.check_point(r_i, r_j, k, samples=6000, seed=1)
    assert check.analytic_always == (r_i == r_j)
    assert check.disagreements == 0  # the analytic predicate, sample by sample
    if check.analytic_always:
        assert check.sampled_inconsistent == 0 and check.analytic_fraction == 0 and check.wedge_samples == 0
    else:
        assert check.wedge_samples > 0 and check.wedge_consistent == 0  # every state in the wedge is inconsistent
    assert abs(check.sampled_fraction - check.analytic_fraction) <= 5 * check.fraction_sigma + 1e-12
    assert check.ok


def test_equal_radii_outcome_is_minus_k_times_the_approach(cmap):
    p = cmap.pair(0.12, 0.12, 0.6)
    assert p.alpha_i == pytest.approx(1.6, rel=1e-14) and p.alpha_j == pytest.approx(1.6, rel=1e-14)
    x, y = np.array([1.0, 3.0, -0.5]), np.array([-2.0, 2.5, -4.0])
    assert np.allclose(cmap.outgoing_closing_rate(p, x, y), -0.6 * (x - y), rtol=1e-14)


def test_prototype_wedge_is_the_larger_ball_catching_up(cmap):
    # r = 0.10 / 0.15, k = 0.8: inconsistent iff x < t* y with x > y: both move clockwise (y < x < 0).
    p = cmap.pair(0.1, 0.15, 0.8)
    t_star = (1 - p.alpha_j) / (1 - p.alpha_i)
    assert 0 < t_star < 1
    y = -1.0
    inside, outside = (1 + t_star) / 2 * y, t_star / 2 * y  # x between y and t* y; x beyond t* y
    assert cmap.predicted_inconsistent(p, inside, y) and cmap.engine_inconsistent(0.1, 0.15, 0.8, inside, y)
    assert not cmap.predicted_inconsistent(p, outside, y) and not cmap.engine_inconsistent(0.1, 0.15, 0.8, outside, y)
    # head-on and rear-end from the other side are consistent
    assert not cmap.engine_inconsistent(0.1, 0.15, 0.8, 1.0, -1.0)
    assert not cmap.engine_inconsistent(0.1, 0.15, 0.8, 2.0, 1.0)
    assert cmap.inconsistent_fraction(0.1, 0.15, 0.8) == pytest.approx(0.1248, abs=1e-3)


def test_fraction_vanishes_toward_equal_radii_except_at_k0(cmap):
    near = [cmap.inconsistent_fraction(0.1, 0.1 * q, 0.8) for q in (1.5, 1.1, 1.01, 1.001)]
    assert all(a > b for a, b in zip(near, near[1:])) and near[-1] < 1e-3
    assert cmap.inconsistent_fraction(0.1, 0.1001, 0.0) > 0.4  # plastic in omega_P: unequal phi'
    a, b = cmap.wedge_angles(0.1, 0.15, 0.8)
    assert b - a == pytest.approx(math.pi * cmap.inconsistent_fraction(0.1, 0.15, 0.8), rel=1e-12)


def test_hit_at_rest(cmap):
    # A ball hitting the other at rest separates iff alpha of the moving ball >= 1.
    for r_j, k in [(0.15, 0.8), (0.2, 0.8), (0.3, 0.2)]:
        p = cmap.pair(0.1, r_j, k)
        j_moves = cmap.engine_inconsistent(0.1, r_j, k, 0.0, -1.0)  # body i at rest, j hits it
        i_moves = cmap.engine_inconsistent(0.1, r_j, k, 1.0, 0.0)
        assert bool(j_moves) == (p.alpha_j < 1) and bool(i_moves) == (p.alpha_i < 1)
        assert cmap.hit_at_rest_consistent(0.1, r_j, k) == (not j_moves and not i_moves)
