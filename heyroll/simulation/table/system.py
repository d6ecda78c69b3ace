"""The table's equations of motion and event functions, compiled once per scene shape.

State per ball (6 numbers): centre x, y; centre velocity vx, vy; slip
ux, uy of the contact point with the cloth (u = v - R omega x z). Between
impacts every ball moves with a constant acceleration (issue 14, "between
impacts the motion is polynomial in t"):

* rolling (u = 0): none, a straight line at constant speed (no rolling
  resistance);
* sliding: Coulomb friction mu m g against the slip direction d, constant
  while the ball slides: v' = -mu g d and, from the friction's moment about
  the centre, omega' such that u' = -mu g kappa/(kappa - 1) d: the centre
  moves on a parabola and u shrinks along d to zero, where the ball rolls
  again (the "roll" event u . d = 0). A particle never slides.

The accelerations, the slip direction and a sliding flag are runtime
parameters per ball, switched by the driver at events; the wall constants
(table geometry and ball radius) and the pairs' reach are parameters too,
so one compiled integrator serves every scene of the same shape.

Riding a cushion (compiled only where it can happen: k < 1 and a curved
cushion, or straight walls where friction can press a sliding ball on).
With k < 1 every impact on a
convex cushion scales the normal speed by k and keeps the tangential one:
the impacts accumulate in a finite time (a Zeno sequence) and, in their
limit, the ball rolls on along the cushion, pressed against it (on a
straight wall only a sliding ball whose friction drives it in gets there).
The driver then sets the ball's riding flag r for that wall (one parameter
per ball and wall) and the centre follows the curve
g(x, y) = 0 of its wall gap under the cushion's normal force alone (no
friction in the cushion, the ball rolls on the cloth): the constraint
acceleration -lambda grad g with

    lambda = (v^T H v + 2 alpha grad g . v + alpha^2 g) / |grad g|^2

(H the Hessian of g), which keeps d^2 g/dt^2 = -2 alpha dg/dt - alpha^2 g:
g'' = 0 exactly, plus Baumgarte's correction of round-off drift
(alpha = 1/the crossing time). The speed is constant (the force is normal
to the motion); the same kind of correction holds it, c (V^2 - |v|^2) v
with c = alpha / (2 V^2), so d|v|^2/dt = alpha (V^2 - |v|^2) to first
order: the round-off of the degree-8 polynomial of a finite ball in an
ellipse, a fixed pattern along the curve, otherwise drifted the speed by
~1e-12 over 400 laps (measured, validation/billiards.py). The normal force,
kappa m v^2/rho_c on a ball rolling
on a curve of radius of curvature rho_c, never changes sign on a convex
table: a rolling rider leaves the cushion only when an impact sends it off.

Skidding along the cushion (a riding ball that slides on the cloth, flag
SKID). The cushion's force goes through the centre (it turns v, not the
spin), the cloth's friction -mu m g u/|u| acts against the slip, whose
direction now turns with the motion (on a free ball it is constant):

    v' = f - lambda grad g,    u' = kappa/(kappa - 1) f - lambda grad g,    f = -mu g u/|u|

with lambda as above plus grad g . f in its numerator (the friction's push
into the cushion). No speed is held (friction changes it). Three events:

* "roll": |u| falls to SLIP_END (2^10 ulps of the scene's top speed); the
  slip then ends (the driver sets u = 0). Not at |u| = 0 itself: there
  the friction's direction is discontinuous, |u| has a corner, not a
  crossing, and the slip's direction behaves like (t0 - t)^gamma, a
  branch point that Taylor steps approach geometrically;
* "lift": the normal force's numerator v^T H v + grad g . f falls through
  0: friction pulls the ball off the cushion faster than its curve turns
  it (a free sliding ball from then on);
* "grip" (``slide`` cushion model, a rolling rider): rolling along the
  curve turns the spin, which needs the cloth's friction
  (kappa - 1) m |v'| = (kappa - 1) m v^T H v/|grad g| (|v'| = v^2/rho_c);
  when that exceeds mu m g the ball starts to skid toward the table's
  inside, the direction the saturated friction drives it (the driver lets
  it roll on until its slip would be SKID_ONSET and starts the skid with
  that slip: driver._Run.grip_lost). The ``rolling`` cushion model keeps a
  rolling ball rolling by its definition (paper section 7.2).

Pressed together (two balls that friction keeps driving into each other after an impact with k < 1: the
limit of their accumulating bounces, as a rider's on the cushion): a system of its own for the run's bonds
(``table_system(..., bonds)``, compiled once per shape of bonds, bonds.topology), the scene's plus the
coupled contact forces of each cluster of bonds (balls pressed together in a chain, a pair pressed into a
cushion one of them rides: that rider's cushion force is then the cluster's, not its own) and their events,
"release" (a pair bond's multiplier through 0), "bond_lift" (a wall bond's), "pair_roll" (a sliding member's
slip falls to its slip end), "pair_grip" (a rolling member would need more than mu m g: it starts to slide, driver._Run.pair_grip_lost); see
_bond_terms.

Events (terminal; the driver resolves them): one per ball and wall (the
boundary's gap polynomial crossing 0 upwards; the constant -1 while the
ball rides that cushion), one per pair of balls
(|c_i - c_j|^2 - (R_i + R_j)^2 crossing 0 downwards), one per ball that can
slide (u . d + (1 - s), the constant 1 while it rolls; |u| - SLIP_END while it
skids), and, where balls can ride, a "lift" and a "grip" event per ball
(each a constant while not armed).
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import heyoka as hy
import mpmath

from ...model._numbers import workprec
from ...model.table import TableScene
from ..compiled_cache import CompiledCache
from ..precision import Precision
from . import bonds as bonds_module

#: Parameters per ball: accelerations of v and of u, sliding flag s, slip direction d, riding flag r, while
#: rolling on the cushion the square of the speed V^2 and the rate c = alpha / (2 V^2) that holds it (0 at
#: rest), the skid flag (riding and sliding), the armed grip event and the held flag (a cluster of bonds holds
#: it on its cushion: its own cushion force off, its wall events still off; the first MODE_PARS, set by the
#: driver per mode); then the ball's constants: mu g, mu g kappa/(kappa - 1) and kappa - 1 (module docstring).
FVX, FVY, FUX, FUY, SLIDING, DX, DY, RIDING, RIDE_SPEED2, RIDE_HOLD, SKID, GRIP, HELD, MU_G, MU_G_U, SPIN = range(16)
MODE_PARS = 13
BALL_PARS = 16
STATE_PER_BALL = 6
#: Added to |u|^2 under the square root of a skid's friction direction: u = 0 (a frictionless skid, a rider
#: that rolls) never divides 0 by 0; 2^-1000 is far below any slip the run resolves (SLIP_END^2 ~ 1e-26).
TINY = 2.0**-1000

#: Parameters of a run's bonds (``table_system(..., bonds)``), appended after the scene's
#: (``TableSystem.bond_pars``): Baumgarte's alpha and the slip at which a member's slide ends; then per member
#: ball (``TableSystem.members``, in the order of the bonds' shape: bonds.topology) whether it slides (1) or
#: rolls (0), its translational mobility w (1/m sliding: the contact forces go through the centre and leave the
#: spin; 1/(kappa m) rolling), whether its grip is watched (a rolling member), its mu g, mu g kappa/(kappa - 1)
#: and kappa - 1, and n numbers that select its ball (1 for it, 0 for the others: the compiled system names no
#: ball); then per bond (``TableSystem.slot_pars``) a pair's (R_i + R_j)^2 or a wall's constants.
B_ALPHA, B_SLIP_END = range(2)
M_SLIDING, M_MOBILITY, M_GRIP, M_MU_G, M_MU_G_U, M_SPIN = range(6)
MEMBER_PARS = 6

_INTEGRATORS = CompiledCache(64)  # (a run compiles a system per shape of its bonds: 22 in a random 16-ball break)
#: Shift of a pair's contact event inside the contact, in ulps of (R_i + R_j)^2 (system.table_system): off the
#: round numbers where heyoka's root isolation lost a root, and polished back (driver._Run.polish_pair).
PAIR_EVENT_SHIFT = 16
#: Events beyond which the integrator is compiled in heyoka's compact mode: measured with 16 balls in a
#: rectangle (184 events) 0.45 s to compile instead of 9.3 s, ~25% fewer impacts per second after.
#: Riding systems compile in compact mode too, but for one ball on a conic: a finite ball in an ellipse (the
#: degree-8 polynomial's Hessian in the equations) 0.6 s instead of 3 s, two of them 0.7 s instead of 11 s,
#: six balls on a circle 0.5 s instead of 10 s (measured); a long ride of one ball is ~2.5x slower per step.
COMPACT_EVENTS = 150


@dataclass(frozen=True)
class TableEvent:
    """What an event index means: ``kind`` wall | pair | roll | lift | grip; ``ball`` (0-based); ``other`` wall
    or ball."""

    kind: str
    ball: int
    other: int = -1


@dataclass(frozen=True)
class TableSystem:
    """The compiled layout of a table scene: events, parameter slots, run-type constants."""

    events: tuple
    #: (ball, wall) -> (first parameter index, constants in the run type)
    walls: dict
    #: (i, j) -> (parameter index of (R_i + R_j)^2, R_i + R_j in the run type)
    pairs: dict
    pars: tuple
    rolls: tuple
    shape: tuple
    #: heyoka's cooldown of every event (s): 2^12 ulps of the time a ball at the scene's top speed takes to
    #: cross the table, rounded to a power of 2 (it is compiled into the events)
    cooldown: float = 0.0
    #: longest step (s): the time a ball at the top speed takes to cross the table; a step of the whole
    #: run (the motion is a polynomial, heyoka would take one) made event detection fail (1e300 s)
    max_step: float = float("inf")
    #: balls can ride the cushion (module docstring): the constraint force is compiled in; the
    #: parameter index of Baumgarte's alpha (or -1)
    ride: bool = False
    alpha: int = -1
    #: parameter index of the slip at which a skid ends (or -1); per ball, the grip event is compiled
    slip_end: int = -1
    grips: tuple = ()
    #: (ball, wall) -> parameter index of the flag: the ball rides that wall (riding systems)
    ride_flags: dict = None
    #: the run's bonds (module bonds) in the order of their shape (``topology``: bonds.topology, what is
    #: compiled), the first of their parameters (B_ALPHA, ...), per member ball the first of its MEMBER_PARS (and
    #: the same in the shape's order of members), per bond the first of its parameters, the first bond event
    bonds: tuple = ()
    bond_pars: int = -1
    members: dict = None
    topology: tuple = ()
    member_pars: tuple = ()
    slot_pars: tuple = ()
    first_bond_event: int = 0

    @property
    def n_balls(self) -> int:
        return len(self.rolls)


def can_slide(scene: TableScene, k: int) -> bool:
    body = scene.balls[k].body
    return scene.slides and scene.friction > 0 and not body.is_particle and body.kappa > 1


def needs_grip(scene: TableScene, k: int) -> bool:
    """Under the ``slide`` cushion model a rolling rider's spin turns only by the cloth's friction: a ball with
    spin inertia (kappa > 1) may skid (module docstring)."""
    body = scene.balls[k].body
    return not scene.cushion.keeps_rolling and not body.is_particle and body.kappa > 1


def can_ride(scene: TableScene) -> bool:
    """A ball can settle onto the cushion and ride it: k < 1 and a curved cushion (its convex curve presses a
    rolling ball on), or straight walls where friction can press a sliding ball on. Under the ``slide`` cushion
    model also at k = 1: the slip a bounce leaves carries the ball back by (kappa - 1)/kappa (1 + k) of its normal
    speed once friction ends it, so its bounces still shrink (by 0.43 at k = 1, a solid sphere) and accumulate
    (acceptance test: 9 of 140 random slide-model scenes at k = 1 stopped the run there). Under the ``rolling``
    model at k = 1 on straight walls where a ball can slide: friction that drives a sliding ball back into the
    wall it bounced off makes bounces of the same height, which below the contact resolution cannot be told
    apart (one passed 1.9 cm through the wall: review); in their limit the ball skids along it. On a curved
    cushion at k = 1 where a ball can slide: friction bends a sliding ball's path into a graze of the cushion,
    whose limit is riding it (a whispering-gallery orbit; a 4-ring break at k = 1 stopped mid-run, 'riding it
    is modelled only for k < 1': acceptance test). Rolling balls alone at k = 1 run straight chords, whose angle
    with a convex cushion does not shrink: riding is compiled only where one starts along it."""
    sliding = any(can_slide(scene, k) for k in range(scene.n_bodies))
    curved = scene.boundary.kind in ("ellipse", "circle")
    if scene.cushion.restitution >= 1:
        return sliding or (curved and starts_along_cushion(scene))
    return curved or sliding


def starts_along_cushion(scene: TableScene) -> bool:
    """A ball starts on its (curved) cushion moving along it: touching (its gap within 2^-30 of the gap's scale)
    with a normal speed under 2^-10 of its speed. At k = 1 too it rides the cushion: the limit of elastic chords
    whose angle goes to 0 (a whispering-gallery orbit), its normal force doing no work. It stopped the run at t = 0
    ('riding it is modelled only for k < 1', fuzz)."""
    with workprec():
        for ball in scene.balls:
            speed2 = ball.vx ** 2 + ball.vy ** 2
            for w, c in enumerate(scene.boundary.wall_constants(ball.body.radius)):
                gx, gy = scene.boundary.gradient(w, ball.x, ball.y, c)
                touching = abs(scene.boundary.gap(w, ball.x, ball.y, c)) <= mpmath.mpf(2) ** -30 * \
                    scene.boundary.gap_scale(w, c)
                if touching and speed2 > 0 and (gx * ball.vx + gy * ball.vy) ** 2 <= \
                        mpmath.mpf(2) ** -20 * (gx * gx + gy * gy) * speed2:
                    return True
    return False


def table_system(scene: TableScene, precision: Precision, bonds: tuple = ()) -> TableSystem:
    """The layout of ``scene``'s system; with ``bonds`` (sorted, module bonds) the same one plus the contact
    forces of each cluster of bonds and their events (module docstring), their parameters after the scene's, so
    that a run switches between the two keeping its parameter vector."""
    num = precision.number
    n = scene.n_bodies
    pars: list = []
    for ball in scene.balls:
        with workprec():  # the constants at the model's precision, rounded once to the run's type
            kappa = ball.body.kappa
            mu_g = scene.friction * scene.g
            mu_g_u = mu_g * kappa / (kappa - 1) if kappa > 1 else 0 * mu_g
            constants = [num(mu_g), num(mu_g_u), num(kappa - 1)]
        pars += [num(0)] * MODE_PARS + constants
    walls = {}
    lengths = []
    for k, ball in enumerate(scene.balls):
        for w, consts in enumerate(scene.boundary.wall_constants(ball.body.radius)):
            values = tuple(num(c) for c in consts)
            walls[(k, w)] = (len(pars), values)
            pars += values
            lengths.append(len(values))
    pairs = {}
    for i in range(n):
        for j in range(i + 1, n):
            with workprec():  # at the model's precision, not mpmath's global 53 bits (quad and MPFR runs)
                reach = scene.balls[i].body.radius + scene.balls[j].body.radius
                reach2 = reach * reach
                shifted = reach2 * (1 - PAIR_EVENT_SHIFT * mpmath.mpf(precision.epsilon))
            pairs[(i, j)] = (len(pars), num(reach))
            # the event 16 ulps of (R_i + R_j)^2 (8 of the distance) inside contact, at the model's precision
            # (in an MPFR run of more bits the shift rounds away, and so does this workaround); the driver
            # polishes the instant onto the exact root (driver._Run.polish_pair). heyoka 7.13 lost the entry
            # root of |dc|^2 - D^2 when its exit root lay exactly on the step's end or midpoint (a ball at
            # x = -0.8 rolling at 1 m/s into one at rest at 0, t_end = 2: roots 0.6 and 1.0; no impact, the
            # ball passed through: acceptance test)
            pars.append(num(shifted))
    events = [TableEvent("wall", k, w) for (k, w) in walls]
    events += [TableEvent("pair", i, j) for (i, j) in pairs]
    rolls = tuple(can_slide(scene, k) for k in range(n))
    events += [TableEvent("roll", k) for k in range(n) if rolls[k]]
    crossing = _crossing_time(scene)
    cooldown = 2.0 ** round(math.log2(2.0**12 * precision.epsilon * crossing))
    ride = can_ride(scene)
    alpha = slip_end = -1
    grips = ()
    ride_flags = {}
    if ride:
        for key in walls:
            ride_flags[key] = len(pars)
            pars.append(num(0))
        slip_end = len(pars)  # before alpha, which every riding system uses last (heyoka counts them)
        pars.append(num(_slip_end(scene, precision, crossing)))
        alpha = len(pars)
        pars.append(num(1 / crossing))
        events += [TableEvent("lift", k) for k in range(n) if rolls[k]]
        grips = tuple(rolls[k] and needs_grip(scene, k) for k in range(n))
        events += [TableEvent("grip", k) for k in range(n) if grips[k]]
    members, bond_pars, local, member_pars, slot_pars, first_bond_event = {}, -1, (), [], [], len(events)
    if bonds:
        bond_pars = len(pars)
        pars += [num(1 / crossing), num(_slip_end(scene, precision, crossing))]
        local, order, bonds = bonds_module.topology(bonds, lambda k, w: len(walls[(k, w)][1]))
        for k in order:
            members[k] = len(pars)
            member_pars.append(len(pars))
            base = BALL_PARS * k
            pars += [num(0)] * 3 + [pars[base + MU_G], pars[base + MU_G_U], pars[base + SPIN]]
            pars += [num(1) if m == k else num(0) for m in range(n)]
        for bond in bonds:
            slot_pars.append(len(pars))
            if bond[0] == "pair":
                with workprec():  # (R_i + R_j)^2 at the model's precision (at mpmath's global 53 bits a quad run
                    reach = scene.balls[bond[1]].body.radius + scene.balls[bond[2]].body.radius  # held a pair
                    reach2 = reach * reach  # 8e-19 too far: overlap)
                pars.append(num(reach2))
            else:
                pars += list(walls[(bond[1], bond[2])][1])
        events += [TableEvent("release" if bond[0] == "pair" else "bond_lift", bond[1], bond[2]) for bond in bonds]
        events += [TableEvent("pair_roll", k) for k in order] + [TableEvent("pair_grip", k) for k in order]
    shape = (scene.boundary.kind, n, tuple(lengths), rolls, cooldown, ride, grips, local)
    return TableSystem(events=tuple(events), walls=walls, pairs=pairs, pars=tuple(pars), rolls=rolls, shape=shape,
                       cooldown=cooldown, max_step=crossing, ride=ride, alpha=alpha, slip_end=slip_end, grips=grips,
                       ride_flags=ride_flags, bonds=tuple(bonds), bond_pars=bond_pars, members=members,
                       topology=local, member_pars=tuple(member_pars), slot_pars=tuple(slot_pars),
                       first_bond_event=first_bond_event)


def _crossing_time(scene: TableScene) -> float:
    """The time a ball at the top speed takes to cross the table (1 s if nothing moves).

    No ball is ever faster than sqrt(2 E / m_min): no law adds energy."""
    energy = float(scene.energy())
    lightest = min(float(b.body.mass) for b in scene.balls)
    top_speed = math.sqrt(2 * energy / lightest) if energy > 0 else 0.0
    size = _extent_size(scene)
    return size / top_speed if top_speed > 0 else 1.0


def _slip_end(scene: TableScene, precision: Precision, crossing: float) -> float:
    """The slip at which a skid (or a cluster member's slide) ends: 2^10 ulps of the scene's top speed, and not
    under 2^10 ulps of the table's size taken as a number: heyoka controls the error on the state's largest
    component, the positions where the balls are slow, and a slip under that resolution is not followed to its
    end (a ball skidding from a slip of 1e-3 m/s in a corner of a 2 m table passed through slip 0: NaN, review)."""
    size = _extent_size(scene)
    return 2.0**10 * precision.epsilon * max(size / crossing, size)


def _extent_size(scene: TableScene) -> float:
    return max(abs(float(v)) for v in _extent(scene.boundary))


def _extent(boundary):
    for name in ("a", "b", "radius", "width", "height"):
        if hasattr(boundary, name):
            yield getattr(boundary, name)
    for vertex in getattr(boundary, "vertices", ()):
        yield from vertex


def integrator(scene: TableScene, system: TableSystem, precision: Precision, options: dict, state):
    """A fresh heyoka integrator for ``system`` (a copy of the one compiled for its shape)."""
    key = (system.shape, precision.name, tuple(sorted((k, str(v)) for k, v in options.items())))

    def build():
        return _compile(scene, system, options, state)

    ta = copy.deepcopy(_INTEGRATORS.get(key, build))
    ta.time = precision.number(0)
    ta.state[:] = state
    ta.pars[:] = list(system.pars)
    return ta


def _compile(scene: TableScene, system: TableSystem, options: dict, state):
    n = system.n_balls
    names = []
    for k in range(n):
        names += [f"x_{k}", f"y_{k}", f"vx_{k}", f"vy_{k}", f"ux_{k}", f"uy_{k}"]
    var = hy.make_vars(*names)
    if n * STATE_PER_BALL == 1:  # pragma: no cover (make_vars returns a bare variable for one name)
        var = [var]
    par = hy.par
    equations = []
    cushion = {}  # ball -> its cushion terms (riding systems)
    press = _bond_terms(scene, system, var) if system.bonds else None
    contact = press.added if press is not None else {}  # ball -> the accelerations of v and u its bonds add
    for k in range(n):
        x, y, vx, vy, ux, uy = var[STATE_PER_BALL * k:STATE_PER_BALL * (k + 1)]
        base = BALL_PARS * k
        ax, ay = par[base + FVX], par[base + FVY]
        bx, by = par[base + FUX], par[base + FUY]
        if system.ride:
            terms = cushion[k] = _cushion_terms(scene, system, k, (x, y, vx, vy, ux, uy))
            ax, ay = ax + terms.ax, ay + terms.ay
            bx, by = bx + terms.bx, by + terms.by
        if k in contact:
            cax, cay, cbx, cby = contact[k]
            ax, ay, bx, by = ax + cax, ay + cay, bx + cbx, by + cby
        equations += [(x, vx), (y, vy), (vx, ax), (vy, ay), (ux, bx), (uy, by)]
    positive, negative = hy.event_direction.positive, hy.event_direction.negative
    typed = {"fp_type": options["fp_type"]} if "fp_type" in options else {}
    # A fixed, tiny cooldown. After an impact the event that fired starts its next step at a root (to
    # within round-off): with no cooldown heyoka then missed that function's next root in the same step
    # (a ball leaving a curved cushion and meeting it again 3 ms later); its automatic cooldown grows as
    # the function's slope falls and hid the next impact of a ball grazing the cushion (measured).
    typed["cooldown"] = state[0] - state[0] + system.cooldown
    events = []
    for ev in system.events[:system.first_bond_event]:
        k = ev.ball
        x, y = var[STATE_PER_BALL * k], var[STATE_PER_BALL * k + 1]
        if ev.kind == "wall":
            first, values = system.walls[(k, ev.other)]
            c = [par[first + m] for m in range(len(values))]
            gap = scene.boundary.gap(ev.other, x, y, c)
            if system.ride:  # the constant -1 while the ball rides this cushion
                riding = par[system.ride_flags[(k, ev.other)]]
                gap = gap * (1. - riding) - riding
            events.append(hy.t_event(gap, direction=positive, **typed))
        elif ev.kind == "pair":
            xj, yj = var[STATE_PER_BALL * ev.other], var[STATE_PER_BALL * ev.other + 1]
            index, _ = system.pairs[(k, ev.other)]
            dx, dy = x - xj, y - yj
            events.append(hy.t_event(dx * dx + dy * dy - par[index], direction=negative, **typed))
        elif ev.kind == "roll":
            ux, uy = var[STATE_PER_BALL * k + 4], var[STATE_PER_BALL * k + 5]
            base = BALL_PARS * k
            along = ux * par[base + DX] + uy * par[base + DY] + (1. - par[base + SLIDING])
            if system.ride:  # while it skids, the slip's size falling to SLIP_END
                skid = par[base + SKID]
                along = along * (1. - skid) + skid * (cushion[k].slip - par[system.slip_end])
            events.append(hy.t_event(along, direction=negative, **typed))
        elif ev.kind == "lift":
            skid = par[BALL_PARS * k + SKID]
            events.append(hy.t_event(skid * cushion[k].pressing + (1. - skid), direction=negative, **typed))
        elif ev.kind == "grip":
            base = BALL_PARS * k
            armed, terms = par[base + GRIP], cushion[k]
            spin, mu_g = par[base + SPIN], par[base + MU_G]
            excess = spin * spin * terms.curvature * terms.curvature - mu_g * mu_g * terms.gradient2
            events.append(hy.t_event(armed * excess - (1. - armed), direction=positive, **typed))
    if press is not None:  # by position: the compiled system serves every set of bonds of its shape
        # a bond's multiplier (without Baumgarte's terms) through 0: it lets go
        events += [hy.t_event(hold, direction=negative, **typed) for hold in press.holds]
        for first, slip in zip(system.member_pars, press.slips):  # a sliding member's slip falls to the slip end
            sliding = par[first + M_SLIDING]
            events.append(hy.t_event(sliding * (slip - par[system.bond_pars + B_SLIP_END]) + (1. - sliding),
                                     direction=negative, **typed))
        for first, need in zip(system.member_pars, press.grips):
            # a rolling member needs more of the cloth's friction than mu m g: (kappa - 1) |a| > mu g
            armed = par[first + M_GRIP]
            excess = par[first + M_SPIN] * par[first + M_SPIN] * need - par[first + M_MU_G] * par[first + M_MU_G]
            events.append(hy.t_event(armed * excess - (1. - armed), direction=positive, **typed))
    # finite balls in an ellipse: one degree-8 gap polynomial per ball; from 3 balls on compact mode compiles in
    # 0.4 s where the default took 1.3 s (3 balls), 3.4 s (5), 46 s (7), at the same speed after (measured)
    conic = any(len(v) > 2 for _, v in system.walls.values())
    big = len(events) > COMPACT_EVENTS or (conic and n > 2) or (system.ride and (n > 1 or conic)) or \
        len(system.bonds) > 2
    if big and "compact_mode" not in options:
        options = dict(options, compact_mode=True)
    if system.bonds and "opt_level" not in options:
        # a run compiles one system per shape of bonds it meets (22 in a random 16-ball break): LLVM's optimisation
        # took 0.4-1 s of each, opt_level 0 takes 0.1-0.2 s, and the steps run slower (measured on that break,
        # compiled systems cached: 4.8 s instead of 2.1 s; in all 8 s instead of ~15 s)
        options = dict(options, opt_level=0)
    return hy.taylor_adaptive(equations, list(state), pars=list(system.pars), t_events=events, **options)


@dataclass(frozen=True)
class _CushionTerms:
    """Ball k's terms from its cushion (riding systems), as heyoka expressions: the accelerations added to
    v' and u', the slip's size, v^T H v, the normal force's numerator v^T H v + grad g . f, |grad g|^2."""

    ax: object
    ay: object
    bx: object
    by: object
    slip: object
    curvature: object
    pressing: object
    gradient2: object


def _cushion_terms(scene: TableScene, system: TableSystem, k: int, variables) -> _CushionTerms:
    """The cushion's constraint acceleration -r lambda grad g on ball k and, while it skids, the cloth's
    friction along the turning slip (module docstring), summed over its walls, each with its flag r (one is
    1 while the ball rides it); none while a cluster of bonds holds the ball on its cushion (flag HELD: the
    force is the cluster's, _bond_terms).

    Where the ball does not ride a wall (r = 0) the denominator is |grad g|^2 + 1, never 0 (grad g vanishes at
    the centre of an ellipse), and the term is multiplied by 0; a ball that does not skid (flag 0) has the
    friction term 0 and |u| under the square root offset by 1."""
    x, y, vx, vy, ux, uy = variables
    par = hy.par
    base = BALL_PARS * k
    alpha, skid = par[system.alpha], par[base + SKID]
    slip = hy.sqrt(ux * ux + uy * uy + (1. - skid) + TINY)
    fx, fy = -skid * par[base + MU_G] * ux / slip, -skid * par[base + MU_G] * uy / slip
    cx = cy = pressing = curvature = gradient2 = 0.
    own = 1. - par[base + HELD]
    for w in range(scene.boundary.n_walls()):
        first, values = system.walls[(k, w)]
        g, gx, gy, gxx, gxy, gyy = _gap_derivatives(scene, [par[first + m] for m in range(len(values))], x, y)
        riding = par[system.ride_flags[(k, w)]]
        bend = vx * vx * gxx + 2. * vx * vy * gxy + vy * vy * gyy
        press = bend + gx * fx + gy * fy
        g2 = gx * gx + gy * gy
        lam = own * riding * (press + 2. * alpha * (gx * vx + gy * vy) + alpha * alpha * g) / (g2 + (1. - riding))
        cx, cy = cx - lam * gx, cy - lam * gy
        pressing, curvature, gradient2 = pressing + riding * press, curvature + riding * bend, gradient2 + riding * g2
    hold = par[base + RIDE_HOLD] * (par[base + RIDE_SPEED2] - vx * vx - vy * vy)  # 0 unless rolling on it
    rate = -skid * par[base + MU_G_U] / slip
    return _CushionTerms(ax=fx + cx + hold * vx, ay=fy + cy + hold * vy, bx=rate * ux + skid * cx,
                         by=rate * uy + skid * cy, slip=slip, curvature=curvature, pressing=pressing,
                         gradient2=gradient2)


def _gap_derivatives(scene: TableScene, c: list, x, y) -> tuple:
    """The gap g of a ball at (x, y) (heyoka expressions) to a wall with constants ``c`` (parameters; every wall
    of a boundary has the same form), its gradient and Hessian."""
    u, v = hy.make_vars("gap_x", "gap_y")  # derivatives by variables, then the position put in (a member's is a sum)
    g = scene.boundary.gap(0, u, v, c)
    gx, gy = hy.diff(g, u), hy.diff(g, v)
    terms = [g, gx, gy, hy.diff(gx, u), hy.diff(gx, v), hy.diff(gy, v)]
    return tuple(hy.subs(t, {"gap_x": x, "gap_y": y}) for t in terms)


@dataclass(frozen=True)
class _BondTerms:
    """The terms of a run's bonds (heyoka expressions): per ball the added (v', u') as (ax, ay, bx, by) (zero
    but for members); per member (the shape's order) its slip's size and |a|^2 of the part of its contact
    acceleration that the cloth's friction must make (pair_grip); per bond its multiplier without Baumgarte's
    terms (release)."""

    added: dict
    slips: list
    grips: list
    holds: list


def _bond_terms(scene: TableScene, system: TableSystem, var) -> _BondTerms:
    """Each cluster of bonds held closed by its coupled contact forces (module bonds): a_k = f_k + w_k sum_e
    lambda_e n_ek with A lambda = r - J f, r holding C'' = -2 alpha C' - alpha^2 C (Baumgarte, as on the
    cushion). f is a sliding member's friction against its slip, -mu g u/|u|, its direction turning with the
    slip (the contact forces go through the centre: they change v and u alike, not the spin); a rolling member
    has none and mobility w = 1/(kappa m). No ball-ball or ball-cushion friction. The forces do no work
    (J v = 0 on the bonds). One pair bond alone: lambda = -(|dv|^2 + dc . (f_j - f_i) + 2 alpha dc . dv +
    alpha^2 C / 2) / ((w_i + w_j) |dc|^2).

    Compiled for the bonds' shape (``system.topology``), not for their balls: each member's state is its
    ball's, picked by its selection parameters (sum_k s_k x_k, exact: ones and zeros), and its accelerations
    go back to its ball the same way."""
    par = hy.par
    n = system.n_balls
    alpha = par[system.bond_pars + B_ALPHA]
    mobility, free, free_u, sliding, slips, state = {}, {}, {}, {}, [], {}
    for m, first in enumerate(system.member_pars):
        pick = [par[first + MEMBER_PARS + k] for k in range(n)]
        x, y, vx, vy, ux, uy = state[m] = [hy.sum([pick[k] * var[STATE_PER_BALL * k + c] for k in range(n)])
                                           for c in range(STATE_PER_BALL)]
        s = sliding[m] = par[first + M_SLIDING]
        slip = hy.sqrt(ux * ux + uy * uy + (1. - s) + TINY)
        slips.append(slip)
        mu_g, mu_g_u = par[first + M_MU_G], par[first + M_MU_G_U]
        free[m] = (-s * mu_g * ux / slip, -s * mu_g * uy / slip)
        free_u[m] = (-s * mu_g_u * ux / slip, -s * mu_g_u * uy / slip)
        mobility[m] = par[first + M_MOBILITY]
    directions, targets, plain = [], [], []
    for bond, first in zip(system.topology, system.slot_pars):
        if bond[0] == "pair":
            _, i, j = bond
            xi, yi, vxi, vyi = state[i][:4]
            xj, yj, vxj, vyj = state[j][:4]
            dx, dy, dvx, dvy = xj - xi, yj - yi, vxj - vxi, vyj - vyi
            directions.append({i: (-dx, -dy), j: (dx, dy)})
            quad = dvx * dvx + dvy * dvy
            plain.append(-quad)
            targets.append(-(quad + 2. * alpha * (dx * dvx + dy * dvy) +
                             alpha * alpha * (dx * dx + dy * dy - par[first]) / 2.))
        else:
            _, m, size = bond
            x, y, vx, vy = state[m][:4]
            g, gx, gy, gxx, gxy, gyy = _gap_derivatives(scene, [par[first + c] for c in range(size)], x, y)
            directions.append({m: (-gx, -gy)})
            bend = vx * vx * gxx + 2. * vx * vy * gxy + vy * vy * gyy
            plain.append(bend)
            targets.append(bend + 2. * alpha * (gx * vx + gy * vy) + alpha * alpha * g)
    work = bonds_module.free_work(directions, free)
    members, grips, holds = {}, [None] * len(system.member_pars), [None] * len(system.topology)
    for group in bonds_module.clusters(system.topology):
        index = [e for e, b in enumerate(system.topology) if b in group]  # (a pinned ball's two walls: one form)
        ds = [directions[e] for e in index]
        matrix = bonds_module.bond_matrix(ds, mobility)
        lam, lam0 = bonds_module.solve(matrix, [[targets[e] - work[e] for e in index],
                                                [plain[e] - work[e] for e in index]])
        for e, value in zip(index, lam0):
            holds[e] = value
        contact = bonds_module.pushes(ds, mobility, lam)
        # the cushion's part needs no friction where its model keeps a ball rolling (paper section 7.2)
        gripped = [(d, v) for d, v, e in zip(ds, lam, index)
                   if system.topology[e][0] == "pair" or not scene.cushion.keeps_rolling]
        needs = bonds_module.pushes([d for d, _ in gripped], mobility, [v for _, v in gripped])
        for m, (ax, ay) in contact.items():
            fx, fy = free[m]
            fux, fuy = free_u[m]
            members[m] = (fx + ax, fy + ay, fux + sliding[m] * ax, fuy + sliding[m] * ay)
            nx, ny = needs.get(m, (0., 0.))
            grips[m] = nx * nx + ny * ny
    added = {}
    for k in range(n):  # each member's accelerations back to its ball
        picks = [(par[first + MEMBER_PARS + k], members[m]) for m, first in enumerate(system.member_pars)]
        added[k] = tuple(hy.sum([p * terms[c] for p, terms in picks]) for c in range(4))
    return _BondTerms(added=added, slips=slips, grips=grips, holds=holds)
