"""The sweep's store: one xarray Dataset in DIR/sweep.zarr (Zarr format 3), written chunk by chunk.

Layout (README, "Sweeps"): one dimension per varied KEY, named by the KEY,
its values as the coordinate (a random sample: a ``point`` dimension with the
sampled values as coordinates along it); per point ``status``, ``message``,
``collisions``, ``t_final``, ``energy_initial``, ``energy_final``,
``final_state`` (dimension ``state``: phi1..phiN, dphi1..dphiN; s or x on a
path track; x1, y1, vx1, vy1, slip_x1, slip_y1, ... on a billiard table), and with --keep impacts:M the last M impacts as ``impact_*``
variables with a trailing ``impact`` dimension of length M (padded: NaN, and
0 for the body and collision numbers, where a point had fewer than M
collisions). Attributes:
the sweep's spec (``heyroll_sweep_spec``, JSON), versions, the base scene's
text and source, the command.

Why a kill never corrupts it: the store is created complete (every variable
at its fill value, the coordinates written) under a temporary name and renamed
into place; a chunk of points is written as region writes aligned to the Zarr
chunks, whose files the local store replaces atomically, ``status`` last. A
point is stored when its status is not '': a chunk interrupted before its
status write is run again, and its rewrite gives the same bytes.
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np

from .errors import SweepStoreError
from .plan import SweepPlan
from .points import TABLE_STATE, empty_columns

STORE_NAME = "sweep.zarr"
SPEC_ATTR = "heyroll_sweep_spec"
#: Temporary files of the Zarr local store's atomic writes (``<name>.<uuid hex>.partial``): what a
#: SIGKILL in the middle of a chunk write leaves behind.
_PARTIAL = re.compile(r"\.[0-9a-f]{32}\.partial$")

#: Descriptions and units of the per-point variables ('{q}' is the track's coordinate unit).
VARIABLES = {
    "status": ("how the point's run ended: a heyroll status, invalid_scene (the loader refused the scene), "
               "error (the run raised); '' not run yet", ""),
    "message": ("the run's message, or the SceneError of an invalid scene", ""),
    "collisions": ("collisions in the run (-1: not run)", ""),
    "t_final": ("time where the run stopped", "s"),
    "energy_initial": ("total mechanical energy (first integral on a turning plane) at t = 0", "J"),
    "energy_final": ("total mechanical energy at t_final", "J"),
    "final_state": ("state at t_final: coordinates, then their rates", ""),
}
#: The impact columns, kept as the last M (impact_*, --keep impacts:M) or the first M (first_impact_*, first:M).
_IMPACT = {
    "n": ("collision number within the run (0: empty slot)", ""),
    "t": ("collision time", "s"),
    "i": ("body before the contact, from 1 (0: empty slot)", ""),
    "j": ("body after the contact, from 1 (0: empty slot)", ""),
    "q_i": ("coordinate of body i at the collision", "{q}"),
    "q_j": ("coordinate of body j at the collision", "{q}"),
    "dq_i_before": ("rate of body i before the collision", "{q}/s"),
    "dq_j_before": ("rate of body j before the collision", "{q}/s"),
    "dq_i_after": ("rate of body i after the collision", "{q}/s"),
    "dq_j_after": ("rate of body j after the collision", "{q}/s"),
    # a table scene's (billiards): j = 0 at a cushion impact
    "x_i": ("x of ball i's centre at the impact", "m"),
    "y_i": ("y of ball i's centre at the impact", "m"),
    "vx_i_after": ("x velocity of ball i after the impact", "m/s"),
    "vy_i_after": ("y velocity of ball i after the impact", "m/s"),
    "boundary_s": ("cushion impacts: arc length along the cushion of the contact point, counter-clockwise "
                   "(Birkhoff coordinate)", "m"),
    "reflection_angle": ("cushion impacts: angle of the outgoing velocity from the inward normal, > 0 toward "
                         "the counter-clockwise tangent (Birkhoff coordinate)", "rad"),
    "law_flag": ("how the impact was resolved (heyroll.simulation.table.result: 0 the law)", ""),
}
for _prefix, _which in (("impact_", "last"), ("first_impact_", "first")):
    for _c, (_text, _units) in _IMPACT.items():
        VARIABLES[f"{_prefix}{_c}"] = (f"{_text} ({_which} impacts kept, oldest first)", _units)
VARIABLES.update({
    "strobe_t": ("time of a stroboscopic sample (once a forcing period; the last M kept, oldest first)", "s"),
    "strobe_state": ("state at a stroboscopic sample: coordinates, then their rates", ""),
    "period": ("period p of the impact sequence: the smallest p <= 32 with which its last max(16, 2p) impacts "
               "repeat (pair, positions, outgoing rates to 1e-6 relative); 0: none (transient or chaotic); "
               "-1: not run", ""),
    "period_time": ("time T of one cycle of p impacts (nan where period is 0)", "s"),
    "lyapunov": ("largest Lyapunov exponent (Benettin, heyroll.analysis.horizon.lyapunov_estimate) over "
                 "the point's run time; nan where not estimated (see lyapunov_message)", "1/s"),
    "lyapunov_error": ("standard error of lyapunov over blocks of renormalisation segments", "1/s"),
    "lyapunov_message": ("the estimate's summary, or why there is none", ""),
    "rotation": ("rotation number: net turns of body 1 per second, (phi_final - phi_initial) / (2 pi t_final); "
                 "circle scenes only (nan elsewhere)", "1/s"),
})
COORDINATE_UNITS = {"phi": "rad", "s": "m", "x": "m"}


def store_path(out_dir: Path) -> Path:
    return Path(out_dir) / STORE_NAME


def template(plan: SweepPlan, attrs: dict):
    """The whole store as an xarray Dataset with every point not run yet (its fill values)."""
    import xarray as xr

    dims, shape = plan.dims, plan.shape
    columns = empty_columns(plan.n_points, plan.n_bodies, plan.keep, plan.table)
    q = plan.coordinate
    unit = COORDINATE_UNITS.get(q, "")
    variables = {}
    for name, column in columns.items():
        description, units = VARIABLES[name]
        variables[name] = (_dims(name, dims), column.reshape(shape + column.shape[1:]),
                           {"description": description, "units": units.format(q=unit)} if units else
                           {"description": description})
    n = plan.n_bodies
    names = ([f"{c}{k}" for k in range(1, n + 1) for c in TABLE_STATE] if plan.table
             else [f"{q}{k}" for k in range(1, n + 1)] + [f"d{q}{k}" for k in range(1, n + 1)])
    coords = {"state": ("state", np.array(names, dtype=object))}
    if plan.sample is not None:
        coords["point"] = ("point", np.arange(plan.n_points))
        for key, values in zip(plan.keys, plan.sample.values):
            coords[key.text] = ("point", np.array([float(v) for v in values]), _key_attrs(plan, key))
    else:
        for axis in plan.axes:
            dtype = np.int64 if axis.key.whole else float
            coords[axis.key.text] = (axis.key.text, np.array([dtype(v) for v in axis.values]), _key_attrs(plan, axis.key))
    for dim, m in (("impact", plan.keep.impacts), ("first_impact", plan.keep.first), ("strobe", plan.keep.strobe)):
        if m:
            coords[dim] = (dim, np.arange(m))
    return xr.Dataset(variables, coords=coords, attrs=attrs)


def _dims(name: str, dims: tuple) -> tuple:
    """A variable's dimensions: the point dimensions, then ``state``, ``impact``, ``first_impact`` or ``strobe``
    (and ``state``) for the per-point vectors."""
    if name == "final_state":
        return dims + ("state",)
    if name == "strobe_t":
        return dims + ("strobe",)
    if name == "strobe_state":
        return dims + ("strobe", "state")
    if name.startswith("first_impact_"):
        return dims + ("first_impact",)
    return dims + ("impact",) if name.startswith("impact_") else dims


def _key_attrs(plan: SweepPlan, key) -> dict:
    units = plan.units(key)
    return {"long_name": key.text, **({"units": units} if units else {})}


def open_or_create(plan: SweepPlan, out_dir: Path, attrs: dict) -> Path:
    """The store of ``plan`` in ``out_dir``: created, or the existing one (its spec checked first: check_spec)."""
    path = store_path(out_dir)
    if path.exists():
        for partial in path.rglob("*.partial"):
            if _PARTIAL.search(partial.name):
                partial.unlink()
        return path
    ds = template(plan, attrs)
    chunks = plan.chunks
    encoding = {name: {"chunks": chunks + ds[name].shape[len(chunks):]} for name in ds.data_vars}
    tmp = path.with_name(f".{path.name}.partial")
    if tmp.exists():  # a creation that was killed: it never was the store
        shutil.rmtree(tmp)
    ds.to_zarr(tmp, mode="w-", encoding=encoding, consolidated=False, zarr_format=3)
    tmp.rename(path)
    return path


def check_spec(path: Path, plan: SweepPlan, versions: dict) -> None:
    """Refuse a store that is not this sweep's (one line naming what differs); nothing is written."""
    import zarr

    try:
        stored = dict(zarr.open_group(str(path), mode="r").attrs)
    except Exception as exc:  # not a Zarr group at all: whatever zarr raises, the answer is the same
        raise SweepStoreError("--out", f"{path} exists and is not a heyroll sweep store ({exc.__class__.__name__}): "
                              "use another --out or remove it") from None
    if SPEC_ATTR not in stored:
        raise SweepStoreError("--out", f"{path} exists and is not a heyroll sweep store: use another --out or remove it")
    old, new = (_comparable(spec) for spec in (json.loads(stored[SPEC_ATTR]), json.loads(json.dumps(plan.spec()))))
    if old != new:
        what = ", ".join(k for k in [*new, *(k for k in old if k not in new)] if old.get(k) != new.get(k)) or "format"
        raise SweepStoreError("--out", f"{path} belongs to a different sweep ({what} differ): "
                              "use another --out, or remove it to start again")
    if stored.get("versions") != versions:
        raise SweepStoreError("--out", f"{path} was written with other versions ({stored.get('versions')}): "
                              "resume it with those, or remove it to start again")


def _comparable(spec: dict) -> dict:
    """A sweep's spec as two sweeps of the same points compare: a grid by its values, each as a number, not by
    the text it was given in (review: ``0.50:1.2:8`` refused to resume the store of ``0.5:1.2:8``)."""
    from decimal import Decimal, InvalidOperation

    def number(text):
        try:
            return str(Decimal(text).normalize())
        except (InvalidOperation, TypeError, ValueError):
            return text

    grid = [{k: ([number(v) for v in axis[k]] if k == "values" else axis[k]) for k in axis if k != "spec"}
            for axis in spec.get("grid") or []]
    return {**spec, "grid": grid}


def stored_mask(path: Path) -> np.ndarray:
    """Which points are stored (flat, C order): their status is not ''."""
    import zarr

    status = zarr.open_array(str(path / "status"), mode="r")[...]
    return np.asarray(status, dtype=object).reshape(-1) != ""


class ChunkWriter:
    """Writes chunks of points into the store, each variable's region straight into its Zarr array.

    The store was created by xarray with plain encodings (no scaling, the
    fill values of ``empty_columns``), so the raw values are what xarray reads
    back; one open group for the whole sweep costs a third of an xarray
    region write per chunk (measured: 18 ms against 60 ms for 7 variables).
    """

    def __init__(self, path: Path):
        import zarr

        self._group = zarr.open_group(str(path), mode="r+")

    def write(self, region: dict, columns: dict) -> None:
        """One chunk's columns (rows in C order over ``region``), ``status`` last: it marks the points stored."""
        index = tuple(region.values())
        shape = tuple(s.stop - s.start for s in index)
        for name in [n for n in columns if n != "status"] + ["status"]:
            column = columns[name]
            self._group[name][index] = column.reshape(shape + column.shape[1:])


def open_sweep(path):
    """A sweep store as an xarray Dataset, loaded into memory."""
    import xarray as xr

    with xr.open_zarr(path, consolidated=False, chunks=None) as ds:
        ds = ds[[name for name in VARIABLES if name in ds.data_vars]].load()  # in VARIABLES' order
    # Zarr's strings come back as numpy's StringDType, which xarray's where() cannot fill with NaN
    # (ds.where(ds.status == "completed") raised DTypePromotionError, acceptance test): unicode arrays.
    for name in list(ds.variables):
        if ds[name].dtype.kind == "T":
            text = np.array(ds[name].values.tolist(), dtype=str)
            ds = ds.assign_coords({name: (ds[name].dims, text, ds[name].attrs)}) if name in ds.coords else \
                ds.assign({name: (ds[name].dims, text, ds[name].attrs)})
    return ds
