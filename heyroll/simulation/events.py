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

Pairs left touching at the same instant (by the collision's neighbours, at
the start of a mode, after a split) are settled by :func:`contact_settler`:
collided, put in contact, or opened by a few ulps so that heyoka can see
them close again (see there). A last guard event per pair stops the run
with status ``overlap`` if a gap ever goes below -overlap_tolerance anyway.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Callable

import heyoka as hy
import mpmath
import numpy as np

from ..model.laws import GeneralizedNewtonLaw, ImpulseMap, impulse_map
from ..model._numbers import DEKKER_SPLIT, TOUCHING_SLACK, halves, workprec
from .resolve.complementarity import complementarity, relative_tolerance
from .resolve.friction import slipping, slipping_law, slipping_members
from .compiled_cache import by_constants
from .system import SceneSystem, overlap_tolerance, unit_acceleration, unit_jerk

#: A post-collision separation rate within this many ulps of zero (relative to
#: the approach rate) counts as no separation (a plastic outcome).
SEPARATION_ULPS = 64

#: Resolution of a run, in ulps: bounces whose height or remaining duration
#: fall below it cannot be told apart from rest in contact; a gap within it
#: of zero is touching.
RESOLUTION_ULPS = 64

#: The height, in ulps (of 1 + |psi_a| + |psi_b|), below which a bounce is rest in contact. heyoka
#: locates the end of a bounce h ulps high on a gap that is rounded to ~1 ulp with a slope of only
#: sqrt(2 A h): at ~100 ulps its bracketed root finding ran out of iterations ("polynomial root finding
#: during event detection failed"), skipped the event, and the bodies passed through each other
#: (acceptance test: a Zeno tail at k = 0.967 with Newton's fallback, bounces of 107 ulps, status
#: overlap 9 s later). Cutting the tail at 1024 ulps errs by at most that height on the pair's relative
#: position, ~2e-13 rad, and by the few microseconds left of the accumulation on when it rests.
BOUNCE_ULPS = 1024

#: A touching pair that is not closing starts the next step with its gap more
#: than this many ulps (of 1 + |psi_a| + |psi_b|) open (see contact_settler).
OPEN_ULPS = 8

#: heyoka's root leaves a gap an ulp either side of zero. Below zero, the opening brings it back
#: up through zero: at once, unless the opening is slow; a gap that would take longer than this
#: (s) is lifted to zero at the collision (settler.lift_gap), since over long times the reopening
#: check's bound is loose (two particles left at rest on top of each other came back through
#: zero 0.5 s later: flagged as a missed collision). Lifting every such gap cost accuracy
#: (collision times 1.5e-15 off the reference where 1e-15 is the bound): only slow ones.
SLOW_REOPENING = 1e-7


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
    #: Junction passages and limiter impacts: (t, body, kind, piece from, piece to, q, q' before, q' after),
    #: kind an index into resolve.bounds.PASSAGE_KINDS (0-based bodies and pieces).
    passages: list = field(default_factory=list)
    #: The bound on every kind of event together (RunOptions.max_events), and the mode changes so far.
    max_events: int | None = None
    mode_changes: int = 0
    #: Passages handed on to a sink (``on_passages_full`` takes a full chunk), and the limiter
    #: impacts among all passages so far.
    passages_flushed: int = 0
    limiter_impacts: int = 0
    on_passages_full: object = None
    #: Changes of friction mode so far (rough tracks; the rows are in the run's FrictionState),
    #: and the stroboscopic section's samples: (t, full state) once a forcing period.
    friction_transitions: int = 0
    strobe: list = field(default_factory=list)
    #: Rough tracks: per record, the friction modes of its bodies i, j before and after, and the speed
    #: each body's spin would roll at where it slips (nan where it rolls) (else None).
    record_modes: list | None = None
    #: The mode handlers built on this log, kept for its next runs (simulation.driver._handlers)
    handler_sets: object = None
    #: The circle's whole turns taken out of the run's angles (simulation.turns.Turns; None elsewhere)
    turns: object = None

    def turn_offset(self):
        """The whole turns taken out of the angles now: what a message adds to a state's angle."""
        return 0 if self.turns is None else self.turns.offset

    def record_passage(self, row: tuple) -> bool:
        """Keep a passage (see ``passages``); False: max_events is reached, the run stops."""
        self.passages.append(row)
        if row[2] != 0:
            self.limiter_impacts += 1
        if self.on_passages_full is not None and len(self.passages) >= self.chunk_size:
            self.on_passages_full()
        return not self.events_exhausted()

    @property
    def n_passages(self) -> int:
        return self.passages_flushed + len(self.passages)

    def events_exhausted(self) -> bool:
        """Whether collisions, passages and mode changes together reached max_events (sets the stop)."""
        if self.max_events is None or (self.count + self.n_passages + self.mode_changes + self.friction_transitions
                                       + len(self.strobe)) < self.max_events:
            return False
        self.stop.reason = "max_events"
        self.stop.message = (f"stopped after max_events = {self.max_events} events ({self.count} collisions, "
                             f"{self.n_passages} junction passages and limiter impacts, {self.mode_changes} "
                             f"contact mode changes, {self.friction_transitions} friction mode changes, "
                             f"{len(self.strobe)} stroboscopic samples); raise it with --max-events N (RunOptions.max_events)")
        return True

    @property
    def count(self) -> int:
        return self.flushed + len(self.records)

    def reset(self, max_collisions: int | None, max_events: int | None, record_modes: list | None) -> "CollisionLog":
        """This log made new for another run, in place: the handlers built on it (and cached with it,
        driver._handlers) hold its lists and its stop request, not copies."""
        self.records.clear()
        self.max_collisions, self.max_events, self.record_modes = max_collisions, max_events, record_modes
        self.stop.reason, self.stop.message, self.stop.data = None, "", {}
        self.flushed = self.fallbacks = self.mode_changes = self.passages_flushed = 0
        self.limiter_impacts = self.friction_transitions = 0
        self.chunk_size = 1 << 62
        self.on_full = self.on_passages_full = None
        self.warnings.clear()
        self.passages.clear()
        self.strobe.clear()
        self.turns = None
        return self


def mode_handlers(
    scene, system: SceneSystem, log: CollisionLog, holder: list, time_scale: float, pieces=None, friction=None
) -> tuple[list, list, object]:
    """The callbacks of one contact mode, in the order of :func:`mode_events`.

    Returns (terminal handlers, non-terminal handlers, settle), ``settle``
    the mode's :func:`contact_settler` (the driver calls it at the start of
    the mode). ``holder[0]`` must be set to the integrator's state array and
    ``holder[1]`` to its parameters (views into heyoka's buffers) before
    integrating; the handlers use them to avoid re-wrapping the buffers at
    every collision. ``pieces`` (open tracks): the piece each body is on.
    ``friction`` (rough tracks): the run's resolve.friction.FrictionState; the mode's
    FrictionModes is then ``settle.friction``.
    """
    if not system.linear_gap:
        return _with_friction(scene, system, log, holder, friction, time_scale,
                              *_local_handlers(scene, system, log, holder, time_scale, pieces))
    fast = not any(u.is_cluster for u in system.units)
    handlers: list = []
    resolvers: list = []
    settle = contact_settler(scene, system, resolvers, log, time_scale, holder)
    # Three or more units: contacts can close at the same instant.
    cascade = settle if system.n_units > 2 else None
    # The (double-length) time of each contact's last collision, or of the mode's start (the
    # driver sets it): where its gap was last known at zero or above (reopening_check).
    touched = settle.touched = [(0.0, 0.0)] * len(system.contacts)
    # collision.simultaneous = "impulses": contacts touching at the fired one's instant resolved at once
    group = simultaneous_resolver(scene, system, log) if scene.simultaneous == "impulses" and system.n_units > 2 \
        else None
    for number in range(len(system.contacts)):
        if fast:
            handler = _make_callback(scene, system, number, log, holder, time_scale, cascade, touched, settle, group)
            resolvers.append(lambda s, t, resolve=handler.resolve: resolve(s, s.tolist(), t))
        else:
            handler = _make_unit_callback(scene, system, number, log, holder, time_scale, settle, touched, group)
            resolvers.append(handler.resolve)
        handlers.append(handler)
    return _with_friction(scene, system, log, holder, friction, time_scale,
                          *_other_handlers(scene, system, log, holder, time_scale, pieces, handlers, settle))


def _with_friction(scene, system, log, holder, friction, time_scale, handlers, warnings, settle):
    """Friction events' handlers after the others (mode_events' order); impacts (collisions,
    limiters) wrapped so that each unit's friction mode follows its new rate; the
    stroboscopic samples of a forced run."""
    if system.strobe_expression is not None:
        warnings = warnings + [_strobe_recorder(log, system)]
    if not system.friction_blocks:
        return handlers, warnings, settle
    from .resolve.friction import FrictionModes

    modes = FrictionModes(scene, system, friction, holder, log, time_scale)
    n_impacts = len(system.contacts) + len(system.link_expressions) + len(system.bound_expressions)

    records, body_modes = log.records, friction.modes
    pair_bodies = [(p.i, p.j) for p in scene.pairs]

    def wrapped(handler):
        def on_impact(ta, d_sgn):
            s = holder[0]
            before = s.tolist()
            was = list(body_modes)
            first = len(records)
            modes.begin(before)
            modes.impact_state = before
            # Records are handed on (log.on_full) only once the modes after the impact are known.
            size, log.chunk_size = log.chunk_size, 1 << 62
            try:
                go_on = handler(ta, d_sgn)
            finally:
                log.chunk_size = size
            fill_record_modes(log, body_modes, pair_bodies, first)  # any earlier ones: the modes they had
            spins = modes.spins(before, ta.time, was)  # (before the modes' sync: its state then)
            modes.reconcile(ta, s, ta.time)  # (modes synced inside the handler reach the integrator)
            fill_record_modes(log, body_modes, pair_bodies, was=was, spins=spins)
            if len(records) >= size and log.on_full is not None and log.stop.reason != "merge":
                log.on_full()
            return go_on

        return on_impact

    handlers = [wrapped(h) if n < n_impacts else h for n, h in enumerate(handlers)]
    handlers += [modes.handler(ev) for ev in system.friction_events]
    settle.friction = modes
    holder[2] = modes  # GapMotion brings the modes up to the rates before judging a contact
    return handlers, warnings, settle


def fill_record_modes(log, body_modes, pair_bodies, upto=None, was=None, spins=None) -> None:
    """Give the records that have no friction modes yet, up to record ``upto``, the bodies' modes:
    ``was`` before (default: the present ones) and the present ones after; ``spins[k]``: the speed body
    k's spin rolls at where it slipped before (FrictionModes.spins; nan: rolling), every body's: a table's
    energies count the slip of a body sliding elsewhere too (it left them out, 1.2 %: acceptance test)."""
    records, record_modes = log.records, log.record_modes
    was = body_modes if was is None else was
    u = tuple(spins) if spins is not None else (math.nan,) * len(body_modes)
    for record in records[len(record_modes): len(records) if upto is None else upto]:
        i, j = pair_bodies[record[1]]
        record_modes.append((was[i], was[j], body_modes[i], body_modes[j]) + u)


def _strobe_recorder(log, system):
    """Once a forcing period (nu t + psi = 2 pi n): the full state, the stroboscopic section."""

    def record(ta, t, d_sgn):
        log.strobe.append((t, system.expand(ta.update_d_output(t).tolist())))  # (the run's own type)

    return record


def _other_handlers(scene, system, log, holder, time_scale, pieces, handlers, settle):
    """Everything after the collisions, in the order of :func:`mode_events`."""
    handlers += [_stopper(log, "split", {"link": number}) for number in range(len(system.links))]
    if system.bound_events:
        from .contact_function import body_function
        from .resolve.bounds import make_bound_callback

        function = body_function(system)
        handlers += [make_bound_callback(scene, system, ev, log, holder, pieces, time_scale, function, settle)
                     for ev in system.bound_events]
    handlers += [_stopper(log, "release", {"bodies": (k,)}) for k in system.release_events]
    handlers += [_track_stopper(log, ev, holder, system) for ev in system.track_events if ev.terminal]
    handlers += [_overlap_stopper(log, number, holder, system) for number in range(len(system.guard_expressions))]
    warnings = [_track_warning(log, ev, system) for ev in system.track_events if not ev.terminal]
    return handlers, warnings, settle


def _local_handlers(scene, system, log, holder, time_scale, pieces):
    """Collisions where the gap is not linear (arc chains, curves): resolve.local_map."""
    from .contact_function import contact_function
    from .resolve.local_map import local_settler, make_local_callback

    function = contact_function(system)
    resolvers: list = []
    settle = local_settler(scene, system, resolvers, log, holder, time_scale, function)
    cascade = settle if system.n_units > 2 else None
    handlers = []
    for number in range(len(system.contacts)):
        handler = make_local_callback(scene, system, number, log, holder, time_scale, function, cascade)
        resolvers.append(handler.resolve)
        handlers.append(handler)
    return _other_handlers(scene, system, log, holder, time_scale, pieces, handlers, settle)


def close_collision(log: CollisionLog, number: int, pressed: bool) -> bool:
    """The end of every collision callback: a pair left pressed below the run's
    resolution enters persistent contact (the run stops for a mode change,
    ``stop.reason = "merge"``); otherwise full chunks of records are handed on."""
    if pressed:
        log.stop.reason, log.stop.data = "merge", {"contact": number}
        return False
    if len(log.records) >= log.chunk_size:
        log.on_full()
    return True


def stop_at_max_collisions(stop: StopRequest, limit: int) -> bool:
    """Ask the driver to stop after the limit-th collision; False stops heyoka."""
    stop.reason = "max_collisions"
    stop.message = f"stopped after max_collisions = {limit} collisions"
    return False


def mode_events(system: SceneSystem, cooldown, slots: list, nt_slots: list) -> tuple[list, list]:
    """heyoka events of one contact mode whose callbacks call ``slots[n]`` / ``nt_slots[n]``.

    The indirection lets one compiled integrator serve many runs of the same
    shape: each run puts its own handlers (:func:`mode_handlers`) in the slots.
    Collisions (gap closing), contact splits (contact force reaching 0,
    decreasing), track limits and overlap guards (gap reaching
    -overlap_tolerance: a missed collision) are terminal; track warnings are
    not.
    """
    options = system.precision.integrator_options()
    negative = hy.event_direction.negative

    def forward(n):
        return lambda ta, d_sgn: slots[n](ta, d_sgn)

    def forward_nt(n):
        return lambda ta, t, d_sgn: nt_slots[n](ta, t, d_sgn)

    # Without guards (SceneSystem.gap_reopening) the gap events fire both ways: closing is a
    # collision, coming back up through zero a check (reopening_check). Both ways cost nothing more.
    gap_direction = hy.event_direction.any if system.gap_reopening else negative
    events = [
        # heyoka's default cooldown (scaled by 1/|gap'|) hides the quick
        # re-collisions of an accumulating (Zeno) sequence; one ulp of the
        # motion's time scale is far below any interval the contact criterion
        # lets through, and direction filtering does the rest. (A cooldown of
        # exactly 0 loses collisions: measured.)
        hy.t_event(gap, callback=forward(n), direction=gap_direction, cooldown=cooldown, **options)
        for n, gap in enumerate(system.gap_expressions)
    ]
    n_gaps = len(system.gap_expressions)
    events += [
        hy.t_event(x, callback=forward(n_gaps + n), direction=negative, **options)
        for n, x in enumerate(system.link_expressions)
    ]
    # Piece ends: the body keeps going (a junction) or rebounds (a limiter) inside the callback;
    # the cooldown as for collisions (impacts on a stop can accumulate too).
    n_before = n_gaps + len(system.link_expressions)
    events += [
        hy.t_event(x, callback=forward(n_before + n), direction=negative, cooldown=cooldown, **options)
        for n, x in enumerate(system.bound_expressions)
    ]
    # A unit resting on a limiter is released where the track's forces pull a member away.
    expressions = list(system.release_expressions)
    expressions += [x for x, ev in zip(system.track_expressions, system.track_events) if ev.terminal]
    expressions += list(system.guard_expressions)
    n_before += len(system.bound_expressions)
    events += [
        hy.t_event(x, callback=forward(n_before + n), direction=negative, **options)
        for n, x in enumerate(expressions)
    ]
    # Friction modes (rough tracks): turning points, sticking, slipping and rolling again. The
    # gated expressions are a constant 1 outside their mode; the cooldown as for collisions.
    n_before += len(expressions)
    events += [
        hy.t_event(x, callback=forward(n_before + n), direction=_friction_direction(ev.kind), cooldown=cooldown,
                   **options)
        for n, (x, ev) in enumerate(zip(system.friction_expressions, system.friction_events))
    ]
    nt_expressions = [x for x, ev in zip(system.track_expressions, system.track_events) if not ev.terminal]
    nt_events = [hy.nt_event(x, forward_nt(n), direction=negative, **options) for n, x in enumerate(nt_expressions)]
    if system.strobe_expression is not None:
        nt_events.append(hy.nt_event(system.strobe_expression, forward_nt(len(nt_events)),
                                     direction=hy.event_direction.any, **options))
    return events, nt_events


def _friction_direction(kind: str):
    """Turning points, slips returning to 0 and the normal force changing sign: both ways;
    a load reaching the static capacity: the margin falling through 0."""
    if kind in ("turn", "reroll", "normal"):
        return hy.event_direction.any
    return hy.event_direction.negative


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
                f"{system.coordinate} = {float(full[body] + log.turn_offset()):.6g}: the two-sided track holds it "
                "(on a one-sided one it would leave here)"
            )

    return record


def _stopper(log, reason, data):
    def stop(ta, d_sgn):
        log.stop.reason, log.stop.data = reason, data
        return False

    return stop


def _track_stopper(log, event, holder, system):
    what = {
        "left_track": "would leave the track: its normal force N reaches 0",
    }[event.kind]

    def stop(ta, d_sgn):
        full = system.expand(holder[0].tolist())
        c = system.coordinate
        log.stop.reason = event.kind
        log.stop.message = (
            f"body {event.body + 1} {what}, at {c} = {float(full[event.body] + log.turn_offset()):.17g}, "
            f"d{c} = {float(full[system.n_bodies + event.body]):.17g}, t = {float(ta.time):.17g} s"
        )
        return False

    return stop


def _overlap_stopper(log, number, holder, system):
    contact = system.contacts[number]

    def stop(ta, d_sgn):
        full = system.expand(holder[0].tolist())
        i, j = contact.pair.i, contact.pair.j
        log.stop.reason = "overlap"
        # The circle's gap is an angle; elsewhere a distance (the guard's bound, see system.py).
        unit = "rad" if system.linear_gap else "m"
        log.stop.message = (
            f"bodies {i + 1} and {j + 1} overlap at t = {float(ta.time):.17g} s (gap below "
            f"about -{overlap_tolerance(full[j]):.3g} {unit}): a collision was missed; stopped"
        )
        return False

    return stop


class GapMotion:
    """The acceleration and jerk of the gap between two units on the circle, for the contact judgments.

    In a fixed plane without friction or forcing, the closed forms of unit_acceleration and
    unit_jerk (the rolling pendulum); otherwise the compiled psi'' and its derivative for every
    unit (SceneSystem.unit_motion) at the state, the mode's parameters and the time (measured:
    with friction the closed forms judged a pressed pair opening, and its collision went unseen).
    """

    def __init__(self, system: SceneSystem, holder: list):
        from .contact_function import motion_function

        self.system, self.holder = system, holder
        self.function = motion_function(system)

    def __call__(self, s, a: int, b: int, t=0.0, va=None, vb=None) -> tuple[float, float]:
        system = self.system
        nu = system.n_units
        if self.function is None:
            psi_a, psi_b = float(s[a]), float(s[b])
            va = float(s[nu + a]) if va is None else va
            vb = float(s[nu + b]) if vb is None else vb
            return (unit_acceleration(system, b, psi_b) - unit_acceleration(system, a, psi_a),
                    unit_jerk(system, b, psi_b, vb) - unit_jerk(system, a, psi_a, va))
        from .contact_function import evaluate

        modes = self.holder[2] if len(self.holder) > 2 else None
        if modes is not None:  # a collision has just changed rates: the friction modes first
            modes.sync(s, t)
        values = evaluate(self.function, s, self.holder[1], t)
        return float(values[2 * b] - values[2 * a]), float(values[2 * b + 1] - values[2 * a + 1])


def reopening_check(system: SceneSystem, number: int, log: CollisionLog, holder: list, touched: list, settle):
    """``check(ta) -> bool`` for the gap of contact ``number`` coming back up through zero
    (circle, fixed plane: :attr:`SceneSystem.gap_reopening`).

    A gap rises through zero only from below. Right after the pair's own
    collision that is rounding: heyoka's root leaves the gap a few ulps either
    side of zero. Otherwise the bodies had overlapped, a collision was missed.
    Since the pair's last collision or the mode's start (``touched[number]``,
    heyoka's double-length time: a long run's time has ulps of ~1e-11 s) the gap can have been at
    most |g'| dt + |g''| dt^2 / 2 + J dt^3 / 6 below zero (Taylor's formula
    backwards from now; J = sum over the two units of A (|psi'| + A dt) bounds
    the third derivative, A = the unit's bound on |psi''|,
    :meth:`SceneSystem.acceleration_bound`; |g''| from the state, as with
    the bound A in its place a plastic pair near the bottom whose gap had
    dipped ~1e-13 rad was flagged: found by tests/test_fuzz.py). Within overlap_tolerance that is
    rounding, or a dip the guard events this replaces let pass too (they
    fired at -overlap_tolerance), and the gap is lifted to >= 0 by an ulp or two (``settle.lift_gap``): left
    there, with a slow opening (the end of a Zeno sequence) the rounded gap
    stays an ulp below zero and the event, truncating every step at its root,
    fired again every ~1e-13 s (measured: 36,000 times in 4e-9 s).
    Beyond it the run stops, status overlap. (True: go on.)
    """
    contact = system.contacts[number]
    a, b, nu = contact.unit_a, contact.unit_b, system.n_units
    bound_a, bound_b = system.acceleration_bound(a), system.acceleration_bound(b)

    def check(ta) -> bool:
        s = holder[0]
        hi, lo = ta.dtime
        t_hi, t_lo = touched[number]
        dt = float((hi - t_hi) + (lo - t_lo))
        psi_a, psi_b, va, vb = float(s[a]), float(s[b]), float(s[nu + a]), float(s[nu + b])
        acceleration = unit_acceleration(system, b, psi_b) - unit_acceleration(system, a, psi_a)
        jerk = bound_a * (abs(va) + bound_a * dt) + bound_b * (abs(vb) + bound_b * dt)
        depth = abs(vb - va) * dt + abs(acceleration) * dt * dt / 2 + jerk * dt * dt * dt / 6
        if depth <= overlap_tolerance(psi_b):
            settle.lift_gap(s, number)
            return True
        i, j = contact.pair.i, contact.pair.j
        log.stop.reason = "overlap"
        log.stop.message = (
            f"bodies {i + 1} and {j + 1} overlapped: their gap came back up through zero at t = {float(hi):.17g} s, "
            f"{dt:.3g} s after their last collision or the start of the mode: a collision was missed; stopped"
        )
        return False

    return check


def below_resolution(opening, gap_acceleration, restitution, t, scale, time_scale, eps, gap_jerk=0.0) -> bool:
    """Whether the bounces left after a collision are below the run's resolution.

    Bodies pressed together (gap acceleration -A < 0) that separate at rate v
    fly apart for 2v/A and rise h = v^2/(2A); with restitution k every next
    bounce is k times slower, so the whole remaining sequence lasts
    T = 2v/(A (1 - k)) (the sum of the geometric series; Zeno's accumulation
    point). When T is below the time resolution of the run or h below the
    resolution of the gap, no further bounce can be resolved and the pair is
    taken to be in persistent contact from now on.

    The bounce is that of the gap's Taylor polynomial to third order,
    g(t) = v t + a t^2/2 + J t^3/6 (a = gap acceleration, J = its jerk): with
    J = 0 the figures above. The jerk matters where a ~ 0: a pair that moves
    on together through the point where its gap acceleration changes sign
    (a plastic collision at the bottom of two pendulums of different
    stiffness) rises by a^3/(3 J^2) and closes again after 3a/|J|: a contact
    if that is below resolution. (At a contact split J > 0: it opens.)
    """
    v = max(opening, 0.0)
    a, J = gap_acceleration, gap_jerk
    duration = _first_return(v, a, J)  # the bounce's: g(duration) = 0
    if duration is None:
        return False
    if J > 0:
        # The gap opens for good after the last root of g(t)/t. Where a ~ 0 (all
        # units near the bottom, where every gap acceleration vanishes) the sign
        # of a is the rounding of the positions (a pair opened by OPEN_ULPS, a
        # collision root ~1e-20 rad off): "pressed" for 3|a|/J, by ~|a|^3/J^2,
        # then opening as J t^3/6. A dip that shallow or short is no contact:
        # merging it made the link split at once and the settler merge it
        # again, for ever at one instant (measured: a solid sphere and two
        # particles, k = 0, colliding at phi = 0).
        last = _positive_roots(J / 6, a / 2, v)[-1:]
        if last:
            g = lambda s: v * s + a * s * s / 2 + J * s * s * s / 6  # noqa: E731
            depth = -min([0.0] + [g(s) for s in _positive_roots(J / 2, a, v) if s < last[0]])
            if depth <= RESOLUTION_ULPS * eps * scale or last[0] <= RESOLUTION_ULPS * eps * (abs(t) + time_scale):
                return False
    height = _bounce_height(v, a, J, duration)
    remaining = duration / (1 - restitution) if restitution < 1 else math.inf
    return height <= BOUNCE_ULPS * eps * scale or remaining <= RESOLUTION_ULPS * eps * (abs(t) + time_scale)


def _first_return(v, a, J):
    """Smallest t >= 0 with v + a t/2 + J t^2/6 = 0 (g(t)/t, g as in below_resolution), or None."""
    if v == 0 and (a < 0 or (a == 0 and J < 0)):
        return 0.0  # closing from the start: pressed
    roots = _positive_roots(J / 6, a / 2, v)
    return roots[0] if roots else None


def _bounce_height(v, a, J, duration) -> float:
    """max of g(t) = v t + a t^2/2 + J t^3/6 over [0, duration]."""
    g = lambda t: v * t + a * t * t / 2 + J * t * t * t / 6  # noqa: E731
    peaks = [t for t in _positive_roots(J / 2, a, v) if t < duration]  # g'(t) = 0
    return max([0.0, g(duration)] + [g(t) for t in peaks])


def _positive_roots(c2, c1, c0) -> list:
    """Positive real roots of c2 t^2 + c1 t + c0, ascending (stable formula)."""
    if c2 == 0:
        return [-c0 / c1] if c1 != 0 and -c0 / c1 > 0 else []
    disc = c1 * c1 - 4 * c2 * c0
    if disc < 0:
        return []
    q = -(c1 + math.copysign(math.sqrt(disc), c1)) / 2
    roots = [q / c2] + ([c0 / q] if q != 0 else [])
    return sorted(r for r in roots if r > 0)


@by_constants()
def fallback_map(scene, pair) -> ImpulseMap:
    """Newton's law on the gap rate with generalized masses, for one pair."""
    law = GeneralizedNewtonLaw(restitution=scene.law.restitution)
    return impulse_map(law, scene.bodies[pair.i], scene.bodies[pair.j], scene.sigma(pair.i), scene.sigma(pair.j))


def unit_map(system: SceneSystem, a: int, b: int, restitution, slipping: tuple = ()) -> ImpulseMap:
    """Newton's law on psi' between two units with their total generalized masses.

    ``slipping``: (body, kappa) of rolling bodies that slip (rough tracks): such a body takes part
    with its translational mass m rho^2 = G / kappa (resolve.friction.slipping_law).
    """
    slip = dict(slipping)
    with workprec():
        Ma = mpmath.fsum(mpmath.mpf(system.gen_mass[k]) / slip.get(k, 1) for k in system.units[a].members)
        Mb = mpmath.fsum(mpmath.mpf(system.gen_mass[k]) / slip.get(k, 1) for k in system.units[b].members)
        k = mpmath.mpf(restitution)
        return ImpulseMap(q=mpmath.mpf(1), a_i=(1 + k) * Mb / (Ma + Mb), a_j=(1 + k) * Ma / (Ma + Mb), one_plus_k=1 + k)


@dataclass(frozen=True)
class WorkingMap:
    """The collision map of one pair in the arithmetic a run applies it in.

    D = phi_i' - q phi_j';  phi_i'+ = phi_i' - a_i D;  phi_j'+ = phi_j' + a_j D,
    with a_i = (1 + k) - q a_j enforced on the rounded constants, which makes
    the elastic map conserve a fixed quadratic form (within a rounding of the
    kinetic energy) exactly: no constant's rounding biases every collision the
    same way. Double runs evaluate the map in double-double arithmetic
    (:func:`_double_double_map`) and round the two outgoing rates once, so the
    energy error of a long elastic run is a random walk (Brouwer's law), not a
    drift; other precisions in the run's own type. ``apply(vi, vj)`` gives
    the two outgoing rates.
    """

    q: object
    a_i: object
    a_j: object
    apply: Callable = field(compare=False, repr=False)


@by_constants()
def pair_maps(scene, precision) -> tuple:
    """Per scene pair: (the law's working map, the fallback's), for ``precision``. Keyed by the scene
    (its hash is computed once) rather than by each pair's maps, whose mpf constants hashed on every
    run cost ~10 us of a run's set-up (measured)."""
    return tuple((working_map(pair.law_map, precision) if pair.law_map is not None else None,
                  working_map(fallback_map(scene, pair), precision)) for pair in scene.pairs)


@functools.lru_cache(maxsize=256)
def working_map(law_map, precision) -> WorkingMap:
    """Round the law's constants once for ``precision`` (see :class:`WorkingMap`)."""
    if precision.name == "double":
        with mpmath.workprec(256):
            q, a_j = _double_double(law_map.q), _double_double(law_map.a_j)
            a_i = _double_double(law_map.one_plus_k - (mpmath.mpf(q[0]) + q[1]) * (mpmath.mpf(a_j[0]) + a_j[1]))
        return WorkingMap(q=q, a_i=a_i, a_j=a_j, apply=_double_double_map(q, a_i, a_j))
    num = precision.number

    def exact(x):
        if hasattr(x, "as_integer_ratio"):  # longdouble: the binary value exactly
            n, d = x.as_integer_ratio()
            return mpmath.mpf(n) / d
        return mpmath.mpf(str(x))  # real128 / real: their text round-trips at their precision

    q, a_j = num(law_map.q), num(law_map.a_j)
    with mpmath.workprec(4 * max(precision.bits, 64) + 64):
        a_i = num(law_map.one_plus_k - exact(q) * exact(a_j))  # a_i + q a_j = 1 + k

    def apply(vi, vj):
        d = vi - q * vj
        return vi - a_i * d, vj + a_j * d

    if law_map.one_plus_k == 1:
        def apply_plastic(vi, vj):
            # k = 0: the outgoing gap rate vi - q vj is 0 exactly, not its rounding (a long run's plastic
            # collision left the pair closing at 1e-19 and met it again at once: a duplicate row, review)
            d = vi - q * vj
            vj_new = vj + a_j * d
            return q * vj_new, vj_new

        return WorkingMap(q=q, a_i=a_i, a_j=a_j, apply=apply_plastic)
    return WorkingMap(q=q, a_i=a_i, a_j=a_j, apply=apply)


def _double_double(x) -> tuple[float, float]:
    """x as hi + lo, two doubles (~106 bits)."""
    hi = float(x)
    return hi, float(mpmath.mpf(x) - hi)


def _double_double_map(q, a_i, a_j):
    """``apply(vi, vj)``: the map with double-double constants, each product exact
    (Dekker's two-product) and each sum with its error (Knuth's two-sum), rounded
    once at the end. Pure float arithmetic: numpy's long double scalars took 2.7 us
    a collision (measured), this ~1 us, with ~30 more bits."""
    qh, ql = q
    aih, ail = a_i
    ajh, ajl = a_j
    qh1, qh2 = halves(qh)
    aih1, aih2 = halves(aih)
    ajh1, ajh2 = halves(ajh)
    S = DEKKER_SPLIT

    def apply(vi, vj):
        c = S * vj
        vh = c - (c - vj)
        vl = vj - vh
        p = qh * vj  # p + e = q vj
        e = ((qh1 * vh - p) + qh1 * vl + qh2 * vh) + qh2 * vl + ql * vj
        s = vi - p  # dh + dl = vi - q vj
        z = s - vi
        t = ((vi - (s - z)) - (p + z)) - e
        dh = s + t
        dl = t - (dh - s)
        c = S * dh
        d1 = c - (c - dh)
        d2 = dh - d1
        p = aih * dh  # vi - a_i d
        e = ((aih1 * d1 - p) + aih1 * d2 + aih2 * d1) + aih2 * d2 + aih * dl + ail * dh
        s = vi - p
        z = s - vi
        vi_new = s + (((vi - (s - z)) - (p + z)) - e)
        p = ajh * dh  # vj + a_j d
        e = ((ajh1 * d1 - p) + ajh1 * d2 + ajh2 * d1) + ajh2 * d2 + ajh * dl + ajl * dh
        s = vj + p
        z = s - vj
        vj_new = s + (((vj - (s - z)) + (p - z)) + e)
        return vi_new, vj_new

    return apply


def _slipping_map(scene, system, i, j, holder) -> WorkingMap:
    """The working map of a collision where a rolling body slips (resolve.friction.slipping_law)."""
    law, bi, bj = slipping_law(scene, i, j, slipping(holder, i, scene), slipping(holder, j, scene))
    return working_map(impulse_map(law, bi, bj, scene.sigma(i), scene.sigma(j)), system.precision)


def _make_callback(scene, system: SceneSystem, number: int, log: CollisionLog, holder: list, time_scale: float,
                   cascade=None, touched=None, settle=None, group=None):
    """The hot path: every body free, the state is [phi_1..phi_N, dphi_1..dphi_N].

    Returns the event callback; its ``resolve(s, before, t)`` applies the law
    to the pair alone (also used by ``cascade``, the mode's contact settler,
    for contacts at the same instant).
    """
    contact = system.contacts[number]
    pair = contact.pair
    pair_index = contact.pair_index
    law_map, fallback = pair_maps(scene, system.precision)[pair_index]
    apply = law_map.apply
    rough = bool(system.friction_blocks)
    i, j = pair.i, pair.j
    vi_index = system.n_bodies + i
    vj_index = system.n_bodies + j
    eps = system.precision.epsilon
    tiny = SEPARATION_ULPS * eps
    k = float(scene.law.restitution)
    records = log.records
    append = records.append
    stop = log.stop
    law_name = system.law_name
    strict = scene.on_inconsistent == "error"
    # g / (kappa rho) = W / G, from the system's floats (no mpmath in a run's set-up)
    a_i_stiff = system.weight[i] / system.gen_mass[i]
    a_j_stiff = system.weight[j] / system.gen_mass[j]
    sin, cos = math.sin, math.cos
    # below_resolution can only hold if v^2 <= 2 A h_res or v <= A (1 - k) t_res / 2, A <= a_i + a_j.
    h_bound = 2 * (a_i_stiff + a_j_stiff) * BOUNCE_ULPS * eps
    t_bound = (a_i_stiff + a_j_stiff) * (1 - k) * RESOLUTION_ULPS * eps / 2
    reopened = reopening_check(system, number, log, holder, touched, settle) if system.gap_reopening else None
    gap_constant = system.gap_constants[number]
    motion = GapMotion(system, holder) if system.unit_motion else None

    def resolve(s, before, t) -> bool:
        """Apply the law (or the policy) to this pair, record it; False: stop the run.

        The run stops (status max_collisions) as soon as the limit-th
        collision is recorded, wherever it happens: in the event callback, in
        a cascade of contacts at the same instant, at the start of a mode,
        before a persistent contact it would start.
        """
        vi = before[vi_index]
        vj = before[vj_index]
        flag = 0
        if rough and (slipping(holder, i, scene) or slipping(holder, j, scene)):
            vi_new, vj_new = _slipping_map(scene, system, i, j, holder).apply(vi, vj)
            flag = 3
        else:
            vi_new, vj_new = apply(vi, vj)
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
            vi_new, vj_new = fallback.apply(vi, vj)
            flag = 1
            log.fallbacks += 1
        append((t, pair_index, before, vi_new, vj_new, flag))
        s[vi_index] = vi_new
        s[vj_index] = vj_new
        limit = log.max_collisions
        if limit is not None and log.flushed + len(records) >= limit:
            return stop_at_max_collisions(stop, limit)
        return True

    def on_any_collision(ta, d_sgn):
        if d_sgn >= 0:  # the gap rising through zero (events both ways: SceneSystem.gap_reopening)
            return d_sgn == 0 or reopened(ta)
        s = holder[0]
        before = s.tolist()  # Python numbers: faster arithmetic than numpy scalars
        t, t_lo = ta.dtime
        touched[number] = (t, t_lo)
        if group is None or (done := group(s, t, number)) is None:  # (group: simultaneous_resolver)
            if not resolve(s, before, t):
                return False
        elif not done:
            return False
        # This pair's event is in heyoka's cooldown: the settler leaves its gap alone.
        if cascade is not None and not cascade(s, t, (i, j), number):
            return False
        # Persistent contact? Only a slow separation can qualify: test that
        # first with |gap''| <= a_i + a_j, then judge with the actual gap''.
        vi_new, vj_new = (s[vi_index], s[vj_index]) if cascade is not None else (records[-1][3], records[-1][4])
        opening = vj_new - vi_new
        phi_i, phi_j = before[i], before[j]
        gap = (s[j] - s[i] if cascade is not None else phi_j - phi_i) + gap_constant
        if gap < 0 and opening * SLOW_REOPENING < -gap:
            settle.lift_gap(s, number)
        pressed = False
        if motion is not None:  # friction or forcing: the compiled accelerations (GapMotion)
            gap_acc, gap_jerk = motion(s, i, j, t, float(vi_new), float(vj_new))
            pressed = below_resolution(opening, gap_acc, k, float(t), 1 + abs(phi_i) + abs(phi_j), time_scale, eps,
                                       gap_jerk)
        elif opening * opening <= h_bound * (1 + abs(phi_i) + abs(phi_j)) or opening <= t_bound * (abs(t) + time_scale):
            gap_acc = a_i_stiff * sin(phi_i) - a_j_stiff * sin(phi_j)
            gap_jerk = a_i_stiff * cos(phi_i) * vi_new - a_j_stiff * cos(phi_j) * vj_new
            scale = 1 + abs(phi_i) + abs(phi_j)
            pressed = below_resolution(opening, gap_acc, k, float(t), scale, time_scale, eps, gap_jerk)
        return close_collision(log, number, pressed)

    two_bodies = cascade is None and motion is None and not rough
    on_collision = _two_body_callback(locals()) if two_bodies else on_any_collision
    on_collision.resolve = resolve
    return on_collision


def _two_body_callback(c: dict):
    """The callback of the most common mode, two free bodies on a fixed circle (no cascade, friction or
    forcing): ``on_any_collision`` of :func:`_make_callback` (``c``: its locals) without its branches for
    cascades, forcing and friction, and with ``close_collision`` inlined (measured 2-5% of the default
    scene's run). tests/test_hot_path.py holds the two to the same bits on every path (law, fallback,
    strict stop, max_collisions, persistent contact)."""
    holder, touched, number, reopened = c["holder"], c["touched"], c["number"], c["reopened"]
    i, j, resolve, records, log = c["i"], c["j"], c["resolve"], c["records"], c["log"]
    gap_constant, settle, h_bound, t_bound = c["gap_constant"], c["settle"], c["h_bound"], c["t_bound"]
    a_i_stiff, a_j_stiff, k, time_scale, eps = c["a_i_stiff"], c["a_j_stiff"], c["k"], c["time_scale"], c["eps"]
    sin, cos = math.sin, math.cos

    def on_collision(ta, d_sgn):
        if d_sgn >= 0:  # the gap rising through zero (events both ways: SceneSystem.gap_reopening)
            return d_sgn == 0 or reopened(ta)
        s = holder[0]
        before = s.tolist()
        dtime = ta.dtime
        touched[number] = dtime
        t = dtime[0]
        if not resolve(s, before, t):
            return False
        record = records[-1]
        vi_new, vj_new = record[3], record[4]
        opening = vj_new - vi_new
        phi_i, phi_j = before[i], before[j]
        gap = phi_j - phi_i + gap_constant
        if gap < 0 and opening * SLOW_REOPENING < -gap:
            settle.lift_gap(s, number)
        scale = 1 + abs(phi_i) + abs(phi_j)
        if opening * opening <= h_bound * scale or opening <= t_bound * (abs(t) + time_scale):
            gap_acc = a_i_stiff * sin(phi_i) - a_j_stiff * sin(phi_j)
            gap_jerk = a_i_stiff * cos(phi_i) * vi_new - a_j_stiff * cos(phi_j) * vj_new
            if below_resolution(opening, gap_acc, k, float(t), scale, time_scale, eps, gap_jerk):
                return close_collision(log, number, True)
        if len(records) >= log.chunk_size:
            log.on_full()
        return True

    return on_collision


def _contact_geometry(system: SceneSystem) -> tuple:
    """(per watched contact (unit a, unit b, gap constant): the gap is psi_b - psi_a + constant; per unit the
    contacts it takes part in, in contact order)."""
    geometry = [(c.unit_a, c.unit_b, system.gap_constants[n]) for n, c in enumerate(system.contacts)]
    by_unit: dict[int, list[int]] = {}
    for n, (a, b, _) in enumerate(geometry):
        by_unit.setdefault(a, []).append(n)
        by_unit.setdefault(b, []).append(n)
    return geometry, by_unit


def contact_settler(scene, system: SceneSystem, resolvers: list, log: CollisionLog, time_scale: float,
                    holder: list | None = None):
    """``settle(s, t, units, skip_open=None, skip_merge=()) -> bool``: pairs touching at one instant.

    Called after a collision (on the two units it involved: contacts closing
    at the same instant) and at the start of every mode (on all units).
    Every watched pair of those units' neighbours whose gap is within
    RESOLUTION_ULPS of zero is

    * **closing**: resolved now by its own law (``resolvers[number](s, t)``),
      and its units' neighbours are looked at again: the classic
      sequential-impulse treatment of simultaneous impacts (momentum is kept,
      and energy at k = 1; for unequal bodies the outcome can depend on the
      order, a known property of simultaneous impacts). Collisions resolved
      here are ordinary rows of the table, at the same t. A cascade that has
      not ended after 64 N collisions is an accumulation at one instant: the
      pair enters persistent contact.
    * **pressed and not opening faster than the run can resolve** (gap
      acceleration closing, :func:`below_resolution`): persistent contact
      (``stop.reason = "merge"``), unless the contact is in ``skip_merge``
      (the pair whose contact just split: its contact force has just turned
      to pulling, it opens).
    * **opening, or at rest and not pressed**: its gap is opened to
      2 OPEN_ULPS ulps (of 1 + |psi_a| + |psi_b|: ~4e-15 rad near the
      bottom) by moving one unit that far.
      heyoka cannot see a root of an event function that is exactly 0.0 at
      the start of a step (pure heyoka: x'' = -1, x(0) = 0, x'(0) = 0.01, an
      event on x, direction negative: the root at t = 0.02 is missed; with
      x(0) = 1e-300 it is found). A pair left touching and opening slowly
      while pressed (after a cascade, after a split, a scene that starts
      touching) re-closes within that first step, and would pass through
      unseen; a gap a few ulps open is seen to close. The move is below the
      run's resolution (the gap's own rounding); the unit with the roomier
      other side moves (in a row of touching units: it and the units that
      crowd it, as one block). ``skip_open``: the contact whose event just fired
      (heyoka's cooldown covers it).

    False: the run stops (``log.stop`` says why).
    """
    nu = system.n_units
    eps = system.precision.epsilon
    k = float(scene.law.restitution)
    stop = log.stop
    geometry, by_unit = _contact_geometry(system)
    left_of: dict[int, int] = {}
    right_of: dict[int, int] = {}
    for number, c in enumerate(system.contacts):
        right_of[c.unit_a] = number
        left_of[c.unit_b] = number
    max_rounds = 64 * system.n_bodies
    gap_motion = GapMotion(system, holder)

    def gap(s, number):
        a, b, constant = geometry[number]
        return s[b] - s[a] + constant

    def room(s, number, moving) -> float:
        """Gap of the moving unit's other contact (inf: none watched)."""
        other = right_of.get(moving) if moving == geometry[number][1] else left_of.get(moving)
        return math.inf if other is None or other == number else gap(s, other)

    def push_block(s, number, delta, target):
        """Move unit b of the contact and the units crowding it on its far side by +delta
        (else unit a and those on its side by -delta); the unit moved, or None."""
        a, b, _ = geometry[number]
        for moving, step, beyond in ((b, delta, right_of), (a, -delta, left_of)):
            block = [moving]
            while True:
                other = beyond.get(block[-1])
                if other is None or other == number or gap(s, other) - delta >= target:
                    break
                block.append(geometry[other][1] if step > 0 else geometry[other][0])
                if block[-1] in (a, b) or len(block) > nu:
                    block = None
                    break
            if block is not None:
                for u in block:
                    s[u] = s[u] + step
                return moving
        return None

    def open_gap(s, number, scale):
        """Open a touching gap to 2 OPEN_ULPS ulps; the unit moved, or None if no unit has room."""
        a, b, _ = geometry[number]
        target = OPEN_ULPS * eps * scale
        for _ in range(8):
            delta = 2 * target - gap(s, number)
            if room(s, number, b) - delta >= target:
                s[b] = s[b] + delta
                moved = b
            elif room(s, number, a) - delta >= target:
                s[a] = s[a] - delta
                moved = a
            else:
                # A row of touching units (four bodies starting in one point,
                # beta = 0): the neighbours' gaps are 0 or just opened, so no
                # single unit has room and this gap stayed 0.0, unseen by
                # heyoka when it closed again (measured: status overlap).
                # Move the unit with the units that crowd it, as one block
                # (their gaps unchanged), if there is room past the block.
                moved = push_block(s, number, delta, target)
                if moved is None:
                    return None
            if gap(s, number) > target:
                return moved
        return moved

    # below_resolution can only hold if v^2 <= 2 A h_res or v <= A (1 - k) t_res / 2, with A a
    # bound on the gap's acceleration: most pairs are cleared without computing it (as on_collision).
    bounds = [system.acceleration_bound(a) + system.acceleration_bound(b) for a, b, _ in geometry]

    def lift_gap(s, number):
        """A gap just below zero (rounding) to a few ulps above it by moving its second unit: clear of
        the rounding of the positions, so that heyoka's next step sees no root at its start."""
        a, b, constant = geometry[number]
        g = s[b] - s[a] + constant
        if g < 0:
            s[b] = s[b] - g + ulp * (1 + abs(s[b]))

    ulp = system.precision.number(eps)

    def touching_elsewhere(s) -> list:
        """The units of every pair touching anywhere: two disjoint pairs of a symmetric scene collide
        at one instant, and the other pair's event cannot fire from a gap of exactly 0 at the
        restart (measured: status overlap). One pass over the positions, in the run's own type
        (Python floats for double: 4x faster than numpy's small-array operations at 8 bodies)."""
        x = s.tolist() if s.dtype == np.float64 else list(s)
        band = RESOLUTION_ULPS * eps
        out = []
        for a, b, constant in geometry:
            pa, pb = x[a], x[b]
            if abs(pb - pa + constant) <= band * (1 + abs(pa) + abs(pb)):
                out += (a, b)
        return out

    def settle(s, t, units, skip_open=None, skip_merge=()) -> bool:
        # Impulses first (positions frozen: every collision of the instant sees
        # the same positions), then open the pairs left touching.
        pending = list(units)
        if len(geometry) > 2 and len(units) <= 2:  # after a collision (the mode's start looks at every unit)
            pending += [u for u in touching_elsewhere(s) if u not in units]
        seen = set(pending)
        judged: set = set()  # contacts found not pressed at this instant (see below)
        rounds = 0
        while pending:
            unit = pending.pop()
            for number in by_unit.get(unit, ()):
                a, b, constant = geometry[number]
                pa, pb = s[a], s[b]
                scale = 1 + abs(pa) + abs(pb)
                if abs(pb - pa + constant) > RESOLUTION_ULPS * eps * scale:
                    continue
                va, vb = s[nu + a], s[nu + b]
                opening = vb - va
                if opening < -SEPARATION_ULPS * eps * (abs(va) + abs(vb)):  # closing: a collision now
                    if rounds >= max_rounds:
                        stop.reason, stop.data = "merge", {"contact": number}
                        return False
                    rounds += 1
                    if not resolvers[number](s, t):
                        return False
                    judged.difference_update(by_unit[a], by_unit[b])  # their rates changed: judge again
                    pending += [a, b]
                    seen.update((a, b))
                    continue
                if number not in skip_merge and number not in judged:
                    judged.add(number)  # (until a collision of one of its units at this instant: see above)
                    pa, pb, va, vb = float(pa), float(pb), float(va), float(vb)
                    v, bound, scale = max(vb - va, 0.0), bounds[number], float(scale)
                    if v * v > 2 * bound * BOUNCE_ULPS * eps * scale and \
                            v > bound * (1 - k) * RESOLUTION_ULPS * eps * (abs(float(t)) + time_scale) / 2:
                        continue
                    acc, jerk = gap_motion(s, a, b, t, va, vb)
                    if below_resolution(v, acc, k, float(t), scale, time_scale, eps, jerk):
                        stop.reason, stop.data = "merge", {"contact": number}
                        return False
        for number in sorted({n for unit in seen for n in by_unit.get(unit, ())}):
            if number == skip_open:
                continue
            a, b, constant = geometry[number]
            scale = 1 + abs(s[a]) + abs(s[b])
            if abs(gap(s, number)) <= OPEN_ULPS * eps * scale:
                open_gap(s, number, scale)
        return True

    def close_start(s) -> None:
        """Pairs that start touching to within the scene's slack (model.touching_slack: places written as
        doubles), past it or short of it, but beyond the settler's band, are moved to touching in the run's
        type, the second unit moved, in order along the circle. In long, quad or MPFR the band is far narrower
        than a double's rounding: a pair 1e-17 rad past touching ran into each other unseen (status overlap),
        and a cradle's stack 4e-17 rad apart chattered at k = 1 every 1e-8 s (review). In double the band
        covers the slack: nothing moves."""
        for a, b, constant in geometry:
            g = s[b] - s[a] + constant
            scale = 1 + abs(s[a]) + abs(s[b])
            if RESOLUTION_ULPS * eps * scale < abs(g) <= TOUCHING_SLACK * scale:
                s[b] = s[b] - g

    # (in double the band covers the slack at every scale: nothing to move, and nothing spent on every run's start)
    settle.close_start = close_start if RESOLUTION_ULPS * eps < TOUCHING_SLACK else None
    settle.lift_gap = lift_gap  # for a gap rising through zero (reopening_check)
    # settle(s, t, every unit) leaves s as it is and returns True where no pair touches (the band of
    # touching_elsewhere is the widest settle looks at): the driver skips it at such a mode's start
    settle.idle = lambda s: not touching_elsewhere(s)
    return settle


def simultaneous_resolver(scene, system: SceneSystem, log: CollisionLog):
    """``group(s, t, number) -> None | bool``: collision.simultaneous = "impulses" on the circle.

    Before contact ``number`` (whose event just fired) is resolved alone, the contacts that touch at
    this instant and share a unit with it (and, transitively, with those: a chain of touching units)
    are gathered; a contact within the settler's band (RESOLUTION_ULPS) of zero touches. None: no
    other contact touches, or the group could not be resolved at once (then the instant is resolved
    sequentially, as without the key; so is a group where only one contact takes an impulse: its law
    alone). Otherwise every contact of the group is resolved at once
    and True returned (False: the run stops at max_collisions).

    Each contact's law is a linear pair map (:class:`WorkingMap`; the unit map where a cluster takes
    part): D = v_a - q v_b, v_a+ = v_a - a_i D, v_b+ = v_b + a_j D, a_i + q a_j = 1 + k. An impulse P
    (in units of D) moves v_a by -alpha P and v_b by +beta P, alpha = a_i / (1 + k), beta = a_j / (1 + k),
    so D by -P: one contact alone, P = (1 + k) D, is exactly the law. For the group, P >= 0 with the
    separations s = -D: s+ >= k D- where the contact approached (D- > 0), s+ >= 0 elsewhere,
    complementary to P (resolve.complementarity: the Delassus matrix here is a symmetric positive
    semi-definite one scaled by positive diagonals, which has the same solutions). Checked as the
    table's: no contact of the group may be left closing beyond SEPARATION_ULPS, and the group's
    kinetic energy (sum 1/2 M psi'^2, M a unit's generalized mass) may not grow beyond 2^20 ulps;
    else None (sequential). Rows: one per contact with P > 0, in contact order, flag 2; the first
    carries the whole change (before: the state before the group, after: after it), the others have
    before = after. Rough tracks (slipping bodies change the laws' masses) are left sequential.
    """
    nu = system.n_units
    eps = system.precision.epsilon
    number_type = system.precision.number
    zero = number_type(0)
    double = system.precision.name == "double"
    clusters = any(u.is_cluster for u in system.units)
    contacts = system.contacts
    geometry, by_unit = _contact_geometry(system)
    masses = [number_type(system.unit_mass(u)) for u in range(nu)]
    relative = relative_tolerance(system.precision)
    maps: dict[int, tuple] = {}
    records = log.records

    def constants(n):
        """(q, alpha, beta) of contact n in the run's type (double: Python floats), or None."""
        if n not in maps:
            c = contacts[n]
            if system.units[c.unit_a].is_cluster or system.units[c.unit_b].is_cluster:
                wm = working_map(unit_map(system, c.unit_a, c.unit_b, scene.law.restitution), system.precision)
            else:
                wm = pair_maps(scene, system.precision)[c.pair_index][0]
            if wm is None:
                maps[n] = None
            else:
                q, a_i, a_j = ((x[0] + x[1]) for x in (wm.q, wm.a_i, wm.a_j)) if double else (wm.q, wm.a_i, wm.a_j)
                one_plus_k = a_i + q * a_j
                maps[n] = (q, a_i / one_plus_k, a_j / one_plus_k, one_plus_k - 1)
        return maps[n]

    def group(s, t, number):
        if system.friction_blocks:
            return None
        x = s.tolist()
        members = [number]
        found = {number}
        pending = [geometry[number][0], geometry[number][1]]
        units = set(pending)
        while pending:
            for n in by_unit.get(pending.pop(), ()):
                if n in found:
                    continue
                a, b, constant = geometry[n]
                pa, pb = x[a], x[b]
                if abs(pb - pa + constant) <= RESOLUTION_ULPS * eps * (1 + abs(pa) + abs(pb)):
                    found.add(n)
                    members.append(n)
                    for u in (a, b):
                        if u not in units:
                            units.add(u)
                            pending.append(u)
        if len(members) == 1:
            return None
        members.sort()
        laws = [constants(n) for n in members]
        if any(law is None for law in laws):
            return None
        v = {u: x[nu + u] for u in units}
        m = len(members)
        # A[c][d] = -dD_c/dP_d, b_c = s_c- - target_c
        a_matrix = [[zero] * m for _ in range(m)]
        rhs = []
        for p, (n, (q, alpha, beta, k)) in enumerate(zip(members, laws)):
            a, b, _ = geometry[n]
            d = v[a] - q * v[b]
            rhs.append(-d - k * d if d > zero else -d)
            for r, (nd, (_, alpha_d, beta_d, _)) in enumerate(zip(members, laws)):
                ad, bd, _ = geometry[nd]
                change = zero  # dD_c / dP_d
                if ad == a:
                    change = change - alpha_d
                if bd == a:
                    change = change + beta_d
                if ad == b:
                    change = change + q * alpha_d
                if bd == b:
                    change = change - q * beta_d
                a_matrix[p][r] = -change
        impulses = complementarity(a_matrix, rhs, zero, relative)
        if impulses is None or sum(P > zero for P in impulses) < 2:
            return None  # (one contact pushed: its law alone, as without the key, with its own flag and policy)
        new = dict(v)
        for n, (q, alpha, beta, k), P in zip(members, laws, impulses):
            if P > zero:
                a, b, _ = geometry[n]
                new[a] = new[a] - alpha * P
                new[b] = new[b] + beta * P
        for n in members:
            a, b, _ = geometry[n]
            va, vb = new[a], new[b]
            if vb - va < -SEPARATION_ULPS * eps * (abs(va) + abs(vb)):
                return None
        energy_before = sum((masses[u] * v[u] * v[u] for u in units), zero)
        energy_after = sum((masses[u] * new[u] * new[u] for u in units), zero)
        if energy_after > energy_before * (1 + number_type(2.0 ** 20 * eps)):
            return None
        before = system.expand(x) if clusters else x
        for u in units:
            s[nu + u] = new[u]
        after = system.expand(s.tolist()) if clusters else s.tolist()
        first = True
        for n, P in zip(members, impulses):
            if not P > zero:
                continue
            records.append((t, contacts[n].pair_index, before if first else after, None, after, 2))
            first = False
        # One resolution, recorded whole: a limit reached inside it stops the run after its last row (stopping
        # at the limit left a change in the state that no row held: review)
        limit = log.max_collisions
        if limit is not None and log.count >= limit:
            stop_at_max_collisions(log.stop, limit)
            if log.count > limit:
                log.stop.message += f" (the last instant's {len(members)} contacts resolved at once, recorded whole)"
            return False
        return True

    return group


def _make_unit_callback(scene, system: SceneSystem, number: int, log: CollisionLog, holder: list, time_scale: float,
                        settle=None, touched=None, group=None):
    """Collisions when some bodies move as clusters: the state holds unit coordinates.

    Two free bodies collide by the scene's law (and policy); a collision that
    involves a cluster is Newton's law on psi' with the units' total
    generalized masses (the cluster moves as one rigid unit through the
    impact), recorded with flag 2. Contacts touching at the same instant are
    then settled by ``settle`` (:func:`contact_settler`), as in the free mode.
    Returns the event callback; its ``resolve(s, t)`` applies the law alone.
    """
    contact = system.contacts[number]
    pair = contact.pair
    a, b = contact.unit_a, contact.unit_b
    nu = system.n_units
    both_free = not system.units[a].is_cluster and not system.units[b].is_cluster
    law_map, fallback = pair_maps(scene, system.precision)[contact.pair_index]
    law = law_map if both_free else working_map(unit_map(system, a, b, scene.law.restitution), system.precision)
    eps = system.precision.epsilon
    k = float(scene.law.restitution)
    strict = scene.on_inconsistent == "error"
    stop = log.stop
    reopened = reopening_check(system, number, log, holder, touched, settle) if system.gap_reopening else None
    gap_motion = GapMotion(system, holder)

    def resolve(s, t) -> bool:
        """Apply the law (or the policy), record it; False: stop the run (policy, max_collisions)."""
        state = s.tolist()
        before = system.expand(state)
        va, vb = state[nu + a], state[nu + b]
        flag = 0 if both_free else 2
        members = system.units[a].members + system.units[b].members
        if system.friction_blocks and any(slipping(holder, k, scene) for k in members):
            if both_free:
                va_new, vb_new = _slipping_map(scene, system, pair.i, pair.j, holder).apply(va, vb)
                flag = 3
            else:  # slipping bodies (free or in a cluster): their translational mass in Newton's law between units
                slips = slipping_members(holder, members, scene)
                va_new, vb_new = working_map(unit_map(system, a, b, scene.law.restitution, slips),
                                             system.precision).apply(va, vb)
        else:
            va_new, vb_new = law.apply(va, vb)
        if vb_new - va_new < -SEPARATION_ULPS * eps * (va - vb):
            if strict:
                stop.reason = "inconsistent"
                stop.message = (
                    f"collision {log.count + 1} at t = {float(t):.17g}: bodies {pair.i + 1} and {pair.j + 1} "
                    f"still approach after the '{system.law_name}' law; stopped (collision.on_inconsistent = 'error')"
                )
                return False
            va_new, vb_new = fallback.apply(va, vb)
            flag = 1
            log.fallbacks += 1
        s[nu + a], s[nu + b] = va_new, vb_new
        after = system.expand(s.tolist())
        log.records.append((t, contact.pair_index, before, None, after, flag))
        if log.max_collisions is not None and log.count >= log.max_collisions:
            return stop_at_max_collisions(stop, log.max_collisions)
        return True

    def on_collision(ta, d_sgn):
        if d_sgn >= 0:  # the gap rising through zero (events both ways: SceneSystem.gap_reopening)
            return d_sgn == 0 or reopened(ta)
        s = holder[0]
        t, t_lo = ta.dtime
        touched[number] = (t, t_lo)
        if group is None or (done := group(s, t, number)) is None:  # (group: simultaneous_resolver)
            if not resolve(s, t):
                return False
        elif not done:
            return False
        if settle is not None:
            if not settle(s, t, (a, b), number):
                return False
            gap = s[b] - s[a] + system.gap_constants[number]
            if gap < 0 and (s[nu + b] - s[nu + a]) * SLOW_REOPENING < -gap:
                settle.lift_gap(s, number)  # as in the free mode's callback
        state = [float(x) for x in s.tolist()]
        psi_a, psi_b = state[a], state[b]
        va_new, vb_new = state[nu + a], state[nu + b]
        gap_acc, gap_jerk = gap_motion(s, a, b, t, va_new, vb_new)
        pressed = below_resolution(
            vb_new - va_new, gap_acc, k, float(t), 1 + abs(psi_a) + abs(psi_b), time_scale, eps, gap_jerk
        )
        return close_collision(log, number, pressed)

    on_collision.resolve = resolve
    return on_collision
