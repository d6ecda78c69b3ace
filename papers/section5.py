"""Paper section 5: generalized rolling pendulums (Figs. 14-16 and 19, the theorem of 5.3), from real runs.

Run:  python papers/section5.py [--out papers/figures]

The paper draws its portraits by hand and gives almost no numbers. PARAMETERS
below are ours, chosen to show each feature it describes; they are printed
and written in the figure titles and in papers/README.md:

* Fig. 14 (beta = 0, R0 > R - 2r): three arcs with central angles 3pi/2, pi,
  3pi/2; the hump is higher than the tops of the bowls, so a body in one bowl
  never reaches the other: two centres, one saddle on the hump top, limiter
  impacts at the tops of the bowls.
* Figs. 15-16 (beta != 0, (R - r) > (R0 + r) - (R0 + R) sin beta): the bowls'
  tops are higher than the hump; the separatrix through the hump's saddle is
  the "figure eight" around both centres, and orbits above it cross the hump
  (junctions) and hit the limiters. Fig. 16b: the energy surface H(s, s').
* Fig. 19 and the theorem of 5.3: a disk on the paper's curves in a rotating
  plane. Portrait at Omega = 3 rad/s (figure-eight homoclinic orbit around
  the centre at x = 0) and bifurcation diagrams for the paper's three curves;
  the bifurcation values are printed.

Every portrait is checked against integrated trajectories: the script prints
the worst drift of the first integral along them and exits 1 if it exceeds 1e-13.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from heyroll.analysis.equilibria import EquilibriumProblem, bifurcations, find_equilibria
from heyroll.interfaces.portrait_figures import bifurcation_figure, energy_surface_figure, portrait_figure
from heyroll.model.bodies import Body
from heyroll.model.scene import Scene
from heyroll.model.frame import Frame
from heyroll.model.tracks import CurveTrack, ThreeArcTrack
from heyroll.model.scene import RunSettings

DISK = dict(shape="disk", radius="0.1", mass="1")

PARAMETERS = {
    "fig14": dict(R="1.0", R0="0.95", beta="0", body=DISK, s="1.0"),
    "fig15_16": dict(R="1.0", R0="0.5", beta="0.3", body=DISK, s="1.0"),
    "fig19": dict(y="0.5*x**2*(x**2 - 1)**2", x_min="-1.6", x_max="1.6", omega="3.0", axis_x="0",
                  body=dict(shape="disk", radius="0.05", mass="1"), x="0.3"),
}

#: The paper's three curves of 5.3 with our constants (k, a, b, c) and ranges.
PAPER_CURVES = {
    "k x^2 (x^2 - a^2)^2, k = 0.5, a = 1": ("0.5*x**2*(x**2 - 1)**2", "-1.6", "1.6"),
    "k x^2 (x^2 - a^2)^2 (x^2 - b^2), k = 0.02, a = 1, b = 2": ("0.02*x**2*(x**2 - 1)**2*(x**2 - 4)", "-2.1", "2.1"),
    "-k x^2 (x^2 - a^2)[c^4 - (x^2 - b^2)^2], k = 0.1, a = 1, b = 2, c^4 = 23.4256 (c = 2.2)":
        ("-0.1*x**2*(x**2 - 1)*(23.4256 - (x**2 - 4)**2)", "-2.1", "2.1"),
}
OMEGAS = np.linspace(0.0, 10.0, 201)


def body(spec) -> Body:
    return Body.of_shape(spec["shape"], spec["radius"], mass=spec["mass"])


def arcs_scene(name: str) -> Scene:
    p = PARAMETERS[name]
    track = ThreeArcTrack.make(p["R"], p["R0"], p["beta"])
    return Scene.make(track, [body(p["body"])], [p["s"]], [0], limiter_restitution=1, name=(
        f"{name}: three arcs R = {p['R']} m, R0 = {p['R0']} m, beta = {p['beta']}, disk r = {p['body']['radius']} m"))


def curve_scene() -> Scene:
    p = PARAMETERS["fig19"]
    track = CurveTrack.make(p["y"], p["x_min"], p["x_max"])
    return Scene.make(track, [body(p["body"])], [p["x"]], [0], frame=Frame.make(p["omega"], p["axis_x"]),
                          run=RunSettings.make(10), name=f"fig19: y = {p['y']}, Omega = {p['omega']} rad/s, disk r = 0.05 m")


def describe(scene: Scene) -> None:
    eq = find_equilibria(EquilibriumProblem(scene.track, scene.bodies[0], scene.frame, float(scene.g)))
    print(f"{scene.name}")
    for e in eq:
        print(f"    {e.type:>6} at {scene.coordinate} = {e.q:.12f} (contact x = {e.x:+.12f}), V/m = {e.potential:.12f} J/kg")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "figures")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    worst = 0.0
    p14 = PARAMETERS["fig14"]
    print(f"Fig. 14 condition R0 > R - 2r: {p14['R0']} > {float(p14['R']) - 2 * float(DISK['radius']):g}")
    p15 = PARAMETERS["fig15_16"]
    lhs = float(p15["R"]) - 0.1
    rhs = float(p15["R0"]) + 0.1 - (float(p15["R0"]) + float(p15["R"])) * np.sin(float(p15["beta"]))
    print(f"Figs. 15-16 condition (R - r) > (R0 + r) - (R0 + R) sin(beta): {lhs:g} > {rhs:.6g}")
    for name, fig in (("fig14", "fig14_three_arcs_beta0.png"), ("fig15_16", "fig15_three_arcs_beta.png")):
        scene = arcs_scene(name)
        describe(scene)
        check = portrait_figure(scene, args.out / fig, duration=20.0)
        worst = max(worst, check.worst_relative_drift)
        print(f"    portrait vs {check.trajectories} integrated trajectories: first integral drift "
              f"{check.worst_relative_drift:.2g}")
    energy_surface_figure(arcs_scene("fig15_16"), args.out / "fig16b_energy_surface.png")
    scene = curve_scene()
    describe(scene)
    check = portrait_figure(scene, args.out / "fig19_rotating_curve_portrait.png", duration=20.0)
    worst = max(worst, check.worst_relative_drift)
    print(f"    portrait vs {check.trajectories} integrated trajectories: first integral drift "
          f"{check.worst_relative_drift:.2g}")
    print("\nBifurcations (section 5.3's theorem), disk r = 0.05 m, axis x = 0, Omega in [0, 10] rad/s:")
    disk = body(PARAMETERS["fig19"]["body"])
    for k, (label, (y, lo, hi)) in enumerate(PAPER_CURVES.items(), start=1):
        track = CurveTrack.make(y, lo, hi)
        sc = Scene.make(track, [disk], [0.0], [0], frame=Frame.make(0, 0), name=f"curve {k}: {label}")
        bifurcation_figure(sc, args.out / f"bifurcation_curve{k}.png", OMEGAS)
        problem = EquilibriumProblem(track, disk, Frame.make(0, 0))
        eq0 = find_equilibria(problem)
        minima = [e.x for e in eq0 if e.type == "center"]
        maxima = [e.x for e in eq0 if e.type == "saddle"]
        print(f"  curve {k}: y = {label}")
        print(f"    at Omega = 0: minima (centres) at x = {', '.join(f'{x:+.6f}' for x in minima)}; "
              f"maxima (saddles) at x = {', '.join(f'{x:+.6f}' for x in maxima)}")
        for b in bifurcations(problem, OMEGAS):
            if min(abs(b.x - float(lo)), abs(b.x - float(hi))) < 1e-6:
                what = "an equilibrium reaches the limiter"
            else:
                on_min = min(minima, key=lambda x: abs(x - b.x)) if minima else None
                on_max = min(maxima, key=lambda x: abs(x - b.x)) if maxima else None
                what = ("pitchfork at the minimum of f on the axis" if on_min is not None and abs(b.x - on_min) < 1e-3
                        else f"saddle-node: the centre from the minimum at {on_min:+.6f} meets the saddle "
                             f"from the maximum at {on_max:+.6f}")
            print(f"    Omega = {b.omega:.12f} rad/s at x = {b.x:+.6f}, {b.before} -> {b.after} equilibria: {what}")
    print(f"\nwrote {args.out}/ ; worst first-integral drift along the portraits' trajectories {worst:.2g}")
    return 0 if worst < 1e-13 else 1


if __name__ == "__main__":
    sys.exit(main())
