"""One task of a sweep: run a chunk of points, one ``simulate`` each, and return their columns.

This is what a Dask worker runs (or the sweep's own process, without Dask).
Each point's scene is built by the normal loader from the base scene's parsed
TOML with the point's values written in; heyroll caches compiled integrators
per scene shape in each process, so the first point of a shape in a worker
compiles and the rest reuse it.
"""

from __future__ import annotations

import copy
import math
import threading
from dataclasses import dataclass

import numpy as np

from ..errors import SceneError
from ..interfaces.scene_file import scene_from_dict
from ..model.table import is_table
from ..simulation.driver import RunOptions, simulate
from ..simulation.result import Status, build_collision_table
from .keys import apply
from .plan import Keep, parse_keep

#: Status of a point whose scene the loader refused (its SceneError is the message).
INVALID_SCENE = "invalid_scene"
#: Status of a point whose run raised an error (its type and text are the message).
ERROR = "error"

#: Columns of the impacts kept per point (--keep impacts:M), from the collision table.
IMPACT_COLUMNS = ("n", "t", "i", "j", "q_i", "q_j", "dq_i_before", "dq_j_before", "dq_i_after", "dq_j_after")
#: A table scene's (billiards): ball i's centre and velocity after the impact, and at a cushion impact
#: (j = 0) the Birkhoff coordinates, arc length along the cushion and reflection angle.
TABLE_IMPACT_COLUMNS = ("n", "t", "i", "j", "x_i", "y_i", "vx_i_after", "vy_i_after", "boundary_s",
                        "reflection_angle", "law_flag")
WHOLE_IMPACT_COLUMNS = ("n", "i", "j", "law_flag")
#: State entries per ball of a table scene (x, y, vx, vy, slip_x, slip_y), per body elsewhere (q, dq).
TABLE_STATE = ("x", "y", "vx", "vy", "slip_x", "slip_y")

#: Period detection (--keep period): the smallest p in 1..PERIOD_MAX such that each of the last
#: max(PERIOD_MATCHES, 2p) impacts equals the impact p before it (same pair; positions, wrapped on a
#: circle, and outgoing rates within PERIOD_RTOL relative; the times p impacts apart equal to it too).
PERIOD_MAX = 32
PERIOD_MATCHES = 16
PERIOD_RTOL = 1e-6
#: The impacts a point keeps for it: enough for p = PERIOD_MAX.
PERIOD_TAIL = 3 * PERIOD_MAX
#: Renormalisation blocks of the Lyapunov exponent's standard error (at most; two segments a block at least).
LYAPUNOV_BLOCKS = 8

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
    keep: Keep
    n_bodies: int
    precision: str = "double"
    batch: bool = False  # points of one shape through heyoka's batch (SIMD) integrator (simulation.batch)

    def __post_init__(self):
        object.__setattr__(self, "keep", parse_keep(self.keep))  # an int: the last M impacts, as keep once was

    @property
    def table(self) -> bool:
        return self.data["track"].get("type") == "table"


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
        times, numbers, before, after, flags = self._last[:5]  # (a rough track adds its friction modes)
        return build_collision_table(self.scene, self.pairs, self.precision, times, numbers, before, after, flags,
                                     first_number=self.rows - len(times) + 1)


def impact_columns(table: bool) -> tuple:
    return TABLE_IMPACT_COLUMNS if table else IMPACT_COLUMNS


def state_size(n_bodies: int, table: bool) -> int:
    return (len(TABLE_STATE) if table else 2) * n_bodies


def empty_columns(count: int, n_bodies: int, keep, table: bool = False) -> dict:
    """Columns of ``count`` points not run: '' status, -1 counts, NaN numbers, 0 body numbers
    (``table``: a billiard table's state and impact columns)."""
    keep = parse_keep(keep)
    columns = {
        "status": np.full(count, "", dtype=object),
        "message": np.full(count, "", dtype=object),
        "collisions": np.full(count, -1, dtype=np.int64),
        "t_final": np.full(count, np.nan),
        "energy_initial": np.full(count, np.nan),
        "energy_final": np.full(count, np.nan),
        "final_state": np.full((count, state_size(n_bodies, table)), np.nan),
    }
    for prefix, m in (("impact_", keep.impacts), ("first_impact_", keep.first)):
        if m:
            for c in impact_columns(table):
                columns[f"{prefix}{c}"] = (np.zeros((count, m), dtype=np.int64) if c in WHOLE_IMPACT_COLUMNS
                                           else np.full((count, m), np.nan))
    if keep.strobe:
        columns["strobe_t"] = np.full((count, keep.strobe), np.nan)
        columns["strobe_state"] = np.full((count, keep.strobe, 2 * n_bodies), np.nan)
    if keep.period:
        columns["period"] = np.full(count, -1, dtype=np.int64)
        columns["period_time"] = np.full(count, np.nan)
    if keep.lyapunov:
        columns["lyapunov"] = np.full(count, np.nan)
        columns["lyapunov_error"] = np.full(count, np.nan)
        columns["lyapunov_message"] = np.full(count, "", dtype=object)
    if keep.rotation:
        columns["rotation"] = np.full(count, np.nan)
    return columns


def run_chunk(chunk: Chunk) -> dict:
    """Run every point of ``chunk``; its columns as numpy arrays (see empty_columns), one row per point.

    Raises KeyboardInterrupt if a run was interrupted (Ctrl-C, SIGTERM): a
    chunk is stored whole or not at all.
    """
    with _ONE_AT_A_TIME:
        columns = empty_columns(len(chunk.values), chunk.n_bodies, chunk.keep, chunk.table)
        options = RunOptions(t_end=chunk.t_end, max_collisions=chunk.max_collisions, precision=chunk.precision)
        make_scene = point_scene_maker(chunk.data, chunk.keys, chunk.default_name)
        if chunk.batch:
            _run_batch(chunk, make_scene, options, columns)
        else:
            for row, values in enumerate(chunk.values):
                _run_point(chunk, make_scene, values, options, columns, row)
        return columns


def _run_batch(chunk: Chunk, make_scene, options: RunOptions, columns: dict) -> None:
    """The chunk's points through simulation.batch.simulate_batch (each point's records in memory);
    where the batch run raises, every point of the chunk runs alone."""
    from ..simulation.batch import simulate_batch

    scenes = []
    for row, values in enumerate(chunk.values):
        try:
            scenes.append((row, make_scene(values)))
        except SceneError as exc:
            columns["status"][row], columns["message"][row] = INVALID_SCENE, str(exc)
    try:
        results = simulate_batch([scene for _row, scene in scenes], options)
    except (ArithmeticError, RuntimeError, ValueError):
        for row, _scene in scenes:
            _run_point(chunk, make_scene, chunk.values[row], options, columns, row)
        return
    keep = chunk.keep
    m = max(keep.impacts, PERIOD_TAIL if keep.period else 0)
    for (row, scene), result in zip(scenes, results):
        if result.status is Status.INTERRUPTED:
            raise KeyboardInterrupt
        _store_point(chunk, scene, result, result.collision_table()[-m:] if m else None, columns, row)


def point_scene_maker(data: dict, keys: tuple, default_name: str):
    """``make(values) -> Scene``: each point's scene, equal to what the loader builds from the base
    scene's TOML with the point's values written in (SceneError where it refuses them).

    Where every KEY is a body's initial coordinate, rate or slip (bodies[2].phi, bodies[1].dx, ...),
    the base scene is built once and each point is the base scene started elsewhere
    (Scene.with_state: the state's rules only, the constants kept): ~0.2 ms a point instead of
    ~1.4 ms. Otherwise, and where the base scene itself is refused, the loader builds every point.
    """
    def by_loader(values):
        return scene_from_dict(point_data(data, keys, values), default_name=default_name)

    try:
        base = scene_from_dict(data, default_name=default_name)
    except SceneError:
        return by_loader
    slots = state_slots(keys, data, base)
    if slots is None:
        return by_loader
    state = {"q": list(base.q), "dq": list(base.dq), "slip": list(base.slip)}

    def by_state(values):
        point = {name: list(v) for name, v in state.items()}
        for (name, body), value in zip(slots, values):
            point[name][body] = value
        return base.with_state(**point)

    return by_state


def state_slots(keys: tuple, data: dict, base) -> tuple | None:
    """Per KEY, ("q" | "dq" | "slip", body index) where every KEY is a body's initial coordinate (named
    as the track names it: phi, x, u, s), its rate (dphi, dx, du, ds) or its slip, and the scene file
    gives that body's state by those names (not by omega, or by segment and angle); else None."""
    if is_table(base):
        return None
    c = base.track.coordinate
    names = {c: "q", f"d{c}": "dq", "slip": "slip"}
    slots = []
    for key in keys:
        path = key.path
        if len(path) != 2 or path[0][0] != "bodies" or path[1][1] is not None or path[1][0] not in names:
            return None
        body = path[0][1] - 1
        entry = data["bodies"][body]
        if any(other in entry for other in ("segment", "angle", "dangle")):  # the loader converts those
            return None
        slots.append((names[path[1][0]], body))
    return tuple(slots)


def _run_point(chunk: Chunk, make_scene, values: tuple, options: RunOptions, columns: dict, row: int) -> None:
    try:
        scene = make_scene(values)
    except SceneError as exc:
        columns["status"][row], columns["message"][row] = INVALID_SCENE, str(exc)
        return
    keep = chunk.keep
    # A table run keeps its impacts in memory (its records are not the tracks' chunks): its tail is cut here.
    sink = None if chunk.table else LastImpacts(max(keep.impacts, PERIOD_TAIL if keep.period else 0))
    try:
        result = simulate(scene, options, sink=sink)
    except (ArithmeticError, RuntimeError, ValueError) as exc:  # heyoka's or the driver's refusal of this point
        columns["status"][row], columns["message"][row] = ERROR, f"{exc.__class__.__name__}: {exc}"
        return
    if result.status is Status.INTERRUPTED:
        raise KeyboardInterrupt
    tail = None
    if keep.impacts or keep.period:
        tail = result.collision_table()[-keep.impacts:] if sink is None else sink.table()
    _store_point(chunk, scene, result, tail, columns, row)


def _store_point(chunk: Chunk, scene, result, tail, columns: dict, row: int) -> None:
    """Row ``row`` of the columns from a point's result; ``tail``: its last collision-table rows (impacts, period)."""
    keep = chunk.keep
    columns["status"][row], columns["message"][row] = result.status.value, result.message
    columns["collisions"][row] = result.n_collisions
    columns["t_final"][row] = float(result.t_final)
    columns["energy_initial"][row] = result.energy_initial
    columns["energy_final"][row] = result.energy_final
    columns["final_state"][row] = np.asarray(result.state_final if chunk.table else result.final_state, dtype=float)
    names = impact_columns(chunk.table)
    if keep.impacts or keep.period:
        if keep.impacts:
            table = tail[-keep.impacts:]
            for c in names:
                columns[f"impact_{c}"][row, :table.size] = table[c]
        if keep.period:
            columns["period"][row], columns["period_time"][row] = impact_period(tail, angle=scene.track.kind == "circle")
    if keep.first:
        table = result.collision_table()[:keep.first]  # a run handed to a sink keeps its first chunk here
        for c in names:
            columns[f"first_impact_{c}"][row, :table.size] = table[c]
    if keep.strobe:
        strobe = result.strobe_table[-keep.strobe:]
        columns["strobe_t"][row, :len(strobe)] = strobe[:, 0]
        columns["strobe_state"][row, :len(strobe)] = strobe[:, 1:]
    if keep.rotation:
        columns["rotation"][row] = rotation_number(result)
    if keep.lyapunov:
        (columns["lyapunov"][row], columns["lyapunov_error"][row],
         columns["lyapunov_message"][row]) = lyapunov(scene, result, chunk.precision)


def impact_period(table: np.ndarray, *, angle: bool, p_max: int = PERIOD_MAX, matches: int = PERIOD_MATCHES,
                  rtol: float = PERIOD_RTOL) -> tuple:
    """(p, T): the period of the impact sequence in ``table`` (collision-table rows, oldest first) and its time.

    p is the smallest of 1..p_max such that each of the last m = max(matches, 2p)
    impacts equals the impact p before it: the same pair (i, j), the positions
    q_i, q_j (wrapped to (-pi, pi] differences on a circle, ``angle``) and the
    outgoing rates dq_i, dq_j after the impact within ``rtol`` relative (to the
    largest magnitude of that column over the compared impacts; pi for an
    angle), and the time between the two within ``rtol`` of its mean. T is the
    time of the last p impacts, t[-1] - t[-1 - p]. (0, nan) where no p fits:
    too few impacts, a transient or a chaotic sequence.
    """
    n = table.size
    for p in range(1, p_max + 1):
        m = max(matches, 2 * p)
        if n < m + p:
            break
        new, old = table[n - m:], table[n - m - p:n - p]
        if not (np.array_equal(new["i"], old["i"]) and np.array_equal(new["j"], old["j"])):
            continue
        ok = True
        for c in ("q_i", "q_j", "dq_i_after", "dq_j_after"):
            a, b = np.asarray(new[c], dtype=float), np.asarray(old[c], dtype=float)
            d = a - b
            if angle and c.startswith("q_"):
                d, scale = (d + np.pi) % (2 * np.pi) - np.pi, np.pi
            else:
                scale = max(float(np.max(np.abs(a))), float(np.max(np.abs(b))))
            if not np.all(np.abs(d) <= rtol * scale):
                ok = False
                break
        if not ok:
            continue
        gaps = np.asarray(new["t"], dtype=float) - np.asarray(old["t"], dtype=float)
        if not np.all(np.abs(gaps - gaps.mean()) <= rtol * abs(gaps.mean())) or not gaps.mean() > 0:
            continue
        return p, float(table["t"][-1] - table["t"][-1 - p])
    return 0, math.nan


def rotation_number(result) -> float:
    """Circle scenes: the net turns of body 1 per second, (phi_final - phi_initial) / (2 pi t_final); nan elsewhere."""
    t = float(result.t_final)
    if result.scene.track.kind != "circle" or not t > 0:
        return math.nan
    turned = float(result.final_state[0]) - float(result.initial_state[0])
    return turned / (2 * math.pi * t)


def lyapunov(scene, result, precision: str) -> tuple:
    """(exponent 1/s, its standard error 1/s, message) by heyroll.analysis.horizon.lyapunov_estimate over the
    point's run time; (nan, nan, the reason) where it does not apply or fails.

    The error is the standard error of the exponent over up to LYAPUNOV_BLOCKS blocks of consecutive
    renormalisation segments (each block's accumulated log-stretch over its time); nan with fewer
    than 4 segments.
    """
    from ..analysis.horizon import lyapunov_estimate

    t = float(result.t_final)
    why = None
    if scene.rough:
        why = "lyapunov_estimate rebuilds scenes without their slip state: not estimated on a rough track"
    elif not t > 0:
        why = "the run has no time to estimate over (t_final = 0)"
    if why is not None:
        return math.nan, math.nan, why
    try:
        est = lyapunov_estimate(scene, t_end=t, precision=precision)
    except (ArithmeticError, NotImplementedError, RuntimeError, ValueError) as exc:
        return math.nan, math.nan, f"{exc.__class__.__name__}: {exc}"
    return float(est.exponent), block_error(est.times, est.history), est.message


def block_error(times, history, blocks: int = LYAPUNOV_BLOCKS) -> float:
    """Standard error of a Benettin estimate from its running history: the segments' log-stretches
    (differences of history * time) split into blocks, each block's rate = its stretch / its time."""
    times, history = np.asarray(times, dtype=float), np.asarray(history, dtype=float)
    n = times.size
    b = min(blocks, n // 2)
    if b < 2:
        return math.nan
    stretch = np.diff(history * times, prepend=0.0)
    span = np.diff(times, prepend=0.0)
    rates = [s.sum() / d.sum() for s, d in zip(np.array_split(stretch, b), np.array_split(span, b))]
    return float(np.std(rates, ddof=1) / math.sqrt(b))


def point_data(data: dict, keys: tuple, values: tuple) -> dict:
    """A deep copy of the base scene's TOML with the point's values written in."""
    point = copy.deepcopy(data)
    for key, value in zip(keys, values):
        apply(point, key, value)
    return point
