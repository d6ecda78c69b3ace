"""Exact-enough scalars for the model layer.

Inputs (decimal strings from scene files, Python numbers from the API) become
mpmath ``mpf`` values at ``MODEL_PRECISION`` bits. Derived constants are
evaluated at that precision and rounded once to the working type of a run.
"""

from __future__ import annotations

import dataclasses
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
    # The common cases without a context switch (~3 us each, a sweep's point converts its whole state):
    # a float is exact at mpmath's precision if that holds a double, and an mpf of at most
    # MODEL_PRECISION bits is its own rounding.
    kind = type(value)
    if kind is float and mpmath.mp.prec >= 53:
        return mpmath.mpf(value)
    if kind is mpmath.mpf and value._mpf_[3] <= MODEL_PRECISION:
        return value
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


# -- pickling without rounding -------------------------------------------------------------
# mpmath pickles an mpf by its digits and rebuilds it at the unpickling process's precision
# (53 bits by default): a Scene sent to another process (multiprocessing, Dask) came back with
# its 256-bit constants rounded to doubles, and ran differently (measured: an 8-body scene
# that fails in one process completed from its pickle). Scene.__reduce__ ships exact mantissas.


def exact_state(value):
    """``value`` with every mpf replaced by its exact (sign, mantissa, exponent, bits) tuple,
    recursively through frozen dataclasses, tuples and lists (see :func:`from_exact_state`)."""
    if isinstance(value, mpmath.mpf):
        return (_MPF, value._mpf_)
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return (_DATACLASS, type(value), tuple((f.name, exact_state(getattr(value, f.name)))
                                               for f in dataclasses.fields(value)))
    if isinstance(value, (tuple, list)):
        return (_SEQUENCE, type(value), tuple(exact_state(v) for v in value))
    return (_PLAIN, value)


def from_exact_state(state):
    """The object :func:`exact_state` took apart (dataclasses rebuilt without re-validation)."""
    kind = state[0]
    if kind == _MPF:
        return mpmath.mp.make_mpf(state[1])
    if kind == _DATACLASS:
        obj = object.__new__(state[1])
        for name, field_state in state[2]:
            object.__setattr__(obj, name, from_exact_state(field_state))
        return obj
    if kind == _SEQUENCE:
        return state[1](from_exact_state(v) for v in state[2])
    return state[1]


_MPF, _DATACLASS, _SEQUENCE, _PLAIN = range(4)


#: Dekker's splitter for doubles, 2^27 + 1: x = hi + lo with halves of 26 bits whose products are exact.
DEKKER_SPLIT = 134217729.0


def halves(x: float) -> tuple[float, float]:
    """x = hi + lo exactly, each of at most 26 significant bits (Dekker's split)."""
    c = DEKKER_SPLIT * x
    hi = c - (c - x)
    return hi, x - hi


def two_product(a: float, b: float) -> tuple[float, float]:
    """a b = p + e exactly, p the rounded product (Dekker's two-product, no fused multiply-add needed)."""
    p = a * b
    ah, al = halves(a)
    bh, bl = halves(b)
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


#: touching_slack relative to the coordinates' size (16 double ulps).
TOUCHING_SLACK = 2.0 ** -48


def touching_slack(*coordinates) -> mpmath.mpf:
    """How far past touching two bodies placed by these coordinates may start (model precision): ~16 ulps of the
    largest, the round-off of places written as doubles (a cradle's angles, a rack's irrational places written to
    17 digits came out 1e-17 past touching and were refused: acceptance tests). The run's start moves such
    contacts to touching in the run's own number type (the settlers' close_start) and settles them. Model numbers
    in, a model number out; floats (the engine's) in, a float out: the same value (2^-48 times one of them)."""
    return TOUCHING_SLACK * max([1.0] + [abs(c) for c in coordinates])
