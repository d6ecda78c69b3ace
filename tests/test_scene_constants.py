"""Scenes that differ only in their start: Scene.with_state, Scene.constants and the engine's caches by them.

A sweep over initial conditions (issue 16, item 5) builds each point as the
base scene started elsewhere, and the engine reuses what it built for the
scene's constants. Both must give what the normal loader and a fresh build
give, to the last bit.
"""

from __future__ import annotations

import math
import pickle
from pathlib import Path

import numpy as np
import pytest

import heyroll
from heyroll.errors import SceneError
from heyroll.interfaces.scene_file import default_scene, load_scene, read_scene_text, scene_from_dict
from heyroll.simulation.precision import Precision
from heyroll.simulation.system import build_system, energy_reach
from heyroll.sweep import SweepKeyError
from heyroll.sweep.keys import parse_key
from heyroll.sweep.points import point_data, point_scene_maker, state_slots

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
DOUBLE = Precision.parse("double")

#: Example scenes of every kind of track with state keys to vary: (file, KEYs, factors applied to the values).
CASES = [
    (None, ("bodies[1].phi", "bodies[2].dphi"), (1.05, 0.7)),
    ("disk_and_ring.toml", ("bodies[1].phi", "bodies[1].dphi"), (0.9, 1.3)),
    ("rough_circle.toml", ("bodies[1].phi",), (0.8,)),
    ("arc_chain.toml", ("bodies[1].s", "bodies[1].ds"), (1.01, 0.5)),
    ("rotating_curve.toml", ("bodies[1].x",), (0.9,)),
    ("rough_parabola_forced.toml", ("bodies[1].x", "bodies[1].dx"), (1.1, 0.5)),
    ("rough_cycloid.toml", ("bodies[2].slip", "bodies[2].du"), (0.05, 0.1)),  # a disk that starts slipping
]


def _data(name):
    text = read_scene_text(ROOT / "examples" / name) if name else heyroll.interfaces.scene_file.default_scene_text()
    return tomllib.loads(text)


def _values(data, keys, factors):
    """The base scene's values of ``keys`` scaled (a value of 0 becomes the factor itself)."""
    out = []
    for key, factor in zip(keys, factors):
        body, field = key.split(".")
        entry = data["bodies"][int(body[len("bodies["):-1]) - 1]
        value = float(entry.get(field, 0.0))
        out.append(value * factor if value else factor)
    return tuple(out)


@pytest.mark.parametrize("name, keys, factors", CASES)
def test_a_point_started_elsewhere_is_the_scene_the_loader_builds_and_runs_the_same(name, keys, factors):
    data = _data(name)
    parsed = tuple(parse_key(k, data) for k in keys)
    base = scene_from_dict(data)
    assert state_slots(parsed, data, base) is not None  # the fast path is taken
    make = point_scene_maker(data, parsed, "scene")
    values = _values(data, keys, factors)
    fast = make(values)
    loaded = scene_from_dict(point_data(data, parsed, values))
    assert fast == loaded
    assert (fast.q, fast.dq) != (base.q, base.dq)
    assert tuple(fast.pairs) == tuple(loaded.pairs)  # reachability included
    assert fast.total_energy() == loaded.total_energy()
    assert fast.constants is base.constants  # interned: the engine's caches find them by identity
    assert loaded.constants is base.constants
    a = heyroll.simulate(fast, t_end=3.0, max_collisions=20)
    b = heyroll.simulate(loaded, t_end=3.0, max_collisions=20)
    assert a.status is b.status and a.message == b.message
    assert float(a.t_final) == float(b.t_final)
    assert np.array_equal(np.asarray(a.final_state, float), np.asarray(b.final_state, float))
    assert np.array_equal(a.collision_table()["t"], b.collision_table()["t"])


def test_a_run_is_the_same_whatever_ran_before_it():
    """The engine's caches by constants: a scene run after its siblings gives what it gives alone (a
    fresh process is not needed: a sibling run first, the scene's own result must not change)."""
    base = default_scene()
    sibling = base.with_state(q=(base.q[0] - 0.2, base.q[1]))
    target = base.with_state(dq=(base.dq[0], base.dq[1] + 0.3))
    first = heyroll.simulate(target, t_end=5.0)
    heyroll.simulate(sibling, t_end=5.0)
    again = heyroll.simulate(pickle.loads(pickle.dumps(target)), t_end=5.0)
    assert np.array_equal(first.collision_table()["t"], again.collision_table()["t"])
    assert first.n_collisions == again.n_collisions > 3


def test_the_state_rules_still_hold():
    base = default_scene()
    beta = float(base.pairs[0].beta)
    with pytest.raises(SceneError) as overlap:
        base.with_state(q=(0.0, beta / 2))
    assert overlap.value.field == "bodies[2].phi" and "overlap" in str(overlap.value)
    with pytest.raises(SceneError) as nan:
        base.with_state(dq=(math.nan, 0.0))
    assert nan.value.field == "bodies[1].dphi"
    with pytest.raises(SceneError) as count:
        base.with_state(q=(0.0,))
    assert count.value.field == "bodies"
    with pytest.raises(SceneError) as smooth:  # a slip needs a rough track
        base.with_state(slip=(0.1, 0.0))
    assert smooth.value.field == "bodies[1].slip"
    with pytest.raises(SceneError) as huge:  # the energies must be finite doubles
        base.with_state(dq=(1e200, 0.0))
    assert huge.value.field == "bodies[1].dphi"
    arcs = load_scene(ROOT / "examples" / "arc_chain.toml")
    with pytest.raises(SceneError) as off:
        arcs.with_state(q=(-1e6,) + arcs.q[1:])
    assert off.value.field == "bodies[1].s" and "on the track" in str(off.value)


def test_scenes_of_one_shape_and_reach_share_one_system_and_more_energy_watches_more():
    base = default_scene()
    near = base.with_state(q=(base.q[0] + 0.01, base.q[1]))
    assert energy_reach(near) == energy_reach(base)
    assert build_system(near, DOUBLE) is build_system(base, DOUBLE)
    # Fast enough to reach the pair across the top and the upper half of the circle: more events.
    fast = base.with_state(dq=(base.dq[0], 30.0))
    assert all(fast_reach for fast_reach in energy_reach(fast).pairs)
    assert not all(energy_reach(base).pairs)
    system = build_system(fast, DOUBLE)
    assert system is not build_system(base, DOUBLE)
    assert len(system.contacts) == 2 and len(system.track_events) > len(build_system(base, DOUBLE).track_events)
    assert system.initial_state_of(fast)[3] == 30.0


@pytest.mark.parametrize("keys", [("collision.restitution",), ("bodies[1].mass",), ("bodies[1].phi", "g")])
def test_other_keys_build_every_point_with_the_loader(keys):
    data = _data(None)
    parsed = tuple(parse_key(k, data) for k in keys)
    assert state_slots(parsed, data, scene_from_dict(data)) is None


def test_a_rate_given_as_omega_or_a_body_given_by_segment_and_angle():
    data = _data(None)
    data["bodies"][0].pop("dphi", None)
    data["bodies"][0]["omega"] = 2.0  # the rolling angular velocity: varying dphi replaces it (as the loader does)
    parsed = (parse_key("bodies[1].dphi", data),)
    base = scene_from_dict(data)
    assert state_slots(parsed, data, base) is not None
    make = point_scene_maker(data, parsed, "scene")
    assert make((0.25,)) == scene_from_dict(point_data(data, parsed, (0.25,)))
    assert state_slots((parse_key("bodies[1].omega", data),), data, base) is None  # converted by the loader


def test_a_parametric_track_is_swept_by_its_own_coordinate_u():
    """Found writing these tests: the KEYs of a parametric track's bodies were checked against an arc
    chain's (s, ds), so bodies[N].u was refused, and the store named its state s."""
    from heyroll.sweep.plan import make_plan

    plan = make_plan(ROOT / "examples" / "rough_cycloid.toml", grid=[("vary", "bodies[2].du=0:0.2:3")])
    assert plan.coordinate == "u" and plan.units(plan.keys[0]) == "1/s"
    with pytest.raises(SweepKeyError) as wrong:
        make_plan(ROOT / "examples" / "rough_cycloid.toml", grid=[("vary", "bodies[2].ds=0:0.2:3")])
    assert "du" in str(wrong.value) and "u" in str(wrong.value)
