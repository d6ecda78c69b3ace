"""The Coulomb-friction reference (heyroll.reference.rough): closed forms checked
against each other, against mpmath.odefun of the equations of motion and against
energy accounts. mpmath only; the whole file runs in a few seconds."""

from __future__ import annotations

import dataclasses

import mpmath
import pytest

from heyroll.reference import rough
from heyroll.reference.rough import (
    NoTurningPoint,
    circle_branch_end,
    circle_branch_rate2,
    circle_branch_time,
    circle_energy,
    circle_friction_work,
    circle_sliding_sequence,
    circle_turning_point,
    incline_roll_from_rest,
    incline_slip_then_roll,
    incline_sliding,
    incline_stopping_distance,
    incline_stopping_time,
    sliding_on_curve,
)

G = "9.81"


@pytest.fixture(autouse=True)
def _test_precision():
    """The tests' own arithmetic (expected values) at 45 digits; the reference sets its own."""
    with mpmath.workdps(45):
        yield


def mp(x):
    return mpmath.mpf(x)


def close(a, b, tol):
    """|a - b| <= tol * max(1, |b|) (relative above 1, absolute below)."""
    return abs(a - b) <= mpmath.mpf(tol) * max(1, abs(b))


def ode_root(fun, a, b):
    """Root of fun in [a, b] (a sign change), by findroot's bracketing solver."""
    return mpmath.findroot(fun, (mp(a), mp(b)), solver="anderson")


# --------------------------------------------------------------------------- 1. incline


def test_incline_stop_and_restart_against_odefun():
    alpha, mu, mu_s, x0, dx0 = mp("0.5"), mp("0.2"), mp("0.3"), mp("0.1"), mp(2)
    run = incline_sliding(alpha, mu, mu_s, x0, dx0, G, 2)
    assert run.mode0 == "sliding+" and run.mode == "sliding-"
    assert [(tr.mode_from, tr.mode_to) for tr in run.transitions] == [("sliding+", "sliding-")]
    tr = run.transitions[0]
    assert tr.t == run.t_stop and tr.x == run.x_stop and tr.dx == 0
    with mpmath.workdps(30):
        g, ca, sa = mp(G), mpmath.cos(alpha), mpmath.sin(alpha)
        up = mpmath.odefun(lambda t, y: [y[1], -g * sa * ca - mu * g * ca**2], 0, [x0, dx0])
        t_stop = ode_root(lambda t: up(t)[1], "0.1", "1")
        assert close(t_stop, run.t_stop, "1e-25")
        assert close(up(t_stop)[0], run.x_stop, "1e-25")
        # closed forms of the stop, along the slope: v0 = dx0 / cos(alpha)
        v0 = dx0 / ca
        assert close((run.x_stop - x0) / ca, incline_stopping_distance(alpha, mu, v0, G), "1e-30")
        assert close(run.t_stop, incline_stopping_time(alpha, mu, v0, G), "1e-30")
        # restart from rest downhill (tan 0.5 = 0.546 > mu_s): the state at t_end
        down = mpmath.odefun(lambda t, y: [y[1], -g * sa * ca + mu * g * ca**2], 0, [run.x_stop, mp(0)])
        x_end, dx_end = down(2 - run.t_stop)
        assert close(x_end, run.x, "1e-25") and close(dx_end, run.dx, "1e-25")
        assert run.dx < 0


@pytest.mark.parametrize("alpha, mu, mu_s, sticks", [
    ("0.5", "0.2", "0.3", False),       # tan a = 0.546 > mu_s
    ("0.5", "0.2", "0.6", True),        # tan a <= mu_s
    ("0.2", "0.2", "0.2", False),       # tan 0.2 = 0.2027 > mu_s = 0.2: just outside
    ("0.19", "0.1", "0.2", True),       # tan 0.19 = 0.1923 <= mu_s = 0.2: just inside
    ("0", "0.2", "0.2", True),          # flat
])
def test_incline_sticking_rule(alpha, mu, mu_s, sticks):
    expected = abs(mpmath.tan(mp(alpha))) <= mp(mu_s)
    run = incline_sliding(alpha, mu, mu_s, 0, 1, G, 5)
    assert expected == sticks
    assert (run.mode == "stuck") == sticks and run.transitions[0].mode_to == run.mode
    # a start from rest obeys the same criterion
    rest = incline_sliding(alpha, mu, mu_s, 0, 0, G, 1)
    assert rest.mode0 == ("stuck" if expected else "sliding-")
    if expected:
        assert rest.x == 0 and rest.dx == 0 and rest.transitions == ()
    else:
        assert rest.dx < 0 and rest.transitions == ()


def test_incline_flat_and_frictionless():
    # flat, mu > 0: stops after dx0^2 / (2 mu g) and sticks
    run = incline_sliding(0, "0.25", "0.3", 1, 3, G, 10)
    assert close(run.x_stop, 1 + mp(9) / (2 * mp("0.25") * mp(G)), "1e-35")
    assert run.mode == "stuck" and run.x == run.x_stop
    # flat, mu = 0: uniform motion
    run = incline_sliding(0, 0, 0, 1, -3, G, 2)
    assert run.transitions == () and run.x == -5 and run.dx == -3 and run.mode == "sliding-"


def test_incline_downhill_cases_and_mirror():
    # downhill with mu > tan(alpha): decelerates, stops, sticks
    run = incline_sliding("0.2", "0.5", "0.5", 0, -1, G, 5)
    assert run.transitions[0].mode_from == "sliding-" and run.mode == "stuck"
    a = mp("0.2")
    dec = mp(G) * (mp("0.5") * mpmath.cos(a) - mpmath.sin(a))
    assert close(run.t_stop, (1 / mpmath.cos(a)) / dec, "1e-35")
    # downhill with mu < tan(alpha): accelerates for ever, no transition
    run = incline_sliding("0.5", "0.1", "0.2", 0, -1, G, 2)
    assert run.transitions == () and run.dx < -1
    # the mirror image y = -tan(a) x with x -> -x gives the same motion
    a1 = incline_sliding("0.5", "0.2", "0.3", "0.1", 2, G, 2)
    a2 = incline_sliding("-0.5", "0.2", "0.3", "-0.1", -2, G, 2)
    assert a2.mode0 == "sliding-" and a2.transitions[0].mode_to == "sliding+"
    assert close(a1.t_stop, a2.t_stop, "1e-38") and close(a1.x, -a2.x, "1e-38") and close(a1.dx, -a2.dx, "1e-38")
    # never stops when sin a + mu cos a <= 0
    assert incline_stopping_distance("-0.5", "0.1", 1, G) == mpmath.inf


# --------------------------------------------------------------------------- 2. circle


@pytest.mark.parametrize("phi0, dphi0", [("0.2", "3.5"), ("0.4", "-2.5"), ("-0.1", "-5")])
def test_circle_closed_form_solves_the_ode(phi0, dphi0):
    """y(phi) = phi'^2 satisfies dy/dphi + 2 s mu y = -(2g/R)(sin phi + s mu cos phi)."""
    mu, R = mp("0.3"), mp("0.8")
    s = 1 if mp(dphi0) > 0 else -1
    with mpmath.workdps(50):
        g = mp(G)
        y = lambda p: circle_branch_rate2(p, phi0, dphi0, mu, R, G, dps=110)  # noqa: E731
        assert close(y(mp(phi0)), mp(dphi0) ** 2, "1e-45")
        for dp in ("0.05", "0.2"):
            p = mp(phi0) + s * mp(dp)
            lhs = mpmath.diff(y, p)
            rhs = -2 * s * mu * y(p) - 2 * g / R * (mpmath.sin(p) + s * mu * mpmath.cos(p))
            assert abs(lhs - rhs) < mpmath.mpf(10) ** -40


@pytest.mark.parametrize("phi0, dphi0, mu", [(0, 4, "0.1"), ("0.5", "-3", "0.3")])
def test_circle_closed_form_against_odefun(phi0, dphi0, mu):
    R, mu = mp(1), mp(mu)
    t_turn = circle_branch_time(phi0, None, dphi0, mu, R, G)
    phi_t = circle_turning_point(phi0, dphi0, mu, R, G)
    s = 1 if mp(dphi0) > 0 else -1
    with mpmath.workdps(20):
        g = mp(G)
        sol = mpmath.odefun(
            lambda t, y: [y[1], (-g * mpmath.sin(y[0]) - s * mu * (R * y[1] ** 2 + g * mpmath.cos(y[0]))) / R],
            0, [mp(phi0), mp(dphi0)])
        for t in ("0.1", "0.2", "0.3"):
            phi, dphi = sol(mp(t))
            assert close(dphi**2, circle_branch_rate2(phi, phi0, dphi0, mu, R, G, dps=25), "1e-16")
            # the time along the branch to where odefun is at t
            assert close(circle_branch_time(phi0, phi, dphi0, mu, R, G, dps=25), mp(t), "1e-16")
        t_ode = ode_root(lambda t: sol(t)[1], t_turn - mp("0.05"), t_turn + mp("0.05"))
        assert close(t_ode, t_turn, "1e-16")
        assert close(sol(t_ode)[0], phi_t, "1e-16")


def test_circle_energy_account_per_branch():
    R, mu, m = mp("1.5"), mp("0.15"), mp(2)
    cases = [  # (phi0, dphi0, sgn, phi1): full branches to the turning point and partial ones
        (0, 4, None, None), ("0.3", "-2", None, None), ("0.9", 0, -1, None),
        ("-1.2", 0, 1, None), (0, 4, None, "0.6"), ("0.9", 0, -1, "0.1"),
    ]
    for phi0, dphi0, sgn, phi1 in cases:
        if phi1 is None:
            phi1 = circle_turning_point(phi0, dphi0, mu, R, G, sgn=sgn)
            dphi1 = 0
        else:
            y1 = circle_branch_rate2(phi1, phi0, dphi0, mu, R, G, sgn=sgn)
            dphi1 = mpmath.sqrt(y1)
        W = circle_friction_work(phi0, phi1, dphi0, mu, R, G, sgn=sgn, m=m)
        dE = circle_energy(phi1, dphi1, R, G, m=m) - circle_energy(phi0, dphi0, R, G, m=m)
        assert W < 0
        assert abs(dE - W) <= mpmath.mpf(10) ** -25 * abs(W)
        assert abs(dE - W) <= mpmath.mpf(10) ** -30


def test_circle_frictionless_limit():
    R, phi0, dphi0 = mp("1.2"), mp("0.3"), mp(3)
    with mpmath.workdps(40):
        g = mp(G)
        # turning point at the energy level: cos phi_t = cos phi0 - R phi0'^2 / (2 g)
        phi_t = circle_turning_point(phi0, dphi0, 0, R, G)
        assert close(mpmath.cos(phi_t), mpmath.cos(phi0) - R * dphi0**2 / (2 * g), "1e-35")
        assert circle_friction_work(phi0, None, dphi0, 0, R, G) == 0
        for phi in (mp("0.5"), mp("0.9")):
            E = circle_energy(phi, mpmath.sqrt(circle_branch_rate2(phi, phi0, dphi0, 0, R, G)), R, G)
            assert close(E, circle_energy(phi0, dphi0, R, G), "1e-35")
        # time bottom -> turning point = quarter period of the pendulum: K(k^2) sqrt(R/g), k = sin(phi_t/2)
        dphi_bottom = mpmath.sqrt(circle_branch_rate2(0, phi0, dphi0, 0, R, G, sgn=1))
        quarter = circle_branch_time(0, None, dphi_bottom, 0, R, G)
        assert close(quarter, mpmath.ellipk(mpmath.sin(phi_t / 2) ** 2) * mpmath.sqrt(R / g), "1e-35")
        # leaving the track: N = R y + g cos phi = 0 with y = y0 + (2g/R)(cos phi - cos phi0)
        dphi_fast = mp(5)
        end = circle_branch_end(0, dphi_fast, 0, R, G)
        assert end.kind == "leaves_track"
        assert close(mpmath.cos(end.phi), (2 * g - R * dphi_fast**2) / (3 * g), "1e-35")
        # over the top iff N >= 0 there: R phi0'^2 >= 5 g from the bottom
        over = circle_branch_end(0, mpmath.sqrt(5 * g / R) * mp("1.001"), 0, R, G)
        assert over.kind == "over_the_top" and close(over.phi, mpmath.pi, "1e-38")


def test_circle_no_turning_point_with_friction():
    R, mu = mp(1), mp("0.2")
    with pytest.raises(NoTurningPoint) as info:
        circle_turning_point(0, 6, mu, R, G)
    assert info.value.kind == "leaves_track"
    phi = info.value.phi
    with mpmath.workdps(40):
        y = circle_branch_rate2(phi, 0, 6, mu, R, G)
        assert mpmath.cos(phi) < 0 and y > 0  # on the upper half, still moving
        assert abs(R * y + mp(G) * mpmath.cos(phi)) < mpmath.mpf(10) ** -35  # N = 0
    # a faster particle passes the top; friction makes it need more than sqrt(5 g / R)
    assert circle_branch_end(0, mpmath.sqrt(5 * mp(G)) * mp("1.05"), mu, R, G).kind == "leaves_track"
    assert circle_branch_end(0, 12, mu, R, G).kind == "over_the_top"
    with pytest.raises(NoTurningPoint) as info:
        circle_turning_point(0, 12, mu, R, G)
    assert info.value.kind == "over_the_top"


def test_circle_sliding_sequence_until_stuck():
    mu, mu_s, R = mp("0.1"), mp("0.15"), mp(1)
    run = circle_sliding_sequence(0, 4, mu, mu_s, R, G, 50)
    assert run.status == "stuck" and run.mode == "stuck" and run.mode0 == "sliding+"
    trs, brs = run.transitions, run.branches
    assert len(trs) == len(brs) >= 3
    band = mpmath.atan(mu_s)
    for k, tr in enumerate(trs):
        inside = abs(tr.phi) <= band
        assert inside == (k == len(trs) - 1)  # only the last turning point is in the sticking band
        if not inside:
            assert tr.mode_to == ("sliding-" if tr.phi > 0 else "sliding+")
    # times add up, energies decrease by the friction work of each branch
    t = mp(0)
    for tr, br in zip(trs, brs):
        t += br.duration
        assert close(tr.t, t, "1e-38") and br.end_kind == "turning_point"
        assert abs(br.energy_end - br.energy_start - br.friction_work) < mpmath.mpf(10) ** -30
        assert br.energy_end < br.energy_start
    # each restart is a branch from rest: its time agrees with circle_branch_time (sgn given)
    br = brs[1]
    assert br.dphi_start == 0
    assert close(circle_branch_time(br.phi_start, None, 0, mu, R, G, sgn=br.sgn), br.duration, "1e-38")
    # max_branches stops early
    short = circle_sliding_sequence(0, 4, mu, mu_s, R, G, 2)
    assert short.status == "max_branches" and len(short.transitions) == 2
    assert short.transitions[1] == trs[1]


def test_circle_sticking_band_from_rest_and_descending_stop():
    mu, mu_s = mp("0.2"), mp("0.3")
    band = mpmath.atan(mu_s)
    inside = circle_sliding_sequence(band * mp("0.99"), 0, mu, mu_s, 1, G)
    assert inside.status == "stuck" and inside.branches == () and inside.mode0 == "stuck"
    outside = circle_sliding_sequence(-band * mp("1.01"), 0, mu, mu_s, 1, G)
    assert outside.mode0 == "sliding+" and outside.status == "stuck"
    # a particle moving towards the bottom slowly inside |tan phi| < mu stops before it: sticks there
    run = circle_sliding_sequence("0.15", "-0.3", "0.5", "0.5", 1, G)
    assert len(run.transitions) == 1 and run.transitions[0].mode_to == "stuck"
    assert 0 < run.phi < mp("0.15") and abs(mpmath.tan(run.phi)) < mp("0.5")


# --------------------------------------------------------------------------- 3. rolling body that slips


def test_roll_from_rest_rule_and_growing_slip():
    kappa, mu, mu_s = mp(7) / 5, mp("0.1"), mp("0.15")
    with mpmath.workdps(40):
        g = mp(G)
        limit = mpmath.atan(mu_s * kappa / (kappa - 1))  # (1 - 1/kappa) tan a = mu_s
        below = incline_roll_from_rest(limit * mp("0.999"), mu, mu_s, kappa, G)
        assert below.mode == "rolling" and below.dw == 0
        assert close(below.dv, -g * mpmath.sin(limit * mp("0.999")) / kappa, "1e-35")
        assert below.friction_needed <= below.friction_available
        a = limit * mp("1.001")
        above = incline_roll_from_rest(a, mu, mu_s, kappa, G)
        assert above.mode == "sliding-" and above.friction_needed > above.friction_available
        assert close(above.dv, -g * (mpmath.sin(a) - mu * mpmath.cos(a)), "1e-35")
        assert close(above.du, -mu * g * mpmath.cos(a) / (kappa - 1), "1e-35")
        assert above.dw < 0  # same sign as the slip: |w| = |dw| t grows
        # the same from a tiny initial slip of that sign: it never ends
        tiny = incline_slip_then_roll(a, mu, mu_s, kappa, 0, mp(10) ** -20, G)
        assert tiny.mode == "sliding-" and tiny.t_star == mpmath.inf and tiny.mode_after == "sliding-"
        assert tiny.dw == above.dw


def _slip_odefun(alpha, mu, kappa, v0, u0, s):
    """odefun of (position, v, u) while slipping with slip sign s."""
    g, a = mp(G), mp(alpha)
    dv = -g * mpmath.sin(a) - s * mu * g * mpmath.cos(a)
    du = s * mu * g * mpmath.cos(a) / (kappa - 1)
    return mpmath.odefun(lambda t, y: [y[1], dv, du], 0, [mp(0), mp(v0), mp(u0)])


@pytest.mark.parametrize("alpha, mu, mu_s, v0, u0, after", [
    ("0.3", "0.1", "0.2", 3, 0, "rolling"),        # launched uphill without spin
    ("0.3", "0.1", "0.2", 1, -5, "rolling"),       # backspin: v changes sign while slipping
    ("0.3", "0.1", "0.2", -1, 2, "rolling"),       # w < 0 on a gentle slope: slip decreases
    ("1.0", "0.25", "0.3", 3, 0, "sliding-"),      # steep: slips the other way after w = 0
])
def test_slip_then_roll_against_odefun(alpha, mu, mu_s, v0, u0, after):
    kappa, mu = mp(7) / 5, mp(mu)
    res = incline_slip_then_roll(alpha, mu, mu_s, kappa, v0, u0, G, m=3)
    assert res.mode == ("sliding+" if v0 > u0 else "sliding-") and res.mode_after == after
    with mpmath.workdps(30):
        s = 1 if v0 > u0 else -1
        sol = _slip_odefun(alpha, mu, kappa, v0, u0, s)
        t_star = ode_root(lambda t: sol(t)[1] - sol(t)[2], res.t_star / 2, res.t_star * 2)
        x, v, u = sol(t_star)
        assert close(t_star, res.t_star, "1e-25")
        assert close(v, res.v_star, "1e-25") and close(u, res.v_star, "1e-25")
        assert close(x, res.displacement, "1e-25")
        # path length: integral of |v|
        assert close(mpmath.quad(lambda t: abs(sol(t)[1]), [0, -mp(v0) / res.dv, t_star]
                                 if 0 < -mp(v0) / res.dv < t_star else [0, t_star]), res.path_length, "1e-25")
        # energy: friction loss = mu N integral |w| dt = -(change of kinetic + potential energy)
        a, m, g = mp(alpha), 3, mp(G)
        N = m * g * mpmath.cos(a)
        loss = mu * N * mpmath.quad(lambda t: abs(sol(t)[1] - sol(t)[2]), [0, t_star])
        assert close(loss, res.friction_loss, "1e-25")
        assert close(res.kinetic_change + res.potential_change, -res.friction_loss, "1e-35")
        T0 = m * mp(v0) ** 2 / 2 + m * (kappa - 1) * mp(u0) ** 2 / 2
        T1 = m * v**2 / 2 + m * (kappa - 1) * u**2 / 2
        assert close(T1 - T0 + m * g * mpmath.sin(a) * x, -loss, "1e-25")
    if after != "rolling":
        # the other way: the new slip sign is -sign(alpha) and its slip rate keeps that sign
        assert after == "sliding-" and res.mode == "sliding+"
        again = incline_slip_then_roll(alpha, mu, mu_s, kappa, res.v_star, res.v_star + mp(10) ** -20, G)
        assert again.t_star == mpmath.inf and again.dw < 0


def test_slip_that_never_ends():
    # w < 0 (spin ahead of the centre) on a steep slope with little friction: |tan a| > mu kappa/(kappa-1)
    res = incline_slip_then_roll("1.0", "0.1", "0.2", "1.4", 0, 1, G)
    assert res.t_star == mpmath.inf and res.mode == "sliding-" and res.dw < 0
    assert res.v_star is None and res.friction_loss is None


# --------------------------------------------------------------------------- 4. general integrator


@pytest.mark.parametrize("alpha, mu, mu_s, dx0", [
    ("0.5", "0.2", "0.3", 2),     # stops, restarts downhill
    ("0.5", "0.2", "0.6", 2),     # stops, sticks
    ("-0.4", "0.1", "0.5", 1),    # downhill (alpha < 0, x' > 0), mu < |tan a|: accelerates
    ("-0.1", "0.2", "0.2", 1),    # downhill, mu > |tan a|: stops and sticks
])
def test_sliding_on_curve_line_against_incline(alpha, mu, mu_s, dx0):
    t_end = mp("1.5")
    ref = incline_sliding(alpha, mu, mu_s, "0.1", dx0, G, t_end)
    with mpmath.workdps(30):
        ta = mpmath.tan(mp(alpha))
        run = sliding_on_curve(lambda x: ta * x, "0.1", dx0, mu, mu_s, G, t_end, dps=25,
                               df=lambda x: ta, d2f=lambda x: mp(0))
    assert run.mode0 == ref.mode0 and run.mode == ref.mode
    assert len(run.transitions) == len(ref.transitions)
    for a, b in zip(run.transitions, ref.transitions):
        assert (a.mode_from, a.mode_to) == (b.mode_from, b.mode_to)
        assert close(a.t, b.t, "1e-20") and close(a.x, b.x, "1e-20")
    assert close(run.x, ref.x, "1e-20") and close(run.dx, ref.dx, "1e-20")


def test_sliding_on_curve_parabola_frictionless():
    """y = x^2/2, released at x = 1, mu = 0: turning points at x = -+1 every half period."""
    with mpmath.workdps(25):
        g = mp(G)
        # half period from energy conservation, (1 + x^2) x'^2 / 2 = g (1 - x^2) / 2, with x = sin(theta):
        # integral of sqrt((1 + x^2) / (g (1 - x^2))) dx = integral of sqrt((1 + sin^2) / g) dtheta
        half = mpmath.quad(lambda th: mpmath.sqrt((1 + mpmath.sin(th) ** 2) / g), [-mpmath.pi / 2, mpmath.pi / 2])
        run = sliding_on_curve(lambda x: x**2 / 2, 1, 0, 0, 0, G, 2 * half + mp("0.1"), dps=20,
                               df=lambda x: x, d2f=lambda x: mp(1))
        assert run.mode0 == "sliding-"
        assert [(tr.mode_from, tr.mode_to) for tr in run.transitions] == [("sliding-", "sliding+"),
                                                                           ("sliding+", "sliding-")]
        (t1, x1), (t2, x2) = [(tr.t, tr.x) for tr in run.transitions]
        assert close(x1, -1, "1e-17") and close(x2, 1, "1e-17")
        assert close(t1, half, "1e-17") and close(t2, 2 * half, "1e-17")
        energy = (1 + run.x**2) * run.dx**2 / 2 + g * run.x**2 / 2
        assert close(energy, g / 2, "1e-17")


def test_sliding_on_curve_matches_the_rough_circle():
    """Inside a circle = on top of its lower arc y = R - sqrt(R^2 - x^2), x = R sin(phi)."""
    R, mu, mu_s = mp(1), mp("0.1"), mp("0.15")
    seq = circle_sliding_sequence(0, 4, mu, mu_s, R, G, 2)
    with mpmath.workdps(25):
        f = lambda x: R - mpmath.sqrt(R**2 - x**2)  # noqa: E731
        df = lambda x: x / mpmath.sqrt(R**2 - x**2)  # noqa: E731
        d2f = lambda x: R**2 / (R**2 - x**2) ** mp("1.5")  # noqa: E731
        t_end = seq.transitions[1].t + mp("0.05")
        run = sliding_on_curve(f, 0, 4 * R, mu, mu_s, G, t_end, dps=20, df=df, d2f=d2f)
    assert len(run.transitions) == 2
    for a, b in zip(run.transitions, seq.transitions):
        assert (a.mode_from, a.mode_to) == (b.mode_from, b.mode_to)
        assert close(a.t, b.t, "1e-15") and close(a.x, R * mpmath.sin(b.phi), "1e-15")


def test_sliding_on_curve_leaves_a_sphere_and_sticks_at_rest():
    # frictionless particle released on top of a circle y = sqrt(R^2 - x^2): leaves at cos = 2/3 cos(theta0)
    R, x0 = mp(1), mp("0.3")
    with mpmath.workdps(25):
        f = lambda x: mpmath.sqrt(R**2 - x**2)  # noqa: E731
        df = lambda x: -x / mpmath.sqrt(R**2 - x**2)  # noqa: E731
        d2f = lambda x: -R**2 / (R**2 - x**2) ** mp("1.5")  # noqa: E731
        run = sliding_on_curve(f, x0, 0, 0, 0, G, 3, dps=20, df=df, d2f=d2f)
        assert run.status == "leaves_track" and run.mode == "sliding+" and run.transitions == ()
        cos_leave = 2 * mpmath.sqrt(R**2 - x0**2) / (3 * R)
        assert close(run.x, R * mpmath.sqrt(1 - cos_leave**2), "1e-17")
        # at rest where |f'| <= mu_s: stuck for ever
        still = sliding_on_curve(f, x0, 0, "0.3", "0.4", G, 3, dps=20, df=df, d2f=d2f)
        assert still.status == "stuck" and still.mode0 == "stuck" and close(still.x, x0, "1e-20")


# --------------------------------------------------------------------------- inputs and outputs


def test_inputs_and_outputs():
    with pytest.raises(ValueError):
        incline_sliding("0.5", "0.3", "0.2", 0, 1, G, 1)  # mu_s < mu
    with pytest.raises(ValueError):
        circle_branch_rate2("0.1", "0.2", 0, "0.1", 1, G)  # from rest without sgn
    with pytest.raises(ValueError):
        incline_slip_then_roll("0.2", "0.1", "0.2", "1.4", 1, 1, G)  # not slipping
    run = incline_sliding("0.5", "0.2", "0.3", 0, 2, G, 1, dps=20)
    assert isinstance(run.x, mpmath.mpf) and isinstance(run.transitions[0].t, mpmath.mpf)
    with pytest.raises(dataclasses.FrozenInstanceError):
        run.x = 0  # type: ignore[misc]
    # float inputs are their binary values; results do not depend on the global precision
    with mpmath.workdps(15):
        a = circle_turning_point(0.0, 4.0, 0.1, 1.0, 9.81)
    with mpmath.workdps(50):
        b = circle_turning_point(0.0, 4.0, 0.1, 1.0, 9.81)
    assert a == b and isinstance(a, mpmath.mpf)
    assert rough.STUCK == "stuck" and rough.ROLLING == "rolling"
