"""The paper's eqs. (109)-(113) taken literally, kept only to reproduce its figures.

Each ball leaves with its own incoming speed, its normal part reversed (and
scaled by k here; k = 1 is the paper): the path of each ball is mirrored in
the common tangent plane as if it had hit a wall, whatever the other ball's
mass and speed ("the outgoing paths ... close the same angles with this
common tangent plane"). That conserves neither momentum nor the sum of
J_P omega_P of eq. (8) unless the normal parts happen to be opposite and
equal (papers/ERRATA.md, section 7).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ..base import RestitutionLaw


@dataclass(frozen=True)
class MirrorTableLaw(RestitutionLaw):
    name: ClassVar[str] = "mirror"
    source: ClassVar[str] = "paper eqs. (109)-(113) literally: each ball's path mirrored in the tangent plane"
    keeps_rolling: ClassVar[bool] = True

    def constants(self, body_i, body_j, number) -> tuple:
        return (number(self.restitution),)

    def normal_rates(self, c, vn_i, vn_j):
        return -c[0] * vn_i, -c[0] * vn_j
