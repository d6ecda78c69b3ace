"""Sweeps: many scenes from one, with one or more scene fields varied (issue 16).

    from heyroll.sweep import run_sweep
    ds = run_sweep("scene.toml", vary={"collision.restitution": (0.5, 1.0, 11)}, keep="impacts:20")
    ds["collisions"], ds["impact_q_i"]           # an xarray Dataset, stored in heyroll-sweep/sweep.zarr

``keys`` (KEY paths), ``plan`` (grid, list and random points), ``points``
(one task: a chunk of points, one simulate each), ``store`` (the Zarr store),
``run`` (Dask or in-process), ``figures``. Needs the ``sweep`` extra
(xarray, zarr, dask[distributed], pyarrow): ``pip install 'heyroll[sweep]'``.
"""

from .errors import SchedulerError, SweepError, SweepKeyError, SweepStoreError
from .run import run_sweep
from .store import open_sweep

__all__ = ["SchedulerError", "SweepError", "SweepKeyError", "SweepStoreError", "open_sweep", "run_sweep"]
