"""Where the time of a collision goes: integration, event detection, the callback.

    python validation/profile_collision_path.py [--t-end 20000]

Runs the default scene three ways over the same time span, one core:
(a) the bare equations of motion (no events): the cost of the Taylor steps;
(b) the gap events with a callback that only returns (bodies pass through
    each other, so the number of steps is comparable): + event detection;
(c) heyroll.simulate: + the collision law, bookkeeping and records.
Prints microseconds per collision for each part and writes
validation/reports/profile_collision_path.md.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import heyoka as hy

import heyroll
from heyroll.simulation.precision import DOUBLE
from heyroll.simulation.system import build_system


def best_of(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        value = fn()
        times.append(time.perf_counter() - t0)
    return min(times), value


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=20000.0)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    scene = heyroll.default_scene()
    bare = build_system(scene, DOUBLE, events=False)
    watched = build_system(scene, DOUBLE)

    def run_bare():
        ta = hy.taylor_adaptive(bare.equations, bare.initial_state, pars=bare.parameters)
        return ta.propagate_until(args.t_end)[3]

    def run_events():
        events = [hy.t_event(g, callback=lambda ta, d: True, direction=hy.event_direction.negative)
                  for g in watched.gap_expressions]
        ta = hy.taylor_adaptive(watched.equations, watched.initial_state, pars=watched.parameters, t_events=events)
        return ta.propagate_until(args.t_end)[3]

    def run_full():
        return heyroll.simulate(scene, t_end=args.t_end, max_collisions=None)

    heyroll.simulate(scene, t_end=1.0)
    run_bare(), run_events()  # compile once
    t_bare, steps_bare = best_of(run_bare, args.repeat)
    t_events, steps_events = best_of(run_events, args.repeat)
    t_full, result = best_of(run_full, args.repeat)
    n = result.n_collisions
    us = 1e6 / n
    lines = [
        "# Where a collision's time goes (default scene, double, tol = eps, one core)",
        "",
        f"t_end = {args.t_end:g} s, {n} collisions, {result.steps} steps in the full run "
        f"({result.steps / n:.1f} steps per collision)",
        "",
        "| part | wall s | us per collision |",
        "|---|---|---|",
        f"| Taylor steps alone ({steps_bare} steps) | {t_bare:.3f} | {t_bare * us:.2f} |",
        f"| + gap event detection (trivial callback, {steps_events} steps) | {t_events - t_bare:.3f} | {(t_events - t_bare) * us:.2f} |",
        f"| + collision law, checks, records (simulate) | {t_full - t_events:.3f} | {(t_full - t_events) * us:.2f} |",
        f"| total (simulate) | {t_full:.3f} | {t_full * us:.2f} |",
        "",
        f"collisions per second: {n / t_full:.3g}",
    ]
    text = "\n".join(lines) + "\n"
    print(text)
    out = Path(__file__).parent / "reports"
    out.mkdir(exist_ok=True)
    (out / "profile_collision_path.md").write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
