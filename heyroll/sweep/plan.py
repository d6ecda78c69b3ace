"""A sweep's plan: the base scene, the points (a grid, lists of values, or a random sample) and what is kept.

Grid and list values are decimal numbers (``decimal.Decimal``), so a point's
scene starts from decimal text as a scene file does: 0.5:1:6 gives exactly
0.5, 0.6, ..., 1.0, the value a scene file with ``restitution = 0.7`` holds.
Random values are doubles drawn with numpy's default generator from the seed
(their shortest decimal text goes into the scene, so the point is that double).

Points are numbered in C order over the grid (the last KEY varies fastest) or
along the sample. The store is chunked so that every chunk is a contiguous
run of point numbers: one task of the parallel run, one region write.
"""

from __future__ import annotations

import json
import math
import tomllib
from dataclasses import dataclass
from decimal import Decimal, InvalidOperation

import numpy as np

from ..errors import SceneError, SceneFileError
from .errors import SweepError
from ..interfaces.scene_file import SWEEP_TABLE_KEYS
from .keys import ALTERNATIVES, Key, parse_key, units

#: Points per chunk (one task, one region write) at most: up to ~0.5 s of work per task on the default
#: scene, so that the per-chunk cost of this process (the store's write, Dask's messages) is small beside it
#: (measured, validation/sweep_speed.py: 10,000 points of 0.5 ms on 2 workers scaled 1.53x at 256, 1.76x at
#: 1024, i.e. 625 a chunk for MIN_CHUNKS).
MAX_CHUNK_POINTS = 1024
#: A sweep is cut into at least this many chunks where it has the points, so that
#: every worker of a small cluster gets several tasks (and the progress bar moves).
MIN_CHUNKS = 16

#: The most impacts ``first:M`` keeps: a run handed to a sink keeps its first chunk of records in
#: memory (RunOptions.chunk_size), and the first M impacts are read from there.
MAX_FIRST = 65536

#: Points of a sweep tried before its base scene is refused (_check_base_scene).
BASE_CHECK_POINTS = 8

#: The coordinate each track type's bodies are placed by (README: phi on a circle).
COORDINATES = {"circle": "phi", "curve": "x", "arcs": "s", "three_arcs": "s", "parametric": "u", "table": "x"}


@dataclass(frozen=True)
class Axis:
    """One dimension of a grid: a KEY and its values (Decimal, or int for whole-number fields)."""

    key: Key
    values: tuple
    how: str  # "vary" (START:STOP:N) or "values" (a list), with the text as given in ``text``
    text: str


@dataclass(frozen=True)
class Sample:
    """Random points: for each KEY a uniform double in [low, high), ``samples`` points, numpy seed ``seed``."""

    keys: tuple  # (Key, low Decimal, high Decimal)
    samples: int
    seed: int
    values: tuple  # per KEY: tuple of Decimal, one per point


@dataclass(frozen=True)
class SweepPlan:
    """Everything that decides a sweep's results and its store's layout (see ``spec``)."""

    data: dict  # the parsed base scene, without its [sweep] table
    text: str  # the base scene's text as read
    source: str
    default_name: str
    axes: tuple  # Axis, one per grid dimension (empty for a random sample)
    sample: Sample | None
    keep: "Keep"  # what is stored per point besides the summary (--keep)
    t_end: float | None  # None: the scene's [run] t_end
    max_collisions: object  # ...: the scene's; None: no limit
    chunk_points: int
    precision: str = "double"  # every point's working precision (Precision.name: double, long, quad, mp:BITS)
    batch: bool = False  # points through heyoka's batch (SIMD) integrator (heyroll.simulation.batch)

    @property
    def dims(self) -> tuple:
        return ("point",) if self.sample is not None else tuple(a.key.text for a in self.axes)

    @property
    def shape(self) -> tuple:
        return (self.sample.samples,) if self.sample is not None else tuple(len(a.values) for a in self.axes)

    @property
    def n_points(self) -> int:
        return math.prod(self.shape)

    @property
    def keys(self) -> tuple:
        return tuple(k for k, _lo, _hi in self.sample.keys) if self.sample is not None else tuple(a.key for a in self.axes)

    @property
    def n_bodies(self) -> int:
        return len(self.data["bodies"])

    @property
    def coordinate(self) -> str:
        return COORDINATES.get(self.data["track"].get("type"), "q")

    @property
    def table(self) -> bool:
        """A billiard table scene: balls with states (x, y, vx, vy, slip_x, slip_y) and their own impact columns."""
        return self.data["track"].get("type") == "table"

    def units(self, key: Key) -> str:
        return units(key, self.data)

    def point_values(self, n: int) -> tuple:
        """The values of point ``n`` (flat C-order number), one per KEY."""
        if self.sample is not None:
            return tuple(v[n] for v in self.sample.values)
        index = np.unravel_index(n, self.shape)
        return tuple(a.values[i] for a, i in zip(self.axes, index))

    @property
    def chunks(self) -> tuple:
        """Chunk shape: whole trailing dimensions, a part of one, 1 before it (contiguous point numbers)."""
        chunk = [1] * len(self.shape)
        size = 1
        for d in reversed(range(len(self.shape))):
            if size * self.shape[d] <= self.chunk_points:
                chunk[d] = self.shape[d]
                size *= self.shape[d]
            else:
                chunk[d] = max(1, self.chunk_points // size)
                break
        return tuple(chunk)

    def regions(self) -> list:
        """Each chunk as (region: {dim: slice}, first point number, point count), in C order."""
        chunks, shape = self.chunks, self.shape
        grid = [range(0, n, c) for n, c in zip(shape, chunks)]
        out = []
        for starts in np.ndindex(*[len(g) for g in grid]):
            lo = [g[i] for g, i in zip(grid, starts)]
            hi = [min(a + c, n) for a, c, n in zip(lo, chunks, shape)]
            first = int(np.ravel_multi_index(lo, shape))
            out.append(({d: slice(a, b) for d, a, b in zip(self.dims, lo, hi)}, first, math.prod(b - a for a, b in zip(lo, hi))))
        return out

    def spec(self) -> dict:
        """What makes two sweeps the same (JSON-ready): a store is resumed only by a sweep of equal spec."""
        return {
            "heyroll_sweep": 1,
            "scene": json.loads(json.dumps(self.data, default=str, sort_keys=True)),
            "default_name": self.default_name,
            "grid": [{"key": a.key.text, "how": a.how, "spec": a.text, "values": [str(v) for v in a.values]}
                     for a in self.axes],
            "random": None if self.sample is None else {
                "keys": [{"key": k.text, "low": str(lo), "high": str(hi)} for k, lo, hi in self.sample.keys],
                "samples": self.sample.samples, "seed": self.sample.seed},
            "keep": self.keep.text,
            "t_end": None if self.t_end is None else repr(self.t_end),
            "max_collisions": "scene" if self.max_collisions is ... else self.max_collisions,
            "chunks": list(self.chunks),
            # Only where it is not double: a store written before --precision existed is a double sweep.
            **({"precision": self.precision} if self.precision != "double" else {}),
            # Batch results differ from scalar ones in the last bits: a store is one or the other.
            **({"batch": True} if self.batch else {}),
        }


def read_scene(scene=None, *, scene_text: str | None = None) -> tuple:
    """(parsed TOML, text, source, default name) of a scene file path, TOML text, or the default scene."""
    from pathlib import Path

    from ..interfaces.scene_file import default_scene_text, read_scene_text

    if scene is not None and scene_text is not None:
        raise SweepError("scene", "give a scene file or scene_text, not both")
    if scene_text is not None:
        text, source, name = scene_text, "<scene text>", "scene"
    elif scene is None:
        text, source, name = default_scene_text(), "<default scene>", "scene"
    else:
        path = Path(scene)
        text = read_scene_text(path)
        source, name = str(path), path.stem
    try:
        data = tomllib.loads(text, parse_float=Decimal)
    except tomllib.TOMLDecodeError as exc:
        raise SceneFileError(source, f"not valid TOML ({exc})") from None
    return data, text, source, name


def make_plan(scene=None, *, scene_text=None, grid=(), random=(), samples=None, seed=None, keep=None,
              t_end=None, max_collisions=..., chunk_points=None, precision=None, batch=None) -> SweepPlan:
    """Check a sweep's specification and build its plan (raises SweepError / SceneError, one line each).

    ``grid``: ("vary" | "values", "KEY=SPEC") pairs in dimension order; ``random``:
    "KEY=LO:HI" strings. Without either, the scene file's [sweep] table says
    (and its samples, seed, keep and precision are defaults for the arguments).
    """
    data, text, source, name = read_scene(scene, scene_text=scene_text)
    table = data.pop("sweep", None)
    if table is not None:
        if not isinstance(table, dict):
            raise SweepError("sweep", "must be a table ([sweep])")
        for k in table:
            if k not in SWEEP_TABLE_KEYS:
                raise SweepError(f"sweep.{k}", f"unknown key; allowed here: {', '.join(sorted(SWEEP_TABLE_KEYS))}")
        if not grid and not random:
            grid = [(how, entry) for how in ("vary", "values") for entry in _strings(table, how)]
            random = _strings(table, "random")
        samples = table.get("samples") if samples is None else samples
        seed = table.get("seed") if seed is None else seed
        keep = table.get("keep") if keep is None else keep
        precision = table.get("precision") if precision is None else precision
        batch = table.get("batch") if batch is None else batch
    batch = False if batch is None else batch
    if not isinstance(batch, bool):
        raise SweepError("batch", f"must be true or false, got {batch!r}")
    if not isinstance(data.get("bodies"), list) or not data["bodies"] or not isinstance(data.get("track"), dict):
        raise SweepError("scene", "a sweep needs a scene with a [track] table and [[bodies]]")
    if not grid and not random:
        raise SweepError("--vary", "nothing to sweep: give --vary KEY=START:STOP:N, --values KEY=v1,v2 or --random KEY=LO:HI")
    if grid and random:
        raise SweepError("--random", "a sweep is a grid (--vary, --values) or a random sample (--random), not both")
    seen = set()

    def key_of(entry: str, flag: str) -> tuple:
        if not isinstance(entry, str) or "=" not in entry:
            raise SweepError(flag, f"expected KEY=..., got {entry!r}")
        text_key, spec = entry.split("=", 1)
        key = parse_key(text_key, data)
        if key.text in seen:
            raise SweepError(flag, f"{key.text} is varied twice")
        other = ALTERNATIVES.get(key.field)
        if other is not None and key.path[0][0] == "bodies":
            twin = ".".join(key.text.split(".")[:-1] + [other])
            if twin in seen:  # (apply() writes one and drops the other: one axis would be ignored)
                raise SweepError(flag, f"{twin} and {key.text} are one quantity (a scene gives {other} or "
                                       f"{key.field}, not both): vary one of them")
        seen.add(key.text)
        return key, spec.strip()

    axes = []
    for how, entry in grid:
        flag = f"--{how}"
        key, spec = key_of(entry, flag)
        values = _range(spec, key, flag) if how == "vary" else _list(spec, key, flag)
        axes.append(Axis(key, values, how, spec))
    sample = None
    if random:
        n = _whole(samples, "--samples", minimum=1, what="the number of random points")
        s = 0 if seed is None else _whole(seed, "--seed", minimum=0, what="the seed")
        bounds = []
        for entry in random:
            key, spec = key_of(entry, "--random")
            bounds.append((key, *_bounds(spec, key)))
        rng = np.random.default_rng(s)
        # One draw per KEY in order: the same seed gives the same points whatever the chunking.
        values = tuple(tuple(Decimal(repr(float(v))) for v in rng.uniform(float(lo), float(hi), n))
                       for _k, lo, hi in bounds)
        sample = Sample(tuple(bounds), n, s, values)
    elif samples is not None or seed is not None:
        raise SweepError("--samples", "--samples and --seed go with --random")
    if t_end is not None:
        try:
            t_end = float(t_end)
        except (TypeError, ValueError):
            t_end = math.nan
        if not math.isfinite(t_end) or t_end <= 0:
            raise SweepError("--t-end", "must be a finite number > 0")
    if max_collisions is not ... and max_collisions is not None:
        max_collisions = _whole(max_collisions, "--max-collisions", minimum=0, what="max_collisions")
    shape = (sample.samples,) if sample else tuple(len(a.values) for a in axes)
    n_points = math.prod(shape)
    if chunk_points is None:
        chunk_points = min(MAX_CHUNK_POINTS, max(1, -(-n_points // MIN_CHUNKS)))
    else:
        chunk_points = _whole(chunk_points, "chunk_points", minimum=1, what="points per chunk")
    keep = parse_keep(keep)
    billiards = data["track"].get("type") == "table"
    if billiards and (keep.strobe or keep.period or keep.lyapunov or keep.rotation):
        raise SweepError("--keep", "a table scene (billiards) keeps summary, impacts:M and first:M (its cushion "
                                   "impacts' Birkhoff coordinates among them); period, lyapunov, rotation and strobe "
                                   "are for tracks")
    if billiards and batch:
        raise SweepError("--batch", "a table scene (billiards) runs on the table engine, which has no batch mode")
    if keep.strobe and not isinstance(data.get("forcing"), dict):
        raise SweepError("--keep", "strobe:M needs a forced scene (a [forcing] table): only forced runs have a "
                                   "stroboscopic section")
    precision = parse_precision(precision)
    if batch and precision != "double":
        raise SweepError("--batch", f"heyoka's batch mode is double precision; this sweep is {precision}")
    plan = SweepPlan(data, text, source, name, tuple(axes), sample, keep, t_end, max_collisions,
                     chunk_points, precision, batch)
    _check_base_scene(plan)
    return plan


def _check_base_scene(plan: SweepPlan) -> None:
    """Raise the loader's SceneError where the base scene is refused for a reason the sweep does not change.

    Acceptance test: a typo in [track] (``raduis``) or k = 1.5 while sweeping g wrote a store of points that
    were all ``invalid_scene``, exit 0. A point refused for its own values stays a recorded point: the base
    scene is refused only where its refusal names no varied KEY and up to BASE_CHECK_POINTS points spread over
    the sweep (its first and last among them) are refused with the very same message. (One point decided it
    at first: the same points in the other order, or another seed, were refused or swept, review.)"""
    from ..interfaces.scene_file import scene_from_dict
    from .points import point_data

    def refusal(data) -> SceneError | None:
        try:
            scene_from_dict(data, default_name=plan.default_name)
        except SceneError as exc:
            return exc
        return None

    refused = refusal(plan.data)
    if refused is None:
        return
    field = str(getattr(refused, "field", ""))
    if any(field == k.text or field.startswith(k.text + ".") or k.text.startswith(field + ".") for k in plan.keys):
        return
    for n in sorted({int(x) for x in np.linspace(0, plan.n_points - 1, BASE_CHECK_POINTS)}):
        other = refusal(point_data(plan.data, plan.keys, plan.point_values(n)))
        if other is None or str(other) != str(refused):
            return
    raise refused


@dataclass(frozen=True)
class Keep:
    """What a sweep stores per point besides the summary (``--keep``, a comma list).

    ``impacts``/``first``: the last/first M impacts (0: none); ``strobe``: the
    last M stroboscopic samples of a forced run; ``period``, ``lyapunov``,
    ``rotation``: the per-point estimates (README, "Sweeps").
    """

    impacts: int = 0
    first: int = 0
    strobe: int = 0
    period: bool = False
    lyapunov: bool = False
    rotation: bool = False

    @property
    def text(self) -> str:
        """The canonical text (the store's spec): the items in a fixed order, 'summary' for none."""
        items = [f"{name}:{getattr(self, name)}" for name in ("impacts", "first", "strobe") if getattr(self, name)]
        items += [name for name in KEEP_ESTIMATES if getattr(self, name)]
        return ",".join(items) or "summary"

    def __bool__(self) -> bool:
        return self.text != "summary"


#: --keep items with a count (NAME:M) and the estimates (a bare NAME), in their canonical order.
KEEP_COUNTS = ("impacts", "first", "strobe")
KEEP_ESTIMATES = ("period", "lyapunov", "rotation")


def parse_keep(text) -> Keep:
    """--keep: a comma list (or a list) of summary, impacts:M, first:M, strobe:M, period, lyapunov, rotation."""
    if isinstance(text, Keep):
        return text
    if text is None:
        return Keep()
    if isinstance(text, int) and not isinstance(text, bool):  # the last M impacts (what keep was once)
        return Keep(impacts=_whole(text, "--keep", minimum=0, what="M in impacts:M"))
    items = text.split(",") if isinstance(text, str) else text
    allowed = "summary, impacts:M, first:M, strobe:M, period, lyapunov, rotation"
    if not isinstance(items, (list, tuple)) or not all(isinstance(i, str) for i in items):
        raise SweepError("--keep", f"must be a comma list of {allowed}, got {text!r}")
    fields, seen = {}, set()
    for item in (i.strip() for i in items):
        name, _, count = item.partition(":")
        if name in seen:
            raise SweepError("--keep", f"{name} is given twice in {text!r}")
        seen.add(name)
        if name in KEEP_COUNTS and count:
            top = MAX_FIRST if name == "first" else None
            fields[name] = _whole(count, "--keep", minimum=1, what=f"M in {name}:M")
            if top is not None and fields[name] > top:
                raise SweepError("--keep", f"M in first:M must be <= {top}, got {fields[name]}")
        elif name in KEEP_ESTIMATES and not count:
            fields[name] = True
        elif item != "summary":
            raise SweepError("--keep", f"must be a comma list of {allowed}, got {item!r}")
    return Keep(**fields)


def parse_precision(text) -> str:
    """--precision: double (default), long, quad or mp:BITS, checked as simulate checks it; its canonical name."""
    if text is None:
        return "double"
    from ..simulation.precision import Precision

    try:
        return Precision.parse(str(text), "--precision").name
    except SceneError as exc:
        raise SweepError("--precision", exc.rule) from None


def _strings(table: dict, name: str) -> list:
    value = table.get(name, [])
    value = [value] if isinstance(value, str) else value
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise SweepError(f"sweep.{name}", 'must be a string or a list of strings like "KEY=..."')
    return value


def _decimal(text: str, key: Key, flag: str) -> Decimal:
    try:
        value = Decimal(text.strip())
    except (InvalidOperation, AttributeError):
        raise SweepError(flag, f"{key.text}: {text!r} is not a number") from None
    if not value.is_finite() or not math.isfinite(float(value)):
        raise SweepError(flag, f"{key.text}: {text!r} is not a finite number")
    return value


def _as_field(value: Decimal, key: Key, flag: str):
    """A value as the scene file would hold it: an int for a whole-number field."""
    if not key.whole:
        return value
    if value != value.to_integral_value():
        raise SweepError(flag, f"{key.text} takes whole numbers, got {value}")
    return int(value)


def _range(spec: str, key: Key, flag: str) -> tuple:
    parts = spec.split(":")
    if len(parts) != 3:
        raise SweepError(flag, f"{key.text}: expected START:STOP:N, got {spec!r}")
    start, stop = _decimal(parts[0], key, flag), _decimal(parts[1], key, flag)
    n = _whole(parts[2], flag, minimum=1, what=f"{key.text}: N in START:STOP:N")
    if n == 1:
        return (_as_field(start, key, flag),)
    # Multiply before dividing: exact wherever the step is a short decimal, and the last value is STOP.
    values = tuple(_as_field(start + (stop - start) * k / (n - 1), key, flag) for k in range(n))
    if len(set(values)) != n:
        raise SweepError(flag, f"{key.text}: START:STOP:N gives repeated values")
    return values


def _list(spec: str, key: Key, flag: str) -> tuple:
    values = tuple(_as_field(_decimal(v, key, flag), key, flag) for v in spec.split(","))
    if len(set(values)) != len(values):
        raise SweepError(flag, f"{key.text}: a value is repeated in {spec!r}")
    return values


def _bounds(spec: str, key: Key) -> tuple:
    parts = spec.split(":")
    if len(parts) != 2:
        raise SweepError("--random", f"{key.text}: expected LO:HI, got {spec!r}")
    if key.whole:
        raise SweepError("--random", f"{key.text} takes whole numbers: use --values")
    low, high = _decimal(parts[0], key, "--random"), _decimal(parts[1], key, "--random")
    if not low < high:
        raise SweepError("--random", f"{key.text}: LO < HI is needed, got {spec!r}")
    return low, high


def _whole(value, flag: str, *, minimum: int, what: str) -> int:
    """A whole number from an int or its decimal text (a TOML float, 2.5 or 2.0, is refused)."""
    n = None
    if isinstance(value, int) and not isinstance(value, bool):
        n = value
    elif isinstance(value, str) and value.strip().isdigit():
        n = int(value)
    if value is None:
        raise SweepError(flag, f"{what} is missing: give a whole number >= {minimum}")
    if n is None or n < minimum:
        raise SweepError(flag, f"{what} must be a whole number >= {minimum}, got {value!r}")
    return n
