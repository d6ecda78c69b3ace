"""Property-based fuzzing (hypothesis) of billiard tables (issue 14).

Random scenes: an ellipse (b/a from 0.2 to 1), a circle, a rectangle or a random convex
polygon; 1-6 balls of random radii, masses and shapes (or particles), at random places and
velocities; a rolling or sliding law and cushion, random restitutions and friction, either
simultaneity policy. Properties, checked with geometry computed here (not the engine's):

* every run ends with a status of the Status enum; never ``overlap``;
* along every piece of motion the runs record (``result.paths``), no two balls overlap and no
  centre leaves the curve it can reach (ellipse: its distance from the ellipse by mpmath's
  foot point, for a sample of the pieces), to 1e-9 of the table's size;
* where every law conserves energy (k = 1, rolling laws on balls of one kappa and rolling
  cushion), the energy is kept to 1e-11.

Deterministic (derandomize=True): CI draws the same examples every time.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from heyroll.errors import SceneError
from heyroll.interfaces.scene_file import parse_scene
from heyroll.reference.billiard import _ellipse_distance
from heyroll.simulation.driver import simulate
from heyroll.simulation.result import Status

EXAMPLES, SLOW_EXAMPLES = 12, 200
FUZZ = dict(deadline=None, derandomize=True, database=None,
            suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])


@st.composite
def table_scenes(draw):
    kind = draw(st.sampled_from(["ellipse", "circle", "rectangle", "polygon"]))
    if kind == "ellipse":
        a = 2.0
        b = draw(st.floats(0.4, 2.0))
        boundary = f'boundary = "ellipse"\na = {a!r}\nb = {b!r}'
        size, limit = a, min(a, b) ** 2 / max(a, b)
    elif kind == "circle":
        boundary, size, limit = 'boundary = "circle"\nradius = 1.0', 1.0, 0.9
    elif kind == "rectangle":
        boundary, size, limit = 'boundary = "rectangle"\nwidth = 2.0\nheight = 1.0', 1.0, 0.45
    else:
        n = draw(st.integers(3, 8))
        phase = draw(st.floats(0, 1))
        radii = [draw(st.floats(0.8, 1.2)) for _ in range(n)]
        angles = sorted((2 * math.pi * (k + phase * 0.5) / n) for k in range(n))
        vertices = [[r * math.cos(t), r * math.sin(t)] for r, t in zip(radii, angles)]
        boundary = f'boundary = "polygon"\nvertices = {vertices!r}'
        size, limit = 1.2, 0.1
    balls = []
    for _ in range(draw(st.integers(1, 6))):
        shape = draw(st.sampled_from(["solid_sphere", "disk", "ring", "particle"]))
        radius = 0.0 if shape == "particle" else draw(st.floats(0.02, min(0.12, 0.9 * limit)))
        x, y = draw(st.floats(-0.6, 0.6)) * size, draw(st.floats(-0.3, 0.3)) * size
        speed, heading = draw(st.floats(0.0, 2.0)), draw(st.floats(0, 2 * math.pi))
        balls.append(dict(shape=shape, radius=radius, mass=draw(st.floats(0.1, 2.0)), x=x, y=y,
                          vx=speed * math.cos(heading), vy=speed * math.sin(heading)))
    particles = any(b["shape"] == "particle" for b in balls)
    law = draw(st.sampled_from(["newton", "slide", "mirror"] + ([] if particles and len(balls) > 1 else ["hedrih"])))
    cushion = draw(st.sampled_from(["rolling", "slide"]))
    k = draw(st.sampled_from([1.0, 0.8, 0.3]))
    cushion_k = draw(st.sampled_from([1.0, 0.7] + ([0.0] if kind in ("rectangle", "polygon") else [])))
    policy = draw(st.sampled_from(["sequential", "impulses"] if law != "mirror" else ["sequential"]))
    friction = draw(st.sampled_from([0.0, 0.2, 1.0]))
    lines = ["[track]", 'type = "table"', boundary, f'cushion_model = "{cushion}"', f"cushion_restitution = {cushion_k!r}",
             f"friction = {friction!r}"]
    for b in balls:
        lines += ["[[bodies]]"] + [f'{key} = "{value}"' if key == "shape" else f"{key} = {value!r}"
                                   for key, value in b.items()]
    lines += ["[collision]", f'law = "{law}"', f"restitution = {k!r}", f'simultaneous = "{policy}"', "[run]",
              "t_end = 6.0", "max_collisions = 3000"]
    conserving = (k == 1 and cushion_k == 1 and law in ("hedrih", "newton") and cushion == "rolling"
                  and len({b["shape"] for b in balls}) == 1 and (law != "hedrih" or len({b["radius"] for b in balls}) == 1))
    return "\n".join(lines), conserving, size


def check(text, conserving, size):
    try:
        scene = parse_scene(text)
    except SceneError:
        assume(False)
    result = simulate(scene, max_events=20000)
    assert isinstance(result.status, Status)
    assert result.status is not Status.OVERLAP, result.message
    n = scene.n_bodies
    radii = [float(b.body.radius) for b in scene.balls]
    tol = 1e-9 * size
    ends = [p[0] for p in result.paths[1:]] + [float(result.t_final)]
    boundary = scene.boundary
    for m, ((t0, state, acc, riding), t1) in enumerate(zip(result.paths, ends)):
        s = np.array(state).reshape(n, 6)
        for tau in (0.0, (t1 - t0) / 2, t1 - t0):
            a = np.array(acc).reshape(n, 2)
            xy = s[:, :2] + s[:, 2:4] * tau + a * tau**2 / 2
            for i in range(n):
                if tau > 0 and i in riding:  # along the cushion's curve, not a polynomial: checked at the ends
                    continue
                for j in range(i + 1, n):
                    if tau > 0 and j in riding:
                        continue
                    assert np.hypot(*(xy[i] - xy[j])) >= radii[i] + radii[j] - tol
                if boundary.kind == "circle":
                    assert np.hypot(*xy[i]) <= float(boundary.radius) - radii[i] + tol
                elif boundary.kind in ("rectangle", "polygon"):
                    for (x0, y0), (x1, y1) in zip(boundary.vertices, boundary.vertices[1:] + boundary.vertices[:1]):
                        ex, ey = float(x1 - x0), float(y1 - y0)
                        inward = (-(ey), ex)  # counter-clockwise polygon: the inside is on the left
                        d = ((xy[i][0] - float(x0)) * inward[0] + (xy[i][1] - float(y0)) * inward[1]) / math.hypot(ex, ey)
                        assert d >= radii[i] - tol
                elif m % 7 == 0 and tau == 0.0:  # the ellipse: mpmath's distance for a sample of the pieces
                    a_, b_ = float(boundary.a), float(boundary.b)
                    assert (xy[i][0] / a_) ** 2 + (xy[i][1] / b_) ** 2 <= 1 + 1e-12  # a particle at an impact is on it
                    d, _ = _ellipse_distance(mpmath.mpf(a_), mpmath.mpf(b_), mpmath.mpf(xy[i][0]), mpmath.mpf(xy[i][1]))
                    assert float(d) >= radii[i] - tol
    if conserving and result.status.success:
        assert result.energy_final == pytest.approx(result.energy_initial, rel=1e-11, abs=1e-14)


@settings(max_examples=EXAMPLES, **FUZZ)
@given(table_scenes())
def test_random_tables_never_overlap_and_keep_energy(scene):
    check(*scene)


@pytest.mark.slow
@settings(max_examples=SLOW_EXAMPLES, **FUZZ)
@given(table_scenes())
def test_random_tables_never_overlap_and_keep_energy_slow_volume(scene):
    check(*scene)
