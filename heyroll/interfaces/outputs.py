"""Files a run writes: collisions.csv, summary.json (figures: see figures.py).

Every file is written under a temporary name and renamed into place, so an
interrupted or failed write never leaves a half-written file behind.
"""

from __future__ import annotations

import json
import math
import os
import platform
from pathlib import Path

import heyoka
import mpmath
import numpy as np

from .._version import __version__
from .csv_text import collisions_csv, csv_rows
from ..model.table import is_table
from ..simulation.table.result import impact_table
from ..simulation.result import (INTEGER_COLUMNS, PASSAGE_COLUMNS, SimulationResult,
                                 build_collision_table, table_columns)


def versions() -> dict:
    return {
        "heyroll": __version__,
        "heyoka": heyoka.__version__,
        "numpy": np.__version__,
        "mpmath": mpmath.__version__,
        "python": platform.python_version(),
    }


def atomic_write_text(path: Path, text: str) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, path)


class _TableFile:
    """A collision table written chunk by chunk under a temporary name.

    ``close`` renames it into place, so the file at ``path`` is always a
    complete table: of the whole run, or of every collision before an
    interruption.
    """

    def __init__(self, path: Path):
        self.path = str(path)
        self._final = Path(path)
        self._tmp = self._final.with_name(f".{self._final.name}.tmp")
        self._file = None
        self.rows = 0
        self._passages = None
        self.passages_path = None  # set by open on an open track
        self.passage_rows = 0

    def open(self, scene, pairs, precision) -> None:
        self.scene, self.pairs, self.precision = scene, pairs, precision
        self._file = open(self._tmp, "wb")
        self._start()
        if not is_table(scene) and scene.domain(0) is not None:  # an open track: passages.csv streamed beside the table
            self.passages_path = str(self._final.with_name("passages.csv"))
            self._passages_tmp = self._final.with_name(".passages.csv.tmp")
            self._passages = open(self._passages_tmp, "wb")
            self._passages.write((",".join(PASSAGE_COLUMNS) + "\n").encode())

    def write_passages(self, table: np.ndarray) -> None:
        """Junction passages and limiter impacts (``passage_table`` rows), appended to passages.csv."""
        self._passages.write(csv_rows(table, self.precision.format))
        self.passage_rows += table.size

    def write(self, chunk, first_number: int) -> None:
        if is_table(self.scene):  # billiards: the chunk is a list of impact records
            table = impact_table(self.scene, chunk, self.precision, first_number, native=True)
            self._append(table)
            self.rows += table.size
            return
        times, numbers, before, after, flags = chunk[:5]
        table = build_collision_table(
            self.scene, self.pairs, self.precision, times, numbers, before, after, flags,
            first_number=first_number, native=True, modes=chunk[5] if len(chunk) > 5 else None,
            spins=chunk[6] if len(chunk) > 6 else None,
        )
        self._append(table)
        self.rows += table.size

    def close(self) -> None:
        if self._file is None:
            return
        self._finish()
        self._file.close()
        self._file = None
        os.replace(self._tmp, self._final)
        if self._passages is not None:
            self._passages.close()
            self._passages = None
            os.replace(self._passages_tmp, self.passages_path)


class CsvTableSink(_TableFile):
    """collisions.csv: header row, then one row per collision (17 digits for double)."""

    format = "csv"

    def _start(self):
        self._file.write((",".join(table_columns(self.scene)) + "\n").encode())

    def _append(self, table):
        if is_table(self.scene):  # a cell that does not apply (a cushion impact's ball j) is empty
            self._file.write(csv_rows(table, _or_empty(self.precision.format)).replace(b",nan", b","))
            return
        self._file.write(csv_rows(table, self.precision.format))

    def _finish(self):
        pass


class NpyTableSink(_TableFile):
    """collisions.npy: one structured numpy array (float64 / int64 columns).

    ``numpy.load("collisions.npy")`` reads it, and ``pandas.DataFrame(...)`` of
    that; the header is rewritten with the final row count at the end.
    """

    format = "npy"
    HEADER_BYTES = 4096

    def open(self, scene, pairs, precision) -> None:
        if precision.name != "double":
            raise ValueError("the npy table holds float64: use csv for quad and MPFR runs")
        super().open(scene, pairs, precision)

    def _header(self, rows: int) -> bytes:
        dtype = _empty_table(self.scene, self.precision).dtype
        d = {"descr": np.lib.format.dtype_to_descr(dtype), "fortran_order": False, "shape": (rows,)}
        text = repr(d).encode("latin1")
        text += b" " * (self.HEADER_BYTES - 10 - len(text) - 1) + b"\n"
        return b"\x93NUMPY\x01\x00" + len(text).to_bytes(2, "little") + text

    def _start(self):
        self._file.write(self._header(0))

    def _append(self, table):
        self._file.write(np.ascontiguousarray(table).tobytes())

    def _finish(self):
        self._file.seek(0)
        self._file.write(self._header(self.rows))


class ParquetTableSink(_TableFile):
    """collisions.parquet: the npy table's columns and types, one row group per chunk (pyarrow).

    ``pandas.read_parquet`` / ``pyarrow.parquet.read_table`` read it. The
    footer is written by ``close``, so an interrupted run's file is complete.
    """

    format = "parquet"

    def open(self, scene, pairs, precision) -> None:
        if precision.name != "double":
            raise ValueError("the parquet table holds float64: use csv for quad and MPFR runs")
        super().open(scene, pairs, precision)

    def _start(self):
        import pyarrow as pa
        import pyarrow.parquet as pq

        dtype = _empty_table(self.scene, self.precision).dtype
        self._schema = pa.schema([(name, pa.from_numpy_dtype(dtype[name])) for name in dtype.names])
        # A dictionary only where values repeat (body numbers, law flags): tried on the float
        # columns it made the write 4x slower (measured) for no saving.
        self._writer = pq.ParquetWriter(self._file, self._schema, compression="snappy",
                                        use_dictionary=[c for c in INTEGER_COLUMNS if c != "n"])

    def _append(self, table):
        import pyarrow as pa

        self._writer.write_table(pa.table({name: table[name] for name in table.dtype.names}, schema=self._schema))

    def _finish(self):
        self._writer.close()


def _empty_table(scene, precision) -> np.ndarray:
    if is_table(scene):
        return impact_table(scene, [], precision)
    return build_collision_table(scene, (), precision, [], [], [], [], [])


def _or_empty(format_value):
    return lambda value: "" if value is None else format_value(value)


TABLE_SINKS = {"csv": CsvTableSink, "npy": NpyTableSink, "parquet": ParquetTableSink}


def summary_dict(result: SimulationResult, *, scene_source: str, files: dict) -> dict:
    data = result.summary()
    data["scene"] = {"name": result.scene.name, "source": scene_source, "description": result.scene.describe()}
    data["files"] = files
    data["versions"] = versions()
    return data


#: The files a run writes (and their temporary names): what a new run in the same directory replaces.
RUN_FILES = ("collisions.csv", "collisions.npy", "collisions.parquet", "passages.csv", "transitions.csv",
             "stroboscopic.csv", "summary.json", "phase_portrait.png", "energy.png", "friction_portrait.png",
             "friction_energy.png", "stroboscopic.png", "impact_map.png", "table_paths.png", "birkhoff_map.png")
#: What `heyroll validate` writes besides energy.png and phase_portrait.png (RUN_FILES too).
REPORT_FILES = ("report.md", "series_error.png", "horizon.png", "lyapunov.png")
#: A run and a validation share figure names, so each replaces the other's outputs too: a run's table
#: beside a report's figures of another run (or a report showing a run's figures) is stale (acceptance test).
OUTPUT_FILES = RUN_FILES + REPORT_FILES


def writable_problem(out: Path) -> str | None:
    """Create ``out`` and check that files can be written in it: None, or what is wrong (one line)."""
    try:
        out.mkdir(parents=True, exist_ok=True)
        probe = out / ".heyroll-write-test"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as exc:
        return f"cannot write to {out}: {exc.strerror or exc}"
    return None


class HeldDirectory:
    """An output directory this process holds (:func:`hold_directory`); ``close`` lets it go."""

    def __init__(self, fd):
        self.fd = fd

    def close(self) -> None:
        if self.fd is not None:
            os.close(self.fd)  # (closing the descriptor releases its flock)
            self.fd = None


def hold_directory(out: Path) -> HeldDirectory | None:
    """Lock the directory ``out`` for this process (an advisory flock on the directory itself: no lock file, so
    nothing is left behind, and one inode for every command): the hold, or None where another command holds it.
    A second command writing into the same directory at the same time removed the first's outputs as it
    started, and the first its (two runs into one --out ended with an empty directory: acceptance test). The
    system lets it go when the process ends, however it ends. Where the platform has no flock: no lock."""
    try:
        import fcntl
    except ImportError:
        return HeldDirectory(None)
    fd = os.open(out, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        os.close(fd)
        return None
    return HeldDirectory(fd)


def busy_message(out: Path) -> str:
    return f"another heyroll command is writing to {out}: let it finish or choose another directory"


def prepare_run_directory(out_dir: Path) -> None:
    """Make ``out_dir`` ready for a run or a validation: created, and without an earlier one's outputs.

    A run or a validation replaces every output of an earlier heyroll run or validation in the
    directory (OUTPUT_FILES and their temporary files), so that no stale table, report or figure
    sits beside the new ones; other files are left alone. Raises OSError.
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    remove_run_files(out_dir)


def remove_run_files(out_dir: Path) -> None:
    """Delete a run's or a validation's outputs (complete or partial) from ``out_dir``."""
    for name in OUTPUT_FILES:
        for path in (out_dir / name, out_dir / f".{name}.tmp"):
            if path.is_file():
                path.unlink()


def table_sink(out_dir: Path, table_format: str = "csv") -> _TableFile:
    """A sink that streams the run's collision table into ``out_dir``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    cls = TABLE_SINKS[table_format]
    return cls(out_dir / f"collisions.{cls.format}")


def write_run(result: SimulationResult, out_dir: Path, *, scene_source: str, figures: bool = True, sink=None) -> dict:
    """Write the table (unless ``sink`` streamed it), summary.json and the figures into ``out_dir``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    if is_table(result.scene):
        return _write_table_run(result, out_dir, scene_source=scene_source, figures=figures, sink=sink)
    if sink is None:
        sink = table_sink(out_dir, "csv")
        sink.open(result.scene, result.pairs, result.precision)
        chunk = (result.times, result.pair_numbers, result.states_before, result.states_after, result.law_flags)
        sink.write(chunk if result.collision_modes is None else chunk + (result.collision_modes, result.collision_spins),
                   1)
        if sink.passages_path:
            sink.write_passages(result.passage_table(native=True))
        sink.close()
    files = {"collisions": Path(sink.path).name, "summary": "summary.json"}
    if getattr(sink, "passages_path", None):  # an open track: junction passages and limiter impacts
        files["passages"] = "passages.csv"
    elif result.scene.domain(0) is not None:  # a sink of the caller's that does not take them
        atomic_write_text(out_dir / "passages.csv",
                          collisions_csv(result.passage_table(native=True), result.precision.format))
        files["passages"] = "passages.csv"
    if result.scene.rough:  # every change of friction mode (see README, "Rough tracks")
        # (full digits of a quad or MPFR run's own numbers, as the collision table)
        atomic_write_text(out_dir / "transitions.csv",
                          collisions_csv(result.transition_table(native=True), result.precision.format))
        files["transitions"] = "transitions.csv"
    if result.scene.forcing is not None:  # the stroboscopic section: one row per forcing period
        atomic_write_text(out_dir / "stroboscopic.csv", collisions_csv(strobe_table(result), result.precision.format))
        files["stroboscopic"] = "stroboscopic.csv"
    if figures:
        return _figures_then_summary(_run_figures, result, out_dir, scene_source, files, sink)
    return _write_summary(result, out_dir, scene_source, files, sink)


def _run_figures(result, out_dir):
    from .figures import run_figures  # (imported here: matplotlib's import is part of drawing, interruptible)

    return run_figures(result, out_dir)


def _table_figures(result, out_dir):
    from .table_figures import table_figures

    return table_figures(result, out_dir)


class FiguresUnavailable(Exception):
    """A run has nothing the figures could draw (it failed at its start): summary.json says so, no figures."""


class FiguresInterrupted(KeyboardInterrupt):
    """Ctrl-C (or SIGTERM) while a run's figures were drawn: its table and summary.json are whole, its figures
    were dropped (``summary``: what summary.json holds)."""

    def __init__(self, summary: dict):
        super().__init__("interrupted while drawing the figures")
        self.summary = summary


def _figures_then_summary(draw, result, out_dir: Path, scene_source: str, files: dict, sink) -> dict:
    """Draw the figures, then write summary.json. Interrupted while drawing: the figures begun are removed (a
    half-written picture is no output), summary.json is written without them (``"figures": "interrupted"``) and
    FiguresInterrupted is raised."""
    before = {p.name for p in out_dir.glob("*.png")}

    def remove_begun():
        for path in out_dir.glob("*.png"):
            if path.name not in before:
                path.unlink(missing_ok=True)

    try:
        files.update(draw(result, out_dir))
    except KeyboardInterrupt:
        remove_begun()
        summary = _write_summary(result, out_dir, scene_source, dict(files, figures="interrupted"), sink)
        raise FiguresInterrupted(summary) from None
    except FiguresUnavailable as exc:  # (a run that failed at its start has no trajectory to draw)
        remove_begun()
        files["figures"] = f"none: {exc}"
    return _write_summary(result, out_dir, scene_source, files, sink)


def _write_summary(result, out_dir: Path, scene_source: str, files: dict, sink) -> dict:
    """summary.json of a run (every track) whose table ``sink`` wrote; returns the summary."""
    summary = summary_dict(result, scene_source=scene_source, files=files)
    summary["table_format"] = sink.format
    summary["table_rows"] = sink.rows
    # strict JSON (jq, node and DuckDB refuse NaN): a number that is not finite (a failed run's energy) is null
    atomic_write_text(out_dir / "summary.json", json.dumps(_finite_or_null(summary), indent=2, allow_nan=False) + "\n")
    return summary


def _finite_or_null(value):
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _finite_or_null(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite_or_null(v) for v in value]
    return value


def _write_table_run(result, out_dir: Path, *, scene_source: str, figures: bool, sink) -> dict:
    """A billiard run's collisions table, summary.json and figures (table paths, Birkhoff map)."""
    if sink is None:
        sink = table_sink(out_dir, "csv")
        sink.open(result.scene, None, result.precision)
        sink.write(result.records, 1)
        sink.close()
    files = {"collisions": Path(sink.path).name, "summary": "summary.json"}
    if figures:
        return _figures_then_summary(_table_figures, result, out_dir, scene_source, files, sink)
    return _write_summary(result, out_dir, scene_source, files, sink)


def strobe_table(result: SimulationResult) -> np.ndarray:
    """The stroboscopic section as a structured table: n, t, q_1..q_N, dq_1..dq_N."""
    n = result.n_bodies
    c = result.scene.coordinate
    names = ["t"] + [f"{c}_{k + 1}" for k in range(n)] + [f"d{c}_{k + 1}" for k in range(n)]
    rows = result.strobe_rows(native=True)
    number = object if rows.dtype == object else np.float64
    table = np.zeros(len(rows), dtype=[("n", np.int64)] + [(name, number) for name in names])
    table["n"] = np.arange(1, len(rows) + 1)
    for col, name in enumerate(names):
        table[name] = rows[:, col]
    return table
