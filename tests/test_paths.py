"""Path tracks (paper sections 5-6): arc chains, curves y = f(x), rotating plane."""

from __future__ import annotations

import json
from pathlib import Path
import math

import mpmath
import numpy as np
import pytest

import heyroll
from heyroll.analysis.equilibria import EquilibriumProblem, bifurcations, find_equilibria, problem_of
from heyroll.errors import SceneError
from heyroll.interfaces.cli import main
from heyroll.interfaces.scene_file import default_scene, default_scene_text, parse_scene
from heyroll.model import expression as ex
from heyroll.model.bodies import Body
from heyroll.model.frame import Frame
from heyroll.model.tracks import ArcChainTrack, CurveTrack, Segment, ThreeArcTrack
from heyroll.model.tracks.curve import MPMATH
from heyroll.model.scene import RunSettings, Scene
from heyroll.model.tracks import CircleTrack
from heyroll.reference.equilibria import equilibrium_roots
from heyroll.interfaces.portrait_figures import body_energy
from heyroll.simulation.driver import simulate

README_CURVE = """
[track]
type = "curve"
y = "0.5*x**2*(x**2 - 1)**2"    # metres, x in metres
x_min = -1.6
x_max = 1.6

[frame]
omega = 3.0                      # rad/s, rotation of the vertical plane about a vertical axis
axis_x = 0.0                     # where that axis crosses the x axis (eccentricity)

[[bodies]]
shape = "disk"
radius = 0.05
mass = 1.0
x = 0.3                          # abscissa of the contact point
dx = 0.0
"""

#: The paper's three example curves (section 5.3), with our choice of constants.
PAPER_CURVES = {
    "k x^2 (x^2 - a^2)^2": "0.5*x**2*(x**2 - 1)**2",
    "k x^2 (x^2 - a^2)^2 (x^2 - b^2)": "0.02*x**2*(x**2 - 1)**2*(x**2 - 4)",
    "-k x^2 (x^2 - a^2) [c^4 - (x^2 - b^2)^2]": "-0.1*x**2*(x**2 - 1)*(16 - (x**2 - 4)**2)",
}

DISK = Body.of_shape("disk", "0.05", mass="1")


# ------------------------------------------------------------------ expressions

@pytest.mark.parametrize("text", ["0.5*x**2*(x**2 - 1)**2", "sin(x) + cos(2*x)", "exp(-x**2)", "sqrt(1 + x**2)",
                                  "-x", "2**3*x", "1e-1*x**2", ".5*x"])
def test_expression_derivatives_agree_with_mpmath_numerical_differentiation(text):
    node = ex.parse(text)
    for x in (mpmath.mpf("-0.7"), mpmath.mpf("0.3"), mpmath.mpf("1.1")):
        with mpmath.workdps(40):
            f = lambda t: ex.evaluate(node, t, MPMATH)  # noqa: E731
            for order, d in ((1, ex.derivative(node)), (2, ex.derivative(ex.derivative(node)))):
                exact = mpmath.diff(f, x, order)
                mine = ex.evaluate(d, x, MPMATH)
                assert abs(mine - exact) <= mpmath.mpf(10) ** -30 * max(1, abs(exact))


@pytest.mark.parametrize("text, fragment", [
    ("__import__('os')", "unknown name"), ("x.real", "not allowed"), ("a*x", "unknown name"),
    ("2**x", "exponent"), ("(x + 1", "ends too early"), ("x + ", "ends too early"), ("", "empty"),
    ("x; 1", "not allowed"), ("log(x)", "unknown name"), ("x)", "unexpected"),
])
def test_bad_expressions_are_one_line_scene_errors(text, fragment):
    with pytest.raises(SceneError) as info:
        CurveTrack.make(text, -1, 1)
    assert fragment in str(info.value) and "\n" not in str(info.value)
    assert info.value.field == "track.y"


def test_expression_text_round_trips():
    node = ex.parse("-0.5*x**2*(x**2 - 1)*(16 - (x**2 - 4)**2)")
    assert ex.parse(ex.to_text(node)) == node


# ----------------------------------------------------------------- geometry

def test_curve_rejects_a_body_larger_than_a_hollow():
    # y = 5 x^2: radius of curvature 1/10 m at the bottom
    with pytest.raises(SceneError, match=r"bodies\[1\]\.radius.*radius of curvature falls to 0\.1"):
        Scene.make(CurveTrack.make("5*x**2", -1, 1), [Body.of_shape("disk", "0.2", mass=1)], [0.5], [0])


def test_curve_that_is_not_finite_on_its_range_is_rejected():
    with pytest.raises(SceneError, match="track.y: y is not finite"):
        CurveTrack.make("sqrt(x)", -1, 1)


def test_arc_chain_rejects_tangents_that_do_not_match():
    segs = [Segment("arc", mpmath.mpf(1), "concave", -mpmath.pi / 2, mpmath.mpf("0.5")),
            Segment("line", angle=mpmath.mpf("0.6"), length=mpmath.mpf(1))]
    with pytest.raises(SceneError, match=r"segments\[2\]\.start: tangent does not match"):
        ArcChainTrack.make(segs)


def test_arc_chain_rejects_a_body_larger_than_a_concave_arc():
    track = ThreeArcTrack.make("0.1", "0.5", "0.2")
    with pytest.raises(SceneError, match=r"bodies\[1\]\.radius: must be < the radius of concave segment 1"):
        Scene.make(track, [Body.of_shape("disk", "0.1", mass=1)], [0.05], [0])


def test_three_arcs_geometry_is_continuous_and_has_the_paper_central_angles():
    R, R0, beta = mpmath.mpf(1), mpmath.mpf("0.5"), mpmath.mpf("0.2")
    track = ThreeArcTrack.make(R, R0, beta)
    spans = [s.end - s.start for s in track.segments]
    assert [float(x) for x in spans] == pytest.approx(
        [float(3 * mpmath.pi / 2 - beta), float(mpmath.pi - 2 * beta), float(3 * mpmath.pi / 2 - beta)], rel=1e-15)
    pieces = track.pieces(DISK)
    for a, b in zip(pieces, pieces[1:]):
        xa, ya = a.centre(a.s1)
        xb, yb = b.centre(b.s0)
        assert abs(xa - xb) < 1e-15 and abs(ya - yb) < 1e-15
        assert abs(math.remainder(a.alpha(a.s1) - b.alpha0, 2 * math.pi)) < 1e-15


def test_stationary_circle_scene_is_unchanged_by_an_empty_frame():
    text = default_scene_text() + "\n[frame]\nomega = 0\n"
    scene = parse_scene(text)
    assert isinstance(scene, Scene) and scene == default_scene()


def test_rotating_circle_runs_like_one_concave_arc():
    """A circle in a turning plane (the Lagrangian default) and the same circle as one arc agree."""
    text = default_scene_text().replace("max_collisions = ", "max_collisions = 0 #") + "\n[frame]\nomega = 2\naxis_x = 0.1\n"
    circle = parse_scene(text)
    R = circle.track.radius
    chain = ArcChainTrack.make([Segment("arc", R, "concave", -mpmath.pi, mpmath.pi)], start_x=0, start_y=-R)
    s = [(R - b.radius) * (p + mpmath.pi) for b, p in zip(circle.bodies, circle.q)]
    v = [(R - b.radius) * d for b, d in zip(circle.bodies, circle.dq)]
    arcs = Scene.make(chain, circle.bodies, s, v, frame=circle.frame, law=circle.law)
    a = heyroll.simulate(circle, t_end=3.0, max_collisions=None)
    b = heyroll.simulate(arcs, t_end=3.0, max_collisions=None)
    assert a.n_collisions == b.n_collisions >= 2
    assert np.max(np.abs(np.asarray(a.times, float) - np.asarray(b.times, float))) < 1e-12


# ------------------------------------------------------- events, analytic cases

def incline_chain(theta: float, length: float):
    """A straight line going down to the right at theta, then a concave arc that
    turns it up: limiter at the top of the line, junction at its foot."""
    a = mpmath.mpf(-theta)
    return ArcChainTrack.make([Segment("line", angle=a, length=mpmath.mpf(length)),
                               Segment("arc", mpmath.mpf(2), "concave", a, mpmath.mpf("1.0"))])


def test_junction_crossing_is_located_to_machine_precision():
    theta, L, s0 = 0.3, 2.0, 0.5
    ball = Body.of_shape("solid_sphere", "0.1", mass=1)
    scene = Scene.make(incline_chain(theta, L), [ball], [s0], [0], run=RunSettings.make(3))
    result = simulate(scene)
    t_junction = result.junctions[0]["t"]
    with mpmath.workdps(40):
        acc = mpmath.mpf("9.81") * mpmath.sin(mpmath.mpf(theta)) / mpmath.mpf(7) * 5
        exact = mpmath.sqrt(2 * (mpmath.mpf(L) - mpmath.mpf(s0)) / acc)
    assert abs(t_junction - float(exact)) <= 4 * np.finfo(float).eps * float(exact)


def test_limiter_impact_is_located_to_machine_precision_and_reverses_with_k():
    theta, s0 = 0.3, 1.5
    ball = Body.of_shape("solid_sphere", "0.1", mass=1)
    # start moving up the line towards the limiter at s = 0 with v0
    v0 = -3.0
    scene = Scene.make(incline_chain(theta, 2.0), [ball], [s0], [v0], limiter_restitution="0.5",
                           run=RunSettings.make("1"))
    result = simulate(scene)
    hit = result.limiter_impacts[0]
    with mpmath.workdps(40):
        acc = mpmath.mpf("9.81") * mpmath.sin(mpmath.mpf(theta)) * 5 / 7  # ds/dt grows at acc
        # s0 + v0 t + acc t^2 / 2 = 0, the first root
        disc = mpmath.mpf(v0) ** 2 - 2 * acc * mpmath.mpf(s0)
        exact = (-mpmath.mpf(v0) - mpmath.sqrt(disc)) / acc
    assert abs(hit["t"] - float(exact)) <= 4 * np.finfo(float).eps * float(exact)
    assert hit["v_after"] == -0.5 * hit["v_before"] and hit["end"] == "lower"


def test_a_body_turning_back_just_after_a_junction_is_not_lost():
    # measured before the fix: heyoka never fires an event whose function is
    # exactly 0.0 at the start of a step; the body crossed back unseen and the
    # first integral jumped by 8 J
    track = ThreeArcTrack.make(1, "0.5", "0.2")
    ball = Body.of_shape("solid_sphere", "0.08", mass=2)
    hi = track.pieces(ball)[1].s1
    for v in (-0.01, -0.3):
        scene = Scene.make(track, [ball], [hi + 1e-9], [v], run=RunSettings.make(1))
        result = simulate(scene)
        assert [(j["from"], j["to"]) for j in result.junctions] == [(3, 2), (2, 3)]
        assert abs(result.energy_final - result.energy_initial) <= 1e-14 * abs(result.energy_initial)


# ---------------------------------------------------------- first integral

def first_integral_drift(scene, t_end, precision="long"):
    result = simulate(scene, t_end=t_end, precision=precision)
    scale = max(abs(result.energy_initial), float(scene.bodies[0].mass * scene.g))
    return result, abs(result.energy_final - result.energy_initial) / scale


def rotating_curve_scene(x0="1.3"):
    scene = parse_scene(README_CURVE)
    return Scene.make(scene.track, scene.bodies, [x0], [0], frame=scene.frame)


def rotating_chain_scene():
    return Scene.make(ThreeArcTrack.make(1, "0.5", "0.2"), [DISK], ["0.6"], [0],
                          frame=Frame.make("1.5", "0.1"))


def test_first_integral_on_a_rotating_curve_over_1000_oscillations():
    scene = rotating_curve_scene()
    result, drift = first_integral_drift(scene, 1367.0)  # outer well, period 1.367 s (validation/path_accuracy.py)
    assert result.status.value == "completed"
    assert drift < 1e-13


def test_first_integral_on_a_rotating_arc_chain_crossing_junctions():
    scene = rotating_chain_scene()
    result, drift = first_integral_drift(scene, 4166.0)  # 1000 periods of 4.166 s
    assert len(result.junctions) >= 2000 and drift < 1e-13


@pytest.mark.slow
@pytest.mark.parametrize("make, t_end", [(rotating_curve_scene, 13670.0), (rotating_chain_scene, 41660.0)])
def test_first_integral_over_ten_thousand_oscillations(make, t_end):
    result, drift = first_integral_drift(make(), t_end)
    assert drift < 1e-13


def test_double_precision_drifts_where_long_does_not():
    scene = rotating_curve_scene("0.3")  # the shallow central well: double drifts ~1e-12 in 1000 s
    _, drift_long = first_integral_drift(scene, 1000.0, "long")
    _, drift_double = first_integral_drift(scene, 1000.0, "double")
    assert drift_long < drift_double


# ---------------------------------------------------------------- equilibria

@pytest.mark.parametrize("name", sorted(PAPER_CURVES))
@pytest.mark.parametrize("omega", ["0", "2.0", "3.0", "4.5"])
def test_equilibria_agree_with_an_independent_mpmath_solve(name, omega):
    track = CurveTrack.make(PAPER_CURVES[name], "-2.1", "2.1")
    problem = EquilibriumProblem(track, DISK, Frame.make(omega, "0.1"))
    eq = find_equilibria(problem)
    assert eq
    spec = {"type": "curve", "y": PAPER_CURVES[name], "x_min": "-2.1", "x_max": "2.1"}
    roots = equilibrium_roots(spec, DISK.radius, omega, "0.1", guesses=[e.q for e in eq])
    for e, r in zip(eq, roots):
        assert abs(e.q - float(r)) <= 1e-12 * max(1, abs(e.q))
    # and an independent coarse scan finds no equilibrium the engine missed
    scan = equilibrium_roots(spec, DISK.radius, omega, "0.1", scan=300, domain=("-2.1", "2.1"))
    assert all(min(abs(e.q - float(r)) for e in eq) < 1e-10 for r in scan)


def test_equilibria_refuse_a_body_that_does_not_fit_the_curve():
    track = CurveTrack.make("0.5*x**2*(x**2 - 1)**2*(x**2 - 4)", "-2.2", "2.2")  # radius of curvature 0.012 m
    with pytest.raises(SceneError, match="radius of curvature"):
        EquilibriumProblem(track, DISK)


def test_equilibria_types_alternate_and_match_the_effective_potential():
    problem = problem_of(parse_scene(README_CURVE))
    eq = find_equilibria(problem)
    types = [e.type for e in eq]
    assert all(a != b for a, b in zip(types, types[1:]))
    for e in eq:
        h = 1e-4
        curvature = problem.potential(e.q + h) + problem.potential(e.q - h) - 2 * problem.potential(e.q)
        assert (curvature > 0) == (e.type == "center")


def test_equilibria_do_not_depend_on_the_body_inertia():
    track = CurveTrack.make(PAPER_CURVES["k x^2 (x^2 - a^2)^2"], -1.6, 1.6)
    frame = Frame.make(3, 0)
    ring = Body.of_shape("ring", "0.05", mass=1)
    sphere = Body.of_shape("solid_sphere", "0.05", mass=7)
    a = find_equilibria(EquilibriumProblem(track, ring, frame))
    b = find_equilibria(EquilibriumProblem(track, sphere, frame))
    assert [e.x for e in a] == [e.x for e in b]


def test_pitchfork_at_the_central_minimum_and_none_at_the_maxima():
    # f'' (0) = 1: the centre at x = 0 turns into a saddle at Omega^2 = g / (1/f''(0) - r),
    # shedding the two saddles that came in from the maxima (section 5.3's theorem)
    track = CurveTrack.make(PAPER_CURVES["k x^2 (x^2 - a^2)^2"], -1.6, 1.6)
    problem = EquilibriumProblem(track, DISK, Frame.make(0, 0))
    found = bifurcations(problem, np.linspace(0, 8, 81))
    assert len(found) == 1
    assert abs(found[0].omega - math.sqrt(9.81 / (1 - 0.05))) < 1e-12 * 3.3
    assert abs(found[0].x) < 1e-6
    # at Omega = 0 the maxima at +-1/sqrt(3) are saddles, with no partner born near them
    eq0 = find_equilibria(problem)
    saddles = [e.x for e in eq0 if e.type == "saddle"]
    assert saddles == pytest.approx([-1 / math.sqrt(3), 1 / math.sqrt(3)], abs=1e-3)


def test_pitchfork_in_a_bowl_under_its_own_axis_is_at_lambda_one():
    # an axis through the centre of the left bowl: lambda = g / ((R - r) Omega^2) = 1
    track = ThreeArcTrack.make(1, "0.5", 0)
    problem = EquilibriumProblem(track, DISK, Frame.make(0, "-1.5"))
    found = bifurcations(problem, np.linspace(3.0, 3.5, 6), samples=20001, refine=30)
    bowl = [b for b in found if abs(b.x + 1.5) < 0.01]
    assert bowl and abs(bowl[0].omega - math.sqrt(9.81 / 0.95)) < 1e-6


# ------------------------------------------------------- collisions on paths

def test_single_concave_arc_reproduces_the_circle_engine():
    """One concave arc of radius R is the circle: same collisions, same times."""
    R = mpmath.mpf(1)
    b1 = Body.of_shape("solid_sphere", "0.1", mass=1)
    b2 = Body.of_shape("solid_sphere", "0.15", mass=2)
    phi = [mpmath.mpf("-1.0"), mpmath.mpf("0.5")]
    circle = Scene.make(track=CircleTrack.of_radius(R), bodies=[b1, b2], phi=phi, dphi=[0, 0],
                        run=RunSettings.make(10))
    ref = heyroll.simulate(circle)
    chain = ArcChainTrack.make([Segment("arc", R, "concave", -mpmath.pi, mpmath.pi)])
    s = [(R - b.radius) * (p + mpmath.pi) for b, p in zip((b1, b2), phi)]
    path = Scene.make(chain, [b1, b2], s, [0, 0], run=RunSettings.make(10))
    result = simulate(path)
    times = np.asarray(result.times, dtype=float)
    assert len(times) == ref.n_collisions > 5
    assert np.max(np.abs(times - np.asarray(ref.times, dtype=float))) < 1e-12


def two_disks_on_rotating_arcs(k="1", t_end="20"):
    text = f"""
name = "two_disks_rotating_arcs"
[track]
type = "three_arcs"
radius = 1.0
hump_radius = 0.5
beta = 0.2
[frame]
omega = 1.5
axis_x = 0.0
[[bodies]]
shape = "disk"
radius = 0.05
mass = 1.0
segment = 1
angle = -2.6
[[bodies]]
shape = "disk"
radius = 0.08
mass = 2.0
segment = 3
angle = 0.3
[collision]
law = "hedrih"
restitution = {k}
[run]
t_end = {t_end}
"""
    return parse_scene(text)


def test_two_bodies_on_a_rotating_arc_track_elastic():
    scene = two_disks_on_rotating_arcs()
    result = simulate(scene, dense=True)
    assert result.status.value == "completed" and result.n_collisions >= 3
    assert abs(result.energy_final - result.energy_initial) <= 1e-12 * abs(result.energy_initial)
    t, X = result.sample(20000)
    gaps = scene.gap(0, 1, X[:, 0], X[:, 1])
    assert gaps.min() > -1e-12
    # energy moves between the bodies at the collisions
    jumps = [abs(body_energy(scene, 0, c["q_i"], c["dq_i_after"]) - body_energy(scene, 0, c["q_i"], c["dq_i_before"]))
             for c in result.collision_table()]
    assert max(jumps) > 1e-3


def test_two_bodies_on_a_rotating_arc_track_inelastic_lose_energy_at_each_collision():
    scene = two_disks_on_rotating_arcs(k="0.7", t_end="10")
    result = simulate(scene)
    assert result.n_collisions >= 2
    for c in result.collision_table():
        assert c["energy_after"] < c["energy_before"]


# --------------------------------------------------------------------- CLI

def test_cli_equilibria_json_on_the_readme_example(tmp_path, capsys):
    path = tmp_path / "curve.toml"
    path.write_text(README_CURVE)
    assert main(["equilibria", str(path), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [sorted(d) for d in data] == [["type", "x"]] * len(data)
    xs = [d["x"] for d in data]
    assert xs == sorted(xs) and {d["type"] for d in data} == {"center", "saddle"}
    assert [d["type"] for d in data] == ["center", "saddle", "center", "saddle", "center"]


def test_cli_portrait_and_run_on_a_path_scene(tmp_path, capsys):
    path = tmp_path / "curve.toml"
    path.write_text(README_CURVE + "\n[run]\nt_end = 5\n")
    assert main(["portrait", str(path), "--out", str(tmp_path / "p")]) == 0
    data = json.loads((tmp_path / "p" / "portrait.json").read_text())
    assert data["check"]["worst_relative_first_integral_drift"] < 1e-13
    assert all((tmp_path / "p" / f).stat().st_size > 0 for f in ("portrait.png", "energy_surface.png", "bifurcation.png"))
    assert main(["run", str(path), "--out", str(tmp_path / "r")]) == 0
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["status"] == "completed" and summary["track"] == "curve"


@pytest.mark.parametrize("edit, field", [
    (('y = "0.5*x**2*(x**2 - 1)**2"', 'y = "import(x)"'), "track.y"),
    (("radius = 0.05", "radius = 0.6"), "bodies[1].radius"),
    (("x = 0.3 ", "x = 3.0 "), "bodies[1].x"),
    (("omega = 3.0", "omega = nan"), "frame.omega"),
    (("axis_x = 0.0", "axis_y = 0.0"), "frame.axis_y"),
])
def test_cli_bad_path_scenes_exit_2_with_the_field(tmp_path, capsys, edit, field):
    path = tmp_path / "bad.toml"
    path.write_text(README_CURVE.replace(*edit))
    out = tmp_path / "o"
    assert main(["run", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert field in err and err.count("\n") == 1
    assert not out.exists()


def test_cli_equilibria_runs_on_a_circle_too(capsys, tmp_path):
    # One engine: every command on every track (the circle's cases: tests/test_circle_equilibria.py).
    path = tmp_path / "c.toml"
    path.write_text(default_scene_text())
    assert main(["equilibria", str(path), "--json"]) == 0
    types = [e["type"] for e in json.loads(capsys.readouterr().out)]
    assert sorted(types) == ["center", "saddle"]


def test_total_energy_is_the_sum_of_body_energies():
    scene = two_disks_on_rotating_arcs()
    result = simulate(scene, t_end=0.5)
    state = np.asarray(result.final_state, dtype=float)
    assert result.energy_final == pytest.approx(
        float(body_energy(scene, 0, state[0], state[2]) + body_energy(scene, 1, state[1], state[3])), rel=1e-15)


ARC_CHAIN = (Path(__file__).resolve().parents[1] / "examples" / "arc_chain.toml").read_text()


@pytest.mark.parametrize("edit, field", [
    (('kind = "line"', 'kind = "spline"'), "track.segments[1].kind"),
    (('side = "concave"', 'side = "inside"'), "track.segments[2].side"),
    (("length = 1.0", "length = -1.0"), "track.segments[1].length"),
    (("start = -0.5 ", "start = -0.4 "), "track.segments[2].start"),
    (("radius = 0.6", "radius = 0.6\ncolour = 1"), "track.segments[3].colour"),
    (("s = 0.2", "segment = 9\nangle = 0.1"), "bodies[1].segment"),
    (("s = 0.2", "s = 0.2\nsegment = 1"), "bodies[1].segment"),
    (("s = 0.2", "s = 99.0"), "bodies[1].s"),
    (("radius = 0.1", "radius = 1.5"), "bodies[1].radius"),
    (('type = "arcs"', 'type = "arcs"\nlimiter_restitution = 2'), "track.limiter_restitution"),
])
def test_bad_arc_chain_scenes_name_the_field(edit, field):
    with pytest.raises(SceneError) as info:
        parse_scene(ARC_CHAIN.replace(*edit, 1))
    assert info.value.field == field and "\n" not in str(info.value)


def test_example_arc_chain_runs_and_keeps_its_first_integral():
    scene = parse_scene(ARC_CHAIN)
    result = simulate(scene)
    assert len(result.junctions) > 5 and result.status.value == "completed"
    assert abs(result.energy_final - result.energy_initial) <= 1e-14 * abs(result.energy_initial)


@pytest.mark.parametrize("shape, kappa", [("disk", 1.5), ("solid_sphere", 1.4), ("ring", 2.0)])
def test_body_leaves_a_one_sided_hump_where_the_normal_force_vanishes(shape, kappa):
    """From the top of a convex arc with speed v0 the centre leaves its circle of radius rho at
    cos(psi) = (kappa v0^2/(g rho) + 2)/(kappa + 2) (energy: kappa v^2 = kappa v0^2 + 2 g rho (1 - cos psi),
    and N = 0 when v^2 = g rho cos psi)."""
    track = ThreeArcTrack.make(1, "0.5", "0.2")
    body = Body.of_shape(shape, "0.05", mass=1)
    piece = track.pieces(body)[1]
    rho, v0 = 0.55, 0.3
    top = piece.s0 + rho * (math.pi / 2 - 0.2)
    one = Scene.make(track, [body], [top], [v0], track_sides="one", run=RunSettings.make(5))
    result = simulate(one)
    assert result.status.value == "left_track" and "body 1 would leave the track" in result.message
    psi = (float(result.final_state[0]) - top) / rho
    with mpmath.workdps(30):
        exact = mpmath.acos((kappa * mpmath.mpf(v0) ** 2 / (mpmath.mpf("9.81") * mpmath.mpf(rho)) + 2) / (kappa + 2))
    assert abs(psi - float(exact)) < 1e-12
    two = simulate(Scene.make(track, [body], [top], [v0], run=RunSettings.make(5)))
    assert two.status.value == "completed" and len(two.warnings) == 1 and "two-sided" in two.warnings[0]


def test_a_body_resting_in_a_bowl_presses_on_it():
    track = ThreeArcTrack.make(1, "0.5", "0.2")
    result = simulate(Scene.make(track, [DISK], ["2.0"], [0], track_sides="one", run=RunSettings.make(20)))
    assert result.status.value == "completed" and result.warnings == []


def test_plastic_collision_in_a_bowl_goes_on_in_persistent_contact_not_overlap():
    # measured before the fix (random scene fuzz): k = 0 left the pair pressed together,
    # the gap went below zero unseen and the run ended 'completed' with a 5 cm overlap;
    # then it stopped with status 'contact'. Now the pair rolls on as one constrained unit.
    track = ThreeArcTrack.make(1, "0.5", "0.2")
    a = Body.of_shape("solid_sphere", "0.06", mass=1)
    b = Body.of_shape("ring", "0.05", mass=2)
    scene = Scene.make(track, [a, b], ["1.5", "3.3"], ["1.0", "0"], law=heyroll.make_law("newton_generalized", 0),
                           limiter_restitution=1, run=RunSettings.make(10))
    result = simulate(scene, dense=True)
    assert result.status.value == "completed", result.message
    assert any(m.clusters == ((1, 2),) for m in result.mode_changes)
    t, X = result.sample(5000)
    assert scene.gap(0, 1, X[:, 0], X[:, 1]).min() > -1e-12


def test_a_body_pressed_against_a_plastic_limiter_comes_to_rest_on_it():
    # measured before the fix (random scene fuzz): k = 0 at a limiter the curve slopes into
    # made the body re-hit it every 4.3e-8 s for ever (the run never ended); then it
    # stopped with status 'contact'. Now the body rests on the stop to t_end.
    track = CurveTrack.make("-0.1*x**2*(x**2 - 1)*(23.4256 - (x**2 - 4)**2)", "-1.5", "1.5")
    ball = Body.of_shape("solid_sphere", "0.08", mass=1)
    scene = Scene.make(track, [ball], ["-1.2"], ["-1.0"], limiter_restitution=0, run=RunSettings.make(5))
    result = simulate(scene)
    assert result.status.value == "completed", result.message
    assert len(result.limiter_impacts) == 1
    assert result.mode_changes[-1].pinned == (((1,), "lower"),)
    assert float(result.final_state[1]) == 0.0 and abs(float(result.final_state[0]) + 1.5) < 1e-12


def test_a_flat_track_has_one_neutral_stretch_not_a_saddle_per_grid_node(tmp_path, capsys):
    # measured before the fix: y = 0.1 listed 19,999 "saddles" and `heyroll portrait` ended in a
    # matplotlib traceback (contour levels of a constant surface).
    path = tmp_path / "flat.toml"
    path.write_text('[track]\ntype = "curve"\ny = "0.1"\nx_min = -1\nx_max = 1\n\n'
                    '[[bodies]]\nshape = "disk"\nradius = 0.05\nmass = 1.0\nx = 0.3\ndx = 0.0\n')
    assert main(["equilibria", str(path), "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == [{"x": -1.0, "type": "neutral", "x_end": 1.0}]
    assert main(["portrait", str(path), "--out", str(tmp_path / "p")]) == 0
    data = json.loads((tmp_path / "p" / "portrait.json").read_text())
    assert [e["type"] for e in data["equilibria"]] == ["neutral"]
    # Turning about x = 0.2 the same flat track has one saddle there (a maximum of -Omega^2 (x - a)^2 / 2).
    turning = EquilibriumProblem(CurveTrack.make("0.1", "-1", "1"), DISK, Frame.make("2", "0.2"))
    eq = find_equilibria(turning)
    assert [e.type for e in eq] == ["saddle"] and abs(eq[0].x - 0.2) < 1e-15


@pytest.mark.parametrize("y", ["1", "0", "0.1*x", "-0.3*x + 2"])
def test_flat_and_straight_curves_run_against_closed_forms(y):
    # Issue 13: flat or straight curves ended in a heyoka ValueError ("extra functions in a Taylor
    # decomposition cannot be constants"). On a straight line the contact abscissa obeys
    # x'' = -g sin(a) cos(a) / kappa (slope tan a), between elastic limiter impacts.
    track = CurveTrack.make(y, "-1.5", "1.5")
    ball = Body.of_shape("solid_sphere", "0.08", mass=1)
    result = simulate(Scene.make(track, [ball], ["-1.0"], ["1.0"], run=RunSettings.make("0.4")))
    assert result.status.value == "completed", result.message
    slope = float(track.numeric(track.df, [0.0])[0])
    a = -9.81 * slope / (1 + slope * slope) / 1.4
    t = 0.4
    assert float(result.final_state[0]) == pytest.approx(-1.0 + t + a * t * t / 2, abs=1e-13)
    assert float(result.final_state[1]) == pytest.approx(1.0 + a * t, abs=1e-13)


def test_energy_surface_is_cut_above_the_potential_and_the_bodys_energy():
    # Issue 13: uncut, the grid's corners (fast and far out) set the z scale and the wells look flat.
    from heyroll.analysis.equilibria import problem_of
    from heyroll.interfaces.portrait_figures import _velocity_range, body_energy, first_integral_grid, surface_top

    scene = parse_scene(README_CURVE)
    problem = problem_of(scene, 0)
    q = np.linspace(*problem.domain, 160)
    vmax = _velocity_range(scene, 0, q, problem)
    H = first_integral_grid(scene, 0, q, np.linspace(-vmax, vmax, 120))
    top = surface_top(scene, 0, q, problem, H)
    own = body_energy(scene, 0, np.array([float(scene.q[0])]), np.array([float(scene.dq[0])]))[0] / float(scene.bodies[0].mass)
    assert top > problem.potential(q).max() and top > own  # every well, saddle and the body's own level shown
    assert top < H.max()  # the far corners cut off
    assert (H <= top).mean() > 0.3


def test_path_branches_drawn_are_the_runs_trajectory_jumping_at_its_collisions():
    # Issue 13: the path-track figures draw result.sample() (the dense output of the run itself);
    # its pieces must meet the collision table: positions continuous through each collision,
    # rates jumping from the table's 'before' to its 'after'.
    disk = Body.of_shape("disk", "0.05", mass="1")
    scene = Scene.make(CurveTrack.make("0.5*x**2*(x**2 - 1)**2 + 0.2*x**2", "-1.6", "1.6"), [disk, disk],
                       ["-0.9", "0.4"], ["0", "0"], law=heyroll.make_law("hedrih", "0.9"), run=RunSettings.make(6))
    result = heyroll.simulate(scene, dense=True)
    table = result.collision_table()
    assert result.status.value == "completed" and len(table) >= 3
    n = len(scene.bodies)

    def state_at(t):
        for t0, t1, c_out, expand, _turns in result.dense:  # (a path track takes no turns out)
            if t0 <= t <= t1:
                values = np.asarray(c_out(np.array([t])), dtype=float)[0]
                return values if expand is None else np.array(expand(values.tolist()))
        raise AssertionError(f"no dense piece covers t = {t}")

    for row in table:
        i, j, tc = row["i"] - 1, row["j"] - 1, float(row["t"])
        before, after = state_at(tc - 1e-9), state_at(tc + 1e-9)
        for k, side in ((i, "i"), (j, "j")):
            assert before[k] == pytest.approx(row[f"q_{side}"], abs=1e-7)
            assert after[k] == pytest.approx(row[f"q_{side}"], abs=1e-7)
            assert before[n + k] == pytest.approx(row[f"dq_{side}_before"], abs=1e-6)
            assert after[n + k] == pytest.approx(row[f"dq_{side}_after"], abs=1e-6)
    t, X = result.sample(2000)
    assert scene.gap(0, 1, X[:, 0], X[:, 1]).min() > -1e-9  # no drawn branch passes through the other body


@pytest.mark.parametrize("shape", ["solid_sphere", "particle"])
def test_a_body_started_where_a_whole_power_of_x_vanishes_runs(shape):
    """y = x**4 - x**2, a body on the hump at x = 0: heyoka's pow(x, 4) has NaN Taylor coefficients at x = 0
    (the run failed at t = 0 with a non-finite state: acceptance test); whole powers are products now."""
    body = 'shape = "particle"\nmass = 1.0' if shape == "particle" else \
        f'shape = "{shape}"\nradius = 0.05\nmass = 1.0'
    scene = heyroll.parse_scene('[track]\ntype = "curve"\ny = "x**4 - x**2"\nx_min = -1.5\nx_max = 1.5\n'
                                f'[[bodies]]\n{body}\nx = 0.0\ndx = 0.5\n[run]\nt_end = 5\n')
    result = heyroll.simulate(scene)
    assert result.status is heyroll.Status.COMPLETED, result.message
    assert abs(result.energy_final - result.energy_initial) <= 1e-13 * abs(result.energy_initial)
    assert abs(float(result.final_state[0])) > 0.5  # it rolled off the hump into a well


@pytest.mark.parametrize("track, rule", [
    ('type = "curve"\ny = "1/x"\nx_min = -2.0\nx_max = 2.2', "track.y: has a pole between x = "),
    ('type = "curve"\ny = "0.5*x**2 + 0.01*(x - 0.3)**-1"\nx_min = -1.0\nx_max = 1.0', "track.y: has a pole"),
    ('type = "parametric"\nx = "u"\ny = "1/(u - 0.123456789)"\nu_min = -1.0\nu_max = 1.0', "track.y: has a pole"),
    ('type = "parametric"\nx = "cos(u)*cos(u)"\ny = "sin(u)"\nu_min = 3.5\nu_max = 5.9', "track.u_min: the tangent turns back between u = "),
])
def test_a_curve_with_a_pole_or_a_cusp_between_its_samples_is_refused(track, rule):
    """The smoothness check sampled the curve: a pole the samples straddle (1/x on [-2, 2.2]: a body ran to
    y = -778 m) or a cusp between them (x = cos^2 u, y = sin u at 3 pi/2: failed mid-run) passed (acceptance
    test). A denominator that changes sign, or a tangent that turns back, is refused."""
    text = f'[track]\n{track}\n[[bodies]]\nshape = "particle"\nmass = 1.0\n' + \
        ('x = 0.9\ndx = 0.0\n' if '"curve"' in track else 'u = 0.9\ndu = 0.0\n' if 'x = "u"' in track else
         'u = 5.0\ndu = 0.0\n')
    with pytest.raises(SceneError) as caught:
        heyroll.parse_scene(text)
    assert f"{caught.value.field}: {caught.value.rule}".startswith(rule)
    smooth = heyroll.parse_scene('[track]\ntype = "curve"\ny = "x*x/(1 + x**2)"\nx_min = -2.0\nx_max = 2.0\n'
                                 '[[bodies]]\nshape = "particle"\nmass = 1.0\nx = 0.5\ndx = 0.0\n')
    assert smooth.track.kind == "curve"  # a denominator that keeps its sign is no pole


def test_a_bowl_with_a_flat_bottom_has_one_neutral_stretch_and_no_saddle_at_its_ends(tmp_path, capsys):
    """A concave arc, a horizontal line, a concave arc: the flat bottom is a neutral stretch; its start, where
    h reaches 0 from the arc, was also listed as a saddle of stiffness 0 (acceptance test)."""
    path = tmp_path / "bowl.toml"
    path.write_text('[track]\ntype = "arcs"\nstart_x = 0.0\nstart_y = 0.0\n'
                    '[[track.segments]]\nkind = "arc"\nradius = 2.0\nside = "concave"\nstart = -1.0\nend = 0.0\n'
                    '[[track.segments]]\nkind = "line"\nangle = 0.0\nlength = 0.5\n'
                    '[[track.segments]]\nkind = "arc"\nradius = 1.0\nside = "concave"\nstart = 0.0\nend = 1.3\n'
                    '[[bodies]]\nshape = "disk"\nradius = 0.05\nmass = 1.0\ns = 0.3\nds = 2.0\n')
    assert main(["equilibria", str(path), "--json"]) == 0
    found = json.loads(capsys.readouterr().out)
    assert [e["type"] for e in found] == ["neutral"]
    assert found[0]["x_end"] - found[0]["x"] == pytest.approx(0.5, abs=1e-12)


@pytest.mark.parametrize("precision", ["double", "long", "quad"])
def test_bodies_placed_past_touching_high_on_a_curve_collide_in_every_precision(precision):
    """Two disks on y = x^2/2 + 200, the second placed past touching by half the scene's slack (2^-48 of the
    centres' coordinates, ~3.6e-13 m here): the start's repair measured its slack against the track coordinate
    x (~1), so it moved nothing and even double ended overlap (review). Now the slack is the scene's."""
    from heyroll.model._numbers import touching_slack

    with mpmath.workdps(40):
        r = mpmath.mpf("0.1")

        def centre(x):
            n = mpmath.sqrt(1 + x * x)
            return x - r * x / n, x * x / 2 + 200 + r / n

        def gap(x2):
            a, b = centre(mpmath.mpf("-0.6")), centre(x2)
            return mpmath.hypot(b[0] - a[0], b[1] - a[1]) - 2 * r

        touching = mpmath.findroot(gap, mpmath.mpf("-0.4"))
        slack = touching_slack(*centre(mpmath.mpf("-0.6")), *centre(touching))
        x2 = float(touching - slack / 2 / mpmath.diff(gap, touching))
    text = ('[track]\ntype = "curve"\ny = "x**2/2 + 200"\nx_min = -1.5\nx_max = 1.5\n'
            '[[bodies]]\nshape = "disk"\nradius = 0.1\nmass = 1.0\nx = -0.6\ndx = 0.0\n'
            f'[[bodies]]\nshape = "disk"\nradius = 0.1\nmass = 1.0\nx = {x2!r}\ndx = -1.0\n'
            '[collision]\nlaw = "newton"\nrestitution = 1.0\n[run]\nt_end = 2.0\n')
    result = heyroll.simulate(heyroll.parse_scene(text), precision=precision)
    assert result.status is heyroll.Status.COMPLETED and result.n_collisions == 2, result.message
    assert float(result.times[0]) == 0.0
