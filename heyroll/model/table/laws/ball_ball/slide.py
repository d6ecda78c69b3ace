"""Impulse through the centres, then sliding (the model of real billiard balls, e.g. pooltool's).

The collision impulse acts along the line of centres through both centres
(frictionless ball-ball contact): Newton's law with masses on the normal
velocities (eqs. 1-5), tangential velocities kept, spins unchanged. Each
ball then slides on the cloth (slip u = v - R omega x z no longer zero) until
Coulomb friction mu brings it back to rolling: the cue ball's path after a
cut shot is a parabola that bends toward its rolling direction.
"""

from __future__ import annotations

from dataclasses import dataclass

from .newton import NewtonTableLaw


@dataclass(frozen=True)
class SlideTableLaw(NewtonTableLaw):
    name = "slide"
    source = "impulse through the centres (Newton's law, eqs. 1-5, on masses), spins kept, then sliding on the cloth"
    keeps_rolling = False
