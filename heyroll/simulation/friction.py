"""Coulomb friction on a rough track (paper section 2): sliding, sticking, rolling that slips.

A scene with ``track_friction = mu`` (and ``static_friction = mu_s >= mu``)
models friction on the one engine. Each unit of the system (a free body, or
bodies in persistent contact moving together) is in one *friction mode*,
held in runtime parameters of the compiled system, so that a change of mode
is a parameter switch inside an event callback, never a recompilation:

* a particle (and a cluster) is ``sliding+`` / ``sliding-`` (the sign of its rate
  q') or ``stuck`` (q' = 0, held by static friction);
* a rolling body (kappa > 1) is ``rolling`` or ``sliding+`` / ``sliding-`` (the sign
  of its slip velocity w = v_C - u, u = r omega_P the speed its spin would roll at).

Per unit mass, with T the tangential driving force (gravity, the frame's
centrifugal force, forcing; :class:`heyroll.model.tracks.BodyTerms`), sigma = |dC/dq|
and N the magnitude of the track's reaction:

* sliding particle: q'' = a_smooth - s mu N / sigma  (the generalized friction force
  -s mu N sigma over the generalized mass sigma^2);
* stuck: q'' = 0; it stays while |T| <= mu_s N (summed over a cluster's members,
  weighted by m sigma: generalized forces), and restarts where the load reaches
  mu_s N, in its direction;
* rolling body, rolling: the rolling equation (kappa); it needs the friction
  F = (1 - 1/kappa) T and slips where |F| reaches mu_s N;
* rolling body, slipping: the centre moves as a particle (kappa = 1) with the
  friction -s mu N, and the spin takes the friction's moment: m (kappa - 1) u' = s mu m N
  (from the energy balance d/dt[m v^2/2 + m (kappa - 1) u^2/2] = F (v - u), whatever the
  track's curvature), so the slip obeys w' = T - s mu N kappa / (kappa - 1). Where w
  returns to 0 it rolls again if |F| <= mu_s N, else it slips the other way.
* a rolling member of a cluster (bodies in persistent contact) has a block of its own:
  it rolls or slips as a free rolling body does, with its cluster's contact forces
  in its centre's acceleration; slipping, its inertia in the cluster is m sigma^2
  (:func:`member_slip_terms`).

N: in a fixed plane the in-plane reaction N_in (BodyTerms.normal); on a
two-sided track its magnitude, the side it pushes from switched by an event where
N_in changes sign; in a plane turning at Omega also the reaction normal to the
plane that balances the Coriolis force, 2 m Omega x_C': N = sqrt(N_in^2 + (2 Omega x_C')^2).

Every change of mode is an event located by heyoka to the integration's
precision (a turning point is the root of q', never a threshold on a small
velocity); the callbacks are in :mod:`heyroll.simulation.resolve.friction`.
"""

from __future__ import annotations

from dataclasses import dataclass

import heyoka as hy
import mpmath

from ..model._numbers import workprec

MODES = ("rolling", "sliding+", "sliding-", "stuck")


@dataclass(frozen=True)
class FrictionBlock:
    """The friction mode of one unit, as parameter and state indices of a system.

    ``rolls``: a rolling body, free or a member of a cluster (modes rolling / sliding+ /
    sliding-, slip state ``slip``); otherwise a particle or a cluster (sliding+ / sliding- / stuck). The
    unit's rate is the state's entry ``rate`` (its first member's).
    """

    unit: int
    members: tuple
    rate: int
    rolls: bool
    stuck: int
    sign: int
    rolling: int = -1
    side: int = -1
    slip: int = -1
    #: State index of the work friction has dissipated in this contact mode (J).
    work: int = -1
    #: A rolling member's own block inside a cluster (it rolls or slips while its cluster's block
    #: slides or sticks; ``stuck`` is the cluster's parameter).
    within: bool = False


@dataclass(frozen=True)
class MemberSlip:
    """A rolling member of a cluster with a friction block of its own (build_friction's ``within``): its
    block's index, the body, its slip variable, its rolling and sign parameters (expressions), N per unit
    mass, its rolling terms, and ``friction``, the generalized force -s mu m N sigma its kinetic friction
    exerts while it slips."""

    block: int
    body: int
    slip: object
    rolling: object
    sign: object
    normal: object
    terms: object
    friction: object


@dataclass(frozen=True)
class FrictionEvent:
    """A friction event of block ``block``: turn, release+, release-, slip+, slip-, reroll, normal."""

    block: int
    kind: str


def slides(body) -> bool:
    """A particle (kappa = 1) slides; any other body rolls (and may slip)."""
    return body.kappa == 1


def normal_magnitude(scene, term, q, v, side, par):
    """N per unit mass: see the module doc (``side`` is the two-sided track's parameter, or None;
    ``q`` the state variable the centre's position depends on)."""
    if scene.frame.rotating:
        with workprec():
            four_omega2 = 4 * scene.frame.omega**2
        coriolis = hy.diff(term.x_c, q) * v  # x_C', the horizontal velocity in the plane
        return hy.sqrt(term.normal * term.normal + par(four_omega2) * coriolis * coriolis)
    return term.normal if side is None else side * term.normal


def build_friction(scene, units, per_body, terms, slide_terms, q_of, v_of, par, slip_vars):
    """The friction of every unit: (blocks, accelerations by body, slip equations, cluster sums).

    ``terms[k]``: body k's BodyTerms (rolling, forcing included); ``slide_terms(k)``: the same
    with kappa = 1 (a rolling body's centre while it slips); ``q_of(k)``, ``v_of(k)``: the
    expressions of body k's coordinate and rate; ``slip_vars``: a new state variable per
    rolling free body, in unit order. (``q_of(k)`` is the state variable body k's position depends
    on: a cluster member's position is psi + o.) Returns
    ``(blocks, body_acc, slip_equations, unit_sums, values, work, within)`` with ``body_acc[k]`` body k's
    q'' with friction (free units and per-body clusters), ``unit_sums[u]`` = ({member: its
    generalized friction force -s mu m N sigma}, the stuck parameter) of a cluster on the circle, ``values`` per block
    [load, static capacity, sigma of the first member] as expressions (the callbacks' decisions).

    Each rolling member of a cluster has a block of its own (``within``): it rolls or slips inside its
    cluster. Its slip equation, its load and its inertia in the cluster's motion depend on the contact
    forces, which the system solves after: ``within`` lists them (:class:`MemberSlip`); their slip
    equations and loads are None here (:func:`member_slip_terms`).
    """
    mu = scene.track_friction
    mu_s = scene.static_coefficient
    two_sided_fixed = scene.track_sides == "two" and not scene.frame.rotating
    blocks, body_acc, slip_eqs, unit_sums, values, work, within = [], {}, [], {}, [], [], []
    slips = iter(slip_vars)
    for u, unit in enumerate(units):
        members = unit.members
        first = members[0]
        rolls = len(members) == 1 and not slides(scene.bodies[first])
        stuck_i = _new_par(par, 0)
        sign_i = _new_par(par, 1)
        rolling_i = _new_par(par, 1) if rolls else -1
        side_i = _new_par(par, 1) if two_sided_fixed else -1
        stuck, sign = hy.par[stuck_i], hy.par[sign_i]
        side = hy.par[side_i] if side_i >= 0 else None
        normals = {k: normal_magnitude(scene, terms[k], q_of(k), v_of(k), side, par) for k in members}
        if rolls:
            k = first
            body = scene.bodies[k]
            t_roll, t_slide = terms[k], slide_terms(k)
            rolling = hy.par[rolling_i]
            n_mag = normals[k]
            with workprec():
                share = 1 - 1 / body.kappa
                boost = body.kappa / (body.kappa - 1)
            need = par(share) * t_roll.driving
            sliding_acc = t_slide.acceleration - sign * par(mu) * n_mag / t_slide.sigma
            body_acc[k] = rolling * t_roll.acceleration + (1 - rolling) * sliding_acc
            w = next(slips)
            if unit.pinned:
                # resting on a stop, its centre held (q' = 0): at rest it needs no friction, and slipping its spin
                # runs down, w' = -u' = -s mu N / (kappa - 1) (review: the free body's w' made its slip grow, +51 J)
                need = par(0)
                slip_eqs.append((w, (1 - rolling) * (-sign * par(mu / (body.kappa - 1)) * n_mag)))
            else:
                slip_eqs.append((w, (1 - rolling) * (t_slide.driving - sign * par(mu * boost) * n_mag)))
            # The power friction takes: mu m N |w| while slipping (s w = |w|).
            work.append((1 - rolling) * sign * par(mu * body.mass) * n_mag * w)
            blocks.append(FrictionBlock(unit=u, members=members, rate=-1, rolls=True, stuck=stuck_i, sign=sign_i,
                                        rolling=rolling_i, side=side_i, slip=-1))
            values.append([need, par(mu_s) * n_mag, t_roll.sigma, t_roll.normal])
            continue
        # Particles, and clusters: the members share the mode. Rolling members of a cluster roll
        # (their friction is internal to rolling); the particles' friction acts on the cluster.
        loads, capacity, member_friction, power = [], [], {}, []
        own = len(members) > 1  # rolling members with blocks of their own (below)
        for k in members:
            body = scene.bodies[k]
            weight = par(body.mass) * terms[k].sigma  # generalized forces: force x sigma
            loads.append(weight * terms[k].driving)
            if slides(body):
                capacity.append(weight * normals[k])
                member_friction[k] = -sign * par(mu * body.mass) * normals[k] * terms[k].sigma
                power.append(-member_friction[k] * v_of(k))  # mu m N sigma |q'| (s q' = |q'|)
                if per_body or len(members) == 1:
                    body_acc[k] = (1 - stuck) * (terms[k].acceleration - sign * par(mu) * normals[k] / terms[k].sigma)
            elif (per_body or len(members) == 1) and not own:
                body_acc[k] = (1 - stuck) * terms[k].acceleration
        if len(members) > 1 and not per_body:
            unit_sums[u] = (member_friction, stuck)
        blocks.append(FrictionBlock(unit=u, members=members, rate=-1, rolls=False, stuck=stuck_i, sign=sign_i,
                                    side=side_i))
        work.append((1 - stuck) * (hy.sum(power) if len(power) > 1 else power[0]) if power else par(0))
        values.append([hy.sum(loads) if len(loads) > 1 else loads[0],
                       par(mu_s) * (hy.sum(capacity) if len(capacity) > 1 else capacity[0]) if capacity else par(0),
                       terms[first].sigma, terms[first].normal])
        if not own:
            continue
        cluster_block, slip_forces = len(blocks) - 1, []
        for k in members:
            body = scene.bodies[k]
            if slides(body):
                continue
            # A rolling member: rolling (its rolling equation, inertia kappa m) or slipping (its centre a
            # particle's with the friction -s mu N, inertia m; its spin takes the friction's moment)
            rolling_k, sign_k = _new_par(par, 1), _new_par(par, 1)
            rolling, s_k = hy.par[rolling_k], hy.par[sign_k]
            t_roll, t_slide = terms[k], slide_terms(k)
            n_mag = normals[k]
            sliding_acc = t_slide.acceleration - s_k * par(mu) * n_mag / t_slide.sigma
            body_acc[k] = (1 - stuck) * (rolling * t_roll.acceleration + (1 - rolling) * sliding_acc)
            w = next(slips)
            slip_eqs.append((w, None))
            work.append((1 - rolling) * s_k * par(mu * body.mass) * n_mag * w)
            # slipping, its kinetic friction -s mu m N acts on the cluster: part of the load static friction holds
            # when the cluster is at rest (review: left out, a stuck cluster turned uphill against its mode)
            member = MemberSlip(block=len(blocks), body=k, slip=w, rolling=rolling, sign=s_k, normal=n_mag,
                                terms=t_roll, friction=-s_k * par(mu * body.mass) * n_mag * t_roll.sigma)
            slip_forces.append((1 - rolling) * member.friction)
            within.append(member)
            blocks.append(FrictionBlock(unit=u, members=(k,), rate=-1, rolls=True, stuck=stuck_i, sign=sign_k,
                                        rolling=rolling_k, side=-1, slip=-1, within=True))
            values.append([None, par(mu_s) * n_mag, t_roll.sigma, t_roll.normal])
        if slip_forces:
            values[cluster_block][0] = hy.sum([values[cluster_block][0]] + slip_forces)
    return blocks, body_acc, slip_eqs, unit_sums, values, work, within


def member_slip_terms(scene, member, acceleration, rolling_acceleration, q, v, par):
    """A rolling member's slip equation, the friction its rolling needs now (for its slip events) and
    the friction it would need rolling (for the callbacks' decisions), from its cluster's contact forces.

    ``member``: a :class:`MemberSlip`; ``acceleration``: its q'' with the contact forces
    (the mode's); ``rolling_acceleration``: the same with this member rolling; ``q``, ``v``: the state
    variables its position and rate are. Rolling, kappa m v_C' = m T + F_c, so the friction is
    F = (1 - 1/kappa)(m T + F_c) = (kappa - 1) m v_C', v_C' = sigma q'' + sigma_q q'^2 its centre's tangential
    acceleration; slipping, the spin's u' = s mu N / (kappa - 1) and w' = v_C' - u'.
    """
    w, rolling, sign, n_mag = member.slip, member.rolling, member.sign, member.normal
    kappa = scene.bodies[member.body].kappa
    sigma = member.terms.sigma
    spread = hy.diff(sigma, q) * v * v
    with workprec():
        spin = 1 / (kappa - 1)
        grip = kappa - 1
    slip_eq = (1 - rolling) * (sigma * acceleration + spread - sign * par(scene.track_friction * spin) * n_mag)
    need_now = par(grip) * (sigma * acceleration + spread)
    need_rolling = par(grip) * (sigma * rolling_acceleration + spread)
    return (w, slip_eq), need_now, need_rolling


def _new_par(par, value) -> int:
    """A new runtime parameter (a mode switch), its index."""
    expr = par(mpmath.mpf(value))
    return int(str(expr)[1:])


def friction_events(scene, blocks, values, rate_of, slip_of, normal_of, loads=None):
    """(events, expressions) of the blocks, gated by their mode parameters (see the module doc):
    an expression that is the constant 1 outside its mode has no root there. ``loads``: per block, the
    load its events watch where it is not the callbacks' (a rolling member of a cluster: the friction it
    needs in the mode's own contact forces)."""
    events, exprs = [], []
    for b, block in enumerate(blocks):
        load, capacity = values[b][:2]
        if loads and b in loads:
            load = loads[b]
        if block.rolls:
            rolling = hy.par[block.rolling]
            events += [FrictionEvent(b, "slip+"), FrictionEvent(b, "slip-"), FrictionEvent(b, "reroll")]
            slip_margins = [rolling * (capacity - load) + (1 - rolling), rolling * (capacity + load) + (1 - rolling)]
            if block.within:  # a stuck cluster holds its members (its own release events watch the load)
                stuck = hy.par[block.stuck]
                slip_margins = [(1 - stuck) * m + stuck for m in slip_margins]
            exprs += slip_margins + [slip_of(b) + rolling]
        else:
            stuck = hy.par[block.stuck]
            events += [FrictionEvent(b, "turn"), FrictionEvent(b, "release+"), FrictionEvent(b, "release-")]
            exprs += [rate_of(block) + stuck,
                      stuck * (capacity - load) + (1 - stuck),
                      stuck * (capacity + load) + (1 - stuck)]
        if block.side >= 0:
            events.append(FrictionEvent(b, "normal"))
            exprs.append(normal_of(block))
    return events, exprs


def forcing_terms(scene, k, term, q, kappa, dyn_par):
    """``term`` with the scene's forcing added (see :mod:`heyroll.model.forcing`), or ``term``."""
    forcing = scene.forcing
    if forcing is None or not forcing.forces(k):
        return term
    import dataclasses

    body = scene.bodies[k]
    wave = hy.cos(dyn_par(forcing.frequency) * hy.time + dyn_par(forcing.phase))
    dx, dy = hy.diff(term.x_c, q), hy.diff(term.y_c, q)
    sigma = term.sigma
    if forcing.kind == "force":
        tangential = dyn_par(forcing.amplitude / body.mass) * wave
        return dataclasses.replace(term, driving=term.driving + tangential,
                                   acceleration=term.acceleration + dyn_par(1 / kappa) * tangential / sigma)
    with workprec():
        reach = forcing.amplitude * forcing.frequency**2
        ax, ay = reach * mpmath.cos(forcing.direction), reach * mpmath.sin(forcing.direction)
    along = (dyn_par(ax) * dx + dyn_par(ay) * dy) * wave  # inertial force . dC/dq
    across = (dyn_par(ax) * dy - dyn_par(ay) * dx) * wave
    return dataclasses.replace(term, driving=term.driving + along / sigma, normal=term.normal + across / sigma,
                               acceleration=term.acceleration + dyn_par(1 / kappa) * along / (sigma * sigma))
