"""Relative equilibria of a rolling pendulum on a path track, and their bifurcations.

The effective potential of a body in the rotating plane (section 5.3) is
V(q) = m g y_C(q) - 1/2 m Omega^2 (x_C(q) - a)^2, so the equilibria are the
roots of V'(q) = m [g y_C' - Omega^2 (x_C - a) x_C'] and, with the positive
inertia kappa m F, a root is a centre where V'' > 0 and a saddle where V'' < 0.

On a curve y = f(x), x_C' = 1 - r k and y_C' = f' (1 - r k) (k the
curvature), so V' = m (1 - r k) h(x) with

    h(x) = g f'(x) - Omega^2 (x - r f'/sqrt(1 + f'^2) - a),

the paper's characteristic equation (97) without its factor 2 kappa / 3:
the equilibria do not depend on the body's inertia at all (gravity and the
centrifugal force are both proportional to m); 2 kappa/3 = 1 only for the
thin disk the paper treats (see papers/ERRATA.md). On an arc chain, with q
the arc length of the centre's path and alpha its tangent angle,
h(s) = g sin(alpha) - Omega^2 (x_C - a) cos(alpha).

On a circle of radius R (centre at the origin) a body of radius r keeps its
centre on the circle of radius rho = R - r, x_C = rho sin(phi),
y_C = -rho cos(phi), with phi from the lowest point, counter-clockwise
positive; the centre's tangent angle is phi itself, so V' = m rho h(phi) with

    h(phi) = g sin(phi) - Omega^2 (rho sin(phi) - a) cos(phi),

and V'' = m rho h'(phi) at a root. The coordinate is periodic: equilibria are
reported once each, with phi in [-pi, pi) (the top is phi = -pi), and there
are no limiters. For a = 0 the bottom is a centre for Omega^2 < g / rho and a
saddle beyond, where two centres branch off at cos(phi) = g / (rho Omega^2)
(the pitchfork of the bead on a turning hoop); the top is always a saddle.
kappa does not enter the equilibria (only their frequencies).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model.bodies import Body
from ..model.frame import STATIONARY, Frame
from ..model.scene import Scene
from ..model.tracks import ArcChainTrack, CircleTrack, CurveTrack, piece_index

#: Samples per unit of the track's parameter range used to bracket roots.
BRACKET_SAMPLES = 20001


@dataclass(frozen=True)
class Equilibrium:
    """A relative equilibrium: contact abscissa x, coordinate q, centre, saddle or neutral (a stretch to x_end)."""

    x: float
    q: float
    type: str
    #: h'(q): > 0 for a centre (V'' = m (1 - r k) h' on a curve, m h' on an arc chain,
    #: m rho h' on a circle)
    stiffness: float
    #: effective potential per unit mass, V/m, at the equilibrium (J/kg)
    potential: float
    #: A neutral stretch (type "neutral": h = 0 all along a flat, fixed track) ends here.
    x_end: float | None = None
    q_end: float | None = None

    def as_json(self) -> dict:
        data = {"x": self.x, "type": self.type}
        if self.x_end is not None:
            data["x_end"] = self.x_end
        return data


@dataclass(frozen=True)
class EquilibriumProblem:
    """h, h' and V/m of one body on one track in one frame, as numpy functions of q."""

    track: CurveTrack | ArcChainTrack | CircleTrack
    body: Body
    frame: Frame = STATIONARY
    g: float = 9.81

    def __post_init__(self):
        self.track.check_body(self.body, "body")

    @property
    def periodic(self) -> bool:
        """True on a circle: q = phi is an angle, the domain [-pi, pi) wraps around."""
        return isinstance(self.track, CircleTrack)

    @property
    def domain(self) -> tuple[float, float]:
        if isinstance(self.track, CurveTrack):
            return float(self.track.x_min), float(self.track.x_max)
        if self.periodic:
            return -np.pi, np.pi
        return 0.0, self.track.path_length(self.body)

    @property
    def rho(self) -> float:
        """Radius of the circle traced by the body's centre, R - r (circle only)."""
        return float(self.track.path_radius(self.body))

    def _chain(self, q):
        pieces = self.track.pieces(self.body)
        q = np.atleast_1d(np.asarray(q, dtype=float))
        idx = piece_index(pieces, q)
        alpha, c, x_c, y_c = (np.empty(q.shape) for _ in range(4))
        for k, p in enumerate(pieces):
            sel = idx == k
            if np.any(sel):
                alpha[sel] = p.alpha(q[sel])
                c[sel] = p.c
                x_c[sel], y_c[sel] = p.centre(q[sel])
        return alpha, c, x_c, y_c

    def h(self, q):
        om2, a, g = float(self.frame.omega) ** 2, float(self.frame.axis_x), self.g
        if isinstance(self.track, CurveTrack):
            t, r = self.track, float(self.body.radius)
            q = np.asarray(q, dtype=float)
            d1 = t.numeric(t.df, q)
            return g * d1 - om2 * (q - r * d1 / np.sqrt(1 + d1 * d1) - a)
        if self.periodic:
            q = np.asarray(q, dtype=float)
            s = np.sin(q)
            return g * s - om2 * (self.rho * s - a) * np.cos(q)
        alpha, _c, x_c, _y = self._chain(q)
        return g * np.sin(alpha) - om2 * (x_c - a) * np.cos(alpha)

    def dh(self, q):
        om2, a, g = float(self.frame.omega) ** 2, float(self.frame.axis_x), self.g
        if isinstance(self.track, CurveTrack):
            t, r = self.track, float(self.body.radius)
            q = np.asarray(q, dtype=float)
            d1, d2 = t.numeric(t.df, q), t.numeric(t.d2f, q)
            return g * d2 - om2 * (1 - r * d2 / (1 + d1 * d1) ** 1.5)
        if self.periodic:
            q = np.asarray(q, dtype=float)
            return g * np.cos(q) - om2 * (self.rho * np.cos(2 * q) + a * np.sin(q))
        alpha, c, x_c, _y = self._chain(q)
        return c * (g * np.cos(alpha) + om2 * (x_c - a) * np.sin(alpha)) - om2 * np.cos(alpha) ** 2

    def centre(self, q):
        if isinstance(self.track, CurveTrack):
            return self.track.centre_at(np.asarray(q, dtype=float), float(self.body.radius))
        if self.periodic:
            return self.track.centre(self.body, q)
        _a, _c, x_c, y_c = self._chain(q)
        return x_c, y_c

    def contact_x(self, q):
        """Abscissa of the contact point (the curve's x; on an arc chain x_C + r sin(alpha);
        on a circle R sin(phi))."""
        if isinstance(self.track, CurveTrack):
            return np.asarray(q, dtype=float)
        if self.periodic:
            return float(self.track.radius) * np.sin(np.asarray(q, dtype=float))
        alpha, _c, x_c, _y = self._chain(q)
        return x_c + float(self.body.radius) * np.sin(alpha)

    def wrap(self, q):
        """q on the circle brought into [-pi, pi) (unchanged on an open track)."""
        if not self.periodic:
            return q
        q = np.asarray(q, dtype=float)
        out = q - 2 * np.pi * np.floor((q + np.pi) / (2 * np.pi))
        out = np.where(out >= np.pi, out - 2 * np.pi, out)
        return float(out) if out.ndim == 0 else out

    def potential(self, q):
        """V/m = g y_C - 1/2 Omega^2 (x_C - a)^2 (J/kg)."""
        x_c, y_c = self.centre(q)
        return self.g * y_c - 0.5 * float(self.frame.omega) ** 2 * (x_c - float(self.frame.axis_x)) ** 2

    def with_omega(self, omega: float) -> "EquilibriumProblem":
        return EquilibriumProblem(self.track, self.body, Frame.make(omega, self.frame.axis_x), self.g)


def problem_of(scene: Scene, body: int = 0) -> EquilibriumProblem:
    if scene.track.kind == "parametric":
        from ..errors import SceneError

        raise SceneError("track.type", "relative equilibria are found on circles, curves y = f(x) and arc chains; "
                         "not yet on a parametric curve")
    return EquilibriumProblem(scene.track, scene.bodies[body], scene.frame, float(scene.g))


def find_equilibria(problem: EquilibriumProblem, samples: int = BRACKET_SAMPLES) -> list[Equilibrium]:
    """All sign-changing roots of h on the track, located to machine precision.

    On an open track they are sorted by x, and roots at the ends of the
    track (on a limiter) are not listed. On a circle the grid goes once
    round (its last node, phi = pi, is the first one, phi = -pi, again, so
    a root at the top is bracketed like any other and listed once), phi is
    reported in [-pi, pi), and the list is sorted by phi (x = R sin(phi)
    takes every value twice).

    A grid brackets the roots (two roots closer than the grid step, which
    only happens within ~step^2 of a bifurcation, show as none); bisection
    then closes each bracket to adjacent doubles.
    """
    lo, hi = problem.domain
    grid = np.linspace(lo, hi, samples)
    if isinstance(problem.track, ArcChainTrack):
        # junctions on the grid: h is continuous there but h' jumps
        grid = np.unique(np.concatenate([grid, [p.s0 for p in problem.track.pieces(problem.body)]]))
    values = problem.h(grid)
    if problem.periodic:
        values[-1] = values[0]  # pi and -pi are one point: one h there, so the wrap bracket is closed
    # A neutral stretch (a flat, fixed track: h = 0 all along) is one neutral equilibrium, not a
    # saddle at every grid node: runs of nodes where h vanishes to rounding.
    scale = problem.g + float(problem.frame.omega) ** 2 * (hi - lo + abs(float(problem.frame.axis_x)))
    flat = np.abs(values) <= 64 * np.finfo(float).eps * scale
    stretches, inside = [], np.zeros(len(grid), dtype=bool)
    k = 0
    while k < len(grid):
        if flat[k]:
            end = k
            while end + 1 < len(grid) and flat[end + 1]:
                end += 1
            if end > k:
                stretches.append((grid[k], grid[end]))
                inside[k:end + 1] = True
            k = end + 1
        else:
            k += 1
    values = np.where(inside, 1.0, values)  # no brackets inside a neutral stretch
    roots = []
    for k in np.flatnonzero(values[:-1] * values[1:] <= 0):
        if inside[k] or inside[k + 1]:
            continue  # the stretch's own end (h reaches 0 there), not a root beside it: it was listed as a saddle
        a, b, fa = grid[k], grid[k + 1], values[k]
        if fa == 0:
            roots.append(a)
            continue
        if values[k + 1] == 0:
            continue  # the next bracket starts on it
        roots.append(_bisect(problem.h, a, b, fa))
    out = []
    edge = 1e-9 * (hi - lo)
    for q in roots:
        if problem.periodic:
            q = problem.wrap(q)
        elif q - lo < edge or hi - q < edge:
            continue  # at a limiter: the stop, not a relative equilibrium of the track
        stiffness = float(np.atleast_1d(problem.dh(q))[0])
        out.append(Equilibrium(
            x=float(np.atleast_1d(problem.contact_x(q))[0]),
            q=float(q), type="center" if stiffness > 0 else "saddle", stiffness=stiffness,
            potential=float(np.atleast_1d(problem.potential(q))[0]),
        ))
    for a, b in stretches:
        out.append(Equilibrium(
            x=float(np.atleast_1d(problem.contact_x(a))[0]), q=float(a), type="neutral", stiffness=0.0,
            potential=float(np.atleast_1d(problem.potential(a))[0]),
            x_end=float(np.atleast_1d(problem.contact_x(b))[0]), q_end=float(b),
        ))
    return sorted(out, key=(lambda e: e.q) if problem.periodic else (lambda e: e.x))


def _bisect(fn, a: float, b: float, fa: float) -> float:
    for _ in range(200):
        m = 0.5 * (a + b)
        if m <= a or m >= b:
            break
        fm = float(np.atleast_1d(fn(m))[0])
        if fm == 0:
            return m
        if (fm < 0) == (fa < 0):
            a, fa = m, fm
        else:
            b = m
    return a if abs(float(np.atleast_1d(fn(a))[0])) <= abs(float(np.atleast_1d(fn(b))[0])) else b


@dataclass(frozen=True)
class Bifurcation:
    """Omega at which the set of equilibria changes: pairs are born or die there."""

    omega: float
    #: contact abscissa of the equilibria born or dying there
    x: float
    before: int
    after: int
    #: their coordinate q (x on a curve, s on an arc chain, phi on a circle)
    q: float = float("nan")


def bifurcation_diagram(problem: EquilibriumProblem, omegas, samples: int = 4001):
    """Equilibria at each Omega: a list of (omega, [Equilibrium])."""
    return [(float(om), find_equilibria(problem.with_omega(float(om)), samples)) for om in omegas]


def bifurcations(problem: EquilibriumProblem, omegas, samples: int = 4001, refine: int = 50) -> list[Bifurcation]:
    """Omegas where the number of equilibria changes, refined by bisection on Omega.

    An interval of the grid where the count changes is split until each piece
    holds one change; on a curve each change is then polished as a fold
    (h = h_x = 0, see :func:`_fold`), on a circle as h = h_phi = 0
    (:func:`_circle_fold`).
    """
    diagram = bifurcation_diagram(problem, omegas, samples)
    count = {float(om): len(eq) for om, eq in diagram}

    def n_at(om: float) -> int:
        if om not in count:
            count[om] = len(find_equilibria(problem.with_omega(om), samples))
        return count[om]

    out = []
    for (o1, e1), (o2, e2) in zip(diagram, diagram[1:]):
        if len(e1) != len(e2):
            _changes(problem, n_at, o1, o2, samples, refine, out, depth=0)
    return out


def _changes(problem, n_at, a: float, b: float, samples: int, refine: int, out: list, depth: int) -> None:
    """Locate every change of the count in (a, b): split at the middle while the
    two halves both change (two events in one interval), then bisect."""
    mid = 0.5 * (a + b)
    na, nm, nb = n_at(a), n_at(mid), n_at(b)
    if depth < 30 and na != nm and nm != nb:
        _changes(problem, n_at, a, mid, samples, refine, out, depth + 1)
        _changes(problem, n_at, mid, b, samples, refine, out, depth + 1)
        return
    lo, hi = a, b
    for _ in range(refine):
        m = 0.5 * (lo + hi)
        if n_at(m) == na:
            lo = m
        else:
            hi = m
    old = find_equilibria(problem.with_omega(lo), samples)
    new = find_equilibria(problem.with_omega(hi), samples)
    born = _new_equilibrium(problem, old, new)
    where, q, omega = born.x, born.q, 0.5 * (lo + hi)
    polish = _fold if isinstance(problem.track, CurveTrack) else _circle_fold if problem.periodic else None
    if polish is not None:
        polished = polish(problem, q, omega)
        # keep the polish only if it converged to the same event
        if np.isfinite(polished[1]) and abs(polished[1] - omega) <= 1e-3 * max(1.0, omega):
            q, omega = problem.wrap(polished[0]), polished[1]
            where = float(np.atleast_1d(problem.contact_x(q))[0])
    out.append(Bifurcation(omega=omega, x=where, before=na, after=n_at(b), q=float(q)))


def _fold(problem: EquilibriumProblem, x: float, omega: float) -> tuple[float, float]:
    """Polish a bifurcation on a curve: h = 0 and h_x = 0 in (x, w = Omega^2).

    Gauss-Newton with the least-squares step, so the symmetric pitchfork
    (where h_xx = 0 and x_C = a make the Jacobian singular) converges too.
    """
    t, r, g, a = problem.track, float(problem.body.radius), problem.g, float(problem.frame.axis_x)
    w = omega * omega
    for _ in range(50):
        d1, d2, d3 = (float(t.numeric(node, x)) for node in (t.df, t.d2f, t.d3f))
        s = 1 + d1 * d1
        x_c = x - r * d1 / np.sqrt(s)
        dx_c = 1 - r * d2 / s**1.5
        ddx_c = -r * (d3 / s**1.5 - 3 * d1 * d2 * d2 / s**2.5)
        F = np.array([g * d1 - w * (x_c - a), g * d2 - w * dx_c])
        J = np.array([[g * d2 - w * dx_c, -(x_c - a)], [g * d3 - w * ddx_c, -dx_c]])
        step = np.linalg.lstsq(J, -F, rcond=None)[0]
        x, w = x + step[0], w + step[1]
        if not (np.isfinite(x) and np.isfinite(w) and w >= 0):
            return float("nan"), float("nan")
        if abs(step[0]) <= 1e-16 * max(1, abs(x)) and abs(step[1]) <= 1e-16 * w:
            break
    return float(x), float(np.sqrt(w))


def _circle_fold(problem: EquilibriumProblem, phi: float, omega: float) -> tuple[float, float]:
    """Polish a bifurcation on a circle: h = 0 and h_phi = 0 in (phi, w = Omega^2).

    h = g sin(phi) - w (rho sin(phi) - a) cos(phi),
    h_phi = g cos(phi) - w (rho cos(2 phi) + a sin(phi)); Gauss-Newton with the
    least-squares step as :func:`_fold` (the symmetric pitchfork at phi = 0,
    w = g / rho, a = 0, has a singular Jacobian and converges linearly).
    """
    rho, g, a = problem.rho, problem.g, float(problem.frame.axis_x)
    w = omega * omega
    for _ in range(200):
        s, c, s2, c2 = np.sin(phi), np.cos(phi), np.sin(2 * phi), np.cos(2 * phi)
        arm = rho * s - a
        bend = rho * c2 + a * s
        F = np.array([g * s - w * arm * c, g * c - w * bend])
        J = np.array([[g * c - w * bend, -arm * c], [-g * s - w * (a * c - 2 * rho * s2), -bend]])
        step = np.linalg.lstsq(J, -F, rcond=None)[0]
        phi, w = phi + step[0], w + step[1]
        if not (np.isfinite(phi) and np.isfinite(w) and w >= 0):
            return float("nan"), float("nan")
        if abs(step[0]) <= 1e-16 * max(1, abs(phi)) and abs(step[1]) <= 1e-16 * w:
            break
    return float(phi), float(np.sqrt(w))


def _new_equilibrium(problem: EquilibriumProblem, old: list[Equilibrium], new: list[Equilibrium]) -> Equilibrium:
    """The equilibrium farthest from any in the other set (where the change happens).

    Distances in x on an open track, in phi (round the circle) on a circle.
    """
    a, b = (old, new) if len(new) > len(old) else (new, old)
    if not a:
        x = float(np.mean([e.x for e in b]))
        q = float(np.mean([e.q for e in b]))
        return Equilibrium(x=x, q=q, type="", stiffness=float("nan"), potential=float("nan"))
    if problem.periodic:
        qs = np.array([e.q for e in a])
        gaps = [min(np.abs(np.remainder(qs - e.q + np.pi, 2 * np.pi) - np.pi)) for e in b]
    else:
        xs = np.array([e.x for e in a])
        gaps = [min(abs(xs - e.x)) for e in b]
    return b[int(np.argmax(gaps))]

