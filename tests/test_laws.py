"""The paper's stated properties of the collision laws, on random inputs (sections 3.2, 3.6-3.7).

Every law in heyroll is of Newton type in its own variables u = c phi' with
inertias M (HedrihRollingLaw: u = omega_P, M = J_P, eqs. 8-12; NewtonCentreLaw:
u = v_C, M = m, eqs. 1-5; GeneralizedNewtonLaw: u = phi', M = kappa m (R-r)^2),
so the statements of the paper hold for each in its own variables. All
arithmetic is 256-bit mpmath; "exact" means to 2^-230 relative.
"""

from __future__ import annotations

import math
import random
from fractions import Fraction

import mpmath
import pytest

import heyroll
from heyroll.model._numbers import workprec
from heyroll.model.bodies import Body
from heyroll.model.laws import (
    GeneralizedNewtonLaw,
    HedrihRollingLaw,
    NewtonCentreLaw,
    collision_impulse,
    impulse_map,
    kinetic_energy_change,
    make_law,
    outgoing,
)
from heyroll.model.tracks import CircleTrack

LAW_NAMES = ("hedrih", "newton", "newton_generalized")
SHAPES = ("solid_sphere", "hollow_sphere", "disk", "ring")
CASES = 40
REL = mpmath.mpf(2) ** (-230)


def close(a, b, scale=None) -> bool:
    with workprec():
        s = max(abs(a), abs(b), 1) if scale is None else max(abs(scale), 1)
        return abs(a - b) <= REL * s


def random_case(rng: random.Random, *, k=None, equal_radii=False):
    """A track, two rolling bodies, a restitution k and incoming law velocities."""
    track = CircleTrack.of_radius(1)
    r1 = Fraction(rng.randint(5, 400), 1000)
    r2 = r1 if equal_radii else Fraction(rng.randint(5, 400), 1000)
    b1 = Body.of_shape(rng.choice(SHAPES), r1, mass=Fraction(rng.randint(1, 10**6), 1000))
    b2 = Body.of_shape(rng.choice(SHAPES), r2, mass=Fraction(rng.randint(1, 10**6), 1000))
    if k is None:
        k = Fraction(rng.randint(0, 1000), 1000)
    u1 = Fraction(rng.randint(-10**6, 10**6), 10**5)
    u2 = Fraction(rng.randint(-10**6, 10**6), 10**5)
    return track, b1, b2, k, mpmath.mpf(u1.numerator) / u1.denominator, mpmath.mpf(u2.numerator) / u2.denominator


def cases(seed, **kw):
    rng = random.Random(seed)
    return [random_case(rng, **kw) for _ in range(CASES)]


def inertias(law, track, b1, b2):
    return law.variables(b1, track.path_radius(b1)).inertia, law.variables(b2, track.path_radius(b2)).inertia


@pytest.mark.parametrize("name", LAW_NAMES)
def test_plastic_k0_gives_equal_outgoing_velocities(name):
    """k = 0 (pure plastic, text after eq. 5 and after eq. 12): u1+ = u2+."""
    with workprec():
        for track, b1, b2, _k, u1, u2 in cases(1, k=0):
            law = make_law(name, 0)
            o1, o2 = outgoing(law, b1, b2, u1, u2, track.path_radius(b1), track.path_radius(b2))
            assert close(o1, o2, scale=abs(u1) + abs(u2))


@pytest.mark.parametrize("name", LAW_NAMES)
def test_elastic_k1_conserves_kinetic_energy(name):
    """k = 1: sum 1/2 M u^2 unchanged (eq. 17; for hedrih 1/2 J_P omega_P^2, eqs. 13-14)."""
    with workprec():
        for track, b1, b2, _k, u1, u2 in cases(2, k=1):
            law = make_law(name, 1)
            M1, M2 = inertias(law, track, b1, b2)
            o1, o2 = outgoing(law, b1, b2, u1, u2, track.path_radius(b1), track.path_radius(b2))
            assert close(M1 * u1**2 + M2 * u2**2, M1 * o1**2 + M2 * o2**2)


@pytest.mark.parametrize("name", LAW_NAMES)
def test_zero_total_momentum_gives_minus_k_times_incoming(name):
    """M1 u1 + M2 u2 = 0 gives u_i+ = -k u_i (text before eq. 13; before Fig. 3 for Newton)."""
    with workprec():
        for track, b1, b2, k, u1, _u2 in cases(3):
            law = make_law(name, k)
            M1, M2 = inertias(law, track, b1, b2)
            u2 = -M1 * u1 / M2
            o1, o2 = outgoing(law, b1, b2, u1, u2, track.path_radius(b1), track.path_radius(b2))
            assert close(o1, -law.restitution * u1, scale=u1)
            assert close(o2, -law.restitution * u2, scale=u2)
            assert close(-o2 / o1, M1 / M2)  # J_P1/J_P2 = -omega_P2+/omega_P1+


@pytest.mark.parametrize("name", LAW_NAMES)
def test_sum_of_momenta_conserved_for_every_k(name):
    """Eq. (8) (hedrih: sum J_P omega_P) and eq. (1) (Newton: sum m v), any k in [0, 1]."""
    with workprec():
        for track, b1, b2, k, u1, u2 in cases(4):
            law = make_law(name, k)
            M1, M2 = inertias(law, track, b1, b2)
            o1, o2 = outgoing(law, b1, b2, u1, u2, track.path_radius(b1), track.path_radius(b2))
            assert close(M1 * u1 + M2 * u2, M1 * o1 + M2 * o2, scale=M1 * abs(u1) + M2 * abs(u2))


@pytest.mark.parametrize("name", LAW_NAMES)
def test_restitution_definition_holds(name):
    """Eq. (9) (and 2): k = (u2+ - u1+)/(u1 - u2)."""
    with workprec():
        for track, b1, b2, k, u1, u2 in cases(5):
            law = make_law(name, k)
            o1, o2 = outgoing(law, b1, b2, u1, u2, track.path_radius(b1), track.path_radius(b2))
            assert close((o2 - o1) / (u1 - u2), law.restitution)


@pytest.mark.parametrize("name", LAW_NAMES)
def test_impulse_eq12_equals_momentum_change(name):
    """Eq. (12) (and 5): J_P1 (w1+ - w1) = -J1 J2/(J1+J2) (1+k)(w1 - w2) = -J_P2 (w2+ - w2)."""
    with workprec():
        for track, b1, b2, k, u1, u2 in cases(6):
            law = make_law(name, k)
            M1, M2 = inertias(law, track, b1, b2)
            o1, o2 = outgoing(law, b1, b2, u1, u2, track.path_radius(b1), track.path_radius(b2))
            L = collision_impulse(M1, M2, law.restitution, u1 - u2)
            scale = M1 * abs(u1) + M2 * abs(u2)
            assert close(L, M1 * (o1 - u1), scale=scale)
            assert close(L, -M2 * (o2 - u2), scale=scale)


@pytest.mark.parametrize("name", LAW_NAMES)
def test_energy_change_eq15_equals_after_minus_before(name):
    """Eq. (15): E_k(t0 + tau) - E_k(t0) = -J1 J2/(2(J1+J2)) (1-k^2)(w1 - w2)^2 <= 0."""
    with workprec():
        for track, b1, b2, k, u1, u2 in cases(7):
            law = make_law(name, k)
            M1, M2 = inertias(law, track, b1, b2)
            o1, o2 = outgoing(law, b1, b2, u1, u2, track.path_radius(b1), track.path_radius(b2))
            before = (M1 * u1**2 + M2 * u2**2) / 2
            after = (M1 * o1**2 + M2 * o2**2) / 2
            dE = kinetic_energy_change(M1, M2, law.restitution, u1 - u2)
            assert close(dE, after - before, scale=before)
            assert dE <= 0


@pytest.mark.parametrize("name", LAW_NAMES)
def test_impulse_map_agrees_with_outgoing(name):
    """The engine form (D = phi_i' - q phi_j') gives the paper's outgoing velocities (10)-(11)."""
    with workprec():
        for track, b1, b2, k, u1, u2 in cases(8):
            law = make_law(name, k)
            c1, c2 = law.variables(b1, track.path_radius(b1)).scale, law.variables(b2, track.path_radius(b2)).scale
            p1, p2 = u1 / c1, u2 / c2  # track rates phi'
            m = impulse_map(law, b1, b2, track.path_radius(b1), track.path_radius(b2))
            D = p1 - m.q * p2
            p1o, p2o = p1 - m.a_i * D, p2 + m.a_j * D
            o1, o2 = outgoing(law, b1, b2, u1, u2, track.path_radius(b1), track.path_radius(b2))
            scale = abs(u1) + abs(u2)
            assert close(c1 * p1o, o1, scale=scale)
            assert close(c2 * p2o, o2, scale=scale)


def test_hedrih_equals_generalized_newton_for_equal_radii():
    """For equal radii the rolling law coincides with newton_generalized.

    omega_P = c phi' with the same c = (R - r)/r for both bodies, and the
    generalized mass kappa m (R - r)^2 = J_P c^2 has the same factor c^2:
    both laws have the same inertia ratio and the same velocity ratio, so
    they give the same outgoing phi' (the same impulse map), for any shapes,
    masses and k. For unequal radii they differ.
    """
    with workprec():
        for track, b1, b2, k, _u1, _u2 in cases(9, equal_radii=True):
            h = impulse_map(HedrihRollingLaw(restitution=k), b1, b2, track.path_radius(b1), track.path_radius(b2))
            g = impulse_map(GeneralizedNewtonLaw(restitution=k), b1, b2, track.path_radius(b1), track.path_radius(b2))
            assert close(h.q, g.q) and close(h.a_i, g.a_i) and close(h.a_j, g.a_j)
        track = CircleTrack.of_radius(1)
        b1 = Body.of_shape("solid_sphere", "0.1", mass=1)
        b2 = Body.of_shape("solid_sphere", "0.2", mass=1)
        h = impulse_map(HedrihRollingLaw(restitution=1), b1, b2, track.path_radius(b1), track.path_radius(b2))
        g = impulse_map(GeneralizedNewtonLaw(restitution=1), b1, b2, track.path_radius(b1), track.path_radius(b2))
        assert not close(h.a_i, g.a_i)


@pytest.mark.parametrize("bad", [-0.1, 1.5, 2, "-1e-30", math.nan, math.inf, -math.inf])
@pytest.mark.parametrize("cls", [HedrihRollingLaw, NewtonCentreLaw, GeneralizedNewtonLaw])
def test_restitution_outside_unit_interval_raises(cls, bad):
    """k must lie in [0, 1] (text after eqs. 5 and 12)."""
    with pytest.raises(heyroll.SceneError) as info:
        cls(restitution=bad)
    assert isinstance(info.value, ValueError)
    with pytest.raises(ValueError):
        make_law(cls.name, bad)


@pytest.mark.parametrize("k", [0, 1, "0.5", Fraction(1, 3)])
def test_restitution_bounds_accepted(k):
    """The ends k = 0 and k = 1 and exact inputs are accepted, kept at model precision."""
    with workprec():
        expected = mpmath.mpf(k.numerator) / k.denominator if isinstance(k, Fraction) else mpmath.mpf(k)
        assert HedrihRollingLaw(restitution=k).restitution == expected


def test_hedrih_with_particle_raises_scene_error():
    """omega_P = (R - r)/r phi' is undefined for r = 0: the rolling law refuses a particle."""
    track = CircleTrack.of_radius(1)
    particle = Body.of_shape("particle", 0, mass=1)
    ball = Body.of_shape("solid_sphere", "0.1", mass=1)
    law = HedrihRollingLaw(restitution="0.5")
    with pytest.raises(heyroll.SceneError):
        law.variables(particle, track.path_radius(particle))
    with pytest.raises(heyroll.SceneError):
        impulse_map(law, ball, particle, track.path_radius(ball), track.path_radius(particle))
    with pytest.raises(ValueError):
        impulse_map(law, particle, ball, track.path_radius(particle), track.path_radius(ball))
    # the Newton laws accept it
    impulse_map(NewtonCentreLaw(restitution="0.5"), ball, particle, track.path_radius(ball), track.path_radius(particle))
    impulse_map(GeneralizedNewtonLaw(restitution="0.5"), ball, particle, track.path_radius(ball), track.path_radius(particle))
