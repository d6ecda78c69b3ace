"""Batch runs (heyroll.simulation.batch): many scenes of one shape in heyoka's batch (SIMD) integrator.

A batch run must give each scene what its scalar run gives: the same
statuses, messages, collision counts and pairs, collision times within a few
ulps (heyoka's vector code rounds differently now and then: not the same
bits), and every scene it cannot run as a scalar run would goes to the scalar
engine.
"""

from __future__ import annotations

import numpy as np
import pytest

import heyroll
from heyroll.interfaces.cli import main
from heyroll.interfaces.scene_file import default_scene, default_scene_text, load_scene
from heyroll.simulation.batch import batch_reason, simulate_batch
from heyroll.sweep import SweepError, SweepStoreError, run_sweep

OPTIONS = heyroll.RunOptions(t_end=1e4, max_collisions=40)


def _points(n: int, lo: float = -1.2, hi: float = -0.8):
    base = default_scene()
    return [base.with_state(q=(v, base.q[1])) for v in np.linspace(lo, hi, n)]


def _agree(scalar, batch, rtol: float = 1e-13) -> None:
    assert batch.status is scalar.status and batch.message == scalar.message
    assert batch.n_collisions == scalar.n_collisions
    a, b = scalar.collision_table(), batch.collision_table()
    assert np.array_equal(a["i"], b["i"]) and np.array_equal(a["j"], b["j"])
    assert np.allclose(a["t"], b["t"], rtol=rtol, atol=0)
    assert np.allclose(np.asarray(batch.final_state, float), np.asarray(scalar.final_state, float), rtol=1e-9, atol=1e-12)
    assert batch.energy_initial == scalar.energy_initial
    assert abs(batch.energy_final - scalar.energy_final) <= 1e-13 * abs(scalar.energy_initial)


def test_each_scene_of_a_batch_is_its_scalar_run_within_a_few_ulps():
    scenes = _points(11)
    batch = simulate_batch(scenes, OPTIONS)
    ran = [r.settings["batch"] for r in batch]
    assert sum(s.startswith("batch of") for s in ran) >= 8  # most of them in SIMD elements
    worst = 0.0
    for scene, result in zip(scenes, batch):
        scalar = heyroll.simulate(scene, OPTIONS)
        _agree(scalar, result)
        t_s, t_b = scalar.collision_table()["t"], result.collision_table()["t"]
        worst = max(worst, float(np.max(np.abs(t_b - t_s) / t_s)))
    assert worst < 1e-14  # measured: ~5e-16 over 30 collisions (a few ulps)


def test_elements_take_the_next_scene_when_one_stops():
    """Width 2 for 5 scenes that reach their 25th collision at different times: each element runs
    several scenes one after the other, and each scene is still its scalar run."""
    scenes = _points(5, -1.1, -0.3)
    options = heyroll.RunOptions(t_end=1e4, max_collisions=25)
    together = simulate_batch(scenes, options, width=2)
    assert len({round(float(r.t_final), 6) for r in together}) == 5  # different lengths
    assert all(r.settings["batch"] == "batch of 2 (heyoka SIMD)" for r in together)
    for scene, result in zip(scenes, together):
        _agree(heyroll.simulate(scene, options), result)


def test_a_body_over_the_top_warns_as_in_its_scalar_run():
    """Fast enough to reach the upper half of the circle: the track's normal force changes sign there
    (a warning on a two-sided track), found by the batch's non-terminal events at the scalar run's time."""
    base = default_scene()
    over_the_top = base.with_state(dq=(base.dq[0], 5.0))
    options = heyroll.RunOptions(t_end=1e4, max_collisions=8)  # (chaotic: later collisions drift apart)
    batch, = simulate_batch([over_the_top], options)
    scalar = heyroll.simulate(over_the_top, options)
    assert batch.settings["batch"].startswith("batch of")
    _agree(scalar, batch)
    assert scalar.settings["warnings"] and len(batch.settings["warnings"]) == len(scalar.settings["warnings"])
    for a, b in zip(scalar.settings["warnings"], batch.settings["warnings"]):
        ta, tb = (float(w.split(" at t = ")[1].split(" s,")[0]) for w in (a, b))
        assert abs(ta - tb) <= 1e-13 * ta


def test_scenes_the_batch_cannot_run_are_their_scalar_runs_to_the_last_bit():
    base = default_scene()
    one_sided = heyroll.parse_scene(default_scene_text().replace('type = "circle"', 'type = "circle"\nsides = "one"'))
    touching = base.with_state(q=(0, base.pairs[0].beta), dq=(0, 0))  # starts in contact, at rest
    results = simulate_batch([one_sided.with_state(dq=(base.dq[0], 5.0)), touching], OPTIONS)
    for scene, result in zip((one_sided.with_state(dq=(base.dq[0], 5.0)), touching), results):
        assert result.settings["batch"].startswith("scalar:")
        scalar = heyroll.simulate(scene, OPTIONS)
        assert np.array_equal(result.collision_table()["t"], scalar.collision_table()["t"])
        assert result.status is scalar.status


@pytest.mark.parametrize("options, scene, says", [
    (heyroll.RunOptions(precision="quad"), None, "double precision"),
    (heyroll.RunOptions(dense=True), None, "dense output"),
    (heyroll.RunOptions(), "rough_circle.toml", "circle in a fixed plane"),
    (heyroll.RunOptions(), "arc_chain.toml", "circle in a fixed plane"),
    (heyroll.RunOptions(), "elliptical_billiard.toml", "table scene"),
])
def test_what_runs_scalar_and_why(options, scene, says):
    from pathlib import Path

    scene = default_scene() if scene is None else load_scene(Path(__file__).parents[1] / "examples" / scene)
    assert says in batch_reason(scene, options)
    assert batch_reason(default_scene(), heyroll.RunOptions()) == ""


def test_a_batch_sweep_agrees_with_the_scalar_sweep_and_is_its_own_store(tmp_path):
    spec = dict(vary={"bodies[1].phi": "-1.2:-0.8:12"}, keep="impacts:4,period", max_collisions=30, t_end=1e4,
                workers=1)
    scalar = run_sweep(out=tmp_path / "scalar", **spec)
    batch = run_sweep(out=tmp_path / "batch", batch=True, **spec)
    assert batch.attrs["batch"] and not scalar.attrs["batch"]
    assert (batch["status"].values == scalar["status"].values).all()
    assert (batch["collisions"].values == scalar["collisions"].values).all()
    assert (batch["period"].values == scalar["period"].values).all()
    assert np.allclose(batch["impact_t"].values, scalar["impact_t"].values, rtol=1e-13, atol=0)
    with pytest.raises(SweepStoreError):  # a scalar sweep does not resume a batch store
        run_sweep(out=tmp_path / "batch", **spec)
    with pytest.raises(SweepError):
        run_sweep(out=tmp_path / "quad", batch=True, precision="quad", **spec)


def test_the_cli_takes_batch_and_refuses_it_with_quad(tmp_path, capsys):
    code = main(["sweep", "--vary", "bodies[1].phi=-1.1:-0.9:4", "--batch", "--workers", "1", "--max-collisions",
                 "10", "--t-end", "100", "--no-figures", "--progress", "off", "--out", str(tmp_path / "a")])
    assert code == 0 and "4 points" in capsys.readouterr().out
    code = main(["sweep", "--vary", "bodies[1].phi=-1.1:-0.9:4", "--batch", "--precision", "quad",
                 "--out", str(tmp_path / "b")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--batch" in err[0] and not (tmp_path / "b").exists()
