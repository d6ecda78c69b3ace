"""The pieces of the long-run energy study (validation/energy_study.py), on short data.

The study itself (validation/long_runs.py) takes minutes; here: the growth
exponent fit, the periodicity detector, and the energy sink on a short elastic
run of the default scene, checked against the same run without a sink.
"""

import sys
from pathlib import Path

import numpy as np
import pytest

VALIDATION = Path(__file__).resolve().parents[1] / "validation"
sys.path.insert(0, str(VALIDATION))

import energy_study  # noqa: E402
from energy_study import (  # noqa: E402
    EnergySink,
    find_recurrence,
    fit_growth_exponent,
    log_grid,
    structure_exponent,
    total_energy,
)


def test_fit_recovers_random_walk_exponent():
    rng = np.random.default_rng(1)
    walks = np.cumsum(rng.standard_normal((400, 20000)), axis=1)  # 400 random walks
    n = log_grid(20000)
    rms = np.sqrt(np.mean(walks[:, n - 1] ** 2, axis=0))
    p, c = fit_growth_exponent(n, rms, 100, 20000)
    assert p == pytest.approx(0.5, abs=0.05)
    assert c == pytest.approx(1.0, rel=0.3)


def test_fit_recovers_linear_drift():
    n = log_grid(10**6)
    p, c = fit_growth_exponent(n, 3e-18 * n, 10, 10**6)
    assert p == pytest.approx(1.0, abs=1e-9)
    assert c == pytest.approx(3e-18, rel=1e-9)


def test_structure_exponent_of_one_trajectory():
    rng = np.random.default_rng(2)
    walk = np.cumsum(rng.standard_normal(5000))
    assert structure_exponent(walk) == pytest.approx(0.5, abs=0.1)
    drift = 1e-3 * np.arange(5000) + 1e-9 * rng.standard_normal(5000)
    assert structure_exponent(drift) == pytest.approx(1.0, abs=0.05)


def test_recurrence_flags_periodic_rows_not_random_ones():
    rng = np.random.default_rng(3)
    transient = rng.standard_normal((5, 4))
    cycle = rng.standard_normal((7, 4))
    periodic = np.concatenate([transient, np.tile(cycle, (50, 1))])
    assert find_recurrence(periodic) == (12, 7)  # row 12 repeats row 5
    assert find_recurrence(rng.standard_normal((5000, 4))) is None
    # bit-for-bit: a value one ulp away is not a recurrence
    near = np.concatenate([cycle, np.nextafter(cycle, np.inf)])
    assert find_recurrence(near) is None


def test_sink_detects_recurrence_across_chunks():
    import heyroll
    from heyroll.simulation.precision import DOUBLE

    rng = np.random.default_rng(4)
    cycle = rng.standard_normal((3, 4))
    states = np.tile(cycle, (10, 1))  # collision 4 repeats collision 1
    sink = EnergySink(30, window=8)
    sink.open(heyroll.default_scene(), (), DOUBLE)
    for start in range(0, 30, 2):  # chunks of 2 rows: every repeat is across a chunk boundary
        rows = states[start:start + 2]
        sink.write((np.zeros(2), np.zeros(2, dtype=int), rows, rows), first_number=start + 1)
    sink.close()
    assert sink.recurrence == (4, 3)
    assert sink.periodic and sink.last_n == 30

    fresh = EnergySink(30, window=8)
    fresh.open(heyroll.default_scene(), (), DOUBLE)
    noise = rng.standard_normal((30, 4))
    for start in range(0, 30, 2):
        rows = noise[start:start + 2]
        fresh.write((np.zeros(2), np.zeros(2, dtype=int), rows, rows), first_number=start + 1)
    assert not fresh.periodic


@pytest.fixture(scope="module")
def default_runs():
    import heyroll

    scene = heyroll.default_scene()
    n = 20000
    sink = EnergySink(n)
    streamed = heyroll.simulate(scene, t_end=1e9, max_collisions=n, sink=sink, chunk_size=4096)
    plain = heyroll.simulate(scene, t_end=1e9, max_collisions=n)
    return scene, sink, streamed, plain


def test_energy_sink_on_a_short_elastic_run(default_runs):
    scene, sink, streamed, plain = default_runs
    assert streamed.status.value == "max_collisions" and plain.status.value == "max_collisions"
    assert streamed.n_collisions == plain.n_collisions == sink.last_n == 20000
    assert abs(sink.last_err) < 1e-13
    assert sink.max_abs_err < 1e-13
    assert not sink.periodic and not sink.frozen
    # the sink's last value is the energy of the same run recomputed without a sink
    constants = energy_study.energy_constants(scene)
    e0 = total_energy(constants, plain.initial_state)[0]
    last = total_energy(constants, plain.states_after[-1])[0]
    assert sink.last_err == float(last / e0 - 1)
    assert np.array_equal(plain.states_after[-1], plain.final_state)
    # and agrees with heyroll's own float64 energies to rounding
    assert sink.last_err == pytest.approx(plain.energy_final / plain.energy_initial - 1, abs=2e-15)
    # the grid holds the same values: spot-check a few collisions against the full table
    table = dict(zip(sink.grid_n, sink.grid_err))
    for k in (1, 100, 1000, 20000):
        assert table[k] == float(total_energy(constants, plain.states_after[k - 1])[0] / e0 - 1)
    # map and integration parts add up to the total
    d = sink.as_dict()
    assert d["map_total"] + d["flight_total"] == pytest.approx(d["last_err"], abs=1e-18)
    assert len(d["block_end_err"]) == 1000 and d["block_end_err"][-1] == d["last_err"]
    assert max(d["block_max"]) == pytest.approx(d["max_abs_err"])


def test_energy_sink_flags_a_periodic_run():
    import heyroll

    text = (
        'g = 9.81\n[track]\ntype = "circle"\nradius = 1.0\n'
        '[[bodies]]\nshape = "solid_sphere"\nradius = 0.1\nmass = 1.0\nphi = -0.5\ndphi = 0.0\n'
        '[[bodies]]\nshape = "solid_sphere"\nradius = 0.1\nmass = 1.0\nphi = 0.5\ndphi = 0.0\n'
        '[collision]\nlaw = "hedrih"\nrestitution = 1.0\n'
    )
    sink = EnergySink(2000)
    heyroll.simulate(heyroll.parse_scene(text), t_end=1e9, max_collisions=2000, sink=sink)
    assert sink.periodic
