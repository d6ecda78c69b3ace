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

Riding a curved cushion (compiled only where it can happen: a curved
cushion with k < 1). With k < 1 every impact on a
convex cushion scales the normal speed by k and keeps the tangential one:
the impacts accumulate in a finite time (a Zeno sequence) and, in their
limit, the ball rolls on along the cushion, pressed against it. The driver
then sets the ball's riding flag r and the centre follows the curve
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
table: a riding ball leaves the cushion only when an impact sends it off.

Events (terminal; the driver resolves them): one per ball and wall (the
boundary's gap polynomial crossing 0 upwards; the constant -1 while the
ball rides that cushion), one per pair of balls
(|c_i - c_j|^2 - (R_i + R_j)^2 crossing 0 downwards), one per ball that can
slide (u . d + (1 - s), the constant 1 while it rolls).
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import heyoka as hy

from ...model._numbers import workprec
from ...model.table import TableScene
from ..compiled_cache import CompiledCache
from ..precision import Precision

#: Parameters per ball: accelerations of v and of u, sliding flag s, slip direction d, riding flag r, and
#: while riding the square of the speed V^2 and the rate c = alpha / (2 V^2) that holds it (0 at rest).
FVX, FVY, FUX, FUY, SLIDING, DX, DY, RIDING, RIDE_SPEED2, RIDE_HOLD = range(10)
BALL_PARS = 10
STATE_PER_BALL = 6

_INTEGRATORS = CompiledCache(16)
#: Events beyond which the integrator is compiled in heyoka's compact mode: measured with 16 balls in a
#: rectangle (184 events) 0.45 s to compile instead of 9.3 s, ~25% fewer impacts per second after.
#: Riding systems compile in compact mode too, but for one ball on a conic: a finite ball in an ellipse (the
#: degree-8 polynomial's Hessian in the equations) 0.6 s instead of 3 s, two of them 0.7 s instead of 11 s,
#: six balls on a circle 0.5 s instead of 10 s (measured); a long ride of one ball is ~2.5x slower per step.
COMPACT_EVENTS = 150


@dataclass(frozen=True)
class TableEvent:
    """What an event index means: ``kind`` wall | pair | roll; ``ball`` (0-based); ``other`` wall or ball."""

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

    @property
    def n_balls(self) -> int:
        return len(self.rolls)


def can_slide(scene: TableScene, k: int) -> bool:
    body = scene.balls[k].body
    return scene.slides and scene.friction > 0 and not body.is_particle and body.kappa > 1


def can_ride(scene: TableScene) -> bool:
    """A ball can settle onto the cushion and ride it: a curved cushion with k < 1 (either cushion model; under
    ``slide`` only a ball the cloth's friction keeps rolling along it, driver._Run.ride)."""
    return scene.boundary.kind in ("ellipse", "circle") and scene.cushion.restitution < 1


def table_system(scene: TableScene, precision: Precision) -> TableSystem:
    num = precision.number
    n = scene.n_bodies
    pars: list = []
    for ball in scene.balls:
        pars += [num(0)] * BALL_PARS
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
            pairs[(i, j)] = (len(pars), num(reach))
            pars.append(num(reach2))
    events = [TableEvent("wall", k, w) for (k, w) in walls]
    events += [TableEvent("pair", i, j) for (i, j) in pairs]
    rolls = tuple(can_slide(scene, k) for k in range(n))
    events += [TableEvent("roll", k) for k in range(n) if rolls[k]]
    crossing = _crossing_time(scene)
    cooldown = 2.0 ** round(math.log2(2.0**12 * precision.epsilon * crossing))
    ride = can_ride(scene)
    alpha = -1
    if ride:
        alpha = len(pars)
        pars.append(num(1 / crossing))
    shape = (scene.boundary.kind, n, tuple(lengths), rolls, cooldown, ride)
    return TableSystem(events=tuple(events), walls=walls, pairs=pairs, pars=tuple(pars), rolls=rolls, shape=shape,
                       cooldown=cooldown, max_step=crossing, ride=ride, alpha=alpha)


def _crossing_time(scene: TableScene) -> float:
    """The time a ball at the top speed takes to cross the table (1 s if nothing moves).

    No ball is ever faster than sqrt(2 E / m_min): no law adds energy."""
    energy = float(scene.energy())
    lightest = min(float(b.body.mass) for b in scene.balls)
    top_speed = math.sqrt(2 * energy / lightest) if energy > 0 else 0.0
    size = max(abs(float(v)) for v in _extent(scene.boundary))
    return size / top_speed if top_speed > 0 else 1.0


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
    for k in range(n):
        x, y, vx, vy, ux, uy = var[STATE_PER_BALL * k:STATE_PER_BALL * (k + 1)]
        base = BALL_PARS * k
        ax, ay = par[base + FVX], par[base + FVY]
        if system.ride:
            cx, cy = _riding_acceleration(scene, system, k, (x, y, vx, vy))
            ax, ay = ax + cx, ay + cy
        equations += [(x, vx), (y, vy), (vx, ax), (vy, ay), (ux, par[base + FUX]), (uy, par[base + FUY])]
    positive, negative = hy.event_direction.positive, hy.event_direction.negative
    typed = {"fp_type": options["fp_type"]} if "fp_type" in options else {}
    # A fixed, tiny cooldown. After an impact the event that fired starts its next step at a root (to
    # within round-off): with no cooldown heyoka then missed that function's next root in the same step
    # (a ball leaving a curved cushion and meeting it again 3 ms later); its automatic cooldown grows as
    # the function's slope falls and hid the next impact of a ball grazing the cushion (measured).
    typed["cooldown"] = state[0] - state[0] + system.cooldown
    events = []
    for ev in system.events:
        k = ev.ball
        x, y = var[STATE_PER_BALL * k], var[STATE_PER_BALL * k + 1]
        if ev.kind == "wall":
            first, values = system.walls[(k, ev.other)]
            c = [par[first + m] for m in range(len(values))]
            gap = scene.boundary.gap(ev.other, x, y, c)
            if system.ride:  # the constant -1 while the ball rides this cushion
                riding = par[BALL_PARS * k + RIDING]
                gap = gap * (1. - riding) - riding
            events.append(hy.t_event(gap, direction=positive, **typed))
        elif ev.kind == "pair":
            xj, yj = var[STATE_PER_BALL * ev.other], var[STATE_PER_BALL * ev.other + 1]
            index, _ = system.pairs[(k, ev.other)]
            dx, dy = x - xj, y - yj
            events.append(hy.t_event(dx * dx + dy * dy - par[index], direction=negative, **typed))
        else:
            ux, uy = var[STATE_PER_BALL * k + 4], var[STATE_PER_BALL * k + 5]
            base = BALL_PARS * k
            events.append(hy.t_event(ux * par[base + DX] + uy * par[base + DY] + (1. - par[base + SLIDING]),
                                     direction=negative, **typed))
    big = len(events) > COMPACT_EVENTS or (system.ride and (n > 1 or any(len(v) > 2 for _, v in system.walls.values())))
    if big and "compact_mode" not in options:
        options = dict(options, compact_mode=True)
    return hy.taylor_adaptive(equations, list(state), pars=list(system.pars), t_events=events, **options)


def _riding_acceleration(scene: TableScene, system: TableSystem, k: int, variables) -> tuple:
    """The cushion's constraint acceleration -r lambda grad g on ball k (module docstring), as expressions.

    Where the ball does not ride (r = 0) the denominator is |grad g|^2 + 1, never 0 (grad g vanishes at the
    centre of an ellipse), and the term is multiplied by 0."""
    x, y, vx, vy = variables
    par = hy.par
    first, values = system.walls[(k, 0)]
    c = [par[first + m] for m in range(len(values))]
    g = scene.boundary.gap(0, x, y, c)
    gx, gy = hy.diff(g, x), hy.diff(g, y)
    gxx, gxy, gyy = hy.diff(gx, x), hy.diff(gx, y), hy.diff(gy, y)
    base = BALL_PARS * k
    riding, alpha = par[base + RIDING], par[system.alpha]
    curvature = vx * vx * gxx + 2. * vx * vy * gxy + vy * vy * gyy
    lam = riding * (curvature + 2. * alpha * (gx * vx + gy * vy) + alpha * alpha * g) \
        / (gx * gx + gy * gy + (1. - riding))
    hold = par[base + RIDE_HOLD] * (par[base + RIDE_SPEED2] - vx * vx - vy * vy)  # 0 unless riding
    return -lam * gx + hold * vx, -lam * gy + hold * vy
