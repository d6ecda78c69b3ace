"""The rolling-collision law of K. (Stevanovic) Hedrih (paper section 3.6-3.7).

Hypothesis of conservation of the sum of angular momenta about the
instantaneous rolling axes, J_P1 omega_P1 + J_P2 omega_P2 (eq. 8), and the
restitution coefficient on rolling angular velocities (eq. 9):

    k = (omega_P2+ - omega_P1+) / (omega_P1 - omega_P2),

which give the outgoing velocities (10)-(11) and, on a circle of radius R,
omega_P = (R - r)/r * phi' (eq. 23), J_P = kappa m r^2 (eq. 24).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import mpmath

from ...errors import SceneError
from .._numbers import workprec
from ..bodies import Body
from .base import LawVariables, check_restitution


@dataclass(frozen=True)
class HedrihRollingLaw:
    """Paper eqs. (8)-(12): Newton-type law on omega_P with inertias J_P."""

    name: ClassVar[str] = "hedrih"
    source: ClassVar[str] = "Hedrih (Stevanovic), rolling-collision law, eqs. (8)-(12), (23)-(24)"
    restitution: mpmath.mpf = field(default_factory=lambda: mpmath.mpf(1))

    def __post_init__(self):
        object.__setattr__(self, "restitution", check_restitution(self.restitution))

    scale_power: ClassVar[int] = 1
    inertia_power: ClassVar[int] = 0

    def variables(self, body: Body, sigma) -> LawVariables:
        if body.is_particle:
            raise SceneError(
                "collision.law",
                "'hedrih' needs rolling bodies (r > 0): omega_P = (R - r)/r phi' is undefined "
                "for a particle; use 'newton' or 'newton_generalized'",
            )
        with workprec():
            return LawVariables(scale=mpmath.mpf(sigma) / body.radius, inertia=body.rolling_inertia())
