"""Collision laws as swappable strategies, named after their source."""

from __future__ import annotations

from ...errors import SceneError
from .base import (
    CollisionLaw,
    ImpulseMap,
    LawVariables,
    collision_impulse,
    conserves_mechanical_energy_bound,
    impulse_map,
    kinetic_energy_change,
    law_velocities,
    outgoing,
)
from .generalized import GeneralizedNewtonLaw
from .hedrih import HedrihRollingLaw
from .newton import NewtonCentreLaw

LAWS: dict[str, type] = {
    law.name: law for law in (HedrihRollingLaw, NewtonCentreLaw, GeneralizedNewtonLaw)
}


def make_law(name: str, restitution=1) -> CollisionLaw:
    """The law registered under ``name`` with restitution coefficient k."""
    try:
        cls = LAWS[name]
    except KeyError:
        names = " | ".join(LAWS)
        raise SceneError("collision.law", f"unknown law {name!r}; expected one of {names}") from None
    return cls(restitution=restitution)


__all__ = [
    "CollisionLaw",
    "GeneralizedNewtonLaw",
    "HedrihRollingLaw",
    "ImpulseMap",
    "LAWS",
    "LawVariables",
    "NewtonCentreLaw",
    "collision_impulse",
    "conserves_mechanical_energy_bound",
    "impulse_map",
    "kinetic_energy_change",
    "law_velocities",
    "make_law",
    "outgoing",
]
