"""Collision sequence of bodies rolling on a path track, in mpmath (an independent reference).

The engine (:func:`heyroll.simulate`) integrates the bodies on a curve
y = f(x) or an arc chain with heyoka; this module solves the same problem
without heyoka and without the engine's model code, at any number of digits
(40 by default), so that the two can be compared. It takes plain data: the
track as a scene file's ``[track]`` table, each body as a dict, the law as a
dict (see :func:`run_path_reference`; :func:`scene_inputs` turns a whole
scene file, read with ``tomllib.loads(text, parse_float=Decimal)``, into
those arguments).

Geometry (shared with :mod:`.equilibria`, which is independent of the model
too): the centre C(q) of a body of radius r, q the contact abscissa x on a
curve (C = (x - r f'/w, f + r/w), w = sqrt(1 + f'^2)) and the arc length s
of the centre's path on an arc chain (0 at the chain's start). On a curve,
f, f', f'', f''' come from the curve evaluator of :mod:`.equilibria` run on
truncated Taylor series (:class:`Jet`, automatic differentiation, never a
symbolic derivative), and C', C'' from them in closed form
(:func:`_curve_centre`); on an arc chain, C', C'' of each piece of
:func:`.equilibria._chain` in closed form (:func:`_arc_geometry`). The tests
check both against mpmath.diff of the equilibria module's centre and
against jets through its pieces.

Motion between collisions: each body is on its own; per unit mass, in a
vertical plane turning at Omega about the vertical line x = a,

    L/m = 1/2 kappa F q'^2 + 1/2 Omega^2 (x_C - a)^2 - g y_C,   F = |dC/dq|^2,

(rolling without slipping: kinetic energy 1/2 kappa m v_C^2 with v_C = sigma q',
sigma = sqrt(F); the plane's rotation adds 1/2 m Omega^2 (x_C - a)^2 for the
centre and a constant for the spin about the vertical), hence

    F q'' + 1/2 F' q'^2 = (Omega^2 (x_C - a) x_C' - g y_C') / kappa,

with the Jacobi integral H/m = 1/2 kappa F q'^2 - 1/2 Omega^2 (x_C - a)^2 + g y_C
(checked along every flight). All bodies are integrated together by
Gragg-Bulirsch-Stoer extrapolation (modified midpoint rule, polynomial
extrapolation in h^2, up to order 2 * MAX_COLUMNS) with a local error below
10^-(dps + 6).

Events are located by *safe steps* that cannot step over a root. For an
event function e >= 0 with rate e' and |e''| <= G over the flight,

    e(t + h) >= e + e' h - G h^2 / 2 > 0   for 0 <= h < (e' + sqrt(e'^2 + 2 G e)) / G,

so no step is longer than that; the steps converge quadratically onto a
transversal root, and a closing event below 10^-(dps + 4) is reached by one
last step of e/|e'|. The events and their bounds G:

* the gap of neighbours i, i + 1, |C_j - C_i| - (r_i + r_j) (q_j - q_i for two
  particles): gap'' >= -(|a_Ci| + |a_Cj|) (the second derivative of a
  distance is at least the projection of the relative acceleration), with
  |a_C| <= |V'|/(kappa sigma) + K v_C^2 (tangential: the driving force;
  normal: the path's curvature K times the centre speed^2);
* both ends of the piece of track a body is on (a junction of an arc chain,
  where the body passes to the next piece, or an end of the track, a
  limiter: q' -> -k_lim q'): |q''| = |V'/kappa + F' q'^2/2| / F.

V/m = g y_C - 1/2 Omega^2 (x_C - a)^2. Along a flight the speed is a
function of q through the Jacobi integral (v_C^2 = 2 (H - V)/(m kappa),
q'^2 = v_C^2/F), so both bounds are maxima over the stretch of track the
body can reach (V <= H), taken on the geometry sampled at GRID points per
piece (H raised by 1% of V's spread, the maxima times SAFETY); a piece end
outside that stretch is not watched. After every step the actual |a_C| and
|q''| are checked against the bounds (a RuntimeError if the sampling missed
a peak) and the first integrals' drift is recorded. Every step stays inside
one piece of an arc chain (its formula is used throughout the step, so no
step straddles a jump of curvature).

Collision law at a contact (i before j along the track), paper eqs. 10-11 in
the law's variables u = c q', inertia M, restitution k:

    u_i+ = u_i - (1 + k) M_j / (M_i + M_j) (u_i - u_j),
    u_j+ = u_j + (1 + k) M_i / (M_i + M_j) (u_i - u_j),

* ``rolling`` (``hedrih``): u = omega_P = sigma q'/r, M = J_P = kappa m r^2 (eqs. 8-12);
* ``newton``: u = v_C = sigma q', M = m (eqs. 1-5, on the centres' speeds along their paths);
* ``newton_generalized``: u = q', M = kappa m sigma^2.

If the outcome still closes the gap (possible for the first two with
unequal metrics or radii), ``on_inconsistent="newton"`` resolves the
collision instead by Newton's law along the line of centres with the
generalized masses G = kappa m sigma^2 (impulse P along the gap's gradient
(g_i, g_j): P = -(1 + k) (g_i q_i' + g_j q_j') / (g_i^2/G_i + g_j^2/G_j),
q_k'+ = q_k' + P g_k / G_k; ``law_flag`` 1), as the engine does;
``"stop"`` ends the run with status ``inconsistent``.

Nothing from ``heyroll.model``, ``heyroll.simulation``, ``heyroll.interfaces``
or ``heyroll.analysis`` is used (tests/test_reference_independent.py).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import mpmath

from .collisions import ReferenceCollision
from .equilibria import FUNCTIONS, _chain, _check_keys, _num, _real, _segments, compile_expression

DIGITS = 40
#: Extra digits carried inside the computation.
GUARD_DPS = 10
#: Largest extrapolation column of a step (order 2 * MAX_COLUMNS).
MAX_COLUMNS = 22
#: The step-size controller aims at convergence in this column.
TARGET_COLUMN = 16
#: Sample points per piece of track for the bounds of the safe steps.
GRID = 1001
#: Factor applied to the sampled bounds.
SAFETY = mpmath.mpf("1.25")
#: Rolling coefficients of the scene file's shapes (J_P = kappa m r^2, paper eqs. 24, 35).
KAPPA = {"solid_sphere": ("7", "5"), "hollow_sphere": ("5", "3"), "disk": ("3", "2"), "ring": ("2", "1"),
         "particle": ("1", "1")}
LAW_NAMES = {"rolling": "rolling", "hedrih": "rolling", "newton": "newton",
             "newton_generalized": "newton_generalized"}
#: Passage kinds, as in the engine's passages table.
JUNCTION, LIMITER_LOWER, LIMITER_UPPER = 0, 1, 2


# ----------------------------------------------------------------- Taylor jets

FACTORIALS = (1, 1, 2, 6, 24, 120)


class Jet:
    """A truncated Taylor series c_0 + c_1 e + ... + c_K e^K (c_k = f^(k)/k!) in mpmath.

    Forward automatic differentiation: evaluating an expression on
    ``Jet.variable(x, K)`` gives its value and first K derivatives at x.
    """

    __slots__ = ("c", "_sc")

    def __init__(self, coefficients):
        self.c = list(coefficients)
        self._sc = None

    @classmethod
    def variable(cls, x, order: int) -> "Jet":
        return cls([x, mpmath.mpf(1)] + [mpmath.mpf(0)] * (order - 1))

    @property
    def order(self) -> int:
        return len(self.c) - 1

    def truncate(self, order: int) -> "Jet":
        return Jet(self.c[: order + 1])

    def derivative(self) -> "Jet":
        """d/de of the series (one order less)."""
        return Jet([(k + 1) * self.c[k + 1] for k in range(self.order)])

    def derivatives(self) -> list:
        """[f, f', f'', ...] at the expansion point."""
        return [self.c[k] * FACTORIALS[k] if k < len(FACTORIALS) else self.c[k] * mpmath.factorial(k)
                for k in range(len(self.c))]

    def _const(self, value) -> "Jet":
        return Jet([value] + [mpmath.mpf(0)] * self.order)

    def __pos__(self):
        return self

    def __neg__(self):
        return Jet([-a for a in self.c])

    def __add__(self, other):
        if isinstance(other, Jet):
            return Jet([a + b for a, b in zip(self.c, other.c)])
        return Jet([self.c[0] + other] + self.c[1:])

    __radd__ = __add__

    def __sub__(self, other):
        if isinstance(other, Jet):
            return Jet([a - b for a, b in zip(self.c, other.c)])
        return Jet([self.c[0] - other] + self.c[1:])

    def __rsub__(self, other):
        return Jet([other - self.c[0]] + [-a for a in self.c[1:]])

    def __mul__(self, other):
        if not isinstance(other, Jet):
            return Jet([a * other for a in self.c])
        a, b = self.c, other.c
        if len(a) == 4 and len(b) == 4:  # the curve's order, unrolled
            a0, a1, a2, a3 = a
            b0, b1, b2, b3 = b
            return Jet([a0 * b0, a0 * b1 + a1 * b0, a0 * b2 + a1 * b1 + a2 * b0,
                        a0 * b3 + a1 * b2 + a2 * b1 + a3 * b0])
        out = []
        for k in range(min(len(a), len(b))):
            acc = a[0] * b[k]
            for j in range(1, k + 1):
                acc += a[j] * b[k - j]
            out.append(acc)
        return Jet(out)

    __rmul__ = __mul__

    def __truediv__(self, other):
        if not isinstance(other, Jet):
            return Jet([a / other for a in self.c])
        a, b, q = self.c, other.c, []
        for k in range(min(len(a), len(b))):
            acc = a[k]
            for j in range(1, k + 1):
                acc -= b[j] * q[k - j]
            q.append(acc / b[0])
        return Jet(q)

    def __rtruediv__(self, other):
        return self._const(other) / self

    def __pow__(self, exponent):
        if isinstance(exponent, Jet):
            raise ValueError("x may not appear in an exponent of the curve")
        if isinstance(exponent, int) or exponent == mpmath.floor(exponent):
            n = int(exponent)
            if n < 0:
                return 1 / (self ** (-n))
            out, base = None, self
            while n:
                if n & 1:
                    out = base if out is None else out * base
                n >>= 1
                if n:
                    base = base * base
            return self._const(mpmath.mpf(1)) if out is None else out
        # p = a^e: a p' = e a' p, coefficient by coefficient
        a, e, p = self.c, mpmath.mpf(exponent), [self.c[0] ** exponent]
        for k in range(1, len(a)):
            acc = mpmath.mpf(0)
            for j in range(1, k + 1):
                acc += (e * j - (k - j)) * a[j] * p[k - j]
            p.append(acc / (k * a[0]))
        return Jet(p)

    def __rpow__(self, base):
        raise ValueError("x may not appear in an exponent of the curve")

    def sqrt(self) -> "Jet":
        a, s = self.c, [mpmath.sqrt(self.c[0])]
        for k in range(1, len(a)):
            acc = a[k]
            for j in range(1, k):
                acc -= s[j] * s[k - j]
            s.append(acc / (2 * s[0]))
        return Jet(s)

    def _scaled(self):
        # j a_j (the coefficients of the derivative), with a placeholder at j = 0
        return [None] + [j * a for j, a in enumerate(self.c) if j]

    def exp(self) -> "Jet":
        ja, e = self._scaled(), [mpmath.exp(self.c[0])]
        for k in range(1, len(ja)):
            acc = ja[1] * e[k - 1]
            for j in range(2, k + 1):
                acc += ja[j] * e[k - j]
            e.append(acc / k)
        return Jet(e)

    def _sincos(self):
        # s' = a' c, c' = -a' s, coefficient by coefficient
        if self._sc is None:
            ja = self._scaled()
            c0, s0 = mpmath.cos_sin(self.c[0])
            s, c = [s0], [c0]
            for k in range(1, len(ja)):
                sk, ck = ja[1] * c[k - 1], ja[1] * s[k - 1]
                for j in range(2, k + 1):
                    sk += ja[j] * c[k - j]
                    ck += ja[j] * s[k - j]
                s.append(sk / k)
                c.append(-ck / k)
            self._sc = (Jet(s), Jet(c))
        return self._sc

    def sin(self) -> "Jet":
        return self._sincos()[0]

    def cos(self) -> "Jet":
        return self._sincos()[1]


def _jet_function(name):
    plain = FUNCTIONS[name]

    def call(value):
        return getattr(value, name)() if isinstance(value, Jet) else plain(value)

    call.__name__ = name
    return call


#: The curve evaluator's functions, extended to jets.
JET_FUNCTIONS = {name: _jet_function(name) for name in FUNCTIONS}


# ------------------------------------------------------------------- records

@dataclass(frozen=True)
class PathCollision(ReferenceCollision):
    """One collision: time, bodies (numbered from 1, i before j along the track), positions and rates.

    The fields of :class:`heyroll.reference.collisions.ReferenceCollision` (so
    :func:`heyroll.reference.collisions.reference_table` takes a list of these), and
    ``law_flag`` 0 for the law, 1 for the fallback (see the module doc);
    ``energy_before``/``energy_after`` the total of the bodies' first integrals
    sum m (1/2 kappa F q'^2 - 1/2 Omega^2 (x_C - a)^2 + g y_C), J.
    """

    law_flag: int = 0
    energy_before: mpmath.mpf = mpmath.mpf(0)
    energy_after: mpmath.mpf = mpmath.mpf(0)


@dataclass(frozen=True)
class PathPassage:
    """A junction passage (kind 0) or a limiter impact (1 lower end, 2 upper end) of one body.

    Fields as in the engine's ``passages.csv``: body and pieces numbered from 1.
    """

    t: mpmath.mpf
    body: int
    kind: int
    piece_from: int
    piece_to: int
    q: mpmath.mpf
    dq_before: mpmath.mpf
    dq_after: mpmath.mpf


@dataclass
class PathReferenceRun:
    """A reference run on a path track.

    ``status``: ``max_collisions``, ``t_end`` (reached t_end), ``contact`` (two
    bodies do not separate after a collision), ``inconsistent`` (the law's
    outcome still closes the gap and ``on_inconsistent="stop"``), ``rest`` (a
    body does not leave a limiter), ``max_steps``. ``q``, ``dq``, ``pieces``
    (from 1): the final state at ``t_final``. ``max_drift``: the largest change
    of a body's first integral per unit mass along a flight (J/kg), a check of
    the integration.
    """

    collisions: list = field(default_factory=list)
    passages: list = field(default_factory=list)
    status: str = "max_collisions"
    message: str = ""
    t_final: mpmath.mpf = mpmath.mpf(0)
    q: list = field(default_factory=list)
    dq: list = field(default_factory=list)
    pieces: list = field(default_factory=list)
    steps: int = 0
    max_drift: mpmath.mpf = mpmath.mpf(0)


# ------------------------------------------------------------------- bodies

@dataclass
class _Body:
    r: mpmath.mpf
    m: mpmath.mpf
    kappa: mpmath.mpf
    geometry: object          # (q, piece) -> (x, x', x'', y, y', y'')
    cuts: list                # piece k spans [cuts[k], cuts[k + 1]]
    # the geometry sampled along the track (see _Run._sample): q and, as floats,
    # V/m, |x_C - a|, the path's curvature, F, |F'|, |V'|/m at each point
    samples: list = field(default_factory=list)
    spread: float = 0.0       # max V - min V over the track
    reach: tuple = (float("-inf"), float("inf"))
    # bounds of the current flight
    centre_acc: mpmath.mpf = mpmath.mpf(0)
    q_acc: mpmath.mpf = mpmath.mpf(0)
    h0: mpmath.mpf = mpmath.mpf(0)

    @property
    def pieces(self) -> int:
        return len(self.cuts) - 1

    def piece_of(self, q) -> int:
        """The piece holding q: a junction belongs to the piece after it."""
        for k in range(self.pieces - 1, 0, -1):
            if q >= self.cuts[k]:
                return k
        return 0


def _geometry(track: dict, r):
    """(geometry(q, piece), cuts) of a body of radius r: the centre and its first two q-derivatives."""
    kind = _check_keys(track)
    if kind == "curve":
        f = compile_expression(track.get("y"), JET_FUNCTIONS)
        if "x_min" not in track or "x_max" not in track:
            raise ValueError("a curve track needs x_min and x_max (its limiters)")
        lo, hi = _num(track["x_min"], "track.x_min"), _num(track["x_max"], "track.x_max")
        if not hi > lo:
            raise ValueError("track.x_max must be > x_min")

        def geometry(q, piece):
            y = f(Jet.variable(q, 3))
            if not isinstance(y, Jet):  # a constant curve
                y = Jet([y] + [mpmath.mpf(0)] * 3)
            f0, f1, f2, f3 = y.derivatives()
            if not all(isinstance(v, mpmath.mpf) for v in (f0, f1, f2, f3)):
                _real(mpmath.mpc(1j), f"x = {mpmath.nstr(q, 10)}")
            return _curve_centre(q, f0, f1, f2, f3, r)

        return geometry, [lo, hi]
    pieces = _chain(track, r)

    def geometry(q, piece):
        return _arc_geometry(pieces[piece], q)

    return geometry, [p.s0 for p in pieces] + [pieces[-1].s1]


def _curve_centre(x, f0, f1, f2, f3, r):
    """(x_C, x_C', x_C'', y_C, y_C', y_C'') on y = f(x) from f0..f3 = f and its first three derivatives.

    C = (x, f) + r n, n = (-f1, 1)/w, w = sqrt(1 + f1^2). Since
    n' = f2/w^3 (-1, -f1), C' = (1, f1) lam with lam = 1 - r f2/w^3 (> 0
    where the body fits the curve), and C'' = (0, f2) lam + (1, f1) lam',
    lam' = -r (f3 w^2 - 3 f1 f2^2)/w^5. (The tests check these against
    mpmath.diff of the centre of :mod:`.equilibria`.)
    """
    if r == 0:
        return x, mpmath.mpf(1), mpmath.mpf(0), f0, f1, f2
    w2 = 1 + f1 * f1
    w = mpmath.sqrt(w2)
    w3 = w2 * w
    lam = 1 - r * f2 / w3
    dlam = -r * (f3 * w2 - 3 * f1 * f2 * f2) / (w3 * w2)
    return x - r * f1 / w, lam, dlam, f0 + r / w, f1 * lam, f2 * lam + f1 * dlam


def _arc_geometry(piece, s):
    """(x, x', x'', y, y', y'') of the centre on one piece of an arc chain (closed form).

    The formulas of :class:`.equilibria._Piece` differentiated by hand (s is
    the centre's arc length, so |C'| = 1; the tests check them against
    :func:`_jet_arc_geometry`): with u = s - s0 and alpha = a0 + u/rho,
    concave (sin, -cos) and convex (sin, +cos) circles of radius rho about
    (ox, oy), or the line (ox, oy) + u (cos a0, sin a0).
    """
    u = s - piece.s0
    if piece.kind == "line":
        c, sn = mpmath.cos(piece.a0), mpmath.sin(piece.a0)
        return piece.ox + u * c, c, mpmath.mpf(0), piece.oy + u * sn, sn, mpmath.mpf(0)
    c, sn = mpmath.cos_sin(piece.a0 + u / piece.rho)
    rho = piece.rho
    if piece.kind == "concave":
        return piece.ox + rho * sn, c, -sn / rho, piece.oy - rho * c, sn, c / rho
    return piece.ox + rho * sn, c, -sn / rho, piece.oy + rho * c, -sn, -c / rho


def _jet_arc_geometry(piece, s):
    """As :func:`_arc_geometry`, by automatic differentiation of ``piece.centre`` (a check)."""
    xc, yc = piece.centre(Jet.variable(s, 2), sin=JET_FUNCTIONS["sin"], cos=JET_FUNCTIONS["cos"])
    return xc.c[0], xc.c[1], 2 * xc.c[2], yc.c[0], yc.c[1], 2 * yc.c[2]


def _kappa(entry: dict, where: str) -> mpmath.mpf:
    if "kappa" in entry:
        if "shape" in entry:
            raise ValueError(f"{where}: give shape or kappa, not both")
        return _num(entry["kappa"], f"{where}.kappa")
    shape = entry.get("shape")
    if shape not in KAPPA:
        raise ValueError(f"{where}: kappa (or shape = {' | '.join(KAPPA)}) is required, got {shape!r}")
    p, q = KAPPA[shape]
    return mpmath.mpf(p) / mpmath.mpf(q)


# ------------------------------------------------------------------ the run

class _Run:
    def __init__(self, track, bodies, law, omega, axis_x, g, limiter_restitution, on_inconsistent, dps):
        self.dps = dps
        self.om2 = _num(omega, "omega") ** 2
        self.a = _num(axis_x, "axis_x")
        self.g = _num(g, "g")
        if not self.g > 0:
            raise ValueError("g must be > 0")
        if not isinstance(law, dict) or law.get("name") not in LAW_NAMES:
            raise ValueError(f"law must be a dict with name = {' | '.join(LAW_NAMES)}, got {law!r}")
        self.law = LAW_NAMES[law["name"]]
        self.k = _num(law.get("restitution", 1), "law.restitution")
        if not 0 <= self.k <= 1:
            raise ValueError("law.restitution must be in [0, 1]")
        k_lim = limiter_restitution
        if k_lim is None:
            k_lim = track.get("limiter_restitution") if isinstance(track, dict) else None
        self.k_lim = self.k if k_lim is None else _num(k_lim, "limiter_restitution")
        if not 0 <= self.k_lim <= 1:
            raise ValueError("limiter_restitution must be in [0, 1]")
        if on_inconsistent not in ("newton", "stop"):
            raise ValueError("on_inconsistent must be 'newton' or 'stop'")
        self.on_inconsistent = on_inconsistent
        if not bodies:
            raise ValueError("at least one body is required")
        self.bodies, q, v = [], [], []
        for n, entry in enumerate(bodies, start=1):
            where = f"bodies[{n}]"
            r = _num(entry.get("radius", 0), f"{where}.radius")
            m = _num(entry["mass"], f"{where}.mass")
            kappa = _kappa(entry, where)
            if r < 0 or not m > 0 or not kappa >= 1:
                raise ValueError(f"{where}: needs radius >= 0, mass > 0, kappa >= 1")
            if self.law == "rolling" and r == 0:
                raise ValueError(f"{where}: the rolling law needs r > 0 (omega_P = sigma q'/r)")
            geometry, cuts = _geometry(track, r)
            body = _Body(r, m, kappa, geometry, cuts)
            self.bodies.append(body)
            q.append(_num(entry["q"], f"{where}.q"))
            v.append(_num(entry.get("dq", 0), f"{where}.dq"))
            if not cuts[0] <= q[-1] <= cuts[-1]:
                raise ValueError(f"{where}.q must be on the track [{mpmath.nstr(cuts[0], 17)}, "
                                 f"{mpmath.nstr(cuts[-1], 17)}]")
        self.n = len(self.bodies)
        self.piece = [b.piece_of(x) for b, x in zip(self.bodies, q)]
        for i in range(self.n - 1):
            if not q[i] < q[i + 1]:
                raise ValueError(f"bodies[{i + 2}].q: bodies must be listed in order along the track")
            if self._gap(i, q)[0] < 0:
                raise ValueError(f"bodies[{i + 2}] overlaps bodies[{i + 1}]")
        self.y = q + v
        for b in self.bodies:
            self._sample(b)
        for k in range(self.n):
            self._new_flight(k)
        self.tol_step = mpmath.mpf(10) ** (-(dps + 6))
        self.tol_event = mpmath.mpf(10) ** (-(dps + 4))
        self.h_acc = mpmath.mpf("0.001")
        self.t = mpmath.mpf(0)
        self.steps = 0
        self.max_drift = mpmath.mpf(0)

    # -- physics of one body --------------------------------------------------

    def _state(self, k, q, v, piece=None):
        """(x, x', x'', y, y', y'', F, q'') of body k at (q, v) on its piece."""
        b = self.bodies[k]
        x0, x1, x2, y0, y1, y2 = b.geometry(q, self.piece[k] if piece is None else piece)
        F = x1 * x1 + y1 * y1
        dF = 2 * (x1 * x2 + y1 * y2)
        force = (self.om2 * (x0 - self.a) * x1 - self.g * y1) / b.kappa
        return x0, x1, x2, y0, y1, y2, F, (force - dF * v * v / 2) / F

    def _integral(self, k, q, v, piece=None):
        """The body's first integral per unit mass, 1/2 kappa F v^2 - 1/2 Omega^2 (x_C - a)^2 + g y_C."""
        x0, x1, _, y0, y1, _ = self.bodies[k].geometry(q, self.piece[k] if piece is None else piece)
        return self.bodies[k].kappa * (x1 * x1 + y1 * y1) * v * v / 2 - self.om2 * (x0 - self.a) ** 2 / 2 \
            + self.g * y0

    def _energy(self):
        return mpmath.fsum(b.m * self._integral(k, self.y[k], self.y[self.n + k]) for k, b in enumerate(self.bodies))

    def _sample(self, b: _Body):
        """The body's geometry on GRID points per piece (20 digits, kept as floats: only for bounds)."""
        rows = []
        with mpmath.workdps(20):
            for p in range(b.pieces):
                lo, hi = b.cuts[p], b.cuts[p + 1]
                for n in range(GRID):
                    q = lo + (hi - lo) * n / (GRID - 1)
                    x0, x1, x2, y0, y1, y2 = b.geometry(q, p)
                    F = x1 * x1 + y1 * y1
                    arm = x0 - self.a
                    rows.append(tuple(float(v) for v in (
                        q, self.g * y0 - self.om2 * arm * arm / 2, abs(arm), abs(x1 * y2 - y1 * x2) / F ** 1.5,
                        F, abs(2 * (x1 * x2 + y1 * y2)), abs(self.g * y1 - self.om2 * arm * x1))))
        b.samples = rows
        vs = [row[1] for row in rows]
        b.spread = max(vs) - min(vs)

    def _new_flight(self, k):
        """The first integral at the start of a flight and the bounds of the safe steps over it.

        The body stays where V/m <= H/m (H its first integral): its stretch of
        track is taken from the samples around it (one sample beyond each
        end, where a turning point lies). At each sample of the stretch the
        speed follows from H: v_C^2 = 2 (H - V)/(m kappa) and q'^2 = v_C^2/F,
        hence |q''| = |V'/kappa + F' q'^2/2| / F and |a_C| <= |V'|/(kappa sigma)
        + K v_C^2 there; the bounds are the largest values over the stretch
        (H raised by a hundredth of V's spread over the track), times SAFETY.
        ``reach``: the stretch's ends (q), beyond which no event can happen.
        """
        b = self.bodies[k]
        q, v = self.y[k], self.y[self.n + k]
        b.h0 = self._integral(k, q, v)
        rows, h = b.samples, float(b.h0)
        level = h + 1e-9 * (abs(h) + b.spread)
        qf = float(q)
        hi = next((n for n, row in enumerate(rows) if row[0] >= qf), len(rows) - 1)
        lo = max(hi - 1, 0)
        while lo > 0 and rows[lo][1] <= level:
            lo -= 1
        while hi < len(rows) - 1 and rows[hi][1] <= level:
            hi += 1
        # one more sample each way: a piece end at a sample of the stretch (in float) counts as in reach
        b.reach = (rows[lo - 1][0] if lo > 0 else float("-inf"), rows[hi + 1][0] if hi + 1 < len(rows) else float("inf"))
        kappa = float(b.kappa)
        top = h + b.spread / 100
        centre_acc = q_acc = 0.0
        for _q, V, _arm, curvature, F, dF, dV in rows[lo:hi + 1]:
            speed2 = 2 * max(top - V, 0.0) / kappa
            centre_acc = max(centre_acc, dV / (kappa * F ** 0.5) + curvature * speed2)
            q_acc = max(q_acc, (dV / kappa + dF * speed2 / F / 2) / F)
        b.centre_acc = SAFETY * mpmath.mpf(centre_acc)
        b.q_acc = SAFETY * mpmath.mpf(q_acc)

    # -- gaps --------------------------------------------------------------------

    def _gap(self, i, y, states=None):
        """(gap, dgap/dq_i, dgap/dq_j) of the pair (i, i + 1) at coordinates y[:n]."""
        j = i + 1
        bi, bj = self.bodies[i], self.bodies[j]
        d = bi.r + bj.r
        if d == 0:
            return y[j] - y[i], mpmath.mpf(-1), mpmath.mpf(1)
        if states is None:
            si, sj = bi.geometry(y[i], self.piece[i]), bj.geometry(y[j], self.piece[j])
        else:
            si, sj = states[i], states[j]
        dx, dy = sj[0] - si[0], sj[3] - si[3]
        dist = mpmath.sqrt(dx * dx + dy * dy)
        nx, ny = dx / dist, dy / dist
        return dist - d, -(nx * si[1] + ny * si[4]), nx * sj[1] + ny * sj[4]

    # -- integration -------------------------------------------------------------

    def _derivs(self, y):
        n = self.n
        return y[n:] + [self._state(k, y[k], y[n + k])[7] for k in range(n)]

    def _midpoint(self, y0, H, steps):
        h = H / steps
        z0 = y0
        z1 = [a + h * b for a, b in zip(z0, self._derivs(z0))]
        for _ in range(steps - 1):
            z0, z1 = z1, [a + 2 * h * b for a, b in zip(z0, self._derivs(z1))]
        return [(a + b + h * c) / 2 for a, b, c in zip(z0, z1, self._derivs(z1))]

    def _extrapolate(self, y0, H):
        """(state at t + H or None, column, error estimate): Gragg-Bulirsch-Stoer.

        Row j holds the modified midpoint rule with 2 (j + 1) substeps and
        its extrapolations in H^2 (Aitken-Neville); the step converges when
        two neighbouring columns agree to ``tol_step`` (relative to 1 + |y|).
        It is given up (None) at MAX_COLUMNS, or earlier once the errors'
        geometric decrease can no longer reach the tolerance by then.
        """
        table, ns, last = [], [], None
        for j in range(MAX_COLUMNS):
            steps = 2 * (j + 1)
            ns.append(steps)
            row = [self._midpoint(y0, H, steps)]
            for col in range(1, j + 1):
                ratio = (mpmath.mpf(ns[j]) / ns[j - col]) ** 2 - 1
                row.append([a + (a - b) / ratio for a, b in zip(row[col - 1], table[j - 1][col - 1])])
            table.append(row)
            if j >= 2:
                err = max(abs(a - b) / (1 + abs(a)) for a, b in zip(row[j], row[j - 1]))
                if err < self.tol_step:
                    return row[j], j, err
                if j >= TARGET_COLUMN and last and err < last:
                    if err * (err / last) ** (MAX_COLUMNS - 1 - j) > self.tol_step:
                        return None, j, err
                last = err
        return None, MAX_COLUMNS, last

    def _step(self, h):
        """Advance by at most h (the accuracy controller may take less); returns the step taken.

        The next step aims at convergence in TARGET_COLUMN: from the error
        estimate e_c of the column c where this one converged, h (tol/e_c)^(1/(2c+1)),
        times 0.9, encouraged up (x 1.3) below the target column and down
        (x 0.8) above it, within [h/2, 2h].
        """
        while True:
            out, column, err = self._extrapolate(self.y, h)
            if out is not None:
                break
            shrink = mpmath.mpf("0.9") * (self.tol_step / err) ** (mpmath.mpf(1) / (2 * column + 1)) if err else 0
            h = h * min(max(shrink, mpmath.mpf("0.2")), mpmath.mpf("0.7"))
            self.h_acc = min(self.h_acc, h)
        if h >= self.h_acc:  # the step was not cut short by an event: adapt
            factor = mpmath.mpf("0.9") * (self.tol_step / err) ** (mpmath.mpf(1) / (2 * column + 1)) if err else 2
            if column < TARGET_COLUMN - 2:
                factor *= mpmath.mpf("1.3")
            elif column > TARGET_COLUMN:
                factor *= mpmath.mpf("0.8")
            self.h_acc = h * min(max(factor, mpmath.mpf("0.5")), 2)
        self.y = out
        self.t += h
        self.steps += 1
        return h

    def _last_step(self, h):
        """The step onto an event's root, h = e/|e'| (e below 10^-(dps+4)): extrapolated like
        any step (a few columns suffice), without touching the step-size controller."""
        if h == 0:
            return
        out, _column, _err = self._extrapolate(self.y, h)
        if out is None:
            raise RuntimeError(f"no convergence on a step of {mpmath.nstr(h, 5)} s onto an event")
        self.y = out
        self.t += h

    def _check(self):
        """The bounds of the safe steps hold at the current state; record the first integrals' drift."""
        # (a body beyond its stretch of track would show as an acceleration above the bound, or a drift)
        n = self.n
        for k, b in enumerate(self.bodies):
            q, v = self.y[k], self.y[n + k]
            x0, x1, x2, y0, y1, y2, F, acc = self._state(k, q, v)
            ax, ay = x1 * acc + x2 * v * v, y1 * acc + y2 * v * v
            if mpmath.sqrt(ax * ax + ay * ay) > b.centre_acc or abs(acc) > b.q_acc:
                raise RuntimeError(
                    f"body {k + 1} at t = {mpmath.nstr(self.t, 17)}, q = {mpmath.nstr(q, 17)}: its acceleration "
                    "exceeds the sampled bound of the safe steps (raise GRID or SAFETY)")
            h = b.kappa * F * v * v / 2 - self.om2 * (x0 - self.a) ** 2 / 2 + self.g * y0
            self.max_drift = max(self.max_drift, abs(h - b.h0))

    # -- events ------------------------------------------------------------------

    def _events(self):
        """[(e, rate, bound, kind, index)]: gaps ('gap', i) and piece ends ('lower'/'upper', k)."""
        n = self.n
        q, v = self.y[:n], self.y[n:]
        states = [self.bodies[k].geometry(q[k], self.piece[k]) for k in range(n)]
        out = []
        for i in range(n - 1):
            e, gi, gj = self._gap(i, q, states)
            bi, bj = self.bodies[i], self.bodies[i + 1]
            bound = bi.centre_acc + bj.centre_acc if bi.r + bj.r else bi.q_acc + bj.q_acc
            out.append((e, gi * v[i] + gj * v[i + 1], bound, "gap", i))
        for k, b in enumerate(self.bodies):
            lo, hi = b.cuts[self.piece[k]], b.cuts[self.piece[k] + 1]
            if lo >= b.reach[0]:  # else out of reach in this flight
                out.append((q[k] - lo, v[k], b.q_acc, "lower", k))
            if hi <= b.reach[1]:
                out.append((hi - q[k], -v[k], b.q_acc, "upper", k))
        return out

    def _is_limiter(self, kind, k) -> bool:
        return (kind == "lower" and self.piece[k] == 0) or (kind == "upper" and self.piece[k] == self.bodies[k].pieces - 1)

    def _event_acceleration(self, kind, index):
        """The second time derivative of an event function at the current state."""
        n = self.n
        if kind != "gap":
            acc = self._state(index, self.y[index], self.y[n + index])[7]
            return acc if kind == "lower" else -acc
        i, j = index, index + 1
        if self.bodies[i].r + self.bodies[j].r == 0:
            return self._state(j, self.y[j], self.y[n + j])[7] - self._state(i, self.y[i], self.y[n + i])[7]
        pos, vel, acc = [], [], []
        for k in (i, j):
            v = self.y[n + k]
            x0, x1, x2, y0, y1, y2, _F, a = self._state(k, self.y[k], v)
            pos.append((x0, y0))
            vel.append((x1 * v, y1 * v))
            acc.append((x1 * a + x2 * v * v, y1 * a + y2 * v * v))
        D = [pos[1][c] - pos[0][c] for c in (0, 1)]
        dD = [vel[1][c] - vel[0][c] for c in (0, 1)]
        ddD = [acc[1][c] - acc[0][c] for c in (0, 1)]
        dist = mpmath.sqrt(D[0] ** 2 + D[1] ** 2)
        along = (D[0] * dD[0] + D[1] * dD[1]) / dist
        return (D[0] * ddD[0] + D[1] * ddD[1] + dD[0] ** 2 + dD[1] ** 2 - along ** 2) / dist

    def _safe(self, e, rate, bound):
        e = max(e, mpmath.mpf(0))
        return (rate + mpmath.sqrt(rate * rate + 2 * bound * e)) / bound

    def _resolve(self, kind, index, run: PathReferenceRun) -> bool:
        """Apply an event at the current state; False to stop the run."""
        n = self.n
        if kind == "gap":
            return self._collide(index, run)
        k, b = index, self.bodies[index]
        q, v = self.y[k], self.y[n + k]
        piece = self.piece[k]
        new = piece + (1 if kind == "upper" else -1)
        if 0 <= new < b.pieces:
            self.piece[k] = new
            with mpmath.workdps(self.dps):
                run.passages.append(PathPassage(t=+self.t, body=k + 1, kind=JUNCTION, piece_from=piece + 1,
                                                piece_to=new + 1, q=+q, dq_before=+v, dq_after=+v))
            return True
        v_new = -self.k_lim * v
        self.y[n + k] = v_new
        with mpmath.workdps(self.dps):
            run.passages.append(PathPassage(
                t=+self.t, body=k + 1, kind=LIMITER_UPPER if kind == "upper" else LIMITER_LOWER,
                piece_from=piece + 1, piece_to=piece + 1, q=+q, dq_before=+v, dq_after=+v_new))
        self._new_flight(k)
        if abs(v_new) <= mpmath.mpf(10) ** (-(self.dps // 2)) * abs(v):
            run.status = "rest"
            run.message = (f"body {k + 1} stays at the {'upper' if kind == 'upper' else 'lower'} limiter "
                           f"at t = {mpmath.nstr(self.t, 17)} (limiter restitution 0)")
            return False
        return True

    def _law(self, body: _Body, sigma):
        """(c, M) of u = c q' and the law's inertia."""
        if self.law == "rolling":
            return sigma / body.r, body.kappa * body.m * body.r ** 2
        if self.law == "newton":
            return sigma, body.m
        return mpmath.mpf(1), body.kappa * body.m * sigma ** 2

    def _collide(self, i, run: PathReferenceRun) -> bool:
        n, j = self.n, i + 1
        bi, bj = self.bodies[i], self.bodies[j]
        qi, qj, vi, vj = self.y[i], self.y[j], self.y[n + i], self.y[n + j]
        si, sj = self._state(i, qi, vi), self._state(j, qj, vj)
        _, gi, gj = self._gap(i, self.y[:n], {i: si, j: sj})
        sig_i, sig_j = mpmath.sqrt(si[6]), mpmath.sqrt(sj[6])
        (ci, Mi), (cj, Mj) = self._law(bi, sig_i), self._law(bj, sig_j)
        du = ci * vi - cj * vj
        one_k = 1 + self.k
        vi_new = vi - one_k * Mj / (Mi + Mj) * du / ci
        vj_new = vj + one_k * Mi / (Mi + Mj) * du / cj
        closing = gi * vi + gj * vj
        tiny = mpmath.mpf(10) ** (-(self.dps // 2)) * (abs(gi * vi) + abs(gj * vj))
        flag = 0
        stop = None
        if gi * vi_new + gj * vj_new < -tiny:
            if self.on_inconsistent == "stop":
                stop = ("inconsistent", "still approach after the law (they would overlap)")
            else:
                Gi, Gj = bi.kappa * bi.m * si[6], bj.kappa * bj.m * sj[6]
                impulse = -one_k * closing / (gi * gi / Gi + gj * gj / Gj)
                vi_new, vj_new = vi + impulse * gi / Gi, vj + impulse * gj / Gj
                flag = 1
        energy_before = self._energy()
        self.y[n + i], self.y[n + j] = vi_new, vj_new
        energy_after = self._energy()
        with mpmath.workdps(self.dps):
            run.collisions.append(PathCollision(
                t=+self.t, i=i + 1, j=j + 1, q_i=+qi, q_j=+qj, dq_i_before=+vi, dq_j_before=+vj,
                dq_i_after=+vi_new, dq_j_after=+vj_new, law_flag=flag, energy_before=+energy_before,
                energy_after=+energy_after))
        self._new_flight(i)
        self._new_flight(j)
        if stop is None and gi * vi_new + gj * vj_new <= tiny:
            stop = ("contact", "do not separate after the law (persistent contact)")
        if stop is not None:
            run.status = stop[0]
            run.message = (f"collision {len(run.collisions)} at t = {mpmath.nstr(self.t, 17)}: "
                           f"bodies {i + 1} and {j + 1} {stop[1]}")
            return False
        return True

    def run(self, n_collisions, t_end, max_steps) -> PathReferenceRun:
        run = PathReferenceRun()
        instant = 0  # events resolved since the last step
        while len(run.collisions) < n_collisions:
            if self.steps >= max_steps:
                run.status, run.message = "max_steps", f"stopped after {max_steps} steps"
                break
            events, watched, due = self._events(), [], []
            for e, rate, bound, kind, index in events:
                at = self.tol_event * (1 + abs(self.y[index]))
                if e < -at:
                    raise RuntimeError(f"event {kind} {index + 1} crossed unseen at t = {mpmath.nstr(self.t, 17)} "
                                       f"(e = {mpmath.nstr(e, 5)}): a bound of the safe steps failed")
                if e <= at and rate < 0:
                    due.append((max(e, mpmath.mpf(0)) / -rate, kind, index))
                elif e <= at and rate <= at:
                    # at the event surface and (nearly) at rest on it: its acceleration decides
                    if self._event_acceleration(kind, index) > 0:
                        continue  # leaving it: no bound needed for this step
                    if kind == "gap" or self._is_limiter(kind, index):
                        run.status = "contact" if kind == "gap" else "rest"
                        run.message = (f"t = {mpmath.nstr(self.t, 17)}: "
                                       + (f"bodies {index + 1} and {index + 2} rest against each other"
                                          if kind == "gap" else f"body {index + 1} rests against the {kind} limiter")
                                       + " (persistent contact is not modelled)")
                        break
                    due.append((mpmath.mpf(0), kind, index))
                else:
                    watched.append((e, rate, bound))
            else:
                watched = watched or [(mpmath.inf, mpmath.mpf(1), mpmath.mpf(1))]
            if run.status != "max_collisions":
                break
            if due:
                h, kind, index = min(due, key=lambda x: x[0])
                if t_end is not None and self.t + h > t_end:
                    break
                instant += 1
                if instant > 16 * (self.n + 1):
                    raise RuntimeError(f"events at t = {mpmath.nstr(self.t, 17)} keep following each other "
                                       "without the time advancing")
                self._last_step(h)
                if not self._resolve(kind, index, run):
                    break
                continue
            h = min(self._safe(e, rate, bound) for e, rate, bound in watched)
            h = min(h, self.h_acc)
            if t_end is not None:
                if self.t >= t_end:
                    break
                h = min(h, t_end - self.t)
            self._step(h)
            instant = 0
            self._check()
        else:
            run.message = f"stopped after {n_collisions} collisions"
        if len(run.collisions) < n_collisions and run.status == "max_collisions" and t_end is not None:
            run.status = "t_end"
            run.message = f"no further collision before t_end = {mpmath.nstr(t_end, 17)}"
        with mpmath.workdps(self.dps):
            run.t_final = +self.t
            run.q = [+x for x in self.y[: self.n]]
            run.dq = [+x for x in self.y[self.n:]]
            run.max_drift = +self.max_drift
        run.pieces = [p + 1 for p in self.piece]
        run.steps = self.steps
        return run


def run_path_reference(track: dict, bodies: list, law: dict, n_collisions: int, *, omega=0, axis_x=0, g="9.81",
                       t_end=None, dps: int = DIGITS, limiter_restitution=None, on_inconsistent: str = "newton",
                       max_steps: int = 1_000_000) -> PathReferenceRun:
    """The first ``n_collisions`` collisions of bodies on a path track (stopping at ``t_end``).

    * ``track``: a scene file's ``[track]`` table (``type`` curve, arcs or
      three_arcs; see :mod:`.equilibria`); numbers as numbers, numeric strings
      or Decimals, each read as ``mpmath.mpf(str(value))``. Its
      ``limiter_restitution`` is used unless the keyword is given; the
      default is the law's restitution (as in the engine).
    * ``bodies``: dicts in order along the track, each with ``radius`` (0 or
      absent: a particle), ``mass``, ``kappa`` (J_P = kappa m r^2; or
      ``shape`` = solid_sphere | hollow_sphere | disk | ring | particle), ``q``
      and ``dq`` (the generalized coordinate and its rate: the contact
      abscissa x on a curve, the arc length s of the centre's path on an arc
      chain, 0 at its start).
    * ``law``: ``{"name": "rolling" | "hedrih" | "newton" | "newton_generalized",
      "restitution": k}`` (see the module doc); ``on_inconsistent``:
      ``"newton"`` (the engine's default fallback) or ``"stop"``.
    * ``omega``, ``axis_x``: the vertical plane turns at omega about the
      vertical line x = axis_x; ``g``; ``t_end`` (None: no limit, the run ends
      after ``n_collisions`` or ``max_steps`` integration steps).
    * ``dps``: decimal digits of the results (computed with GUARD_DPS more).

    Returns a :class:`PathReferenceRun` (collisions, passages, status, final state).
    """
    if n_collisions < 0:
        raise ValueError("n_collisions must be >= 0")
    with mpmath.workdps(dps + GUARD_DPS):
        solver = _Run(track, bodies, law, omega, axis_x, g, limiter_restitution, on_inconsistent, dps)
        end = None if t_end is None else _num(t_end, "t_end")
        return solver.run(n_collisions, end, max_steps)


def path_reference_collisions(track, bodies, law, n_collisions, **options) -> list:
    """The collisions of :func:`run_path_reference` (a list of :class:`PathCollision`)."""
    return run_path_reference(track, bodies, law, n_collisions, **options).collisions


# ------------------------------------------------------------ scene files

def scene_inputs(data: dict) -> dict:
    """Keyword arguments of :func:`run_path_reference` (all but n_collisions) from a scene file.

    ``data`` is the whole file as read by ``tomllib.loads(text,
    parse_float=Decimal)``. Bodies give ``shape`` or ``kappa``, ``radius``,
    ``mass`` (``density`` is not supported here) and their start as ``x``/``dx``
    (curve), ``s``/``ds`` or ``segment``/``angle``/``dangle`` (arc chains:
    s = s0 + rho (angle - start) on an arc, rho = R - r concave or R + r
    convex, s0 + angle on a line; ds = rho dangle). ``t_end`` comes from
    ``[run]`` (default 100 s).
    """
    track = data["track"]
    kind = _check_keys(track)
    collision = data.get("collision", {})
    frame = data.get("frame", {})
    bodies = []
    with mpmath.workdps(DIGITS + 2 * GUARD_DPS):
        for n, entry in enumerate(data["bodies"], start=1):
            where = f"bodies[{n}]"
            if "density" in entry:
                raise ValueError(f"{where}: give mass (density is not supported by the reference)")
            r = entry.get("radius", 0)
            body = {"radius": r, "mass": entry["mass"], "kappa": _kappa(entry, where)}
            if kind == "curve":
                body["q"], body["dq"] = entry["x"], entry.get("dx", 0)
            elif "segment" in entry:
                segs = _segments(track)[2]
                pieces = _chain(track, _num(r, f"{where}.radius"))
                number = entry["segment"]
                seg, piece = segs[number - 1], pieces[number - 1]
                angle = _num(entry["angle"], f"{where}.angle")
                dangle = _num(entry.get("dangle", 0), f"{where}.dangle")
                if seg[0] == "line":
                    body["q"], body["dq"] = piece.s0 + angle, dangle
                else:
                    body["q"], body["dq"] = piece.s0 + piece.rho * (angle - seg[3]), piece.rho * dangle
            else:
                body["q"], body["dq"] = entry["s"], entry.get("ds", 0)
            bodies.append(body)
    return {
        "track": track,
        "bodies": bodies,
        "law": {"name": collision.get("law", "hedrih"), "restitution": collision.get("restitution", 1)},
        "omega": frame.get("omega", 0),
        "axis_x": frame.get("axis_x", 0),
        "g": data.get("g", "9.81"),
        "t_end": data.get("run", {}).get("t_end", 100),
        "on_inconsistent": "stop" if collision.get("on_inconsistent") == "error" else "newton",
    }
