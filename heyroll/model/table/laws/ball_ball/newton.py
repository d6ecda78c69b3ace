"""Newton's law of central collision on the centre velocities (paper section 3.2, eqs. 1-5).

Momentum m1 v1n + m2 v2n is conserved along the line of centres and the
normal velocity difference is reversed and scaled by k; tangential parts
are kept. The balls roll on (their spins turn with v): the classical law
with rolling imposed, for comparison with Hedrih's, as in the paper's Table 1.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import mpmath

from ....laws import NewtonCentreLaw, impulse_map
from ....laws.base import check_restitution


@dataclass(frozen=True)
class NewtonTableLaw:
    name: ClassVar[str] = "newton"
    source: ClassVar[str] = "Newton's law of central collision (eqs. 1-5) on the centre velocities' normal parts"
    keeps_rolling: ClassVar[bool] = True
    restitution: mpmath.mpf = field(default_factory=lambda: mpmath.mpf(1))

    def __post_init__(self):
        object.__setattr__(self, "restitution", check_restitution(self.restitution))

    def one_dimensional(self):
        return NewtonCentreLaw(restitution=self.restitution)

    def constants(self, body_i, body_j, number) -> tuple:
        m = impulse_map(self.one_dimensional(), body_i, body_j, 1, 1)
        return number(m.q), number(m.a_i), number(m.a_j)

    def normal_rates(self, c, vn_i, vn_j):
        d = vn_i - c[0] * vn_j
        return vn_i - c[1] * d, vn_j + c[2] * d
