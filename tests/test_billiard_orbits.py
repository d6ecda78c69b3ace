"""Periodic orbits of billiard tables (heyroll billiard orbits): closed forms and the engine's own runs."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from heyroll.analysis.billiard_orbits import periodic_orbits
from heyroll.simulation.driver import simulate

from test_billiards import ELLIPSE, TABLE, ball, particle, table_scene, write


def two_orbit_trace(chord, rho):
    """The 2-bounce orbit between two points of equal curvature radius rho: tr = 4 (1 - chord/rho)^2 - 2."""
    return 4 * (1 - chord / rho) ** 2 - 2


@pytest.mark.parametrize("radius", ["0", "0.1", "0.3"])
def test_the_two_period_two_orbits_of_the_ellipse_and_their_stability(radius):
    a, b, r = 2.0, 1.0, float(radius)
    body = particle(0.3, -0.2, 1, 0.7) if r == 0 else ball("0.3", "-0.2", "1", "0.7", radius=radius)
    major, minor = periodic_orbits(table_scene(ELLIPSE, [body]), 2)
    assert (major.kind, minor.kind) == ("max", "minimax")
    assert major.perimeter == pytest.approx(4 * (a - r), rel=1e-14)
    assert minor.perimeter == pytest.approx(4 * (b - r), rel=1e-14)
    # the centre's curve has the ellipse's radii of curvature less R: b^2/a - R at the major axis' ends
    assert major.trace == pytest.approx(two_orbit_trace(2 * (a - r), b * b / a - r), rel=1e-8)
    assert minor.trace == pytest.approx(two_orbit_trace(2 * (b - r), a * a / b - r), rel=1e-8, abs=1e-9)
    assert (major.stability, minor.stability) == ("unstable", "stable")


def test_poncelet_families_of_a_particle_have_one_perimeter():
    orbits4 = periodic_orbits(table_scene(ELLIPSE, [particle(0.3, -0.2, 1, 0.7)]), 4)
    assert len(orbits4) == 1 and orbits4[0].kind == "family" and orbits4[0].stability == "parabolic"
    assert orbits4[0].perimeter == pytest.approx(4 * math.sqrt(5), rel=1e-13)  # the rhombus through the vertices
    orbits3 = periodic_orbits(table_scene(ELLIPSE, [particle(0.3, -0.2, 1, 0.7)]), 3)
    assert len(orbits3) == 1 and orbits3[0].kind == "family"


def test_a_finite_ball_breaks_the_families_and_the_engine_closes_the_orbits():
    scene = table_scene(ELLIPSE, [ball("0.3", "-0.2", "1", "0.7")])
    orbits = periodic_orbits(scene, 4)
    assert {o.kind for o in orbits} == {"max", "minimax"}
    assert all(o.stability != "parabolic" for o in orbits)
    for orbit in orbits:
        p0, p1 = orbit.points[0], orbit.points[1]
        mid = (p0 + p1) / 2
        d = (p1 - p0) / np.linalg.norm(p1 - p0)
        run = table_scene(ELLIPSE, [ball(repr(float(mid[0])), repr(float(mid[1])), repr(float(d[0])), repr(float(d[1])))], max_collisions=8)
        table = simulate(run, t_end=1e3).collision_table()
        # the ball hits the orbit's vertices in turn: p1, p2, ..., then p1 again
        centres = np.stack([table["x_i"], table["y_i"]], 1)
        expected = np.roll(orbit.points, -1, axis=0)
        assert np.max(np.abs(centres[:4] - expected)) < 1e-9
        assert np.max(np.abs(centres[4:8] - expected)) < 1e-6 if orbit.stability == "unstable" else 1e-9
        assert table["t"][4] - table["t"][0] == pytest.approx(orbit.perimeter, rel=1e-9)  # unit speed: time = length


def test_the_cli_lists_orbits_and_refuses_bad_periods(tmp_path):
    path = write(tmp_path, TABLE)
    out = subprocess.run([sys.executable, "-m", "heyroll.interfaces.cli", "billiard", "orbits", str(path),
                          "--period", "2", "--json", "--progress", "on"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "orbits: 100%" in out.stderr  # a bar over the searches (a polygon's period 8 took 39 s with none)
    orbits = json.loads(out.stdout)
    assert [o["stability"] for o in orbits] == ["unstable", "stable"]
    bad = subprocess.run([sys.executable, "-m", "heyroll.interfaces.cli", "billiard", "orbits", str(path),
                          "--period", "1"], capture_output=True, text=True)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "--period" in bad.stderr


def test_the_birkhoff_portrait_of_a_circle_keeps_each_launch_at_one_angle(tmp_path):
    """In a circular table every reflection angle of a launch is the same (angular momentum about the centre)."""
    from heyroll.analysis.billiard_portrait import birkhoff_portrait

    scene = table_scene('boundary = "circle"\nradius = 1.0', [ball("0.2", "0.1", "0.6", "0.9")])
    launches = birkhoff_portrait(scene, runs=5, impacts=50)
    for run in launches:
        assert run["status"] == "max_collisions" and len(run["s"]) == 50
        assert np.ptp(run["sin_angle"]) < 1e-12
        assert run["sin_angle"][0] == pytest.approx(run["p"], abs=1e-8)
    path = write(tmp_path, TABLE)
    out = subprocess.run([sys.executable, "-m", "heyroll.interfaces.cli", "billiard", "portrait", str(path),
                          "--runs", "3", "--impacts", "20", "--out", str(tmp_path / "bp"), "--progress", "on"],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "birkhoff: 100%" in out.stderr and "3/3" in out.stderr
    rows = (tmp_path / "bp" / "birkhoff_portrait.csv").read_text().splitlines()
    assert rows[0] == "run,theta,p,n,boundary_s,sin_reflection_angle" and len(rows) == 1 + 3 * 20
    assert (tmp_path / "bp" / "birkhoff_portrait.png").stat().st_size > 0


def test_the_birkhoff_portrait_of_a_dissipative_table_ends_where_each_launch_settles():
    """k < 1: a launch's ball settles onto the cushion and rides it (no impact comes any more): the launch ends
    at its time bound with fewer points, its reflection angles drawn towards grazing (was: never ended)."""
    from heyroll.analysis.billiard_portrait import birkhoff_portrait

    scene = table_scene('boundary = "circle"\nradius = 1.0', [ball("0.2", "0.1", "0.6", "0.9")], cushion_k="0.5")
    launches = birkhoff_portrait(scene, runs=4, impacts=200)  # p = +-0.2375, +-0.7125: none head-on
    for run in launches:
        assert run["status"] == "completed" and 5 < len(run["s"]) < 200
        assert abs(run["sin_angle"][-1]) > 0.999 > abs(run["sin_angle"][0])


# -- polygonal tables: orbits by their sequences of sides ----------------------------------------------------

RECTANGLE = 'boundary = "rectangle"\nwidth = 3.0\nheight = 2.0'
ACUTE = 'boundary = "polygon"\nvertices = [[0.0, 0.0], [4.0, 0.0], [1.5, 3.0]]'


def orthic_perimeter(corners):
    """Fagnano's orbit, the orthic triangle of an acute triangle: its perimeter is 2 area / circumradius."""
    a, b, c = (np.linalg.norm(corners[(k + 1) % 3] - corners[(k + 2) % 3]) for k in range(3))
    (x0, y0), (x1, y1), (x2, y2) = corners
    area = abs((x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0)) / 2
    return 2 * area / (a * b * c / (4 * area))


@pytest.mark.parametrize("radius", ["0", "0.1"])
def test_a_rectangle_has_families_of_parallel_orbits_with_the_unfolded_lengths(radius):
    """Unfolded, an orbit of a W x H rectangle (W, H of the centre's rectangle) is a straight segment to a
    lattice point (2 a W, 2 b H): period 2 (a + b) and perimeter 2 sqrt((a W)^2 + (b H)^2), one family of
    parallel orbits for each (a, b) coprime; those of period 6 pass 12 corners (rotation 3)."""
    r = float(radius)
    body = particle(0.3, -0.2, 1, 0.7) if r == 0 else ball("0.3", "-0.2", "1", "0.7", radius=radius)
    scene = table_scene(RECTANGLE, [body])
    w, h = 3 - 2 * r, 2 - 2 * r
    two = periodic_orbits(scene, 2)
    assert [o.perimeter for o in two] == pytest.approx([2 * w, 2 * h], rel=1e-14)
    four = periodic_orbits(scene, 4)
    assert [(o.rotation, o.perimeter) for o in four] == [(1, pytest.approx(2 * math.hypot(w, h), rel=1e-14))]
    six = periodic_orbits(scene, 6)
    assert [(o.rotation, o.perimeter) for o in six] == [(3, pytest.approx(2 * math.hypot(2 * w, h), rel=1e-14)),
                                                        (3, pytest.approx(2 * math.hypot(w, 2 * h), rel=1e-14))]
    for o in two + four + six:
        assert (o.kind, o.stability) == ("family", "parabolic") and o.trace == pytest.approx(2, abs=1e-6)
    assert periodic_orbits(scene, 6, rotation=1) == [] and periodic_orbits(scene, 3) == []


@pytest.mark.parametrize("radius", ["0", "0.2"])
def test_fagnanos_orbit_of_an_acute_triangle_and_the_engine_runs_it(radius):
    """The only period-3 orbit of an acute triangle is Fagnano's, the orthic triangle of the centre's triangle:
    the inscribed triangle of least perimeter (kind min), isolated, parabolic with trace -2 (a parallel orbit
    beside it closes after 6 impacts, mirrored). The engine launched along it hits its vertices in turn."""
    r = float(radius)
    body = particle(1.5, 1.0, 1, 0.7) if r == 0 else ball("1.5", "1.0", "1", "0.7", radius=radius)
    scene = table_scene(ACUTE, [body])
    (orbit,) = periodic_orbits(scene, 3)
    corners = scene.boundary.centre_polygon(scene.balls[0].body.radius)
    assert orbit.perimeter == pytest.approx(orthic_perimeter(corners), rel=1e-13)
    assert (orbit.kind, orbit.stability, orbit.rotation) == ("min", "parabolic", 1)
    assert orbit.trace == pytest.approx(-2, abs=1e-6)
    p0, p1 = orbit.points[0], orbit.points[1]
    mid, d = (p0 + p1) / 2, (p1 - p0) / np.linalg.norm(p1 - p0)
    launch = particle(*(repr(float(v)) for v in (*mid, *d))) if r == 0 else \
        ball(*(repr(float(v)) for v in (*mid, *d)), radius=radius)
    table = simulate(table_scene(ACUTE, [launch], max_collisions=9), t_end=1e3).collision_table()
    centres = np.stack([table["x_i"], table["y_i"]], 1)
    assert np.max(np.abs(centres - np.tile(np.roll(orbit.points, -1, axis=0), (3, 1)))) < 1e-12
    assert table["t"][3] - table["t"][0] == pytest.approx(orbit.perimeter, rel=1e-13)


def test_a_right_triangle_has_no_fagnano_orbit_and_rotations_are_checked(tmp_path):
    right = 'boundary = "polygon"\nvertices = [[0.0, 0.0], [3.0, 0.0], [0.0, 2.0]]'
    assert periodic_orbits(table_scene(right, [particle(0.5, 0.5, 1, 0.7)]), 3) == []
    with pytest.raises(ValueError, match="--rotation"):
        periodic_orbits(table_scene(ELLIPSE, [particle(0.3, -0.2, 1, 0.7)]), 6, rotation=3)  # gcd on a smooth table
    path = write(tmp_path, TABLE.replace('boundary = "ellipse"\na = 2.0\nb = 1.0', RECTANGLE))
    assert RECTANGLE in path.read_text()
    out = subprocess.run([sys.executable, "-m", "heyroll.interfaces.cli", "billiard", "orbits", str(path),
                          "--period", "6", "--json"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert [(o["rotation"], o["kind"]) for o in json.loads(out.stdout)] == [(3, "family"), (3, "family")]


def test_a_family_whose_newton_start_diverges_is_found_and_long_periods_are_refused():
    """A 4 x 2 rectangle, period 6: the (2, 1) family's side sequence sent undamped Newton steps from the sides'
    middles to t ~ 1e9 (acceptance test: only the (1, 2) family was listed); period 100000 ended in a
    RecursionError, period 10 ran for minutes."""
    scene = table_scene('boundary = "rectangle"\nwidth = 4.0\nheight = 2.0', [particle(0.3, -0.2, 1, 0.7)])
    assert [o.perimeter for o in periodic_orbits(scene, 6)] == pytest.approx([2 * math.hypot(8, 2),
                                                                              2 * math.hypot(4, 4)], rel=1e-13)
    for period in (9, 100000):
        with pytest.raises(ValueError, match="--period"):
            periodic_orbits(scene, period)
