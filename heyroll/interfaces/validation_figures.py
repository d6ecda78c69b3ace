"""Figures of the validation analyses (heyroll.analysis): series error, predictability horizon, Lyapunov.

Each function takes the analysis' result and a path, draws with matplotlib's
object API on the Agg canvas (no pyplot, no global state) and writes a PNG
atomically (``.<name>.tmp`` next to the target, then ``os.replace``).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

__all__ = ["horizon_figure", "lyapunov_figure", "series_error_figure"]

#: log10 relative errors below this (beyond double precision) share the lowest colour.
ERROR_FLOOR_LOG10 = -16.0


def _save(fig: Figure, path) -> Path:
    path = Path(path)
    FigureCanvasAgg(fig)
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        fig.savefig(tmp, format="png", dpi=130)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def series_error_figure(maps, path) -> Path:
    """log10 relative error of the time integral, one panel per series kind.

    ``maps``: a :class:`heyroll.analysis.series_error.SeriesErrorMap` or a
    sequence of them (same regime and grid). Libration maps put the amplitude
    (degrees) on the y axis and phi/phi_max on the x axis (1 = turning point);
    rotation maps k^2 against phi/pi (1 = the top). Contours mark the
    convergence ratio max(u^2, k^2 u^2) = 0.5, 0.9, 0.99 (red, dotted);
    errors below 1e-16 share the lowest colour.
    """
    if not isinstance(maps, (list, tuple)):
        maps = [maps]
    if not maps:
        raise ValueError("no maps to draw")
    regime = maps[0].regime
    fig = Figure(figsize=(4.2 * len(maps) + 1.0, 4.4), layout="constrained")
    axes = fig.subplots(1, len(maps), squeeze=False)[0]
    logs = [np.log10(np.clip(m.rel_error, 10.0**ERROR_FLOOR_LOG10, None)) for m in maps]
    vmin = max(ERROR_FLOOR_LOG10, math.floor(min(float(np.min(x)) for x in logs)))
    vmax = math.ceil(max(float(np.max(x)) for x in logs))
    mesh = None
    for ax, m, lg in zip(axes, maps, logs):
        y = np.degrees(m.parameter) if regime == "libration" else m.parameter
        mesh = ax.pcolormesh(m.fractions, y, lg, shading="nearest", cmap="viridis", vmin=vmin, vmax=vmax)
        levels = [lv for lv in (-12, -8, -4, -2, -1) if vmin < lv < vmax]
        if levels:
            cs = ax.contour(m.fractions, y, lg, levels=levels, colors="w", linewidths=0.6)
            ax.clabel(cs, fmt="%d", fontsize=7)
        rs = ax.contour(m.fractions, y, m.ratio, levels=[0.5, 0.9, 0.99], colors="tab:red", linewidths=0.8, linestyles=":")
        ax.clabel(rs, fmt="%g", fontsize=6)
        ax.set_title(m.label, fontsize=10)
        if regime == "libration":
            ax.set_xlabel(r"$\varphi/\varphi_{max}$ (1: turning point)")
        else:
            ax.set_xlabel(r"$\varphi/\pi$ (1: the top)")
    axes[0].set_ylabel("amplitude $\\varphi_{max}$ (deg)" if regime == "libration" else "$k^2 = 4a/C$")
    fig.colorbar(mesh, ax=list(axes), label="log10 relative error of t", extend="min")
    what = (
        "libration ($k^2 > 1$): time from the lowest point to $\\varphi$"
        if regime == "libration"
        else "rotation ($k^2 < 1$): time from the lowest point to $\\varphi$"
    )
    fig.suptitle(f"Paper series (54) vs Legendre's F, {what}; red dotted: convergence ratio max($u^2, k^2u^2$)", fontsize=9)
    return _save(fig, path)


def horizon_figure(horizon, path) -> Path:
    """Relative difference of double and quad collision times per collision (log scale).

    ``horizon``: a :class:`heyroll.analysis.horizon.HorizonResult`. The
    threshold is drawn as a horizontal line, the first disagreeing collision
    as a vertical one; collisions with a different pair are marked in red.
    Exact agreement (0) is drawn at the bottom of the axis.
    """
    rel = np.asarray(horizon.rel_diff, dtype=float)
    n = np.arange(1, rel.size + 1)
    positive = rel[rel > 0]
    floor = (positive.min() / 3) if positive.size else horizon.threshold * 1e-6
    floor = min(floor, horizon.threshold * 1e-3)
    shown = np.where(rel > 0, rel, floor)
    fig = Figure(figsize=(8, 4.2), layout="constrained")
    ax = fig.add_subplot(1, 1, 1)
    # (the range set first: one collision alone, or all at one value, gave matplotlib a range of zero height)
    values = np.concatenate([shown, [horizon.threshold, 2.0**-52]])
    ax.set_ylim(values.min() / 3, values.max() * 3)
    ax.semilogy(n, shown, ".-", ms=3, lw=0.7, color="C0", label="|t_double - t_quad| / t_quad")
    if not np.all(horizon.same_pair):
        bad = ~np.asarray(horizon.same_pair)
        ax.semilogy(n[bad], shown[bad], "x", color="C3", ms=5, label="different pair")
    ax.axhline(horizon.threshold, color="k", ls="--", lw=0.9, label=f"threshold {horizon.threshold:g}")
    ax.axhline(2.0**-52, color="0.6", ls=":", lw=0.8, label="double epsilon")
    if horizon.first_disagreement is not None:
        ax.axvline(horizon.first_disagreement, color="C3", lw=0.8, ls="-.")
    ax.set_xlabel("collision number")
    ax.set_ylabel("relative difference of t")
    ax.set_title(
        f"Predictability horizon: {horizon.n_agree} of {rel.size} collisions agree "
        f"(double {horizon.wall_time_double:.3g} s, quad {horizon.wall_time_quad:.3g} s wall)",
        fontsize=9,
    )
    ax.legend(fontsize=8, loc="lower right")
    return _save(fig, path)


def lyapunov_figure(estimates, path) -> Path:
    """Running estimate of the largest Lyapunov exponent against time.

    ``estimates``: a :class:`heyroll.analysis.horizon.LyapunovEstimate`, or a
    dict ``{label: estimate}`` to compare scenes. The dotted curve log(t)/t
    is the decay of a regular (non-chaotic) scene, for comparison.
    """
    if not isinstance(estimates, dict):
        estimates = {"scene": estimates}
    fig = Figure(figsize=(8, 4.2), layout="constrained")
    ax = fig.add_subplot(1, 1, 1)
    t_max = 0.0
    for k, (label, est) in enumerate(estimates.items()):
        t = np.asarray(est.times, dtype=float)
        h = np.asarray(est.history, dtype=float)
        if t.size == 0:
            continue
        t_max = max(t_max, float(t[-1]))
        ax.plot(t, h, lw=1.2, color=f"C{k}", label=f"{label}: {est.exponent:.3g} 1/s")
    if t_max > 0:
        tt = np.linspace(min(2.0, t_max / 10), t_max, 200)
        ax.plot(tt, np.log(tt) / tt, ":", color="0.5", label="log(t)/t (regular)")
    ax.axhline(0, color="0.7", lw=0.6)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("running estimate of $\\lambda_{max}$ (1/s)")
    ax.set_title("Largest Lyapunov exponent, two trajectories with renormalisation (Benettin)", fontsize=9)
    ax.legend(fontsize=8)
    return _save(fig, path)
