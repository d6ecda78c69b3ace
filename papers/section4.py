"""Paper section 4.2.5: Fig. 11 (phase trajectory branches with jumps) and Fig. 12 (configurations), from real runs.

Run:  python papers/section4.py [--out papers/figures]

The paper sketches (it computes nothing) the vibro-impact motion of two heavy
balls of different radii rolling inside a circle in a vertical plane, over
the first two collisions:

* Fig. 11 — the phase plane of each ball, ball 2 above and ball 1 below:
  the single-ball phase portrait (closed curves of libration around the
  stable centre at the lowest point, the separatrix through the saddles at
  phi = +-pi, rotations outside it, eq. 29/40) and the branches the ball
  actually travels: from N_0 to N_impact,1 on its initial phase curve, a
  jump at fixed phi to N_outgoing,1 (the rolling law, eqs. 60-63), the next
  branch to N_impact,2, a jump to N_outgoing,2, and on.
* Fig. 12 — the configurations: the balls in the circle at the start and at
  the first two collisions, with the contact point between them.

The paper gives no numbers; PARAMETERS below are ours, chosen so that both
balls move at the start, the collisions happen away from the lowest point,
and the jumps change each ball's phase curve visibly. They are written in
the figure titles and in papers/README.md. The figures are drawn from
``heyroll.simulate`` (collision times and states located by heyoka) and
``heyroll.simulation.trajectory.sample_branches`` (the branches). The script
also prints the first two collisions, checks them against the independent
mpmath reference, and solves the paper's (56)=(57) for the first collision
with its series (54)-(55).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Circle

import heyroll
from heyroll.simulation.trajectory import sample_branches

#: The scene of Figs. 11-12 (paper: none given). Steel balls, radii 0.10 and 0.15 m (r2/r1 = 3/2, as example c* of 3.6), in a 1 m circle.
PARAMETERS = """
name = "paper-fig-11-12"
g = 9.81

[track]
type = "circle"
radius = 1.0

[[bodies]]
shape = "solid_sphere"
radius = 0.10
density = 7850.0
phi = -1.2
dphi = 1.0

[[bodies]]
shape = "solid_sphere"
radius = 0.15
density = 7850.0
phi = 0.8
dphi = -1.0

[collision]
law = "hedrih"
restitution = 1.0

[run]
t_end = 30.0
"""

#: Collisions drawn; the branch after the last one is drawn up to the next collision.
COLLISIONS_SHOWN = 2


def scene():
    return heyroll.parse_scene(PARAMETERS)


def parameter_text(sc, tex: bool = True) -> str:
    """The scene's parameters in two lines, for titles (``tex``) or the terminal."""
    b1, b2 = sc.bodies
    p1, p2, v1, v2 = (
        ("$\\varphi_{1,0}$", "$\\varphi_{2,0}$", "$\\dot\\varphi_{1,0}$", "$\\dot\\varphi_{2,0}$")
        if tex
        else ("phi1_0", "phi2_0", "phi1_0'", "phi2_0'")
    )
    g_unit, rho_unit = ("m/s$^2$", "kg/m$^3$") if tex else ("m/s^2", "kg/m^3")
    return (
        f"R = {float(sc.track.radius):g} m, g = {float(sc.g):g} {g_unit}, law {sc.law.name}, "
        f"k = {float(sc.law.restitution):g}; ball 1: {b1.describe()} kg, "
        f"{p1} = {float(sc.phi[0]):g} rad, {v1} = {float(sc.dphi[0]):g} rad/s;\n"
        f"ball 2: {b2.describe()} kg, {p2} = {float(sc.phi[1]):g} rad, "
        f"{v2} = {float(sc.dphi[1]):g} rad/s (steel, 7850 {rho_unit})"
    )


def _save(fig: Figure, path: Path) -> Path:
    FigureCanvasAgg(fig)
    tmp = path.with_name(f".{path.name}.tmp")
    fig.savefig(tmp, format="png", dpi=130)
    os.replace(tmp, path)
    return path


# ----------------------------------------------------------------------------- Fig. 11


def _portrait(ax, a: float, vmax: float) -> None:
    """Single-ball phase portrait: level curves of phi'^2/2 + 2a sin^2(phi/2) (eqs. 28-29)."""
    x = np.linspace(-np.pi - 0.5, np.pi + 0.5, 400)
    y = np.linspace(-vmax, vmax, 400)
    X, Y = np.meshgrid(x, y)
    H = 0.5 * Y**2 + 2 * a * np.sin(X / 2) ** 2
    sep = 2 * a
    levels = sorted(set(np.concatenate([np.linspace(0.05, 0.95, 8) * sep, sep * np.array([1.15, 1.4, 1.8, 2.4])])))
    ax.contour(X, Y, H, levels=levels, colors="0.8", linewidths=0.6)
    ax.contour(X, Y, H, levels=[sep], colors="0.45", linewidths=1.0, linestyles="-.")
    ax.plot([0], [0], "o", color="0.45", ms=4)  # stable centre (lowest point)
    ax.plot([-np.pi, np.pi], [0, 0], "x", color="0.45", ms=6)  # saddles (top of the circle)
    ax.axhline(0, color="0.85", lw=0.5)
    ax.set_xlim(x[0], x[-1])
    ax.set_ylim(-vmax, vmax)


def fig11(result, path: Path) -> Path:
    sc = result.scene
    branches = sample_branches(result, max_branches=COLLISIONS_SHOWN + 1, points=300)
    table = result.collision_table()[:COLLISIONS_SHOWN]
    nb = 2
    fig = Figure(figsize=(9, 8), layout="constrained")
    colours = ["C0", "C1", "C2"]
    for k in range(nb):
        ax = fig.add_subplot(2, 1, 2 - k)  # ball 2 upper, ball 1 lower (as the paper)
        a = float(sc.track.angular_stiffness(sc.bodies[k], sc.g))
        rates = np.concatenate([b.states[:, nb + k] for b in branches])
        vmax = max(1.25 * float(np.max(np.abs(rates))), 1.3 * 2 * np.sqrt(a))
        _portrait(ax, a, vmax)
        for n, b in enumerate(branches):
            label = f"branch {n}: " + ("start" if n == 0 else f"collision {n}") + f" to collision {n + 1}"
            ax.plot(b.states[:, k], b.states[:, nb + k], color=colours[n % len(colours)], lw=1.8, label=label)
        phi0, dphi0 = float(sc.phi[k]), float(sc.dphi[k])
        ax.plot([phi0], [dphi0], "o", color="k", ms=5)
        ax.annotate(f"$N_{{{k + 1},0}}$", (phi0, dphi0), textcoords="offset points", xytext=(5, 5), fontsize=9)
        for n, row in enumerate(table, start=1):
            side = "i" if row["i"] == k + 1 else "j"
            phi = row[f"q_{side}"]
            before, after = row[f"dq_{side}_before"], row[f"dq_{side}_after"]
            ax.vlines(phi, before, after, colors="k", linestyles="--", lw=1.0)
            ax.plot([phi], [before], "o", color="k", ms=4.5)
            ax.plot([phi], [after], "s", mfc="white", mec="k", ms=5)
            ax.annotate(
                f"$N_{{{k + 1},impact,{n}}}$", (phi, before), textcoords="offset points", xytext=(6, -2), fontsize=8
            )
            ax.annotate(
                f"$N_{{{k + 1},outgoing,{n}}}$", (phi, after), textcoords="offset points", xytext=(6, -2), fontsize=8
            )
        ax.set_ylabel(f"$\\dot\\varphi_{k + 1}$ (rad/s)")
        ax.set_xlabel(f"$\\varphi_{k + 1}$ (rad)")
        ax.set_title(f"ball {k + 1}: {sc.bodies[k].describe()}", fontsize=9)
        if k == 1:
            ax.legend(fontsize=7, loc="upper right")
    fig.suptitle(
        "Fig. 11: phase trajectory branches with jumps at the first two collisions "
        "(background: single-ball phase portrait, eq. 29; dash-dot: separatrix; x: saddles; dot: centre)\n"
        + parameter_text(sc),
        fontsize=8,
    )
    return _save(fig, path)


# ----------------------------------------------------------------------------- Fig. 12


def _centre(rho, phi):
    """Centre of a ball at angle phi (from the lowest point, counter-clockwise): (rho sin phi, -rho cos phi)."""
    return np.array([rho * np.sin(phi), -rho * np.cos(phi)])


def _configuration(ax, sc, phis, dphis_in, dphis_out, title, contact: bool) -> None:
    R = float(sc.track.radius)
    ax.add_patch(Circle((0, 0), R, fill=False, color="k", lw=1.4))
    ax.plot([0], [0], "+", color="k", ms=8)
    ax.annotate("$C_0$", (0, 0), textcoords="offset points", xytext=(4, 4), fontsize=8)
    ax.plot([0, 0], [0, -R], ":", color="0.6", lw=0.8)
    colours = ("C0", "C3")
    centres = []
    speed_scale = 0.12
    for k, body in enumerate(sc.bodies):
        r = float(body.radius)
        rho = R - r
        c = _centre(rho, phis[k])
        centres.append(c)
        ax.add_patch(Circle(tuple(c), r, fill=True, alpha=0.25, color=colours[k]))
        ax.add_patch(Circle(tuple(c), r, fill=False, color=colours[k], lw=1.2))
        ax.plot([0, c[0]], [0, c[1]], "-", color=colours[k], lw=0.6)
        ax.plot(*c, ".", color=colours[k])
        ax.annotate(f"$C_{k + 1}$", tuple(c), textcoords="offset points", xytext=(3, 3), fontsize=8)
        p = _centre(R, phis[k])  # rolling contact with the track (instantaneous axis P)
        ax.plot(*p, "^", color=colours[k], ms=4)
        tangent = np.array([np.cos(phis[k]), np.sin(phis[k])])
        for rate, ls in ((dphis_in[k], "-"), (dphis_out[k], "--")):
            if rate is None:
                continue
            v = rho * rate * tangent * speed_scale
            ax.annotate(
                "", xy=tuple(c + v), xytext=tuple(c),
                arrowprops=dict(arrowstyle="->", color=colours[k], lw=1.2, ls=ls),
            )
    if contact:
        c1, c2 = centres
        r1 = float(sc.bodies[0].radius)
        point = c1 + r1 * (c2 - c1) / np.linalg.norm(c2 - c1)
        ax.plot(*point, "*", color="k", ms=9)
    ax.set_xlim(-1.08 * R, 1.08 * R)
    ax.set_ylim(-1.08 * R, 1.08 * R)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    ax.set_title(title, fontsize=8)


def fig12(result, path: Path) -> Path:
    sc = result.scene
    table = result.collision_table()[:COLLISIONS_SHOWN]
    fig = Figure(figsize=(4 * (1 + COLLISIONS_SHOWN), 4.6), layout="constrained")
    axes = fig.subplots(1, 1 + COLLISIONS_SHOWN)
    phis = [float(p) for p in sc.phi]
    rates = [float(v) for v in sc.dphi]
    _configuration(
        axes[0], sc, phis, rates, (None, None),
        f"start, t = 0\n$\\varphi_1$ = {phis[0]:.4f}, $\\varphi_2$ = {phis[1]:.4f} rad", contact=False,
    )
    for n, row in enumerate(table, start=1):
        i, j = int(row["i"]) - 1, int(row["j"]) - 1
        ph = [0.0, 0.0]
        before, after = [0.0, 0.0], [0.0, 0.0]
        ph[i], ph[j] = float(row["q_i"]), float(row["q_j"])
        before[i], before[j] = float(row["dq_i_before"]), float(row["dq_j_before"])
        after[i], after[j] = float(row["dq_i_after"]), float(row["dq_j_after"])
        _configuration(
            axes[n], sc, ph, before, after,
            f"collision {n}, t = {float(row['t']):.6f} s\n"
            f"$\\varphi_1$ = {ph[0]:.4f}, $\\varphi_2$ = {ph[1]:.4f} rad ($\\varphi_2 - \\varphi_1 = \\beta$)",
            contact=True,
        )
    fig.suptitle(
        "Fig. 12: configurations at the start and at the first two collisions "
        "(arrows: centre velocities $(R - r)\\dot\\varphi$, solid before, dashed after; triangles: rolling contact P; "
        "star: contact point)\n"
        + parameter_text(sc),
        fontsize=8,
    )
    return _save(fig, path)


# ----------------------------------------------------------------------------- main


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "figures")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)

    sc = scene()
    result = heyroll.simulate(sc, max_collisions=COLLISIONS_SHOWN + 1)
    if result.n_collisions < COLLISIONS_SHOWN + 1:
        print(f"expected {COLLISIONS_SHOWN + 1} collisions, got {result.n_collisions}: {result.message}", file=sys.stderr)
        return 1
    print(f"Scene: {parameter_text(sc, tex=False)}")
    print(f"run: {result.status.value}, {result.message}\n")

    from heyroll.reference.collisions import compare_with_engine, reference_collisions

    ref = reference_collisions(sc, COLLISIONS_SHOWN, dps=30)
    table = result.collision_table()
    cmp = compare_with_engine(table[:COLLISIONS_SHOWN], ref)
    print(f"{'n':>2} {'i,j':>4} {'t (s)':>20} {'q_i':>12} {'q_j':>12} {'phi_i dot in/out':>24} {'phi_j dot in/out':>24} {'t rel. err vs exact':>20}")
    for n in range(COLLISIONS_SHOWN):
        row = table[n]
        d1 = f"{row['dq_i_before']:+.5f}/{row['dq_i_after']:+.5f}"
        d2 = f"{row['dq_j_before']:+.5f}/{row['dq_j_after']:+.5f}"
        print(f"{n + 1:>2} {str(row['i']) + ',' + str(row['j']):>4} {row['t']:>20.15f} {row['q_i']:>12.8f} {row['q_j']:>12.8f} {d1:>24} {d2:>24} {cmp['t_rel'][n]:>20.2e}")
    ok = bool(np.all(cmp["same_pair"]) and np.all(cmp["t_rel"] < 1e-13))

    from heyroll.analysis.series_error import paper_method_first_collision

    print("\nFirst collision by the paper's (56)=(57) with its series (54)-(55), against the exact reference:")
    for kind in ("printed", "corrected", 4, 8, 16, "exact"):
        pm = paper_method_first_collision(sc, kind)
        if pm.ok:
            print(f"  {pm.label:<16} t = {pm.t_series:.10f} s  phi_1 = {pm.phi_series:+.10f} rad  "
                  f"rel. error t {pm.t_rel_error:.2e}, phi_1 {pm.phi_rel_error:.2e}")
        else:
            print(f"  {pm.label:<16} {pm.status}: {pm.message}")
    print(f"  (exact: t = {pm.t_exact:.10f} s, phi_1 = {pm.phi_exact:+.10f} rad; "
          f"convergence ratios max(u^2, k^2 u^2) on the arcs: {', '.join(f'{r:.3f}' for r in pm.ratio)})")

    written = [fig11(result, args.out / "fig11_phase_trajectories.png"), fig12(result, args.out / "fig12_configurations.png")]
    print()
    for path in written:
        print(f"wrote {path}")
    print("\nengine agrees with the exact reference" if ok else "\nENGINE DISAGREES WITH THE REFERENCE")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
