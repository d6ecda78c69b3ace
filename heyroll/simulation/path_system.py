"""The heyoka system of a scene on an arc chain or a curve y = f(x).

State: (q_1, v_1, ..., q_N, v_N), q the body's coordinate (arc length s of
its centre's path on an arc chain, contact abscissa x on a curve), v = q'.

The equation of relative motion comes from the Lagrangian in the rotating
plane (paper section 5.3, derived here for any body):

    L = 1/2 kappa m |dC/dq|^2 q'^2 + 1/2 m Omega^2 (x_C - a)^2 - m g y_C

(the body's own moment about the vertical axis adds a constant, and the
Coriolis forces are normal to the plane, taken by the constraint). With
F = |dC/dq|^2 (eq. 94 on a curve, 1 on an arc chain):

    F q'' + 1/2 F' q'^2 - Omega^2/kappa (x_C - a) x_C' + g/kappa y_C' = 0,

which is eq. (93) with J_z = m (x_C - a)^2 + const, J_P = kappa m r^2.
Only what the scene needs is compiled: without rotation the centrifugal
term is absent, and one body needs no centre positions on an arc chain.

On an arc chain the geometry of the piece a body is on is held in runtime
parameters; events at the piece's ends switch them (junctions) or reverse
the body (limiters at the chain's ends), so no Taylor step crosses a jump
of curvature.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import heyoka as hy
import mpmath
import numpy as np

from ..model import expression as ex
from ..model.path_scene import PathScene
from ..model.paths import ArcChainTrack, CurveTrack, PathPiece

#: Runtime parameters of one body on an arc chain, in this order.
PIECE_PARAMETERS = ("lo", "hi", "alpha0", "c", "s0", "A", "B", "D", "E", "G")


#: Floating-point types of a path run: double, or x87 extended (64-bit mantissa),
#: which keeps the first integral to ~1e-16 over 1e4 oscillations where
#: double's rounding drifts it by ~1e-11 (validation/path_accuracy.py).
FLOAT_TYPES = {"double": np.float64, "long": np.longdouble}


def to_float(value, fp_type):
    """Round an mpmath/decimal number once to ``fp_type``."""
    if fp_type is np.float64 or fp_type is float:
        return float(value)
    return fp_type(mpmath.nstr(mpmath.mpf(value), 30, strip_zeros=False))


def heyoka_library(fp_type=np.float64):
    return ex.Library(number=lambda t: hy.expression(to_float(t, fp_type)),
                      functions={"sin": hy.sin, "cos": hy.cos, "exp": hy.exp, "sqrt": hy.sqrt})


@dataclass(frozen=True)
class BodyTerms:
    """heyoka expressions for one body: centre, metric, acceleration."""

    q: hy.expression
    v: hy.expression
    x_c: hy.expression
    y_c: hy.expression
    acceleration: hy.expression
    #: N/m, the track's normal force per unit mass (> 0: pressing on the track)
    normal: hy.expression


@dataclass(frozen=True)
class PathEvent:
    """A terminal event: ``kind`` is lower | upper (ends of the body's piece or of
    the curve), gap (bodies ``body`` and ``body + 1``) or normal (the track's
    normal force on ``body`` falls to zero: it would leave a one-sided track)."""

    kind: str
    body: int


class PathSystem:
    """Equations, events and parameter layout of one :class:`PathScene`."""

    def __init__(self, scene: PathScene, fp_type=np.float64):
        self.scene = scene
        self.fp_type = fp_type
        self.n = len(scene.bodies)
        self.variables = hy.make_vars(*[f"{c}{n}" for n in range(1, self.n + 1) for c in ("q", "v")])
        self.chain = isinstance(scene.track, ArcChainTrack)
        self.pieces = [scene.track.pieces(b) for b in scene.bodies] if self.chain else None
        self.exact_pieces = [scene.track.pieces(b, exact=True) for b in scene.bodies] if self.chain else None
        self.terms = [self._terms(n) for n in range(self.n)]

    # ------------------------------------------------------------ parameters
    def par_index(self, body: int, name: str) -> int:
        return body * len(PIECE_PARAMETERS) + PIECE_PARAMETERS.index(name)

    def piece_values(self, body: int, k: int) -> list[float]:
        """Parameter values of body ``body`` on piece ``k``."""
        p: PathPiece = self.exact_pieces[body][k]
        return [to_float(v, self.fp_type) for v in (p.s0, p.s1, p.alpha0, p.c, p.s0, p.A, p.B, p.D, p.E, p.G)]

    def initial_parameters(self, pieces: list[int]) -> list[float]:
        if not self.chain:
            return []
        out = []
        for body, k in enumerate(pieces):
            out += self.piece_values(body, k)
        return out

    # ------------------------------------------------------------- equations
    def _terms(self, n: int) -> BodyTerms:
        scene, body = self.scene, self.scene.bodies[n]
        q, v = self.variables[2 * n], self.variables[2 * n + 1]
        fp = lambda v: to_float(v, self.fp_type)  # noqa: E731
        r = fp(body.radius)
        g_k = hy.expression(fp(scene.g / body.kappa))
        g = hy.expression(fp(scene.g))
        omega2 = scene.frame.omega**2
        om2 = hy.expression(fp(omega2))
        om_k = hy.expression(fp(omega2 / body.kappa))
        a = hy.expression(fp(scene.frame.axis_x))
        if self.chain:
            P = lambda name: hy.par[self.par_index(n, name)]  # noqa: E731
            alpha = P("alpha0") + P("c") * (q - P("s0"))
            x_c = P("A") + P("B") * hy.sin(alpha) + P("D") * (q - P("s0"))
            y_c = P("E") - P("B") * hy.cos(alpha) + P("G") * (q - P("s0"))
            acc = -g_k * hy.sin(alpha)  # F = 1, y_C' = sin(alpha), x_C' = cos(alpha)
            # along the left normal n = (-sin, cos): m c v^2 = N - m g cos(alpha) - m Omega^2 (x_C - a) sin(alpha)
            normal = P("c") * v * v + g * hy.cos(alpha)
            if omega2:
                acc = acc + om_k * (x_c - a) * hy.cos(alpha)
                normal = normal + om2 * (x_c - a) * hy.sin(alpha)
            return BodyTerms(q, v, x_c, y_c, acc, normal)
        track: CurveTrack = scene.track
        lib = heyoka_library(self.fp_type)
        has_radius = bool(body.radius)
        r = hy.expression(r)
        f0, f1, f2, f3 = (ex.evaluate(node, q, lib) for node in (track.f, track.df, track.d2f, track.d3f))
        w2 = 1.0 + f1 * f1
        w = hy.sqrt(w2)
        curv = f2 / (w2 * w)  # signed curvature of the track
        if has_radius:
            one = 1.0 - r * curv  # |dC/dx| / |dP/dx|: > 0 by the track check
            dcurv = f3 / (w2 * w) - 3.0 * f1 * f2 * f2 / (w2 * w2 * w)
            F = w2 * one * one
            dF = 2.0 * f1 * f2 * one * one - 2.0 * r * w2 * one * dcurv
            x_c, y_c = q - r * f1 / w, f0 + r / w
        else:
            one = hy.expression(1.0)
            F, dF = w2, 2.0 * f1 * f2
            x_c, y_c = q, f0
        force = -0.5 * dF * v * v - g_k * f1 * one
        # centre path curvature k/(1 - r k) times the centre speed^2 F v^2, plus gravity and
        # the centrifugal force along the normal (-f', 1)/sqrt(1 + f'^2)
        normal = curv * w2 * one * v * v + g / w
        if omega2:
            force = force + om_k * (x_c - a) * one
            normal = normal + om2 * (x_c - a) * f1 / w
        return BodyTerms(q, v, x_c, y_c, force / F, normal)

    @cached_property
    def equations(self) -> list:
        return [eq for t in self.terms for eq in ((t.q, t.v), (t.v, t.acceleration))]

    # ---------------------------------------------------------------- events
    @cached_property
    def event_specs(self) -> tuple[PathEvent, ...]:
        specs = []
        for n in range(self.n):
            specs += [PathEvent("lower", n), PathEvent("upper", n)]
        specs += [PathEvent("gap", n) for n in range(self.n - 1)]
        specs += [PathEvent("normal", n) for n in range(self.n)]
        return tuple(specs)

    def event_expression(self, ev: PathEvent) -> hy.expression:
        t = self.terms[ev.body]
        if ev.kind == "normal":
            return t.normal
        if ev.kind in ("lower", "upper"):
            if self.chain:
                return t.q - hy.par[self.par_index(ev.body, "lo" if ev.kind == "lower" else "hi")]
            track = self.scene.track
            return t.q - hy.expression(to_float(track.x_min if ev.kind == "lower" else track.x_max, self.fp_type))
        u = self.terms[ev.body + 1]
        d = hy.expression(to_float(self.scene.bodies[ev.body].radius + self.scene.bodies[ev.body + 1].radius,
                                   self.fp_type))
        dx, dy = u.x_c - t.x_c, u.y_c - t.y_c
        return dx * dx + dy * dy - d * d  # squared: smooth, same sign as the gap

    def events(self, fired: list, cooldown: float = -1.0) -> list:
        """Terminal events; ``cooldown`` for the gaps and limiters (heyoka's default,
        scaled by 1/|g'|, hides the quick re-collisions of an accumulating sequence)."""
        def callback(n):
            def cb(ta, d_sgn):
                fired.append(n)
                return False
            return cb

        direction = {"lower": hy.event_direction.negative, "upper": hy.event_direction.positive,
                     "gap": hy.event_direction.negative, "normal": hy.event_direction.negative}
        return [hy.t_event(self.event_expression(ev), callback=callback(n), direction=direction[ev.kind],
                           cooldown=self.fp_type(cooldown if ev.kind != "normal" else -1.0), fp_type=self.fp_type)
                for n, ev in enumerate(self.event_specs)]

    @cached_property
    def event_function(self):
        """Compiled values of every event expression (state, pars) -> array."""
        return hy.cfunc([self.event_expression(ev) for ev in self.event_specs], vars=list(self.variables),
                        fp_type=self.fp_type)

    @cached_property
    def centre_function(self):
        """Compiled (x_C, y_C, acceleration, N/m) of every body, for checks and outputs."""
        outs = [e for t in self.terms for e in (t.x_c, t.y_c, t.acceleration, t.normal)]
        return hy.cfunc(outs, vars=list(self.variables), fp_type=self.fp_type)
