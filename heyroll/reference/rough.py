"""Coulomb friction on rough tracks in a vertical plane: an independent reference.

Closed forms (and one plain mpmath integrator) for a particle sliding on a rough
track and for a rolling body that slips, in the line of work of the paper's
section 2 (bodies on rough tracks). Used to check the engine: like every module
of ``heyroll.reference`` it imports nothing from ``heyroll.model``,
``heyroll.simulation``, ``heyroll.interfaces`` or ``heyroll.analysis`` (and not
heyoka); every formula is derived below from Newton's law and Coulomb's law.

Conventions
-----------
* SI units; g is always given explicitly (no default).
* Kinetic friction coefficient ``mu``, static ``mu_s >= mu``. While sliding the
  friction force is ``mu N`` against the sliding velocity; at rest (or at a
  turning point) the body sticks iff the tangential load it needs is at most
  ``mu_s N``, otherwise it restarts from rest in the direction of that load.
* A contact mode is one of ``"rolling"``, ``"sliding+"``, ``"sliding-"``,
  ``"stuck"``. For a sliding particle the sign is the sign of its coordinate's
  rate (x' on a line or curve, phi' on the circle); for a rolling body that
  slips, the sign of its slip velocity ``w = v_C - r omega_P = v - u`` (centre
  speed minus rolling-equivalent speed).
* ``kappa = 1 + i_C^2 / r^2`` (solid sphere 7/5, disk 3/2, ring 2); the
  rotational kinetic energy about the centre is ``1/2 m (kappa - 1) u^2`` with
  ``u = r * spin`` the rolling-equivalent speed; rolling <=> ``u = v``.
* Inputs are plain numbers: ints, floats (taken as their exact binary value, as
  a double engine sees them), decimal strings or mpf. Every function works at
  ``dps`` digits plus :data:`GUARD_DPS` guard digits in a local
  ``mpmath.workdps`` (the global precision is never changed) and returns mpf
  values rounded to ``dps`` digits (or frozen dataclasses of them).

Contents
--------
1. Straight rough incline, particle: :func:`incline_sliding`,
   :func:`incline_stopping_distance`, :func:`incline_stopping_time`.
2. Particle inside a rough circle, closed-form branches:
   :func:`circle_branch_rate2`, :func:`circle_branch_end`,
   :func:`circle_turning_point`, :func:`circle_branch_time`,
   :func:`circle_energy`, :func:`circle_friction_work`,
   :func:`circle_sliding_sequence`.
3. Rolling body that slips on an incline: :func:`incline_roll_from_rest`,
   :func:`incline_slip_then_roll`.
4. General integrator, particle on top of y = f(x): :func:`sliding_on_curve`
   (mpmath.odefun, Taylor series, branch by branch).
"""

from __future__ import annotations

from dataclasses import dataclass

import mpmath

__all__ = [
    "GUARD_DPS",
    "ROLLING",
    "SLIDING_PLUS",
    "SLIDING_MINUS",
    "STUCK",
    "InclineTransition",
    "InclineRun",
    "incline_sliding",
    "incline_stopping_distance",
    "incline_stopping_time",
    "NoTurningPoint",
    "CircleBranchEnd",
    "CircleBranch",
    "CircleTransition",
    "CircleRun",
    "circle_branch_rate2",
    "circle_branch_end",
    "circle_turning_point",
    "circle_branch_time",
    "circle_energy",
    "circle_friction_work",
    "circle_sliding_sequence",
    "RollFromRest",
    "SlipToRoll",
    "incline_roll_from_rest",
    "incline_slip_then_roll",
    "CurveTransition",
    "CurveRun",
    "sliding_on_curve",
]

#: Extra decimal digits carried inside every evaluation.
GUARD_DPS = 10

ROLLING = "rolling"
SLIDING_PLUS = "sliding+"
SLIDING_MINUS = "sliding-"
STUCK = "stuck"


# ----------------------------------------------------------------- helpers


def _sign(x) -> int:
    return 1 if x > 0 else (-1 if x < 0 else 0)


def _sliding(sgn: int) -> str:
    return SLIDING_PLUS if sgn > 0 else SLIDING_MINUS


def _num(value, name: str):
    """An mpf at the current precision from an int, float, decimal string or mpf."""
    if isinstance(value, bool):
        raise TypeError(f"{name} must be a number, not bool")
    try:
        out = mpmath.mpf(value)
    except TypeError:  # Decimal and the like: through their decimal string
        try:
            out = mpmath.mpf(str(value))
        except (TypeError, ValueError) as exc:
            raise ValueError(f"{name} must be a real number, got {value!r}") from exc
    except ValueError as exc:
        raise ValueError(f"{name} must be a real number, got {value!r}") from exc
    if not mpmath.isfinite(out):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return out


def _out(dps: int, value):
    """``value`` rounded to ``dps`` digits (None, ints and inf pass through)."""
    if value is None:
        return None
    with mpmath.workdps(dps):
        return +value


def _check_dps(dps) -> int:
    if not isinstance(dps, int) or isinstance(dps, bool) or dps < 15:
        raise ValueError("dps must be an int >= 15")
    return dps


def _friction(mu, mu_s):
    mu = _num(mu, "mu")
    mu_s = _num(mu_s, "mu_s") if mu_s is not None else None
    if mu < 0:
        raise ValueError("mu must be >= 0")
    if mu_s is not None and mu_s < mu:
        raise ValueError("mu_s must be >= mu")
    return mu, mu_s


def _positive(value, name):
    out = _num(value, name)
    if not out > 0:
        raise ValueError(f"{name} must be > 0")
    return out


def _bracketed_root(f, a, b):
    """The root of f in the closed interval between a and b, where f(a) and f(b)
    have opposite signs (or one of them is 0): mpmath.findroot (Anderson's
    bracketing method), checked to stay inside the bracket, with bisection to
    the working precision as the fallback."""
    fa, fb = f(a), f(b)
    if fa == 0:
        return a
    if fb == 0:
        return b
    if _sign(fa) == _sign(fb):
        raise ValueError("root not bracketed")
    lo, hi = (a, b) if a < b else (b, a)
    try:
        r = mpmath.findroot(f, (a, b), solver="anderson", verify=False)
        if isinstance(r, mpmath.mpf) and lo <= r <= hi:
            fr = f(r)
            scale = max(abs(fa), abs(fb))
            if abs(fr) <= scale * mpmath.eps * 2**20:
                return r
    except (ZeroDivisionError, ValueError, TypeError):
        pass
    # Bisection: one bit per step, to the working precision.
    s_lo = _sign(f(lo))
    for _ in range(mpmath.mp.prec + 20):
        mid = (lo + hi) / 2
        if mid == lo or mid == hi:
            break
        fm = f(mid)
        if fm == 0:
            return mid
        if _sign(fm) == s_lo:
            lo = mid
        else:
            hi = mid
    return (lo + hi) / 2


# =====================================================================
# 1. Particle on a straight rough incline
# =====================================================================


@dataclass(frozen=True)
class InclineTransition:
    """A change of contact mode at time ``t``, position ``x`` and rate ``dx``."""

    t: object
    mode_from: str
    mode_to: str
    x: object
    dx: object


@dataclass(frozen=True)
class InclineRun:
    """Result of :func:`incline_sliding`.

    ``mode0`` is the mode just after t = 0, ``transitions`` the mode changes in
    (0, t_end], ``t_stop``/``x_stop`` the first stop (None if the particle never
    stops before t_end), and ``t``, ``mode``, ``x``, ``dx`` the state at t_end.
    """

    mode0: str
    transitions: tuple
    t_stop: object
    x_stop: object
    t: object
    mode: str
    x: object
    dx: object


def _incline_angle(alpha):
    alpha = _num(alpha, "alpha")
    if not abs(alpha) < mpmath.pi / 2:
        raise ValueError("alpha must satisfy |alpha| < pi/2")
    return alpha


def incline_sliding(alpha, mu, mu_s, x0, dx0, g, t_end, *, dps: int = 40) -> InclineRun:
    """A particle sliding on top of the rough line y = tan(alpha) x, to ``t_end``.

    Coordinate x, the abscissa of the contact point; arc length along the
    slope s = x / cos(alpha) (increasing s climbs when alpha > 0), speed
    v = s' = x' / cos(alpha). Unit tangent T = (cos a, sin a), upward normal
    n = (-sin a, cos a). The normal balance gives N = m g cos(alpha) > 0 (the
    contact never opens on a straight line), and the tangential one, with
    kinetic friction mu N against the velocity, sgn = sign(x'),

        s'' = -g sin(alpha) - sgn mu g cos(alpha) =: A_sgn     (x'' = cos(alpha) s'').

    A_sgn is constant on a branch, so s(t) = s0 + v0 t + A t^2 / 2. The branch
    decelerates iff sgn A_sgn < 0, i.e. always uphill, and downhill iff
    mu > |tan alpha|; then the particle stops at

        t_stop = |v0| / |A_sgn|,   s_stop = s0 + v0 t_stop / 2.

    At rest the tangential load is the weight's component -m g sin(alpha) and
    static friction can supply at most mu_s N = mu_s m g cos(alpha): the
    particle sticks for ever iff |tan alpha| <= mu_s; otherwise it restarts
    from rest downhill (sgn = -sign(alpha): "sliding-" when alpha > 0) with
    |A| = g (|sin a| - mu cos a) > 0 and accelerates for ever. A start with
    dx0 = 0 is decided by the same rule. Downhill with mu cos a = |sin a| the
    speed stays constant; with mu cos a < |sin a| the particle accelerates for
    ever. alpha = 0 (flat) is included: it decelerates at mu g and sticks.
    """
    dps = _check_dps(dps)
    with mpmath.workdps(dps + GUARD_DPS):
        a = _incline_angle(alpha)
        mu, mu_s = _friction(mu, mu_s)
        x0 = _num(x0, "x0")
        dx0 = _num(dx0, "dx0")
        g = _positive(g, "g")
        t_end = _num(t_end, "t_end")
        if t_end < 0:
            raise ValueError("t_end must be >= 0")
        ca, sa = mpmath.cos(a), mpmath.sin(a)
        s, v = x0 / ca, dx0 / ca

        def static_mode():
            # |m g sin a| <= mu_s m g cos a  <=>  |tan a| <= mu_s
            return STUCK if abs(sa) <= mu_s * ca else _sliding(-_sign(sa))

        mode = _sliding(_sign(v)) if v != 0 else static_mode()
        mode0 = mode
        t = mpmath.mpf(0)
        transitions = []
        t_stop = x_stop = None
        while True:
            if mode == STUCK:
                break
            sgn = 1 if mode == SLIDING_PLUS else -1
            A = -g * sa - sgn * mu * g * ca
            if sgn * A < 0 and v != 0:
                dt = abs(v) / abs(A)
                if t + dt <= t_end:
                    s = s + v * dt / 2  # = s + v dt + A dt^2/2 with A dt = -v
                    t = t + dt
                    v = mpmath.mpf(0)
                    new = static_mode()
                    if t_stop is None:
                        t_stop, x_stop = t, s * ca
                    transitions.append((t, mode, new, s * ca, mpmath.mpf(0)))
                    mode = new
                    continue
            dt = t_end - t
            s = s + v * dt + A * dt**2 / 2
            v = v + A * dt
            t = t_end
            break
        t = t_end
        return InclineRun(
            mode0=mode0,
            transitions=tuple(
                InclineTransition(_out(dps, tt), m0, m1, _out(dps, xx), _out(dps, dd))
                for tt, m0, m1, xx, dd in transitions
            ),
            t_stop=_out(dps, t_stop),
            x_stop=_out(dps, x_stop),
            t=_out(dps, t),
            mode=mode,
            x=_out(dps, s * ca),
            dx=_out(dps, v * ca),
        )


def incline_stopping_distance(alpha, mu, v0, g, *, dps: int = 40):
    """Distance along the slope of a particle launched uphill at speed v0 > 0.

    Uphill the deceleration is constant, g (sin a + mu cos a) (see
    :func:`incline_sliding`), so v^2 = v0^2 - 2 g (sin a + mu cos a) d gives

        d = v0^2 / (2 g (sin(alpha) + mu cos(alpha))).

    "Uphill" is the direction of increasing x on y = tan(alpha) x; for
    alpha < 0 that direction descends, and if sin a + mu cos a <= 0 the
    particle never stops: the result is mpmath.inf.
    """
    return _uphill_stop(alpha, mu, v0, g, dps, lambda v, dec: v**2 / (2 * dec))


def _uphill_stop(alpha, mu, v0, g, dps, of):
    """``of(v0, deceleration)`` for a particle launched uphill at v0 (inf if it never stops)."""
    dps = _check_dps(dps)
    with mpmath.workdps(dps + GUARD_DPS):
        a = _incline_angle(alpha)
        mu, _ = _friction(mu, None)
        v0 = _num(v0, "v0")
        g = _positive(g, "g")
        if v0 < 0:
            raise ValueError("v0 must be >= 0 (a speed uphill)")
        dec = g * (mpmath.sin(a) + mu * mpmath.cos(a))
        if not dec > 0:
            return mpmath.inf if v0 > 0 else mpmath.mpf(0)
        return _out(dps, of(v0, dec))


def incline_stopping_time(alpha, mu, v0, g, *, dps: int = 40):
    """Time to stop of a particle launched uphill at speed v0 > 0:
    t = v0 / (g (sin(alpha) + mu cos(alpha))) (constant deceleration, see
    :func:`incline_stopping_distance`); mpmath.inf if it never stops."""
    return _uphill_stop(alpha, mu, v0, g, dps, lambda v, dec: v / dec)


# =====================================================================
# 2. Particle inside a rough circle
# =====================================================================

TURNING_POINT = "turning_point"
LEAVES_TRACK = "leaves_track"
OVER_THE_TOP = "over_the_top"


class NoTurningPoint(ValueError):
    """The branch ends before its velocity vanishes: ``kind`` is
    ``"leaves_track"`` (N reaches 0 at ``phi``, on the upper half) or
    ``"over_the_top"`` (the particle passes the top ``phi`` still pressed on the
    track, y > 0 and N > 0 there)."""

    def __init__(self, kind: str, phi):
        self.kind = kind
        self.phi = phi
        super().__init__(f"no turning point: the particle {kind.replace('_', ' ')} at phi = {mpmath.nstr(phi, 15)}")


@dataclass(frozen=True)
class CircleBranchEnd:
    """Where a sliding branch on the circle ends: ``kind`` is ``"turning_point"``
    (phi' = 0), ``"leaves_track"`` (N = 0) or ``"over_the_top"`` (the top is
    reached with N > 0, phi' != 0), at the angle ``phi``."""

    kind: str
    phi: object


class _CircleBranch:
    """phi'^2 = y(phi) on one sliding branch (fixed sign s), in closed form.

    R phi'' = -g sin phi - s mu (R phi'^2 + g cos phi). With y = phi'^2,
    dy/dphi = 2 phi'' (d/dt y = 2 phi' phi'' = dy/dphi phi'), so

        y' + c y = -k (sin phi + s mu cos phi),    c = 2 s mu,  k = 2 g / R,

    linear of first order. Particular solution y_p = A sin phi + B cos phi:
    (A c - B) sin + (A + B c) cos = -k sin - k s mu cos gives B = A c + k and
    A (1 + c^2) = -k s mu - c k = -3 k s mu:

        A = -3 s mu k / (1 + 4 mu^2),   B = k (1 - 2 mu^2) / (1 + 4 mu^2),

    and y(phi) = y_p(phi) + (y0 - y_p(phi0)) exp(-c (phi - phi0)). Evaluated
    anchored at any known point (phi_a, y_a) of the branch, with delta =
    phi - phi_a and y_p(phi_a + delta) = y_p(phi_a) cos delta + y_p'(phi_a) sin delta:

        y = y_a e^{-c delta} + y_p(phi_a) (cos delta - e^{-c delta}) + y_p'(phi_a) sin delta,

    cos delta - e^{-c delta} = -2 sin^2(delta/2) - expm1(-c delta): every term is
    O(delta) and accurate relative to itself near delta = 0, so y/delta keeps
    full precision next to a turning point (y_a = 0).
    """

    def __init__(self, phi0, y0, s, mu, R, g):
        self.phi0, self.y0, self.s, self.mu, self.R, self.g = phi0, y0, s, mu, R, g
        self.k = 2 * g / R
        self.c = 2 * s * mu
        den = 1 + 4 * mu**2
        self.A = -3 * s * mu * self.k / den
        self.B = self.k * (1 - 2 * mu**2) / den

    def yp(self, phi):
        return self.A * mpmath.sin(phi) + self.B * mpmath.cos(phi)

    def dyp(self, phi):
        return self.A * mpmath.cos(phi) - self.B * mpmath.sin(phi)

    def anchored(self, phi_a, y_a, delta):
        e = mpmath.exp(-self.c * delta)
        cos_minus_e = -2 * mpmath.sin(delta / 2) ** 2 - mpmath.expm1(-self.c * delta)
        return y_a * e + self.yp(phi_a) * cos_minus_e + self.dyp(phi_a) * mpmath.sin(delta)

    def y(self, phi):
        return self.anchored(self.phi0, self.y0, phi - self.phi0)

    def n(self, phi):
        """N/m = R y + g cos phi (the track pushes inwards)."""
        return self.R * self.y(phi) + self.g * mpmath.cos(phi)

    def breakpoints(self, count):
        """The first ``count`` points beyond phi0 in the direction s where
        z = y e^{c phi} or N e^{c phi} may stop being monotone:
        d/dphi (y e^{c phi}) = -k sqrt(1 + mu^2) e^{c phi} sin(phi + s atan mu)
        vanishes at phi = -s atan(mu) + n pi, and d/dphi (N/m e^{c phi}) =
        e^{c phi} (R (y' + c y) - g sin + c g cos) = -3 g e^{c phi} sin phi at
        phi = n pi. Between consecutive points both y and N have at most one
        zero each, signalled by their signs at the ends."""
        s, pi = self.s, mpmath.pi
        pts = []
        for offset, tag in ((-s * mpmath.atan(self.mu), "y"), (mpmath.mpf(0), "n")):
            # first n with s (offset + n pi - phi0) > 0
            n = mpmath.floor((self.phi0 - offset) / pi) if s > 0 else mpmath.ceil((self.phi0 - offset) / pi)
            for j in range(count + 2):
                p = offset + (n + s * j) * pi
                if s * (p - self.phi0) > 0:
                    pts.append((s * (p - self.phi0), p, tag, int(n + s * j)))
        pts.sort(key=lambda item: item[0])
        return pts[:count]

    def end(self):
        """The first end of the branch in the direction s (see circle_branch_end)."""
        s = self.s
        a = self.phi0
        for _dist, b, tag, n in self.breakpoints(12):
            yb, nb = self.y(b), self.n(b)
            if yb <= 0 or nb <= 0:
                cands = []
                if yb <= 0:
                    cands.append((TURNING_POINT, _bracketed_root(self.y, a, b)))
                if nb <= 0:
                    cands.append((LEAVES_TRACK, _bracketed_root(self.n, a, b)))
                # the first in the direction of motion; a tie (both at phi = +-pi/2) is a turning point
                cands.sort(key=lambda item: (s * (item[1] - self.phi0), item[0] != TURNING_POINT))
                return cands[0]
            if tag == "n" and n % 2 != 0:
                return OVER_THE_TOP, b
            a = b
        raise AssertionError("a branch ends within one turn")  # pragma: no cover


def _circle_setup(phi0, dphi0, mu, R, g, sgn):
    phi0 = _num(phi0, "phi0")
    dphi0 = _num(dphi0, "dphi0")
    mu, _ = _friction(mu, None)
    R = _positive(R, "R")
    g = _positive(g, "g")
    s = _sign(dphi0)
    if sgn is not None:
        if sgn not in (1, -1):
            raise ValueError("sgn must be +1 or -1")
        if s and s != sgn:
            raise ValueError("sgn contradicts the sign of dphi0")
        s = sgn
    if s == 0:
        raise ValueError("dphi0 = 0: give the direction of the branch as sgn=+1 or -1")
    branch = _CircleBranch(phi0, dphi0**2, s, mu, R, g)
    if branch.n(phi0) < 0:
        raise ValueError("N < 0 at the start: the particle is not on the track")
    return branch


def circle_branch_rate2(phi, phi0, dphi0, mu, R, g, *, sgn=None, dps: int = 40):
    """phi'^2 at ``phi`` on the sliding branch through (phi0, dphi0).

    Particle inside a circle of radius R, phi from the lowest point
    counter-clockwise, position (R sin phi, -R cos phi). The inward normal
    force is N/m = R phi'^2 + g cos phi (centripetal balance), and with
    friction mu N against the motion, s = sign(phi'),

        R phi'' = -g sin phi - s mu (R phi'^2 + g cos phi).

    With y = phi'^2 (dy/dphi = 2 phi''):
    dy/dphi + 2 s mu y = -(2g/R) (sin phi + s mu cos phi), whose solution is

        y(phi) = A sin phi + B cos phi + (y0 - A sin phi0 - B cos phi0) e^{-2 s mu (phi - phi0)},
        A = -(2g/R) 3 s mu / (1 + 4 mu^2),   B = (2g/R) (1 - 2 mu^2) / (1 + 4 mu^2)

    (derivation in ``_CircleBranch``; mu = 0 gives the energy integral
    y = y0 + (2g/R)(cos phi - cos phi0)). Valid between phi0 and the branch
    end (:func:`circle_branch_end`); beyond it the value is the analytic
    continuation. ``dphi0 = 0`` (a start from rest) needs ``sgn``.
    """
    dps = _check_dps(dps)
    with mpmath.workdps(dps + GUARD_DPS):
        branch = _circle_setup(phi0, dphi0, mu, R, g, sgn)
        return _out(dps, branch.y(_num(phi, "phi")))


def circle_branch_end(phi0, dphi0, mu, R, g, *, sgn=None, dps: int = 40) -> CircleBranchEnd:
    """Where the sliding branch through (phi0, dphi0) ends, in its direction s.

    The branch ends at the first of: y = phi'^2 = 0 (a turning point), N = 0
    (the particle leaves the track) or the top phi = (2n+1) pi reached with
    y > 0 and N > 0 (it goes over the top; the closed form would continue but
    this reference stops there). Safe bracketing: with c = 2 s mu,
    d(y e^{c phi})/dphi = -(2g/R) sqrt(1 + mu^2) e^{c phi} sin(phi + s atan mu) and
    d(N/m e^{c phi})/dphi = -3 g e^{c phi} sin phi, so on every interval between
    consecutive points of {-s atan(mu) + n pi} U {n pi} each of y and N is a
    positive factor times a monotone function: it has at most one zero there,
    found by mpmath.findroot on the closed form from the signs at the ends.

    Since N/m = R y + g cos phi, y = 0 with N >= 0 needs cos phi >= 0: turning
    points lie on the lower half, and a particle that passes phi = +-pi/2 with
    y > 0 loses contact (N = 0 on the upper half) before it could stop there.
    """
    dps = _check_dps(dps)
    with mpmath.workdps(dps + GUARD_DPS):
        branch = _circle_setup(phi0, dphi0, mu, R, g, sgn)
        kind, phi = branch.end()
        return CircleBranchEnd(kind, _out(dps, phi))


def circle_turning_point(phi0, dphi0, mu, R, g, *, sgn=None, dps: int = 40):
    """The first phi in the direction of motion where phi' = 0 on the branch
    through (phi0, dphi0) (the root of the closed form y(phi) of
    :func:`circle_branch_rate2`, bracketed as in :func:`circle_branch_end`).
    Raises :class:`NoTurningPoint` with ``kind`` ``"leaves_track"`` (N reaches
    0 first, on the upper half) or ``"over_the_top"`` (the top is passed first)."""
    dps = _check_dps(dps)
    with mpmath.workdps(dps + GUARD_DPS):
        branch = _circle_setup(phi0, dphi0, mu, R, g, sgn)
        kind, phi = branch.end()
        if kind != TURNING_POINT:
            raise NoTurningPoint(kind, _out(dps, phi))
        return _out(dps, phi)


def _resolve_end(branch, phi1, dps):
    """(phi1, y1) for a branch integral: phi1 None -> the turning point (y1 = 0
    exactly); a phi1 within 10^-dps of the branch's turning point is snapped to
    it; a phi1 beyond the branch end is an error."""
    kind, phi_e = branch.end()
    s = branch.s
    if phi1 is None:
        if kind != TURNING_POINT:
            raise NoTurningPoint(kind, _out(dps, phi_e))
        return phi_e, mpmath.mpf(0)
    phi1 = _num(phi1, "phi1")
    tol = mpmath.mpf(10) ** (-dps) * max(1, abs(phi_e))
    if kind == TURNING_POINT and abs(phi1 - phi_e) <= tol:
        return phi_e, mpmath.mpf(0)
    if s * (phi1 - branch.phi0) < 0:
        raise ValueError("phi1 lies behind phi0 (against the direction of motion)")
    if s * (phi1 - phi_e) > tol:
        raise ValueError(f"phi1 lies beyond the end of the branch ({kind} at {mpmath.nstr(phi_e, 15)})")
    return phi1, max(branch.y(phi1), mpmath.mpf(0))


def circle_branch_time(phi0, phi1, dphi0, mu, R, g, *, sgn=None, dps: int = 40):
    """Time to slide from phi0 to phi1 on the branch through (phi0, dphi0).

    t = integral_{phi0}^{phi1} |dphi| / sqrt(y(phi)) with the closed-form
    y = phi'^2 of :func:`circle_branch_rate2`. ``phi1=None`` means the branch's
    turning point. At a turning point (and at a start from rest, dphi0 = 0)
    y vanishes linearly, y ~ |y'| |phi - phi_e|, an integrable 1/sqrt
    singularity. The interval is cut at its middle and each half is
    substituted phi = phi_end +- v^2 from its own end (dphi = 2 v dv):

        t = integral_0^{sqrt(L/2)} 2 v dv / sqrt(y(phi0 + s v^2))
          + integral_0^{sqrt(L/2)} 2 v dv / sqrt(y(phi1 - s v^2)),   L = |phi1 - phi0|,

    whose integrands tend to 2 / sqrt(|y'|) at v = 0 (smooth), with y
    evaluated anchored at that end (see ``_CircleBranch``: accurate relative
    to itself as v -> 0), by mpmath.quad (tanh-sinh).
    """
    dps = _check_dps(dps)
    with mpmath.workdps(dps + GUARD_DPS):
        branch = _circle_setup(phi0, dphi0, mu, R, g, sgn)
        phi1, y1 = _resolve_end(branch, phi1, dps)
        return _out(dps, _branch_time(branch, phi1, y1))


def _branch_time(branch, phi1, y1):
    s = branch.s
    L = abs(phi1 - branch.phi0)
    if L == 0:
        return mpmath.mpf(0)
    h = mpmath.sqrt(L / 2)

    def first(v):
        return 2 * v / mpmath.sqrt(branch.anchored(branch.phi0, branch.y0, s * v * v))

    def second(v):
        return 2 * v / mpmath.sqrt(branch.anchored(phi1, y1, -s * v * v))

    return mpmath.quad(first, [0, h]) + mpmath.quad(second, [0, h])


def circle_energy(phi, dphi, R, g, *, m=1, dps: int = 40):
    """E = 1/2 m R^2 phi'^2 + m g R (1 - cos phi) (zero at rest at the bottom)."""
    dps = _check_dps(dps)
    with mpmath.workdps(dps + GUARD_DPS):
        phi, dphi = _num(phi, "phi"), _num(dphi, "dphi")
        R, g, m = _positive(R, "R"), _positive(g, "g"), _positive(m, "m")
        return _out(dps, m * R**2 * dphi**2 / 2 + m * g * R * (1 - mpmath.cos(phi)))


def circle_friction_work(phi0, phi1, dphi0, mu, R, g, *, sgn=None, m=1, dps: int = 40):
    """Work of kinetic friction from phi0 to phi1 on the branch through (phi0, dphi0).

    W = -mu integral N ds, ds = R |dphi|, N = m (R y + g cos phi):

        W = -mu m R s integral_{phi0}^{phi1} (R y(phi) + g cos phi) dphi

    by mpmath.quad on the closed-form y (smooth: no singularity). The energy
    theorem dE/dt = m R phi' (R phi'' + g sin phi) = -mu N R |phi'| gives
    E(phi1) - E(phi0) = W (checked in the tests). ``phi1=None``: the turning point.
    """
    dps = _check_dps(dps)
    with mpmath.workdps(dps + GUARD_DPS):
        branch = _circle_setup(phi0, dphi0, mu, R, g, sgn)
        phi1, _y1 = _resolve_end(branch, phi1, dps)
        m = _positive(m, "m")
        return _out(dps, _friction_work(branch, phi1, m))


def _friction_work(branch, phi1, m):
    if phi1 == branch.phi0 or branch.mu == 0:
        return mpmath.mpf(0)
    integral = mpmath.quad(branch.n, [branch.phi0, phi1])
    return -branch.mu * m * branch.R * branch.s * integral


@dataclass(frozen=True)
class CircleBranch:
    """One sliding branch of :func:`circle_sliding_sequence`: it starts at
    ``t_start`` at ``(phi_start, dphi_start)`` moving with sign ``sgn``, ends
    (``end_kind`` as :class:`CircleBranchEnd`) at ``(phi_end, dphi_end)`` after
    ``duration``; energies (:func:`circle_energy`) at both ends and the
    friction work along it (:func:`circle_friction_work`)."""

    t_start: object
    phi_start: object
    dphi_start: object
    sgn: int
    end_kind: str
    phi_end: object
    dphi_end: object
    duration: object
    energy_start: object
    energy_end: object
    friction_work: object


@dataclass(frozen=True)
class CircleTransition:
    """A change of mode at a turning point: time ``t``, angle ``phi``."""

    t: object
    phi: object
    mode_from: str
    mode_to: str


@dataclass(frozen=True)
class CircleRun:
    """Result of :func:`circle_sliding_sequence`. ``status``: ``"stuck"`` (the
    particle rests for ever at ``phi``), ``"max_branches"``, ``"leaves_track"`` or
    ``"over_the_top"`` (the last branch ends there, no transition recorded).
    ``t``, ``phi``, ``dphi``, ``mode``: the state where the sequence stops."""

    mode0: str
    transitions: tuple
    branches: tuple
    status: str
    t: object
    phi: object
    dphi: object
    mode: str


def circle_sliding_sequence(phi0, dphi0, mu, mu_s, R, g, max_branches=50, *, m=1, dps: int = 40) -> CircleRun:
    """Successive sliding branches of a particle inside a rough circle until it sticks.

    Each branch is closed form (:func:`circle_branch_rate2`), ends at its
    turning point (:func:`circle_turning_point`) after
    :func:`circle_branch_time`. At rest at phi_t the track must supply the
    tangential load m g sin(phi_t) with N = m g cos(phi_t) (phi' = 0): the
    particle sticks iff |tan phi_t| <= mu_s (the sticking band
    |phi| <= atan(mu_s) about the bottom), else it restarts from rest towards
    the bottom, sign -sign(sin phi_t). A start with dphi0 = 0 is decided by
    the same rule (at rest on the upper half, N < 0: ValueError).

    Turning points reached while moving towards the bottom lie in
    |tan phi| < mu (there friction exceeds the weight's component) and always
    stick. Each branch records E at both ends and the friction work W,
    E_end - E_start = W.
    """
    dps = _check_dps(dps)
    if not isinstance(max_branches, int) or max_branches < 1:
        raise ValueError("max_branches must be an int >= 1")
    with mpmath.workdps(dps + GUARD_DPS):
        phi = _num(phi0, "phi0")
        dphi = _num(dphi0, "dphi0")
        mu, mu_s = _friction(mu, mu_s)
        R, g, m = _positive(R, "R"), _positive(g, "g"), _positive(m, "m")

        def energy(p, dp):
            return m * R**2 * dp**2 / 2 + m * g * R * (1 - mpmath.cos(p))

        def sticks(p):
            return abs(mpmath.sin(p)) <= mu_s * mpmath.cos(p)

        t = mpmath.mpf(0)
        transitions, branches = [], []
        if dphi == 0:
            if mpmath.cos(phi) < 0:
                raise ValueError("at rest on the upper half of the circle: N < 0")
            if sticks(phi):
                return CircleRun(STUCK, (), (), STUCK, _out(dps, t), _out(dps, phi), _out(dps, dphi), STUCK)
            sgn = -_sign(mpmath.sin(phi))
        else:
            sgn = _sign(dphi)
        mode0 = mode = _sliding(sgn)
        status = "max_branches"
        for _ in range(max_branches):
            branch = _CircleBranch(phi, dphi**2, sgn, mu, R, g)
            if branch.n(phi) < 0:
                raise ValueError("N < 0 at the start: the particle is not on the track")
            kind, phi_e = branch.end()
            y_e = mpmath.mpf(0) if kind == TURNING_POINT else max(branch.y(phi_e), mpmath.mpf(0))
            duration = _branch_time(branch, phi_e, y_e)
            work = _friction_work(branch, phi_e, m)
            dphi_e = sgn * mpmath.sqrt(y_e)
            branches.append(CircleBranch(
                t_start=_out(dps, t), phi_start=_out(dps, phi), dphi_start=_out(dps, dphi), sgn=sgn,
                end_kind=kind, phi_end=_out(dps, phi_e), dphi_end=_out(dps, dphi_e),
                duration=_out(dps, duration), energy_start=_out(dps, energy(phi, dphi)),
                energy_end=_out(dps, energy(phi_e, dphi_e)), friction_work=_out(dps, work)))
            t = t + duration
            phi, dphi = phi_e, dphi_e
            if kind != TURNING_POINT:
                status = kind
                break
            new = STUCK if sticks(phi) else _sliding(-_sign(mpmath.sin(phi)))
            transitions.append(CircleTransition(_out(dps, t), _out(dps, phi), mode, new))
            mode = new
            if mode == STUCK:
                status = STUCK
                break
            sgn = -_sign(mpmath.sin(phi))
        return CircleRun(mode0, tuple(transitions), tuple(branches), status,
                         _out(dps, t), _out(dps, phi), _out(dps, dphi), mode)


# =====================================================================
# 3. Rolling body that slips on a straight incline
# =====================================================================


@dataclass(frozen=True)
class RollFromRest:
    """Result of :func:`incline_roll_from_rest` (per unit mass, signed along +x).

    ``mode``: ``"rolling"`` or the slipping mode; ``friction_needed`` = F/m a
    rolling body needs, (1 - 1/kappa) g sin(alpha) (signed, +x);
    ``friction_available`` = mu_s g cos(alpha); ``dv``, ``du``, ``dw``: the
    accelerations of v, u and the slip w = v - u in that mode."""

    mode: str
    friction_needed: object
    friction_available: object
    dv: object
    du: object
    dw: object


@dataclass(frozen=True)
class SlipToRoll:
    """Result of :func:`incline_slip_then_roll` (velocities along +x of the
    slope, i.e. uphill for alpha > 0).

    ``mode`` the slipping mode before t_star; ``t_star`` the time slip ends
    (mpmath.inf if the slip never ends; then every field after ``mode_after``
    is None); ``v_star`` = u at t_star; ``displacement`` the signed centre
    displacement along the slope, ``path_length`` the distance travelled
    (they differ if v changes sign while slipping); ``mode_after``
    ``"rolling"`` or the opposite slipping mode; ``dv``, ``du``, ``dw`` the
    accelerations while slipping; energies for mass ``m``: ``friction_loss``
    = mu N integral |w| dt >= 0, ``kinetic_change``, ``potential_change``
    (kinetic_change + potential_change = -friction_loss)."""

    mode: str
    dv: object
    du: object
    dw: object
    t_star: object
    mode_after: str
    v_star: object
    displacement: object
    path_length: object
    friction_loss: object
    kinetic_change: object
    potential_change: object


def _kappa(kappa):
    kappa = _num(kappa, "kappa")
    if not kappa > 1:
        raise ValueError("kappa must be > 1 (a body with a moment of inertia about its centre)")
    return kappa


def _slip_rates(sgn, a, mu, kappa, g):
    """(v', u', w') while slipping with slip sign sgn (see incline_slip_then_roll)."""
    sa, ca = mpmath.sin(a), mpmath.cos(a)
    dv = -g * sa - sgn * mu * g * ca
    du = sgn * mu * g * ca / (kappa - 1)
    return dv, du, dv - du


def incline_roll_from_rest(alpha, mu, mu_s, kappa, g, *, dps: int = 40) -> RollFromRest:
    """Does a body released at rest on the rough incline y = tan(alpha) x roll?

    Velocities along the slope, positive towards +x (uphill for alpha > 0):
    centre speed v, rolling-equivalent speed u = r omega (omega positive in
    the sense of rolling towards +x), slip w = v - u (the contact point's
    velocity). With friction F on the body at the contact (along +x),
    m v' = -m g sin a + F and, about the centre, I_C omega' = -F r, i.e.
    u' = -F / (m (kappa - 1)) (I_C = m (kappa - 1) r^2). Rolling (v' = u')
    needs F = (1 - 1/kappa) m g sin(alpha), and then v' = -g sin(alpha) / kappa.
    Static friction supplies at most mu_s N = mu_s m g cos(alpha), so the body
    rolls iff (1 - 1/kappa) |tan alpha| <= mu_s. Otherwise it slips from t = 0
    with slip sign -sign(alpha) and F = -sgn mu N:

        v' = -g sin a + sign(a) mu g cos a,   u' = -sign(a) mu g cos a / (kappa - 1),
        w' = -sign(a) g (|sin a| - mu cos a kappa / (kappa - 1)),

    i.e. the centre accelerates downhill at g (|sin a| - mu cos a) and the
    spin at mu g cos a / (kappa - 1). |tan a| > mu_s kappa/(kappa - 1) >=
    mu kappa/(kappa - 1) makes w' have the slip's sign: w = w' t grows for
    ever and the body never re-rolls on a constant slope. The radius r does
    not enter (u = r omega).
    """
    dps = _check_dps(dps)
    with mpmath.workdps(dps + GUARD_DPS):
        a = _incline_angle(alpha)
        mu, mu_s = _friction(mu, mu_s)
        kappa = _kappa(kappa)
        g = _positive(g, "g")
        sa, ca = mpmath.sin(a), mpmath.cos(a)
        needed = (1 - 1 / kappa) * g * sa
        available = mu_s * g * ca
        if abs(needed) <= available:
            acc = -g * sa / kappa
            out = (ROLLING, needed, available, acc, acc, mpmath.mpf(0))
        else:
            sgn = -_sign(sa)
            dv, du, dw = _slip_rates(sgn, a, mu, kappa, g)
            out = (_sliding(sgn), needed, available, dv, du, dw)
        return RollFromRest(out[0], *(_out(dps, v) for v in out[1:]))


def incline_slip_then_roll(alpha, mu, mu_s, kappa, v0, u0, g, *, m=1, dps: int = 40) -> SlipToRoll:
    """A body launched slipping on the rough incline y = tan(alpha) x.

    Velocities along the slope, positive towards +x (uphill for alpha > 0):
    centre speed v0, rolling-equivalent speed u0 = r omega0, u0 != v0. With
    slip w = v - u of sign s the friction is F = -s mu N, N = m g cos a, so
    (see :func:`incline_roll_from_rest` for m v' = -m g sin a + F and
    u' = -F / (m (kappa - 1)))

        v' = -g sin a - s mu g cos a,     u' = s mu g cos a / (kappa - 1),
        w' = -g sin a - s mu g cos a kappa / (kappa - 1),

    all constant. The slip decreases iff s w' < 0, i.e. always for
    s sin a >= 0 and, for s sin a < 0, iff |tan a| < mu kappa/(kappa - 1);
    then it vanishes at

        t* = -w0 / w' = |w0| / (mu g cos a kappa/(kappa - 1) + s g sin a),

    with v(t*) = u(t*) = v0 + v' t*, displacement v0 t* + v' t*^2/2. At w = 0
    the body rolls on iff (1 - 1/kappa) |tan a| <= mu_s (the friction rolling
    needs is within mu_s N); otherwise it slips the other way (sign
    -sign(alpha) = -s: w' with that sign has that sign, since
    |tan a| > mu_s kappa/(kappa - 1) >= mu kappa/(kappa - 1)).

    Energy: T = 1/2 m v^2 + 1/2 m (kappa - 1) u^2, V = m g sin(a) s_C, and
    d(T + V)/dt = m v (v' + g sin a) + m (kappa - 1) u u' = -s mu N (v - u)
    = -mu N |w|: the friction loss is mu N integral_0^t* |w| dt =
    mu N |w0| t* / 2 (w linear in t).
    """
    dps = _check_dps(dps)
    with mpmath.workdps(dps + GUARD_DPS):
        a = _incline_angle(alpha)
        mu, mu_s = _friction(mu, mu_s)
        kappa = _kappa(kappa)
        v0, u0 = _num(v0, "v0"), _num(u0, "u0")
        g, m = _positive(g, "g"), _positive(m, "m")
        w0 = v0 - u0
        s = _sign(w0)
        if s == 0:
            raise ValueError("u0 = v0: the body is rolling, not slipping (see incline_roll_from_rest)")
        if mu == 0:
            raise ValueError("mu = 0: the slip never changes")
        dv, du, dw = _slip_rates(s, a, mu, kappa, g)
        mode = _sliding(s)
        if not s * dw < 0:
            return SlipToRoll(mode, _out(dps, dv), _out(dps, du), _out(dps, dw), mpmath.inf, mode,
                              None, None, None, None, None, None)
        t_star = -w0 / dw
        v_star = v0 + dv * t_star
        disp = v0 * t_star + dv * t_star**2 / 2
        # path length: v may change sign once (dv constant)
        t_turn = -v0 / dv if dv != 0 else mpmath.mpf(-1)
        if 0 < t_turn < t_star:
            d1 = v0 * t_turn / 2
            path = abs(d1) + abs(disp - d1)
        else:
            path = abs(disp)
        sa, ca = mpmath.sin(a), mpmath.cos(a)
        rolls = (1 - 1 / kappa) * abs(sa) <= mu_s * ca
        after = ROLLING if rolls else _sliding(-_sign(sa))
        loss = mu * m * g * ca * abs(w0) * t_star / 2
        dT = m * (v_star**2 - v0**2) / 2 + m * (kappa - 1) * (v_star**2 - u0**2) / 2
        dV = m * g * sa * disp
        return SlipToRoll(mode, _out(dps, dv), _out(dps, du), _out(dps, dw), _out(dps, t_star), after,
                          _out(dps, v_star), _out(dps, disp), _out(dps, path), _out(dps, loss),
                          _out(dps, dT), _out(dps, dV))


# =====================================================================
# 4. General reference integrator: particle on top of y = f(x)
# =====================================================================


@dataclass(frozen=True)
class CurveTransition:
    """A change of mode on the curve at time ``t`` and abscissa ``x``."""

    t: object
    x: object
    mode_from: str
    mode_to: str


@dataclass(frozen=True)
class CurveRun:
    """Result of :func:`sliding_on_curve`: ``mode0`` just after t = 0, the
    ``transitions``, and the state where the run stops: ``t``, ``x``, ``dx``,
    ``mode``. ``status``: ``"t_end"`` (sliding at t_end), ``"stuck"`` (at rest
    for ever; t = t_end), ``"leaves_track"`` (N = 0 at t) or
    ``"max_transitions"``."""

    mode0: str
    transitions: tuple
    status: str
    t: object
    x: object
    dx: object
    mode: str


def sliding_on_curve(f, x0, dx0, mu, mu_s, g, t_end, dps: int = 30, *, df=None, d2f=None,
                     sample="0.01", max_transitions: int = 50) -> CurveRun:
    """A particle sliding on top of the rough curve y = f(x), integrated with mpmath.odefun.

    Position (x, f(x)); sigma = sqrt(1 + f'^2); unit tangent T = (1, f')/sigma,
    upward normal n = (-f', 1)/sigma. Acceleration (x'', f' x'' + f'' x'^2):
    a.n = f'' x'^2 / sigma and a.T = (sigma^2 x'' + f' f'' x'^2)/sigma. Newton
    with gravity -g e_y, normal force N n and friction -sgn mu N T
    (sgn = sign(x')):

        normal:      f'' x'^2 / sigma = -g / sigma + N/m   =>  N/m = (f'' x'^2 + g) / sigma,
        tangential:  sigma^2 x'' + f' f'' x'^2 = -g f' - sgn mu (N/m) sigma.

    One-sided contact: the run stops (status ``"leaves_track"``) where N
    reaches 0. Each branch (fixed sgn, so the right-hand side is analytic) is
    integrated by mpmath.odefun (Taylor series) from its start; the solution
    is sampled every ``sample`` seconds, a sign change of x' (or of N)
    between samples is solved by mpmath.findroot on the interpolant, and a
    local minimum of sgn x' between samples is checked (findroot on x'') so a
    brief stop between two samples is not missed. At a turning point x_t the
    static load is the weight's tangential component -g f'/sigma against at
    most mu_s N/m = mu_s g / sigma: the particle sticks for ever iff
    |f'(x_t)| <= mu_s, else restarts from rest downhill, sgn = -sign(f'(x_t)).
    A start with dx0 = 0 is decided the same way.

    ``f`` maps an mpf to an mpf; ``df`` and ``d2f`` (f', f'') default to
    mpmath.diff of f, which is slow (odefun evaluates the right-hand side at
    many times the working precision): pass them when you can. Works at
    ``dps`` + 5 digits; results rounded to ``dps``. Intended for a handful of
    turning points.
    """
    dps = _check_dps(dps)
    if not isinstance(max_transitions, int) or max_transitions < 1:
        raise ValueError("max_transitions must be an int >= 1")
    with mpmath.workdps(dps + 5):
        x = _num(x0, "x0")
        v = _num(dx0, "dx0")
        mu, mu_s = _friction(mu, mu_s)
        g = _positive(g, "g")
        t_end = _num(t_end, "t_end")
        h = _positive(sample, "sample")
        if t_end < 0:
            raise ValueError("t_end must be >= 0")
        fp = df if df is not None else (lambda q: mpmath.diff(f, q))
        fpp = d2f if d2f is not None else (lambda q: mpmath.diff(f, q, 2))

        def normal(q, dq):
            d1, d2 = fp(q), fpp(q)
            return (d2 * dq**2 + g) / mpmath.sqrt(1 + d1**2)

        def accel(q, dq, sgn):
            d1, d2 = fp(q), fpp(q)
            # sigma^2 x'' = -g f' - f' f'' x'^2 - sgn mu (N/m) sigma,  (N/m) sigma = f'' x'^2 + g
            return (-g * d1 - d1 * d2 * dq**2 - sgn * mu * (d2 * dq**2 + g)) / (1 + d1**2)

        def static(q):
            return STUCK if abs(fp(q)) <= mu_s else _sliding(-_sign(fp(q)))

        if normal(x, v) < 0:
            raise ValueError("N < 0 at the start: the particle is not on the track")
        t = mpmath.mpf(0)
        mode = _sliding(_sign(v)) if v != 0 else static(x)
        mode0 = mode
        transitions = []

        def result(status, t, x, v, mode):
            return CurveRun(mode0, tuple(transitions), status, _out(dps, t), _out(dps, x), _out(dps, v), mode)

        while True:
            if mode == STUCK:
                return result(STUCK, t_end, x, mpmath.mpf(0), STUCK)
            if len(transitions) >= max_transitions:
                return result("max_transitions", t, x, v, mode)
            sgn = 1 if mode == SLIDING_PLUS else -1
            sol = mpmath.odefun(lambda _tau, y, sgn=sgn: [y[1], accel(y[0], y[1], sgn)], 0, [x, v])

            def rate(tau, sol=sol, sgn=sgn):
                return sgn * sol(tau)[1]

            def load(tau, sol=sol):
                y = sol(tau)
                return normal(y[0], y[1])

            def acc(tau, sol=sol, sgn=sgn):
                y = sol(tau)
                return sgn * accel(y[0], y[1], sgn)

            span = t_end - t
            event = None  # (tau, kind)
            tau_prev, r_prev, r_prev2 = mpmath.mpf(0), sgn * v, None
            tau_prev2 = None
            k = 0
            while event is None:
                k += 1
                tau = min(k * h, span)
                y = sol(tau)
                r = sgn * y[1]
                n_now = normal(y[0], y[1])
                cands = []
                if r <= 0:
                    lo = tau_prev
                    if not r_prev > 0:
                        # a start from rest (r = 0 at tau = 0) that stops again before the
                        # first sample: bracket from the maximum of sgn x' in between
                        if not (acc(tau_prev) > 0 > acc(tau)):
                            raise ValueError("a stop within the first sample: use a smaller sample")
                        lo = _bracketed_root(acc, tau_prev, tau)
                    cands.append((_bracketed_root(rate, lo, tau), TURNING_POINT))
                elif (r_prev2 is not None and r_prev < r_prev2 and r_prev < r):
                    # a local minimum of sgn x' between tau_prev2 and tau: does it dip below 0?
                    try:
                        if acc(tau_prev2) < 0 < acc(tau):
                            t_min = _bracketed_root(acc, tau_prev2, tau)
                            if rate(t_min) <= 0:
                                cands.append((_bracketed_root(rate, tau_prev2, t_min), TURNING_POINT))
                    except ValueError:
                        pass
                if n_now < 0:
                    cands.append((_bracketed_root(load, tau_prev, tau), LEAVES_TRACK))
                if cands:
                    cands.sort(key=lambda item: item[0])
                    event = cands[0]
                    break
                if tau >= span:
                    break
                tau_prev2, r_prev2 = tau_prev, r_prev
                tau_prev, r_prev = tau, r
            if event is None:
                y = sol(span)
                return result("t_end", t_end, y[0], y[1], mode)
            tau_e, kind = event
            y = sol(tau_e)
            t = t + tau_e
            x = y[0]
            if kind == LEAVES_TRACK:
                return result(LEAVES_TRACK, t, x, y[1], mode)
            v = mpmath.mpf(0)
            new = static(x)
            transitions.append(CurveTransition(_out(dps, t), _out(dps, x), mode, new))
            mode = new
