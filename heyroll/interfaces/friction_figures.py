"""Figures of a rough-track or forced run (paper section 2): modes, energy, stroboscopic section.

:func:`friction_figures` writes, for a run with Coulomb friction
(``result.scene.rough``) or periodic forcing (``result.scene.forcing``):

* ``friction_portrait.png``: each body's phase trajectory (q, q') coloured by its
  friction mode (rolling, sliding+, sliding-, stuck), the jumps at collisions as
  thin dashed vertical segments (q fixed, q' before -> after), and behind them the
  curves of constant mechanical energy of that body alone, the level curves of its
  first integral H(q, q') (:func:`heyroll.model.tracks.first_integral`, eq. 92).
  This is the paper's section 2 method ("energy curves"): on a smooth track a body
  travels along one curve; friction carries it across the curves towards lower
  energy (sliding), or holds it on the axis q' = 0 (stuck), forcing can carry it up,
  and a collision makes it jump from one curve to another at fixed q.
  The trajectory comes from the dense output (``result.sample``) when the run was made
  with ``dense=True``; otherwise only the mode transitions (points) and the jumps are drawn.
* ``friction_energy.png``: each body's mechanical energy H at its mode transitions
  (step points) and the cumulative work friction has dissipated on it
  (``result.transition_work``), with the run's totals in the title: initial and
  final energy, friction work, energy lost in impacts.
* ``stroboscopic.png`` (forced runs with samples): the stroboscopic Poincare section,
  (q, q') of each body once a forcing period.
* ``impact_map.png`` (forced runs with impacts): the impact map of vibro-impact dynamics,
  the forcing's phase nu t + psi (mod 2 pi) at each impact against the impact speed (the
  closing rate of a collision, |q'| at a limiter), coloured by time.

Matplotlib's object API with the Agg canvas (:func:`heyroll.interfaces.figures._save`,
written atomically): nothing global happens on import or on drawing. Empty data
(no transitions, no collisions, no samples) gives emptier figures, never an error.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from ..model.tracks import first_integral
from ..simulation.result import SimulationResult
from .figures import _save
from .portrait_figures import _coordinate_label

#: Friction modes (heyroll.simulation.friction.MODES) and their colours in every figure.
MODE_COLOURS = {
    "rolling": "tab:green",
    "sliding+": "tab:red",
    "sliding-": "tab:blue",
    "stuck": "black",
}
#: A body without a friction mode (a forced run on a smooth track).
NO_MODE = "no friction"
NO_MODE_COLOUR = "0.45"
_MODE_NAMES = tuple(MODE_COLOURS) + (NO_MODE,)
_COLOURS = tuple(MODE_COLOURS.values()) + (NO_MODE_COLOUR,)

#: Points sampled from the dense output for the portrait.
PORTRAIT_POINTS = 4000
#: Grid of the energy curves behind the portrait.
GRID_Q, GRID_V = 320, 220
ENERGY_LEVELS = 24


def friction_figures(result: SimulationResult, out_dir, whole: SimulationResult | None = None) -> dict[str, str]:
    """Write friction_portrait.png, friction_energy.png (and stroboscopic.png) into ``out_dir``.

    ``whole``: the complete run, where ``result`` is its dense re-run up to a few dozen collisions (the
    stroboscopic section and the impact map are the whole run's: cut at the 60th collision, a forced run
    with more before its first period drew no stroboscopic.png, acceptance test). Default: ``result``.

    Returns {name: file name in out_dir}: keys "friction_portrait", "friction_energy" and,
    for a forced run (``result.scene.forcing is not None``) with stroboscopic samples,
    "stroboscopic_figure" (the key "stroboscopic" is the table's, stroboscopic.csv: the figure's took it over
    in summary.json, acceptance test).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    files = {}
    friction_portrait_figure(result, out / "friction_portrait.png")
    files["friction_portrait"] = "friction_portrait.png"
    friction_energy_figure(result, out / "friction_energy.png")
    files["friction_energy"] = "friction_energy.png"
    whole = result if whole is None else whole
    if whole.scene.forcing is not None and _strobe(whole).shape[0] > 0:
        stroboscopic_figure(whole, out / "stroboscopic.png")
        files["stroboscopic_figure"] = "stroboscopic.png"
    if whole.scene.forcing is not None and _impacts(whole)[0].size:
        impact_map_figure(whole, out / "impact_map.png")
        files["impact_map"] = "impact_map.png"
    return files


def _impacts(result: SimulationResult):
    """(t, impact speed, label) of every collision (closing rate q'_i - q'_j) and limiter impact (|q'|)."""
    table = _collisions(result)
    t, speed, label = [], [], []
    if table.size:
        t += [float(x) for x in table["t"]]
        speed += [abs(float(a) - float(b)) for a, b in zip(table["dq_i_before"], table["dq_j_before"])]
        label += [f"collision {int(i)}-{int(j)}" for i, j in zip(table["i"], table["j"])]
    for row in result.passages:
        if row[2] != 0:
            t.append(float(row[0]))
            speed.append(abs(float(row[6])))
            label.append(f"body {row[1] + 1} at a limiter")
    order = np.argsort(t, kind="stable")
    return np.asarray(t)[order], np.asarray(speed)[order], [label[k] for k in order]


def impact_map_figure(result: SimulationResult, path) -> None:
    """The impact map: forcing phase (nu t + psi mod 2 pi) against impact speed, one marker per kind."""
    f = result.scene.forcing
    t, speed, labels = _impacts(result)
    phase = np.mod(float(f.frequency) * t + float(f.phase), 2 * np.pi)
    fig = Figure(figsize=(7.5, 4.8), layout="constrained")
    ax = fig.add_subplot(1, 1, 1)
    markers = dict(zip(sorted(set(labels)), "osD^v<>px*"))
    mappable = None
    for name, marker in markers.items():
        sel = np.array([x == name for x in labels])
        mappable = ax.scatter(phase[sel], speed[sel], c=t[sel], cmap="viridis", vmin=float(t.min()),
                              vmax=float(t.max()) if t.max() > t.min() else float(t.min()) + 1, marker=marker,
                              s=14 if t.size < 500 else 4, edgecolors="none", label=name)
    if mappable is not None:
        fig.colorbar(mappable, ax=ax, label="t (s)")
    ax.set_xlim(0, 2 * np.pi)
    ax.set_xlabel("forcing phase at impact, nu t + psi (mod 2 pi) [rad]")
    ax.set_ylabel("impact speed (closing rate, or |q'| at a limiter)")
    ax.legend(fontsize=7, loc="best")
    # (a run streamed to its table keeps its first chunk of records: the map says it shows those)
    shown = f"{t.size} impacts" if result.kept_collisions == result.n_collisions else \
        f"the first {t.size} impacts; {result.n_collisions} collisions in the run"
    ax.set_title(f"{result.scene.name}: impact map ({shown}; {f.describe()})", fontsize=8)
    _save(fig, Path(path))


# --------------------------------------------------------------------------- data

def _grid_shape(n_bodies: int) -> tuple[int, int]:
    """One column up to 4 bodies, then up to 4 columns (as portrait figures)."""
    n_cols = min(4, -(-n_bodies // 4))
    return n_cols, -(-n_bodies // n_cols)


def _transitions(result: SimulationResult) -> list[tuple]:
    """Transition rows (t, body0, from, to, q, dq, work) as plain Python values, sorted by t."""
    works = list(result.transition_work)
    rows = []
    for r, (t, body, old, new, q, dq) in enumerate(result.transitions):
        w = float(works[r]) if r < len(works) else np.nan
        rows.append((float(t), int(body), str(old), str(new), float(q), float(dq), w))
    rows.sort(key=lambda row: row[0])
    return rows


def _mode_index(name) -> int:
    try:
        return _MODE_NAMES.index(str(name))
    except ValueError:
        return len(_MODE_NAMES) - 1


def _body_modes(result: SimulationResult, rows: list[tuple], k: int, t: np.ndarray) -> np.ndarray:
    """Index (in _MODE_NAMES) of body k's friction mode at each time t.

    Before the body's first transition: that transition's ``from`` mode; with no
    transition at all: its final mode; at and after a transition: its ``to`` mode
    (the last one when several share an instant).
    """
    mine = [row for row in rows if row[1] == k]
    if not mine:
        finals = list(result.final_modes)
        return np.full(t.shape, _mode_index(finals[k] if k < len(finals) else NO_MODE), dtype=int)
    times = np.array([row[0] for row in mine])
    modes = np.array([_mode_index(mine[0][2])] + [_mode_index(row[3]) for row in mine])
    return modes[np.searchsorted(times, t, side="right")]


def _collisions(result: SimulationResult) -> np.ndarray:
    try:
        return result.collision_table()
    except Exception:  # noqa: BLE001 - a figure never fails on a table it cannot build
        return np.zeros(0, dtype=[("t", float), ("i", int), ("j", int), ("energy_before", float),
                                  ("energy_after", float)])


def _jumps(table: np.ndarray, k: int) -> list[tuple[float, float, float, float]]:
    """Body k's (0-based) collisions: (t, q, q' before, q' after)."""
    out = []
    names = table.dtype.names or ()
    if not {"i", "j", "q_i", "dq_i_before"} <= set(names):
        return out
    for row in table:
        for side in ("i", "j"):
            if int(row[side]) == k + 1:
                out.append((float(row["t"]), float(row[f"q_{side}"]), float(row[f"dq_{side}_before"]),
                            float(row[f"dq_{side}_after"])))
    return out


def _limiter_jumps(result: SimulationResult, k: int) -> list[tuple[float, float, float, float]]:
    """Body k's limiter impacts: (t, q, q' before, q' after)."""
    return [(float(p[0]), float(p[5]), float(p[6]), float(p[7])) for p in result.passages
            if int(p[1]) == k and int(p[2]) != 0]


def _body_energy(result: SimulationResult, k: int, q, dq) -> np.ndarray:
    scene = result.scene
    with np.errstate(all="ignore"):
        return np.asarray(first_integral(scene.track, scene.bodies[k], np.asarray(q, dtype=float),
                                         np.asarray(dq, dtype=float), scene.g, scene.frame), dtype=float)


def _state(result: SimulationResult, which: str) -> np.ndarray | None:
    try:
        return np.asarray([float(x) for x in getattr(result, which)], dtype=float)
    except Exception:  # noqa: BLE001
        return None


def _strobe(result: SimulationResult) -> np.ndarray:
    try:
        table = np.asarray(result.strobe_table, dtype=float)
    except Exception:  # noqa: BLE001
        return np.zeros((0, 1 + 2 * result.n_bodies))
    return table if table.ndim == 2 else np.zeros((0, 1 + 2 * result.n_bodies))


def _impact_losses(table: np.ndarray) -> float:
    names = table.dtype.names or ()
    if table.size == 0 or "energy_before" not in names:
        return 0.0
    loss = np.asarray(table["energy_before"], dtype=float) - np.asarray(table["energy_after"], dtype=float)
    return float(np.nansum(loss))


def _friction_text(scene) -> str:
    if not getattr(scene, "rough", False):
        return "smooth track"
    return (f"mu = {_safe_float(lambda: scene.track_friction):g}, "
            f"mu_s = {_safe_float(lambda: scene.static_coefficient):g}")


def _safe_float(f) -> float:
    try:
        return float(f())
    except Exception:  # noqa: BLE001
        return float("nan")


# --------------------------------------------------------------------------- portrait

def friction_portrait_figure(result: SimulationResult, path) -> None:
    """Each body's (q, q') trajectory coloured by friction mode over its energy curves (section 2)."""
    scene = result.scene
    n = result.n_bodies
    rows = _transitions(result)
    table = _collisions(result)
    dense = bool(result.dense)
    if dense:
        t, X = result.sample(PORTRAIT_POINTS)
        t, X = np.asarray(t, dtype=float), np.asarray(X, dtype=float)
    else:
        t, X = np.zeros(0), np.zeros((0, 2 * n))
    x0, x1 = _state(result, "initial_state"), _state(result, "final_state")
    strobe = _strobe(result)
    xlabel, ylabel = _coordinate_label(scene)
    n_cols, n_rows = _grid_shape(n)
    fig = Figure(figsize=(8 if n_cols == 1 else 4.5 * n_cols, (3.4 if n_cols == 1 else 3.0) * n_rows + 0.6),
                 layout="constrained")
    used = set()
    for k in range(n):
        cell = n - k  # body N on top, as the other portraits
        ax = fig.add_subplot(n_rows, n_cols, cell)
        mine = [row for row in rows if row[1] == k]
        jumps = _jumps(table, k)
        limits = _limiter_jumps(result, k)
        q, v = X[:, k], X[:, n + k]
        # Every point the panel shows: the grid of energy curves covers them all.
        qs = [q, [row[4] for row in mine], [j[1] for j in jumps + limits]]
        vs = [v, [row[5] for row in mine], [j[2] for j in jumps + limits], [j[3] for j in jumps + limits]]
        for x in (x0, x1):
            if x is not None and x.size >= 2 * n:
                qs.append([x[k]])
                vs.append([x[n + k]])
        if not dense and strobe.shape[0] and strobe.shape[1] >= 1 + 2 * n:
            qs.append(strobe[:, 1 + k])
            vs.append(strobe[:, 1 + n + k])
        qs = np.concatenate([np.asarray(a, dtype=float).ravel() for a in qs])
        vs = np.concatenate([np.asarray(a, dtype=float).ravel() for a in vs])
        qs, vs = qs[np.isfinite(qs)], vs[np.isfinite(vs)]
        lo, hi = (float(qs.min()), float(qs.max())) if qs.size else (-1.0, 1.0)
        pad = 0.08 * max(hi - lo, 0.5)
        vmax = 1.15 * max(float(np.max(np.abs(vs))) if vs.size else 0.0, 1e-6)
        if not vmax > 1e-5:
            vmax = 1.0
        qg = np.linspace(lo - pad, hi + pad, GRID_Q)
        vg = np.linspace(-vmax, vmax, GRID_V)
        _energy_curves(result, k, ax, qg, vg, _body_energy(result, k, qs, vs) if qs.size == vs.size else None)
        ax.axhline(0.0, color="0.75", lw=0.5, zorder=0)
        if dense and t.size:
            used |= _mode_trajectory(ax, t, q, v, _body_modes(result, rows, k, t),
                                     sorted(j[0] for j in jumps + limits))
        if mine:
            idx = [_mode_index(row[3]) for row in mine]
            used |= set(idx)
            ax.scatter([row[4] for row in mine], [row[5] for row in mine], s=16, c=[_COLOURS[i] for i in idx],
                       edgecolors="k", linewidths=0.5, zorder=4)
        for _tc, qc, v0, v1 in jumps:
            ax.plot([qc, qc], [v0, v1], color="k", ls="--", lw=0.6, zorder=3)
            ax.plot(qc, v0, "o", color="k", ms=2.5, zorder=3)
            ax.plot(qc, v1, "s", mfc="white", mec="k", ms=3, zorder=3)
        for _tc, qc, v0, v1 in limits:
            ax.plot([qc, qc], [v0, v1], color="tab:purple", ls="--", lw=0.6, zorder=3)
            ax.plot(qc, v0, "x", color="tab:purple", ms=4, zorder=3)
        if not dense and not mine and x0 is not None and x0.size >= 2 * n:
            i0 = _body_modes(result, rows, k, np.zeros(1))[0]
            used.add(int(i0))
            ax.plot(x0[k], x0[n + k], "o", color=_COLOURS[i0], ms=5, zorder=4)
        ax.set_xlim(qg[0], qg[-1])
        ax.set_ylim(-vmax, vmax)
        ax.ticklabel_format(useOffset=False)
        ax.set_ylabel(ylabel, fontsize=8)
        ax.set_title(f"body {k + 1}: {scene.bodies[k].describe()}  ({len(mine)} transitions, "
                     f"{len(jumps)} collisions)", fontsize=8)
        if cell + n_cols > n:
            ax.set_xlabel(xlabel, fontsize=8)
    handles = [Line2D([], [], color=_COLOURS[i], lw=2, label=_MODE_NAMES[i]) for i in sorted(used)]
    handles.append(Line2D([], [], color="k", ls="--", lw=0.8, marker="o", ms=3, label="collision jump"))
    handles.append(Line2D([], [], color="0.7", lw=0.8, label="curves of constant energy of the body alone"))
    fig.legend(handles=handles, loc="outside lower center", ncols=min(len(handles), 4), fontsize=8, frameon=False)
    what = "phase trajectory" if dense else "friction mode transitions (run without dense output: no trajectory)"
    fig.suptitle(f"{scene.name}: {what} coloured by friction mode over the energy curves "
                 f"(paper section 2)\n{_friction_text(scene)}; points: mode transitions "
                 "(colour of the new mode); dashed: jumps at collisions (dots before, squares after)",
                 fontsize=8)
    _save(fig, Path(path))


def _energy_curves(result: SimulationResult, k: int, ax, qg: np.ndarray, vg: np.ndarray, own) -> None:
    """Level curves of body k's first integral on the grid, up to a little above its highest energy."""
    Q, V = np.meshgrid(qg, vg)
    try:
        H = _body_energy(result, k, Q.ravel(), V.ravel()).reshape(Q.shape)
    except Exception:  # noqa: BLE001 - a track that cannot evaluate the grid: no background
        return
    finite = np.isfinite(H)
    if not finite.any():
        return
    low = float(np.min(H[finite]))
    high = float(np.max(H[finite]))
    if own is not None:
        own = np.asarray(own, dtype=float)
        own = own[np.isfinite(own)]
        if own.size:
            top = float(np.max(own))
            high = min(high, top + 0.35 * max(top - low, 1e-12))
    if not high > low:
        return
    levels = np.linspace(low, high, ENERGY_LEVELS + 1)[1:]
    try:
        ax.contour(qg, vg, np.ma.masked_invalid(H), levels=levels, colors="0.72", linewidths=0.5,
                   negative_linestyles="solid", zorder=1)
    except Exception:  # noqa: BLE001
        pass


def _mode_trajectory(ax, t: np.ndarray, q: np.ndarray, v: np.ndarray, modes: np.ndarray, jump_times) -> set:
    """The sampled trajectory as one line collection, coloured by mode, broken at jumps."""
    seg = np.searchsorted(np.asarray(jump_times, dtype=float), t, side="right")
    if t.size < 2:
        return set()
    points = np.column_stack([q, v])
    same_branch = seg[1:] == seg[:-1]
    ok = same_branch & np.all(np.isfinite(points[1:]), axis=1) & np.all(np.isfinite(points[:-1]), axis=1)
    segments = np.stack([points[:-1], points[1:]], axis=1)[ok]
    # A segment takes the mode at its start: a mode change colours from the first sample after it.
    colours = [_COLOURS[i] for i in modes[:-1][ok]]
    if len(segments):
        ax.add_collection(LineCollection(segments, colors=colours, linewidths=1.2, zorder=2))
    return {int(i) for i in modes[:-1][ok]}


# --------------------------------------------------------------------------- energy

def friction_energy_figure(result: SimulationResult, path) -> None:
    """Each body's energy at its mode transitions and the cumulative friction work, run totals in the title."""
    scene = result.scene
    n = result.n_bodies
    rows = _transitions(result)
    table = _collisions(result)
    x0, x1 = _state(result, "initial_state"), _state(result, "final_state")
    t_final = _safe_float(lambda: result.t_final)
    work_final = [float(w) for w in result.friction_work]
    n_cols, n_rows = _grid_shape(n)
    fig = Figure(figsize=(8 if n_cols == 1 else 4.5 * n_cols, (3.0 if n_cols == 1 else 2.7) * n_rows + 0.9),
                 layout="constrained")
    for k in range(n):
        cell = k + 1
        ax = fig.add_subplot(n_rows, n_cols, cell)
        mine = [row for row in rows if row[1] == k]
        t = [row[0] for row in mine]
        E = list(_body_energy(result, k, [row[4] for row in mine], [row[5] for row in mine])) if mine else []
        W = [row[6] for row in mine]
        # The run's ends, so that a body without transitions still shows its energy and work.
        if x0 is not None and x0.size >= 2 * n and not (t and t[0] <= 0.0):
            t.insert(0, 0.0)
            E.insert(0, float(_body_energy(result, k, x0[k], x0[n + k])))
            W.insert(0, 0.0)
        if x1 is not None and x1.size >= 2 * n and np.isfinite(t_final) and not (t and t[-1] >= t_final):
            t.append(t_final)
            E.append(float(_body_energy(result, k, x1[k], x1[n + k])))
            W.append(work_final[k] if k < len(work_final) else (W[-1] if W else np.nan))
        t, E, W = (np.asarray(a, dtype=float) for a in (t, E, W))
        if t.size:
            ax.step(t, E, where="post", color="tab:blue", lw=1.0, marker="o", ms=3, label="energy H at transitions")
            if np.isfinite(W).any():
                ax.step(t, W, where="post", color="tab:red", lw=1.0, marker=".", ms=3,
                        label="cumulative friction work")
                ax.step(t, E + W, where="post", color="0.4", lw=0.8, ls=":", label="H + friction work")
        for tc, *_ in _jumps(table, k):
            ax.axvline(tc, color="k", ls="--", lw=0.5, alpha=0.5)
        ax.ticklabel_format(useOffset=False)
        ax.set_ylabel("J", fontsize=8)
        ax.set_title(f"body {k + 1}: {len(mine)} transitions, friction work "
                     f"{work_final[k] if k < len(work_final) else float('nan'):.4g} J", fontsize=8)
        if cell + n_cols > n:
            ax.set_xlabel("t (s)", fontsize=8)
    handles = [Line2D([], [], color="tab:blue", marker="o", ms=3, lw=1, label="mechanical energy H (eq. 92)"),
               Line2D([], [], color="tab:red", marker=".", ms=3, lw=1, label="cumulative friction work"),
               Line2D([], [], color="0.4", ls=":", lw=0.8, label="H + friction work"),
               Line2D([], [], color="k", ls="--", lw=0.5, label="collision")]
    fig.legend(handles=handles, loc="outside lower center", ncols=4, fontsize=8, frameon=False)
    e0, e1 = _safe_float(lambda: result.energy_initial), _safe_float(lambda: result.energy_final)
    w = float(np.nansum(work_final)) if work_final else 0.0
    impacts = _impact_losses(table)
    rest = e0 - e1 - w - impacts
    fig.suptitle(f"{scene.name}: energy at friction transitions and friction work\n"
                 f"E initial {e0:.6g} J, E final {e1:.6g} J, friction work {w:.6g} J, "
                 f"impact losses {impacts:.6g} J ({table.size} collisions); "
                 f"E0 - E1 - work - impacts = {rest:.3g} J"
                 + (" (the forcing's work)" if scene.forcing is not None else ""), fontsize=8)
    _save(fig, Path(path))


# --------------------------------------------------------------------------- stroboscopic section

def stroboscopic_figure(result: SimulationResult, path) -> None:
    """The stroboscopic Poincare section: each body's (q, q') once a forcing period, coloured by time."""
    scene = result.scene
    n = result.n_bodies
    S = _strobe(result)
    xlabel, ylabel = _coordinate_label(scene)
    n_cols, n_rows = _grid_shape(n)
    fig = Figure(figsize=(7 if n_cols == 1 else 4.5 * n_cols, (3.4 if n_cols == 1 else 3.0) * n_rows + 0.6),
                 layout="constrained")
    t = S[:, 0] if S.shape[0] else np.zeros(0)
    mappable = None
    for k in range(n):
        cell = n - k
        ax = fig.add_subplot(n_rows, n_cols, cell)
        if S.shape[0] and S.shape[1] >= 1 + 2 * n:
            q, v = S[:, 1 + k], S[:, 1 + n + k]
            mappable = ax.scatter(q, v, c=t, cmap="viridis", s=10 if len(t) < 500 else 3, edgecolors="none")
            ax.plot(q[-1:], v[-1:], "o", mfc="none", mec="tab:red", ms=7)
        ax.axhline(0.0, color="0.75", lw=0.5, zorder=0)
        ax.ticklabel_format(useOffset=False)
        ax.set_ylabel(ylabel, fontsize=8)
        ax.set_title(f"body {k + 1}: {scene.bodies[k].describe()}", fontsize=8)
        if cell + n_cols > n:
            ax.set_xlabel(xlabel, fontsize=8)
    if mappable is not None:
        fig.colorbar(mappable, ax=fig.axes, label="t (s)", shrink=0.8)
    f = scene.forcing
    text = ""
    if f is not None:
        try:
            text = f"{f.kind}: {f.describe()}, period {float(f.period):.4g} s; "
        except Exception:  # noqa: BLE001
            text = f"{getattr(f, 'kind', 'forcing')}; "
    fig.suptitle(f"{scene.name}: stroboscopic Poincare section ({text}{S.shape[0]} samples, "
                 "red circle: the last)", fontsize=8)
    _save(fig, Path(path))
