"""One task of a sweep: run a chunk of points, one ``simulate`` each, and return their columns.

This is what a Dask worker runs (or the sweep's own process, without Dask).
Each point's scene is built by the normal loader from the base scene's parsed
TOML with the point's values written in; heyroll caches compiled integrators
per scene shape in each process, so the first point of a shape in a worker
compiles and the rest reuse it.
"""

from __future__ import annotations

import copy
import threading
from dataclasses import dataclass

import numpy as np

from ..errors import SceneError
from ..interfaces.scene_file import scene_from_dict
from ..simulation.driver import RunOptions, simulate
from ..simulation.result import Status, build_collision_table
from .keys import apply

#: Status of a point whose scene the loader refused (its SceneError is the message).
INVALID_SCENE = "invalid_scene"
#: Status of a point whose run raised an error (its type and text are the message).
ERROR = "error"

#: Columns of the impacts kept per point (--keep impacts:M), from the collision table.
IMPACT_COLUMNS = ("n", "t", "i", "j", "q_i", "q_j", "dq_i_before", "dq_j_before", "dq_i_after", "dq_j_after")
WHOLE_IMPACT_COLUMNS = ("n", "i", "j")

#: A worker started with several threads (``dask worker --nthreads 4``) would run chunks side
#: by side in one process, and the compiled integrators heyroll caches per shape are single
#: objects with their own state: one chunk at a time per process.
_ONE_AT_A_TIME = threading.Lock()


@dataclass(frozen=True)
class Chunk:
    """What a task needs: the base scene's TOML, the KEYs and each point's values, the run options."""

    data: dict
    default_name: str
    keys: tuple
    values: tuple  # one tuple of values per point
    t_end: float | None
    max_collisions: object
    keep: int
    n_bodies: int


class LastImpacts:
    """A collision sink that counts every collision and keeps only the last ``keep`` records.

    With it a point's memory does not grow with its collisions (a long run
    hands its records on in chunks, see heyroll.simulation.driver.CollisionSink).
    """

    def __init__(self, keep: int):
        self.keep = keep
        self.rows = 0
        self._last = None  # (times, numbers, before, after, flags) of the last records

    def open(self, scene, pairs, precision) -> None:
        self.scene, self.pairs, self.precision = scene, pairs, precision

    def write(self, chunk: tuple, first_number: int) -> None:
        self.rows += len(chunk[0])
        if self.keep:
            joined = chunk if self._last is None else tuple(np.concatenate([a, b]) for a, b in zip(self._last, chunk))
            self._last = tuple(a[-self.keep:] for a in joined)

    def close(self) -> None:
        pass

    def table(self) -> np.ndarray:
        """The kept records as collision-table rows (numbered as in the whole run)."""
        if self._last is None:
            return build_collision_table(self.scene, self.pairs, self.precision, [], [], [], [], [])
        times, numbers, before, after, flags = self._last
        return build_collision_table(self.scene, self.pairs, self.precision, times, numbers, before, after, flags,
                                     first_number=self.rows - len(times) + 1)


def empty_columns(count: int, n_bodies: int, keep: int) -> dict:
    """Columns of ``count`` points not run: '' status, -1 counts, NaN numbers, 0 body numbers."""
    columns = {
        "status": np.full(count, "", dtype=object),
        "message": np.full(count, "", dtype=object),
        "collisions": np.full(count, -1, dtype=np.int64),
        "t_final": np.full(count, np.nan),
        "energy_initial": np.full(count, np.nan),
        "energy_final": np.full(count, np.nan),
        "final_state": np.full((count, 2 * n_bodies), np.nan),
    }
    if keep:
        for c in IMPACT_COLUMNS:
            columns[f"impact_{c}"] = (np.zeros((count, keep), dtype=np.int64) if c in WHOLE_IMPACT_COLUMNS
                                      else np.full((count, keep), np.nan))
    return columns


def run_chunk(chunk: Chunk) -> dict:
    """Run every point of ``chunk``; its columns as numpy arrays (see empty_columns), one row per point.

    Raises KeyboardInterrupt if a run was interrupted (Ctrl-C, SIGTERM): a
    chunk is stored whole or not at all.
    """
    with _ONE_AT_A_TIME:
        columns = empty_columns(len(chunk.values), chunk.n_bodies, chunk.keep)
        options = RunOptions(t_end=chunk.t_end, max_collisions=chunk.max_collisions)
        for row, values in enumerate(chunk.values):
            _run_point(chunk, values, options, columns, row)
        return columns


def _run_point(chunk: Chunk, values: tuple, options: RunOptions, columns: dict, row: int) -> None:
    data = point_data(chunk.data, chunk.keys, values)
    try:
        scene = scene_from_dict(data, default_name=chunk.default_name)
    except SceneError as exc:
        columns["status"][row], columns["message"][row] = INVALID_SCENE, str(exc)
        return
    sink = LastImpacts(chunk.keep)
    try:
        result = simulate(scene, options, sink=sink)
    except (ArithmeticError, RuntimeError, ValueError) as exc:  # heyoka's or the driver's refusal of this point
        columns["status"][row], columns["message"][row] = ERROR, f"{exc.__class__.__name__}: {exc}"
        return
    if result.status is Status.INTERRUPTED:
        raise KeyboardInterrupt
    columns["status"][row], columns["message"][row] = result.status.value, result.message
    columns["collisions"][row] = result.n_collisions
    columns["t_final"][row] = float(result.t_final)
    columns["energy_initial"][row] = result.energy_initial
    columns["energy_final"][row] = result.energy_final
    columns["final_state"][row] = np.asarray(result.final_state, dtype=float)
    if chunk.keep:
        table = sink.table()
        for c in IMPACT_COLUMNS:
            columns[f"impact_{c}"][row, :table.size] = table[c]


def point_data(data: dict, keys: tuple, values: tuple) -> dict:
    """A deep copy of the base scene's TOML with the point's values written in."""
    point = copy.deepcopy(data)
    for key, value in zip(keys, values):
        apply(point, key, value)
    return point
