"""Many bodies in one circle: compile time and cost per collision against N (issue 12).

    python validation/many_bodies.py [--sizes 2 4 8 16 32 64] [--collisions 5000] [--repeat 5]
                                     [--t-end 100000] [--t-end-inelastic 10] [--seed 0]

For each N: N bodies of random shape (solid sphere, disk, ring), radius and
mass, equally spaced around a circle of radius 1 m with random rates in
[-1, 1] rad/s (seeded), run with the rolling law elastic (k = 1) and at
k = 0.9 (the bodies gather at the bottom, pairs merge into clusters and split
again: later modes are compiled on the way). A run stops after
``--collisions`` collisions or at its t_end (``--t-end`` elastic, long enough
for the 2-body scene to reach the collision count; ``--t-end-inelastic``
shorter: at k = 0.9 a few bodies soon come to rest in contact, and a crowd's
collision rate explodes as it gathers at the bottom, 1D inelastic collapse). All in one
process, one core, with heyoka's on-disk cache off (otherwise a repeated
study reads compiled code from ~/.cache/heyoka):

* compile: wall time of a run stopped at t = 1e-9 s, i.e. building and
  compiling everything the first mode needs (the elastic and inelastic scenes
  of one N share it, so it is measured once per N);
* first run: the run as a user's first call pays for it: compile + the full
  run (later modes compiled on the way; at k = 0.9 the first mode is
  compiled already, by the elastic row);
* second run: the same run again, every mode compiled (the best of
  ``--repeat``: the machine is shared): wall time, steps and us per
  collision and its ratio to the 2-body elastic cost (the hot path), each
  repetition timed right after a run of the 2-body scene.

Goals (issue 12): a collision at 8 and 16 bodies costs at most 1.5x one at 2
bodies; the first mode of 64 bodies compiles in under 10 s. Prints a markdown
table and writes validation/reports/many_bodies.md.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import heyoka as hy
import numpy as np

import heyroll
from heyroll.interfaces.outputs import versions
from _report import publish

REPORT = Path(__file__).parent / "reports" / "many_bodies.md"
SHAPES = ("solid_sphere", "disk", "ring")
#: A run stopped this soon after its start has compiled its first mode and taken a step.
FIRST_STEP_T_END = 1e-9
#: Issue 12's goals: cost per collision at these sizes against 2 bodies; compile of the largest.
COST_GOAL_SIZES, COST_GOAL_RATIO = (8, 16), 1.5
COMPILE_GOAL_SIZE, COMPILE_GOAL_S = 64, 10.0


def crowd(n: int, restitution: str, t_end: float, rng: np.random.Generator):
    """n random bodies equally spaced around the circle; each radius is that of two equal
    bodies touching at 15-30 % of the spacing (so any two neighbours start apart)."""
    spacing = 2 * np.pi / n
    # Two equal bodies of radius r touch at beta = 2 asin(r / (R - r)): r = R s / (1 + s), s = sin(beta / 2).
    half = np.sin(rng.uniform(0.15, 0.3, n) * spacing / 2)
    radii = half / (1 + half)
    shapes = rng.choice(SHAPES, n)
    masses = rng.uniform(0.5, 2.0, n)
    bodies = [heyroll.Body.of_shape(str(s), repr(float(r)), mass=repr(float(m)))
              for s, r, m in zip(shapes, radii, masses)]
    phi = [repr(float(-np.pi + spacing * (k + 0.5))) for k in range(n)]
    dphi = [repr(float(x)) for x in rng.uniform(-1.0, 1.0, n)]
    return heyroll.Scene.make(heyroll.CircleTrack.of_radius(1), bodies, phi=phi, dphi=dphi,
                              law=heyroll.make_law("hedrih", restitution), run=heyroll.RunSettings.make(t_end),
                              name=f"{n} bodies, k = {restitution}")


def timed(scene, **options):
    t0 = time.perf_counter()
    result = heyroll.simulate(scene, **options)
    return time.perf_counter() - t0, result


def measure(n: int, args, reference) -> list[dict]:
    """The elastic and the inelastic row of one N (the same bodies and rates).

    Each compiled run is timed right after a run of ``reference`` (the 2-body
    elastic scene, the same as this N's when N = 2), so that a row and its
    ratio's denominator see the same machine load (measured: the same run
    0.13 s or 0.19 s, minutes apart).
    """
    scenes = {k: crowd(n, k, t_end, np.random.default_rng([args.seed, n]))
              for k, t_end in (("1", args.t_end), ("0.9", args.t_end_inelastic))}
    if n == 2:
        scenes["1"] = reference
    # Both scenes have the first mode's shape (the law's constants are runtime parameters).
    compile_s, _ = timed(scenes["1"], t_end=FIRST_STEP_T_END)
    rows = []
    for k, scene in scenes.items():
        first_s, first = timed(scene, max_collisions=args.collisions)
        if not first.success:
            raise SystemExit(f"{scene.name}: {first.message}")
        warm, base = [], []
        for _ in range(args.repeat):
            if scene is not reference:
                base.append(timed(reference, max_collisions=args.collisions))
            warm.append(timed(scene, max_collisions=args.collisions))
        base = base or warm  # the reference itself: its own runs
        if any(result.n_collisions != first.n_collisions for _, result in warm):
            raise SystemExit(f"{scene.name}: a repeated run differs from the first")
        second_s, second = min(warm, key=lambda run: run[0])
        base_s, base_run = min(base, key=lambda run: run[0])
        elastic = k == "1"
        rows.append(dict(
            n=n,
            k=k,
            compile_s=compile_s if elastic else None,
            first_s=first_s + (compile_s if elastic else 0.0),
            collisions=second.n_collisions,
            t_final=float(second.t_final),
            mode_changes=len(second.mode_changes) - 1,  # the first entry is the start
            steps=second.steps,
            wall_s=second_s,
            us=1e6 * second_s / max(second.n_collisions, 1),
            base_us=1e6 * base_s / base_run.n_collisions,
            energy=(second.energy_final - second.energy_initial) / abs(second.energy_initial),
        ))
    return rows


def goals(rows) -> list[str]:
    """Issue 12's goals against the measured rows, met or not."""
    lines = []
    for n in COST_GOAL_SIZES:
        row = next((r for r in rows if r["n"] == n and r["k"] == "1"), None)
        if row is not None:
            ratio = row["us"] / row["base_us"]
            lines.append(f"- cost per collision at {n} bodies (k = 1): {row['us']:.1f} us, {ratio:.2f}x the 2-body "
                         f"{row['base_us']:.1f} us timed beside it (goal <= {COST_GOAL_RATIO}x): "
                         f"{'met' if ratio <= COST_GOAL_RATIO else 'NOT met'}")
    row = next((r for r in rows if r["n"] == COMPILE_GOAL_SIZE and r["compile_s"] is not None), None)
    if row is not None:
        ok = row["compile_s"] < COMPILE_GOAL_S
        lines.append(f"- compile of the first mode at {COMPILE_GOAL_SIZE} bodies: {row['compile_s']:.2f} s "
                     f"(goal < {COMPILE_GOAL_S:g} s): {'met' if ok else 'NOT met'}")
    return lines


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[2, 4, 8, 16, 32, 64])
    parser.add_argument("--collisions", type=int, default=5000, help="each run stops after this many collisions")
    parser.add_argument("--t-end", type=float, default=1e5, help="t_end of the elastic runs (s)")
    parser.add_argument("--t-end-inelastic", type=float, default=10.0, help="t_end of the k = 0.9 runs (s)")
    parser.add_argument("--repeat", type=int, default=5, help="compiled runs timed per row (the best counts)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--output", type=Path, default=REPORT, help="where the markdown report is written")
    args = parser.parse_args(argv)
    if 2 not in args.sizes:
        parser.error("--sizes must include 2: the 2-body cost is the reference of the ratios")
    hy.llvm_state.set_diskcache_enabled(False)
    # The 2-body elastic scene of the study (its N = 2 elastic row, measured first and cold).
    reference = crowd(2, "1", args.t_end, np.random.default_rng([args.seed, 2]))
    rows = [row for n in sorted(args.sizes) for row in measure(n, args, reference)]
    lines = [
        "# Many bodies in one circle: compile time and cost per collision (issue 12)",
        "",
        f"Random solid spheres, disks and rings, equally spaced, rates in [-1, 1] rad/s (seed {args.seed}); "
        f"runs stop after {args.collisions} collisions or at t_end = {args.t_end:g} s (k = 1), "
        f"{args.t_end_inelastic:g} s (k = 0.9). Double, tol = eps, one core (cpu count {os.cpu_count()}), "
        f"heyoka's on-disk cache off; versions {versions()}.",
        "",
        "compile: a run stopped after its first step (everything the first mode needs; shared by both k). "
        "first run: compile + the whole run (later modes compiled on the way). second run: the same run, "
        f"all compiled, best of {args.repeat}. ratio: us per collision over that of the 2-body elastic run, "
        "timed in turn with it (same machine load).",
        "",
        "| N | k | compile s | first run s | collisions | t_final s | mode changes | second run s "
        "| steps per collision | us per step | us per collision | ratio to 2 bodies | rel. energy change |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        compile_text = "(as k = 1)" if r["compile_s"] is None else f"{r['compile_s']:.2f}"
        lines.append(
            f"| {r['n']} | {r['k']} | {compile_text} | {r['first_s']:.2f} | {r['collisions']} | {r['t_final']:.4g} | "
            f"{r['mode_changes']} | {r['wall_s']:.3f} | {r['steps'] / max(r['collisions'], 1):.2f} | "
            f"{1e6 * r['wall_s'] / max(r['steps'], 1):.1f} | {r['us']:.1f} | {r['us'] / r['base_us']:.2f} | {r['energy']:.2e} |"
        )
    lines += ["", "Goals:", *goals(rows)]
    text = "\n".join(lines) + "\n"
    publish(text, args.output)


if __name__ == "__main__":
    main()
