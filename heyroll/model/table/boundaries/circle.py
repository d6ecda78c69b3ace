"""A circular table of radius R_t: the ball's centre stays within R_t - R of the centre."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import mpmath
import numpy as np

from ....errors import SceneError
from ..._numbers import workprec
from .base import positive_length as _positive_length


@dataclass(frozen=True)
class CircleBoundary:
    radius: mpmath.mpf

    kind: ClassVar[str] = "circle"

    def __post_init__(self):
        _positive_length(self, "radius")

    def check_ball(self, radius, field: str) -> None:
        if radius >= self.radius:
            raise SceneError(field, f"a ball of radius {mpmath.nstr(radius, 6)} does not fit in a circular table "
                                    f"of radius {mpmath.nstr(self.radius, 6)}")

    def n_walls(self) -> int:
        return 1

    def wall_constants(self, radius) -> tuple:
        with workprec():
            return (((self.radius - radius) ** 2,),)

    def gap(self, wall, x, y, c):
        return x * x + y * y - c[0]

    def gap_scale(self, wall, c):
        """Magnitude of the gap function's terms at the wall (its round-off is a few ulps of this)."""
        return c[0]

    def gradient(self, wall, x, y, c):
        return 2 * x, 2 * y

    def least_curvature_radius(self, radius) -> float:
        return float(self.radius - radius)

    def centre_curve(self, radius, theta):
        """(x, y, dx/dtheta, dy/dtheta) of the curve a ball's centre reaches, theta in [0, 2 pi) (numpy)."""
        rho = float(self.radius - radius)
        return rho * np.cos(theta), rho * np.sin(theta), -rho * np.sin(theta), rho * np.cos(theta)

    def perimeter(self) -> float:
        return float(2 * mpmath.pi * self.radius)

    def arc_length(self, px, py):
        return float(self.radius) * np.mod(np.arctan2(py, px), 2 * np.pi)

    def outline(self, n: int = 400):
        t = np.linspace(0, 2 * np.pi, n)
        return float(self.radius) * np.cos(t), float(self.radius) * np.sin(t)

    def describe(self) -> str:
        return f"circular table R={mpmath.nstr(self.radius, 6)}"
