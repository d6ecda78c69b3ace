"""Events of one contact mode: collisions, contact splits, track limits.

A collision event fires when a gap between neighbouring units closes
(direction negative only: approach). Its callback applies the collision law
as an impulse map on the rates and appends one raw record to the log (time,
pair, state before, outgoing rates); the table is built from the records
afterwards, vectorized. The callback also judges the outcome:

* the law leaves the bodies approaching in position (they would overlap):
  the scene's policy applies, ``newton`` (Newton's law on the gap rate with
  generalized masses for that collision, counted and flagged) or ``error``
  (stop, naming the collision);
* the bodies are pressed together (the gap's acceleration is closing) and
  the bounces that remain are below the run's resolution: the pair enters
  persistent contact (see :func:`below_resolution`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import heyoka as hy
import mpmath
import numpy as np

from ..model.laws import GeneralizedNewtonLaw, ImpulseMap, impulse_map
from ..model._numbers import workprec
from .system import SceneSystem, unit_acceleration

#: A post-collision separation rate within this many ulps of zero (relative to
#: the approach rate) counts as no separation (a plastic outcome).
SEPARATION_ULPS = 64

#: Resolution of a run, in ulps: bounces whose height or remaining duration
#: fall below it cannot be told apart from rest in contact.
RESOLUTION_ULPS = 64


@dataclass
class StopRequest:
    """Why a callback asked the integrator to stop (None: it did not)."""

    reason: str | None = None
    message: str = ""
    data: dict = field(default_factory=dict)


@dataclass
class CollisionLog:
    """Raw collision records appended by the event callbacks.

    When ``chunk_size`` records have piled up the callback calls ``on_full``,
    which hands them on (to a file) and clears the list, so memory stays flat
    however long the run; ``flushed`` counts the records handed on.
    ``fallbacks`` counts collisions resolved by the fallback law.
    """

    records: list = field(default_factory=list)
    max_collisions: int | None = None
    stop: StopRequest = field(default_factory=StopRequest)
    flushed: int = 0
    chunk_size: int = 1 << 62
    on_full: object = None
    fallbacks: int = 0
    #: First time each body's normal force changed sign on a two-sided track.
    warnings: dict = field(default_factory=dict)

    @property
    def count(self) -> int:
        return self.flushed + len(self.records)


def mode_handlers(scene, system: SceneSystem, log: CollisionLog, holder: list, time_scale: float) -> tuple[list, list]:
    """The callbacks of one contact mode, in the order of :func:`mode_events`.

    Returns (terminal handlers, non-terminal handlers). ``holder[0]`` must be
    set to the integrator's state array (a view into heyoka's buffer) before
    integrating; the handlers use it to avoid re-wrapping the buffer at every
    collision.
    """
    fast = not any(u.is_cluster for u in system.units)
    handlers: list = []
    # Three or more bodies: contacts can close at the same instant.
    cascade = simultaneous_contacts(system, handlers) if fast and system.n_bodies > 2 else None
    for number in range(len(system.contacts)):
        if fast:
            handlers.append(_make_callback(scene, system, number, log, holder, time_scale, cascade))
        else:
            handlers.append(_make_unit_callback(scene, system, number, log, holder, time_scale))
    handlers += [_stopper(log, "split", {"link": number}) for number in range(len(system.links))]
    handlers += [_track_stopper(log, ev, holder, system) for ev in system.track_events if ev.terminal]
    warnings = [_track_warning(log, ev, system) for ev in system.track_events if not ev.terminal]
    return handlers, warnings


def mode_events(system: SceneSystem, cooldown, slots: list, nt_slots: list) -> tuple[list, list]:
    """heyoka events of one contact mode whose callbacks call ``slots[n]`` / ``nt_slots[n]``.

    The indirection lets one compiled integrator serve many runs of the same
    shape: each run puts its own handlers (:func:`mode_handlers`) in the slots.
    Collisions (gap closing), contact splits (contact force reaching 0,
    decreasing) and track limits are terminal; track warnings are not.
    """
    options = system.precision.integrator_options()
    negative = hy.event_direction.negative

    def forward(n):
        return lambda ta, d_sgn: slots[n](ta, d_sgn)

    def forward_nt(n):
        return lambda ta, t, d_sgn: nt_slots[n](ta, t, d_sgn)

    events = [
        # heyoka's default cooldown (scaled by 1/|gap'|) hides the quick
        # re-collisions of an accumulating (Zeno) sequence; one ulp of the
        # motion's time scale is far below any interval the contact criterion
        # lets through, and direction filtering does the rest. (A cooldown of
        # exactly 0 loses collisions: measured.)
        hy.t_event(gap, callback=forward(n), direction=negative, cooldown=cooldown, **options)
        for n, gap in enumerate(system.gap_expressions)
    ]
    expressions = list(system.link_expressions)
    expressions += [x for x, ev in zip(system.track_expressions, system.track_events) if ev.terminal]
    events += [
        hy.t_event(x, callback=forward(len(system.gap_expressions) + n), direction=negative, **options)
        for n, x in enumerate(expressions)
    ]
    nt_expressions = [x for x, ev in zip(system.track_expressions, system.track_events) if not ev.terminal]
    nt_events = [hy.nt_event(x, forward_nt(n), direction=negative, **options) for n, x in enumerate(nt_expressions)]
    return events, nt_events


def _track_warning(log, ev, system):
    """Record, once per body, where a two-sided track's normal force changes sign.

    On a two-sided track such a body goes on rolling (the outer race holds
    it); the first time is worth knowing.
    """

    def record(ta, t, d_sgn, body=ev.body):
        if body not in log.warnings:
            # Non-terminal events see the state at the end of the step: ask for t's.
            full = system.expand(ta.update_d_output(t).tolist())
            log.warnings[body] = (
                f"body {body + 1}: the normal force of the track changes sign at t = {float(t):.17g} s, "
                f"phi = {float(full[body]):.6g} rad (on a one-sided track it would leave it here)"
            )

    return record


def _stopper(log, reason, data):
    def stop(ta, d_sgn):
        log.stop.reason, log.stop.data = reason, data
        return False

    return stop


def _track_stopper(log, event, holder, system):
    what = {
        "left_track": "leaves the track: the normal force N = m (rho phi'^2 + g cos phi) reaches 0",
        "slip": "starts to slip: the friction needed to roll, m g sin phi (1 - 1/kappa), exceeds mu N",
    }[event.kind]

    def stop(ta, d_sgn):
        full = system.expand(holder[0].tolist())
        log.stop.reason = event.kind
        log.stop.message = (
            f"body {event.body + 1} {what}, at phi = {float(full[event.body]):.17g} rad, "
            f"dphi = {float(full[system.n_bodies + event.body]):.17g} rad/s, t = {float(ta.time):.17g} s"
        )
        return False

    return stop


def below_resolution(opening, gap_acceleration, restitution, t, scale, time_scale, eps) -> bool:
    """Whether the bounces left after a collision are below the run's resolution.

    Bodies pressed together (gap acceleration -A < 0) that separate at rate v
    fly apart for 2v/A and rise h = v^2/(2A); with restitution k every next
    bounce is k times slower, so the whole remaining sequence lasts
    T = 2v/(A (1 - k)) (the sum of the geometric series; Zeno's accumulation
    point). When T is below the time resolution of the run or h below the
    resolution of the gap, no further bounce can be resolved and the pair is
    taken to be in persistent contact from now on.
    """
    if gap_acceleration >= 0:
        return False
    A = -gap_acceleration
    v = max(opening, 0.0)
    h = v * v / (2 * A)
    remaining = 2 * v / (A * (1 - restitution)) if restitution < 1 else math.inf
    return h <= RESOLUTION_ULPS * eps * scale or remaining <= RESOLUTION_ULPS * eps * (abs(t) + time_scale)


@functools.lru_cache(maxsize=256)
def fallback_map(scene, pair) -> ImpulseMap:
    """Newton's law on the gap rate with generalized masses, for one pair."""
    law = GeneralizedNewtonLaw(restitution=scene.law.restitution)
    return impulse_map(law, scene.track, scene.bodies[pair.i], scene.bodies[pair.j])


def unit_map(system: SceneSystem, a: int, b: int, restitution) -> ImpulseMap:
    """Newton's law on psi' between two units with their total generalized masses."""
    with workprec():
        Ma = mpmath.fsum(mpmath.mpf(system.gen_mass[k]) for k in system.units[a].members)
        Mb = mpmath.fsum(mpmath.mpf(system.gen_mass[k]) for k in system.units[b].members)
        k = mpmath.mpf(restitution)
        return ImpulseMap(q=mpmath.mpf(1), a_i=(1 + k) * Mb / (Ma + Mb), a_j=(1 + k) * Ma / (Ma + Mb), one_plus_k=1 + k)


#: numpy's extended type where it has more bits than a double (x86: 64-bit
#: mantissa), else None: then the map runs in the run's own type.
EXTENDED = np.longdouble if np.finfo(np.longdouble).nmant > 52 else None


@dataclass(frozen=True)
class WorkingMap:
    """The collision map of one pair in the arithmetic a run applies it in.

    D = phi_i' - q phi_j';  phi_i'+ = phi_i' - a_i D;  phi_j'+ = phi_j' + a_j D,
    with a_i = (1 + k) - q a_j enforced on the rounded constants, which makes
    the elastic map conserve a fixed quadratic form (within a rounding of the
    kinetic energy) exactly: no constant's rounding biases every collision the
    same way. Double runs evaluate the map in extended precision and round the
    two outgoing rates once, so the energy error of a long elastic run is a
    random walk (Brouwer's law), not a drift.
    """

    q: object
    a_i: object
    a_j: object
    extended: bool


@functools.lru_cache(maxsize=256)
def working_map(law_map, precision) -> WorkingMap:
    """Round the law's constants once for ``precision`` (see :class:`WorkingMap`)."""
    extended = precision.name == "double" and EXTENDED is not None
    if extended:

        def num(x):
            with mpmath.workprec(256):
                return EXTENDED(mpmath.nstr(mpmath.mpf(x), 25, strip_zeros=False))

    else:
        num = precision.number

    def exact(x):
        if hasattr(x, "as_integer_ratio"):  # float, longdouble: the binary value exactly
            n, d = x.as_integer_ratio()
            return mpmath.mpf(n) / d
        return mpmath.mpf(str(x))  # real128 / real: their text round-trips at their precision

    q, a_j = num(law_map.q), num(law_map.a_j)
    with mpmath.workprec(4 * max(precision.bits, 64) + 64):
        a_i = num(law_map.one_plus_k - exact(q) * exact(a_j))  # a_i + q a_j = 1 + k
    return WorkingMap(q=q, a_i=a_i, a_j=a_j, extended=extended)


def _apply(m: "WorkingMap", vi, vj):
    if m.extended:
        ei, ej = EXTENDED(vi), EXTENDED(vj)
        d = ei - m.q * ej
        return float(ei - m.a_i * d), float(ej + m.a_j * d)
    d = vi - m.q * vj
    return vi - m.a_i * d, vj + m.a_j * d


def _make_callback(scene, system: SceneSystem, number: int, log: CollisionLog, holder: list, time_scale: float,
                   cascade=None):
    """The hot path: every body free, the state is [phi_1..phi_N, dphi_1..dphi_N].

    Returns the event callback; its ``resolve(s, before, t)`` applies the law
    to the pair alone (also used by ``cascade`` for simultaneous contacts).
    """
    contact = system.contacts[number]
    pair = contact.pair
    pair_index = contact.pair_index
    law_map = working_map(pair.law_map, system.precision)
    fallback = working_map(fallback_map(scene, pair), system.precision)
    q, a_i, a_j = law_map.q, law_map.a_i, law_map.a_j
    i, j = pair.i, pair.j
    vi_index = system.n_bodies + i
    vj_index = system.n_bodies + j
    eps = system.precision.epsilon
    tiny = SEPARATION_ULPS * eps
    k = float(scene.law.restitution)
    records = log.records
    append = records.append
    limit = log.max_collisions
    stop = log.stop
    law_name = system.law_name
    extended = law_map.extended
    strict = scene.on_inconsistent == "error"
    a_i_stiff = float(scene.track.angular_stiffness(scene.bodies[i], scene.g))
    a_j_stiff = float(scene.track.angular_stiffness(scene.bodies[j], scene.g))
    sin = math.sin
    # below_resolution can only hold if v^2 <= 2 A h_res or v <= A (1 - k) t_res / 2, A <= a_i + a_j.
    h_bound = 2 * (a_i_stiff + a_j_stiff) * RESOLUTION_ULPS * eps
    t_bound = (a_i_stiff + a_j_stiff) * (1 - k) * RESOLUTION_ULPS * eps / 2

    def resolve(s, before, t) -> bool:
        """Apply the law (or the policy) to this pair, record it; False: stop the run."""
        vi = before[vi_index]
        vj = before[vj_index]
        if extended:
            ei, ej = EXTENDED(vi), EXTENDED(vj)
            d = ei - q * ej
            vi_new = float(ei - a_i * d)
            vj_new = float(ej + a_j * d)
        else:
            d = vi - q * vj
            vi_new = vi - a_i * d
            vj_new = vj + a_j * d
        flag = 0
        # The gap opens at rate vj_new - vi_new; it closed at vi - vj.
        closing = vi - vj
        if vj_new - vi_new < -tiny * closing:
            if strict:
                append((t, pair_index, before, vi_new, vj_new, 0))
                s[vi_index], s[vj_index] = vi_new, vj_new
                stop.reason = "inconsistent"
                stop.message = (
                    f"collision {log.count} at t = {float(t):.17g}: bodies {i + 1} and {j + 1} still "
                    f"approach after the '{law_name}' law (gap rate {float(closing):.3g} -> "
                    f"{float(vi_new - vj_new):.3g} rad/s closing): the outcome would make them overlap; "
                    "stopped (collision.on_inconsistent = 'error')"
                )
                return False
            vi_new, vj_new = _apply(fallback, vi, vj)
            flag = 1
            log.fallbacks += 1
        append((t, pair_index, before, vi_new, vj_new, flag))
        s[vi_index] = vi_new
        s[vj_index] = vj_new
        return True

    def on_collision(ta, d_sgn):
        s = holder[0]
        before = s.tolist()  # Python numbers: faster arithmetic than numpy scalars
        t = ta.time
        if not resolve(s, before, t):
            return False
        if cascade is not None and not cascade(s, t, (i, j)):
            return False
        # Persistent contact? Only a slow separation can qualify: test that
        # first with |gap''| <= a_i + a_j, then judge with the actual gap''.
        opening = s[vj_index] - s[vi_index] if cascade is not None else records[-1][4] - records[-1][3]
        phi_i, phi_j = before[i], before[j]
        if opening * opening <= h_bound * (1 + abs(phi_i) + abs(phi_j)) or opening <= t_bound * (abs(t) + time_scale):
            gap_acc = a_i_stiff * sin(phi_i) - a_j_stiff * sin(phi_j)
            if below_resolution(opening, gap_acc, k, float(t), 1 + abs(phi_i) + abs(phi_j), time_scale, eps):
                stop.reason, stop.data = "merge", {"contact": number}
                return False
        if limit is not None and log.flushed + len(records) >= limit:
            stop.reason = "max_collisions"
            stop.message = f"stopped after max_collisions = {limit} collisions"
            return False
        if len(records) >= log.chunk_size:
            log.on_full()
        return True

    on_collision.resolve = resolve
    return on_collision


def simultaneous_contacts(system: SceneSystem, callbacks: list):
    """Sequential impulses for contacts that close at the same instant (three or more bodies).

    After a collision, any other pair of the two bodies' neighbours that
    touches (gap within a few ulp) and still closes is resolved at the same
    instant by its own law, and so on until no touching pair closes: the
    classic sequential-impulse treatment of simultaneous impacts (momentum is
    kept, and energy at k = 1; for unequal bodies the outcome can depend on
    the order, a known property of simultaneous impacts). Collisions resolved
    here are ordinary rows of the table, at the same t.
    """
    nb = system.n_bodies
    eps = system.precision.epsilon
    by_body: dict[int, list[int]] = {}
    geometry = []
    for number, c in enumerate(system.contacts):
        by_body.setdefault(c.pair.i, []).append(number)
        by_body.setdefault(c.pair.j, []).append(number)
        with workprec():
            geometry.append((c.pair.i, c.pair.j, float(c.pair.offset - c.pair.beta)))

    def cascade(s, t, bodies) -> bool:
        pending = list(bodies)
        rounds = 0
        while pending and rounds < 64 * nb:
            body = pending.pop()
            for number in by_body.get(body, ()):
                i, j, constant = geometry[number]
                gap = s[j] - s[i] + constant
                closing = s[nb + i] - s[nb + j]
                if abs(gap) <= RESOLUTION_ULPS * eps * (1 + abs(s[i]) + abs(s[j])) and closing > 0:
                    rounds += 1
                    if not callbacks[number].resolve(s, s.tolist(), t):
                        return False
                    pending += [i, j]
        return True

    return cascade


def _make_unit_callback(scene, system: SceneSystem, number: int, log: CollisionLog, holder: list, time_scale: float):
    """Collisions when some bodies move as clusters: the state holds unit coordinates.

    Two free bodies collide by the scene's law (and policy); a collision that
    involves a cluster is Newton's law on psi' with the units' total
    generalized masses (the cluster moves as one rigid unit through the
    impact), recorded with flag 2.
    """
    contact = system.contacts[number]
    pair = contact.pair
    a, b = contact.unit_a, contact.unit_b
    nu = system.n_units
    both_free = not system.units[a].is_cluster and not system.units[b].is_cluster
    law = working_map(pair.law_map if both_free else unit_map(system, a, b, scene.law.restitution), system.precision)
    fallback = working_map(fallback_map(scene, pair), system.precision)
    eps = system.precision.epsilon
    k = float(scene.law.restitution)
    strict = scene.on_inconsistent == "error"
    stop = log.stop

    def on_collision(ta, d_sgn):
        s = holder[0]
        state = s.tolist()
        before = system.expand(state)
        va, vb = state[nu + a], state[nu + b]
        va_new, vb_new = _apply(law, va, vb)
        flag = 0 if both_free else 2
        if vb_new - va_new < -SEPARATION_ULPS * eps * (va - vb):
            if strict:
                stop.reason = "inconsistent"
                stop.message = (
                    f"collision {log.count + 1} at t = {float(ta.time):.17g}: bodies {pair.i + 1} and {pair.j + 1} "
                    f"still approach after the '{system.law_name}' law; stopped (collision.on_inconsistent = 'error')"
                )
                return False
            va_new, vb_new = _apply(fallback, va, vb)
            flag = 1
            log.fallbacks += 1
        s[nu + a], s[nu + b] = va_new, vb_new
        after = system.expand(s.tolist())
        log.records.append((ta.time, contact.pair_index, before, None, after, flag))
        psi_a, psi_b = state[a], state[b]
        gap_acc = unit_acceleration(system, b, psi_b) - unit_acceleration(system, a, psi_a)
        if gap_acc < 0 and below_resolution(
            vb_new - va_new, gap_acc, k, float(ta.time), 1 + abs(psi_a) + abs(psi_b), time_scale, eps
        ):
            stop.reason, stop.data = "merge", {"contact": number}
            return False
        if log.max_collisions is not None and log.count >= log.max_collisions:
            stop.reason = "max_collisions"
            stop.message = f"stopped after max_collisions = {log.max_collisions} collisions"
            return False
        if len(log.records) >= log.chunk_size:
            log.on_full()
        return True

    return on_collision
