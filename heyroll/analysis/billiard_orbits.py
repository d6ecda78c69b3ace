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


def periodic_orbits(scene, period: int, rotation: int | None = None, ball: int = 1,
                    progress=None) -> list[PeriodicOrbit]:
    """Periodic orbits of ``period`` impacts and rotation number ``rotation/period`` for ball ``ball``.

    ``rotation`` None: 1 on a smooth table; on a polygon every rotation number (each orbit says its own: a
    rectangle's orbits of period 6 have 3, see :func:`_polygon_orbits`). ``progress``: called as
    ``progress(done, total, stage)`` as the searches go (a polygon's side sequences, a smooth table's starts)."""
    if not isinstance(period, int) or period < 2:
        raise SceneError("--period", f"must be a whole number >= 2, got {period!r}")
    polygon = hasattr(scene.boundary, "centre_polygon")
    if rotation is not None and (not isinstance(rotation, int) or not 1 <= rotation <= period // 2
                                 or (not polygon and np.gcd(rotation, period) != 1)):
        rule = "1 <= p <= period/2" + ("" if polygon else " and gcd(p, period) = 1")
        raise SceneError("--rotation", f"must be a whole number p with {rule}, got {rotation!r}")
    if not 1 <= ball <= scene.n_bodies:
        raise SceneError("--ball", f"must be a ball number 1..{scene.n_bodies}, got {ball}")
    radius = scene.balls[ball - 1].body.radius
    if polygon:
        rotations = range(1, period // 2 + 1) if rotation is None else (rotation,)
        found = [o for p in rotations for o in _polygon_orbits(scene, period, p, radius, progress)]
        return sorted(found, key=lambda o: (o.rotation, -o.perimeter))
    rotation = 1 if rotation is None else rotation
    curve = _Curve(scene.boundary, radius)
    found: list[np.ndarray] = []
    step = 2 * np.pi * rotation / period
    for done, theta0 in enumerate(np.linspace(0, 2 * np.pi / period, STARTS, endpoint=False)):
        if progress is not None:
            progress(done, STARTS, f"{len(found)} found")
        thetas = _newton(curve, theta0 + step * np.arange(period))
        if thetas is None or not _rotates(thetas, rotation, period):
            continue
        if not any(_same_orbit(curve, thetas, other) for other in found):
            found.append(thetas)
    if progress is not None:
        progress(STARTS, STARTS, f"{len(found)} found")
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


#: Side sequences tried at most for a polygon's orbits of one period (each a small Newton solve), and the
#: longest period searched there.
MAX_CODES = 5000
MAX_POLYGON_PERIOD = 8
#: Starts of Newton's method per side sequence: the middle of every side, then seeded random ones.
POLYGON_STARTS = 4


def _polygon_orbits(scene, period: int, rotation: int, radius, progress=None) -> list[PeriodicOrbit]:
    """The periodic orbits of a ball's centre in a polygonal table, by their sequences of sides.

    The perimeter of an inscribed n-gon is not smooth where a vertex passes a corner, so the search of
    the smooth tables does not apply. Each cyclic sequence of n sides (no side twice in a row; one per
    orbit up to rotation and reversal; none that repeats a shorter one) fixes the sides of the vertices
    P_k = V_{s_k} + t_k (V_{s_k + 1} - V_{s_k}), and the perimeter is smooth in t: its critical points
    with every t_k in (0, 1), the chord arriving from inside and leaving inward, are the orbits of that
    sequence (Birkhoff's variational principle again). Going once round the table passes each of its m
    corners once, so an orbit of rotation number p/n passes p m corners on its way (counted
    counter-clockwise from each vertex to the next; p <= n/2, the orbit run the way it turns less): that
    selects the sequences. Unlike on a smooth table p and n need not be coprime: an orbit of a polygon
    need not move its vertices round the table monotonically (a rectangle's orbits of period 6 pass 12
    corners, rotation 3). Newton's method starts from the middle of every side and from seeded random
    points (POLYGON_STARTS), its steps damped; periods up to MAX_POLYGON_PERIOD are searched (the
    sequences grow as (m - 1)^n, and a family's sequence can still be missed: a 4 x 2 rectangle's
    (3, 1) family of period 8 is). A sequence whose unfolding closes by a translation gives a family of parallel orbits of
    one perimeter (the Hessian then has a zero eigenvalue): one member stands for it, kind "family";
    every orbit of a polygon is parabolic (|trace| = 2: the return map is a shear or its mirror image).
    Fagnano's orbit of an acute triangle, its orthic triangle, is the isolated minimum of period 3.
    """
    if period > MAX_POLYGON_PERIOD:
        raise SceneError("--period", f"on a polygonal table at most {MAX_POLYGON_PERIOD} (its orbits are searched by "
                                     f"their sequences of sides), got {period}")
    corners = scene.boundary.centre_polygon(radius)
    m = len(corners)
    ends = np.roll(corners, -1, axis=0)
    edges = ends - corners
    lengths = np.hypot(*edges.T)
    normals = np.stack([edges[:, 1], -edges[:, 0]], 1) / lengths[:, None]  # outward (counter-clockwise polygon)
    codes = _side_codes(m, period, rotation)
    if codes is None:
        raise SceneError("--period", f"a {m}-sided table has more than {MAX_CODES} side sequences of period {period} "
                                     f"to search; take a shorter period")
    starts = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
    orbits = []
    for done, code in enumerate(codes):
        if progress is not None:
            progress(done, len(codes), f"rotation {rotation}: {len(orbits)} found")
        code = np.array(code)

        def perimeter_gradient(t):
            points = corners[code] + t[:, None] * edges[code]
            chords = np.roll(points, -1, axis=0) - points
            norms = np.linalg.norm(chords, axis=1)
            u = chords / norms[:, None]
            return np.sum(edges[code] * (np.roll(u, 1, axis=0) - u), axis=1), points, u, norms

        rng = np.random.default_rng(0)  # (deterministic: the same orbits every time)
        for start in [np.full(period, 0.5)] + [rng.uniform(0.2, 0.8, period) for _ in range(POLYGON_STARTS - 1)]:
            t = _polygon_newton(perimeter_gradient, start, lengths.max())
            if t is None:
                continue
            t = _into_sides(perimeter_gradient, t)
            grad, points, u, norms = perimeter_gradient(t)
            inside = np.all((t > 1e-9) & (t < 1 - 1e-9))
            # the chord into vertex k comes from inside (toward its side), the one out of it goes inward
            reflects = np.all(np.sum(normals[code] * np.roll(u, 1, axis=0), axis=1) > 1e-12) and \
                np.all(np.sum(normals[code] * u, axis=1) < -1e-12)
            if inside and reflects and np.max(np.abs(grad)) < 1e-10 * lengths.max():
                break
        else:
            continue
        eig = np.linalg.eigvalsh(_polygon_hessian(perimeter_gradient, t))
        scale = np.max(np.abs(eig))
        if np.min(np.abs(eig)) < 1e-7 * scale:
            kind = "family"
        else:
            kind = "min" if np.all(eig > 0) else "max" if np.all(eig < 0) else "minimax"
        tangents = edges[code] / lengths[code][:, None]
        trace = return_map_trace(scene, points, u, radius)
        thetas = 2 * np.pi * (starts[code] + t * lengths[code]) / lengths.sum()
        orbits.append(PeriodicOrbit(period=period, rotation=rotation, points=points, thetas=thetas,
                                    perimeter=float(norms.sum()), sin_reflection=np.sum(u * tangents, axis=1),
                                    kind=kind, trace=trace, stability=_stability(trace)))
    if progress is not None:
        progress(len(codes), len(codes), f"rotation {rotation}: {len(orbits)} found")
    return sorted(orbits, key=lambda o: -o.perimeter)


def _polygon_newton(perimeter_gradient, t, size: float):
    """Newton's least-squares steps on the perimeter's gradient from ``t``, each at most a quarter of a side (an
    undamped start diverged to 1e9 for a rectangle's (2, 1) family); None where it leaves the sides' stretch or
    does not converge."""
    for _ in range(40):
        grad, _points, _u, norms = perimeter_gradient(t)
        if not np.all(norms > 1e-12 * size) or np.any(t < -0.5) or np.any(t > 1.5):
            return None
        if np.max(np.abs(grad)) < 1e-14 * size:
            return t
        step = np.linalg.lstsq(_polygon_hessian(perimeter_gradient, t), -grad, rcond=1e-10)[0]
        t = t + step * min(1.0, 0.25 / max(np.max(np.abs(step)), 1e-300))
    return t if np.max(np.abs(perimeter_gradient(t)[0])) < 1e-10 * size else None


def _into_sides(perimeter_gradient, t):
    """A critical point of a family (the Hessian singular along the family's direction v) moved along v to the
    middle of the stretch where every vertex lies inside its side: Newton's least-squares step stops at the member
    nearest its start, which can lie past a corner (a 4 x 2 rectangle's (2, 1) family of period 6 was missed)."""
    eig, vec = np.linalg.eigh(_polygon_hessian(perimeter_gradient, t))
    scale = np.max(np.abs(eig)) if eig.size else 0.0
    for m in np.flatnonzero(np.abs(eig) < 1e-7 * scale):
        v = vec[:, m]
        low, high = -np.inf, np.inf
        for tk, vk in zip(t, v):
            if abs(vk) < 1e-12:
                continue
            a, b = (1e-6 - tk) / vk, (1 - 1e-6 - tk) / vk
            low, high = max(low, min(a, b)), min(high, max(a, b))
        if low < high and np.isfinite(low) and np.isfinite(high):
            t = t + (low + high) / 2 * v
    return t


def _polygon_hessian(perimeter_gradient, t):
    return _central_hessian(lambda x: perimeter_gradient(x)[0], t, 1e-7)


def _side_codes(m: int, period: int, rotation: int) -> list[tuple]:
    """Cyclic sequences of ``period`` sides of an m-gon, no side twice in a row, passing rotation * m corners
    counter-clockwise on their way (or (period - rotation) m: the same orbits run backwards), one per orbit up
    to rotation and reversal, none a repetition of a shorter one."""
    codes = []
    targets = {rotation * m, (period - rotation) * m}
    visited = [0]

    def extend(code, passed):
        visited[0] += 1
        if len(codes) > MAX_CODES or visited[0] > 50 * MAX_CODES:
            return
        if len(code) == period:
            closing = (code[0] - code[-1]) % m
            if closing and passed + closing in targets and _canonical(code):
                codes.append(tuple(code))
            return
        for side in range(m):
            step = (side - code[-1]) % m
            if step and passed + step + (period - len(code) - 1) <= max(targets):
                extend(code + [side], passed + step)

    for first in range(m):
        extend([first], 0)
    return None if len(codes) > MAX_CODES or visited[0] > 50 * MAX_CODES else codes


def _canonical(code: list) -> bool:
    """The code is the least of its rotations and reversed rotations, and repeats no shorter code."""
    n = len(code)
    variants = [tuple(code[k:] + code[:k]) for k in range(n)]
    reverse = code[::-1]
    variants += [tuple(reverse[k:] + reverse[:k]) for k in range(n)]
    if tuple(code) != min(variants):
        return False
    return not any(n % d == 0 and tuple(code) == tuple(code[d:] + code[:d]) for d in range(1, n))


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


def _hessian(curve, thetas):
    return _central_hessian(lambda x: _gradient(curve, x)[0], thetas, 1e-6)


def _central_hessian(gradient, x, h: float):
    """The Hessian of a function by central differences of its ``gradient``, symmetrized."""
    n = len(x)
    hess = np.empty((n, n))
    for k in range(n):
        d = np.zeros(n)
        d[k] = h
        hess[:, k] = (gradient(x + d) - gradient(x - d)) / (2 * h)
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
    return PeriodicOrbit(period=len(thetas), rotation=rotation, points=points, thetas=np.mod(thetas, 2 * np.pi),
                         perimeter=perimeter, sin_reflection=sin_reflection, kind=kind, trace=trace,
                         stability=_stability(trace))


def _stability(trace: float) -> str:
    """|trace| of the linearized return map < 2 stable (elliptic), > 2 unstable, = 2 parabolic (to 1e-6)."""
    if abs(abs(trace) - 2) < 1e-6:
        return "parabolic"
    return "stable" if abs(trace) < 2 else "unstable"


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
