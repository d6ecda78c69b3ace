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
import mpmath
import numpy as np

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
    """Raw collision records appended by the event callbacks.

    When ``chunk_size`` records have piled up the callback calls ``on_full``,
    which hands them on (to a file) and clears the list, so memory stays flat
    however long the run; ``flushed`` counts the records handed on.
    """

    records: list = field(default_factory=list)
    max_collisions: int | None = None
    stop: StopRequest = field(default_factory=StopRequest)
    flushed: int = 0
    chunk_size: int = 1 << 62
    on_full: object = None

    @property
    def count(self) -> int:
        return self.flushed + len(self.records)


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


def _make_callback(system: SceneSystem, number: int, log: CollisionLog, holder: list):
    pair = system.pairs[number]
    law_map = working_map(pair.law_map, system.precision)
    q, a_i, a_j = law_map.q, law_map.a_i, law_map.a_j
    vi_index = system.n_bodies + pair.i
    vj_index = system.n_bodies + pair.j
    tiny = SEPARATION_ULPS * system.precision.epsilon
    records = log.records
    append = records.append
    limit = log.max_collisions
    stop = log.stop
    law_name = system.law_name
    extended = law_map.extended

    def on_collision(ta, d_sgn):
        s = holder[0]
        before = s.tolist()  # Python numbers: faster arithmetic than numpy scalars
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
        append((ta.time, number, before, vi_new, vj_new))
        s[vi_index] = vi_new
        s[vj_index] = vj_new
        # The gap opens at rate vj_new - vi_new; it closed at vi - vj.
        opening = vj_new - vi_new
        if opening <= tiny * (vi - vj):
            where = f"collision {log.count} at t = {float(ta.time):.17g}: bodies {pair.i + 1} and {pair.j + 1}"
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
        if limit is not None and log.flushed + len(records) >= limit:
            stop.reason = "max_collisions"
            stop.message = f"stopped after max_collisions = {limit} collisions"
            return False
        if len(records) >= log.chunk_size:
            log.on_full()
        return True

    on_collision.pair = pair
    return on_collision
