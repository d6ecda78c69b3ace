"""Exact-enough scalars for the model layer.

Inputs (decimal strings from scene files, Python numbers from the API) become
mpmath ``mpf`` values at ``MODEL_PRECISION`` bits. Derived constants are
evaluated at that precision and rounded once to the working type of a run.
"""

from __future__ import annotations

import math
from decimal import Decimal
from fractions import Fraction
from typing import Union

import mpmath

#: Bits carried by model scalars: far beyond quad (113) so that one rounding
#: to the run's type is all that separates a constant from its exact value.
MODEL_PRECISION = 256

Real = Union[int, float, str, Decimal, Fraction, "mpmath.mpf"]


def workprec():
    """Context manager for model-precision arithmetic (no global state change)."""
    return mpmath.workprec(MODEL_PRECISION)


def to_mpf(value: Real) -> mpmath.mpf:
    """Convert ``value`` to an mpf at model precision, exactly where possible.

    Decimal and str go through their decimal text (so "0.12" is 0.12 to 256
    bits, not the double nearest to it); floats are taken at their exact
    binary value.
    """
    with workprec():
        if isinstance(value, mpmath.mpf):
            return +value
        if isinstance(value, bool):
            raise TypeError("a boolean is not a number")
        if isinstance(value, Fraction):
            return mpmath.mpf(value.numerator) / value.denominator
        if isinstance(value, Decimal):
            return mpmath.mpf(str(value))
        return mpmath.mpf(value)


def is_finite(value: Real) -> bool:
    """True for a finite real number that a double can hold (rejects NaN, infinities, 1e400)."""
    try:
        if not math.isfinite(float(value)):
            return False
    except (ValueError, OverflowError, TypeError):
        return False
    if isinstance(value, Decimal):
        return value.is_finite()
    if isinstance(value, (int, Fraction)):
        return True
    if isinstance(value, float):
        return math.isfinite(value)
    if isinstance(value, mpmath.mpf):
        return bool(mpmath.isfinite(value))
    if isinstance(value, str):
        try:
            return Decimal(value.strip()).is_finite()
        except ArithmeticError:
            return False
    return False


def is_number(value) -> bool:
    return isinstance(value, (int, float, Decimal, Fraction, mpmath.mpf)) and not isinstance(
        value, bool
    )


def is_positive_double(value: Real) -> bool:
    """True when ``value`` rounds to a positive double (not 0 by underflow)."""
    return float(value) > 0
