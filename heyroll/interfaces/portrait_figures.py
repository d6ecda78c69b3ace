"""Phase portraits and run figures on every track (paper sections 4-6).

* :func:`portrait_figure`: the complete phase portrait of one body (level
  curves of the first integral, separatrices through the saddles, centres,
  limiters, junctions) with integrated trajectories drawn over it (Figs. 14-16, 19).
  On a circle it is drawn in (phi, phi') over phi in [-pi, pi], whose two
  ends are one point (the top), and the trajectories are wrapped into it.
* :func:`energy_surface_figure`: the total-mechanical-energy surface H(q, q') (Fig. 16b).
* :func:`bifurcation_figure`: equilibria against Omega (section 5.3's theorem).
* :func:`branches_figure` / :func:`body_energy_figure`: a multi-body run's phase
  trajectory branches with the jumps at collisions, and each body's first
  integral through the collisions (Figs. 19-20, energy transfer).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from matplotlib.figure import Figure

from ..analysis.equilibria import EquilibriumProblem, bifurcation_diagram, find_equilibria, problem_of
from ..model.scene import RunSettings, Scene
from ..model.tracks import ArcChainTrack, first_integral
from ..simulation.driver import simulate
from ..simulation.result import SimulationResult
from .figures import _save



def body_energy(scene: Scene, body: int, q, v):
    """First integral of one body (J), float64 (eq. 92)."""
    return first_integral(scene.track, scene.bodies[body], q, v, scene.g, scene.frame)


def speed_factor(scene: Scene, body: int, q):
    """sigma = |dC/dq| of one body at q."""
    return scene.track.sigma(scene.bodies[body], np.asarray(q, dtype=float))

GRID = 500


@dataclass(frozen=True)
class PortraitCheck:
    """Integrated trajectories drawn on a portrait: worst relative drift of H."""

    trajectories: int
    worst_relative_drift: float
    duration: float


def first_integral_grid(scene: Scene, body: int, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """H per unit mass on the (q, v) grid: 1/2 kappa F v^2 + V/m."""
    Q, Vv = np.meshgrid(q, v)
    m = float(scene.bodies[body].mass)
    return body_energy(scene, body, Q.ravel(), Vv.ravel()).reshape(Q.shape) / m


def _velocity_range(scene: Scene, body: int, q: np.ndarray, problem: EquilibriumProblem) -> float:
    V = problem.potential(q)
    F = speed_factor(scene, body, q) ** 2
    kappa = float(scene.bodies[body].kappa)
    spread = float(V.max() - V.min())
    if not spread > 0:  # a flat, fixed track: no potential to scale by; the body's own speed (or 1 unit)
        return 1.15 * max(abs(float(scene.dq[body])), 1.0)
    return 1.15 * float(np.sqrt(2 * spread / (kappa * F.min())))


def _wrapped(q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """An angle's trajectory brought into [-pi, pi), broken (NaN) where it wraps round."""
    w = np.remainder(q + np.pi, 2 * np.pi) - np.pi
    jumps = np.flatnonzero(np.abs(np.diff(w)) > np.pi) + 1
    return np.insert(w, jumps, np.nan), np.insert(v, jumps, np.nan)


def _path_scale(problem: EquilibriumProblem) -> float:
    """A length of the track (m): its parameter range, or the circumference 2 pi rho on a circle."""
    lo, hi = problem.domain
    return (hi - lo) * problem.rho if problem.periodic else hi - lo


def _coordinate_label(scene: Scene) -> tuple[str, str]:
    return {
        "x": ("x (contact abscissa) [m]", "dx/dt [m/s]"),
        "s": ("s (arc length of the centre's path) [m]", "ds/dt [m/s]"),
        "phi": ("phi (angle from the lowest point) [rad]", "dphi/dt [rad/s]"),
        "u": ("u (parameter of the contact point)", "du/dt [1/s]"),
    }[scene.coordinate]


def _junctions(scene: Scene, body: int) -> list[float]:
    if isinstance(scene.track, ArcChainTrack):
        return [p.s0 for p in scene.track.pieces(scene.bodies[body])[1:]]
    return []


def portrait_figure(scene: Scene, path, *, body: int = 0, trajectories: int = 4,
                    duration: float | None = None) -> PortraitCheck:
    problem = problem_of(scene, body)
    lo, hi = problem.domain
    q = np.linspace(lo, hi, GRID)
    vmax = _velocity_range(scene, body, q, problem)
    v = np.linspace(-vmax, vmax, GRID)
    H = first_integral_grid(scene, body, q, v)
    eq = find_equilibria(problem)
    fig = Figure(figsize=(10, 6))
    ax = fig.add_subplot()
    low, high = np.nanmin(H), np.nanpercentile(H, 70)
    if not high > low:  # a flat, fixed track: H is the kinetic energy only, levels by the speed alone
        high = np.nanmax(H) if np.nanmax(H) > low else low + 1.0
    levels = np.linspace(low, high, 28)
    ax.contour(q, v, H, levels=levels, colors="0.6", linewidths=0.6, negative_linestyles="solid")
    saddle_levels = sorted({e.potential for e in eq if e.type == "saddle"})
    if saddle_levels:
        ax.contour(q, v, H, levels=saddle_levels, colors="tab:red", linewidths=1.4, negative_linestyles="solid")
    for e in eq:
        ax.plot(e.q, 0, "o" if e.type == "center" else "x", color="tab:green" if e.type == "center" else "tab:red",
                ms=8, mew=2, clip_on=False, zorder=5)
    if problem.periodic:
        for x in (lo, hi):
            ax.axvline(x, color="k", lw=1, ls="--")
        for e in eq:  # the top, phi = -pi, is phi = pi too
            if e.q <= lo + 1e-9:
                ax.plot(hi, 0, "o" if e.type == "center" else "x",
                        color="tab:green" if e.type == "center" else "tab:red", ms=8, mew=2, clip_on=False, zorder=5)
        ends = "dashed: phi = -pi and pi, the top (one point)"
    else:
        for x in (lo, hi):
            ax.axvline(x, color="k", lw=2)
        ends = "black: limiters"
    for s in _junctions(scene, body):
        ax.axvline(s, color="0.3", lw=0.8, ls="--")
    check = _overlay(scene, body, problem, eq, ax, duration)
    xlabel, ylabel = _coordinate_label(scene)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    omega = float(scene.frame.omega)
    ax.set_title(f"{scene.name}\nphase portrait of body {body + 1}, Omega = {omega:g} rad/s "
                 f"(red: separatrices, o centres, x saddles, {ends}"
                 f"{', dashed: junctions' if _junctions(scene, body) else ''}; colour: integrated)", fontsize=8)
    if problem.periodic:
        ax.set_xlim(lo, hi)
    ax.set_ylim(-vmax, vmax)
    _save(fig, path)
    return check


def _overlay(scene, body, problem, eq, ax, duration) -> PortraitCheck:
    """Integrate a few trajectories and draw them; measure H along each.

    They start at rest between each centre and the next equilibrium, and
    just off the first saddle; on a circle (up to) one more starts at the
    deepest centre fast enough to go round over the top.
    """
    lo, hi = problem.domain
    centres = [e for e in eq if e.type == "center"]
    saddles = [e for e in eq if e.type == "saddle"]
    if problem.periodic:
        period = hi - lo
        starts = [c.q + 0.4 * (min([s.q for s in eq if s.q > c.q] + [eq[0].q + period]) - c.q) for c in centres]
    else:
        starts = [c.q + 0.4 * (min([s.q for s in eq if s.q > c.q] + [hi]) - c.q) for c in centres]
    if saddles:
        starts.append(saddles[0].q + 1e-3 * (hi - lo))
    starts = [(q0, 0.0) for q0 in starts]
    span = _path_scale(problem)
    if problem.periodic:
        starts = starts[:3]
        bottom = min(centres or eq, key=lambda e: e.potential)
        q = np.linspace(lo, hi, GRID)
        barrier = float(np.max(problem.potential(q))) - bottom.potential
        kappa = float(scene.bodies[body].kappa)
        starts.append((bottom.q, float(np.sqrt(2 * 1.2 * barrier / kappa)) / problem.rho))
    starts = starts[:4] or [(lo + 0.3 * (hi - lo), 0.0)]
    worst, T = 0.0, duration or 4 * float(np.sqrt(span / problem.g)) * 3
    bodies = (scene.bodies[body],)
    for k, (q0, v0) in enumerate(starts):
        single = Scene.make(scene.track, bodies, [q0], [v0], law=scene.law,
                            limiter_restitution=1, frame=scene.frame, g=scene.g, run=RunSettings.make(T),
                            name=scene.name)
        res = simulate(single, dense=True, precision="long")
        t, X = res.sample(3000)
        q, v = X[:, 0].astype(float), X[:, 1].astype(float)
        H = body_energy(single, 0, q, v)
        # the run reports a fixed circle's energy with its zero at the bottom (eq. 26), H puts it at y = 0
        h0 = float(body_energy(single, 0, q0, v0)) if problem.periodic else res.energy_initial
        scale = max(abs(h0), float(single.bodies[0].mass) * problem.g * span)
        worst = max(worst, float(np.max(np.abs(H - h0))) / scale)
        if problem.periodic:
            q, v = _wrapped(q, v)
        ax.plot(q, v, lw=0.9, color=f"C{k}")
    return PortraitCheck(trajectories=len(starts), worst_relative_drift=worst, duration=T)


def energy_surface_figure(scene: Scene, path, *, body: int = 0) -> None:
    problem = problem_of(scene, body)
    lo, hi = problem.domain
    q = np.linspace(lo, hi, 160)
    vmax = _velocity_range(scene, body, q, problem)
    v = np.linspace(-vmax, vmax, 120)
    H = first_integral_grid(scene, body, q, v)
    top = surface_top(scene, body, q, problem, H)
    fig = Figure(figsize=(9, 6))
    ax = fig.add_subplot(projection="3d")
    Q, Vv = np.meshgrid(q, v)
    ax.plot_surface(Q, Vv, np.minimum(H, top), cmap="viridis", linewidth=0, antialiased=True, alpha=0.9)
    ax.set_zlim(float(H.min()), top)
    xlabel, ylabel = _coordinate_label(scene)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_zlabel("H / m [J/kg]")
    ax.set_title(f"{scene.name}: first integral (total mechanical energy in the rotating plane) of body {body + 1}"
                 f"\n(cut at H/m = {top:.4g} J/kg: the top of the potential, the body's energy, with a margin)",
                 fontsize=8)
    _save(fig, path)


def surface_top(scene: Scene, body: int, q: np.ndarray, problem: EquilibriumProblem, H: np.ndarray) -> float:
    """Where the energy surface is cut: above the highest potential on the track and the body's
    own energy by a quarter of the range below them. Uncut, the corners of the grid (fast and far
    out) set the scale and the wells and saddles that matter look flat (issue 13)."""
    m = float(scene.bodies[body].mass)
    V = problem.potential(q)
    own = float(body_energy(scene, body, np.array([float(scene.q[body])]), np.array([float(scene.dq[body])]))[0]) / m
    level = max(float(V.max()), own)  # V is per unit mass already
    low = float(H.min())
    return min(float(H.max()), level + 0.25 * max(level - low, 1e-12))


def bifurcation_figure(scene: Scene, path, omegas, *, body: int = 0) -> list:
    """Equilibria against Omega: their contact x on an open track, their phi on a circle
    (where x = R sin(phi) would put the bottom and the top on one point)."""
    problem = problem_of(scene, body)
    diagram = bifurcation_diagram(problem, omegas)
    fig = Figure(figsize=(8, 5))
    ax = fig.add_subplot()
    where = (lambda e: e.q) if problem.periodic else (lambda e: e.x)
    for kind, colour, marker in (("center", "tab:green", "."), ("saddle", "tab:red", "x")):
        pts = [(om, where(e)) for om, eq in diagram for e in eq if e.type == kind]
        if pts:
            ax.plot(*zip(*pts), marker, color=colour, ms=3, ls="none", label=kind)
    ax.axvline(float(scene.frame.omega), color="0.5", ls=":", label="scene's Omega")
    critical = np.sqrt(problem.g / problem.rho) if problem.periodic else None
    if problem.periodic and float(scene.frame.axis_x) == 0 and float(np.max(omegas)) > critical:
        # the closed form of the hoop's pitchfork: cos(phi) = g / (rho Omega^2) beyond sqrt(g / rho)
        om = np.linspace(critical, float(np.max(omegas)), 200)[1:]
        branch = np.arccos(np.clip(problem.g / (problem.rho * om * om), -1, 1))
        ax.plot(om, branch, color="0.4", lw=0.7, label="cos(phi) = g / (rho Omega^2)")
        ax.plot(om, -branch, color="0.4", lw=0.7)
    if isinstance(scene.track, ArcChainTrack) or problem.periodic:
        # the paper's bifurcation parameter of the (first concave) arc, lambda = g / ((R - r) Omega^2)
        rho = problem.rho if problem.periodic else next(
            1 / p.c for p in scene.track.pieces(scene.bodies[body]) if p.c > 0)
        g = float(scene.g)

        def to_lambda(om):
            with np.errstate(divide="ignore"):
                return g / (rho * np.square(om))

        def to_omega(lam):
            with np.errstate(divide="ignore"):
                return np.sqrt(g / (rho * np.asarray(lam)))

        top = ax.secondary_xaxis("top", functions=(to_lambda, to_omega))
        top.set_xlabel(f"lambda = g / ((R - r) Omega^2), R - r = {rho:.4g} m")
        top_om = float(np.max(omegas))
        top.set_xticks([lam for lam in (16, 4, 2, 1, 0.5, 0.25) if np.sqrt(g / (rho * lam)) <= top_om])
    ax.set_xlabel("Omega [rad/s]")
    ax.set_ylabel("phi of the equilibrium [rad]" if problem.periodic else "x of the equilibrium's contact point [m]")
    ax.legend(fontsize=8)
    ax.set_title(f"{scene.name}: relative equilibria of body {body + 1} against Omega", fontsize=9)
    _save(fig, path)
    return diagram


def branches_figure(result: SimulationResult, path, *, max_points: int = 4000) -> None:
    """Each body's phase trajectory from a dense run, as the circle's Fig. 11: the body's own level
    curves of its first integral behind, one colour per branch on a scale of collision number,
    jumps at collisions (dots incoming, squares outgoing), junctions dashed, limiter impacts x."""
    from matplotlib import cm, colors

    scene = result.scene
    t, X = result.sample(max_points)
    table = result.collision_table()
    times = np.asarray(table["t"], dtype=float)
    n = len(scene.bodies)
    xlabel, ylabel = _coordinate_label(scene)
    fig = Figure(figsize=(9, 3.4 * n), layout="constrained")
    norm = colors.Normalize(0, max(len(times), 1))
    cmap = cm.viridis
    passages = result.passages
    for b in range(n):
        ax = fig.add_subplot(n, 1, b + 1)
        q, v = X[:, b], X[:, n + b]
        span = max(float(np.ptp(q)), 1e-9)
        vmax = 1.15 * max(float(np.max(np.abs(v))), 1e-9)
        qg = np.linspace(float(q.min()) - 0.05 * span, float(q.max()) + 0.05 * span, 220)
        vg = np.linspace(-vmax, vmax, 160)
        with np.errstate(all="ignore"):
            H = first_integral_grid(scene, b, qg, vg)
        if np.all(np.isfinite(H)) and np.ptp(H) > 0:
            ax.contour(qg, vg, H, levels=24, colors="0.82", linewidths=0.5, negative_linestyles="solid")
        seg = np.searchsorted(times, t, side="right")
        for k in np.unique(seg):
            sel = seg == k
            ax.plot(q[sel], v[sel], lw=1.0, color=cmap(norm(k)))
        for row in table:
            if b + 1 in (row["i"], row["j"]):
                side = "i" if row["i"] == b + 1 else "j"
                qc, v0, v1 = row[f"q_{side}"], row[f"dq_{side}_before"], row[f"dq_{side}_after"]
                ax.plot([qc, qc], [v0, v1], "k--", lw=0.6)
                ax.plot(qc, v0, "o", color="k", ms=3)
                ax.plot(qc, v1, "s", mfc="white", mec="k", ms=3.5)
        for s_j in _junctions(scene, b):
            if qg[0] <= s_j <= qg[-1]:  # only the junctions this body's branches reach
                ax.axvline(s_j, color="0.5", lw=0.7, ls=":")
        ax.set_xlim(qg[0], qg[-1])
        hits = [(float(p[5]), float(p[6]), float(p[7])) for p in passages if int(p[1]) == b and int(p[2]) != 0
                and float(p[0]) <= float(t[-1])]
        for qc, v0, v1 in hits:
            ax.plot([qc, qc], [v0, v1], color="tab:red", lw=0.6, ls="--")
            ax.plot(qc, v0, "x", color="tab:red", ms=5)
        ax.set_ylim(-vmax, vmax)
        ax.ticklabel_format(useOffset=False)
        ax.set_ylabel(f"body {b + 1}: {ylabel}")
        ax.set_title(f"body {b + 1}: {scene.bodies[b].describe()}", fontsize=9)
    ax.set_xlabel(xlabel)
    fig.colorbar(cm.ScalarMappable(norm=norm, cmap=cmap), ax=fig.axes, label="branch (collisions before it)",
                 shrink=0.8)
    shown = int(np.sum(times <= t[-1]))
    fig.suptitle(f"{scene.name}: phase trajectory branches, {shown} collisions\n(grey: the body's own level "
                 "curves; dots incoming, squares outgoing; red x: limiter impacts; dotted: junctions)", fontsize=9)
    _save(fig, path)


def body_energy_figure(result: SimulationResult, path, *, max_points: int = 4000) -> None:
    """Each body's first integral (its mechanical energy in a fixed plane) and their sum along the run."""
    scene = result.scene
    t, X = result.sample(max_points)
    fig = Figure(figsize=(9, 4.2), layout="constrained")
    ax = fig.add_subplot()
    total = 0
    n = len(scene.bodies)
    for b in range(n):
        H = body_energy(scene, b, X[:, b], X[:, n + b])
        total = total + H
        ax.plot(t, H, lw=0.9, label=f"body {b + 1}")
    if n > 1:
        ax.plot(t, total, "k", lw=1.2, label="sum")
    ax.set_xlabel("t [s]")
    name = "Jacobi integral" if scene.frame.rotating else "mechanical energy"
    ax.set_ylabel(f"{name} H [J]")
    ax.ticklabel_format(useOffset=False)
    fig.legend(loc="outside lower center", ncols=n + 1, fontsize=8, frameon=False)
    what = ("energy exchanged between the bodies at collisions" if n > 1
            else "constant between limiter impacts, which change it by their restitution")
    ax.set_title(f"{scene.name}: each body's {name} ({what})", fontsize=9)
    _save(fig, path)
