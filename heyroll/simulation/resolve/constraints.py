"""Persistent contact where the gap is not linear: clusters as holonomic constraints.

On an arc chain or a curve, bodies pressed together (their bounces below the
run's resolution, see :func:`heyroll.simulation.events.below_resolution`)
form a cluster whose contacts keep g_l = |C_i - C_j| - r_i - r_j = 0; the
system integrates the constrained motion with the contact forces as Lagrange
multipliers (:func:`heyroll.simulation.system._constrained_accelerations`) and
a cluster splits by an event where a contact force would pull. A unit resting
on a limiter is pinned there (q' = 0) until the track's forces pull it away.

This module puts the state on the constraints as a mode starts, in the run's
own number type: positions first (the later member of each contact moves
along its coordinate until g_l = 0), then rates by a plastic impulse on every
contact at once (the tridiagonal system of the contacts' inverse masses),
which keeps the generalized momentum along the constraints, as the circle's
rigid clusters do (:func:`heyroll.simulation.driver._merge`). Pinned units
stop (q' = 0): a stop absorbs the plastic impact.
"""

from __future__ import annotations

from ..contact_function import BODY_VALUES, body_function, evaluate, link_function
from ..system import link_bodies

#: Newton steps on the positions (the gaps start within a few ulps of 0).
POSITION_PASSES = 3


def project_onto_contacts(system, state: list, pars, friction=None) -> list:
    """The state with every cluster's contacts closed (g = 0, g' = 0) and pinned units at rest.

    ``friction``: the run's FrictionState on a rough track: a member that slips takes the plastic
    impulse with its translational mass, and its slip w = sigma q' - u changes by sigma times its
    rate's jump (its spin u unchanged)."""
    s = list(state)
    n = system.n_bodies
    slipping = friction.slipping() if friction is not None else {}
    for unit in system.units:
        if unit.pinned:
            for k in unit.members:
                s[n + k] = s[n + k] * 0
    links = link_function(system)
    if links is None:
        return s
    per_link = 3
    for _ in range(POSITION_PASSES):
        for number, link in enumerate(system.links):
            i, j = link_bodies(system, link)
            gap, _gi, gj = evaluate(links, s, pars)[per_link * number: per_link * number + 3].tolist()
            s[j] = s[j] - gap / gj
    values = evaluate(links, s, pars).tolist()
    bodies = evaluate(body_function(system), s, pars).tolist()
    for u, unit in enumerate(system.units):
        numbers = [m for m, link in enumerate(system.links) if link.unit == u]
        if not numbers or unit.pinned:
            continue
        members = unit.members
        M = [_mass(system, k, slipping) * bodies[BODY_VALUES * k + 3] ** 2 for k in members]
        grads = [(values[per_link * m + 1], values[per_link * m + 2]) for m in numbers]
        rates = [gi * s[n + i] + gj * s[n + j] for (gi, gj), (i, j) in zip(grads, zip(members, members[1:]))]
        impulses = _tridiagonal(grads, M, [-r for r in rates], inverse=False)
        for p, k in enumerate(members):
            jump = _push(impulses, grads, p) / M[p]
            s[n + k] = s[n + k] + jump
            if k in slipping:
                friction.slips[k] = friction.slips[k] + bodies[BODY_VALUES * k + 3] * jump
    return s


def _mass(system, k, slipping):
    """Body k's mass in an impulse: kappa m rolling, m slipping (``slipping``: body -> kappa; its spin
    untouched), in the run's type."""
    return system.precision.number(system.rolling_mass[k] / slipping[k] if k in slipping else system.rolling_mass[k])


def cluster_impact(system, s, pars, contact, grad, closing, restitution, slipping=()):
    """A body or cluster hits a cluster, or a unit resting on a stop: Newton's law on the gap rate
    with the clusters kept rigid through the impact (flag 2, as on the circle).

    The bodies of the two units form a chain of contacts (the clusters' links and
    the colliding contact). Impulses P_l along the contacts' gap gradients, with
    the inverse generalized masses 1/M_k (0 for a unit on a stop: the stop takes
    the impulse), leave every link's rate at 0 and turn the contact's closing
    rate c into -k c: one tridiagonal system. Returns the new rates of the
    chain's bodies {k: q_k'}, or None where a link would have to pull (a negative
    impulse): the impact does not move the cluster rigidly, and the caller
    releases it (its contacts are then resolved one by one).
    """
    n = system.n_bodies
    ua, ub = system.units[contact.unit_a], system.units[contact.unit_b]
    if ua.pinned and ub.pinned:
        return None
    links = link_function(system)
    link_values = evaluate(links, s, pars).tolist() if links is not None else []
    bodies = evaluate(body_function(system), s, pars).tolist()
    chain = list(ua.members + ub.members)
    inverse = []
    slip = dict(slipping)  # (body, kappa) of rolling bodies that slip: their translational mass m
    for k in chain:
        pinned = system.units[system.unit_of[k]].pinned
        inverse.append(0 if pinned else 1 / (_mass(system, k, slip) * bodies[BODY_VALUES * k + 3] ** 2))
    grads, rhs = [], []
    for x, y in zip(chain, chain[1:]):
        if (x, y) == (contact.pair.i, contact.pair.j):
            grads.append(tuple(grad))
            rhs.append(-(1 + restitution) * closing)
            continue
        number = next((m for m, link in enumerate(system.links) if link_bodies(system, link) == (x, y)), None)
        if number is None:  # the units do not meet end to end here (no link between x and y: StopIteration, review)
            return None  # the caller releases the cluster: its contacts are resolved one by one
        grads.append(tuple(link_values[3 * number + 1: 3 * number + 3]))
        rhs.append(closing * 0)
    # Links inside a unit on a stop do not move (both inverse masses 0): leave them out.
    keep = [l for l in range(len(grads)) if inverse[l] != 0 or inverse[l + 1] != 0]
    if keep != list(range(keep[0], keep[-1] + 1)):
        return None
    first = keep[0]
    impulses = _tridiagonal(grads[first:keep[-1] + 1], inverse[first:keep[-1] + 2], rhs[first:keep[-1] + 1])
    if any(float(x) < 0 for x in impulses):
        return None
    out = {}
    for p in range(len(impulses) + 1):
        out[chain[first + p]] = s[n + chain[first + p]] + _push(impulses, grads[first:], p) * inverse[first + p]
    return out


def stop_impact(system, s, pars, k, upper: bool, restitution, slipping=()):
    """A member of a cluster hits a stop (a limiter): Newton's law on the gap to the stop with the
    cluster kept rigid through the impact, as when a body hits a cluster (:func:`cluster_impact`).

    The stop is the chain's end with inverse mass 0 (the one-body limit, m -> infinity);
    impulses on the stop's contact and on the cluster's links leave every link's rate at 0 and
    turn member k's closing rate on the stop c into -k c. Returns the new rates of the unit's
    members {m: q_m'}, or None where k is not the cluster's end at that stop or a link would have
    to pull: the caller releases the cluster (its contacts then resolved one by one). Resolving
    them one by one where a plastic cluster is pressed onto a stop is an endless cascade at one
    instant, a factor smaller each round (a forced chain of four on a parametric track: stopped
    after 33 mode changes).
    """
    n = system.n_bodies
    members = list(system.units[system.unit_of[k]].members)
    if k != (members[-1] if upper else members[0]):
        return None
    links = link_function(system)
    if links is None:
        return None
    link_values = evaluate(links, s, pars).tolist()
    bodies = evaluate(body_function(system), s, pars).tolist()
    slip = dict(slipping)  # (body, kappa) of rolling members that slip: their translational mass m
    inverse = [1 / (_mass(system, m, slip) * bodies[BODY_VALUES * m + 3] ** 2) for m in members]
    grads, rhs = [], []
    for x, y in zip(members, members[1:]):
        number = next((m for m, link in enumerate(system.links) if link_bodies(system, link) == (x, y)), None)
        if number is None:
            return None
        grads.append(tuple(link_values[3 * number + 1: 3 * number + 3]))
        rhs.append(s[n + k] * 0)
    one = s[n + k] * 0 + 1
    # the gap to the stop: q_hi - q_k (upper) or q_k - q_lo (lower); the stop's own gradient is moot
    closing = -s[n + k] if upper else s[n + k]
    if upper:
        chain_grads, weights = grads + [(-one, 0 * one)], inverse + [0 * one]
        rhs.append(-(1 + restitution) * closing)
    else:
        chain_grads, weights = [(0 * one, one)] + grads, [0 * one] + inverse
        rhs.insert(0, -(1 + restitution) * closing)
    impulses = _tridiagonal(chain_grads, weights, rhs)
    if any(float(x) < 0 for x in impulses):
        return None
    out = {}
    offset = 0 if upper else 1  # the members' places in the chain
    for p, m in enumerate(members):
        out[m] = s[n + m] + _push(impulses, chain_grads, p + offset) * weights[p + offset]
    return out


def _push(impulses, grads, p):
    """The generalized impulse on the p-th body of a chain of contacts: P_{p-1} dg_{p-1}/dq_p + P_p dg_p/dq_p
    (contact l joins bodies l and l + 1; ``grads[l]`` = (dg_l/dq_l, dg_l/dq_l+1))."""
    push = 0
    if p > 0:
        push = push + impulses[p - 1] * grads[p - 1][1]
    if p < len(impulses):
        push = push + impulses[p] * grads[p][0]
    return push


def _tridiagonal(grads, M, rhs, *, inverse=True) -> list:
    """Solve sum_m A_lm x_m = rhs_l, A_lm = sum_k dg_l/dq_k dg_m/dq_k w_k (members k of links l, m).

    ``M``: the members' inverse masses w_k (or their masses, ``inverse=False``).
    """
    w = list(M) if inverse else [1 / m for m in M]
    L = len(grads)
    cp, dp = [None] * L, [None] * L
    for l in range(L):
        diag = grads[l][0] ** 2 * w[l] + grads[l][1] ** 2 * w[l + 1]
        if l == 0:
            den = diag
            dp[l] = rhs[l] / den
        else:
            sub = grads[l][0] * grads[l - 1][1] * w[l]
            den = diag - sub * cp[l - 1]
            dp[l] = (rhs[l] - sub * dp[l - 1]) / den
        if l < L - 1:
            cp[l] = grads[l][1] * grads[l + 1][0] * w[l + 1] / den
    x = [None] * L
    x[L - 1] = dp[L - 1]
    for l in range(L - 2, -1, -1):
        x[l] = dp[l] - cp[l] * x[l + 1]
    return x
