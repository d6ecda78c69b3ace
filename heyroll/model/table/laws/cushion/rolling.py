"""The paper's cushion impact (section 7.2, Fig. 22): rolling kept through the impact.

The normal part of the centre velocity (and with it the normal rolling
rate) is reversed and scaled by the cushion restitution k; the tangential
part is kept; the ball rolls on. Energy lost: 1/2 kappa m (1 - k^2) v_n^2.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ..base import RestitutionLaw


@dataclass(frozen=True)
class RollingCushion(RestitutionLaw):
    name: ClassVar[str] = "rolling"
    source: ClassVar[str] = "paper section 7.2 (Fig. 22): normal rolling rate reversed and scaled by k, rolling kept"
    keeps_rolling: ClassVar[bool] = True
    restitution_field: ClassVar[str] = "track.cushion_restitution"
