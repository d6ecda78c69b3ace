"""The inlined two-body collision callback (events._two_body_callback) gives, bit for bit, what the general
callback gives: same collision table, statuses and final states, on every path it takes (the law, Newton's
fallback, on_inconsistent = error, max_collisions, persistent contact at k < 1, the gap rising through zero)."""

from __future__ import annotations

import numpy as np
import pytest

import heyroll
from heyroll.simulation import events

from test_hard_cases import scene, unequal_balls
from conftest import body


def runs(sc, **options):
    fast = heyroll.simulate(sc, **options)
    original = events._two_body_callback
    events._two_body_callback = lambda c: c["on_any_collision"]
    try:
        general = heyroll.simulate(sc, **options)
    finally:
        events._two_body_callback = original
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
