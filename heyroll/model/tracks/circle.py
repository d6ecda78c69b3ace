"""The circular track of paper section 4: bodies rolling inside a circle.

Angles phi are measured at the circle's centre C0 from its lowest point,
counter-clockwise positive. A body of radius r keeps its centre on the circle
of radius rho = R - r (a particle, r = 0, slides on the track itself).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import heyoka as hy
import mpmath
import numpy as np

from ...errors import SceneError
from .._numbers import Real, is_finite, to_mpf, workprec
from ..bodies import Body
from .base import BodyTerms, Dynamics, lagrangian_terms


@dataclass(frozen=True)
class CircleTrack:
    """A circle of radius R in a vertical plane; bodies roll on its inside.

    Closed (bodies N and 1 can touch across the top), gap linear in the
    angles (phi_j - phi_i - beta), constant metric sigma = R - r; the equation
    of motion is the closed form of eq. (25) in a fixed plane.
    """

    radius: mpmath.mpf
    kind: ClassVar[str] = "circle"
    coordinate: ClassVar[str] = "phi"
    closed: ClassVar[bool] = True
    linear_gap: ClassVar[bool] = True
    constant_metric: ClassVar[bool] = True

    @classmethod
    def of_radius(cls, radius: Real, field: str = "track.radius") -> "CircleTrack":
        if not is_finite(radius):
            raise SceneError(field, f"must be a finite number, got {radius!r}")
        R = to_mpf(radius)
        if R <= 0 or float(R) == 0:
            raise SceneError(field, f"must be > 0 (and at least 1e-300), got {radius}")
        return cls(radius=R)

    def check_body(self, body: Body, field: str) -> None:
        if body.radius >= self.radius:
            raise SceneError(
                f"{field}.radius",
                f"must be < track.radius (r < R), got r = {mpmath.nstr(body.radius, 17)} "
                f">= R = {mpmath.nstr(self.radius, 17)}",
            )

    # -- the Track strategy ------------------------------------------------

    def domain(self, body: Body):
        return None

    def junctions(self, body: Body) -> tuple:
        return ()

    def piece_parameters(self, body: Body, piece: int) -> tuple:
        return ()

    def terms(self, body: Body, q, v, dyn: Dynamics, piece_par) -> BodyTerms:
        """Centre rho (sin phi, -cos phi) from the circle's centre; eq. (25) in a fixed plane."""
        if dyn.frame.rotating:
            rho = dyn.par(self.path_radius(body))
            return lagrangian_terms(rho * hy.sin(q), -rho * hy.cos(q), q, v, body.kappa, dyn)
        # the stiffness first: the engine's hot path reads it as the body's first parameter
        acceleration = -dyn.par(self.angular_stiffness(body, dyn.g)) * hy.sin(q)
        rho = dyn.par(self.path_radius(body))
        g = dyn.par(dyn.g)
        return BodyTerms(
            x_c=rho * hy.sin(q), y_c=-rho * hy.cos(q),
            acceleration=acceleration,
            normal=rho * v**2 + g * hy.cos(q),  # N/m = rho phi'^2 + g cos phi; v**2, not v*v: heyoka decomposes the events with the equations, and this form keeps the validated trajectories bit for bit
            sigma=rho,
            driving=-g * hy.sin(q),
        )

    def centre(self, body: Body, q):
        rho = float(self.path_radius(body))
        q = np.asarray(q, dtype=float)
        return rho * np.sin(q), -rho * np.cos(q)

    def sigma(self, body: Body, q):
        return np.full(np.shape(q), float(self.path_radius(body)))

    def describe(self) -> str:
        return f"a circle R={mpmath.nstr(self.radius, 6)}"

    # -- the circle's own closed forms ---------------------------------------

    def path_radius(self, body: Body) -> mpmath.mpf:
        """rho = R - r, radius of the circle traced by the body's centre."""
        with workprec():
            return self.radius - body.radius

    def rolling_ratio(self, body: Body) -> mpmath.mpf:
        """(R - r)/r: omega_P = (R - r)/r * dphi/dt (paper eq. 23)."""
        if body.is_particle:
            raise ValueError("a particle does not roll: omega_P is undefined for r = 0")
        with workprec():
            return (self.radius - body.radius) / body.radius

    def angular_stiffness(self, body: Body, g: mpmath.mpf) -> mpmath.mpf:
        """g / (kappa (R - r)): phi'' + g/(kappa (R - r)) sin phi = 0 (eq. 25)."""
        with workprec():
            return g / (body.kappa * (self.radius - body.radius))

    def generalized_mass(self, body: Body) -> mpmath.mpf:
        """kappa m (R - r)^2: kinetic energy = 1/2 kappa m rho^2 phi'^2 (eq. 21)."""
        with workprec():
            return body.kappa * body.mass * (self.radius - body.radius) ** 2

    def weight_moment(self, body: Body, g: mpmath.mpf) -> mpmath.mpf:
        """m g (R - r): potential energy = m g rho (1 - cos phi) (eq. 21)."""
        with workprec():
            return body.mass * g * (self.radius - body.radius)

    def contact_angle(self, body_i: Body, body_j: Body) -> mpmath.mpf:
        """beta, the central angle between the centres of two touching bodies (eq. 44).

        Law of cosines on the triangle C0 C_i C_j with sides R - r_i, R - r_j,
        r_i + r_j. Raises ValueError when the bodies cannot touch side by side.
        """
        with workprec():
            rho_i = self.radius - body_i.radius
            rho_j = self.radius - body_j.radius
            d = body_i.radius + body_j.radius
            cos_beta = (rho_i**2 + rho_j**2 - d**2) / (2 * rho_i * rho_j)
            if cos_beta <= -1:
                raise ValueError("bodies too large to touch side by side: r_i + r_j must be < R")
            # Bodies of radius ~1e-200 beside a circle of metres: cos beta rounds a hair above 1
            # at 256 bits, where acos turns complex (found by the slow fuzz run). beta is 0 there.
            return mpmath.acos(min(cos_beta, mpmath.mpf(1)))

    def contact_potential_minimum(self, body_i: Body, body_j: Body, g: mpmath.mpf) -> mpmath.mpf:
        """Least potential energy of the pair over all configurations where they touch.

        U = B (1 - cos x) + C (1 - cos(x + beta)) with B, C the weight moments;
        its minimum over x is B + C - |B + C e^{i beta}|. A pair whose total
        energy stays below it can never collide.
        """
        with workprec():
            B = self.weight_moment(body_i, g)
            C = self.weight_moment(body_j, g)
            beta = self.contact_angle(body_i, body_j)
            return B + C - mpmath.sqrt(B**2 + C**2 + 2 * B * C * mpmath.cos(beta))


def mechanical_energy(generalized_mass, weight_moment, phi, dphi, sin):
    """E = 1/2 kappa m rho^2 phi'^2 + m g rho (1 - cos phi) (paper eq. 26).

    Works on floats, numpy arrays or mpmath numbers: pass the matching ``sin``.
    1 - cos phi is written 2 sin^2(phi/2), which keeps full relative accuracy
    near the lowest point.
    """
    half = sin(phi / 2)
    return generalized_mass * dphi * dphi / 2 + 2 * weight_moment * half * half
