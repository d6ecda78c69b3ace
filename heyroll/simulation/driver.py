"""The driver: integrate a scene with heyoka, mode by mode, until t_end.

A *mode* says which bodies move together in persistent contact. Most runs
stay in the all-free mode for good; an accumulating sequence of collisions
(Zeno) switches a pair into contact, a contact force that would pull splits
it again. Each mode is one heyoka integrator (compiled code is cached per
mode shape); collisions inside a mode are handled by event callbacks without
leaving heyoka.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import gc
import itertools
import math
import signal
import threading
import time
from dataclasses import dataclass
from typing import Protocol

import heyoka as hy
import mpmath
import numpy as np

from ..model.scene import Scene
from ..model.table import is_table
from .events import CollisionLog, StopRequest, fill_record_modes, mode_events, mode_handlers
from .resolve.friction import FrictionState, initial_modes
from .compiled_cache import CompiledCache, by_constants, by_scene
from .precision import Precision
from .result import SimulationResult, Status, counted, passage_table
from .contact_function import body_function, evaluate
from .resolve.bounds import left_track_message, parameters_on_pieces
from .resolve.constraints import project_onto_contacts
from .turns import WIND_DENSE, WIND_GROWTH, Turns, Winder
from .system import (
    SceneSystem, Unit, build_system, cluster_unit, energy_reach, link_bodies, singleton_units_of, overlap_tolerance, piece_of, singleton_units,
    unit_acceleration,
)

#: A gap below -overlap_tolerance (system.py) means a collision was missed:
#: the run stops with status overlap, never a success. Gaps are watched all
#: along the run by a guard event per pair, and checked at the start and end
#: of every mode and at the end of the run (every pair, watched or not).

#: A run that changes contact mode more than this many times N at one instant
#: (merging and splitting for ever) stops with status failed.
MAX_CHANGES_AT_ONE_INSTANT = 8


class CollisionSink(Protocol):
    """Where a streamed run sends its collision records, chunk by chunk."""

    def open(self, scene: Scene, pairs: tuple, precision: Precision) -> None:
        """Called once before the run, with the scene's contact pairs."""

    def write(self, chunk: tuple, first_number: int) -> None:
        """``chunk`` = (times, pair_numbers, states_before, states_after, flags) arrays."""

    def close(self) -> None:
        """Called once at the end of the run (also after an interruption)."""

    # Optional: ``rows``, the number of records the sink has taken so far. With it, a Ctrl-C
    # that lands inside ``write`` is resolved exactly (the chunk is written once); without it
    # the driver takes an interrupted write as not done and hands the chunk on again at the end.


@dataclass(frozen=True)
class ModeChange:
    """From time ``t`` on, bodies move in ``clusters`` (1-based body numbers); ``state`` is the full state then."""

    t: float
    clusters: tuple[tuple[int, ...], ...]
    state: tuple
    #: Units resting on a limiter: ((1-based bodies), 'lower' | 'upper').
    pinned: tuple = ()


class OptionsError(ValueError):
    """A run option breaks a rule (``field``: the option's name)."""

    def __init__(self, field: str, rule: str):
        self.field, self.rule = field, rule
        super().__init__(f"{field}: {rule}")


#: Events (collisions, passages, mode changes) a run may have unless told otherwise: about
#: 25 s of collisions on the default scene, and a bound on the passages kept in memory (~0.4 kB each).
DEFAULT_MAX_EVENTS = 2_000_000


@dataclass(frozen=True)
class RunOptions:
    """How to run a scene; every field defaults to the scene's own setting or the engine's default.

    ``t_end`` and ``max_collisions`` override the scene's [run] table (pass
    ``max_collisions=None`` for no limit, ``...`` for the scene's);
    ``precision`` is ``double | long | quad | mp:BITS`` (every event, law map
    and fallback is evaluated in that type); ``tolerance`` defaults to the
    precision's epsilon; ``high_accuracy`` turns on heyoka's compensated
    summation (measured on the default scene: no change of the collision
    times over tens of collisions nor of the energy error over 1e6
    collisions, a few per cent of cost, validation/long_runs.py);
    ``fast_math`` compiles with heyoka's fast-math flags (LLVM may reorder and
    contract floating-point operations: faster steps, results no longer
    reproducible to the last bit; the speed and accuracy price are measured in
    validation/work_precision.py); ``watch_all_contacts`` also watches pairs the scene's energy cannot
    bring together; ``chunk_size`` collisions are handed to a sink at a
    time; ``dense`` keeps heyoka's continuous output of the whole run
    (``SimulationResult.dense``, for figures; memory grows with the run);
    ``max_events`` bounds every kind of event together (collisions, junction
    passages, limiter impacts, contact mode changes; ``...`` for
    DEFAULT_MAX_EVENTS, ``None`` for no limit): a run whose events pile up (a
    body flung against a limiter at Omega = 1e6 rad/s) stops there with status
    ``max_events`` instead of filling the memory with passages.
    """

    t_end: object = None
    max_collisions: object = ...
    precision: object = "double"
    tolerance: object = None
    high_accuracy: bool = False
    fast_math: bool = False
    watch_all_contacts: bool = False
    chunk_size: int = 65536
    dense: bool = False
    max_events: object = ...

    def __post_init__(self):
        if self.t_end is not None:
            try:
                t_end = float(self.t_end)
            except (TypeError, ValueError):
                raise OptionsError("t_end", f"must be a number, got {self.t_end!r}") from None
            if not math.isfinite(t_end) or t_end < 0:
                raise OptionsError("t_end", f"must be a finite number >= 0, got {self.t_end!r}")
        limit = self.max_collisions
        if limit is not ... and limit is not None:
            if isinstance(limit, bool) or not isinstance(limit, (int, np.integer)) or limit < 0:
                raise OptionsError("max_collisions", f"must be a whole number >= 0 or None, got {limit!r}")
        if self.tolerance is not None:
            try:
                tol = float(self.tolerance)
            except (TypeError, ValueError):
                raise OptionsError("tolerance", f"must be a number, got {self.tolerance!r}") from None
            if not math.isfinite(tol) or not 0 < tol < 1:  # (as the CLI's --tolerance: acceptance test)
                raise OptionsError("tolerance", f"must be a number > 0 and < 1, got {self.tolerance!r}")
        if isinstance(self.precision, str):
            try:
                object.__setattr__(self, "precision", Precision.parse(self.precision))
            except ValueError as exc:  # one error class for every option (a SceneError before: acceptance test)
                raise OptionsError("precision", getattr(exc, "rule", str(exc))) from None
        events = self.max_events
        if events is not ... and events is not None and (
                isinstance(events, bool) or not isinstance(events, (int, np.integer)) or events < 1):
            raise OptionsError("max_events", f"must be a whole number >= 1 or None, got {events!r}")
        if isinstance(self.chunk_size, bool) or not isinstance(self.chunk_size, int) or self.chunk_size < 1:
            raise OptionsError("chunk_size", f"must be a whole number >= 1, got {self.chunk_size!r}")


def simulate(
    scene: Scene,
    options: RunOptions | None = None,
    *,
    sink: CollisionSink | None = None,
    progress=None,
    **fields,
) -> SimulationResult:
    """Integrate ``scene`` on its track and apply its collision law at every contact.

    Collision instants are the roots of the gap functions, located by
    heyoka's event detection to the precision of the run; collisions,
    junction passages and limiter impacts are resolved inside heyoka's event
    callbacks. ``options`` is a :class:`RunOptions`; keyword ``fields``
    replace single options (``simulate(scene, t_end=5.0, precision="quad")``).

    Long runs: with a ``sink`` (see :class:`CollisionSink`) the records are
    handed on every ``chunk_size`` collisions and only the first chunk stays
    in memory, so memory does not grow with the number of collisions.
    ``progress(t, collisions)``, if given, is called about every 0.2 s of
    wall time (checked once per 1024 collisions) and at the end.
    """
    options = options or RunOptions()
    if fields:
        unknown = set(fields) - set(RunOptions.__dataclass_fields__)
        if unknown:
            raise TypeError(f"simulate() got unknown options {sorted(unknown)}")
        options = dataclasses.replace(options, **fields)
    return _simulate(scene, options, sink, progress)


def _simulate(scene: Scene, opts: RunOptions, sink, progress) -> SimulationResult:
    with _collector_paused():
        if is_table(scene):  # billiards: balls on a table (paper section 7)
            from .table.driver import simulate_table

            return simulate_table(scene, opts, sink, progress)
        _, _, events, collision_limit = run_limits(scene, opts)
        log = _take_log(collision_limit, events, [] if scene.rough else None)
        try:
            return _run(scene, opts, sink, progress, log)
        finally:
            _RUN_LOGS.free.append(log)


@contextlib.contextmanager
def _collector_paused():
    """Python's cyclic garbage collector is paused while a run integrates, and restored after. Each
    collision's record (a tuple holding a list) is an object the collector tracks, and its passes over a
    growing list of them, in the integration and in turning the records into arrays after it, cost a
    tenth of a long run (measured on the default scene, 93,594 collisions: 9.1e4 collisions/s with it on
    outside the integration, 1.02e5 with it paused throughout). Reference counting still frees everything a
    run drops (it makes no reference cycles per collision)."""
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


#: Each thread's logs free for a run (a run inside a run, from a progress callback or a sink, takes another).
_RUN_LOGS = threading.local()
#: Handler sets cached on one log (by system and scene constants), least recently used dropped first.
HANDLER_SETS = 64


def _take_log(max_collisions, max_events, record_modes) -> CollisionLog:
    """A log for one run: one of this thread's, reset, with the handlers built on it before (see _handlers)."""
    free = getattr(_RUN_LOGS, "free", None)
    if free is None:
        free = _RUN_LOGS.free = []
    if free:
        return free.pop().reset(max_collisions, max_events, record_modes)
    log = CollisionLog(max_collisions=max_collisions, max_events=max_events, record_modes=record_modes)
    log.handler_sets = CompiledCache(HANDLER_SETS)
    return log


def forget_handlers() -> None:
    """Drop this thread's logs and the handlers cached with them (for tests that replace a handler factory)."""
    _RUN_LOGS.free = []


def _handlers(scene: Scene, system: SceneSystem, log: CollisionLog, time_scale: float, pieces, friction) -> tuple:
    """(holder, handlers, warnings, settle) of a mode (events.mode_handlers), built once per log, system and
    scene constants where they hold nothing of one run but the log and the holder: every system of a circle
    without friction (set-up before the first step measured ~15 us of ~40 us for the default scene run again).
    A system of an open track (its pieces) or with friction (the run's friction state) gets new ones."""
    if friction is not None or not system.linear_gap:
        holder = [None, None, None]
        return (holder,) + tuple(mode_handlers(scene, system, log, holder, time_scale, pieces, friction))

    def build():
        holder = [None, None, None]
        return (system, holder) + tuple(mode_handlers(scene, system, log, holder, time_scale, pieces, None))

    # by the system's identity: the entry holds the system, so no other object can take its id meanwhile
    return log.handler_sets.get((id(system), scene.constants, time_scale), build)[1:]


def _run(scene: Scene, opts: RunOptions, sink, progress, log: CollisionLog) -> SimulationResult:
    precision = opts.precision
    tolerance, high_accuracy, watch_all_contacts = opts.tolerance, opts.high_accuracy, opts.watch_all_contacts
    chunk_size = opts.chunk_size
    started = time.perf_counter()
    t_end, limit, events, collision_limit = run_limits(scene, opts)
    if limit is not None and limit < 0:
        raise ValueError("max_collisions must be >= 0")
    pairs = scene.pairs if watch_all_contacts else None
    options = dict(precision.integrator_options(), high_accuracy=high_accuracy)
    if opts.fast_math:
        options["fast_math"] = True
    if tolerance is not None:
        options["tol"] = precision.number(tolerance)
    time_scale = motion_time_scale(scene)

    stream = _Stream(log, sink, progress, len(scene.bodies))
    # The circle: whole turns out of the angles (simulation.turns), between stretches of integration where a body
    # can go round, and at every mode's start.
    turns = stream.turns = log.turns = Turns(precision) if scene.track.linear_gap else None
    winds = turns is not None and any(energy_reach(scene).top_half)
    if sink is not None:
        sink.open(scene, scene.pairs, precision)
        log.chunk_size = chunk_size
    elif progress is not None:
        log.chunk_size = 1024
    log.on_full = stream.on_full
    if hasattr(sink, "write_passages"):  # junction passages and limiter impacts streamed too
        log.on_passages_full = stream.flush_passages

    num = precision.number
    friction = FrictionState(scene, precision, initial_modes(scene), [num(w) for w in scene.slip]) \
        if scene.rough else None
    stream.friction = friction  # (and the pairs' bodies, for the friction modes of its records)
    stream.pair_bodies = [(p.i, p.j) for p in scene.pairs] if friction is not None else None
    try:
        start = _start(scene, precision, watch_all_contacts)
    except KeyboardInterrupt:  # while the first mode compiles: nothing integrated, outputs still whole
        start = _Start(tuple(num(x) for x in scene.phi) + tuple(num(x) for x in scene.dphi),
                       singleton_units(len(scene.bodies)),
                       tuple(num(x) for x in scene.phi) + tuple(num(x) for x in scene.dphi), None,
                       tuple(piece_of(scene.track, b, q) for b, q in zip(scene.bodies, scene.q)),
                       ("interrupted", "interrupted at t = 0 s while the run was being set up (compiling)"))
    units, first_system = start.units, start.system
    full_state = list(start.state)
    initial_state = np.array(start.initial_state)
    pieces = list(start.pieces)
    dense = [] if opts.dense else None
    modes = [ModeChange(0.0, _clusters(units), tuple(full_state))]
    t = (num(0), num(0))  # double-length time (hi, lo), kept across modes
    steps, outcome, first = 0, None, True
    contacts_open: dict[int, float] = {}
    intervals: list[dict] = []
    for unit in units:
        for a, b in zip(unit.members, unit.members[1:]):
            contacts_open[(a, b)] = 0.0

    if limit == 0:
        log.stop.reason, log.stop.message = "max_collisions", "max_collisions = 0: nothing integrated"
    start_limit = start.limit
    if start_limit:
        log.stop.reason, log.stop.message = start_limit
    split_pair = None  # scene pair index of a contact that has just split
    merged_pair = None  # scene pair index of a contact that has just entered persistent contact (path tracks)
    same_instant = 0  # mode changes in a row at one instant (bounded: see MAX_CHANGES_AT_ONE_INSTANT)
    while limit != 0 and not start_limit:
        try:
            system = first_system if first else build_system(scene, precision, pairs=pairs, units=units)
            later_mode, first = not first, False
            # holder: state, parameters, the mode's FrictionModes (rough tracks)
            holder, handlers, warnings, settle = _handlers(scene, system, log, time_scale, pieces, friction)
            cooldown = precision.number(precision.epsilon * time_scale)
            # The first mode is compiled optimized; a later one (a cluster forming or splitting,
            # a body coming to rest) quickly first (see QUICK_STEPS), also when the optimized one is
            # cached already: the two round differently, and a run must not depend on what ran before.
            quick = later_mode
            ta, slots, nt_slots = _integrator(system, options, cooldown, quick=quick)
            slots[:], nt_slots[:] = handlers, warnings
            params = parameters_on_pieces(scene, system, pieces) if system.piece_blocks else list(system.parameters)
            ta.pars[:] = params[: len(ta.pars)]  # heyoka keeps those up to the last one used
            if system.per_body and (system.links or any(u.pinned for u in units)):
                before_projection, slips = full_state, list(friction.slips) if friction is not None else None
                full_state = project_onto_contacts(system, full_state, params, friction)
                if merged_pair is not None:
                    _record_merge(scene, log, stream, friction, t, merged_pair, before_projection, full_state, slips)
            merged_pair = None
            ta.state[:] = system.reduce(full_state) + [num(0)] * system.n_extra
            if turns is not None:
                with signals_deferred():  # (the state, its turns and full_state move together)
                    if turns.take(ta.state, system.n_coordinates, log, friction):
                        full_state = system.expand(ta.state.tolist())
            ta.dtime = t
            if slots:
                ta.reset_cooldowns()
            touched = getattr(settle, "touched", [])  # the circle's gap reopening checks (events.reopening_check)
            touched[:] = [ta.dtime] * len(touched)
            # The full parameter vector (compiled contact functions may read some that the
            # integrator does not keep); the junction callbacks update it and the integrator's.
            holder[0], holder[1] = ta.state, np.array(params)
            stream.ta = ta
            _reset(log.stop)
            if not later_mode and getattr(settle, "close_start", None) is not None:
                settle.close_start(ta.state)  # (bodies placed past touching by round-off: model.touching_slack)
            # Pairs touching as the mode starts (bodies that start so, the rest of a
            # cascade, a contact that has just split): collide, enter contact, or
            # open by a few ulps so that their events can see them close again.
            skip_merge = {n for n, c in enumerate(system.contacts) if c.pair_index == split_pair}
            split_pair = None
            friction_modes = getattr(settle, "friction", None)
            if friction_modes is not None:  # each unit's friction mode from the run's modes and the state now
                friction_modes.start(ta, ta.state, ta.time)
                friction_modes.begin(ta.state.tolist())
                was = list(friction.modes)
                spins = friction_modes.spins(ta.state.tolist(), ta.time, was)
            # every body free and none touching: settle would leave the state as set (reduce and
            # expand are copies then), and the mode starts at full_state
            idle = (friction_modes is None and system.n_units == len(scene.bodies)
                    and getattr(settle, "idle", None) is not None and settle.idle(ta.state))
            settled = idle or settle(ta.state, ta.time, range(system.n_coordinates), None, skip_merge)
            if friction_modes is not None:  # the modes follow the rates collisions at the mode's start left
                friction_modes.reconcile(ta, ta.state, ta.time)
                fill_record_modes(log, friction.modes, stream.pair_bodies, was=was, spins=spins)
            if settled:
                if not idle:
                    full_state = system.expand(ta.state.tolist())
                    modes[-1] = ModeChange(modes[-1].t, modes[-1].clusters, tuple(_reported(turns, full_state)),
                                           modes[-1].pinned)
                overlap = _overlap(scene, precision, full_state, "at the start of a mode")
                if overlap:
                    log.stop.reason, log.stop.message = "overlap", overlap
                else:
                    optimized = _optimized_successor(system, options, cooldown, handlers, warnings, holder, stream) \
                        if quick else None
                    wind = Winder(turns, system.n_coordinates, log, friction,
                                  WIND_GROWTH if dense is None else WIND_DENSE, STEP_CHUNK) if winds else None
                    outcome, n_steps, ta = _propagate(
                        ta, log, precision.number(t_end), dense,
                        None if system.per_body or system.n_units == len(scene.bodies) else system.expand, optimized,
                        wind, turns)
                    if turns is not None:
                        turns.settle(ta.state)  # (a shift a Ctrl-C cut in two: see Turns.take)
                    steps += n_steps
            full_state = system.expand(ta.state.tolist())
            if friction_modes is not None:
                friction_modes.finish(ta.state)
            t = ta.dtime
            reason = log.stop.reason
            if reason in ("merge", "split", "release", "rest"):
                overlap = _overlap(scene, precision, full_state, "at the end of a mode")
                if overlap:
                    log.stop.reason, log.stop.message = "overlap", overlap
                    break
                same_instant = same_instant + 1 if float(t[0]) == modes[-1].t else 0
                if same_instant > MAX_CHANGES_AT_ONE_INSTANT * len(scene.bodies):
                    log.stop.reason = "failed"
                    log.stop.message = (
                        f"contacts kept merging and splitting at t = {float(t[0]):.17g} s "
                        f"({same_instant} mode changes at one instant); stopped"
                    )
                    break
            if reason == "merge" and system.per_body:
                contact = system.contacts[log.stop.data["contact"]]
                units = _join(scene, units, contact.unit_a, contact.unit_b)
                merged_pair = contact.pair_index
                contacts_open[(contact.pair.i, contact.pair.j)] = float(t[0])
            elif reason == "rest":
                u = system.unit_of[log.stop.data["body"]]
                units = units[:u] + (dataclasses.replace(units[u], pinned=log.stop.data["end"]),) + units[u + 1:]
            elif reason == "release":
                units, opened = _release(units, log.stop.data["bodies"])
                for i, j in opened:
                    intervals.append({"i": i + 1, "j": j + 1, "t_start": contacts_open.pop((i, j)), "t_end": float(t[0])})
            elif reason == "merge":
                contact = system.contacts[log.stop.data["contact"]]
                units, full_state = _merge(scene, system, units, contact, full_state, friction)
                contacts_open[(contact.pair.i, contact.pair.j)] = float(t[0])
            elif reason == "split":
                link = system.links[log.stop.data["link"]]
                units = _split(scene, units, link)
                i, j = link_bodies(system, link)
                split_pair = link.pair_index
                intervals.append({"i": i + 1, "j": j + 1, "t_start": contacts_open.pop((i, j)), "t_end": float(t[0])})
            else:
                break
            modes.append(ModeChange(float(t[0]), _clusters(units), tuple(_reported(turns, full_state)), _pinned(units)))
            log.mode_changes += 1
            if log.events_exhausted():
                break
        except KeyboardInterrupt:
            # Ctrl-C (or SIGTERM) outside the integration itself: while a mode compiles, between
            # modes. The run ends there, with everything recorded so far (as in _propagate).
            log.stop.reason = "interrupted"
            log.stop.message = (f"interrupted at t = {float(t[0]):.17g} s after {counted(log.count, 'collision')} "
                                "(between two stretches of integration)")
            break

    t_final = t[0] + t[1] if precision.name != "double" else float(t[0]) + float(t[1])
    for (i, j), t_start in contacts_open.items():
        intervals.append({"i": i + 1, "j": j + 1, "t_start": t_start, "t_end": float(t_final), "open": True})
    intervals.sort(key=lambda d: (d["t_start"], d["i"]))
    final_state = np.array(_reported(turns, full_state))  # (its messages give the angles reported)
    status, message = final_status(scene, precision, log, outcome, t_end, final_state, limit, events)
    total = log.count
    if sink is not None:
        stream.flush()
        stream.flush_passages()
        sink.close()
        kept = stream.kept or records_to_arrays([], len(scene.bodies), [] if scene.rough else None)
    else:
        if friction is not None:
            fill_record_modes(log, friction.modes, [(p.i, p.j) for p in scene.pairs])
        kept = stream.arrays()
    if progress is not None:
        progress(float(t_final), total)
    times, numbers, before, after, flags = kept[:5]
    return SimulationResult(
        scene=scene,
        status=status,
        message=message,
        precision=precision,
        t_final=t_final,
        initial_state=initial_state,
        final_state=final_state,
        times=times,
        pair_numbers=numbers,
        pairs=scene.pairs,
        states_before=before,
        states_after=after,
        law_flags=flags,
        wall_time_s=time.perf_counter() - started,
        steps=steps,
        settings={
            "tolerance": float(precision.epsilon if tolerance is None else tolerance),
            "high_accuracy": high_accuracy,
            "fast_math": opts.fast_math,
            "t_end": float(t_end),
            "max_collisions": limit,
            "max_events": events,
            "on_inconsistent": scene.on_inconsistent,
            # (with on_inconsistent = "error" the one that stopped the run counts too: it was 0 there)
            "inconsistent_collisions": log.fallbacks + (status is Status.INCONSISTENT),
            "track_sides": scene.track_sides,
            **({"simultaneous": scene.simultaneous} if scene.simultaneous != "sequential" else {}),
            "warnings": [log.warnings[k] for k in sorted(log.warnings)] + law_caveats(scene),
        },
        passages=tuple(log.passages) if stream.kept_passages is None else stream.kept_passages,
        passage_counts=(log.n_passages - log.limiter_impacts, log.limiter_impacts),
        dense=tuple(dense) if dense is not None else None,
        total_collisions=total,
        table_file=getattr(sink, "path", None) if sink is not None else None,
        contact_intervals=tuple(intervals),
        mode_changes=tuple(modes),
        transitions=_reported_items(turns, friction.transitions, 2) if friction is not None else (),
        collision_modes=kept[5] if len(kept) > 5 else None,
        collision_spins=kept[6] if len(kept) > 6 else None,
        final_modes=tuple(friction.modes) if friction is not None else (),
        final_slip=tuple(friction.slips) if friction is not None else (),
        friction_work=tuple(friction.work) if friction is not None else (),
        transition_work=tuple(friction.transition_work) if friction is not None else (),
        strobe=_reported_items(turns, log.strobe, 1),
    )


def law_caveats(scene) -> list:
    """What the scene's law does that a user may not expect, as run warnings (review: Newton's law gained
    0.17 J in one collision of a mixed three-body scene at k = 0.7, as documented, with no word in the output)."""
    if scene.law.name != "newton":
        return []
    bodies = scene.bodies
    unequal = [(p.i + 1, p.j + 1) for p in scene.pairs if bodies[p.i].kappa != bodies[p.j].kappa]
    if not unequal:
        return []
    i, j = unequal[0]
    return [f"collision.law = 'newton' keeps the centres' sum of 1/2 m v^2, not the rolling energy: bodies {i} and "
            f"{j}{' (and others)' if len(unequal) > 1 else ''} have different kappa, so a collision between them can "
            "gain energy at any k (use 'newton_generalized' or 'hedrih' to keep it; README, \"Collision laws\")"]


def _reported(turns, state) -> list:
    """A full state [phi_1..phi_N, dphi_1..dphi_N] in the run's angles, as reported: the whole turns put back."""
    return list(state) if turns is None else turns.angles(state, len(state) // 2)


def _reported_items(turns, items, kind: int) -> tuple:
    """Stroboscopic samples (kind 1) or friction transitions (kind 2), as reported (Turns.items)."""
    return tuple(items) if turns is None else turns.items(items, kind)


#: propagate_until is called for at most this many steps at a time, to see
#: that the integrator advances (see _propagate).
STEP_CHUNK = 1 << 16


def _propagate(ta, log, t_end, dense=None, expand=None, optimized=None, wind=None, turns=None):
    """propagate_until with the cyclic GC off and Ctrl-C turned into a clean stop: (outcome, steps, ta).

    In chunks of at most STEP_CHUNK steps: STEP_CHUNK steps in a row that leave
    the time where it was mean heyoka is stuck (measured: g = 1e29 with a track-force event makes
    it take zero-length steps for ever); the run then stops, status failed.
    ``optimized(ta)``: for a quickly compiled integrator, the optimized one
    that takes over, in the same state, after QUICK_STEPS steps. ``wind``: a
    simulation.turns.Winder, whole turns out of the angles after every
    ``wind.steps`` steps; ``turns``: the run's, for the dense output's angles.
    """
    steps = 0  # (the cyclic garbage collector is paused for the whole run: _collector_paused)
    still = 0  # steps that left the time where it was, in a row
    try:
        while True:
            before = ta.dtime
            t0 = ta.time
            chunk = QUICK_STEPS if optimized is not None else wind.steps if wind is not None else STEP_CHUNK
            if dense is None:
                result = ta.propagate_until(t_end, max_steps=chunk)
            else:
                result = ta.propagate_until(t_end, max_steps=chunk, c_output=True)
                if result[4] is not None:
                    dense.append((float(t0), float(ta.time), result[4], expand, turns.offset if turns else 0))
            steps += int(result[3])
            if result[0] != hy.taylor_outcome.step_limit:
                return result[0], steps, ta
            if wind is not None:
                wind(ta.state, int(result[3]))
            if optimized is not None:
                ta, optimized = optimized(ta), None
                continue
            still = still + chunk if ta.dtime == before else 0  # (zero-length steps: heyoka may not count them)
            if still >= STEP_CHUNK:
                log.stop.reason = "failed"
                log.stop.message = (
                    f"the integrator does not advance from t = {float(ta.time):.17g} s ({STEP_CHUNK} steps of "
                    "zero length): stopped"
                )
                return result[0], steps, ta
    except KeyboardInterrupt:
        # Ctrl-C (or SIGTERM turned into it by the CLI): keep every completed collision.
        log.stop.reason = "interrupted"
        log.stop.message = f"interrupted at t = {float(ta.time):.17g} s after {counted(log.count, 'collision')}"
        return None, steps, ta


def _reset(stop: StopRequest) -> None:
    stop.reason, stop.message, stop.data = None, "", {}


@functools.lru_cache(maxsize=256)
def _clusters(units) -> tuple:
    return tuple(tuple(k + 1 for k in u.members) for u in units if u.is_cluster)


def _pinned(units) -> tuple:
    return tuple((tuple(k + 1 for k in u.members), u.pinned) for u in units if u.pinned)


def _join(scene, units, a, b):
    """Units a and b (next to each other on an open track) become one; a stop holds it if it held either.

    Their rates are put on the contact at the start of the next mode
    (:func:`.resolve.constraints.project_onto_contacts`).
    """
    merged = cluster_unit(scene, units[a].members + units[b].members, pinned=units[a].pinned or units[b].pinned)
    return units[:a] + (merged,) + units[b + 1:]


def _release(units, bodies) -> tuple:
    """The units holding ``bodies`` fall apart into free bodies; returns (units, the contacts opened)."""
    out, opened = [], []
    for unit in units:
        if any(k in unit.members for k in bodies) and (unit.is_cluster or unit.pinned):
            out += singleton_units_of(unit.members)
            opened += list(zip(unit.members, unit.members[1:]))
        else:
            out.append(unit)
    return tuple(out), opened


#: A merge's plastic impulse on a path track changing no rate by more than this many ulps (of the largest rate,
#: double's) is round-off: no row (_record_merge).
MERGE_ROW_ULPS = 2**10


def _record_merge(scene, log, stream, friction, t, pair, before, after, slips) -> None:
    """A row for the plastic impulse that closes a new persistent contact on a path track (law_flag 2).

    The law acts on the rates along the paths, while the contact's gap rate is their projection on the line
    of centres: a merge after the last resolvable bounce still removes a gap rate by the impulse that puts
    the state on the constraints (constraints.project_onto_contacts), which had no row (review: 3e-5 J of a
    plastic pair of slipping disks on a parabola, up to 0.1 J on arc chains, missing from the energy
    account). Nothing where it changed the rates by round-off alone (MERGE_ROW_ULPS of the largest: rows of 0 J
    and 1e-15 J counted as collisions, review)."""
    n = len(scene.bodies)
    largest = max(abs(float(v)) for v in list(before[n:]) + list(after[n:]))
    if max(abs(float(b) - float(a)) for a, b in zip(before[n:], after[n:])) <= MERGE_ROW_ULPS * 2.0**-52 * largest:
        return
    log.records.append((t[0] + t[1], pair, list(before), None, list(after), 2))
    if friction is not None:  # its rows' modes, and the spins of slipping bodies (the impulse leaves them)
        spins = [float("nan")] * n
        for k in friction.slipping():
            spins[k] = float(scene.sigma(k, float(before[k]))) * float(before[n + k]) - float(slips[k])
        fill_record_modes(log, friction.modes, stream.pair_bodies, spins=spins)
    if len(log.records) >= log.chunk_size and log.on_full is not None:
        log.on_full()


def _merge(scene, system, units, contact, full_state, friction=None):
    """Units a and b become one cluster; their rates become the common rate (plastic).

    The generalized momentum sum G psi' is kept; what the remaining bounces
    would have dissipated (below the run's resolution) is dissipated here.
    On a rough track (``friction``: the run's FrictionState) a member that slips
    takes part with its translational inertia G / kappa, its spin unchanged: its
    slip changes by rho times its rate's jump.
    """
    a, b = contact.unit_a, contact.unit_b
    nb = len(scene.bodies)
    members = units[a].members + units[b].members
    slipping = friction.slipping() if friction is not None else {}
    G = [g / float(slipping[k]) if k in slipping else g for k, g in enumerate(system.gen_mass)]
    momentum = sum(G[k] * full_state[nb + k] for k in members)
    rate = momentum / sum(G[k] for k in members)
    merged = cluster_unit(scene, members)
    first = full_state[members[0]]
    for k, o in zip(members, merged.offsets):
        full_state[k] = first + system.precision.number(o)
        if k in slipping:  # (the circle: sigma = rho, constant)
            friction.slips[k] = friction.slips[k] + system.precision.number(scene.sigma(k)) * (rate - full_state[nb + k])
        full_state[nb + k] = rate
    if b == 0:  # across the top: the merged unit comes first, others keep their order
        new_units = (merged,) + tuple(units[1:a])
    else:
        new_units = tuple(units[:a]) + (merged,) + tuple(units[b + 1:])
    return new_units, full_state


def _split(scene, units, link):
    unit = units[link.unit]
    m = link.position
    left, right = unit.members[: m + 1], unit.members[m + 1:]
    left = cluster_unit(scene, left) if len(left) > 1 else Unit(left, (mpmath.mpf(0),))
    right = cluster_unit(scene, right) if len(right) > 1 else Unit(right, (mpmath.mpf(0),))
    return _canonical(tuple(units[: link.unit]) + (left, right) + tuple(units[link.unit + 1:]))


def _canonical(units):
    """The units in circular order starting from the one that holds body 1.

    The order is what the compiled system and the state layout follow; with
    no cluster it must be bodies 1..N (the free-mode state is the body
    state). A contact across the top (bodies N, 1) that splits leaves (N),
    (1), ...: rotated here to (1), ..., (N).
    """
    first = next(n for n, u in enumerate(units) if 0 in u.members)
    return tuple(units[first:]) + tuple(units[:first])


@dataclass(frozen=True)
class _Start:
    """How a run of a scene starts: the same for every run of it (cached by :func:`_start`)."""

    initial_state: tuple
    units: tuple
    state: tuple  # after the bodies that start pressed together were merged
    system: SceneSystem
    pieces: tuple  # the piece of track each body is on (open tracks)
    limit: tuple | None  # a body the track cannot hold at the start: (reason, message)


@by_scene(keep=64)
def _start(scene: Scene, precision: Precision, watch_all_contacts: bool) -> _Start:
    """Everything before a run's first step that depends on the scene alone: computed once per
    scene (a benchmark's repeated runs of one scene skip it)."""
    pairs = scene.pairs if watch_all_contacts else None
    num = float if precision.name == "double" else precision.number  # (the same rounding, one call less)
    full_state = [num(x) for x in scene.phi] + [num(x) for x in scene.dphi]
    initial_state = tuple(full_state)
    units = singleton_units(len(scene.bodies))
    system = build_system(scene, precision, pairs=pairs, units=units)
    if scene.track.linear_gap:
        units, full_state = _initial_contacts(scene, precision, pairs, units, full_state, system)
    if any(u.is_cluster for u in units):
        system = build_system(scene, precision, pairs=pairs, units=units)
    pieces = (0,) * len(scene.bodies) if scene.track.linear_gap else \
        tuple(piece_of(scene.track, b, q) for b, q in zip(scene.bodies, scene.q))  # (a circle is one piece)
    return _Start(initial_state, units, tuple(full_state), system, pieces,
                  _track_limit_at_start(scene, system, full_state))


def _initial_contacts(scene, precision, pairs, units, full_state, system=None):
    """Bodies that start touching at rest, pressed together, start in contact (with friction or
    forcing the settler judges them at the mode's start, with the compiled accelerations)."""
    if scene.rough or scene.forcing is not None:
        return units, full_state
    system = system or build_system(scene, precision, pairs=pairs, units=units)
    nb = len(scene.bodies)
    eps = precision.epsilon
    unit_state = system.reduce(full_state)
    constants = system.gap_constants
    for number, contact in enumerate(system.contacts):
        p = contact.pair
        a, b = contact.unit_a, contact.unit_b
        gap = unit_state[b] - unit_state[a] + constants[number]  # (gap_value, inlined: every run's start)
        rate = full_state[nb + p.j] - full_state[nb + p.i]
        scale = 1 + abs(full_state[p.i]) + abs(full_state[p.j])
        if gap <= 4 * eps * scale and abs(rate) <= 4 * eps * (abs(full_state[nb + p.i]) + abs(full_state[nb + p.j]) + 1):
            acc = unit_acceleration(system, b, unit_state[b]) - unit_acceleration(system, a, unit_state[a])
            if acc < 0:
                units, full_state = _merge(scene, system, units, contact, full_state)
                return _initial_contacts(scene, precision, pairs, units, full_state)
    return units, full_state


@by_constants()
def motion_time_scale(scene: Scene) -> float:
    """The motion's time scale (s): 1/sqrt of the stiffest body's g/(kappa rho) on a circle,
    sqrt(L/g) on an open track of length L (the longest body's range)."""
    track = scene.track
    if track.linear_gap:
        return 1 / math.sqrt(max(float(track.angular_stiffness(b, scene.g)) for b in scene.bodies))
    length = max(float(hi - lo) for lo, hi in (track.domain(b) for b in scene.bodies))
    return math.sqrt(max(length, 1e-300) / float(scene.g))


def _track_limit_at_start(scene: Scene, system: SceneSystem, state) -> tuple[str, str] | None:
    """A body that starts where the track cannot hold it (one-sided, N < 0) or where it slips.

    Events only see later crossings, so the start is checked here, with the
    same forces as the events (see system._track_events), in the run's type.
    """
    n = len(scene.bodies)
    if scene.track_sides != "one":  # nothing to check (the usual case; a rough track's modes start in friction)
        return None
    function = body_function(system)
    if function is None:
        return None
    values = evaluate(function, system.reduce(list(state)), system.parameters).tolist()
    for k in range(n):
        message = left_track_message(scene, values, k, state[k], state[n + k], 0)
        if message is not None:
            return "left_track", message
    return None


def records_to_arrays(records: list, n_bodies: int, modes: list | None = None) -> tuple:
    """Raw callback records -> (times, pair_numbers, states_before, states_after, flags).

    A record is (t, pair number, full state before, rate_i, rate_j, flag) on the
    hot path (only bodies i and j change), or (t, pair number, state before,
    None, full state after, flag) when clusters move. Columns are built from one
    transposition of the records (a run of 30 collisions spent 40 us here in
    per-record loops).
    """
    n, nb = len(records), n_bodies
    # Rough tracks: a sixth and a seventh array, the friction modes of each collision's bodies and
    # the speed every body's spin would roll at where it slips (events.CollisionLog.record_modes).
    extra = () if modes is None else (np.array([m[:4] for m in modes], dtype="U8").reshape(n, 4),
                                      np.array([m[4:] for m in modes], dtype=float).reshape(n, n_bodies))
    if not n:
        empty = np.zeros((0, 2 * nb))
        return (np.zeros(0), np.zeros(0, dtype=np.int64), empty, empty.copy(), np.zeros(0, dtype=np.int64)) + extra
    t, number, state, rate_i, rate_j, flag = zip(*records)
    # np.fromiter with a count: a third of np.array's time on a tuple of numbers or a list of lists (a
    # batch of 100-collision runs spent ~12% of its time here, measured)
    double = type(t[0]) is float
    times = np.fromiter(t, float, count=n) if double else np.array(t)
    numbers = np.fromiter(number, np.int64, count=n)
    flags = np.fromiter(flag, np.int64, count=n)
    width = 2 * nb
    if double and type(state[0][0]) is float and sum(map(len, state)) == n * width:  # no slip velocities
        before = np.fromiter(itertools.chain.from_iterable(state), float, count=n * width).reshape(n, width)
    else:  # the fast path's states carry slip velocities after the rates (rough tracks)
        before = np.array([r[:width] for r in state]).reshape(n, width)
    after = before.copy()
    if None not in rate_i:  # every record from the hot path
        bodies = pair_bodies(nb)[numbers]
        flat = after.reshape(-1)  # (a view: flat indices cost less than row and column ones)
        rates = np.arange(nb, n * width, width)  # each row's first rate
        if double and type(rate_i[0]) is float:
            rate_i, rate_j = np.fromiter(rate_i, float, count=n), np.fromiter(rate_j, float, count=n)
        flat[rates + bodies[:, 0]] = rate_i
        flat[rates + bodies[:, 1]] = rate_j
        return (times, numbers, before, after, flags) + extra
    fast = np.array([k for k, r in enumerate(rate_i) if r is not None], dtype=np.int64)
    if fast.size:
        bodies = pair_bodies(nb)[numbers[fast]]
        after[fast, nb + bodies[:, 0]] = [rate_i[k] for k in fast]
        after[fast, nb + bodies[:, 1]] = [rate_j[k] for k in fast]
    for k, r in enumerate(rate_i):
        if r is None:
            after[k] = rate_j[k][: 2 * nb]
    return (times, numbers, before, after, flags) + extra


@functools.lru_cache(maxsize=64)
def pair_bodies(n_bodies: int) -> np.ndarray:
    """Body indices (i, j) of scene pair number p: (p, p + 1), and (N - 1, 0) for the last (read-only)."""
    n = n_bodies
    out = np.array([(p, p + 1) for p in range(n - 1)] + ([(n - 1, 0)] if n > 1 else []), dtype=np.int64).reshape(-1, 2)
    out.flags.writeable = False
    return out


class _Stream:
    """Hands collision records on to a sink in chunks and reports progress."""

    def __init__(self, log, sink, progress, n_bodies):
        self.log, self.sink, self.progress, self.n_bodies = log, sink, progress, n_bodies
        self.kept: tuple | None = None  # the first chunk stays in memory for figures
        self.kept_passages: tuple | None = None  # the same for passages, if the sink takes them
        self.turns = None  # the circle's whole turns taken out of the angles (simulation.turns)
        self.last_report = time.perf_counter()
        self.ta = None

    def flush(self) -> None:
        log = self.log
        if self.sink is None or not log.records:
            return
        if log.record_modes is not None:
            fill_record_modes(log, self.friction.modes, self.pair_bodies)
        chunk = self.arrays()
        rows = getattr(self.sink, "rows", None)
        # Ctrl-C or SIGTERM during the write waits for its end (measured: a signal between the
        # sink's write and its row count left a chunk in the file twice).
        with signals_deferred():
            try:
                self.sink.write(chunk, first_number=log.flushed + 1)
            except BaseException:
                # An interruption raised by the sink itself: a chunk it took (its row count moved)
                # must not be written again by the final flush, one it did not take must.
                if rows is not None and self.sink.rows > rows:
                    self._taken(chunk)
                raise
            self._taken(chunk)

    def flush_passages(self) -> None:
        """Hand the passages on to the sink (``write_passages``), keeping the first chunk in memory."""
        log = self.log
        if not log.passages or not hasattr(self.sink, "write_passages"):
            return
        table = passage_table(log.passages, first_number=log.passages_flushed + 1,
                              native=getattr(getattr(self.sink, "precision", None), "name", "double") != "double")
        with signals_deferred():  # as for collisions: a chunk is written once
            self.sink.write_passages(table)
            if self.kept_passages is None:
                self.kept_passages = tuple(log.passages)
            log.passages_flushed += len(log.passages)
            log.passages.clear()

    def arrays(self) -> tuple:
        """records_to_arrays of the log's records (those not handed on yet), the whole turns put back."""
        log = self.log
        arrays = records_to_arrays(log.records, self.n_bodies, log.record_modes)
        return arrays if self.turns is None else self.turns.records(arrays, log.flushed, self.n_bodies)

    def _taken(self, chunk) -> None:
        log = self.log
        if self.kept is None:
            self.kept = chunk
        log.flushed += len(log.records)
        log.records.clear()
        if log.record_modes is not None:
            log.record_modes.clear()

    def on_full(self) -> None:
        if self.sink is not None:
            self.flush()
        else:  # progress only: keep every record, look again 1024 collisions later
            self.log.chunk_size += 1024
        if self.progress is not None and time.perf_counter() - self.last_report > 0.2:
            self.last_report = time.perf_counter()
            self.progress(float(self.ta.time), self.log.count)


@contextlib.contextmanager
def signal_handled(signum, handler):
    """``handler`` for signal ``signum`` during the block, the previous one after (main thread only: elsewhere
    the block runs with the handlers as they are)."""
    try:
        previous = signal.signal(signum, handler)
    except ValueError:  # not the main thread
        yield
        return
    try:
        yield
    finally:
        signal.signal(signum, previous)


@contextlib.contextmanager
def signals_deferred():
    """SIGINT and SIGTERM wait until the block ends, then go to their handlers (main thread only)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    pending: list = []
    saved = {}
    for sig in (signal.SIGINT, signal.SIGTERM):
        saved[sig] = signal.getsignal(sig)
        signal.signal(sig, lambda signum, frame: pending.append((signum, frame)))
    try:
        yield
    finally:
        for sig, handler in saved.items():
            signal.signal(sig, handler)
        for signum, frame in pending[:1]:
            handler = saved[signum]
            if callable(handler):
                handler(signum, frame)
            elif handler == signal.SIG_DFL:
                signal.raise_signal(signum)  # the default action (terminate), now that the write is whole


def final_status(scene, precision, log, outcome, t_end, final_state, limit, events) -> tuple[Status, str]:
    """How a run ended, (status, message): its stop or the integrator's outcome, an overlap found in the
    final state, and the collisions the policy resolved by Newton's law."""
    if log.stop.reason == "max_collisions" and events is not None and log.count >= events and (
            limit is None or limit > events):
        log.events_exhausted()  # the collisions reached max_events, not max_collisions
    status, message = _status(log, outcome, t_end)
    if status.success:
        overlap = _overlap(scene, precision, final_state, "at the end of the run")
        if overlap:
            status, message = Status.OVERLAP, overlap
    if log.fallbacks and status.success:
        message += (
            f"; {counted(log.fallbacks, 'collision')} left the bodies approaching under the '{scene.law.name}' law and "
            f"{'was' if log.fallbacks == 1 else 'were'} "
            "resolved by Newton's law on the gap rate (law_flag = 1)"
        )
    return status, message


def run_limits(scene, opts) -> tuple:
    """(t_end, max_collisions, max_events, the collision count that stops the run) of ``opts`` for
    ``scene`` (its [run] settings where the options leave them)."""
    t_end = scene.run.t_end if opts.t_end is None else opts.t_end
    limit = scene.run.max_collisions if opts.max_collisions is ... else opts.max_collisions
    events = DEFAULT_MAX_EVENTS if opts.max_events is ... else opts.max_events
    # Collisions stop at whichever limit comes first; passages and mode changes check max_events.
    return t_end, limit, events, limit if events is None else events if limit is None else min(limit, events)


def _status(log, outcome, t_end) -> tuple[Status, str]:
    reason = log.stop.reason
    if reason == "max_collisions":
        return Status.MAX_COLLISIONS, log.stop.message
    if reason == "max_events":
        return Status.MAX_EVENTS, log.stop.message
    if reason == "inconsistent":
        return Status.INCONSISTENT, log.stop.message
    if reason == "interrupted":
        return Status.INTERRUPTED, log.stop.message
    if reason == "left_track":
        return Status.LEFT_TRACK, log.stop.message
    if reason == "overlap":
        return Status.OVERLAP, log.stop.message
    if reason == "failed":
        return Status.FAILED, log.stop.message
    if outcome == hy.taylor_outcome.time_limit:
        return Status.COMPLETED, f"reached t_end = {float(t_end)!r} s after {counted(log.count, 'collision')}"
    return Status.FAILED, f"the integrator stopped with outcome {outcome!s}"


@by_constants()
def _gap_constants(scene: Scene) -> tuple[float, ...]:
    """offset - beta of each pair as a float (linear gaps; converted once per scene)."""
    return tuple(float(p.gap_constant()) for p in scene.pairs) if scene.track.linear_gap else (None,) * len(scene.pairs)


@by_constants()
def _overlap_geometry(scene: Scene) -> tuple:
    """((i, j, gap constant or None) of each pair, each body's domain or None): what _overlap reads,
    converted once per scene constants (it runs at every mode's start and end)."""
    return (tuple((p.i, p.j, c) for p, c in zip(scene.pairs, _gap_constants(scene))),
            tuple((k, d) for k, d in enumerate(scene.domain(k) for k in range(len(scene.bodies))) if d is not None))


def _overlap(scene: Scene, precision: Precision, state, where: str) -> str:
    """A message if a pair's gap is below -overlap_tolerance in ``state`` (a full state), else ''."""
    pairs, domains = _overlap_geometry(scene)
    for i, j, constant in pairs:
        if constant is not None:
            gap = float(state[j]) - float(state[i]) + constant
            unit = "rad"
        else:
            gap = float(scene.gap(i, j, float(state[i]), float(state[j])))
            unit = "m"
        if gap < -overlap_tolerance(state[j]):
            return f"bodies {i + 1} and {j + 1} overlap {where} (gap {gap:.3g} {unit}): a collision was missed"
    for k, domain in domains:
        q = float(state[k])
        if q < domain[0] - overlap_tolerance(q) or q > domain[1] + overlap_tolerance(q):
            return (f"body {k + 1} is beyond the end of the track {where} ({scene.coordinate} = {q:.17g}): "
                    "a limiter impact was missed")
    return ""


#: Integrators already built, by shape (see SceneSystem.shape) and options:
#: a run reuses one with its own parameters, state and handlers.
_INTEGRATORS = CompiledCache(32)


#: From this many bodies on, every mode is compiled in compact mode. Compilation in
#: heyoka's default mode grows like N^2 (measured on a circle, double: 1.5 s for 8 bodies,
#: 15.5 s for 32, about a minute for 64) and compact mode stays under a second, for
#: 1.4-1.8x the cost per step (measured with the same systems: 79 against 45 us for 8 bodies,
#: 1.75 against 1.23 ms for 32, per 2 s of motion). validation/many_bodies.py has the
#: resulting cost per collision and compile time against N. Up to 16 bodies the default
#: mode's compilation (3.8 s for 16, once per scene shape; heyoka also keeps it on disk)
#: is worth its faster steps on runs of many collisions.
COMPACT_FROM_BODIES = 17


def _compact(system: SceneSystem) -> bool:
    """Whether ``system`` is compiled in heyoka's compact mode."""
    if system.n_bodies >= COMPACT_FROM_BODIES:
        return True
    # Friction and forcing on a path track multiply its decomposition: optimized, three bodies compiled in
    # 58 s and four in 95 s; compact, 7 s and 4 s, for 1.7x the cost per step (measured on a forced rough
    # ellipse; heyoka caches a compiled shape on disk, so a sweep pays it once).
    if system.per_body and system.friction_blocks and system.strobe_expression is not None and \
            system.n_bodies >= 3:
        return True
    # A cluster on a path track (contact forces solved in the equations) has a large
    # decomposition: compact mode compiles it ~10x faster (measured 0.8 s against 8.4 s
    # for two disks on a parabola) for ~2x the cost per step, in a mode that is rarely long.
    return system.per_body and any(u.is_cluster or u.pinned for u in system.units)


#: A mode compiled quickly (compact mode, no LLVM optimization: ~10x faster to
#: compile, 2-3x slower per step) that lasts this many steps is compiled
#: optimized and goes on with that. Modes after the first are often short (a
#: cluster that splits again, a contact of a many-body cascade): measured on 16
#: bodies in a circle, 16 modes cost 6.3 s of compilation for 1 s of integration.
#: A step count, not a time, so that a run is the same every time.
QUICK_STEPS = 4096


def _integrator_key(system: SceneSystem, options: dict, cooldown, quick: bool) -> tuple:
    """The integrator cache's key, made once per system and options (~1 us of every run's set-up, measured)."""
    tol, high, fast = options.get("tol"), options["high_accuracy"], options.get("fast_math", False)
    memo = _KEYS.get((id(system), high, fast, quick))
    if memo is not None and memo[0] is system and memo[1] == tol and memo[2] == cooldown:
        return memo[3]
    key = (system.shape, repr(tol), high, fast, repr(cooldown), quick)
    if len(_KEYS) > 1024:  # a bound on memory
        _KEYS.clear()
    _KEYS[(id(system), high, fast, quick)] = (system, tol, cooldown, key)
    return key


#: _integrator_key's keys by system (held: its id cannot be another's meanwhile) and options
_KEYS: dict = {}


def _optimized_successor(system: SceneSystem, options: dict, cooldown, handlers, warnings, holder, stream):
    """For a quickly compiled mode: ``optimized(ta)``, the optimized integrator taking over from ``ta``."""

    def optimized(old):
        new, slots, nt_slots = _integrator(system, options, cooldown)
        slots[:], nt_slots[:] = handlers, warnings
        new.pars[:] = old.pars  # as the junction callbacks left them
        new.state[:] = old.state
        new.dtime = old.dtime
        new.reset_cooldowns()
        holder[0], stream.ta = new.state, new
        return new

    return optimized


def _integrator(system: SceneSystem, options: dict, cooldown, quick: bool = False):
    """(taylor_adaptive, slots, nt_slots) for ``system``'s shape, built once and reused.

    ``quick``: compiled in compact mode without LLVM optimization (see QUICK_STEPS).
    """

    def build():
        slots: list = []
        nt_slots: list = []
        events, nt_events = mode_events(system, cooldown, slots, nt_slots)
        if quick:
            level = {"compact_mode": True, "opt_level": 0}
        else:
            level = {"compact_mode": True} if _compact(system) else {}
        ta = hy.taylor_adaptive(
            system.equations, [system.precision.number(0)] * len(system.equations), t_events=events, nt_events=nt_events, **level, **options,
        )
        return ta, slots, nt_slots

    return _INTEGRATORS.get(_integrator_key(system, options, cooldown, quick), build)
