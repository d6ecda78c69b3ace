"""Exact motion of one rolling body between collisions (a pendulum).

Between two collisions a body rolling inside the circle obeys

    phi'' = -a sin(phi),    a = g / (kappa (R - r))               (paper eq. 25)

with the energy first integral (eqs. 28-29, written with
1 - cos phi = 2 sin^2(phi/2) as the paper does before eq. 48)

    phi'^2 = C - 4 a sin^2(phi/2),    C = phi0'^2 + 4 a sin^2(phi0/2).

The paper's modulus is k^2 = 4a / C (eq. 46 with omega_1^2 = 2a) and the time
integral is t = (2/sqrt C) int dtheta / sqrt(1 - k^2 sin^2 theta),
theta = phi/2 (eqs. 48-50), a Legendre integral of the first kind. Here we
use the parameter m = 1/k^2 = C/(4a), the energy in units of the separatrix
energy:

* m < 1, libration (k^2 > 1): sin(phi/2) = sqrt(m) sn(u | m),
  phi' = 2 sqrt(a m) cn(u | m), u = sqrt(a) (t - tau); period 4 K(m)/sqrt(a).
* m > 1, rotation over the top (k^2 < 1):
  phi/2 = am(+-sqrt(C)/2 (t - t0) + F(phi0/2 | k^2) | k^2),
  phi' = +-sqrt(C) dn(... | k^2).
* m = 1, separatrix: sin(phi/2) = tanh(sqrt(a) (t - tau)), phi' = 2 sqrt(a) sech(...).

The Jacobi parametrisation covers turning points naturally (the paper's
integrals (48)-(50) only cover monotone branches); :meth:`ExactPendulum.time_to_angle`
is the paper's monotone-branch integral, evaluated with Legendre's F.

Angles are unwrapped: a librating body may oscillate about 2 pi n, a
rotating one keeps counting turns. All arithmetic is mpmath at the pendulum's
own precision (``mpmath.workdps`` locally; the global precision is never
changed).

Everything here is written from the equations above, independently of the
heyoka engine and of ``heyroll.model``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import mpmath

#: Extra decimal digits carried inside every evaluation.
GUARD_DPS = 10

LIBRATION = "libration"
ROTATION = "rotation"
SEPARATRIX = "separatrix"


def _sign(x) -> int:
    return 1 if x > 0 else (-1 if x < 0 else 0)


def jacobi_am(u, m):
    """Jacobi amplitude am(u | m) for real u and 0 <= m < 1.

    mpmath has no ``am``: with u = 2 K n + r, |r| <= K, am(u) = n pi + am(r),
    and on [-K, K] am(r) = atan2(sn(r | m), cn(r | m)) (cn >= 0 there).
    Returns (am, sn(r), cn(r), dn(r)); sn, cn, dn of u itself follow from the
    quasi-periodicity (dn has period 2K, sn and cn change sign with n odd).
    """
    K = mpmath.ellipk(m)
    n = mpmath.nint(u / (2 * K))
    r = u - 2 * K * n
    sn = mpmath.ellipfun("sn", r, m=m)
    cn = mpmath.ellipfun("cn", r, m=m)
    dn = mpmath.ellipfun("dn", r, m=m)
    return n * mpmath.pi + mpmath.atan2(sn, cn), sn, cn, dn


@dataclass(frozen=True)
class ExactPendulum:
    """The exact solution of phi'' = -a sin phi through (phi0, dphi0) at t0.

    ``a``, ``phi0``, ``dphi0``, ``t0`` are converted to mpmath numbers at
    ``dps`` decimal digits (plus guard digits). Methods return mpf values
    rounded to ``dps`` digits.
    """

    a: object
    phi0: object
    dphi0: object
    t0: object = 0
    dps: int = 40
    # Derived constants, filled in __post_init__.
    regime: str = field(init=False)
    energy: object = field(init=False, repr=False)  # C = phi'^2 + 4 a sin^2(phi/2)
    m: object = field(init=False, repr=False)  # C / (4 a) = 1 / k^2
    _c: dict = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        if self.dps < 15:
            raise ValueError("dps must be >= 15")
        with self._ctx():
            a = mpmath.mpf(self.a)
            if not a > 0:
                raise ValueError("a must be > 0")
            phi0 = mpmath.mpf(self.phi0)
            dphi0 = mpmath.mpf(self.dphi0)
            t0 = mpmath.mpf(self.t0)
            for name, value in (("a", a), ("phi0", phi0), ("dphi0", dphi0), ("t0", t0)):
                object.__setattr__(self, name, value)
            s_half = mpmath.sin(phi0 / 2)
            C = dphi0**2 + 4 * a * s_half**2
            # 1 - m written without cancellation: (4 a cos^2(phi0/2) - phi0'^2) / (4 a).
            one_minus_m = (4 * a * mpmath.cos(phi0 / 2) ** 2 - dphi0**2) / (4 * a)
            m = C / (4 * a)
            sqa = mpmath.sqrt(a)
            c = {"sqrt_a": sqa, "one_minus_m": one_minus_m}
            if one_minus_m > 0:
                regime = LIBRATION
                # Centre of the libration: phi0 = 2 pi n + psi0, |psi0| < pi.
                n = mpmath.nint(phi0 / (2 * mpmath.pi))
                centre = 2 * mpmath.pi * n
                psi0 = phi0 - centre
                K = mpmath.ellipk(m)
                # sn(u0) = sin(psi0/2)/sqrt(m), cn(u0) = phi0'/(2 sqrt(a m)):
                # the amplitude am(u0) is the angle of that point, u0 = F(am | m).
                theta0 = mpmath.atan2(mpmath.sin(psi0 / 2), dphi0 / (2 * sqa))
                u0 = mpmath.ellipf(theta0, m)
                c.update(centre=centre, K=K, theta0=theta0, u0=u0, sqrt_m=mpmath.sqrt(m))
            elif one_minus_m < 0:
                regime = ROTATION
                k2 = 1 / m  # the paper's k^2 = 4a/C < 1 (eq. 46)
                sqC = mpmath.sqrt(C)
                s = _sign(dphi0)
                F0 = mpmath.ellipf(phi0 / 2, k2)
                c.update(k2=k2, sqrt_C=sqC, s=s, F0=F0, K=mpmath.ellipk(k2))
            else:
                regime = SEPARATRIX
                n = mpmath.nint(phi0 / (2 * mpmath.pi))
                centre = 2 * mpmath.pi * n
                psi0 = phi0 - centre
                s = _sign(dphi0)
                if s == 0:  # resting at the unstable top
                    c.update(centre=centre, s=0, v0=None)
                else:
                    c.update(centre=centre, s=s, v0=mpmath.atanh(mpmath.sin(psi0 / 2)))
            object.__setattr__(self, "regime", regime)
            object.__setattr__(self, "energy", C)
            object.__setattr__(self, "m", m)
            object.__setattr__(self, "_c", c)

    # -- helpers ---------------------------------------------------------------

    def _ctx(self):
        return mpmath.workdps(self.dps + GUARD_DPS)

    def _out(self, *values):
        with mpmath.workdps(self.dps):
            return tuple(+v for v in values)

    @property
    def k2(self):
        """The paper's squared modulus k^2 = 4a/C (eq. 46)."""
        with self._ctx():
            return 4 * self.a / self.energy

    @property
    def direction(self) -> int:
        """+1 / -1: sense of motion along the current monotone branch (0: at rest at an equilibrium)."""
        s = _sign(self.dphi0)
        if s:
            return s
        with self._ctx():
            return -_sign(mpmath.sin(self.phi0))

    # -- the solution ------------------------------------------------------------

    def state(self, t):
        """(phi(t), phi'(t)) from the Jacobi elliptic functions (see module docstring)."""
        c = self._c
        with self._ctx():
            dt = mpmath.mpf(t) - self.t0
            if self.regime == LIBRATION:
                m, K = self.m, c["K"]
                u = c["u0"] + c["sqrt_a"] * dt
                u = u - 4 * K * mpmath.nint(u / (4 * K))
                sn = mpmath.ellipfun("sn", u, m=m)
                cn = mpmath.ellipfun("cn", u, m=m)
                dn = mpmath.ellipfun("dn", u, m=m)
                # sin(phi/2) = sqrt(m) sn and cos(phi/2) = dn: atan2 keeps full
                # accuracy at the turning points (where asin would not).
                phi = c["centre"] + 2 * mpmath.atan2(c["sqrt_m"] * sn, dn)
                dphi = 2 * c["sqrt_a"] * c["sqrt_m"] * cn
            elif self.regime == ROTATION:
                u = c["F0"] + c["s"] * c["sqrt_C"] / 2 * dt
                am, _sn, _cn, dn = jacobi_am(u, c["k2"])
                phi = 2 * am
                dphi = c["s"] * c["sqrt_C"] * dn
            else:
                if c["s"] == 0:
                    return self._out(self.phi0, self.dphi0)
                v = c["v0"] + c["s"] * c["sqrt_a"] * dt
                phi = c["centre"] + 2 * mpmath.atan(mpmath.sinh(v))  # gd(v): sin(phi/2) = tanh v
                dphi = 2 * c["s"] * c["sqrt_a"] * mpmath.sech(v)
            return self._out(phi, dphi)

    def acceleration(self, phi):
        """phi'' = -a sin(phi) (eq. 25)."""
        with self._ctx():
            return self._out(-self.a * mpmath.sin(phi))[0]

    def period(self):
        """Libration period 4 K(m)/sqrt(a), m = 1/k^2; None for a rotation, inf on the separatrix."""
        if self.regime == ROTATION:
            return None
        if self.regime == SEPARATRIX:
            return mpmath.inf
        with self._ctx():
            return self._out(4 * self._c["K"] / self._c["sqrt_a"])[0]

    def revolution_time(self):
        """Time for one full turn of a rotation, 4 K(k^2)/sqrt(C); None otherwise."""
        if self.regime != ROTATION:
            return None
        with self._ctx():
            return self._out(4 * self._c["K"] / self._c["sqrt_C"])[0]

    def amplitude(self):
        """Largest |phi - centre| of a libration, 2 asin(sqrt m); None otherwise."""
        if self.regime != LIBRATION:
            return None
        with self._ctx():
            return self._out(2 * mpmath.asin(self._c["sqrt_m"]))[0]

    def time_to_angle(self, phi):
        """Time t >= t0 at which the body reaches ``phi`` on its current monotone branch.

        The paper's eqs. (48)-(50): t - t0 = (2/sqrt C) [F(phi/2 | k^2) -
        F(phi0/2 | k^2)] along a branch where phi' keeps its sign.

        * rotation (k^2 < 1): F is Legendre's F at modulus k^2 directly; the
          branch is the whole future motion (angles unwrapped).
        * libration (k^2 > 1): reciprocal-modulus transformation,
          F(theta | k^2) = F(psi | 1/k^2) / k with sin psi = k sin theta,
          so t - t0 = [F(psi | m) - F(psi0 | m)] / sqrt(a); psi is the
          Jacobi amplitude of sn(sqrt(a)(t - tau) | m), and the branch runs
          from the current point to the next turning point (psi = pi/2 + k pi).
        * separatrix: t - t0 = [atanh(sin(phi/2)) - atanh(sin(phi0/2))] / sqrt(a).

        Returns None if ``phi`` is not on the branch (behind the body, or
        beyond the turning point).
        """
        c = self._c
        s = self.direction
        if s == 0:
            return None
        with self._ctx():
            phi = mpmath.mpf(phi)
            if self.regime == ROTATION:
                dt = s * (mpmath.ellipf(phi / 2, c["k2"]) - c["F0"]) * 2 / c["sqrt_C"]
            elif self.regime == LIBRATION:
                psi = phi - c["centre"]
                x = mpmath.sin(psi / 2) / c["sqrt_m"]
                # A target given at the amplitude (rounded to dps digits) counts as reached.
                if abs(psi) >= mpmath.pi or abs(x) > 1 + mpmath.mpf(10) ** -self.dps:
                    return None
                x = max(-1, min(1, x))
                # psi here is the Jacobi amplitude: sin(amplitude) = x. The
                # current point is am(u0) = theta0 (kept from the start, not
                # recomputed with asin, which loses half the digits at a
                # turning point). The branch ends at the next turning point,
                # amplitude pi/2 + k pi: k even at the upper one, odd at the lower one.
                theta0 = c["theta0"]
                half_pi = mpmath.pi / 2
                if self.dphi0 == 0:
                    k = int(mpmath.nint((theta0 + half_pi) / mpmath.pi))
                else:
                    k = int(mpmath.ceil((theta0 - half_pi) / mpmath.pi))
                theta = k * mpmath.pi + (mpmath.asin(x) if k % 2 == 0 else -mpmath.asin(x))
                if theta < theta0:
                    return None
                dt = (mpmath.ellipf(theta, self.m) - c["u0"]) / c["sqrt_a"]
            else:
                psi = phi - c["centre"]
                if abs(psi) >= mpmath.pi:
                    return None
                dt = s * (mpmath.atanh(mpmath.sin(psi / 2)) - c["v0"]) / c["sqrt_a"]
            if dt < 0:
                return None
            return self._out(self.t0 + dt)[0]
