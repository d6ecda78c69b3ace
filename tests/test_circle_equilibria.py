"""Relative equilibria, bifurcations and the portrait of a body in a circle (the bead on a turning hoop).

A body of radius r in a circle of radius R keeps its centre on the circle of
radius rho = R - r: x_C = rho sin(phi), y_C = -rho cos(phi). In a vertical
plane turning at Omega about the vertical line x = a the effective potential
per unit mass is V/m = g y_C - 1/2 Omega^2 (x_C - a)^2, and

    dV/dphi / (m rho) = g sin(phi) - Omega^2 (rho sin(phi) - a) cos(phi).

The checks below solve that in mpmath at 30 digits, here in the test, from
the closed forms only (never through heyroll's model, analysis or reference).
"""

from __future__ import annotations

import json
import math

import mpmath
import numpy as np
import pytest

from heyroll.analysis.equilibria import EquilibriumProblem, bifurcations, find_equilibria, problem_of
from heyroll.interfaces.cli import main
from heyroll.interfaces.scene_file import default_scene_text, parse_scene
from heyroll.model.bodies import Body
from heyroll.model.frame import Frame
from heyroll.model.tracks import ArcChainTrack, CircleTrack, Segment

G = 9.81
R = "1.3"
BODIES = {
    "disk": Body.of_shape("disk", "0.12", mass="2"),
    "ring": Body.of_shape("ring", "0.12", mass="0.7"),
    "particle": Body.of_shape("particle", 0, mass="1"),
}
DIGITS = 30


def problem(body="disk", omega=0, a=0):
    return EquilibriumProblem(CircleTrack.of_radius(R), BODIES[body], Frame.make(omega, a), G)


def rho_of(body):
    return mpmath.mpf(R) - BODIES[body].radius


def angle_gap(p, q):
    """Distance of two angles round the circle."""
    return abs(math.remainder(float(p) - float(q), 2 * math.pi))


def assert_listed_once_in_range(eq):
    qs = [e.q for e in eq]
    assert all(-math.pi <= q < math.pi for q in qs)
    assert qs == sorted(qs)
    assert all(angle_gap(p, q) > 1e-9 for i, p in enumerate(qs) for q in qs[i + 1:])


def mp_roots(body, omega, a):
    """Every root of g sin(phi) = Omega^2 (rho sin(phi) - a) cos(phi) on the circle, at 30 digits,
    with the sign of d/dphi of the left minus the right (> 0: a centre)."""
    with mpmath.workdps(DIGITS):
        rho, w, a, g = rho_of(body), mpmath.mpf(omega) ** 2, mpmath.mpf(a), mpmath.mpf(G)

        def h(phi):
            return g * mpmath.sin(phi) - w * (rho * mpmath.sin(phi) - a) * mpmath.cos(phi)

        # brackets from a scan that does not start on the top (so no root sits on its ends)
        nodes = [-mpmath.pi + mpmath.mpf("0.0123") + 2 * mpmath.pi * k / 2000 for k in range(2001)]
        values = [h(p) for p in nodes]
        out = []
        for p0, p1, v0, v1 in zip(nodes, nodes[1:], values, values[1:]):
            if v0 * v1 < 0:
                root = mpmath.findroot(h, (p0, p1), solver="anderson")
                root = root - 2 * mpmath.pi * mpmath.floor((root + mpmath.pi) / (2 * mpmath.pi))
                out.append((root, mpmath.diff(h, root) > 0))
        return sorted(out)


# ------------------------------------------------------------------ equilibria

@pytest.mark.parametrize("body", sorted(BODIES))
@pytest.mark.parametrize("a", [0, "0.3"])
def test_fixed_plane_bottom_is_a_centre_and_the_top_a_saddle(body, a):
    eq = find_equilibria(problem(body, 0, a))
    assert [e.type for e in eq] == ["saddle", "center"]
    top, bottom = eq
    assert top.q == -math.pi and abs(bottom.q) <= 1e-12  # the top once, as -pi
    assert abs(top.x) < 1e-12 and abs(bottom.x) < 1e-12
    rho = float(rho_of(body))
    assert top.potential == pytest.approx(G * rho, rel=1e-15)
    assert bottom.potential == pytest.approx(-G * rho, rel=1e-15)
    # V'' = m rho h': h' = g at the bottom, -g at the top
    assert bottom.stiffness == pytest.approx(G, rel=1e-15) and top.stiffness == pytest.approx(-G, rel=1e-15)


@pytest.mark.parametrize("body", sorted(BODIES))
@pytest.mark.parametrize("factor", ["0.5", "0.999", "1.001", "2", "10"])
def test_turning_hoop_centres_at_the_closed_form(body, factor):
    rho = rho_of(body)
    with mpmath.workdps(DIGITS):
        omega = mpmath.sqrt(mpmath.mpf(factor) * G / rho)
        side = mpmath.acos(G / (rho * omega**2)) if mpmath.mpf(factor) > 1 else None
    eq = find_equilibria(problem(body, float(omega), 0))
    assert_listed_once_in_range(eq)
    if side is None:  # below the pitchfork: the bottom holds
        assert [(e.type, e.q) for e in eq] == [("saddle", -math.pi), ("center", pytest.approx(0, abs=1e-12))]
        return
    assert [e.type for e in eq] == ["saddle", "center", "saddle", "center"]
    assert eq[0].q == -math.pi and abs(eq[2].q) <= 1e-12
    assert abs(eq[1].q + side) <= 1e-12 and abs(eq[3].q - side) <= 1e-12
    assert abs(eq[3].x - float(mpmath.mpf(R) * mpmath.sin(side))) <= 1e-12
    # V/m at the side centres: -g rho cos - 1/2 Omega^2 rho^2 sin^2
    with mpmath.workdps(DIGITS):
        v = -G * rho * mpmath.cos(side) - omega**2 * (rho * mpmath.sin(side)) ** 2 / 2
    assert eq[3].potential == pytest.approx(float(v), rel=1e-13, abs=1e-13)


@pytest.mark.parametrize("body", ["disk", "particle"])
@pytest.mark.parametrize("omega, a", [("1.5", "0.3"), ("4", "0.2"), ("4", "-0.2"), ("7", "0.05"), ("3", "-1.0"),
                                      ("9", "2.0")])
def test_off_axis_equilibria_against_mpmath_findroot(body, omega, a):
    eq = find_equilibria(problem(body, omega, a))
    assert_listed_once_in_range(eq)
    ref = mp_roots(body, omega, a)
    assert len(eq) == len(ref) and len(eq) % 2 == 0
    for e in eq:  # every engine root is one of the reference's, to 1e-12, of the same type
        root, centre = min(ref, key=lambda rc: angle_gap(rc[0], e.q))
        assert angle_gap(root, e.q) <= 1e-12
        assert e.type == ("center" if centre else "saddle")
        assert abs(e.x - float(mpmath.mpf(R) * mpmath.sin(root))) <= 1e-12


def test_equilibria_do_not_depend_on_kappa():
    a = find_equilibria(problem("disk", 5, "0.1"))
    b = find_equilibria(problem("ring", 5, "0.1"))
    assert [(e.q, e.type) for e in a] == [(e.q, e.type) for e in b]


def test_circle_agrees_with_the_same_circle_as_one_concave_arc():
    """One concave arc from the top round to the top, centred like the circle: the same points
    (off the top, which is not on the arc's limiters when a != 0)."""
    circle = find_equilibria(problem("disk", 5, "0.1"))
    Rm = mpmath.mpf(R)
    chain = ArcChainTrack.make([Segment("arc", Rm, "concave", -mpmath.pi, mpmath.pi)], start_x=0, start_y=Rm)
    arcs = find_equilibria(EquilibriumProblem(chain, BODIES["disk"], Frame.make(5, "0.1"), G))
    assert len(circle) == len(arcs) == 4
    for f in arcs:
        e = min(circle, key=lambda e: abs(e.x - f.x) + abs(e.potential - f.potential))
        assert e.type == f.type and abs(e.x - f.x) <= 1e-12 and abs(e.potential - f.potential) <= 1e-12
        rho = float(rho_of("disk"))
        assert angle_gap(e.q, f.q / rho - math.pi) <= 1e-12  # s = rho (phi + pi)


# ----------------------------------------------------------------- bifurcations

@pytest.mark.parametrize("body", ["disk", "particle"])
def test_pitchfork_at_sqrt_g_over_rho(body):
    found = bifurcations(problem(body, 0, 0), np.linspace(0, 8, 81))
    assert len(found) == 1
    b = found[0]
    assert abs(b.omega - math.sqrt(G / float(rho_of(body)))) < 1e-6
    assert (b.before, b.after) == (2, 4) and abs(b.q) < 1e-6 and abs(b.x) < 1e-6


def test_off_axis_fold_against_mpmath():
    """a != 0 breaks the pitchfork: a saddle-node (h = h_phi = 0) where two equilibria are born."""
    found = bifurcations(problem("disk", 0, "0.2"), np.linspace(0, 8, 81))
    assert len(found) == 1 and (found[0].before, found[0].after) == (2, 4)
    with mpmath.workdps(DIGITS):
        rho, a, g = rho_of("disk"), mpmath.mpf("0.2"), mpmath.mpf(G)

        def system(phi, w):
            s, c = mpmath.sin(phi), mpmath.cos(phi)
            return [g * s - w * (rho * s - a) * c, g * c - w * (rho * mpmath.cos(2 * phi) + a * s)]

        phi, w = mpmath.findroot(system, (mpmath.mpf(found[0].q), mpmath.mpf(found[0].omega) ** 2))
    assert abs(found[0].omega - float(mpmath.sqrt(w))) < 1e-6
    assert abs(found[0].q - float(phi)) < 1e-4


# -------------------------------------------------------------------------- CLI

def circle_scene(tmp_path, frame=""):
    path = tmp_path / "circle.toml"
    path.write_text(default_scene_text() + frame)
    return path


def test_cli_equilibria_on_a_circle(tmp_path, capsys):
    path = circle_scene(tmp_path)
    assert main(["equilibria", str(path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[1].split()[:3] == ["x", "type", "phi"]
    rows = [line.split() for line in lines[2:]]
    assert [r[1] for r in rows] == ["saddle", "center"]
    assert float(rows[0][2]) == -math.pi and float(rows[1][2]) == 0
    assert main(["equilibria", str(path), "--json", "--body", "2"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [sorted(d) for d in data] == [["type", "x"]] * 2
    assert [d["type"] for d in data] == ["saddle", "center"]


def test_cli_equilibria_on_a_turning_circle(tmp_path, capsys):
    path = circle_scene(tmp_path, "\n[frame]\nomega = 5.0\naxis_x = 0.0\n")
    assert main(["equilibria", str(path), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [d["type"] for d in data] == ["saddle", "center", "saddle", "center"]
    scene = parse_scene(path.read_text())
    rho = float(scene.track.path_radius(scene.bodies[0]))
    side = math.acos(G / (rho * 25))
    assert data[3]["x"] == pytest.approx(float(scene.track.radius) * math.sin(side), abs=1e-12)


@pytest.mark.parametrize("command", ["equilibria", "portrait"])
@pytest.mark.parametrize("value", ["0", "3", "x", "-1", "1.5"])
def test_cli_bad_body_on_a_circle_exits_2_with_one_line(tmp_path, capsys, command, value):
    path = circle_scene(tmp_path)
    out = tmp_path / "o"
    extra = ["--out", str(out)] if command == "portrait" else []
    assert main([command, str(path), "--body", value, *extra]) == 2
    captured = capsys.readouterr()
    assert "--body" in captured.err and captured.err.count("\n") == 1 and captured.out == ""
    assert not out.exists()


@pytest.mark.parametrize("frame, count", [("", 2), ("\n[frame]\nomega = 4.0\naxis_x = 0.0\n", 4),
                                          ("\n[frame]\nomega = 4.0\naxis_x = 0.2\n", 2)])
def test_cli_portrait_on_a_circle(tmp_path, capsys, frame, count):
    path = circle_scene(tmp_path, frame)
    out = tmp_path / "p"
    assert main(["portrait", str(path), "--out", str(out), "--progress", "on"]) == 0
    printed = capsys.readouterr()
    assert "portrait: 100%" in printed.err
    assert {p.name for p in out.iterdir()} == {"portrait.png", "energy_surface.png", "bifurcation.png",
                                               "portrait.json"}
    assert all((out / f).stat().st_size > 0 for f in ("portrait.png", "energy_surface.png", "bifurcation.png"))
    data = json.loads((out / "portrait.json").read_text())
    assert data["track"] == "circle" and data["coordinate"] == "phi"
    assert len(data["equilibria"]) == count
    assert all(-math.pi <= e["q"] < math.pi for e in data["equilibria"])
    assert data["check"]["integrated_trajectories"] >= 3
    assert data["check"]["worst_relative_first_integral_drift"] < 1e-12
    assert len(data["bifurcations"]) == 1
    scene = parse_scene(path.read_text())
    rho = float(scene.track.path_radius(scene.bodies[0]))
    if float(scene.frame.axis_x) == 0:
        assert abs(data["bifurcations"][0]["omega"] - math.sqrt(G / rho)) < 1e-6
    # the separatrix through the top (the highest point, a saddle): H/m = V/m there
    top = max(data["equilibria"], key=lambda e: e["potential_per_mass"])
    assert top["type"] == "saddle" and abs(abs(top["q"]) - math.pi) < 0.2
    assert top["potential_per_mass"] in data["separatrix_levels_per_mass"]
    assert "phi = " in printed.out


def test_problem_of_a_circle_scene_uses_its_frame_and_gravity():
    scene = parse_scene(default_scene_text().replace("g = 9.81", "g = 3.7") + "\n[frame]\nomega = 3\naxis_x = 0\n")
    p = problem_of(scene, 1)
    rho = float(scene.track.path_radius(scene.bodies[1]))
    eq = find_equilibria(p)
    assert p.g == 3.7 and [e.type for e in eq] == ["saddle", "center", "saddle", "center"]
    assert eq[3].q == pytest.approx(math.acos(3.7 / (rho * 9)), abs=1e-12)
