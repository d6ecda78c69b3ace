"""A rectangular table (width along x, height along y) centred on the origin.

A convex polygon (its four walls are straight), kept as its own kind because
the rectangle is the billiard that unfolds: reflected in its walls a path is
a straight line, which gives every impact time in closed form (tests).
Arc length starts at the corner (-width/2, -height/2), counter-clockwise.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import mpmath

from ....errors import SceneError
from ..._numbers import workprec
from .polygon import PolygonBoundary


@dataclass(frozen=True)
class RectangleBoundary(PolygonBoundary):
    width: mpmath.mpf = mpmath.mpf(1)
    height: mpmath.mpf = mpmath.mpf(1)

    kind: ClassVar[str] = "rectangle"

    @classmethod
    def of_size(cls, width, height) -> "RectangleBoundary":
        for name, value in (("width", width), ("height", height)):
            if not value > 0:
                raise SceneError(f"track.{name}", f"must be > 0, got {mpmath.nstr(value, 6)}")
        with workprec():
            w, h = width / 2, height / 2
            verts = ((-w, -h), (w, -h), (w, h), (-w, h))
        return cls(vertices=verts, width=width, height=height)

    def check_ball(self, radius, field: str) -> None:
        if 2 * radius >= min(self.width, self.height):
            raise SceneError(field, f"a ball of radius {mpmath.nstr(radius, 6)} does not fit in a "
                                    f"{mpmath.nstr(self.width, 6)} x {mpmath.nstr(self.height, 6)} table")

    def describe(self) -> str:
        return f"rectangular table {mpmath.nstr(self.width, 6)} x {mpmath.nstr(self.height, 6)}"
