"""Working precision of a run: double, long (x87 extended), quad (real128) or MPFR (mp:BITS).

Model constants are mpmath numbers at 256 bits; a precision rounds each of
them once, through its decimal text at more digits than the target carries.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import heyoka as hy
import mpmath
import numpy as np

from ..errors import SceneError


@dataclass(frozen=True)
class Precision:
    """A floating-point type for heyoka: ``double``, ``long``, ``quad`` or ``mp:BITS``.

    ``long`` is numpy's longdouble where it is wider than a double (x87
    extended, 64-bit mantissa, on x86); elsewhere it is refused.
    """

    name: str
    bits: int

    @classmethod
    def parse(cls, text: str, field: str = "precision") -> "Precision":
        text = str(text).strip().lower()
        if text in ("double", "float64", "dbl"):
            return cls("double", 53)
        if text in ("long", "longdouble", "extended"):
            if np.finfo(np.longdouble).nmant <= 52:
                raise SceneError(field, "long precision needs a longdouble wider than a double (x86's x87 extended)")
            return cls("long", np.finfo(np.longdouble).nmant + 1)
        if text in ("quad", "real128", "f128"):
            if not hasattr(hy, "real128"):
                raise SceneError(field, "quad precision needs a heyoka build with real128")
            return cls("quad", 113)
        if text.startswith("mp:"):
            try:
                bits = int(text[3:])
            except ValueError:
                raise SceneError(field, f"mp:BITS needs a whole number of bits, got {text!r}") from None
            if not 64 <= bits <= 4096:
                raise SceneError(field, f"mp:BITS must be between 64 and 4096, got {bits}")
            if not hasattr(hy, "real"):
                raise SceneError(field, "MPFR precision needs a heyoka build with real")
            return cls(f"mp:{bits}", bits)
        raise SceneError(field, f"unknown precision {text!r}; expected double | long | quad | mp:BITS")

    @property
    def fp_type(self):
        if self.name == "double":
            return float
        if self.name == "long":
            return np.longdouble
        if self.name == "quad":
            return hy.real128
        return hy.real

    @property
    def epsilon(self) -> float:
        return math.ldexp(1.0, 1 - self.bits)

    @property
    def digits(self) -> int:
        """Significant decimal digits that round-trip a number of this type."""
        return math.ceil(self.bits * math.log10(2)) + 1  # 17 for double, 21 for long, 36 for quad

    def number(self, value):
        """Round an mpmath (or Python) number once to this precision."""
        if self.name == "double":
            return float(value)
        # Inside a wide working precision: a bare mpf() would round to mpmath's
        # global 53 bits before the text is made.
        with mpmath.workprec(max(256, 2 * self.bits)):
            text = mpmath.nstr(mpmath.mpf(value), self.digits + 10, strip_zeros=False, min_fixed=1, max_fixed=0)
        if self.name == "long":
            return np.longdouble(text)
        if self.name == "quad":
            return hy.real128(text)
        return hy.real(text, self.bits)

    def integrator_options(self) -> dict:
        return {} if self.name == "double" else {"fp_type": self.fp_type}

    def format(self, value) -> str:
        """Text with enough significant digits to read back to the same number."""
        if self.name == "double":
            return f"{float(value):.17g}"
        if self.name == "long":
            return np.format_float_scientific(np.longdouble(value), precision=self.digits - 1, unique=False)
        with mpmath.workprec(self.bits + 16):
            return mpmath.nstr(mpmath.mpf(str(value)), self.digits, strip_zeros=False)


DOUBLE = Precision("double", 53)
