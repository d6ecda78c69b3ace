"""A ball riding the cushion and a sliding ball that friction pushes into it again and again: contacts the
instant's resolutions (a rider put back onto its curve, leave()'s opening) leave overlapping past round-off
must be opened before the next step, else the pair's gap starts below zero, friction turns it back before it
crosses zero, and the next impact goes unseen (status overlap: review)."""

from __future__ import annotations

import pytest

from heyroll import Status, simulate
from heyroll.interfaces.scene_file import parse_scene
from heyroll.simulation.driver import RunOptions
from heyroll.simulation.table.driver import _Run
from heyroll.simulation.table.system import STATE_PER_BALL

from test_billiards import ball, table_scene

CIRCLE = 'boundary = "circle"\nradius = 1.0'
RECTANGLE = 'boundary = "rectangle"\nwidth = 2.0\nheight = 1.0'

#: review case fd_12_93: ball 2 rides the elliptical cushion, ball 6 (sliding, mu = 0.5) is pushed into it again
#: and again; the pair was left 1.2e-11 m, then 4.4e-12 m, into each other (rider projected back onto its curve
#: after leave() had moved it into the cushion) and the run stopped at t = 1.845 s: "balls 2 and 6 overlap by
#: 3.02e-08 m ... an impact was missed", in double, long and quad
RIDER_AND_PUSHED_BALL = """
[track]
type = "table"
boundary = "ellipse"
a = 1.054
b = 0.763
cushion_model = "rolling"
cushion_restitution = 0.3
friction = 0.5
[[bodies]]
shape = "hollow_sphere"
radius = 0.0873
mass = 0.441
x = -0.2908
y = -0.2995
vx = 2.509
vy = -0.670
[[bodies]]
shape = "hollow_sphere"
radius = 0.0954
mass = 0.465
x = 0.3026
y = 0.0929
vx = -2.438
vy = 1.225
wx = -31.81
wy = 31.62
[[bodies]]
shape = "disk"
radius = 0.0726
mass = 0.457
x = -0.3971
y = 0.1064
vx = 2.808
vy = -2.645
[[bodies]]
shape = "ring"
radius = 0.0766
mass = 0.198
x = 0.1493
y = 0.3245
vx = 1.748
vy = -0.807
wx = -17.22
wy = -11.21
[[bodies]]
shape = "solid_sphere"
radius = 0.0955
mass = 0.193
x = 0.2989
y = -0.3106
vx = -2.868
vy = -0.118
wx = -35.80
wy = -14.11
[[bodies]]
shape = "solid_sphere"
radius = 0.0924
mass = 0.441
x = -0.0282
y = -0.0384
vx = 2.171
vy = 1.643
[collision]
law = "slide"
restitution = 0.5
simultaneous = "impulses"
[run]
t_end = 2.5
"""


@pytest.mark.parametrize("precision", ["double", "long"])
def test_a_rider_and_a_ball_friction_pushes_into_it_are_not_left_overlapping(precision):
    result = simulate(parse_scene(RIDER_AND_PUSHED_BALL, default_name="fd_12_93"), precision=precision)
    assert result.status is Status.COMPLETED, result.message  # was: overlap at t = 1.8455 s


def _run(scene):
    return _Run(scene, RunOptions(), None, None)


def test_leave_opens_a_pair_with_a_riding_ball_by_moving_the_other_ball_only():
    """The rider stays on its cushion's curve (its constraint): moved off it into the cushion, it was put back
    onto it when next settled, straight into its partner (review)."""
    scene = table_scene(CIRCLE, [ball("0.9", "0", "0", "1"), ball("0.7", "0", "0", "0")], cushion_k="0.5")
    run = _run(scene)
    run.riding[0], run.ride_wall[0] = True, 0
    rider = list(run.state[:2])
    contact, = [c for c in run.touching() if c.kind == "pair"]
    run.leave(contact)
    assert run.state[:2] == rider  # the rider unmoved, on its curve
    distance, _ = run.geometry.pair(0, 1, run.state)
    assert 0 < distance < 2.0**20 * 2.2e-16  # opened past round-off, by ulps
    assert run.state[STATE_PER_BALL] > 0.7 - 1e-12 and run.state[STATE_PER_BALL] < 0.7


def test_the_contact_that_fired_is_opened_where_the_instant_left_it_overlapping():
    """The fired contact keeps its cooldown only at its root: a pair 1e-11 m into each other (100x the opening
    of a touching contact), separating, was left so, and friction closed it unseen (review)."""
    scene = table_scene(RECTANGLE, [ball("-0.3", "0", "-1e-6", "0"), ball("-0.1", "0", "1e-6", "0")],
                        friction="0.5", k="0.5")
    run = _run(scene)
    s = STATE_PER_BALL
    run.state[s] = run.state[s] - 1e-11  # the second ball 1e-11 m into the first, both moving apart
    fired, = [c for c in run.touching() if c.kind == "pair"]
    assert fired.distance < -5e-12
    run.at_instant(fired)
    assert run.status is None
    distance, _ = run.geometry.pair(0, 1, run.state)
    assert distance > 0
