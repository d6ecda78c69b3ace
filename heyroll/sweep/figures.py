"""Figures of a sweep store (matplotlib, Agg): what `heyroll sweep` writes and `heyroll plot` draws.

- one varied KEY, impacts kept: the bifurcation diagram, each point's last M
  impacts as small dots against the parameter: the impact position of body i
  (its coordinate; on a circle phi wrapped to [-pi, pi)) and the closing rate
  dq_i - dq_j just before the impact;
- one varied KEY, summary only: collisions and energy loss against the parameter;
- two varied KEYs: a map of a per-point scalar (energy loss, collisions, ...)
  with a colour bar (a grid as cells, a random sample as coloured dots).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .errors import SweepError
from .store import COORDINATE_UNITS, SPEC_ATTR, open_sweep

#: Per-point scalars for the maps: name -> (values from the Dataset, label with units).
SCALARS = {
    "energy_loss": (lambda ds: ds["energy_initial"] - ds["energy_final"], "energy loss E₀ − E (J)"),
    "collisions": (lambda ds: ds["collisions"].where(ds["collisions"] >= 0), "collisions"),
    "t_final": (lambda ds: ds["t_final"], "t_final (s)"),
    "relative_energy_change": (lambda ds: ds["energy_final"] / ds["energy_initial"] - 1, "E / E₀ − 1"),
}


def sweep_figures(store, out_dir, scalar: str | None = None) -> list[Path]:
    """Draw the figures of the sweep in ``store`` into ``out_dir``; their paths (none for 3 KEYs or more)."""
    import matplotlib

    matplotlib.use("Agg")
    if scalar is not None and scalar not in SCALARS:
        raise SweepError("--scalar", f"must be one of {', '.join(SCALARS)}, got {scalar!r}")
    ds = open_sweep(store)
    spec = json.loads(ds.attrs[SPEC_ATTR])
    keys = [g["key"] for g in spec["grid"]] or [k["key"] for k in spec["random"]["keys"]]
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    title = f"{spec['scene'].get('name', spec['default_name'])}: {ds['status'].size} points"
    if len(keys) == 1:
        if "impact" in ds.dims:
            return [_bifurcation(ds, keys[0], out_dir / "bifurcation.png", title)]
        return [_scalars_1d(ds, keys[0], out_dir / "scalars.png", title, [scalar] if scalar else
                            ["collisions", "energy_loss"])]
    if len(keys) == 2:
        names = [scalar] if scalar else ["energy_loss", "collisions"]
        return [_map(ds, keys, name, out_dir / f"map_{name}.png", title) for name in names]
    return []


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

    coordinate = ds.attrs.get("coordinate", "q")
    unit = COORDINATE_UNITS.get(coordinate, "")
    symbol = {"phi": "φ"}.get(coordinate, coordinate)
    parameter, q = _flat(ds, key, "impact_q_i")
    _, rate_i = _flat(ds, key, "impact_dq_i_before")
    _, rate_j = _flat(ds, key, "impact_dq_j_before")
    if coordinate == "phi":
        q = (q + np.pi) % (2 * np.pi) - np.pi  # the position on the circle, whatever the turns
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7.5, 6.5), sharex=True, constrained_layout=True)
    for ax, y, label in ((top, q, f"{symbol}_i at impact ({unit})"),
                         (bottom, rate_i - rate_j, f"closing rate {symbol}'_i − {symbol}'_j ({unit}/s)")):
        ax.scatter(parameter, y, s=2 if y.size < 20000 else 0.3, color="k", linewidths=0)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    bottom.set_xlabel(_label(ds, key))
    top.set_title(f"{title}, last {ds.sizes['impact']} impacts each (i: the body before the contact)", fontsize=10)
    return _save(fig, path)


def _flat(ds, key: str, name: str) -> tuple:
    """(parameter, value) for every filled impact slot of every point, as flat arrays."""
    values = ds[name]
    parameter = ds[key].broadcast_like(values)
    filled = (ds["impact_n"] > 0).values
    return np.asarray(parameter.values)[filled], np.asarray(values.values, dtype=float)[filled]


def _scalars_1d(ds, key: str, path: Path, title: str, names: list) -> Path:
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(names), 1, figsize=(7.5, 2.2 + 2.2 * len(names)), sharex=True,
                             constrained_layout=True, squeeze=False)
    order = np.argsort(ds[key].values)
    for ax, name in zip(axes[:, 0], names):
        values, label = SCALARS[name]
        ax.plot(ds[key].values[order], np.asarray(values(ds).values, dtype=float)[order], ".-", ms=3, lw=0.6)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel(_label(ds, key))
    axes[0, 0].set_title(title)
    return _save(fig, path)


def _map(ds, keys: list, name: str, path: Path, title: str) -> Path:
    import matplotlib.pyplot as plt

    values, label = SCALARS[name]
    z = values(ds)
    fig, ax = plt.subplots(figsize=(7, 5.5), constrained_layout=True)
    if "point" in ds.dims:
        art = ax.scatter(ds[keys[0]].values, ds[keys[1]].values, c=np.asarray(z.values, dtype=float), s=12,
                         cmap="viridis")
    else:
        z = z.transpose(keys[1], keys[0])
        art = ax.pcolormesh(ds[keys[0]].values, ds[keys[1]].values, np.ma.masked_invalid(np.asarray(z.values, float)),
                            shading="nearest", cmap="viridis")
    fig.colorbar(art, ax=ax, label=label)
    ax.set_xlabel(_label(ds, keys[0]))
    ax.set_ylabel(_label(ds, keys[1]))
    missing = int(np.isnan(np.asarray(z.values, dtype=float)).sum())
    ax.set_title(f"{title}" + (f"; {missing} invalid or not run" + ("" if "point" in ds.dims else " (blank)")
                               if missing else ""))
    return _save(fig, path)
