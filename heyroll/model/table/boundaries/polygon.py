"""A convex polygonal table: one straight wall per edge.

The inner parallel curve of a convex polygon at distance R is the polygon
with every edge moved inward by R (its corners stay sharp): wall e has the
gap n_e . c - (h_e - R), n_e the edge's outward unit normal, h_e its support
value. A ball fits while every moved edge keeps a positive length:
L_e > R (cot(alpha_0/2) + cot(alpha_1/2)), alpha the interior angles at the
edge's ends. At a corner of that inner polygon the ball touches two cushions
at once; the engine resolves the two impacts at the same instant.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import mpmath
import numpy as np

from ....errors import SceneError
from ..._numbers import to_mpf, workprec
from .base import signed_area


@dataclass(frozen=True)
class PolygonBoundary:
    #: vertices counter-clockwise (mpmath pairs)
    vertices: tuple

    kind: ClassVar[str] = "polygon"

    @classmethod
    def make(cls, vertices, field: str = "track.vertices") -> "PolygonBoundary":
        # (at model precision from the decimal text: mpmath.mpf alone rounded 0.4 to 53 bits, and long, quad and
        # mp runs met a polygon 1e-17 m off the scene's; review)
        verts = tuple((to_mpf(x), to_mpf(y)) for x, y in vertices)
        if len(verts) < 3:
            raise SceneError(field, f"a polygon needs at least 3 vertices, got {len(verts)}")
        with workprec():
            if signed_area(verts) < 0:  # counter-clockwise from the same first vertex (boundary_s starts there)
                verts = verts[:1] + verts[:0:-1]
            n = len(verts)
            for k in range(n):
                (x0, y0), (x1, y1), (x2, y2) = verts[k - 1], verts[k], verts[(k + 1) % n]
                if (x1 - x0) == 0 and (y1 - y0) == 0:
                    raise SceneError(field, f"vertices {k} and {k + 1} coincide")
                cross = (x1 - x0) * (y2 - y1) - (y1 - y0) * (x2 - x1)
                if cross <= 0:
                    raise SceneError(field, f"the polygon must be strictly convex; it turns the wrong way (or not "
                                            f"at all) at vertex {k + 1}")
            # a convex polygon turns once: the exterior angles add up to 2 pi (a star would give 4 pi, ...)
            turn = sum(mpmath.atan2((verts[k][0] - verts[k - 1][0]) * (verts[(k + 1) % n][1] - verts[k][1])
                                    - (verts[k][1] - verts[k - 1][1]) * (verts[(k + 1) % n][0] - verts[k][0]),
                                    (verts[k][0] - verts[k - 1][0]) * (verts[(k + 1) % n][0] - verts[k][0])
                                    + (verts[k][1] - verts[k - 1][1]) * (verts[(k + 1) % n][1] - verts[k][1]))
                       for k in range(n))
            if abs(turn - 2 * mpmath.pi) > mpmath.mpf(10) ** -30:
                raise SceneError(field, "the polygon must be convex and simple (its edges wind more than once)")
        return cls(vertices=verts)

    def _edges(self):
        n = len(self.vertices)
        with workprec():
            for k in range(n):
                (x0, y0), (x1, y1) = self.vertices[k], self.vertices[(k + 1) % n]
                length = mpmath.hypot(x1 - x0, y1 - y0)
                nx, ny = (y1 - y0) / length, -(x1 - x0) / length  # outward for a counter-clockwise polygon
                yield nx, ny, nx * x0 + ny * y0, length

    def _half_angle_cotangents(self):
        n = len(self.vertices)
        with workprec():
            out = []
            for k in range(n):
                (x0, y0), (x1, y1), (x2, y2) = self.vertices[k - 1], self.vertices[k], self.vertices[(k + 1) % n]
                a = mpmath.atan2(y0 - y1, x0 - x1) - mpmath.atan2(y2 - y1, x2 - x1)
                alpha = abs(mpmath.atan2(mpmath.sin(a), mpmath.cos(a)))  # interior angle at vertex k
                out.append(mpmath.cot(alpha / 2))
            return out

    def check_ball(self, radius, field: str) -> None:
        cot = self._half_angle_cotangents()
        n = len(self.vertices)
        with workprec():
            for k, (_nx, _ny, _h, length) in enumerate(self._edges()):
                if length <= radius * (cot[k] + cot[(k + 1) % n]):
                    raise SceneError(field, f"a ball of radius {mpmath.nstr(radius, 6)} cannot reach edge {k + 1} "
                                            f"of the {self.kind} (its centre's polygon loses that edge)")

    def n_walls(self) -> int:
        return len(self.vertices)

    def wall_constants(self, radius) -> tuple:
        with workprec():
            return tuple((nx, ny, h - radius) for nx, ny, h, _ in self._edges())

    def gap(self, wall, x, y, c):
        return c[0] * x + c[1] * y - c[2]

    def gap_scale(self, wall, c):
        """Magnitude of the gap function's terms at the wall (its round-off is a few ulps of this)."""
        # the vertices are mpmath numbers: a float of their size (a scale of round-off, not a value) adds to any
        # run type (quad and MPFR runs raised TypeError on real128 + mpf: review)
        return abs(c[2]) + float(abs(self.vertices[wall][0]) + abs(self.vertices[wall][1]))

    def gradient(self, wall, x, y, c):
        return c[0], c[1]

    def centre_polygon(self, radius) -> np.ndarray:
        """Vertices of the polygon a ball's centre reaches: every edge moved inward by R (float64)."""
        verts = np.array([[float(x), float(y)] for x, y in self.vertices])
        normals = np.array([[float(nx), float(ny)] for nx, ny, _h, _l in self._edges()])
        before = np.roll(normals, 1, axis=0)  # the edge ending at vertex k
        r = float(radius)
        return verts - r * (before + normals) / (1 + np.sum(before * normals, axis=1))[:, None]

    def centre_curve(self, radius, theta):
        """(x, y, dx/dtheta, dy/dtheta) along the centre's polygon, theta in [0, 2 pi) mapped to arc length."""
        verts = self.centre_polygon(radius)
        ends = np.roll(verts, -1, axis=0)
        lengths = np.hypot(*(ends - verts).T)
        total = lengths.sum()
        start = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
        s = np.mod(np.asarray(theta, float), 2 * np.pi) * total / (2 * np.pi)
        k = np.clip(np.searchsorted(start, s, side="right") - 1, 0, len(verts) - 1)
        along = (ends[k] - verts[k]) / lengths[k][..., None]
        point = verts[k] + along * (s - start[k])[..., None]
        scale = total / (2 * np.pi)
        return point[..., 0], point[..., 1], along[..., 0] * scale, along[..., 1] * scale

    def perimeter(self) -> float:
        return float(sum(e[3] for e in self._edges()))

    def arc_length(self, px, py):
        """From vertex 1, counter-clockwise: the edge a point lies on is the one it is closest to."""
        px, py = np.asarray(px, dtype=float), np.asarray(py, dtype=float)
        verts = np.array([[float(x), float(y)] for x, y in self.vertices])
        ends = np.roll(verts, -1, axis=0)
        lengths = np.hypot(*(ends - verts).T)
        start = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
        dist = np.empty((len(verts),) + px.shape)
        along = np.empty_like(dist)
        for k in range(len(verts)):
            d = (ends[k] - verts[k]) / lengths[k]
            t = np.clip((px - verts[k, 0]) * d[0] + (py - verts[k, 1]) * d[1], 0, lengths[k])
            dist[k] = np.hypot(px - verts[k, 0] - t * d[0], py - verts[k, 1] - t * d[1])
            along[k] = start[k] + t
        best = np.argmin(dist, axis=0)
        return np.take_along_axis(along, best[None], axis=0)[0]

    def outline(self, n: int = 400):
        verts = np.array([[float(x), float(y)] for x, y in self.vertices] + [[float(self.vertices[0][0]),
                                                                               float(self.vertices[0][1])]])
        return verts[:, 0], verts[:, 1]

    def describe(self) -> str:
        return f"polygonal table with {len(self.vertices)} vertices"
