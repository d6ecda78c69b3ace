"""The vertical plane of the track, fixed or turning about a vertical axis (paper section 5.3)."""

from __future__ import annotations

from dataclasses import dataclass

import mpmath

from ..errors import SceneError
from ._numbers import Real, is_finite, to_mpf


@dataclass(frozen=True)
class Frame:
    """The vertical plane rotates about the vertical line x = axis_x at omega (rad/s)."""

    omega: mpmath.mpf
    axis_x: mpmath.mpf

    @classmethod
    def make(cls, omega: Real = 0, axis_x: Real = 0, field: str = "frame") -> "Frame":
        for name, value in (("omega", omega), ("axis_x", axis_x)):
            if not is_finite(value):
                raise SceneError(f"{field}.{name}", f"must be a finite number, got {value!r}")
        return cls(omega=to_mpf(omega), axis_x=to_mpf(axis_x))

    @property
    def rotating(self) -> bool:
        # read off omega's mpf tuple (zero has mantissa and exponent 0; inf and nan a special
        # exponent): a mpf comparison cost ~1 us, and every energy of a scene asks this
        exact = getattr(self.omega, "_mpf_", None)
        if exact is None:  # a Frame built by hand with a Python number
            return self.omega != 0
        _, mantissa, exponent, _ = exact
        return bool(mantissa or exponent)


STATIONARY = Frame(mpmath.mpf(0), mpmath.mpf(0))
