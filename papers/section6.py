"""Paper section 6: two disks colliding on a rotating three-arc track (Figs. 18-20), from a real run.

Run:  python papers/section6.py [--out papers/figures]

The scene is examples/two_disks_rotating_arcs.toml (our parameters; the paper
gives none): R = 1 m, R0 = 0.5 m, beta = 0.2, Omega = 1.5 rad/s about the
axis of symmetry, disks r = 0.05 m (1 kg) and 0.08 m (2 kg), the rolling law
with k = 0.9. The bifurcation parameters of the bowls, lambda_i =
g/((R - r_i) Omega^2), are printed (the paper's Fig. 20 is for lambda_i < 1;
ours are > 1 so that the first disk can cross the hump).

Figures: fig20_phase_branches.png (each disk's phase-trajectory branches,
with the jumps at the collisions) and fig20_energy_transfer.png (each disk's
first integral H_i, constant between collisions, jumping at each one: the
energy transfer of section 6.2). The script checks, at every collision
resolved by the rolling law, that the loss of H_1 + H_2 equals eq. (15)
(-J1 J2/(2(J1 + J2)) (1 - k^2)(omega_P1 - omega_P2)^2), and exits 1 if not.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from heyroll.interfaces.portrait_figures import body_energy_figure, branches_figure
from heyroll.interfaces.scene_file import load_scene
from heyroll.model.laws import kinetic_energy_change
from heyroll.simulation.driver import simulate

SCENE = Path(__file__).resolve().parents[1] / "examples" / "two_disks_rotating_arcs.toml"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "figures")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    scene = load_scene(SCENE)
    omega, g = float(scene.frame.omega), float(scene.g)
    for n, b in enumerate(scene.bodies, start=1):
        print(f"disk {n}: r = {float(b.radius)} m, m = {float(b.mass)} kg, lambda = g/((R - r) Omega^2) = "
              f"{g / ((1.0 - float(b.radius)) * omega**2):.6f}")
    result = simulate(scene, dense=True)
    print(f"{result.status.value}: {result.message}; {result.n_collisions} collisions, "
          f"{len(result.junctions)} junction crossings, {result.settings['inconsistent_collisions']} rolling-law outcomes left the disks "
          f"approaching (resolved by Newton's law on the gap rate)")
    k = float(scene.law.restitution)
    worst = 0.0
    print(f"{'n':>3} {'t (s)':>19} {'H1 before':>12} {'H1 after':>12} {'H2 before':>12} {'H2 after':>12} "
          f"{'dH':>12} {'eq. (15)':>12} law")
    from heyroll.interfaces.portrait_figures import body_energy

    for c in result.collision_table():
        h1b = float(body_energy(scene, 0, c["q_i"], c["dq_i_before"]))
        h1a = float(body_energy(scene, 0, c["q_i"], c["dq_i_after"]))
        h2b = float(body_energy(scene, 1, c["q_j"], c["dq_j_before"]))
        h2a = float(body_energy(scene, 1, c["q_j"], c["dq_j_after"]))
        dH = c["energy_after"] - c["energy_before"]
        J1, J2 = (float(b.rolling_inertia()) for b in scene.bodies)
        predicted = kinetic_energy_change(J1, J2, k, c["omega_i_before"] - c["omega_j_before"])
        if c["law_flag"] == 0:
            worst = max(worst, abs(dH - predicted) / max(abs(c["energy_before"]), 1.0))
        print(f"{c['n']:>3} {c['t']:>19.15f} {h1b:>12.6f} {h1a:>12.6f} {h2b:>12.6f} {h2a:>12.6f} {dH:>12.6f} "
              f"{predicted if c['law_flag'] == 0 else float('nan'):>12.6f} {'rolling' if c['law_flag'] == 0 else 'newton'}")
    branches_figure(result, args.out / "fig20_phase_branches.png")
    body_energy_figure(result, args.out / "fig20_energy_transfer.png")
    print(f"worst |dH - eq. (15)| / |H| over rolling-law collisions: {worst:.2g}")
    print(f"wrote {args.out}/")
    return 0 if worst < 1e-12 else 1


if __name__ == "__main__":
    sys.exit(main())
