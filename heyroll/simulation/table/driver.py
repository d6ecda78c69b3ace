"""The run loop of a table scene: heyoka finds the events, the laws resolve them.

Called by :func:`heyroll.simulation.driver.simulate` for a
:class:`~heyroll.model.table.TableScene`: the same entry point, options
(:class:`~heyroll.simulation.driver.RunOptions`), precision ladder, statuses,
sinks, progress callback and Ctrl-C handling as every other track.
"""

from __future__ import annotations

import math
import time

import heyoka as hy
import numpy as np

from ...model._numbers import touching_slack, workprec
from ...model.table import TableScene
from ...model.table.boundaries import sqrt
from ..driver import DEFAULT_MAX_EVENTS, RunOptions, signals_deferred
from ..result import Status, counted
from . import bonds as bonds_module
from .bonds import MAX_CLUSTER_BONDS, bond_balls
from .contacts import Contact, ContactGeometry
from .resolve import SETTLED, SIMULTANEOUS, Resolver
from .result import TableResult
from .system import (BALL_PARS, DX, DY, FUX, FUY, FVX, FVY, GRIP, HELD, M_GRIP, M_MOBILITY, M_SLIDING, MODE_PARS, MU_G, MU_G_U,
                     RIDE_HOLD, RIDE_SPEED2, RIDING, SKID, SLIDING, SPIN, STATE_PER_BALL, integrator, needs_grip,
                     table_system)

#: Resolutions of one pair with a riding ball at one instant before the sequence is taken to its limit
#: (_Run.collapse_limit).
RIDER_PAIR_REPEATS = 32
#: Rounds of a collapse's sequence, without rows, at most (_Run.collapse_limit): a sequence that shrinks the
#: normal speeds by 1e-6 a round still ends within it.
COLLAPSE_ROUNDS = 100_000
#: A corner's walls one after the other (sequential): at most this many impacts, else the simultaneous solution
#: (an elastic corner of angle theta takes at most ceil(pi / theta)).
CORNER_TURNS = 64
#: The farthest a cushion impact's instant is moved from heyoka's root of the gap polynomial onto the exact
#: distance's (_Run.polish), in crossing times; a root that far from a contact the ball is not approaching is
#: spurious (_Run.about_to_touch).
NEAR_ROOT = 2.0**-24
#: Steps per call of propagate_until (a call that does not advance the time means heyoka is stuck).
STEP_CHUNK = 100_000
#: Impacts at one instant before the run is declared stuck (an inelastic collapse).
MAX_AT_ONE_INSTANT = 10_000
#: Impacts at one instant under the sequential policy after which the touching contacts are resolved together
#: (the collapse's limit: _Run.at_instant).
SEQUENTIAL_COLLAPSE = 1000
#: Rounds of an instant again where its presses made contacts that approach (_Run.at_instant), at most.
AT_INSTANT_REPEATS = 8
#: Doublings of leave()'s step at most (from an ulp of the table's size).
LEAVE_DOUBLINGS = 20
#: Newton steps of close_start on the pairs that start touching, at most (a rack: two)
CLOSE_STEPS = 8
#: Pieces of motion kept for figures.
MAX_PATH_PIECES = 200_000
#: Newton steps at most putting a settling ball's centre onto the curve of its cushion.
PROJECTION_STEPS = 8
#: The slip (relative to the scene's top speed) with which a rolling rider that lost its grip starts to skid
#: (:meth:`_Run.grip_lost`): the motion's error falls a little faster than SKID_ONSET (measured ~8e-12 m/s at
#: 2^-26, validation/billiards.py section 6), its cost grows as SKID_ONSET^-0.5 (~1400 steps at 2^-26).
SKID_ONSET = 2.0**-26
#: A pressed member's skid onset: rounds of friction's impulse and its cluster's holding impulses (each round the
#: bonds take at most (kappa - 1)/kappa of the slip made: member_skid)
SKID_IMPULSES = 64


def simulate_table(scene: TableScene, opts: RunOptions, sink=None, progress=None) -> TableResult:
    started = time.perf_counter()
    run = _Run(scene, opts, sink, progress)
    try:
        run.loop()
    except KeyboardInterrupt:
        run.stop(Status.INTERRUPTED, f"interrupted at t = {float(run.t):.17g} s after {counted(run.count, 'impact')}")
    return run.finish(time.perf_counter() - started)


class _Run:
    def __init__(self, scene: TableScene, opts: RunOptions, sink, progress):
        self.scene, self.sink, self.progress = scene, sink, progress
        precision = self.precision = opts.precision
        num = self.num = precision.number
        self.t_end = num(scene.run.t_end if opts.t_end is None else opts.t_end)
        self.limit = scene.run.max_collisions if opts.max_collisions is ... else opts.max_collisions
        self.max_events = DEFAULT_MAX_EVENTS if opts.max_events is ... else opts.max_events
        self.chunk_size = opts.chunk_size
        options = dict(precision.integrator_options(), high_accuracy=opts.high_accuracy)
        if opts.fast_math:
            options["fast_math"] = True
        if opts.tolerance is not None:
            options["tol"] = num(opts.tolerance)
        self.system = self.base_system = table_system(scene, precision)
        #: the systems of the run by its bonds (() the scene's own: :meth:`switch_system`)
        self.systems = {(): self.system}
        self.geometry = ContactGeometry(scene, self.system, precision)
        self.resolver = Resolver(scene, precision)
        self.state = [num(v) for b in scene.balls for v in (b.x, b.y, b.vx, b.vy, b.ux, b.uy)]
        self.state_initial = list(self.state)
        self.pars = list(self.system.pars)
        self.zero = num(0)
        self.mass = [num(b.body.mass) for b in scene.balls]
        with workprec():  # model constants at the model's precision, rounded once to the run's type
            self.spin_inertia = [num(b.body.kappa - 1) for b in scene.balls]
            mu_g = scene.friction * scene.g
            self.slide_v = [num(mu_g) for _ in scene.balls]
            self.slide_u = [num(mu_g * b.body.kappa / (b.body.kappa - 1)) if b.body.kappa > 1 else num(0)
                            for b in scene.balls]
        self.radius = [num(b.body.radius) for b in scene.balls]
        #: a slip within this fraction of its starting size has ended (re-roll events at one instant)
        self.slip_tolerance = num(2.0**10 * precision.epsilon)
        self.slip_scale = [num(0) for _ in scene.balls]
        #: per ball, a slip that friction ends within 4 event cooldowns (set_mode ends it at once)
        self.slip_floor = [4 * rate * num(self.system.cooldown) for rate in self.slide_u]
        #: leave(): the first step (an ulp of the table's size) and the margin, in ulps of the gap's terms
        self.nudge = num(precision.epsilon) * self.geometry.size
        self.round_off = num(2.0**8 * precision.epsilon)
        self.solver_tolerance = num(2.0**20 * precision.epsilon)
        #: an approach slower than this (2^8 ulps of the scene's top speed) is round-off, not an impact: a corner's
        #: solution left 2.8e-16 m/s, then 4.9e-32, ... 10,000 times at one instant (random scenes)
        self.speed_floor = self.round_off * self.geometry.size / num(self.system.max_step)
        #: (v_n / v)^2 below which a ball grazing a curved cushion cannot be followed (check_grazing):
        #: the chord's dip v_n^2 rho/(2 v^2) under the contact resolution, rho the least radius of curvature
        curvature = scene.boundary.least_curvature_radius(max(b.body.radius for b in scene.balls)) \
            if hasattr(scene.boundary, "least_curvature_radius") else None
        self.grazing = None if curvature is None else num(2 * float(self.geometry.touch) / curvature)
        self.grazing_straight = num(2.0**10 * precision.epsilon) ** 2
        #: (v_n / v)^2 below which a ball on a cushion that can be ridden settles onto it (settle_riders)
        self.settle_limit = self.grazing if self.grazing is not None else self.grazing_straight
        #: the same for a sliding ball on a curved cushion: its chord's dip under the overlap limit, not the
        #: contact resolution. Its slip ends (an event) within ~1e-6 s of a bounce, while it still touches the
        #: cushion, and leave() then opens that contact past the gap polynomial's round-off, ~1e-10 m for a
        #: finite ball in an ellipse: each such nudge fed the next bounce (measured: 20,000 bounces at
        #: v_n/v ~ 2e-5 that never settled)
        self.settle_limit_sliding = self.settle_limit if curvature is None else \
            num(2 * float(self.geometry.overlap) / curvature)
        #: the least radius of curvature of a curved cushion's centre curve (None: straight walls)
        self.curvature_radius = curvature
        self.t = num(0)
        self.depth = 0  # at_instant within at_instant (presses that made new contacts)
        self.count = self.cushion = self.rerolls = self.events = self.steps = 0
        self.records: list = []
        self.kept: list | None = None  # with a sink: the first chunk, kept for the result
        self.flushed = 0
        self.paths: list = []
        #: balls riding the cushion (system module docstring): their wall event is off, the cushion's
        #: normal force keeps them on its curve
        self.riding = [False] * scene.n_bodies
        #: the wall each riding ball rides (0 on a curved cushion, its one wall)
        self.ride_wall = [0] * scene.n_bodies
        #: per ball, the two walls of a corner friction pins it in (at rest, both walls ridden), or None
        self.pinned: list = [None] * scene.n_bodies
        #: under the slide cushion model a rolling rider needs the cloth's friction to turn its spin (system)
        self.needs_grip = [needs_grip(scene, k) for k in range(scene.n_bodies)]
        #: the instant each ball last lifted off its cushion (it is not settled again at that instant)
        self.lifted: dict = {}
        #: rolling riders past their grip, by ball: the instant their slip reaches SKID_ONSET (:meth:`grip_lost`)
        self.onsets: dict = {}
        #: contacts held closed (module bonds: balls pressed together, :meth:`press`, and the cushion a member
        #: of such a cluster rides); per ball, its bonds
        self.bonds: set = set()
        self.ball_bonds: list = [set() for _ in scene.balls]
        #: the instant each pair last let go (it is not pressed again at that instant: its push is zero to
        #: round-off there, and pressed again it let go again at once, for ever, or was held by a pull: review)
        self.let_go: dict = {}
        #: the instant the integrator was last replaced (switch_system): its events have no cooldown
        self.switched = None
        self.skid_onset = num(SKID_ONSET * float(self.geometry.size) / self.system.max_step)
        self.status, self.message = None, ""
        self.fired = None
        self.one_by_one = False
        self.resolved: list = []
        self.max_step = num(self.system.max_step)
        self.energy_initial = float(self.energy(self.state))
        self.options = options
        self.ta = None
        self._tick = time.perf_counter()
        if sink is not None:
            sink.open(scene, None, precision)
        for k in range(scene.n_bodies):
            self.set_mode(k)

    # -- the loop ------------------------------------------------------------------------------
    def close_start(self) -> None:
        """Balls that start touching a cushion or each other to within the scene's slack (model.touching_slack:
        places written as doubles) but beyond the contact tolerance are moved to touching in the run's type: in
        long, quad or MPFR the tolerance is far below a double's rounding (measured: status overlap at t = 0). In
        double the tolerance covers the slack: nothing moves. A ball is put onto its cushion along the normal; then
        the balls move, all at once, the least that closes every touching pair, those on a cushion along it
        (moving a ball on a cushion off it pushed a ball of a rack through the rail: review)."""
        touch = float(self.geometry.touch)
        num = self.num

        def slack(*balls) -> float:
            return touching_slack(*(float(self.state[STATE_PER_BALL * k + m]) for k in balls for m in (0, 1)))

        def shift(k, step, nx, ny) -> None:
            s = STATE_PER_BALL * k
            self.state[s], self.state[s + 1] = self.state[s] + step * nx, self.state[s + 1] + step * ny

        for k in range(self.system.n_balls):
            s = STATE_PER_BALL * k
            near = [self.geometry.wall(k, w, self.state[s], self.state[s + 1]) for (b, w) in self.system.walls if b == k]
            near = [(d, normal) for d, normal in near if abs(float(d)) <= slack(k)]
            if not any(abs(float(d)) > touch for d, _ in near):
                continue
            if len(near) == 1:
                (d, (nx, ny)), = near
                shift(k, d, nx, ny)
            elif len(near) == 2:
                # in a corner onto both walls at once (n_A . step = d_A, n_B . step = d_B): one wall after the other
                # moved it off the first where the corner is not square (quad: overlap at t = 0, review)
                (da, (ax, ay)), (db, (bx, by)) = near
                det = ax * by - ay * bx
                if abs(float(det)) > 1e-3:
                    step_x, step_y = (da * by - ay * db) / det, (ax * db - da * bx) / det
                    self.state[s], self.state[s + 1] = self.state[s] + step_x, self.state[s + 1] + step_y
        # All pairs at once (Newton's method on the touching pairs' distances, the least displacement that closes
        # them, in doubles: the steps are ~1e-17 m, their rounding far below the run's): pair by pair, putting a
        # ball of a rack onto one neighbour moved it into the next (quad: balls 5 and 9 of a break overlapped by
        # 2.9e-17 m however often the pairs were passed over, status overlap at t = 0, review). A free ball moves
        # in the plane, a ball on one cushion along it (then put back onto it: a curved cushion), a ball in a
        # corner not at all: held, the balls of a rack against a rail overlapped by 2e-19 m (review). A rack
        # written as doubles is a lattice to within the slack: two steps close it.
        n = self.system.n_balls

        def walls(k) -> list:
            s = STATE_PER_BALL * k
            near = [self.geometry.wall(k, w, self.state[s], self.state[s + 1]) for (b, w) in self.system.walls
                    if b == k]
            return [(d, normal) for d, normal in near if float(d) <= touch + slack(k)]

        directions: dict = {}  # ball -> the unit directions it may move along
        for k in range(n):
            on = walls(k)
            if not on:
                directions[k] = [(1.0, 0.0), (0.0, 1.0)]
            elif len(on) == 1:
                (_d, (nx, ny)), = on
                directions[k] = [(-float(ny), float(nx))]
        column, columns = {}, 0
        for k, along in directions.items():
            column[k] = columns
            columns += len(along)
        pairs = [(i, j) for i in range(n) for j in range(i + 1, n) if (i in column or j in column)
                 and abs(float(self.geometry.pair(i, j, self.state)[0])) <= slack(i, j)]
        for _ in range(CLOSE_STEPS):
            rows = [(i, j, *self.geometry.pair(i, j, self.state)) for i, j in pairs]
            if not any(abs(float(d)) > touch for _i, _j, d, _n in rows):
                break
            jacobian = np.zeros((len(rows), columns))
            for r, (i, j, _d, (nx, ny)) in enumerate(rows):
                for k, sign in ((i, -1.0), (j, 1.0)):
                    for c, (ex, ey) in enumerate(directions.get(k, ())):
                        jacobian[r, column[k] + c] = sign * (float(nx) * ex + float(ny) * ey)
            step = np.linalg.lstsq(jacobian, [-float(d) for _i, _j, d, _n in rows], rcond=None)[0]
            for k, along in directions.items():
                s = STATE_PER_BALL * k
                dx = sum(step[column[k] + c] * ex for c, (ex, _ey) in enumerate(along))
                dy = sum(step[column[k] + c] * ey for c, (_ex, ey) in enumerate(along))
                self.state[s], self.state[s + 1] = self.state[s] + num(dx), self.state[s + 1] + num(dy)
                on = walls(k) if len(along) == 1 else ()
                if len(on) == 1:  # back onto its cushion (a step along a curved one's tangent leaves it)
                    (d, (nx, ny)), = on
                    shift(k, d, nx, ny)

    def loop(self) -> None:
        if self.limit == 0:
            self.stop(Status.MAX_COLLISIONS, "max_collisions = 0: nothing integrated")
            return
        self.close_start()
        self.ta = integrator(self.scene, self.system, self.precision, self.options, self.state)
        self.ta.pars[:] = self.pars
        # contacts that touch and approach at the start (a ball launched into a touching neighbour)
        self.at_instant(None)
        if self.status is None:
            self.push()
        time_limit, step_limit = hy.taylor_outcome.time_limit, hy.taylor_outcome.step_limit
        while self.status is None:
            ta = self.ta  # (a bond made or released switches the system: switch_system)
            n_events = len(self.system.events)
            before = ta.time
            until = min([self.t_end, *self.onsets.values()])
            trace = self.trace if self.bonds and len(self.paths) < MAX_PATH_PIECES else None
            propagated = ta.propagate_until(until, max_steps=STEP_CHUNK, max_delta_t=self.max_step, callback=trace)
            outcome = propagated[0]
            self.steps += int(propagated[3])
            self.t = ta.time
            if outcome == time_limit and until < self.t_end:  # a rider that lost its grip skids from now
                self.pull()
                for k in [k for k, t in self.onsets.items() if t <= self.t]:
                    del self.onsets[k]
                    if self.ball_bonds[k]:
                        self.member_skid(k)
                    elif self.riding[k] and self._grip_excess(k) > 0:
                        self.start_skid(k, self.skid_onset)
                    else:  # its grip came back meanwhile (a crossing near a tangency): it rolls on, watched
                        self.set_mode(k)
                self.at_instant(None)
                if self.status is None:
                    self.push()
                continue
            if outcome == time_limit:
                self.pull()
                self.stop(Status.COMPLETED, f"reached t_end = {float(self.t_end)!r} s after {counted(self.count, 'impact')}")
                break
            if outcome == step_limit:
                if ta.time == before:
                    self.pull()
                    self.stop(Status.FAILED, f"the integrator does not advance from t = {float(ta.time):.17g} s")
                continue
            index = -outcome.value - 1
            if not 0 <= index < n_events:
                self.pull()
                self.stop(Status.FAILED, f"heyoka stopped with {outcome} at t = {float(ta.time):.17g} s")
                break
            self.pull()
            event = self.system.events[index]
            if event.kind in ("roll", "lift", "grip"):
                # a slip ends, a skidding ball lifts off its cushion, a rolling rider starts to skid
                {"roll": self.reroll, "lift": self.lift, "grip": self.grip_lost}[event.kind](event.ball)
                # the accelerations changed: a pair or cushion touching now may start to close
                self.at_instant(None)
            elif event.kind in ("release", "bond_lift", "pair_roll", "pair_grip"):
                # a bond's contact force vanishes (friction no longer drives the balls together, or the ball into
                # the cushion), a member's slip ends, a rolling member loses its grip
                if event.kind in ("release", "bond_lift"):
                    self.let_bonds_go([("pair" if event.kind == "release" else "wall", event.ball, event.other)])
                else:
                    {"pair_roll": self.pair_reroll, "pair_grip": self.pair_grip_lost}[event.kind](event.ball)
                if self.status is None:
                    self.at_instant(None)
            else:
                fired = self.fired_contact(event)
                if fired is None:  # a spurious root of the parallel curve's polynomial: nothing touches
                    self.push()
                    continue
                self.at_instant(fired)
            if self.status is None:
                self.push()
            self.tick()

    def pull(self) -> None:
        self.state = self.ta.state.tolist() if self.precision.name == "double" else list(self.ta.state)

    def push(self) -> None:
        self.ta.time = self.t
        self.ta.state[:] = self.state
        self.ta.pars[:] = self.pars
        if len(self.paths) < MAX_PATH_PIECES:
            self._path_piece(self.t)

    def _accelerations(self) -> list:
        members = {}  # a member of a cluster of bonds: its acceleration now, the figures' parabola of its curve
        for group in bonds_module.clusters(self.bonds):
            members.update(self.bond_forces(group)[1])
        out = []
        for k in range(self.scene.n_bodies):
            b = BALL_PARS * k
            out += list(members[k]) if k in members else [float(self.pars[b + FVX]), float(self.pars[b + FVY])]
        return out

    def trace(self, ta) -> bool:
        """heyoka's callback after each step while bonds hold: a piece of path for the figures at every step (a
        cluster member's motion is no parabola: drawn from its acceleration at the start of the piece between two
        events, a turning pressed pair was millimetres off, review). The run's state is untouched."""
        if len(self.paths) < MAX_PATH_PIECES:
            kept = self.state
            self.state = ta.state.tolist() if self.precision.name == "double" else list(ta.state)
            self._path_piece(ta.time)
            self.state = kept
        return True

    def _path_piece(self, t) -> None:
        """A piece of path for the figures from the present state at ``t``: (t, state, accelerations, riders)."""
        self.paths.append((float(t), [float(v) for v in self.state], self._accelerations(),
                           tuple(k for k, on in enumerate(self.riding) if on)))

    def tick(self) -> None:
        self.events += 1
        if self.max_events is not None and self.events >= self.max_events and self.status is None:
            self.stop(Status.MAX_EVENTS, f"stopped after max_events = {self.max_events} events")
        if self.progress is not None and self.events % 256 == 0:
            now = time.perf_counter()
            if now - self._tick > 0.2:
                self._tick = now
                self.progress(float(self.t), self.count)

    def stop(self, status: Status, message: str) -> None:
        if self.status is None:
            self.status, self.message = status, message

    # -- modes ---------------------------------------------------------------------------------
    def set_mode(self, k: int) -> None:
        """Ball k's mode parameters from its slip and riding (module system). Free: it slides against
        d = u/|u| or rolls. Riding: it skids (slides along the cushion, its friction's direction turning with
        the slip) or rolls on the cushion at the speed it has now, held, its grip watched where the cushion
        model needs it."""
        if self.ball_bonds[k]:
            self._set_pressed_mode(k)
            return
        b, s = BALL_PARS * k, STATE_PER_BALL * k
        ux, uy = self.state[s + 4], self.state[s + 5]
        zero = self.zero
        mode = [zero] * MODE_PARS
        sliding = ux != zero or uy != zero
        if self.riding[k] and sliding and self.pinned[k] is None:
            # a rider's slip under SKID_ONSET/2 ends at once (with friction; SLIP_END without): its direction
            # relaxes at nu/|u|, so a skid from a slip of 1e-13 took steps of that size and heyoka's state went
            # non-finite (a ball in a 60 degree corner, its bounces leaving slips of 1e-12: random scenes); an
            # error of at most that slip (7e-9 of the top speed) where a corner or settle leaves one
            floor = self.skid_onset / 2 if self.pars[BALL_PARS * k + MU_G] > zero else self.pars[self.system.slip_end]
            if ux * ux + uy * uy < floor * floor:
                self.end_slip(k, self._wall_gradient(k, self.ride_wall[k]))
                sliding = False
        if self.pinned[k] is not None and sliding and ux * ux + uy * uy < self.slip_floor[k] ** 2:
            # pinned with a slip that friction ends within a few cooldowns (the pin took the speed from a slip of the
            # same size: 1.9e-20 left): heyoka missed that root and the slip grew on, reversed, to 16 m/s over 5 s,
            # +4.4 J (random scenes). It ends now: the ball rests there, rolling, still pinned (its walls' events
            # off; unpinned was a ball a cluster pushes into the corner, pinned again, unpinned, ... at one instant,
            # and it passed through a wall: review); an impact or leaving its cluster unpins it
            self.end_slip(k)
            self.rerolls += 1
            sliding = False
        if self.pinned[k] is not None and sliding:
            # pinned in a corner: at rest, the walls take the friction's push, the slip shrinks along its own
            # direction at mu g/(kappa - 1) (w' = -f/((kappa - 1) m), v' = 0)
            norm = sqrt(ux * ux + uy * uy)
            dx, dy = ux / norm, uy / norm
            rate = self.slide_u[k] - self.slide_v[k]
            mode[FUX:RIDING] = [-rate * dx, -rate * dy, zero + 1, dx, dy]
            mode[RIDING] = zero + 1
            self.slip_scale[k] = norm
        elif self.riding[k]:
            mode[RIDING] = zero + 1
            if sliding:
                mode[SKID] = zero + 1
            else:
                vx, vy = self.state[s + 2], self.state[s + 3]
                speed2 = vx * vx + vy * vy
                mode[RIDE_SPEED2] = speed2
                # (0 at rest, and for a speed of round-off: alpha / (2 V^2) overflowed, random scenes)
                slow = self.speed_floor * self.speed_floor
                mode[RIDE_HOLD] = self.pars[self.system.alpha] / (2 * speed2) if speed2 > slow else zero
                if self.system.grips[k] and k not in self.onsets:
                    mode[GRIP] = zero + 1
        elif self.system.rolls[k] and sliding and ux * ux + uy * uy < self.slip_floor[k] ** 2:
            # a slip that friction ends within a few cooldowns of the roll event: heyoka would miss that root
            # (it lies in the event's cooldown after a re-roll at the same ball's last bounce) and the constant
            # friction would drive the slip through zero and on, making energy (+1.3e-13 J at 1.6e-8 J, corner
            # bounces: acceptance test)
            self.end_slip(k)
            self.rerolls += 1
        elif self.system.rolls[k] and sliding:
            norm = sqrt(ux * ux + uy * uy)
            dx, dy = ux / norm, uy / norm
            mode[FVX:RIDING] = [-self.slide_v[k] * dx, -self.slide_v[k] * dy, -self.slide_u[k] * dx,
                                -self.slide_u[k] * dy, zero + 1, dx, dy]
            self.slip_scale[k] = norm
        self.pars[b:b + MODE_PARS] = mode
        if self.system.ride:
            for w in range(self.scene.boundary.n_walls()):
                on = self.riding[k] and (w == self.ride_wall[k] or w in (self.pinned[k] or ()))
                self.pars[self.system.ride_flags[(k, w)]] = zero + 1 if on else zero

    def _set_pressed_mode(self, k: int) -> None:
        """Ball k is a member of a cluster of bonds (:meth:`press`): its own mode parameters are 0 (its friction,
        with its turning direction, is in the cluster's terms: system._bond_terms; so is its cushion's force
        where it rides one, that wall's event staying off) and its member parameters say whether it slides, its
        mobility and whether its grip is watched. A slip under SKID_ONSET/2 ends at once, as a rider's (its
        direction relaxes too fast to follow: set_mode)."""
        b, s = BALL_PARS * k, STATE_PER_BALL * k
        zero = self.zero
        ux, uy = self.state[s + 4], self.state[s + 5]
        sliding = self._has_slip(k)
        if sliding and ux * ux + uy * uy < (self.skid_onset / 2) ** 2:
            self.end_slip(k)
            self.hold_cluster(k)
            self.rerolls += 1
            sliding = False
        self.pars[b:b + MODE_PARS] = [zero] * MODE_PARS
        if self.system.ride:
            walls = self.held_walls(k)
            self.pars[b + HELD] = zero + 1 if walls else zero  # bonds: their events off, their forces the cluster's
            for w in range(self.scene.boundary.n_walls()):
                self.pars[self.system.ride_flags[(k, w)]] = zero + 1 if w in walls else zero
        first = self.system.members.get(k)
        if first is None:  # (switch_system sets every member once the system has its bonds)
            return
        self.pars[first + M_SLIDING] = zero + 1 if sliding else zero
        self.pars[first + M_MOBILITY] = self._mobility(k)
        grips = not sliding and float(self.pars[b + SPIN]) > 0 and float(self.pars[b + MU_G]) > 0 and \
            k not in self.onsets  # (its onset pending: pair_grip_lost)
        self.pars[first + M_GRIP] = zero + 1 if grips else zero
        if grips and self._member_excess(k) > 0:
            # pushed past its grip already (pressed so, or a bond made or let go, an impact): its event, armed
            # where the excess is > 0, would never cross (a ball at rest pushed by a spinning one rolled on)
            self.pair_grip_lost(k)

    def _has_slip(self, k: int) -> bool:
        s = STATE_PER_BALL * k
        return self.state[s + 4] != self.zero or self.state[s + 5] != self.zero

    def _mobility(self, k: int):
        """1/m of ball k sliding (a force through its centre leaves its spin), 1/(kappa m) rolling (run type)."""
        if self._has_slip(k):
            return 1 / self.mass[k]
        return 1 / (self.mass[k] * (self.spin_inertia[k] + 1))

    # -- balls pressed together (bonds) -------------------------------------------------------
    def bonded_pair(self, i: int, j: int) -> bool:
        return ("pair", min(i, j), max(i, j)) in self.bonds

    def held_walls(self, k: int) -> tuple:
        """The walls ball k rides (both walls of the corner it is pinned in)."""
        return () if not self.riding[k] else self.pinned[k] or (self.ride_wall[k],)

    def new_bonds(self, i: int, j: int) -> list:
        """The bonds that pressing balls i and j together makes: their pair, and the cushion walls each rides."""
        made = [("pair", min(i, j), max(i, j))] + [("wall", k, w) for k in (i, j) for w in self.held_walls(k)]
        return [b for b in made if b not in self.bonds]

    def why_not_pressed(self, i: int, j: int) -> str:
        """'' where balls i and j can be pressed together (:meth:`press`), else why not (one clause)."""
        return self._why_not_held(bonds_module.cluster_of(self.bonds | set(self.new_bonds(i, j)), i))

    def _why_not_held(self, cluster: list) -> str:
        """'' where a cluster of these bonds can be held (solved together), else why not (one clause)."""
        if len(cluster) > MAX_CLUSTER_BONDS:
            return f"their cluster would hold {len(cluster)} contacts (at most {MAX_CLUSTER_BONDS} are solved together)"
        if not bonds_module.independent(bonds_module.bond_matrix(*self._cluster_rows(cluster))):
            return (f"their cluster's {len(cluster)} contacts would not be independent (more contacts than the balls "
                    "can move in: the forces are not determined)")
        return ""

    def press(self, contact: Contact) -> None:
        """Balls i and j stay pressed together from now on: the limit of their accumulating impacts (k < 1,
        sliding friction driving them into each other), as a rider's on the cushion. A pair bond (and, for a
        ball that rides the cushion, a bond to it) joins the cluster of bonds the balls are in (module bonds).
        The cluster's normal relative speeds (round-off, or a bounce too low to resolve) are removed by
        impulses through the centres that keep the momentum with the mobilities of :meth:`_mobility` (a sliding
        ball's spin unchanged, a rolling one rolling): one row, law_flag SETTLED, whose energy change is what the
        rest of the accumulation would dissipate. Then the cluster's contact forces hold it together
        (system._bond_terms) until one vanishes (the release event), an impact on a member ends its bonds, or a
        member needs more friction than the cloth gives."""
        self.hold_with(self.new_bonds(contact.i, contact.j), (contact.i, contact.j), contact)

    def hold_with(self, bonds: list, balls: tuple, contact: Contact | None) -> None:
        """``bonds`` join the cluster of ``balls`` (whose modes change): the cluster put onto its contacts and
        every normal relative speed of it removed (one row for ``contact``, law_flag SETTLED; none for None),
        then a bond the new ones leave without force lets go."""
        before = list(self.state)
        energy_before = self.energy(before)
        for bond in bonds:
            self._bond(bond)
        self.project_cluster(balls[0])
        self.hold_cluster(balls[0])
        for k in balls:
            self.onsets.pop(k, None)
        self.switch_system(balls)
        if contact is not None:
            self.record(contact, before, self.state, energy_before, self.energy(self.state), SETTLED)
        self.let_bonds_go([], pressed=True)

    def _bond(self, bond: tuple) -> None:
        self.bonds.add(bond)
        for k in bond_balls(bond):
            self.ball_bonds[k].add(bond)

    def _unbond(self, bond: tuple) -> None:
        self.bonds.discard(bond)
        for k in bond_balls(bond):
            self.ball_bonds[k].discard(bond)

    def _cluster_rows(self, group: list, run_type: bool = False) -> tuple:
        """Directions and mobilities of a cluster's bonds (module bonds) at the present state, as floats (for
        decisions) or in the run's type (``run_type``: the impulses of :meth:`hold_cluster`)."""
        value = (lambda v: v) if run_type else float
        directions = []
        for bond in group:
            if bond[0] == "pair":
                _, i, j = bond
                dx, dy = self._difference(i, j, 0, value)
                directions.append({i: (-dx, -dy), j: (dx, dy)})
            else:
                _, k, w = bond
                gx, gy = self._wall_gradient(k, w)
                directions.append({k: (-value(gx), -value(gy))})
        mobility = {k: value(self._mobility(k)) for bond in group for k in bond_balls(bond)}
        return directions, mobility

    def _difference(self, i: int, j: int, m: int, value=lambda v: v) -> tuple:
        """State entries m, m + 1 of ball j minus ball i (m = 0: dc, 2: dv), through ``value``."""
        si, sj = STATE_PER_BALL * i, STATE_PER_BALL * j
        return value(self.state[sj + m] - self.state[si + m]), value(self.state[sj + m + 1] - self.state[si + m + 1])

    def project_cluster(self, k: int) -> None:
        """Put ball k's cluster onto its bonds' contacts (C = 0), the centres moved along the bonds' directions
        with the mobilities as weights (A mu = -C/2 for a pair, g for a wall: Newton's method, module bonds):
        else the round-off by which a contact was opened before (leave(), 2.3e-13 m at a touching start) stayed
        for Baumgarte's correction to close at ~1e-13 m/s."""
        group = bonds_module.cluster_of(self.bonds, k)
        for _ in range(2):  # from ~1e-13 m: one step, one check
            directions, mobility = self._cluster_rows(group, run_type=True)
            errors = []
            for bond in group:
                if bond[0] == "pair":
                    _, i, j = bond
                    dx, dy = self._difference(i, j, 0)
                    _, reach = self.system.pairs[(i, j)]
                    errors.append(-(dx * dx + dy * dy - reach * reach) / 2)
                else:
                    _, b, w = bond
                    s = STATE_PER_BALL * b
                    _, c = self.system.walls[(b, w)]
                    errors.append(self.scene.boundary.gap(w, self.state[s], self.state[s + 1], c))
            for b, (dx, dy) in bonds_module.correction(directions, mobility, errors).items():
                s = STATE_PER_BALL * b
                self.state[s], self.state[s + 1] = self.state[s] + dx, self.state[s + 1] + dy

    def hold_cluster(self, k: int) -> None:
        """Remove the normal relative speeds of the bonds of ball k's cluster (J v = 0) by impulses through the
        centres with the mobilities of :meth:`_mobility` (A P = -J v, module bonds): after a bond is made, or a
        member's velocity jumped (its slip ended by friction's impulse at the slip end, :meth:`end_slip`) as the
        cushion does a rider's (else a pair opened or closed at ~1e-13 m/s, seen as an impact where it let go)."""
        group = bonds_module.cluster_of(self.bonds, k)
        if not group:
            return
        directions, mobility = self._cluster_rows(group, run_type=True)
        velocity = {b: (self.state[STATE_PER_BALL * b + 2], self.state[STATE_PER_BALL * b + 3]) for b in mobility}
        opening = [-v for v in bonds_module.free_work(directions, velocity)]
        for b, (dvx, dvy) in bonds_module.correction(directions, mobility, opening).items():
            s = STATE_PER_BALL * b
            sliding = self._has_slip(b)
            self.state[s + 2], self.state[s + 3] = self.state[s + 2] + dvx, self.state[s + 3] + dvy
            if sliding:
                self.state[s + 4], self.state[s + 5] = self.state[s + 4] + dvx, self.state[s + 5] + dvy

    def bond_forces(self, group: list) -> tuple:
        """The multipliers of a cluster's bonds without Baumgarte's terms (float; > 0 pushing) and per member the
        acceleration they give it (module bonds; the cushion's v^T H v by central differences: for decisions)."""
        matrix, right, directions, mobility, free = self._bond_system(group)
        lam, = bonds_module.solve(matrix, [right])
        contact = bonds_module.pushes(directions, mobility, lam)
        return lam, {k: (free[k][0] + contact[k][0], free[k][1] + contact[k][1]) for k in contact}

    def _bond_system(self, group: list) -> tuple:
        """A lambda = b of a cluster's bonds now (float, without Baumgarte's terms; A lambda - b is the bonds'
        opening acceleration), their directions, the members' mobilities and own accelerations."""
        directions, mobility = self._cluster_rows(group)
        plain = []
        for bond in group:
            if bond[0] == "pair":
                dvx, dvy = self._difference(bond[1], bond[2], 2, float)
                plain.append(-(dvx * dvx + dvy * dvy))
            else:
                plain.append(self._gap_terms(bond[1], wall=bond[2])[2])
        free = {k: self._free_acceleration(k) for k in mobility}
        work = bonds_module.free_work(directions, free)
        matrix = bonds_module.bond_matrix(directions, mobility)
        return matrix, [p - w for p, w in zip(plain, work)], directions, mobility, free

    def release(self, bonds: list, let_go: bool = False) -> None:
        """The ``bonds`` no longer hold: each ball moves on its own or in what is left of its cluster. A wall bond
        goes with the last pair bond of its ball (the ball rides its cushion on, alone); a released wall bond
        lifts the ball off its cushion. ``let_go``: their push has turned (not an impact on a member, after which
        they may be pressed again at once: kept apart from that, such a pair closed unseen, random scenes)."""
        if not bonds:
            return
        touched = {k for bond in bonds for k in bond_balls(bond)}
        for bond in bonds:
            self._unbond(bond)
            if bond[0] == "pair" and let_go:
                self.let_go[(bond[1], bond[2])] = self.t
            if bond[0] == "wall":
                k = bond[1]
                if self.pinned[k] is not None:  # out of its corner: it rides the other wall
                    self.ride_wall[k] = next(w for w in self.pinned[k] if w != bond[2])
                    self.pinned[k] = None
                else:
                    self.riding[k] = False
                    self.lifted[k] = self.t
        for k in list(touched):
            if not any(b[0] == "pair" for b in self.ball_bonds[k]):
                for bond in list(self.ball_bonds[k]):  # its cushion, held by the cluster no more: it rides it alone
                    self._unbond(bond)
                if self.pinned[k] is not None and not self._has_slip(k):
                    self.unpin(k)  # at rest in its corner, rolling: nothing presses it any more
        self.switch_system(touched)

    def let_bonds_go(self, bonds: list, pressed: bool = False) -> None:
        """Release ``bonds`` (their force has vanished) and then every bond the cluster's contact problem leaves
        without force: lambda >= 0, opening acceleration A lambda - b >= 0, one of them 0 on each bond (the
        complementarity problem, bonds.complementary). ``pressed``: after a press, such a bond may be pressed again
        at this instant (later presses' impulses can turn its contact closing, 1e-10 m/s: it met again 1.6e-5 s
        later, over and over, 6,190 rows in 5 s of a k = 0 break, review)."""
        self.release(bonds, let_go=True)
        for group in bonds_module.clusters(self.bonds):
            matrix, right, *_ = self._bond_system(group)
            lam = bonds_module.complementary(matrix, right)
            self.release([bond for bond, value in zip(group, lam) if not value > 0], let_go=not pressed)

    def release_balls(self, balls) -> None:
        """An impact on a ball in a cluster ends its pair bonds (the impact is resolved as any other; its pairs
        are judged again after it, :meth:`check_pressed_pair`)."""
        ending = [b for k in balls for b in self.ball_bonds[k] if b[0] == "pair"]
        self.release(sorted(set(ending)))

    def pair_reroll(self, k: int) -> None:
        """Member k's slip ended: it rolls on, pressed (its mobility now 1/(kappa m)), unless its cluster's
        forces have turned (then those bonds let go). A member whose slip ends at the same instant (a row of equal
        balls) rolls too (set_mode): heyoka does not see a root at the very start of its next step."""
        self.end_slip(k)
        self.hold_cluster(k)
        self.rerolls += 1
        for member in sorted({b for bond in bonds_module.cluster_of(self.bonds, k) for b in bond_balls(bond)}):
            self.set_mode(member)
        self.let_bonds_go([])

    def pair_grip_lost(self, k: int) -> None:
        """Rolling member k needs more of the cloth's friction than mu m g (the pair_grip event): its bonds push it
        into sliding. As a rider's grip (:meth:`grip_lost`): it rolls on until its slip would reach SKID_ONSET
        (the excess e = (kappa - 1)|a_b| - mu g, a_b its bonds' push, growing at e' from 0 now), then slides from
        there (:meth:`member_skid`); where the excess turns back first it never slides."""
        b = BALL_PARS * k
        first = self.system.members[k]
        if self._slip_rate(k) < -2.0**-20 * float(self.pars[b + MU_G]):
            # sliding, its slip would shrink at once (a ball its walls hold still, pinned in a corner under the
            # rolling cushion model, pushed by its pair: it slid, rolled, slid, ... 1e-8 s apart): the friction it
            # needs is the model's limit, not a slide; it rolls on, its grip judged again at its cluster's next
            # event. (Only where the slip clearly shrinks: at a rider's grip crossing u'.d is 0 to round-off, and
            # judged so it rolled on unwatched needing 4.5 mu m g, review.)
            self.pars[first + M_GRIP] = self.zero
            return
        h = 1e-6 * float(self.system.max_step)
        rate = (self._member_excess(k, h) - self._member_excess(k, -h)) / (2 * h)
        wait = _onset_wait(max(self._member_excess(k), 0.0), rate, float(self.pars[b + SPIN]) * float(self.skid_onset))
        if wait is None:  # the excess turns back first: it rolls on, watched
            self.pars[first + M_GRIP] = self.zero + 1
            return
        self.onsets[k] = self.t + self.num(wait)
        self.pars[first + M_GRIP] = self.zero

    def _member_need(self, k: int) -> tuple:
        """(ax, ay), float: the acceleration member k's bonds give it where the cloth's friction must turn its spin
        with it (system._bond_terms' grips: every pair bond, a cushion bond where its model does not keep a ball
        rolling), without Baumgarte's terms."""
        group = bonds_module.cluster_of(self.bonds, k)
        matrix, right, directions, mobility, _ = self._bond_system(group)
        lam, = bonds_module.solve(matrix, [right])
        keeps = self.scene.cushion.keeps_rolling
        gripped = [(d, v) for d, v, bond in zip(directions, lam, group) if bond[0] == "pair" or not keeps]
        return bonds_module.pushes([d for d, _ in gripped], mobility, [v for _, v in gripped]).get(k, (0.0, 0.0))

    def _member_excess(self, k: int, shift: float = 0.0) -> float:
        """(kappa - 1)|a_b| - mu g of member k (float), the cluster's motion moved ``shift`` seconds on (its
        members' positions and velocities by their present velocities and accelerations)."""
        b = BALL_PARS * k
        saved = None
        if shift:
            saved = list(self.state)
            _, accelerations = self.bond_forces(bonds_module.cluster_of(self.bonds, k))
            for m, (ax, ay) in accelerations.items():
                s = STATE_PER_BALL * m
                vx, vy = float(saved[s + 2]), float(saved[s + 3])
                self.state[s] = saved[s] + self.num(vx * shift + ax * shift * shift / 2)
                self.state[s + 1] = saved[s + 1] + self.num(vy * shift + ay * shift * shift / 2)
                self.state[s + 2], self.state[s + 3] = saved[s + 2] + self.num(ax * shift), saved[s + 3] + self.num(ay * shift)
        try:
            nx, ny = self._member_need(k)
            return float(self.pars[b + SPIN]) * math.hypot(nx, ny) - float(self.pars[b + MU_G])
        finally:
            if saved is not None:
                self.state[:] = saved

    def _slip_rate(self, k: int) -> float:
        """u'.d of rolling member k sliding with a slip along its bonds' push d (float): u' = kappa/(kappa - 1) f
        + (a - f), f = -mu g d its friction, a its acceleration in the cluster with its mobility 1/m."""
        nx, ny = self._member_need(k)
        norm = math.hypot(nx, ny)
        if not norm > 0:
            return 0.0
        s, b = STATE_PER_BALL * k, BALL_PARS * k
        saved = self.state[s + 4], self.state[s + 5]
        self.state[s + 4], self.state[s + 5] = self.num(nx / norm), self.num(ny / norm)  # (a direction only)
        try:
            _, accelerations = self.bond_forces(bonds_module.cluster_of(self.bonds, k))
            fx, fy = self._free_acceleration(k)
        finally:
            self.state[s + 4], self.state[s + 5] = saved
        ax, ay = accelerations[k]
        gain = float(self.pars[b + MU_G_U]) / float(self.pars[b + MU_G]) if float(self.pars[b + MU_G]) > 0 else 1.0
        return ((gain * fx + ax - fx) * nx + (gain * fy + ay - fy) * ny) / norm

    def member_skid(self, k: int) -> None:
        """Rolling member k starts to slide (its onset, :meth:`pair_grip_lost`) with a slip of SKID_ONSET along its
        bonds' push (the saturated friction lags it: the contact point moves that way). The slip is made by
        friction's impulse at the contact, v gaining (kappa - 1)/kappa of it (:meth:`end_slip` in reverse), and the
        cluster's bonds held by impulses through the centres (:meth:`hold_cluster`: they take part of the member's
        slip, now that it slides; repeated until the slip is made): neither does work to first order at a rolling
        contact and a closed bond, so the energy is the rolling motion's to O(SKID_ONSET^2). Then its bonds are
        judged again."""
        nx, ny = self._member_need(k)
        norm = math.hypot(nx, ny)
        b, s = BALL_PARS * k, STATE_PER_BALL * k
        if not float(self.pars[b + SPIN]) * norm > float(self.pars[b + MU_G]):
            self.set_mode(k)  # its grip came back meanwhile: it rolls on, watched
            return
        share = self.spin_inertia[k] / (self.spin_inertia[k] + 1)
        dx, dy = self.num(nx / norm), self.num(ny / norm)
        for _ in range(SKID_IMPULSES):
            missing = self.skid_onset - (self.state[s + 4] * dx + self.state[s + 5] * dy)
            if missing <= self.skid_onset / 4:  # (a slip under SKID_ONSET/2 would end at once: set_mode)
                break
            self.state[s + 2], self.state[s + 3] = self.state[s + 2] + share * missing * dx, \
                self.state[s + 3] + share * missing * dy
            self.state[s + 4], self.state[s + 5] = self.state[s + 4] + missing * dx, self.state[s + 5] + missing * dy
            self.hold_cluster(k)
        for member in sorted({m for bond in bonds_module.cluster_of(self.bonds, k) for m in bond_balls(bond)}):
            self.set_mode(member)
        self.let_bonds_go([])

    def switch_system(self, balls=()) -> None:
        """The run's system for its bonds now (compiled once per set of bonds), its parameters the scene's part
        of the present ones plus the bonds', the mode of every member and of ``balls`` (whose bonds changed)
        set; a pair bond's own impact event is off (its parameter -1: |dc|^2 + 1 never crosses zero)."""
        key = tuple(sorted(self.bonds))
        system = self.systems.get(key)
        if system is None:
            system = self.systems[key] = table_system(self.scene, self.precision, key)
        base = self.base_system
        self.pars = self.pars[:len(base.pars)] + list(system.pars[len(base.pars):])
        for pair, (index, _) in base.pairs.items():
            self.pars[index] = self.num(-1) if ("pair", *pair) in self.bonds else base.pars[index]
        self.system = system
        for k in sorted(set(balls) | set(system.members)):
            self.set_mode(k)
        if self.ta is not None:
            self.switched = self.t
            self.ta = integrator(self.scene, system, self.precision, self.options, self.state)
            self.ta.time = self.t
            self.ta.pars[:] = self.pars

    def end_slip(self, k: int, cushion=None) -> None:
        """End ball k's slip at once, as friction ends a slip: by an impulse against it, v losing (kappa - 1)/kappa
        of it (setting u = 0 alone turned the spin by u and made energy: +1.8e-13 J, acceptance test). A rider's
        cushion (its gap's ``cushion`` gradient) takes the part of that change that points into it."""
        s = STATE_PER_BALL * k
        share = self.spin_inertia[k] / (self.spin_inertia[k] + 1)
        dvx, dvy = -share * self.state[s + 4], -share * self.state[s + 5]
        if cushion is not None:
            gx, gy = cushion
            into = (dvx * gx + dvy * gy) / (gx * gx + gy * gy)
            if into > self.zero:
                dvx, dvy = dvx - into * gx, dvy - into * gy
        self.state[s + 2], self.state[s + 3] = self.state[s + 2] + dvx, self.state[s + 3] + dvy
        self.state[s + 4] = self.state[s + 5] = self.zero

    def _wall_gradient(self, k: int, wall: int) -> tuple:
        """The gradient of ball k's gap to ``wall`` where the ball is (run type): out of the table."""
        s = STATE_PER_BALL * k
        _, c = self.system.walls[(k, wall)]
        return self.scene.boundary.gradient(wall, self.state[s], self.state[s + 1], c)

    def reroll(self, k: int) -> None:
        """Ball k's slip reached zero (a skidding rider's, SLIP_END): it rolls from now on; so does every
        free ball whose slip ends now too (heyoka does not see a root at the very start of its next step). A
        rider that cannot grip the cloth skids again at once (:meth:`grip_or_skid`)."""
        s = STATE_PER_BALL * k
        self.state[s + 4] = self.state[s + 5] = self.zero
        self.unpin(k)  # at rest in its corner, rolling: nothing presses it any more
        self.set_mode(k)
        self.rerolls += 1
        self.grip_or_skid(k)
        for other in range(self.scene.n_bodies):
            b, s = BALL_PARS * other, STATE_PER_BALL * other
            if other == k or self.pars[b + SLIDING] == self.zero:
                continue
            along = self.state[s + 4] * self.pars[b + DX] + self.state[s + 5] * self.pars[b + DY]
            if along <= self.slip_tolerance * self.slip_scale[other]:
                self.state[s + 4] = self.state[s + 5] = self.zero
                self.set_mode(other)
                self.rerolls += 1

    def grip_or_skid(self, k: int) -> None:
        """A rider rolling under the ``slide`` cushion model keeps rolling while the cloth's friction can turn
        its spin with it, (kappa - 1) |v'| <= mu g (system module docstring); otherwise it skids from now."""
        if not self.riding[k] or self.slides(k) or not self.needs_grip[k] or k in self.onsets or self.ball_bonds[k]:
            return
        excess = self._grip_excess(k)
        if excess > 0:
            self.grip_lost(k, excess)

    def _grip_excess(self, k: int, shift: float = 0.0) -> float:
        """(kappa - 1) |v'| - mu g of rolling rider k (float), its position moved by ``shift`` along v."""
        b = BALL_PARS * k
        gx, gy, curvature = self._gap_terms(k, shift)
        return float(self.pars[b + SPIN]) * curvature / math.hypot(gx, gy) - float(self.pars[b + MU_G])

    def grip_lost(self, k: int, excess: float = 0.0) -> None:
        """Rolling rider k has lost its grip: the cloth's friction cannot turn its spin with it (the grip event,
        ``excess`` 0, or :meth:`grip_or_skid`, ``excess`` > 0 where it settled or an impact left it so).

        The slip grows from 0 as s' = e/(kappa - 1) (e = (kappa - 1)|v'| - mu g, now ``excess``, changing at
        e'), in the direction of the table's inside (where the saturated friction drives it; a slip's
        direction turns toward it at a rate nu/|u|, nu the cushion's push per unit mass). Integrated from a
        slip of ulps that rate makes steps of ~1e-13 s (measured: 9e5 steps for one onset at e = 0, 8.8e6 for
        a small e). So the ball rolls on, as the motion does to O(s), until its slip reaches SKID_ONSET,
        (kappa - 1) SKID_ONSET = e t* + e' t*^2/2, and skids from there with that slip: an error of
        ~SKID_ONSET t* in its speed (estimated; measured 8e-12 m/s, validation/billiards.py section 6) for
        ~1400 steps. Where the excess falls back to 0 first, it never skids. Without friction there is no
        direction to relax: it skids at once."""
        b, s = BALL_PARS * k, STATE_PER_BALL * k
        if not float(self.pars[b + MU_G]) > 0:
            self.start_skid(k, 2 * self.pars[self.system.slip_end])
            return
        speed = math.hypot(float(self.state[s + 2]), float(self.state[s + 3]))
        h = 1e-6 * float(self.geometry.size)
        rate = speed * (self._grip_excess(k, h) - self._grip_excess(k, -h)) / (2 * h)
        wait = _onset_wait(excess, rate, float(self.pars[b + SPIN]) * float(self.skid_onset))
        if wait is None:
            self.pars[b + GRIP] = self.zero + 1  # the excess turns back first: it keeps rolling
            return
        self.onsets[k] = self.t + self.num(wait)
        self.pars[b + GRIP] = self.zero

    def start_skid(self, k: int, slip) -> None:
        """Rolling rider k starts to skid with a slip of size ``slip`` toward the table's inside, where the
        saturated friction drives it (system module docstring; :meth:`grip_lost`)."""
        s = STATE_PER_BALL * k
        gx, gy = self._wall_gradient(k, self.ride_wall[k])
        norm = sqrt(gx * gx + gy * gy)
        self.state[s + 4], self.state[s + 5] = -slip * gx / norm, -slip * gy / norm
        self.set_mode(k)

    def unpin(self, k: int) -> None:
        """Ball k is no longer pinned in a corner (its slip ended, or an impact moved it): it rides nothing."""
        if self.pinned[k] is not None:
            self.pinned[k] = None
            self.riding[k] = False

    def pin(self, k: int, walls: tuple, normal) -> None:
        """Sliding friction presses ball k into both walls of a corner (the limit of its bounces between
        them): it stops there, the walls taking the friction's push, until its slip ends (set_mode). One row,
        law_flag SETTLED, on the second wall; the velocity's removal keeps the spin (the slip takes it)."""
        self.release_balls((k,))
        s = STATE_PER_BALL * k
        before = list(self.state)
        energy_before = self.energy(before)
        vx, vy = self.state[s + 2], self.state[s + 3]
        self.state[s + 2] = self.state[s + 3] = self.zero
        self.state[s + 4], self.state[s + 5] = self.state[s + 4] - vx, self.state[s + 5] - vy
        self.riding[k], self.ride_wall[k], self.pinned[k] = True, walls[0], tuple(walls)
        self.onsets.pop(k, None)
        self.set_mode(k)
        self.record(Contact("wall", k, walls[1], normal, self.zero), before, self.state, energy_before,
                    self.energy(self.state), SETTLED)

    def settle_corners(self, near: list) -> None:
        """A sliding ball at rest in a corner (two walls touching, its speed round-off, as a corner's solution at
        k = 0 leaves it, or too slow to leave the overlap limit): friction f = a n_A + b n_B (n the walls'
        outward normals). With a, b >= 0 it
        drives the ball into the corner: pinned (:meth:`pin`). Otherwise it rides the wall f presses into,
        away from the other, or neither. (Each wall on its own is not the test: in a 60 degree corner f
        pressed into one wall, drew away from the other, and still drove the ball into the corner along the
        first; it slid through the second: review.)"""
        walls: dict = {}
        for c in near:
            if c.kind == "wall":
                walls.setdefault(c.i, []).append(c)
        for k, touching in walls.items():
            if len(touching) < 2 or self.pinned[k] is not None or not self.slides(k):
                continue
            s = STATE_PER_BALL * k
            vx, vy = float(self.state[s + 2]), float(self.state[s + 3])
            fx, fy = self._free_acceleration(k)
            # at rest: its speed round-off, or too slow to get out of the overlap limit before friction turns it
            # (a corner's bounces at k = 0.1 left 4e-9 m/s; riding one wall, friction along it drove the ball into
            # the other from a gap of +6e-14 and heyoka missed that root: it slid through, review of random scenes)
            rest = max(float(self.speed_floor) ** 2, 2 * math.hypot(fx, fy) * float(self.geometry.overlap))
            if vx * vx + vy * vy > rest:
                continue
            first, second = touching[0], touching[1]
            (ax_, ay_), (bx_, by_) = ((float(v) for v in c.normal) for c in (first, second))
            det = ax_ * by_ - ay_ * bx_
            if det == 0:
                continue
            a = (fx * by_ - fy * bx_) / det
            b = (ax_ * fy - ay_ * fx) / det
            if a >= 0 and b >= 0:
                self.pin(k, (first.j, second.j), second.normal)
            elif a > 0 or b > 0:
                wall, (nx, ny) = (first.j, first.normal) if a > 0 else (second.j, second.normal)
                if not (self.riding[k] and self.ride_wall[k] == wall):
                    # its normal speed (up to sqrt(2 |f| overlap), more than round-off) removed in a row, the slip
                    # taking it (unrecorded, the spin took it: +2.2e-9 J, review)
                    moved = abs(vx * float(nx) + vy * float(ny)) > float(self.speed_floor)
                    self.ride(k, record=moved, wall=wall)

    def presses(self, k: int, wall: int) -> bool:
        """Ball k's free acceleration (its sliding friction; a cluster's member: its bonds' forces too) drives it into
        ``wall``."""
        gx, gy = self._wall_gradient(k, wall)
        ax, ay = self._present_acceleration(k) if self.ball_bonds[k] else self._free_acceleration(k)
        return ax * float(gx) + ay * float(gy) > 0

    def lift(self, k: int) -> None:
        """Skidding rider k lifts off its cushion (the cushion's normal force fell to zero): friction draws it
        into the table faster than the curve turns it. It slides freely from now, its wall event on again."""
        self.riding[k], self.pinned[k] = False, None
        self.lifted[k] = self.t
        self.set_mode(k)

    # -- impacts ---------------------------------------------------------------------------------
    def fired_contact(self, event) -> Contact | None:
        if event.kind == "wall":
            k = event.ball
            s = STATE_PER_BALL * k
            if k in self.geometry.exact:
                found = self.geometry.exact_wall(k, self.state[s], self.state[s + 1])
                if found is not None and found[0] > self.geometry.overlap and not self.about_to_touch(k, found):
                    # The degree-8 polynomial of a nearly circular ellipse can graze zero inside the
                    # table (measured: -1.1e-6 at x = 1.19 on the axis for a = 2, b = 1.605, R = 0.088),
                    # and its round-off then makes a root there: the exact distance says it is not a contact.
                    return None
                polished = self.polish(k)
                if polished is not None:
                    return Contact("wall", k, event.other, polished[1], polished[0])
            else:
                self.polish_root(k, event.other)
            d, normal = self.geometry.wall(k, event.other, self.state[s], self.state[s + 1])
            return Contact("wall", k, event.other, normal, d)
        self.polish_pair(event.ball, event.other)
        d, normal = self.geometry.pair(event.ball, event.other, self.state)
        return Contact("pair", event.ball, event.other, normal, d)

    def polish_pair(self, i: int, j: int) -> None:
        """One Newton step in time from heyoka's root of the shifted pair event (system.PAIR_EVENT_SHIFT) onto
        the exact contact |c_j - c_i| = R_i + R_j (the motion is a known quadratic over this round-off)."""
        si, sj = STATE_PER_BALL * i, STATE_PER_BALL * j
        dx, dy = self.state[sj] - self.state[si], self.state[sj + 1] - self.state[si + 1]
        dvx, dvy = self.state[sj + 2] - self.state[si + 2], self.state[sj + 3] - self.state[si + 3]
        _, reach = self.system.pairs[(i, j)]
        rate = 2 * (dx * dvx + dy * dvy)
        if rate < self.zero:
            dt = -(dx * dx + dy * dy - reach * reach) / rate
            if abs(dt) < self.system.cooldown:  # a correction of round-off, never a step of the motion
                self.advance(dt)

    def about_to_touch(self, k: int, found) -> bool:
        """Ball k, at ``found`` (exact distance, normal) from its cushion when the gap polynomial's root fired,
        meets the cushion within NEAR_ROOT of the crossing time: the root is the impact's, off by the polynomial's
        round-off, which grows near the nearly cusped ends of a ball with R near b^2/a (3.5e-8 m at R = 0.995
        b^2/a: taken for a spurious root, the impact was lost and the ball left the table, review)."""
        s = STATE_PER_BALL * k
        excess, (nx, ny) = found
        speed = self.state[s + 2] * nx + self.state[s + 3] * ny
        return speed > self.speed_floor and excess < NEAR_ROOT * self.geometry.size and \
            excess / speed < NEAR_ROOT * self.max_step

    def polish(self, k: int):
        """Move the instant of ball k's cushion impact onto the root of its exact distance (Newton's method
        in time: every ball's motion is a known quadratic). The gap polynomial of a small ball in an
        ellipse is ill conditioned near its root (contacts.ContactGeometry.exact); heyoka's root of it
        is off by up to ~1e-12 relative for R = a/200, this brings it back to round-off."""
        s = STATE_PER_BALL * k
        found = None
        for _ in range(2):  # Newton's method from heyoka's root, already within ~1e-12: one step, one check
            found = self.geometry.exact_wall(k, self.state[s], self.state[s + 1])
            if found is None:
                return None
            excess, (nx, ny) = found  # distance from the cushion minus R: 0 at contact
            speed = self.state[s + 2] * nx + self.state[s + 3] * ny
            if not speed > self.speed_floor:
                return found
            dt = excess / speed  # the distance falls at the approach speed
            if dt == self.zero:
                break
            if not abs(dt) < NEAR_ROOT * self.max_step:
                # a correction of heyoka's root, never a step of the motion (at a round-off approach speed it was
                # -0.96 s: every ball moved back, the impact times ran backwards; +0.42 s: another ball's impact
                # skipped, review)
                return found
            self.advance(dt)
        return found

    def polish_root(self, k: int, w: int) -> None:
        """One Newton step in time on the wall's gap function from heyoka's root (the motion is a known
        quadratic): heyoka's roots fell inside the cushion a little more often than outside (measured for a
        particle in an ellipse: 74 % of 1e5, mean gap -9e-18), which made its caustic drift one way."""
        s = STATE_PER_BALL * k
        _, c = self.system.walls[(k, w)]
        x, y = self.state[s], self.state[s + 1]
        g = self.scene.boundary.gap(w, x, y, c)
        gx, gy = self.scene.boundary.gradient(w, x, y, c)
        rate = gx * self.state[s + 2] + gy * self.state[s + 3]
        if rate > self.zero:
            dt = -g / rate
            if abs(dt) < self.system.cooldown:  # a correction of round-off, never a step of the motion
                self.advance(dt)

    def advance(self, dt) -> None:
        """Every ball along its constant-acceleration motion by dt (tiny: a polished impact instant)."""
        half = dt * dt / 2
        for k in range(self.scene.n_bodies):
            s, b = STATE_PER_BALL * k, BALL_PARS * k
            x, y, vx, vy, ux, uy = self.state[s:s + 6]
            fvx, fvy, fux, fuy = self.pars[b + FVX], self.pars[b + FVY], self.pars[b + FUX], self.pars[b + FUY]
            self.state[s:s + 6] = [x + vx * dt + fvx * half, y + vy * dt + fvy * half, vx + fvx * dt, vy + fvy * dt,
                                   ux + fux * dt, uy + fuy * dt]
        self.t = self.t + dt

    def at_instant(self, fired: Contact | None) -> None:
        """Resolve the contact heyoka found and every other one touching and approaching at this instant,
        then check the instant: no overlap, no ball grazing a curved cushion or pressed against a cushion;
        last, open the contacts resolved beside the one that fired past round-off (leave).

        Before each round of impacts the balls on a curved cushion are settled (:meth:`settle_riders`:
        a grazing ball starts riding, a riding ball keeps its cushion's normal speed at zero or leaves),
        so that every pair is judged with the velocities the balls go on with."""
        self.fired = fired
        self.resolved = []
        self.one_by_one = False  # set where a simultaneous solution would make energy (simultaneous)
        impulses = self.scene.simultaneous == "impulses"
        near = None  # the touching contacts of the state as it now is
        if fired is not None and not impulses:
            # a ball that meets a cushion in a corner meets both walls at once: one solution, as in the rounds below
            # (the fired wall alone first split a corner hit into two rows, flags 0 and 2: acceptance test)
            corner = [c for c in self._together(fired, self.touching(), False) if not _same(c, fired)] \
                if fired.kind == "wall" else []
            self._resolve_group(fired, [fired] + corner)
        first = fired if impulses else None
        cleanup = False  # 'impulses' after its simultaneous resolution: what it left, one by one
        rider_hits: dict = {}  # a pair with a riding ball resolved at this instant, how often
        collapsed = None  # such a pair resolved more than RIDER_PAIR_REPEATS times
        limited: set = set()  # such pairs whose sequence was taken to its limit, "sequential" (collapse_limit)
        for round_ in range(MAX_AT_ONE_INSTANT):
            if self.status is not None:
                if not impulses:
                    return
                break
            near = self.touching()
            if self.system.ride:
                self.settle_riders(near)
            if impulses and not cleanup:
                touching = self._simultaneous_group(near, first)
                approaching = [c for c in touching if self.closing(c)]
                if not approaching:
                    break
                if self.one_by_one:
                    self.resolve(approaching[0] if first is None or not _same(first, approaching[0]) else first)
                else:
                    # each set of touching contacts linked through their balls to one that approaches is one
                    # solution; one impact alone goes by the scene's law itself (a lone cushion impact was solved
                    # with a touching pair at rest elsewhere on the table, and flagged 2: acceptance test)
                    for group in _linked(touching, approaching):
                        self._resolve_group(first if first is not None and _same(first, group[0]) else group[0],
                                            group)
                        if self.one_by_one or self.status is not None:
                            break
                    cleanup = True
                first = None
            else:
                # 'impulses' leaves nothing approaching to its solver's tolerance (projected Gauss-Seidel beyond
                # MAX_SIMULTANEOUS contacts); what approaches faster (Hedrih's law on unequal radii inside the
                # solution, a ball settled since) goes by the scene's law, in order
                waiting = [c for c in near if self.closing(c) and (not cleanup or self.beyond_solver(c))]
                if not waiting:
                    break
                contact = waiting[0]
                if contact.kind == "pair" and (self.riding[contact.i] or self.riding[contact.j]):
                    key = (contact.i, contact.j)
                    rider_hits[key] = rider_hits.get(key, 0) + 1
                    if rider_hits[key] > RIDER_PAIR_REPEATS:
                        # resolved, settled back onto the cushion, met again, at one instant: the cushion turns
                        # them into each other (it went on 10,000 times: random scenes). Their limit: the sequence
                        # taken on without rows (then pressed together below where the pair is driven together);
                        # where it does not end either, the run stops
                        if key in limited or not self.collapse_limit(near):
                            collapsed = contact  # (met again after its limit: pressed together, or the run stops)
                            break
                        limited.add(key)
                        rider_hits[key] = 0
                        continue
                if self.bounces_back_at_once(contact):
                    # its limit: the impact and the re-roll, again and again at this instant, shrink the normal
                    # speed by (kappa - 1 - k)/kappa each, the tangential part kept: it settles on the wall, rolling
                    # (law_flag SETTLED). Impact by impact they went on to round-off and left 3e-14 m/s into the
                    # wall, and a ball that bounced at 1e-14 m/s every few hundred seconds (acceptance test)
                    self.ride(contact.i, record=True, wall=contact.j)
                    continue
                group = self._together(contact, near, cleanup)
                wedged = rider_hits.get((contact.i, contact.j), 0) > RIDER_PAIR_REPEATS // 2
                if round_ >= SEQUENTIAL_COLLAPSE and self.one_by_one and "sequential" not in limited:
                    # (where the simultaneous solution would make energy: the sequence's own limit, tried once; a
                    # ball between two others, plastic both sides, went past 2,000 impacts at one instant: random
                    # scenes. An elastic sequence that does not shrink has none: 0.5 s a try, random scenes)
                    limited.add("sequential")
                    if self.collapse_limit(near):
                        continue
                if (round_ >= SEQUENTIAL_COLLAPSE or wedged) and not self.one_by_one:
                    # a sequential collapse (k = 0 down a touching row: each impact leaves the next pair approaching,
                    # more slowly, for ever; a cradle of five went past 10,000 impacts; a ball wedged between two
                    # riders, bouncing from one to the other, 10 % slower each time: the run stopped): its limit,
                    # the touching contacts resolved together (the 'impulses' solution: at k = 0 on a row, every
                    # ball at the row's common speed, as the sequence's limit)
                    group = self._simultaneous_group(near)
                self._resolve_group(contact, group)
        else:
            self.stop(Status.FAILED, f"more than {MAX_AT_ONE_INSTANT} impacts at t = {float(self.t):.17g} s "
                                     "(an inelastic collapse): stopped")
            return
        if self.status is not None and self.status is not Status.MAX_COLLISIONS:
            return
        near = self.touching()
        overlapping = self.overlapping(near)
        if overlapping:
            c = overlapping[0]
            what = f"balls {c.i + 1} and {c.j + 1}" if c.kind == "pair" else f"ball {c.i + 1} and the cushion"
            self.status, self.message = Status.OVERLAP, (
                f"{what} overlap by {float(-c.distance):.3g} m at t = {float(self.t):.17g} s: an impact was missed")
            return
        if self.system.ride:
            self.settle_corners(near)
        # cushions first: a ball that settles onto its cushion now is judged as a rider in its pairs (a ball
        # driven by friction into one riding the cushion was judged against the free ball and went on impact by
        # impact, 1e-8 s apart); then pairs; and both again until nothing is pressed anew: a bond changes its
        # members' accelerations (a ball driven into a pressed pair's member was judged against the free member
        # and went on impact by impact, 6e-7 s apart: random scenes; a pair pressed into a cushion pushes its
        # member onto it)
        for _ in range(len(near) + 1):
            made = (frozenset(self.bonds), tuple(self.riding))
            for c in near:
                if c.kind == "wall" and self.status is None:
                    self.check_cushion_contact(c)
            for c in near:
                if c.kind == "pair" and self.status is None:
                    self.check_pressed_pair(c)
            if (frozenset(self.bonds), tuple(self.riding)) == made or self.status is not None:
                break
        if collapsed is not None and self.status is None:
            waiting = [c for c in self.touching() if c.kind == "pair" and self.closing(c)]
            if waiting:
                self.stop_pressed(waiting[0])
                return
        if self.status is None and self.bonds:
            # a press puts its cluster onto its contacts (project_cluster): a member moved by ~1e-11 m can touch a
            # ball outside the cluster that was not touching before; approaching, that is an impact of this instant
            # (its gap started the next step below zero and was never seen: an overlap of 2.5 cm, review)
            moved = [c for c in self.touching() if not any(_same(c, n) for n in near)]
            if any(self.closing(c) for c in moved) and self.depth < AT_INSTANT_REPEATS:
                self.depth += 1
                try:
                    self.at_instant(None)
                finally:
                    self.depth -= 1
                return
            near = near + moved
        # every touching contact but the one that fired (it has its cooldown, system.TableSystem.cooldown)
        # is opened past round-off, resolved now or not: one whose gap starts a step at zero would
        # close unseen if the motion turns it (a re-roll, friction). The one that fired too where it does not
        # separate (k = 0): friction closed such a pair 1.4 ms later, beyond the cooldown (random scenes); and
        # where a bond made or released at this instant replaced the integrator, whose events have no cooldown
        # (a ball's bounce off a cushion at the instant a pair let go: its next bounce was missed, random scenes)
        # The fired one's cooldown covers only a root at its event's own: where this instant moved its balls into
        # each other or into the cushion past the gap's round-off (a rider projected back onto its curve, a ball
        # carried, a member of a pressed pair left off the cushion without its partner), its gap starts the next
        # step below zero and, turned back by friction before it crosses zero, never fires (an overlap of 3e-8 m
        # from a pair left 4.4e-12 m into each other, separating at 4.5e-6 m/s: review); it is opened too.
        fresh = self.switched == self.t
        for c in near:
            if self.fired is None or fresh or not _same(c, self.fired) or self._past_round_off(c) or \
                    not -self.geometry.approach(c, self.state) > self.round_off * self._speed_scale(c):
                self.leave(c)

    def _resolve_group(self, contact: Contact, group: list) -> None:
        """``group`` (``contact`` and the touching contacts resolved with it) in one solution, or ``contact`` alone
        by the scene's law; a corner under 'sequential' wall after wall where that ends (:meth:`_corner_in_turn`)."""
        if len(group) > 1 and self._corner_in_turn(contact, group):
            return
        if len(group) > 1:
            self.simultaneous(group)
        else:
            self.resolve(contact)

    def _corner_in_turn(self, contact: Contact, group: list) -> bool:
        """A ball meeting the walls of a corner at once, under 'sequential': the walls one after the other, each by
        the cushion's law, starting with the one heyoka found, then whichever the ball approaches, while one is
        approached: one row per impact, if the sequence ends within CORNER_TURNS impacts (tried on a copy first).

        That is the limit of the hits beside the corner, where the two sides have one (a corner of pi/n: after n
        reflections v leaves mirrored in the line across the corner for n odd, as -v for n even); the one
        simultaneous solution gave -v in every corner (a 60 degree corner: review). Where the sequence does not
        end (an acute corner at k = 0 passes the velocity between its walls for ever, shrinking: 3,499 impacts,
        into denormals) its limit is the simultaneous solution: False, and the caller takes that."""
        if self.scene.simultaneous == "impulses" or any(c.kind != "wall" or self.rides(c) for c in group) \
                or self.pinned[contact.i] is not None:
            return False
        saved, order, current = self.state, [], contact
        self.state = list(saved)
        try:
            for _ in range(CORNER_TURNS):
                waiting = [c for c in group if self.closing(c)]
                if not waiting:
                    break
                c = next((w for w in waiting if _same(w, current)), waiting[0])
                self.resolver.wall(self.state, c.i, c.normal)
                order.append(c)
                current = next((w for w in group if not _same(w, c)), c)
            else:
                return False
        finally:
            self.state = saved
        for c in order:
            self.resolve(c)
        return True

    def collapse_limit(self, near: list) -> bool:
        """The limit of a sequence of impacts that does not end at one instant (a ball in a corner riding one wall,
        bouncing elastically off the other and plastically off a ball pressed onto it: each round keeps ~90 % of
        the normal speeds; it stopped the run after 32 rounds: random scenes): the touching contacts of the group
        resolved one by one, each by its own law (a ridden wall: the normal speed into it removed, as ride()), on
        the state without rows, until none approaches past round-off, at most COLLAPSE_ROUNDS rounds. Then one row
        per contact it resolved, law_flag SIMULTANEOUS, the group's energy change on the first. False (the state
        as it was): the sequence did not end."""
        group = self._simultaneous_group(near)
        balls = {c.i for c in group} | {c.j for c in group if c.kind == "pair"}
        self.release_balls(balls)
        before = list(self.state)
        energy_before = self.energy(before)
        used: list = []
        for _ in range(COLLAPSE_ROUNDS):
            waiting = [c for c in group if (self._pressing(c) if self.rides(c) else self.closing(c))]
            if not waiting:
                break
            c = waiting[0]
            if self.rides(c):
                self._remove_normal_speed(c.i, c.normal, keep_spin=self.slides(c.i) or self.needs_grip[c.i])
            elif c.kind == "wall":
                self.resolver.wall(self.state, c.i, c.normal)
            else:
                self.resolver.pair(self.state, c.i, c.j, c.normal)
            if not any(_same(c, u) for u in used):
                used.append(c)
        else:
            self.state = before
            return False
        self._impulses_done(balls, before, energy_before, used)
        return True

    def _pressing(self, contact: Contact) -> bool:
        """The ball moves into the wall it rides faster than round-off (as settle_riders records it: ride())."""
        s = STATE_PER_BALL * contact.i
        into = self.state[s + 2] * contact.normal[0] + self.state[s + 3] * contact.normal[1]
        speed2 = self.state[s + 2] * self.state[s + 2] + self.state[s + 3] * self.state[s + 3]
        return into > self.zero and into * into > self.round_off * self.round_off * speed2

    def _remove_normal_speed(self, k: int, normal, keep_spin: bool) -> None:
        """Ball k's velocity along the unit ``normal`` removed; ``keep_spin``: its slip takes the change (the
        spin kept), else its rolling is kept (the slip unchanged)."""
        s = STATE_PER_BALL * k
        nx, ny = normal
        vn = self.state[s + 2] * nx + self.state[s + 3] * ny
        self.state[s + 2], self.state[s + 3] = self.state[s + 2] - vn * nx, self.state[s + 3] - vn * ny
        if keep_spin:
            self.state[s + 4], self.state[s + 5] = self.state[s + 4] - vn * nx, self.state[s + 5] - vn * ny

    def _simultaneous_group(self, near: list, first: Contact | None = None) -> list:
        """The touching contacts of one simultaneous solution (``first``: the contact heyoka found). A riding
        ball's cushion takes part where the ball is driven into it or hit by a ball (the ball presses on it as the
        impact happens; resolving the pair first and the cushion in a second solution put impulses on a separating
        pair and made energy: review)."""
        hit = {b for c in near if c.kind == "pair" and self.closing(c) for b in (c.i, c.j)}
        if first is not None and first.kind == "pair":
            hit.update((first.i, first.j))
        touching = [c for c in near if not self.rides(c) or c.i in hit or self.closing(c)]
        if first is not None and not any(_same(first, c) for c in touching):
            touching.append(first)
        return touching

    def _together(self, contact: Contact, near: list, cleanup: bool) -> list:
        """The touching contacts resolved with ``contact`` in one solution, one by one otherwise:

        * a ball in a corner meets both walls at once (pairwise, an acute corner at k = 0 passed the velocity
          between them 3,499 times, into denormals, and the ball left the table);
        * a hit riding ball presses on its cushion as the impact happens: the pair and the riders' cushions,
          as under 'impulses' (not in the clean-up after that solution: Hedrih's law on unequal radii leaves
          pairs approaching there, and they go by the scene's law)."""
        if self.one_by_one:
            return [contact]
        if contact.kind == "wall":
            return [c for c in near if c.kind == "wall" and c.i == contact.i]
        if not cleanup and (self.riding[contact.i] or self.riding[contact.j]):
            return [contact] + [c for c in near if self.rides(c) and c.i in (contact.i, contact.j)]
        return [contact]

    def touching(self) -> list:
        """The contacts touching now (within the contact tolerance), and every riding ball's cushion wherever
        round-off has put the ball: an impact can drive a rider into it (a hit rider 2.9e-12 m off its curve,
        beyond the tolerance, rode on into the cushion at 0.41 m/s and overlapped it by 6 mm: review)."""
        near = self.geometry.contacts(self.state, self.geometry.touch)
        for k, on in enumerate(self.riding):
            if on and not any(self.rides(c) and c.i == k for c in near):
                s, w = STATE_PER_BALL * k, self.ride_wall[k]
                distance, normal = self.geometry.wall(k, w, self.state[s], self.state[s + 1])
                near.append(Contact("wall", k, w, normal, distance))
        return near

    def overlapping(self, near: list) -> list:
        """The contacts of ``near`` that overlap: an impact was missed. A riding ball is held on its wall's gap
        polynomial, g = 0; for a finite ball in an ellipse that polynomial's zero is off the exact parallel
        curve by its round-off, which grows where the curve nearly has a cusp (R near b^2/a: 3.2e-9 m at
        R = 0.49, b^2/a = 0.5, measured by a review): its own wall overlaps only beyond 2^10 times the limit."""
        limit = self.geometry.overlap
        return [c for c in near if c.distance < -(limit * 2**10 if self.rides(c) else limit)]

    def closing(self, contact: Contact) -> bool:
        """The contact approaches: an impact to resolve. Where balls can ride (system.can_ride) a cushion only
        when the ball is driven into it faster than the grazing limit: slower, the ball settles onto it
        (settle_riders; its normal speed is otherwise round-off: measured, k = 0 met +4.6e-17 again and
        again, 10,000 impacts at one instant)."""
        if contact.kind == "pair" and self.bonded_pair(contact.i, contact.j):
            return False  # pressed together: held at contact by its force, never an impact
        speed = self.geometry.approach(contact, self.state)
        if not speed > self.speed_floor:
            return False
        if contact.kind == "pair":  # round-off is no approach: a law leaving +6.9e-18 was resolved 10,000 times
            return speed > self.round_off * self._speed_scale(contact)
        if contact.kind == "wall" and self.system.ride:  # below it the ball grazes: it settles (settle_riders)
            s = STATE_PER_BALL * contact.i
            vx, vy = self.state[s + 2], self.state[s + 3]
            return speed * speed >= self._grazing_limit(contact.i, contact.j, self.settle_limit) * (vx * vx + vy * vy)
        return True

    def rides(self, contact: Contact) -> bool:
        """The contact is a ball's cushion wall that it rides (or one of the two it is pinned by)."""
        k = contact.i
        return contact.kind == "wall" and self.riding[k] and (contact.j == self.ride_wall[k]
                                                              or contact.j in (self.pinned[k] or ()))

    def beyond_solver(self, contact: Contact) -> bool:
        """The contact approaches faster than a simultaneous solution's tolerance (2^20 ulps of the speeds)."""
        return self.geometry.approach(contact, self.state) > self.solver_tolerance * self._speed_scale(contact)

    def _speed_scale(self, contact: Contact) -> object:
        """|vx| + |vy| of the contact's ball(s): the scale of its approach speed's round-off."""
        balls = (contact.i,) if contact.kind == "wall" else (contact.i, contact.j)
        scale = self.zero
        for b in balls:
            s = STATE_PER_BALL * b
            scale = scale + abs(self.state[s + 2]) + abs(self.state[s + 3])
        return scale

    def resolve(self, contact: Contact) -> None:
        self.release_balls((contact.i,) if contact.kind == "wall" else (contact.i, contact.j))
        before = list(self.state)
        energy_before = self.energy(before)
        if contact.kind == "wall":
            flag = self.resolver.wall(self.state, contact.i, contact.normal)
        else:
            flag = self.resolver.pair(self.state, contact.i, contact.j, contact.normal)
        for k in (contact.i,) if contact.kind == "wall" else (contact.i, contact.j):
            self.onsets.pop(k, None)  # its velocity changed: its grip is judged again (grip_or_skid)
            self.unpin(k)
            self.set_mode(k)
        self.record(contact, before, self.state, energy_before, self.energy(self.state), flag)
        self.resolved.append(contact)

    def leave(self, contact: Contact) -> None:
        """Put a contact just resolved on its open side by more than its gap function's round-off.

        heyoka misses the later roots of an event function whose value at the start of a step is
        zero to within round-off, unless the event has just fired and its cooldown covers that root
        (measured: a ball leaving a circular cushion from g = x^2 + y^2 - rho^2 = -1.1e-16 recrossed
        it 3.3 ms later unseen, in a step of 0.01 s, while g = -3e-16 was seen). For the contacts
        resolved at an instant besides the one that fired (simultaneous impacts, touching starts)
        this moves the ball(s) along the normal, by ulps of position, until the gap is open by a
        margin of a few hundred ulps of its terms.
        """
        s = STATE_PER_BALL * contact.i
        nx, ny = contact.normal
        step = self.nudge
        if self.rides(contact) or (contact.kind == "pair" and self.bonded_pair(contact.i, contact.j)):
            return  # it stays on the cushion's curve (at its partner: pressed together); its event is off
        if contact.kind == "wall":
            x0, y0 = self.state[s], self.state[s + 1]
            for _ in range(LEAVE_DOUBLINGS):  # at most ~2^20 ulps in all: never past the overlap guard's reach
                if self._open_gap(contact) > 0:
                    break
                self.state[s] = self.state[s] - step * nx
                self.state[s + 1] = self.state[s + 1] - step * ny
                step = step * 2
            self._carry(contact.i, self.state[s] - x0, self.state[s + 1] - y0)
            return
        o = STATE_PER_BALL * contact.j
        # a ball riding its cushion stays on its curve: the other ball takes the whole opening (moved off the curve
        # into the cushion, the rider was put back onto it when it was next settled, into its partner: 4.4e-12 m,
        # which the pair's gap never came back up through, review; as close_start moves the ball not on a cushion)
        mine, other = (self.zero, 2 * self.zero + 2) if self.riding[contact.i] and not self.riding[contact.j] else \
            (2 * self.zero + 2, self.zero) if self.riding[contact.j] and not self.riding[contact.i] else \
            (self.zero + 1, self.zero + 1)
        for _ in range(LEAVE_DOUBLINGS):
            if self._open_gap(contact) > 0:
                return
            self.state[s], self.state[s + 1] = self.state[s] - mine * step * nx, self.state[s + 1] - mine * step * ny
            self.state[o], self.state[o + 1] = self.state[o] + other * step * nx, self.state[o + 1] + other * step * ny
            step = step * 2

    def _gap_opening(self, contact: Contact) -> tuple:
        """(the contact's gap function, > 0 open, and the margin of its round-off; leave's measure), in the
        function's own units: -g for a wall, |dc|^2 - (R_i + R_j)^2 for a pair."""
        s = STATE_PER_BALL * contact.i
        if contact.kind == "wall":
            _, c = self.system.walls[(contact.i, contact.j)]
            return (-self.scene.boundary.gap(contact.j, self.state[s], self.state[s + 1], c),
                    self.round_off * self.scene.boundary.gap_scale(contact.j, c))
        o = STATE_PER_BALL * contact.j
        _, reach = self.system.pairs[(contact.i, contact.j)]
        reach2 = reach * reach  # the exact contact (the event's parameter is shifted inside it: system)
        dx, dy = self.state[o] - self.state[s], self.state[o + 1] - self.state[s + 1]
        return dx * dx + dy * dy - reach2, self.round_off * (reach2 + reach * self.geometry.size)

    def _open_gap(self, contact: Contact):
        """The contact's gap past its round-off margin (> 0: leave() has opened it)."""
        opening, margin = self._gap_opening(contact)
        return opening - margin

    def _past_round_off(self, contact: Contact) -> bool:
        """The contact overlaps past its gap function's round-off: not at a root heyoka has just found (a held
        contact, a ridden wall or a pressed pair, is the cushion's or the bond's to keep)."""
        if self.rides(contact) or (contact.kind == "pair" and self.bonded_pair(contact.i, contact.j)):
            return False
        opening, margin = self._gap_opening(contact)
        return opening < -margin

    def _carry(self, k: int, dx, dy) -> None:
        """Ball k was moved by (dx, dy) off its cushion (leave): a ball it touches and now overlaps beyond
        round-off moves with it, and so on along a row (opening a cushion contact moved a ball 4.7e-10 m into its
        neighbour, and that pair, overlapping from the start of a step, closed unseen: fuzz review)."""
        if dx == self.zero and dy == self.zero:
            return
        moved, queue = {k}, [k]
        while queue:
            a = queue.pop()
            for b in range(self.scene.n_bodies):
                if b in moved or self.bonded_pair(a, b):
                    continue
                _, reach = self.system.pairs[(min(a, b), max(a, b))]
                sa, sb = STATE_PER_BALL * a, STATE_PER_BALL * b
                ex, ey = self.state[sb] - self.state[sa], self.state[sb + 1] - self.state[sa + 1]
                now = ex * ex + ey * ey - reach * reach  # and before a moved: (e + d)^2 - reach^2
                before = (ex + dx) * (ex + dx) + (ey + dy) * (ey + dy) - reach * reach
                if not (now < before and now < -self.round_off * (reach * reach + reach * self.geometry.size)):
                    continue
                self.state[sb], self.state[sb + 1] = self.state[sb] + dx, self.state[sb + 1] + dy
                moved.add(b)
                queue.append(b)

    def check_cushion_contact(self, contact: Contact) -> None:
        """A ball that stays on a cushion: settled where it can ride it; else the run stops, saying why.

        * Grazing a curved cushion: after an impact at normal speed v_n along a cushion of radius of
          curvature rho the ball's chord dips into the table by about v_n^2 rho / (2 v^2) before the
          next impact; below the contact resolution the impacts can no longer be told apart. With
          k < 1 they accumulate (v_n shrinks by k each time, in a finite time): the ball settles onto
          the cushion and rolls or skids along it pressed against it (:meth:`settle_riders`,
          :meth:`ride`). A ball started touching a curved cushion and moving along it is the same case.
          A sliding ball that friction draws into the table leaves it. Where riding is not compiled
          (k = 1, no ball can slide nor starts along a curved cushion: system.can_ride) the run stops.
        * Pressed against a cushion: no normal speed left (k = 0), or bounces too low to resolve, while
          sliding friction drives the ball into the cushion. Where riding is compiled (k < 1) it is their
          limit: the ball settles and skids along this wall (a ball riding another wall, in a corner, now rides
          this one); otherwise (k = 1: its bounces do not shrink) the run stops.
        """
        k = contact.i
        s = STATE_PER_BALL * k
        vx, vy = self.state[s + 2], self.state[s + 3]
        nx, ny = contact.normal
        vn = -(vx * nx + vy * ny)  # into the table
        speed2 = vx * vx + vy * vy
        # (where riding is not compiled, k = 1, a graze the contact resolution can follow goes on: unchanged)
        limit = self._grazing_limit(k, contact.j, self.grazing) if self.system.ride else self.grazing
        grazing = self.grazing is not None and vn * vn < limit * speed2
        if self.rides(contact):
            return
        if grazing and speed2 > self.zero:
            if self.lifted.get(k) == self.t or not self.pressed_on(k, contact.j):
                return  # friction draws it into the table: it leaves the cushion
            if self.system.ride:
                # pressed on only since the instant's last settle (settle_riders, before each round of impacts): a
                # press made below put it into a cluster whose push holds it on the cushion, where its own friction
                # drew it off. The limit of its accumulating impacts, as settle_riders would take it now: it rides
                # (a member: its cushion joins the cluster). It stopped the run here, "too slow to resolve its next
                # impact", at k = 0.7, 0.3 and 0 (review; tests/test_table_grazing.py)
                self.ride(k, record=True, wall=contact.j)
                return
            self.stop(Status.FAILED, f"ball {k + 1} moves along the curved cushion at t = {float(self.t):.17g} s with a "
                                     f"normal speed {abs(float(vn / sqrt(speed2))):.3g} of its speed, too slow to resolve its "
                                     "next impact (impacts accumulate: the ball settles onto the cushion; at k = 1 riding is "
                                     "compiled only where a ball can slide or starts along a curved cushion)")
            return
        # sliding friction, also a skid's along another wall (a corner); a cluster's member: its bonds' forces too
        ax, ay = self._present_acceleration(k) if self.ball_bonds[k] else self._free_acceleration(k)
        push = ax * float(nx) + ay * float(ny)
        if self.lifted.get(k) == self.t:
            # it left its cushion at this instant (its cluster's cushion bond let go): its push and the bond's
            # force disagree at round-off; settled again, it was let go again, 4,900 rows at one instant (review)
            return
        if push > 0 and (not vn * vn > self.grazing_straight * speed2 or self.pressed(k, vn, speed2, push, contact.j)):
            if self.system.ride:  # the limit of its bounces: it skids along this wall (a rider: now this one)
                # (a rider that its cluster holds on its wall presses into it: the bond's force is > 0; judged by its
                # acceleration with that force it never does, and went wall to wall, 1,383 rows at one instant)
                held = ("wall", k, self.ride_wall[k]) in self.ball_bonds[k]
                if self.riding[k] and self.pinned[k] is None and (held or self.presses(k, self.ride_wall[k])):
                    self.pin(k, (self.ride_wall[k], contact.j), contact.normal)  # into both: a corner holds it
                else:
                    self.ride(k, record=True, wall=contact.j)
                return
            self.stop(Status.FAILED, f"ball {k + 1} is pressed against the cushion at t = {float(self.t):.17g} s (no "
                                     "normal speed left, sliding friction driving it into the cushion): sliding along "
                                     "a cushion is not modelled")

    def bounces_back_at_once(self, contact: Contact) -> bool:
        """Ball k, bounced off this wall at this instant already, rolls into it again: under the ``slide``
        cushion model at k_c < kappa - 1 the slip of a slow bounce is so small that friction ends it within the
        cooldown (set_mode ends it at once), and the ball, rolling again at ((kappa - 1) - k_c)/kappa of its
        normal speed, comes straight back (paper section 7; a sequence of impacts in zero time). Only straight
        back: a ball sent into the cushion again by another ball at this instant bounces (review)."""
        k = contact.i
        return (contact.kind == "wall" and self.scene.cushion.name == "slide" and self.system.ride
                and not self.riding[k] and not self.ball_bonds[k] and not self.slides(k) and self.pinned[k] is None
                and bool(self.resolved) and _same(self.resolved[-1], contact))

    def pressed(self, k: int, vn, speed2, push, wall: int) -> bool:
        """Sliding friction drives ball k back into the cushion it has just left at v_n: its bounces then
        shrink by k_c each (a Zeno sequence: over in 2 v_n / (a (1 - k_c)), a = the push) and end with it
        pressed on, still sliding, unless (a) a bounce, v_n^2 / (2 a), can still be resolved, (b) the slip
        ends first (|u| / its rate of decrease: the ball rolls), or (c) the cushion's curve feeds the normal
        speed faster than the bounces lose it (v_t turns by v_t tau / rho each bounce of tau = 2 v_n / a:
        2 v_t^2 / (rho a) >= 1 - k_c, rho the least radius of curvature: a chatter that goes on until the
        slip ends). Found by review: a ball sliding head-on into a cushion (friction 0.01, k_c = 0.3) piled
        up 29 bounces, then passed through the cushion unseen (status overlap). A bounce is resolved where it
        rises above the contact resolution and above the opening leave() gives the wall's gap (its round-off
        in metres, 4.5e-10 m on an ellipse's parallel curve): lower, the ball falls that opening back into
        the cushion every bounce and comes back faster than it left (acceptance test: a pressed pair's member
        chattered at 1e-5 m/s every 1.2e-4 s, thousands of rows, instead of settling)."""
        a, vn = float(push), float(vn)
        if vn * vn >= 2 * a * max(float(self.geometry.touch), self._opening(k, wall)):
            return False
        k_c = float(self.scene.cushion.restitution)
        if k_c >= 1:
            # its bounces do not shrink, but one that friction turns back within the contact resolution is not
            # seen (review: a disk left 4.8e-13 m/s from a cushion at k = 1 passed 1.9 cm through it)
            return True
        if self.grazing is not None:  # a curved cushion
            rho = self.scene.boundary.least_curvature_radius(self.scene.balls[k].body.radius)
            if 2 * (float(speed2) - vn * vn) / (rho * a) >= 1 - k_c:
                return False
        if self.ball_bonds[k]:
            return True  # its cluster's push, not its own slip, drives it in: it lasts while the bonds hold
        s = STATE_PER_BALL * k
        slip = math.hypot(float(self.state[s + 4]), float(self.state[s + 5]))
        rate = float(self.slide_u[k])
        if rate == 0 or 2 * vn / (a * (1 - k_c)) < slip / rate:
            return True
        # the slip ends first and the ball rolls on; on a curved cushion one still moving back into it then returns,
        # rolling, from no higher than the unresolved bounce (on a straight wall such returns come at the same
        # instant: bounces_back_at_once): it settles now. On an ellipse they crept back from leave()'s opening,
        # bounces of 1e-7..1e-11 m/s for seconds, and settled 6.6 s late (review)
        return self.grazing is not None and vn - a * slip / rate <= 0

    def _opening(self, k: int, wall: int) -> float:
        """How far (m) leave() puts ball k off this wall at most: the margin of the gap function's round-off
        over its gradient, twice (leave's steps double), and never more than leave's steps can reach (near the
        parallel curve's nearly cusped ends the gradient vanishes: 2.1e-4 m there glued a ball bouncing at
        0.02 m/s to the cushion, review)."""
        s = STATE_PER_BALL * k
        _, c = self.system.walls[(k, wall)]
        gx, gy = self.scene.boundary.gradient(wall, self.state[s], self.state[s + 1], c)
        margin = self.round_off * self.scene.boundary.gap_scale(wall, c)
        reach = float(self.nudge) * 2.0**LEAVE_DOUBLINGS
        return min(2 * float(margin) / max(math.hypot(float(gx), float(gy)), 1e-300), reach)

    def _grazing_limit(self, k: int, wall: int, limit):
        """(v_n/v)^2 under which ball k grazing this curved cushion cannot be followed: ``limit`` (the chord's dip
        under the contact resolution), or the dip under the opening leave() gives its gap there where that is
        larger (near the centre curve's tightest bends: a ball left at v_n/v = 7.5e-6 dipped 2e-12 m into the
        cushion, unseen, and went through it, review)."""
        if self.curvature_radius is None:
            return limit
        return max(limit, self.num(2 * self._opening(k, wall) / self.curvature_radius))

    def slides(self, k: int) -> bool:
        """Ball k slides on the cloth (a slip, with or without friction to end it)."""
        return self.pars[BALL_PARS * k + SLIDING] != self.zero or self._has_slip(k)

    def settle_riders(self, near: list) -> bool:
        """The balls on a curved cushion at this instant, before a round of impacts (system.can_ride).

        A ball that grazes its cushion (normal speed under the grazing limit) and rolls starts riding it
        (:meth:`ride`); a riding ball whose normal speed is under the limit keeps riding, that speed
        removed (the limit of its accumulating impacts again: a row, law_flag SETTLED, where an impact at
        this instant gave it that speed), and one sent into the table faster leaves the cushion (its wall
        event is on again). Faster into the cushion it is an impact (``closing``). A sliding ball is left
        only while it is pressed on (a sliding ball whose friction draws it into the table leaves; so does one
        that has just lifted off). True: a ball's velocity or riding changed."""
        changed = False
        walls = [c for c in near if c.kind == "wall"]
        held = {(c.i, c.j) for c in walls}
        for k, on in enumerate(self.riding):  # a riding ball is judged wherever round-off has put it
            if on and (k, self.ride_wall[k]) not in held:
                s, w = STATE_PER_BALL * k, self.ride_wall[k]
                distance, normal = self.geometry.wall(k, w, self.state[s], self.state[s + 1])
                walls.append(Contact("wall", k, w, normal, distance))
        for c in walls:
            k = c.i
            if self.riding[k] and (not self.rides(c) or self.ball_bonds[k]):
                continue  # another wall of a riding ball (a corner): an ordinary contact; its cluster holds it on
            s = STATE_PER_BALL * k
            vx, vy = self.state[s + 2], self.state[s + 3]
            into = vx * c.normal[0] + vy * c.normal[1]
            speed2 = vx * vx + vy * vy
            limit = self._grazing_limit(k, c.j, self.settle_limit_sliding if not self.riding[k] and self.slides(k)
                                        else self.settle_limit)
            grazing = into * into < limit * speed2
            if not self.riding[k]:
                if grazing and speed2 > self.zero and self.lifted.get(k) != self.t and self.pressed_on(k, c.j):
                    self.ride(k, record=True, wall=c.j)
                    changed = True
            elif grazing:
                if into != self.zero:  # more than round-off: an impact at this instant gave it that speed
                    moved = abs(into) > self.round_off * sqrt(speed2) and any(
                        r.i == k or (r.kind == "pair" and r.j == k) for r in self.resolved)
                    self.ride(k, record=moved)
                    changed = changed or moved
            elif into < self.zero:
                # (out of its corner too: left pinned while riding nothing, its second wall's event stayed off when
                # it joined a cluster again, which carried it 7e-5 m through that wall: random scenes)
                self.riding[k], self.pinned[k] = False, None
                self.set_mode(k)
                changed = True
        return changed

    def pressed_on(self, k: int, wall: int | None = None) -> bool:
        """Ball k, touching its curved cushion with no normal speed, is pressed on: the second derivative of
        its gap, v^T H v + grad g . a (a its acceleration without the cushion), is > 0. A rolling ball on a
        convex cushion always is; friction can draw a sliding ball off."""
        gx, gy, curvature = self._gap_terms(k, wall=wall)
        ax, ay = self._present_acceleration(k) if self.ball_bonds[k] else self._free_acceleration(k)
        return curvature + gx * ax + gy * ay > 0

    def _gap_terms(self, k: int, shift: float = 0.0, wall: int | None = None) -> tuple:
        """(dg/dx, dg/dy, v^T H v) of ball k's gap to ``wall`` (default: the one it rides; float, the Hessian
        along v by central differences of the gradient: for a decision, not the motion), its position moved by
        ``shift`` along v (v then turned to stay normal to the gradient, as on a ride)."""
        s = STATE_PER_BALL * k
        w = self.ride_wall[k] if wall is None else wall
        _, c = self.system.walls[(k, w)]
        c = [float(v) for v in c]
        gradient = self.scene.boundary.gradient

        x, y, vx, vy = (float(v) for v in self.state[s:s + 4])
        speed = math.hypot(vx, vy)
        if speed == 0:
            return (*gradient(w, x, y, c), 0.0)
        ux, uy = vx / speed, vy / speed
        if shift:
            x, y = x + shift * ux, y + shift * uy
            gx, gy = gradient(w, x, y, c)
            norm = math.hypot(gx, gy)
            turn = 1.0 if gx * uy - gy * ux >= 0 else -1.0  # the side of the normal v is on
            ux, uy = -turn * gy / norm, turn * gx / norm
        gx, gy = gradient(w, x, y, c)
        h = 1e-6 * float(self.geometry.size)
        fx, fy = gradient(w, x + h * ux, y + h * uy, c)
        bx, by = gradient(w, x - h * ux, y - h * uy, c)
        return gx, gy, speed * speed * (ux * (fx - bx) + uy * (fy - by)) / (2 * h)

    def _free_acceleration(self, k: int) -> tuple:
        """Ball k's acceleration without its cushion (float): its free sliding one, or, skidding, the cloth's
        friction against its slip now."""
        b, s = BALL_PARS * k, STATE_PER_BALL * k
        if self.ball_bonds[k] and not self.slides(k):
            return 0.0, 0.0  # a rolling member of a cluster of bonds: no friction of its own
        if self.pars[b + SKID] == self.zero and not self.ball_bonds[k]:
            return float(self.pars[b + FVX]), float(self.pars[b + FVY])
        ux, uy = float(self.state[s + 4]), float(self.state[s + 5])
        norm, mu_g = math.hypot(ux, uy), float(self.pars[b + MU_G])
        return (-mu_g * ux / norm, -mu_g * uy / norm) if norm > 0 else (0.0, 0.0)

    def check_pressed_pair(self, contact: Contact) -> None:
        """Stop where two touching balls stay pressed together: a contact mode that is not modelled. After the
        instant the pair opens at v and its gap's acceleration a < 0 (sliding friction, or a riding ball's
        curve, turns one into the other) closes it again; if it opens by less than the contact resolution,
        v^2 / (2 |a|), heyoka cannot see it close (the review found a riding pair overlapping unseen; random
        scenes found two sliding balls whose friction drove them together overlapping after their bounces
        accumulated)."""
        i, j = contact.i, contact.j
        if self.bonded_pair(i, j) or self.let_go.get((i, j)) == self.t:
            return  # pressed together already, or let go at this very instant
        si, sj = STATE_PER_BALL * i, STATE_PER_BALL * j
        nx, ny = (float(v) for v in contact.normal)
        vi = float(self.state[si + 2]), float(self.state[si + 3])
        vj = float(self.state[sj + 2]), float(self.state[sj + 3])
        ai, aj = self._present_acceleration(i), self._present_acceleration(j)
        rvx, rvy = vj[0] - vi[0], vj[1] - vi[1]
        opening = rvx * nx + rvy * ny
        tangential2 = rvx * rvx + rvy * rvy - opening * opening
        _, reach = self.system.pairs[(i, j)]
        if not reach > self.zero:
            return  # two particles: points, nothing to press (and no curvature of their gap to divide by)
        acceleration = (aj[0] - ai[0]) * nx + (aj[1] - ai[1]) * ny + tangential2 / float(reach)
        if acceleration < 0 and opening * opening < 2 * -acceleration * float(self.geometry.touch):
            if self.why_not_pressed(i, j):
                self.stop_pressed(contact)
            else:
                self.press(contact)

    def stop_pressed(self, contact: Contact) -> None:
        i, j = contact.i, contact.j
        why = self.why_not_pressed(i, j)
        if why:
            self.stop(Status.FAILED, f"balls {i + 1} and {j + 1} stay pressed together at t = {float(self.t):.17g} "
                                     f"s, where {why}: not modelled")
        else:  # (the rider-pair repeats of at_instant; the old text said a cushion turned them into each other)
            self.stop(Status.FAILED, f"balls {i + 1} and {j + 1}, one riding the cushion, meet again and again at "
                                     f"t = {float(self.t):.17g} s, neither separating nor driven together (an "
                                     "inelastic collapse through the cushion): not modelled")

    def _present_acceleration(self, k: int) -> tuple:
        """Ball k's acceleration now (float): its free one (:meth:`_free_acceleration`) and, riding, the
        cushion's -lambda grad g."""
        if self.ball_bonds[k]:  # its cluster's contact forces (system._bond_terms, without Baumgarte's terms)
            return self.bond_forces(bonds_module.cluster_of(self.bonds, k))[1][k]
        ax, ay = self._free_acceleration(k)
        if not self.riding[k]:
            return ax, ay
        gx, gy, curvature = self._gap_terms(k)
        lam = (curvature + gx * ax + gy * ay) / (gx * gx + gy * gy)
        return ax - lam * gx, ay - lam * gy

    def ride(self, k: int, record: bool, wall: int | None = None) -> None:
        """Ball k settles onto its (curved) cushion and rides it from now on (system module docstring).

        The limit of the accumulating impacts (k < 1): the centre put onto the cushion's curve g = 0
        (Newton's method along grad g), the normal part of its velocity removed, the tangential part
        kept; rolling kept under the ``rolling`` model (the slip unchanged), the spin kept under ``slide``
        (the slip changed as v). With ``record`` it is one row of the impact table,
        law_flag SETTLED, whose energy change is what the rest of the accumulation would dissipate.
        """
        if self.ball_bonds[k] and self.joins_cluster_on_cushion(k, self.ride_wall[k] if wall is None else wall, record):
            return
        self.release_balls((k,))  # (riding and pressed together at once is not modelled: check_pressed_pair)
        s = STATE_PER_BALL * k
        w = self.ride_wall[k] = self.ride_wall[k] if wall is None else wall
        sliding = self.slides(k)
        before = list(self.state)
        energy_before = self.energy(before)
        _, c = self.system.walls[(k, w)]
        boundary = self.scene.boundary
        x, y = self.state[s], self.state[s + 1]
        for _ in range(PROJECTION_STEPS):
            g = boundary.gap(w, x, y, c)
            gx, gy = boundary.gradient(w, x, y, c)
            step = g / (gx * gx + gy * gy)
            x, y = x - step * gx, y - step * gy
            if abs(step) * sqrt(gx * gx + gy * gy) <= self.nudge:
                break
        gx, gy = boundary.gradient(w, x, y, c)
        norm = sqrt(gx * gx + gy * gy)
        nx, ny = gx / norm, gy / norm
        self.state[s], self.state[s + 1] = x, y
        # the slide model's cushion pushes through the centre, and a sliding ball's rolling is no rolling to keep:
        # the spin is kept, the slip takes the change of v (energy then falls by 1/2 m v_n^2; keeping the slip
        # turned the spin and made energy: +6.8e-9 J, review; so did removing a skidding rider's drift of 5e-10 m/s,
        # unrecorded: +6.2e-11 J, acceptance test). Not for a rolling rider's round-off normal speed (record
        # False): that is no impulse, and as a slip of ~1e-17 it made a skid end at once, an event at every instant
        # of every other ball (measured); its rolling is kept.
        self._remove_normal_speed(k, (nx, ny), keep_spin=sliding or (record and self.needs_grip[k]))
        self.riding[k] = True
        self.set_mode(k)
        if record:
            self.record(Contact("wall", k, w, (nx, ny), self.zero), before, self.state, energy_before,
                        self.energy(self.state), SETTLED)
        self.grip_or_skid(k)

    def joins_cluster_on_cushion(self, k: int, wall: int, record: bool) -> bool:
        """Member k of a cluster of bonds settles onto its cushion: the cushion joins the cluster as a bond of k
        (as a rider's does when it is pressed, :meth:`new_bonds`), its centre projected and its normal speed
        removed by the cluster's holding impulses (one row, law_flag SETTLED, with ``record``). Its pair bonds
        were let go instead, and the pair, riding the cushion together with no force between them, met again
        3e-4 s later, pressed, let the cushion go, settled, ... 7 rows each time (acceptance test). False where
        the cluster cannot hold it (:meth:`why_not_pressed`'s limits): it is let go of its bonds and rides."""
        bond = ("wall", k, wall)
        if self._why_not_held(bonds_module.cluster_of(self.bonds | {bond}, k)):
            return False
        self.ride_wall[k], self.riding[k] = wall, True
        s = STATE_PER_BALL * k
        _, normal = self.geometry.wall(k, wall, self.state[s], self.state[s + 1])
        self.hold_with([bond], (k,), Contact("wall", k, wall, normal, self.zero) if record else None)
        return True

    def simultaneous(self, contacts: list) -> None:
        self.release_balls({c.i for c in contacts} | {c.j for c in contacts if c.kind == "pair"})
        before = list(self.state)
        energy_before = self.energy(before)
        impulses = self.resolver.impulses(self.state, contacts, self.geometry.approach)
        if impulses is None:
            self.state = before
            self.stop(Status.FAILED, f"no simultaneous impulses found for {len(contacts)} contacts at "
                                     f"t = {float(self.t):.17g} s")
            return
        if self.energy(self.state) > energy_before * (1 + self.solver_tolerance):
            # Newton's restitution on several contacts at once is not energy-consistent: a touching contact that
            # separates can take an impulse that drives its ball into another (review: a ball leaving the top
            # cushion, hit from below, ended at rest and sent the other off at 1.5 m/s, +80 % energy). Such an
            # instant goes contact by contact, in the sequential policy's order (each row its own law's flag).
            self.state = before
            self.one_by_one = True
            waiting = [c for c in contacts if self.closing(c)]
            if waiting:
                self.resolve(waiting[0])
            return
        balls = {c.i for c in contacts} | {c.j for c in contacts if c.kind == "pair"}
        self._impulses_done(balls, before, energy_before, [c for c, lam in zip(contacts, impulses) if lam > self.zero])

    def _impulses_done(self, balls, before, energy_before, contacts: list) -> None:
        """After impulses on ``balls`` that moved the state from ``before``: each ball's mode and grip judged again,
        one row per contact that took an impulse (law_flag SIMULTANEOUS), the group's energy change on the first
        (the rows' changes add up to the run's)."""
        for k in balls:
            self.onsets.pop(k, None)  # its velocity changed: its grip is judged again (grip_or_skid)
            self.unpin(k)
            self.set_mode(k)
        energy_after = self.energy(self.state)
        for c in contacts:
            self.record(c, before, self.state, energy_before, energy_after, SIMULTANEOUS)
            energy_before = energy_after
            self.resolved.append(c)

    def record(self, contact: Contact, before, after, energy_before, energy_after, flag) -> None:
        i = contact.i
        si = STATE_PER_BALL * i
        row = [self.t, i + 1]
        if contact.kind == "wall":
            nan = float("nan")
            nx, ny = contact.normal
            r = self.radius[i]
            row += [0, before[si], before[si + 1], before[si + 2], before[si + 3], after[si + 2], after[si + 3],
                    nan, nan, nan, nan, nan, nan, energy_before, energy_after,
                    before[si] + r * nx, before[si + 1] + r * ny, nx, ny, flag]
            self.cushion += 1
        else:
            j = contact.j
            sj = STATE_PER_BALL * j
            nan = float("nan")
            row += [j + 1, before[si], before[si + 1], before[si + 2], before[si + 3], after[si + 2], after[si + 3],
                    before[sj], before[sj + 1], before[sj + 2], before[sj + 3], after[sj + 2], after[sj + 3],
                    energy_before, energy_after, nan, nan, nan, nan, flag]
        self.records.append(row)
        self.count += 1
        if self.sink is not None and len(self.records) >= self.chunk_size:
            self.flush()
        if self.limit is not None and self.count >= self.limit:
            self.stop(Status.MAX_COLLISIONS, f"stopped after max_collisions = {self.limit} impacts")

    def flush(self) -> None:
        if self.sink is None or not self.records:
            return
        with signals_deferred():  # a chunk is written whole and counted once, then Ctrl-C or SIGTERM acts
            self.sink.write(self.records, self.flushed + 1)
            self.flushed += len(self.records)
            if self.kept is None:
                self.kept = self.records
            self.records = []

    def energy(self, state):
        total = self.zero
        for k in range(self.scene.n_bodies):
            s = STATE_PER_BALL * k
            vx, vy, ux, uy = state[s + 2:s + 6]
            wx, wy = vx - ux, vy - uy
            total = total + self.mass[k] * (vx * vx + vy * vy + self.spin_inertia[k] * (wx * wx + wy * wy)) / 2
        return total

    def finish(self, wall: float) -> TableResult:
        if self.status is None:
            self.stop(Status.INTERRUPTED, "interrupted before the run began")
        if self.status is Status.MAX_COLLISIONS and self.limit is not None and self.count > self.limit:
            # (an instant's simultaneous rows are written whole: the message said 1 where the table had 3, review)
            self.message = (f"stopped after max_collisions = {self.limit} impacts ({self.count} written: the last "
                            "instant's simultaneous impacts are kept together)")
        if self.status.success:  # the guarantee ends with the run: nothing overlaps at its last instant either
            overlapping = self.overlapping(self.geometry.contacts(self.state, self.geometry.touch))
            if overlapping:
                c = overlapping[0]
                what = f"balls {c.i + 1} and {c.j + 1}" if c.kind == "pair" else f"ball {c.i + 1} and the cushion"
                self.status, self.message = Status.OVERLAP, (
                    f"{what} overlap by {float(-c.distance):.3g} m at the end of the run (t = {float(self.t):.17g} s): "
                    "an impact was missed")
        if self.sink is not None:
            try:
                with signals_deferred():  # the table is written whole, then Ctrl-C or SIGTERM acts
                    self.flush()
                    self.sink.close()
            except KeyboardInterrupt:  # (after the integration's end: the run is whole, its outputs too)
                if self.status.success:
                    self.status, self.message = Status.INTERRUPTED, (
                        f"interrupted at t = {float(self.t):.17g} s after {counted(self.count, 'impact')}, while the table was "
                        "written (it is whole)")
        if self.progress is not None:
            self.progress(float(self.t), self.count)
        records = self.kept if self.kept is not None else self.records
        return TableResult(
            scene=self.scene, status=self.status, message=self.message, precision=self.precision, t_final=self.t,
            state_initial=self.state_initial, state_final=list(self.state), energy_initial=self.energy_initial,
            energy_final=float(self.energy(self.state)), n_collisions=self.count, n_cushion=self.cushion,
            n_rerolls=self.rerolls, records=records, paths=self.paths, wall_time_s=wall,
            settings={"precision": self.precision.name, "t_end": float(self.t_end), "max_collisions": self.limit,
                      "tolerance": float(self.options.get("tol", self.precision.epsilon)),
                      "high_accuracy": bool(self.options["high_accuracy"]),
                      "fast_math": bool(self.options.get("fast_math", False))},
            steps=self.steps, riding_final=tuple(k + 1 for k, on in enumerate(self.riding) if on),
        )


def _linked(contacts: list, approaching: list) -> list:
    """The ``contacts`` in sets linked through shared balls (bonds.clusters: a contact is named as a bond is), each
    set that holds one of ``approaching``, each in the order of ``contacts``."""
    order = {(c.kind, c.i, c.j): n for n, c in enumerate(contacts)}
    groups = sorted((sorted(group, key=order.get) for group in bonds_module.clusters(order)), key=lambda g: order[g[0]])
    return [[contacts[order[name]] for name in group] for group in groups
            if any(name[0] == a.kind and name[1] == a.i and name[2] == a.j for name in group for a in approaching)]


def _onset_wait(excess: float, rate: float, target: float) -> float | None:
    """The time t* > 0 at which a slip growing from 0 as (kappa - 1) s' = e + e' t reaches ``target`` = (kappa - 1)
    SKID_ONSET, e = ``excess`` >= 0, e' = ``rate``: the root of e t + e' t^2/2 = target (stable for any sign of
    e'); None where the excess turns back first."""
    reach = excess * excess + 2 * rate * target
    if reach < 0 or not excess + math.sqrt(reach) > 0:
        return None
    return 2 * target / (excess + math.sqrt(reach))


def _same(a: Contact, b: Contact) -> bool:
    return a.kind == b.kind and a.i == b.i and a.j == b.j
