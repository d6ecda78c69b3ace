"""Collisions per second on one core for the default scene, collision table kept.

    python validation/speed.py [--t-end 100000] [--repeat 3]

Times (a) the integration with every collision recorded and (b) the same plus
building the structured collision table, for the default scene on its circle
and for the same physics as an arc-chain track (one concave arc equal to the
circle: the general-track path of the one engine), side by side in one run; the JIT compilation of the system is
done once before timing (heyoka caches compiled code per scene shape). Prints
the figures and writes validation/reports/speed.md.

``--baseline REV`` also times the circle with heyroll as it was at git
revision REV (checked out into a temporary worktree, run in a subprocess),
interleaved with the current code, so that the speed-up is measured on the
same machine load; the goals of issue 12 (>= 1.0e5 collisions/s, >= 1.4x the
baseline) are printed against the best rates.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import mpmath

import heyroll
from heyroll.interfaces.outputs import versions


def as_one_arc(scene):
    """The circle scene on one concave arc of the same radius: s = (R - r)(phi + pi)."""
    R = scene.track.radius
    chain = heyroll.ArcChainTrack.make([heyroll.Segment("arc", R, "concave", -mpmath.pi, mpmath.pi)],
                                       start_x=0, start_y=-R)
    s = [(R - b.radius) * (p + mpmath.pi) for b, p in zip(scene.bodies, scene.q)]
    v = [(R - b.radius) * d for b, d in zip(scene.bodies, scene.dq)]
    return heyroll.Scene.make(chain, scene.bodies, s, v, law=scene.law, g=scene.g, run=scene.run, name=scene.name + " (one arc)")


#: Run by the baseline's interpreter: one timed run of the default scene's circle, printed as "collisions seconds".
BASELINE_RUN = """
import sys, time, heyroll
scene = heyroll.default_scene()
heyroll.simulate(scene, t_end=1.0)
t0 = time.perf_counter()
result = heyroll.simulate(scene, t_end=float(sys.argv[1]), max_collisions=None)
result.collision_table()
print(result.n_collisions, time.perf_counter() - t0)
"""


def subprocess_rate(tree: Path, t_end: float) -> float:
    """Collisions/s (table built) of the heyroll in ``tree``, in a fresh process that imports it from there.

    The baseline and this tree are both timed this way: timed in this process, beside the
    baseline's subprocesses, this tree measured 0.8x its own speed alone (measured)."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    out = subprocess.run([sys.executable, "-c", BASELINE_RUN, repr(t_end)], env=env, check=True, cwd=tree,
                         capture_output=True, text=True).stdout.split()
    return int(out[0]) / float(out[1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=1e5)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--high-accuracy", choices=["on", "off"], default="off")
    parser.add_argument("--baseline", metavar="REV", help="also time the circle at this git revision (e.g. a tag or commit)")
    args = parser.parse_args()
    repo = Path(__file__).resolve().parent.parent
    worktree = None
    if args.baseline:
        worktree = Path(tempfile.mkdtemp(prefix="heyroll-baseline-")) / "tree"
        subprocess.run(["git", "-C", str(repo), "worktree", "add", "--detach", "-q", str(worktree), args.baseline],
                       check=True)
    circle = heyroll.default_scene()
    ha = args.high_accuracy == "on"
    lines = [
        "# heyroll speed: default scene, on its circle and as one concave arc",
        "",
        f"t_end = {args.t_end:g} s, high_accuracy = {ha}, tol = eps, one core "
        f"(cpu count {os.cpu_count()}), versions {versions()}",
        "",
        "| track | run | collisions | steps | wall s (integrate) | wall s (+ table) | coll/s (integrate) | coll/s (+ table) | rel. energy change |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    best = {}
    scenes = {"circle": circle, "one arc": as_one_arc(circle)}
    for name, scene in scenes.items():
        heyroll.simulate(scene, t_end=1.0, high_accuracy=ha)  # compile once
    for k in range(1, args.repeat + 1):  # alternate, so both see the same machine load
        if worktree is not None:
            for name, tree in ((f"circle at {args.baseline}", worktree), ("circle (this tree, subprocess)", repo)):
                rate = subprocess_rate(tree, args.t_end)
                lines.append(f"| {name} | {k} | | | | | | {rate:.3g} | |")
                best[name] = max(best.get(name, 0.0), rate)
        for name, scene in scenes.items():
            t0 = time.perf_counter()
            result = heyroll.simulate(scene, t_end=args.t_end, max_collisions=None, high_accuracy=ha)
            t1 = time.perf_counter()
            result.collision_table()
            t2 = time.perf_counter()
            n = result.n_collisions
            drift = (result.energy_final - result.energy_initial) / result.energy_initial
            lines.append(f"| {name} | {k} | {n} | {result.steps} | {t1 - t0:.3f} | {t2 - t0:.3f} | "
                         f"{n / (t1 - t0):.3g} | {n / (t2 - t0):.3g} | {drift:.2e} |")
            best[name] = max(best.get(name, 0.0), n / (t2 - t0))
    lines += ["", *(f"best {name}: {rate:.3g} collisions/s with the table built" for name, rate in best.items()),
              f"one arc / circle: {best['one arc'] / best['circle']:.2f}"]
    if worktree is not None:
        subprocess.run(["git", "-C", str(repo), "worktree", "remove", "--force", str(worktree)], check=True)
        ours, theirs = best["circle (this tree, subprocess)"], best[f"circle at {args.baseline}"]
        lines += [f"circle / circle at {args.baseline} (both in subprocesses): {ours / theirs:.2f} "
                  f"(goal >= 1.4: {'met' if ours / theirs >= 1.4 else 'not met'}); best circle "
                  f"{max(ours, best['circle']):.3g} collisions/s (goal >= 1.0e5: "
                  f"{'met' if max(ours, best['circle']) >= 1e5 else 'not met'})"]
    text = "\n".join(lines) + "\n"
    print(text)
    out = Path(__file__).parent / "reports"
    out.mkdir(exist_ok=True)
    (out / "speed.md").write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
