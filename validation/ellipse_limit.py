"""How close to the limit R = b^2/a a ball in an elliptical table runs cleanly.

    python validation/ellipse_limit.py [--fractions 0.99 0.995 0.998 0.999] [--launches 20] [--t-end 8]

A ball of radius R in the ellipse x^2/a^2 + y^2/b^2 <= 1 keeps its centre inside
the inner parallel curve, the zero set of a degree-8 polynomial
(heyroll/model/table/boundaries/ellipse.py). The curve's least radius of
curvature, b^2/a - R at the ends of the major axis, goes to 0 as R -> b^2/a:
there the polynomial is nearly singular, its roots are off by up to ~1e-7 m,
and its gradient's direction by round-off. The engine refuses R >= b^2/a; this
study measures how runs end at R = f b^2/a for f just below 1.

For each fraction f: random launches (a fixed seed) of one or two balls of
radius f b^2/a from inside an a = 2 ellipse (b = 1, 1.4 or 1.8), both cushion
models, cushion restitution 1 (impacts only) and 0 (every cushion impact ends
in a ride along the cushion: the hard case, a rider crossing the nearly
cusped end), each run to t_end. Counted: runs that end in a success status,
and runs that end `overlap` (a missed impact, caught by the overlap guard) or
`failed`. Prints the table and writes validation/reports/ellipse_limit.md.
"""

from __future__ import annotations

import argparse
import math
import random
import sys
import time
from collections import Counter
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _report import publish  # noqa: E402

REPORT = HERE / "reports" / "ellipse_limit.md"
A = 2.0
SEMI_MINOR = (1.0, 1.4, 1.8)
SHAPES = ("solid_sphere", "disk", "ring")


def launch_scene(f: float, cushion_model: str, cushion_restitution: float, rng: random.Random, t_end: float) -> str:
    """A table scene (TOML) of one or two balls of radius f b^2/a launched at random from the ellipse's axis."""
    b = rng.choice(SEMI_MINOR)
    radius = f * b * b / A
    room = A - radius  # the centre's reach along the major axis
    two = rng.random() < 0.5 and room > 2.2 * radius
    places = [(-room / 2, 0.0), (room / 2, 0.0)] if two else [(0.0, 0.0)]
    bodies = ""
    for x, y in places:
        speed, angle = rng.uniform(0.3, 3.0), rng.uniform(0.0, 2 * math.pi)
        bodies += (f'\n[[bodies]]\nshape = "{rng.choice(SHAPES)}"\nradius = {radius!r}\nmass = 0.17\n'
                   f"x = {x!r}\ny = {y!r}\nvx = {speed * math.cos(angle)!r}\nvy = {speed * math.sin(angle)!r}\n")
    return (f'[track]\ntype = "table"\nboundary = "ellipse"\na = {A}\nb = {b}\ncushion_model = "{cushion_model}"\n'
            f"cushion_restitution = {cushion_restitution}\nfriction = {rng.choice((0.01, 0.2, 0.5))}\n{bodies}\n"
            f'[collision]\nlaw = "{rng.choice(("hedrih", "newton", "slide"))}"\nrestitution = 0.5\n\n'
            f"[run]\nt_end = {t_end}\nmax_collisions = 5000\n")


def study(fractions, launches: int, t_end: float, seed: int = 2026) -> list[dict]:
    """One row per fraction, cushion model and cushion restitution: how its launches ended."""
    import heyroll
    from heyroll.interfaces.scene_file import parse_scene

    rows = []
    for f in fractions:
        for model in ("rolling", "slide"):
            for restitution in (1.0, 0.0):
                rng = random.Random(f"{seed} {f} {model} {restitution}")
                ends: Counter = Counter()
                impacts, started, example = 0, time.perf_counter(), ""
                for _ in range(launches):
                    result = heyroll.simulate(parse_scene(launch_scene(f, model, restitution, rng, t_end)))
                    ends[result.status.value] += 1
                    impacts += result.n_collisions
                    if not result.success and not example:
                        example = result.message
                rows.append({"f": f, "model": model, "restitution": restitution, "ends": ends, "impacts": impacts,
                             "wall": time.perf_counter() - started, "example": example})
                print(f"  f = {f}, {model}, k_c = {restitution}: {dict(ends)}", file=sys.stderr, flush=True)
    return rows


def report(rows, launches: int, t_end: float) -> str:
    import heyroll
    from heyroll.interfaces.outputs import versions

    lines = [
        "# A ball near the size limit of an elliptical table (R -> b^2/a)",
        "",
        f"Written by `python validation/ellipse_limit.py` ({launches} random launches per row, t_end = {t_end} s, "
        f"a = {A}, b in {SEMI_MINOR}, 1 or 2 balls of radius f b^2/a, random shape, friction and ball-ball law; "
        f"heyroll {heyroll.__version__}); versions {versions()}.",
        "",
        "k_c = 0: every cushion impact ends in a ride along the cushion (the rider crosses the nearly cusped ends "
        "of the centre's curve). `overlap`: a missed impact, caught by the overlap guard (the run stops there).",
        "",
        "| f = R a / b^2 | least radius of curvature / R | cushion model | k_c | runs | success | overlap | failed "
        "| impacts | wall s |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        ends = r["ends"]
        success = sum(n for status, n in ends.items() if status in ("completed", "max_collisions", "max_events"))
        lines.append(f"| {r['f']} | {(1 - r['f']) / r['f']:.1e} | {r['model']} | {r['restitution']:g} | "
                     f"{sum(ends.values())} | {success} | {ends.get('overlap', 0)} | {ends.get('failed', 0)} | "
                     f"{r['impacts']} | {r['wall']:.1f} |")
    examples = [r for r in rows if r["example"]]
    if examples:
        lines += ["", "First unsuccessful run's message per row:", ""]
        lines += [f"- f = {r['f']}, {r['model']}, k_c = {r['restitution']:g}: {r['example']}" for r in examples]
    return "\n".join(lines) + "\n"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fractions", type=float, nargs="+", default=[0.99, 0.995, 0.998, 0.999])
    parser.add_argument("--launches", type=int, default=20)
    parser.add_argument("--t-end", type=float, default=8.0)
    parser.add_argument("--output", type=Path, default=REPORT)
    args = parser.parse_args(argv)
    rows = study(args.fractions, args.launches, args.t_end)
    publish(report(rows, args.launches, args.t_end), args.output)


if __name__ == "__main__":
    main()
