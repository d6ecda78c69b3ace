"""One test per entry I1-I8 of papers/ERRATA.md (section 7, billiards): printed form wrong, corrected form right.

The frame of eqs. (104)-(113): x in the common tangent plane, y along the line
of centres, z vertical, (i, j, k) right-handed. By (104) ball 1 moves toward
-y and ball 2 toward +y, so ball 1 is on the +y side: C1 = T12 + R j,
C2 = T12 - R j, and the lever arms to the collision point are C1T1 = -R j,
C2T2 = +R j. The independent facts: the rolling condition (the contact with
the cloth at rest, v_C + omega_P x (-R k_up) = 0), the velocity of a point of
a rigid body (v_C + omega x CT), heyroll's law classes
(heyroll.model.table.laws) and engine runs of table scenes (heyroll.simulate).
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest

from heyroll.model.bodies import Body
from heyroll.model.scene import RunSettings
from heyroll.model.table import CircleBoundary, EllipseBoundary, TableBall, TableScene
from heyroll.model.table.laws import HedrihTableLaw, MirrorTableLaw
from heyroll.simulation.driver import simulate

R = 0.1
BALL = dict(radius="0.1", mass="0.17")
K_UP = np.array([0.0, 0.0, 1.0])
ALPHAS = [(30.0, 50.0), (10.0, 70.0), (45.0, 45.0), (60.0, 20.0)]


def body():
    return Body.of_shape("solid_sphere", BALL["radius"], mass=BALL["mass"])


def vec(x, y, z=0.0):
    return np.array([x, y, z], dtype=float)


def incoming(v1, v2, a1, a2):
    """Eq. (105): v_C1 = -v1 (i sin a1 + j cos a1), v_C2 = v2 (-i sin a2 + j cos a2) (a in radians)."""
    return vec(-v1 * math.sin(a1), -v1 * math.cos(a1)), vec(-v2 * math.sin(a2), v2 * math.cos(a2))


def rolling_omega(v, radius=R, up=K_UP):
    """omega_P of a ball rolling on the cloth: v_C + omega x (-R up) = 0, omega horizontal -> omega = up x v / R."""
    return np.cross(up, v) / radius


def contact_with_cloth(v, omega, radius=R, up=K_UP):
    return v + np.cross(omega, -radius * up)


def oblique_run(law, k, alphas, speeds, lead="0.6", after="0.5"):
    """Two equal rolling balls that touch at t = lead at the origin, ball 1 at (0, R), ball 2 at (0, -R), with the
    incoming velocities of eq. (105); returns (v1_before, v2_before, v1_after, v2_after, normal from 1 to 2)."""
    with mpmath.workdps(40):
        a1, a2 = (mpmath.radians(a) for a in alphas)
        s1, s2 = (mpmath.mpf(s) for s in speeds)
        t = mpmath.mpf(lead)
        r = mpmath.mpf(BALL["radius"])
        v1 = (-s1 * mpmath.sin(a1), -s1 * mpmath.cos(a1))
        v2 = (-s2 * mpmath.sin(a2), s2 * mpmath.cos(a2))
        balls = [TableBall.make(body(), -v1[0] * t, r - v1[1] * t, *v1),
                 TableBall.make(body(), -v2[0] * t, -r - v2[1] * t, *v2)]
    scene = TableScene.make(CircleBoundary(mpmath.mpf(5)), balls, law=law, restitution=k,
                            run=RunSettings.make(mpmath.mpf(lead) + mpmath.mpf(after)))
    table = simulate(scene).collision_table()
    assert len(table) == 1 and table["j"][0] == 2  # one ball-ball impact, no cushion
    row = table[0]
    n = np.array([row["x_j"] - row["x_i"], row["y_j"] - row["y_i"]])
    n /= np.hypot(*n)
    return (np.array([row["vx_i_before"], row["vy_i_before"]]), np.array([row["vx_j_before"], row["vy_j_before"]]),
            np.array([row["vx_i_after"], row["vy_i_after"]]), np.array([row["vx_j_after"], row["vy_j_after"]]), n)


# ----------------------------------------------------------------------------- I1: eq. (106)


@pytest.mark.parametrize("a1, a2", ALPHAS)
def test_I1_eq106_printed_rolling_axes_are_not_perpendicular_to_the_velocities(a1, a2):
    a1, a2 = math.radians(a1), math.radians(a2)
    v1, v2 = 1.0, 0.6
    vc1, vc2 = incoming(v1, v2, a1, a2)
    printed1 = v1 / R * vec(math.cos(a1), math.sin(a1))
    printed2 = v2 / R * vec(math.cos(a2), -math.sin(a2))
    # printed: omega . v = -(v^2/R) sin 2a, not 0, and the ball slips on the cloth
    assert printed1 @ vc1 == pytest.approx(-v1**2 / R * math.sin(2 * a1), rel=1e-12)
    assert printed2 @ vc2 == pytest.approx(-v2**2 / R * math.sin(2 * a2), rel=1e-12)
    if math.sin(2 * a1) != 0:
        assert np.linalg.norm(contact_with_cloth(vc1, printed1)) > 0.1 * v1
    # corrected (k up): omega_P1 = (v1/R)(i cos a1 - j sin a1), omega_P2 = -(v2/R)(i cos a2 + j sin a2)
    corr1 = v1 / R * vec(math.cos(a1), -math.sin(a1))
    corr2 = -v2 / R * vec(math.cos(a2), math.sin(a2))
    assert np.allclose(corr1, rolling_omega(vc1), atol=1e-14) and np.allclose(corr2, rolling_omega(vc2), atol=1e-14)
    assert np.abs(contact_with_cloth(vc1, corr1)).max() < 1e-14
    assert np.abs(contact_with_cloth(vc2, corr2)).max() < 1e-14
    # with k pointing down both corrected vectors change sign; the printed ones stay wrong (not perpendicular)
    assert np.allclose(-corr1, rolling_omega(vc1, up=-K_UP), atol=1e-14)
    # heyroll agrees: a ball given the corrected spin rolls (slip u = v - R omega x z = 0), the printed one slips
    with mpmath.workdps(30):
        ok = TableBall.make(body(), 0, 0, vc1[0], vc1[1], spin=(corr1[0], corr1[1]))
        bad = TableBall.make(body(), 0, 0, vc1[0], vc1[1], spin=(printed1[0], printed1[1]))
    assert abs(float(ok.ux)) < 1e-14 and abs(float(ok.uy)) < 1e-14
    assert math.hypot(float(bad.ux), float(bad.uy)) > 0.1 * v1
    # the printed directions are those of the OUTGOING rolling axes (perpendicular to n_out of eqs. 109, 113)
    n1_out, n2_out = vec(-math.sin(a1), math.cos(a1)), -vec(math.sin(a2), math.cos(a2))
    assert abs(printed1 @ n1_out) < 1e-12 and abs(printed2 @ n2_out) < 1e-12


# ----------------------------------------------------------------------------- I2: eq. (108)


@pytest.mark.parametrize("a1, a2", ALPHAS)
def test_I2_eq108_vertical_velocity_of_the_collision_point_has_cos_alpha(a1, a2):
    a1, a2 = math.radians(a1), math.radians(a2)
    v1, v2 = 1.0, 0.6
    vc1, vc2 = incoming(v1, v2, a1, a2)
    w1, w2 = rolling_omega(vc1), rolling_omega(vc2)
    vt1 = vc1 + np.cross(w1, -R * vec(0, 1))  # T1 = C1 - R j
    vt2 = vc2 + np.cross(w2, R * vec(0, 1))  # T2 = C2 + R j
    # horizontal part = v_C (eq. 107 is right)
    assert np.allclose(vt1[:2], vc1[:2], atol=1e-15) and np.allclose(vt2[:2], vc2[:2], atol=1e-15)
    # vertical part: printed -R omega_P k = -v_C k; correct -R omega_P cos(a) k = -v_C cos(a) k
    assert vt1[2] == pytest.approx(-v1 * math.cos(a1), abs=1e-15)
    assert vt2[2] == pytest.approx(-v2 * math.cos(a2), abs=1e-15)
    assert abs(vt1[2] - (-v1)) > 0.01 * v1 and abs(vt2[2] - (-v2)) > 0.01 * v2  # the printed (108)
    # it is the normal part of v_C (what the collision law acts on), and (112) has the same cos for the outgoing
    assert vt1[2] == pytest.approx(vc1[1], abs=1e-15) and vt2[2] == pytest.approx(-vc2[1], abs=1e-15)


# ----------------------------------------------------------------------------- I3: eqs. (109)-(110)


def rolling_sum(vs, bodies):
    """sum J_P omega_P = sum kappa m R^2 (z x v / R) (horizontal vector)."""
    return sum(float(b.kappa * b.mass * b.radius) * np.array([-v[1], v[0]]) for v, b in zip(vs, bodies))


def test_I3_eq109_110_each_ball_keeping_its_speed_breaks_eq8_and_momentum():
    b = (body(), body())
    alphas, speeds = (30.0, 50.0), ("1.0", "0.6")
    v1, v2, m1, m2, n = oblique_run("mirror", "1", alphas, speeds)
    # the engine's mirror law is (109)-(110): each ball keeps its speed, its normal part reversed
    a1, a2 = math.radians(30), math.radians(50)
    assert np.allclose(m1, [-math.sin(a1), math.cos(a1)], atol=1e-14)
    assert np.allclose(m2, -0.6 * np.array([math.sin(a2), math.cos(a2)]), atol=1e-14)
    j0, j1 = rolling_sum((v1, v2), b), rolling_sum((m1, m2), b)
    p0, p1 = v1 + v2, m1 + m2  # equal masses
    # the change predicted: -2 (J1 u1 + J2 u2)/R along z x n, u the normal parts
    u1, u2 = v1 @ n, v2 @ n
    jp = float(b[0].kappa * b[0].mass * b[0].radius)
    assert np.allclose(j1 - j0, -2 * jp * (u1 + u2) * np.array([-n[1], n[0]]), atol=1e-14)
    assert np.hypot(*(j1 - j0)) / np.hypot(*j0) > 0.5 and np.hypot(*(p1 - p0)) / np.hypot(*p0) > 0.5
    # the vector form of (8)-(11) keeps both (equal balls)
    h1, h2 = oblique_run("hedrih", "1", alphas, speeds)[2:4]
    assert np.hypot(*(rolling_sum((h1, h2), b) - j0)) < 1e-15 * np.hypot(*j0) * 4
    assert np.allclose(h1 + h2, p0, atol=1e-15)
    # k = 1, equal balls: the normal parts are exchanged, the tangential ones kept
    t = np.array([-n[1], n[0]])
    assert h1 @ n == pytest.approx(u2, abs=1e-15) and h2 @ n == pytest.approx(u1, abs=1e-15)
    assert h1 @ t == pytest.approx(v1 @ t, abs=1e-15) and h2 @ t == pytest.approx(v2 @ t, abs=1e-15)
    # the plainest case: a ball rolling head-on into a ball at rest. (109)-(110) send it back as from a wall and
    # leave the other at rest (momentum 2 m v lost); (8)-(11) hand its velocity on to the ball at rest
    for law, expected in (("mirror", (-1.0, 0.0)), ("hedrih", (0.0, 1.0))):
        balls = [TableBall.make(body(), "-0.5", "0", "1", "0"), TableBall.make(body(), "0.2", "0", "0", "0")]
        result = simulate(TableScene.make(CircleBoundary(mpmath.mpf(5)), balls, law=law, run=RunSettings.make(1)))
        assert (result.state_final[2], result.state_final[8]) == pytest.approx(expected, abs=1e-15)
        assert result.energy_final == pytest.approx(result.energy_initial, rel=1e-15)


@pytest.mark.parametrize("k", ["1", "0.6"])
def test_I3_the_laws_on_the_normal_parts_and_the_one_case_mirror_is_right(k):
    b1 = Body.of_shape("solid_sphere", "0.1", mass="0.17")
    b2 = Body.of_shape("solid_sphere", "0.15", mass="0.4")
    hed = HedrihTableLaw(restitution=k)
    mir = MirrorTableLaw(restitution=k)
    c_h, c_m = hed.constants(b1, b2, float), mir.constants(b1, b2, float)
    J1, J2 = (float(b.kappa * b.mass * b.radius**2) for b in (b1, b2))
    for vn1, vn2 in ((1.0, -0.4), (0.7, 0.2), (0.3, -1.1)):
        h = hed.normal_rates(c_h, vn1, vn2)
        m = mir.normal_rates(c_m, vn1, vn2)
        before = J1 * vn1 / 0.1 + J2 * vn2 / 0.15  # eq. (8) on omega_n = v_n / R
        assert J1 * h[0] / 0.1 + J2 * h[1] / 0.15 == pytest.approx(before, rel=1e-14)
        assert h[1] / 0.15 - h[0] / 0.1 == pytest.approx(float(k) * (vn1 / 0.1 - vn2 / 0.15), rel=1e-13)  # (9)
        assert abs(J1 * m[0] / 0.1 + J2 * m[1] / 0.15 - before) > 0.1 * abs(before)
    # (109)-(110) agree with (8) only when J1 omega_1n = -J2 omega_2n (for equal balls: v1 cos a1 = v2 cos a2)
    vn1 = 0.5
    vn2 = -J1 * vn1 / 0.1 / J2 * 0.15
    m = mir.normal_rates(c_m, vn1, vn2)
    assert J1 * m[0] / 0.1 + J2 * m[1] / 0.15 == pytest.approx(0, abs=1e-15)


# ----------------------------------------------------------------------------- I4: eq. (111) against (108), (112)


@pytest.mark.parametrize("a1, a2", ALPHAS)
def test_I4_eq111_outgoing_axes_have_the_sign_of_k_down_while_108_112_need_k_up(a1, a2):
    a1, a2 = math.radians(a1), math.radians(a2)
    v1, v2 = 1.0, 0.6
    out1, out2 = v1 * vec(-math.sin(a1), math.cos(a1)), -v2 * vec(math.sin(a2), math.cos(a2))  # (109)
    printed1 = v1 / R * vec(math.cos(a1), math.sin(a1))  # (111)
    printed2 = v2 / R * vec(-math.cos(a2), math.sin(a2))
    # perpendicular to the outgoing velocities, but rolling with k up needs the opposite sign ...
    assert np.allclose(printed1, -rolling_omega(out1), atol=1e-13)
    assert np.allclose(printed2, -rolling_omega(out2), atol=1e-13)
    assert np.allclose(printed1, rolling_omega(out1, up=-K_UP), atol=1e-13)  # ... it is right only with k down
    # and then the vertical velocity of T1 (lever arm -R j) has the sign opposite to (112)'s + R omega cos a1 k
    vt1 = np.cross(printed1, -R * vec(0, 1))
    assert vt1[2] == pytest.approx(-v1 * math.cos(a1), abs=1e-14)
    # corrected (k up, as in 108 and 112): omega_P1,out = -(v1/R)(i cos a1 + j sin a1), omega_P2,out = (v2/R)(i cos a2
    # - j sin a2): the contact with the cloth at rest and (112) with its + sign
    c1, c2 = -v1 / R * vec(math.cos(a1), math.sin(a1)), v2 / R * vec(math.cos(a2), -math.sin(a2))
    assert np.abs(contact_with_cloth(out1, c1)).max() < 1e-14 and np.abs(contact_with_cloth(out2, c2)).max() < 1e-14
    assert np.cross(c1, -R * vec(0, 1))[2] == pytest.approx(R * np.linalg.norm(c1) * math.cos(a1), abs=1e-14)
    assert np.cross(c2, R * vec(0, 1))[2] == pytest.approx(R * np.linalg.norm(c2) * math.cos(a2), abs=1e-14)
    # and (108) with k up: the incoming vertical velocity -v cos a k (I2) has the sign (108) prints
    assert np.cross(rolling_omega(incoming(v1, v2, a1, a2)[0]), -R * vec(0, 1))[2] < 0


# ----------------------------------------------------------------------------- I5: eq. (113)


def test_I5_eq113_second_outgoing_direction_is_the_incoming_one():
    a1, a2 = 30.0, 50.0
    r2 = math.radians(a2)
    n2_in = np.array([-math.sin(r2), math.cos(r2)])  # (104)
    printed = np.array([-math.sin(r2), math.cos(r2)])  # (113)
    assert np.array_equal(printed, n2_in)
    # ball 1 is on the +y side: with the printed direction ball 2 keeps approaching it (the gap would close)
    assert printed @ np.array([0.0, 1.0]) > 0
    # the mirror run (eqs. 109-110) leaves along -(i sin a2 + j cos a2)
    out2 = oblique_run("mirror", "1", (a1, a2), ("1.0", "0.6"))[3]
    assert np.allclose(out2 / np.hypot(*out2), -np.array([math.sin(r2), math.cos(r2)]), atol=1e-14)


# ----------------------------------------------------------------------------- I6: the Conclusion-Theorem


def angle_to_normal(v, n):
    return math.degrees(math.atan2(abs(v[0] * n[1] - v[1] * n[0]), abs(v @ n)))


def test_I6_conclusion_theorem_holds_for_the_mirror_only():
    alpha = 35.0
    ta = math.tan(math.radians(alpha))
    # mirror: equal incoming angles -> outgoing at the same angles, whatever the speeds
    *_, m1, m2, n = oblique_run("mirror", "1", (alpha, alpha), ("1.0", "0.6"))
    assert angle_to_normal(m1, n) == pytest.approx(alpha, abs=1e-10)
    assert angle_to_normal(m2, n) == pytest.approx(alpha, abs=1e-10)
    # hedrih (equal balls, k = 1): the normal parts are exchanged, tan b1 = (v1/v2) tan a, tan b2 = (v2/v1) tan a
    *_, h1, h2, n = oblique_run("hedrih", "1", (alpha, alpha), ("1.0", "0.6"))
    b1, b2 = angle_to_normal(h1, n), angle_to_normal(h2, n)
    assert b1 == pytest.approx(math.degrees(math.atan(ta / 0.6)), abs=1e-10)
    assert b2 == pytest.approx(math.degrees(math.atan(0.6 * ta)), abs=1e-10)
    assert abs(b1 - b2) > 20 and abs(b1 - alpha) > 10
    # equal speeds, k < 1: the two outgoing angles agree with each other but not with the incoming one
    *_, h1, h2, n = oblique_run("hedrih", "0.8", (alpha, alpha), ("0.8", "0.8"))
    b1, b2 = angle_to_normal(h1, n), angle_to_normal(h2, n)
    assert b1 == pytest.approx(b2, abs=1e-10)
    assert b1 == pytest.approx(math.degrees(math.atan(ta / 0.8)), abs=1e-10)


# ----------------------------------------------------------------------------- I7: the theorem of 7.2.2


def first_contact(c1, v1, c2, v2, reach):
    """The smaller root t >= 0 of |dc + dv t| = reach, or None (mpmath)."""
    with mpmath.workdps(40):
        dc = [mpmath.mpf(c2[i]) - mpmath.mpf(c1[i]) for i in (0, 1)]
        dv = [mpmath.mpf(v2[i]) - mpmath.mpf(v1[i]) for i in (0, 1)]
        a = dv[0] ** 2 + dv[1] ** 2
        b = 2 * (dc[0] * dv[0] + dc[1] * dv[1])
        c = dc[0] ** 2 + dc[1] ** 2 - mpmath.mpf(reach) ** 2
        if a == 0 or b >= 0 or b * b - 4 * a * c < 0:
            return None
        return (-b - mpmath.sqrt(b * b - 4 * a * c)) / (2 * a)


def past_crossing(c1, v1, c2, v2, t):
    """Signed distances of both centres past the crossing of their tracks at time t (< 0: not reached)."""
    cross = v1[0] * v2[1] - v1[1] * v2[0]
    dx, dy = c2[0] - c1[0], c2[1] - c1[1]
    p = (dx * v2[1] - dy * v2[0]) / cross  # c1 + v1 p = c2 + v2 q
    q = (dx * v1[1] - dy * v1[0]) / cross
    return (t - p) * math.hypot(*v1), (t - q) * math.hypot(*v2)


TEN = math.radians(10)
CASES = {  # ball 1 (x, y, vx, vy), ball 2, what the theorem says
    "both before the crossing": ((-1.0, 0.0, 1.0, 0.0), (0.0, -1.0, 0.0, 1.0), "impossible"),
    "parallel tracks 0.15 m apart": ((-1.0, 0.0, 1.0, 0.0), (0.0, 0.15, 0.2, 0.0), "impossible"),
    "both past the crossing": ((1.0, 0.0, 0.1, 0.0), (0.05 * math.cos(TEN), 0.05 * math.sin(TEN), 2 * math.cos(TEN),
                                                       2 * math.sin(TEN)), "impossible"),
    "one before, one past: no collision": ((-1.0, 0.0, 1.0, 0.0), (0.0, 0.1, 0.0, 1.0), "possible"),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_I7_sec722_feasibility_theorem_is_no_criterion(name):
    s1, s2, paper = CASES[name]
    scene = TableScene.make(CircleBoundary(mpmath.mpf(20)),
                            [TableBall.make(body(), *s1), TableBall.make(body(), *s2)], law="hedrih",
                            run=RunSettings.make(4, 1))
    e1, e2 = ([float(getattr(b, a)) for a in ("x", "y", "vx", "vy")] for b in scene.balls)
    t_star = first_contact(e1[:2], e1[2:], e2[:2], e2[2:], 2 * R)
    table = simulate(scene).collision_table()
    pairs = table[table["j"] > 0]
    if paper == "impossible":  # the theorem's condition fails, yet they collide, at the quadratic's smaller root
        assert t_star is not None and len(pairs) == 1
        assert abs(pairs["t"][0] - float(t_star)) <= 1e-14 * float(t_star)
        if e1[2] * e2[3] - e1[3] * e2[2] != 0:
            a, b = past_crossing(e1[:2], e1[2:], e2[:2], e2[2:], float(t_star))
            assert (a < 0) == (b < 0)  # NOT one before and one past
    else:  # one before and one past (the theorem's configuration), yet they never meet
        a, b = past_crossing(e1[:2], e1[2:], e2[:2], e2[2:], 0.0)
        assert (a < 0) != (b < 0)
        assert t_star is None and len(pairs) == 0


# ----------------------------------------------------------------------------- I8: Poncelet and the centre's curve


def test_I8_the_curve_of_the_centre_is_not_a_conic_and_the_path_has_no_confocal_caustic():
    a, b, r = mpmath.mpf(2), mpmath.mpf(1), mpmath.mpf("0.2")
    with mpmath.workdps(40):
        def centre(th):  # P(th) - R n(th)
            nx, ny = b * mpmath.cos(th), a * mpmath.sin(th)
            norm = mpmath.hypot(nx, ny)
            return a * mpmath.cos(th) - r * nx / norm, b * mpmath.sin(th) - r * ny / norm

        pts = [centre(mpmath.mpf(t) / 10) for t in (1, 5, 9, 14, 20)]
        # the conic x^2 + c1 xy + c2 y^2 + c3 x + c4 y + c5 = 0 through five points of the curve
        m = mpmath.matrix([[x * y, y * y, x, y, 1] for x, y in pts])
        c = mpmath.lu_solve(m, mpmath.matrix([-x * x for x, _ in pts]))
        off = []
        for t in (3, 7, 25, 30, 40):
            x, y = centre(mpmath.mpf(t) / 10)
            q = x * x + c[0] * x * y + c[1] * y * y + c[2] * x + c[3] * y + c[4]
            g = mpmath.hypot(2 * x + c[0] * y + c[2], c[0] * x + 2 * c[1] * y + c[3])
            off.append(abs(q / g))  # distance of the curve's point from that conic (first order)
        assert max(off) > mpmath.mpf("0.01") and min(off) > mpmath.mpf(10) ** -4
    # the engine: the confocal caustic integral of the shrunk ellipse (a - R, b - R) drifts; a particle's does not
    for radius, shape, law, drift in (("0.2", "solid_sphere", "hedrih", True), ("0", "particle", "newton", False)):
        ball = TableBall.make(Body.of_shape(shape, radius, mass="0.17"), "0.3", "-0.2", "1.0", "0.7")
        scene = TableScene.make(EllipseBoundary(a, b), [ball], law=law, run=RunSettings.make(1000, 60))
        t = simulate(scene).collision_table()
        x, y, vx, vy = t["x_i"], t["y_i"], t["vx_i_after"], t["vy_i_after"]
        s = np.hypot(vx, vy)
        dx, dy = vx / s, vy / s
        aa, bb = 2 - float(radius), 1 - float(radius)
        caustic = aa * aa * dy * dy + bb * bb * dx * dx - (x * dy - y * dx) ** 2
        spread = np.ptp(caustic) / np.mean(caustic)
        assert (spread > 1e-2) if drift else (spread < 1e-13)


def test_every_section7_entry_of_the_errata_names_a_test_here():
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "papers" / "ERRATA.md").read_text()
    section = text[text.index("## I. Section 7"):]
    rows = [line for line in section.splitlines() if line.startswith("| I")]
    assert [row.split("|")[1].strip() for row in rows] == [f"I{m}" for m in range(1, 9)]
    for row in rows:
        for name in row.split("|")[-2].replace("`", "").split(","):
            assert callable(globals().get(name.strip())), name
