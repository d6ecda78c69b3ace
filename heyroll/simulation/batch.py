"""Many scenes of one shape advanced together by heyoka's batch (SIMD) integrator (issue 16, item 3).

heyoka's batch mode integrates B copies of one system at once (B = its
recommended SIMD width, 4 doubles with AVX2), each copy with its own state,
parameters, time, step size and events. Here each copy is one scene: the
collision callbacks, the contact criterion and the reopening check are those
of a scalar run (events.mode_handlers), one set per batch element (built once
per element and scene constants, as a scalar run's: driver._handlers), and a
scene that stops (max_collisions, t_end) leaves its element to the next one.

What runs here: double precision, a circle in a fixed plane, no friction and
no forcing, every body free for the whole run, gap events and the two-sided
track's warnings (the engine's circle hot path). A scene this path cannot run as a scalar run would (it
starts in contact, it would enter persistent contact, a collision was
missed, the integrator failed, options it does not take) runs through
:func:`heyroll.simulation.driver.simulate` instead, from its start: the
result is then the scalar one, and says so in ``settings["batch"]``.

Not the same bits as a scalar run: heyoka's batch code evaluates the Taylor
polynomials in vector registers, and its rounding differs from the scalar
code's in the last bit now and then (measured: x'' = -x, identical steps,
the state one ulp apart after 25 steps). Collision times of a batch run agree
with the scalar run's to a few ulps at first; a chaotic motion then takes
the two apart as it takes any two runs apart. validation/sweep_speed.py
measures the largest difference.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import heyoka as hy
import numpy as np

from ..model.table import is_table
from .compiled_cache import CompiledCache
from .driver import (
    HANDLER_SETS, STEP_CHUNK, ModeChange, RunOptions, _collector_paused, _handlers, _overlap, _start, final_status,
    law_caveats,
    motion_time_scale,
    records_to_arrays, run_limits, simulate,
)
from .events import CollisionLog
from .result import SimulationResult
from .system import energy_reach
from .turns import WIND_STEPS, Turns

#: Batch integrators already built, by system shape, width and cooldown.
_BATCHES = CompiledCache(8)


def batch_reason(scene, options: RunOptions) -> str:
    """'' where the batch path runs ``scene`` with ``options``; else why it runs scalar (one line)."""
    return _batch_start(scene, options)[1]


def _batch_start(scene, options: RunOptions) -> tuple:
    """(the scene's start (driver._start), ''), or (None, why it runs scalar). A batch asks once per
    scene: _start's memo keeps the last 64 scenes only, and a second pass over thousands of scenes
    built each start twice (measured: a fifth of a 100-collision scene's batch time)."""
    if is_table(scene):
        return None, "a table scene (billiards) runs on the table engine"
    if options.precision.name != "double":
        return None, f"heyoka's batch mode is double precision; this run is {options.precision.name}"
    if options.dense or options.watch_all_contacts or options.fast_math or options.high_accuracy \
            or options.tolerance is not None:
        return None, "dense output, watch_all_contacts, fast_math, high_accuracy and tolerance run scalar"
    if not scene.track.linear_gap or scene.frame.rotating or scene.forcing is not None or scene.rough:
        return None, "only a circle in a fixed plane without friction or forcing runs in batch"
    start = _start(scene, options.precision, False)
    if start.limit or any(u.is_cluster for u in start.units):
        return None, "the scene starts in contact or where the track cannot hold it"
    system = start.system
    if (system.guard_expressions or any(ev.terminal for ev in system.track_events) or system.links
            or system.bound_events or system.release_events or system.strobe_expression is not None
            or system.friction_blocks or not system.gap_reopening):
        return None, "its events are not the gap events and track warnings alone (one-sided track, limiters, guards)"
    return start, ""


@dataclass
class _Point:
    """A scene in a batch element: its run's log, handlers and state view."""

    number: int
    scene: object
    system: object
    log: CollisionLog
    holder: list
    handlers: list
    started: float
    turns: Turns
    steps: int = 0
    initial_state: np.ndarray = field(default=None)


class _Element:
    """What a scalar run's callbacks read of the integrator (its time), for one batch element.

    heyoka's batch time arrays are live views of its buffers: read once, indexed at every event
    (ta.dtime builds the two views anew: 1.3 us, measured, a collision's third)."""

    __slots__ = ("ta", "hi", "lo", "index")

    def __init__(self, ta, index: int):
        self.ta, (self.hi, self.lo), self.index = ta, ta.dtime, index

    @property
    def dtime(self) -> tuple:
        return float(self.hi[self.index]), float(self.lo[self.index])

    @property
    def time(self) -> float:
        return float(self.hi[self.index])

    def update_d_output(self, t):
        """The element's state at time t of its last step (the others' at their own time)."""
        times = np.array(self.ta.time)
        times[self.index] = t
        return self.ta.update_d_output(times)[:, self.index]


def simulate_batch(scenes, options: RunOptions | None = None, *, width: int | None = None) -> list[SimulationResult]:
    """Run ``scenes`` (any mix) and return their results in order, with the options of one
    :func:`simulate` each. Scenes the batch path takes (:func:`batch_reason`) share batch
    integrators of ``width`` elements (default heyoka.recommended_simd_size()), one per system shape;
    the others run through :func:`simulate`. ``settings["batch"]`` of each result says which.
    """
    options = options or RunOptions()
    width = width or hy.recommended_simd_size()
    results: list = [None] * len(scenes)
    groups: dict = {}
    starts: dict = {}
    for number, scene in enumerate(scenes):
        start, why = _batch_start(scene, options)
        if why:
            results[number] = _scalar(scene, options, why)
            continue
        starts[number] = start
        cooldown = options.precision.epsilon * motion_time_scale(scene)
        groups.setdefault((start.system.shape, cooldown), []).append(number)
    for (shape, cooldown), numbers in groups.items():
        _run_group([scenes[n] for n in numbers], [starts.pop(n) for n in numbers], numbers, options, width, cooldown,
                   results)
    return results


def _scalar(scene, options, why: str) -> SimulationResult:
    result = simulate(scene, options)
    result.settings["batch"] = f"scalar: {why}"
    return result


def _run_group(scenes, starts, numbers, options, width, cooldown, results) -> None:
    """The scenes of one shape (``starts``: their driver._start) through one batch integrator, each element
    taking the next scene."""
    ta, slots = _batch_integrator(starts[0].system, width, cooldown)
    # Whole turns out of the angles as in a scalar run (simulation.turns): one energy reach for the group
    n_coordinates = starts[0].system.n_coordinates
    chunk = WIND_STEPS if any(energy_reach(scenes[0]).top_half) else STEP_CHUNK
    t_end_of = [float(run_limits(s, options)[0]) for s in scenes]
    queue = list(range(len(scenes)))
    queue.reverse()
    running: list = [None] * width
    # One log per element, reset for each scene it takes, with the handlers built on it by system and scene
    # constants (driver._handlers, as a scalar run's): a scene's handlers cost ~40 us to build (measured)
    logs = [CollisionLog(handler_sets=CompiledCache(HANDLER_SETS)) for _ in range(width)]
    hi, lo = (np.array(a) for a in ta.dtime)
    targets = np.zeros(width)

    def load(index: int) -> None:
        """The next scene of the queue into element ``index`` (or the element idles at its time)."""
        while queue:
            k = queue.pop()
            point = _load(scenes[k], starts[k], numbers[k], index, ta, slots, options, logs[index])
            starts[k] = None  # (a start holds the scene's initial numbers: let it go with the scene's run)
            if point is None:  # its start needs the scalar engine's modes
                results[numbers[k]] = _scalar(scenes[k], options, "it starts with a contact to settle")
                continue
            running[index] = (k, point)
            hi[index], lo[index] = 0.0, 0.0
            ta.set_dtime(hi, lo)
            targets[index] = t_end_of[k]
            return
        running[index] = None
        targets[index] = ta.time[index]

    with _collector_paused():  # as a scalar run: the logs grow by small lists, no cycles
        for index in range(width):
            hi, lo = (np.array(a) for a in ta.dtime)
            load(index)
        while any(r is not None for r in running):
            ta.propagate_until(targets, max_steps=chunk)
            hi, lo = (np.array(a) for a in ta.dtime)
            if chunk == WIND_STEPS:
                state = ta.state
                for index, run in enumerate(running):
                    if run is not None:
                        run[1].turns.take(state[:, index], n_coordinates, run[1].log)
            for index, (outcome, _hmin, _hmax, steps) in enumerate(ta.propagate_res):
                if running[index] is None:
                    continue
                k, point = running[index]
                point.steps += int(steps)
                stop = point.log.stop.reason
                failed = outcome == hy.taylor_outcome.err_nf_state or (
                    outcome == hy.taylor_outcome.step_limit and steps == 0)
                if stop is None and not failed and hi[index] < targets[index]:
                    # On its way: STEP_CHUNK steps a call, or another element's run stopped the batch's.
                    continue
                if stop == "max_collisions" or (stop is None and not failed):
                    results[numbers[k]] = _result(point, ta, index, hy.taylor_outcome.time_limit, t_end_of[k],
                                                  options)
                else:  # persistent contact, a missed collision, an integrator failure: the scalar engine's
                    results[numbers[k]] = _scalar(scenes[k], options,
                                                  f"the batch run stopped ({stop or outcome!s})")
                load(index)


def _load(scene, start, number, index, ta, slots, options, log):
    """Element ``index`` set to ``scene``'s start (driver._start) and its callbacks (built on ``log``, the
    element's, reset here); None where the start settles contacts."""
    precision = options.precision
    system = start.system
    _t_end, limit, events, collision_limit = run_limits(scene, options)
    log.reset(collision_limit, events, None)
    element = _Element(ta, index)
    holder, handlers, warnings, settle = _handlers(scene, system, log, motion_time_scale(scene), list(start.pieces),
                                                   None)
    params = system.parameters
    ta.pars[:, index] = params[: ta.pars.shape[0]]
    ta.state[:, index] = system.reduce(list(start.state)) + [0.0] * system.n_extra
    holder[0], holder[1] = ta.state[:, index], np.array(params)
    touched = getattr(settle, "touched", [])
    touched[:] = [(0.0, 0.0)] * len(touched)
    ta.reset_cooldowns(index)
    turns = log.turns = Turns(precision)  # (as at a scalar mode's start)
    turns.take(ta.state[:, index], system.n_coordinates, log)
    if limit == 0:
        return None
    # as a scalar run's first mode (driver._run): with no pair touching the settler would leave the state
    if not (settle.idle(holder[0]) or settle(holder[0], 0.0, range(system.n_coordinates), None, set())) \
            or log.records or log.stop.reason \
            or _overlap(scene, precision, system.expand(holder[0].tolist()), "at the start of a mode"):
        return None
    slots[0][index] = [(h, element) for h in handlers]
    slots[1][index] = [(h, element) for h in warnings]
    return _Point(number=number, scene=scene, system=system, log=log, holder=holder, handlers=handlers,
                  started=time.perf_counter(), turns=turns, initial_state=np.array(start.initial_state))


def _result(point: _Point, ta, index: int, outcome, t_end: float, options) -> SimulationResult:
    """A scalar run's result for the scene that ran in element ``index``."""
    scene, log, precision = point.scene, point.log, options.precision
    hi, lo = ta.dtime
    t_final = float(hi[index]) + float(lo[index])
    full_state = point.system.expand(ta.state[:, index].tolist())
    _t_end, limit, events, _collisions = run_limits(scene, options)
    final_state = np.array(point.turns.angles(full_state, len(scene.bodies)))
    status, message = final_status(scene, precision, log, outcome, t_end, final_state, limit, events)
    times, numbers, before, after, flags = point.turns.records(records_to_arrays(log.records, len(scene.bodies)), 0,
                                                               len(scene.bodies))
    return SimulationResult(
        scene=scene, status=status, message=message, precision=precision, t_final=t_final,
        initial_state=point.initial_state, final_state=final_state, times=times, pair_numbers=numbers,
        pairs=scene.pairs, states_before=before, states_after=after, law_flags=flags,
        wall_time_s=time.perf_counter() - point.started, steps=point.steps,
        settings={"tolerance": float(precision.epsilon), "high_accuracy": False, "fast_math": False,
                  "t_end": float(t_end), "max_collisions": limit, "max_events": log.max_events,
                  "on_inconsistent": scene.on_inconsistent, "inconsistent_collisions": log.fallbacks,
                  "track_sides": scene.track_sides,
                  **({"simultaneous": scene.simultaneous} if scene.simultaneous != "sequential" else {}),
                  "warnings": [log.warnings[k] for k in sorted(log.warnings)] + law_caveats(scene),
                  "batch": f"batch of {ta.batch_size} (heyoka SIMD)"},
        total_collisions=log.count, passage_counts=(0, 0),
        mode_changes=(ModeChange(0.0, (), tuple(point.initial_state)),),
    )


def _batch_integrator(system, width: int, cooldown: float):
    """(taylor_adaptive_batch, (terminal, warnings)) for ``system``'s shape: gap events whose callbacks
    call ``handler(element, d_sgn)`` for ``terminal[index][n] = (handler, element)``, and track warnings
    ``handler(element, t, d_sgn)`` from ``warnings[index][n]`` (each element's own run's handlers and
    its view of the integrator)."""

    def build():
        terminal: list = [[] for _ in range(width)]
        warnings: list = [[] for _ in range(width)]

        def forward(n):
            def call(ta, d_sgn, index):
                handler, element = terminal[index][n]
                return handler(element, d_sgn)

            return call

        def forward_nt(n):
            def call(ta, t, d_sgn, index):
                handler, element = warnings[index][n]
                handler(element, t, d_sgn)

            return call

        # As events.mode_events: the gaps both ways (SceneSystem.gap_reopening), the track's normal force
        # changing sign as a warning (a two-sided track).
        events = [hy.t_event_batch(gap, callback=forward(n), direction=hy.event_direction.any, cooldown=cooldown)
                  for n, gap in enumerate(system.gap_expressions)]
        nt_events = [hy.nt_event_batch(x, callback=forward_nt(n), direction=hy.event_direction.negative)
                     for n, x in enumerate(system.track_expressions)]
        ta = hy.taylor_adaptive_batch(system.equations, np.zeros((len(system.equations), width)), t_events=events,
                                      nt_events=nt_events)
        return ta, (terminal, warnings)

    return _BATCHES.get((system.shape, width, repr(cooldown)), build)
