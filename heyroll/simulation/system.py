"""The heyoka ODE system of a scene in one contact mode, on any track: only what it needs.

Bodies move in *units*: a free body is a unit of one; bodies held in
persistent contact form a cluster that moves as one unit (one degree of
freedom less per contact). A unit's coordinate psi is the coordinate of its
first member; member k sits at psi + o_k (rigid clusters: tracks whose gap
is linear in the coordinates, the circle).

State layout: [psi_1 .. psi_U, dpsi_1 .. dpsi_U]; with no clusters (the usual
case) that is [q_1 .. q_N, dq_1 .. dq_N]. Each free body follows its track's
equation of motion (:meth:`heyroll.model.tracks.Track.terms`: on a fixed
circle the rolling pendulum phi'' = -g/(kappa (R - r)) sin phi, eq. 25;
elsewhere eq. 93 from the Lagrangian in a plane turning at Omega). A cluster
on the circle obeys

    (sum_k G_k) psi'' = -sum_k W_k sin(psi + o_k)

(G = kappa m rho^2, W = m g rho, eq. 21), and the compressive contact force
between members m and m+1 (a generalized force, N m) is

    lambda_m = sum_{k <= m} (-W_k sin(psi + o_k) - G_k psi'').

Events: the gap between neighbouring units (collisions; on the circle in a
fixed plane both ways: a gap coming back up through zero is checked for a
missed collision, events.reopening_check), elsewhere the gap going below
-overlap_tolerance (a guard: a missed collision, see
:func:`overlap_tolerance`), lambda_m = 0 (a contact that would pull: the
cluster splits), the ends of the piece of track each body is on (a junction
of an arc chain, or a limiter at an end of an open track), and, where the
scene's energy can get there, the normal force of the track reaching zero
(the body leaves the track) and the friction needed to roll exceeding mu N
(it slips). All constants are runtime parameters, so scenes of one shape
share compiled code; the piece a body is on is a block of parameters that
the junction events switch.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import re
from dataclasses import dataclass, field

import heyoka as hy
import mpmath

from ..model._numbers import workprec
from ..model.scene import ContactPair, Scene
from ..model.tracks import Dynamics
from .compiled_cache import CompiledCache, HashedKey, by_constants, by_scene
from .friction import build_friction, forcing_terms, friction_events, member_slip_terms, slides
from .precision import Precision

#: Interpenetration allowed before a run is declared failed (status overlap):
#: OVERLAP_FLOOR rad near the bottom, growing like 1 + phi_j^2 so that the
#: rounding of a gap between angles of many turns (~ eps |phi|) never trips
#: it (phi_j: the angle of the pair's second body; phi_i is within 2 pi of it).
OVERLAP_FLOOR = 1e-12

#: A cluster's contact splits where its force falls this many ulps (of the cluster's weight
#: moments) below zero (see build_system).
SPLIT_ULPS = 64


def overlap_tolerance(phi_j) -> float:
    """How far below zero the gap of a pair whose second body is at phi_j may go (rad)."""
    phi_j = float(phi_j)
    return OVERLAP_FLOOR * (1 + phi_j * phi_j)


@dataclass(frozen=True)
class Unit:
    """Bodies moving together (0-based indices, clockwise first) and their offsets o_k.

    ``pinned`` ('lower' or 'upper', open tracks): the unit rests against that
    limiter, held there by the track's forces, until they pull it away.
    """

    members: tuple[int, ...]
    offsets: tuple  # mpf, o_k relative to the first member (0 where the gap is not linear)
    pinned: str = ""

    def __hash__(self) -> int:  # units key the systems built (build_system): mpf hashing once
        cached = self.__dict__.get("_hash")
        if cached is None:
            cached = hash((self.members, self.offsets, self.pinned))
            object.__setattr__(self, "_hash", cached)
        return cached

    def __getstate__(self) -> dict:  # str hashes (pinned) differ between processes: not pickled
        return {k: v for k, v in self.__dict__.items() if k != "_hash"}

    @property
    def is_cluster(self) -> bool:
        return len(self.members) > 1


@dataclass(frozen=True)
class WatchedContact:
    """A scene pair whose gap is watched: bodies i (last of unit a) and j (first of unit b)."""

    pair_index: int  # into scene.pairs
    pair: ContactPair
    unit_a: int
    unit_b: int


@dataclass(frozen=True)
class ContactLink:
    """A persistent contact inside a cluster: members m and m+1 of unit ``unit``."""

    unit: int
    position: int  # m
    pair_index: int


@dataclass(frozen=True)
class TrackEvent:
    """Where the track stops holding a body: ``kind`` is 'left_track' (its normal force reaches 0).

    ``terminal``: the run stops there (a one-sided track);
    otherwise (a two-sided track) the first time is only recorded.
    """

    body: int
    kind: str
    terminal: bool = True


@dataclass(frozen=True)
class BoundEvent:
    """The end of the piece of track body ``body`` is on: ``end`` is 'lower' or 'upper'.

    At a junction of an arc chain the body passes to the next piece (its
    piece parameters switch); at an end of the track it hits the limiter.
    """

    body: int
    end: str


@dataclass(frozen=True)
class PieceBlock:
    """Where body ``body``'s bounds and piece parameters sit in the parameter vector."""

    body: int
    lower: int  # index of the piece's lower bound; the upper bound follows it
    first: int  # index of the first piece parameter
    size: int


@dataclass(frozen=True)
class SceneSystem:
    """Expressions and parameter values of a scene in one mode, at one precision."""

    equations: list
    parameters: list
    units: tuple[Unit, ...]
    contacts: tuple[WatchedContact, ...]
    gap_expressions: list
    #: Per watched contact (none where ``gap_reopening``): gap + overlap_tolerance(psi_b)
    #: (psi_b = phi_j), a terminal guard that fires only if a collision was missed.
    guard_expressions: list
    links: tuple[ContactLink, ...]
    link_expressions: list
    track_events: tuple[TrackEvent, ...]
    track_expressions: list
    n_bodies: int
    precision: Precision
    law_name: str = ""
    unit_of: tuple[int, ...] = field(default=())
    #: Generalized masses G_k and weight moments W_k of the bodies, as floats.
    gen_mass: tuple[float, ...] = field(default=())
    weight: tuple[float, ...] = field(default=())
    #: Piece ends of each body on an open track (junctions and limiters) and their expressions.
    bound_events: tuple[BoundEvent, ...] = ()
    bound_expressions: list = field(default_factory=list)
    piece_blocks: tuple[PieceBlock, ...] = ()
    #: Per watched contact where the gap is not linear: the expressions of
    #: _contact_terms (gap, its gradient, the metrics, the gap's acceleration and jerk).
    contact_expressions: list = field(default_factory=list)
    #: Per body, [x_C, y_C, N/m, sigma, driving force per unit mass, q''] (free modes): outputs and checks.
    body_expressions: list = field(default_factory=list)
    variables: list = field(default_factory=list)
    #: What of the track the compiled code depends on (its type; a curve's expression).
    track_shape: tuple = ()
    linear_gap: bool = True
    #: Which bodies are particles (r = 0): a curve's equations and a particle pair's gap differ for them.
    particles: tuple = ()
    #: Per link of a cluster where the gap is not linear: [gap, dgap/dq_i, dgap/dq_j] (projections onto the contact).
    link_terms: list = field(default_factory=list)
    #: Per pinned unit: its members' free accelerations (the unit is released where one pulls away).
    release_events: tuple = ()
    release_expressions: list = field(default_factory=list)
    #: kappa m of each body (exact): M_k = kappa m sigma^2 is its generalized mass on a path track.
    rolling_mass: tuple = ()
    #: The circle in a fixed plane: the gap events fire both ways and a gap coming back up
    #: through zero is a missed collision (see events.reopening_check), instead of guard events.
    gap_reopening: bool = False
    #: Friction (a rough track, see simulation.friction): the mode parameters of each unit,
    #: its events (terminal) and expressions, and per block [load, static capacity, sigma].
    friction_blocks: tuple = ()
    friction_events: tuple = ()
    friction_expressions: list = field(default_factory=list)
    friction_values: list = field(default_factory=list)
    #: State entries after the rates (rough tracks): the slip velocities of rolling bodies, then
    #: the work friction has dissipated per block (FrictionBlock.slip, .work).
    n_extra: int = 0
    #: The forcing's phase nu t + psi over 2 (sin of it is 0 once a period): the stroboscopic
    #: section's event, or None.
    strobe_expression: object = None
    #: What else the compiled code depends on: friction (sides, frame), forcing (kind, bodies).
    extra_shape: tuple = ()
    #: The circle with friction or forcing: per unit [psi'', psi'''] as expressions (the contact
    #: judgments' gap acceleration and jerk, which the closed forms of unit_acceleration miss).
    unit_motion: list = field(default_factory=list)

    @property
    def per_body(self) -> bool:
        """The state holds every body's own q, q' (tracks whose gap is not linear: contacts are constraints)."""
        return not self.linear_gap

    @property
    def n_coordinates(self) -> int:
        return self.n_bodies if self.per_body else self.n_units

    def state_index(self, body: int) -> int:
        """Where body ``body``'s coordinate sits in this mode's state (its rate: + n_coordinates)."""
        return body if self.per_body else self.unit_of[body]

    @property
    def n_units(self) -> int:
        return len(self.units)

    @functools.cached_property
    def shape(self) -> "HashedKey":
        """Everything the compiled code depends on (constants are parameters); computed and hashed once
        (systems are cached, and each run looks its integrator and compiled functions up by it)."""
        return HashedKey((
            self.track_shape,
            self.particles,
            self.n_bodies,
            tuple(u.members for u in self.units),
            tuple(c.pair_index for c in self.contacts),
            tuple((l.unit, l.position) for l in self.links),
            tuple((e.body, e.kind, e.terminal) for e in self.track_events),
            self.precision.name,
            tuple((u.members, u.pinned) for u in self.units if u.pinned),
            self.extra_shape,
        ))

    @property
    def coordinate(self) -> str:
        return self.track_shape[2] if len(self.track_shape) > 2 else "q"

    @property
    def pairs(self) -> tuple[ContactPair, ...]:
        return tuple(c.pair for c in self.contacts)

    @functools.cached_property
    def gap_constants(self) -> tuple:
        """Per watched contact (linear gaps): offset - beta - o_last of unit a, in the run's own type
        (a touching gap is zero to its ulps); rounded once per system, not at every mode start."""
        with workprec():
            return tuple(self.precision.number(c.pair.offset - c.pair.beta - self.units[c.unit_a].offsets[-1])
                         for c in self.contacts)

    def acceleration_bound(self, unit: int) -> float:
        """A bound on |psi''| of a unit on the circle in a fixed plane: sum W_k / sum G_k (|sin| <= 1);
        none (inf) with friction or forcing."""
        if self.friction_blocks or self.strobe_expression is not None:
            return math.inf
        _, weights, total = self._unit_floats[unit]
        return sum(weights) / total

    def offsets_float(self, unit: int) -> list[float]:
        return self._unit_floats[unit][0]

    def unit_mass(self, unit: int) -> float:
        """The unit's total generalized mass (its members' sum)."""
        return self._unit_floats[unit][2]

    @functools.cached_property
    def _unit_floats(self) -> tuple:
        """Per unit: its offsets, members' weight moments and total generalized mass, as floats
        (converted once: the contact gates use them after every collision)."""
        return tuple(
            ([float(o) for o in u.offsets], [self.weight[k] for k in u.members], sum(self.gen_mass[k] for k in u.members))
            for u in self.units
        )

    def expand(self, unit_state) -> list:
        """Full state [phi_1..phi_N, dphi_1..dphi_N] from a unit state."""
        if self.n_extra:
            unit_state = unit_state[: len(unit_state) - self.n_extra]
        if self.per_body or not any(u.is_cluster for u in self.units):
            return list(unit_state)
        nu = self.n_units
        phi = [0.0] * self.n_bodies
        dphi = [0.0] * self.n_bodies
        for u, unit in enumerate(self.units):
            psi, dpsi = unit_state[u], unit_state[nu + u]
            for k, o in zip(unit.members, self.offsets_float(u)):
                phi[k] = psi + o
                dphi[k] = dpsi
        return phi + dphi

    def initial_state_of(self, scene: Scene) -> list:
        """``scene``'s initial state in this mode's coordinates, at the run's precision, the slips and
        friction work (rough tracks) at 0. (A system serves every scene of its constants and energy
        reach, see build_system: the state is the scene's, not the system's.)"""
        num = self.precision.number
        full = [num(x) for x in scene.q] + [num(x) for x in scene.dq]
        return self.reduce(full) + [num(0)] * self.n_extra

    def reduce(self, full_state) -> list:
        """Unit state from a full state (first member's angle and rate)."""
        n = self.n_bodies
        if self.per_body or self.n_units == n:  # (every body free: the units are the bodies, in order)
            return list(full_state)
        psi = [full_state[u.members[0]] for u in self.units]
        dpsi = [full_state[n + u.members[0]] for u in self.units]
        return psi + dpsi


def link_bodies(system: SceneSystem, link: ContactLink) -> tuple[int, int]:
    """The two bodies (0-based) of a persistent contact."""
    members = system.units[link.unit].members
    return members[link.position], members[link.position + 1]


@functools.lru_cache(maxsize=128)
@functools.lru_cache(maxsize=None)
def singleton_units(n: int) -> tuple[Unit, ...]:
    """Every one of n bodies free (one tuple per n, its units' hashes computed once: a run's set-up
    looks its systems up by it)."""
    return singleton_units_of(range(n))


def singleton_units_of(bodies) -> tuple[Unit, ...]:
    return tuple(Unit(members=(k,), offsets=(mpmath.mpf(0),)) for k in bodies)


def cluster_unit(scene: Scene, members: tuple[int, ...], pinned: str = "") -> Unit:
    """A cluster of consecutive touching bodies, offsets accumulated from the pairs' beta.

    Where the gap is not linear the members keep their own coordinates (offsets 0).
    """
    if not scene.track.linear_gap:
        return Unit(members=tuple(members), offsets=(mpmath.mpf(0),) * len(members), pinned=pinned)
    offsets = [mpmath.mpf(0)]
    with workprec():
        for a, b in zip(members, members[1:]):
            pair = scene_pair(scene, a, b)
            offsets.append(offsets[-1] + pair.beta - pair.offset)
    return Unit(members=tuple(members), offsets=tuple(offsets))


def scene_pair_index(scene: Scene, i: int, j: int) -> int:
    n = len(scene.bodies)
    if j == i + 1:
        return i
    if i == n - 1 and j == 0:
        return n - 1
    raise ValueError(f"bodies {i + 1} and {j + 1} are not neighbours")


def scene_pair(scene: Scene, i: int, j: int) -> ContactPair:
    return scene.pairs[scene_pair_index(scene, i, j)]


def build_system(
    scene: Scene,
    precision: Precision,
    *,
    pairs: tuple[ContactPair, ...] | None = None,
    units: tuple[Unit, ...] | None = None,
    events: bool = True,
) -> SceneSystem:
    """The ODEs and events of ``scene`` with bodies grouped in ``units``.

    ``units`` defaults to every body free. Gaps are watched between
    neighbouring units for the pairs in ``pairs`` (default: those the scene's
    energy can reach). ``events=False`` gives the bare equations of motion
    (no event expressions, no parameters for them). Results are cached by the
    scene's constants and what its energy can reach (:func:`energy_reach`),
    not by its state: scenes that differ only in where they start share one
    (a sweep's points build none). Treat the returned lists as read-only.
    """
    units = singleton_units(len(scene.bodies)) if units is None else tuple(units)
    watched = None if pairs is None else tuple((p.i, p.j) for p in pairs)
    key = (scene.constants, energy_reach(scene), precision, watched, units, events)
    return _SYSTEMS.get(key, lambda: _build_system(scene, precision, watched, units, events))


#: Systems built, by scene constants, energy reach, precision, watched pairs, units and events.
_SYSTEMS = CompiledCache(64)


@dataclass(frozen=True)
class EnergyReach:
    """What a scene's energy lets its bodies reach: the part of its state its system depends on.

    ``pairs``: whether each scene pair can touch (ContactPair.reachable);
    ``top_half``: whether each body can get where the track's normal force can
    vanish (the track events watched); ``ends``: whether each body can get to
    the lower and upper end of an open track (the limiter events watched);
    ``pieces``: the piece of an open track each body starts on.
    """

    pairs: tuple
    top_half: tuple
    ends: tuple
    pieces: tuple

    @classmethod
    def interned(cls, pairs: tuple, top_half: tuple, ends: tuple, pieces: tuple) -> "EnergyReach":
        """One object per value (a scene's systems are looked up by it at every run: an interned
        reach is hashed once and compared by identity, ~2 us of a new point's set-up, measured)."""
        key = (pairs, top_half, ends, pieces)
        made = _REACHES.get(key)
        if made is None:
            if len(_REACHES) > 4096:  # a bound on memory; lookups keep working by value
                _REACHES.clear()
            made = _REACHES[key] = cls(pairs, top_half, ends, pieces)
            object.__setattr__(made, "_hash", hash(key))
        return made

    def __hash__(self) -> int:
        cached = self.__dict__.get("_hash")
        return hash((self.pairs, self.top_half, self.ends, self.pieces)) if cached is None else cached


_REACHES: dict = {}


@by_scene
def energy_reach(scene: Scene) -> EnergyReach:
    """The scene's :class:`EnergyReach` (model precision, with a 1e-9 relative margin toward watching)."""
    track, n = scene.track, len(scene.bodies)
    thresholds = _top_half_energies(scene)
    energy = scene.total_energy() if thresholds else None
    top_half = []
    energy_float = float(energy) if thresholds else None
    for k, body in enumerate(scene.bodies):
        if thresholds:
            # decided on doubles where they are far apart (correctly rounded, they cannot be wrong then;
            # a 256-bit comparison costs ~1 us of a new point's set-up), else at model precision
            threshold, threshold_float = thresholds[k]
            apart = energy_float - threshold_float
            margin = 1e-12 * (abs(energy_float) + abs(threshold_float))
            top_half.append(apart > 0 if abs(apart) > margin else bool(energy >= threshold))
        else:
            # An open track in a fixed plane: where its centre can rise to, can N vanish?
            height = scene.height_bound(k)
            top_half.append(height is None or not track.holds_below(body, _with_margin(height)))
    open_track = track.domain(scene.bodies[0]) is not None
    ends = tuple((_can_reach_end(scene, k, 0), _can_reach_end(scene, k, 1)) for k in range(n)) if open_track \
        else ((True, True),) * n
    pieces = tuple(piece_of(track, b, q) for b, q in zip(scene.bodies, scene.q)) if open_track else ()
    return EnergyReach.interned(tuple(p.reachable for p in scene.pairs), tuple(top_half), ends, pieces)


@by_constants()
def _top_half_energies(scene: Scene) -> tuple:
    """On a fixed circle: the energy each body needs to rise above the horizontal diameter, where the
    normal force can vanish (W (1 - cos phi) > W), less 1e-9 relative, each as (model number, its double);
    () where not bounded so."""
    if not (scene.track.linear_gap and not scene.frame.rotating and scene.forcing is None):
        return ()
    with workprec():
        energies = [scene.track.weight_moment(b, scene.g) * (1 - mpmath.mpf(10) ** -9) for b in scene.bodies]
    return tuple((e, float(e)) for e in energies)


def _build_system(scene: Scene, precision: Precision, watched, units: tuple, events: bool) -> SceneSystem:
    n = len(scene.bodies)
    nu = len(units)
    allowed = None if watched is None else set(watched)
    reach = energy_reach(scene)
    track, g = scene.track, scene.g
    per_body = not track.linear_gap
    unit_of = [0] * n
    for u, unit in enumerate(units):
        for k in unit.members:
            unit_of[k] = u
    # Where the gap is not linear every body keeps its own coordinate and a contact is a
    # constraint (see _constrained_accelerations); on the circle a cluster is one rigid unit.
    nc = n if per_body else nu
    name = track.coordinate if per_body or all(not u.is_cluster for u in units) else "psi"
    psi, dpsi = _vars(name, nc), _vars(f"d{name}", nc)
    num = precision.number
    params: list = []

    def par(value) -> hy.expression:
        params.append(num(value))
        return hy.par[len(params) - 1]

    # Each body on an open track: its piece's bounds, then the piece's parameters,
    # at fixed places so that the junction events can switch them.
    blocks = []
    if track.domain(scene.bodies[0]) is not None:
        for k, body in enumerate(scene.bodies):
            piece = reach.pieces[k]
            lo, hi = piece_bounds(track, body, piece)
            first = len(params)
            par(lo)
            par(hi)
            values = track.piece_parameters(body, piece)
            for v in values:
                par(v)
            blocks.append(PieceBlock(body=k, lower=first, first=first + 2, size=len(values)))
    dyn = Dynamics(g=g, frame=scene.frame, par=par)

    def body_terms(k, q, v, sliding=False, variable=None):
        """Body k's terms (forcing included); ``sliding``: its centre as a particle's (kappa = 1);
        ``variable``: the state variable q depends on (a cluster member's q is psi + o)."""
        block = blocks[k] if blocks else None
        body = dataclasses.replace(scene.bodies[k], kappa=mpmath.mpf(1)) if sliding else scene.bodies[k]
        term = track.terms(body, q, v, dyn, lambda m: hy.par[block.first + m])
        return forcing_terms(scene, k, term, q if variable is None else variable, body.kappa, par)

    rough = scene.rough
    member_loads: dict = {}  # clusters' rolling members: the friction they need now (below)
    member_slips: dict = {}  # unit -> {member: its rolling parameter, slip friction, inertia lost slipping}
    # a slip velocity per rolling body, free or in a cluster (friction.build_friction)
    n_rolls = sum(1 for u in units for k in u.members if not slides(scene.bodies[k])) if rough else 0
    slip_vars = _vars("w", n_rolls) if n_rolls else []
    friction = None
    work_vars: list = []

    G = [track.generalized_mass(b) for b in scene.bodies] if track.linear_gap else []
    W = [track.weight_moment(b, g) for b in scene.bodies] if track.linear_gap else []
    accelerations, terms = [], [None] * n
    member_accelerations: dict = {}  # unit -> {member: its own q''} (a circle's cluster in a turning plane, forced)
    links, link_exprs, link_terms = [], [], []
    with workprec():
        if per_body:
            terms = [body_terms(k, psi[k], dpsi[k]) for k in range(n)]
        else:
            for u, unit in enumerate(units):
                if unit.is_cluster and not rough:  # a cluster's equation is its own (below)
                    continue
                for k, o in zip(unit.members, unit.offsets):
                    terms[k] = body_terms(k, psi[u] + par(o) if unit.is_cluster else psi[u], dpsi[u], variable=psi[u])
        if rough:
            def coordinate(k):
                return k if per_body else unit_of[k]

            def position(k):
                u = unit_of[k]
                return psi[k] if per_body else (psi[u] + par(units[u].offsets[units[u].members.index(k)])
                                               if units[u].is_cluster else psi[u])

            friction = build_friction(
                scene, units, per_body, terms,
                lambda k: body_terms(k, position(k), dpsi[coordinate(k)], sliding=True, variable=psi[coordinate(k)]),
                lambda k: psi[coordinate(k)], lambda k: dpsi[coordinate(k)], par, slip_vars)
            for k, acc in friction[1].items():
                terms[k] = dataclasses.replace(terms[k], acceleration=acc)
        if per_body:
            # A rolling member of a cluster that slips takes part in the contacts with its translational
            # inertia m (kappa_eff = 1), rolling with kappa m (friction.build_friction's own blocks)
            within = friction[6] if rough else []
            inertia = {m.body: 1 + m.rolling * par(scene.bodies[m.body].kappa - 1) for m in within}
            accelerations, links, link_exprs, link_terms = _constrained_accelerations(
                scene, units, terms, psi, dpsi, par, events, inertia)
            if rough:
                for block in friction[0]:
                    if len(block.members) > 1:  # a stuck cluster does not move, whatever its contacts
                        for k in block.members:
                            accelerations[k] = (1 - hy.par[block.stuck]) * accelerations[k]
                slip_numbers = [b for b, block in enumerate(friction[0]) if block.rolls]  # slip_eqs' order
                for member in within:
                    b, k = member.block, member.body
                    # the friction its rolling would need: the contact forces solved with it rolling
                    as_rolling = dict(inertia)
                    as_rolling[k] = par(scene.bodies[k].kappa)
                    rolling_terms = list(terms)
                    rolling_terms[k] = dataclasses.replace(terms[k], acceleration=member.terms.acceleration)
                    rolling_acc = _constrained_accelerations(
                        scene, units, rolling_terms, psi, dpsi, par, False, as_rolling)[0]
                    slip_eq, need_now, need_rolling = member_slip_terms(
                        scene, member, accelerations[k], rolling_acc[k], psi[k], dpsi[k], par)
                    friction[2][slip_numbers.index(b)] = slip_eq
                    friction[4][b][0] = need_rolling
                    member_loads[b] = need_now
        else:
            within = friction[6] if rough else []
            slip_numbers = [b for b, block in enumerate(friction[0]) if block.rolls] if rough else []
            for u, unit in enumerate(units):
                if not unit.is_cluster:
                    acc = terms[unit.members[0]].acceleration
                else:
                    total = mpmath.fsum(G[k] for k in unit.members)
                    if scene.frame.rotating or scene.forcing is not None:
                        # (sum G_k) psi'' = sum G_k a_k, each member's a_k from its own terms at psi + o (the
                        # centrifugal force, the forcing): the fixed plane's -W sin alone moved a cluster in a
                        # turning hoop as if it did not turn (acceptance test: its Jacobi integral drifted);
                        # its contact forces (the links below) take the same G_k a_k
                        own = member_accelerations[u] = {
                            k: body_terms(k, psi[u] + par(o), dpsi[u], variable=psi[u]).acceleration
                            for k, o in zip(unit.members, unit.offsets)}
                        acc = hy.sum([par(G[k] / total) * own[k] for k in unit.members])
                    else:
                        acc = hy.sum([
                            -par(W[k] / total) * hy.sin(psi[u] + par(o)) for k, o in zip(unit.members, unit.offsets)
                        ])
                    if rough:
                        member_friction, stuck = friction[3][u]
                        forces = [f for f in member_friction.values()]
                        if forces:
                            acc = acc + par(1 / total) * hy.sum(forces) if len(forces) > 1 \
                                else acc + par(1 / total) * forces[0]
                        members = [m for m in within if m.body in unit.members]
                        if members:
                            acc, rolling_accs, slips = _slipping_members_motion(scene, members, acc, total, G, par)
                            member_slips[u] = {m.body: slip for m, slip in zip(members, slips)}
                            for member, rolling_acc in zip(members, rolling_accs):
                                b = member.block
                                slip_eq, need_now, need_rolling = member_slip_terms(
                                    scene, member, (1 - stuck) * acc, rolling_acc, psi[u], dpsi[u], par)
                                friction[2][slip_numbers.index(b)] = slip_eq
                                friction[4][b][0] = need_rolling
                                member_loads[b] = need_now
                        acc = (1 - stuck) * acc
                accelerations.append(acc)
    equations = [(psi[c], dpsi[c]) for c in range(nc)] + [(dpsi[c], accelerations[c]) for c in range(nc)]
    friction_blocks, friction_events_, friction_exprs, friction_values = (), (), [], []
    if rough:
        blocks_f, _, slip_eqs, _, friction_values, powers, _within = friction
        work_vars = _vars("D", len(blocks_f))
        equations += slip_eqs + list(zip(work_vars, powers))
        slip_index = {}
        fixed = []
        rolls_seen = 0
        for block in blocks_f:
            first = block.members[0]
            rate = nc + (first if per_body else block.unit)
            slip = -1
            if block.rolls:
                slip = 2 * nc + rolls_seen
                slip_index[len(fixed)] = rolls_seen
                rolls_seen += 1
            fixed.append(dataclasses.replace(block, rate=rate, slip=slip,
                                             work=2 * nc + len(slip_vars) + len(fixed)))
        friction_blocks = tuple(fixed)
        # A fifth value per block: the derivative of the rate that turns (q'' of a particle or a
        # cluster, w' of a slipping body), for the time-resolution test of resolve.friction.
        slip_rates = iter(eq[1] for eq in slip_eqs)
        friction_values = [list(v) + [next(slip_rates) if block.rolls else accelerations[block.rate - nc]]
                           for v, block in zip(friction_values, friction_blocks)]
        if events:
            evs, friction_exprs = friction_events(
                scene, friction_blocks, friction_values,
                lambda block: dpsi[block.rate - nc],
                lambda b: slip_vars[slip_index[b]],
                lambda block: terms[block.members[0]].normal, member_loads)
            friction_events_ = tuple(evs)

    def at(k):  # a body's place in the state
        return k if per_body else unit_of[k]

    contacts, gaps, guards, contact_exprs = [], [], [], []
    # A guard event costs as much as the gap's own (measured: 2.7 us of 15 per collision on
    # the default scene). In a fixed plane the circle's |psi''| has a closed bound, with which
    # a gap coming back up through zero tells a missed collision from rounding: no guards there.
    # (Friction and forcing break the bound: guards there.)
    reopening = track.linear_gap and not scene.frame.rotating and not rough and scene.forcing is None
    if nu > 1 and events:
        for a in range(nu):
            b = (a + 1) % nu
            if b == 0 and not track.closed:
                continue
            i, j = units[a].members[-1], units[b].members[0]
            index = scene_pair_index(scene, i, j)
            pair = scene.pairs[index]
            if allowed is not None and (pair.i, pair.j) not in allowed:
                continue
            if allowed is None and not pair.reachable:
                continue
            contacts.append(WatchedContact(pair_index=index, pair=pair, unit_a=a, unit_b=b))
            if track.linear_gap:
                with workprec():
                    constant = pair.offset - pair.beta - units[a].offsets[-1]
                gaps.append(psi[b] - psi[a] + par(constant))
                if not reopening:
                    guards.append(gaps[-1] + par(OVERLAP_FLOOR) * (1 + psi[b] * psi[b]))
            else:
                gap = _gap(scene, i, j, terms[i], terms[j], psi[i], psi[j], par)
                contact_exprs.append(_contact_terms(gap, terms[i], terms[j], psi[i], psi[j], dpsi[i], dpsi[j],
                                                    accelerations[i], accelerations[j]))
                # The event watches |C_j - C_i|^2 - d^2, same root and direction as the gap: heyoka
                # sizes its steps on the event functions too, and the square root's branch points
                # (|D|/|D'| away in complex time) halved the steps as bodies closed in (measured:
                # 384k steps against 229k on one arc equal to the default circle).
                with workprec():  # at the model's precision, not mpmath's global one (quad runs need it)
                    d = scene.bodies[i].radius + scene.bodies[j].radius
                if scene.point_contact(i, j):
                    gaps.append(gap)
                    guards.append(gap + par(OVERLAP_FLOOR) * (1 + psi[j] * psi[j]))
                else:
                    dx, dy = terms[j].x_c - terms[i].x_c, terms[j].y_c - terms[i].y_c
                    # |D|^2 - d^2 ~ 2 d gap: the overlap tolerance in metres, with 1 + q^2 at its largest on
                    # the track (q is bounded on an open track): a constant, cheaper per step (measured 2-6 %).
                    lo, hi = track.domain(scene.bodies[j])
                    with workprec():  # mpmath's global precision may be 15 digits: d^2 exact for quad
                        d2 = d * d
                        tolerance = 2 * d * OVERLAP_FLOOR * (1 + max(abs(lo), abs(hi)) ** 2)
                    gaps.append(hy.sum([dx * dx, dy * dy]) - par(d2))
                    guards.append(gaps[-1] + par(tolerance))

    for u, unit in enumerate(units):
        if per_body or not unit.is_cluster or not events:
            continue
        member_friction, stuck = friction[3][u] if rough else ({}, None)
        partial = []
        # A contact splits where lambda_m falls below -SPLIT_ULPS ulps of the cluster's weight
        # moments, not at 0.0: between bodies of one stiffness g / (kappa rho) at one angle
        # (particles on top of each other) lambda is 0 identically and its rounding crossed 0 at
        # once after every merge: they merged and split for ever at one instant (found by a
        # random-scene sweep: 8 bodies, k = 0, status failed). A real split is delayed by
        # ~1e-14 |lambda| / |lambda'|.
        with workprec():
            slack = SPLIT_ULPS * precision.epsilon * mpmath.fsum(W[k] for k in unit.members)
        for m, (k, o) in enumerate(zip(unit.members[:-1], unit.offsets[:-1])):
            own = par(G[k]) * member_accelerations[u][k] if u in member_accelerations else \
                -par(W[k]) * hy.sin(psi[u] + par(o))  # member k's generalized force Q_k = G_k a_k
            partial.append(own - par(G[k]) * accelerations[u])
            if k in member_friction:
                partial.append(member_friction[k])
            if k in member_slips.get(u, {}):  # slipping: its inertia is m rho^2, and friction acts on its centre
                rolling, slip_friction, lost = member_slips[u][k]
                partial.append((1 - rolling) * (lost * accelerations[u] + slip_friction))
            links.append(ContactLink(unit=u, position=m, pair_index=scene_pair_index(scene, k, unit.members[m + 1])))
            link = hy.sum(list(partial) + [par(slack)])
            # A stuck cluster's contact forces are statically indeterminate: it splits once it moves.
            link_exprs.append(link if stuck is None else (1 - stuck) * link + stuck)

    bound_events, bound_exprs = [], []
    release_events, release_exprs = [], []
    if blocks and events:
        for k in range(n):
            unit = units[unit_of[k]]
            if unit.pinned:
                # Resting on a stop: released where the track's forces pull a member away from it.
                release_events.append(k)
                acc = terms[k].acceleration
                release_exprs.append(-acc if unit.pinned == "lower" else acc)
                continue
            chain = len(track.junctions(scene.bodies[k])) > 0
            # Without junctions only the outermost bodies can reach a limiter, and only
            # if the energy can take them to its height.
            if chain or (k == 0 and reach.ends[k][0]):
                bound_events.append(BoundEvent(k, "lower"))
                bound_exprs.append(psi[at(k)] - hy.par[blocks[k].lower])
            if chain or (k == n - 1 and reach.ends[k][1]):
                bound_events.append(BoundEvent(k, "upper"))
                bound_exprs.append(hy.par[blocks[k].lower + 1] - psi[at(k)])

    strobe = None
    if scene.forcing is not None and events:
        # sin((nu t + psi)/2) vanishes once a forcing period, at nu t + psi = 2 pi n.
        strobe = hy.sin(par(scene.forcing.frequency / 2) * hy.time + par(scene.forcing.phase / 2))
    track_units = singleton_units(n) if per_body else units
    track_events, track_exprs = (_track_events(scene, reach, track_units, psi, dpsi, par, body_terms, terms)
                                 if events else ([], []))
    if per_body:
        body_exprs = [[t.x_c, t.y_c, t.normal, t.sigma, t.driving, a] for t, a in zip(terms, accelerations)]
    else:
        body_exprs = [[t.x_c, t.y_c, t.normal, t.sigma, t.driving, t.acceleration] for t in terms] if nu == n else []
    with workprec():
        rolling_mass = tuple(b.kappa * b.mass for b in scene.bodies)
    if not events:
        # The bare equations: only the parameters they read (a caller passes them to heyoka,
        # which wants exactly those up to the last one used).
        used = [int(m) for eq in equations for m in re.findall(r"\bp(\d+)\b", str(eq[1]))]
        del params[max(used, default=-1) + 1:]
    unit_motion = []
    # (a turning plane too: the fixed plane's closed forms judged a plastic pair in a turning hoop separating,
    # and it collided 65 times before it merged; acceptance test)
    if not per_body and events and (rough or scene.forcing is not None or scene.frame.rotating):
        for u in range(nu):
            acc = accelerations[u]
            jerk = hy.sum([hy.diff(acc, psi[c]) * dpsi[c] + hy.diff(acc, dpsi[c]) * accelerations[c]
                           for c in range(nu)])
            unit_motion.append([acc, jerk])
    return SceneSystem(
        equations=equations,
        parameters=params,
        units=units,
        contacts=tuple(contacts),
        gap_expressions=gaps,
        guard_expressions=guards,
        links=tuple(links),
        link_expressions=link_exprs,
        track_events=tuple(track_events),
        track_expressions=track_exprs,
        n_bodies=n,
        precision=precision,
        law_name=scene.law.name,
        unit_of=tuple(unit_of),
        gen_mass=tuple(float(x) for x in G),
        weight=tuple(float(x) for x in W),
        bound_events=tuple(bound_events),
        bound_expressions=bound_exprs,
        piece_blocks=tuple(blocks),
        contact_expressions=contact_exprs,
        body_expressions=body_exprs,
        variables=psi + dpsi + slip_vars + work_vars,
        track_shape=track_shape(track, scene.frame),
        linear_gap=track.linear_gap,
        particles=tuple(b.is_particle for b in scene.bodies),
        link_terms=link_terms,
        rolling_mass=rolling_mass,
        release_events=tuple(release_events),
        release_expressions=release_exprs,
        gap_reopening=reopening and bool(gaps),
        friction_blocks=friction_blocks,
        friction_events=friction_events_,
        friction_expressions=friction_exprs,
        friction_values=friction_values,
        n_extra=len(slip_vars) + len(work_vars),
        strobe_expression=strobe,
        unit_motion=unit_motion,
        extra_shape=(rough, scene.track_sides if rough else "",
                     None if scene.forcing is None else (scene.forcing.kind, scene.forcing.bodies)),
    )


def track_shape(track, frame) -> tuple:
    """What of a track compiled code depends on: its type, a curve's expression, a turning plane."""
    return (track.kind, getattr(track, "text", None), track.coordinate, frame.rotating)


def piece_of(track, body, q) -> int:
    """The piece of track holding coordinate q (a junction belongs to the piece after it)."""
    junctions = track.junctions(body)
    return sum(1 for s in junctions if q >= s) if junctions else 0


def piece_bounds(track, body, piece: int):
    """(lower, upper) coordinate of a piece: junctions, or the track's ends."""
    lo, hi = track.domain(body)
    cuts = [lo, *track.junctions(body), hi]
    return cuts[piece], cuts[piece + 1]


def _gap(scene, i, j, ti, tj, qi, qj, par):
    """Distance between the surfaces of bodies i and j (m); q_j - q_i where they meet at a point of
    the track (two particles, a particle and a rolling body: Scene.point_contact)."""
    with workprec():  # at the model's precision, not mpmath's global one (quad runs need it)
        d = scene.bodies[i].radius + scene.bodies[j].radius
    if scene.point_contact(i, j):  # two points of one curve: a signed gap along it
        return qj - qi
    dx, dy = tj.x_c - ti.x_c, tj.y_c - ti.y_c
    return hy.sqrt(dx * dx + dy * dy) - par(d)


def _contact_terms(gap, ti, tj, qi, qj, vi, vj, ai, aj) -> list:
    """[gap, dgap/dq_i, dgap/dq_j, sigma_i, sigma_j, d2gap/dt2, d3gap/dt3] of a pair, as expressions.

    The gradient gives the gap rate dgap/dt = g_i q_i' + g_j q_j' (and the
    direction of the fallback impulse), sigma the law's metric at the
    contact; the gap's acceleration and jerk judge whether bodies that do
    not separate are pressed together (persistent contact, see
    events.below_resolution).
    """
    gi, gj = hy.diff(gap, qi), hy.diff(gap, qj)
    rate = gi * vi + gj * vj

    def d_dt(x):
        return hy.diff(x, qi) * vi + hy.diff(x, qj) * vj + hy.diff(x, vi) * ai + hy.diff(x, vj) * aj

    acc = d_dt(rate)
    return [gap, gi, gj, ti.sigma, tj.sigma, acc, d_dt(acc)]


def _constrained_accelerations(scene, units, terms, q, v, par, events, inertia=None):
    """Each body's q'' with the contacts inside clusters as holonomic constraints (tracks whose gap is not linear).

    A cluster's links l (members m_l, m_l+1) keep their gap g_l = |C_i - C_j| - r_i - r_j
    at zero, written h_l = |C_j - C_i|^2 - (r_i + r_j)^2 = 0 (see _link_constraint). With the generalized masses M_k = kappa_k m_k sigma_k^2 (d2T/dq'^2) and
    Lagrange multipliers lambda_l on the gaps (ideal contacts: no work),

        M_k q_k'' = M_k a_k + sum_l lambda_l dg_l/dq_k,

    a_k the body's own acceleration (lambda_l on h_l). h_l'' = 0 is a tridiagonal linear system for
    the lambdas (solved here symbolically, Thomas' algorithm); lambda_l > 0 is a
    compressive contact, and the cluster splits where it reaches 0 (the link
    event). The drift of the constraint under round-off is damped (Baumgarte):
    h'' + 2 alpha h' + alpha^2 h = 0, alpha the inverse of the motion's time
    scale sqrt(L/g); the exact constrained motion (h = h' = 0) is unchanged.
    Pinned units (resting on a limiter) do not move. ``inertia[k]``: member k's kappa_eff where it is not
    its kappa (a rolling body that may slip on a rough track: 1 while it slips). Returns (accelerations,
    links, their lambda expressions, their [gap, dg/dq_i, dg/dq_j]).
    """
    track = scene.track
    acc = [t.acceleration for t in terms]
    out = list(acc)
    links, lambdas, link_terms = [], [], []
    length = max(float(hi - lo) for lo, hi in (track.domain(b) for b in scene.bodies))
    alpha = par(math.sqrt(float(scene.g) / max(length, 1e-300)))
    inertia = inertia or {}
    for u, unit in enumerate(units):
        if unit.pinned:
            for k in unit.members:
                out[k] = par(0)
            continue
        if not unit.is_cluster:
            continue
        members = unit.members
        M = [(par(scene.bodies[k].mass) * inertia[k] if k in inertia else par(scene.bodies[k].kappa * scene.bodies[k].mass))
             * terms[k].sigma * terms[k].sigma for k in members]
        grads, rhs = [], []
        for i, j in zip(members, members[1:]):
            h, hi, hj, h_rate, h_free = _link_constraint(scene, i, j, terms, q, v, acc, par)
            grads.append((hi, hj))
            rhs.append(-(h_free + 2 * alpha * h_rate + alpha * alpha * h))
            gap = _gap(scene, i, j, terms[i], terms[j], q[i], q[j], par)  # the watched gap's own form
            link_terms.append([gap, hy.diff(gap, q[i]), hy.diff(gap, q[j])])
            links.append(ContactLink(unit=u, position=len(grads) - 1, pair_index=scene_pair_index(scene, i, j)))
        L = len(grads)
        diag = [grads[l][0] * grads[l][0] / M[l] + grads[l][1] * grads[l][1] / M[l + 1] for l in range(L)]
        sub = [None] + [grads[l][0] * grads[l - 1][1] / M[l] for l in range(1, L)]
        sup = [grads[l][1] * grads[l + 1][0] / M[l + 1] for l in range(L - 1)] + [None]
        cp, dp = [None] * L, [None] * L
        for l in range(L):
            den = diag[l] if l == 0 else diag[l] - sub[l] * cp[l - 1]
            if l < L - 1:
                cp[l] = sup[l] / den
            dp[l] = rhs[l] / den if l == 0 else (rhs[l] - sub[l] * dp[l - 1]) / den
        lam = [None] * L
        lam[L - 1] = dp[L - 1]
        for l in range(L - 2, -1, -1):
            lam[l] = dp[l] - cp[l] * lam[l + 1]
        for p, k in enumerate(members):
            push = []
            if p > 0:
                push.append(lam[p - 1] * grads[p - 1][1])
            if p < L:
                push.append(lam[p] * grads[p][0])
            out[k] = acc[k] + hy.sum(push) / M[p]
        lambdas += lam
    if not events:
        links, lambdas = [], []
    return out, links, lambdas, link_terms


def _centre_derivatives(term, q):
    """(C', C'') of a body's centre along its coordinate, as expression pairs."""
    dx, dy = hy.diff(term.x_c, q), hy.diff(term.y_c, q)
    return (dx, dy), (hy.diff(dx, q), hy.diff(dy, q))


def _link_constraint(scene, i, j, terms, q, v, acc, par):
    """A contact kept closed: h = |C_j - C_i|^2 - (r_i + r_j)^2 (no square root), its gradient,
    its rate and its second derivative under the bodies' own accelerations.

    With D = C_j - C_i: h' = 2 D.D', h'' = 2 (D'.D' + D.D''), D' = C_j' q_j' - C_i' q_i',
    D'' = C_j'' q_j'^2 + C_j' q_j'' - (i). Two particles (r = 0) keep q_j - q_i = 0.
    """
    if scene.point_contact(i, j):
        return q[j] - q[i], -1.0, 1.0, v[j] - v[i], acc[j] - acc[i]
    (xi1, yi1), (xi2, yi2) = _centre_derivatives(terms[i], q[i])
    (xj1, yj1), (xj2, yj2) = _centre_derivatives(terms[j], q[j])
    Dx, Dy = terms[j].x_c - terms[i].x_c, terms[j].y_c - terms[i].y_c
    Vx, Vy = xj1 * v[j] - xi1 * v[i], yj1 * v[j] - yi1 * v[i]
    Ax = xj2 * v[j] * v[j] + xj1 * acc[j] - xi2 * v[i] * v[i] - xi1 * acc[i]
    Ay = yj2 * v[j] * v[j] + yj1 * acc[j] - yi2 * v[i] * v[i] - yi1 * acc[i]
    with workprec():  # at the model's precision, not mpmath's global one (quad runs need it)
        d = scene.bodies[i].radius + scene.bodies[j].radius
        d2 = d * d
    h = Dx * Dx + Dy * Dy - par(d2)
    hi, hj = -2.0 * (Dx * xi1 + Dy * yi1), 2.0 * (Dx * xj1 + Dy * yj1)
    return h, hi, hj, 2.0 * (Dx * Vx + Dy * Vy), 2.0 * (Vx * Vx + Vy * Vy + Dx * Ax + Dy * Ay)


def _vars(prefix: str, n: int) -> list:
    names = [f"{prefix}_{k + 1}" for k in range(n)]
    made = hy.make_vars(*names)
    return [made] if n == 1 else list(made)


def _track_events(scene: Scene, reach: EnergyReach, units, psi, dpsi, par, body_terms, free_terms):
    """Normal force events, only for bodies the energy can take there.

    The track pushes with N (per unit mass, :class:`heyroll.model.tracks.BodyTerms`;
    on the circle N/m = rho phi'^2 + g cos phi). On a one-sided track N = 0 ends the
    run; on a two-sided one (the default) the first time is recorded as a
    warning. On a fixed circle N can vanish only above the centre's height
    (cos phi < 0): a body whose weight moment exceeds the system's whole
    energy never gets there. Bodies in a cluster are checked with these
    free-body forces (the contact forces' share is not included; see README).
    (Slipping on a rough track: :mod:`heyroll.simulation.friction`, for free bodies and cluster members.)
    """
    events, exprs = [], []
    for u, unit in enumerate(units):
        for k, o in zip(unit.members, unit.offsets):
            if not reach.top_half[k]:
                continue
            terms = body_terms(k, psi[u] + par(o), dpsi[u], variable=psi[u]) if unit.is_cluster else free_terms[k]
            events.append(TrackEvent(body=k, kind="left_track", terminal=scene.track_sides == "one"))
            exprs.append(terms.normal)
    return events, exprs


def _slipping_members_motion(scene, members, acc, total, G, par):
    """A rigid cluster's psi'' on the circle with rolling members that may slip, and per member the psi''
    it would have were that member rolling.

    (sum G_eff) psi'' = sum Q_k + the particles' friction + each slipping member's -s mu m N rho: a slipping
    member's generalized force from gravity, the frame and forcing is the same as rolling (G_k a_k: forces
    on the centre), its inertia m rho^2 = G_k / kappa_k, and the friction on its centre adds to the sum.
    ``acc``: psi'' with every member rolling, (sum Q_k + friction) / sum G_k (mpf ``total``). Returns (psi'',
    per member the psi'' were it rolling, per member :func:`_member_slip`)."""
    generalized = par(total) * acc
    mass = par(total)
    pieces, slips = [], []
    for member in members:
        rolling, slip_friction, lost = _member_slip(scene, member, G, par)
        slips.append((rolling, slip_friction, lost))
        pieces.append(((1 - rolling) * slip_friction, (1 - rolling) * lost))
    slipping_force = hy.sum([p[0] for p in pieces]) if len(pieces) > 1 else pieces[0][0]
    slipping_mass = hy.sum([p[1] for p in pieces]) if len(pieces) > 1 else pieces[0][1]
    out = (generalized + slipping_force) / (mass - slipping_mass)
    as_rolling = [(generalized + slipping_force - force) / (mass - slipping_mass + lost) for force, lost in pieces]
    return out, as_rolling, slips


def _member_slip(scene, member, G, par):
    """(rolling parameter, -s mu m N rho its friction's generalized force, G (1 - 1/kappa) the inertia it
    loses slipping) of a rolling member of a rigid cluster (a friction.MemberSlip)."""
    with workprec():
        lost = G[member.body] * (1 - 1 / scene.bodies[member.body].kappa)
    return member.rolling, member.friction, par(lost)


def _with_margin(height: float) -> float:
    """A height bound widened against rounding (m)."""
    return height + 1e-9 * (1 + abs(height))


def _can_reach_end(scene: Scene, k: int, end: int) -> bool:
    """Whether body k's energy can take it to the lower (0) or upper (1) end of the track."""
    height = scene.height_bound(k)
    if height is None:
        return True
    body = scene.bodies[k]
    q = float(scene.track.domain(body)[end])
    return float(scene.track.centre(body, [q])[1][0]) <= _with_margin(height)


def gap_value(system: SceneSystem, number: int, unit_state) -> float:
    """Gap of the number-th watched contact, in rad, from a unit state (in the state's number type)."""
    c = system.contacts[number]
    return unit_state[c.unit_b] - unit_state[c.unit_a] + system.gap_constants[number]


def unit_acceleration(system: SceneSystem, unit: int, psi: float) -> float:
    """psi'' of a unit at angle psi (floats; used to judge contacts)."""
    offsets, weights, total = system._unit_floats[unit]
    return -sum(w * math.sin(psi + o) for w, o in zip(weights, offsets)) / total


def unit_jerk(system: SceneSystem, unit: int, psi: float, dpsi: float) -> float:
    """Third derivative of a unit's angle at psi, moving at dpsi (floats): d/dt of unit_acceleration."""
    offsets, weights, total = system._unit_floats[unit]
    return -dpsi * sum(w * math.cos(psi + o) for w, o in zip(weights, offsets)) / total
