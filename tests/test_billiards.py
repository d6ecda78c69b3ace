"""Billiards on the one engine (paper section 7, issue 14): closed forms, an mpmath reference, bad input.

Every check below compares the engine with something it does not compute
itself: unfolded straight lines in a rectangle, the integrals of the
elliptical billiard, Poncelet orbits built geometrically, the slide models'
closed forms from the angular momentum about the cloth contact, the
independent mpmath reference (heyroll.reference.billiard).
"""

from __future__ import annotations

import csv
import math
import subprocess
import sys
from pathlib import Path

import mpmath
import numpy as np
import pytest

from heyroll.errors import SceneError
from heyroll.interfaces.scene_file import parse_scene
from heyroll.model.table import EllipseBoundary
from heyroll.reference.billiard import _cushion_time, reference_impacts
from heyroll.simulation.driver import simulate
from heyroll.simulation.result import Status

ROOT = Path(__file__).resolve().parent.parent


def table_scene(boundary: str, balls: list[dict], *, law="hedrih", k=1, cushion="rolling", cushion_k=1,
                friction="0.2", simultaneous="sequential", t_end=50, max_collisions=None, name="t"):
    lines = ['[track]', 'type = "table"', boundary, f'cushion_model = "{cushion}"',
             f'cushion_restitution = {cushion_k}', f'friction = {friction}']
    for ball in balls:
        lines.append("[[bodies]]")
        lines += [f'{key} = "{value}"' if key == "shape" else f"{key} = {value}" for key, value in ball.items()]
    lines += ["[collision]", f'law = "{law}"', f"restitution = {k}", f'simultaneous = "{simultaneous}"', "[run]",
              f"t_end = {t_end}"]
    if max_collisions is not None:
        lines.append(f"max_collisions = {max_collisions}")
    return parse_scene("\n".join(lines), default_name=name)


ELLIPSE = 'boundary = "ellipse"\na = 2.0\nb = 1.0'


def particle(x, y, vx, vy):
    return {"shape": "particle", "radius": 0, "mass": 1, "x": x, "y": y, "vx": vx, "vy": vy}


def ball(x, y, vx, vy, radius="0.1", mass="0.17", shape="solid_sphere"):
    return {"shape": shape, "radius": radius, "mass": mass, "x": x, "y": y, "vx": vx, "vy": vy}


# -- the cushion of a finite ball in an ellipse ------------------------------------------------


@pytest.mark.parametrize("a, b, r", [("2", "1", "0.1"), ("3", "2.5", "1.2"), ("1", "0.3", "0.05")])
def test_the_parallel_curve_polynomial_vanishes_on_the_curve_of_the_centre(a, b, r):
    """The degree-8 polynomial against the parallel curve P(th) - R n(th), built here in mpmath."""
    with mpmath.workdps(60):
        ell = EllipseBoundary(mpmath.mpf(a), mpmath.mpf(b))
        c = ell.wall_constants(mpmath.mpf(r))[0]
        a, b, r = mpmath.mpf(a), mpmath.mpf(b), mpmath.mpf(r)
        for th in mpmath.linspace(0, 2 * mpmath.pi, 23):
            n = (b * mpmath.cos(th), a * mpmath.sin(th))
            norm = mpmath.hypot(*n)
            x, y = a * mpmath.cos(th) - r * n[0] / norm, b * mpmath.sin(th) - r * n[1] / norm
            assert abs(ell.gap(0, x, y, c)) < mpmath.mpf(10) ** -50
            # and it is negative just inside, positive just outside, along the normal
            assert ell.gap(0, x - r / 100 * n[0] / norm, y - r / 100 * n[1] / norm, c) < 0
            assert ell.gap(0, x + r / 100 * n[0] / norm, y + r / 100 * n[1] / norm, c) > 0


def test_the_gap_has_no_zero_inside_the_curve_of_the_centre():
    ell = EllipseBoundary(mpmath.mpf(2), mpmath.mpf(1))
    c = [float(v) for v in ell.wall_constants(mpmath.mpf("0.4"))[0]]
    rng = np.random.default_rng(3)
    # points well inside the centre's curve: a shrunk copy of it
    th = rng.uniform(0, 2 * np.pi, 20000)
    shrink = rng.uniform(0, 0.97, th.size)
    n = np.stack([1 * np.cos(th), 2 * np.sin(th)])
    n /= np.hypot(*n)
    x = shrink * (2 * np.cos(th) - 0.4 * n[0])
    y = shrink * (1 * np.sin(th) - 0.4 * n[1])
    assert np.all(ell.gap(0, x, y, c) < 0)


# -- the rectangle unfolds into straight lines -------------------------------------------------


def unfolded_times(x0, v, half, n):
    """Wall times of x0 + v t reflected between -half and half."""
    if v == 0:
        return []
    first = (half - x0) / v if v > 0 else (-half - x0) / v
    period = 2 * half / abs(v)
    return [first + m * period for m in range(n)]


@pytest.mark.parametrize("radius, shape", [("0", "particle"), ("0.05", "solid_sphere")])
def test_rectangle_impact_times_are_the_unfolded_lines(radius, shape):
    body = {"shape": shape, "radius": radius, "mass": 1, "x": 0.1, "y": -0.13, "vx": 0.7, "vy": 0.31}
    scene = table_scene('boundary = "rectangle"\nwidth = 2.0\nheight = 1.0', [body], law="newton", t_end=2000,
                        max_collisions=400)
    result = simulate(scene)
    table = result.collision_table()
    r = float(radius)
    times = sorted(unfolded_times(0.1, 0.7, 1 - r, 400) + unfolded_times(-0.13, 0.31, 0.5 - r, 400))[:400]
    assert result.status is Status.MAX_COLLISIONS
    got = table["t"]
    assert np.max(np.abs(got - times) / np.array(times)) < 1e-14
    # speed and |vx|, |vy| kept exactly by reflections in straight walls
    assert set(np.abs(table["vx_i_after"])) == {0.7} and set(np.abs(table["vy_i_after"])) == {0.31}


def test_a_corner_hit_reverses_the_ball_two_cushions_at_one_instant():
    body = ball("0.0", "0.0", "0.95", "0.45", radius="0.05")  # at t = 1 at the corner (0.95, 0.45) of its centre
    scene = table_scene('boundary = "rectangle"\nwidth = 2.0\nheight = 1.0', [body], max_collisions=2)
    result = simulate(scene)
    t = result.collision_table()
    assert t["t"][0] == t["t"][1] == pytest.approx(1, rel=1e-15)
    assert (t["vx_i_after"][1], t["vy_i_after"][1]) == (-0.95, -0.45)


# -- the elliptical billiard -------------------------------------------------------------------


def ellipse_run(x, y, vx, vy, n=1000):
    scene = table_scene(ELLIPSE, [particle(x, y, vx, vy)], law="newton", t_end=1e6, max_collisions=n)
    return simulate(scene).collision_table()


def test_ellipse_integrals_of_a_particle_are_conserved_over_a_thousand_impacts():
    """Joachimsthal's integral at the impacts, the focal angular momenta product and the caustic."""
    t = ellipse_run(0.3, -0.2, 1.0, 0.7)
    a, b = 2.0, 1.0
    f = math.sqrt(a * a - b * b)
    x, y, vx, vy = t["x_i"], t["y_i"], t["vx_i_after"], t["vy_i_after"]
    speed = np.hypot(vx, vy)
    dx, dy = vx / speed, vy / speed
    joachimsthal = -(x * dx / a**2 + y * dy / b**2)
    product = ((x - f) * dy - y * dx) * ((x + f) * dy - y * dx)
    caustic = a * a * dy * dy + b * b * dx * dx - (x * dy - y * dx) ** 2
    for integral in (joachimsthal, product, caustic):
        assert np.ptp(integral) < 1e-12 * max(1, np.max(np.abs(integral)))
    assert np.all(joachimsthal > 0)
    assert np.allclose(caustic, b * b - product, atol=1e-13)  # one integral seen two ways
    assert np.ptp(speed) < 1e-13


def test_the_period_two_orbits_close_with_the_axes_as_perimeters():
    for x, y, vx, vy, half in ((0.0, 0.3, 0.0, 1.0, 1.0), (0.5, 0.0, 1.0, 0.0, 2.0)):
        t = ellipse_run(x, y, vx, vy, n=21)
        steps = np.diff(t["t"])
        assert np.allclose(steps, 2 * half, rtol=1e-14)  # the minor axis 4b, the major 4a per period


def test_the_poncelet_period_four_rhombus_closes():
    a, b = 2.0, 1.0
    # a particle on the chord from (0, b) to (a, 0), moving towards (a, 0)
    side = math.hypot(a, b)
    t = ellipse_run(a / 2, b / 2, a / side, -b / side, n=40)
    assert np.allclose(np.abs(t["x_i"][::2]), a, atol=1e-12) or np.allclose(np.abs(t["x_i"][1::2]), a, atol=1e-12)
    assert np.allclose(t["t"][4:] - t["t"][:-4], 4 * side, rtol=1e-13)


def test_the_poncelet_period_three_triangle_closes():
    """The isosceles 3-orbit with a vertex at (a, 0): its other two vertices (x1, +-y1) solved here."""
    a, b = mpmath.mpf(2), mpmath.mpf(1)

    def mirror_defect(x1):
        y1 = b * mpmath.sqrt(1 - x1**2 / a**2)
        nx, ny = x1 / a**2, y1 / b**2
        inc = mpmath.matrix([a - x1, -y1]) / mpmath.hypot(a - x1, y1)  # towards (a, 0)
        out = mpmath.matrix([0, -1])  # the vertical chord to (x1, -y1)
        return (inc[0] * nx + inc[1] * ny) - (out[0] * nx + out[1] * ny)

    x1 = mpmath.findroot(mirror_defect, (mpmath.mpf("-1.99"), mpmath.mpf(0)), solver="anderson")
    y1 = b * mpmath.sqrt(1 - x1**2 / a**2)
    perimeter = 2 * mpmath.hypot(a - x1, y1) + 2 * y1
    start = ((a + x1) / 2, y1 / 2)
    d = mpmath.matrix([x1 - a, y1]) / mpmath.hypot(a - x1, y1)  # from (a, 0) towards (x1, y1)
    t = ellipse_run(float(start[0]), float(start[1]), float(d[0]), float(d[1]), n=30)
    assert np.allclose(t["t"][3:] - t["t"][:-3], float(perimeter), rtol=1e-12)


def test_impact_times_in_the_ellipse_against_the_mpmath_reference():
    """Each cushion impact of a finite ball, predicted by the reference from the engine's previous one."""
    scene = table_scene(ELLIPSE, [ball("0.3", "-0.2", "1.0", "0.7")], t_end=1e4, max_collisions=25)
    table = simulate(scene).collision_table()
    with mpmath.workdps(40):
        ell = scene.boundary
        worst = 0.0
        for prev, row in zip(table[:-1], table[1:]):
            state = [mpmath.mpf(float(prev[c])) for c in ("x_i", "y_i", "vx_i_after", "vy_i_after")]
            tau, _ = _cushion_time(ell, state, mpmath.mpf("0.1"), mpmath.mpf(10) ** -30)
            worst = max(worst, abs(float(row["t"]) - float(prev["t"] + tau)) / float(row["t"]))
    assert worst < 4e-15


@pytest.mark.parametrize("radius", ["0.1", "0.0001"])
def test_a_small_ball_leaves_each_cushion_impact_in_the_ellipse_with_the_exact_reflection(radius):
    """Review: the normal at a finite ball's cushion impact came from the foot point minus the centre (two points
    ~a from the origin and R apart): with R = 1e-4 in a = 2 each impact's outgoing velocity was 3e-12 off. From
    each row's incoming state the reference finds the impact and mirrors the velocity in its exact normal."""
    scene = table_scene(ELLIPSE, [ball("0.6", "-0.2", "1.0", "0.7", radius=radius, mass="1")], t_end=1e4,
                        max_collisions=40)
    table = simulate(scene).collision_table()
    with mpmath.workdps(40):
        worst = 0.0
        for prev, row in zip(table[:-1], table[1:]):
            state = [mpmath.mpf(float(prev[c])) for c in ("x_i", "y_i", "vx_i_after", "vy_i_after")]
            _tau, (nx, ny) = _cushion_time(scene.boundary, state, mpmath.mpf(radius), mpmath.mpf(10) ** -30)
            vx, vy = state[2], state[3]
            vn = vx * nx + vy * ny
            exact = (vx - 2 * vn * nx, vy - 2 * vn * ny)
            worst = max(worst, max(abs(float(row[c] - e)) for c, e in zip(("vx_i_after", "vy_i_after"), exact)))
    assert worst < 2e-15


def test_two_balls_against_the_reference_for_the_first_impacts():
    scene = table_scene(ELLIPSE, [ball("0.3", "-0.2", "1.0", "0.7"), ball("-0.5", "0.2", "-0.3", "0.5")],
                        t_end=100, max_collisions=12)
    table = simulate(scene).collision_table()
    ref = reference_impacts(scene, 12, dps=40)
    assert [(r["i"], r["j"]) for r in table] == [(x.i, x.j) for x in ref]
    times = np.array([float(x.t) for x in ref])
    assert np.max(np.abs(table["t"] - times) / times) < 1e-12  # round-off grows with every reflection


@pytest.mark.parametrize("law", ["hedrih", "newton", "mirror"])
def test_ball_laws_against_the_reference_in_a_circle(law):
    scene = table_scene('boundary = "circle"\nradius = 1.0',
                        [ball("-0.5", "0.0", "1.0", "0.05", radius="0.1", mass="1"),
                         ball("0.4", "0.02", "-0.5", "0.0", radius="0.15", mass="2", shape="disk")],
                        law=law, k="0.8", t_end=3, max_collisions=3)
    table = simulate(scene).collision_table()
    ref = reference_impacts(scene, 3, dps=40)
    pair = [x for x in ref if x.j == 2][0]
    row = table[table["j"] == 2][0]
    assert float(pair.t) == pytest.approx(row["t"], rel=1e-14)
    after = pair.state_after
    for col, value in (("vx_i_after", after[0][2]), ("vy_i_after", after[0][3]), ("vx_j_after", after[1][2]),
                       ("vy_j_after", after[1][3])):
        assert row[col] == pytest.approx(float(value), rel=1e-13, abs=1e-15)


# -- energy --------------------------------------------------------------------------------------


def test_energy_is_exact_at_k_one_and_eq_15_gives_the_loss_below():
    balls = [ball("0.3", "-0.2", "1.0", "0.7"), ball("-0.5", "0.2", "-0.3", "0.5"),
             ball("1.0", "0.1", "0.2", "-0.9", radius="0.12", mass="0.3")]
    elastic = simulate(table_scene(ELLIPSE, balls, t_end=200)).collision_table()
    assert len(elastic) > 100
    assert np.max(np.abs(elastic["energy_after"] - elastic["energy_before"])) < 1e-15
    lossy = simulate(table_scene(ELLIPSE, balls, k="0.6", t_end=200)).collision_table()
    pairs = lossy[(lossy["j"] > 0) & (lossy["law_flag"] == 0)]
    assert len(pairs) > 3
    radii, masses, kappa, k = {1: 0.1, 2: 0.1, 3: 0.12}, {1: 0.17, 2: 0.17, 3: 0.3}, 1.4, 0.6
    for row in pairs:
        i, j = int(row["i"]), int(row["j"])
        n = np.array([row["x_j"] - row["x_i"], row["y_j"] - row["y_i"]])
        n /= np.hypot(*n)
        wi = (row["vx_i_before"] * n[0] + row["vy_i_before"] * n[1]) / radii[i]
        wj = (row["vx_j_before"] * n[0] + row["vy_j_before"] * n[1]) / radii[j]
        ji, jj = kappa * masses[i] * radii[i] ** 2, kappa * masses[j] * radii[j] ** 2
        loss = 0.5 * ji * jj / (ji + jj) * (1 - k * k) * (wi - wj) ** 2  # eq. (15)
        assert row["energy_before"] - row["energy_after"] == pytest.approx(loss, rel=1e-9)


# -- sliding: the slide models' closed forms ---------------------------------------------------


@pytest.mark.parametrize("k", ["1", "0.5"])
def test_a_rolling_ball_comes_back_from_a_head_on_cushion_at_kappa_minus_1_minus_k_over_kappa(k):
    scene = table_scene('boundary = "rectangle"\nwidth = 2.0\nheight = 1.0', [ball("0", "0", "1.5", "0")],
                        cushion="slide", cushion_k=k, friction="0.2", t_end=5, max_collisions=1)
    result = simulate(scene, max_collisions=None, t_end=1.5)
    assert result.n_rerolls == 1
    vx = result.state_final[2]
    kappa = 1.4
    assert vx == pytest.approx(1.5 * (kappa - 1 - float(k)) / kappa, rel=1e-13)
    assert result.state_final[3] == 0 and result.state_final[4] == result.state_final[5] == 0


@pytest.mark.parametrize("vy", ["0", "0.3"])
def test_bounces_of_a_rolling_ball_driven_back_into_the_cushion_settle_in_their_limit(vy):
    """k_c < kappa - 1: each bounce leaves the ball sliding back into the cushion, rolling again at
    r = (kappa - 1 - k_c)/kappa of its normal speed before it returns: impacts at geometric speeds, in a
    finite time. Acceptance test: the last ones, at one instant, went on to round-off and left 3e-14 m/s into
    the wall, and the ball bounced again at 1e-14 m/s every few hundred seconds."""
    scene = table_scene('boundary = "rectangle"\nwidth = 4.0\nheight = 2.0', [ball("1", "0", "1", vy, radius="0.05")],
                        cushion="slide", cushion_k="0.2", friction="0.2", t_end=2)  # before the corner
    result = simulate(scene)
    rows = result.collision_table()
    kappa, k_c, mu, g, v = 1.4, 0.2, 0.2, 9.81, 1.0
    r = (kappa - 1 - k_c) / kappa
    assert rows["vx_i_before"][1:] == pytest.approx(v * r ** np.arange(1, len(rows)), rel=1e-9, abs=0)
    assert rows["vx_i_after"][:4] == pytest.approx(-k_c * v * r ** np.arange(4), rel=1e-12, abs=0)
    # the cycle of normal speed u: slide for t1 = (1 + k_c) u (kappa - 1)/(mu g kappa), roll back d/(r u)
    t1 = (1 + k_c) * v * (kappa - 1) / (mu * g * kappa)
    cycle = t1 + (k_c * v * t1 - mu * g * t1 ** 2 / 2) / (r * v)
    assert rows["t"][:4] == pytest.approx(0.95 + cycle * (1 - r ** np.arange(4)) / (1 - r), rel=1e-13, abs=0)
    # the limit: the last row settles it on the wall (law_flag 4), normal speed 0, the tangential one kept;
    # its instant is the sequence's to the position resolution over the speed (3.5e-7 s: the bounces of
    # 1e-6 m/s turn 4e-13 m from the wall)
    settle = rows[-1]
    assert settle["law_flag"] == 4 and settle["vx_i_after"] == 0 and settle["vy_i_after"] == float(vy)
    assert (rows["law_flag"][:-1] == 0).all() and rows["t"][-2] == settle["t"]
    assert settle["t"] == pytest.approx(0.95 + cycle / (1 - r), abs=1e-6)
    assert result.state_final[0] == 1.95 and result.state_final[2] == 0
    assert result.energy_final == pytest.approx(0.5 * kappa * 0.17 * float(vy) ** 2, rel=1e-15, abs=0)


def cut_shot(angle):
    """A rolling cue ball hits a resting object ball with the line of centres at ``angle`` (rad) to its path."""
    d = 0.2  # two radii of 0.1
    ox, oy = 0.0, 0.0
    cx, cy = ox - d * math.cos(angle), oy - d * math.sin(angle)
    start = (cx - 0.3, cy)
    balls = [ball(repr(start[0]), repr(start[1]), "1.0", "0"), ball("0", "0", "0", "0")]
    scene = table_scene('boundary = "circle"\nradius = 5.0', balls, law="slide", friction="0.2", t_end=1.5)
    return simulate(scene)


@pytest.mark.parametrize("angle", [0.2, math.atan(math.sqrt(0.4 / 1.4)), 0.9])
def test_the_cue_ball_deflection_after_a_rolling_cut_shot(angle):
    """After the impulse through the centres and sliding: tan theta = sin c cos c / (sin^2 c + 2/5)."""
    result = cut_shot(angle)
    vx, vy = result.state_final[2], result.state_final[3]
    assert result.n_rerolls == 2  # both balls slide after the impact, and roll again
    theta = math.atan2(-vy, vx)
    expected = math.atan(math.sin(angle) * math.cos(angle) / (math.sin(angle) ** 2 + 0.4))
    assert theta == pytest.approx(expected, abs=1e-12)
    if angle == math.atan(math.sqrt(0.4 / 1.4)):  # the maximum: 1 / (2 sqrt(p (1 + p))), p = 2/5
        assert math.degrees(theta) == pytest.approx(math.degrees(math.atan(1 / (2 * math.sqrt(0.56)))), abs=1e-9)
        assert 33.7 < math.degrees(theta) < 33.8


# -- simultaneous collisions: Newton's cradle --------------------------------------------------


def cradle(policy):
    row = [ball("-0.5", "0", "1", "0", mass="1")] + [ball(repr(0.2 * m), "0", "0", "0", mass="1") for m in range(2)]
    scene = table_scene('boundary = "circle"\nradius = 5.0', row, law="newton", simultaneous=policy, t_end=1)
    return simulate(scene)


def test_newtons_cradle_sequential_passes_the_impulse_along_the_row():
    result = cradle("sequential")
    v = [result.state_final[6 * k + 2] for k in range(3)]
    assert v == [0, 0, 1]


def test_newtons_cradle_simultaneous_impulses_give_the_complementarity_outcome():
    result = cradle("impulses")
    v = np.array([result.state_final[6 * k + 2] for k in range(3)])
    assert np.allclose(v, [-1 / 3, 2 / 3, 2 / 3], atol=1e-15)
    assert v.sum() == pytest.approx(1, abs=1e-15)  # momentum
    assert result.energy_final == pytest.approx(result.energy_initial, rel=1e-14)


def test_symmetric_starts_resolve_every_pair_at_the_same_instant():
    """Four balls launched at the centre meet at one instant: no overlap, momentum zero, energy kept."""
    s = 0.5
    balls = [ball(repr(x), repr(y), repr(-x), repr(-y)) for x, y in ((s, 0), (0, s), (-s, 0), (0, -s))]
    scene = table_scene('boundary = "circle"\nradius = 1.0', balls, law="newton", t_end=1.5)  # before the cushion
    result = simulate(scene)
    assert result.status is Status.COMPLETED
    assert result.n_collisions >= 2 and result.n_cushion == 0
    state = np.array(result.state_final, dtype=float).reshape(4, 6)
    assert np.allclose(state[:, 2:4].sum(axis=0), 0, atol=1e-14)
    assert result.energy_final == pytest.approx(result.energy_initial, rel=1e-14)


# -- precision ladder ----------------------------------------------------------------------------


def test_quad_precision_agrees_with_double_and_keeps_its_digits():
    scene = table_scene(ELLIPSE, [ball("0.3", "-0.2", "1.0", "0.7")], t_end=100, max_collisions=5)
    double = simulate(scene).collision_table()
    quad = simulate(scene, precision="quad").collision_table(native=True)
    assert [float(t) for t in quad["t"]] == pytest.approx(list(double["t"]), rel=1e-14)
    ref = reference_impacts(scene, 5, dps=50)
    with mpmath.workdps(50):
        assert abs(mpmath.mpf(str(quad["t"][4])) - ref[4].t) < 1e-28


# -- files and bad input -------------------------------------------------------------------------


def write(tmp_path, text, name="table.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


TABLE = """
[track]
type = "table"
boundary = "ellipse"
a = 2.0
b = 1.0
cushion_model = "rolling"
cushion_restitution = 1.0
friction = 0.2

[[bodies]]
shape = "solid_sphere"
radius = 0.1
mass = 0.17
x = 0.3
y = -0.2
vx = 1.0
vy = 0.7

[collision]
law = "hedrih"
restitution = 1.0
simultaneous = "sequential"

[run]
t_end = 20.0
max_collisions = 10000
"""


def run_cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "heyroll.interfaces.cli", *args], cwd=cwd, capture_output=True, text=True)


def test_the_cli_writes_the_table_columns_summary_and_figures(tmp_path):
    path = write(tmp_path, TABLE)
    out = run_cli("run", str(path), "--out", str(tmp_path / "out"), "--progress", "off", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    with open(tmp_path / "out" / "collisions.csv") as f:
        rows = list(csv.DictReader(f))
    need = ("n,t,i,j,x_i,y_i,vx_i_before,vy_i_before,vx_i_after,vy_i_after,x_j,y_j,vx_j_before,vy_j_before,"
            "vx_j_after,vy_j_after,energy_before,energy_after,boundary_s,reflection_angle").split(",")
    assert list(rows[0])[:len(need)] == need
    assert all(r["j"] == "0" and r["x_j"] == "" and r["boundary_s"] != "" for r in rows)
    import json

    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["status"] == "completed" and summary["collisions"] == len(rows)
    assert (tmp_path / "out" / "table_paths.png").stat().st_size > 0
    assert (tmp_path / "out" / "birkhoff_map.png").stat().st_size > 0
    # 17 digits round-trip
    first = simulate(parse_scene(TABLE), max_collisions=1).collision_table()
    assert float(rows[0]["t"]) == first["t"][0]


BAD = [
    ("x = 0.3\ny = -0.2", "x = 1.95\ny = 0.0", "bodies[1].x"),
    ("radius = 0.1\nmass", "radius = 0.5\nmass", "bodies[1].radius"),  # R >= b^2/a = 0.5
    ("restitution = 1.0\nsimultaneous", "restitution = 1.5\nsimultaneous", "collision.restitution"),
    ("cushion_restitution = 1.0", "cushion_restitution = -0.1", "track.cushion_restitution"),
    ('boundary = "ellipse"\na = 2.0\nb = 1.0',
     'boundary = "polygon"\nvertices = [[-1, -1], [1, -1], [0, -0.5], [1, 1], [-1, 1]]', "track.vertices"),
    ('law = "hedrih"', 'law = "elastic"', "collision.law"),
    ('boundary = "ellipse"', 'boundary = "oval"', "track.boundary"),
]


@pytest.mark.parametrize("old, new, field", BAD)
def test_bad_table_input_is_one_line_exit_2_nothing_written(tmp_path, old, new, field):
    assert old in TABLE
    path = write(tmp_path, TABLE.replace(old, new))
    out = run_cli("run", str(path), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert out.returncode == 2
    assert out.stderr.count("\n") == 1 and field in out.stderr, out.stderr
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_overlapping_balls_are_refused():
    with pytest.raises(SceneError, match=r"bodies\[2\]"):
        table_scene(ELLIPSE, [ball("0", "0", "1", "0"), ball("0.15", "0", "0", "0")])


def test_a_break_of_sixteen_balls_keeps_momentum_and_energy_and_never_overlaps():
    """A cue ball into a rack of 15 touching balls in a rectangle (the numpy contact pass of many balls)."""
    r = 0.028575
    balls = [ball("-0.6", "0.0", "3.0", "0.0", radius=repr(r))]
    for row in range(5):
        for m in range(row + 1):
            spread = 1 + 1e-9  # touching up to a gap of ~1e-10 m: the impacts come one by one, as in a real break
            balls.append(ball(repr(0.3 + row * math.sqrt(3) * r * spread), repr((m - row / 2) * 2 * r * spread), "0",
                              "0", radius=repr(r)))
    scene = table_scene('boundary = "rectangle"\nwidth = 2.54\nheight = 1.27', balls, law="newton", t_end=0.4)
    result = simulate(scene)
    assert result.status is Status.COMPLETED, result.message
    state = np.array(result.state_final, dtype=float).reshape(16, 6)
    table = result.collision_table()
    before_walls = table["t"] < table[table["j"] == 0]["t"].min() if (table["j"] == 0).any() else np.ones(len(table), bool)
    assert before_walls.sum() > 15  # the break itself
    if not (table["j"] == 0).any():
        assert np.allclose(state[:, 2:4].sum(axis=0), [3.0, 0.0], atol=1e-13)
    assert result.energy_final == pytest.approx(result.energy_initial, rel=1e-13)
    # no two balls closer than their radii, no ball outside the cushion's reach
    xy = state[:, :2]
    d = np.hypot(*(xy[:, None, :] - xy[None, :, :]).transpose(2, 0, 1))
    assert np.all(d[np.triu_indices(16, 1)] >= 2 * r * (1 - 1e-12))
    assert np.all(np.abs(xy[:, 0]) <= 1.27 - r + 1e-12) and np.all(np.abs(xy[:, 1]) <= 0.635 - r + 1e-12)


def test_ctrl_c_leaves_a_complete_table_and_summary(tmp_path):
    import signal
    import time

    path = write(tmp_path, TABLE.replace("t_end = 20.0", "t_end = 1e9").replace("max_collisions = 10000",
                                                                                 "max_collisions = 1000000000"))
    proc = subprocess.Popen([sys.executable, "-m", "heyroll.interfaces.cli", "run", str(path), "--out",
                             str(tmp_path / "out"), "--no-figures", "--progress", "off"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.time() + 60
    table = tmp_path / "out" / ".collisions.csv.tmp"
    while time.time() < deadline and not table.exists():
        time.sleep(0.2)
    # until rows reach the file (a fixed 4 s left no impact yet on a loaded machine: compilation first)
    header = table.stat().st_size if table.exists() else 0
    while time.time() < deadline and (not table.exists() or table.stat().st_size <= header):
        time.sleep(0.2)
    time.sleep(0.5)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    import json

    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    with open(tmp_path / "out" / "collisions.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == summary["collisions"] > 0
    assert all(len(r) == len(rows[0]) and r["reflection_angle"] != "" for r in rows)


@pytest.mark.parametrize("name", ["elliptical_billiard", "cut_shot", "newtons_cradle", "dissipative_ellipse",
                                  "skidding_ellipse"])
def test_the_table_examples_run(name):
    from heyroll.interfaces.scene_file import load_scene

    scene = load_scene(ROOT / "examples" / f"{name}.toml")
    result = simulate(scene, t_end=min(float(scene.run.t_end), 20.0))
    assert result.status.success, result.message
    assert result.n_collisions > 0
    if name == "newtons_cradle":  # the first impacts: 1-2, 2-3, 3-4 at one instant, the last ball leaves at 1 m/s
        table = result.collision_table()
        first = table[table["t"] == table["t"][0]]
        assert [(r["i"], r["j"]) for r in first] == [(1, 2), (2, 3), (3, 4)]
        assert first["vx_j_after"][-1] == 1.0 and first["vx_i_after"][-1] == 0.0
    if name == "dissipative_ellipse":  # balls settle onto the cushion, ride it, are knocked off, settle again
        longer = simulate(scene, t_end=100)
        assert longer.status is Status.COMPLETED and list(longer.collision_table()["law_flag"]).count(4) >= 5
        summary = longer.summary()
        assert summary["riding_final"] == list(longer.riding_final) and set(summary["riding_final"]) <= {1, 2, 3}
        assert summary["steps"] > 0 and summary["settings"]["tolerance"] == 2.0**-52
    if name == "skidding_ellipse":  # ball 1 loses its grip and skids, again and again; ball 2 settles and skids
        assert result.riding_final == (1, 2) and result.n_rerolls >= 3
        assert list(result.collision_table()["law_flag"]).count(4) >= 2
        assert result.energy_final < result.energy_initial


def test_a_ball_settling_onto_a_curved_cushion_rides_it():
    """k < 1 in a convex table: the reflection angle shrinks by k each time, impacts accumulate (Zeno); in
    their limit the ball rides the cushion (tests/test_cushion_riding.py checks the ride itself)."""
    scene = table_scene('boundary = "circle"\nradius = 1.0', [ball("0.2", "0.1", "0.6", "0.9")], cushion_k="0.5",
                        t_end=100)
    result = simulate(scene)
    assert result.status is Status.COMPLETED, result.message
    assert result.n_collisions > 5 and result.collision_table()["law_flag"][-1] == 4
    # k = 0 under the slide model: the ball skids along the cushion (tests/test_cushion_riding.py)
    skid = simulate(table_scene('boundary = "circle"\nradius = 1.0', [ball("0.2", "0.1", "0.6", "0.9")],
                                cushion="slide", cushion_k="0", t_end=10))
    assert skid.status is Status.COMPLETED and skid.riding_final == (1,)
    # on straight walls k = 0 is fine: the ball slides along the wall into the corner and stops there
    square = table_scene('boundary = "rectangle"\nwidth = 2.0\nheight = 1.0', [ball("0.2", "0.1", "0.6", "0.9")],
                         cushion_k="0", t_end=10)
    result = simulate(square)
    assert result.status is Status.COMPLETED and result.energy_final == 0


def test_regressions_found_by_review():
    """Newton's method on the foot point landing on a bracket end; constants at 53 bits in quad runs."""
    ell = EllipseBoundary(mpmath.mpf(2), mpmath.mpf(1))
    d, _ = ell.exact_distance(-1.3137518502318222, -0.30714794704282095, 4.0, 1.0, 0.0, -0.5668176139419914, 2.0**-27)
    assert abs(d - 0.4) < 1e-15
    scene = table_scene(ELLIPSE, [ball("1.4165877768793114", "-0.0962310802555661", "-0.9476787997412875",
                                       "0.31922545719432815", radius="0.4", mass="1")], t_end=500)
    assert simulate(scene).status is Status.COMPLETED  # was: overlap at t = 258.41
    quad = table_scene('boundary = "ellipse"\na = 2.1\nb = 1.3', [ball("0.3", "-0.2", "1.0", "0.7")], t_end=50)
    assert simulate(quad, precision="quad").status is Status.COMPLETED  # was: overlap after 1 impact
    two = table_scene(ELLIPSE, [ball("0.3", "-0.2", "1.0", "0.7"), ball("-0.5", "0.2", "-0.3", "0.5")], t_end=100,
                      max_collisions=17)
    table = simulate(two, precision="quad").collision_table(native=True)
    ref = reference_impacts(two, 17, dps=50)
    with mpmath.workdps(50):
        errors = [abs(mpmath.mpf(str(t)) - r.t) for t, r in zip(table["t"], ref)]
    assert max(errors) < 1e-28  # the first ball-ball impact (16th) included: reach^2 at the model's precision


def test_second_review_regressions():
    """Each found by an adversarial review: outside an ellipse, Hedrih under 'impulses', a skidding ball at a
    rolling cushion, k = 0 with spin into a straight cushion, grazing under 'impulses', kappa = 1 spin."""
    with pytest.raises(SceneError, match=r"bodies\[1\].x"):  # far outside: the polynomial's sign turns back
        table_scene(ELLIPSE, [ball("3.0", "0", "-1", "0")])
    touching = simulate(table_scene(ELLIPSE, [ball("1.9", "0", "-1", "0")], t_end=2))  # touching exactly
    assert touching.status is Status.COMPLETED
    along = simulate(table_scene(ELLIPSE, [ball("0", "0.9", "1", "0")], t_end=5))  # starts moving along it
    assert along.status is Status.COMPLETED and along.riding_final == (1,)  # it rides (was: failed)
    pair = [ball("-0.5", "0", "1", "0", radius="0.1", mass="1"),
            ball("0.5", "0.05", "0", "0", radius="0.2", mass="1", shape="ring")]
    alone = simulate(table_scene('boundary = "circle"\nradius = 5.0', pair, simultaneous="impulses", t_end=1.5))
    order = simulate(table_scene('boundary = "circle"\nradius = 5.0', pair, simultaneous="sequential", t_end=1.5))
    assert alone.state_final == order.state_final  # one contact alone is the scene's law under either policy
    assert alone.energy_final == pytest.approx(alone.energy_initial, rel=1e-14)
    skid = dict(ball("0.8", "0", "1", "0", mass="1"), wx=0, wy=0)  # sliding into a rolling cushion, k = 1
    rows = simulate(table_scene('boundary = "rectangle"\nwidth = 2.0\nheight = 1.0', [skid], law="newton",
                                t_end=0.2)).collision_table()
    assert rows["energy_after"][0] == pytest.approx(rows["energy_before"][0], rel=1e-14)
    # k = 0, slide model: its spin drives it into the wall; it skids along it (its slip ends at
    # t = 0.9 + 0.4/(mu g) with no tangential friction), rolls into the corner, stops there, pressed on by a spin
    # whose slip also ends (was: failed, "pressed against the cushion"; before the corner's ride, an overlap)
    pressed = simulate(table_scene('boundary = "rectangle"\nwidth = 2.0\nheight = 1.0', [ball("0", "0", "1", "0.3")],
                                   cushion="slide", cushion_k=0, t_end=10))
    assert pressed.status is Status.COMPLETED, pressed.message
    assert pressed.state_final[2:] == [0.0] * 4 and pressed.energy_final == 0
    assert pressed.state_final[:2] == pytest.approx([0.9, 0.4], abs=1e-12)  # in the corner (nudged off by ulps)
    t_roll = next(p[0] for p in pressed.paths if p[0] > 0.9 and p[1][4:6] == [0.0, 0.0])
    assert t_roll == pytest.approx(0.9 + 0.4 / (0.2 * 9.81), rel=1e-14)
    from heyroll.interfaces.table_figures import path_points
    riding = path_points(pressed)[0][1:]  # along the wall x = 0.9 to the corner, drawn as segments
    assert all(np.allclose(x, 0.9, atol=1e-12) for x, _y, _s in riding) and riding[-1][1][-1] == pytest.approx(0.4)
    graze = simulate(table_scene(ELLIPSE, [ball("0", "0", "1", "0.3")], cushion_k="0.3", simultaneous="impulses",
                                 t_end=30))
    assert graze.status is Status.COMPLETED and graze.n_collisions < 100  # it settles and rides (was: failed)
    assert graze.collision_table()["law_flag"][-1] == 4
    with pytest.raises(SceneError, match="kappa = 1"):
        table_scene('boundary = "circle"\nradius = 10.0',
                    [{"kappa": 1, "radius": "0.1", "mass": 1, "x": 0, "y": 0, "vx": 1, "vy": 0, "wx": 0, "wy": 0}])


def test_a_touching_rack_under_simultaneous_impulses_is_solved_quickly():
    """15 touching balls: 30 contacts at one instant, beyond the exact active-set search (Gauss-Seidel)."""
    import time

    r = 0.028575
    balls = [ball("-0.6", "0.0", "3.0", "0.0", radius=repr(r))]
    for row in range(5):
        for m in range(row + 1):
            balls.append(ball(repr(0.3 + row * math.sqrt(3) * r * (1 + 1e-14)), repr((m - row / 2) * 2 * r), "0",
                              "0", radius=repr(r)))
    scene = table_scene('boundary = "rectangle"\nwidth = 2.54\nheight = 1.27', balls, law="newton",
                        simultaneous="impulses", t_end=0.4)
    started = time.perf_counter()
    result = simulate(scene)
    assert time.perf_counter() - started < 30
    assert result.status is Status.COMPLETED
    assert result.energy_final == pytest.approx(result.energy_initial, rel=1e-12)


def test_a_particle_in_the_ellipse_runs_long():
    """A particle touching the ellipse at each impact is on it, not past it (the overlap check of balls)."""
    result = simulate(table_scene(ELLIPSE, [particle(0.3, -0.2, 1.0, 0.7)], law="newton", t_end=500))
    assert result.status is Status.COMPLETED and result.n_collisions > 250


@pytest.mark.parametrize("law", ["hedrih", "newton", "slide"])
def test_simultaneous_impulses_never_make_energy(law):
    """Found by a review: a heavy disk driven into a ball resting on a rolling cushion, under 'impulses' and the
    slide law: the pair's impulse (spin kept) and the cushion's (rolling kept) cancelled in the ball's v but not
    in its spin: 3.0 -> 9.13 J. Now a group with a sliding ball or a slide law is Newton's law on the masses,
    every spin kept: here the disk leaves at -k v (0.6 m/s) with its spin, the ball stays: 1.18 J (slide)."""
    rect = 'boundary = "rectangle"\nwidth = 2.0\nheight = 1.0'
    balls = [ball("0.0", "0.0", "2.0", "0.0", shape="disk", mass="1.0"), ball(repr(0.9 - 1e-12), "0", "0", "0")]
    result = simulate(table_scene(rect, balls, law=law, k="0.3", friction="0", simultaneous="impulses", t_end=0.6))
    table = result.collision_table()
    assert result.status is Status.COMPLETED
    assert np.all(table["energy_after"] <= table["energy_before"] * (1 + 1e-14))
    if law == "slide":
        assert result.energy_final == pytest.approx(0.5 * (0.6**2 + 0.5 * 2.0**2), rel=1e-12)
    # a sliding disk (spin given) and a sphere, Hedrih's law at k = 1 in an ellipse (+1.7e-3 J in one row)
    pair = [{"shape": "disk", "radius": "0.05", "mass": "0.05", "x": "-0.8636253641169541", "y": "-0.7626910878029183",
             "vx": "1.2260421186086627", "vy": "2.2212428462825162", "wx": "-44.424856925650325",
             "wy": "24.520842372173252"},
            {"shape": "solid_sphere", "radius": "0.05", "mass": "1.0", "x": "0.630780664627302",
             "y": "0.11253022047820749", "vx": "1.3219667366931893", "vy": "0.4058430693681317",
             "wx": "11.736951476123924", "wy": "-6.7296399224472125"}]
    result = simulate(table_scene(ELLIPSE, pair, law=law, k="1", cushion="slide", cushion_k="0.5",
                                  simultaneous="impulses", t_end=15))
    table = result.collision_table()
    assert np.all(table["energy_after"] - table["energy_before"] <= 1e-13 * result.energy_initial)


TRIANGLE = 'boundary = "polygon"\nvertices = [[-1.0, -0.6], [1.0, -0.6], [0.0, 1.0]]'


@pytest.mark.parametrize("law, cushion, k, k_c, mu, vx, vy, ux, uy", [
    ("newton", "slide", "0.9", "0", "1e-6", "-1.7554", "2.2787", "0", "0"),   # into the apex: pinned there
    ("slide", "slide", "1", "0", "0.5", "-0.3", "1.8", "0", "0"),               # a corner at k = 0
    ("mirror", "rolling", "1", "0", "0.01", "0.4", "1.6", "0", "0"),
    ("newton", "slide", "1", "0.3", "0.05", "0.3", "-0.2", "-1.0", "1.0"),      # review 2's triangle
])
def test_a_ball_in_an_acute_corner_stays_on_the_table(law, cushion, k, k_c, mu, vx, vy, ux, uy):
    """Random scenes and review 2, 60-degree corners: a ball riding one wall into the other at k_c = 0 was passed
    between them 10,000 times at one instant (velocities into denormals, 'inelastic collapse'), or friction drove
    it into the corner along one wall while drawing it from the other and it slid through that one (overlap,
    up to 0.11 m). Now a ball meeting two walls is one simultaneous solution, a round-off approach is no impact,
    and a sliding ball at rest in a corner is pinned there or rides the wall its friction presses into."""
    from test_cushion_riding import slipping

    start = slipping(-0.36033, -0.13482, float(vx), float(vy), float(ux or 0), float(uy or 0), radius=0.1)
    if ux == "0" and uy == "0":
        start = ball("-0.36033", "-0.13482", vx, vy)
    result = simulate(table_scene(TRIANGLE, [start], law=law, k=k, cushion=cushion, cushion_k=k_c, friction=mu,
                                  t_end=30))
    assert result.status is Status.COMPLETED, result.message
    assert result.n_collisions < 500
    table = result.collision_table()
    assert np.all(table["energy_after"] <= table["energy_before"] * (1 + 1e-15) + 1e-16)


@pytest.mark.parametrize("t_end", [2.0, 1.0, 20.0])
def test_a_head_on_impact_is_not_lost_where_its_exit_root_is_round(t_end):
    """Acceptance test: a ball at x = -0.8 rolling at 1 m/s into one at rest at 0 (D = 0.2): the pair's gap
    |dc|^2 - D^2 has roots 0.6 and 1.0; in one step over [0, 2] (or [0, 1]) heyoka 7.13 lost the first when the
    second lay exactly on the step's midpoint or end: no impact, the ball passed through the other, 'completed'.
    The event is now 16 ulps of (R_i + R_j)^2 inside the contact and the instant polished back onto it."""
    big = 'boundary = "rectangle"\nwidth = 4.0\nheight = 2.0'
    balls = [ball("-0.8", "0", "1", "0", mass="1"), ball("0", "0", "0", "0", mass="1")]
    result = simulate(table_scene(big, balls, t_end=t_end))
    table = result.collision_table()
    assert result.status is Status.COMPLETED and table["t"][0] == 0.6 and (table["i"][0], table["j"][0]) == (1, 2)
    assert result.state_final[0] < result.state_final[6]  # never passed through


def test_two_particles_at_one_point_are_no_contact():
    """Random scenes: two particles stopped in the same corner (k_c = 0) coincided; the contact between them had
    no direction (0/0: a ZeroDivisionError, or NaN in the vector path and heyoka's state non-finite). Two points
    at one place do not meet; two finite balls at one centre still overlap (any normal)."""
    from heyroll.simulation.precision import DOUBLE
    from heyroll.simulation.table.contacts import ContactGeometry
    from heyroll.simulation.table.system import table_system

    rect = 'boundary = "rectangle"\nwidth = 2.0\nheight = 1.0'
    for pair in ([particle("-0.5", "0", "1", "0"), particle("0.5", "0", "0", "1")],
                 [ball("-0.5", "0", "1", "0"), ball("0.5", "0", "0", "1")]):
        scene = table_scene(rect, pair, law="newton")
        geometry = ContactGeometry(scene, table_system(scene, DOUBLE), DOUBLE)
        state = [0.3, 0.2, 1.0, 0.0, 0.0, 0.0, 0.3, 0.2, 0.0, 1.0, 0.0, 0.0]
        contacts = geometry.contacts(state, geometry.touch)
        if pair[0]["radius"] == 0:
            assert contacts == []
        else:
            assert len(contacts) == 1 and contacts[0].distance < -geometry.overlap


def test_polygon_vertices_are_the_scene_decimals_not_doubles():
    """Review: PolygonBoundary.make rounded each vertex to 53 bits (mpmath.mpf outside workprec), so long,
    quad and mp runs met a triangle 2e-17 m off the scene's: impact times off by up to 8e-16 in quad."""
    scene = table_scene('boundary = "polygon"\nvertices = [[0, 0], [3, 0], [0.4, 0.9]]', [ball("1.0", "0.3", "1", "0")])
    with mpmath.workprec(256):
        for (x, y), (dx, dy) in zip(scene.boundary.vertices, [("0", "0"), ("3", "0"), ("0.4", "0.9")]):
            assert abs(x - mpmath.mpf(dx)) < mpmath.mpf(2) ** -250
            assert abs(y - mpmath.mpf(dy)) < mpmath.mpf(2) ** -250
