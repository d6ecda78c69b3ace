"""The work-precision study's pieces (validation/work_precision.py, validation/scipy_baseline.py).

The study itself is long and runs from validation/; here: its error metric
flags a diverged collision sequence, and the scipy baseline solves the same
problem as heyroll (first collisions of the default scene against the exact
reference). The scipy tests skip when scipy (the ``validation`` extra) is
missing.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

import heyroll
from heyroll.reference.collisions import reference_collisions

VALIDATION = Path(__file__).resolve().parents[1] / "validation"


def _load(name: str):
    """A module of validation/ by path (it is not a package)."""
    key = f"heyroll_validation_{name}"
    if key in sys.modules:
        return sys.modules[key]
    spec = importlib.util.spec_from_file_location(key, VALIDATION / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[key] = module  # dataclasses need their module registered
    try:
        spec.loader.exec_module(module)
    except BaseException:
        del sys.modules[key]
        raise
    return module


@pytest.fixture(scope="module")
def study():
    return _load("work_precision")


@pytest.fixture(scope="module")
def baseline():
    pytest.importorskip("scipy")
    return _load("scipy_baseline")


REF_T = [1.0, 2.0, 3.0, 4.0, 5.0]
REF_P = [(1, 2), (2, 3), (1, 2), (2, 3), (1, 2)]


def test_metric_gives_errors_of_a_matching_sequence(study):
    found = [1.0 + 1e-12, 2.0, 3.0 - 3e-12, 4.0]
    acc = study.collision_time_errors(found, REF_P[:4], REF_T, REF_P, 4)
    assert acc.ok and acc.failure == ""
    assert acc.max_rel == pytest.approx(1e-12, rel=1e-3)  # 3e-12 / 3
    assert acc.first_rel == pytest.approx(1e-12, rel=1e-3)


@pytest.mark.parametrize(
    "times, pairs, why",
    [
        ([1.0, 2.0, 3.0], REF_P[:3], "found 3 of 4"),  # a collision lost
        ([1.0, 2.0, 3.0, 4.0], [(1, 2), (2, 3), (2, 3), (2, 3)], "between bodies"),  # another pair
        # Collision 2 missed, a spurious one later: the count and the pairs still match.
        ([1.0, 3.0, 3.5, 4.0], [(1, 2), (2, 3), (1, 2), (2, 3)], "nearest reference collision 3"),
        ([1.0, 1.2, 2.0, 3.0], [(1, 2), (2, 3), (1, 2), (2, 3)], "nearest reference collision 1"),  # an extra one
    ],
)
def test_metric_detects_a_diverged_sequence(study, times, pairs, why):
    acc = study.collision_time_errors(times, pairs, REF_T, REF_P, 4)
    assert not acc.ok
    assert acc.max_rel is None and acc.first_rel is None
    assert why in acc.failure


def test_headline_picks_the_cheapest_heyroll_run_at_dop853_best(study):
    A, R = study.Accuracy, study.Row
    rows = [
        R("heyroll double", "tol = 1e-08", A(1e-11, 1e-12), 0.004, 30, x=1e-8),
        R("heyroll double", "tol = eps", A(2e-16, 1e-17), 0.006, 30, x=2.0**-52),
        R("DOP853", "rtol = 1e-12", A(2e-12, 1e-13), 0.05, 30, x=1e-12),
        R("DOP853", "rtol = 2.22e-14", A(1e-14, 1e-16), 0.08, 30, x=2.2e-14),
        R("DOP853", "rtol = 1e-03", A(None, None, "found 29 of 30 collisions"), 0.01, 29, x=1e-3),
    ]
    h = study.headline(rows)
    assert h["dop"].setting == "rtol = 2.22e-14"
    assert h["match"].setting == "tol = eps"
    assert h["speed"] == pytest.approx(0.08 / 0.006)
    assert h["accuracy"] == pytest.approx(1e-14 / 2e-16)


def test_scipy_baseline_reproduces_the_first_collisions(study, baseline):
    scene = heyroll.default_scene()
    n = 3
    ref = reference_collisions(scene, n + 1, dps=30, t_end=100)
    problem = baseline.problem_from_scene(scene)
    run = baseline.run_baseline(problem, "DOP853", 1e-12, n, 100.0)
    assert run.status == "max_collisions", run.message
    acc = study.collision_time_errors(run.times, run.pairs, [c.t for c in ref], [(c.i, c.j) for c in ref], n)
    assert acc.ok, acc.failure
    assert acc.max_rel <= 1e-9


def test_scipy_baseline_right_hand_sides_agree(baseline):
    import numpy as np

    problem = baseline.problem_from_scene(heyroll.default_scene())
    numpy_rhs, jac = baseline.make_rhs(problem, "numpy")
    two_rhs, _ = baseline.make_rhs(problem, "two")
    y = np.array([-1.1, 0.4, 0.7, -2.0])
    assert np.allclose(numpy_rhs(0.0, y), two_rhs(0.0, y), rtol=1e-15, atol=0)
    assert np.allclose(two_rhs(0.0, y)[2:], -problem.a * np.sin(y[:2]), rtol=1e-15, atol=0)
    J = jac(0.0, y)  # d(rhs)/dy for the implicit methods
    h = 1e-7
    numeric = np.column_stack([(two_rhs(0.0, y + h * e) - two_rhs(0.0, y - h * e)) / (2 * h) for e in np.eye(4)])
    assert np.allclose(J, numeric, atol=1e-7)


def test_scipy_baseline_applies_heyroll_law(baseline):
    """The same impulse map as the engine: one elastic collision conserves the engine's energy."""
    import numpy as np

    scene = heyroll.default_scene()
    problem = baseline.problem_from_scene(scene)
    (pair,) = problem.pairs  # the default scene's energy reaches only the (1, 2) contact
    y = np.array([0.0, 0.3, 2.0, -1.0])
    result = heyroll.simulate(scene, t_end=0.0, max_collisions=0)
    before = result.energy(y)
    baseline.apply_law(pair, y, problem.n_bodies)
    assert y[2] != 2.0 and y[3] != -1.0
    assert result.energy(y) == pytest.approx(before, rel=1e-14)
