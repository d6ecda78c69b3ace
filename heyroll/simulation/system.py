"""The heyoka ODE system of a scene in one contact mode: only what it needs.

Bodies move in *units*: a free body is a unit of one; bodies held in
persistent contact form a cluster that moves as one unit (one degree of
freedom less per contact). A unit's coordinate psi is the angle of its first
(most clockwise) member; member k sits at psi + o_k.

State layout: [psi_1 .. psi_U, dpsi_1 .. dpsi_U]; with no clusters (the usual
case) that is [phi_1 .. phi_N, dphi_1 .. dphi_N] and each body is a rolling
pendulum, phi'' = -g/(kappa (R - r)) sin phi (paper eq. 25). A cluster obeys

    (sum_k G_k) psi'' = -sum_k W_k sin(psi + o_k)

(G = kappa m rho^2, W = m g rho, eq. 21), and the compressive contact force
between members m and m+1 (a generalized force, N m) is

    lambda_m = sum_{k <= m} (-W_k sin(psi + o_k) - G_k psi'').

Events: the gap between neighbouring units (collisions), the gap going
below -overlap_tolerance (a guard: a missed collision, see
:func:`overlap_tolerance`), lambda_m = 0 (a contact that would pull: the
cluster splits), and, where the scene's energy
can get there, the normal force of the track reaching zero (the body leaves
the track) and the friction needed to roll exceeding mu N (it slips). All
constants are runtime parameters, so scenes of one shape share compiled code.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import heyoka as hy
import mpmath

from ..model._numbers import workprec
from ..model.scene import ContactPair, Scene
from .precision import Precision

#: Interpenetration allowed before a run is declared failed (status overlap):
#: OVERLAP_FLOOR rad near the bottom, growing like 1 + phi_j^2 so that the
#: rounding of a gap between angles of many turns (~ eps |phi|) never trips
#: it (phi_j: the angle of the pair's second body; phi_i is within 2 pi of it).
OVERLAP_FLOOR = 1e-12


def overlap_tolerance(phi_j) -> float:
    """How far below zero the gap of a pair whose second body is at phi_j may go (rad)."""
    phi_j = float(phi_j)
    return OVERLAP_FLOOR * (1 + phi_j * phi_j)


@dataclass(frozen=True)
class Unit:
    """Bodies moving together (0-based indices, clockwise first) and their offsets o_k."""

    members: tuple[int, ...]
    offsets: tuple  # mpf, o_k relative to the first member

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
    """Where the track stops holding a body: ``kind`` is 'left_track' or 'slip'.

    ``terminal``: the run stops there (a one-sided track, or slipping);
    otherwise (a two-sided track) the first time is only recorded.
    """

    body: int
    kind: str
    terminal: bool = True


@dataclass(frozen=True)
class SceneSystem:
    """Expressions and parameter values of a scene in one mode, at one precision."""

    equations: list
    parameters: list
    units: tuple[Unit, ...]
    contacts: tuple[WatchedContact, ...]
    gap_expressions: list
    #: Per watched contact: gap + overlap_tolerance(psi_b) (psi_b = phi_j), a
    #: terminal guard that fires only if a collision was missed.
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
    #: The scene's initial state in this mode's coordinates, at the run's precision.
    initial_state: list = field(default_factory=list)

    @property
    def n_units(self) -> int:
        return len(self.units)

    @property
    def shape(self) -> tuple:
        """Everything the compiled code depends on (constants are parameters)."""
        return (
            self.n_bodies,
            tuple(u.members for u in self.units),
            tuple(c.pair_index for c in self.contacts),
            tuple((l.unit, l.position) for l in self.links),
            tuple((e.body, e.kind, e.terminal) for e in self.track_events),
            self.precision.name,
        )

    @property
    def pairs(self) -> tuple[ContactPair, ...]:
        return tuple(c.pair for c in self.contacts)

    def offsets_float(self, unit: int) -> list[float]:
        return [float(o) for o in self.units[unit].offsets]

    def expand(self, unit_state) -> list:
        """Full state [phi_1..phi_N, dphi_1..dphi_N] from a unit state."""
        if not any(u.is_cluster for u in self.units):
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

    def reduce(self, full_state) -> list:
        """Unit state from a full state (first member's angle and rate)."""
        n = self.n_bodies
        psi = [full_state[u.members[0]] for u in self.units]
        dpsi = [full_state[n + u.members[0]] for u in self.units]
        return psi + dpsi


def singleton_units(n: int) -> tuple[Unit, ...]:
    return tuple(Unit(members=(k,), offsets=(mpmath.mpf(0),)) for k in range(n))


def cluster_unit(scene: Scene, members: tuple[int, ...]) -> Unit:
    """A cluster of consecutive touching bodies, offsets accumulated from the pairs' beta."""
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


@functools.lru_cache(maxsize=64)
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
    (no event expressions, no parameters for them). Results are cached (scenes
    are immutable): treat the returned lists as read-only.
    """
    n = len(scene.bodies)
    units = singleton_units(n) if units is None else tuple(units)
    nu = len(units)
    allowed = None if pairs is None else {id(p) for p in pairs}
    psi = _vars("phi", nu) if all(not u.is_cluster for u in units) else _vars("psi", nu)
    dpsi = _vars("dphi", nu) if all(not u.is_cluster for u in units) else _vars("dpsi", nu)
    num = precision.number
    tr, g = scene.track, scene.g
    params: list = []

    def par(value) -> hy.expression:
        params.append(num(value))
        return hy.par[len(params) - 1]

    G = [tr.generalized_mass(b) for b in scene.bodies]
    W = [tr.weight_moment(b, g) for b in scene.bodies]
    equations = [(psi[u], dpsi[u]) for u in range(nu)]
    accelerations = []
    with workprec():
        for u, unit in enumerate(units):
            if not unit.is_cluster:
                acc = -par(tr.angular_stiffness(scene.bodies[unit.members[0]], g)) * hy.sin(psi[u])
            else:
                total = mpmath.fsum(G[k] for k in unit.members)
                acc = hy.sum([
                    -par(W[k] / total) * hy.sin(psi[u] + par(o)) for k, o in zip(unit.members, unit.offsets)
                ])
            accelerations.append(acc)
            equations.append((dpsi[u], acc))

    contacts, gaps, guards = [], [], []
    if nu > 1 and events:
        for a in range(nu):
            b = (a + 1) % nu
            i, j = units[a].members[-1], units[b].members[0]
            index = scene_pair_index(scene, i, j)
            pair = scene.pairs[index]
            if allowed is not None and id(pair) not in allowed:
                continue
            if allowed is None and not pair.reachable:
                continue
            with workprec():
                constant = pair.offset - pair.beta - units[a].offsets[-1]
            contacts.append(WatchedContact(pair_index=index, pair=pair, unit_a=a, unit_b=b))
            gaps.append(psi[b] - psi[a] + par(constant))
            # (1 + psi_b^2): measured +16 % per collision on the two-ball hot path,
            # against +10 % for a constant tolerance that large angles would trip.
            guards.append(gaps[-1] + par(OVERLAP_FLOOR) * (1 + psi[b] * psi[b]))

    links, link_exprs = [], []
    for u, unit in enumerate(units):
        if not unit.is_cluster or not events:
            continue
        partial = []
        for m, (k, o) in enumerate(zip(unit.members[:-1], unit.offsets[:-1])):
            partial.append(-par(W[k]) * hy.sin(psi[u] + par(o)) - par(G[k]) * accelerations[u])
            links.append(ContactLink(unit=u, position=m, pair_index=scene_pair_index(scene, k, unit.members[m + 1])))
            link_exprs.append(hy.sum(list(partial)))

    track_events, track_exprs = _track_events(scene, units, psi, dpsi, par) if events else ([], [])
    unit_of = [0] * n
    for u, unit in enumerate(units):
        for k in unit.members:
            unit_of[k] = u
    start = [num(x) for x in scene.phi]
    rates = [num(x) for x in scene.dphi]
    return SceneSystem(
        initial_state=[start[u.members[0]] for u in units] + [rates[u.members[0]] for u in units],
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
    )


def _vars(prefix: str, n: int) -> list:
    names = [f"{prefix}_{k + 1}" for k in range(n)]
    made = hy.make_vars(*names)
    return [made] if n == 1 else list(made)


def _track_events(scene: Scene, units, psi, dpsi, par):
    """Normal force and friction events, only for bodies the energy can take there.

    Per unit mass, the track pushes with N/m = rho phi'^2 + g cos phi and
    rolling needs the friction F/m = g sin phi (1 - 1/kappa) (paper eqs. 21,
    25). On a one-sided track N = 0 ends the run; on a two-sided one (the
    default) the first time is recorded as a warning. N can vanish
    only above the centre's height (cos phi < 0): a body whose weight moment
    exceeds the system's whole energy never gets there. Bodies in a cluster
    are checked with these free-body forces (the contact force's share is
    not included; see README).
    """
    tr, g = scene.track, scene.g
    energy = scene.total_energy()
    mu = scene.track_friction
    events, exprs = [], []
    for u, unit in enumerate(units):
        for k, o in zip(unit.members, unit.offsets):
            body = scene.bodies[k]
            rho = tr.path_radius(body)
            reach_top_half = energy >= tr.weight_moment(body, scene.g) * (1 - mpmath.mpf(10) ** -9)
            slips = mu is not None and body.kappa > 1
            if not (reach_top_half or slips):
                continue
            phi = psi[u] + par(o) if unit.is_cluster else psi[u]
            # Above the horizontal diameter the body needs W (1 - cos phi) > W of energy.
            if reach_top_half:
                events.append(TrackEvent(body=k, kind="left_track", terminal=scene.track_sides == "one"))
                exprs.append(par(rho) * dpsi[u] ** 2 + par(g) * hy.cos(phi))
            if slips:
                normal = par(rho) * dpsi[u] ** 2 + par(g) * hy.cos(phi)
                friction = par(g * (1 - 1 / body.kappa)) * hy.sin(phi)
                events.append(TrackEvent(body=k, kind="slip"))
                exprs.append(par(mu) * normal - friction)
                events.append(TrackEvent(body=k, kind="slip"))
                exprs.append(par(mu) * normal + friction)
    return events, exprs


def gap_value(system: SceneSystem, number: int, unit_state) -> float:
    """Gap of the number-th watched contact, in rad, from a unit state (in the state's number type)."""
    c = system.contacts[number]
    a, b = c.unit_a, c.unit_b
    with workprec():
        constant = system.precision.number(c.pair.offset - c.pair.beta - system.units[a].offsets[-1])
    return unit_state[b] - unit_state[a] + constant


def unit_acceleration(system: SceneSystem, unit: int, psi: float) -> float:
    """psi'' of a unit at angle psi (floats; used to judge contacts)."""
    members = system.units[unit].members
    total = sum(system.gen_mass[k] for k in members)
    return -sum(system.weight[k] * math.sin(psi + o) for k, o in zip(members, system.offsets_float(unit))) / total


def unit_jerk(system: SceneSystem, unit: int, psi: float, dpsi: float) -> float:
    """Third derivative of a unit's angle at psi, moving at dpsi (floats): d/dt of unit_acceleration."""
    members = system.units[unit].members
    total = sum(system.gen_mass[k] for k in members)
    moments = sum(system.weight[k] * math.cos(psi + o) for k, o in zip(members, system.offsets_float(unit)))
    return -dpsi * moments / total
