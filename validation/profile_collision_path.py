"""Where the time of a collision goes: integration, event detection, the callback.

    python validation/profile_collision_path.py [--t-end 20000] [--repeat 3] [--output PATH]

Runs the default scene three ways over the same time span, one core:
(a) the bare equations of motion (no events): the cost of the Taylor steps;
(b) the events heyroll.simulate compiles for the scene's first mode (the
    gaps, and any overlap guards and track events, as the engine builds them
    today), each callback a no-op that lets the integration go on (bodies
    pass through each other, so the number of steps is comparable): + event
    detection;
(c) heyroll.simulate: + the collision law, bookkeeping and records.
Each integrator is compiled once, before timing, and reset for every
repetition; the best of ``--repeat`` counts. Prints microseconds per
collision for each part and writes the table to ``--output`` (default
validation/reports/profile_collision_path.md).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import heyoka as hy

import heyroll
from heyroll.simulation.driver import motion_time_scale
from heyroll.simulation.events import mode_events
from heyroll.simulation.precision import DOUBLE
from heyroll.simulation.system import build_system
from _report import publish

REPORT = Path(__file__).parent / "reports" / "profile_collision_path.md"


def best_of(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        value = fn()
        times.append(time.perf_counter() - t0)
    return min(times), value


def bare_integrator(scene):
    """The equations of motion alone (build_system keeps only the parameters they read)."""
    system = build_system(scene, DOUBLE, events=False)
    return system, hy.taylor_adaptive(system.equations, system.initial_state_of(scene), pars=system.parameters)


def event_integrator(scene):
    """The first mode's equations and events as simulate compiles them, with no-op callbacks.

    The events come from the engine's own mode_events, so a change of the
    event set is profiled as it is run. heyoka wants exactly the parameters
    up to the last one the equations and events read: the system's vector
    also holds constants that only the callbacks use, so it is cut as the
    driver cuts it. Returns (system, integrator, number of events).
    """
    system = build_system(scene, DOUBLE)
    slots, nt_slots = [], []
    cooldown = DOUBLE.epsilon * motion_time_scale(scene)
    events, nt_events = mode_events(system, cooldown, slots, nt_slots)
    slots[:] = [lambda ta, d_sgn: True] * len(events)
    nt_slots[:] = [lambda ta, t, d_sgn: None] * len(nt_events)
    ta = hy.taylor_adaptive(system.equations, system.initial_state_of(scene), t_events=events, nt_events=nt_events)
    ta.pars[:] = system.parameters[: len(ta.pars)]
    return system, ta, len(events) + len(nt_events)


def propagate_from_start(scene, system, ta, t_end: float) -> int:
    """Steps taken from the scene's initial state to t_end."""
    ta.time = 0.0
    ta.state[:] = system.initial_state_of(scene)
    if ta.with_events:
        ta.reset_cooldowns()
    return ta.propagate_until(t_end)[3]


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=20000.0)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--output", type=Path, default=REPORT, help="where the markdown table is written")
    args = parser.parse_args(argv)
    scene = heyroll.default_scene()
    bare_system, bare = bare_integrator(scene)
    watched_system, watched, n_events = event_integrator(scene)
    heyroll.simulate(scene, t_end=1.0)  # compiles (and caches) simulate's integrator

    t_bare, steps_bare = best_of(lambda: propagate_from_start(scene, bare_system, bare, args.t_end), args.repeat)
    t_events, steps_events = best_of(lambda: propagate_from_start(scene, watched_system, watched, args.t_end), args.repeat)
    t_full, result = best_of(lambda: heyroll.simulate(scene, t_end=args.t_end, max_collisions=None), args.repeat)
    n = result.n_collisions
    if n == 0:
        raise SystemExit(f"no collision before t_end = {args.t_end:g} s: nothing to divide by")
    n_gaps = len(watched_system.gap_expressions)
    us = 1e6 / n
    lines = [
        "# Where a collision's time goes (default scene, double, tol = eps, one core)",
        "",
        f"t_end = {args.t_end:g} s, {n} collisions, {result.steps} steps in the full run "
        f"({result.steps / n:.1f} steps per collision), best of {args.repeat}",
        "",
        "| part | wall s | us per collision |",
        "|---|---|---|",
        f"| Taylor steps alone ({steps_bare} steps) | {t_bare:.3f} | {t_bare * us:.2f} |",
        f"| + event detection (events: {n_events}, gaps among them: {n_gaps}; no-op callbacks; {steps_events} steps) | "
        f"{t_events - t_bare:.3f} | {(t_events - t_bare) * us:.2f} |",
        f"| + collision law, checks, records (simulate) | {t_full - t_events:.3f} | {(t_full - t_events) * us:.2f} |",
        f"| total (simulate) | {t_full:.3f} | {t_full * us:.2f} |",
        "",
        f"collisions per second: {n / t_full:.3g}",
    ]
    text = "\n".join(lines) + "\n"
    publish(text, args.output)


if __name__ == "__main__":
    main()
