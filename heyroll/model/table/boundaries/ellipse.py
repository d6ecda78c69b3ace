"""An elliptical table x^2/a^2 + y^2/b^2 <= 1 (paper Fig. 22).

For a particle (R = 0) the wall is the ellipse itself. For a ball of radius
R the centre moves inside the inner parallel curve at distance R, which is not
a conic: it is the zero set of a polynomial of degree 8 in x, y (degree 4 in
u = x^2, v = y^2), the resultant in lambda of the two foot-point conditions

    a^2 u (b^2 + l)^2 + b^2 v (a^2 + l)^2 = (a^2 + l)^2 (b^2 + l)^2    (the foot point on the ellipse)
    l^2 (u (b^2 + l)^2 + v (a^2 + l)^2) = R^2 (a^2 + l)^2 (b^2 + l)^2  (its distance is R)

(the foot point of (x, y) is (a^2 x/(a^2 + l), b^2 y/(b^2 + l))), freed of
its spurious factors. Its coefficients are below in lengths scaled by a
(A = 1, B = b^2/a^2, r = R^2/a^2); a test checks that it vanishes on the
parallel curve P(theta) - R n(theta) computed independently in mpmath. Inside
the parallel curve the polynomial has no zero (a zero is a point at distance R
from the ellipse along some normal, so within R of it), and it is positive at
the centre, so its negative is the gap. The parallel curve is smooth and
convex only while R < b^2/a (the smallest radius of curvature, at the ends of
the major axis); a larger ball is refused.

Arc length runs from (a, 0) counter-clockwise, through the eccentric angle
theta = atan2(y/b, x/a) and the Fourier series of |P'(theta)|.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar

import mpmath
import numpy as np

from ....errors import SceneError
from ..._numbers import workprec
from .base import positive_length as _positive_length
from .base import sqrt

#: (i, j) of the coefficient of u^i v^j, in the order of ``offset_coefficients``.
OFFSET_MONOMIALS = tuple((i, j) for i in range(5) for j in range(5 - i))


def offset_coefficients(B, r, A=1):
    """Coefficients q_ij of the parallel curve's polynomial sum q_ij u^i v^j (module docstring).

    Derived with a computer-algebra resultant (sympy: resultant of the two
    foot-point conditions in l, factored); checked against the parametric
    parallel curve in tests/test_billiard_tables.py.
    """
    q = {
        (0, 0): (r - A) ** 2 * (A - B) ** 2 * (r - B) ** 2,
        (0, 1): -2 * (r - A) * (A - B) * (-A**2 * B - A**2 * r + 2 * A * B**2 + 2 * A * r**2 - B**2 * r - B * r**2),
        (0, 2): (A**4 - 6 * A**3 * B - 6 * A**3 * r + 6 * A**2 * B**2 + 10 * A**2 * B * r + 6 * A**2 * r**2
                 - 6 * A * B**2 * r - 6 * A * B * r**2 + B**2 * r**2),
        (0, 3): -2 * A * (-A**2 + 2 * A * B + 2 * A * r - B * r),
        (0, 4): A**2,
        (1, 0): -2 * (A - B) * (r - B) * (-2 * A**2 * B + A**2 * r + A * B**2 + A * r**2 + B**2 * r - 2 * B * r**2),
        (1, 1): 2 * (3 * A**3 * B + 2 * A**3 * r - 5 * A**2 * B**2 - 3 * A**2 * B * r + 3 * A**2 * r**2
                     + 3 * A * B**3 - 3 * A * B**2 * r - 5 * A * B * r**2 + 2 * B**3 * r + 3 * B**2 * r**2),
        (1, 2): -2 * (A**3 - A**2 * B + 3 * A**2 * r + 3 * A * B**2 - A * B * r + B**2 * r),
        (1, 3): 2 * A * (A + B),
        (2, 0): (6 * A**2 * B**2 - 6 * A**2 * B * r + A**2 * r**2 - 6 * A * B**3 + 10 * A * B**2 * r
                 - 6 * A * B * r**2 + B**4 - 6 * B**3 * r + 6 * B**2 * r**2),
        (2, 1): -2 * (3 * A**2 * B + A**2 * r - A * B**2 - A * B * r + B**3 + 3 * B**2 * r),
        (2, 2): A**2 + 4 * A * B + B**2,
        (3, 0): 2 * B * (-2 * A * B + A * r + B**2 - 2 * B * r),
        (3, 1): 2 * B * (A + B),
        (4, 0): B**2,
    }
    return tuple(q[m] for m in OFFSET_MONOMIALS)


#: Positions in ``OFFSET_MONOMIALS`` of q_i0, q_i1, ... for each power i of u.
_ROWS = tuple(tuple(OFFSET_MONOMIALS.index((i, j)) for j in range(5 - i)) for i in range(5))


def _horner(coefficients, x):
    total = coefficients[-1]
    for c in coefficients[-2::-1]:
        total = total * x + c
    return total


def offset_polynomial(u, v, q):
    """sum q_ij u^i v^j by Horner's rule in v, then u."""
    rows = [_horner([q[m] for m in row], v) for row in _ROWS]
    return _horner(rows, u)


def _offset_partials(u, v, q):
    """(dQ/du, dQ/dv), by Horner's rule on the derivative's coefficients."""
    rows = [_horner([q[m] for m in row], v) for row in _ROWS]
    du = _horner([i * rows[i] for i in range(1, 5)], u)
    drows = [_horner([j * q[row[j]] for j in range(1, len(row))], v) for row in _ROWS[:4]]
    dv = _horner(drows, u)
    return du, dv


@dataclass(frozen=True)
class EllipseBoundary:
    a: mpmath.mpf
    b: mpmath.mpf

    kind: ClassVar[str] = "ellipse"

    def __post_init__(self):
        _positive_length(self, "a")
        _positive_length(self, "b")

    def check_ball(self, radius, field: str) -> None:
        with workprec():
            limit = min(self.a, self.b) ** 2 / max(self.a, self.b)
        if radius >= limit:
            raise SceneError(field, f"a ball of radius {mpmath.nstr(radius, 6)} needs R < min(a, b)^2/max(a, b) = "
                                    f"{mpmath.nstr(limit, 8)} on this ellipse (beyond it the curve of its centre has "
                                    "cusps: it would touch the cushion at two points)")

    def n_walls(self) -> int:
        return 1

    def conic(self, radius) -> bool:
        """The centre's curve is a conic: for a particle, or on a circle (a = b)."""
        return radius == 0 or self.a == self.b

    def wall_constants(self, radius) -> tuple:
        with workprec():
            if self.conic(radius):
                return ((1 / (self.a - radius) ** 2, 1 / (self.b - radius) ** 2),)
            A, B, r = 1, (self.b / self.a) ** 2, (radius / self.a) ** 2
            q = offset_coefficients(B, r, A)
            scale = max(abs(c) for c in q)
            return ((1 / self.a**2,) + tuple(-c / scale for c in q),)

    def gap(self, wall, x, y, c):
        if len(c) == 2:
            return c[0] * x * x + c[1] * y * y - 1
        return offset_polynomial(c[0] * x * x, c[0] * y * y, c[1:])

    def within(self, x, y):
        """The centre (x, y) is strictly inside the ellipse itself (the gap polynomial of a finite ball turns
        back to negative beyond the outer parallel curve: its sign alone cannot tell a ball far outside)."""
        return x * x / self.a**2 + y * y / self.b**2 < 1

    def gap_scale(self, wall, c):
        """Magnitude of the gap function's terms at the wall (its round-off is a few ulps of this)."""
        if len(c) == 2:
            return 1
        return sum(abs(v) for v in c[1:])

    def gradient(self, wall, x, y, c):
        if len(c) == 2:
            return 2 * c[0] * x, 2 * c[1] * y
        du, dv = _offset_partials(c[0] * x * x, c[0] * y * y, c[1:])
        return 2 * c[0] * x * du, 2 * c[0] * y * dv

    def exact_distance(self, x, y, a2, b2, zero, guess=None, tol=None):
        """(distance of (x, y) from the ellipse, outward unit normal there) in the numbers' own type.

        Well conditioned where the gap polynomial is not (for a small ball its
        zero sits between two nearly equal branches, inner and outer parallel
        curves): the engine polishes each cushion impact of a finite ball with
        it. The nearest point is (a^2 x/(a^2 + l), b^2 y/(b^2 + l)) with l the
        root in (-min(a^2, b^2), 0) of a^2 x^2/(a^2 + l)^2 + b^2 y^2/(b^2 + l)^2 = 1,
        a decreasing convex function of l there: Newton's method kept inside a
        bracket, from ``guess`` (about -R/|(x/a^2, y/b^2)| for a point at distance R), until a
        step is below ``tol`` relative (one more Newton step then: quadratic convergence).
        None for a point not inside the ellipse.
        """
        xx, yy = a2 * x * x, b2 * y * y

        def phi(lam):
            p, q = a2 + lam, b2 + lam
            return xx / (p * p) + yy / (q * q) - 1, -2 * (xx / (p * p * p) + yy / (q * q * q))

        if not phi(zero)[0] < zero:
            return None
        lo, hi = -(a2 if a2 < b2 else b2), zero
        lam = guess if guess is not None and lo < guess < hi else hi
        previous = None
        for _ in range(200):
            value, slope = phi(lam)
            if value == zero:  # on the root
                break
            if value > zero:
                lo = lam
            else:
                hi = lam
            new = lam - value / slope
            if new == lam:  # Newton's step is below an ulp: converged (before the bracket test: lam may be an end)
                break
            if not lo < new < hi:
                new = (lo + hi) / 2
            step = abs(new - lam)
            # in Newton's quadratic regime (steps shrinking) a step below sqrt(eps) leaves an error ~eps
            # (near the pole at -min(a^2, b^2) steps are small but growing: not converged)
            done = new == lam or (tol is not None and previous is not None and step <= tol * abs(lam)
                                  and step < previous / 2)
            lam, previous = new, step
            if done:
                break
        # The foot is x + (-lam) grad, grad = (x/(a^2 + l), y/(b^2 + l)) the ellipse's own (unnormalized) normal
        # there: the distance -lam |grad| and the normal grad/|grad| to the last bits. From the difference foot - x
        # (of two points ~a apart from the origin, ~R apart from each other) they had lost a/R of their digits:
        # a ball of R = 1e-4 in an ellipse of a = 2 left each cushion impact with its velocity 3e-12 off (review).
        gx, gy = x / (a2 + lam), y / (b2 + lam)
        g = sqrt(gx * gx + gy * gy)
        return -lam * g, (gx / g, gy / g)

    @cached_property
    def _speed_series(self):
        """Fourier cosine coefficients f_k of |P'(theta)| = sqrt(a^2 sin^2 + b^2 cos^2) (period pi)."""
        a, b = float(self.a), float(self.b)
        m = 1024
        while True:
            t = np.arange(m) * (np.pi / m)
            f = np.sqrt((a * np.sin(t)) ** 2 + (b * np.cos(t)) ** 2)
            coef = np.fft.rfft(f).real / m
            coef[1:] *= 2
            if abs(coef[m // 4]) < 1e-18 * coef[0] or m >= 2**22:
                return coef[: m // 4]
            m *= 4

    def least_curvature_radius(self, radius) -> float:
        """The least radius of curvature of the curve of the centre: b^2/a - R at the ends of the major axis."""
        return float(min(self.a, self.b) ** 2 / max(self.a, self.b) - radius)

    def centre_curve(self, radius, theta):
        """(x, y, dx/dtheta, dy/dtheta) of P(theta) - R n(theta), the curve a ball's centre reaches (numpy)."""
        a, b, r = float(self.a), float(self.b), float(radius)
        c, s = np.cos(theta), np.sin(theta)
        mx, my = b * c, a * s  # the outward normal's direction
        dmx, dmy = -b * s, a * c
        norm = np.hypot(mx, my)
        dnorm = (mx * dmx + my * dmy) / norm
        nx, ny = mx / norm, my / norm
        dnx, dny = dmx / norm - mx * dnorm / norm**2, dmy / norm - my * dnorm / norm**2
        return a * c - r * nx, b * s - r * ny, -a * s - r * dnx, b * c - r * dny

    def perimeter(self) -> float:
        return float(2 * np.pi * self._speed_series[0])

    def eccentric_angle(self, px, py):
        return np.mod(np.arctan2(np.asarray(py, float) / float(self.b), np.asarray(px, float) / float(self.a)),
                      2 * np.pi)

    def arc_length(self, px, py):
        theta = self.eccentric_angle(px, py)
        f = self._speed_series
        k = np.arange(1, len(f))
        s = f[0] * theta
        s = s + np.sum(f[1:, None] * np.sin(2 * np.outer(k, np.ravel(theta))) / (2 * k[:, None]), axis=0).reshape(
            np.shape(theta))
        return s

    def outline(self, n: int = 400):
        t = np.linspace(0, 2 * np.pi, n)
        return float(self.a) * np.cos(t), float(self.b) * np.sin(t)

    def describe(self) -> str:
        return f"elliptical table a={mpmath.nstr(self.a, 6)} b={mpmath.nstr(self.b, 6)}"
