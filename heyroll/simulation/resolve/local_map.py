"""Body-body collisions where the law's map depends on where the bodies touch.

On an arc chain or a curve the gap is the distance between the centres
minus r_i + r_j, and on a curve the metric sigma = |dC/dq| changes along
the track. At each contact the callback reads, in the run's own type (a
compiled function of the state, see :mod:`..contact_function`), the gap's
gradient (g_i, g_j) and the metrics (sigma_i, sigma_j), and applies the
scene's law in its own variables u = c q' with inertias M (paper eqs.
10-11; c = c_1 sigma^p, M = M_1 sigma^p', see :mod:`heyroll.model.laws`):

    u_i+ = u_i - (1 + k) M_j/(M_i + M_j) (u_i - u_j),
    u_j+ = u_j + (1 + k) M_i/(M_i + M_j) (u_i - u_j).

The bodies approach while the gap rate g_i q_i' + g_j q_j' < 0; an outcome
that leaves them approaching takes the scene's policy: ``newton`` resolves
that collision by Newton's law along the gap's gradient with the
generalized masses G = kappa m sigma^2 (impulse P = -(1 + k) rate /
(g_i^2/G_i + g_j^2/G_j), q_k'+ = q_k' + P g_k/G_k), flagged 1; ``error``
stops the run.
"""

from __future__ import annotations

import numpy as np

from ...model._numbers import touching_slack, workprec
from .friction import slipping, slipping_law, slipping_members
from ..contact_function import CONTACT_VALUES, evaluate
from .constraints import cluster_impact
from ..events import (
    BOUNCE_ULPS, OPEN_ULPS, RESOLUTION_ULPS, SEPARATION_ULPS, below_resolution, close_collision,
    stop_at_max_collisions,
)


def law_constants(scene, body, number):
    """(c_1, M_1, G_1) of a body in the run's type: c = c_1 sigma^p, M = M_1 sigma^p', G = G_1 sigma^2."""
    with workprec():  # mpmath's global precision may be lower than the run's type
        v = scene.law.variables(body, 1)
        return number(v.scale), number(v.inertia), number(body.kappa * body.mass)


def make_local_callback(scene, system, number, log, holder, time_scale, function, settle=None):
    """The collision callback of watched contact ``number``; ``resolve(s, t, pars)`` applies the law alone."""
    contact = system.contacts[number]
    pair = contact.pair
    a, b = system.state_index(pair.i), system.state_index(pair.j)
    nu = system.n_coordinates
    # A member of a cluster (or of a unit resting on a limiter) is hit: constraints.cluster_impact,
    # or, where a contact of the cluster would pull, the law on the pair alone, then the unit is
    # released and its contacts are looked at again (cascade).
    held = [pair.i, pair.j] if any(system.units[u].is_cluster or system.units[u].pinned
                                   for u in (contact.unit_a, contact.unit_b)) else None
    num = system.precision.number
    law = scene.law
    rough = bool(system.friction_blocks)
    ci1, Mi1, Gi1 = law_constants(scene, scene.bodies[pair.i], num)
    cj1, Mj1, Gj1 = law_constants(scene, scene.bodies[pair.j], num)
    ps, pm = law.scale_power, law.inertia_power
    with workprec():
        one_k = num(1 + law.restitution)
    k = float(law.restitution)
    law_k = num(law.restitution)
    eps = system.precision.epsilon
    tiny = SEPARATION_ULPS * eps
    strict = scene.on_inconsistent == "error"
    base = CONTACT_VALUES * number
    stop = log.stop
    limit = log.max_collisions
    records = log.records

    if system.precision.name == "double":
        # The hot path: one output buffer, the parameter view sliced once (measured: the call
        # itself is most of the ~4 us a compiled-function evaluation costs from Python).
        buffer = np.empty(function.nouts)
        npar = function.nparams
        timed = function.is_time_dependent  # a forced system: the gap's acceleration depends on t

        def values(s, pars, t=0.0):
            if timed:
                function(s, pars=pars[:npar], outputs=buffer, time=t)
            elif npar:
                function(s, pars=pars[:npar], outputs=buffer)
            else:
                function(s, outputs=buffer)
            return buffer[base:base + CONTACT_VALUES].tolist()
    else:
        def values(s, pars, t=0.0):
            return evaluate(function, s, pars, t)[base:base + CONTACT_VALUES].tolist()

    seen: list = []  # what resolve saw: gap'', gradient, metrics and rates before the collision
    # Friction modes and forcing change the accelerations at the collision: no bound from before it.
    varying = bool(system.friction_blocks) or system.strobe_expression is not None
    # below_resolution holds only if v^2 <= 2 A h_res or v <= A (1 - k) t_res / 2 (see on_collision).
    h_bound = 2 * BOUNCE_ULPS * eps
    t_bound = (1 - k) * RESOLUTION_ULPS * eps / 2
    d = scene.bodies[pair.i].radius + scene.bodies[pair.j].radius
    length = max(float(hi - lo) for lo, hi in (scene.track.domain(body) for body in scene.bodies))
    curvature_scale = float(d) if d > 0 else length / 1000

    def resolve(s, t, pars) -> bool:
        _gap, gi, gj, si, sj, acc, _jerk = values(s, pars, t)
        vi, vj = s[nu + a], s[nu + b]
        seen[:] = (float(acc), gi, gj, float(si), float(sj), float(vi), float(vj))
        if held is not None:
            # A cluster or a unit on a stop takes part: rigid through the impact if its contacts push.
            slips = slipping_members(holder, system.units[contact.unit_a].members  # (in either unit)
                                     + system.units[contact.unit_b].members, scene) if rough else ()
            rates = cluster_impact(system, s, pars, contact, (gi, gj), gi * vi + gj * vj, law_k, slips)
            if rates is not None:
                before = s.tolist()
                for body, rate in rates.items():
                    s[nu + body] = rate
                records.append((t, contact.pair_index, before, None, s.tolist(), 2))
                if limit is not None and log.count >= limit:
                    return stop_at_max_collisions(stop, limit)
                return not log.events_exhausted()
        if rough and (slipping(holder, pair.i, scene) or slipping(holder, pair.j, scene)):
            # a rolling body that slips: Newton's law with kappa_eff m sigma^2 (resolve.friction.slipping_law)
            _law, bi, bj = slipping_law(scene, pair.i, pair.j, slipping(holder, pair.i, scene),
                                        slipping(holder, pair.j, scene))
            with workprec():
                Mi, Mj = num(bi.kappa * bi.mass) * si * si, num(bj.kappa * bj.mass) * sj * sj
            ci = cj = num(1)
            law_flag = 3
        else:
            ci = ci1 * si**ps if ps else ci1
            cj = cj1 * sj**ps if ps else cj1
            Mi = Mi1 * si**pm if pm else Mi1
            Mj = Mj1 * sj**pm if pm else Mj1
            law_flag = 0
        du = ci * vi - cj * vj
        total = Mi + Mj
        vi_new = vi - one_k * Mj / total * du / ci
        vj_new = vj + one_k * Mi / total * du / cj
        closing = gi * vi + gj * vj
        flag = law_flag
        if gi * vi_new + gj * vj_new < -tiny * abs(closing):
            if strict:
                records.append((t, contact.pair_index, s.tolist(), vi_new, vj_new, 0))
                s[nu + a], s[nu + b] = vi_new, vj_new
                stop.reason = "inconsistent"
                stop.message = (
                    f"collision {log.count} at t = {float(t):.17g}: bodies {pair.i + 1} and {pair.j + 1} still "
                    f"approach after the '{law.name}' law (gap rate {float(closing):.3g} -> "
                    f"{float(gi * vi_new + gj * vj_new):.3g} m/s): the outcome would make them overlap; "
                    "stopped (collision.on_inconsistent = 'error')"
                )
                return False
            Gi, Gj = Gi1 * si * si, Gj1 * sj * sj
            if law_flag == 3:  # a slipping body's translational mass (its kappa_eff = 1)
                Gi, Gj = Mi, Mj
            impulse = -one_k * closing / (gi * gi / Gi + gj * gj / Gj)
            vi_new, vj_new = vi + impulse * gi / Gi, vj + impulse * gj / Gj
            flag = 1
            log.fallbacks += 1
        records.append((t, contact.pair_index, s.tolist(), vi_new, vj_new, flag))
        s[nu + a], s[nu + b] = vi_new, vj_new
        if limit is not None and log.count >= limit:
            return stop_at_max_collisions(stop, limit)
        if log.events_exhausted():
            return False
        if held is not None:
            stop.reason, stop.data = "release", {"bodies": tuple(held)}
            return False
        return True

    def on_collision(ta, d_sgn):
        s, pars = holder[0], holder[1]
        t = ta.time
        if not resolve(s, t, pars):
            return False
        _sync_friction(holder, s, t)
        if settle is not None and not settle(s, t, (a, b), number):
            return False
        # Persistent contact: bounces left below the run's resolution while pressed together.
        # Only a slow separation can qualify (v^2 <= 2 A h_res or v <= A (1 - k) t_res / 2): test
        # that first with a generous bound A on |gap''| (the one before the collision plus the
        # velocity terms over the contact's curvature scale; too small a bound only delays the
        # contact by a bounce), then judge with the gap's actual acceleration and jerk.
        acc0, gi, gj, si, sj, vi0, vj0 = seen
        vi, vj = s[nu + a], s[nu + b]
        # Positions do not change in a collision: nor the gradient. The paper's law acts on the
        # speeds along the track, so the opening is not -k times the closing; which of the two the
        # bounces are judged by, judged_opening says (k times the closing is a lower bound of it).
        closing = abs(float(gi) * vi0 + float(gj) * vj0)
        bounce = k * closing
        opening = min(float(gi * vi + gj * vj), bounce)
        vi, vj = float(vi), float(vj)
        bound = 8 * (abs(acc0) + (vi0 * vi0 + vj0 * vj0 + vi * vi + vj * vj) * (si * si + sj * sj) / curvature_scale)
        scale = 1 + abs(float(s[a])) + abs(float(s[b]))
        if not varying and opening * opening > bound * h_bound * scale and \
                opening > bound * t_bound * (abs(float(t)) + time_scale):
            return close_collision(log, number, False)
        _gap, gi, gj, _si, _sj, acc, jerk = values(s, pars, t)
        opening = judged_opening(float(gi * s[nu + a] + gj * s[nu + b]), closing, k, float(acc), curvature_scale)
        return close_collision(log, number,
                               below_resolution(opening, float(acc), k, float(t), scale, time_scale, eps, float(jerk)))

    on_collision.resolve = resolve
    return on_collision


#: A residual opening is chatter (judged_opening) if it is at least this fraction of the approach (its bounces
#: do not die out: measured 0.999 on a curve, against 0.4-0.6 and 0.92 for pairs the law sends apart) ...
CHATTER_RATIO = 0.9
#: ... and its bounce rises less than this fraction of the pair's size (r_i + r_j): measured 6e-9 on the
#: curve, against 11 for the 0.92 separation (review).
CHATTER_HEIGHT = 1e-6


def judged_opening(actual: float, closing: float, k: float, acc: float, size: float) -> float:
    """The gap's opening rate after a collision by which its bounces are judged (persistent contact or not).

    The paper's law acts on the rates along the track (eqs. 8-11), so where the track curves between the
    contact points, or the radii differ, the gap's outgoing rate ``actual`` is not k times the incoming
    ``closing``. Mostly that is the law's outcome and is resolved as it is: judged by k times the closing
    (0 at k = 0), a ring that the law sends ahead of a disk after a plastic collision was glued at once,
    while the same collision on the circle separated (review; also a sphere and a ring sent apart at 0.92
    of their approach, review of this stop). But the curvature leaves a residual on a pair moving on pressed
    together, set by their common motion, not by the closing: it opens at about the rate it closed, each
    bounce tiny (9.4e-7 m/s after every plastic collision on a curve, bounces of 4 us that never died out,
    then a missed one). Such a bounce (opening at CHATTER_RATIO of the closing or more, rising less than
    CHATTER_HEIGHT of ``size``, the gap's acceleration ``acc`` closing it) is judged as the law's own, k
    times the closing. The test is local to the pair (a first try compared the flight with the whole
    track's time scale: straight ends never reached glued real bounces; review).
    """
    if actual <= k * closing or actual < CHATTER_RATIO * closing or not acc < 0 \
            or actual * actual > -2 * acc * CHATTER_HEIGHT * size:
        return actual
    return k * closing


def local_settler(scene, system, resolvers, log, holder, time_scale, function):
    """``settle(s, t, units, skip_open=None, skip_merge=())``: pairs touching at one instant.

    As :func:`heyroll.simulation.events.contact_settler`, with the gap, its
    rate and acceleration read from the compiled contact function: a closing
    pair collides now (and its neighbours are looked at again), a pressed
    pair whose bounces are below resolution enters persistent contact
    (``stop.reason = "merge"``), any other touching pair has its gap opened
    by 2 OPEN_ULPS ulps by moving the second body along its coordinate
    (heyoka misses a root of an event function that starts a step at 0).
    """
    nu = system.n_coordinates
    eps = system.precision.epsilon
    k = float(scene.law.restitution)
    stop = log.stop
    by_unit: dict[int, list[int]] = {}
    where = []  # each contact's two places in the state
    domains = []  # each contact's second body's track ends (None: none)
    for number, c in enumerate(system.contacts):
        a, b = system.state_index(c.pair.i), system.state_index(c.pair.j)
        where.append((a, b))
        domains.append(scene.domain(c.pair.j))
        by_unit.setdefault(a, []).append(number)
        by_unit.setdefault(b, []).append(number)
    max_rounds = 64 * system.n_bodies
    # each place in the state -> the places of its cluster's members: a collision with a member moves them all,
    # and their other contacts are looked at again too (a cluster hit from one side ran on into a body touching
    # its other side at that instant, unseen: status overlap, acceptance test)
    together: dict[int, list[int]] = {}
    for unit in system.units:
        places = [system.state_index(m) for m in unit.members]
        for place in places:
            together[place] = places

    def values(s, number, t=0.0):
        base = CONTACT_VALUES * number
        return evaluate(function, s, holder[1], t)[base:base + CONTACT_VALUES].tolist()

    def touching_elsewhere(s) -> list:
        """Every pair whose gap is within resolution (one evaluation for all): disjoint pairs of a
        symmetric scene collide at one instant, and the other pair's event cannot fire from 0."""
        values = evaluate(function, s, holder[1]).tolist()
        out = []
        for number, (a, b) in enumerate(where):
            gap = float(values[CONTACT_VALUES * number])
            if abs(gap) <= RESOLUTION_ULPS * eps * (1 + abs(float(s[a])) + abs(float(s[b]))):
                out += [a, b]
        return out

    def settle(s, t, units, skip_open=None, skip_merge=()) -> bool:
        if function is None:
            return True
        after_collision = len(units) <= 2  # (the mode's start looks at every body)
        pending = list(dict.fromkeys(p for u in units for p in together.get(u, [u])))
        if len(where) > 2 and after_collision:
            pending += [u for u in touching_elsewhere(s) if u not in pending]
        seen, rounds = set(pending), 0
        while pending:
            unit = pending.pop()
            for number in by_unit.get(unit, ()):
                a, b = where[number]
                gap, gi, gj, _si, _sj, acc, jerk = values(s, number, t)
                scale = 1 + abs(float(s[a])) + abs(float(s[b]))
                if abs(float(gap)) > RESOLUTION_ULPS * eps * scale:
                    continue
                va, vb = s[nu + a], s[nu + b]
                rate = gi * va + gj * vb
                if rate < -SEPARATION_ULPS * eps * (abs(gi * va) + abs(gj * vb)):
                    if rounds >= max_rounds:
                        stop.reason, stop.data = "merge", {"contact": number}
                        return False
                    rounds += 1
                    if not resolvers[number](s, t, holder[1]):
                        return False
                    _sync_friction(holder, s, t)
                    moved = together.get(a, [a]) + together.get(b, [b])
                    pending += moved
                    seen.update(moved)
                    continue
                if number not in skip_merge and below_resolution(
                        max(float(rate), 0.0), float(acc), k, float(t), scale, time_scale, eps, float(jerk)):
                    stop.reason, stop.data = "merge", {"contact": number}
                    return False
        for number in sorted({n for unit in seen for n in by_unit.get(unit, ())}):
            if number == skip_open:
                continue
            a, b = where[number]
            gap, gi, gj = values(s, number)[:3]
            scale = 1 + abs(float(s[a])) + abs(float(s[b]))
            target = OPEN_ULPS * eps * scale
            if abs(float(gap)) <= target and float(gj) > 0:
                moved = s[b] + (2 * target - gap) / gj
                end = domains[number]
                if end is not None and float(gi) < 0 and float(moved) >= end[1] - target:
                    # the second body sits at the track's upper stop (it has just rebounded there): the first
                    # one steps back instead (moved past the stop, its bound event never fired and it ran off
                    # the track: review)
                    s[a] = s[a] + (2 * target - gap) / gi
                else:
                    s[b] = moved
        return True

    def close_start(s) -> None:
        """As the circle's (events.contact_settler): pairs that start touching to within the scene's slack
        (model.touching_slack, of the centres' coordinates, as the scene checks it: scaled by the track
        coordinates, a bowl of radius 100 m accepted 1e-14 m and ended overlap, review) but beyond the
        settler's band are moved to touching in the run's type (Newton steps on the second body's coordinate)."""
        if function is None:
            return
        for number, (a, b) in enumerate(where):
            pair = system.contacts[number].pair
            centres = [float(c) for k, q in ((pair.i, s[a]), (pair.j, s[b]))
                       for c in scene.track.centre(scene.bodies[k], float(q))]
            slack = touching_slack(*centres)
            band = RESOLUTION_ULPS * eps * (1 + abs(float(s[a])) + abs(float(s[b])))
            for _ in range(3):
                gap, _gi, gj = values(s, number)[:3]
                if not (band < abs(float(gap)) <= slack and gj > 0):
                    break
                s[b] = s[b] - gap / gj

    settle.close_start = close_start
    return settle


def _sync_friction(holder, s, t) -> None:
    """Rough tracks: the units' friction modes follow the rates a collision has just set, before the
    contact is judged (resolve.friction.FrictionModes.sync; found by fuzzing: a stuck particle hit
    plastically was judged with its zero acceleration, the pair let open, its next collision unseen)."""
    modes = holder[2] if len(holder) > 2 else None
    if modes is not None:
        modes.sync(s, t)
