"""What a billiard table's cushion is to the engine (paper section 7).

A boundary is a closed convex curve with vertical walls. A ball of radius R
keeps its centre inside the boundary's inner parallel curve at distance R
(Fig. 22: "the geometric location of the points of ball centres of the
impacts"), so every cushion is seen through its *walls*: smooth pieces of
that parallel curve, each with a gap function g(x, y) of the centre that is
negative inside, zero at contact and a polynomial in x, y (so that heyoka's
event detection finds its roots to machine precision).

Every function below is written with + - * / only, so it evaluates heyoka
expressions, floats, longdoubles, real128, MPFR reals and mpmath numbers
alike: the engine compiles it, the reference evaluates it in mpmath.
"""

from __future__ import annotations

from typing import ClassVar, Protocol, runtime_checkable

import mpmath
import numpy as np


@runtime_checkable
class Boundary(Protocol):
    """A convex table boundary (see the module docstring)."""

    kind: ClassVar[str]

    def check_ball(self, radius, field: str) -> None:
        """Raise SceneError when a ball of this radius cannot roll along every wall."""
        ...

    def n_walls(self) -> int:
        ...

    def wall_constants(self, radius) -> tuple[tuple, ...]:
        """Per wall, the constants of its gap function for a ball of ``radius`` (mpmath numbers)."""
        ...

    def gap(self, wall: int, x, y, c):
        """Gap function of ``wall`` at centre (x, y) with constants ``c``: < 0 inside, 0 at contact."""
        ...

    def gap_scale(self, wall: int, c):
        """Magnitude of the gap function's terms at the wall: its round-off is a few ulps of this."""
        ...

    def gradient(self, wall: int, x, y, c) -> tuple:
        """(dg/dx, dg/dy): points out of the table; its direction is the cushion's outward normal."""
        ...

    def perimeter(self) -> float:
        ...

    def arc_length(self, px, py):
        """Arc length (numpy, float64) of boundary points (px, py) from the boundary's origin, counter-clockwise."""
        ...

    def outline(self, n: int = 400):
        """(x, y) arrays of the closed boundary, for figures."""
        ...

    def describe(self) -> str:
        ...


def signed_area(vertices) -> mpmath.mpf:
    """Twice the signed area of a polygon (> 0 counter-clockwise)."""
    total = 0
    for k in range(len(vertices)):
        (x0, y0), (x1, y1) = vertices[k], vertices[(k + 1) % len(vertices)]
        total += x0 * y1 - x1 * y0
    return total


def sqrt(value):
    """Square root in the number's own type (mpmath, float, numpy longdouble, heyoka real128 / real)."""
    if isinstance(value, mpmath.mpf):
        return mpmath.sqrt(value)
    return np.sqrt(value)


def unit_normal(gx, gy):
    """The unit vector along (gx, gy) in the numbers' own type."""
    norm = sqrt(gx * gx + gy * gy)
    return gx / norm, gy / norm


def positive_length(boundary, name: str) -> None:
    """Make ``boundary.name`` an mpmath number at model precision, refusing one that is not > 0."""
    from ....errors import SceneError
    from ..._numbers import is_finite, to_mpf

    value = getattr(boundary, name)
    if not is_finite(value) or not to_mpf(value) > 0:
        raise SceneError(f"track.{name}", f"must be a finite number > 0, got {value!r}")
    object.__setattr__(boundary, name, to_mpf(value))
