"""One test per entry of papers/ERRATA.md: the printed form is wrong, the corrected form is right.

Each test evaluates the paper's expression as printed and the corrected one
on concrete numbers and checks them against an independent fact: the
hypothesis (8), the definition (9), the binomial product of (51)-(52),
mpmath's elliptic integral, a direct quadrature of (48), or a numerical
solution of the equation of motion (25) (mpmath.odefun).
"""

from __future__ import annotations

import random
from fractions import Fraction

import mpmath
import pytest

from heyroll.model._numbers import workprec
from heyroll.model.bodies import Body
from heyroll.model.laws import GeneralizedNewtonLaw, HedrihRollingLaw, impulse_map, outgoing
from heyroll.model.tracks import CircleTrack, mechanical_energy
from heyroll.reference.series import (
    CORRECTED_TERMS,
    PRINTED_TERMS,
    binomial_coefficient,
    block_coefficient,
    exact_time_integral,
    paper_series_as_printed,
    paper_series_corrected,
    series_terms,
    series_time_integral,
    time_between,
)

with workprec():
    G = mpmath.mpf("9.81")


# ----------------------------------------------------------------------------- helpers


def mp(x) -> mpmath.mpf:
    if isinstance(x, Fraction):
        return mpmath.mpf(x.numerator) / x.denominator
    return mpmath.mpf(x)


def rel_close(a, b, rel=mpmath.mpf(2) ** (-200)) -> bool:
    return abs(a - b) <= rel * max(abs(a), abs(b), 1)


def hedrih_out(J1, J2, w1, w2, k):
    """Eqs. (10)-(11), second forms (correct)."""
    du = w1 - w2
    return w1 - (1 + k) / (1 + J1 / J2) * du, w2 + (1 + k) / (1 + J2 / J1) * du


def random_collision(seed):
    rng = random.Random(seed)
    J1, J2 = mp(rng.uniform(0.1, 10)), mp(rng.uniform(0.1, 10))
    while abs(J1 - J2) < 0.5:
        J2 = mp(rng.uniform(0.1, 10))
    w1, w2 = mp(rng.uniform(-5, 5)), mp(rng.uniform(-5, 5))
    k = mp(rng.uniform(0.05, 0.95))
    return J1, J2, w1, w2, k


def momentum(J1, J2, w1, w2):
    return J1 * w1 + J2 * w2


def omega_sq(kappa, R, r):
    """omega^2 = 2 g / (kappa (R - r)), eq. (45)."""
    return 2 * G / (mp(kappa) * (mp(R) - mp(r)))


def omega0_sq(phi0, dphi0, w2):
    """omega_0^2 = phi_0'^2 + 2 omega^2 sin^2(phi_0/2): the symbol of (49)-(55), never defined."""
    return dphi0**2 + 2 * w2 * mpmath.sin(phi0 / 2) ** 2


def modulus_sq(phi0, dphi0, w2):
    """k^2 = 2 omega^2 / omega_0^2, eq. (46), first line (correct)."""
    return 2 * w2 / omega0_sq(phi0, dphi0, w2)


def modulus_sq_second_line(phi0, dphi0, w2):
    """Eq. (46), second line as printed: a stray sin^2(phi_0/2) in the numerator."""
    return 2 * w2 * mpmath.sin(phi0 / 2) ** 2 / omega0_sq(phi0, dphi0, w2)


def rate(phi, phi0, dphi0, w2):
    """phi' on the phase trajectory through (phi0, dphi0), eq. (29)/(40) with omega^2 of (45)."""
    return mpmath.sqrt(dphi0**2 + w2 * (mpmath.cos(phi) - mpmath.cos(phi0)))


def arc_time_quad(phi_a, phi_b, dphi_a, w2):
    """Eq. (48): t = integral dphi / phi'(phi), by quadrature (monotone arc)."""
    return mpmath.quad(lambda p: 1 / rate(p, phi_a, dphi_a, w2), [phi_a, phi_b])


def arc_time_elliptic(phi_a, phi_b, dphi_a, w2, k2=None, omega0=None):
    """Eq. (50): t = (2/omega_0)(F(asin u_b | k^2) - F(asin u_a | k^2)), u = sin(phi/2)."""
    k2 = modulus_sq(phi_a, dphi_a, w2) if k2 is None else k2
    omega0 = mpmath.sqrt(omega0_sq(phi_a, dphi_a, w2)) if omega0 is None else omega0
    return time_between(mpmath.sin(phi_a / 2), mpmath.sin(phi_b / 2), k2, omega0)


def pendulum(phi0, dphi0, w2):
    """Numerical solution of phi'' + (omega^2/2) sin phi = 0, eq. (25) with (45)."""
    return mpmath.odefun(lambda t, y: [y[1], -w2 / 2 * mpmath.sin(y[0])], 0, [phi0, dphi0])


# Two solid balls inside a circle, used by the section-4 tests (constants at model precision).
with workprec():
    R, R1, R2 = mp(1), mp("0.1"), mp("0.25")
    KAPPA = mp("1.4")
    W1SQ, W2SQ = omega_sq(KAPPA, R, R1), omega_sq(KAPPA, R, R2)


# ----------------------------------------------------------------------------- section 3.2 / 3.6 text


def test_sec32_elastic_opposite_speeds_claim():
    """Text after (5) (and its rolling analogue after (12)): k = 1, u1 = -u2 does NOT give
    equal-and-opposite outgoing velocities 'independent of the masses'; it does only for M1 = M2."""
    with workprec():
        u = mp(2)
        for M1, M2 in ((mp(1), mp(3)), (mp("0.7"), mp("5.2"))):
            o1, o2 = hedrih_out(M1, M2, u, -u, 1)  # same formula for Newton (eqs. 3-4)
            assert abs(o1 + o2) > mp("0.1")  # printed claim: o1 = -o2
        o1, o2 = hedrih_out(mp(4), mp(4), u, -u, 1)
        assert o1 == -u and o2 == u  # true for equal masses: the velocities are exchanged


def test_sec36_plastic_is_k0():
    """Text after (12): 'pure plastic collision ... k = 1' gives equal outgoing rates only at k = 0."""
    with workprec():
        for seed in range(10):
            J1, J2, w1, w2, _ = random_collision(seed)
            o1, o2 = hedrih_out(J1, J2, w1, w2, 1)  # printed: k = 1
            assert abs(o1 - o2) > mp("1e-6") * abs(w1 - w2)
            o1, o2 = hedrih_out(J1, J2, w1, w2, 0)  # correct: k = 0
            assert rel_close(o1, o2)


def test_eq2_9_relative_velocity_sign():
    """(2), (9), (9.a): k = v_r(t0+tau)/v_r(t0) with v_r = v2 - v1 after but v1 - v2 before. With one
    relative velocity v_r = u1 - u2 throughout, k = -v_r(t0+tau)/v_r(t0); the right-hand sides are right."""
    with workprec():
        for seed in range(10):
            J1, J2, w1, w2, k = random_collision(seed)
            o1, o2 = hedrih_out(J1, J2, w1, w2, k)
            assert rel_close((o2 - o1) / (w1 - w2), k)  # the printed right-hand side
            assert rel_close((o1 - o2) / (w1 - w2), -k)  # one v_r: the ratio is -k
            assert rel_close(-(o1 - o2) / (w1 - w2), k)


def test_table1_second_outgoing_row():
    """Table 1: u2+ = u2 + (1+k)/(1 + M1/M2)(u1 - u2) as printed breaks (1)/(8) and (2)/(9);
    (4)/(11)'s 1 + M2/M1 satisfies both."""
    with workprec():
        for seed in range(10):
            J1, J2, w1, w2, k = random_collision(seed)
            o1 = w1 - (1 + k) / (1 + J1 / J2) * (w1 - w2)
            printed = w2 + (1 + k) / (1 + J1 / J2) * (w1 - w2)
            correct = w2 + (1 + k) / (1 + J2 / J1) * (w1 - w2)
            before = momentum(J1, J2, w1, w2)
            assert not rel_close(momentum(J1, J2, o1, printed), before, mp("1e-6"))
            assert not rel_close((printed - o1) / (w1 - w2), k, mp("1e-6"))
            assert rel_close(momentum(J1, J2, o1, correct), before)
            assert rel_close((correct - o1) / (w1 - w2), k)


def test_table1_energy_change_sign():
    """Table 1: Delta E_k = E(t0+tau) - E(t0) is printed positive; (15)/(16) and the direct
    computation give -J1 J2/(2(J1+J2))(1-k^2)(w1-w2)^2 <= 0 (both columns, same formula)."""
    with workprec():
        for seed in range(10):
            J1, J2, w1, w2, k = random_collision(seed)
            o1, o2 = hedrih_out(J1, J2, w1, w2, k)
            dE = (J1 * o1**2 + J2 * o2**2 - J1 * w1**2 - J2 * w2**2) / 2
            printed = J1 * J2 / (2 * (J1 + J2)) * (1 - k**2) * (w1 - w2) ** 2
            assert dE < 0 < printed
            assert rel_close(dE, -printed)
            # translation column, plastic case as printed: + m1 m2/(2(m1+m2))(v1-v2)^2
            o1, o2 = hedrih_out(J1, J2, w1, w2, 0)
            dE0 = (J1 * o1**2 + J2 * o2**2 - J1 * w1**2 - J2 * w2**2) / 2
            assert rel_close(dE0, -J1 * J2 / (2 * (J1 + J2)) * (w1 - w2) ** 2)


def test_carnot_theorem_eq18_sec36():
    """(18) of 3.6 as printed, E(t0) - E(t0+tau) = 2 E_lost = sum J_P omega_P(tau)^2, is wrong;
    the generalized Carnot theorem is E(t0) - E(t0+tau) = (1-k)/(1+k) sum 1/2 J_P (Delta omega_P)^2."""
    with workprec():
        for seed in range(10):
            J1, J2, w1, w2, k = random_collision(seed)
            o1, o2 = hedrih_out(J1, J2, w1, w2, k)
            loss = (J1 * w1**2 + J2 * w2**2 - J1 * o1**2 - J2 * o2**2) / 2
            lost_energy = (J1 * (o1 - w1) ** 2 + J2 * (o2 - w2) ** 2) / 2  # E of the lost velocities
            assert rel_close(loss, (1 - k) / (1 + k) * lost_energy)
            printed = J1 * o1**2 + J2 * o2**2  # sum J_P [omega_P(tau)]^2
            assert not rel_close(loss, printed, mp("1e-6"))
            assert not rel_close(loss, 2 * lost_energy, mp("1e-6"))
            # k = 0: the loss is the kinetic energy of the lost velocities (Carnot), not twice it
            o1, o2 = hedrih_out(J1, J2, w1, w2, 0)
            loss0 = (J1 * w1**2 + J2 * w2**2 - J1 * o1**2 - J2 * o2**2) / 2
            assert rel_close(loss0, (J1 * (o1 - w1) ** 2 + J2 * (o2 - w2) ** 2) / 2)


# ----------------------------------------------------------------------------- section 3.6 examples


def test_examples_ball_mass_and_inertia():
    """Examples of 3.6: m = rho (4/8) r^3 pi should be rho (4/3) r^3 pi, so
    J_P = 7/5 m r^2 = (28/15) rho pi r^5, not (7/10) rho pi r^5."""
    with workprec():
        rho, r = mp(7800), mp("0.05")
        ball = Body.of_shape("solid_sphere", r, density=rho)
        vol = mpmath.quad(lambda s: 4 * mpmath.pi * s**2, [0, r])  # volume of the ball
        assert rel_close(ball.mass, rho * vol, mp("1e-40"))
        assert rel_close(ball.mass, rho * mp(4) / 3 * r**3 * mpmath.pi)
        assert not rel_close(ball.mass, rho * mp(4) / 8 * r**3 * mpmath.pi, mp("1e-3"))
        JP = ball.rolling_inertia()
        assert rel_close(JP, mp(28) / 15 * rho * mpmath.pi * r**5)
        assert not rel_close(JP, mp(7) / 10 * rho * mpmath.pi * r**5, mp("1e-3"))


def test_examples_inertia_ratio_power():
    """'J_P1/J_P2 = (r1/r2)(rho1/rho2) = lambda_2^5' should be (r1/r2)^5 (rho1/rho2) = lambda_2^-5 rho1/rho2."""
    with workprec():
        r1, r2, rho1, rho2 = mp("0.03"), mp("0.07"), mp(7800), mp(2700)
        b1 = Body.of_shape("solid_sphere", r1, density=rho1)
        b2 = Body.of_shape("solid_sphere", r2, density=rho2)
        ratio = b1.rolling_inertia() / b2.rolling_inertia()
        lam2 = r2 / r1
        assert rel_close(ratio, (r1 / r2) ** 5 * rho1 / rho2)
        assert rel_close(ratio, lam2 ** (-5) * rho1 / rho2)
        assert not rel_close(ratio, (r1 / r2) * (rho1 / rho2), mp("1e-3"))
        assert not rel_close(ratio, lam2**5, mp("1e-3"))


def test_examples_lambda_labels():
    """a*, b*, c*: the numbers 1/32, 1/243, 32/243 are J_P1/J_P2 = (r1/r2)^5, not lambda_2 = r2/r1
    (printed 'lambda_2 = (r2/r1)^3 = 1/2^5', 'lambda_2 = r2/r1 = 1/3^5', 'lambda_2 = r2/r1 = 2^5/3^5');
    the radius ratios are lambda_2 = 2, 3, 3/2."""
    for printed, lam2 in ((Fraction(1, 32), Fraction(2)), (Fraction(1, 243), Fraction(3)), (Fraction(32, 243), Fraction(3, 2))):
        assert lam2 ** (-5) == printed  # the inertia ratio for equal densities
        assert lam2 != printed and lam2**3 != printed and (1 / lam2) ** 3 != printed
        b1 = Body.of_shape("solid_sphere", Fraction(1, 8), density=1000)
        b2 = Body.of_shape("solid_sphere", Fraction(1, 8) * lam2, density=1000)
        with workprec():
            assert rel_close(b1.rolling_inertia() / b2.rolling_inertia(), mp(printed))


# ----------------------------------------------------------------------------- section 3.7


def common_rate(J1, J2, w1, w2):
    """omega_CP: the common rolling rate at the end of compression, from (8) with equal rates."""
    return (J1 * w1 + J2 * w2) / (J1 + J2)


def test_sec372_restitution_phase_text():
    """3.7.2 text: in restitution omega_P1 decreases by k(omega_P1(t0) - omega_CP), not by
    k(omega_CP - omega_P2(t0)) as printed; the printed reading breaks (8) unless J_P1 = J_P2."""
    with workprec():
        for seed in range(10):
            J1, J2, w1, w2, k = random_collision(seed)
            wc = common_rate(J1, J2, w1, w2)
            o2 = wc + k * (wc - w2)  # second body: compression gain + k times it
            o1_printed = wc - k * (wc - w2)
            o1_correct = wc - k * (w1 - wc)
            before = momentum(J1, J2, w1, w2)
            assert not rel_close(momentum(J1, J2, o1_printed, o2), before, mp("1e-6"))
            assert rel_close(momentum(J1, J2, o1_correct, o2), before)
            assert rel_close(o1_correct, hedrih_out(J1, J2, w1, w2, k)[0])


def test_eq18_sec37_common_velocity():
    """(18) of 3.7: omega_P1 - (1+k)(omega_P1 - omega_l) = (1+k) omega_CP - k omega_P1 holds only
    for omega_l = omega_CP; with omega_CP = (J1 w1 + J2 w2)/(J1 + J2) it is (10)."""
    with workprec():
        for seed in range(10):
            J1, J2, w1, w2, k = random_collision(seed)
            wc = common_rate(J1, J2, w1, w2)
            lhs = lambda x: w1 - (1 + k) * (w1 - x)  # noqa: E731
            rhs = (1 + k) * wc - k * w1
            assert rel_close(lhs(wc), rhs)
            assert not rel_close(lhs(wc + mp("0.1")), rhs, mp("1e-6"))
            assert rel_close(rhs, hedrih_out(J1, J2, w1, w2, k)[0])
            assert rel_close(wc, hedrih_out(J1, J2, w1, w2, 0)[0])  # = plastic outgoing rate


def test_eq19_time_label():
    """(19): omega_P2(t_2) must be omega_P2(t_0), the pre-collision rate: then (19) is (11)
    and (8) holds; any other value in that place breaks (8)."""
    with workprec():
        for seed in range(10):
            J1, J2, w1, w2, k = random_collision(seed)
            wc = common_rate(J1, J2, w1, w2)
            eq19 = lambda w2_at: w2_at + (1 + k) * (wc - w2)  # noqa: E731
            o1 = (1 + k) * wc - k * w1
            assert rel_close(eq19(w2), hedrih_out(J1, J2, w1, w2, k)[1])
            assert rel_close(eq19(w2), (1 + k) * wc - k * w2)
            assert rel_close(momentum(J1, J2, o1, eq19(w2)), momentum(J1, J2, w1, w2))
            assert not rel_close(momentum(J1, J2, o1, eq19(w2 + mp("0.3"))), momentum(J1, J2, w1, w2), mp("1e-6"))


def test_eq20_difference():
    """(20): (18) - (19) gives omega_P2+ - omega_P1+ = k(omega_P1 - omega_P2), not k(omega_P2 + omega_P1)."""
    with workprec():
        for seed in range(10):
            J1, J2, w1, w2, k = random_collision(seed)
            wc = common_rate(J1, J2, w1, w2)
            o1, o2 = (1 + k) * wc - k * w1, (1 + k) * wc - k * w2
            assert rel_close(o2 - o1, k * (w1 - w2))
            assert not rel_close(o2 - o1, k * (w2 + w1), mp("1e-6"))


def test_eq11a_leading_term():
    """(11.a) starts with omega_P1(t0); it must be omega_P2(t0) as in (11): the printed form
    violates (8) and (9a) whenever omega_P1 != omega_P2."""
    with workprec():
        for seed in range(10):
            J1, J2, w1, w2, k = random_collision(seed)
            o1 = hedrih_out(J1, J2, w1, w2, k)[0]
            printed = w1 + (1 + k) / (1 + J2 / J1) * (w1 - w2)
            correct = w2 + (1 + k) / (1 + J2 / J1) * (w1 - w2)
            before = momentum(J1, J2, w1, w2)
            assert not rel_close(momentum(J1, J2, o1, printed), before, mp("1e-6"))
            assert not rel_close((printed - o1) / (w1 - w2), k, mp("1e-6"))
            assert rel_close(momentum(J1, J2, o1, correct), before)
            assert rel_close((correct - o1) / (w1 - w2), k)


# ----------------------------------------------------------------------------- section 4.1


def test_eq44_lambda_definitions():
    """(44)'s 'where lambda_2 = r2/r1 and lambda_2 = r2/r1' must define lambda_1 = R/r1; with it the
    lambda form equals the law of cosines (and CircleTrack.contact_angle); with lambda_1 = lambda_2
    (the duplicate read literally) it does not."""
    rng = random.Random(44)
    with workprec():
        for _ in range(20):
            Rv = mp(1)
            r1, r2 = mp(rng.uniform(0.02, 0.45)), mp(rng.uniform(0.02, 0.45))
            law_of_cosines = ((Rv - r1) ** 2 + (Rv - r2) ** 2 - (r1 + r2) ** 2) / (2 * (Rv - r1) * (Rv - r2))
            lam_form = lambda l1, l2: (l1 * (l1 - l2 - 1) - l2) / ((l1 - l2) * (l1 - 1))  # noqa: E731
            lam1, lam2 = Rv / r1, r2 / r1
            assert rel_close(lam_form(lam1, lam2), law_of_cosines)
            track = CircleTrack.of_radius(Rv)
            b1, b2 = Body.of_shape("disk", r1, mass=1), Body.of_shape("disk", r2, mass=1)
            assert rel_close(track.contact_angle(b1, b2), mpmath.acos(lam_form(lam1, lam2)))
            if abs(lam2 - 1) > 0.05:
                literal = lam_form(lam2 * (1 + mp("1e-30")), lam2)  # lambda_1 = lambda_2 (0/0 otherwise)
                assert not rel_close(literal, law_of_cosines, mp("1e-3"))


def test_eq46_modulus():
    """(46), second line: the label must be k_1 (ball 1 quantities) and the numerator has a stray
    sin^2(phi_0/2); the first line's k^2 = 2 omega^2/(phi_0'^2 + 2 omega^2 sin^2(phi_0/2)) is the one
    that makes (50) equal the quadrature (48)."""
    with mpmath.workdps(30):
        phi0, dphi0, phi1 = mp("-0.4"), mp("2.5"), mp("0.6")
        truth = arc_time_quad(phi0, phi1, dphi0, W1SQ)
        good = arc_time_elliptic(phi0, phi1, dphi0, W1SQ)
        bad = arc_time_elliptic(phi0, phi1, dphi0, W1SQ, k2=modulus_sq_second_line(phi0, dphi0, W1SQ))
        assert abs(good - truth) < mp("1e-25")
        assert abs(bad - truth) > mp("1e-3")
        # ball 2's modulus in ball 1's equations (the label) is also wrong
        wrong_label = arc_time_elliptic(phi0, phi1, dphi0, W1SQ, k2=modulus_sq(phi0, dphi0, W2SQ))
        assert abs(wrong_label - truth) > mp("1e-3")


def test_eq47_missing_omega0_and_eq49_limits():
    """omega_{0,1} of (49)-(54) is never defined (an eq. 47 is missing): it must be
    omega_{0,1}^2 = phi_{1,0}'^2 + 2 omega_1^2 sin^2(phi_{1,0}/2). (49) integrates d(phi/2), so its
    limits are phi_{1,0}/2 .. phi_1/2, not phi_{1,0} .. phi_1. Checked against the motion itself."""
    with mpmath.workdps(25):
        phi0, dphi0 = mp("-0.5"), mp(2)
        motion = pendulum(phi0, dphi0, W1SQ)
        t = mp("0.3")
        phi_t = motion(t)[0]
        assert motion(t)[1] > 0  # monotone arc
        assert abs(arc_time_elliptic(phi0, phi_t, dphi0, W1SQ) - t) < mp("1e-18")
        om0 = mpmath.sqrt(omega0_sq(phi0, dphi0, W1SQ))
        k2 = modulus_sq(phi0, dphi0, W1SQ)
        integrand = lambda x: 1 / mpmath.sqrt(1 - k2 * mpmath.sin(x) ** 2)  # noqa: E731
        assert abs(2 / om0 * mpmath.quad(integrand, [phi0 / 2, phi_t / 2]) - t) < mp("1e-18")
        assert abs(2 / om0 * mpmath.quad(integrand, [phi0, phi_t]) - t) > mp("1e-2")
        # other readings of omega_{0,1}: omega_1 of (45), or phi_{1,0}'
        for guess in (mpmath.sqrt(W1SQ), dphi0):
            assert abs(2 / guess * mpmath.quad(integrand, [phi0 / 2, phi_t / 2]) - t) > mp("1e-3")


# ----------------------------------------------------------------------------- series (51)-(55)


def test_eq51_52_exponent():
    """(51)-(52) print (1 - x)^(+1/2) but the series shown (1 + x/2 + 3x^2/8 + 15x^3/48 ...) and the
    sum with binom(-1/2, n) are those of (1 - x)^(-1/2), which is what (50) needs."""
    with mpmath.workdps(30):
        shown = [Fraction(1), Fraction(1, 2), Fraction(1 * 3, 2 * 4), Fraction(1 * 3 * 5, 2 * 4 * 6)]
        minus_half = mpmath.taylor(lambda x: (1 - x) ** mp(-0.5), 0, 3)
        plus_half = mpmath.taylor(lambda x: (1 - x) ** mp(0.5), 0, 3)
        for c, a, b in zip(shown, minus_half, plus_half):
            assert abs(mp(c) - a) < mp("1e-25")
        assert any(abs(mp(c) - b) > mp("0.1") for c, b in zip(shown, plus_half))
        assert [binomial_coefficient(n) for n in range(4)] == shown


def binom(a: Fraction, n: int) -> Fraction:
    out = Fraction(1)
    for j in range(n):
        out *= (a - j) / Fraction(j + 1)
    return out


def double_factorial(n: int) -> int:
    return 1 if n <= 0 else n * double_factorial(n - 2)


def test_eq53_binomial_sign():
    """(53): '(-1) binom(-1/2, n) = (2n-1)!!/(2n)!!' needs (-1)^n (as in 51-52); likewise
    (-1)^n binom(1/2, n) = -(2n-3)!!/(2n)!! for n >= 1. With a plain (-1) the sign is wrong for even n."""
    half = Fraction(1, 2)
    for n in range(1, 9):
        assert (-1) ** n * binom(-half, n) == Fraction(double_factorial(2 * n - 1), double_factorial(2 * n))
        assert (-1) ** n * binom(half, n) == -Fraction(double_factorial(2 * n - 3), double_factorial(2 * n))
        if n % 2 == 0:
            assert -binom(-half, n) != Fraction(double_factorial(2 * n - 1), double_factorial(2 * n))


def test_eq54_first_group_coefficient():
    """(54) (and 55-57, 68-69, 78-79): first group's k^4 u^5 coefficient 1*3/(2*4*6) should be
    1*3/(2*4*5) = 3/40; every other printed coefficient equals c_m c_n/(2(m+n)+1)."""
    wrong = [(p, c) for p, c in zip(PRINTED_TERMS, CORRECTED_TERMS) if p != c]
    assert wrong == [((Fraction(1, 16), 2, 5), (Fraction(3, 40), 2, 5))]
    assert block_coefficient(2, 0) == Fraction(1 * 3, 2 * 4 * 5)
    # (78) as extracted also shows 2/(2^2*4*7) for 1*3/(2^2*4*7) and k_2^2 u^7 for k_2^4 u^7
    assert block_coefficient(2, 1) == Fraction(1 * 3, 2**2 * 4 * 7) != Fraction(2, 2**2 * 4 * 7)
    assert [m for c, m, p in CORRECTED_TERMS[3:6] if p == 7] == [2]  # k^(2m) = k^4 in group n = 1
    with mpmath.workdps(40):
        k2 = mp("0.7")
        for u in (mp("1e-3"), mp("1e-4")):
            exact = exact_time_integral(u, k2)
            # printed: error ~ k^4 u^5 / 80; corrected: error O(u^7)
            assert abs((exact - paper_series_as_printed(u, k2)) / u**5 - k2**2 / 80) < mp("1e-5")
            assert abs((exact - paper_series_corrected(u, k2)) / u**5) < mp("1e-5")


def test_eq54_truncation_order():
    """(54)/(55): the 3x3 block is complete only through u^5; u^7 and u^9 are partial (the u^7 terms
    (m,n) = (3,0), (0,3) are missing), so the error is 5/112 (1 + k^6) u^7 + ..., not O(u^11).
    A truncation by total degree (series_time_integral) has error O(u^(2N+3))."""
    with mpmath.workdps(100):
        k2 = mp("0.7")
        for u in (mp("1e-3"), mp("1e-4")):
            exact = exact_time_integral(u, k2)
            lead = (exact - paper_series_corrected(u, k2)) / u**7
            assert abs(lead - mp(5) / 112 * (1 + k2**3)) < mp("1e-4")
            for order in (2, 4, 6):
                err = abs(exact - series_time_integral(u, k2, order))
                assert err < u ** (2 * order + 3)
                assert err > u ** (2 * order + 3) / 100
        # the block contains u^7, u^9 terms but not all of them
        degrees = {}
        for c, m, p in CORRECTED_TERMS:
            degrees.setdefault(p, set()).add(m)
        assert degrees[7] == {1, 2} and degrees[9] == {2}
        assert {m for _, m, p in series_terms(4) if p == 7} == {0, 1, 2, 3}


def test_eq55_prefactor():
    """(55) (second ball) keeps 2/omega_{0,1}; it must be 2/omega_{0,2} of the second ball."""
    with mpmath.workdps(30):
        phi_a, dphi_a = mp("0.2"), mp("-1.5")  # ball 2 moving clockwise
        motion = pendulum(phi_a, dphi_a, W2SQ)
        t = mp("0.2")
        phi_t = motion(t)[0]
        u_a, u_t = mpmath.sin(phi_a / 2), mpmath.sin(phi_t / 2)
        k2 = modulus_sq(phi_a, dphi_a, W2SQ)
        om02 = mpmath.sqrt(omega0_sq(phi_a, dphi_a, W2SQ))
        om01 = mpmath.sqrt(omega0_sq(mp("-0.4"), mp("2.5"), W1SQ))  # some state of ball 1
        series = lambda om: time_between(u_a, u_t, k2, om, series_time_integral, order=30)  # noqa: E731
        # the ball moves clockwise here: t = -(2/omega_0)(I(u_t) - I(u_a))
        assert abs(-series(om02) - t) < mp("1e-18")
        assert abs(-series(om01) - t) > mp("1e-3")


def test_eq69_third_group_indices():
    """(69) (second ball, second interval): the third group has 2/omega_{0,1} and k_1 where
    omega_{0,2} and k_2 belong; with them the 3x3 form is as accurate as (54) is for ball 1."""
    with mpmath.workdps(30):
        phi_a, dphi_a = mp("0.05"), mp(5)  # ball 2 just after a collision
        motion = pendulum(phi_a, dphi_a, W2SQ)
        t = mp("0.05")
        phi_t = motion(t)[0]
        u_a, u_t = mpmath.sin(phi_a / 2), mpmath.sin(phi_t / 2)
        k2_2, om02 = modulus_sq(phi_a, dphi_a, W2SQ), mpmath.sqrt(omega0_sq(phi_a, dphi_a, W2SQ))
        k2_1, om01 = modulus_sq(mp("-0.6"), mp("1.1"), W1SQ), mpmath.sqrt(omega0_sq(mp("-0.6"), mp("1.1"), W1SQ))

        def groups(u, k2):
            g = [mpmath.mpf(0)] * 3
            for n in range(3):
                for c, m, p in CORRECTED_TERMS[3 * n : 3 * n + 3]:
                    g[n] += mp(c) * k2**m * u**p
            return g

        def eq69(third_k2, third_om):
            ga, gt = groups(u_a, k2_2), groups(u_t, k2_2)
            ha, ht = groups(u_a, third_k2), groups(u_t, third_k2)
            return 2 / om02 * ((gt[0] - ga[0]) + (gt[1] - ga[1])) + 2 / third_om * (ht[2] - ha[2])

        correct_err = abs(eq69(k2_2, om02) - t)
        printed_err = abs(eq69(k2_1, om01) - t)
        assert correct_err < mp("1e-6")
        assert printed_err > 10 * correct_err


# ----------------------------------------------------------------------------- section 4.2


def test_eq32_43_impact_vs_outgoing():
    """(32)/(43) write omega_P1,impact,2 = omega_P1,outgoing,1: false, gravity changes the rate
    between the collisions; only the right-hand side sqrt(...) of (32) is right."""
    with workprec():
        c1 = (R - R1) / R1
        phi_c, dphi_out = mp("0.3"), mp(3)  # first collision point, outgoing rate
        phi_next = mp("0.9")
        omega_out = c1 * dphi_out
        omega_next = c1 * rate(phi_next, phi_c, dphi_out, W1SQ)
        assert abs(omega_next - omega_out) > mp("0.1")
        # energy conservation between the collisions (eq. 26) confirms the sqrt form
        track, ball = CircleTrack.of_radius(R), Body.of_shape("solid_sphere", R1, mass=1)
        gm, wm = track.generalized_mass(ball), track.weight_moment(ball, G)
        E = mechanical_energy(gm, wm, phi_c, dphi_out, mpmath.sin)
        assert rel_close(mechanical_energy(gm, wm, phi_next, omega_next / c1, mpmath.sin), E)


def test_lambda2_rolling_ratio():
    """(59), (62), (63), (71), (81) and 4.2.3-4.2.5 use omega_P2 = (lambda_2 - 1) phi_2' with
    lambda_2 = r2/r1; eq. (34) gives omega_P2 = (R/r2 - 1) phi_2' = (lambda_1/lambda_2 - 1) phi_2'."""
    with workprec():
        track = CircleTrack.of_radius(R)
        b2 = Body.of_shape("solid_sphere", R2, mass=1)
        lam1, lam2 = R / R1, R2 / R1
        assert rel_close(track.rolling_ratio(b2), lam1 / lam2 - 1)
        assert rel_close(track.rolling_ratio(b2), R / R2 - 1)
        assert not rel_close(track.rolling_ratio(b2), lam2 - 1, mp("1e-3"))
        dphi2 = mp("0.8")
        vC2 = (R - R2) * dphi2  # eq. (34): v_C2 = (R - r2) phi_2' = r2 omega_P2
        assert rel_close(R2 * (lam1 / lam2 - 1) * dphi2, vC2)
        assert not rel_close(R2 * (lam2 - 1) * dphi2, vC2, mp("1e-3"))


def test_eq64_first_ball_branch():
    """(64) prints phi_2(t_impact,1) = phi_1,impact,1 + beta (the second ball's initial coordinate,
    repeated in the next bullet) where the first ball's branch belongs:
    phi_1' = sqrt(phi'_1,outgoing,1^2 + omega_1^2 (cos phi_1 - cos phi_1,impact,1)), cf. (65), (74)."""
    with workprec():
        track = CircleTrack.of_radius(R)
        b1 = Body.of_shape("solid_sphere", R1, mass=1)
        b2 = Body.of_shape("solid_sphere", R2, mass=1)
        beta = track.contact_angle(b1, b2)
        phi_c, dphi_out = mp("-0.2"), mp("1.7")
        printed_64 = phi_c + beta
        second_bullet = phi_c + beta
        assert printed_64 == second_bullet  # a duplicate; no phi_1' in it
        gm, wm = track.generalized_mass(b1), track.weight_moment(b1, G)
        E = mechanical_energy(gm, wm, phi_c, dphi_out, mpmath.sin)
        for phi in (mp("-0.1"), mp("0.3"), mp("0.6")):
            from_energy = mpmath.sqrt(2 * (E - 2 * wm * mpmath.sin(phi / 2) ** 2) / gm)
            assert rel_close(rate(phi, phi_c, dphi_out, W1SQ), from_energy)


def test_eq70_71_80_81_restart_rate():
    """(70), (71), (80), (81): the rate inside the square root must be the OUTGOING rate of the
    previous collision (phi'_1,outgoing,n), not the pre-collision phi'_1,impact,n printed there
    ((32), (43), (74), (75) have it right). Checked on a real collision with energy conservation."""
    with workprec():
        track = CircleTrack.of_radius(R)
        b1 = Body.of_shape("solid_sphere", R1, density=7800)
        b2 = Body.of_shape("solid_sphere", R2, density=7800)
        law = HedrihRollingLaw(restitution="0.8")
        c1, c2 = track.rolling_ratio(b1), track.rolling_ratio(b2)
        beta = track.contact_angle(b1, b2)
        phi_c, dphi1_in, dphi2_in = mp("-0.3"), mp("1.5"), mp("-0.4")
        w1o, w2o = outgoing(law, b1, b2, c1 * dphi1_in, c2 * dphi2_in, track.path_radius(b1), track.path_radius(b2))
        dphi1_out, dphi2_out = w1o / c1, w2o / c2
        gm1, wm1 = track.generalized_mass(b1), track.weight_moment(b1, G)
        gm2, wm2 = track.generalized_mass(b2), track.weight_moment(b2, G)
        E1 = mechanical_energy(gm1, wm1, phi_c, dphi1_out, mpmath.sin)
        E2 = mechanical_energy(gm2, wm2, phi_c + beta, dphi2_out, mpmath.sin)
        phi_next = mp("-0.4")
        for (E, gm, wm, c, phi, dout, din, w2) in (
            (E1, gm1, wm1, c1, phi_next, dphi1_out, dphi1_in, W1SQ),
            (E2, gm2, wm2, c2, phi_next + beta, dphi2_out, dphi2_in, W2SQ),
        ):
            phi0 = phi - phi_next + phi_c
            truth = c * mpmath.sqrt(2 * (E - 2 * wm * mpmath.sin(phi / 2) ** 2) / gm)
            assert rel_close(c * rate(phi, phi0, dout, w2), truth)
            assert not rel_close(c * rate(phi, phi0, din, w2), truth, mp("1e-3"))


def test_eq77_upper_limit():
    """(77): the second ball's integral runs to phi_1,u,(n+1) + beta, not phi_1,u,(n+1).
    A genuine collision is built with the equations of motion and both readings are checked."""
    with mpmath.workdps(25):
        beta = mp("0.45")
        phi1a, dphi1a = mp("-0.5"), mp(2)
        phi2a = phi1a + beta
        motion1 = pendulum(phi1a, dphi1a, W1SQ)
        T = mp("0.25")
        phi1b = motion1(T)[0]
        # choose ball 2's rate so that it is at phi1b + beta at time T (collision at T)
        dphi2a = mpmath.findroot(
            lambda d: arc_time_elliptic(phi2a, phi1b + beta, d, W2SQ) - T, (mp(2), mp(3)), solver="illinois"
        )
        motion2 = pendulum(phi2a, dphi2a, W2SQ)
        assert abs(motion2(T)[0] - motion1(T)[0] - beta) < mp("1e-15")  # they do touch at T
        correct = arc_time_quad(phi2a, phi1b + beta, dphi2a, W2SQ)
        printed = arc_time_quad(phi2a, phi1b, dphi2a, W2SQ)
        assert abs(correct - T) < mp("1e-15")
        assert abs(printed - T) > mp("0.1")


def test_eq83_index():
    """(83) uses omega_P2,impact,2 where omega_P2,impact,(n+1) belongs; mixing a different
    collision's rate breaks (8) at the (n+1)-th collision."""
    with workprec():
        for seed in range(10):
            J1, J2, w1, w2, k = random_collision(seed)  # rates at the (n+1)-th collision
            w2_second = w2 + mp("0.7")  # the rate at the second collision (another value)
            o1 = w1 - (1 + k) / (1 + J1 / J2) * (w1 - w2)  # (82)
            printed = w2_second + (1 + k) / (1 + J2 / J1) * (w1 - w2)
            correct = w2 + (1 + k) / (1 + J2 / J1) * (w1 - w2)
            before = momentum(J1, J2, w1, w2)
            assert rel_close(momentum(J1, J2, o1, correct), before)
            assert not rel_close(momentum(J1, J2, o1, printed), before, mp("1e-6"))


def test_sec426_energy_jump_claim():
    """4.2.6: 'the ball with the larger angular velocity ... jumps from the upper to the lower energy
    level, the other from lower to upper'. False in general: the faster ball can gain energy, and for
    k < 1 both can lose. (Per-ball energy changes by 1/2 J_P (omega+^2 - omega^2) at a fixed position.)"""
    with workprec():
        dE = lambda J, a, b: J * (b * b - a * a) / 2  # noqa: E731
        # the faster ball (by value and by magnitude) gains energy
        J1, J2, w1, w2 = mp("0.01"), mp(1), mp(1), mp("-0.9")
        o1, o2 = hedrih_out(J1, J2, w1, w2, 1)
        assert w1 > w2 and abs(w1) > abs(w2)
        assert dE(J1, w1, o1) > 0 and dE(J2, w2, o2) < 0
        # both lose (k = 0, head-on, equal inertias): no ball goes up
        o1, o2 = hedrih_out(mp(1), mp(1), mp(1), mp(-1), 0)
        assert dE(1, 1, o1) < 0 and dE(1, -1, o2) < 0


# ----------------------------------------------------------------------------- modelling remark


def test_remark_hedrih_may_not_separate():
    """Not a misprint, a property of the law: for unequal radii the rolling law (9) on omega_P does
    not make the bodies separate. On the circle the gap between i and j closes at phi_i' - phi_j'
    and omega_P = (R - r)/r phi' has a different factor for each body; after an elastic hedrih
    collision of a large ball on a small one the gap can keep closing. newton_generalized (Newton
    on phi') always gives phi_j'+ - phi_i'+ = k (phi_i' - phi_j') >= 0."""
    with workprec():
        track = CircleTrack.of_radius(1)
        big = Body.of_shape("solid_sphere", "0.3", density=7800)
        small = Body.of_shape("solid_sphere", "0.05", density=7800)
        p1, p2 = mp(1), mp(0)  # big ball (behind) hits the small one at rest
        for k in (0, 1):
            m = impulse_map(HedrihRollingLaw(restitution=k), big, small, track.path_radius(big), track.path_radius(small))
            D = p1 - m.q * p2
            p1o, p2o = p1 - m.a_i * D, p2 + m.a_j * D
            assert p2o - p1o < 0  # still approaching: the bodies would interpenetrate
            g = impulse_map(GeneralizedNewtonLaw(restitution=k), big, small, track.path_radius(big), track.path_radius(small))
            D = p1 - g.q * p2
            assert rel_close((p2 + g.a_j * D) - (p1 - g.a_i * D), k * (p1 - p2))
        # equal rolling rates, unequal radii: approaching in position, but no impulse at all
        c_big, c_small = track.rolling_ratio(big), track.rolling_ratio(small)
        w = mp(2)
        assert w / c_big - w / c_small > 0  # the gap closes
        o1, o2 = outgoing(HedrihRollingLaw(restitution=1), big, small, w, w, track.path_radius(big), track.path_radius(small))
        assert o1 == w and o2 == w
