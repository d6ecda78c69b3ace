"""The collision-law strategy interface.

Every law here is of Newton type in some velocity u_i = c_i q_i' (q the
body's generalized coordinate on its track) with some inertia M_i: the sum
M_i u_i is conserved and the difference of u is reversed and scaled by the
restitution k (paper eqs. 1-2 and 8-9).

A law is written on the generalized rate q' and the track's metric at the
contact point, sigma = |dC/dq| (C the body's centre): the centre speed is
v_C = sigma q', the rolling angular velocity omega_P = sigma q'/r (eqs. 22-23,
98, 100), the kinetic energy 1/2 kappa m sigma^2 q'^2. On the circle
sigma = R - r for every phi, so the law compiles once per pair to an
impulse map (three constants); on other tracks the engine reads sigma at
each contact. c and M are powers of sigma times a body's constant
(``scale_power``, ``inertia_power``), so the engine evaluates them in the
run's own number type.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Protocol, runtime_checkable

import mpmath

from .._numbers import workprec
from ..bodies import Body


@dataclass(frozen=True)
class ImpulseMap:
    """The law for one pair, written on the angular rates phi' of the track.

    With D = phi_i' - q phi_j' (q = c_j / c_i):
        phi_i'+ = phi_i' - a_i D,    phi_j'+ = phi_j' + a_j D.
    Constants are mpmath numbers at model precision; round them once to the
    run's type.
    """

    q: mpmath.mpf
    a_i: mpmath.mpf
    a_j: mpmath.mpf
    #: 1 + k; with it the map reads D = phi_i' - q phi_j', Delta = (1 + k) D / (1 + q r),
    #: phi_i'+ = phi_i' - Delta, phi_j'+ = phi_j' + r Delta, where r = a_j / a_i.
    one_plus_k: mpmath.mpf | None = None

    @property
    def r(self) -> mpmath.mpf:
        with workprec():
            return self.a_j / self.a_i


@dataclass(frozen=True)
class LawVariables:
    """Generalized velocity scale c (u = c phi') and inertia M of one body."""

    scale: mpmath.mpf
    inertia: mpmath.mpf


@runtime_checkable
class CollisionLaw(Protocol):
    """A collision law: pre-collision rates of two touching bodies -> outgoing rates."""

    name: ClassVar[str]
    #: Where the law comes from (paper and equation numbers).
    source: ClassVar[str]
    restitution: mpmath.mpf
    #: c = c_1 sigma^scale_power, M = M_1 sigma^inertia_power (c_1, M_1: variables at sigma = 1)
    scale_power: ClassVar[int]
    inertia_power: ClassVar[int]

    def variables(self, body: Body, sigma) -> LawVariables:
        """The law's velocity scale and inertia for ``body`` where |dC/dq| = sigma."""
        ...


def check_restitution(k, field: str = "collision.restitution") -> mpmath.mpf:
    from ...errors import SceneError
    from .._numbers import is_finite, to_mpf

    if not is_finite(k):
        raise SceneError(field, f"must be a finite number, got {k!r}")
    x = to_mpf(k)
    if not (0 <= x <= 1):
        raise SceneError(field, f"must be in [0, 1], got {k}")
    return x


def impulse_map(law: CollisionLaw, body_i: Body, body_j: Body, sigma_i, sigma_j) -> ImpulseMap:
    """Compile ``law`` for the pair (i, j) at metrics sigma_i, sigma_j into an :class:`ImpulseMap` (eqs. 10-11)."""
    vi, vj = law.variables(body_i, sigma_i), law.variables(body_j, sigma_j)
    with workprec():
        k = law.restitution
        total = vi.inertia + vj.inertia
        return ImpulseMap(
            q=vj.scale / vi.scale,
            a_i=(1 + k) * vj.inertia / total,
            a_j=(1 + k) * vi.inertia * vi.scale / (total * vj.scale),
            one_plus_k=1 + k,
        )


def law_velocities(law: CollisionLaw, body: Body, sigma, rate):
    """u = c q' for ``body`` (omega_P for the rolling law, v_C for Newton's)."""
    return law.variables(body, sigma).scale * rate


def outgoing(law: CollisionLaw, body_i: Body, body_j: Body, u_i, u_j, sigma_i, sigma_j):
    """Outgoing law velocities (u_i+, u_j+) from incoming ones, eqs. (10)-(11).

    Written as in the paper, in the law's own variables, for tables and tests;
    the engine uses the equivalent :func:`impulse_map`.
    """
    vi, vj = law.variables(body_i, sigma_i), law.variables(body_j, sigma_j)
    with workprec():
        k = law.restitution
        ratio_ij = vi.inertia / vj.inertia
        ratio_ji = vj.inertia / vi.inertia
        du = u_i - u_j
        return u_i - (1 + k) / (1 + ratio_ij) * du, u_j + (1 + k) / (1 + ratio_ji) * du


def collision_impulse(inertia_i, inertia_j, k, du):
    """Impulse on body i in the law's variables, M_i (u_i+ - u_i) (eqs. 5, 12).

    For the rolling law: the moment of the collision impulse about the rolling
    axis, J_P1 (omega_P1+ - omega_P1) = -J1 J2/(J1 + J2) (1 + k)(w1 - w2), with
    du = w1 - w2. Works on floats, arrays and mpmath numbers.
    """
    reduced = inertia_i * inertia_j / (inertia_i + inertia_j)
    return -reduced * (1 + k) * du


def kinetic_energy_change(inertia_i, inertia_j, k, du):
    """Change of the law's kinetic energy sum 1/2 M u^2 (eq. 15; 16-17 at k = 0, 1)."""
    reduced = inertia_i * inertia_j / (inertia_i + inertia_j)
    return -reduced / 2 * (1 - k * k) * du * du


def conserves_mechanical_energy_bound(law: CollisionLaw, body_i: Body, body_j: Body, sigma_i, sigma_j) -> bool:
    """True when this law can never raise the pair's mechanical energy.

    The law dissipates its own kinetic energy 1/2 M u^2 = 1/2 M c^2 phi'^2
    (eq. 15). That is proportional to the true kinetic energy 1/2 kappa m
    rho^2 phi'^2 with one factor for both bodies only if M c^2 / (kappa m
    rho^2) agrees for i and j; otherwise (e.g. Newton's law on centre speeds
    for a disk hitting a ring) an elastic collision can create energy.
    """
    def ratio(body, sigma):
        v = law.variables(body, sigma)
        return v.inertia * v.scale**2 / (body.kappa * body.mass * sigma**2)

    with workprec():
        ri, rj = ratio(body_i, sigma_i), ratio(body_j, sigma_j)
        return abs(ri - rj) <= mpmath.mpf(2) ** (-200) * abs(ri)
