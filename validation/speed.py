"""Collisions per second on one core for the default scene, collision table kept.

    python validation/speed.py [--t-end 100000] [--repeat 3]

Times (a) the integration with every collision recorded and (b) the same plus
building the structured collision table; the JIT compilation of the system is
done once before timing (heyoka caches compiled code per scene shape). Prints
the figures and writes validation/reports/speed.md.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import heyroll
from heyroll.interfaces.outputs import versions


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=1e5)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--high-accuracy", choices=["on", "off"], default="off")
    args = parser.parse_args()
    scene = heyroll.default_scene()
    ha = args.high_accuracy == "on"
    heyroll.simulate(scene, t_end=1.0, high_accuracy=ha)  # compile once
    rows = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        result = heyroll.simulate(scene, t_end=args.t_end, max_collisions=None, high_accuracy=ha)
        t1 = time.perf_counter()
        table = result.collision_table()
        t2 = time.perf_counter()
        n = result.n_collisions
        drift = (result.energy_final - result.energy_initial) / result.energy_initial
        rows.append((n, t1 - t0, t2 - t0, n / (t1 - t0), n / (t2 - t0), result.steps, drift, table.size))
    best = max(rows, key=lambda r: r[4])
    lines = [
        "# heyroll speed: default scene",
        "",
        f"scene: {scene.describe()}",
        f"t_end = {args.t_end:g} s, high_accuracy = {ha}, tol = eps, one core "
        f"(cpu count {os.cpu_count()}), versions {versions()}",
        "",
        "| run | collisions | steps | wall s (integrate) | wall s (+ table) | coll/s (integrate) | coll/s (+ table) | rel. energy change |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for k, (n, w1, w2, r1, r2, steps, drift, _) in enumerate(rows, start=1):
        lines.append(f"| {k} | {n} | {steps} | {w1:.3f} | {w2:.3f} | {r1:.3g} | {r2:.3g} | {drift:.2e} |")
    lines += ["", f"best: {best[4]:.3g} collisions/s with the table built ({best[3]:.3g}/s integration only)"]
    text = "\n".join(lines) + "\n"
    print(text)
    out = Path(__file__).parent / "reports"
    out.mkdir(exist_ok=True)
    (out / "speed.md").write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
