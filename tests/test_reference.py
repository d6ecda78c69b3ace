"""The heyoka engine against the independent mpmath reference (heyroll.reference).

The reference solves every inter-collision arc exactly with Jacobi elliptic
functions (paper eqs. 25, 45-50) and finds collisions with a root-safe
stepping, at 40 significant digits; see heyroll/reference/README.md.

Two kinds of comparison:

* single body: the engine's heyoka system (build_system) against the
  closed-form period 4 K(m)/sqrt(a), the Jacobi state and the Legendre-F
  time integral;
* whole runs: engine collision tables against reference collisions, relative
  error in the collision times, for scenes of different shapes, radii,
  masses, laws and restitution.

Measured worst relative errors in t are written next to each bound (heyoka
7.x, double, tol = eps). Where a bound is above the project target of 1e-15
the scene itself amplifies rounding: this is measured, not assumed, by
``test_engine_error_is_at_the_scene_conditioning`` (the spread of an ideal
double computation, modelled by jittering the exact solution by one unit
roundoff per quantity per collision).
"""

from __future__ import annotations

import functools
import math
import random

import heyoka as hy
import mpmath
import numpy as np
import pytest

import heyroll
from heyroll.reference.collisions import (
    ReferenceCollision,
    compare_with_engine,
    reference_collisions,
    reference_table,
    run_reference,
)
from heyroll.reference.pendulum import LIBRATION, ROTATION, SEPARATRIX, ExactPendulum
from heyroll.simulation.precision import DOUBLE
from heyroll.simulation.system import build_system

EPS = 2.0**-52
UNIT_ROUNDOFF = 2.0**-53

# ---------------------------------------------------------------------------
# Single body
# ---------------------------------------------------------------------------

# g = 9, a disk (kappa = 3/2) of radius 0.25 in R = 1: a = 9 / (1.5 * 0.75) = 8
# exactly, so the engine's double parameter is the exact a. With phi0 = 0 and
# phi0' a double, the engine integrates exactly the problem the reference
# solves: no input rounding enters the comparison.
A_EXACT = 8


def _disk_scene(phi0: float, dphi0: float) -> heyroll.Scene:
    return heyroll.Scene.make(
        track=heyroll.CircleTrack.of_radius(1),
        bodies=[heyroll.Body.of_shape("disk", 0.25, mass=1)],
        phi=[phi0],
        dphi=[dphi0],
        g=9,
    )


def _integrator(scene, high_accuracy=True, nt_events=()):
    sys_ = build_system(scene, DOUBLE, events=False)
    assert sys_.parameters[0] == A_EXACT
    return hy.taylor_adaptive(
        sys_.equations,
        sys_.initial_state_of(scene),
        pars=sys_.parameters,
        high_accuracy=high_accuracy,
        nt_events=list(nt_events),
    )


def _dphi_for_energy(m) -> float:
    """phi0' (a double) at phi0 = 0 for energy m = C/(4a) in separatrix units."""
    with mpmath.workdps(40):
        return float(2 * mpmath.sqrt(A_EXACT * mpmath.mpf(m)))


def _period_condition(m) -> mpmath.mpf:
    """kappa = d ln T / d ln m = m K'(m)/K(m) = (E - (1-m) K) / (2 (1-m) K).

    The relative change of the libration period per relative change of the
    energy. It grows like 1/(2 (1-m) K(m)) at the separatrix.
    """
    with mpmath.workdps(40):
        m = mpmath.mpf(m)
        K, E = mpmath.ellipk(m), mpmath.ellipe(m)
        return (E - (1 - m) * K) / (2 * (1 - m) * K)


ENERGIES = ["0.01", "0.5", "0.9", "0.99", "0.999999", "0.999999999999"]


@pytest.mark.parametrize("high_accuracy", [True, False], ids=["ha", "no_ha"])
@pytest.mark.parametrize("m", ENERGIES)
def test_engine_period_matches_4K_over_sqrt_a(m, high_accuracy):
    dphi0 = _dphi_for_energy(m)
    exact = ExactPendulum(A_EXACT, 0, dphi0, 0, dps=40)
    assert exact.regime == LIBRATION
    T = exact.period()
    with mpmath.workdps(40):
        assert abs(T - 4 * mpmath.ellipk(exact.m) / mpmath.sqrt(A_EXACT)) < mpmath.mpf(10) ** -38 * T

    times = []
    phi = hy.make_vars("phi_1")
    event = hy.nt_event(phi, lambda ta, t, d: times.append(t), direction=hy.event_direction.positive)
    ta = _integrator(_disk_scene(0.0, dphi0), high_accuracy, [event])
    ta.propagate_until(float(4.5 * T))
    # Upward passages through the lowest point: t = 0 (the start), T, 2T, 3T, 4T.
    assert len(times) == 5
    with mpmath.workdps(40):
        measured = (mpmath.mpf(times[4]) - mpmath.mpf(times[0])) / 4
        rel = float(abs(measured - T) / T)
    kappa = float(_period_condition(m))
    # Near the separatrix the period is ill-conditioned in the energy (kappa
    # above): any double-precision integration carries energy errors of a
    # few ulp (the state alone is stored to 1 ulp), so the best achievable
    # relative error in T is about kappa * eps -- 7e-12 at 1 - 1e-6 and 4e-6 at
    # 1 - 1e-12 of the separatrix energy. Measured (ha / no_ha):
    #   0.01: 8.0e-17 / 8.0e-17    0.5: 9.6e-17 / 9.6e-17    0.9: 1.9e-16 / 5.5e-17
    #   0.99: 6.6e-16 / 5.3e-15 (kappa eps 2.9e-15)
    #   1-1e-6: 3.7e-12 / 1.3e-11 (kappa eps 1.3e-11)
    #   1-1e-12: 3.9e-6 / 5.4e-6 (kappa eps 7.3e-6)
    # The project target 1e-15 is asserted wherever kappa * eps < 4e-16.
    bound = 1e-15 if kappa * EPS < 4e-16 else 8 * kappa * EPS
    print(f"m={m} high_accuracy={high_accuracy}: period rel err {rel:.2e}, kappa*eps {kappa * EPS:.2e}, bound {bound:.1e}")
    assert rel <= bound


@pytest.mark.parametrize("m", ["2", "1.000001"])
def test_engine_revolution_time_matches_4K_over_sqrt_C(m):
    dphi0 = _dphi_for_energy(m)
    exact = ExactPendulum(A_EXACT, 0, dphi0, 0, dps=40)
    assert exact.regime == ROTATION and exact.period() is None
    T = exact.revolution_time()
    times = []
    phi = hy.make_vars("phi_1")
    # cos(phi/2) = 0 at the top, phi = pi + 2 pi n: once per revolution.
    event = hy.nt_event(hy.cos(phi / 2), lambda ta, t, d: times.append(t))
    ta = _integrator(_disk_scene(0.0, dphi0), True, [event])
    ta.propagate_until(float(4.5 * T))
    assert len(times) == 4
    with mpmath.workdps(40):
        measured = (mpmath.mpf(times[3]) - mpmath.mpf(times[0])) / 3
        rel = float(abs(measured - T) / T)
        first = float(abs(mpmath.mpf(times[0]) - exact.time_to_angle(mpmath.pi)) / T)
    # T_rev = 2 K(1/m) / sqrt(a m): the same conditioning as the libration
    # period, mirrored above the separatrix, |d ln T / d ln m| <= kappa(1/m) + 1/2.
    kappa = float(_period_condition(1 / mpmath.mpf(m))) + 0.5
    bound = 1e-15 if kappa * EPS < 4e-16 else 8 * kappa * EPS
    # Measured: m = 2: 4e-17 (first top 1e-16); m = 1 + 1e-6: 7e-12 (first top 5e-13), kappa eps 1.3e-11.
    print(f"m={m}: revolution rel err {rel:.2e}, first top {first:.2e}, kappa*eps {kappa * EPS:.2e}")
    assert rel <= bound and first <= bound


def _odefun_state(a, phi0, dphi0, t):
    with mpmath.workdps(25):
        f = mpmath.odefun(lambda _t, y: [y[1], -a * mpmath.sin(y[0])], 0, [mpmath.mpf(phi0), mpmath.mpf(dphi0)])
        return f(mpmath.mpf(t))


@pytest.mark.parametrize(
    "phi0, dphi0, regime",
    [
        (-1.1, 0.3, LIBRATION),
        (2.9, 0.0, LIBRATION),  # starts at a turning point, near the top
        (0.3, -6.5, ROTATION),
    ],
)
def test_jacobi_state_matches_a_taylor_series_solution(phi0, dphi0, regime):
    """The elliptic-function state against mpmath's own Taylor ODE solver (25 digits)."""
    a = mpmath.mpf("7.5")
    p = ExactPendulum(a, phi0, dphi0, 0, dps=40)
    assert p.regime == regime
    t = "1.9"  # past a turning point for both librations
    phi, dphi = p.state(t)
    ref = _odefun_state(a, phi0, dphi0, t)
    assert abs(phi - ref[0]) < 1e-22 and abs(dphi - ref[1]) < 1e-22


@pytest.mark.parametrize(
    "phi0, dphi0, t_max, bound",
    [
        (0.4, 1.3, 10.0, 2e-15),  # libration, m = 0.09
        (2 * math.pi + 0.4, -5.4, 10.0, 1e-14),  # libration about 2 pi, m = 0.95, passes turning points
        (0.3, -6.5, 10.0, 1e-14),  # rotation, clockwise over the top, |phi| grows to ~60 rad
        (-3.0, 9.0, 10.0, 2e-14),  # fast rotation, |phi| grows to ~90 rad
    ],
)
def test_jacobi_state_matches_heyoka(phi0, dphi0, t_max, bound):
    """Heyoka's state of one body against the Jacobi solution at random times (inputs exact doubles).

    Errors are absolute, in rad and rad/s, measured relative to the size of
    the state: the integrator's phase error grows linearly with time, and an
    unwrapped angle of tens of rad carries an ulp of ~1e-14 by itself.
    Measured: 2.3e-16, 4.8e-15, 2.5e-15, 5.4e-16 (relative to 1 + |phi| + |phi'|).
    """
    exact = ExactPendulum(A_EXACT, phi0, dphi0, 0, dps=40)
    rng = random.Random(1)
    grid = [0.0] + sorted(rng.uniform(0, t_max) for _ in range(25))
    ta = _integrator(_disk_scene(phi0, dphi0))
    out = ta.propagate_grid(grid)[5]
    worst = 0.0
    for t, (phi_e, dphi_e) in zip(grid, out):
        phi, dphi = exact.state(t)
        scale = 1 + abs(float(phi)) + abs(float(dphi))
        worst = max(worst, float(abs(phi_e - phi)) / scale, float(abs(dphi_e - dphi)) / scale)
    print(f"{exact.regime} phi0={phi0} dphi0={dphi0}: worst state error {worst:.2e}")
    assert worst <= bound


def _quad_time(a, phi0, dphi0, phi_to):
    """int dphi / sqrt(phi0'^2 + 4 a (sin^2(phi0/2) - sin^2(phi/2))) along a monotone branch (eq. 48).

    sin^2 A - sin^2 B = sin(A - B) sin(A + B) keeps the radicand accurate at
    a turning point, where tanh-sinh quadrature samples the 1/sqrt endpoint
    singularity at distances far below 1e-40. The quadrature runs at 60
    digits: at 40 its estimated error at a turning point is 1e-23.
    """
    with mpmath.workdps(60):
        a, phi0, dphi0 = mpmath.mpf(a), mpmath.mpf(phi0), mpmath.mpf(dphi0)
        f = lambda x: 1 / mpmath.sqrt(dphi0**2 + 4 * a * mpmath.sin((phi0 - x) / 2) * mpmath.sin((phi0 + x) / 2))
        lo, hi = sorted((phi0, mpmath.mpf(phi_to)))
        return mpmath.quad(f, [lo, (lo + hi) / 2, hi])


@pytest.mark.parametrize(
    "a, phi0, dphi0, targets",
    [
        ("7.5", "-1.1", "0.3", ["-1.0", "0.0", "1.1"]),  # libration moving up to its turning point
        ("7.5", "0.6", "-0.8", ["0.0", "-0.6"]),  # libration moving down
        ("7.5", "6.9", "0.0", ["6.5", "6.0"]),  # at rest at a turning point about 2 pi: starts down
        ("7.5", "0.3", "6.5", ["3.0", "9.0", "20.0"]),  # rotation over several turns
        ("7.5", "0.3", "-6.5", ["-3.0", "-10.0"]),  # rotation, clockwise
        ("4", "0", "4", ["1.0", "2.5", "3.1"]),  # separatrix: C = 4 a exactly
    ],
)
def test_time_to_angle_matches_quadrature_and_the_state(a, phi0, dphi0, targets):
    p = ExactPendulum(a, phi0, dphi0, 0, dps=40)
    if a == "4":
        assert p.regime == SEPARATRIX
    with mpmath.workdps(40):
        for target in targets:
            t = p.time_to_angle(target)
            assert t is not None and t > 0
            q = _quad_time(a, phi0, dphi0, target)
            assert abs(t - q) < mpmath.mpf(10) ** -30 * (1 + q)
            phi, _ = p.state(t)
            assert abs(phi - mpmath.mpf(target)) < mpmath.mpf(10) ** -30


def test_time_to_angle_is_none_off_the_branch():
    p = ExactPendulum("7.5", "-1.1", "0.3", 0, dps=40)  # libration, moving up
    amplitude = p.amplitude()
    assert p.time_to_angle(-1.2) is None  # behind
    assert p.time_to_angle(amplitude + mpmath.mpf("0.01")) is None  # beyond the turning point
    turning = p.time_to_angle(amplitude)
    assert turning is not None
    with mpmath.workdps(40):
        assert abs(p.state(turning)[1]) < mpmath.mpf(10) ** -15
    rot = ExactPendulum("7.5", "0.3", "6.5", 0, dps=40)
    assert rot.time_to_angle("0.2") is None  # a rotation never comes back


def test_pendulum_energy_is_kept_and_precision_is_local():
    dps_before = mpmath.mp.dps
    for phi0, dphi0 in (("-1.1", "0.3"), ("0.3", "6.5"), ("3.1", "-0.01")):
        p = ExactPendulum("7.5", phi0, dphi0, 0, dps=50)
        with mpmath.workdps(50):
            for t in ("0.1", "3.7", "41.9"):
                phi, dphi = p.state(t)
                C = dphi**2 + 4 * p.a * mpmath.sin(phi / 2) ** 2
                assert abs(C - p.energy) < mpmath.mpf(10) ** -45 * p.energy
    assert mpmath.mp.dps == dps_before


# ---------------------------------------------------------------------------
# Whole runs: engine collision tables against the reference
# ---------------------------------------------------------------------------

ISSUE_SCENE = """
g = 9.81
[track]
type = "circle"
radius = 1.3
[[bodies]]
shape = "disk"
radius = 0.12
mass = 2.0
phi = -1.1
dphi = 0.3
[[bodies]]
shape = "ring"
radius = 0.12
mass = 0.7
phi = 0.6
dphi = -0.8
[collision]
law = "hedrih"
restitution = 1.0
[run]
t_end = 100.0
max_collisions = 20
"""


def _two(b1: str, b2: str, law: str, k: str, R: str = "1.0") -> str:
    return (
        f'g = 9.81\n[track]\ntype = "circle"\nradius = {R}\n'
        f"[[bodies]]\n{b1}\n[[bodies]]\n{b2}\n"
        f'[collision]\nlaw = "{law}"\nrestitution = {k}\n[run]\nt_end = 100.0\n'
    )


SCENES = {
    # The issue's example: disk and ring of equal radii, rolling law, elastic.
    "issue_disk_ring": ISSUE_SCENE,
    # The default scene: steel solid spheres r = 0.10 / 0.15 in R = 1, rolling law.
    "default_solid_spheres": None,
    # Two particles (r = 0), Newton's law on centre speeds, masses 1 and 3.
    "particles_newton": _two(
        'shape = "particle"\nmass = 1.0\nphi = -0.9\ndphi = 0.4',
        'shape = "particle"\nmass = 3.0\nphi = 0.7\ndphi = 0.0',
        "newton",
        "1.0",
    ),
    # Solid and hollow spheres of equal radii, rolling law, k = 0.7.
    "hedrih_k07": _two(
        'shape = "solid_sphere"\nradius = 0.1\nmass = 1.0\nphi = -1.5\ndphi = 1.0',
        'shape = "hollow_sphere"\nradius = 0.1\nmass = 4.0\nphi = 0.3\ndphi = 0.0',
        "hedrih",
        "0.7",
    ),
    # Three bodies of three shapes, generalized Newton law.
    "three_bodies": (
        'g = 9.81\n[track]\ntype = "circle"\nradius = 1.0\n'
        '[[bodies]]\nshape = "solid_sphere"\nradius = 0.1\nmass = 1.0\nphi = -1.3\ndphi = 0.2\n'
        '[[bodies]]\nshape = "disk"\nradius = 0.12\nmass = 2.0\nphi = 0.0\ndphi = 0.0\n'
        '[[bodies]]\nshape = "ring"\nradius = 0.09\nmass = 0.5\nphi = 1.2\ndphi = -0.3\n'
        '[collision]\nlaw = "newton_generalized"\nrestitution = 1.0\n[run]\nt_end = 100.0\n'
    ),
    # A ball that goes over the top and hits its neighbour from the other
    # side (the wrap-around pair), rolling law.
    "over_the_top": _two(
        'shape = "solid_sphere"\nradius = 0.1\nmass = 1.0\nphi = 0.0\ndphi = 8.0',
        'shape = "solid_sphere"\nradius = 0.1\nmass = 1.0\nphi = 1.5\ndphi = 0.0',
        "hedrih",
        "1.0",
    ),
}

N_COLLISIONS = 30

# Bounds on the relative error in t as (first n collisions, bound), for the
# default engine (high_accuracy off) and, where it differs, with high_accuracy
# on. The project target is 1e-15 over the first 30 collisions of a
# non-chaotic scene. Measured worst relative error over the first 30
# (high_accuracy off / on; collision map in extended precision, constants
# consistent with a_i + q a_j = 1 + k) and the spread of an ideal double
# computation (max over 3 seeds, see the conditioning test):
#   issue_disk_ring        8.1e-16 / 1.8e-15   spread 9.7e-16  (on: <= 1e-15 up to collision 3)
#   default_solid_spheres  1.4e-16 / 1.3e-16   spread 3.1e-16
#   particles_newton       2.6e-16 / 9.6e-17   (spread 3.5e-16 with 4 seeds)
#   hedrih_k07             2.0e-14 / 1.2e-14   spread 7.0e-14  (<= 1e-15 up to collision 19-20: then the
#                          inelastic pair chatters towards rest and closing speeds fall)
#   three_bodies           4.4e-16 / 1.8e-15   spread 8.6e-15  (on: <= 1e-15 up to collision 22)
#   over_the_top           3.5e-15 / 1.9e-15   spread 2.5e-15  (<= 1e-15 up to collision 11 / 14)
# For the last three, double rounding alone (the spread) costs as much: the
# 1e-15 target is out of reach of any double computation there. (Before the
# extended-precision map the issue's scene measured 1.9e-15 over 30.)
BOUNDS = {
    "issue_disk_ring": [(30, 1e-15)],
    "default_solid_spheres": [(30, 1e-15)],
    "particles_newton": [(30, 1e-15)],
    "hedrih_k07": [(20, 1e-15), (30, 2e-13)],
    "three_bodies": [(18, 1e-15), (30, 5e-14)],
    "over_the_top": [(11, 1e-15), (30, 5e-14)],
}
BOUNDS_HIGH_ACCURACY = {"issue_disk_ring": [(3, 1e-15), (30, 1e-14)], "hedrih_k07": [(19, 1e-15), (30, 2e-13)]}


def _scene(name):
    text = SCENES[name]
    return heyroll.default_scene() if text is None else heyroll.parse_scene(text)


@functools.lru_cache(maxsize=None)
def _reference(name, dps=40):
    return run_reference(_scene(name), N_COLLISIONS, dps=dps, t_end=100)


@functools.lru_cache(maxsize=None)
def _engine(name, high_accuracy):
    return heyroll.simulate(_scene(name), t_end=100.0, max_collisions=N_COLLISIONS, high_accuracy=high_accuracy)


def _t_errors(table, collisions):
    with mpmath.workdps(40):
        return np.array([float(abs(mpmath.mpf(float(x)) - c.t) / c.t) for x, c in zip(table["t"], collisions)])


def test_issue_example_scene_first_20_collisions():
    scene = heyroll.parse_scene(ISSUE_SCENE)
    result = heyroll.simulate(scene)  # run settings from the file: t_end 100, 20 collisions
    assert result.status is heyroll.Status.MAX_COLLISIONS
    table = result.collision_table()
    ref = reference_collisions(scene, 20)
    assert len(table) == len(ref) == 20
    cmp = compare_with_engine(table, ref)
    assert cmp["same_pair"].all()
    assert (table["i"] == 1).all() and (table["j"] == 2).all()
    # The issue asks 1e-13; measured 4.3e-16.
    assert cmp["t_rel"].max() <= 1e-13
    # Positions and rates: measured <= 3e-14 rad, rad/s (absolute, the rates are ~2 rad/s).
    for name in ("q_i", "q_j", "dq_i_before", "dq_j_before", "dq_i_after", "dq_j_after"):
        assert cmp[f"{name}_abs"].max() <= 1e-12, name
    # The contact geometry: phi_j - phi_i = beta (eq. 44) at every collision.
    beta = math.acos((1.18**2 + 1.18**2 - 0.24**2) / (2 * 1.18 * 1.18))
    assert np.allclose(table["q_j"] - table["q_i"], beta, rtol=0, atol=1e-14)


@pytest.mark.parametrize("high_accuracy", [False, True], ids=["no_ha", "ha"])
@pytest.mark.parametrize("name", list(SCENES))
def test_engine_collision_table_matches_reference(name, high_accuracy):
    ref = _reference(name)
    result = _engine(name, high_accuracy)
    table = result.collision_table()
    # Same collisions, same pairs, same ending.
    assert len(table) == len(ref.collisions), (result.status, ref.status)
    if ref.status == "max_collisions":
        assert result.status is heyroll.Status.MAX_COLLISIONS
    cmp = compare_with_engine(table, ref.collisions)
    assert cmp["same_pair"].all()
    rel = cmp["t_rel"]
    print(f"{name} high_accuracy={high_accuracy}: worst relative t error over {rel.size}: {rel.max():.2e}; "
          f"first index above 1e-15: {int(np.argmax(rel > 1e-15)) + 1 if (rel > 1e-15).any() else None}")
    bounds = BOUNDS_HIGH_ACCURACY.get(name, BOUNDS[name]) if high_accuracy else BOUNDS[name]
    for n, bound in bounds:
        assert rel[:n].max() <= bound, (n, bound, rel[:n].max())
    # Positions and rates at the collisions: an error in t moves them by
    # (rate) * dt and (acceleration) * dt, so they follow the time error.
    worst_dt = max(float(rel.max()) * float(ref.collisions[-1].t), 1e-15)
    for col in ("q_i", "q_j", "dq_i_before", "dq_j_before", "dq_i_after", "dq_j_after"):
        assert cmp[f"{col}_abs"].max() <= 100 * worst_dt + 1e-13, col


@pytest.mark.parametrize("name", ["issue_disk_ring", "default_solid_spheres", "three_bodies", "over_the_top", "hedrih_k07"])
def test_engine_error_is_at_the_scene_conditioning(name):
    """The engine is as accurate as an ideal double computation of the same scene.

    The ideal computation is modelled by the reference with double-rounded
    inputs and every post-collision position and rate multiplied by
    (1 + u N(0, 1)), u = 2^-53 (one rounding each). Its spread around the
    exact solution is what rounding alone costs on this scene; the engine
    must stay within a small factor of it (or below the 1e-15 target).
    """
    exact = _reference(name)
    n = len(exact.collisions)
    spread = np.zeros(n)
    for seed in range(3):
        noisy = run_reference(_scene(name), N_COLLISIONS, dps=25, t_end=100, double_inputs=True,
                              jitter=UNIT_ROUNDOFF, seed=seed)
        m = min(n, len(noisy.collisions))
        with mpmath.workdps(25):
            e = np.array([float(abs(a.t - b.t) / a.t) for a, b in zip(exact.collisions[:m], noisy.collisions[:m])])
        spread[:m] = np.maximum(spread[:m], e)
    engine = max(_t_errors(_engine(name, ha).collision_table(), exact.collisions).max() for ha in (False, True))
    print(f"{name}: engine worst {engine:.2e}, ideal-double spread {spread.max():.2e}")
    assert engine <= max(1e-15, 4 * spread.max())


# Every constant a binary fraction: g = 8, R = 1, particles (a = g/R = 8,
# beta = 0), Newton's law with masses 1 and 3 (impulse map 1.5 / 0.5), initial
# state in 1/8ths. No rounding separates the engine's problem from the exact
# one at any precision.
BINARY_SCENE = """
g = 8
[track]
type = "circle"
radius = 1.0
[[bodies]]
shape = "particle"
mass = 1.0
phi = -0.875
dphi = 0.375
[[bodies]]
shape = "particle"
mass = 3.0
phi = 0.75
dphi = 0.0
[collision]
law = "newton"
restitution = 1.0
"""


def test_multiprecision_engine_agrees_with_reference_to_45_digits():
    """heyoka at 180 bits and the Jacobi reference at 50 digits: two independent exact solutions.

    Measured 0 at 50 digits (6.5e-62 with 220 bits against 60 digits) over
    30 collisions: the reference's arcs, root finding and law are right to
    far beyond double precision.
    """
    scene = heyroll.parse_scene(BINARY_SCENE)
    ref = reference_collisions(scene, 30, dps=50, t_end=100)
    result = heyroll.simulate(scene, t_end=100.0, max_collisions=30, precision="mp:180")
    assert len(result.times) == len(ref) == 30
    with mpmath.workdps(50):
        worst = max(abs(mpmath.mpf(str(t)) - c.t) / c.t for t, c in zip(result.times, ref))
    assert worst < mpmath.mpf(10) ** -45


def test_multiprecision_engine_matches_reference_on_decimal_inputs():
    """mp:180 on the issue's decimal scene matches the reference to 1e-40.

    Every constant reaches the engine from the scene's decimal text at the run's
    precision (a regression test: inputs once went through a double).
    """
    scene = heyroll.parse_scene(ISSUE_SCENE)
    ref = reference_collisions(scene, 10, dps=50, t_end=100)
    result = heyroll.simulate(scene, t_end=100.0, max_collisions=10, precision="mp:180")
    with mpmath.workdps(50):
        worst = max(abs(mpmath.mpf(str(t)) - c.t) / c.t for t, c in zip(result.times, ref))
    assert worst < mpmath.mpf(10) ** -40


# ---------------------------------------------------------------------------
# The reference on its own
# ---------------------------------------------------------------------------


def test_reference_collisions_satisfy_geometry_and_law():
    """Every reference collision is a contact (gap 0, closing) and obeys eqs. (10)-(11)."""
    for name in ("issue_disk_ring", "three_bodies", "hedrih_k07", "over_the_top"):
        scene = _scene(name)
        ref = _reference(name)
        R, k = scene.track.radius, scene.law.restitution
        with mpmath.workdps(40):
            for c in ref.collisions[:10]:
                bi, bj = scene.bodies[c.i - 1], scene.bodies[c.j - 1]
                rho_i, rho_j = R - bi.radius, R - bj.radius
                beta = mpmath.acos((rho_i**2 + rho_j**2 - (bi.radius + bj.radius) ** 2) / (2 * rho_i * rho_j))
                offset = 2 * mpmath.pi if c.j < c.i else 0
                assert abs(c.q_j + offset - c.q_i - beta) < mpmath.mpf(10) ** -35
                assert c.dq_j_before - c.dq_i_before < 0  # closing
                assert c.dq_j_after - c.dq_i_after > 0  # opening
                if scene.law.name == "hedrih":
                    ci, cj = rho_i / bi.radius, rho_j / bj.radius
                    Mi, Mj = bi.kappa * bi.mass * bi.radius**2, bj.kappa * bj.mass * bj.radius**2
                else:  # newton_generalized
                    ci = cj = 1
                    Mi, Mj = bi.kappa * bi.mass * rho_i**2, bj.kappa * bj.mass * rho_j**2
                ui, uj = ci * c.dq_i_before, cj * c.dq_j_before
                ui_, uj_ = ci * c.dq_i_after, cj * c.dq_j_after
                assert abs((Mi * ui_ + Mj * uj_) - (Mi * ui + Mj * uj)) < mpmath.mpf(10) ** -35 * (abs(Mi * ui) + abs(Mj * uj))
                assert abs((uj_ - ui_) + k * (uj - ui)) < mpmath.mpf(10) ** -35 * abs(uj - ui)


def test_reference_misses_no_contact_between_collisions():
    """Brute force: every gap stays >= 0 on a dense grid between the reference's collisions."""
    scene = _scene("three_bodies")
    ref = run_reference(scene, 6, dps=20, t_end=100)
    R = scene.track.radius
    times = [mpmath.mpf(0)] + [c.t for c in ref.collisions]
    # Rebuild the pendulums arc by arc from the reference's own collision data.
    a = [scene.g / (b.kappa * (R - b.radius)) for b in scene.bodies]
    pend = [ExactPendulum(a[n], scene.phi[n], scene.dphi[n], 0, dps=20) for n in range(3)]
    betas = []
    for i, j in ((0, 1), (1, 2), (2, 0)):
        bi, bj = scene.bodies[i], scene.bodies[j]
        rho_i, rho_j = R - bi.radius, R - bj.radius
        betas.append(((i, j), mpmath.acos((rho_i**2 + rho_j**2 - (bi.radius + bj.radius) ** 2) / (2 * rho_i * rho_j))))
    with mpmath.workdps(20):
        for start, c in zip(times, ref.collisions):
            for s in range(1, 40):
                t = start + (c.t - start) * s / 40
                phis = [p.state(t)[0] for p in pend]
                for (i, j), beta in betas:
                    offset = 2 * mpmath.pi if j == 0 else 0
                    assert phis[j] + offset - phis[i] - beta > 0
            pend[c.i - 1] = ExactPendulum(a[c.i - 1], c.q_i, c.dq_i_after, c.t, dps=20)
            pend[c.j - 1] = ExactPendulum(a[c.j - 1], c.q_j, c.dq_j_after, c.t, dps=20)


def test_reference_keeps_mechanical_energy_for_an_energy_conserving_law():
    """newton_generalized at k = 1 conserves sum 1/2 kappa m rho^2 phi'^2 + m g rho (1 - cos phi)."""
    scene = _scene("three_bodies")
    ref = _reference("three_bodies")
    R, g = scene.track.radius, scene.g
    with mpmath.workdps(40):
        def energy(n, phi, dphi):
            b = scene.bodies[n]
            rho = R - b.radius
            return b.kappa * b.mass * rho**2 * dphi**2 / 2 + 2 * b.mass * g * rho * mpmath.sin(phi / 2) ** 2

        e0 = mpmath.fsum(energy(n, scene.phi[n], scene.dphi[n]) for n in range(3))
        for p in ref.pendulums:
            assert p.regime == LIBRATION
        t = ref.collisions[-1].t
        e1 = mpmath.fsum(energy(n, *ref.pendulums[n].state(t)) for n in range(3))
        assert abs(e1 - e0) < mpmath.mpf(10) ** -35 * e0


def test_reference_precision_is_converged():
    """40 digits against 60: the reference's collision times agree to far below double precision."""
    lo = _reference("issue_disk_ring")
    hi = run_reference(_scene("issue_disk_ring"), 10, dps=60, t_end=100)
    with mpmath.workdps(60):
        for a, b in zip(lo.collisions, hi.collisions):
            assert abs(a.t - b.t) < mpmath.mpf(10) ** -35 * b.t


def test_reference_statuses_match_the_engine():
    # Rolling law, unequal radii, k = 0.7: the law's outgoing rates can keep
    # closing the gap (u = c phi' with c_i != c_j); both stop there.
    text = _two(
        'shape = "solid_sphere"\nradius = 0.1\nmass = 1.0\nphi = -1.2\ndphi = 0.0',
        'shape = "solid_sphere"\nradius = 0.15\nmass = 3.0\nphi = 0.5\ndphi = 0.0',
        "hedrih",
        "0.7",
    )
    scene = heyroll.parse_scene(text.replace('restitution = 0.7', 'restitution = 0.7\non_inconsistent = "error"'))
    assert scene.on_inconsistent == "error"
    ref = run_reference(scene, 30, t_end=100)
    result = heyroll.simulate(scene, t_end=100.0, max_collisions=30)
    assert ref.status == "inconsistent"
    assert result.status.value == "inconsistent_collision"
    assert len(result.times) == len(ref.collisions)
    # One body alone: no pairs, no collisions.
    single = heyroll.parse_scene(
        'g = 9.81\n[track]\ntype = "circle"\nradius = 1.0\n[[bodies]]\nshape = "disk"\nradius = 0.1\nmass = 1.0\nphi = 1.0\ndphi = 0.0\n'
    )
    run = run_reference(single, 5, t_end=10)
    assert run.collisions == [] and run.status == "t_end"


def test_reference_table_has_engine_columns():
    ref = _reference("particles_newton").collisions[:5]
    table = reference_table(ref)
    engine = _engine("particles_newton", False).collision_table()
    assert table.dtype.names == tuple(n for n in table.dtype.names if n in engine.dtype.names)
    assert list(table["n"]) == [1, 2, 3, 4, 5]
    assert np.allclose(table["t"], engine["t"][:5], rtol=1e-15, atol=0)
    assert isinstance(ref[0], ReferenceCollision)
