"""A billiard scene: balls rolling on a horizontal table inside a cushion (paper section 7)."""

from __future__ import annotations

from dataclasses import dataclass

import mpmath

from ...errors import SceneError
from .._numbers import Real, is_finite, to_mpf, touching_slack, workprec
from ..bodies import Body
from ..scene import STANDARD_GRAVITY, RunSettings
from .boundaries import Boundary
from .laws import BallLaw, CushionLaw, MirrorTableLaw, make_ball_law, make_cushion_law

SIMULTANEOUS_POLICIES = ("sequential", "impulses")


@dataclass(frozen=True)
class TableBall:
    """A ball on the cloth: centre (x, y), centre velocity (vx, vy) and slip (ux, uy) = v - R omega x z.

    Rolling without slipping is u = 0 (omega_P = z x v / R). A particle (R = 0)
    is the point of the mathematical billiard: it has no spin, u = 0.
    """

    body: Body
    x: mpmath.mpf
    y: mpmath.mpf
    vx: mpmath.mpf
    vy: mpmath.mpf
    ux: mpmath.mpf = mpmath.mpf(0)
    uy: mpmath.mpf = mpmath.mpf(0)

    @classmethod
    def make(cls, body: Body, x: Real, y: Real, vx: Real = 0, vy: Real = 0, spin=None,
             field: str = "bodies[1]") -> "TableBall":
        """``spin`` = (wx, wy), the horizontal angular velocity in rad/s; None: rolling."""
        values = {}
        for name, value in (("x", x), ("y", y), ("vx", vx), ("vy", vy)):
            if not is_finite(value):
                raise SceneError(f"{field}.{name}", f"must be a finite number, got {value!r}")
            values[name] = to_mpf(value)
        ux = uy = mpmath.mpf(0)
        if spin is not None:
            # the component given (a scene with wy alone was told about its wx: acceptance test)
            given = "wy" if to_mpf(spin[0]) == 0 and to_mpf(spin[1]) != 0 else "wx"
            if body.is_particle:
                raise SceneError(f"{field}.{given}", "a particle has no spin (it is the point of the mathematical "
                                                     "billiard)")
            if body.kappa == 1:
                raise SceneError(f"{field}.{given}", "a body with kappa = 1 has no rotational inertia: it has no spin "
                                                     "to give")
            wx, wy = (to_mpf(w) for w in spin)
            with workprec():  # u = v - R omega x z, omega x z = (wy, -wx)
                ux = values["vx"] - body.radius * wy
                uy = values["vy"] + body.radius * wx
        return cls(body=body, ux=ux, uy=uy, **values)

    @property
    def rolling(self) -> bool:
        return self.ux == 0 and self.uy == 0


@dataclass(frozen=True)
class TableScene:
    """Balls on a table with cushions; the laws of ball-ball and ball-cushion impacts."""

    boundary: Boundary
    balls: tuple
    law: BallLaw
    cushion: CushionLaw
    friction: mpmath.mpf
    simultaneous: str
    g: mpmath.mpf
    run: RunSettings
    name: str = "table"

    kind = "table"

    @classmethod
    def make(cls, boundary: Boundary, balls, *, law: str | BallLaw = "hedrih", restitution: Real = 1,
             cushion_model: str | CushionLaw = "rolling", cushion_restitution: Real = 1, friction: Real = "0.2",
             simultaneous: str = "sequential", g: Real = STANDARD_GRAVITY, run: RunSettings | None = None,
             name: str = "table") -> "TableScene":
        balls = tuple(balls)
        if not balls:
            raise SceneError("bodies", "a table scene needs at least one ball")
        law = make_ball_law(law, restitution) if isinstance(law, str) else law
        cushion = make_cushion_law(cushion_model, cushion_restitution) if isinstance(cushion_model, str) \
            else cushion_model
        if not is_finite(friction) or to_mpf(friction) < 0:
            raise SceneError("track.friction", f"must be a finite number >= 0, got {friction!r}")
        if not is_finite(g) or to_mpf(g) <= 0:
            raise SceneError("g", f"must be a finite number > 0, got {g!r}")
        if simultaneous not in SIMULTANEOUS_POLICIES:
            raise SceneError("collision.simultaneous", f"unknown policy {simultaneous!r}; expected "
                                                       f"{' | '.join(SIMULTANEOUS_POLICIES)}")
        if simultaneous == "impulses" and isinstance(law, MirrorTableLaw):
            raise SceneError("collision.simultaneous", "'impulses' needs a law with an impulse (hedrih | newton | "
                                                       "slide); 'mirror' moves each ball on its own")
        if law.name == "hedrih" and any(b.body.is_particle for b in balls) and len(balls) > 1:
            raise SceneError("collision.law", "'hedrih' needs rolling balls (R > 0): omega_P = z x v / R is "
                                              "undefined for a particle; use 'newton'")
        scene = cls(boundary=boundary, balls=balls, law=law, cushion=cushion, friction=to_mpf(friction),
                    simultaneous=simultaneous, g=to_mpf(g), run=run or RunSettings.make(), name=name)
        scene._check_places()
        return scene

    def _check_places(self) -> None:
        with workprec():
            for k, ball in enumerate(self.balls, start=1):
                field = f"bodies[{k}]"
                self.boundary.check_ball(ball.body.radius, f"{field}.radius")
                within = getattr(self.boundary, "within", None)
                for w, c in enumerate(self.boundary.wall_constants(ball.body.radius)):
                    # a ball exactly at its curve's point (touching) passes, and one past it by the slack of places
                    # written as doubles (x = R - r = 0.9 lies 2.2e-17 m past: refused, review): the distance is
                    # the gap over its gradient's length
                    gx, gy = self.boundary.gradient(w, ball.x, ball.y, c)
                    past = touching_slack(ball.x, ball.y) * mpmath.sqrt(gx * gx + gy * gy) + mpmath.mpf(2) ** -200
                    if self.boundary.gap(w, ball.x, ball.y, c) > past or \
                            (within is not None and not within(ball.x, ball.y)):
                        raise SceneError(f"{field}.x", f"the ball overlaps the cushion or is outside the table (its centre "
                                                       f"({mpmath.nstr(ball.x, 8)}, {mpmath.nstr(ball.y, 8)}) is beyond "
                                                       "the curve a ball of its radius can reach)")
            for i in range(len(self.balls)):
                for j in range(i + 1, len(self.balls)):
                    a, b = self.balls[i], self.balls[j]
                    reach = a.body.radius + b.body.radius
                    slack = touching_slack(a.x, a.y, b.x, b.y)
                    if (a.x - b.x) ** 2 + (a.y - b.y) ** 2 < (reach - slack) ** 2:
                        raise SceneError(f"bodies[{j + 1}].x", f"ball {j + 1} overlaps ball {i + 1} (centres closer "
                                                               f"than the sum of the radii)")

    @property
    def n_bodies(self) -> int:
        return len(self.balls)

    @property
    def bodies(self) -> tuple:
        return tuple(b.body for b in self.balls)

    @property
    def slides(self) -> bool:
        """Some ball may slide: a law with an impulse through the centre, or a ball that starts slipping."""
        return not (self.law.keeps_rolling and self.cushion.keeps_rolling) or any(not b.rolling for b in self.balls)

    def energy(self) -> mpmath.mpf:
        """Kinetic energy 1/2 m (|v|^2 + (kappa - 1) |v - u|^2) of all balls (spin from omega x z = (v - u)/R)."""
        with workprec():
            return sum(b.body.mass * ((b.vx**2 + b.vy**2) + (b.body.kappa - 1) * ((b.vx - b.ux) ** 2
                                                                                   + (b.vy - b.uy) ** 2)) / 2
                       for b in self.balls)

    def describe(self) -> str:
        balls = ", ".join(b.body.describe() for b in self.balls)
        return (f"{self.name}: {self.boundary.describe()}, {len(self.balls)} ball{'' if len(self.balls) == 1 else 's'} [{balls}], law {self.law.name} "
                f"k={mpmath.nstr(self.law.restitution, 6)}, cushion {self.cushion.name} "
                f"k={mpmath.nstr(self.cushion.restitution, 6)}, friction {mpmath.nstr(self.friction, 6)}")


def is_table(scene) -> bool:
    """True for a billiard scene (a TableScene, or a result of one): the one test every layer uses."""
    return getattr(scene, "kind", None) == "table"
