"""Rough tracks (paper section 2, issue 15): sliding, sticking, slipping and rolling again, forcing.

The engine against closed forms from the independent reference
(heyroll.reference.rough, mpmath) and against conservation laws: the
change of mechanical energy over each branch equals minus the friction
work integrated with the motion, mu = 0 reproduces the smooth runs.
"""

from __future__ import annotations

import csv
import json
import math
import subprocess
import sys
from pathlib import Path

import mpmath
import numpy as np
import pytest

from heyroll.errors import SceneError
from heyroll.interfaces.scene_file import parse_scene
from heyroll.model.bodies import Body
from heyroll.model.forcing import Forcing
from heyroll.model.frame import Frame
from heyroll.model.laws import make_law
from heyroll.model.scene import RunSettings, Scene
from heyroll.model.tracks import ArcChainTrack, CircleTrack, CurveTrack, ParametricTrack, Segment, first_integral
from heyroll.reference import rough
from heyroll.simulation.driver import simulate
from heyroll.simulation.result import Status

G = "9.81"
ROOT = Path(__file__).resolve().parent.parent
PARTICLE = Body.of_shape("particle", 0, mass=1)
DISK = Body.of_shape("disk", "0.1", mass=1)


def incline(slope: str, lo=-10, hi=10) -> CurveTrack:
    return CurveTrack.make(f"{slope}*x", lo, hi)


def body_energy(result, k, q, dq) -> float:
    s = result.scene
    return float(first_integral(s.track, s.bodies[k], q, dq, s.g, s.frame))


# -- a particle on a straight rough incline ---------------------------------------------------------


@pytest.mark.parametrize("slope, mu_s, sticks", [("0.3", "0.5", True), ("0.6", "0.5", False)])
def test_a_particle_launched_up_an_incline_stops_where_the_closed_form_says_and_sticks_iff_tan_alpha_le_mu_s(
        slope, mu_s, sticks):
    mu = "0.2"
    scene = Scene.make(incline(slope), [PARTICLE], [0], [2], friction=mu, static_friction=mu_s, track_sides="one",
                       run=RunSettings.make(2))
    result = simulate(scene)
    assert result.status is Status.COMPLETED
    alpha = mpmath.atan(mpmath.mpf(slope))
    ref = rough.incline_sliding(alpha, mu, mu_s, 0, 2, G, 2)
    assert [(r[2], r[3]) for r in result.transitions] == [(t.mode_from, t.mode_to) for t in ref.transitions]
    assert (ref.transitions[0].mode_to == "stuck") is sticks
    for row, t in zip(result.transitions, ref.transitions):
        assert row[0] == pytest.approx(float(t.t), abs=2e-15)
        assert float(row[4]) == pytest.approx(float(t.x), abs=2e-15)
        assert float(row[5]) == 0.0  # the rate is exactly zero at a turning point
    assert float(result.final_state[0]) == pytest.approx(float(ref.x), abs=1e-13)
    assert float(result.final_state[1]) == pytest.approx(float(ref.dx), abs=1e-13)
    assert result.final_modes == (ref.mode,)


def test_a_particle_released_at_rest_on_an_incline_slides_iff_tan_alpha_exceeds_mu_s():
    for slope, expected in (("0.49", "stuck"), ("0.51", "sliding-")):
        scene = Scene.make(incline(slope), [PARTICLE], [0], [0], friction="0.3", static_friction="0.5",
                           track_sides="one", run=RunSettings.make("0.5"))
        result = simulate(scene)
        assert result.final_modes == (expected,)
        moved = float(result.final_state[0]) != 0.0
        assert moved is (expected != "stuck")


# -- a particle on a rough circle ---------------------------------------------------------------------


def test_a_particle_on_a_rough_circle_turns_where_the_closed_form_law_of_phi_dot_squared_says():
    mu, mu_s = "0.1", "0.15"
    scene = Scene.make(CircleTrack.of_radius(1), [PARTICLE], [0], [4], friction=mu, static_friction=mu_s,
                       track_sides="one", run=RunSettings.make(20))
    result = simulate(scene)
    ref = rough.circle_sliding_sequence(0, 4, mu, mu_s, 1, G)
    assert ref.status == "stuck"
    assert len(result.transitions) == len(ref.transitions) >= 4
    for row, t in zip(result.transitions, ref.transitions):
        assert (row[2], row[3]) == (t.mode_from, t.mode_to)
        assert row[0] == pytest.approx(float(t.t), rel=1e-14, abs=1e-14)
        assert float(row[4]) == pytest.approx(float(t.phi), abs=1e-14)
    # the final sticking band |tan phi| <= mu_s, and nothing moves afterwards
    phi_end = float(result.final_state[0])
    assert abs(math.tan(phi_end)) <= 0.15 and result.final_modes == ("stuck",)
    assert float(result.final_state[1]) == 0.0


def test_the_energy_lost_on_every_branch_is_the_friction_work_to_round_off():
    scene = Scene.make(CircleTrack.of_radius(1), [PARTICLE], [0], [4], friction="0.1", static_friction="0.15",
                       track_sides="one", run=RunSettings.make(20))
    result = simulate(scene)
    energies = [body_energy(result, 0, 0, 4)] + [body_energy(result, 0, r[4], r[5]) for r in result.transitions]
    work = [0.0] + list(result.transition_work)
    for k in range(1, len(energies)):
        lost, dissipated = energies[k - 1] - energies[k], work[k] - work[k - 1]
        assert dissipated > 0
        assert lost == pytest.approx(dissipated, rel=1e-13, abs=1e-14)
    assert result.energy_initial - result.energy_final == pytest.approx(sum(result.friction_work), rel=1e-13)
    ref = rough.circle_sliding_sequence(0, 4, "0.1", "0.15", 1, G)
    for branch, k in zip(ref.branches, range(1, len(work))):
        assert work[k] - work[k - 1] == pytest.approx(float(-branch.friction_work if branch.friction_work < 0
                                                            else branch.friction_work), rel=1e-12)


def test_two_particles_on_a_rough_circle_account_for_every_joule():
    """Friction work plus the impacts' losses is the whole loss; a stuck particle that is hit slides."""
    scene = Scene.make(CircleTrack.of_radius(1), [PARTICLE, Body.of_shape("particle", 0, mass=2)], [-0.5, 0.8],
                       [3, 0], law=make_law("newton", "0.7"), friction="0.1", static_friction="0.2",
                       run=RunSettings.make(10))
    result = simulate(scene)
    assert result.status is Status.COMPLETED and result.n_collisions >= 2
    table = result.collision_table()
    impacts = float((table["energy_before"] - table["energy_after"]).sum())
    assert result.energy_initial - result.energy_final == pytest.approx(sum(result.friction_work) + impacts,
                                                                        rel=1e-12)
    hit = [r for r in result.transitions if r[2] == "stuck" and r[0] in set(table["t"].tolist())]
    assert hit, "a stuck particle hit by the other must start sliding at the collision"
    assert result.final_modes == ("stuck", "stuck")


# -- rolling bodies that slip ---------------------------------------------------------------------------


def test_a_disk_thrown_without_spin_slips_then_rolls_at_the_closed_form_time_and_speed():
    # an incline of slope 0.2 (alpha > 0: uphill is +x); the disk moves uphill with v0 and no spin
    slope, mu = "0.2", "0.3"
    alpha = mpmath.atan(mpmath.mpf(slope))
    dx0 = "2"
    v0 = mpmath.mpf(dx0) / mpmath.cos(alpha)  # along the slope
    scene = Scene.make(incline(slope), [DISK], [0], [dx0], slip=[float(v0)], friction=mu, track_sides="one",
                       run=RunSettings.make(1))
    result = simulate(scene)
    ref = rough.incline_slip_then_roll(alpha, mu, mu, "1.5", v0, 0, G)
    assert ref.mode_after == "rolling"
    (row,) = [r for r in result.transitions if r[3] == "rolling"]
    assert row[0] == pytest.approx(float(ref.t_star), rel=1e-14)
    assert float(row[5]) / math.cos(float(alpha)) == pytest.approx(float(ref.v_star), rel=1e-13)
    assert result.energy_initial - result.energy_final == pytest.approx(float(ref.friction_loss), rel=1e-12)


@pytest.mark.parametrize("slope", ["0.5", "1.2"])
def test_a_disk_released_on_an_incline_rolls_iff_the_friction_it_needs_is_within_mu_s_n(slope):
    mu = "0.2"
    alpha = mpmath.atan(mpmath.mpf(slope))
    ref = rough.incline_roll_from_rest(alpha, mu, mu, "1.5", G)
    scene = Scene.make(incline(slope), [DISK], [0], [0], friction=mu, track_sides="one", run=RunSettings.make("0.5"))
    result = simulate(scene)
    assert result.final_modes == (ref.mode,)
    t = 0.5
    if ref.mode == "rolling":
        x = -0.5 * 9.81 * math.sin(float(alpha)) / 1.5 * t * t * math.cos(float(alpha))
        assert float(result.final_slip[0]) == 0.0
    else:
        x = 0.5 * float(ref.dv) * t * t * math.cos(float(alpha))
        assert float(result.final_slip[0]) == pytest.approx(float(ref.dw) * t, rel=1e-12)
    assert float(result.final_state[0]) == pytest.approx(x, rel=1e-12)


# -- mu = 0 and the smooth engine --------------------------------------------------------------------------


@pytest.mark.parametrize("track, q, dq", [
    (CircleTrack.of_radius(1), [-0.5, 0.8], [3, 0]),
    (CurveTrack.make("x**2/2", -2, 2), [-0.5, 0.8], [2, 0]),
])
def test_friction_zero_reproduces_the_smooth_track(track, q, dq):
    law = make_law("newton", "0.8")
    smooth = simulate(Scene.make(track, [PARTICLE, PARTICLE], q, dq, law=law, run=RunSettings.make(4)))
    rough_run = simulate(Scene.make(track, [PARTICLE, PARTICLE], q, dq, law=law, friction=0,
                                    run=RunSettings.make(4)))
    assert smooth.n_collisions == rough_run.n_collisions >= 2
    np.testing.assert_allclose(rough_run.times, smooth.times, rtol=0, atol=1e-13)
    np.testing.assert_allclose(rough_run.final_state, smooth.final_state, rtol=0, atol=1e-11)
    assert sum(rough_run.friction_work) == 0.0


def test_a_relative_equilibrium_of_a_turning_plane_holds_with_friction_zero_and_sticks_nearby_with_friction():
    from heyroll.analysis.equilibria import find_equilibria, problem_of

    track = CurveTrack.make("0.5*x**2*(x**2 - 1)**2", "-1.6", "1.6")  # section 5.3's curve (examples/)
    frame = Frame.make("3", 0)
    probe = Scene.make(track, [PARTICLE], ["0.1"], [0], frame=frame)
    centres = [e for e in find_equilibria(problem_of(probe)) if e.type == "center" and e.x > 0.01]
    x_eq = centres[0].x
    for mu in (0, "0.1"):
        scene = Scene.make(track, [PARTICLE], [x_eq], [0], frame=frame, friction=mu, run=RunSettings.make(3))
        result = simulate(scene)
        assert result.status is Status.COMPLETED
        assert float(result.final_state[0]) == pytest.approx(x_eq, abs=1e-9)
    # slightly off the equilibrium a rough particle sticks at once (within the sticking band)
    scene = Scene.make(track, [PARTICLE], [x_eq + 1e-3], [0], frame=frame, friction="0.1", run=RunSettings.make(1))
    result = simulate(scene)
    assert result.final_modes == ("stuck",) and float(result.final_state[0]) == x_eq + 1e-3


# -- every track type, turning planes, two-sided tracks ----------------------------------------------------


def test_a_rough_arc_chain_passes_its_junctions_and_accounts_for_its_energy():
    track = ArcChainTrack.make([Segment("line", angle=mpmath.mpf("-0.5"), length=mpmath.mpf(1)),
                                Segment("arc", radius=mpmath.mpf(1), side="concave", start=mpmath.mpf("-0.5"),
                                        end=mpmath.mpf("1.2"))], 0, 0)
    scene = Scene.make(track, [PARTICLE], ["0.1"], [0], friction="0.05", static_friction="0.1", track_sides="one",
                       run=RunSettings.make(10))
    result = simulate(scene)
    assert result.status is Status.COMPLETED
    assert result.junctions, "the particle slides through the junction"
    assert result.final_modes == ("stuck",)
    assert result.energy_initial - result.energy_final == pytest.approx(sum(result.friction_work), rel=1e-12)


def test_in_a_turning_plane_the_jacobi_integral_drops_by_the_friction_work_with_the_coriolis_reaction():
    track = CurveTrack.make("x**2", -1, 1)
    scene = Scene.make(track, [PARTICLE], ["-0.5"], [1], frame=Frame.make("2", 0), friction="0.1",
                       run=RunSettings.make(5), limiter_restitution=1)
    result = simulate(scene)
    assert result.status is Status.COMPLETED and result.transitions
    # no impacts lose energy (limiter restitution 1): the Jacobi integral falls by the friction work alone
    assert result.energy_initial - result.energy_final == pytest.approx(sum(result.friction_work), rel=1e-11)


def test_on_a_two_sided_circle_friction_acts_on_the_magnitude_of_the_reaction_over_the_top():
    # 6 rad/s: above the horizontal diameter the weight outgrows the centripetal need and the outer
    # side takes over (N changes sign near phi = 2.2), below the top: the particle swings back
    scene = Scene.make(CircleTrack.of_radius(1), [PARTICLE], [0], [6], friction="0.05", track_sides="two",
                       run=RunSettings.make(3))
    result = simulate(scene)
    assert result.status is Status.COMPLETED
    assert result.warnings  # the normal force changed sign (the outer side held the particle)
    assert result.energy_initial - result.energy_final == pytest.approx(sum(result.friction_work), rel=1e-12)
    assert all(w >= 0 for w in result.friction_work)


# -- forcing ------------------------------------------------------------------------------------------------


def test_a_periodic_force_releases_a_stuck_particle_where_it_exceeds_mu_s_n():
    f0, nu, mu_s = 3, 2, "0.2"
    forcing = Forcing.make("force", amplitude=f0, frequency=nu, phase=-math.pi / 2)  # F0 sin(nu t)
    scene = Scene.make(CurveTrack.make("0*x", -5, 5), [PARTICLE], [0], [0], friction="0.1", static_friction=mu_s,
                       forcing=forcing, track_sides="one", run=RunSettings.make("0.8"))
    result = simulate(scene)
    first = result.transitions[0]
    assert (first[2], first[3]) == ("stuck", "sliding+")
    with mpmath.workdps(30):
        expected = mpmath.asin(mpmath.mpf(mu_s) * mpmath.mpf(G) / f0) / nu
    assert first[0] == pytest.approx(float(expected), abs=1e-14)


def test_a_moving_base_releases_a_stuck_particle_where_its_inertial_force_exceeds_mu_s_n():
    amplitude, nu, mu_s = "0.1", 8, "0.5"  # A nu^2 = 6.4 m/s^2 > mu_s g = 4.905
    forcing = Forcing.make("base", amplitude=amplitude, frequency=nu, phase=math.pi / 2)  # -A nu^2 sin: starts at 0
    scene = Scene.make(CurveTrack.make("0*x", -5, 5), [PARTICLE], [0], [0], friction="0.3", static_friction=mu_s,
                       forcing=forcing, track_sides="one", run=RunSettings.make("0.3"))
    result = simulate(scene)
    first = result.transitions[0]
    assert first[2] == "stuck" and first[3] in ("sliding+", "sliding-")
    with mpmath.workdps(30):
        expected = mpmath.asin(mpmath.mpf(mu_s) * mpmath.mpf(G) / (mpmath.mpf(amplitude) * nu**2)) / nu
    assert first[0] == pytest.approx(float(expected), abs=1e-14)


def test_the_stroboscopic_section_samples_once_a_forcing_period_and_finds_the_periodic_stick_slip_orbit():
    forcing = Forcing.make("force", amplitude=2, frequency=2)
    scene = Scene.make(CurveTrack.make("x**2/2", -3, 3), [PARTICLE], [0], [0], friction="0.1", static_friction="0.2",
                       forcing=forcing, track_sides="one", run=RunSettings.make(40))
    result = simulate(scene)
    table = result.strobe_table
    period = 2 * math.pi / 2
    np.testing.assert_allclose(table[:, 0], period * np.arange(len(table)), rtol=0, atol=1e-12)
    assert len(table) == int(40 // period) + 1
    # the forced stick-slip oscillator settles on a periodic orbit: successive samples converge
    assert abs(table[-1, 1] - table[-2, 1]) < 1e-6 and abs(table[-1, 2] - table[-2, 2]) < 1e-6


# -- precision ladder -------------------------------------------------------------------------------------


def test_a_quad_run_finds_the_turning_point_to_quad_precision():
    scene = Scene.make(incline("0.3"), [PARTICLE], [0], [2], friction="0.2", static_friction="0.5",
                       track_sides="one", run=RunSettings.make(1))
    result = simulate(scene, precision="quad")
    with mpmath.workdps(50):  # the slope's angle beyond a double
        alpha = mpmath.atan(mpmath.mpf("0.3"))
        ref = rough.incline_sliding(alpha, "0.2", "0.5", 0, 2, G, 1)
    t, x = result.transitions[0][0], result.transitions[0][4]
    # transitions keep the run's own numbers: the instant and the place to quad precision
    with mpmath.workdps(40):
        assert abs(mpmath.mpf(str(t)) - ref.transitions[0].t) < mpmath.mpf("1e-30")
        assert abs(mpmath.mpf(str(x)) - ref.transitions[0].x) < mpmath.mpf("1e-30")


# -- scene files and the CLI ------------------------------------------------------------------------------

ROUGH_SCENE = """
name = "rough"
[track]
type = "curve"
y = "x**2/2"
x_min = -2
x_max = 2
friction = 0.1
static_friction = 0.2
sides = "one"
[forcing]
kind = "force"
amplitude = 2.0
frequency = 2.0
[[bodies]]
shape = "particle"
mass = 1.0
x = 0.0
[[bodies]]
shape = "disk"
radius = 0.1
mass = 1.0
x = 1.0
slip = 0.5
[collision]
law = "newton"
restitution = 0.5
[run]
t_end = 6
"""


def test_a_scene_file_gives_static_friction_slip_and_forcing():
    scene = parse_scene(ROUGH_SCENE)
    assert scene.rough and float(scene.static_coefficient) == 0.2
    assert [float(w) for w in scene.slip] == [0.0, 0.5]
    assert scene.forcing.kind == "force" and scene.forcing.frequency == 2


@pytest.mark.parametrize("edit, field", [
    (("static_friction = 0.2", "static_friction = 0.05"), "track.static_friction"),
    (("kind = \"force\"", "kind = \"push\""), "forcing.kind"),
    (("frequency = 2.0", "frequency = 0"), "forcing.frequency"),
    (("x = 0.0\n", "x = 0.0\nslip = 1.0\n"), "bodies[1].slip"),
    (("amplitude = 2.0", "amplitude = 2.0\nstrength = 1"), "forcing.strength"),
])
def test_bad_rough_scene_fields_are_named(edit, field):
    with pytest.raises(SceneError) as info:
        parse_scene(ROUGH_SCENE.replace(*edit))
    assert info.value.field == field


def test_the_cli_writes_transitions_and_the_stroboscopic_section(tmp_path):
    path = tmp_path / "rough.toml"
    path.write_text(ROUGH_SCENE)
    out = tmp_path / "out"
    run = subprocess.run([sys.executable, "-m", "heyroll.interfaces.cli", "run", str(path), "--out", str(out),
                          "--no-figures"], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    with open(out / "transitions.csv") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["n", "t", "body", "from", "to", "q", "dq"]
    assert len(rows) > 2 and {r[3] for r in rows[1:]} <= {"rolling", "sliding+", "sliding-", "stuck"}
    assert [int(r[0]) for r in rows[1:]] == list(range(1, len(rows)))
    with open(out / "stroboscopic.csv") as fh:
        strobe = list(csv.reader(fh))
    assert strobe[0] == ["n", "t", "x_1", "x_2", "dx_1", "dx_2"] and len(strobe) == 3  # t = 0, pi (t_end 6)
    # with figures summary.json lists the table and the figure (the figure's key took the table's: acceptance test)
    figures = tmp_path / "figures"
    run = subprocess.run([sys.executable, "-m", "heyroll.interfaces.cli", "run", str(path), "--out", str(figures)],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    files = json.loads((figures / "summary.json").read_text())["files"]
    assert files["stroboscopic"] == "stroboscopic.csv" and files["stroboscopic_figure"] == "stroboscopic.png"
    bad = path.with_name("bad.toml")
    bad.write_text(ROUGH_SCENE.replace("static_friction = 0.2", "static_friction = 0.01"))
    run = subprocess.run([sys.executable, "-m", "heyroll.interfaces.cli", "run", str(bad), "--out",
                          str(tmp_path / "bad")], capture_output=True, text=True, timeout=120)
    assert run.returncode == 2 and "track.static_friction" in run.stderr and run.stderr.count("\n") == 1


# -- a parametric curve: the cycloid ------------------------------------------------------------------------


@pytest.mark.parametrize("u0", [1.0, 2.0, 2.8])
def test_on_the_smooth_cycloid_every_swing_lasts_2_pi_sqrt_a_over_g_whatever_its_amplitude(u0):
    """The tautochrone: x = a (u - sin u), y = a (1 + cos u) = s^2 / (8a) with s = 4a cos(u/2) the arc
    length from the bottom, so s'' = -g s / (4a): a period 4 pi sqrt(a/g) for every amplitude."""
    track = ParametricTrack.make("u - sin(u)", "1 + cos(u)", "0.5", "5.78")
    result = simulate(Scene.make(track, [PARTICLE], [u0], [0], friction=0, track_sides="one",
                                 run=RunSettings.make(7)))
    turns = [r for r in result.transitions if r[0] > 0]
    half = 2 * math.pi * math.sqrt(1 / 9.81)
    assert len(turns) == 3
    for n, row in enumerate(turns, start=1):
        assert row[0] == pytest.approx(n * half, rel=1e-14)
    assert float(turns[0][4]) == pytest.approx(2 * math.pi - u0, abs=1e-13)  # the mirror point


def test_every_rough_example_runs_from_its_scene_file(tmp_path):
    from heyroll.interfaces.scene_file import load_scene

    examples = sorted(ROOT.joinpath("examples").glob("rough_*.toml"))
    assert len(examples) >= 4
    for path in examples:
        scene = load_scene(path)
        result = simulate(scene)
        assert result.status is Status.COMPLETED, (path.name, result.message)
        assert result.transitions, path.name
        work = sum(result.friction_work)
        assert work > 0
        if scene.forcing is None and all(b.is_particle for b in scene.bodies):
            # energy falls by the friction work and the impacts' losses (the table's energies are the
            # rolling form: for particles the whole energy)
            table = result.collision_table()
            impacts = float((table["energy_before"] - table["energy_after"]).sum())
            limiters = sum(0.5 * float(scene.bodies[b].mass) * (v * v - w * w)
                           * float(scene.track.sigma(scene.bodies[b], q)) ** 2 * float(scene.bodies[b].kappa)
                           for t, b, kind, _f, _t, q, v, w in result.passages if kind != 0)
            assert result.energy_initial - result.energy_final == pytest.approx(work + impacts + limiters, rel=1e-9), \
                path.name


def test_bodies_moving_together_turn_and_stick_together():
    """Three particles after plastic collisions slide as one; the turning points of units moving together
    fall in one Taylor step: the first one's event ends the step past the others' roots, which must
    still be turning points (before: a cluster slid on with friction pushing it the wrong way)."""
    scene = Scene.make(CircleTrack.of_radius(1), [PARTICLE] * 3, [-1.0, 0.3, 0.9], [2, 0, 0],
                       law=make_law("newton", 0), friction="0.05", static_friction="0.1", run=RunSettings.make(10))
    result = simulate(scene)
    assert result.status is Status.COMPLETED, result.message
    assert result.final_modes == ("stuck",) * 3
    stuck = [r for r in result.transitions if r[3] == "stuck"]
    assert len({r[0] for r in stuck}) == 1 and len(stuck) == 3  # one instant, all three
    # every sliding stretch moves in its mode's direction: no rate against the mode's sign
    rows = {}
    for t, k, old, new, q, dq in result.transitions:
        if new.startswith("sliding") and float(dq) != 0:
            assert (float(dq) > 0) == (new == "sliding+")
        rows.setdefault(k, []).append(new)
    table = result.collision_table()
    impacts = float((table["energy_before"] - table["energy_after"]).sum())
    assert result.energy_initial - result.energy_final == pytest.approx(sum(result.friction_work) + impacts, rel=1e-12)


def _mode_at(result, k, times):
    rows = [r for r in result.transitions if r[1] == k]
    first = rows[0][2] if rows else result.final_modes[k]
    starts = np.array([r[0] for r in rows])
    modes = [first] + [r[3] for r in rows]
    return [modes[int(np.searchsorted(starts, t, side="right"))] for t in times]


@pytest.mark.parametrize("name", ["rough_circle", "rough_rotating_curve", "rough_parabola_forced", "rough_cycloid"])
def test_a_sliding_particle_never_moves_against_its_mode_and_a_stuck_one_never_moves(name):
    """The invariant the friction events keep, checked on the dense trajectory of every example."""
    from heyroll.interfaces.scene_file import load_scene

    scene = load_scene(ROOT / "examples" / f"{name}.toml")
    result = simulate(scene, dense=True)
    times = np.linspace(0, float(result.t_final), 20001)
    states = result.states_at(times)
    n = len(scene.bodies)
    for k, body in enumerate(scene.bodies):
        if not body.is_particle:
            continue
        rate = states[:, n + k]
        scale = 1e-9 * (1 + np.abs(rate).max())
        for mode, v in zip(_mode_at(result, k, times), rate):
            if mode == "sliding+":
                assert v >= -scale
            elif mode == "sliding-":
                assert v <= scale
            else:
                assert abs(v) <= scale


# -- regressions found by review (issue 15) ----------------------------------------------------------------


def test_a_cascade_at_a_modes_start_reaches_the_integrators_friction_signs():
    """Eight particles, plastic: a cascade of cluster collisions at the start of a contact mode
    reversed a cluster; its recorded mode changed but the integrator's sign parameter did not, and
    friction pushed it along its motion (negative friction work) for 0.24 s."""
    bodies = [Body.of_shape("particle", 0, mass=1 + i % 3) for i in range(8)]
    scene = Scene.make(CircleTrack.of_radius(1), bodies, [-2.8 + i * 0.7 for i in range(8)], [3, -2, 1, 0, 2, -3, 1, -1],
                       law=make_law("newton", "0"), friction="0.1", static_friction="0.2", run=RunSettings.make(10))
    result = simulate(scene)
    assert result.status is Status.COMPLETED, result.message
    assert all(w >= 0 for w in result.friction_work)
    table = result.collision_table()
    impacts = float((table["energy_before"] - table["energy_after"]).sum())
    assert result.energy_initial - result.energy_final == pytest.approx(sum(result.friction_work) + impacts, rel=1e-11)


def test_a_particle_held_on_a_two_sided_incline_stays_through_weightlessness():
    """Vertical base motion with A nu^2 = 20 > g: the effective gravity passes through 0, load and static
    capacity vanish together (their ratio is tan alpha = 0.1 < mu_s): it stays stuck. Before: released at
    N = 0 and run away with friction doing positive work."""
    forcing = Forcing.make("base", amplitude="0.2", frequency=10, direction=math.pi / 2)
    scene = Scene.make(CurveTrack.make("0.1*x", -20, 20), [PARTICLE], [0], [0], friction="0.2", static_friction="0.3",
                       forcing=forcing, track_sides="two", run=RunSettings.make(2))
    result = simulate(scene)
    assert result.final_modes == ("stuck",) and float(result.final_state[0]) == 0.0
    assert result.friction_work == (0.0,)


@pytest.mark.parametrize("precision", ["long", "quad", "mp:128"])
def test_a_forced_rough_scene_runs_in_every_precision(precision):
    scene = Scene.make(CurveTrack.make("x**2/2", -3, 3), [PARTICLE], [0], [0], friction="0.1", static_friction="0.2",
                       forcing=Forcing.make("force", amplitude=2, frequency=2), track_sides="one",
                       run=RunSettings.make(2))
    double, other = simulate(scene), simulate(scene, precision=precision)
    assert other.status is Status.COMPLETED
    assert [r[2:4] for r in other.transitions] == [r[2:4] for r in double.transitions]
    for a, b in zip(other.transitions, double.transitions):
        assert float(a[0]) == pytest.approx(float(b[0]), abs=1e-13)


@pytest.mark.parametrize("k", ["1", "0.5"])
def test_the_collision_tables_energies_count_a_slipping_bodys_spin(k):
    """A disk slipping without spin hits a particle: the impulse through its centre leaves its spin, and
    the table's energies are the bodies' whole kinetic and potential energy (before: the rolling form)."""
    disk = Body.of_shape("disk", "0.1", mass=1)
    scene = Scene.make(CurveTrack.make("0*x", -50, 50), [disk, PARTICLE], [0, "0.5"], [2, 0], slip=[2.0, 0],
                       law=make_law("newton", k), friction="0.01", track_sides="one", run=RunSettings.make(1))
    result = simulate(scene)
    (row,) = result.collision_table()
    assert row["mode_i_before"] == "sliding+" and row["law_flag"] == 3  # Newton's law, translational inertia
    lost = float(row["energy_before"] - row["energy_after"])
    closing = float(row["dq_i_before"] - row["dq_j_before"])  # sigma = 1 on a flat line
    assert lost == pytest.approx((1 - float(k) ** 2) / 2 * 0.5 * closing**2, abs=1e-14)  # m_i m_j/(m_i+m_j) = 1/2
    assert result.energy_initial - result.energy_final == pytest.approx(sum(result.friction_work) + lost, rel=1e-12)


def test_a_particle_meets_a_disk_at_its_contact_point_and_never_passes_it():
    """The distance between the centres minus r only touches 0 where a particle reaches a disk's contact
    point: the particle passed under the disk on the cycloid, unseen. Now the gap of such a pair is the
    difference of their contact coordinates."""
    track = ParametricTrack.make("u - sin(u)", "1 + cos(u)", "0.5", "5.78")
    scene = Scene.make(track, [PARTICLE, Body.of_shape("disk", "0.05", mass=1)], ["1.2", "4.4"], [0, 0],
                       law=make_law("newton", "0.6"), friction="0.08", static_friction="0.12", track_sides="one",
                       limiter_restitution="0.5", run=RunSettings.make(4))
    result = simulate(scene, dense=True)
    assert result.status is Status.COMPLETED and result.n_collisions >= 1
    states = result.states_at(np.linspace(0, 4, 8001))
    assert np.min(states[:, 1] - states[:, 0]) >= -1e-12
    with pytest.raises(SceneError) as info:
        Scene.make(ArcChainTrack.make([Segment("line", angle=mpmath.mpf(0), length=mpmath.mpf(2))], 0, 0),
                   [PARTICLE, DISK], ["0.2", "1"], [0, 0], law=make_law("newton", 1))
    assert info.value.field == "bodies[2].shape"


def test_a_forced_run_with_limiter_impacts_draws_its_impact_map(tmp_path):
    """A base-excited particle between limiters settles on a periodic impact orbit: two impacts a period,
    at forcing phases pi apart, with one impact speed (the impact map's fixed points)."""
    from heyroll.interfaces.friction_figures import _impacts, friction_figures

    scene = Scene.make(CurveTrack.make("x**2/2", "-0.4", "0.4"), [PARTICLE], [0], [0], friction="0.05",
                       static_friction="0.1", forcing=Forcing.make("base", amplitude="0.3", frequency=7),
                       limiter_restitution="0.7", track_sides="one", run=RunSettings.make(60))
    result = simulate(scene)
    files = friction_figures(result, tmp_path)
    assert files["impact_map"] == "impact_map.png" and (tmp_path / "impact_map.png").stat().st_size > 5000
    t, speed, _labels = _impacts(result)
    late = t > 40
    phase = np.mod(7 * t[late], np.pi)  # the two limiters' impacts, half a period apart
    assert np.ptp(speed[late]) < 1e-9  # one impact speed on the orbit
    assert np.ptp(phase) < 1e-9 and late.sum() >= 20


def test_colliding_while_slipping_never_creates_energy():
    """Found by fuzzing: the rolling law applied to slipping bodies (rolling is its premise) made 0.017 J
    at one collision. A slipping body now collides with its translational inertia (law_flag 3)."""
    balls = [Body.of_shape("solid_sphere", r, mass=1) for r in ("0.125", "0.25", "0.25", "0.25")]
    scene = Scene.make(CircleTrack.of_radius(1), balls, ["0.0", "0.43997595479091894", "1.3696497736991629",
                                                        "2.0493235926074069"],
                       ["1.5499835417164392", "1.5499835417154391", "1.5499835417154391", "1.5499835417154391"],
                       law=make_law("hedrih", 0), friction="0.125", run=RunSettings.make(1, 60))
    result = simulate(scene)
    assert result.status not in (Status.FAILED, Status.OVERLAP), result.message
    table = result.collision_table()
    assert (table["law_flag"] == 3).any()
    newton = table["law_flag"] != 0  # flags 2 and 3: Newton's laws, which cannot create energy
    gain = (table["energy_after"] - table["energy_before"])[newton]
    assert np.all(gain <= 1e-12 * (1 + abs(result.energy_initial)))
    assert result.energy_final <= result.energy_initial + 1e-12


def test_bodies_that_slip_as_they_enter_persistent_contact_keep_their_spins_in_the_cluster():
    """Two slipping disks in a rough circle, plastic: they enter persistent contact slipping. Each keeps its
    spin (before: the run stopped, since a spin that vanished into the cluster's rolling and came back at the
    split had created energy, review): every joule is the friction work or an impact's loss."""
    disks = [Body.of_shape("disk", "0.1", mass=1), Body.of_shape("disk", "0.1", mass=2)]
    scene = Scene.make(CircleTrack.of_radius(1), disks, ["-0.5", "0.5"], [1, -1], law=make_law("hedrih", 0),
                       friction="0.1", static_friction="0.15", slip=["0.5", "-0.5"], run=RunSettings.make("1.5", 200))
    result = simulate(scene)
    assert result.status is Status.COMPLETED, result.message
    merge = next(m for m in result.mode_changes if m.clusters == ((1, 2),))
    # both slip as the cluster forms (the plastic impact reversed their slips), and roll again inside it
    assert sorted(tr[1:4] for tr in result.transitions if tr[0] == merge.t) == \
        [(0, "sliding+", "sliding-"), (1, "sliding-", "sliding+")]
    assert sorted(tr[1] for tr in result.transitions if tr[0] > merge.t and tr[3] == "rolling") == [0, 1]
    assert result.mode_changes[-1].clusters == ((1, 2),)
    table = result.collision_table()
    impacts = float((table["energy_before"] - table["energy_after"]).sum())
    # (the merge's plastic step is below the run's resolution: no row, nothing measurable lost)
    assert result.energy_initial - result.energy_final == pytest.approx(sum(result.friction_work) + impacts, rel=1e-9)


def test_a_slipping_disk_hitting_a_cluster_on_a_curve_moves_it_with_its_translational_mass():
    """Review: the cluster impact on a path track used the slipping striker's rolling inertia kappa m
    (+6.9 J at one elastic collision)."""
    r = 0.1
    disks = [Body.of_shape("disk", r, mass=1) for _ in range(3)]
    track = CurveTrack.make("x**2/2", -2, 2)

    def centre(x):
        n = np.array([-x, 1.0]) / math.hypot(x, 1.0)
        return np.array([x, x * x / 2]) + r * n

    lo, hi = -0.1, 0.9  # the third disk touching the second
    for _ in range(200):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if np.linalg.norm(centre(mid) - centre(-0.1)) < 2 * r else (lo, mid)
    scene = Scene.make(track, disks, [-1.2, -0.1, hi + 1e-14], [3, 0, 0], law=make_law("hedrih", 1),
                       friction="0.05", slip=[2.0, 0, 0], run=RunSettings.make("0.3", 5))
    result = simulate(scene)
    row = result.collision_table()[0]
    assert row["law_flag"] == 2 and row["mode_i_before"] == "sliding+"
    assert float(row["energy_after"]) <= float(row["energy_before"]) + 1e-12
    impacts = float((result.collision_table()["energy_before"] - result.collision_table()["energy_after"]).sum())
    assert result.energy_initial - result.energy_final == pytest.approx(sum(result.friction_work) + impacts, rel=1e-11)


def test_collisions_at_a_modes_start_count_a_slipping_bodys_spin():
    """Fuzz: a particle and a ball that slips from t = 0 collide in the settler at the mode's start; the
    table's energies were the rolling form there (an apparent gain of 2.4 mJ)."""
    P, B = Body.of_shape("particle", 0, mass=1), Body.of_shape("solid_sphere", "0.25", mass=1)
    scene = Scene.make(CircleTrack.of_radius(1), [P, P, B, B], ["-1.0", "-1.0", "-1.0", "-0.32032618109075611"],
                       ["0.0", "1.6591356909948332", "1.6491356909948331", "1.6491356909948331"],
                       law=make_law("newton", 0), friction="0.25", run=RunSettings.make(1, 60))
    result = simulate(scene)
    table = result.collision_table()
    assert table.size and np.all(table["energy_after"] - table["energy_before"] <= 1e-12)


def test_a_quad_runs_transitions_and_stroboscopic_section_are_written_in_full_digits(tmp_path):
    from heyroll.interfaces.outputs import write_run

    scene = Scene.make(CurveTrack.make("x**2/2", -3, 3), [PARTICLE], [0], [0], friction="0.1", static_friction="0.2",
                       forcing=Forcing.make("force", amplitude=2, frequency=2), track_sides="one",
                       run=RunSettings.make(4))
    result = simulate(scene, precision="quad")
    write_run(result, tmp_path, scene_source="test", figures=False)
    with open(tmp_path / "transitions.csv") as fh:
        rows = list(csv.reader(fh))[1:]
    with open(tmp_path / "stroboscopic.csv") as fh:
        strobe = list(csv.reader(fh))[1:]
    stop = next(r for r in rows if r[4] == "stuck")
    assert len(stop[1].replace(".", "").lstrip("0")) >= 33  # t: 36 significant digits, not 17
    assert len(strobe[1][1].replace(".", "").lstrip("0")) >= 33


def test_an_impact_that_turns_the_reaction_turns_the_side_friction_pushes_from():
    """Acceptance test: on a two-sided rough circle an elastic collision sent body 1 over the top fast enough to
    press on the outer side of the guide at once; the side parameter stayed (it follows the 'normal' event, and
    the reaction jumped without a root), so friction pushed the body along: +4.4 J in 0.5 s, friction work < 0.
    The side now follows every impact; friction only dissipates and the energy account closes."""
    from heyroll import simulate

    scene = parse_scene('[track]\ntype = "circle"\nradius = 1.0\nfriction = 0.3\n'
                        '[[bodies]]\nshape = "particle"\nmass = 1.0\nphi = -2.4\ndphi = 0.0\n'
                        '[[bodies]]\nshape = "particle"\nmass = 1.0\nphi = -2.0\ndphi = -5.0\n'
                        '[collision]\nlaw = "newton"\nrestitution = 1.0\n')
    result = simulate(scene, t_end=0.5)
    assert result.n_collisions == 1
    assert all(w > 0 for w in result.friction_work)
    lost = float(result.energy_initial) - float(result.energy_final)
    assert lost == pytest.approx(sum(result.friction_work), abs=1e-12)


def test_the_validation_report_says_friction_works_between_collisions(tmp_path):
    """Acceptance test: the validate report of a rough track said each body keeps its mechanical energy between
    collisions."""
    from types import SimpleNamespace

    from heyroll import simulate
    from heyroll.interfaces.report import section_energy

    result = simulate(parse_scene(ROUGH_SCENE), t_end=2.0)
    text = "\n".join(section_energy(SimpleNamespace(double=result, out_dir=tmp_path, figures=[])))
    assert "keeps its own mechanical energy" not in text and "the work of friction" in text


# -- junctions: the reaction jumps with the curvature (review) ---------------------------------------------

#: A line at -0.3 rad into a convex arc of radius 1: the centre path's curvature jumps at s = 1.
LINE_INTO_HUMP = """
[track]
type = "arcs"
start_x = 0.0
start_y = 3.0
{extra}
[[track.segments]]
kind = "line"
angle = -0.3
length = 1.0
[[track.segments]]
kind = "arc"
radius = 1.0
side = "convex"
start = 0.3
end = 1.0
[[bodies]]
{body}
s = 0.5
ds = {ds}
"""


def _junction_scene(extra, body, ds):
    return parse_scene(LINE_INTO_HUMP.format(extra=extra, body=body, ds=ds))


def test_a_rolling_disk_slips_where_it_passes_onto_an_arc_whose_friction_cannot_hold_it():
    """mu = 0.15, a disk rolling down the line: at the junction (closed form: v = sqrt(1.9^2 + 2 a 0.5),
    a = g sin 0.3 / kappa) rolling needs F = (1 - 1/kappa) g sin 0.3 = 0.966 N but mu N = 0.15 (g cos 0.3 -
    v^2/1.1) = 0.650 N: it slips there. Before, no event saw the jump and it rolled on."""
    scene = _junction_scene("friction = 0.15", 'shape = "disk"\nradius = 0.1\nmass = 1.0', "1.9")
    result = simulate(scene, t_end=0.5)
    with mpmath.workdps(30):
        g, s3 = mpmath.mpf("9.81"), mpmath.sin(mpmath.mpf("0.3"))
        a = g * s3 / mpmath.mpf("1.5")
        v = mpmath.sqrt(mpmath.mpf("1.9") ** 2 + a)
        t = (v - mpmath.mpf("1.9")) / a
        assert (1 - 1 / mpmath.mpf("1.5")) * g * s3 > mpmath.mpf("0.15") * (g * mpmath.cos(mpmath.mpf("0.3")) - v**2 / mpmath.mpf("1.1"))
    first = result.transitions[0]
    assert (first[1], first[2], first[3]) == (0, "rolling", "sliding+")
    assert first[0] == pytest.approx(float(t), rel=1e-13) and first[5] == pytest.approx(float(v), rel=1e-13)
    assert result.energy_initial - result.energy_final == pytest.approx(sum(result.friction_work), rel=1e-9)


def test_a_sliding_particle_passing_onto_a_hump_is_braked_whichever_side_the_track_pushes_from():
    """mu = 0.3, two-sided: at the junction N = g cos 0.3 - v^2/1 jumps below 0 (v = 3.51): the track pushes
    from the other side. The side is judged there; a stale one made friction push the particle on (the energy
    rose by 0.24 J)."""
    scene = _junction_scene("friction = 0.3", 'shape = "particle"\nmass = 1.0', "3.5")
    result = simulate(scene, t_end=0.3)
    assert result.passage_counts[0] == 1 and all(w > 0 for w in result.friction_work)
    assert result.energy_initial - result.energy_final == pytest.approx(sum(result.friction_work), rel=1e-9)


def test_a_body_leaves_a_one_sided_track_where_it_passes_onto_a_hump_too_sharp_for_its_speed():
    """One-sided, smooth: N = g cos 0.3 - v^2/1.1 < 0 just past the junction (v = 3.766): left_track there
    (it stayed glued to the hump and bounced off the limiter)."""
    scene = _junction_scene('sides = "one"', 'shape = "disk"\nradius = 0.1\nmass = 1.0', "3.5")
    result = simulate(scene, t_end=0.5)
    assert result.status.value == "left_track" and "N < 0 at s = 1," in result.message
    assert float(result.final_state[0]) == pytest.approx(1.0, abs=1e-12)


def test_a_cluster_leaves_a_one_sided_track_where_a_member_passes_onto_a_hump_too_sharp():
    """A sphere pressing a disk (a cluster) down a one-sided line into a convex arc of radius 0.5 at 3.4 m/s:
    N < 0 for the disk as it passes the junction (t = 0.1249 s). The junction check skipped cluster members and
    the disk rode the hump; the run stopped later, naming the sphere (review)."""
    scene = parse_scene('[track]\ntype = "arcs"\nstart_x = 0.0\nstart_y = 0.0\nsides = "one"\n'
                        '[[track.segments]]\nkind = "line"\nangle = -0.5\nlength = 1.0\n'
                        '[[track.segments]]\nkind = "arc"\nradius = 0.5\nside = "convex"\nstart = 0.5\nend = 1.5\n'
                        '[[bodies]]\nshape = "solid_sphere"\nradius = 0.05\nmass = 1.0\ns = 0.5\nds = 3.0\n'
                        '[[bodies]]\nshape = "disk"\nradius = 0.05\nmass = 1.0\ns = 0.6\nds = 3.0\n[run]\nt_end = 0.4\n')
    result = simulate(scene)
    assert result.status.value == "left_track" and result.message.startswith("body 2 cannot stay")
    assert float(result.t_final) == pytest.approx(0.1249, abs=1e-4)


def test_a_collision_rows_energy_counts_the_slip_of_a_body_sliding_elsewhere():
    """Bodies 1 and 2 collide while body 3 slides elsewhere (started with a slip): the row's energies left out
    body 3's slip energy (15.97 J where the scene held 15.27 J: acceptance test). Each row's energy_before is
    the energy of the run stopped at that instant."""
    text = ('[track]\ntype = "circle"\nradius = 1.0\nfriction = 0.1\n'
            + "".join(f'[[bodies]]\nshape = "solid_sphere"\nradius = 0.1\nmass = 1.0\nphi = {p}\ndphi = {v}\n{extra}'
                      for p, v, extra in (("-0.5", "1.0", ""), ("0.3", "-1.0", ""), ("2.0", "0.0", "slip = 1.0\n")))
            + '[collision]\nlaw = "hedrih"\nrestitution = 1.0\n[run]\nt_end = 0.6\n')
    scene = parse_scene(text)
    table = simulate(scene).collision_table()
    assert table.size == 2
    for row in table:
        at = simulate(scene, t_end=float(row["t"]))  # (k = 1: the impact itself keeps the energy)
        assert row["energy_before"] == pytest.approx(at.energy_final, rel=1e-12)


def test_mirror_images_start_to_slip_together():
    """Two solid spheres at phi = -+0.2 moving apart at -+3 rad/s on a rough circle reach mu_s N at one
    instant: one event fired and the other's root lay at the start of the next step, unseen; body 2 rolled on
    needing more friction than mu N (acceptance test). Both slip at t = 0.19024 s, as each alone does."""
    def scene(bodies):
        return parse_scene('[track]\ntype = "circle"\nradius = 1.0\nfriction = 0.15\n' + "".join(
            f'[[bodies]]\nshape = "solid_sphere"\nradius = 0.1\nmass = 1.0\nphi = {p}\ndphi = {v}\n' for p, v in bodies)
            + '[run]\nt_end = 0.6\n')

    both = simulate(scene([("-0.2", "-3.0"), ("0.2", "3.0")])).transition_table()
    alone = simulate(scene([("0.2", "3.0")])).transition_table()
    assert [(int(r["body"]), str(r["to"])) for r in both[:2]] == [(1, "sliding+"), (2, "sliding-")]
    assert both["t"][0] == both["t"][1] == alone["t"][0]


def test_rows_of_one_instant_count_each_slipping_bodys_spin_with_the_rows_own_rates():
    """The outer two of three spheres slip (slip = +-1) and hit the middle one at one instant (Newton, k = 1):
    three rows. Each body's spin keeps its u through the instant, but a slip energy computed once with the
    rates before the instant was added to rows with other rates: 13.31 and 16.42 J where the scene held
    15.69 J (review). Every row now holds the energy of the run stopped at that instant."""
    text = ('[track]\ntype = "circle"\nradius = 1.0\nfriction = 0.1\n' + "".join(
        f'[[bodies]]\nshape = "solid_sphere"\nradius = 0.1\nmass = 1.0\nphi = {p}\ndphi = {v}\n{extra}'
        for p, v, extra in (("-1.0", "3.0", "slip = 1.0\n"), ("0.0", "0.0", ""), ("1.0", "-3.0", "slip = -1.0\n")))
        + '[collision]\nlaw = "newton"\nrestitution = 1.0\n[run]\nt_end = 0.5\n')
    scene = parse_scene(text)
    table = simulate(scene).collision_table()
    instant = table[table["t"] == table["t"][0]]
    assert instant.size == 3
    at = simulate(scene, t_end=float(instant["t"][0]))
    for row in instant:
        assert row["energy_before"] == pytest.approx(at.energy_final, rel=1e-9)
        assert row["energy_after"] == pytest.approx(at.energy_final, rel=1e-9)


def test_a_rolling_body_that_an_impact_leaves_needing_more_than_mu_s_n_slips_at_the_impact():
    """A sphere rolling up a rough circle is nearly stopped by a heavier particle: after the impact rolling
    needs 2.669 N/kg against mu_s N = 2.335 N/kg. Its slip event started past its root, and it rolled on 14 %
    over the capacity (review). It slips at the impact now."""
    beta = 2 * math.asin(0.1 / 0.9)
    scene = parse_scene('[track]\ntype = "circle"\nradius = 1.0\nfriction = 0.3\nstatic_friction = 0.5\n'
                        '[[bodies]]\nshape = "solid_sphere"\nradius = 0.1\nmass = 1.0\nphi = 1.0\ndphi = 5.0\n'
                        f'[[bodies]]\nshape = "particle"\nmass = 1.4\nphi = {1.0 + beta + 0.05!r}\ndphi = 0.0\n'
                        '[collision]\nlaw = "newton"\nrestitution = 1.0\n[run]\nt_end = 0.2\n')
    result = simulate(scene)
    impact = float(result.collision_table()["t"][0])
    sphere = [r for r in result.transition_table() if int(r["body"]) == 1]
    assert sphere and float(sphere[0]["t"]) == impact and str(sphere[0]["from"]) == "rolling"


def test_a_unit_that_stays_at_the_static_limit_holds_when_another_starts_to_slip():
    """A disk on a line of slope tan a = mu_s kappa/(kappa - 1) needs exactly mu_s N; a sphere elsewhere starts
    to slip. The disk was set sliding at that instant (its load at the capacity to within round-off, review);
    its load does not rise through the capacity: it rolls on, as it does alone."""
    a = math.atan(0.45)

    def scene(with_sphere):
        text = ('[track]\ntype = "arcs"\nstart_x = 0.0\nstart_y = 0.0\nfriction = 0.1\nstatic_friction = 0.15\n'
                '[[track.segments]]\nkind = "arc"\nradius = 1.0\nside = "concave"\nstart = -1.4\n'
                f'end = {a!r}\n[[track.segments]]\nkind = "line"\nangle = {a!r}\nlength = 5.0\n')
        if with_sphere:
            text += '[[bodies]]\nshape = "solid_sphere"\nradius = 0.1\nmass = 1.0\ns = 1.2\nds = -3.0\n'
        return parse_scene(text + '[[bodies]]\nshape = "disk"\nradius = 0.1\nmass = 1.0\ns = 6.0\nds = 0.0\n'
                                  '[run]\nt_end = 0.4\n')

    alone, both = simulate(scene(False)), simulate(scene(True))
    assert [int(r["body"]) for r in both.transition_table()] == [1]  # the sphere only
    assert both.final_modes[1] == alone.final_modes[0] == "rolling"
    assert float(both.final_state[1]) == pytest.approx(float(alone.final_state[0]), rel=1e-12)


def _ring_and_disk_on_a_slope(mu_s: str) -> Scene:
    # y = x/2: both roll alone (the ring needs F/N = tan(a)/2 = 0.25), the disk faster; it catches the ring
    # and they merge (plastic). Rolling together at a = g sin(a) (m1 + m2)/(kappa1 m1 + kappa2 m2) = 4/7 g sin(a),
    # the ring (the lower one, pushed) needs F = (kappa - 1) m a: F/N = (4/7) tan(a) = 2/7.
    ring = Body.of_shape("ring", "0.05", mass=1)
    disk = Body.of_shape("disk", "0.05", mass=1)
    return Scene.make(CurveTrack.make("0.5*x", "-2", "2"), [ring, disk], ["0", "0.5"], [0, 0],
                      law=make_law("newton", 0), friction=mu_s, static_friction=mu_s, g=G, run=RunSettings.make(2))


@pytest.mark.parametrize("mu_s, slips", [("0.2855", True), ("0.2859", False)])
def test_a_cluster_member_pushed_down_a_slope_slips_in_it_where_mu_s_is_below_the_closed_form_need(mu_s, slips):
    result = simulate(_ring_and_disk_on_a_slope(mu_s))
    assert result.status is Status.COMPLETED, result.message
    assert [m.clusters for m in result.mode_changes][:2] == [(), ((1, 2),)]
    merge = result.mode_changes[1].t
    at_merge = [tr[1:4] for tr in result.transitions if tr[0] == merge]
    assert at_merge == ([(0, "rolling", "sliding-")] if slips else [])


def test_a_ring_slipping_inside_a_cluster_follows_the_closed_forms_to_the_stop_and_spins_down_there():
    # mu = mu_s = 0.27: the ring rolls alone (it needs 0.25), slips in the cluster (2/7). Slipping, it takes part
    # with its translational mass: 2.5 m a = 2 m g sin(a) - mu m g cos(a) along the slope; its spin speeds up at
    # u' = mu g cos(a) / (kappa - 1), so w = v - u grows at w' = -(a - mu g cos(a)) (downhill, w < 0). The cluster
    # stops on the plastic limiter; the impulse through the ring's centre leaves its spin: w jumps by sigma |v|,
    # then the spin runs down at mu g cos(a) while the cluster rests on the stop.
    scene = _ring_and_disk_on_a_slope("0.27")
    result = simulate(scene, dense=True)
    assert result.status is Status.COMPLETED, result.message
    merge = result.mode_changes[1]
    assert merge.clusters == ((1, 2),) and result.mode_changes[2].pinned == (((1, 2), "lower"),)
    assert [tr[1:4] for tr in result.transitions] == [(0, "rolling", "sliding-"), (0, "sliding-", "sliding+")]
    g, sigma = 9.81, math.sqrt(1.25)
    sin_a, cos_a = 1 / math.sqrt(5), 2 / math.sqrt(5)
    a = (2 * g * sin_a - 0.27 * g * cos_a) / 2.5
    t0 = merge.t
    x0, v0 = result.states_at([t0 + 1e-9])[0][[0, 2]]
    x0, v0 = x0 - v0 * 1e-9, v0 + a / sigma * 1e-9  # (back to the merge)
    stop = result.passage_table()[0]
    # the ring's contact point reaches x = -2: x0 + v0 t - a t^2 / (2 sigma) = -2
    c = -a / (2 * sigma)
    dt = (-v0 - math.sqrt(v0 * v0 - 4 * c * (x0 + 2))) / (2 * c)
    assert stop["t"] == pytest.approx(t0 + dt, abs=1e-9)
    t = np.linspace(t0 + 0.01, stop["t"] - 0.01, 7)
    assert np.allclose(result.states_at(t)[:, 0], x0 + v0 * (t - t0) + c * (t - t0) ** 2, atol=1e-9)
    w_stop = -(a - 0.27 * g * cos_a) * dt + sigma * abs(stop["dq_before"])
    w_end = w_stop - 0.27 * g * cos_a * (2 - stop["t"])
    assert result.final_modes == ("sliding+", "rolling")
    assert float(result.final_slip[0]) == pytest.approx(w_end, abs=1e-8)
    # every joule: the energy lost is the friction work plus the plastic merge's and the stop's losses
    lost = result.energy_initial - result.energy_final
    table = result.collision_table()
    merge_loss = float(table["energy_before"][0] - table["energy_after"][0])
    v_stop = sigma * stop["dq_before"]
    stop_loss = 0.5 * 1 * v_stop**2 + 0.5 * 1.5 * v_stop**2  # the ring's centre and the rolling disk stop
    assert lost == pytest.approx(float(sum(result.friction_work)) + merge_loss + stop_loss, rel=1e-9)


def test_a_cluster_rising_up_a_steepening_bowl_slips_where_a_member_needs_more_than_mu_s_n():
    # Review: on a path track no event watched a cluster member's slip, and two rings rolled together up
    # y = 2 x^2 to x = 0.32, where rolling needs twice what mu_s N holds. The ring in front needs
    # F = (kappa - 1) m v' (v' its centre's tangential acceleration, the contact force included): where it
    # starts to slip F = mu_s N, checked here from that instant's state with the constrained motion solved
    # independently.
    ring = Body.of_shape("ring", "0.05", mass=1)
    track = CurveTrack.make("2*x**2", "-1", "1")
    scene = Scene.make(track, [ring, ring], ["-0.12", "0"], ["2.5", 0], law=make_law("newton", 0),
                       friction="0.3", static_friction="0.3", g=G, run=RunSettings.make(1))
    result = simulate(scene, dense=True)
    assert result.status is Status.COMPLETED, result.message
    onset = next(tr for tr in result.transitions if tr[2] == "rolling" and tr[3].startswith("sliding"))
    assert onset[1] == 1 and result.mode_changes[-1].clusters == ((1, 2),) and onset[0] > result.mode_changes[-1].t
    state = result.states_at([onset[0]])[0]
    q, v = state[:2], state[2:]
    g, h = 9.81, 1e-5

    def centre(k, x):
        cx, cy = track.centre(ring, [x])
        return np.array([cx[0], cy[0]])

    def sigma(k, x):
        return float(track.sigma(ring, [x])[0])

    def own(k):  # a rolling ring alone: kappa sigma^2 q'' = -g dy_C/dq - kappa sigma sigma' q'^2
        dy = (centre(k, q[k] + h)[1] - centre(k, q[k] - h)[1]) / (2 * h)
        ds = (sigma(k, q[k] + h) - sigma(k, q[k] - h)) / (2 * h)
        return (-g * dy - 2 * sigma(k, q[k]) * ds * v[k] ** 2) / (2 * sigma(k, q[k]) ** 2)

    def gap(x1, x2):
        return np.linalg.norm(centre(1, x2) - centre(0, x1)) - 0.1

    g1 = (gap(q[0] + h, q[1]) - gap(q[0] - h, q[1])) / (2 * h)
    g2 = (gap(q[0], q[1] + h) - gap(q[0], q[1] - h)) / (2 * h)
    d = h * 10
    second = (gap(q[0] + d * v[0], q[1] + d * v[1]) - 2 * gap(*q) + gap(q[0] - d * v[0], q[1] - d * v[1])) / d**2
    M = [2 * sigma(k, q[k]) ** 2 for k in (0, 1)]  # kappa m sigma^2 per unit mass
    lam = -(g1 * own(0) + g2 * own(1) + second) / (g1**2 / M[0] + g2**2 / M[1])
    acc2 = own(1) + lam * g2 / M[1]
    ds2 = (sigma(1, q[1] + h) - sigma(1, q[1] - h)) / (2 * h)
    tangential = sigma(1, q[1]) * acc2 + ds2 * v[1] ** 2  # v' of the front ring's centre
    slope = 4 * q[1]
    radius = (1 + slope**2) ** 1.5 / 4 - 0.05  # the centre's path: y = 2 x^2's radius of curvature less r
    normal = g / math.sqrt(1 + slope**2) + (sigma(1, q[1]) * v[1]) ** 2 / radius  # N/m, concave side
    assert abs(abs(tangential) - 0.3 * normal) < 1e-6 * normal  # (N without the contact forces' share, as documented)


def test_a_rigid_cluster_on_a_rough_circle_slips_where_the_contact_force_makes_a_member_need_mu_s_n_and_goes_on():
    # A ring and a disk (same r and m) start touching, moving up together: one rigid cluster, psi'' =
    # -(W1 sin phi1 + W2 sin phi2) / (G1 + G2). The ring needs F = (kappa - 1) m rho |psi''| (its contact force
    # included; free-body forces alone gave (1 - 1/kappa) m g sin phi) and slips where that reaches mu_s N.
    ring, disk = Body.of_shape("ring", "0.1", mass=1), Body.of_shape("disk", "0.1", mass=1)
    rho, g = 0.9, 9.81
    half = math.asin(0.2 / (2 * rho))  # touching: the centres 2 r apart
    scene = Scene.make(CircleTrack.of_radius(1), [ring, disk], phi=[repr(-half), repr(half)], dphi=["3", "3"],
                       law=make_law("newton", 0), friction="0.3", static_friction="0.3", g=G,
                       run=RunSettings.make(2))
    result = simulate(scene, dense=True)
    assert result.status is Status.COMPLETED, result.message
    assert [m.clusters for m in result.mode_changes] == [(), ((1, 2),)]
    onset = result.transitions[0]
    assert onset[1:4] == (0, "rolling", "sliding-")
    state = result.states_at([onset[0]])[0]
    phi, rate = state[:2], state[2]
    acc = -g * rho * (math.sin(phi[0]) + math.sin(phi[1])) / ((2 + 1.5) * rho**2)
    need = (2 - 1) * rho * abs(acc)
    assert need == pytest.approx(0.3 * (rho * rate**2 + g * math.cos(phi[0])), rel=1e-12)
    assert (1.5 - 1) * rho * abs(acc) < 0.3 * (rho * rate**2 + g * math.cos(phi[1]))  # the disk holds


def test_a_stuck_cluster_counts_its_slipping_members_friction_and_releases_when_it_rolls_again():
    """Review: a particle (front), a ring with backspin and a disk slide down y = 0.3 x (mu = mu_s = 0.4). Sliding,
    the cluster decelerates at a = (-2.5 g sin + 0.8 g cos) / 2.75 (the particle's and the ring's kinetic friction,
    the ring with its translational mass) and stops at t = 0.2 sigma / a. There its load is 0.75 m g cos along the
    slope less the ring's kinetic friction 0.4 m g cos: 0.35 < mu_s = 0.4, it sticks (the ring's friction left out
    of the load, it had turned uphill against its mode). The ring spins down at mu g cos; rolling, its friction is
    gone from the load, 0.75 > 0.4: the cluster slides at once (it had stayed stuck). Every joule is friction work."""
    particle = Body.of_shape("particle", 0, mass=1)
    ring, disk = Body.of_shape("ring", "0.05", mass=1), Body.of_shape("disk", "0.05", mass="0.5")
    sigma = math.sqrt(1.09)
    scene = Scene.make(CurveTrack.make("0.3*x", "-3", "3"), [particle, ring, disk], ["0", "1e-30", repr(0.1 / sigma)],
                       ["-0.2"] * 3, law=make_law("newton", 0), friction="0.4", static_friction="0.4",
                       slip=[0, "-6", 0], track_sides="one", g=G, run=RunSettings.make("2.5"))
    result = simulate(scene)
    assert result.status is Status.COMPLETED, result.message
    g_cos, g_sin = 9.81 / sigma, 9.81 * 0.3 / sigma
    a = (-2.5 * g_sin + 0.8 * g_cos) / 2.75
    t_stop = 0.2 * sigma / a
    t_spun = t_stop + (6 - (a + 0.4 * g_cos) * t_stop) / (0.4 * g_cos)
    rows = [tr[:4] for tr in result.transitions]
    assert rows[:2] == [(pytest.approx(t_stop, abs=1e-12), 0, "sliding-", "stuck"),
                        (pytest.approx(t_stop, abs=1e-12), 2, "rolling", "stuck")]
    assert (pytest.approx(t_spun, abs=1e-9), 0, "stuck", "sliding-") in rows
    assert result.final_modes == ("sliding-", "rolling", "rolling")
    assert result.energy_initial - result.energy_final == pytest.approx(sum(result.friction_work), rel=1e-12)


def test_the_table_counts_a_stuck_clusters_rolling_member_as_rolling():
    """Review: a disk hits a stuck particle + ring cluster; the table's energy_after counted the ring (mode 'stuck')
    as slipping with no spin: 0.116 J short, exactly 1/2 (kappa - 1) m v^2 of the ring after the impact."""
    particle, ring, disk = (Body.of_shape("particle", 0, mass=1), Body.of_shape("ring", "0.05", mass=1),
                            Body.of_shape("disk", "0.05", mass=1))
    scene = Scene.make(CurveTrack.make("0.2*x", "-3", "3"), [particle, ring, disk], ["0", "1e-30", "0.5"], [0, 0, "-1"],
                       law=make_law("newton", 0), friction="0.5", static_friction="0.5", g=G, run=RunSettings.make("0.6"))
    result = simulate(scene)
    table = result.collision_table()
    sigma2 = 1.04
    kinetic = [sum(0.5 * kappa * sigma2 * float(s[3 + i]) ** 2 for i, kappa in enumerate((1, 2, 1.5)))
               for s in (result.states_before[0], result.states_after[0])]
    assert table["energy_before"][0] - table["energy_after"][0] == pytest.approx(kinetic[0] - kinetic[1], rel=1e-13)
    impacts = float((table["energy_before"] - table["energy_after"]).sum())
    assert result.energy_initial - result.energy_final == pytest.approx(sum(result.friction_work) + impacts, rel=1e-12)


def test_a_rolling_body_resting_on_a_stop_spins_down_and_keeps_its_energy_account():
    """Review: a ring on y = x/2 (mu = mu_s = 0.05: it slips from the start) comes to rest on the plastic lower stop.
    Its centre held, its spin runs down at u' = mu g cos / (kappa - 1) until it rolls (at rest) again; it had kept the
    free body's slip equation, its slip grew to -9.6 m/s and the energy rose by 51 J. Every joule now: the friction
    work plus the stop's 1/2 m v^2 (the impulse through the centre leaves the spin)."""
    ring = Body.of_shape("ring", "0.05", mass=1)
    scene = Scene.make(CurveTrack.make("0.5*x", "-1.5", "1.5"), [ring], ["-1.4"], ["0"], law=make_law("newton", 1),
                       friction="0.05", static_friction="0.05", limiter_restitution="0", g=G, run=RunSettings.make(3))
    result = simulate(scene)
    assert result.status is Status.COMPLETED, result.message
    stop = result.passage_table()[0]
    sigma = math.sqrt(1.25)
    v = sigma * stop["dq_before"]
    rows = [tr[:4] for tr in result.transitions]
    assert rows[-1][1:] == (0, "sliding+", "rolling") and result.final_modes == ("rolling",)
    # sliding down from rest: v' = g sin - mu g cos, u' = mu g cos / (kappa - 1): at the stop w = v - u; then w -> -u ...
    g_cos, g_sin = 9.81 / sigma * 1, 9.81 * 0.5 / sigma
    u_stop = -0.05 * g_cos * stop["t"]  # (spinning down the slope)
    assert v == pytest.approx(-(g_sin - 0.05 * g_cos) * stop["t"], rel=1e-12)
    assert rows[-1][0] - stop["t"] == pytest.approx(-u_stop / (0.05 * g_cos), rel=1e-9)
    lost = result.energy_initial - result.energy_final
    assert lost == pytest.approx(sum(result.friction_work) + 0.5 * v * v, rel=1e-12)
