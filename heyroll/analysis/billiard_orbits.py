"""Periodic orbits of a billiard table and their stability (paper section 7.1; issue 14).

A periodic orbit of period n and rotation number p/n of a ball of radius R
is a closed n-gon inscribed in the curve its centre reaches (the cushion's
inner parallel curve; the reflection there is specular, its normal being the
cushion's), with equal angles of incidence and reflection at every vertex.
Those are exactly the critical points of the perimeter
L(theta_1, ..., theta_n) = sum |C(theta_{k+1}) - C(theta_k)| (Birkhoff's
variational principle): dL/dtheta_k = C'(theta_k) . (e_{k-1} - e_k) = 0, e_k
the unit chord from vertex k to k + 1. Birkhoff's theorem gives at least two
for every p/n on a smooth convex table: the one of largest perimeter and a
minimax one.

Search: Newton's method on grad L (Hessian by central differences,
least-squares steps, so the degenerate families of an integrable table,
Poncelet's orbits in an ellipse, are reached too) from the regular polygon
theta_k = theta_0 + 2 pi p k/n for several theta_0; orbits found twice are
merged. Stability: the trace of the linearized return map (n reflections),
computed by central differences of the billiard map in mpmath with the
independent reference's geometry (heyroll.reference.billiard): |trace| < 2
elliptic (stable), > 2 hyperbolic (unstable), = 2 parabolic (the families
of integrable tables).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import mpmath
import numpy as np

from ..errors import SceneError

#: Starting phases theta_0 tried (spread over one step 2 pi / n of the regular polygon).
STARTS = 12


@dataclass(frozen=True)
class PeriodicOrbit:
    period: int
    rotation: int
    #: the centre's vertices, (n, 2)
    points: np.ndarray
    #: parameters theta_k on the centre's curve
    thetas: np.ndarray
    perimeter: float
    #: sin of the reflection angle (from the inward normal) at each vertex
    sin_reflection: np.ndarray
    #: "max" (the largest perimeter: every Hessian eigenvalue < 0), "minimax", or "family" (one of a
    #: continuous family of parabolic orbits of one perimeter, as Poncelet's in an ellipse)
    kind: str
    trace: float
    stability: str

    def as_dict(self) -> dict:
        return {"period": self.period, "rotation": self.rotation, "kind": self.kind, "perimeter": self.perimeter,
                "trace": self.trace, "stability": self.stability,
                "points": [[float(x), float(y)] for x, y in self.points],
                "sin_reflection": [float(v) for v in self.sin_reflection]}


def periodic_orbits(scene, period: int, rotation: int = 1, ball: int = 1) -> list[PeriodicOrbit]:
    """Periodic orbits of ``period`` impacts and rotation number ``rotation/period`` for ball ``ball``."""
    if not isinstance(period, int) or period < 2:
        raise SceneError("--period", f"must be a whole number >= 2, got {period!r}")
    if not isinstance(rotation, int) or not 1 <= rotation < period / 2 + (period % 2 == 0) * 0.5 or \
            np.gcd(rotation, period) != 1:
        raise SceneError("--rotation", f"must be a whole number p with 1 <= p <= period/2 and gcd(p, period) = 1, "
                                       f"got {rotation!r}")
    if not 1 <= ball <= scene.n_bodies:
        raise SceneError("--ball", f"must be a ball number 1..{scene.n_bodies}, got {ball}")
    radius = scene.balls[ball - 1].body.radius
    curve = _Curve(scene.boundary, radius)
    found: list[np.ndarray] = []
    step = 2 * np.pi * rotation / period
    for theta0 in np.linspace(0, 2 * np.pi / period, STARTS, endpoint=False):
        thetas = _newton(curve, theta0 + step * np.arange(period))
        if thetas is None or not _rotates(thetas, rotation, period):
            continue
        if not any(_same_orbit(curve, thetas, other) for other in found):
            found.append(thetas)
    orbits = []
    for thetas in found:
        orbit = _describe(scene, curve, thetas, rotation, radius)
        # an integrable table's orbits come in families of one perimeter (Poncelet's porism in the
        # ellipse: every n-gon tangent to one caustic closes, with the same length): one stands for all
        same = [o for o in orbits if o.stability == orbit.stability == "parabolic"
                and abs(o.perimeter - orbit.perimeter) < 1e-9 * orbit.perimeter]
        if same:
            continue
        if orbit.stability == "parabolic":
            orbit = dataclasses.replace(orbit, kind="family")
        orbits.append(orbit)
    return sorted(orbits, key=lambda o: -o.perimeter)


class _Curve:
    def __init__(self, boundary, radius):
        self.boundary, self.radius = boundary, radius

    def __call__(self, theta):
        x, y, dx, dy = self.boundary.centre_curve(self.radius, np.asarray(theta, float))
        return np.stack([x, y], -1), np.stack([dx, dy], -1)


def _gradient(curve, thetas):
    points, tangents = curve(thetas)
    chords = np.roll(points, -1, axis=0) - points
    e = chords / np.linalg.norm(chords, axis=1)[:, None]
    return np.sum(tangents * (np.roll(e, 1, axis=0) - e), axis=1), np.linalg.norm(chords, axis=1).sum()


def _hessian(curve, thetas, h=1e-6):
    n = len(thetas)
    hess = np.empty((n, n))
    for k in range(n):
        d = np.zeros(n)
        d[k] = h
        hess[:, k] = (_gradient(curve, thetas + d)[0] - _gradient(curve, thetas - d)[0]) / (2 * h)
    return (hess + hess.T) / 2


def _newton(curve, thetas):
    for _ in range(60):
        grad, _ = _gradient(curve, thetas)
        if np.max(np.abs(grad)) < 1e-13:
            return thetas
        step = np.linalg.lstsq(_hessian(curve, thetas), -grad, rcond=1e-10)[0]
        limit = np.pi / (2 * len(thetas))
        if np.max(np.abs(step)) > limit:
            step *= limit / np.max(np.abs(step))
        thetas = thetas + step
    grad, _ = _gradient(curve, thetas)
    return thetas if np.max(np.abs(grad)) < 1e-10 else None


def _rotates(thetas, rotation, period) -> bool:
    """The vertices go round the table ``rotation`` times, each step forward by less than a turn."""
    steps = np.mod(np.diff(np.concatenate([thetas, thetas[:1] + 2 * np.pi * rotation])), 2 * np.pi)
    return abs(steps.sum() - 2 * np.pi * rotation) < 1e-6 and np.all(steps > 1e-9)


def _same_orbit(curve, a, b) -> bool:
    pa, _ = curve(a)
    pb, _ = curve(b)
    for shift in range(len(a)):
        rolled = np.roll(pb, shift, axis=0)
        if np.max(np.abs(pa - rolled)) < 1e-7 or np.max(np.abs(pa - rolled[::-1])) < 1e-7:
            return True
    return False


def _describe(scene, curve, thetas, rotation, radius) -> PeriodicOrbit:
    points, tangents = curve(thetas)
    chords = np.roll(points, -1, axis=0) - points
    perimeter = float(np.linalg.norm(chords, axis=1).sum())
    out = chords / np.linalg.norm(chords, axis=1)[:, None]
    t = tangents / np.linalg.norm(tangents, axis=1)[:, None]
    sin_reflection = np.sum(out * t, axis=1)  # the outgoing chord's component along the tangent
    eig = np.linalg.eigvalsh(_hessian(curve, thetas))
    kind = "max" if np.all(eig < 1e-7 * np.max(np.abs(eig))) else "minimax"
    trace = return_map_trace(scene, points, out, radius)
    if abs(trace - 2) < 1e-6 or abs(trace + 2) < 1e-6:
        stability = "parabolic"
    else:
        stability = "stable" if abs(trace) < 2 else "unstable"
    return PeriodicOrbit(period=len(thetas), rotation=rotation, points=points, thetas=np.mod(thetas, 2 * np.pi),
                         perimeter=perimeter, sin_reflection=sin_reflection, kind=kind, trace=trace,
                         stability=stability)


def return_map_trace(scene, points, directions, radius, dps: int = 30, h: str = "1e-12") -> float:
    """Trace of the linearized n-bounce return map at a periodic orbit, in mpmath.

    Coordinates: the chord's start, moved along the first chord by a (so it
    is inside the table), and the chord's direction angle psi; the n-bounce
    map takes (a, psi) on the first chord to the same chord's line after n
    reflections, read as (signed offset across the chord, psi). The trace
    does not depend on the coordinates.
    """
    from ..reference.billiard import _cushion_time, _reflect

    n = len(points)
    with mpmath.workdps(dps):
        hh = mpmath.mpf(h)
        p0 = [mpmath.mpf(float(v)) for v in points[0]]
        d0 = [mpmath.mpf(float(v)) for v in directions[0]]
        psi0 = mpmath.atan2(d0[1], d0[0])
        chord = mpmath.sqrt(sum((mpmath.mpf(float(points[1][k])) - p0[k]) ** 2 for k in range(2)))
        mid = [p0[k] + d0[k] * chord / 2 for k in range(2)]  # the middle of the first chord
        across = [-d0[1], d0[0]]
        r = mpmath.mpf(radius)

        def bounce(offset, psi):
            ball = [mid[0] + offset * across[0], mid[1] + offset * across[1], mpmath.cos(psi), mpmath.sin(psi)]
            for _ in range(n):
                tau, normal = _cushion_time(scene.boundary, ball, r, 0)
                ball[0] += ball[2] * tau
                ball[1] += ball[3] * tau
                _reflect(ball, normal, 1)
            # back on the first chord's line: where it crosses the normal line through mid
            vx, vy = ball[2], ball[3]
            along = (mid[0] - ball[0]) * d0[0] + (mid[1] - ball[1]) * d0[1]
            speed_along = vx * d0[0] + vy * d0[1]
            t = along / speed_along
            x, y = ball[0] + vx * t, ball[1] + vy * t
            return (x - mid[0]) * across[0] + (y - mid[1]) * across[1], mpmath.atan2(vy, vx)

        def psi_wrap(v):
            return (v - psi0 + mpmath.pi) % (2 * mpmath.pi) - mpmath.pi

        col = []
        for do, dp in ((hh, 0), (0, hh)):
            plus = bounce(do, psi0 + dp)
            minus = bounce(-do, psi0 - dp)
            col.append(((plus[0] - minus[0]) / (2 * hh), (psi_wrap(plus[1]) - psi_wrap(minus[1])) / (2 * hh)))
        return float(col[0][0] + col[1][1])
