"""Collision events: one terminal heyoka event per watched contact.

The event fires when a gap closes (direction negative only: approach). Its
callback applies the collision law as an impulse map on the two bodies'
rates and appends one record to the log. Records are kept raw (time, pair,
state before, the two outgoing rates) on the hot path; the table is built
from them afterwards, vectorized.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import heyoka as hy

from .system import SceneSystem

#: A post-collision separation rate below this multiple of the approach rate
#: (times the precision's epsilon) counts as no separation: the bodies would
#: stay in contact, which this engine does not model yet.
SEPARATION_ULPS = 64


@dataclass
class StopRequest:
    """Why a callback asked the integrator to stop (None: it did not)."""

    reason: str | None = None
    message: str = ""


@dataclass
class CollisionLog:
    """Raw collision records appended by the event callbacks."""

    records: list = field(default_factory=list)
    max_collisions: int | None = None
    stop: StopRequest = field(default_factory=StopRequest)


def collision_events(system: SceneSystem, log: CollisionLog, state_view_holder: list) -> list:
    """The terminal events of ``system``; callbacks write into ``log``.

    ``state_view_holder[0]`` must be set to the integrator's state array (a
    view into heyoka's buffer) before integrating; the callbacks use it to
    avoid re-wrapping the buffer at every collision.
    """
    events = []
    for number, pair in enumerate(system.pairs):
        cb = _make_callback(system, number, log, state_view_holder)
        events.append(
            hy.t_event(
                system.gap_expressions[number],
                callback=cb,
                direction=hy.event_direction.negative,
                **system.precision.integrator_options(),
            )
        )
    return events


def _make_callback(system: SceneSystem, number: int, log: CollisionLog, holder: list):
    pair = system.pairs[number]
    num = system.precision.number
    q, a_i, a_j = num(pair.law_map.q), num(pair.law_map.a_i), num(pair.law_map.a_j)
    vi_index = system.n_bodies + pair.i
    vj_index = system.n_bodies + pair.j
    tiny = SEPARATION_ULPS * system.precision.epsilon
    records = log.records
    append = records.append
    limit = log.max_collisions
    stop = log.stop
    law_name = system.law_name

    def on_collision(ta, d_sgn):
        s = holder[0]
        before = s.tolist()  # Python numbers: faster arithmetic than numpy scalars
        vi = before[vi_index]
        vj = before[vj_index]
        d = vi - q * vj
        vi_new = vi - a_i * d
        vj_new = vj + a_j * d
        append((ta.time, number, before, vi_new, vj_new))
        s[vi_index] = vi_new
        s[vj_index] = vj_new
        # The gap opens at rate vj_new - vi_new; it closed at vi - vj.
        opening = vj_new - vi_new
        if opening <= tiny * (vi - vj):
            where = f"collision {len(records)} at t = {float(ta.time):.17g}: bodies {pair.i + 1} and {pair.j + 1}"
            if opening < -tiny * (vi - vj):
                stop.reason = "inconsistent"
                stop.message = (
                    f"{where} still approach after the '{law_name}' law (gap rate {float(vi - vj):.3g} -> "
                    f"{float(-opening):.3g} rad/s closing): the law's outcome would make them overlap; stopped"
                )
            else:
                stop.reason = "contact"
                stop.message = (
                    f"{where} do not separate after the law (gap rate {float(opening):.3g} rad/s): "
                    "persistent contact is not modelled yet"
                )
            return False
        if limit is not None and len(records) >= limit:
            stop.reason = "max_collisions"
            stop.message = f"stopped after max_collisions = {limit} collisions"
            return False
        return True

    on_collision.pair = pair
    return on_collision
