"""Rolling bodies: shape, radius, mass and the rolling coefficient kappa.

The rolling coefficient is kappa = 1 + i_C^2 / r^2 (paper eq. 24), so that
the moment of inertia about the instantaneous rolling axis through the contact
point P is J_P = kappa m r^2 (eqs. 24, 35).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from fractions import Fraction

import mpmath

from ..errors import SceneError
from ._numbers import Real, is_finite, to_mpf, workprec


class Shape(str, Enum):
    """Homogeneous body shapes with a known rolling coefficient."""

    SOLID_SPHERE = "solid_sphere"
    HOLLOW_SPHERE = "hollow_sphere"
    DISK = "disk"
    RING = "ring"
    PARTICLE = "particle"


#: kappa = 1 + i_C^2/r^2 for each shape (solid sphere i_C^2 = 2r^2/5, thin
#: spherical shell 2r^2/3, thin disk r^2/2, thin ring r^2; a particle has r = 0
#: and slides, kappa = 1).
ROLLING_COEFFICIENT: dict[Shape, Fraction] = {
    Shape.SOLID_SPHERE: Fraction(7, 5),
    Shape.HOLLOW_SPHERE: Fraction(5, 3),
    Shape.DISK: Fraction(3, 2),
    Shape.RING: Fraction(2),
    Shape.PARTICLE: Fraction(1),
}

#: How a density turns into a mass: (power of r, factor multiplying pi).
#: Solid sphere: volumetric kg/m^3 * 4/3 pi r^3; hollow sphere (thin shell):
#: areal kg/m^2 * 4 pi r^2; thin disk: areal kg/m^2 * pi r^2; thin ring:
#: linear kg/m * 2 pi r.
DENSITY_MEASURE: dict[Shape, tuple[int, Fraction, str]] = {
    Shape.SOLID_SPHERE: (3, Fraction(4, 3), "kg/m^3"),
    Shape.HOLLOW_SPHERE: (2, Fraction(4), "kg/m^2"),
    Shape.DISK: (2, Fraction(1), "kg/m^2"),
    Shape.RING: (1, Fraction(2), "kg/m"),
}


def parse_shape(value: str, field: str = "shape") -> Shape:
    try:
        return Shape(value)
    except ValueError:
        names = " | ".join(s.value for s in Shape)
        raise SceneError(field, f"unknown shape {value!r}; expected one of {names}") from None


def _positive(value: Real, field: str, *, allow_zero: bool = False) -> mpmath.mpf:
    if not is_finite(value):
        raise SceneError(field, f"must be a finite number, got {value!r}")
    x = to_mpf(value)
    if x < 0 or (x == 0 and not allow_zero):
        rule = "must be >= 0" if allow_zero else "must be > 0"
        raise SceneError(field, f"{rule}, got {value}")
    if x > 0 and float(x) == 0:
        raise SceneError(field, f"must be at least 1e-300 (a double's range), got {value}")
    return x


def mass_from_density(shape: Shape, radius: Real, density: Real, field: str = "density") -> mpmath.mpf:
    """Mass of a homogeneous body of the given shape (see ``DENSITY_MEASURE``)."""
    if shape not in DENSITY_MEASURE:
        raise SceneError(field, f"a {shape.value} has no size to fill: give mass instead")
    power, factor, _unit = DENSITY_MEASURE[shape]
    rho = _positive(density, field)
    with workprec():
        return rho * mpmath.mpf(factor.numerator) / factor.denominator * mpmath.pi * to_mpf(radius) ** power


@dataclass(frozen=True)
class Body:
    """A homogeneous body rolling without slipping (or a sliding particle).

    Attributes are mpmath numbers at model precision. Build one with
    :meth:`Body.of_shape` or :meth:`Body.with_kappa`, which check the rules.
    """

    radius: mpmath.mpf
    mass: mpmath.mpf
    kappa: mpmath.mpf
    shape: Shape | None = None

    def __hash__(self) -> int:  # bodies key the engine's caches (Scene.constants): mpf hashing once
        cached = self.__dict__.get("_hash")
        if cached is None:
            cached = hash((self.radius, self.mass, self.kappa, self.shape))
            object.__setattr__(self, "_hash", cached)
        return cached

    def __getstate__(self) -> dict:  # str hashes (the shape) differ between processes: not pickled
        return {k: v for k, v in self.__dict__.items() if k != "_hash"}

    @classmethod
    def of_shape(
        cls,
        shape: Shape | str,
        radius: Real,
        *,
        mass: Real | None = None,
        density: Real | None = None,
        field: str = "body",
    ) -> "Body":
        shape = parse_shape(shape, f"{field}.shape") if isinstance(shape, str) else shape
        if shape is Shape.PARTICLE:
            r = _positive(radius, f"{field}.radius", allow_zero=True)
            if r != 0:
                raise SceneError(f"{field}.radius", f"a particle has radius 0, got {radius}")
        else:
            r = _positive(radius, f"{field}.radius")
        m = _mass(shape, r, mass, density, field)
        kappa = ROLLING_COEFFICIENT[shape]
        return cls(radius=r, mass=m, kappa=to_mpf(kappa), shape=shape)

    @classmethod
    def with_kappa(cls, kappa: Real, radius: Real, *, mass: Real, field: str = "body") -> "Body":
        """A body given by its rolling coefficient kappa = 1 + i_C^2/r^2 >= 1."""
        if not is_finite(kappa):
            raise SceneError(f"{field}.kappa", f"must be a finite number, got {kappa!r}")
        k = to_mpf(kappa)
        if k < 1:
            raise SceneError(f"{field}.kappa", f"must be >= 1 (kappa = 1 + i_C^2/r^2), got {kappa}")
        r = _positive(radius, f"{field}.radius")
        m = _mass(None, r, mass, None, field)
        return cls(radius=r, mass=m, kappa=k, shape=None)

    @property
    def is_particle(self) -> bool:
        return self.radius == 0

    def rolling_inertia(self) -> mpmath.mpf:
        """J_P = kappa m r^2, moment of inertia about the rolling axis (eq. 24)."""
        with workprec():
            return self.kappa * self.mass * self.radius**2

    def describe(self) -> str:
        kind = self.shape.value if self.shape else f"kappa={mpmath.nstr(self.kappa, 6)}"
        return f"{kind} r={mpmath.nstr(self.radius, 6)} m={mpmath.nstr(self.mass, 6)}"


def _mass(shape, r, mass, density, field) -> mpmath.mpf:
    if mass is not None and density is not None:
        raise SceneError(f"{field}.mass", "give mass or density, not both")
    if mass is not None:
        return _positive(mass, f"{field}.mass")
    if density is not None:
        if shape is None:
            raise SceneError(f"{field}.density", "a body given by kappa has no shape to fill: give mass")
        return mass_from_density(shape, r, density, f"{field}.density")
    raise SceneError(f"{field}.mass", "missing: give mass (kg) or density")
