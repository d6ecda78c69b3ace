"""Random scenes through the engine: every run must end in a success status.

    python validation/random_scenes.py [--seed 0] [--scenes 200]

Draws scenes of 2-20 bodies of mixed shapes in a circle (a third of them
mirror-symmetric starts at rest, where disjoint pairs collide at one instant;
every other one with ``[collision] simultaneous = "impulses"``),
of 2-4 bodies on curves with limiters, with the rolling or Newton's law
and restitutions from 0 to 1, and of 2-4 bodies on rough curves (Coulomb
friction, a third of them on a moving base), and runs each to its t_end. Prints
every run that does not end completed / max_collisions / max_events, with its scene,
and writes validation/reports/random_scenes.md. This sweep found four engine
bugs of issue 12's session (merge/split loops at one instant, a missed
collision flagged on particles at rest, endless chatter on a curve); each is
now a regression test.
"""

from __future__ import annotations

import argparse
import math
import random
import time
from collections import Counter
from pathlib import Path

import heyroll
from heyroll.interfaces.outputs import versions
from heyroll.model.bodies import Body
from heyroll.model.forcing import Forcing
from heyroll.model.scene import RunSettings, Scene
from heyroll.model.tracks import CircleTrack, CurveTrack
from _report import publish

SHAPES = ("solid_sphere", "disk", "ring", "hollow_sphere", "particle")
CURVES = ("0.5*x**2", "0.3*x**4 - 0.4*x**2", "0.1*exp(2*x) + 0.1*exp(-2*x)")
SUCCESS = ("completed", "max_collisions", "max_events")


def circle_scene(rng: random.Random, simultaneous: str = "sequential") -> Scene:
    n = rng.choice([2, 3, 4, 5, 6, 8, 12, 20])
    law = rng.choice(["hedrih", "newton"])
    symmetric = rng.random() < 0.3
    r = min(0.2, 0.7 * math.pi / n / 2)
    shapes = SHAPES if law == "newton" else SHAPES[:4]  # the rolling law needs r > 0
    bodies = []
    for _ in range(n):
        shape = rng.choice(shapes)
        radius = 0 if shape == "particle" else round(r * rng.uniform(0.3, 1.0), 4)
        bodies.append(Body.of_shape(shape, radius, mass=str(round(rng.uniform(0.5, 2), 3))))
    if symmetric:  # mirror images about the bottom, at rest
        bodies = bodies[: (n + 1) // 2] + bodies[: n // 2][::-1]
    span = 2 * math.pi * 0.9
    phi = [str(round(-span / 2 + span * (i + 0.5) / n, 6)) for i in range(n)]
    dphi = ["0" if symmetric else str(round(rng.uniform(-2, 2), 4)) for _ in range(n)]
    return Scene.make(CircleTrack.of_radius(1), bodies, phi=phi, dphi=dphi,
                      law=heyroll.make_law(law, rng.choice(["1", "0.99", "0.9", "0.5", "0"])),
                      run=RunSettings.make(rng.choice([2, 5, 10])), name="symmetric" if symmetric else "random",
                      simultaneous=simultaneous)


def curve_scene(rng: random.Random) -> Scene:
    n = rng.choice([2, 3, 4])
    track = CurveTrack.make(rng.choice(CURVES), "-1.5", "1.5")
    bodies = [Body.of_shape(rng.choice(SHAPES[:4]), "0.05", mass=str(round(rng.uniform(0.5, 2), 3))) for _ in range(n)]
    x = sorted(rng.sample([round(-1.3 + 0.2 * i, 2) for i in range(14)], n))
    return Scene.make(track, bodies, [str(v) for v in x], [str(round(rng.uniform(-1, 1), 3)) for _ in range(n)],
                      law=heyroll.make_law(rng.choice(["hedrih", "newton"]), rng.choice(["1", "0.9", "0.5", "0"])),
                      limiter_restitution="0.5", run=RunSettings.make(rng.choice([2, 5])), name="curve")


def rough_scene(rng: random.Random) -> Scene:
    """2-4 bodies of mixed shapes on a rough curve (Coulomb friction, mu_s >= mu), a third of them forced."""
    n = rng.choice([2, 3, 4])
    track = CurveTrack.make(rng.choice(CURVES), "-1.5", "1.5")
    shapes = SHAPES  # particles slide and stick; the others roll, slip and roll again
    bodies = [Body.of_shape(shape, 0 if shape == "particle" else "0.05", mass=str(round(rng.uniform(0.5, 2), 3)))
              for shape in (rng.choice(shapes) for _ in range(n))]
    x = sorted(rng.sample([round(-1.3 + 0.2 * i, 2) for i in range(14)], n))
    mu = round(rng.uniform(0.02, 0.5), 3)
    forcing = None
    if rng.random() < 1 / 3:
        forcing = Forcing.make("base", amplitude=str(round(rng.uniform(0.01, 0.1), 3)),
                               frequency=str(round(rng.uniform(2, 8), 3)))
    return Scene.make(track, bodies, [str(v) for v in x], [str(round(rng.uniform(-1, 1), 3)) for _ in range(n)],
                      law=heyroll.make_law("newton", rng.choice(["1", "0.9", "0.5", "0"])),
                      friction=str(mu), static_friction=str(round(mu * rng.uniform(1, 1.5), 3)), forcing=forcing,
                      limiter_restitution="0.5", run=RunSettings.make(rng.choice([2, 5])),
                      name="rough, forced" if forcing is not None else "rough")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--scenes", type=int, default=200)
    parser.add_argument("--output", type=Path, default=Path(__file__).parent / "reports" / "random_scenes.md")
    parser.add_argument("--simultaneous", choices=("sequential", "impulses", "both"), default="both",
                        help="the circle scenes' [collision] simultaneous (both: impulses for every other scene, "
                             "by its number: a seed draws the same scenes whichever is chosen)")
    args = parser.parse_args()
    rng = random.Random(args.seed)
    statuses: Counter = Counter()
    failures = []
    started = time.perf_counter()
    for number in range(args.scenes):
        draw = rng.random()
        policy = args.simultaneous if args.simultaneous != "both" else ("impulses", "sequential")[number % 2]
        scene = circle_scene(rng, policy) if draw < 0.6 else curve_scene(rng) if draw < 0.8 else rough_scene(rng)
        result = heyroll.simulate(scene)
        statuses[result.status.value] += 1
        line = (f"{number}: {scene.name}, {scene.track.describe()}, {len(scene.bodies)} bodies, "
                f"{scene.law.name} k = {float(scene.law.restitution):g}"
                + (", simultaneous impulses" if scene.simultaneous == "impulses" else "") + f": {result.status.value}, "
                f"{result.n_collisions} collisions, {len(result.mode_changes)} modes")
        print(line, flush=True)
        if result.status.value not in SUCCESS:
            failures.append(f"- {line}: {result.message}\n  bodies {[b.describe() for b in scene.bodies]}, "
                            f"q {[float(q) for q in scene.q]}, dq {[float(v) for v in scene.dq]}")
    lines = [
        "# Random scenes through the engine",
        "",
        f"`python validation/random_scenes.py --seed {args.seed} --scenes {args.scenes} "
        f"--simultaneous {args.simultaneous}`: "
        f"{args.scenes} scenes in {time.perf_counter() - started:.0f} s; versions {versions()}.",
        "",
        "| status | runs |",
        "|---|---|",
        *(f"| {status} | {count} |" for status, count in sorted(statuses.items())),
        "",
        f"Runs not ending in {', '.join(SUCCESS)}: {len(failures)}",
        *failures,
    ]
    text = "\n".join(lines) + "\n"
    publish(text, args.output)


if __name__ == "__main__":
    main()
