"""The driver: integrate a scene with heyoka, stop at t_end or max_collisions."""

from __future__ import annotations

import gc
import time
from typing import Protocol

import heyoka as hy
import numpy as np

from ..model.scene import Scene
from .events import CollisionLog, collision_events
from .precision import DOUBLE, Precision
from .result import SimulationResult, Status
from .system import build_system, gap_value

#: A gap below -OVERLAP_TOLERANCE rad at the end of a run means a collision
#: was missed; the run is then reported as failed, never as a success.
OVERLAP_TOLERANCE = 1e-9


def simulate(
    scene: Scene,
    *,
    t_end=None,
    max_collisions: int | None = ...,
    precision: Precision | str = DOUBLE,
    tolerance=None,
    high_accuracy: bool = False,
    watch_all_contacts: bool = False,
    sink: CollisionSink | None = None,
    chunk_size: int = 65536,
    progress=None,
) -> SimulationResult:
    """Integrate ``scene`` and apply its collision law at every contact.

    Collision instants are the roots of the gap functions, located by
    heyoka's event detection to the precision of the run. ``t_end`` and
    ``max_collisions`` override the scene's run settings (pass
    ``max_collisions=None`` for no limit). ``tolerance`` defaults to the
    precision's epsilon. ``watch_all_contacts`` also watches pairs whose
    contact the scene's energy cannot reach. ``high_accuracy`` turns on
    heyoka's compensated summation: it slows double runs by about a fifth and
    matters for very long runs (see validation/), not for collision times over
    tens of collisions, which stay within a few ulp either way.

    Long runs: with a ``sink`` (see :class:`CollisionSink`) the records are
    handed on every ``chunk_size`` collisions and only the first chunk stays
    in memory, so memory does not grow with the number of collisions.
    ``progress(t, collisions)``, if given, is called about every 0.2 s of
    wall time (checked once per 1024 collisions) and at the end.
    """
    started = time.perf_counter()
    precision = Precision.parse(precision) if isinstance(precision, str) else precision
    t_end = scene.run.t_end if t_end is None else t_end
    limit = scene.run.max_collisions if max_collisions is ... else max_collisions
    if limit is not None and limit < 0:
        raise ValueError("max_collisions must be >= 0")
    system = build_system(scene, precision, pairs=scene.pairs if watch_all_contacts else None)
    log = CollisionLog(max_collisions=limit)
    holder: list = [None]
    events = collision_events(system, log, holder)
    options = dict(precision.integrator_options(), high_accuracy=high_accuracy)
    if tolerance is not None:
        options["tol"] = precision.number(tolerance)
    ta = hy.taylor_adaptive(
        system.equations, system.initial_state, pars=system.parameters, t_events=events, **options
    )
    holder[0] = ta.state
    initial_state = np.array(ta.state, copy=True)
    stream = _Stream(log, system, sink, progress, ta)
    if sink is not None:
        sink.open(scene, system.pairs, precision)
    if sink is not None or progress is not None:
        log.chunk_size = chunk_size if sink is not None else 1024
        log.on_full = stream.on_full

    steps = 0
    outcome = None
    if limit == 0:
        log.stop.reason, log.stop.message = "max_collisions", "max_collisions = 0: nothing integrated"
    else:
        _collide_touching_pairs(system, events, ta, holder)
        if log.stop.reason is None:
            # The log grows by one small list per collision: the cyclic garbage
            # collector would rescan it again and again, for nothing (no cycles).
            gc_was_enabled = gc.isenabled()
            gc.disable()
            try:
                result = ta.propagate_until(precision.number(t_end))
                outcome, steps = result[0], int(result[3])
            except KeyboardInterrupt:
                # Ctrl-C (or SIGTERM turned into it by the CLI): keep every completed collision.
                log.stop.reason = "interrupted"
                log.stop.message = f"interrupted at t = {float(ta.time):.17g} s after {log.count} collisions"
            finally:
                if gc_was_enabled:
                    gc.enable()

    status, message = _status(log, outcome, t_end)
    final_state = np.array(ta.state, copy=True)
    if status.success:
        overlap = _overlap(scene, precision, final_state)
        if overlap:
            status, message = Status.OVERLAP, overlap
    total = log.count
    if sink is not None:
        stream.flush()
        sink.close()
        times, numbers, before, after = stream.kept or records_to_arrays([], system)
    else:
        times, numbers, before, after = records_to_arrays(log.records, system)
    if progress is not None:
        progress(float(ta.time), total)
    return SimulationResult(
        scene=scene,
        status=status,
        message=message,
        precision=precision,
        t_final=ta.time,
        initial_state=initial_state,
        final_state=final_state,
        times=times,
        pair_numbers=numbers,
        pairs=system.pairs,
        states_before=before,
        states_after=after,
        total_collisions=total,
        table_file=getattr(sink, "path", None) if sink is not None else None,
        wall_time_s=time.perf_counter() - started,
        steps=steps,
        settings={
            "tolerance": float(ta.tol),
            "high_accuracy": high_accuracy,
            "t_end": float(t_end),
            "max_collisions": limit,
        },
    )


class CollisionSink(Protocol):
    """Where a streamed run sends its collision records, chunk by chunk."""

    def open(self, scene: Scene, pairs: tuple, precision: Precision) -> None:
        """Called once before the run, with the contacts it watches."""

    def write(self, chunk: tuple, first_number: int) -> None:
        """``chunk`` = (times, pair_numbers, states_before, states_after) arrays."""

    def close(self) -> None:
        """Called once at the end of the run (also after an interruption)."""


def records_to_arrays(records: list, system) -> tuple:
    """Raw callback records -> (times, pair_numbers, states_before, states_after)."""
    n = len(records)
    nb = system.n_bodies
    if not n:
        return np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros((0, 2 * nb)), np.zeros((0, 2 * nb))
    before = np.array([r[2] for r in records]).reshape(n, 2 * nb)
    after = before.copy()
    numbers = np.array([r[1] for r in records], dtype=np.int64)
    vi_index = nb + np.array([system.pairs[k].i for k in numbers])
    vj_index = nb + np.array([system.pairs[k].j for k in numbers])
    rows = np.arange(n)
    after[rows, vi_index] = [r[3] for r in records]
    after[rows, vj_index] = [r[4] for r in records]
    times = np.array([r[0] for r in records])
    return times, numbers, before, after


class _Stream:
    """Hands collision records on to a sink in chunks and reports progress."""

    def __init__(self, log, system, sink, progress, ta):
        self.log, self.system, self.sink, self.progress, self.ta = log, system, sink, progress, ta
        self.kept: tuple | None = None  # the first chunk stays in memory for figures
        self.last_report = time.perf_counter()

    def flush(self) -> None:
        log = self.log
        if self.sink is None or not log.records:
            return
        chunk = records_to_arrays(log.records, self.system)
        self.sink.write(chunk, first_number=log.flushed + 1)
        if self.kept is None:
            self.kept = chunk
        log.flushed += len(log.records)
        log.records.clear()

    def on_full(self) -> None:
        if self.sink is not None:
            self.flush()
        else:  # progress only: keep every record, look again 1024 collisions later
            self.log.chunk_size += 1024
        if self.progress is not None and time.perf_counter() - self.last_report > 0.2:
            self.last_report = time.perf_counter()
            self.progress(float(self.ta.time), self.log.count)


def _collide_touching_pairs(system, events, ta, holder) -> None:
    """Bodies that start touching and approaching collide at t = 0.

    An event cannot see a root at the very start of a step, so such a
    collision is applied here, by the same callback.
    """
    state = holder[0]
    nb = system.n_bodies
    for number, pair in enumerate(system.pairs):
        gap = gap_value(system, number, state)
        closing = state[nb + pair.i] - state[nb + pair.j]
        if gap <= 4 * system.precision.epsilon * (1 + abs(state[pair.i]) + abs(state[pair.j])) and closing > 0:
            if not events[number].callback(ta, -1):
                return


def _status(log, outcome, t_end) -> tuple[Status, str]:
    if log.stop.reason == "max_collisions":
        return Status.MAX_COLLISIONS, log.stop.message
    if log.stop.reason == "contact":
        return Status.CONTACT, log.stop.message
    if log.stop.reason == "inconsistent":
        return Status.INCONSISTENT, log.stop.message
    if log.stop.reason == "interrupted":
        return Status.INTERRUPTED, log.stop.message
    if outcome == hy.taylor_outcome.time_limit:
        return Status.COMPLETED, f"reached t_end = {float(t_end):.17g} s after {len(log.records)} collisions"
    return Status.FAILED, f"the integrator stopped with outcome {outcome!s}"


def _overlap(scene: Scene, precision: Precision, state) -> str:
    system = build_system(scene, precision, pairs=scene.pairs)
    for number, pair in enumerate(system.pairs):
        gap = float(gap_value(system, number, state))
        if gap < -OVERLAP_TOLERANCE:
            return (
                f"bodies {pair.i + 1} and {pair.j + 1} overlap at the end of the run (gap {gap:.3g} rad): "
                "a collision was missed"
            )
    return ""
