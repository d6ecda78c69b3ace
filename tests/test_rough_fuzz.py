"""Property-based fuzzing (hypothesis) of rough tracks (issue 15).

Random scenes: 1-4 bodies (particles under Newton's law, or rolling bodies under the
rolling law), on a circle, a parabola, the cycloid (parametric) or a curve in a turning
plane; random mu, mu_s >= mu, restitution, one- or two-sided, touching or apart, at rest
or moving, sometimes a rolling body's initial slip or a periodic force. Properties:

* every run ends with a status of the Status enum, never ``failed`` nor ``overlap``;
* each body's transitions chain: every ``from`` is the previous ``to``, times ascend;
* without forcing: the fall of mechanical energy is the friction work plus the impacts'
  losses (collisions and limiters for particles; for rolling bodies, slipping ones and
  clusters, collisions where no limiter took any), to 1e-9 of the energy scale;
* on the dense trajectory, a sliding particle never moves against its mode's sign and a
  stuck one never moves.

Deterministic (derandomize=True): CI draws the same examples every time.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from heyroll.errors import SceneError
from heyroll.model.bodies import Body
from heyroll.model.forcing import Forcing
from heyroll.model.frame import Frame
from heyroll.model.laws import make_law
from heyroll.model.scene import RunSettings, Scene
from heyroll.model.tracks import CircleTrack, CurveTrack, ParametricTrack
from heyroll.simulation.driver import simulate
from heyroll.simulation.result import Status

#: Examples in the default run (~60 s on 2 cores: most of it compiles a new scene shape), and in
#: the slow run (``python -m pytest -m slow tests/test_rough_fuzz.py``).
EXAMPLES, SLOW_EXAMPLES = (16, 5), (200, 40)
FUZZ = dict(deadline=None, derandomize=True, database=None,
            suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])

TRACKS = {
    "circle": (lambda: CircleTrack.of_radius(1), (-1.4, 1.4), None),
    "parabola": (lambda: CurveTrack.make("x**2/2", -2, 2), (-1.8, 1.8), None),
    "cycloid": (lambda: ParametricTrack.make("u - sin(u)", "1 + cos(u)", "0.6", "5.68"), (0.8, 5.4), None),
    "turning": (lambda: CurveTrack.make("x**2", -1, 1), (-0.9, 0.9), "2"),
}


@st.composite
def rough_scenes(draw):
    name = draw(st.sampled_from(sorted(TRACKS)))
    make_track, (lo, hi), omega = TRACKS[name]
    track = make_track()
    particles = draw(st.booleans())
    n = draw(st.integers(1, 4))
    if particles:
        bodies = [Body.of_shape("particle", 0, mass=draw(st.floats(0.2, 5.0))) for _ in range(n)]
        law = make_law("newton", draw(st.sampled_from((0.0, 0.3, 0.7, 1.0))))
    else:
        shape = draw(st.sampled_from(("disk", "solid_sphere", "ring")))
        bodies = [Body.of_shape(shape, "0.05", mass=draw(st.floats(0.2, 5.0))) for _ in range(n)]
        law = make_law("hedrih", draw(st.sampled_from((0.0, 0.5, 1.0))))
    qs = sorted(draw(st.lists(st.floats(lo, hi), min_size=n, max_size=n)))
    # some bodies start touching (particles: at one point)
    if particles and n > 1 and draw(st.booleans()):
        qs[1] = qs[0]
    assume(all(b - a > 0.12 for a, b in zip(qs, qs[1:])) or particles)
    dqs = [draw(st.sampled_from((0.0, 0.0, 0.5, -0.5, 2.0, -2.0))) for _ in range(n)]
    mu = draw(st.sampled_from((0.0, 0.01, 0.1, 0.3, 1.0)))
    mu_s = mu * draw(st.sampled_from((1.0, 1.5, 3.0)))
    slip = None
    if not particles and draw(st.booleans()):
        slip = [draw(st.sampled_from((0.0, 0.5, -0.5))) for _ in range(n)]
    forcing = None
    if draw(st.integers(0, 4)) == 0:
        forcing = Forcing.make(draw(st.sampled_from(("force", "base"))), amplitude=draw(st.sampled_from((0.05, 1.0))),
                               frequency=draw(st.sampled_from((1.0, 5.0))))
    try:
        return Scene.make(track, bodies, qs, dqs, law=law, friction=mu, static_friction=mu_s, slip=slip,
                          forcing=forcing, frame=Frame.make(omega) if omega else Frame.make(0),
                          track_sides=draw(st.sampled_from(("one", "two"))),
                          # (limiter restitution 0 beside an elastic neighbour: the squeeze Zeno of
                          # tests/test_hard_cases.py::test_a_body_squeezed_between_a_plastic_stop_and_a_neighbour,
                          # an engine bug older than friction, xfail there)
                          limiter_restitution=draw(st.sampled_from((0.3, 0.5, 1.0))),
                          run=RunSettings.make(draw(st.sampled_from((1.0, 3.0))), 200))
    except SceneError:
        assume(False)


def _check(result):
    scene = result.scene
    assert isinstance(result.status, Status)
    assert result.status not in (Status.FAILED, Status.OVERLAP), result.message
    last: dict = {}
    for t, k, old, new, _q, _dq in result.transitions:
        if k in last:
            assert old == last[k][1] and t >= last[k][0]
        last[k] = (t, new)
    if scene.forcing is not None or not result.success:
        return
    if not all(b.is_particle for b in scene.bodies):
        # rolling bodies (slipping too, inside clusters too): every joule is friction work or a row's loss, where
        # no limiter took any (a limiter's loss depends on the member's mode and the cluster's rigid rebound)
        if any(kind != 0 for _t, _b, kind, *_rest in result.passages):
            return
        table = result.collision_table()
        impacts = float((table["energy_before"] - table["energy_after"]).sum()) if table.size else 0.0
        scale = 1.0 + abs(result.energy_initial) + sum(result.friction_work)
        assert abs(result.energy_initial - result.energy_final - sum(result.friction_work) - impacts) <= 1e-9 * scale
        return
    table = result.collision_table()
    impacts = float((table["energy_before"] - table["energy_after"]).sum()) if table.size else 0.0
    for _t, b, kind, _f, _to, q, v, w in result.passages:
        if kind != 0:
            sigma = float(scene.track.sigma(scene.bodies[b], float(q)))
            impacts += 0.5 * float(scene.bodies[b].mass) * sigma * sigma * (float(v) ** 2 - float(w) ** 2)
    scale = 1.0 + abs(result.energy_initial) + sum(result.friction_work)
    assert abs(result.energy_initial - result.energy_final - sum(result.friction_work) - impacts) <= 1e-9 * scale


def _modes_followed(scene):
    assume(all(b.is_particle for b in scene.bodies))
    result = simulate(scene, dense=True)
    assume(result.success and result.transitions)
    times = np.linspace(0, float(result.t_final), 4001)
    states = result.states_at(times)
    n = len(scene.bodies)
    for k in range(n):
        rows = [r for r in result.transitions if r[1] == k]
        starts = np.array([r[0] for r in rows])
        modes = [rows[0][2] if rows else result.final_modes[k]] + [r[3] for r in rows]
        rate = states[:, n + k]
        tol = 1e-9 * (1 + float(np.abs(rate).max()))
        for t, v in zip(times, rate):
            mode = modes[int(np.searchsorted(starts, t, side="right"))]
            if mode == "sliding+":
                assert v >= -tol, (k, t, v, mode)
            elif mode == "sliding-":
                assert v <= tol, (k, t, v, mode)
            else:
                assert abs(v) <= tol or math.isclose(t, float(starts[np.searchsorted(starts, t) - 1]), abs_tol=1e-9), \
                    (k, t, v, mode)


@settings(**FUZZ, max_examples=EXAMPLES[0])
@given(rough_scenes())
def test_random_rough_scenes_run_cleanly_and_account_for_their_energy(scene):
    _check(simulate(scene))


@settings(**FUZZ, max_examples=EXAMPLES[1])
@given(rough_scenes())
def test_random_rough_scenes_keep_every_particle_moving_with_its_mode(scene):
    _modes_followed(scene)


@pytest.mark.slow
@settings(**FUZZ, max_examples=SLOW_EXAMPLES[0])
@given(rough_scenes())
def test_rough_fuzz_volume(scene):
    _check(simulate(scene))


@pytest.mark.slow
@settings(**FUZZ, max_examples=SLOW_EXAMPLES[1])
@given(rough_scenes())
def test_rough_fuzz_volume_modes(scene):
    _modes_followed(scene)
