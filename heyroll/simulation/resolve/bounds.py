"""The ends of a piece of track: junction passages and limiter impacts.

Each body on an open track watches the two ends of the piece it is on
(runtime parameters). At a junction of an arc chain it passes to the next
piece: its piece parameters switch inside the event callback and the
integration goes on, so no Taylor step crosses a jump of curvature. At an
end of the track it hits the limiter, a fixed stop: q' -> -k q' (the
one-body limit of the collision laws, m_2 -> infinity), with k the scene's
``limiter_restitution``. Both are recorded as passages (see
``CollisionLog.passages``).

A body whose rebounds on a stop fall below the run's resolution while the
track pushes it there comes to rest on it (the driver pins its unit, see
:class:`heyroll.simulation.system.Unit`); a cluster whose end member hits a
stop rebounds as one (:func:`.constraints.stop_impact`), or, where that would
need a contact to pull, is released, its contacts then resolved as collisions.

After either the body sits exactly on an event surface, and heyoka misses a
root of an event function that starts a step at 0.0: the new piece's far
bound moves a few ulps out (the piece formulas hold there to the ulp), or
the body moves a few ulps off the stop.
"""

from __future__ import annotations

from ..contact_function import BODY_VALUES, evaluate
from ..events import OPEN_ULPS, below_resolution
from ..system import piece_bounds
from .constraints import stop_impact
from .friction import slipping_members

#: Passage kinds, in the passages table.
PASSAGE_KINDS = ("junction", "limiter_lower", "limiter_upper")


def parameters_on_pieces(scene, system, pieces) -> list:
    """The mode's parameter values with each body's piece block set to the piece it is on now.

    A system is built with the pieces of the scene's start; a new contact mode
    (a merge, a split, a body coming to rest) starts wherever the bodies are.
    """
    params = list(system.parameters)
    num = system.precision.number
    for block in system.piece_blocks:
        body = scene.bodies[block.body]
        lo, hi = piece_bounds(scene.track, body, pieces[block.body])
        params[block.lower], params[block.lower + 1] = num(lo), num(hi)
        values = scene.track.piece_parameters(body, pieces[block.body])
        params[block.first:block.first + len(values)] = [num(v) for v in values]
    return params


def left_track_message(scene, values, k: int, q, dq, t) -> str | None:
    """Why body k cannot stay on a one-sided track (its normal force N < 0, read from the compiled body
    function's ``values``), or None: the run's start and every junction passage ask this."""
    if scene.track_sides != "one" or not float(values[BODY_VALUES * k + 2]) < 0:
        return None
    c = scene.coordinate
    return (f"body {k + 1} cannot stay on the one-sided track: its normal force N < 0 at {c} = {float(q):.17g}, "
            f"d{c} = {float(dq):.17g}, t = {float(t):.17g} s")


def make_bound_callback(scene, system, event, log, holder, pieces, time_scale, function, settle=None):
    """The callback of a piece end; ``pieces[k]`` is the piece body k is on (kept per run); ``settle``: the
    mode's contact settler, for a neighbour touching the body as it rebounds."""
    k = event.body
    body = scene.bodies[k]
    track = scene.track
    block = system.piece_blocks[k]
    u = system.state_index(k)
    nu = system.n_coordinates
    in_cluster = system.units[system.unit_of[k]].is_cluster
    num = system.precision.number
    n_pieces = len(track.junctions(body)) + 1
    bounds = [tuple(num(x) for x in piece_bounds(track, body, p)) for p in range(n_pieces)]
    values = [[num(x) for x in track.piece_parameters(body, p)] for p in range(n_pieces)]
    k_lim = num(scene.limiter_restitution)
    k_float = float(scene.limiter_restitution)
    eps = system.precision.epsilon
    upper = event.end == "upper"
    step = 1 if upper else -1
    stop = log.stop
    # (a cluster's members too: its left_track events watch each member's N as well, review)
    one_sided = scene.track_sides == "one" and function is not None

    def after_junction(ta, s, pars, t) -> bool:
        """The reaction jumps with the curvature at a junction, and the events that watch its sign (a one-sided
        track's left_track, a rough track's side and slip onset) see no root there: judged now, as at a run's
        start (review: a body glued to a hump it should leave; a stale side made friction push a particle on,
        +0.24 J; a rolling disk whose needed friction exceeded mu_s N on the new arc never slipped)."""
        if one_sided:
            values = evaluate(function, s, pars, t)
            message = left_track_message(scene, values, k, s[u], s[nu + u], t)
            if message is not None:
                stop.reason, stop.message = "left_track", message
                return False
        modes = holder[2] if len(holder) > 2 else None
        if modes is not None:
            modes.at_junction(ta, s, t, k)
            return not log.events_exhausted()
        return True

    def on_bound(ta, d_sgn):
        s, pars = holder[0], holder[1]  # pars: the full parameter vector (see driver)
        t = ta.time
        q, v = s[u], s[nu + u]
        margin = OPEN_ULPS * eps * (1 + abs(float(q)))
        piece = pieces[k]
        new = piece + step
        if 0 <= new < n_pieces:
            pieces[k] = new
            lo, hi = bounds[new]
            pars[block.lower] = lo - margin if upper else lo
            pars[block.lower + 1] = hi if upper else hi + margin
            pars[block.first:block.first + len(values[new])] = values[new]
            kept = ta.pars  # heyoka keeps the parameters up to the last one its equations and events use
            kept[:] = pars[: len(kept)]
            return log.record_passage((t, k, 0, piece, new, q, v, v)) and after_junction(ta, s, pars, t)
        v_new = -k_lim * v
        rigid = stop_impact(system, s, pars, k, upper, k_lim,
                            slipping_members(holder, system.units[system.unit_of[k]].members, scene)) \
            if in_cluster and system.per_body else None
        if rigid is not None:  # the cluster rebounds as one (each member's rate from the links)
            for m, rate in rigid.items():  # (all moved off the stop alike: the links stay closed)
                s[nu + m] = rate
                s[m] = s[m] - margin if upper else s[m] + margin
            v_new = s[nu + u]
        else:
            s[nu + u] = v_new
            s[u] = q - margin if upper else q + margin
        if not log.record_passage((t, k, 2 if upper else 1, piece, piece, q, v, v_new)):
            return False
        # Resting on the stop: the rebounds left are below the run's resolution
        # while the track pushes the body onto it (as for a pair, events.below_resolution).
        if function is not None:
            acc = evaluate(function, s, pars, t)[BODY_VALUES * k + 5]
            away = float(v_new) if not upper else -float(v_new)
            pushed = float(acc) if not upper else -float(acc)
            if below_resolution(away, pushed, k_float, float(t), 1 + abs(float(q)), time_scale, eps):
                # The driver pins its unit on the stop (system.Unit.pinned) until the forces pull it away.
                stop.reason, stop.data = "rest", {"body": k, "end": event.end}
                return False
        if in_cluster and rigid is None:
            # The rest of its cluster runs on into it: the contacts are resolved as collisions.
            stop.reason, stop.data = "release", {"bodies": (k,)}
            return False
        if rigid is not None:
            return settle is None or settle(s, t, [system.state_index(m) for m in rigid])
        # A neighbour touching it at this instant (a collision has just sent it into the stop) now approaches
        # from a gap of 0.0, where its collision event cannot fire: it ran on into the body unseen (status
        # overlap, acceptance test). The settler resolves it now, as after a collision.
        return settle is None or settle(s, t, [u])

    return on_bound
