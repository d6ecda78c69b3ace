"""The phase portrait of a billiard: the Birkhoff map of many launches of one ball (paper section 7).

Each launch starts on the curve the ball's centre reaches (a hair inside it)
at a boundary parameter theta, leaving at the angle asin(p) from the inward
normal, and is run by the engine for a number of cushion impacts; each impact
gives a point (s, p) in the Birkhoff coordinates: the contact point's arc
length s along the cushion and p, the sine of the reflection angle. For a
particle in an ellipse the points of one launch lie on an invariant curve
(its caustic); a finite ball or a stadium-like table breaks them up.
"""

from __future__ import annotations

import dataclasses

import mpmath
import numpy as np

from ..errors import SceneError

#: Launches start this fraction of the table's size inside the curve of the centre.
INSIDE = 1e-9


def birkhoff_portrait(scene, runs: int = 12, impacts: int = 300, ball: int = 1, p_max: float = 0.95,
                      progress=None) -> list[dict]:
    """``runs`` launches of ball ``ball`` alone (the other balls removed), ``impacts`` cushion impacts each.

    Returns per launch: theta, p (the launch), status, and the arrays ``s``, ``sin_angle``. A launch runs
    until its ``impacts``-th impact or for ``impacts`` times the longest a chord can take (the table's
    extent twice over at the launch speed), so that a ball that settles onto a cushion with k < 1 (it
    rides it: no impact comes any more) ends; it then has fewer points, status completed. A launch
    interrupted (Ctrl-C) ends the portrait: the launches so far are returned, the last one with status
    interrupted.
    """
    from ..simulation.driver import simulate

    if not isinstance(runs, int) or runs < 1:
        raise SceneError("--runs", f"must be a whole number >= 1, got {runs!r}")
    if not isinstance(impacts, int) or impacts < 1:
        raise SceneError("--impacts", f"must be a whole number >= 1, got {impacts!r}")
    if not 1 <= ball <= scene.n_bodies:
        raise SceneError("--ball", f"must be a ball number 1..{scene.n_bodies}, got {ball}")
    template = scene.balls[ball - 1]
    radius = template.body.radius
    speed = float(mpmath.sqrt(template.vx**2 + template.vy**2)) or 1.0
    bx, by = scene.boundary.outline()
    longest_chord = 2 * float(max(np.ptp(bx), np.ptp(by))) / speed
    golden = (np.sqrt(5) - 1) / 2
    out = []
    for k in range(runs):
        theta = 2 * np.pi * ((k * golden) % 1.0)
        p = -p_max + 2 * p_max * (k + 0.5) / runs
        x, y, dx, dy = (float(v) for v in scene.boundary.centre_curve(radius, np.array(theta)))
        tangent = np.array([dx, dy]) / np.hypot(dx, dy)
        inward = np.array([-tangent[1], tangent[0]])  # the curve runs counter-clockwise: its left is inside
        size = max(abs(x), abs(y), 1.0)
        start = np.array([x, y]) + INSIDE * size * inward
        direction = np.sqrt(1 - p * p) * inward + p * tangent
        launched = dataclasses.replace(template, x=mpmath.mpf(start[0]), y=mpmath.mpf(start[1]),
                                       vx=mpmath.mpf(speed * direction[0]), vy=mpmath.mpf(speed * direction[1]),
                                       ux=mpmath.mpf(0), uy=mpmath.mpf(0))
        alone = dataclasses.replace(scene, balls=(launched,))
        result = simulate(alone, t_end=impacts * longest_chord, max_collisions=impacts, max_events=None)
        table = result.collision_table()
        cushion = table[table["j"] == 0]
        out.append({"theta": theta, "p": p, "status": result.status.value, "message": result.message,
                    "s": cushion["boundary_s"], "sin_angle": np.sin(cushion["reflection_angle"])})
        if progress is not None:
            progress(k + 1, runs)
        if result.status.value == "interrupted":
            break
    return out
