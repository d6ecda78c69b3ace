"""Collision table writers: the vectorised CSV text is "%.17g" exactly; the parquet table is the npy table."""

import json
import math
import sys
from pathlib import Path
from fractions import Fraction

import numpy as np
import pytest

import heyroll
from heyroll.interfaces.cli import main
from heyroll.interfaces.csv_text import collisions_csv, csv_rows
from heyroll.interfaces.outputs import table_sink
from heyroll.simulation.result import TABLE_COLUMNS, Status

from conftest import ROOT


def per_value_rows(table) -> bytes:
    """The writer before issue 12: one "%.17g" (or str for integers) per value in Python."""
    columns = [table[name].tolist() for name in table.dtype.names]
    kinds = [table.dtype[name].kind for name in table.dtype.names]
    return "".join(
        ",".join(str(v) if kind == "i" else "%.17g" % v for kind, v in zip(kinds, row)) + "\n"
        for row in zip(*columns)
    ).encode()


def exact_ties() -> list[float]:
    """Doubles exactly halfway between two 17-digit decimals (10^k + j 2^(k-17)): "%.17g" rounds them to even."""
    ties = []
    for k in range(-4, 17):
        for j in range(1, 100, 2):
            x = Fraction(10) ** k + Fraction(j, 2 ** (17 - k))
            y = x * Fraction(10) ** (16 - k)
            if Fraction(float(x)) == x and y - math.floor(y) == Fraction(1, 2):
                ties += [float(x), -float(x)]
    assert len(ties) > 1000
    return ties


def awkward_doubles(rng, n) -> np.ndarray:
    """Every kind of double: random bit patterns (subnormal, huge, nan, inf), powers of ten and their
    neighbours, numbers with few digits (trailing zeros), signed zeros, exact and near ties at the 17th digit."""
    powers = 10.0 ** np.arange(-320, 309)
    parts = [
        rng.integers(0, 2**64, n, dtype=np.uint64).view(np.float64),
        rng.standard_normal(n) * 10.0 ** rng.integers(-30, 30, n),
        powers, -np.nextafter(powers, 0), np.nextafter(powers, np.inf),
        np.round(rng.standard_normal(n) * 1e4, 3), np.arange(-500.0, 500.0),
        np.array([0.0, -0.0, np.nan, -np.nan, np.inf, -np.inf, 5e-324, -2.2250738585072014e-308,
                  1.7976931348623157e308, 1e16, 1e17, 2.0**53, 1e-4, 1e-5, 9.999999999999999e-5]),
        np.array([float("%de%d" % (v, e)) for v, e in zip(rng.integers(10**16, 10**17, 2000) * 10 + 5,
                                                           rng.integers(-40, 40, 2000))]),
        np.array(exact_ties()),
    ]
    values = np.concatenate(parts)
    return values[rng.permutation(values.size)]


def test_csv_text_is_the_per_value_text_for_every_kind_of_double():
    rng = np.random.default_rng(12)
    values = awkward_doubles(rng, 30000)
    rows = values.size // 3
    table = np.zeros(rows, dtype=[("n", np.int64), ("a", np.float64), ("i", np.int64), ("b", np.float64),
                                  ("c", np.float64)])
    table["n"] = np.arange(1, rows + 1)
    table["i"] = rng.integers(-(2**52), 2**52, rows)
    table["a"], table["b"], table["c"] = values[:3 * rows].reshape(3, rows)
    text = csv_rows(table)
    assert text == per_value_rows(table)
    cells = np.array([line.split(",") for line in text.decode().splitlines()])
    for c, name in enumerate(table.dtype.names):  # and the text reads back to the same numbers
        back = cells[:, c].astype(np.int64 if name in ("n", "i") else np.float64)
        assert np.array_equal(back, table[name], equal_nan=True), name
        if name not in ("n", "i"):  # -0.0 too ("%.17g" writes every nan as "nan")
            numbers = ~np.isnan(back)
            assert np.array_equal(np.signbit(back[numbers]), np.signbit(table[name][numbers])), name


def test_collision_and_passage_tables_as_before():
    table = heyroll.simulate(heyroll.default_scene(), t_end=300.0).collision_table()
    assert table.dtype.names == TABLE_COLUMNS and table.size > 200
    assert collisions_csv(table) == ",".join(TABLE_COLUMNS) + "\n" + per_value_rows(table).decode()
    assert collisions_csv(table[:0]) == ",".join(TABLE_COLUMNS) + "\n"
    passages = heyroll.simulate(heyroll.load_scene(ROOT / "examples" / "arc_chain.toml"), t_end=5.0).passage_table()
    assert passages.size > 0
    assert collisions_csv(passages) == ",".join(passages.dtype.names) + "\n" + per_value_rows(passages).decode()


def test_object_columns_keep_their_own_formatter():
    table = np.zeros(2, dtype=[("n", np.int64), ("t", object)])
    table["n"], table["t"] = [1, 2], [0.5, 0.25]
    assert csv_rows(table, lambda v: f"<{v}>") == b"1,<0.5>\n2,<0.25>\n"


def test_parquet_table_is_the_npy_table(tmp_path, capsys):
    pytest.importorskip("pyarrow")
    import pyarrow.parquet as pq

    args = ["run", "--max-collisions", "40", "--no-figures", "--progress", "off"]
    assert main([*args, "--out", str(tmp_path / "npy"), "--table", "npy"]) == 0
    assert main([*args, "--out", str(tmp_path / "pq"), "--table", "parquet"]) == 0
    assert sorted(p.name for p in (tmp_path / "pq").iterdir()) == ["collisions.parquet", "summary.json"]
    expected = np.load(tmp_path / "npy" / "collisions.npy")
    table = pq.read_table(tmp_path / "pq" / "collisions.parquet")
    assert table.column_names == list(expected.dtype.names) and table.num_rows == expected.size == 40
    for name in expected.dtype.names:
        column = table[name].to_numpy()
        assert column.dtype == expected.dtype[name] and np.array_equal(column, expected[name], equal_nan=True), name


class InterruptAt:
    """A table sink that raises KeyboardInterrupt as chunk ``at`` is handed to it (Ctrl-C mid-run)."""

    def __init__(self, inner, at):
        self.inner, self.at, self.path, self.writes = inner, at, inner.path, 0

    def open(self, *args):
        self.inner.open(*args)

    def write(self, chunk, first_number):
        self.writes += 1
        if self.writes == self.at:
            raise KeyboardInterrupt
        self.inner.write(chunk, first_number)

    @property
    def rows(self):
        return self.inner.rows

    def close(self):
        self.inner.close()


def test_parquet_streams_chunks_and_an_interruption_leaves_a_complete_table(tmp_path):
    pytest.importorskip("pyarrow")
    import pyarrow.parquet as pq

    scene = heyroll.default_scene()
    full = heyroll.simulate(scene, t_end=60.0).collision_table()
    streamed = heyroll.simulate(scene, t_end=60.0, sink=table_sink(tmp_path / "all", "parquet"), chunk_size=8)
    table = pq.read_table(tmp_path / "all" / "collisions.parquet")
    assert streamed.status is Status.COMPLETED and table.num_rows == full.size > 16
    assert pq.ParquetFile(tmp_path / "all" / "collisions.parquet").num_row_groups > 1
    for name in TABLE_COLUMNS:
        assert np.array_equal(table[name].to_numpy(), full[name], equal_nan=True), name
    out = tmp_path / "cut"
    result = heyroll.simulate(scene, t_end=60.0, sink=InterruptAt(table_sink(out, "parquet"), 3), chunk_size=8)
    assert result.status is Status.INTERRUPTED
    table = pq.read_table(out / "collisions.parquet")  # the footer is there: a complete file
    assert table["n"].to_pylist() == list(range(1, table.num_rows + 1)) and table.num_rows >= 16
    assert np.array_equal(table["t"].to_numpy(), full["t"][:table.num_rows])
    assert [p.name for p in out.iterdir()] == ["collisions.parquet"]


def test_parquet_without_pyarrow_is_one_line_exit_2_and_nothing_written(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "pyarrow", None)  # import pyarrow -> ImportError
    monkeypatch.setitem(sys.modules, "pyarrow.parquet", None)
    out = tmp_path / "out"
    assert main(["run", "--out", str(out), "--t-end", "1", "--table", "parquet", "--progress", "off"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("heyroll: error: --table:")
    assert "pip install 'heyroll[parquet]'" in err[0]
    assert not out.exists()


@pytest.mark.parametrize("table", ["npy", "parquet"])
def test_binary_tables_refuse_other_precisions(table, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", "--out", str(out), "--t-end", "1", "--table", table, "--precision", "quad"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"heyroll: error: --table: {table} holds float64 columns: use csv for long, quad and MPFR runs"]
    assert not out.exists()


def test_passages_are_streamed_to_passages_csv_and_only_the_first_chunk_kept(tmp_path):
    # Issue 13: every table is streamed; junction passages and limiter impacts piled up in memory.
    import heyroll
    from heyroll.interfaces.outputs import write_run
    from heyroll.interfaces.scene_file import load_scene

    scene = load_scene(str(Path(__file__).resolve().parent.parent / "examples" / "arc_chain.toml"))
    whole = heyroll.simulate(scene, t_end=20)
    assert len(whole.passages) > 12
    sink = table_sink(tmp_path, "csv")
    streamed = heyroll.simulate(scene, t_end=20, sink=sink, chunk_size=5)
    write_run(streamed, tmp_path, scene_source="arc_chain.toml", figures=False, sink=sink)
    assert len(streamed.passages) == 5  # the first chunk, for figures
    summary = json.loads((tmp_path / "summary.json").read_text())
    counts = whole.summary()
    assert (summary["junction_passages"], summary["limiter_impacts"]) == (counts["junction_passages"],
                                                                        counts["limiter_impacts"])
    text = (tmp_path / "passages.csv").read_text()
    assert text == collisions_csv(whole.passage_table())  # every passage, the same text as unstreamed
    assert not list(tmp_path.glob(".*.tmp"))
