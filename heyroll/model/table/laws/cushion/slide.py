"""Cushion impulse through the centre, then sliding (real balls, cushion at centre height).

The normal centre velocity is reversed and scaled by k, the spin is
unchanged, so the ball leaves sliding and Coulomb friction on the cloth
brings it back to rolling. A solid ball rolling head-on into the cushion at
speed v0 comes back rolling at (kappa - 1 - k)/kappa v0 (-3/7 v0 at k = 1):
the angular momentum about the contact with the cloth is conserved while it
slides. No friction acts in the cushion contact itself.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ..base import RestitutionLaw


@dataclass(frozen=True)
class SlideCushion(RestitutionLaw):
    name: ClassVar[str] = "slide"
    source: ClassVar[str] = "impulse through the centre, spin kept, then sliding on the cloth (Coulomb friction)"
    keeps_rolling: ClassVar[bool] = False
    restitution_field: ClassVar[str] = "track.cushion_restitution"
