"""Figures of a sweep store (matplotlib, Agg): what `heyroll sweep` writes and `heyroll plot` draws.

- one varied KEY, impacts kept: the bifurcation diagram, each point's last M
  impacts as small dots against the parameter: the impact position of body i
  (its coordinate; on a circle phi wrapped to [-pi, pi)) and the closing rate
  dq_i - dq_j just before the impact; on a billiard table the Birkhoff
  coordinates of the cushion impacts among them (arc length, reflection angle);
- one varied KEY, summary only: collisions and energy loss against the parameter;
- two varied KEYs: a map of a per-point scalar (energy loss, collisions, and
  the estimates period, lyapunov, rotation where kept) with a colour bar (a
  grid as cells, a random sample as coloured dots);
- one varied KEY with estimates kept: the estimates against the parameter
  (the Lyapunov exponent with its standard error as bars);
- stroboscopic samples kept (--keep strobe:M): the Poincare section of chosen
  points (a few spread over the sweep by default), each body's (q, q') at the
  samples, one colour per point.
"""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import numpy as np

from .errors import SweepError
from .store import COORDINATE_UNITS, SPEC_ATTR, open_sweep

#: Per-point scalars for the maps: name -> (values from the Dataset, label with units).
SCALARS = {
    "energy_loss": (lambda ds: ds["energy_initial"] - ds["energy_final"], "energy loss E₀ − E (J)"),
    "collisions": (lambda ds: ds["collisions"].where(ds["collisions"] >= 0), "collisions"),
    "t_final": (lambda ds: ds["t_final"], "t_final (s)"),
    "relative_energy_change": (lambda ds: ((ds["energy_final"] - ds["energy_initial"]) / abs(ds["energy_initial"]))
                               .where(ds["energy_initial"] != 0), "(E − E₀) / |E₀|"),
    # The estimates (--keep period, lyapunov, rotation): offered where the store has them.
    "period": (lambda ds: ds["period"].where(ds["period"] >= 0), "period p of the impact sequence (0: none)"),
    "period_time": (lambda ds: ds["period_time"], "time of one impact cycle T (s)"),
    "lyapunov": (lambda ds: ds["lyapunov"], "largest Lyapunov exponent (1/s)"),
    "rotation": (lambda ds: ds["rotation"], "rotation number of body 1 (turns/s)"),
}
#: The scalars drawn by default (the estimates only where kept), in this order.
DEFAULT_SCALARS = ("energy_loss", "collisions", "period", "lyapunov", "rotation")
#: Points whose Poincare section is drawn when none are chosen (spread over the sweep).
POINCARE_POINTS = 6


def available_scalars(ds) -> list:
    """The scalars ``ds`` can give (the estimates' variables must be in the store)."""
    needs = {"period_time": "period"}
    return [name for name in SCALARS
            if name not in ("period", "period_time", "lyapunov", "rotation") or needs.get(name, name) in ds.data_vars]


def sweep_figures(store, out_dir, scalar: str | None = None, points=None) -> list[Path]:
    """Draw the figures of the sweep in ``store`` into ``out_dir``; their paths (none for 3 KEYs or more,
    but the Poincare section).

    ``points``: flat point numbers (C order, as in the store) whose Poincare section is drawn when
    stroboscopic samples are kept (default: up to POINCARE_POINTS spread over the sweep).
    """
    import matplotlib

    matplotlib.use("Agg")
    ds = open_sweep(store)
    if points is not None and "strobe" not in ds.dims:  # refused, not ignored, before anything is drawn
        raise SweepError("--points", "the Poincare section needs stroboscopic samples: run the sweep with "
                                     "--keep strobe:M (forced scenes)")
    if points is not None:
        _check_points(points, ds["status"].size)
    offered = available_scalars(ds)
    if scalar is not None and scalar not in offered:
        raise SweepError("--scalar", f"must be one of {', '.join(offered)}, got {scalar!r}")
    if scalar == "relative_energy_change" and not np.isfinite(np.asarray(SCALARS[scalar][0](ds).values,
                                                                         dtype=float)).any():
        # (an empty figure with a made-up axis was drawn, exit 0: acceptance test, a forced track starting at E = 0;
        # an estimate's NaN says "none found" and is drawn)
        raise SweepError("--scalar", "relative_energy_change is undefined at every point of this store (it is where "
                                     "energy_initial = 0): try energy_loss")
    defaults = [name for name in DEFAULT_SCALARS if name in offered]
    spec = json.loads(ds.attrs[SPEC_ATTR])
    keys = [g["key"] for g in spec["grid"]] or [k["key"] for k in spec["random"]["keys"]]
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    title = f"{spec['scene'].get('name', spec['default_name'])}: {ds['status'].size} points"
    # (review: a 1-D sweep of invalid points drew an empty diagram with no word why; the maps said it)
    statuses = np.asarray(ds["status"].values).reshape(-1)
    for text, count in (("invalid", int((statuses == "invalid_scene").sum())), ("not run", int((statuses == "").sum()))):
        if count:
            title += f", {count} {text}"
    paths = []
    estimates = [name for name in defaults if name in ("period", "lyapunov", "rotation")]
    if len(keys) == 1:
        if "impact" in ds.dims:
            paths.append(_bifurcation(ds, keys[0], out_dir / "bifurcation.png", title))
        if "impact" not in ds.dims or estimates or scalar:
            names = [scalar] if scalar else (["collisions", "energy_loss"] if "impact" not in ds.dims else []) + estimates
            paths.append(_scalars_1d(ds, keys[0], out_dir / "scalars.png", title, names))
    elif len(keys) == 2:
        names = [scalar] if scalar else defaults
        paths += [_map(ds, keys, name, out_dir / f"map_{name}.png", title) for name in names]
    if "strobe" in ds.dims:
        paths.append(poincare(ds, keys, out_dir / "poincare.png", title, points))
    return paths


def _label(ds, key: str) -> str:
    units = ds[key].attrs.get("units")
    return f"{key} ({units})" if units else key


def _save(fig, path: Path) -> Path:
    tmp = path.with_name(f".{path.stem}.tmp.png")
    fig.savefig(tmp, dpi=130)
    tmp.replace(path)  # never a half-written figure under the final name
    import matplotlib.pyplot as plt

    plt.close(fig)
    return path


def _bifurcation(ds, key: str, path: Path, title: str) -> Path:
    import matplotlib.pyplot as plt

    if "impact_boundary_s" in ds.data_vars:
        return _billiard_bifurcation(ds, key, path, title)
    coordinate = ds.attrs.get("coordinate", "q")
    unit = COORDINATE_UNITS.get(coordinate, "")
    symbol = {"phi": "φ"}.get(coordinate, coordinate)
    parameter, q = _flat(ds, key, "impact_q_i")
    _, rate_i = _flat(ds, key, "impact_dq_i_before")
    _, rate_j = _flat(ds, key, "impact_dq_j_before")
    if coordinate == "phi":
        q = (q + np.pi) % (2 * np.pi) - np.pi  # the position on the circle, whatever the turns
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7.5, 6.5), sharex=True, constrained_layout=True)
    _none_to_draw(top, q.size)
    for ax, y, label in ((top, q, f"{symbol}_i at impact ({unit})"),
                         (bottom, rate_i - rate_j, f"closing rate {symbol}'_i − {symbol}'_j ({unit}/s)")):
        ax.scatter(parameter, y, s=2 if y.size < 20000 else 0.3, color="k", linewidths=0)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    bottom.set_xlabel(_label(ds, key))
    _title(top, f"{title}, last {ds.sizes['impact']} impacts each (i: the body before the contact)", fontsize=10)
    return _save(fig, path)


def _billiard_bifurcation(ds, key: str, path: Path, title: str) -> Path:
    """A table sweep: the Birkhoff coordinates (arc length s along the cushion, reflection angle) of
    each point's last cushion impacts against the parameter (ball-ball impacts are left out)."""
    import matplotlib.pyplot as plt

    cushion = (ds["impact_j"] == 0) & (ds["impact_n"] > 0)
    parameter, s = _flat(ds, key, "impact_boundary_s", cushion)
    _, angle = _flat(ds, key, "impact_reflection_angle", cushion)
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7.5, 6.5), sharex=True, constrained_layout=True)
    _none_to_draw(top, s.size)
    for ax, y, label in ((top, s, "arc length s along the cushion (m)"),
                         (bottom, angle, "reflection angle from the normal (rad)")):
        ax.scatter(parameter, y, s=2 if y.size < 20000 else 0.3, color="k", linewidths=0)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    bottom.set_xlabel(_label(ds, key))
    _title(top, f"{title}: cushion impacts among the last {ds.sizes['impact']} impacts each (Birkhoff "
           "coordinates)", fontsize=10)
    return _save(fig, path)


def _none_to_draw(ax, count: int) -> None:
    """Say so on an empty diagram (no point has an impact kept: each invalid, not run or without impacts)."""
    if not count:
        ax.text(0.5, 0.5, "no impacts to draw: see the title and the store's status", transform=ax.transAxes,
                ha="center", va="center", color="0.4")


def _title(ax, text: str, fontsize: float = 12) -> None:
    """``text`` over ``ax``, broken into lines that fit the figure's width (a scene's name and a long
    description would run past the edge)."""
    width_pt = ax.figure.get_figwidth() * 72
    ax.set_title(textwrap.fill(text, width=max(20, int(width_pt / (0.55 * fontsize)))), fontsize=fontsize)


def _flat(ds, key: str, name: str, where=None) -> tuple:
    """(parameter, value) for every filled impact slot of every point (of those ``where`` is true), flat."""
    values = ds[name]
    parameter = ds[key].broadcast_like(values)
    filled = (ds["impact_n"] > 0 if where is None else where).values
    return np.asarray(parameter.values)[filled], np.asarray(values.values, dtype=float)[filled]


def _scalars_1d(ds, key: str, path: Path, title: str, names: list) -> Path:
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(names), 1, figsize=(7.5, 2.2 + 2.2 * len(names)), sharex=True,
                             constrained_layout=True, squeeze=False)
    order = np.argsort(ds[key].values)
    for ax, name in zip(axes[:, 0], names):
        values, label = SCALARS[name]
        y = np.asarray(values(ds).values, dtype=float)[order]
        ax.plot(ds[key].values[order], y, ".-", ms=3, lw=0.6)
        if name == "lyapunov":
            error = np.asarray(ds["lyapunov_error"].values, dtype=float)[order]
            ax.errorbar(ds[key].values[order], y, yerr=error, fmt="none", ecolor="0.5", lw=0.6, capsize=2)
            ax.axhline(0, color="0.6", lw=0.5)
        # (wrapped: a panel is ~2 inches high, and "period p of the impact sequence" ran into the one above)
        ax.set_ylabel("\n".join(textwrap.wrap(label, 22)), fontsize=9)
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel(_label(ds, key))
    _title(axes[0, 0], title)
    return _save(fig, path)


def _map(ds, keys: list, name: str, path: Path, title: str) -> Path:
    import matplotlib.pyplot as plt

    values, label = SCALARS[name]
    z = values(ds)
    status = ds["status"]
    fig, ax = plt.subplots(figsize=(7, 5.5), constrained_layout=True)
    if "point" in ds.dims:
        art = ax.scatter(ds[keys[0]].values, ds[keys[1]].values, c=np.asarray(z.values, dtype=float), s=12,
                         cmap="viridis")
    else:
        z, status = z.transpose(keys[1], keys[0]), status.transpose(keys[1], keys[0])
        art = ax.pcolormesh(ds[keys[0]].values, ds[keys[1]].values, np.ma.masked_invalid(np.asarray(z.values, float)),
                            shading="nearest", cmap="viridis")
    blank = np.isnan(np.asarray(z.values, dtype=float))
    if blank.all():  # (a colour bar of nothing read -0.1..0.1)
        ax.text(0.5, 0.5, f"no point has a value of {name}: see the title", transform=ax.transAxes,
                ha="center", va="center", color="0.4")
    else:
        fig.colorbar(art, ax=ax, label=label)
    ax.set_xlabel(_label(ds, keys[0]))
    ax.set_ylabel(_label(ds, keys[1]))
    # a blank point is one that did not run (invalid scene, not yet run) or one that ran with no value (no period
    # found, no Lyapunov estimate on its track: every point of a rough track was called "invalid or not run", review)
    statuses = np.asarray(status.values)
    failed = int((blank & ((statuses == "invalid_scene") | (statuses == ""))).sum())
    valueless = int(blank.sum()) - failed
    notes = ([f"{failed} invalid or not run"] if failed else []) + ([f"{valueless} ran with no value"] if valueless
                                                                    else [])
    _title(ax, f"{title}" + (f"; {', '.join(notes)}" + ("" if "point" in ds.dims else " (blank)") if notes else ""))
    return _save(fig, path)


def _check_points(points, total: int) -> list[int]:
    chosen = [int(p) for p in points]
    bad = [p for p in chosen if not 0 <= p < total]
    if bad:
        raise SweepError("--points", f"point numbers run from 0 to {total - 1}, got {bad}")
    return chosen


def poincare(ds, keys: list, path: Path, title: str, points=None) -> Path:
    """The stroboscopic Poincare section of chosen points: each body's (q, q') at the kept samples,
    one colour per point (a circle's phi wrapped to [-pi, pi))."""
    import matplotlib.pyplot as plt

    dims = ds["status"].dims
    shape = ds["status"].shape
    total = int(np.prod(shape))
    t = np.asarray(ds["strobe_t"].values, dtype=float).reshape(total, -1)
    state = np.asarray(ds["strobe_state"].values, dtype=float).reshape(total, t.shape[1], -1)
    with_samples = [p for p in range(total) if np.isfinite(t[p]).any()]
    if points is None:
        chosen = [with_samples[int(round(k))] for k in
                  np.linspace(0, len(with_samples) - 1, min(POINCARE_POINTS, len(with_samples)))] if with_samples else []
        chosen = list(dict.fromkeys(chosen))
    else:
        chosen = _check_points(points, total)
    n = state.shape[2] // 2
    coordinate = ds.attrs.get("coordinate", "q")
    unit = COORDINATE_UNITS.get(coordinate, "")
    symbol = {"phi": "φ"}.get(coordinate, coordinate)
    fig, axes = plt.subplots(1, n, figsize=(4.2 * n + 1.5, 4.2), constrained_layout=True, squeeze=False)
    for p in chosen:
        index = np.unravel_index(p, shape)
        label = ", ".join(f"{k} = {float(ds[k].values[index[dims.index(ds[k].dims[0])]]):.4g}" for k in keys)
        filled = np.isfinite(t[p])
        for b, ax in enumerate(axes[0]):
            q = state[p, filled, b]
            if coordinate == "phi":
                q = (q + np.pi) % (2 * np.pi) - np.pi
            ax.scatter(q, state[p, filled, n + b], s=8, label=label if b == 0 else None)
    for b, ax in enumerate(axes[0]):
        ax.set_xlabel(f"{symbol}{b + 1} ({unit})")
        ax.set_ylabel(f"{symbol}'{b + 1} ({unit}/s)")
        ax.grid(alpha=0.3)
    if chosen:
        axes[0, 0].legend(fontsize=7, loc="best")
    fig.suptitle(f"{title}\nstroboscopic section (last {ds.sizes['strobe']} samples, once a forcing period) of "
                 f"{len(chosen)} points", fontsize=10)
    return _save(fig, path)
