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

from ....laws import NewtonCentreLaw
from ..base import NormalImpulseLaw
from ....laws.base import check_restitution


@dataclass(frozen=True)
class NewtonTableLaw(NormalImpulseLaw):
    name: ClassVar[str] = "newton"
    source: ClassVar[str] = "Newton's law of central collision (eqs. 1-5) on the centre velocities' normal parts"
    keeps_rolling: ClassVar[bool] = True
    restitution: mpmath.mpf = field(default_factory=lambda: mpmath.mpf(1))

    def __post_init__(self):
        object.__setattr__(self, "restitution", check_restitution(self.restitution))

    def one_dimensional(self):
        return NewtonCentreLaw(restitution=self.restitution)
