"""A chain of circular arcs and straight segments with limiters at both ends (paper section 5.1).

Arcs (concave: the body rolls inside; convex: on top) and lines joined with
continuous tangents (Figs. 13-16). The coordinate of a body is ``s``, the arc
length along the path of its centre; on each piece that path is a circle of
radius R - r (concave) or R + r (convex) or a straight line, and its
curvature jumps at the junctions. The body lies on the left of the direction
in which the track runs; its centre is the contact point plus r times the
left normal.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import ClassVar

import heyoka as hy
import mpmath
import numpy as np

from ...errors import SceneError
from .._numbers import Real, to_mpf, workprec
from ..bodies import Body, Shape
from .base import BodyTerms, Dynamics

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
    kind: ClassVar[str] = "arcs"
    coordinate: ClassVar[str] = "s"
    closed: ClassVar[bool] = False
    linear_gap: ClassVar[bool] = False
    constant_metric: ClassVar[bool] = True  # s is the centre's arc length: sigma = 1

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

    # -- the Track strategy ------------------------------------------------

    def domain(self, body: Body):
        pieces = self.pieces(body, exact=True)
        return pieces[0].s0, pieces[-1].s1

    def junctions(self, body: Body) -> tuple:
        return tuple(p.s0 for p in self.pieces(body, exact=True)[1:])

    def piece_parameters(self, body: Body, piece: int) -> tuple:
        p = self.pieces(body, exact=True)[piece]
        return (p.alpha0, p.c, p.s0, p.A, p.B, p.D, p.E, p.G)

    def terms(self, body: Body, q, v, dyn: Dynamics, piece_par) -> BodyTerms:
        """On each piece alpha = alpha0 + c (s - s0); sigma = 1, so eq. (93) reads
        s'' = -g/kappa sin(alpha) + Omega^2/kappa (x_C - a) cos(alpha)."""
        alpha0, c, s0, A, B, D, E, G = (piece_par(k) for k in range(8))
        alpha = alpha0 + c * (q - s0)
        x_c = A + B * hy.sin(alpha) + D * (q - s0)
        y_c = E - B * hy.cos(alpha) + G * (q - s0)
        g = dyn.par(dyn.g)
        acc = -dyn.par(dyn.g / body.kappa) * hy.sin(alpha)
        # along the left normal (-sin, cos): c v^2 = N/m - g cos(alpha) - Omega^2 (x_C - a) sin(alpha)
        normal = c * v * v + g * hy.cos(alpha)
        driving = -g * hy.sin(alpha)
        if dyn.frame.rotating:
            with workprec():
                om2, om2_k = dyn.frame.omega**2, dyn.frame.omega**2 / body.kappa
            arm = x_c - dyn.par(dyn.frame.axis_x)
            acc = acc + dyn.par(om2_k) * arm * hy.cos(alpha)
            normal = normal + dyn.par(om2) * arm * hy.sin(alpha)
            driving = driving + dyn.par(om2) * arm * hy.cos(alpha)
        return BodyTerms(x_c=x_c, y_c=y_c, acceleration=acc, normal=normal, sigma=hy.expression(1.0),
                         driving=driving)

    def lowest_centre(self, body: Body) -> float:
        """The lowest height the body's centre has anywhere on the track (m), for energy bounds."""
        return min(_piece_lowest(p) for p in self.pieces(body))

    def holds_below(self, body: Body, height: float) -> bool:
        """Whether, in a fixed plane, the normal force N/m = c s'^2 + g cos(alpha) stays > 0
        wherever the body's centre is at or below ``height`` (m), at any speed.

        A line needs cos(alpha) > 0 (not past vertical); a concave arc (c > 0,
        y_C = E - B cos(alpha)) has cos(alpha) > 0 wherever y_C < E, its
        centre's height; a convex arc (c < 0) can always be left at speed.
        Pieces entirely above ``height`` do not count.
        """
        for p in self.pieces(body):
            if _piece_lowest(p) > height:
                continue
            if p.c < 0:
                return False
            if p.c == 0:
                if math.cos(p.alpha0) <= 0:
                    return False
            elif height >= p.E and _least_cos(p.alpha(p.s0), p.alpha(p.s1)) <= 0:
                return False
        return True

    def centre(self, body: Body, q):
        pieces = self.pieces(body)
        q = np.asarray(q, dtype=float)
        idx = piece_index(pieces, q)
        xs, ys = np.empty(q.shape), np.empty(q.shape)
        for k, piece in enumerate(pieces):
            sel = idx == k
            if np.any(sel):
                xs[sel], ys[sel] = piece.centre(q[sel])
        return xs, ys

    def sigma(self, body: Body, q):
        return np.ones(np.shape(q))

    def tangent_angle(self, body: Body, q):
        pieces = self.pieces(body)
        q = np.asarray(q, dtype=float)
        idx = piece_index(pieces, q)
        out = np.empty(q.shape)
        for k, piece in enumerate(pieces):
            sel = idx == k
            if np.any(sel):
                out[sel] = piece.alpha(q[sel])
        return out

    def describe(self) -> str:
        return f"an arc chain of {len(self.segments)} segments"

    def coordinate_of(self, body: Body, segment: int, angle: Real, field: str) -> mpmath.mpf:
        """s for a body on ``segment`` (1-based) at ``angle`` (phi, psi or distance on a line)."""
        if not 1 <= segment <= len(self.segments):
            raise SceneError(f"{field}.segment", f"must be in 1..{len(self.segments)}, got {segment}")
        seg = self.segments[segment - 1]
        a = to_mpf(angle)
        lo, hi = (0, seg.length) if seg.kind == "line" else (seg.start, seg.end)
        if not lo <= a <= hi:
            raise SceneError(f"{field}.angle", f"must be within segment {segment}: [{float(lo):.17g}, {float(hi):.17g}]")
        piece = self.pieces(body, exact=True)[segment - 1]  # not the float pieces: quad runs start exactly
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


def _piece_lowest(p: PathPiece) -> float:
    """Lowest centre height on a piece: its ends, and on an arc the bottoms of its circle inside it."""
    heights = [p.centre(p.s0, math)[1], p.centre(p.s1, math)[1]]
    if p.c != 0:
        a0, a1 = sorted((p.alpha(p.s0), p.alpha(p.s1)))
        # y = E - B cos(alpha) is lowest where cos(alpha) = sign(B): alpha = 0 or pi (mod 2 pi).
        base = 0.0 if p.B > 0 else math.pi
        k = math.ceil((a0 - base) / (2 * math.pi))
        if base + 2 * math.pi * k <= a1:
            heights.append(p.E - abs(p.B))
    return min(heights)


def _least_cos(a0: float, a1: float) -> float:
    a0, a1 = sorted((a0, a1))
    if math.pi + 2 * math.pi * math.ceil((a0 - math.pi) / (2 * math.pi)) <= a1:
        return -1.0
    return min(math.cos(a0), math.cos(a1))


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




def piece_index(pieces, s) -> np.ndarray:
    """Index of the piece holding each s (a junction belongs to the piece after it)."""
    starts = np.array([float(p.s0) for p in pieces[1:]])
    return np.searchsorted(starts, np.asarray(s, dtype=float), side="right")
