"""The inlined two-body collision callback (events._two_body_callback) gives, bit for bit, what the general
callback gives: same collision table, statuses and final states, on every path it takes (the law, Newton's
fallback, on_inconsistent = error, max_collisions, persistent contact at k < 1, the gap rising through zero)."""

from __future__ import annotations

import numpy as np
import pytest

import heyroll
from heyroll.simulation import events
from heyroll.simulation.driver import forget_handlers

from test_hard_cases import scene, unequal_balls
from conftest import body


def runs(sc, **options):
    """(the run with the inlined callback, the run with the general one); each builds its own handlers (they
    are cached between runs, driver._handlers) and the test sees that each factory was used."""
    original = events._two_body_callback
    built = {"fast": 0, "general": 0}

    def counted(kind, make):
        def factory(c):
            built[kind] += 1
            return make(c)
        return factory

    try:
        forget_handlers()
        events._two_body_callback = counted("fast", original)
        fast = heyroll.simulate(sc, **options)
        forget_handlers()
        events._two_body_callback = counted("general", lambda c: c["on_any_collision"])
        general = heyroll.simulate(sc, **options)
    finally:
        events._two_body_callback = original
        forget_handlers()
    assert built["fast"] > 0 and built["general"] > 0
    return fast, general


CASES = {
    "default elastic": (heyroll.default_scene(), {"t_end": 3000.0}),
    "fallback (Hedrih, unequal)": (unequal_balls(), {}),
    "on_inconsistent error": (unequal_balls(policy="error"), {}),
    "max_collisions": (heyroll.default_scene(), {"max_collisions": 17}),
    "k = 0.5 into contact": (scene([body(radius="0.1", phi="-0.6"), body(shape="disk", radius="0.2", mass="3.0",
                                                                        phi="0.4", dphi="-0.2")], k="0.5",
                                   t_end="60"), {}),
    "plastic": (scene([body(radius="0.1", phi="-0.6", dphi="1.0"), body(radius="0.1", phi="0.5")], k="0",
                      t_end="30"), {}),
}


@pytest.mark.parametrize("name", list(CASES))
def test_the_inlined_callback_is_the_general_one_bit_for_bit(name):
    sc, options = CASES[name]
    fast, general = runs(sc, **options)
    assert fast.status is general.status and fast.message == general.message
    assert fast.n_collisions == general.n_collisions > 0
    assert np.array_equal(fast.times, general.times)
    assert np.array_equal(fast.states_after, general.states_after)
    assert np.array_equal(fast.law_flags, general.law_flags)
    assert np.array_equal(fast.final_state, general.final_state)
    assert [m.t for m in fast.mode_changes] == [m.t for m in general.mode_changes]


def _same(a, b):
    return (a.status is b.status and a.message == b.message and np.array_equal(a.times, b.times)
            and np.array_equal(a.states_after, b.states_after) and np.array_equal(a.final_state, b.final_state)
            and a.settings == b.settings)


def test_handlers_cached_between_runs_change_no_result():
    """A mode's handlers are built once per log, system and scene constants (driver._handlers) and serve the
    next runs: whatever ran before, with whatever limits, a run gives what a fresh one gives."""
    sc = heyroll.default_scene()
    inelastic = scene([body(radius="0.1", phi="-0.6"), body(shape="disk", radius="0.2", mass="3.0", phi="0.4",
                                                            dphi="-0.2")], k="0.5", t_end="60")
    plan = [(sc, {"max_collisions": 5}), (sc, {"t_end": 300.0}), (inelastic, {}), (sc, {"max_collisions": 40}),
            (sc, {"max_events": 7}), (inelastic, {"max_collisions": 3}), (sc, {"t_end": 300.0})]
    fresh = []
    for s, options in plan:
        forget_handlers()
        fresh.append(heyroll.simulate(s, **options))
    forget_handlers()
    again = [heyroll.simulate(s, **options) for s, options in plan]
    for (s, options), a, b in zip(plan, fresh, again):
        assert _same(a, b), (s.name, options)


def test_a_run_inside_a_run_takes_its_own_log():
    """A progress callback that runs another scene (the engine's logs are per run, not shared)."""
    sc = heyroll.default_scene()
    alone = heyroll.simulate(sc, t_end=2000.0)
    inner = []

    def progress(t, collisions):
        inner.append(heyroll.simulate(sc, t_end=50.0).n_collisions)

    outer = heyroll.simulate(sc, t_end=2000.0, progress=progress)
    assert inner and _same(outer, alone)
    assert set(inner) == {heyroll.simulate(sc, t_end=50.0).n_collisions}


def test_the_cyclic_collector_is_paused_during_a_run_and_restored_after():
    """A run pauses Python's cyclic garbage collector (its passes over the growing records cost a tenth of a
    long run: validation/speed.py) and leaves it as it found it, on or off, also when the run raises."""
    import gc

    import heyroll

    seen = []
    scene = heyroll.default_scene()
    for enabled in (True, False):
        (gc.enable if enabled else gc.disable)()
        try:
            heyroll.simulate(scene, t_end=2.0, progress=lambda t, n: seen.append(gc.isenabled()))
            assert gc.isenabled() is enabled and seen and not any(seen)
            try:
                heyroll.simulate(scene, t_end=2.0, progress=lambda t, n: 1 / 0)
            except ZeroDivisionError:
                pass
            assert gc.isenabled() is enabled
        finally:
            gc.enable()
