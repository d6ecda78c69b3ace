"""What a table collision law is: incoming centre velocities v and slips u -> outgoing ones.

A ball on the cloth has centre velocity v and horizontal spin omega; the
slip of its contact point with the cloth is u = v - R omega x z (z up), so
a rolling ball has u = 0 and omega_P = z x v / R (issue 14). Laws act along
the unit normal n of the contact (from ball i to ball j, or out of the
table at a cushion): normal parts change, tangential parts are kept. A law
that keeps the ball rolling through the impact changes v and omega together
(u unchanged); a law whose impulse goes through the centre leaves omega
alone, so the slip takes the whole velocity change and the ball then slides.

Laws are evaluated in the run's own number type with constants rounded once
(:meth:`constants`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar, Protocol, runtime_checkable

import mpmath

from ..._numbers import two_product


@runtime_checkable
class BallLaw(Protocol):
    """Ball-ball collision law (``[collision] law``)."""

    name: ClassVar[str]
    source: ClassVar[str]
    #: the balls keep rolling through the impact (u unchanged); otherwise the spin is unchanged
    keeps_rolling: ClassVar[bool]

    def constants(self, body_i, body_j, number) -> tuple:
        """The pair's constants in the run type (``number`` rounds an mpmath value)."""
        ...

    def normal_rates(self, c: tuple, vn_i, vn_j) -> tuple:
        """Outgoing normal velocities (vn_i+, vn_j+) from incoming ones (n from i to j)."""
        ...


@runtime_checkable
class CushionLaw(Protocol):
    """Ball-cushion impact law (``[track] cushion_model``)."""

    name: ClassVar[str]
    source: ClassVar[str]
    keeps_rolling: ClassVar[bool]


def split(v, n):
    """(v . n, v - (v . n) n / |n|^2): the tangential part exactly normal to n (see :func:`with_normal`)."""
    vn = v[0] * n[0] + v[1] * n[1]
    f = vn / (n[0] * n[0] + n[1] * n[1])
    return vn, (v[0] - f * n[0], v[1] - f * n[1])


def with_normal(v, n, vn_new):
    """v with its normal part v . n replaced by vn_new (tangential part kept): v + (vn_new - v . n) n / |n|^2.

    A unit normal computed in floats is off unity by round-off, and the plain v + (vn_new - v . n) n
    then changed |v|^2 at every elastic reflection by 4 v_n^2 (|n|^2 - 1), with one sign where the
    normal is always the same (a polygon's edge) or rounded the same way (a circle's g/|grad g|): the
    energy drifted by -2.8e-16 per impact on a circle and +3.1e-16 on a pentagon, linearly (review).
    Dividing by |n|^2 is exact only in exact arithmetic: its roundings still drift, by ~1e-16 per
    impact (measured). In double precision the result is therefore computed in double-double
    arithmetic and rounded once, which leaves the energy a random walk of half-ulp roundings."""
    if isinstance(v[0], float) and isinstance(v[1], float) and isinstance(vn_new, float):
        return _with_normal_rounded_once(float(v[0]), float(v[1]), float(n[0]), float(n[1]), float(vn_new))
    vn = v[0] * n[0] + v[1] * n[1]
    f = (vn_new - vn) / (n[0] * n[0] + n[1] * n[1])
    return v[0] + f * n[0], v[1] + f * n[1]


def _add(ah: float, al: float, bh: float, bl: float) -> tuple:
    """(ah + al) + (bh + bl) as a normalised double-double (Knuth's two-sum on the heads)."""
    s = ah + bh
    z = s - ah
    e = ((ah - (s - z)) + (bh - z)) + al + bl
    hi = s + e
    return hi, e - (hi - s)


def _with_normal_rounded_once(vx: float, vy: float, nx: float, ny: float, vn_new: float) -> tuple:
    """:func:`with_normal` on doubles: every product exact, every sum with its error, rounded once."""
    vn = _add(*two_product(vx, nx), *two_product(vy, ny))
    nn = _add(*two_product(nx, nx), *two_product(ny, ny))
    dh, dl = _add(vn_new, 0.0, -vn[0], -vn[1])
    q = dh / nn[0]  # f = d / |n|^2: one Newton correction of the quotient
    ph, pl = two_product(q, nn[0])
    rh, rl = _add(dh, dl, -ph, -pl - q * nn[1])
    fh, fl = _add(q, 0.0, rh / nn[0], 0.0)
    out = []
    for v, c in ((vx, nx), (vy, ny)):
        ph, pl = two_product(fh, c)
        out.append(_add(v, 0.0, ph, pl + fl * c)[0])
    return out[0], out[1]


def after_impact(v, u, n, vn_new, keeps_rolling: bool, particle: bool):
    """(v+, u+) after the normal part of v becomes vn_new.

    Rolling kept: the spin turns with v, the slip is unchanged (a rolling ball
    stays rolling). Impulse through the centre: the spin is unchanged, so the
    slip changes by the velocity change. A particle has no spin: u = 0.
    """
    v_new = with_normal(v, n, vn_new)
    if particle:
        return v_new, (v_new[0] * 0, v_new[1] * 0)
    if keeps_rolling:
        return v_new, u
    return v_new, (u[0] + v_new[0] - v[0], u[1] + v_new[1] - v[1])


class NormalImpulseLaw:
    """A ball law that is a one-dimensional law along the line of centres (eqs. 10-11), compiled once
    per pair into an impulse map on the normal centre velocities (sigma = 1): Hedrih's, Newton's.

    Subclasses name the one-dimensional law (``heyroll.model.laws``) in ``one_dimensional``.
    """

    def one_dimensional(self):
        raise NotImplementedError

    def impulse_map(self, body_i, body_j):
        """The pair's map at model precision (heyroll.model.laws.ImpulseMap)."""
        from ...laws import impulse_map

        return impulse_map(self.one_dimensional(), body_i, body_j, 1, 1)

    def constants(self, body_i, body_j, number) -> tuple:
        m = self.impulse_map(body_i, body_j)
        return number(m.q), number(m.a_i), number(m.a_j)

    def normal_rates(self, c, vn_i, vn_j):
        # D = vn_i - q vn_j; vn_i+ = vn_i - a_i D, vn_j+ = vn_j + a_j D (see heyroll.model.laws.base.ImpulseMap)
        d = vn_i - c[0] * vn_j
        return vn_i - c[1] * d, vn_j + c[2] * d


@dataclass(frozen=True)
class RestitutionLaw:
    """A table law's one number, its restitution k in [0, 1], checked on construction."""

    restitution: mpmath.mpf = field(default_factory=lambda: mpmath.mpf(1))
    #: the scene-file field a bad k is reported under
    restitution_field: ClassVar[str] = "collision.restitution"

    def __post_init__(self):
        from ....model.laws.base import check_restitution

        object.__setattr__(self, "restitution", check_restitution(self.restitution, self.restitution_field))
