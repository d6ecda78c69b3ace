"""Tracks other than the circle (paper section 5) and the rotating frame (5.3).

Two kinds of track, both in a vertical plane (x to the right, y up):

* :class:`ArcChainTrack`, circular arcs (concave: the body rolls inside;
  convex: on top) and straight segments joined with continuous tangents
  (section 5.1, Figs. 13-16). The coordinate of a body is ``s``, the arc
  length along the path of its centre; on each piece that path is a circle of
  radius R - r (concave) or R0 + r (convex) or a straight line, and its
  curvature jumps at the junctions.
* :class:`CurveTrack`, a curve y = f(x) given as an expression; the coordinate
  is the abscissa x of the contact point (section 5.3, eqs. 91-95).

The body always lies on the left of the direction in which the track runs
(so on top of a curve run from left to right). Its centre is the contact point
plus r times the left normal. A :class:`Frame` rotates the plane about a
vertical axis at constant Omega.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import mpmath
import numpy as np

from ..errors import SceneError
from . import expression as ex
from ._numbers import Real, is_finite, to_mpf, workprec
from .bodies import Body, Shape

#: Moment of inertia about a diameter (the vertical axis through the centre,
#: when the body rolls in a vertical plane), in units of m r^2. It only shifts
#: the rotating frame's first integral by a constant (paper eq. 92's J_z).
DIAMETRAL_INERTIA = {
    Shape.SOLID_SPHERE: mpmath.mpf(2) / 5,
    Shape.HOLLOW_SPHERE: mpmath.mpf(2) / 3,
    Shape.DISK: mpmath.mpf(1) / 4,
    Shape.RING: mpmath.mpf(1) / 2,
    Shape.PARTICLE: mpmath.mpf(0),
}

TANGENT_TOLERANCE = 1e-12


def diametral_inertia(body: Body) -> mpmath.mpf | None:
    """J about the vertical axis through the centre, or None for a body given by kappa."""
    if body.shape is None:
        return None
    with workprec():
        return DIAMETRAL_INERTIA[body.shape] * body.mass * body.radius**2


@dataclass(frozen=True)
class Frame:
    """The vertical plane rotates about the vertical line x = axis_x at omega (rad/s)."""

    omega: mpmath.mpf
    axis_x: mpmath.mpf

    @classmethod
    def make(cls, omega: Real = 0, axis_x: Real = 0, field: str = "frame") -> "Frame":
        for name, value in (("omega", omega), ("axis_x", axis_x)):
            if not is_finite(value):
                raise SceneError(f"{field}.{name}", f"must be a finite number, got {value!r}")
        return cls(omega=to_mpf(omega), axis_x=to_mpf(axis_x))

    @property
    def rotating(self) -> bool:
        return self.omega != 0


STATIONARY = Frame(mpmath.mpf(0), mpmath.mpf(0))


# -------------------------------------------------------------------- arc chains

@dataclass(frozen=True)
class Segment:
    """One piece of an arc chain, as given in the scene.

    ``arc``: radius R, ``side`` concave (angles phi from the lowest point of
    its circle, counter-clockwise, as on the circle track) or convex (angles
    psi from the top, clockwise, as in paper eq. 86); the track runs from
    ``start`` to ``end`` (start < end). ``line``: tangent ``angle`` from the
    +x axis and ``length``.
    """

    kind: str
    radius: mpmath.mpf = mpmath.mpf(0)
    side: str = ""
    start: mpmath.mpf = mpmath.mpf(0)
    end: mpmath.mpf = mpmath.mpf(0)
    angle: mpmath.mpf = mpmath.mpf(0)
    length: mpmath.mpf = mpmath.mpf(0)

    def tangents(self) -> tuple[mpmath.mpf, mpmath.mpf]:
        """Direction of travel (angle from +x) at the start and the end."""
        if self.kind == "line":
            return self.angle, self.angle
        if self.side == "concave":
            return self.start, self.end  # tangent of O + R(sin phi, -cos phi) is phi
        return -self.start, -self.end  # tangent of O + R(sin psi, cos psi) is -psi


@dataclass(frozen=True)
class PathPiece:
    """The path of a body's centre over one segment, as a function of arc length s.

    alpha(s) = alpha0 + c (s - s0) is the tangent angle (c: signed curvature,
    +1/rho concave, -1/rho convex, 0 on a line);
    x_C = A + B sin(alpha) + D (s - s0),  y_C = E - B cos(alpha) + G (s - s0).
    """

    s0: float
    s1: float
    alpha0: float
    c: float
    A: float
    B: float
    D: float
    E: float
    G: float

    def alpha(self, s):
        return self.alpha0 + self.c * (s - self.s0)

    def centre(self, s, lib=np):
        a = self.alpha(s)
        return (self.A + self.B * lib.sin(a) + self.D * (s - self.s0),
                self.E - self.B * lib.cos(a) + self.G * (s - self.s0))


@dataclass(frozen=True)
class ArcChainTrack:
    """Arcs and lines joined with continuous tangents, with limiters at both ends."""

    segments: tuple[Segment, ...]
    start_x: mpmath.mpf
    start_y: mpmath.mpf
    kind = "arcs"

    @classmethod
    def make(cls, segments, start_x: Real = 0, start_y: Real = 0, field: str = "track") -> "ArcChainTrack":
        if not segments:
            raise SceneError(f"{field}.segments", "at least one segment is required")
        segs = tuple(segments)
        for n, seg in enumerate(segs, start=1):
            where = f"{field}.segments[{n}]"
            if seg.kind == "arc":
                if seg.side not in ("concave", "convex"):
                    raise SceneError(f"{where}.side", f"must be concave or convex, got {seg.side!r}")
                if not seg.radius > 0:
                    raise SceneError(f"{where}.radius", f"must be > 0, got {mpmath.nstr(seg.radius, 17)}")
                if not seg.end > seg.start:
                    raise SceneError(f"{where}.end", "must be > start (the track runs from start to end)")
                if seg.end - seg.start > 2 * mpmath.pi:
                    raise SceneError(f"{where}.end", "an arc spans at most 2 pi")
            elif seg.kind == "line":
                if not seg.length > 0:
                    raise SceneError(f"{where}.length", f"must be > 0, got {mpmath.nstr(seg.length, 17)}")
            else:
                raise SceneError(f"{where}.kind", f"unknown segment kind {seg.kind!r}; expected arc | line")
        for n in range(1, len(segs)):
            before, after = segs[n - 1].tangents()[1], segs[n].tangents()[0]
            jump = float(mpmath.fmod(after - before + 3 * mpmath.pi, 2 * mpmath.pi) - mpmath.pi)
            if abs(jump) > TANGENT_TOLERANCE:
                raise SceneError(
                    f"{field}.segments[{n + 1}].start",
                    f"tangent does not match the end of segment {n}: direction {float(after):.17g} rad "
                    f"vs {float(before):.17g} rad (a jump of {jump:.3g} rad); the track must be smooth",
                )
        return cls(segments=segs, start_x=to_mpf(start_x), start_y=to_mpf(start_y))

    @classmethod
    def three_arcs(cls, radius: Real, hump_radius: Real, beta: Real = 0, field: str = "track") -> "ArcChainTrack":
        """Paper section 5.1: concave R, convex R0, concave R with central angles
        3pi/2 - beta, pi - 2 beta, 3pi/2 - beta (Figs. 13-16); the hump's centre
        is at the origin, so x = 0 is the axis of symmetry."""
        R, R0, b = (to_mpf(v) for v in (radius, hump_radius, beta))
        if not R > 0:
            raise SceneError(f"{field}.radius", f"must be > 0, got {radius}")
        if not R0 > 0:
            raise SceneError(f"{field}.hump_radius", f"must be > 0, got {hump_radius}")
        if not (0 <= b < mpmath.pi / 2):
            raise SceneError(f"{field}.beta", f"must be in [0, pi/2), got {beta}")
        with workprec():
            half = mpmath.pi / 2 - b
            d = R + R0
            segs = (
                Segment("arc", R, "concave", -mpmath.pi, half),
                Segment("arc", R0, "convex", -half, half),
                Segment("arc", R, "concave", -half, mpmath.pi),
            )
            return cls.make(segs, start_x=-d * mpmath.cos(b), start_y=d * mpmath.sin(b) + R, field=field)

    def surface_points(self):
        """Start point of each segment and the chain's end point (mpmath)."""
        x, y = self.start_x, self.start_y
        points = [(x, y)]
        with workprec():
            for seg in self.segments:
                x, y = _advance(seg, x, y)
                points.append((x, y))
        return points

    def check_body(self, body: Body, field: str) -> None:
        for n, seg in enumerate(self.segments, start=1):
            if seg.kind == "arc" and seg.side == "concave" and not body.radius < seg.radius:
                raise SceneError(
                    f"{field}.radius",
                    f"must be < the radius of concave segment {n} ({mpmath.nstr(seg.radius, 17)} m): "
                    "the body cannot roll inside an arc smaller than itself",
                )

    def pieces(self, body: Body, exact: bool = False) -> tuple[PathPiece, ...]:
        """The centre path of ``body`` over every segment, s from 0 at the chain start
        (floats; with ``exact`` the same pieces in mpmath numbers at model precision)."""
        return _pieces(self, body, exact)

    def _build_pieces(self, body: Body, exact: bool) -> tuple[PathPiece, ...]:
        out, s = [], mpmath.mpf(0)
        r = body.radius
        with workprec():
            for seg, (px, py) in zip(self.segments, self.surface_points()):
                a0 = seg.tangents()[0]
                if seg.kind == "line":
                    length = seg.length
                    cx, cy = px - r * mpmath.sin(a0), py + r * mpmath.cos(a0)
                    piece = (a0, 0, cx, 0, mpmath.cos(a0), cy, mpmath.sin(a0))
                else:
                    concave = seg.side == "concave"
                    rho = seg.radius - r if concave else seg.radius + r
                    ox, oy = _arc_centre(seg, px, py)
                    length = rho * (seg.end - seg.start)
                    b = rho if concave else -rho
                    piece = (a0, 1 / b, ox, b, 0, oy, 0)
                a0, c, A, B, D, E, G = piece
                conv = (lambda v: to_mpf(v)) if exact else float
                out.append(PathPiece(*(conv(v) for v in (s, s + length, a0, c, A, B, D, E, G))))
                s += length
        return tuple(out)

    def path_length(self, body: Body) -> float:
        return self.pieces(body)[-1].s1

    def coordinate_of(self, body: Body, segment: int, angle: Real, field: str) -> mpmath.mpf:
        """s for a body on ``segment`` (1-based) at ``angle`` (phi, psi or distance on a line)."""
        if not 1 <= segment <= len(self.segments):
            raise SceneError(f"{field}.segment", f"must be in 1..{len(self.segments)}, got {segment}")
        seg = self.segments[segment - 1]
        a = to_mpf(angle)
        lo, hi = (0, seg.length) if seg.kind == "line" else (seg.start, seg.end)
        if not lo <= a <= hi:
            raise SceneError(f"{field}.angle", f"must be within segment {segment}: [{float(lo):.17g}, {float(hi):.17g}]")
        piece = self.pieces(body)[segment - 1]
        with workprec():
            if seg.kind == "line":
                return to_mpf(piece.s0) + a
            return to_mpf(piece.s0) + abs(1 / to_mpf(piece.c)) * (a - seg.start)

    def rate_scale(self, body: Body, segment: int) -> mpmath.mpf:
        """ds/d(angle) on ``segment``: rho on arcs, 1 on lines."""
        seg = self.segments[segment - 1]
        if seg.kind == "line":
            return mpmath.mpf(1)
        return seg.radius - body.radius if seg.side == "concave" else seg.radius + body.radius


@lru_cache(maxsize=256)
def _pieces(track: ArcChainTrack, body: Body, exact: bool) -> tuple[PathPiece, ...]:
    # pure function of frozen inputs: the geometry is computed once per (track, body)
    return track._build_pieces(body, exact)


def _arc_centre(seg: Segment, px, py):
    if seg.side == "concave":
        return px - seg.radius * mpmath.sin(seg.start), py + seg.radius * mpmath.cos(seg.start)
    return px - seg.radius * mpmath.sin(seg.start), py - seg.radius * mpmath.cos(seg.start)


def _advance(seg: Segment, x, y):
    if seg.kind == "line":
        return x + seg.length * mpmath.cos(seg.angle), y + seg.length * mpmath.sin(seg.angle)
    ox, oy = _arc_centre(seg, x, y)
    if seg.side == "concave":
        return ox + seg.radius * mpmath.sin(seg.end), oy - seg.radius * mpmath.cos(seg.end)
    return ox + seg.radius * mpmath.sin(seg.end), oy + seg.radius * mpmath.cos(seg.end)


# ------------------------------------------------------------------ y = f(x)

NUMPY = ex.Library(number=float, functions={"sin": np.sin, "cos": np.cos, "exp": np.exp, "sqrt": np.sqrt})
MPMATH = ex.Library(number=lambda t: mpmath.mpf(t), functions={
    "sin": mpmath.sin, "cos": mpmath.cos, "exp": mpmath.exp, "sqrt": mpmath.sqrt})

#: Points at which a curve is checked (curvature, finiteness) before a run.
CURVE_CHECK_POINTS = 20001


@dataclass(frozen=True)
class CurveTrack:
    """y = f(x) on [x_min, x_max], limiters at both ends; bodies roll on top."""

    text: str
    f: ex.Node
    df: ex.Node
    d2f: ex.Node
    d3f: ex.Node
    x_min: mpmath.mpf
    x_max: mpmath.mpf
    kind = "curve"

    @classmethod
    def make(cls, y: str, x_min: Real, x_max: Real, field: str = "track") -> "CurveTrack":
        f = ex.parse(y, f"{field}.y")
        ex.check_differentiable(f, f"{field}.y")
        for name, value in (("x_min", x_min), ("x_max", x_max)):
            if not is_finite(value):
                raise SceneError(f"{field}.{name}", f"must be a finite number, got {value!r}")
        lo, hi = to_mpf(x_min), to_mpf(x_max)
        if not hi > lo:
            raise SceneError(f"{field}.x_max", f"must be > x_min, got x_min = {x_min}, x_max = {x_max}")
        df = ex.derivative(f)
        d2f = ex.derivative(df)
        track = cls(text=y, f=f, df=df, d2f=d2f, d3f=ex.derivative(d2f), x_min=lo, x_max=hi)
        xs = track.check_grid()
        with np.errstate(all="ignore"):
            for node, what in ((f, "y"), (df, "dy/dx"), (d2f, "d2y/dx2")):
                values = track.numeric(node, xs)
                bad = ~np.isfinite(values)
                if bad.any():
                    raise SceneError(f"{field}.y", f"{what} is not finite at x = {xs[bad][0]:.17g} "
                                     f"(the curve must be smooth on [x_min, x_max])")
        return track

    def check_grid(self) -> np.ndarray:
        return np.linspace(float(self.x_min), float(self.x_max), CURVE_CHECK_POINTS)

    def numeric(self, node: ex.Node, x):
        value = ex.evaluate(node, np.asarray(x, dtype=float), NUMPY)
        return np.broadcast_to(value, np.shape(x)).astype(float)

    def curvature(self, x):
        """Signed curvature f'' / (1 + f'^2)^(3/2), > 0 where the curve is concave up."""
        d1, d2 = self.numeric(self.df, x), self.numeric(self.d2f, x)
        return d2 / (1 + d1 * d1) ** 1.5

    def check_body(self, body: Body, field: str) -> None:
        """The body on top must fit every hollow: curvature radius > r (eq. 94's 1 - r k > 0)."""
        if body.radius == 0:
            return
        xs = self.check_grid()
        k = self.curvature(xs)
        n = int(np.argmax(k))
        # refine the worst point on a finer grid around it
        h = xs[1] - xs[0]
        fine = np.linspace(max(xs[0], xs[n] - h), min(xs[-1], xs[n] + h), 2001)
        kf = self.curvature(fine)
        m = int(np.argmax(kf))
        r = float(body.radius)
        if kf[m] * r >= 1:
            raise SceneError(
                f"{field}.radius",
                f"the curve's radius of curvature falls to {1 / kf[m]:.6g} m at x = {fine[m]:.6g} "
                f"(concave side), below the body's radius {r:.6g} m: it cannot roll there",
            )

    def centre(self, x, r: float):
        """Centre of a body of radius r touching at abscissa x (eq. 95 and its x part)."""
        d1 = self.numeric(self.df, x)
        w = np.sqrt(1 + d1 * d1)
        return x - r * d1 / w, self.numeric(self.f, x) + r / w

    def metric(self, x, r: float):
        """F(x, r) = (1 + f'^2)(1 - r f''/(1 + f'^2)^(3/2))^2 (eq. 94): |dC/dx|^2."""
        d1, d2 = self.numeric(self.df, x), self.numeric(self.d2f, x)
        w2 = 1 + d1 * d1
        return w2 * (1 - r * d2 / w2**1.5) ** 2
