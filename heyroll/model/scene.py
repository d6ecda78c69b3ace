"""A scene: gravity, a track, bodies with their initial states, a collision law.

Bodies are numbered 1..N in scene order, which must be counter-clockwise
around the circle (paper section 4: phi_2 = phi_1 + beta at contact).
Neighbours (i, i+1) can touch, and so can (N, 1) across the top of the circle
(the wrap-around pair): a body that goes over the top can hit its neighbour
from the other side.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import mpmath

from ..errors import SceneError
from ._numbers import Real, is_finite, to_mpf, workprec
from .bodies import Body
from .laws import CollisionLaw, HedrihRollingLaw, ImpulseMap, conserves_mechanical_energy_bound, impulse_map
from .tracks import CircleTrack, mechanical_energy

STANDARD_GRAVITY = "9.81"

#: Policies for a collision whose law outcome leaves the bodies approaching in
#: position (they would overlap): fall back to Newton's law on the gap rate
#: with generalized masses for that collision, or stop the run.
INCONSISTENCY_POLICIES = ("newton", "error")


@dataclass(frozen=True)
class RunSettings:
    """When a run stops: at t_end, or after max_collisions collisions (None: no limit)."""

    t_end: mpmath.mpf
    max_collisions: int | None = None

    @classmethod
    def make(cls, t_end: Real = 100, max_collisions: int | None = None, field: str = "run") -> "RunSettings":
        if not is_finite(t_end):
            raise SceneError(f"{field}.t_end", f"must be a finite number, got {t_end!r}")
        t = to_mpf(t_end)
        if t <= 0 or float(t) == 0:
            raise SceneError(f"{field}.t_end", f"must be > 0 (and at least 1e-300), got {t_end}")
        if max_collisions is not None:
            if isinstance(max_collisions, bool) or not isinstance(max_collisions, int):
                raise SceneError(f"{field}.max_collisions", f"must be a whole number, got {max_collisions!r}")
            if max_collisions < 0:
                raise SceneError(f"{field}.max_collisions", f"must be >= 0, got {max_collisions}")
        return cls(t_end=t, max_collisions=max_collisions)


@dataclass(frozen=True)
class ContactPair:
    """Two neighbours that can touch; the gap is phi_j + offset - phi_i - beta >= 0.

    ``i`` is the body on the clockwise side, ``j`` the one counter-clockwise
    of it (0-based indices); ``offset`` is 2 pi for the wrap-around pair (N, 1).
    """

    i: int
    j: int
    beta: mpmath.mpf
    offset: mpmath.mpf
    law_map: ImpulseMap
    reachable: bool

    @property
    def wraps(self) -> bool:
        return self.offset != 0

    def gap_constant(self) -> mpmath.mpf:
        """offset - beta, the constant term of the gap function, at model precision."""
        with workprec():
            return self.offset - self.beta


@dataclass(frozen=True)
class Scene:
    """Everything a run needs. Build it with :meth:`Scene.make`, which checks the rules."""

    g: mpmath.mpf
    track: CircleTrack
    bodies: tuple[Body, ...]
    phi: tuple[mpmath.mpf, ...]
    dphi: tuple[mpmath.mpf, ...]
    law: CollisionLaw
    run: RunSettings
    name: str = "scene"
    #: Coefficient of friction between the bodies and the track (None: rolling never slips).
    track_friction: mpmath.mpf | None = None
    #: What to do when the law's outcome leaves two bodies approaching: "newton" or "error".
    on_inconsistent: str = "newton"
    #: "two": the track guides the bodies on both sides (rolling elements between two
    #: races; eq. 25 holds whatever the normal force); "one": bodies rest on the inside
    #: of the circle and a run stops when one would leave it (normal force 0).
    track_sides: str = "two"
    pairs: tuple[ContactPair, ...] = field(default=(), compare=False)

    @classmethod
    def make(
        cls,
        *,
        track: CircleTrack,
        bodies,
        phi,
        dphi,
        law: CollisionLaw | None = None,
        g: Real = STANDARD_GRAVITY,
        run: RunSettings | None = None,
        name: str = "scene",
        friction: Real | None = None,
        on_inconsistent: str = "newton",
        track_sides: str = "two",
    ) -> "Scene":
        bodies = tuple(bodies)
        if not bodies:
            raise SceneError("bodies", "at least one body is required")
        if len(phi) != len(bodies) or len(dphi) != len(bodies):
            raise SceneError("bodies", "need one phi and one dphi per body")
        if not is_finite(g):
            raise SceneError("g", f"must be a finite number, got {g!r}")
        gv = to_mpf(g)
        if gv <= 0 or float(gv) == 0:
            raise SceneError("g", f"must be > 0 (and at least 1e-300), got {g}")
        for n, body in enumerate(bodies, start=1):
            track.check_body(body, f"bodies[{n}]")
        phis = tuple(_finite(p, f"bodies[{n}].phi") for n, p in enumerate(phi, start=1))
        dphis = tuple(_finite(v, f"bodies[{n}].dphi") for n, v in enumerate(dphi, start=1))
        law = law if law is not None else HedrihRollingLaw()
        mu = None
        if friction is not None:
            if not is_finite(friction) or to_mpf(friction) < 0:
                raise SceneError("track.friction", f"must be a finite number >= 0, got {friction!r}")
            mu = to_mpf(friction)
        if on_inconsistent not in INCONSISTENCY_POLICIES:
            raise SceneError(
                "collision.on_inconsistent",
                f"unknown policy {on_inconsistent!r}; expected one of {' | '.join(INCONSISTENCY_POLICIES)}",
            )
        if track_sides not in ("one", "two"):
            raise SceneError("track.sides", f"must be 'one' or 'two', got {track_sides!r}")
        scene = cls(
            g=gv,
            track=track,
            bodies=bodies,
            phi=phis,
            dphi=dphis,
            law=law,
            run=run or RunSettings.make(),
            name=name,
            track_friction=mu,
            on_inconsistent=on_inconsistent,
            track_sides=track_sides,
        )
        object.__setattr__(scene, "pairs", scene._contact_pairs())
        return scene

    # -- geometry -----------------------------------------------------------

    def _contact_pairs(self) -> tuple[ContactPair, ...]:
        n = len(self.bodies)
        if n == 1:
            return ()
        neighbours = [(i, i + 1) for i in range(n - 1)] + [(n - 1, 0)]
        betas = []
        for i, j in neighbours:
            try:
                betas.append(self.track.contact_angle(self.bodies[i], self.bodies[j]))
            except ValueError:
                raise SceneError(
                    f"bodies[{j + 1}].radius",
                    f"bodies {i + 1} and {j + 1} cannot both fit in the circle: r_{i + 1} + r_{j + 1} must be < R",
                ) from None
        with workprec():
            if mpmath.fsum(betas) >= 2 * mpmath.pi:
                raise SceneError("bodies", "the bodies do not fit around the circle (sum of contact angles >= 2 pi)")
        energy_bounded = all(
            conserves_mechanical_energy_bound(self.law, self.track, self.bodies[i], self.bodies[j])
            for i, j in neighbours
        )
        energy = self.total_energy()
        pairs = []
        for (i, j), beta in zip(neighbours, betas):
            wraps = j == 0
            offset = 2 * mpmath.pi if wraps else mpmath.mpf(0)
            with workprec():
                offset = +offset
                gap = self.phi[j] + offset - self.phi[i] - beta
            if gap < 0:
                raise SceneError(
                    f"bodies[{j + 1}].phi",
                    f"bodies {i + 1} and {j + 1} overlap at start (gap {mpmath.nstr(gap, 6)} rad < 0): list bodies "
                    f"counter-clockwise with neighbours at least beta = {mpmath.nstr(beta, 10)} rad apart",
                )
            reachable = True
            if energy_bounded:
                reachable = energy >= self._least_contact_energy(i, j, beta, wraps) * (1 - mpmath.mpf(10) ** -9)
            pairs.append(
                ContactPair(
                    i=i,
                    j=j,
                    beta=beta,
                    offset=offset,
                    law_map=impulse_map(self.law, self.track, self.bodies[i], self.bodies[j]),
                    reachable=reachable,
                )
            )
        return tuple(pairs)

    def _least_contact_energy(self, i: int, j: int, beta, wraps: bool):
        """A lower bound on the energy the system needs for pair (i, j) to touch.

        Direct neighbours: the least potential energy of any touching
        configuration. Across the top (wrap-around), either body must cross
        the top (potential 2 m g rho) or both sit beyond pi - beta from the
        bottom, where each has potential at least m g rho (1 + cos beta).
        """
        bi, bj = self.bodies[i], self.bodies[j]
        with workprec():
            if not wraps:
                return self.track.contact_potential_minimum(bi, bj, self.g)
            wi = self.track.weight_moment(bi, self.g)
            wj = self.track.weight_moment(bj, self.g)
            return min(2 * wi, 2 * wj, (wi + wj) * (1 + mpmath.cos(beta)))

    # -- energy -------------------------------------------------------------

    def body_energy(self, n: int, phi=None, dphi=None):
        """Mechanical energy of body n (0-based) at model precision (eq. 26)."""
        body = self.bodies[n]
        with workprec():
            return mechanical_energy(
                self.track.generalized_mass(body),
                self.track.weight_moment(body, self.g),
                self.phi[n] if phi is None else phi,
                self.dphi[n] if dphi is None else dphi,
                mpmath.sin,
            )

    def total_energy(self):
        with workprec():
            return mpmath.fsum(self.body_energy(n) for n in range(len(self.bodies)))

    def describe(self) -> str:
        parts = ", ".join(b.describe() for b in self.bodies)
        return f"{self.name}: {len(self.bodies)} bodies in a circle R={mpmath.nstr(self.track.radius, 6)} ({parts}); law {self.law.name} k={mpmath.nstr(self.law.restitution, 6)}"


def _finite(value, field):
    if not is_finite(value):
        raise SceneError(field, f"must be a finite number, got {value!r}")
    return to_mpf(value)
