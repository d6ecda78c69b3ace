"""Changes of friction mode: turning points, sticking, restarts, slipping and rolling again.

The modes and their equations are in :mod:`heyroll.simulation.friction`; the
mode of each unit lives in runtime parameters, switched here, inside heyoka's
event callbacks (the integration goes on: no recompilation, no restart). A
run keeps every body's mode and slip velocity in a :class:`FrictionState`
across contact modes, and every change of mode is a row of the transitions
table (t, body, from, to, q, q').

Decisions at an event are taken in the run's own number type from the
compiled block values [load, static capacity mu_s N, sigma]:

* turning point of a sliding unit (q' = 0): it sticks if |load| <= mu_s N, and the
  rate is set to exactly 0; else it slides on in the direction of the load;
* a stuck unit whose load reaches mu_s N: it slides in the load's direction;
* a rolling body whose needed friction reaches mu_s N: it slips in that direction
  (its slip w = 0 at that instant, then grows);
* a slipping body whose slip returns to 0: it rolls if |F| <= mu_s N, else it slips
  the other way.

heyoka does not see a root of an event function that is exactly 0.0 at the
start of a step (see events.contact_settler): a restart from rest (q' = 0) or
from rolling (w = 0) is therefore not taken for a new turning point.
"""

from __future__ import annotations


import heyoka as hy

import numpy as np

from ..compiled_cache import CompiledCache, by_constants
from ..contact_function import evaluate
from ..friction import MODES

_COMPILED = CompiledCache(64)

#: Values per friction block in its compiled function: load, static capacity, sigma, N_in (signed),
#: and the derivative of the rate that turns (q'', or a slipping body's w').
BLOCK_VALUES = 5

#: Resolution of a run, in ulps of its time (as for persistent contacts, events.RESOLUTION_ULPS).
RESOLUTION_ULPS = 64

#: A unit set going from rest (a release, a slip onset) starts this many ulps (of its rate's scale)
#: along its new direction, not at 0.0: heyoka does not see a root of an event function that is
#: exactly 0.0 at the start of a step, so a unit that the forces then turn back at once (the load
#: reversing at the instant of release) would slide on against its mode unseen (found by review:
#: friction doing positive work); a few ulps off zero, its turning point is an ordinary root. As
#: the settler opens touching gaps by a few ulps (events.OPEN_ULPS): far below the resolution.
START_ULPS = 8

#: How far ahead (in motion time scales) a unit at static friction's limit is looked at, on the step's Taylor
#: polynomial, to tell a load rising through the capacity (an onset at this instant) from one that stays at it.
ONSET_LOOK_AHEAD = 1e-6


class FrictionState:
    """Every body's friction mode and slip velocity in a run (kept across contact modes)."""

    def __init__(self, scene, precision, modes, slips):
        self.scene = scene
        self.modes = list(modes)
        self.slips = list(slips)
        self.transitions: list = []  # (t, body (0-based), from, to, q, q')
        #: Per transition: the work friction had dissipated on the body's unit since t = 0 (J).
        self.transition_work: list = []
        #: Per body: the work friction dissipated in finished contact modes (a cluster's on its first member).
        self.work = [0.0] * len(scene.bodies)
        self.num = precision.number

    def slipping(self) -> dict:
        """The rolling bodies that slip now, with their kappa: an impulse moves them with their translational
        mass m, through their centres, their spins untouched."""
        bodies = self.scene.bodies
        return {k: bodies[k].kappa for k, mode in enumerate(self.modes) if mode in SLIDING and bodies[k].kappa != 1}

    def record(self, t, body, old, new, q, dq, work=0.0) -> None:
        if old != new:
            self.transitions.append((t, body, old, new, q, dq))  # (t, q, dq in the run's own type)
            self.transition_work.append(work)
            self.modes[body] = new


def friction_function(system):
    """``f(state, pars)``: BLOCK_VALUES numbers per friction block (see the module doc), or None."""
    outputs = [x for values in system.friction_values for x in values]
    if not outputs:
        return None

    def build():
        precision = system.precision
        options = {} if precision.name == "double" else {"fp_type": precision.fp_type}
        if precision.name.startswith("mp:"):
            options["prec"] = precision.bits
        return hy.cfunc(outputs, vars=system.variables, **options)

    return _COMPILED.get(("friction", system.shape), build)


def block_mode(system, block, pars) -> str:
    if block.rolls:
        if pars[block.rolling] == 1:
            return "rolling"
    elif pars[block.stuck] == 1:
        return "stuck"
    return "sliding+" if pars[block.sign] > 0 else "sliding-"


class FrictionModes:
    """The friction callbacks of one contact mode (see :func:`make_friction_handlers`)."""

    def __init__(self, scene, system, state: FrictionState, holder, log, time_scale: float = 1.0):
        self.scene, self.system, self.state, self.holder, self.log = scene, system, state, holder, log
        self.time_scale = time_scale
        self.eps = system.precision.epsilon
        #: Inside an impact's callback: the rates (and slips) the modes were last synced to, and
        #: the state before the impact (its positions are recorded: a limiter moves a body off its
        #: stop by a few ulps after).
        self.pending = None
        self.impact_state = None
        g = float(scene.g)
        #: Per block: its weight, sum of m g (times sigma: the scale of its generalized loads).
        self.weights = [g * sum(float(scene.bodies[k].mass) for k in block.members) for block in system.friction_blocks]
        self.function = friction_function(system)
        self.num = system.precision.number
        self.zero, self.one = self.num(0), self.num(1)
        #: Rolling members of clusters with blocks of their own (path tracks): body -> its block.
        self.own = {block.members[0]: block for block in system.friction_blocks if block.within}

    # -- parameters ----------------------------------------------------------------------

    def _set(self, ta, index, value) -> None:
        self.holder[1][index] = value
        if ta is None:  # (FrictionModes.sync: the impact's wrapper copies them into the integrator)
            return
        kept = ta.pars
        if index < len(kept):
            kept[index] = value

    def _evaluate(self, s, t):
        return evaluate(self.function, s, self.holder[1], t)

    def _where(self, s, k):
        full = self.system.expand(list(s))
        n = self.system.n_bodies
        return full[k], full[n + k]

    def _note(self, t, s, block, new: str, record: bool = True, at=None) -> None:
        """The block's members pass to mode ``new`` (rolling members of a cluster roll, or are stuck);
        ``at``: the state whose positions to record (an impact's, before a limiter moved the body off
        its stop by a few ulps)."""
        pars = self.holder[1]
        for k in block.members:
            target = new
            if not block.rolls and self.scene.bodies[k].kappa != 1:
                target = "stuck" if new == "stuck" else "rolling"
                if k in self.own:  # it rolls or slips by its own block; a stuck cluster holds it where it rolls
                    held = self.state.modes[k] in ("rolling", "stuck")
                    if not held:
                        continue
                    target = "stuck" if new == "stuck" else "rolling"
            elif block.within and new == "rolling" and pars[block.stuck] == 1:
                target = "stuck"  # (rolling again inside a stuck cluster: at rest with it)
            if record:
                q, dq = self._where(s, k)
                if at is not None:
                    q = self._where(at, k)[0]
                work = self.state.work[block.members[0]] + float(s[block.work])
                self.state.record(t, k, self.state.modes[k], target, q, dq, work)
            self.state.modes[k] = target

    def apply(self, ta, block, mode: str) -> None:
        """Set the block's parameters for ``mode``."""
        if block.rolls:
            self._set(ta, block.rolling, self.one if mode == "rolling" else self.zero)
        else:
            self._set(ta, block.stuck, self.one if mode == "stuck" else self.zero)
        if mode in ("sliding+", "sliding-"):
            self._set(ta, block.sign, self.one if mode == "sliding+" else -self.one)

    # -- decisions -------------------------------------------------------------------------

    def _holds(self, s, t, b, weightless: bool = False, values=None):
        """(static friction holds the block, the load's sign) at state s. The capacity is taken on
        the reaction's magnitude: on a two-sided track the side parameter may lag an instant where
        N changes sign (events at one instant), where mu_s side N_in < 0 is no release.
        ``weightless``: also whether the capacity is below the rounding of the loads (the reaction
        passing through zero: load and capacity vanish together and their ratio is noise). ``values``: the
        friction function's at s, where the caller has them."""
        values = self._evaluate(s, t) if values is None else values
        load, capacity = values[BLOCK_VALUES * b], values[BLOCK_VALUES * b + 1]
        guard = RESOLUTION_ULPS * self.eps * self.weights[b] * abs(float(values[BLOCK_VALUES * b + 2]))
        out = (abs(load) <= abs(capacity) + guard, (1 if load > 0 else -1))
        return out + (abs(float(capacity)) <= guard,) if weightless else out

    def at_rest(self, ta, s, t, b) -> str:
        """A unit at rest (particle: q' = 0; rolling body: w = 0): the mode it takes now."""
        block = self.system.friction_blocks[b]
        holds, direction = self._holds(s, t, b)
        if block.rolls:
            s[block.slip] = self.zero
            return "rolling" if holds else ("sliding+" if direction > 0 else "sliding-")
        for k in block.members:
            s[self.system.state_index(k) + self.system.n_coordinates] = self.zero
        return "stuck" if holds else ("sliding+" if direction > 0 else "sliding-")

    def _start_moving(self, s, block, direction: int) -> None:
        """A unit set going from rest: its rate (a slip: w) a few ulps along ``direction`` (START_ULPS)."""
        system = self.system
        if block.rolls:
            q = abs(float(s[block.rate]))
            scale = float(self.scene.g) * self.time_scale + q
            s[block.slip] = self.num(direction * START_ULPS * self.eps * scale)
            return
        for k in block.members:
            c = system.state_index(k)
            scale = (1 + abs(float(s[c]))) / self.time_scale
            s[c + system.n_coordinates] = self.num(direction * START_ULPS * self.eps * scale)

    def handler(self, event):
        b = event.block
        block = self.system.friction_blocks[b]
        kind = event.kind

        def on_event(ta, d_sgn):
            s = self.holder[0]
            t = ta.time
            old = block_mode(self.system, block, self.holder[1])
            if kind == "normal":
                self._set(ta, block.side, self.one if d_sgn > 0 else -self.one)
                return True
            if kind in ("turn", "reroll"):
                if old in ("stuck", "rolling"):
                    return True
                # A true turning point (or slip returning to 0) crosses zero against the motion. A
                # restart from rest leaves zero along it: heyoka can report that start as a root
                # (measured: a release at once followed by a "turning point" at the same instant).
                if d_sgn == (1 if old == "sliding+" else -1):
                    return True
                new = self.at_rest(ta, s, t, b)
            else:  # release+/-, slip+/-: the load reached the static capacity
                holds, direction, weightless = self._holds(s, t, b, weightless=True)
                if holds and weightless:  # no release where the reaction, and with it the load, vanishes
                    return True
                if block.side >= 0:
                    normal = self._evaluate(s, t)[BLOCK_VALUES * b + 3]
                    side = -1 if normal < 0 else 1
                    if side != self.holder[1][block.side]:
                        # The reaction has just changed sign (two-sided track) and the side parameter
                        # lags it (events at one instant): mu_s side N_in < 0 was no release. Load and
                        # capacity vanish together there; the unit stays unless it really exceeds.
                        self._set(ta, block.side, self.one if side > 0 else -self.one)
                        if holds:
                            return True
                new = "sliding+" if direction > 0 else "sliding-"
                self._start_moving(s, block, direction)
            self.apply(ta, block, new)
            self._note(t, s, block, new)
            self.log.friction_transitions += 1
            if block.within:
                # a member's mode changes its cluster's load at once (its kinetic friction comes or goes), with no
                # root for the cluster's release events: judged now (review: a stuck cluster whose slipping ring
                # rolled again stayed stuck with a load of 0.75 against a capacity of 0.4)
                self._slip_where_not_held(ta, s, t, block.members[0])
            if kind not in ("turn", "reroll"):
                self._onsets_at(ta, s, t, b)
            self.settle(ta, s, t)  # units turning at the same instant (bodies moving together)
            return not self.log.events_exhausted()

        return on_event

    def _onsets_at(self, ta, s, t, fired: int) -> None:
        """Units whose load reaches static friction's capacity at the same instant as unit ``fired`` (mirror
        images: two bodies at phi = -+0.2 reach it together): their events' roots lie at the start of the next
        step, where heyoka does not see them, and one of the two rolled on needing more than mu_s N
        (acceptance test). A unit at its capacity to within round-off whose excess load is rising (read off
        the step's Taylor polynomial a moment later) slides from here, as its event would have made it; one
        that stays at the limit (a disk on a slope of exactly mu_s kappa/(kappa - 1): review) holds."""
        later = values = None
        for b, block in enumerate(self.system.friction_blocks):
            if b == fired or block_mode(self.system, block, self.holder[1]) not in ("stuck", "rolling"):
                continue
            values = self._evaluate(s, t) if values is None else values
            load, capacity = values[BLOCK_VALUES * b], values[BLOCK_VALUES * b + 1]
            guard = RESOLUTION_ULPS * self.eps * self.weights[b] * abs(float(values[BLOCK_VALUES * b + 2]))
            if abs(float(capacity)) <= guard or abs(load) < abs(capacity) - guard:
                continue
            if later is None:
                dt = ONSET_LOOK_AHEAD * self.time_scale
                later = self._evaluate(np.array(ta.update_d_output(t + dt)), t + dt)
            rising = (abs(float(later[BLOCK_VALUES * b])) - abs(float(later[BLOCK_VALUES * b + 1]))
                      > abs(float(load)) - abs(float(capacity)) + guard)
            if rising:
                self._start_sliding(ta, s, t, block, 1 if load > 0 else -1)
                values = None  # (its mode changed the state and parameters: evaluated again)

    def _slip_where_not_held(self, ta, s, t, body: int | None = None) -> None:
        """Rolling or stuck units (of ``body``; every one for None) that static friction no longer holds
        slide from here, as their release or slip event would have made them."""
        values = None  # (one evaluation for every unit, again after a unit's mode changed)
        for b, block in enumerate(self.system.friction_blocks):
            if body is not None and body not in block.members:
                continue
            if block_mode(self.system, block, self.holder[1]) in ("stuck", "rolling"):
                values = self._evaluate(s, t) if values is None else values
                holds, direction, weightless = self._holds(s, t, b, weightless=True, values=values)
                if not (holds or weightless):
                    self._start_sliding(ta, s, t, block, direction)
                    values = None

    def _start_sliding(self, ta, s, t, block, direction: int) -> None:
        """Static friction no longer holds the unit: it slides from here along ``direction``, recorded."""
        new = "sliding+" if direction > 0 else "sliding-"
        self._start_moving(s, block, direction)
        self.apply(ta, block, new)
        self._note(t, s, block, new)
        self.log.friction_transitions += 1

    def settle(self, ta, s, t) -> None:
        """Units whose turning point (q' = 0, or a slip w = 0) is nearer than the run's time
        resolution: decided now, as at their turning point. heyoka cannot see a root that close
        to the start of a step (measured: a particle left sliding at 5e-25 m/s by a plastic
        collision went on with friction pushing it the wrong way)."""
        system = self.system
        pars = self.holder[1]
        values = None
        horizon = RESOLUTION_ULPS * self.eps * (abs(float(t)) + self.time_scale)
        for b, block in enumerate(system.friction_blocks):
            mode = block_mode(system, block, pars)
            if mode in ("stuck", "rolling"):
                continue
            rate = float(s[block.slip] if block.rolls else s[block.rate])
            if values is None:
                values = self._evaluate(s, t)
            acc = float(values[BLOCK_VALUES * b + 4])
            sign = 1 if mode == "sliding+" else -1
            # At rest and pushed along the mode's direction: a restart (release, slip onset); at rest
            # and not: decided now. Moving: turning within the resolution, or turned already (its
            # rate against the mode's sign: two units that turn in one step, the event of the first
            # stops the step past the second's root, measured): decided now.
            if (acc * sign <= 0) if rate == 0 else (
                    rate * sign < 0 or (rate * acc < 0 and abs(rate) <= abs(acc) * horizon)):
                new = self.at_rest(ta, s, t, b)
                if new != mode:
                    self.apply(ta, block, new)
                    self._note(t, s, block, new)
                    self.log.friction_transitions += 1
                values = None

    def at_junction(self, ta, s, t, body: int) -> None:
        """Body ``body`` has passed a junction of its track: its reaction jumps with the curvature, and the
        events that watch it (normal: the side a two-sided track pushes from; release and slip: static
        friction's capacity) see no root. Judged now, as at a mode's start (:meth:`start`)."""
        values = None
        for b, block in enumerate(self.system.friction_blocks):
            if body not in block.members:
                continue
            if block.side >= 0:
                values = self._evaluate(s, t) if values is None else values
                normal = values[BLOCK_VALUES * b + 3]
                if normal != 0:
                    self._set(ta, block.side, -self.one if normal < 0 else self.one)
        self._slip_where_not_held(ta, s, t, body)

    def spins(self, before, t, was) -> list:
        """Per body: u = sigma q' - w, the speed its spin rolls at, where it slipped in state ``before``
        (modes ``was``); nan where it rolled. An impulse through a slipping body's centre leaves u, through
        every impact of an instant: the collision table's energies count every slipping body's spin, each
        row with its own rates (result.build_collision_table)."""
        out = [float("nan")] * len(self.scene.bodies)
        values = None
        for b, block in enumerate(self.system.friction_blocks):
            k = block.members[0]
            if not block.rolls or was[k] in ("rolling", "stuck"):  # (stuck: a rolling member of a stuck cluster)
                continue
            if values is None:
                values = self._evaluate(np.asarray(before), t)
            sigma = float(values[BLOCK_VALUES * b + 2])
            out[k] = sigma * float(before[block.rate]) - float(before[block.slip])
        return out

    def begin(self, before) -> None:
        """An impact's callback starts: ``before`` is the state (rates, slips) before it."""
        self.pending = list(before)

    def sync(self, s, t, ta=None) -> None:
        """Each unit's mode follows the rates impacts have set since :meth:`begin` (or the last
        sync): a stuck unit that is hit slides, a sliding one reverses; a slipping body's spin is
        unchanged by an impulse through its centre, so its slip changes by sigma times the jump of
        q'. Called inside a collision's callback before its contact is judged (measured: judged
        with the old modes' accelerations, a pressed pair was let open and its next collision went
        unseen), and after it (``reconcile``). ``ta``: the integrator, whose parameters follow
        (None inside a callback: the impact's wrapper copies them after it)."""
        before = self.pending
        if before is None:
            return
        system = self.system
        pars = self.holder[1]
        values = None
        previous = list(before)  # (a cluster's block and its members' own blocks share rates)
        for b, block in enumerate(system.friction_blocks):
            old_rate, rate = previous[block.rate], s[block.rate]
            if old_rate == rate:
                continue
            before[block.rate] = rate
            if block.side >= 0:
                # A two-sided track's reaction has a v^2 term: an impact can turn its sign at once, with no
                # root for the "normal" event to see; the side it pushes from follows here (stale, friction
                # pushed the body along and made energy: +4.4 J in 0.5 s, acceptance test)
                if values is None:
                    values = self._evaluate(s, t)
                normal = values[BLOCK_VALUES * b + 3]
                if normal != 0:
                    self._set(ta, block.side, -self.one if normal < 0 else self.one)
            old = block_mode(system, block, pars)
            if block.rolls:
                if old == "rolling":  # the law keeps it rolling through the impact
                    continue
                if values is None:
                    values = self._evaluate(s, t)
                sigma = values[BLOCK_VALUES * b + 2]
                s[block.slip] = s[block.slip] + sigma * (rate - old_rate)
                w = s[block.slip]
                new = self.at_rest(ta, s, t, b) if w == 0 else ("sliding+" if w > 0 else "sliding-")
            elif rate == 0:
                new = self.at_rest(ta, s, t, b)
            else:
                new = "sliding+" if rate > 0 else "sliding-"
            if new != old:
                self.apply(ta, block, new)
                self._note(t, s, block, new, at=self.impact_state)
                self.log.friction_transitions += 1

    def reconcile(self, ta, s, t, before=None) -> None:
        """After impacts (collisions, limiters): the modes follow the new rates (:meth:`sync`, from
        ``before`` or from :meth:`begin`), the integrator's parameters follow the modes, and units
        left at a turning point are decided (:meth:`settle`)."""
        if before is not None:
            self.begin(before)
        self.impact_state = list(self.pending) if self.impact_state is None else self.impact_state
        self.sync(s, t)
        # An impact changes the reaction (its v^2 term) with the rates: a rolling unit can need more than
        # mu_s N at once, where its slip event starts past its root (a sphere nearly stopped by a heavy
        # particle rolled on 14 % over the capacity: review)
        self._slip_where_not_held(ta, s, t)
        kept = ta.pars
        kept[:] = self.holder[1][: len(kept)]
        self.pending = self.impact_state = None
        self.settle(ta, s, t)

    def start(self, ta, s, t, record: bool = True) -> None:
        """At the start of a contact mode: the blocks' parameters from the run's modes and state
        (``record``: changes are transitions; not at the run's start, where they are the initial modes)."""
        system = self.system
        for b, block in enumerate(system.friction_blocks):
            first = block.members[0]
            s[block.work] = self.zero
            if block.rolls:
                s[block.slip] = self.state.slips[first]
                w = s[block.slip]
                # Slipping on, or rolling if static friction holds it (at the run's start: a body
                # set rolling where rolling needs more than mu_s N slips from t = 0).
                mode = ("sliding+" if w > 0 else "sliding-") if w != 0 else self.at_rest(ta, s, t, b)
            else:
                rate = s[block.rate]
                if rate != 0:
                    mode = "sliding+" if rate > 0 else "sliding-"
                else:
                    mode = self.at_rest(ta, s, t, b)
            if block.side >= 0:  # the side a two-sided track pushes from
                normal = self._evaluate(s, t)[BLOCK_VALUES * b + 3]
                self._set(ta, block.side, -self.one if normal < 0 else self.one)
            self.apply(ta, block, mode)
            self._note(t, s, block, mode, record)
        self.settle(ta, s, t)

    def finish(self, s) -> None:
        """Keep the slip velocities for the next contact mode."""
        for block in self.system.friction_blocks:
            self.state.work[block.members[0]] += float(s[block.work])
            if block.rolls:
                self.state.slips[block.members[0]] = s[block.slip]


SLIDING = ("sliding+", "sliding-")


def slipping(holder, body: int, scene) -> bool:
    """Whether rolling body ``body`` slips now (rough tracks: the mode's FrictionModes in holder[2])."""
    modes = holder[2] if len(holder) > 2 else None
    return modes is not None and scene.bodies[body].kappa != 1 and modes.state.modes[body] in SLIDING


def slipping_members(holder, bodies, scene) -> tuple:
    """(body, kappa) of the rolling bodies among ``bodies`` that slip now (FrictionState.slipping): an impulse
    moves them with their translational mass m (resolve.constraints, events.unit_map)."""
    modes = holder[2] if len(holder) > 2 else None
    slips = modes.state.slipping() if modes is not None else {}
    return tuple((k, slips[k]) for k in bodies if k in slips)


@by_constants()
def slipping_law(scene, i: int, j: int, slip_i: bool, slip_j: bool):
    """The law of a collision where a rolling body slips: Newton's law on the rates with the
    generalized masses kappa_eff m sigma^2, kappa_eff = 1 for a body that slips (the impulse acts
    through its centre; its spin, free of the track's grip, is unchanged) and kappa for one that
    rolls. The rolling law assumes rolling through the impact; applied to a slipping body it could
    create kinetic energy (found by fuzzing: +0.017 J at one collision). At k = 1 this conserves
    the kinetic energy, below it loses some."""
    import dataclasses

    import mpmath

    from ...model.laws import GeneralizedNewtonLaw

    one = mpmath.mpf(1)
    bi, bj = scene.bodies[i], scene.bodies[j]
    law = GeneralizedNewtonLaw(restitution=scene.law.restitution)
    return law, (dataclasses.replace(bi, kappa=one) if slip_i else bi), (dataclasses.replace(bj, kappa=one) if slip_j else bj)


def initial_modes(scene) -> list[str]:
    """Before the first step every body is taken as rolling (a rolling body) or sliding in the
    direction of its rate; FrictionModes.start settles the rest from the state."""
    out = []
    for k, body in enumerate(scene.bodies):
        if body.kappa != 1:
            out.append("rolling" if scene.slip[k] == 0 else ("sliding+" if scene.slip[k] > 0 else "sliding-"))
        else:
            out.append("sliding+" if scene.dq[k] > 0 else "sliding-" if scene.dq[k] < 0 else "stuck")
    return out


__all__ = ["FrictionModes", "FrictionState", "MODES", "friction_function", "initial_modes", "slipping_members"]
