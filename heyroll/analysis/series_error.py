"""How good are the paper's truncated series (54)-(55), and its first-collision method (56)=(57)?

The time a body takes along a monotone arc of its circle is (paper eqs. 48-50)

    t = (2 / omega_0) [I(u) - I(u_0)],   I(u) = integral_0^u du / sqrt((1 - u^2)(1 - k^2 u^2)),

u = sin(phi/2), omega_0^2 = phi_0'^2 + 2 omega^2 sin^2(phi_0/2), k^2 = 2 omega^2 / omega_0^2
(eqs. 45-46; omega^2 = 2 g / (kappa (R - r))). I is Legendre's F(asin u | k^2).
The paper expands both factors of the integrand in binomial series (51)-(52)
and keeps a 3 x 3 block of the product (54). Four approximations of I are
compared with the exact F here (``kind``):

* ``"printed"``   — (54) as printed (with the misprinted 1*3/(2*4*6) k^4 u^5 term, ERRATA B6);
* ``"corrected"`` — the same 3 x 3 block with every coefficient c_m c_n / (2(m+n)+1);
* ``N`` (an int)  — the product truncated consistently at total degree 2N of the
  integrand (:func:`heyroll.reference.series.series_time_integral`);
* ``"exact"``     — Legendre's F itself (a check of the root finding below).

Where the series converge, and how fast
---------------------------------------
The integrand's two series converge for k^2 u^2 < 1 and u^2 < 1; the
truncated product converges geometrically with ratio

    rho = max(u^2, k^2 u^2)       (the error of order N behaves like rho^N / N^(3/2)),

which :data:`SeriesErrorMap.ratio` reports. The two regimes differ:

* **libration** (k^2 > 1, the body swings back): along the swing
  k^2 u^2 = sin^2(phi/2) / sin^2(phi_max/2) runs from 0 at the bottom to
  exactly 1 at the turning point, *whatever the amplitude*. At the turning
  point the series in k^2 u^2 converges only algebraically (error ~ N^(-1/2)):
  the time to the turning point (a quarter period) is poorly approximated by
  any order, even for a 10 degree swing, and a body that *starts* from rest
  (as in the built-in default scene) starts exactly there. Beyond the turning
  point (k^2 u^2 > 1) there is no motion and the series diverges. (The
  classical cure is Legendre's reciprocal-modulus substitution
  sin psi = k sin(phi/2), which gives a series in 1/k^2 with ratio
  sin^2(phi_max/2); the paper does not use it.)
* **rotation** (k^2 < 1, the body goes over the top): rho = u^2 = sin^2(phi/2),
  geometric for |phi| < pi, algebraic at the top phi = pi (u = 1), and
  u = sin(phi/2) is no longer monotone beyond it: (50) then needs one arc per
  half turn, which the paper does not write.

Both regimes thus share one rule: the series is fine in the middle of an arc
and fails at its ends (turning points, the top). The paper's (56)=(57) uses
the series from each body's initial state to the collision, so its accuracy
depends on where the bodies start and collide (:func:`paper_method_first_collision`).

All arithmetic is mpmath at ``dps`` digits inside local ``workdps`` contexts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from fractions import Fraction

import mpmath
import numpy as np

from ..reference.series import CORRECTED_TERMS, PRINTED_TERMS, binomial_coefficient

__all__ = [
    "LIBRATION",
    "ROTATION",
    "TABLE_AMPLITUDES_DEG",
    "TABLE_FRACTIONS",
    "TABLE_KINDS",
    "PaperMethodResult",
    "SeriesErrorMap",
    "SeriesErrorTable",
    "convergence_ratio",
    "exact_integral",
    "kind_label",
    "paper_method_first_collision",
    "series_coefficients",
    "series_error_map",
    "series_error_maps",
    "series_error_table",
    "series_integral",
]

LIBRATION = "libration"
ROTATION = "rotation"

#: The brief's table: amplitudes (degrees), series kinds and positions along the swing.
TABLE_AMPLITUDES_DEG = (10, 30, 60, 90, 120, 150, 170)
TABLE_KINDS = ("printed", "corrected", 2, 4, 8, 16)
#: phi / phi_max: half way (in angle) to the turning point, near it, and at it (quarter period).
TABLE_FRACTIONS = (0.5, 0.9, 1.0)


# ----------------------------------------------------------------------------- the series


def _check_kind(kind):
    if kind in ("printed", "corrected", "exact"):
        return kind
    if isinstance(kind, (int, np.integer)) and not isinstance(kind, bool) and kind >= 0:
        return int(kind)
    raise ValueError(f"kind must be 'printed', 'corrected', 'exact' or an order N >= 0, got {kind!r}")


def kind_label(kind) -> str:
    """A short label for plots and tables."""
    kind = _check_kind(kind)
    return {
        "printed": "(54) as printed",
        "corrected": "(54) corrected",
        "exact": "exact F",
    }.get(kind, f"order {kind}") if isinstance(kind, str) else f"order {kind}"


def _mp(q: Fraction):
    return mpmath.mpf(q.numerator) / q.denominator


def series_coefficients(kind, k2) -> list:
    """Coefficients a_d of I(u) = u * sum_d a_d (u^2)^d for a series ``kind`` at modulus ``k2``.

    a_d collects every kept term c_m c_n k^(2m) / (2(m+n)+1) with m + n = d.
    Evaluated at the ambient mpmath precision.
    """
    kind = _check_kind(kind)
    if kind == "exact":
        raise ValueError("'exact' has no series coefficients")
    k2 = mpmath.mpf(k2)
    if isinstance(kind, int):
        c = [_mp(binomial_coefficient(n)) for n in range(kind + 1)]
        powers = [k2**m for m in range(kind + 1)]
        return [sum(c[m] * c[d - m] * powers[m] for m in range(d + 1)) / (2 * d + 1) for d in range(kind + 1)]
    terms = PRINTED_TERMS if kind == "printed" else CORRECTED_TERMS
    degree = max(p for _, _, p in terms) // 2
    a = [mpmath.mpf(0)] * (degree + 1)
    for coef, k_power, u_power in terms:
        a[u_power // 2] += _mp(coef) * k2**k_power
    return a


def _horner(a, u):
    u2 = u * u
    total = mpmath.mpf(0)
    for coef in reversed(a):
        total = total * u2 + coef
    return u * total


def exact_integral(u, k2):
    """I(u) = F(asin u | k^2), Legendre's integral (50), robust at the ends of an arc.

    Libration (k^2 > 1) uses the reciprocal-modulus form
    F(asin u | k^2) = F(asin(k u) | 1/k^2) / k, real up to and including the
    turning point k u = +-1 (a k u a rounding error beyond it is clamped).
    Rotation (k^2 <= 1): F(asin u | k^2) directly, |u| <= 1 (clamped).
    """
    u, k2 = mpmath.mpf(u), mpmath.mpf(k2)
    if k2 > 1:
        k = mpmath.sqrt(k2)
        x = max(-1, min(1, k * u))
        return mpmath.ellipf(mpmath.asin(x), 1 / k2) / k
    u = max(-1, min(1, u))
    return mpmath.ellipf(mpmath.asin(u), k2)


def series_integral(kind, u, k2):
    """I(u) by the series ``kind`` ('printed', 'corrected', order N) or 'exact' (Legendre's F)."""
    kind = _check_kind(kind)
    if kind == "exact":
        return exact_integral(u, k2)
    return _horner(series_coefficients(kind, k2), mpmath.mpf(u))


def convergence_ratio(u, k2):
    """rho = max(u^2, k^2 u^2): the geometric ratio of the series' terms at u (1: algebraic; > 1: diverges)."""
    u2 = mpmath.mpf(u) ** 2
    return max(u2, mpmath.mpf(k2) * u2)


# ----------------------------------------------------------------------------- error maps


@dataclass(frozen=True)
class SeriesErrorMap:
    """Relative error of the time from the lowest point to phi, on a grid.

    ``regime`` 'libration': rows are amplitudes phi_max (rad, ``parameter``),
    k^2 = 1/sin^2(phi_max/2); columns are phi/phi_max (``fractions``, 1 = the
    turning point, a quarter period). 'rotation': rows are k^2 in (0, 1)
    (``parameter``: the energy, C = 4a/k^2); columns are phi/pi (1 = the top).
    ``rel_error[row, col]`` = |I_series(u) - F(asin u | k^2)| / F, u = sin(phi/2)
    (the factor 2/omega_0 cancels). ``ratio`` is max(u^2, k^2 u^2).
    """

    kind: object
    label: str
    regime: str
    parameter: np.ndarray
    fractions: np.ndarray
    k2: np.ndarray
    rel_error: np.ndarray
    ratio: np.ndarray

    @property
    def parameter_name(self) -> str:
        return "amplitude phi_max (rad)" if self.regime == LIBRATION else "k^2 = 4a/C"


def _grid(regime, n_parameter, n_fraction, parameter, fractions):
    if regime not in (LIBRATION, ROTATION):
        raise ValueError(f"regime must be {LIBRATION!r} or {ROTATION!r}, got {regime!r}")
    if parameter is None:
        if regime == LIBRATION:
            parameter = np.radians(np.linspace(2.0, 178.0, n_parameter))
        else:
            parameter = np.linspace(0.02, 0.98, n_parameter)
    if fractions is None:
        fractions = np.linspace(1.0 / n_fraction, 1.0, n_fraction)
    parameter = np.asarray(parameter, dtype=float)
    fractions = np.asarray(fractions, dtype=float)
    if regime == LIBRATION and (np.any(parameter <= 0) or np.any(parameter >= math.pi)):
        raise ValueError("libration amplitudes must lie in (0, pi)")
    if regime == ROTATION and (np.any(parameter < 0) or np.any(parameter >= 1)):
        raise ValueError("rotation needs 0 <= k^2 < 1")
    if np.any(fractions <= 0) or np.any(fractions > 1):
        raise ValueError("fractions must lie in (0, 1]")
    return parameter, fractions


def _row_points(regime, p, fractions):
    """(k^2, list of u) for one row of the grid, in mpmath."""
    if regime == LIBRATION:
        amp = mpmath.mpf(p)
        s = mpmath.sin(amp / 2)
        k2 = 1 / s**2
        # At fraction 1 put u exactly on the turning point (k u = 1), not a rounding away.
        us = [s if f == 1.0 else mpmath.sin(mpmath.mpf(f) * amp / 2) for f in fractions]
        return k2, us
    k2 = mpmath.mpf(p)
    return k2, [mpmath.sin(mpmath.mpf(f) * mpmath.pi / 2) for f in fractions]


def series_error_maps(
    kinds=("printed", "corrected", 8),
    regime: str = LIBRATION,
    *,
    n_parameter: int = 45,
    n_fraction: int = 40,
    parameter=None,
    fractions=None,
    dps: int = 30,
) -> list[SeriesErrorMap]:
    """One :class:`SeriesErrorMap` per kind on a shared grid (the exact F is computed once).

    Default grids: amplitudes 2..178 degrees (libration) or k^2 0.02..0.98
    (rotation), fractions 1/n..1. Relative errors below ~10^-dps are rounding.
    """
    kinds = [_check_kind(k) for k in kinds]
    parameter, fractions = _grid(regime, n_parameter, n_fraction, parameter, fractions)
    shape = (parameter.size, fractions.size)
    errors = {kind: np.empty(shape) for kind in kinds}
    ratio = np.empty(shape)
    k2s = np.empty(parameter.size)
    with mpmath.workdps(dps + 10):
        for row, p in enumerate(parameter):
            k2, us = _row_points(regime, p, fractions)
            k2s[row] = float(k2)
            exact = [exact_integral(u, k2) for u in us]
            ratio[row] = [float(convergence_ratio(u, k2)) for u in us]
            for kind in kinds:
                if kind == "exact":
                    errors[kind][row] = 0.0
                    continue
                a = series_coefficients(kind, k2)
                errors[kind][row] = [float(abs(_horner(a, u) - e) / abs(e)) for u, e in zip(us, exact)]
    return [
        SeriesErrorMap(
            kind=kind, label=kind_label(kind), regime=regime, parameter=parameter, fractions=fractions,
            k2=k2s, rel_error=errors[kind], ratio=ratio,
        )
        for kind in kinds
    ]


def series_error_map(kind, regime: str = LIBRATION, **kwargs) -> SeriesErrorMap:
    """The error map of one series kind (see :func:`series_error_maps` for the options)."""
    return series_error_maps((kind,), regime, **kwargs)[0]


# ----------------------------------------------------------------------------- amplitude table


@dataclass(frozen=True)
class SeriesErrorTable:
    """Relative error of the libration time from the bottom to phi = fraction * phi_max.

    ``rel_error[kind index, amplitude index, fraction index]``; ``ratio`` is
    k^2 u^2 = sin^2(phi/2)/sin^2(phi_max/2) (the convergence ratio, 1 at the
    turning point).
    """

    amplitudes_deg: tuple
    fractions: tuple
    kinds: tuple
    rel_error: np.ndarray
    ratio: np.ndarray

    def error(self, kind, amplitude_deg, fraction=1.0) -> float:
        return float(
            self.rel_error[
                self.kinds.index(_check_kind(kind)),
                self.amplitudes_deg.index(amplitude_deg),
                self.fractions.index(fraction),
            ]
        )

    def to_markdown(self) -> str:
        """One markdown table per fraction: amplitudes as rows, kinds as columns."""
        parts = []
        for f_index, f in enumerate(self.fractions):
            where = "at the turning point (a quarter period)" if f == 1.0 else f"to phi = {f:g} phi_max"
            parts.append(f"Relative error of the time from the lowest point {where}:\n")
            parts.append("| amplitude | k^2 u^2 | " + " | ".join(kind_label(k) for k in self.kinds) + " |")
            parts.append("|---" * (len(self.kinds) + 2) + "|")
            for a_index, amp in enumerate(self.amplitudes_deg):
                cells = [f"{self.rel_error[k, a_index, f_index]:.2e}" for k in range(len(self.kinds))]
                parts.append(f"| {amp:g} deg | {self.ratio[a_index, f_index]:.3f} | " + " | ".join(cells) + " |")
            parts.append("")
        return "\n".join(parts)


def series_error_table(
    amplitudes_deg=TABLE_AMPLITUDES_DEG, kinds=TABLE_KINDS, fractions=TABLE_FRACTIONS, dps: int = 30
) -> SeriesErrorTable:
    """The errors of each series kind at a few amplitudes and positions along the swing (libration)."""
    amplitudes_deg = tuple(amplitudes_deg)
    fractions = tuple(float(f) for f in fractions)
    kinds = tuple(_check_kind(k) for k in kinds)
    maps = series_error_maps(
        kinds, LIBRATION, parameter=np.radians(np.asarray(amplitudes_deg, dtype=float)), fractions=fractions, dps=dps
    )
    return SeriesErrorTable(
        amplitudes_deg=amplitudes_deg,
        fractions=fractions,
        kinds=kinds,
        rel_error=np.stack([m.rel_error for m in maps]),
        ratio=maps[0].ratio,
    )


# ----------------------------------------------------------------------------- the paper's method


@dataclass(frozen=True)
class PaperMethodResult:
    """The first collision by the paper's method (56)=(57) against the exact reference.

    ``status``:

    * ``ok`` — both bodies move monotonically to the exact first collision and
      the series equation has a root; errors are filled in;
    * ``not_monotone`` — a body turns back (or passes the top) before the exact
      first collision: the integrals (48)-(57) cover monotone arcs only, so
      the method does not apply (series fields are NaN);
    * ``no_root`` — the bodies do move monotonically, but the series equation
      has no root on the monotone arcs (the truncation is too poor there);
    * ``no_collision`` — the exact reference finds no collision before t_end;
    * ``unsupported`` — not two bodies, a body beyond the top (|phi_0| >= pi),
      or a first collision across the top (the wrap-around pair 2, 1).

    Times in s, angles in rad (phi of body 1 at the collision; body 2 is at
    phi + beta). ``t_rel_error`` = |t_series - t_exact| / t_exact,
    ``phi_abs_error`` = |phi_series - phi_exact| and ``phi_rel_error`` that
    over |phi_exact|, all computed in mpmath before rounding to float.
    ``k2`` is each body's k^2 (eq. 46) and ``ratio`` the largest
    max(u^2, k^2 u^2) on the arc it travels (1 = algebraic convergence).
    """

    kind: object
    label: str
    status: str
    message: str
    t_series: float = math.nan
    phi_series: float = math.nan
    t_exact: float = math.nan
    phi_exact: float = math.nan
    t_rel_error: float = math.nan
    phi_abs_error: float = math.nan
    phi_rel_error: float = math.nan
    beta: float = math.nan
    k2: tuple = ()
    ratio: tuple = ()
    monotone: bool | None = None

    @property
    def ok(self) -> bool:
        return self.status == "ok"


@dataclass(frozen=True)
class _Arc:
    """A body's monotone arc from its initial state (the paper's (50) for it)."""

    phi0: object
    dphi0: object
    a: object  # g / (kappa (R - r)) = omega^2 / 2
    omega0: object  # sqrt(C)
    k2: object
    direction: int  # +1, -1, or 0 (at rest at the bottom)
    end: object  # the turning point (libration) or +-pi (rotation)
    coefficients: dict = field(default_factory=dict, compare=False)

    def interval(self):
        if self.direction == 0:
            return self.phi0, self.phi0
        return (self.phi0, self.end) if self.direction > 0 else (self.end, self.phi0)

    def integral(self, kind, u):
        if kind == "exact":
            return exact_integral(u, self.k2)
        if kind not in self.coefficients:
            self.coefficients[kind] = series_coefficients(kind, self.k2)
        return _horner(self.coefficients[kind], u)

    def time(self, kind, phi):
        """The paper's (54)/(55): time to reach phi along the arc (s)."""
        u0, u = mpmath.sin(self.phi0 / 2), mpmath.sin(phi / 2)
        return self.direction * 2 / self.omega0 * (self.integral(kind, u) - self.integral(kind, u0))

    def ratio(self, phi):
        return max(
            convergence_ratio(mpmath.sin(self.phi0 / 2), self.k2), convergence_ratio(mpmath.sin(phi / 2), self.k2)
        )


def _arc(g, R, body, phi0, dphi0) -> _Arc:
    a = g / (mpmath.mpf(body.kappa) * (R - mpmath.mpf(body.radius)))
    C = dphi0**2 + 4 * a * mpmath.sin(phi0 / 2) ** 2
    if dphi0 != 0:
        direction = 1 if dphi0 > 0 else -1
    else:
        s = mpmath.sin(phi0)
        direction = 0 if s == 0 else (-1 if s > 0 else 1)
    if C == 0:
        return _Arc(phi0, dphi0, a, mpmath.mpf(0), mpmath.inf, 0, phi0)
    k2 = 4 * a / C
    if k2 > 1:
        end = direction * 2 * mpmath.asin(1 / mpmath.sqrt(k2))
        if direction == 0:
            end = phi0
        elif abs(phi0) > abs(end):  # a start from rest: the turning point is phi0's mirror image
            end = -phi0
    else:
        end = direction * mpmath.pi
    return _Arc(phi0, dphi0, a, mpmath.sqrt(C), k2, direction, end)


def _bisect(f, lo, hi, f_lo, tol):
    for _ in range(400):
        mid = (lo + hi) / 2
        f_mid = f(mid)
        if f_mid == 0:
            return mid
        if (f_mid < 0) == (f_lo < 0):
            lo, f_lo = mid, f_mid
        else:
            hi = mid
        if hi - lo <= tol * (1 + abs(mid)):
            break
    return (lo + hi) / 2


def _solve(kind, arc1, arc2, beta, scan_points, dps):
    """phi_1 at the first collision from T_1(phi_1) = T_2(phi_1 + beta), or None.

    The unknown runs over the part of body 1's monotone arc where body 2
    (at phi_1 + beta) is also on its own arc. Sign changes of
    T_1 - T_2 on a grid are refined by bisection; the root with the
    smallest time is the first collision (every root is a contact, because
    along a monotone arc each angle is reached once).
    """
    lo1, hi1 = arc1.interval()
    lo2, hi2 = arc2.interval()
    lo, hi = max(lo1, lo2 - beta), min(hi1, hi2 - beta)
    if lo > hi:
        return None
    if arc1.direction == 0:
        return (arc1.phi0, arc2.time(kind, arc1.phi0 + beta)) if lo <= arc1.phi0 <= hi else None
    if arc2.direction == 0:
        x = arc2.phi0 - beta
        return (x, arc1.time(kind, x)) if lo <= x <= hi else None

    def f(x):
        return arc1.time(kind, x) - arc2.time(kind, x + beta)

    tol = mpmath.mpf(10) ** (-(dps + 5))
    xs = [lo + (hi - lo) * mpmath.mpf(n) / scan_points for n in range(scan_points + 1)]
    fs = [f(x) for x in xs]
    roots = []
    for n in range(scan_points):
        if fs[n] == 0:
            roots.append(xs[n])
        elif (fs[n] < 0) != (fs[n + 1] < 0) and fs[n + 1] != 0:
            roots.append(_bisect(f, xs[n], xs[n + 1], fs[n], tol))
    if fs[-1] == 0:
        roots.append(xs[-1])
    if not roots:
        return None
    timed = [(arc1.time(kind, x), x) for x in roots]
    t, x = min(timed, key=lambda item: item[0])
    return x, t


def paper_method_first_collision(
    scene, kind="corrected", *, dps: int = 30, t_end=None, scan_points: int = 200
) -> PaperMethodResult:
    """The paper's method end to end: first-collision time and place from (56)=(57) with a truncated series.

    For two bodies (the paper's 4.2.2): body 1 reaches phi_1 at
    T_1(phi_1) = (2/omega_0,1)[I(sin(phi_1/2)) - I(sin(phi_1,0/2))] (eq. 56,
    sign-corrected for a body moving towards smaller phi) and body 2 reaches
    phi_1 + beta at T_2 (eq. 57); the collision is the earliest root of
    T_1 = T_2, with I from the series ``kind`` ('printed', 'corrected',
    order N, or 'exact' to check the method itself). The result is compared
    with the exact first collision of :func:`heyroll.reference.collisions.reference_collisions`.

    The method holds only while both bodies move monotonically from their
    initial states to the collision (the integrals cover one monotone arc,
    |phi| < pi): this is checked on the exact solution (each body's exact
    time to its collision angle on its first monotone arc must equal the
    collision time) and reported as ``not_monotone`` rather than solved.
    A body starting from rest (phi_0' = 0, as in the default scene) starts
    at a turning point, where k^2 u_0^2 = 1 and the series converge only
    algebraically: expect slow convergence with the order there.
    """
    from ..reference.collisions import reference_collisions
    from ..reference.pendulum import ExactPendulum

    kind = _check_kind(kind)
    label = kind_label(kind)

    def fail(status, message, **extra):
        return PaperMethodResult(kind=kind, label=label, status=status, message=message, **extra)

    if len(scene.bodies) != 2:
        return fail("unsupported", f"the paper's method (56)=(57) is for two bodies, the scene has {len(scene.bodies)}")
    with mpmath.workdps(dps + 10):
        g, R = mpmath.mpf(scene.g), mpmath.mpf(scene.track.radius)
        phi0 = [mpmath.mpf(p) for p in scene.phi]
        dphi0 = [mpmath.mpf(v) for v in scene.dphi]
        if any(abs(p) >= mpmath.pi for p in phi0):
            return fail("unsupported", "a body starts at or beyond the top (|phi_0| >= pi): u = sin(phi/2) is not monotone there")
        r1, r2 = (mpmath.mpf(b.radius) for b in scene.bodies)
        rho1, rho2 = R - r1, R - r2
        beta = mpmath.acos((rho1**2 + rho2**2 - (r1 + r2) ** 2) / (2 * rho1 * rho2))  # eq. (44)
        arcs = [_arc(g, R, b, p, v) for b, p, v in zip(scene.bodies, phi0, dphi0)]
        k2 = tuple(float(arc.k2) for arc in arcs)

        ref = reference_collisions(scene, 1, dps=dps, t_end=t_end)
        common = dict(beta=float(beta), k2=k2)
        if not ref:
            return fail("no_collision", "the exact reference has no collision before t_end", **common)
        first = ref[0]
        t_exact, phi_exact = mpmath.mpf(first.t), mpmath.mpf(first.q_i)
        common.update(t_exact=float(t_exact), phi_exact=float(phi_exact))
        if (first.i, first.j) != (1, 2):
            return fail(
                "unsupported",
                "the first exact collision is across the top (bodies 2 and 1): (56)=(57) assume phi_2 = phi_1 + beta",
                **common,
            )
        # Monotone arcs up to the exact collision?
        problems = []
        for n, (arc, phi_c) in enumerate(zip(arcs, (first.q_i, first.q_j)), start=1):
            if arc.direction == 0:
                if abs(mpmath.mpf(phi_c) - arc.phi0) > mpmath.mpf(10) ** (-dps // 2):
                    problems.append(f"body {n} rests at phi = {mpmath.nstr(arc.phi0, 6)} but is hit elsewhere")
                continue
            pend = ExactPendulum(arc.a, arc.phi0, arc.dphi0, 0, dps)
            t_arc = pend.time_to_angle(phi_c)
            lo, hi = arc.interval()
            on_arc = lo - mpmath.mpf(10) ** (-dps // 2) <= phi_c <= hi + mpmath.mpf(10) ** (-dps // 2)
            if t_arc is None or not on_arc or abs(t_arc - t_exact) > mpmath.mpf(10) ** (-dps // 2) * (1 + t_exact):
                problems.append(
                    f"body {n} does not reach phi = {mpmath.nstr(phi_c, 8)} on its first monotone arc "
                    f"(it turns back or passes the top before the collision at t = {mpmath.nstr(t_exact, 8)} s)"
                )
        if problems:
            return fail(
                "not_monotone",
                "; ".join(problems) + ": the paper's integrals (48)-(57) cover monotone arcs only",
                monotone=False,
                **common,
            )
        common["ratio"] = tuple(
            float(arc.ratio(mpmath.mpf(p))) for arc, p in zip(arcs, (first.q_i, first.q_j))
        )
        solved = _solve(kind, arcs[0], arcs[1], beta, scan_points, dps)
        if solved is None:
            return fail(
                "no_root",
                f"the {label} series gives no root of T_1(phi) = T_2(phi + beta) on the monotone arcs "
                "(the exact collision is on them)",
                monotone=True,
                **common,
            )
        x, t = solved
        t_rel = abs(t - t_exact) / abs(t_exact)
        phi_abs = abs(x - phi_exact)
        phi_rel = phi_abs / abs(phi_exact) if phi_exact != 0 else mpmath.inf
        return PaperMethodResult(
            kind=kind,
            label=label,
            status="ok",
            message=(
                f"{label}: t = {mpmath.nstr(t, 12)} s (exact {mpmath.nstr(t_exact, 12)}), "
                f"phi_1 = {mpmath.nstr(x, 12)} rad (exact {mpmath.nstr(phi_exact, 12)}); "
                f"relative error in t {mpmath.nstr(t_rel, 3)}"
            ),
            t_series=float(t),
            phi_series=float(x),
            t_rel_error=float(t_rel),
            phi_abs_error=float(phi_abs),
            phi_rel_error=float(phi_rel),
            monotone=True,
            **common,
        )
