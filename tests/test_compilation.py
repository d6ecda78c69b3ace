"""How modes are compiled (issue 12): compact mode for many bodies, and modes after the first
compiled quickly and handed over to the optimized integrator once they last (driver.QUICK_STEPS).

The hand-over must not change the run beyond round-off: the same modes, the same collisions,
the same final state to ~1e-12, on the circle and on path tracks (whose parameters the
junction and limiter callbacks change during a mode).
"""

from __future__ import annotations

import numpy as np
import pytest

import heyroll
from heyroll.model.bodies import Body
from heyroll.model.scene import RunSettings, Scene
from heyroll.model.tracks import CircleTrack, CurveTrack
from heyroll.simulation import driver
from heyroll.simulation.compiled_cache import CompiledCache
from heyroll.simulation.precision import Precision
from heyroll.simulation.system import build_system

DISK = Body.of_shape("disk", "0.05", mass="1")


def circle_cluster():
    a = Body.of_shape("solid_sphere", "0.1", mass="1")
    b = Body.of_shape("disk", "0.15", mass="2")
    return Scene.make(CircleTrack.of_radius(1), [a, b], phi=["-0.9", "0.5"], dphi=[0, 0],
                      law=heyroll.make_law("hedrih", "0.4"), run=RunSettings.make(15))


def parabola_cluster():
    return Scene.make(CurveTrack.make("0.5*x**2", "-1.5", "1.5"), [DISK] * 3, ["-0.8", "0.0", "0.6"], [0, 0, 0],
                      law=heyroll.make_law("newton", "0.3"), run=RunSettings.make(20))


def pile_on_a_limiter():
    return Scene.make(CurveTrack.make("0.5*x**2", "0.2", "1.5"), [DISK] * 2, ["0.5", "1.2"], [0, 0],
                      limiter_restitution="0.5", law=heyroll.make_law("newton", "0.5"), run=RunSettings.make(20))


def run_with(monkeypatch, scene, quick_steps):
    monkeypatch.setattr(driver, "QUICK_STEPS", quick_steps)
    monkeypatch.setattr(driver, "_INTEGRATORS", CompiledCache(32))  # nothing compiled before
    return heyroll.simulate(scene)


@pytest.mark.parametrize("make", [circle_cluster, parabola_cluster, pile_on_a_limiter])
def test_the_hand_over_to_the_optimized_integrator_keeps_the_run(monkeypatch, make):
    scene = make()
    early = run_with(monkeypatch, scene, 32)  # every later mode handed over after 32 steps
    never = run_with(monkeypatch, scene, 1 << 40)  # later modes stay quickly compiled
    for r in (early, never):
        assert r.status.value == "completed", r.message
        assert len(r.mode_changes) > 1  # a later mode ran
    assert [m.clusters for m in early.mode_changes] == [m.clusters for m in never.mode_changes]
    assert [m.pinned for m in early.mode_changes] == [m.pinned for m in never.mode_changes]
    assert early.n_collisions == never.n_collisions
    assert np.allclose(np.asarray(early.times, float), np.asarray(never.times, float), rtol=0, atol=1e-9)
    assert np.allclose(np.asarray(early.final_state, float), np.asarray(never.final_state, float), rtol=0, atol=1e-10)


def test_a_lasting_later_mode_is_handed_over_and_its_optimized_integrator_reused(monkeypatch):
    scene = circle_cluster()
    result = run_with(monkeypatch, scene, 32)
    assert result.mode_changes[-1].clusters == ((1, 2),)
    keys = list(driver._INTEGRATORS._entries)
    quick = {k[0] for k in keys if k[-1]}
    optimized = {k[0] for k in keys if not k[-1]}
    assert quick and quick <= optimized  # the cluster's mode compiled quickly, then optimized
    heyroll.simulate(scene)  # the next run finds the optimized one: nothing compiled again
    assert set(driver._INTEGRATORS._entries) == set(keys)


@pytest.mark.parametrize("n, compact", [(4, False), (driver.COMPACT_FROM_BODIES, True)])
def test_many_bodies_compile_in_compact_mode(n, compact):
    bodies = [Body.of_shape("solid_sphere", "0.02", mass="1")] * n
    phi = [str(-1.5 + 3.0 * k / n) for k in range(n)]
    scene = Scene.make(CircleTrack.of_radius(1), bodies, phi=phi, dphi=[0] * n, run=RunSettings.make(1))
    assert driver._compact(build_system(scene, Precision.parse("double"))) is compact
