"""Newton's law on the gap rate with generalized masses.

The gap between two neighbours closes at the rate phi_j' - phi_i'; the
kinetic energy of a body is 1/2 (kappa m rho^2) phi'^2 (eq. 21). Newton's law
written on phi' with the generalized masses kappa m (R - r)^2 conserves
sum kappa m rho^2 phi' and always separates the bodies in position, and at
k = 1 it conserves the mechanical energy.

For bodies of equal radii it coincides with the rolling law (omega_P is then
the same multiple (R - r)/r of phi' for both, and J_P (R-r)^2/r^2 = kappa m
rho^2): see tests/test_laws.py.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import mpmath

from .._numbers import workprec
from ..bodies import Body
from .base import LawVariables, check_restitution


@dataclass(frozen=True)
class GeneralizedNewtonLaw:
    """Newton-type law on phi' with generalized masses kappa m (R - r)^2."""

    name: ClassVar[str] = "newton_generalized"
    source: ClassVar[str] = "Newton's law (eqs. 1-2) on the gap rate with generalized masses from eq. (21)"
    restitution: mpmath.mpf = field(default_factory=lambda: mpmath.mpf(1))

    def __post_init__(self):
        object.__setattr__(self, "restitution", check_restitution(self.restitution))

    scale_power: ClassVar[int] = 0
    inertia_power: ClassVar[int] = 2

    def variables(self, body: Body, sigma) -> LawVariables:
        with workprec():
            return LawVariables(scale=mpmath.mpf(1), inertia=body.kappa * body.mass * mpmath.mpf(sigma) ** 2)
