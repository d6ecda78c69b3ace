"""Newton's law of central collision on the centre velocities (paper section 3.2, eqs. 1-5).

Momentum m1 v1n + m2 v2n is conserved along the line of centres and the
normal velocity difference is reversed and scaled by k; tangential parts
are kept. The balls roll on (their spins turn with v): the classical law
with rolling imposed, for comparison with Hedrih's, as in the paper's Table 1.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ....laws import NewtonCentreLaw
from ..base import NormalImpulseLaw, RestitutionLaw


@dataclass(frozen=True)
class NewtonTableLaw(NormalImpulseLaw, RestitutionLaw):
    name: ClassVar[str] = "newton"
    source: ClassVar[str] = "Newton's law of central collision (eqs. 1-5) on the centre velocities' normal parts"
    keeps_rolling: ClassVar[bool] = True

    def one_dimensional(self):
        return NewtonCentreLaw(restitution=self.restitution)
