"""Independent mpmath solution of the equilibrium condition on a path track.

Shares no code with :mod:`heyroll.analysis.equilibria`: f' comes from
mpmath's numerical differentiation of f (not from the symbolic derivative),
the arc chain's geometry from the exact (mpmath) pieces, and roots from
mpmath's solvers at 40 digits. The condition is the derivative of the
effective potential V/m = g y_C - 1/2 Omega^2 (x_C - a)^2 along the track,
taken numerically here as well.
"""

from __future__ import annotations

import mpmath

from ..model import expression as ex
from ..model.path_scene import piece_index
from ..model.paths import MPMATH, ArcChainTrack, CurveTrack

DIGITS = 40


def _potential(track, body, omega, axis_x, g):
    r = mpmath.mpf(body.radius)
    om2, a = mpmath.mpf(omega) ** 2, mpmath.mpf(axis_x)
    if isinstance(track, CurveTrack):
        def f(x):
            return ex.evaluate(track.f, x, MPMATH)

        def V(x):
            d1 = mpmath.diff(f, x)
            w = mpmath.sqrt(1 + d1 * d1)
            x_c, y_c = x - r * d1 / w, f(x) + r / w
            return g * y_c - om2 * (x_c - a) ** 2 / 2
        return V
    pieces = track.pieces(body, exact=True)
    floats = track.pieces(body)

    def V(s):
        p = pieces[int(piece_index(floats, float(s)))]
        alpha = p.alpha0 + p.c * (s - p.s0)
        x_c = p.A + p.B * mpmath.sin(alpha) + p.D * (s - p.s0)
        y_c = p.E - p.B * mpmath.cos(alpha) + p.G * (s - p.s0)
        return g * y_c - om2 * (x_c - a) ** 2 / 2
    return V


def equilibrium_roots(track: CurveTrack | ArcChainTrack, body, omega, axis_x=0, g="9.81", guesses=(),
                      scan: int = 0, domain=None) -> list[mpmath.mpf]:
    """Roots of dV/dq near each guess (secant at 40 digits), plus, with ``scan`` > 0,
    roots bracketed by an independent scan of that many points over ``domain``."""
    with mpmath.workdps(DIGITS):
        V = _potential(track, body, omega, axis_x, mpmath.mpf(g))

        def dV(q):
            return mpmath.diff(V, q)

        roots = [mpmath.findroot(dV, mpmath.mpf(q0)) for q0 in guesses]
        if scan:
            lo, hi = (mpmath.mpf(v) for v in domain)
            qs = [lo + (hi - lo) * k / (scan - 1) for k in range(scan)]
            vals = [dV(q) for q in qs]
            for q1, q2, v1, v2 in zip(qs, qs[1:], vals, vals[1:]):
                if v1 * v2 < 0:
                    roots.append(mpmath.findroot(dV, (q1, q2), solver="anderson"))
        return roots
