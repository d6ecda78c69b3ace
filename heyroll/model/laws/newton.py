"""Newton's classical law of central collision (paper section 3.2).

Conservation of linear momentum m1 v1 + m2 v2 (eq. 1) and Newton's
restitution on the velocity difference (eq. 2), applied to the speeds of the
bodies' centres along their paths, v_C = (R - r) phi' (eq. 22), with the
masses m. Rotational inertia plays no part: kept for comparison with the
rolling law, as in the paper's Table 1.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import mpmath

from .._numbers import workprec
from ..bodies import Body
from .base import LawVariables, check_restitution


@dataclass(frozen=True)
class NewtonCentreLaw:
    """Paper eqs. (1)-(5) on centre speeds v_C = (R - r) phi' with masses m."""

    name: ClassVar[str] = "newton"
    source: ClassVar[str] = "Newton's law of central collision, eqs. (1)-(5), with v_C from eq. (22)"
    restitution: mpmath.mpf = field(default_factory=lambda: mpmath.mpf(1))

    def __post_init__(self):
        object.__setattr__(self, "restitution", check_restitution(self.restitution))

    scale_power: ClassVar[int] = 1
    inertia_power: ClassVar[int] = 0

    def variables(self, body: Body, sigma) -> LawVariables:
        with workprec():
            return LawVariables(scale=+mpmath.mpf(sigma), inertia=body.mass)
