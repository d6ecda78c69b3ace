"""Sweeps of billiard tables (issue 14 on the sweep of issue 16): the same store, KEYs, resume and figures.

A table point keeps its summary, its state per ball (x, y, vx, vy, slip_x,
slip_y) and, with impacts:M, its last M impacts with the Birkhoff coordinates
of the cushion impacts; each point equals simulate on that scene alone.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import heyroll
from heyroll.interfaces.cli import main
from heyroll.interfaces.scene_file import read_scene_text
from heyroll.sweep import SweepError, SweepKeyError, run_sweep
from heyroll.sweep.points import TABLE_IMPACT_COLUMNS

ROOT = Path(__file__).resolve().parents[1]
ELLIPSE = ROOT / "examples" / "elliptical_billiard.toml"


def _scene_with(text: str, old: str, new: str) -> heyroll.TableScene:
    assert old in text
    return heyroll.parse_scene(text.replace(old, new, 1))


def test_each_table_point_is_what_simulate_gives_to_the_last_bit(tmp_path):
    ds = run_sweep(ELLIPSE, vary={"bodies[1].vy": "0.3:0.9:3"}, keep="impacts:5,first:2", t_end=12.0, workers=1,
                   out=tmp_path)
    assert list(ds["state"].values[:6]) == ["x1", "y1", "vx1", "vy1", "slip_x1", "slip_y1"]
    text = read_scene_text(ELLIPSE)
    for k, vy in enumerate(["0.3", "0.6", "0.9"]):
        result = heyroll.simulate(_scene_with(text, "vy = 0.7", f"vy = {vy}"), t_end=12.0)
        point = ds.isel({"bodies[1].vy": k})
        assert str(point["status"].values) == result.status.value and str(point["message"].values) == result.message
        assert int(point["collisions"]) == result.n_collisions >= 5
        assert float(point["t_final"]) == float(result.t_final)
        assert float(point["energy_initial"]) == result.energy_initial
        assert float(point["energy_final"]) == result.energy_final
        assert np.array_equal(point["final_state"].values, np.array(result.state_final, dtype=float))
        table = result.collision_table()
        for c in TABLE_IMPACT_COLUMNS:
            assert np.array_equal(point[f"impact_{c}"].values[:min(5, table.size)], table[-5:][c], equal_nan=True), c
            assert np.array_equal(point[f"first_impact_{c}"].values, table[:2][c], equal_nan=True), c
    cushion = ds["impact_j"].values == 0
    assert np.isfinite(ds["impact_boundary_s"].values[cushion & (ds["impact_n"].values > 0)]).all()


def test_table_keys_a_map_and_its_invalid_points(tmp_path, capsys):
    code = main(["sweep", str(ELLIPSE), "--vary", "track.a=0.35:2.5:3", "--vary", "bodies[1].y=-0.2:0.2:2",
                 "--t-end", "2", "--workers", "1", "--progress", "off", "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == 0 and "6 points" in out and "invalid_scene" in out  # a = 0.35: the ball is outside
    ds = heyroll.sweep.open_sweep(tmp_path / "sweep.zarr")
    statuses = ds["status"].values
    assert (statuses[0] == "invalid_scene").all() and (statuses[1:] == "completed").all()
    assert "bodies[1]" in str(ds["message"].values[0, 0]) or "track" in str(ds["message"].values[0, 0])
    assert (tmp_path / "map_energy_loss.png").exists() and (tmp_path / "map_collisions.png").exists()


@pytest.mark.parametrize("key, says", [
    ("track.boundary", "no numeric field 'boundary'"),
    ("bodies[1].phi", "no numeric field 'phi'"),
    ("bodies[2].x", "the table has 1 ball,"),
    ("frame.omega", "numeric fields are in"),
])
def test_keys_a_table_does_not_have_are_one_line(key, says, tmp_path):
    with pytest.raises(SweepKeyError) as bad:
        run_sweep(ELLIPSE, vary={key: "0:1:2"}, out=tmp_path / "never")
    assert says in str(bad.value) and "\n" not in str(bad.value)
    assert not (tmp_path / "never").exists()


@pytest.mark.parametrize("how, says", [(dict(keep="period"), "a table scene"), (dict(batch=True), "table engine")])
def test_track_estimates_and_batch_are_refused_for_a_table(how, says, tmp_path):
    with pytest.raises(SweepError) as bad:
        run_sweep(ELLIPSE, vary={"bodies[1].vx": "0.5:1:2"}, out=tmp_path / "x", **how)
    assert says in str(bad.value)
    assert not (tmp_path / "x").exists()


def test_the_bifurcation_diagram_of_a_table_is_in_birkhoff_coordinates(tmp_path):
    run_sweep(ELLIPSE, vary={"bodies[1].vy": "-1:1:9"}, keep="impacts:10", t_end=10.0, workers=1, out=tmp_path,
              figures=True)
    assert (tmp_path / "bifurcation.png").stat().st_size > 10_000
