"""collision.simultaneous = "impulses" on the circle: contacts touching at one instant resolved at once.

Every law on the circle is a linear pair map (events.WorkingMap); the contacts that touch at the
fired one's instant and share a unit with it (a chain) get impulses P >= 0 from one linear
complementarity problem (resolve.complementarity, the table's solver), Newton's restitution on each
contact's D = phi_i' - q phi_j' (one contact alone: exactly the law). Rows: one per contact with an
impulse, law_flag 2, the first carrying the whole change (events.simultaneous_resolver).
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest

import heyroll
from heyroll import SceneError, Status, parse_scene
from heyroll.model._numbers import workprec
from test_hard_cases import GAP_FLOOR
from test_many_bodies import MIRROR_TOLERANCE, generalized_masses, instants, recorded_gaps, touching_row

TRACK = heyroll.CircleTrack.of_radius(1)
BALL = heyroll.Body.of_shape("solid_sphere", "0.1", mass="1")


def scene(bodies, phi, dphi, *, k="0.5", t_end="0.8", simultaneous="impulses", max_collisions=None):
    return heyroll.Scene.make(TRACK, bodies, phi=phi, dphi=dphi, law=heyroll.make_law("hedrih", k),
                              run=heyroll.RunSettings.make(t_end, max_collisions), simultaneous=simultaneous)


def three_balls(k, simultaneous="impulses", **kw):
    """The review's case: the outer two balls reach the middle one at the same instant."""
    return scene([BALL] * 3, ["-0.6", "0", "0.6"], [0] * 3, k=k, simultaneous=simultaneous, **kw)


@pytest.mark.parametrize("k", ["0.5", "0", "1"])
def test_three_equal_balls_struck_from_both_sides_leave_the_middle_at_rest(k):
    sc = three_balls(k)
    result = heyroll.simulate(sc)
    assert result.status is Status.COMPLETED, result.message
    table = result.collision_table()
    first = instants(table["t"])[0]
    rows = table[first]
    assert len(rows) == 2 and np.all(rows["law_flag"] == 2)
    assert rows["i"].tolist() == [1, 2] and rows["j"].tolist() == [2, 3]
    before = np.asarray(result.states_before[first.start], dtype=float)
    after = np.asarray(result.states_after[first.start], dtype=float)
    # later rows of the instant: before = after = the state after the group
    assert np.array_equal(np.asarray(result.states_before[first.start + 1], dtype=float), after)
    assert np.array_equal(np.asarray(result.states_after[first.start + 1], dtype=float), after)
    v = before[3]
    assert v > 1 and before[5] == pytest.approx(-v, abs=1e-13)
    assert abs(after[4]) <= 1e-13  # the middle ball stays at rest
    assert abs(after[3] + after[5]) <= 1e-13  # the outer rates mirror each other
    assert after[3] == pytest.approx(-float(k) * v, abs=1e-13)
    G = generalized_masses(sc)
    assert abs(G @ after[3:] - G @ before[3:]) <= 1e-13 * (G @ np.abs(before[3:]))  # sum J_P omega_P kept
    if k == "1":
        assert rows["energy_after"][0] == pytest.approx(rows["energy_before"][0], rel=1e-14)
        assert G @ after[3:] ** 2 == pytest.approx(G @ before[3:] ** 2, rel=1e-14)
    assert recorded_gaps(result).min() >= GAP_FLOOR


def test_sequential_is_the_default_and_unchanged():
    plain = heyroll.Scene.make(TRACK, [BALL] * 3, phi=["-0.6", "0", "0.6"], dphi=[0] * 3,
                               law=heyroll.make_law("hedrih", "0.5"), run=heyroll.RunSettings.make("0.8"))
    assert plain.simultaneous == "sequential"
    explicit = three_balls("0.5", simultaneous="sequential")
    assert explicit == plain and explicit.constants is plain.constants
    a, b = heyroll.simulate(plain), heyroll.simulate(explicit)
    for x, y in ((a.times, b.times), (a.states_before, b.states_before), (a.states_after, b.states_after),
                 (a.law_flags, b.law_flags)):
        assert np.array_equal(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
    # pair by pair: the middle ball drifts (the review's finding), law_flag 0
    first = np.asarray(a.states_after[2], dtype=float)
    assert abs(first[4]) > 1e-2 and a.law_flags[0] == 0
    impulses = three_balls("0.5")
    assert impulses != plain and impulses.constants != plain.constants  # caches keyed by constants see it


def test_the_limit_counts_the_group_rows():
    """Review: a limit reached inside a group stopped after its first row, the state already holding the whole
    group (body 3's new rate in no row). A group is one resolution: recorded whole, then the run stops."""
    result = heyroll.simulate(three_balls("0.5", max_collisions=1))
    assert result.status is Status.MAX_COLLISIONS and "recorded whole" in result.message
    assert result.total_collisions == 2 and len(result.times) == 2
    table = result.collision_table()
    assert list(result.final_state[3:]) == pytest.approx(list(result.states_after[-1][3:]), abs=1e-12)
    assert table["omega_j_after"][-1] == pytest.approx(-table["omega_i_after"][0], rel=1e-13)


CIRCLE_TEXT = ('[track]\ntype = "circle"\nradius = 1.0\n'
               '[[bodies]]\nshape = "solid_sphere"\nradius = 0.1\nmass = 1.0\nphi = -0.6\n'
               '[[bodies]]\nshape = "solid_sphere"\nradius = 0.1\nmass = 1.0\nphi = 0.0\n'
               '[[bodies]]\nshape = "solid_sphere"\nradius = 0.1\nmass = 1.0\nphi = 0.6\n'
               '[collision]\nlaw = "hedrih"\nrestitution = 0.5\n{line}')


def test_the_scene_file_key():
    assert parse_scene(CIRCLE_TEXT.format(line='simultaneous = "impulses"\n')) == three_balls("0.5", t_end="100")
    assert parse_scene(CIRCLE_TEXT.format(line="")).simultaneous == "sequential"


@pytest.mark.parametrize("value", ['"lcp"', "1"])
def test_a_bad_value_is_refused_in_one_line(value):
    with pytest.raises(SceneError) as info:
        parse_scene(CIRCLE_TEXT.format(line=f"simultaneous = {value}\n"))
    assert info.value.field == "collision.simultaneous"
    assert "\n" not in str(info.value) and "sequential" in str(info.value)


def test_a_path_track_refuses_impulses():
    text = ('[track]\ntype = "curve"\ny = "0.5*x**2"\nx_min = -1.5\nx_max = 1.5\n'
            '[[bodies]]\nshape = "disk"\nradius = 0.05\nmass = 1.0\nx = -0.5\n'
            '[[bodies]]\nshape = "disk"\nradius = 0.05\nmass = 1.0\nx = 0.5\n'
            '[collision]\nsimultaneous = "impulses"\n')
    with pytest.raises(SceneError) as info:
        parse_scene(text)
    assert info.value.field == "collision.simultaneous"
    assert "\n" not in str(info.value) and "circle" in str(info.value)
    assert parse_scene(text.replace("impulses", "sequential")).simultaneous == "sequential"


def test_two_strikers_on_a_pressed_row_give_the_mirror_outcome():
    """Three balls touching at rest at the bottom (pressed: one cluster), struck at once from both sides
    by two equal balls at k = 1: the row stays at rest and the strikers bounce back, mirror images."""
    row = touching_row(3, mpmath.mpf(0))
    sc = scene([BALL] * 5, [mpmath.mpf(-1)] + row + [mpmath.mpf(1)], [0] * 5, k="1", t_end="0.6")
    result = heyroll.simulate(sc)
    assert result.status is Status.COMPLETED, result.message
    assert result.mode_changes[0].clusters == ((2, 3, 4),)
    table = result.collision_table()
    rows = table[instants(table["t"])[0]]
    assert len(rows) == 2 and np.all(rows["law_flag"] == 2)
    before = np.asarray(result.states_before[0], dtype=float)
    after = np.asarray(result.states_after[0], dtype=float)
    v = before[5]
    assert v > 1 and before[9] == pytest.approx(-v, rel=1e-13)
    assert np.abs(after[6:9]).max() <= 1e-13  # the row at rest
    assert after[5] == pytest.approx(-v, rel=1e-13) and abs(after[5] + after[9]) <= 1e-13
    G = generalized_masses(sc)
    assert abs(G @ after[5:] - G @ before[5:]) <= 1e-13 * (G @ np.abs(before[5:]))
    assert G @ after[5:] ** 2 == pytest.approx(G @ before[5:] ** 2, rel=1e-14)
    assert recorded_gaps(result).min() >= GAP_FLOOR


def mirror_unequal(n, simultaneous="impulses"):
    """n balls at rest 0.4 rad apart about the bottom, radii 0.1 and 0.13 in a mirror-symmetric pattern."""
    radii = [mpmath.mpf("0.13") if min(k, n - 1 - k) % 2 else mpmath.mpf("0.1") for k in range(n)]
    bodies = [heyroll.Body.of_shape("solid_sphere", r, mass="1") for r in radii]
    with workprec():
        phi = [mpmath.mpf("0.4") * (k - mpmath.mpf(n - 1) / 2) for k in range(n)]
    return scene(bodies, phi, [0] * n, k="0.5", t_end="3", simultaneous=simultaneous)


@pytest.mark.parametrize("n", [4, 5, 6, 7, 8])
def test_mirror_symmetric_unequal_starts_stay_mirror_symmetric(n):
    # Odd n: the middle ball is struck from both sides at once (pair by pair it drifts: next test).
    sc = mirror_unequal(n)
    result = heyroll.simulate(sc)
    assert result.status is Status.COMPLETED, result.message
    table = result.collision_table()
    assert len(table) > 0
    assert result.energy_final <= result.energy_initial * (1 + 1e-12)
    assert recorded_gaps(result).min() >= GAP_FLOOR
    final = np.asarray(result.final_state, dtype=float)
    assert np.abs(final[:n] + final[n - 1::-1]).max() <= MIRROR_TOLERANCE
    assert np.abs(final[n:] + final[:n - 1:-1]).max() <= MIRROR_TOLERANCE
    after = np.asarray(result.states_after, dtype=float)[[s.stop - 1 for s in instants(table["t"])]]
    assert np.abs(after[:, :n] + after[:, n - 1::-1]).max() <= MIRROR_TOLERANCE
    assert np.abs(after[:, n:] + after[:, :n - 1:-1]).max() <= MIRROR_TOLERANCE


def test_pair_by_pair_the_odd_mirror_start_loses_its_symmetry():
    result = heyroll.simulate(mirror_unequal(5, "sequential"))
    final = np.asarray(result.final_state, dtype=float)
    assert np.abs(final[5:] + final[:4:-1]).max() > 1e-3  # (measured: 0.05 rad/s at t = 3 s)


def test_a_collision_with_no_other_contact_touching_is_the_law_alone_bit_for_bit():
    kw = dict(k="0.7", t_end="2")
    phi, dphi = ["-0.5", "0.1", "2.5"], ["2", "0", "0"]
    a = heyroll.simulate(scene([BALL] * 3, phi, dphi, simultaneous="sequential", **kw))
    b = heyroll.simulate(scene([BALL] * 3, phi, dphi, **kw))
    assert len(a.times) > 3 and 2 not in list(a.law_flags)
    for x, y in ((a.times, b.times), (a.states_before, b.states_before), (a.states_after, b.states_after),
                 (a.law_flags, b.law_flags), (a.final_state, b.final_state)):
        assert np.array_equal(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
