"""Whole turns taken out of a circle run's angles (heyroll.simulation.turns).

Review (many bodies): phi was never reduced, so bodies going round carried a growing angle and the
integrator's rounding grew with it: two disks going round for 1e5 s lost 5e-9 of their energy at k = 1
(1.4e-13 oscillating), and a group drifting round in a many-body run 2.5e-10 over 1e6 collisions.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest

import heyroll
from heyroll import parse_scene
from heyroll.reference.pendulum import ExactPendulum
from heyroll.simulation import turns as turns_module
from heyroll.simulation.precision import DOUBLE, Precision
from heyroll.simulation.turns import Turns

# g = 9, a disk of radius 0.25 in R = 1: phi'' = -8 sin phi exactly in double (tests/test_reference.py)
A_EXACT = 8


def _going_round(t_end: float) -> heyroll.SimulationResult:
    scene = heyroll.Scene.make(track=heyroll.CircleTrack.of_radius(1),
                               bodies=[heyroll.Body.of_shape("disk", 0.25, mass=1)], phi=[0.0], dphi=[8.0], g=9)
    return heyroll.simulate(scene, t_end=t_end)


def test_a_body_going_round_follows_the_exact_pendulum():
    """Over 1000 s (848 turns, phi = 6777 rad): without the turns taken out, phi was off by 5.5e-9 rad and the
    energy by 1.1e-12; now 3.4e-12 rad and 1.2e-13 (measured)."""
    result = _going_round(1000.0)
    exact = ExactPendulum(A_EXACT, 0, 8.0, 0, dps=40)
    phi, dphi = exact.state(1000)[:2]
    with mpmath.workdps(40):
        assert abs(float(mpmath.mpf(result.final_state[0]) - phi)) < 1e-10
        assert abs(float(mpmath.mpf(result.final_state[1]) - dphi)) < 1e-10
    assert float(result.final_state[0]) > 6000  # reported unwrapped: the turns put back
    assert abs(result.energy_final - result.energy_initial) < 5e-13 * result.energy_initial


@pytest.mark.parametrize("precision", [DOUBLE, Precision.parse("long")], ids=["double", "long"])
def test_turns_are_taken_exactly_so_gaps_keep_their_last_bit(precision):
    num = precision.number
    rng = np.random.default_rng(5)

    class Log:
        count, strobe = 0, []

    for first in (13.0, -13.0, 40.0, -1000.5, 7e5):
        turns = Turns(precision)
        angles = [num(first + x) for x in np.sort(rng.uniform(0, 2 * math.pi - 0.1, 6))]
        dtype = float if precision is DOUBLE else np.longdouble
        state = np.array(angles + [num(1.0)] * 6, dtype=dtype)
        gaps = [angles[k + 1] - angles[k] for k in range(5)]
        assert turns.take(state, 6, Log())
        assert abs(float(state[0])) < turns_module.WIND_AT
        assert [state[k + 1] - state[k] for k in range(5)] == gaps  # not one bit changed
        assert list(state[6:]) == [num(1.0)] * 6  # the rates are left alone
        back = turns.angles(list(state), 6)
        assert all(abs(float(b - a)) <= 4 * abs(float(a)) * precision.epsilon for a, b in zip(angles, back))


def test_the_residual_keeps_the_angles_on_the_true_turns():
    """A fixed shift fl(2 pi) would drift by 2.4e-16 rad a turn (1.2e-11 rad over 50,000 turns); error feedback
    keeps the shifts taken within an ulp of the shift of the whole turns, however many."""
    turns = Turns(DOUBLE)

    class Log:
        count, strobe = 0, []

    state = np.array([0.0, 0.0])
    whole = 0
    for _ in range(20000):
        state[0] += 16.0  # (past WIND_AT = 4 pi from anywhere in [-pi, pi])
        whole += round(float(state[0]) / (2 * math.pi))
        assert turns.take(state, 1, Log())
    with mpmath.workprec(256):
        total = mpmath.mpf(turns._total[0]) + mpmath.mpf(turns._total[1])  # (double: a compensated pair)
        drift = abs(total - whole * 2 * mpmath.pi)
    assert float(drift) < 4e-15


TWO_ROUND = """
[track]
type = "circle"
radius = 1.0
[[bodies]]
shape = "disk"
radius = 0.1
mass = 1.0
phi = -0.3
dphi = 9.0
[[bodies]]
shape = "solid_sphere"
radius = 0.12
mass = 0.8
phi = 0.3
dphi = 6.5
[collision]
law = "hedrih"
restitution = 1.0
"""


def test_what_a_run_reports_is_unwrapped_in_every_output(monkeypatch, tmp_path):
    """The table (in memory and streamed to a file), the final state and the mode changes give the same
    unwrapped angles as a run that takes no turns out, to that run's accuracy."""
    from heyroll.interfaces.outputs import table_sink
    from heyroll.simulation.batch import simulate_batch

    scene = parse_scene(TWO_ROUND)
    options = heyroll.RunOptions(t_end=40.0)
    wound = heyroll.simulate(scene, options)
    sink = table_sink(tmp_path, "npy")
    streamed = heyroll.simulate(scene, heyroll.RunOptions(t_end=40.0, chunk_size=7), sink=sink)
    batch = simulate_batch([scene], options)[0]
    assert batch.settings["batch"].startswith("batch")
    monkeypatch.setattr(turns_module, "WIND_AT", math.inf)
    plain = heyroll.simulate(scene, options)
    assert wound.n_collisions == plain.n_collisions == streamed.n_collisions == batch.n_collisions > 20
    assert float(plain.final_state[0]) > 100  # they went round
    for result in (wound, batch):
        # (two runs apart by rounding: the motion is chaotic, 1e-8 apart after 40 s; a turn left in or out
        # would be 6.28 rad)
        assert np.allclose(result.times, plain.times, rtol=1e-9, atol=0)
        assert np.allclose(result.states_before, plain.states_before, rtol=1e-6, atol=1e-6)
        assert np.allclose(result.states_after, plain.states_after, rtol=1e-6, atol=1e-6)
        assert np.allclose(result.final_state, plain.final_state, rtol=1e-6, atol=1e-6)
    table = np.load(tmp_path / "collisions.npy")
    assert np.array_equal(table["q_i"], wound.collision_table()["q_i"])
    assert np.array_equal(table["t"], wound.collision_table()["t"])
    assert np.array_equal(streamed.final_state, wound.final_state)
    # the energy at every row: kept to round-off at k = 1 (the unwrapped angles' own rounding included)
    energies = wound.collision_table()["energy_after"]
    assert np.max(np.abs(energies - wound.energy_initial)) < 1e-12 * wound.energy_initial


def test_a_shift_cut_in_two_by_ctrl_c_is_settled_by_the_state():
    """Review: a Ctrl-C between the state's shift and its record left the final state whole turns off (17 of
    60 interrupted runs). The state moves in one numpy operation; settle() records it or forgets it."""

    class Log:
        count, strobe = 0, []

    class Cut(Turns):
        __slots__ = ("cut",)

        def _commit(self):
            if not self.cut:
                super()._commit()

    for moved in (True, False):
        turns = Cut(DOUBLE)
        turns.cut = True  # (interrupted right after the state's shift)
        state = np.array([20.0, 21.0])
        assert turns.take(state, 1, Log())
        turns.cut = False
        if not moved:
            state[0] = turns._pending[0]  # (interrupted before it)
        turns.settle(state)
        assert turns._pending is None
        assert (float(state[0]) + float(turns.offset)) == pytest.approx(20.0, abs=1e-14)


ONE_SIDED = """
[track]
type = "circle"
radius = 1.0
sides = "one"
friction = 0.001
[[bodies]]
shape = "particle"
mass = 1.0
phi = 0.0
dphi = 8.5
[collision]
law = "newton"
[run]
t_end = 60.0
"""

FAR_OUT = """
[track]
type = "circle"
radius = 1.0
[[bodies]]
shape = "disk"
radius = 0.1
mass = 1.0
phi = 1000.0
dphi = 1.0
[[bodies]]
shape = "ring"
radius = 0.1
mass = 0.5
phi = 1000.5
dphi = -1.0
[run]
t_end = 20.0
"""


def test_messages_give_the_angles_reported():
    """Review: the left_track message and the two-sided track's warning printed the angle with the turns
    taken out (phi = 3.06 where the final state said 292.09; 1.67 for a body started at phi = 1000)."""
    import re

    result = heyroll.simulate(parse_scene(ONE_SIDED))
    assert result.status.value == "left_track"
    phi = float(re.search(r"at phi = (\S+),", result.message).group(1))
    assert phi == float(result.final_state[0]) and phi > 100
    result = heyroll.simulate(parse_scene(FAR_OUT))
    (warning,) = [w for w in result.settings["warnings"] if "normal force" in w]
    assert 990 < float(re.search(r"phi = (\S+):", warning).group(1)) < 1010
