"""A scene: gravity, a track, bodies with their initial states, a collision law.

One scene type for every track. Bodies are numbered 1..N in scene order:
counter-clockwise around a circle (paper section 4: phi_2 = phi_1 + beta at
contact), in increasing coordinate along an open track (an arc chain, a
curve). Neighbours (i, i+1) can touch, and on a closed track so can (N, 1)
across the top (the wrap-around pair). q is each body's generalized
coordinate (phi, s or x, as the track says) and dq its rate.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import math

import mpmath
import numpy as np

from ..errors import SceneError
from ._numbers import Real, exact_state, from_exact_state, is_finite, to_mpf, touching_slack, workprec
from .bodies import Body
from .forcing import Forcing
from .frame import STATIONARY, Frame
from .laws import CollisionLaw, HedrihRollingLaw, ImpulseMap, conserves_mechanical_energy_bound, impulse_map
from .laws.base import check_restitution
from .tracks import Track, first_integral

STANDARD_GRAVITY = "9.81"

#: Policies for a collision whose law outcome leaves the bodies approaching in
#: position (they would overlap): fall back to Newton's law on the gap rate
#: with generalized masses for that collision, or stop the run.
INCONSISTENCY_POLICIES = ("newton", "error")
#: How contacts touching at one instant are resolved on the circle (see Scene.simultaneous).
SIMULTANEOUS_POLICIES = ("sequential", "impulses")


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
    """Two neighbours that can touch.

    ``i`` is the body before (clockwise of, on a circle) ``j`` (0-based). On a
    track with a linear gap (the circle) the gap is q_j - q_i + ``constant``
    with constant = offset - beta, ``offset`` 2 pi for the wrap-around pair;
    ``law_map`` is the law compiled for the pair where the metric is constant
    (None elsewhere: the engine maps at each contact); ``reachable`` is False
    where the scene's energy can never bring the pair together.
    """

    i: int
    j: int
    beta: mpmath.mpf = mpmath.mpf(0)
    offset: mpmath.mpf = mpmath.mpf(0)
    law_map: ImpulseMap | None = None
    reachable: bool = True

    @property
    def wraps(self) -> bool:
        return self.offset != 0

    def gap_constant(self) -> mpmath.mpf:
        """offset - beta, the constant term of a linear gap, at model precision."""
        with workprec():
            return self.offset - self.beta


@dataclass(frozen=True)
class Scene:
    """Everything a run needs. Build it with :meth:`Scene.make`, which checks the rules.

    Scenes key the engine's caches (compiled systems, per-scene constants): the
    hash of its exact numbers is computed once (hashing every mpf of a scene took
    ~0.1 ms of each run's set-up, measured).
    """

    def __reduce__(self):
        return (from_exact_state, (exact_state(self),))  # mpf values exactly (see _numbers)

    def __hash__(self) -> int:
        cached = self.__dict__.get("_hash")
        if cached is None:  # (the constants' hash is computed once for every scene that has them)
            cached = hash((self.constants, self.q, self.dq, self.slip, self.name, self.run))
            object.__setattr__(self, "_hash", cached)
        return cached

    @property
    def memo(self) -> dict:
        """Values the engine derives from this scene, its state included (its start, what its energy
        can reach), kept with it (simulation.compiled_cache.by_scene); not part of its value."""
        memo = self.__dict__.get("_memo")
        if memo is None:
            memo = {}
            object.__setattr__(self, "_memo", memo)
        return memo

    @property
    def constants(self) -> "SceneConstants":
        """Everything of the scene but its state (q, dq, slip), its name and its run settings.

        What the engine compiles and precomputes (systems, collision maps, time
        scales) depends on these alone, so scenes that differ only in their
        start (a sweep over initial conditions, a basin) share it: the engine's
        caches are keyed by this, built once per scene.
        """
        cached = self.__dict__.get("_constants")
        if cached is None:
            cached = SceneConstants.interned(tuple(getattr(self, name) for name in _CONSTANT_FIELDS))
            object.__setattr__(self, "_constants", cached)
        return cached

    g: mpmath.mpf
    track: Track
    bodies: tuple[Body, ...]
    q: tuple[mpmath.mpf, ...]
    dq: tuple[mpmath.mpf, ...]
    law: CollisionLaw
    run: RunSettings
    name: str = "scene"
    #: Coefficient of kinetic (Coulomb) friction between the bodies and the track (None: a
    #: smooth track for particles, rolling that never slips for bodies; see simulation.friction).
    track_friction: mpmath.mpf | None = None
    #: What to do when the law's outcome leaves two bodies approaching: "newton" or "error".
    on_inconsistent: str = "newton"
    #: "two": the track guides the bodies on both sides (rolling elements between two
    #: races; the motion holds whatever the normal force); "one": bodies rest on the
    #: track and a run stops where one would leave it (normal force 0).
    track_sides: str = "two"
    #: The vertical plane, fixed or turning about a vertical axis.
    frame: Frame = STATIONARY
    #: Restitution at the limiters of an open track (q' -> -k q').
    limiter_restitution: mpmath.mpf = mpmath.mpf(1)
    #: Coefficient of static friction mu_s >= mu (None: mu_s = mu), with track_friction.
    static_friction: mpmath.mpf | None = None
    #: Initial slip velocity w = v_C - r omega_P of each body on a rough track (m/s; 0: rolling).
    slip: tuple = ()
    #: Periodic forcing (a force along the track or a motion of the track), or None.
    forcing: Forcing | None = None
    #: Contacts touching at one instant on the circle: "sequential" (pair by pair, contact_settler) or
    #: "impulses" (all at once: a linear complementarity problem, as the table's).
    simultaneous: str = "sequential"
    pairs: tuple[ContactPair, ...] = field(default=(), compare=False)

    @classmethod
    def make(
        cls,
        track: Track,
        bodies,
        q=None,
        dq=None,
        *,
        phi=None,
        dphi=None,
        law: CollisionLaw | None = None,
        g: Real = STANDARD_GRAVITY,
        run: RunSettings | None = None,
        name: str = "scene",
        friction: Real | None = None,
        on_inconsistent: str = "newton",
        track_sides: str = "two",
        frame: Frame = STATIONARY,
        limiter_restitution: Real | None = None,
        static_friction: Real | None = None,
        slip=None,
        forcing: Forcing | None = None,
        simultaneous: str = "sequential",
    ) -> "Scene":
        """``q``/``dq`` (or, on a circle, their names ``phi``/``dphi``): one per body."""
        q = phi if q is None else q
        dq = dphi if dq is None else dq
        bodies = tuple(bodies)
        if not bodies:
            raise SceneError("bodies", "at least one body is required")
        if q is None or dq is None or len(q) != len(bodies) or len(dq) != len(bodies):
            raise SceneError("bodies", f"need one {track.coordinate} and one d{track.coordinate} per body")
        if not is_finite(g):
            raise SceneError("g", f"must be a finite number, got {g!r}")
        gv = to_mpf(g)
        if gv <= 0 or float(gv) == 0:
            raise SceneError("g", f"must be > 0 (and at least 1e-300), got {g}")
        law = law if law is not None else HedrihRollingLaw()
        for n, body in enumerate(bodies, start=1):
            track.check_body(body, f"bodies[{n}]")
        qs, dqs = _state(track, q, dq)
        mu = None
        if friction is not None:
            if not is_finite(friction) or to_mpf(friction) < 0:
                raise SceneError("track.friction", f"must be a finite number >= 0, got {friction!r}")
            mu = to_mpf(friction)
        mu_s = None
        if static_friction is not None:
            if mu is None:
                raise SceneError("track.static_friction", "needs track.friction (the kinetic coefficient mu)")
            if not is_finite(static_friction) or to_mpf(static_friction) < mu:
                raise SceneError("track.static_friction",
                                 f"must be a finite number >= track.friction = {mpmath.nstr(mu, 17)}, got {static_friction!r}")
            mu_s = to_mpf(static_friction)
        slips = _slips(slip, bodies, mu)
        if on_inconsistent not in INCONSISTENCY_POLICIES:
            raise SceneError(
                "collision.on_inconsistent",
                f"unknown policy {on_inconsistent!r}; expected one of {' | '.join(INCONSISTENCY_POLICIES)}",
            )
        if simultaneous not in SIMULTANEOUS_POLICIES:
            raise SceneError("collision.simultaneous",
                             f"unknown policy {simultaneous!r}; expected one of {' | '.join(SIMULTANEOUS_POLICIES)}")
        if simultaneous == "impulses" and not track.linear_gap:
            raise SceneError("collision.simultaneous",
                             "'impulses' is offered on the circle (and on tables), not on path tracks: use 'sequential'")
        if track_sides not in ("one", "two"):
            raise SceneError("track.sides", f"must be 'one' or 'two', got {track_sides!r}")
        k_lim = law.restitution if limiter_restitution is None else limiter_restitution
        try:
            k_lim = check_restitution(k_lim)
        except SceneError as exc:
            raise SceneError("track.limiter_restitution", exc.rule) from None
        scene = cls(
            g=gv, track=track, bodies=bodies, q=qs, dq=dqs, law=law, run=run or RunSettings.make(), name=name,
            track_friction=mu, on_inconsistent=on_inconsistent, track_sides=track_sides, frame=frame,
            limiter_restitution=k_lim, static_friction=mu_s, slip=slips, forcing=forcing,
            simultaneous=simultaneous,
        )
        return scene._with_checked_state()

    def with_state(self, q=None, dq=None, slip=None) -> "Scene":
        """This scene started elsewhere: new coordinates ``q``, rates ``dq`` and slips (None: as now).

        The same scene as :meth:`make` gives with those values (equal, and so
        with the same results), checked by the same rules, but only those of
        the state: the constants (bodies, track, law) were checked when this
        scene was made, and the contact pairs' constants are kept (a sweep over
        initial conditions builds a point in microseconds, not milliseconds).
        """
        n = len(self.bodies)
        for name, values in (("q", q), ("dq", dq), ("slip", slip)):
            if values is not None and len(values) != n:
                raise SceneError("bodies", f"need one {name} per body, got {len(values)} for {n} bodies")
        qs, dqs = _state(self.track, self.q if q is None else q, self.dq if dq is None else dq)
        slips = self.slip if slip is None else _slips(slip, self.bodies, self.track_friction)
        scene = Scene(g=self.g, track=self.track, bodies=self.bodies, q=qs, dq=dqs, law=self.law, run=self.run,
                      name=self.name, track_friction=self.track_friction, on_inconsistent=self.on_inconsistent,
                      track_sides=self.track_sides, frame=self.frame, limiter_restitution=self.limiter_restitution,
                      static_friction=self.static_friction, slip=slips, forcing=self.forcing,
                      simultaneous=self.simultaneous)
        object.__setattr__(scene, "_constants", self.constants)
        own = self.__dict__.get("_circle_energies")
        if own:  # the energies of the bodies whose state is unchanged (a sweep varies one or two)
            kept = {n: e for n, e in own.items() if (qs[n] is self.q[n] or qs[n] == self.q[n])
                    and (dqs[n] is self.dq[n] or dqs[n] == self.dq[n])}
            if kept:
                object.__setattr__(scene, "_circle_energies", kept)
        return scene._with_checked_state(self.pairs)

    def _with_checked_state(self, pairs_of=None) -> "Scene":
        """Check the rules of the state and set the contact pairs (their constants from ``pairs_of``,
        a scene's of the same constants, where given); returns self."""
        self._check_finite_energies(constants_checked=pairs_of is not None)
        pairs = self._linear_gap_pairs(pairs_of) if self.track.linear_gap else self._open_pairs(pairs_of)
        object.__setattr__(self, "pairs", pairs)
        return self

    def _check_finite_energies(self, constants_checked: bool = False) -> None:
        """Refuse scenes whose energies overflow a double (measured: track.radius = 1e308 ran to
        'completed' with infinite energies and nan in the table; dphi = 1e200 ended in a traceback).
        ``constants_checked``: the generalized masses and weight moments were (with_state)."""
        for n, body in enumerate(self.bodies):
            if self.track.linear_gap and not constants_checked:  # the engine works with G = kappa m rho^2 and W = m g rho
                for name, value in (("generalized mass kappa m (R - r)^2", self.track.generalized_mass(body)),
                                    ("weight moment m g (R - r)", self.track.weight_moment(body, self.g))):
                    if not math.isfinite(float(value)):
                        raise SceneError("track.radius", f"the {name} of body {n + 1} ({mpmath.nstr(value, 6)}) is "
                                         "not a finite double: the radius, the masses or g are out of range")
            with np.errstate(all="ignore"):  # an overflow is what is checked here, not a warning
                try:
                    if self._energy_at_model_precision:
                        kinetic, potential = self._circle_energy(n)
                        total, at_rest = float(kinetic + potential), float(potential)
                    else:
                        total = float(self.body_energy(n))
                        at_rest = float(self.body_energy(n, dphi=0))
                except OverflowError:  # Python floats raise it (Omega^2 of a frame at 1e154 rad/s: fuzz)
                    total = at_rest = math.inf
            if not math.isfinite(at_rest):
                where = "track.radius" if self.track.linear_gap else "track"
                raise SceneError(where, f"the potential energy of body {n + 1} ({at_rest}) is not a finite double: "
                                 "the track's size, the masses, g or frame.omega are out of range")
            if not math.isfinite(total):
                raise SceneError(f"bodies[{n + 1}].d{self.coordinate}",
                                 f"the kinetic energy of body {n + 1} is not a finite double: the rate is out of range")

    # -- names ----------------------------------------------------------------

    @property
    def phi(self) -> tuple:
        """The coordinates q (named phi on a circle)."""
        return self.q

    @property
    def dphi(self) -> tuple:
        return self.dq

    @property
    def coordinate(self) -> str:
        return self.track.coordinate

    # -- geometry -------------------------------------------------------------

    def sigma(self, n: int, q=None):
        """|dC/dq| of body n (0-based) at q (default: its initial coordinate), model precision where constant."""
        body = self.bodies[n]
        if self.track.linear_gap:  # the circle: sigma = R - r
            return self.track.path_radius(body)
        return to_mpf(float(self.track.sigma(body, float(self.q[n] if q is None else q))))

    def centre(self, n: int, q):
        """Centre (x_C, y_C) of body n at coordinate(s) q, float64."""
        return self.track.centre(self.bodies[n], q)

    def point_contact(self, i: int, j: int) -> bool:
        """Whether bodies i and j meet at a point of the track: two particles, or a particle and a
        rolling body on a track whose coordinate is the contact point (a curve, a parametric curve).

        A particle slides on the track itself and a rolling body fits the track's curvature, so the
        particle reaches the body's surface only at the body's contact point, where the two
        surfaces are tangent: the distance between the centres minus r_i + r_j touches 0 there
        without changing sign (found by review: a particle passed under a disk on the cycloid,
        unseen). Such a pair's gap is the signed difference of the contact coordinates.
        """
        bi, bj = self.bodies[i], self.bodies[j]
        return (bi.is_particle and bj.is_particle) or (
            (bi.is_particle or bj.is_particle) and self.track.coordinate in ("x", "u"))

    def gap(self, i: int, j: int, q_i, q_j):
        """Distance between the surfaces of bodies i and j at coordinates q_i, q_j (m), float64."""
        xi, yi = self.centre(i, q_i)
        xj, yj = self.centre(j, q_j)
        d = float(self.bodies[i].radius + self.bodies[j].radius)
        if self.point_contact(i, j):  # a signed distance along the track (between the contact points)
            xi, yi = self.track.centre(Body.of_shape("particle", 0, mass=1), q_i)
            xj, yj = self.track.centre(Body.of_shape("particle", 0, mass=1), q_j)
            return np.sign(np.asarray(q_j, float) - np.asarray(q_i, float)) * np.hypot(xj - xi, yj - yi)
        return np.hypot(xj - xi, yj - yi) - d

    def domain(self, n: int):
        """Where body n's coordinate may go (limiters), floats; None on a closed track."""
        d = self.track.domain(self.bodies[n])
        return None if d is None else (float(d[0]), float(d[1]))

    def _open_pairs(self, pairs_of=None) -> tuple[ContactPair, ...]:
        """Neighbours along an open track; the law compiled once where the metric is constant
        (``pairs_of``: the pairs of a scene of the same constants, whose law maps serve)."""
        c = self.track.coordinate
        for n in range(len(self.bodies)):
            lo, hi = self.track.domain(self.bodies[n])
            if not lo <= self.q[n] <= hi:
                raise SceneError(f"bodies[{n + 1}].{c}",
                                 f"must be on the track: [{float(lo):.17g}, {float(hi):.17g}], got {float(self.q[n]):.17g}")
        pairs = []
        for i in range(len(self.bodies) - 1):
            j = i + 1
            if self.bodies[i].is_particle != self.bodies[j].is_particle and self.track.coordinate == "s":
                raise SceneError(f"bodies[{j + 1}].shape",
                                 "a particle beside a rolling body on an arc chain is not modelled: they meet at "
                                 "the rolling body's contact point, and the chain's coordinates (arc lengths of "
                                 "each centre's path) do not compare; use a curve or a parametric track")
            if not self.q[i] < self.q[j]:
                raise SceneError(f"bodies[{j + 1}].{c}",
                                 "bodies must be listed in order along the track (increasing coordinate)")
            gap = float(self.gap(i, j, float(self.q[i]), float(self.q[j])))
            # (places written to 17 digits come out ~1e-17 m past touching: the circle's and the table's slack)
            if gap < -float(touching_slack(*self.centre(i, float(self.q[i])), *self.centre(j, float(self.q[j])))):
                raise SceneError(f"bodies[{j + 1}].{c}", f"body {j + 1} overlaps body {i + 1} (gap {gap:.3g} m)")
            law_map = None
            if pairs_of is not None:
                law_map = pairs_of[i].law_map
            elif self.track.constant_metric:
                law_map = impulse_map(self.law, self.bodies[i], self.bodies[j], self.sigma(i), self.sigma(j))
            pairs.append(ContactPair(i=i, j=j, law_map=law_map))
        return tuple(pairs)

    def _linear_gap_pairs(self, pairs_of=None) -> tuple[ContactPair, ...]:
        """Neighbours around the circle, the wrap-around pair last; ``pairs_of``: the pairs of a scene
        of the same constants, whose contact angles, law maps and least contact energies serve."""
        n = len(self.bodies)
        if n == 1:
            return ()
        neighbours = [(i, i + 1) for i in range(n - 1)] + [(n - 1, 0)]
        constants = self._circle_pair_constants() if pairs_of is None else pairs_of.constants
        energy = self.total_energy()
        pairs = []
        for (i, j), (beta, offset, law_map, least_energy) in zip(neighbours, constants):
            with workprec():
                gap = self.phi[j] + offset - self.phi[i] - beta
                slack = touching_slack(self.phi[i], self.phi[j] + offset)
            if gap < -slack:
                raise SceneError(
                    f"bodies[{j + 1}].phi",
                    f"bodies {i + 1} and {j + 1} overlap at start (gap {mpmath.nstr(gap, 6)} rad < 0): list bodies "
                    f"counter-clockwise with neighbours at least beta = {mpmath.nstr(beta, 17)} rad apart",
                )
            # (the bound across the top holds for angles in [-pi, pi]: with phi = 5.0 that pair touched low on the
            # circle, unwatched, and the run ended overlap: acceptance test)
            across_the_top = j != 0 or all(-mpmath.pi <= p <= mpmath.pi for p in self.phi)
            reachable = least_energy is None or energy >= least_energy or not across_the_top
            pairs.append(ContactPair(i=i, j=j, beta=beta, offset=offset, law_map=law_map, reachable=reachable))
        return ScenePairs(pairs, constants=constants)

    def _circle_pair_constants(self) -> tuple:
        """Per neighbour pair on the circle: (beta, offset, law map, the least energy that lets it touch
        less 1e-9 relative, or None where every pair is watched); the rules of the bodies' fit checked."""
        n = len(self.bodies)
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
        sigma = [self.track.path_radius(b) for b in self.bodies]
        energy_bounded = all(
            conserves_mechanical_energy_bound(self.law, self.bodies[i], self.bodies[j], sigma[i], sigma[j])
            for i, j in neighbours
        ) and not self.frame.rotating and self.forcing is None
        constants = []
        for (i, j), beta in zip(neighbours, betas):
            wraps = j == 0
            offset = 2 * mpmath.pi if wraps else mpmath.mpf(0)
            with workprec():
                offset = +offset
            least = self._least_contact_energy(i, j, beta, wraps) * (1 - mpmath.mpf(10) ** -9) \
                if energy_bounded else None
            constants.append((beta, offset, impulse_map(self.law, self.bodies[i], self.bodies[j], sigma[i], sigma[j]),
                              least))
        return tuple(constants)

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
        """Mechanical energy of body n (0-based): on a fixed circle at model precision
        (eq. 26, zero at the lowest point), else the first integral of eq. (92) (float64)."""
        body = self.bodies[n]
        q = self.q[n] if phi is None else phi
        dq = self.dq[n] if dphi is None else dphi
        if not self._energy_at_model_precision:
            return to_mpf(float(first_integral(self.track, body, float(q), float(dq), self.g, self.frame)))
        kinetic, potential = self._circle_energy(n, phi, dphi)
        with workprec():
            return kinetic + potential

    @property
    def _energy_at_model_precision(self) -> bool:
        return self.track.linear_gap and not self.frame.rotating

    def _circle_energy(self, n: int, phi=None, dphi=None) -> tuple:
        """(1/2 G phi'^2, W (1 - cos phi)) of body n on a fixed circle at model precision (eq. 26; the
        terms of mechanical_energy), body n's own state by default (computed once per scene)."""
        own = phi is None and dphi is None
        if own:
            cached = self.__dict__.setdefault("_circle_energies", {})
            if n in cached:
                return cached[n]
        moments = self.constants.memo.get("circle_moments")
        if moments is None:  # G = kappa m rho^2, W = m g rho, once per scene constants
            moments = self.constants.memo["circle_moments"] = tuple(
                (self.track.generalized_mass(b), self.track.weight_moment(b, self.g)) for b in self.bodies)
        G, W = moments[n]
        with workprec():
            half = mpmath.sin((self.phi[n] if phi is None else phi) / 2)
            rate = self.dphi[n] if dphi is None else dphi
            parts = (G * rate * rate / 2, 2 * W * half * half)
        if own:
            cached[n] = parts
        return parts

    def height_bound(self, n: int):
        """The highest the centre of body ``n`` (0-based) can rise (m) on an open track, or None.

        In a fixed plane, with a law that never creates mechanical energy and
        limiters with restitution <= 1, the total energy E never grows: body n
        can reach a height y only if m_n g y <= E - sum over the others of
        m_j g (their lowest centre height). None where that does not hold or
        the track gives no lowest height (the events are then all watched).
        """
        track = self.track
        if self.frame.rotating or self.forcing is not None or not hasattr(track, "lowest_centre") \
                or not track.constant_metric:
            return None
        if self.limiter_restitution > 1 or self.law.restitution > 1:
            return None
        one = mpmath.mpf(1)
        bodies = self.bodies
        if not all(conserves_mechanical_energy_bound(self.law, bodies[k], bodies[k + 1], one, one)
                   for k in range(len(bodies) - 1)):
            return None
        with workprec():
            others = mpmath.fsum(b.mass * self.g * track.lowest_centre(b) for k, b in enumerate(bodies) if k != n)
            return float((self.total_energy() - others) / (bodies[n].mass * self.g))

    @property
    def rough(self) -> bool:
        """Whether friction is modelled (sliding particles, rolling bodies that can slip)."""
        return self.track_friction is not None

    @property
    def static_coefficient(self):
        """mu_s (mu where not given), or None on a smooth track."""
        return self.track_friction if self.static_friction is None else self.static_friction

    def total_energy(self):
        """The bodies' mechanical energy; a rolling body that starts slipping (slip w != 0) spins at
        u = v - w instead of v: its kinetic energy of rotation is 1/2 m (kappa - 1) u^2.
        At model precision, computed once per scene (the checks of make and the engine's choice of
        the events the energy can reach all ask for it)."""
        cached = self.__dict__.get("_total_energy")
        if cached is None:
            cached = self._total_energy()
            object.__setattr__(self, "_total_energy", cached)
        return cached

    def _total_energy(self):
        with workprec():
            total = mpmath.fsum(self.body_energy(n) for n in range(len(self.bodies)))
            for n, w in enumerate(self.slip):
                if w != 0:
                    body = self.bodies[n]
                    v = self.sigma(n) * self.dq[n]
                    total += body.mass * (body.kappa - 1) * ((v - w) ** 2 - v**2) / 2
            return total

    def describe(self) -> str:
        parts = ", ".join(b.describe() for b in self.bodies)
        turning = f", plane turning at Omega={mpmath.nstr(self.frame.omega, 6)} rad/s" if self.frame.rotating else ""
        n = len(self.bodies)
        return (f"{self.name}: {n} bod{'y' if n == 1 else 'ies'} on {self.track.describe()}{turning} ({parts}); "
                f"law {self.law.name} k={mpmath.nstr(self.law.restitution, 6)}")


class ScenePairs(tuple):
    """A scene's contact pairs (a tuple of ContactPair) with the constants they were made from
    (Scene.with_state builds a scene of the same constants from them without recomputing them)."""

    def __new__(cls, pairs, constants=()):
        made = super().__new__(cls, pairs)
        made.constants = constants
        return made

    def __reduce__(self):
        return (ScenePairs, (tuple(self), self.constants))


def _state(track, q, dq) -> tuple:
    """The coordinates and rates as model numbers, each finite (named as in a scene file)."""
    c = track.coordinate
    qs = tuple(_finite(p, f"bodies[{n}].{c}") for n, p in enumerate(q, start=1))
    dqs = tuple(_finite(v, f"bodies[{n}].d{c}") for n, v in enumerate(dq, start=1))
    return qs, dqs


def _slips(slip, bodies, mu) -> tuple:
    """Each body's initial slip velocity (0: rolling), checked against the bodies and the friction."""
    if slip is None:
        return tuple(mpmath.mpf(0) for _ in bodies)
    if len(slip) != len(bodies):
        raise SceneError("bodies", "need one slip per body")
    slips = tuple(_finite(w, f"bodies[{n}].slip") for n, w in enumerate(slip, start=1))
    for n, (w, body) in enumerate(zip(slips, bodies), start=1):
        if w != 0 and mu is None:
            raise SceneError(f"bodies[{n}].slip", "a body can slip only on a rough track: give track.friction")
        if w != 0 and (body.is_particle or body.kappa == 1):
            raise SceneError(f"bodies[{n}].slip", "only a rolling body (kappa > 1, r > 0) has a slip velocity")
    return slips


#: The fields of a scene that are not its state, name or run settings (Scene.constants).
_CONSTANT_FIELDS = ("g", "track", "bodies", "law", "track_friction", "on_inconsistent", "track_sides", "frame",
                    "limiter_restitution", "static_friction", "forcing", "simultaneous")


class SceneConstants:
    """A scene's constants (Scene.constants) as a cache key: compared by value, hashed once.

    Equal constants are one object (``interned``), so that the engine's caches,
    looked up several times a run, find them by identity: comparing two scenes'
    mpf constants by value took ~10 us a lookup (measured).
    """

    __slots__ = ("values", "_hash", "memo")
    _seen: dict = {}
    SEEN_LIMIT = 4096

    def __init__(self, values: tuple):
        self.values = values
        self._hash = hash(values)
        self.memo = {}  # values derived from the constants alone, shared by every scene that has them

    @classmethod
    def interned(cls, values: tuple) -> "SceneConstants":
        made = cls(values)
        seen = cls._seen.setdefault(made, made)
        if len(cls._seen) > cls.SEEN_LIMIT:  # a bound on memory; the caches keep working by value
            cls._seen.clear()
        return seen

    def __hash__(self) -> int:
        return self._hash

    def __reduce__(self):
        # the values alone, their mpf exactly (see _numbers): the memo holds the engine's derived values (keyed
        # by its functions), and the hash of text differs between processes
        return (_constants_from_exact, (exact_state(self.values),))

    def __eq__(self, other) -> bool:
        return self is other or (isinstance(other, SceneConstants) and self._hash == other._hash
                                 and self.values == other.values)


def _constants_from_exact(values) -> SceneConstants:
    return SceneConstants.interned(from_exact_state(values))


def _finite(value, field):
    if not is_finite(value):
        raise SceneError(field, f"must be a finite number, got {value!r}")
    return to_mpf(value)
