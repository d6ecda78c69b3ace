"""Figures of a run: phase portraits with jumps (paper Fig. 11), energy (4.2.6).

Uses matplotlib's object API with the Agg canvas, so nothing global (no
pyplot state, no backend switch) happens on import or on drawing.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ..simulation.result import SimulationResult
from ..simulation.trajectory import sample_branches

#: Branches drawn in a phase portrait: beyond a few dozen the jumps blur.
DEFAULT_PORTRAIT_COLLISIONS = 30


def _save(fig: Figure, path: Path) -> None:
    FigureCanvasAgg(fig)
    tmp = path.with_name(f".{path.name}.tmp")
    fig.savefig(tmp, format="png", dpi=130)
    os.replace(tmp, path)


def phase_portrait_figure(result: SimulationResult, path: Path, *, collisions: int = DEFAULT_PORTRAIT_COLLISIONS) -> None:
    """Each body's (phi, phi') branches between collisions and the jumps at them.

    As in the paper's Fig. 11: the single-body phase portrait in the
    background (closed curves, the separatrix through the saddles at +-pi),
    the branch travelled between collisions, and at each collision a jump at
    fixed phi from the incoming to the outgoing phase curve.
    """
    n_bodies = result.n_bodies
    shown = min(collisions, result.kept_collisions)
    branches = sample_branches(result, max_branches=shown + 1)
    # One column up to 4 bodies, then up to 4 columns (50 bodies in one column made a
    # 1040 x 20800 pixel strip: measured).
    n_cols = min(4, -(-n_bodies // 4))
    n_rows = -(-n_bodies // n_cols)
    fig = Figure(figsize=(8 if n_cols == 1 else 4.5 * n_cols, 3.2 * n_rows if n_cols == 1 else 2.8 * n_rows),
                 layout="constrained")
    stiffness = [float(result.scene.track.angular_stiffness(b, result.scene.g)) for b in result.scene.bodies]
    colours = _branch_colours(len(branches))
    table = result.collision_table()[:shown]
    for k in range(n_bodies):
        # Body N on top, body 1 at the bottom, as in the paper (row by row in a grid).
        cell = n_bodies - k
        ax = fig.add_subplot(n_rows, n_cols, cell)
        phis = np.concatenate([b.states[:, k] for b in branches])
        rates = np.concatenate([b.states[:, n_bodies + k] for b in branches])
        _background(ax, stiffness[k], phis, rates)
        for b, colour in zip(branches, colours):
            ax.plot(b.states[:, k], b.states[:, n_bodies + k], color=colour, lw=1.2)
        for side in ("i", "j"):
            rows = table[table[side] == k + 1]
            if rows.size:
                phi = rows[f"q_{side}"]
                ax.vlines(phi, rows[f"dq_{side}_before"], rows[f"dq_{side}_after"], colors="k", linestyles="--", lw=0.8)
                ax.plot(phi, rows[f"dq_{side}_before"], "o", ms=3.5, color="k", label=None)
                ax.plot(phi, rows[f"dq_{side}_after"], "s", ms=3.5, mfc="white", mec="k")
        ax.set_ylabel(f"$\\dot\\varphi_{{{k + 1}}}$ (rad/s)")
        ax.set_title(f"body {k + 1}: {result.scene.bodies[k].describe()}", fontsize=9)
        if cell + n_cols > n_bodies:  # no cell below it
            ax.set_xlabel("$\\varphi$ (rad)")
    fig.suptitle(
        f"Phase trajectory branches with jumps at collisions (first {shown} of {result.n_collisions}); "
        "dots: incoming, squares: outgoing",
        fontsize=9,
    )
    _save(fig, path)


def _background(ax, a: float, phis: np.ndarray, rates: np.ndarray) -> None:
    """Level curves of the single-body energy phi'^2/2 + 2a sin^2(phi/2) (eq. 28)."""
    lo, hi = float(np.min(phis)), float(np.max(phis))
    pad = 0.15 * max(hi - lo, 0.5)
    vmax = 1.2 * max(float(np.max(np.abs(rates))), 2 * np.sqrt(a) * 0.5)
    x = np.linspace(lo - pad, hi + pad, 300)
    y = np.linspace(-vmax, vmax, 300)
    X, Y = np.meshgrid(x, y)
    H = 0.5 * Y**2 + 2 * a * np.sin(X / 2) ** 2
    ax.contour(X, Y, H, levels=12, colors="0.85", linewidths=0.6)
    ax.contour(X, Y, H, levels=[2 * a], colors="0.55", linewidths=0.9, linestyles="-.")
    ax.axhline(0, color="0.7", lw=0.5)


def _branch_colours(n: int):
    from matplotlib import colormaps

    cmap = colormaps["viridis"]
    return [cmap(x) for x in np.linspace(0.0, 0.9, max(n, 1))]


def energy_figure(result: SimulationResult, path: Path) -> None:
    """Mechanical energy of each body and of the system across collisions (4.2.6)."""
    streamed = result.kept_collisions < result.n_collisions
    t_last = [] if streamed else [float(result.t_final)]
    t = np.concatenate([[0.0], np.asarray(result.times, dtype=float), t_last])
    states = [np.asarray(result.initial_state, dtype=float)]
    states += list(np.asarray(result.states_after, dtype=float))
    if not streamed:
        states.append(np.asarray(result.final_state, dtype=float))
    energies = result.body_energies(np.array(states))
    total0 = energies[0].sum()
    drift = (energies[-1].sum() - total0) / total0 if total0 else 0.0
    if len(t) > LONG_RUN_ROWS:
        _energy_error_figure(result, energies, path, streamed, drift)
        return
    fig = Figure(figsize=(8, 4.2), layout="constrained")
    ax = fig.add_subplot(1, 1, 1)
    for k in range(result.n_bodies):
        ax.step(t, energies[:, k], where="post", lw=1.2, label=f"body {k + 1}")
    ax.step(t, energies.sum(axis=1), where="post", color="k", lw=1.4, label="system")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("mechanical energy (J)")
    ax.set_title(
        f"Energy exchanged at {result.kept_collisions}"
        + (f" (the first, of {result.n_collisions})" if streamed else "")
        + " collisions "
        f"(law {result.scene.law.name}, k = {float(result.scene.law.restitution):g}; "
        f"relative change of the total {drift:.2e})",
        fontsize=9,
    )
    ax.legend(fontsize=8)
    _save(fig, path)


#: Beyond this many states the step plot of every body's energy is a solid block: a long run
#: shows the system's energy error against collision number instead.
LONG_RUN_ROWS = 400


def _energy_error_figure(result: SimulationResult, energies: np.ndarray, path: Path, streamed: bool,
                         drift: float) -> None:
    """E/E0 - 1 of the system after each collision (thinned to ~4000 points), legend off the data."""
    total = energies.sum(axis=1)
    total0 = total[0]
    error = total / total0 - 1 if total0 else total - total0
    n = np.arange(len(total))
    step = max(1, len(total) // 4000)
    fig = Figure(figsize=(8, 4.2), layout="constrained")
    ax = fig.add_subplot(1, 1, 1)
    ax.plot(n[::step], error[::step], ",", color="k", alpha=0.6, label="system, after each collision")
    ax.axhline(0.0, color="0.6", lw=0.8)
    ax.set_xlabel("collision number")
    ax.set_ylabel("E / E0 - 1" if total0 else "E - E0 (J)")
    ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3), useOffset=False)
    law = result.scene.law
    conservative = float(law.restitution) == 1
    ax.set_title(
        f"Energy {'error' if conservative else 'change'} over {result.kept_collisions}"
        + (f" (the first, of {result.n_collisions})" if streamed else "")
        + f" collisions (law {law.name}, k = {float(law.restitution):g}; final {drift:.2e}"
        + (f"; every {step}th shown" if step > 1 else "") + ")",
        fontsize=9,
    )
    fig.legend(loc="outside lower center", fontsize=8, frameon=False)
    _save(fig, path)


#: Open tracks: the figures show at most this many collisions of a run (a dense re-run up to there).
FIGURE_COLLISIONS = 60


def run_figures(result: SimulationResult, out_dir: Path) -> dict:
    """phase_portrait.png and energy.png of a run, on every track; returns {name: file}.

    On the circle the branches are re-integrated between the recorded
    collisions (simulation.trajectory). On an open track the figures come
    from heyoka's continuous output of the same run repeated with
    ``dense=True`` up to the FIGURE_COLLISIONS-th collision (junction
    parameters switch inside that run, so no re-integration could skip them).
    """
    scene = result.scene
    # Friction modes and forcing: the branches between collisions are not the smooth track's
    # phase curves; every figure then reads the repeated run's continuous output.
    rough = scene.rough or scene.forcing is not None
    files = {"phase_portrait": "phase_portrait.png", "energy": "energy.png"}
    if scene.track.linear_gap and not rough:
        if not float(result.t_final) > 0:  # (stopped at its start: empty axes were drawn, acceptance test)
            from .outputs import FiguresUnavailable

            raise FiguresUnavailable(f"the run has no trajectory to draw ({result.status.value} at t = 0 s: "
                                     f"{result.message})")
        phase_portrait_figure(result, out_dir / "phase_portrait.png")
        energy_figure(result, out_dir / "energy.png")
        return files
    from ..simulation.driver import simulate
    from .portrait_figures import body_energy_figure, branches_figure

    t_end = float(result.t_final)
    if result.n_collisions > FIGURE_COLLISIONS and result.kept_collisions > FIGURE_COLLISIONS:
        t_end = float(result.times[FIGURE_COLLISIONS])
    if not t_end > 0:
        t_end = float(scene.run.t_end)
    dense = simulate(scene, t_end=t_end, max_collisions=None, precision="double", dense=True)
    if not dense.dense:
        from .outputs import FiguresUnavailable

        raise FiguresUnavailable(f"the run has no trajectory to draw ({dense.status.value} at t = {dense.t_final:.6g} s: "
                                 f"{dense.message})")
    if scene.track.linear_gap:
        phase_portrait_figure(dense, out_dir / "phase_portrait.png")
        energy_figure(dense, out_dir / "energy.png")
    else:
        branches_figure(dense, out_dir / "phase_portrait.png")
        body_energy_figure(dense, out_dir / "energy.png")
    if rough:
        from .friction_figures import friction_figures

        files.update(friction_figures(dense, out_dir, whole=result))
    return files

