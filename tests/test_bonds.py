"""The linear algebra and bookkeeping of clusters of bonds (heyroll.simulation.table.bonds), checked against
independent computations: numpy's solver, brute force over every active set, relabelled clusters."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from heyroll.simulation.table.bonds import (bond_matrix, clusters, complementary, free_work, pushes, solve,
                                            topology)


def random_cluster(rng, balls: int, bonds: int):
    """Random directions of ``bonds`` pair bonds along a chain (a tree: independent rows) and mobilities."""
    directions = []
    for e in range(bonds):
        dx, dy = rng.normal(size=2)
        directions.append({e: (-dx, -dy), e + 1: (dx, dy)})
    mobility = {k: rng.uniform(0.5, 6.0) for k in range(balls)}
    return directions, mobility


def dense(matrix):
    return np.array([[0.0 if v is None else v for v in row] for row in matrix])


@pytest.mark.parametrize("bonds", [1, 2, 4, 7])
def test_the_elimination_agrees_with_numpy_and_forces_follow_the_rows(bonds):
    rng = np.random.default_rng(bonds)
    directions, mobility = random_cluster(rng, bonds + 1, bonds)
    matrix = bond_matrix(directions, mobility)
    right = list(rng.normal(size=bonds))
    lam, = solve(matrix, [right])
    assert np.allclose(lam, np.linalg.solve(dense(matrix), right), rtol=1e-12, atol=1e-12)
    # a_k = w_k sum_e lambda_e n_ek, and J a = A lambda (J the rows of directions)
    accelerations = pushes(directions, mobility, lam)
    assert np.allclose(free_work(directions, accelerations), dense(matrix) @ lam, rtol=1e-12, atol=1e-12)
    assert matrix[0][-1] is None or bonds <= 2  # bonds sharing no ball: a structural zero


def brute_force_lcp(a: np.ndarray, b: np.ndarray):
    """Every active set in turn: lambda_S = A_SS^-1 b_S >= 0 and (A lambda - b)_e >= 0 off S."""
    m = len(b)
    found = []
    for size in range(m + 1):
        for active in itertools.combinations(range(m), size):
            lam = np.zeros(m)
            if active:
                index = list(active)
                lam[index] = np.linalg.solve(a[np.ix_(index, index)], b[index])
            w = a @ lam - b
            if np.all(lam >= -1e-12) and np.all(w >= -1e-12):
                found.append(lam)
    return found


@settings(max_examples=60, deadline=None)
@given(st.integers(min_value=1, max_value=6), st.integers(min_value=0, max_value=2**31))
def test_the_complementarity_solution_is_the_only_one_brute_force_finds(bonds, seed):
    rng = np.random.default_rng(seed)
    directions, mobility = random_cluster(rng, bonds + 1, bonds)
    matrix = bond_matrix(directions, mobility)
    right = list(rng.normal(size=bonds))
    lam = np.array(complementary(matrix, right))
    solutions = brute_force_lcp(dense(matrix), np.array(right))
    assert len(solutions) == 1  # A is symmetric positive definite: one solution
    assert np.allclose(lam, solutions[0], rtol=1e-10, atol=1e-12)
    w = dense(matrix) @ lam - np.array(right)
    assert np.all(lam >= 0) and np.all(w >= -1e-12) and abs(float(lam @ w)) < 1e-12


def test_isomorphic_clusters_share_one_shape_and_keep_their_balls():
    walls = lambda ball, wall: 3  # noqa: E731 (every wall's gap of one form)
    chain_a = [("pair", 0, 1), ("pair", 1, 2)]
    chain_b = [("pair", 3, 9), ("pair", 5, 9)]  # the same chain, its middle ball 9
    shape_a, members_a, slots_a = topology(chain_a, walls)
    shape_b, members_b, slots_b = topology(chain_b, walls)
    assert shape_a == shape_b and members_a[0] == 1 and members_b[0] == 9
    assert sorted(slots_a) == chain_a and sorted(slots_b) == chain_b
    # each local bond names the slot's actual balls through the members
    for (kind, a, b), slot in zip(shape_b, slots_b):
        assert kind == "pair" and {members_b[a], members_b[b]} == {slot[1], slot[2]}
    # two clusters (a pair pressed into the cushion, a chain) in any numbering: one shape
    mixed = [("pair", 3, 7), ("wall", 7, 1), ("pair", 0, 5), ("pair", 5, 6)]
    renamed = [("pair", 10, 2), ("wall", 2, 0), ("pair", 4, 8), ("pair", 8, 11)]
    renamed = [(k, min(a, b), max(a, b)) if k == "pair" else (k, a, b) for k, a, b in renamed]
    assert topology(mixed, walls)[0] == topology(renamed, walls)[0]
    assert [sorted(g) for g in clusters(mixed)] == [[("pair", 0, 5), ("pair", 5, 6)],
                                                    [("pair", 3, 7), ("wall", 7, 1)]]
