"""The rolling-collision law of Hedrih in vector form (paper sections 3.7 and 7.2.1, issue 14).

Along the line of centres n the balls collide as two rolling bodies: the
sum J_P1 omega_P1 + J_P2 omega_P2 of the normal rolling rates omega = v.n/R is
conserved (eq. 8) and their difference is reversed and scaled by k
(eqs. 9-11); the tangential parts of v and of omega_P are kept, and both
balls roll on (omega_P = z x v / R before and after). The energy lost is
eq. (15) on the normal rates.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ....laws import HedrihRollingLaw
from ..base import NormalImpulseLaw, RestitutionLaw


@dataclass(frozen=True)
class HedrihTableLaw(NormalImpulseLaw, RestitutionLaw):
    name: ClassVar[str] = "hedrih"
    source: ClassVar[str] = "Hedrih's rolling-collision law (eqs. 8-15) on the normal rolling rates v.n/R"
    keeps_rolling: ClassVar[bool] = True

    def one_dimensional(self):
        return HedrihRollingLaw(restitution=self.restitution)
