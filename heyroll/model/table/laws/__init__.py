"""Table collision laws, strategies by pair type: ``ball_ball/<law>`` and ``cushion/<model>``."""

from __future__ import annotations

from ....errors import SceneError
from .ball_ball.hedrih import HedrihTableLaw
from .ball_ball.mirror import MirrorTableLaw
from .ball_ball.newton import NewtonTableLaw
from .ball_ball.slide import SlideTableLaw
from .base import BallLaw, CushionLaw, after_impact, split, with_normal
from .cushion.rolling import RollingCushion
from .cushion.slide import SlideCushion

BALL_LAWS = {law.name: law for law in (HedrihTableLaw, NewtonTableLaw, SlideTableLaw, MirrorTableLaw)}
CUSHION_LAWS = {law.name: law for law in (RollingCushion, SlideCushion)}


def _make(registry, name, restitution, field):
    try:
        cls = registry[name]
    except (KeyError, TypeError):
        raise SceneError(field, f"unknown {'law' if 'law' in field else 'model'} {name!r}; expected one of "
                                f"{' | '.join(registry)}") from None
    return cls(restitution=restitution)


def make_ball_law(name: str, restitution=1) -> BallLaw:
    return _make(BALL_LAWS, name, restitution, "collision.law")


def make_cushion_law(name: str, restitution=1) -> CushionLaw:
    return _make(CUSHION_LAWS, name, restitution, "track.cushion_model")


__all__ = ["BALL_LAWS", "BallLaw", "CUSHION_LAWS", "CushionLaw", "HedrihTableLaw", "MirrorTableLaw",
           "NewtonTableLaw", "RollingCushion", "SlideCushion", "SlideTableLaw", "after_impact", "make_ball_law",
           "make_cushion_law", "split", "with_normal"]
