"""The hard cases of README "Hard cases: what heyroll does", one test (or more) each.

Zeno accumulation and persistent contact, law outcomes that keep the bodies
approaching (the rolling law with unequal radii), contacts that split, three
bodies meeting at one instant, grazing contacts, bodies that start touching,
the separatrix, the wrap-around pair, leaving the track, slipping,
determinism of the CLI and Ctrl-C.

Gaps are checked on dense samples of every branch between events
(``sample_branches``): gap of pair p = phi_j + offset - phi_i - beta >= -1e-12.
"""

from __future__ import annotations

import json
import math
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import mpmath
import numpy as np
import pytest

import heyroll
from heyroll import Status, parse_scene
from heyroll.interfaces.cli import main as cli_main
from heyroll.simulation.trajectory import sample_branches

GAP_FLOOR = -1e-12


# -- scenes -------------------------------------------------------------------


def body(shape="solid_sphere", radius="0.1", mass="1.0", phi="0.0", dphi="0.0", density=None) -> str:
    lines = ["[[bodies]]", f'shape = "{shape}"']
    if radius is not None:
        lines.append(f"radius = {radius}")
    lines.append(f"density = {density}" if density is not None else f"mass = {mass}")
    lines += [f"phi = {phi}", f"dphi = {dphi}"]
    return "\n".join(lines) + "\n"


def scene_toml(bodies, *, law="hedrih", k="1.0", t_end="10", radius="1.0", track="", collision="") -> str:
    return (
        f'g = 9.81\n[track]\ntype = "circle"\nradius = {radius}\n{track}\n'
        + "".join(bodies)
        + f'[collision]\nlaw = "{law}"\nrestitution = {k}\n{collision}\n[run]\nt_end = {t_end}\n'
    )


def scene(bodies, **kw):
    return parse_scene(scene_toml(bodies, **kw))


def contact_angle(body_i: str, body_j: str):
    """beta of two bodies (mpf), from a scene that holds them far apart."""
    far = scene([body_i.replace("phi = 0.0", "phi = -1.5"), body_j.replace("phi = 0.0", "phi = 1.5")])
    return far.pairs[0].beta


def touching(phi, beta) -> str:
    """Decimal text of phi + beta, 1e-22 rad on the safe side (touching, not overlapping)."""
    with mpmath.workprec(256):
        return mpmath.nstr(mpmath.mpf(phi) + beta + mpmath.mpf(10) ** -22, 25, strip_zeros=False)


def stiffness(sc, n: int) -> float:
    return float(sc.track.angular_stiffness(sc.bodies[n], sc.g))


def generalized_masses(sc) -> np.ndarray:
    return np.array([float(sc.track.generalized_mass(b)) for b in sc.bodies])


# -- gaps along the run --------------------------------------------------------


def branches(result, points=200):
    """The run sampled between its collisions and mode changes (full states)."""
    return sample_branches(result, points=points)


def pair_gaps(sc, states) -> np.ndarray:
    states = np.atleast_2d(states)
    return np.array([states[:, p.j] + float(p.offset) - states[:, p.i] - float(p.beta) for p in sc.pairs]).T


def min_gap(result, points=200, sampler=branches) -> float:
    if not result.scene.pairs:
        return math.inf
    return min(float(pair_gaps(result.scene, b.states).min()) for b in sampler(result, points=points))


# -- (a) Zeno: accumulation of collisions, then persistent contact ------------------


ZENO = scene_toml(
    [body(mass="1.0", phi="-0.9"), body(mass="2.0", phi="0.7")], k="0.5", t_end="20",
)


def test_zeno_prototype_accumulates_into_contact_in_bounded_time():
    sc = parse_scene(ZENO)
    result = heyroll.simulate(sc)
    assert result.status is Status.COMPLETED and float(result.t_final) == 20.0
    assert result.wall_time_s < 10 and result.n_collisions < 200
    (contact,) = result.contact_intervals
    assert (contact["i"], contact["j"]) == (1, 2) and contact.get("open") and contact["t_end"] == 20.0
    t_start = contact["t_start"]
    assert t_start == pytest.approx(3.3578, abs=1e-4)
    table = result.collision_table()
    assert np.all(table["t"] <= t_start) and np.all(table["law_flag"] == 0)

    # The accumulation point: the geometric series summed from each of the last
    # collisions, t_n + 2 v_n+ / (A_n (1 - k)), v_n+ the opening gap rate after
    # it and A_n the closing gap acceleration there.
    k = 0.5
    a1, a2 = stiffness(sc, 0), stiffness(sc, 1)
    last = table[-6:]
    v = last["dq_j_after"] - last["dq_i_after"]
    A = a2 * np.sin(last["q_j"]) - a1 * np.sin(last["q_i"])
    assert np.all(v > 0) and np.all(A > 0)
    predicted = last["t"] + 2 * v / (A * (1 - k))
    assert np.ptp(predicted) < 1e-9  # every collision predicts the same accumulation point
    # Contact starts at the last bounce higher than BOUNCE_ULPS (1024 ulps, ~2e-13 rad here: heyoka's
    # root finding gave out on ~100-ulp bounces): what the series has left is a bounce lower than that,
    # and a few microseconds.
    remaining = 2 * v[-1] / (A[-1] * (1 - k))
    assert remaining < 1e-5 and v[-1] ** 2 / (2 * A[-1]) < 1024 * 2.0**-52 * 2
    assert t_start == pytest.approx(float(predicted.mean()), abs=1.01 * remaining)

    assert min_gap(result, points=100) >= GAP_FLOOR
    final = result.final_state
    assert abs(pair_gaps(sc, final)[0, 0]) < 1e-14 and final[2] == final[3]
    assert result.energy_final < result.energy_initial


# -- (b) law outcomes that keep the bodies approaching -----------------------------


def unequal_balls(k="0.8", policy="newton", t_end="100"):
    return scene(
        [body(radius="0.10", density="7850", phi="-0.5"), body(radius="0.15", density="7850", phi="0.8")],
        k=k, t_end=t_end, collision=f'on_inconsistent = "{policy}"',
    )


@pytest.fixture(scope="module")
def unequal_run():
    return heyroll.simulate(unequal_balls())


def test_inconsistent_prototype_default_policy_flags_and_never_overlaps(unequal_run):
    result = unequal_run
    table = result.collision_table()
    assert result.status is Status.COMPLETED
    flags = table["law_flag"]
    flagged = flags[:88] == 1
    # Measured: the run reaches persistent contact at t = 9.585 s after 68
    # collisions, 52 of them flagged (the first is collision 8).
    (contact,) = result.contact_intervals  # the k < 1 sequence ends in persistent contact
    assert contact["t_start"] == pytest.approx(9.585, abs=1e-2) and flags.size == result.n_collisions < 88
    assert int(np.argmax(flagged)) + 1 == 8
    assert 0 < int(flagged.sum()) <= flagged.size
    assert int((flags == 1).sum()) == result.settings["inconsistent_collisions"]
    assert f"{result.settings['inconsistent_collisions']} collisions left the bodies approaching" in result.message
    rows = table[flags == 1]
    assert np.all(rows["dq_i_after"] < rows["dq_j_after"])  # the fallback separates them
    # ... and the rolling law itself would not have: its outcome still closes the gap.
    law = result.scene.pairs[0].law_map
    q, ai, aj = float(law.q), float(law.a_i), float(law.a_j)
    d = rows["dq_i_before"] - q * rows["dq_j_before"]
    assert np.all((rows["dq_i_before"] - ai * d) > (rows["dq_j_before"] + aj * d))
    assert np.all(np.diff(table["energy_after"]) <= 1e-12 * result.energy_initial)
    assert min_gap(result, points=100) >= GAP_FLOOR


def test_inconsistent_prototype_error_policy_stops_at_the_first_flagged_collision(unequal_run):
    stopped = heyroll.simulate(unequal_balls(policy="error"))
    first = int(np.argmax(unequal_run.collision_table()["law_flag"] == 1)) + 1
    assert stopped.status is Status.INCONSISTENT and not stopped.success
    assert stopped.n_collisions == first == 8
    assert "collision 8 at t = " in stopped.message and "bodies 1 and 2 still approach" in stopped.message
    t = float(re.search(r"at t = ([0-9.eE+-]+):", stopped.message).group(1))
    assert t == float(stopped.times[-1]) == float(unequal_run.times[first - 1])
    assert stopped.settings["inconsistent_collisions"] == 1  # the one that stopped it (was 0: acceptance test)


def test_inconsistent_prototype_elastic_has_no_flagged_collision():
    result = heyroll.simulate(unequal_balls(k="1.0", t_end="100000"), max_collisions=1000)
    assert result.status is Status.MAX_COLLISIONS and result.n_collisions == 1000
    assert result.settings["inconsistent_collisions"] == 0
    assert not np.any(result.collision_table()["law_flag"])


# -- equal radii: the rolling law is always consistent -----------------------------


@pytest.mark.parametrize("seed", range(5))
def test_equal_radii_rolling_law_outcome_is_always_consistent(seed):
    rng = np.random.default_rng(seed)
    n = 2 + seed % 2
    r = float(rng.uniform(0.05, 0.25))
    shapes = rng.choice(["solid_sphere", "hollow_sphere", "disk", "ring"], n)
    sc0 = scene([body(radius=repr(r), phi="-1.5"), body(radius=repr(r), phi="1.5")])
    beta = float(sc0.pairs[0].beta)
    phis = np.cumsum(np.r_[rng.uniform(-1.6, -1.2), beta + rng.uniform(0.01, 0.5, n - 1)])
    bodies = [
        body(shape=str(s), radius=repr(r), mass=repr(float(rng.uniform(0.2, 5.0))), phi=repr(float(p)),
             dphi=repr(float(rng.uniform(-2, 2))))
        for s, p in zip(shapes, phis)
    ]
    k = float(rng.uniform(0.0, 1.0))
    result = heyroll.simulate(scene(bodies, k=repr(k), t_end="10"), max_collisions=300)
    assert result.success
    assert result.n_collisions > 0
    assert result.settings["inconsistent_collisions"] == 0
    assert not np.any(result.collision_table()["law_flag"] == 1)


# -- contacts that split ------------------------------------------------------------


def test_pair_in_contact_rolling_past_90_degrees_splits_and_collides_again():
    beta = contact_angle(body(), body())
    sc = scene(
        [body(phi="-0.2", dphi="5.0"), body(mass="2.0", phi=touching("-0.2", beta), dphi="5.0")], k="0.9", t_end="5",
    )
    result = heyroll.simulate(sc)
    assert result.status is Status.COMPLETED
    (contact,) = result.contact_intervals
    assert contact["t_start"] == 0.0 and not contact.get("open")
    t_split = contact["t_end"]
    assert 0 < t_split < float(result.t_final)
    # Equal stiffness: the contact force ~ sin(phi_2) - sin(phi_1) changes sign
    # when the pair's midpoint passes 90 degrees.
    change = result.mode_changes[1]
    assert change.t == t_split and change.clusters == ()
    assert (change.state[0] + change.state[1]) / 2 == pytest.approx(math.pi / 2, abs=1e-12)
    table = result.collision_table()
    again = table[(table["i"] == 1) & (table["j"] == 2)]
    assert again.size and again["t"][0] > t_split
    assert min_gap(result) >= GAP_FLOOR


def test_cluster_pushed_past_90_degrees_by_a_third_body_splits_and_collides_again():
    beta = contact_angle(body(), body())
    sc = scene(
        [body(phi="-1.4", dphi="6.0"), body(phi="0.05"), body(phi=touching("0.05", beta))], k="0.9", t_end="2",
    )
    result = heyroll.simulate(sc)
    assert result.status is Status.COMPLETED
    table = result.collision_table()
    assert table["law_flag"][0] == 2 and (table["i"][0], table["j"][0]) == (1, 2)  # a free body hits the cluster
    contact = result.contact_intervals[0]
    assert (contact["i"], contact["j"], contact["t_start"]) == (2, 3, 0.0) and not contact.get("open")
    later = table[(table["i"] == 2) & (table["j"] == 3)]
    assert later.size and later["t"][0] > contact["t_end"] and later["law_flag"][0] == 0
    assert min_gap(result) >= GAP_FLOOR


def test_zeno_of_three_bodies_ends_in_one_cluster():
    sc = scene([body(phi="-1.0"), body(mass="2.0", phi="0.0"), body(mass="0.5", phi="0.9")], k="0.5", t_end="10")
    result = heyroll.simulate(sc)
    assert result.status is Status.COMPLETED and result.n_collisions < 200
    assert result.mode_changes[-1].clusters == ((1, 2, 3),)
    assert 2 in set(result.collision_table()["law_flag"].tolist())  # free body against a cluster
    assert min_gap(result) >= GAP_FLOOR
    final = result.final_state
    assert np.all(np.abs(pair_gaps(sc, final)[0, :2]) < 1e-13) and len(set(final[3:].tolist())) == 1


# -- three bodies at one instant -------------------------------------------------------


def same_instant_groups(table):
    """Row index ranges of collisions that share one t (length >= 2)."""
    t = table["t"]
    groups, start = [], 0
    for n in range(1, t.size + 1):
        if n == t.size or t[n] != t[start]:
            if n - start >= 2:
                groups.append((start, n))
            start = n
    return groups


@pytest.mark.parametrize(
    "masses, k",
    [(("1.0", "1.0", "1.0"), "1.0"), (("1.0", "3.0", "0.5"), "1.0"), (("2.0", "1.0", "2.0"), "1.0"), (("1.0", "3.0", "0.5"), "0.7")],
    ids=["symmetric", "asymmetric", "heavy-outer", "asymmetric-inelastic"],
)
def test_three_bodies_colliding_at_the_same_instant(masses, k):
    sc = scene([body(mass=masses[0], phi="-1.0"), body(mass=masses[1], phi="0.0"), body(mass=masses[2], phi="1.0")], k=k, t_end="3")
    result = heyroll.simulate(sc)
    assert result.status is Status.COMPLETED
    table = result.collision_table()
    groups = same_instant_groups(table)
    assert groups and groups[0][0] == 0  # bodies 1 and 3 reach body 2 together
    assert {(1, 2), (2, 3)} <= set(zip(table["i"][: groups[0][1]].tolist(), table["j"][: groups[0][1]].tolist()))
    G = generalized_masses(sc)
    for a, b in groups:
        before, after = result.states_before[a], result.states_after[b - 1]
        assert np.array_equal(before[:3], after[:3])
        # Equal radii: the rolling law keeps sum kappa m rho^2 phi' (and sum J_P omega_P).
        assert G @ after[3:] == pytest.approx(G @ before[3:], abs=1e-13 * (G @ np.abs(before[3:])))
        if k == "1.0":
            assert table["energy_after"][b - 1] == pytest.approx(table["energy_before"][a], rel=1e-13)
        else:
            assert table["energy_after"][b - 1] < table["energy_before"][a]
        assert np.all(pair_gaps(sc, after)[0, :2] >= -1e-13)
        # after the group no touching pair closes
        touching_pairs = np.abs(pair_gaps(sc, after)[0, :2]) < 1e-12
        closing = np.array([after[3] - after[4], after[4] - after[5]]) > 0
        assert not np.any(touching_pairs & closing)
    if masses == ("1.0", "1.0", "1.0"):
        a, b = groups[0]
        out = result.states_after[b - 1][3:]
        assert out[1] == pytest.approx(0, abs=1e-13) and out[0] == pytest.approx(-out[2], rel=1e-13)
        # the mirror symmetry phi_1 = -phi_3, phi_2 = 0 holds for the whole run
        final = result.final_state
        assert final[0] == pytest.approx(-final[2], abs=1e-12) and abs(final[1]) < 1e-12
    assert min_gap(result) >= GAP_FLOOR


# -- grazing -------------------------------------------------------------------------


def grazing_scene(gap_min: float, t_touch=0.3):
    """Two bodies whose gap has a local minimum ``gap_min`` (free motion) at t = t_touch.

    At t_touch both are at rest at phi_1 = 1.0, phi_2 = 1.0 + beta + gap_min
    (a solid sphere and a ring: the gap's acceleration there is +1.43 rad/s^2);
    the state at t = 0 comes from integrating the free motion backwards.
    """
    import heyoka as hy

    b1, b2 = body(), body(shape="ring", mass="2.0")
    sc0 = scene([b1.replace("phi = 0.0", "phi = -1.5"), b2.replace("phi = 0.0", "phi = 1.5")])
    a1, a2, beta = stiffness(sc0, 0), stiffness(sc0, 1), float(sc0.pairs[0].beta)
    x1, x2, v1, v2 = hy.make_vars("x1", "x2", "v1", "v2")
    ta = hy.taylor_adaptive(
        [(x1, v1), (x2, v2), (v1, -a1 * hy.sin(x1)), (v2, -a2 * hy.sin(x2))],
        [1.0, 1.0 + beta + gap_min, 0.0, 0.0], time=t_touch,
    )
    ta.propagate_until(0.0)
    s = [float(x) for x in ta.state]
    accel = a1 * math.sin(1.0) - a2 * math.sin(1.0 + beta)
    sc = scene(
        [body(phi=repr(s[0]), dphi=repr(s[2])), body(shape="ring", mass="2.0", phi=repr(s[1]), dphi=repr(s[3]))],
        k="0.8", t_end=repr(2 * t_touch),
    )
    return sc, accel


@pytest.mark.parametrize("gap_min", [1e-10, -1e-10, 1e-13, -1e-13])
def test_grazing_contact(gap_min):
    sc, accel = grazing_scene(gap_min)
    result = heyroll.simulate(sc)
    assert result.status is Status.COMPLETED
    assert min_gap(result, points=2000) >= GAP_FLOOR
    if gap_min > 0:
        assert result.n_collisions == 0
        return
    assert result.n_collisions == 1
    row = result.collision_table()[0]
    assert row["t"] == pytest.approx(0.3, abs=1e-4)
    # the approach rate of a gap that dips gap_min below zero: sqrt(2 A |gap_min|)
    closing = row["dq_i_before"] - row["dq_j_before"]
    assert closing == pytest.approx(math.sqrt(2 * accel * -gap_min), rel=0.05)
    assert abs(row["law_impulse"]) < 1e-4 and row["dq_j_after"] > row["dq_i_after"]


# -- bodies that start touching -----------------------------------------------------------


def test_bodies_starting_pressed_at_rest_start_in_contact():
    beta = contact_angle(body(), body())
    p2 = touching("0.1", beta)
    sc = scene([body(phi="0.1"), body(mass="2.0", phi=p2), body(mass="0.5", phi=touching(p2, beta))], k="0.5", t_end="5")
    result = heyroll.simulate(sc)
    assert result.status is Status.COMPLETED and result.n_collisions == 0
    assert result.mode_changes[0].t == 0.0 and result.mode_changes[0].clusters == ((1, 2, 3),)
    assert [(c["i"], c["j"], c["t_start"], c.get("open")) for c in result.contact_intervals] == [
        (1, 2, 0.0, True), (2, 3, 0.0, True)
    ]
    final = result.final_state
    assert len(set(final[3:].tolist())) == 1 and np.all(np.abs(pair_gaps(sc, final)[0, :2]) < 1e-13)


def test_bodies_starting_touching_at_rest_not_pressed_separate():
    # Past 90 degrees the lower body falls faster: the gap opens, no contact.
    beta = contact_angle(body(), body())
    sc = scene([body(phi="1.5"), body(phi=touching("1.5", beta))], k="0.5", t_end="0.2")
    result = heyroll.simulate(sc)
    assert result.status is Status.COMPLETED and result.n_collisions == 0 and result.contact_intervals == ()
    assert pair_gaps(sc, result.final_state)[0, 0] > 1e-4


def test_bodies_starting_touching_and_approaching_collide_at_t0():
    beta = contact_angle(body(), body())
    sc = scene([body(phi="-0.1", dphi="1.0"), body(mass="2.0", phi=touching("-0.1", beta), dphi="-1.0")], k="0.5", t_end="1")
    result = heyroll.simulate(sc)
    assert result.status is Status.COMPLETED
    assert result.times[0] == 0.0 and result.collision_table()["law_flag"][0] == 0
    assert result.states_after[0][2] < result.states_after[0][3]
    assert min_gap(result) >= GAP_FLOOR


@pytest.mark.parametrize("precision", ["double", "long", "quad"])
@pytest.mark.parametrize("track", ["circle", "curve"])
def test_bodies_placed_past_touching_by_round_off_collide_at_t0_in_every_precision(track, precision):
    """Places written to 17 digits land up to ~1e-17 past touching; the scene accepts that
    (model.touching_slack). In long and quad such a gap is far beyond the settler's band: the run
    used to miss the contact (status overlap at t_end); the start now moves the pair to touching
    in the run's type and the approaching pair collides at t = 0, as in double."""
    with mpmath.workdps(40):
        if track == "circle":  # centres on a circle of radius 0.9 touch 2 asin(1/9) rad apart
            place = mpmath.mpf("0.1") + 2 * mpmath.asin(mpmath.mpf(1) / 9) - mpmath.mpf("3e-17")
            where = f'[track]\ntype = "circle"\nradius = 1.0\n'
            coordinate = "phi"
        else:  # on the line y = 0.1 x the contact points are 0.2 m apart along it
            place = mpmath.mpf("0.1") + mpmath.mpf("0.2") / mpmath.sqrt(mpmath.mpf("1.01")) - mpmath.mpf("3e-17")
            where = '[track]\ntype = "curve"\ny = "0.1*x"\nx_min = -1.0\nx_max = 1.0\n'
            coordinate = "x"
    text = where + "".join(
        f'[[bodies]]\nshape = "disk"\nradius = 0.1\nmass = 1.0\n{coordinate} = {q}\nd{coordinate} = {v}\n'
        for q, v in (("0.1", "0.5"), (mpmath.nstr(place, 17, min_fixed=-1, max_fixed=2), "0.0")))
    result = heyroll.simulate(heyroll.parse_scene(text + "[run]\nt_end = 0.5\n"), precision=precision)
    assert result.status is Status.COMPLETED, result.message
    assert result.n_collisions >= 1 and float(result.times[0]) == 0.0
    after = np.asarray(result.states_after[0], dtype=float)
    assert after[2] == pytest.approx(0.0, abs=1e-12) and after[3] == pytest.approx(0.5, rel=1e-12)  # exchanged


# -- near the separatrix ----------------------------------------------------------------------


@pytest.mark.parametrize("side", [-1, 1], ids=["libration", "rotation"])
def test_single_body_next_to_the_separatrix(side):
    sc0 = scene([body()])
    b, tr = sc0.bodies[0], sc0.track
    with mpmath.workprec(256):
        G, W = tr.generalized_mass(b), tr.weight_moment(b, sc0.g)
        energy = 2 * W * (1 + side * mpmath.mpf(10) ** -12)  # the top is at 2 W
        rate = mpmath.nstr(mpmath.sqrt(2 * energy / G), 30)
    sc = scene([body(dphi=rate)], t_end="10")
    result = heyroll.simulate(sc)
    assert result.status is Status.COMPLETED and float(result.t_final) == 10.0
    e0 = result.energy_initial
    assert e0 / float(2 * W) - 1 == pytest.approx(side * 1e-12, rel=1e-3)
    assert abs(result.energy_final - e0) <= 1e-13 * e0
    phi = np.concatenate([br.states[:, 0] for br in branches(result, points=5000)] + [result.final_state[:1]])
    if side < 0:
        assert np.abs(phi).max() < math.pi  # turns back 2e-6 rad short of the top
    else:
        assert np.abs(phi).max() > math.pi and result.final_state[0] > math.pi


# -- the wrap-around pair ----------------------------------------------------------------------


def test_body_going_over_the_top_hits_its_neighbour_from_behind():
    sc = scene([body(phi="-0.8"), body(mass="2.0", phi="0.0"), body(phi="0.8", dphi="9.0")], k="1.0", t_end="1.5")
    result = heyroll.simulate(sc)
    assert result.status is Status.COMPLETED
    table = result.collision_table()
    wrap = table[(table["i"] == 3) & (table["j"] == 1)]
    assert wrap.size >= 1
    first = wrap[0]
    assert first["q_i"] > math.pi  # body 3 came over the top
    beta = float(sc.pairs[2].beta)
    assert first["q_j"] + 2 * math.pi - first["q_i"] == pytest.approx(beta, abs=1e-13)
    assert first["dq_i_after"] < first["dq_j_after"]
    assert min_gap(result) >= GAP_FLOOR


# -- leaving the track, slipping -----------------------------------------------------------------


def normal_force(sc, n, state):
    """N / m = rho phi'^2 + g cos phi."""
    rho, g, nb = float(sc.track.path_radius(sc.bodies[n])), float(sc.g), len(sc.bodies)
    return rho * state[nb + n] ** 2 + g * math.cos(state[n])


def test_one_sided_track_body_leaves_the_track():
    sc = scene([body(mass="2.0", phi="-0.3"), body(phi="0.3", dphi="5.0")], track='sides = "one"', t_end="5")
    result = heyroll.simulate(sc)
    assert result.status is Status.LEFT_TRACK and not result.success
    match = re.match(r"body (\d+) would leave the track.* at phi = (\S+), dphi = (\S+), t = (\S+) s", result.message)
    assert match, result.message
    assert int(match.group(1)) == 2
    assert float(match.group(2)) == result.final_state[1] and float(match.group(4)) == float(result.t_final)
    assert math.pi / 2 < result.final_state[1] < math.pi
    rho, g = float(sc.track.path_radius(sc.bodies[1])), float(sc.g)
    assert abs(normal_force(sc, 1, result.final_state)) < 1e-12 * (rho * result.final_state[3] ** 2 + g)


def test_two_sided_track_warns_and_goes_on():
    sc = scene([body(mass="2.0", phi="-0.3"), body(phi="0.3", dphi="5.0")], t_end="5")
    result = heyroll.simulate(sc)
    assert result.status is Status.COMPLETED and float(result.t_final) == 5.0
    (warning,) = result.settings["warnings"]
    assert warning.startswith("body 2: the normal force of the track changes sign at t = 0.4513131272944")


def test_friction_limit_a_swinging_disk_starts_to_slip_where_it_needs_more_than_mu_n():
    # (Before issue 15 the run stopped here with status slip; now the disk slips and rolls again.)
    mu = 0.05
    sc = scene([body(shape="disk", phi="0.0", dphi="4.0")], track=f"friction = {mu}", t_end="5")
    result = heyroll.simulate(sc)
    assert result.status is Status.COMPLETED
    t, k, old, new, phi, dphi = result.transitions[0]
    assert (k, old) == (0, "rolling") and new in ("sliding+", "sliding-") and 0 < t < 5
    s = [float(phi), float(dphi)]
    kappa = float(sc.bodies[0].kappa)
    F = float(sc.g) * math.sin(s[0]) * (1 - 1 / kappa)
    N = normal_force(sc, 0, s)
    assert N > 0 and abs(abs(F) - mu * N) <= 1e-9 * mu * N
    # its slip then returns to zero where rolling would still need more than mu N: it slips the other
    # way (at mu = 0.05 it never rolls again in 5 s); friction takes exactly the energy lost
    for _t, _k, old, new, phi, dphi in result.transitions[1:]:
        assert {old, new} == {"sliding+", "sliding-"}
        F = float(sc.g) * math.sin(float(phi)) * (1 - 1 / kappa)
        assert abs(F) > mu * normal_force(sc, 0, [float(phi), float(dphi)])
    assert result.energy_initial - result.energy_final == pytest.approx(sum(result.friction_work), rel=1e-12)


def test_one_sided_track_body_starting_where_it_cannot_stay_leaves_at_t0():
    sc = scene([body(phi="2.0")], track='sides = "one"', t_end="5")
    result = heyroll.simulate(sc)
    # before 9b98a1c: left_track only at t = 1.27 s, phi = -1.818 (after rolling through the bottom)
    assert result.status is Status.LEFT_TRACK and float(result.t_final) == 0.0


def test_friction_limit_already_exceeded_at_t0_slips_from_t0():
    sc = scene([body(shape="disk", phi="-0.5")], track="friction = 0.05", t_end="5")
    result = heyroll.simulate(sc)
    # before 9b98a1c: slip only at t = 0.722 s, phi = 0.170, on the other side of the bottom;
    # before issue 15 the run stopped at t = 0 with status slip
    assert result.transitions[0][:4] == (0.0, 0, "rolling", "sliding+")


def test_sample_branches_restart_from_the_merged_state():
    sc = scene([body(phi="-1.0"), body(mass="2.0", phi="0.0"), body(mass="0.5", phi="0.9")], k="0.5", t_end="3")
    result = heyroll.simulate(sc)
    # before 9b98a1c: the samples showed bodies 1 and 2 overlapping by 7.4e-9 rad
    # just before body 1 hits the (2, 3) cluster at t = 1.325 s.
    assert min_gap(result, sampler=sample_branches) >= GAP_FLOOR


# -- the CLI: determinism, interruption -------------------------------------------------------------


def test_cli_runs_are_deterministic(tmp_path, capsys):
    scene_file = tmp_path / "unequal.toml"
    # Unequal balls starting in contact at a common rate: the contact splits past
    # 90 degrees, 42 rolling-law outcomes are flagged, a contact across the top follows.
    b1, b2 = body(radius="0.10", density="7850"), body(radius="0.15", density="7850")
    beta = contact_angle(b1, b2)
    scene_file.write_text(scene_toml(
        [body(radius="0.10", density="7850", phi="-0.2", dphi="5.5"),
         body(radius="0.15", density="7850", phi=touching("-0.2", beta), dphi="5.5")], k="0.8", t_end="30",
    ))
    summaries, tables = [], []
    for out in ("A", "B"):
        code = cli_main(["run", str(scene_file), "--out", str(tmp_path / out), "--no-figures", "--progress", "off"])
        assert code == 0
        tables.append((tmp_path / out / "collisions.csv").read_bytes())
        summary = json.loads((tmp_path / out / "summary.json").read_text())
        summary.pop("wall_time_s")
        summaries.append(summary)
    capsys.readouterr()
    assert tables[0] == tables[1]
    assert summaries[0] == summaries[1]
    s = summaries[0]
    assert s["inconsistent_collisions"] > 0 and s["contact_intervals"]  # both hard cases happen in this run
    assert any(not c.get("open") for c in s["contact_intervals"])  # and a contact split


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_cli_interrupted_run_leaves_a_complete_table(tmp_path, sig):
    scene_file = tmp_path / "elastic.toml"
    scene_file.write_text(
        scene_toml([body(phi="-1.0"), body(shape="disk", mass="2.0", phi="0.5")], k="1.0")
    )
    out = tmp_path / "out"
    proc = subprocess.Popen(
        [sys.executable, "-m", "heyroll.interfaces.cli", "run", str(scene_file), "--t-end", "1e7", "--table", "npy",
         "--progress", "off", "--no-figures", "--out", str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        started = time.monotonic()
        table = out / ".collisions.npy.tmp"
        # The run has begun and written its first chunk of rows (not a fixed delay: on a loaded machine
        # the first mode's compilation can outlast it, and an interruption there has no rows).
        while not table.exists() or table.stat().st_size <= 4096:
            assert proc.poll() is None and time.monotonic() - started < 120
            time.sleep(0.02)
        proc.send_signal(sig)
        stdout, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, stderr
    assert "Traceback" not in stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    table = np.load(out / "collisions.npy")
    assert table.size == summary["collisions"] == summary["table_rows"] > 1000
    assert np.array_equal(table["n"], np.arange(1, table.size + 1))
    for name in table.dtype.names:
        assert np.all(np.isfinite(table[name]))
    assert np.all(np.diff(table["t"]) > 0) and table["t"][-1] <= summary["t_final"]
    assert np.allclose(table["energy_after"], summary["energy_initial"], rtol=1e-10)
    assert not (out / ".collisions.npy.tmp").exists()


# -- engine bugs found by tests/test_fuzz.py (fixed) -----------------------------------------------
#
# One root cause behind the first three: heyoka's event detection cannot see a
# root of an event function that is exactly 0.0 at the start of a step (pure
# heyoka: x'' = -1, x(0) = 0, x'(0) = 0.01, t_event on x with direction
# negative: the root at t = 0.02 is missed; with x(0) = 1e-300 it is found).
# A watched gap that starts a step at exactly 0.0, opening slowly while its
# acceleration closes it, re-closed inside that first step unseen. Now every
# pair touching at the start of a mode or after a cascade is collided, put in
# contact, or opened by a few ulps (events.contact_settler), and a guard event
# per pair stops a run whose gap goes below -overlap_tolerance anyway.


def test_heyoka_misses_a_root_when_the_event_function_starts_at_exactly_zero():
    """The heyoka behaviour behind the first three bugs below (if heyoka changes, this says so)."""
    import heyoka as hy

    x, v = hy.make_vars("x", "v")
    found = {}
    for x0 in (0.0, 1e-300):
        hits = []
        event = hy.t_event(x, callback=lambda ta, d, hits=hits: hits.append(ta.time) or False,
                           direction=hy.event_direction.negative)
        ta = hy.taylor_adaptive([(x, v), (v, -1.0 + 0.0 * x)], [x0, 0.01], t_events=[event])
        ta.propagate_until(1.0)
        found[x0] = hits
    assert found[0.0] == []  # x = 0.01 t - t^2/2 returns to 0 at t = 0.02: unseen
    assert found[1e-300] == [pytest.approx(0.02, rel=1e-12)]


def test_gap_exactly_zero_at_a_mode_start_touching_start():
    # phi_2 - phi_1 - beta is +2e-17 exactly and 0.0 in double; body 2 moves away at 0.02 rad/s,
    # the pair is pressed (gap'' < 0): the gap re-closes at t ~ 0.01 s.
    sc = scene([body(phi="0.0"), body(mass="2.0", phi="0.2226820286819278", dphi="0.02")], k="0.5", t_end="2")
    result = heyroll.simulate(sc)
    # before the fix: 0 collisions, status overlap (gap -0.060 rad at t = 2 s; -0.446 along the run)
    assert result.status is Status.COMPLETED and result.n_collisions > 0
    # the bounce that re-closes the gap: v^2 / (2 A) high, back after 2 v / A
    A = stiffness(sc, 0) * math.sin(0.0) - stiffness(sc, 1) * math.sin(0.2226820286819278)
    assert float(result.times[0]) == pytest.approx(2 * 0.02 / -A, rel=0.05)
    assert min_gap(result) >= GAP_FLOOR


def test_gap_exactly_zero_at_a_mode_start_after_a_split():
    sc = scene(
        [body(radius="0.20552171037334813", phi="-1.5492089749104005"),
         body(radius="0.12647999996429304", phi="-1.1596784170279733")], k="0.0", t_end="5",
    )
    result = heyroll.simulate(sc)
    # before the fix: contact from t = 0 (pressed), split at t = 1.2206 s, then the gap
    # fell to -1.199 rad; one collision at 4.68 s; status completed.
    t_split = result.contact_intervals[0]["t_end"]
    assert t_split == pytest.approx(1.2206, abs=1e-3)
    assert result.status is Status.COMPLETED
    assert result.n_collisions and float(result.times[0]) > t_split  # the pair meets again after the split
    assert min_gap(result) >= GAP_FLOOR


def test_three_equal_bodies_at_the_same_instant_inelastic():
    sc = scene([body(phi="-1.0"), body(phi="0.0"), body(phi="1.0")], k="0.3", t_end="3")
    result = heyroll.simulate(sc)
    # before the fix: 4 rows at t = 0.5163 left (2, 3) at gap 0 opening at 0.0056 rad/s;
    # no further (2, 3) collision; the gap fell to -0.685 rad; status completed.
    assert result.status is Status.COMPLETED
    table = result.collision_table()
    first = table["t"][0]
    later = table[(table["t"] > first) & (table["i"] == 2) & (table["j"] == 3)]
    assert later.size  # the slowly opening pair is seen to close again
    assert min_gap(result) >= GAP_FLOOR


def test_max_collisions_holds_inside_a_same_instant_cascade():
    sc = scene([body(phi="-1.0"), body(phi="0.0"), body(phi="1.0")], k="0.0", t_end="3")
    result = heyroll.simulate(sc, max_collisions=2)
    # before the fix: 195 collisions, all at t = 0.5163 s (the plastic sequential impulses
    # converge only geometrically and are cut at 64 N rounds), status completed.
    assert result.status is Status.MAX_COLLISIONS and result.n_collisions == 2
    assert result.message == "stopped after max_collisions = 2 collisions"


def test_plastic_collision_of_three_at_one_instant_ends_in_one_cluster():
    sc = scene([body(phi="-1.0"), body(phi="0.0"), body(phi="1.0")], k="0.0", t_end="3")
    result = heyroll.simulate(sc)
    assert result.status is Status.COMPLETED
    # k = 0: each pair leaves its collision at rest relative to the other and
    # pressed: contact at once, no endless geometric cascade of impulses.
    t_hit = float(result.times[0])
    assert np.all(result.times == t_hit) and result.n_collisions <= 4
    assert result.mode_changes[-1].clusters == ((1, 2, 3),) and result.mode_changes[-1].t == t_hit
    G = generalized_masses(sc)
    before, final = result.states_before[0], result.final_state
    assert len(set(final[3:].tolist())) == 1
    assert min_gap(result) >= GAP_FLOOR
    # equal radii: the impacts keep sum G phi' (0 here, by symmetry: the cluster starts at rest)
    assert G @ result.mode_changes[-1].state[3:] == pytest.approx(G @ before[3:], abs=1e-12)
    assert np.allclose(result.mode_changes[-1].state[3:], 0, atol=1e-12)


def test_sample_branches_with_a_branch_one_ulp_long():
    sc = scene(
        [body(radius="0.25"), body(radius="0.125", phi="0.43997595479091994"),
         body(shape="particle", radius=None, mass="2.0", phi="0.439975954790921"),
         body(shape="particle", radius=None, mass="5.0", phi="0.43997595479092205", dphi="5.7833751885407318")],
        law="newton", k="0.0", t_end="5",
    )
    result = heyroll.simulate(sc)
    # before the fix (of the engine's cascade too): splits at t = 1.9271096213324175 and ...177 s
    assert result.status is Status.COMPLETED
    assert min_gap(result, points=40) >= GAP_FLOOR


def test_sample_branches_keeps_each_time_once():
    sc = scene([body(phi="-0.5"), body(phi="0.5")], t_end="1")
    result = heyroll.simulate(sc)
    t0 = float(result.t_final)
    t1 = math.nextafter(t0, math.inf)
    assert np.unique(np.linspace(t0, t1, 40)).size < 40  # what np.linspace gives for a branch 1 ulp long
    from dataclasses import replace

    from heyroll.simulation.driver import ModeChange

    short = replace(result, t_final=t1, mode_changes=result.mode_changes + (ModeChange(t0, (), tuple(result.final_state)),))
    last = sample_branches(short, points=40)[-1]
    assert last.times[0] == t0 and last.times[-1] == t1 and np.all(np.diff(last.times) > 0)


def test_same_instant_contacts_next_to_a_cluster_are_resolved():
    sc = scene(
        [body(radius="0.25", phi="-1.0"), body(radius="0.25", phi="-0.32032618109175509"),
         body(radius="0.25", mass="0.5", phi="0.35934763781648982", dphi="5.6956792857789704"),
         body(radius="0.25", mass="2.0", phi="1.2890214567247338")], k="0.125", t_end="1",
    )
    result = heyroll.simulate(sc)
    # before the fix: (1, 2) in contact from t = 0; body 3 bounced between the cluster and
    # body 4 ever faster; at t = 0.2906267 a (3, 4) row and a (2, 3) cluster row shared
    # one instant and left (3, 4) closing; the gap never recovered.
    assert result.status is Status.COMPLETED
    assert min_gap(result) >= GAP_FLOOR
    # after every group of rows at one instant no touching pair closes
    table = result.collision_table()
    for a, b in same_instant_groups(table):
        after = result.states_after[b - 1]
        gaps = pair_gaps(sc, after)[0]
        rates = np.array([after[4 + p.j] - after[4 + p.i] for p in sc.pairs])
        assert not np.any((np.abs(gaps) < 1e-12) & (rates < 0))


def test_contact_across_the_top_splits_cleanly():
    sc = scene([body(phi="-0.5"), body(phi="0.5", dphi="8.5")], k="0.0", t_end="5")
    result = heyroll.simulate(sc)
    # before the fix: ball 2 goes over the top and hits ball 1 from behind at t = 0.7795 s
    # (plastic: contact (2, 1)); the contact splits at 1.1243 s; from then on body 1
    # carried body 2's state and vice versa (phi = [-7.568, -1.507] at 2.7413 s).
    contact = result.contact_intervals[0]
    assert contact["i"] == 2 and contact["j"] == 1 and not contact.get("open")
    assert result.status is Status.COMPLETED
    assert min_gap(result) >= GAP_FLOOR
    # the split keeps every body's own state: both still in contact, at one rate
    split = next(m for m in result.mode_changes if m.t == contact["t_end"])
    merged = next(m for m in result.mode_changes if m.t == contact["t_start"])
    assert split.clusters == () and merged.clusters == ((2, 1),)
    assert split.state[2] == split.state[3]
    assert pair_gaps(sc, np.array(split.state))[0, 1] == pytest.approx(0, abs=1e-13)


def test_max_collisions_holds_when_the_last_collision_starts_a_contact():
    sc = scene([body(phi="-1.0"), body(mass="2.0", phi="0.0"), body(mass="0.5", phi="0.9")], k="0.5", t_end="10")
    full = heyroll.simulate(sc)
    merging = int(np.flatnonzero(full.times == full.mode_changes[1].t)[-1]) + 1  # measured: collision 23
    result = heyroll.simulate(sc, max_collisions=merging)
    # before the fix: status max_collisions, message "stopped after max_collisions = 23", 24 collisions
    assert result.status is Status.MAX_COLLISIONS and result.n_collisions == merging
    assert np.array_equal(result.times, full.times[:merging])


# -- the overlap guard ------------------------------------------------------------------------------


MISSED_COLLISION_SCENES = {
    "touching start": lambda: scene([body(phi="0.0"), body(mass="2.0", phi="0.2226820286819278", dphi="0.02")],
                                    k="0.5", t_end="2"),
    "after a split": lambda: scene(
        [body(radius="0.20552171037334813", phi="-1.5492089749104005"),
         body(radius="0.12647999996429304", phi="-1.1596784170279733")], k="0.0", t_end="5",
    ),
    "after a cascade": lambda: scene([body(phi="-1.0"), body(phi="0.0"), body(phi="1.0")], k="0.3", t_end="3"),
}


@pytest.mark.parametrize("case", list(MISSED_COLLISION_SCENES))
def test_gaps_left_at_exactly_zero_never_end_in_an_unnoticed_overlap(case, monkeypatch):
    """With the gap opening switched off (gaps left at exactly 0.0, which heyoka cannot see close
    when its event only looks for closing: the bugs above) a run either still finds every
    collision (the circle's gap events look both ways) or stops, status overlap: never completed
    with the bodies through each other."""
    from heyroll.simulation import events

    sc = MISSED_COLLISION_SCENES[case]()
    assert heyroll.simulate(sc).status is Status.COMPLETED
    monkeypatch.setattr(events, "OPEN_ULPS", 0)  # opening a gap by 0 ulps: exactly 0.0 stays
    broken = heyroll.simulate(sc, dense=True)
    if broken.status is Status.COMPLETED:
        assert min_gap(broken) >= GAP_FLOOR
    else:
        assert broken.status is Status.OVERLAP and "a collision was missed" in broken.message


@pytest.mark.parametrize("case", list(MISSED_COLLISION_SCENES))
def test_a_missed_collision_never_ends_completed(case, monkeypatch):
    """Collision callbacks that ignore every collision (a missed collision, made on purpose): the
    bodies pass into each other and the run stops, status overlap, where the gap comes back up
    through zero (the circle's gap events look both ways, events.reopening_check) or, if it
    never does, at the end of the mode or the run: never completed."""
    from heyroll.simulation import events

    real = events._make_callback

    def blind(*args, **kwargs):
        seeing = real(*args, **kwargs)

        def on_gap(ta, d_sgn):
            return True if d_sgn < 0 else seeing(ta, d_sgn)  # closing: ignored

        on_gap.resolve = seeing.resolve
        return on_gap

    monkeypatch.setattr(events, "_make_callback", blind)
    sc = MISSED_COLLISION_SCENES[case]()
    broken = heyroll.simulate(sc)
    assert broken.status is Status.OVERLAP and not broken.success
    assert "a collision was missed" in broken.message and broken.n_collisions == 0


@pytest.mark.parametrize("phi", ["0.0", "1e-10"])
def test_plastic_collision_where_the_gap_acceleration_changes_sign_starts_a_contact(phi):
    # Found by tests/test_fuzz.py. A particle and a ball of radius r touch across
    # one radius (beta = 0), so their gap acceleration (a_1 - a_2) sin phi vanishes
    # at the bottom. The ball hits the particle there, plastically: the pair moves on
    # together with gap'' ~ 0 now (0, or +3e-10 rad/s^2 at phi = 1e-10) but closing at
    # once (jerk < 0: the particle is the stiffer pendulum; the gap rises by
    # a^3 / (3 J^2) ~ 1e-30 rad before it closes). Before the fix this was not
    # "pressed": no contact, the gap closed unseen (as t^3) and the guard stopped
    # the run at t = 9e-5 s (status overlap).
    sc = scene([body(shape="particle", radius=None, mass="2.8", phi=phi),
                body(radius="0.02", mass="5.5", phi=repr(float(phi) + 1e-12), dphi="-4.0")],
               law="newton_generalized", k="0.0", t_end="1.5")
    assert sc.pairs[0].beta == 0
    result = heyroll.simulate(sc)
    assert result.status is Status.COMPLETED
    assert result.n_collisions == 1 and float(result.times[0]) == pytest.approx(1e-12 / 4.0, rel=1e-3)
    contact = result.contact_intervals[0]
    assert (contact["i"], contact["j"]) == (1, 2) and contact["t_start"] == float(result.times[0])
    assert min_gap(result) >= GAP_FLOOR


def test_bounce_model_of_the_contact_criterion():
    from heyroll.simulation.events import _bounce_height, _first_return

    # J = 0: the parabola of the Zeno criterion, up for 2v/A, h = v^2 / (2A)
    v, A = 1e-3, 2.0
    assert _first_return(v, -A, 0.0) == pytest.approx(2 * v / A, rel=1e-15)
    assert _bounce_height(v, -A, 0.0, 2 * v / A) == pytest.approx(v * v / (2 * A), rel=1e-12)
    # a ~ 0 > J: back after 3a/|J|, h = a^3 / (3 J^2)
    a, J = 3e-10, -5.0
    assert _first_return(0.0, a, J) == pytest.approx(3 * a / -J, rel=1e-12)
    assert _bounce_height(0.0, a, J, 3 * a / -J) == pytest.approx(a**3 / (3 * J * J), rel=1e-9)
    # pressed from the start, or never back
    assert _first_return(0.0, -1.0, 0.0) == 0.0 and _first_return(0.0, 0.0, -1.0) == 0.0
    assert _first_return(0.0, 1.0, 1.0) is None and _first_return(1.0, 1.0, 0.0) is None
    assert _first_return(0.0, 0.0, 0.0) is None  # at rest, no force: not pressed


@pytest.mark.parametrize("change", [("g", "1e29"), ("dphi", "-3e16")], ids=["g=1e29", "dphi=-3e16"])
def test_a_run_heyoka_cannot_advance_stops_in_bounded_time(change):
    # Found by tests/test_fuzz.py (the CLI on a mutated scene): with a track-force
    # event of size ~1e29, heyoka 7.13 takes zero-length steps for ever
    # (propagate_until never returned). The driver now sees the time stand still.
    key, value = change
    bodies = [body(phi="-0.5", dphi=value if key == "dphi" else "0.0"),
              body(shape="disk", radius="0.15", density="7850", phi="0.5", dphi="0.052941176470588235")]
    text = scene_toml(bodies, k="0.8", t_end="1e-12")
    sc = parse_scene(text.replace("g = 9.81", f"g = {value}") if key == "g" else text)
    started = time.perf_counter()
    result = heyroll.simulate(sc)
    assert time.perf_counter() - started < 30
    assert result.status in (Status.COMPLETED, Status.FAILED)
    if result.status is Status.FAILED:
        assert result.message.startswith("the integrator does not advance from t = ")


@pytest.mark.parametrize("precision", ["quad", "mp:80"])
def test_same_instant_cascade_in_extended_precision(precision):
    # The settler judged "touching" with the gap's constant rounded to double: in
    # quad a freshly collided pair sat 1e-17 rad (the double's rounding) from zero,
    # far outside quad's 64 ulps. The second impact of the instant was never seen
    # as touching: bodies 1 and 2 stayed closing and the guard stopped the run.
    sc = scene([body(phi="-1.0"), body(phi="0.0"), body(phi="1.0")], k="0.3", t_end="1")
    result = heyroll.simulate(sc, precision=precision)
    assert result.status is Status.COMPLETED
    table = result.collision_table()
    first = table[table["t"] == table["t"][0]]
    assert first.size >= 3  # (1, 2), (2, 3), then (1, 2) again at the same instant
    after = np.array(result.states_after[first.size - 1], dtype=float)
    closing = np.array([after[3] - after[4], after[4] - after[5]]) > 0
    assert not np.any((np.abs(pair_gaps(sc, after)[0, :2]) < 1e-12) & closing)
    assert min_gap(result, points=50) >= GAP_FLOOR


def _energy_never_created(result):
    """No energy gain at a collision resolved by the fallback or cluster laws (flags 1
    and 2: Newton's law on the gap rate, which cannot create energy)."""
    table = result.collision_table()
    scale = float(sum(result.scene.track.weight_moment(b, result.scene.g) for b in result.scene.bodies))
    rows = table["law_flag"] != 0
    assert np.all((table["energy_after"] - table["energy_before"])[rows] <= 1e-12 * (scale + abs(result.energy_initial)))


@pytest.mark.parametrize("mu", [None, "1.0"])
def test_plastic_cascade_at_the_bottom_where_every_gap_acceleration_vanishes(mu):
    # Found by tests/test_fuzz.py. A ball rests at phi = 0; two particles (beta = 0)
    # merge, then hit it there at k = 0. At phi = 0 every gap acceleration is 0 and its
    # sign was the rounding of the positions (-1.8e-19 rad/s^2 from a collision root
    # 1.9e-20 rad off, -3.5e-14 from a gap opened by OPEN_ULPS), while the jerk
    # (+0.027: the particles are the stiffer pendulums, moving left) opens the gap for
    # good after 3|a|/J: "pressed" by ~1e-38 rad. Judged a contact, the pair merged,
    # its link split at once, the settler merged it again: 25 mode changes at one
    # instant, status failed. Now the ball leaves the particles (as t^3).
    from heyroll.simulation.events import below_resolution

    eps = float(np.finfo(float).eps)
    assert not below_resolution(0.0, -1.8e-19, 0.0, 0.54, 1.0, 0.33, eps, 0.027)  # dips 5e-54 rad: opening
    assert not below_resolution(0.0, -3.5e-14, 0.0, 0.54, 1.0, 0.33, eps, 0.027)  # dips 4e-38 rad: opening
    assert below_resolution(0.0, -1e-3, 0.0, 0.54, 1.0, 0.33, eps, 0.027)  # pressed for 0.1 s: a contact
    assert below_resolution(0.0, 3e-10, 0.0, 0.54, 1.0, 0.33, eps, -5.0)  # J < 0: closes at once, as before
    sc = scene([body(radius="0.25", mass="2.5", phi="0.0"),
                body(shape="particle", radius=None, mass="2.3638328551650014", phi="9.9999999999999998e-13",
                     dphi="0.01"),
                body(shape="particle", radius=None, mass="0.75", phi="0.12500000000100001", dphi="0.01")],
               law="newton", k="0.0", t_end="1.0", track=f"friction = {mu}" if mu else "")
    result = heyroll.simulate(sc, max_collisions=60)
    assert result.status is Status.COMPLETED, result.message
    assert min_gap(result) >= GAP_FLOOR
    if mu is not None:
        # (The fuzz scene had friction = 1 when friction only stopped runs that would slip.) With
        # friction modelled, the particles' 0.01 rad/s dies in ~1 ms: they stick apart, no collision,
        # and the energy lost is the friction work.
        assert result.n_collisions == 0 and result.final_modes == ("rolling", "stuck", "stuck")
        assert result.energy_initial - result.energy_final == pytest.approx(sum(result.friction_work), rel=1e-12)
        return
    hit = float(result.times[1])
    assert hit == pytest.approx(0.5357721124358830, abs=1e-12)  # the particles reach the ball at phi = 0
    assert sum(1 for m in result.mode_changes if m.t == hit) <= 2
    assert min_gap(result) >= GAP_FLOOR
    assert result.energy_final < result.energy_initial
    _energy_never_created(result)


def test_a_row_of_touching_bodies_opens_every_gap_at_the_start():
    # Found by tests/test_fuzz.py. Ball, particle, ball, particle (beta = 0 for each
    # pair), all starting at phi = -1. Pair (2, 3) opens at 0.01 rad/s but is pressed
    # (the ball is the softer pendulum): it closes again at t = 0.0509 s. The settler
    # opens touching gaps by moving one unit a few ulps, but here both neighbours' gaps
    # were 0 or only just opened: no unit had room, the gap stayed 0.0, heyoka did not
    # see it close (a root at the very start of a step) and the guard stopped the run
    # (status overlap). Now the unit moves with the units that crowd it, as one block.
    bodies = [body(radius="0.25", phi="-1.0"), body(shape="particle", radius=None, phi="-1.0"),
              body(radius="0.25", phi="-1.0", dphi="0.01"), body(shape="particle", radius=None, phi="-1.0", dphi="0.01")]
    # (The fuzz scene had friction = 1.0, when friction only stopped runs that would slip: see the
    # rough variant below.)
    sc = scene(bodies, law="newton", k="0.0", t_end="1.0")
    result = heyroll.simulate(sc, max_collisions=60)
    assert result.status is Status.COMPLETED, result.message
    start = np.array(result.mode_changes[0].state, dtype=float)
    gaps = pair_gaps(sc, start)[0, :3]  # (4, 1) is the far side
    assert np.all((gaps > 0) & (gaps < 1e-13))  # every touching pair opened by a few ulps
    table = result.collision_table()
    assert (table["i"][0], table["j"][0]) == (2, 3) and table["t"][0] == pytest.approx(0.0508820791, abs=1e-9)
    for states in (result.states_before, result.states_after):
        assert pair_gaps(sc, np.asarray(states, dtype=float)).min() >= GAP_FLOOR
    assert min_gap(result) >= GAP_FLOOR
    # Newton's law on centre speeds with unequal kappa can create energy (by design):
    # only the collisions that cannot are checked.
    _energy_never_created(result)
    # Rough: each ball, the faster pendulum, presses on the particle that friction holds back: both
    # pairs start in persistent contact, slide together and stick together.
    rough = heyroll.simulate(scene(bodies, law="newton", k="0.0", t_end="1.0", track="friction = 1.0"),
                             max_collisions=60)
    assert rough.status is Status.COMPLETED, rough.message
    assert rough.mode_changes[-1].clusters == ((1, 2), (3, 4)) and rough.mode_changes[-1].t == 0.0
    assert rough.final_modes == ("stuck",) * 4 and min_gap(rough) >= GAP_FLOOR
    assert rough.energy_initial - rough.energy_final == pytest.approx(sum(rough.friction_work), rel=1e-12)


@pytest.mark.parametrize("n, precision", [(4, "double"), (8, "double"), (4, "quad")])
def test_disjoint_pairs_colliding_at_one_instant_are_all_resolved(n, precision):
    # Issue 12: bodies started mirror-symmetrically at rest make two disjoint pairs collide at the
    # same instant; the settler looked only at the neighbours of the pair whose event fired, the
    # other pair restarted at a gap of exactly 0, heyoka could not see it close: status overlap
    # after 2 collisions (4 balls) or 55 (8 balls). Elastic: the energy is kept.
    b = heyroll.Body.of_shape("solid_sphere", "0.1", mass="1")
    phis = [str(round(-0.2 * (n - 1) + 0.4 * k, 10)) for k in range(n)]
    sc = heyroll.Scene.make(heyroll.CircleTrack.of_radius(5), [b] * n, phi=phis, dphi=[0] * n,
                            law=heyroll.make_law("hedrih", "1"), run=heyroll.RunSettings.make(10 if precision == "double" else 3))
    result = heyroll.simulate(sc, precision=precision)
    assert result.status is Status.COMPLETED, result.message
    table = result.collision_table()
    assert np.any(np.diff(table["t"]) == 0)  # simultaneous collisions happened and were resolved
    assert abs(result.energy_final - result.energy_initial) <= 1e-12 * abs(result.energy_initial)


def test_a_body_squeezed_between_a_plastic_stop_and_a_neighbour():
    """Found by the rough-track fuzz (and present on smooth tracks at 931748b): on y = x^2 in a plane
    turning at 2 rad/s, ring 1 rests at the lower stop (limiter restitution 0) and heavy ring 2 comes
    down on it (k = 1). Ring 1 bounces between ring 2 and the stop ever faster while ring 2 slows:
    collisions accumulate at t = 0.4992304107 s. Each contact alone opens (both rings are pulled away
    from the stop, the lighter one less); the bounces fell below the resolution and one was missed (a
    known failure, xfail, until a stop's rebound handed a neighbour touching the body to the contact
    settler, as a collision does: acceptance test). Now the accumulation ends in persistent contact there."""
    from heyroll.model.frame import Frame
    from heyroll.model.laws import make_law
    from heyroll.model.scene import RunSettings, Scene
    from heyroll.model.tracks import CurveTrack

    ring = lambda m: heyroll.Body.of_shape("ring", "0.05", mass=m)  # noqa: E731
    sc = Scene.make(CurveTrack.make("x**2", -1, 1), [ring("0.25"), ring(2), ring(4), ring(1)],
                    ["-0.75", "-0.5", "-0.375", "0.0"], [0, 0, "-2.0", 0], law=make_law("hedrih", 1),
                    track_sides="one", frame=Frame.make("2.0", 0), limiter_restitution=0, run=RunSettings.make(1, 200))
    result = heyroll.simulate(sc)
    assert result.status is Status.COMPLETED, result.message
    (contact,) = result.contact_intervals
    assert (contact["i"], contact["j"]) == (1, 2) and contact["t_start"] == pytest.approx(0.4992304107, abs=1e-6)
    assert result.passage_counts[1] > 10 and result.energy_final < result.energy_initial


def test_ctrl_c_while_a_run_compiles_ends_it_interrupted_not_with_a_traceback(monkeypatch):
    """Found by CI on a slow machine: SIGTERM 2 s after the table file appeared landed in the first
    mode's compilation (before the integration, where Ctrl-C was caught): a traceback. Now the run ends
    with status interrupted there too, and also when a later mode is compiling."""
    import heyroll.simulation.driver as driver

    sc = scene([body(phi="-1.0"), body(shape="disk", mass="2.0", phi="0.5")], k="0.0", t_end="5")

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    with monkeypatch.context() as m:
        m.setattr(driver, "_start", interrupted)
        result = heyroll.simulate(sc)
    assert result.status is Status.INTERRUPTED and float(result.t_final) == 0.0
    assert result.n_collisions == 0 and np.array_equal(result.final_state, result.initial_state)
    real = driver._integrator
    calls = []

    def second_compile_interrupted(system, options, cooldown, quick=False):
        calls.append(quick)
        if len(calls) > 1:  # a later mode (the plastic pair's persistent contact)
            raise KeyboardInterrupt
        return real(system, options, cooldown, quick)

    with monkeypatch.context() as m:
        m.setattr(driver, "_integrator", second_compile_interrupted)
        result = heyroll.simulate(sc)
    assert len(calls) == 2 and result.status is Status.INTERRUPTED and result.n_collisions >= 1
    assert "between two stretches of integration" in result.message


REVIEWS_H = Path(__file__).parent / "data" / "reviews_h"


@pytest.mark.parametrize("end", ["upper", "lower"])
def test_a_pair_rolling_into_a_stop_rebounds_from_it(end):
    """Review: two touching disks rolling into a line's stop. The stop's rebound handed the touching neighbour to
    the contact settler, which opened their gap by moving the second body: at the upper stop that is the body on
    the stop, moved past it, whose bound event then never fired (it ran off the track, status overlap). The
    first body now steps back instead."""
    from heyroll.interfaces.scene_file import load_scene

    scene = load_scene(REVIEWS_H / "pair_into_stop.toml")
    if end == "lower":
        scene = scene.with_state(q=(0.5, 0.6000000000000001), dq=(-1.0, -1.0))
    result = heyroll.simulate(scene, t_end=3.0)
    assert result.status is Status.COMPLETED, result.message
    assert result.passage_counts[1] >= 2 and result.n_collisions >= 1


def test_a_cluster_impact_between_units_that_do_not_meet_end_to_end_falls_back():
    """Review: a cluster impact whose units' chain had no link between two of its bodies raised StopIteration (a
    traceback); the impact now falls back to releasing the cluster and resolving its contacts one by one."""
    from heyroll.interfaces.scene_file import load_scene

    result = heyroll.simulate(load_scene(REVIEWS_H / "v_track_cluster_impact.toml"))
    assert result.status.success, result.message


@pytest.mark.parametrize("name", ["turning_hoop_cluster_split", "forced_cluster_split"])
def test_a_circle_cluster_splits_where_the_same_scene_on_one_arc_splits(name):
    """Review: a circle's cluster in a turning plane or under forcing moved by its members' own terms, but its
    contact forces (the split events) were still the fixed plane's: the cluster stayed glued under tension (a
    turning hoop) or split at the wrong time (a forced pair). The same physics on one arc of the circle (per-body
    equations, constraint forces) is the reference: the contact intervals agree."""
    import mpmath

    from heyroll.interfaces.scene_file import load_scene

    scene = load_scene(REVIEWS_H / f"{name}.toml")
    R = scene.track.radius
    chain = heyroll.ArcChainTrack.make([heyroll.Segment("arc", R, "concave", -mpmath.pi, mpmath.pi)],
                                       start_x=0, start_y=-R)
    arc = heyroll.Scene.make(chain, scene.bodies, [(R - b.radius) * (p + mpmath.pi) for b, p in zip(scene.bodies, scene.q)],
                             [(R - b.radius) * d for b, d in zip(scene.bodies, scene.dq)], law=scene.law, g=scene.g,
                             run=scene.run, frame=scene.frame, forcing=scene.forcing, name="one arc")
    circle, reference = heyroll.simulate(scene, t_end=3.5), heyroll.simulate(arc, t_end=3.5)
    spans = lambda r: [(c["t_start"], c["t_end"]) for c in r.contact_intervals]  # noqa: E731
    assert len(spans(circle)) == len(spans(reference)) >= 2
    assert np.allclose(spans(circle), spans(reference), rtol=0, atol=1e-6)


@pytest.mark.parametrize("precision", ["double", "long", "quad"])
def test_a_cradle_placed_at_the_doubles_nearest_touching_runs_alike_in_every_precision(precision):
    """Five balls on a circle, four at the doubles nearest to touching (gaps of either sign, ~4e-17 rad): in long and
    quad a positive gap beyond the settler's band was a real one, and the pressed stack chattered at k = 1
    every 1e-8 s (max_collisions at t = 3.7e-7 s: review). The start closes gaps within the slack of either
    sign: every precision ends like double, 3 collisions by t = 3 s."""
    with mpmath.workdps(50):
        beta = 2 * mpmath.asin(mpmath.mpf("0.1") / mpmath.mpf("0.9"))
        places = [-1.0, 0.3] + [float(mpmath.mpf("0.3") + j * beta) for j in (1, 2, 3)]
    text = '[track]\ntype = "circle"\nradius = 1.0\n' + "".join(
        f'[[bodies]]\nshape = "solid_sphere"\nradius = 0.1\nmass = 1.0\nphi = {p!r}\ndphi = {v}\n'
        for p, v in zip(places, (3.0, 0, 0, 0, 0)))
    result = heyroll.simulate(parse_scene(text + '[collision]\nlaw = "newton"\nrestitution = 1.0\n[run]\nt_end = 3.0\n'),
                              max_collisions=40, precision=precision)
    assert result.status is Status.COMPLETED and result.n_collisions == 3, result.message


def test_a_slow_zeno_tail_under_newtons_fallback_ends_in_contact_not_in_a_missed_collision():
    """Acceptance test (a point of a sweep): the default scene at phi_1 = -0.80513, k = 0.96667 ends in an
    accumulation of Newton fallback impacts (law_flag 1) at t = 58.609 s whose bounces shrink by 3% each. At
    107 ulps high, heyoka's root finding gave out ("polynomial root finding during event detection failed due
    to too many iterations"), the next collision was missed and the balls passed through each other (status
    overlap at 67.86 s). The tail is now cut at BOUNCE_ULPS: persistent contact, energy kept to the row
    losses."""
    from heyroll.interfaces.scene_file import default_scene_text

    text = default_scene_text().replace("phi = -1.0", "phi = -0.8051282051282051282051282051").replace(
        "restitution = 1.0", "restitution = 0.9666666666666666666666666667")
    result = heyroll.simulate(heyroll.parse_scene(text), t_end=80.0)
    assert result.status.value == "completed", result.message
    assert any(m.clusters == ((1, 2),) for m in result.mode_changes if 58.6 < float(m.t) < 58.62)
    table = result.collision_table()
    losses = float(np.sum(table["energy_before"] - table["energy_after"]))
    assert result.energy_initial - result.energy_final == pytest.approx(losses, rel=1e-9)
