"""The paper's series for the time of rolling along the circle, eqs. (48)-(55).

Between collisions a body on the circle obeys phi'^2 = phi_0'^2 + omega^2
(cos phi - cos phi_0) (eqs. 29, 40; omega^2 = 2 g / (kappa (R - r)), eq. 45).
With u = sin(phi/2), omega_0^2 = phi_0'^2 + 2 omega^2 sin^2(phi_0/2) and
k^2 = 2 omega^2 / omega_0^2 (eq. 46, first line) the time on a monotone arc
is (eqs. 48-50)

    t = (2 / omega_0) * integral_{u_0}^{u} du / sqrt((1 - u^2)(1 - k^2 u^2)),

Legendre's incomplete elliptic integral of the first kind,
F(asin u | k^2) (mpmath.ellipf). The paper expands both factors in binomial
series (eqs. 51-52; the exponent is -1/2, printed +1/2):

    (1 - k^2 u^2)^(-1/2) = sum_m c_m k^(2m) u^(2m),
    (1 - u^2)^(-1/2)     = sum_n c_n u^(2n),     c_n = (2n-1)!! / (2n)!!  (eq. 53),

multiplies them and integrates term by term. Eq. (54) keeps the 3 x 3 block
m, n in {0, 1, 2}, printed as three groups (one per n):

    n = 0:  u + 1/(2.3) k^2 u^3 + 1.3/(2.4.6) k^4 u^5      <- printed; c_2/5 = 1.3/(2.4.5) = 3/40
    n = 1:  1/(2.3) u^3 + 1/(4.5) k^2 u^5 + 1.3/(2^2.4.7) k^4 u^7
    n = 2:  1.3/(2.4.5) u^5 + 1.3/(2^2.4.7) k^2 u^7 + 1/9 (1.3/(2.4))^2 k^4 u^9

Every coefficient is c_m c_n / (2(m + n) + 1); all but the first group's u^5
term agree with that (see :data:`PRINTED_TERMS` and papers/ERRATA.md). The
3 x 3 block is not a consistent truncation: it contains every term only up to
u^5 (m + n <= 2), and some but not all terms of u^7 and u^9, so its error is
O(u^7) whatever the printed u^9 term suggests; :func:`series_time_integral`
truncates by total degree instead.

All functions here return the antiderivative I(u) = integral_0^u (value 0 at
u = 0); the time between u_0 and u_1 is (2/omega_0) (I(u_1) - I(u_0)), see
:func:`time_between`. They evaluate at the ambient mpmath precision.
"""

from __future__ import annotations

from fractions import Fraction
from functools import lru_cache

import mpmath

__all__ = [
    "PRINTED_TERMS",
    "CORRECTED_TERMS",
    "binomial_coefficient",
    "block_coefficient",
    "exact_time_integral",
    "paper_series_as_printed",
    "paper_series_corrected",
    "series_terms",
    "series_time_integral",
    "time_between",
]


@lru_cache(maxsize=None)
def binomial_coefficient(n: int) -> Fraction:
    """c_n = (-1)^n binom(-1/2, n) = (2n-1)!!/(2n)!!, eq. (53): 1, 1/2, 3/8, 5/16, ..."""
    if n < 0:
        raise ValueError("n must be >= 0")
    c = Fraction(1)
    for j in range(1, n + 1):
        c *= Fraction(2 * j - 1, 2 * j)
    return c


def block_coefficient(m: int, n: int) -> Fraction:
    """Coefficient of k^(2m) u^(2(m+n)+1) in the term-by-term integral of (51) x (52)."""
    return binomial_coefficient(m) * binomial_coefficient(n) / (2 * (m + n) + 1)


#: Eq. (54) as printed: (coefficient, power of k^2, power of u), group by group
#: (group n multiplies the n-th term of (52) by the first three terms of (51)).
PRINTED_TERMS: tuple[tuple[Fraction, int, int], ...] = (
    # group n = 0
    (Fraction(1), 0, 1),
    (Fraction(1, 2 * 3), 1, 3),
    (Fraction(1 * 3, 2 * 4 * 6), 2, 5),  # as printed; should be 1*3/(2*4*5)
    # group n = 1
    (Fraction(1, 2 * 3), 0, 3),
    (Fraction(1, 4 * 5), 1, 5),
    (Fraction(1 * 3, 2**2 * 4 * 7), 2, 7),
    # group n = 2
    (Fraction(1 * 3, 2 * 4 * 5), 0, 5),
    (Fraction(1 * 3, 2**2 * 4 * 7), 1, 7),
    (Fraction(1, 9) * Fraction(1 * 3, 2 * 4) ** 2, 2, 9),
)

#: The same 3 x 3 block with every coefficient c_m c_n / (2(m+n)+1).
CORRECTED_TERMS: tuple[tuple[Fraction, int, int], ...] = tuple(
    (block_coefficient(m, n), m, 2 * (m + n) + 1) for n in range(3) for m in range(3)
)


def series_terms(order: int) -> tuple[tuple[Fraction, int, int], ...]:
    """All terms of the Cauchy product of (51) and (52), integrated, of integrand degree <= 2*order.

    Returned as (coefficient, power of k^2, power of u), coefficients exact.
    """
    if order < 0:
        raise ValueError("order must be >= 0")
    return tuple(
        (block_coefficient(m, d - m), m, 2 * d + 1) for d in range(order + 1) for m in range(d + 1)
    )


def _evaluate(terms, u, k2):
    u = mpmath.mpf(u)
    k2 = mpmath.mpf(k2)
    total = mpmath.mpf(0)
    for coef, k_power, u_power in terms:
        total += mpmath.mpf(coef.numerator) / coef.denominator * k2**k_power * u**u_power
    return total


def paper_series_as_printed(u, k2):
    """The bracketed sum of eq. (54) exactly as printed (3 x 3 grouping, 1*3/(2*4*6) in group 1).

    ``k2`` is k^2 (k_1^2 of eq. 46). Multiply by 2/omega_0 and take the
    difference between the limits for the time, as in (54).
    """
    return _evaluate(PRINTED_TERMS, u, k2)


def paper_series_corrected(u, k2):
    """Eq. (54)'s 3 x 3 block with every coefficient c_m c_n/(2(m+n)+1) from (51)-(53).

    Differs from the printed form only in the first group's u^5 term:
    1*3/(2*4*5) = 3/40 instead of 1*3/(2*4*6) = 1/16. Accurate to O(u^7).
    """
    return _evaluate(CORRECTED_TERMS, u, k2)


def series_time_integral(u, k2, order: int):
    """integral_0^u du/sqrt((1-u^2)(1-k^2 u^2)) from the product of (51)-(52), truncated consistently.

    Keeps every term of the integrand up to total degree 2*order in u (so the
    error is O(u^(2*order+3))); converges for |u| < 1 and |k u| < 1.
    """
    return _evaluate(series_terms(order), u, k2)


def exact_time_integral(u, k2):
    """integral_0^u du/sqrt((1-u^2)(1-k^2 u^2)) = F(asin u | k^2), eq. (50), via mpmath.ellipf.

    Valid for |u| <= 1 and k^2 u^2 <= 1 (k^2 > 1 is allowed: an oscillating body).
    """
    u = mpmath.mpf(u)
    return mpmath.ellipf(mpmath.asin(u), mpmath.mpf(k2))


def time_between(u0, u1, k2, omega0, antiderivative=exact_time_integral, **kwargs):
    """t = (2/omega_0) (I(u_1) - I(u_0)), eqs. (50) and (54); u = sin(phi/2).

    ``antiderivative`` is one of the functions above (extra keyword arguments,
    e.g. ``order``, are passed on). Valid on an arc where phi is monotone and
    |phi| < pi. Like (48)-(55) it assumes phi' > 0: on an arc where phi
    decreases the time is minus this value.
    """
    I1 = antiderivative(u1, k2, **kwargs)
    I0 = antiderivative(u0, k2, **kwargs)
    return 2 / mpmath.mpf(omega0) * (I1 - I0)
