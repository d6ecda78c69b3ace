"""Periodic forcing of the bodies on a track (paper section 2: forced oscillators).

Two kinds, both harmonic at ``frequency`` nu (rad/s) with ``phase`` psi:

* ``force``: a force F0 cos(nu t + psi) (N, ``amplitude`` F0) on each forced body,
  along the track's tangent in the direction of increasing coordinate;
* ``base``: the track moves in its plane as a rigid whole, its displacement
  X(t) = A cos(nu t + psi) (m, ``amplitude`` A) along the direction at
  ``direction`` rad from the horizontal (0: horizontal, pi/2: vertical). In the
  track's frame each body of mass m feels the inertial force -m X''(t) =
  m A nu^2 cos(nu t + psi) (cos d, sin d): its tangential part drives the body,
  its normal part adds to the track's reaction (and so to friction).

Either makes the system non-autonomous: the engine samples the state once
per forcing period (the stroboscopic Poincare section, at nu t + psi = 2 pi n).
"""

from __future__ import annotations

from dataclasses import dataclass

import mpmath

from ..errors import SceneError
from ._numbers import Real, is_finite, to_mpf

FORCING_KINDS = ("force", "base")


@dataclass(frozen=True)
class Forcing:
    kind: str
    amplitude: mpmath.mpf
    frequency: mpmath.mpf
    phase: mpmath.mpf = mpmath.mpf(0)
    direction: mpmath.mpf = mpmath.mpf(0)
    #: Forced bodies (0-based) for kind ``force``; None: every body. A base motion moves every body.
    bodies: tuple | None = None

    @classmethod
    def make(cls, kind: str = "force", amplitude: Real = 0, frequency: Real = 1, phase: Real = 0,
             direction: Real = 0, bodies=None, n_bodies: int | None = None, field: str = "forcing") -> "Forcing":
        if not isinstance(kind, str) or kind not in FORCING_KINDS:
            raise SceneError(f"{field}.kind", f"must be one of {' | '.join(FORCING_KINDS)}, got {kind!r}")
        values = {}
        for name, value in (("amplitude", amplitude), ("frequency", frequency), ("phase", phase),
                            ("direction", direction)):
            if not is_finite(value):
                raise SceneError(f"{field}.{name}", f"must be a finite number, got {value!r}")
            values[name] = to_mpf(value)
        if values["frequency"] <= 0:
            raise SceneError(f"{field}.frequency", f"must be > 0 (rad/s), got {frequency}")
        chosen = None
        if bodies is not None:
            if kind != "force":
                raise SceneError(f"{field}.bodies", "a base motion moves every body: give bodies only with kind = 'force'")
            if not isinstance(bodies, (list, tuple)) or not bodies or not all(
                    isinstance(b, int) and not isinstance(b, bool) for b in bodies):
                raise SceneError(f"{field}.bodies", f"must be a list of body numbers (1..N), got {bodies!r}")
            if n_bodies is not None and not all(1 <= b <= n_bodies for b in bodies):
                raise SceneError(f"{field}.bodies", f"body numbers must be in 1..{n_bodies}, got {list(bodies)}")
            chosen = tuple(sorted({b - 1 for b in bodies}))
        return cls(kind=kind, bodies=chosen, **values)

    @property
    def period(self) -> float:
        return float(2 * mpmath.pi / self.frequency)

    def forces(self, body: int) -> bool:
        return self.kind == "base" or self.bodies is None or body in self.bodies

    def describe(self) -> str:
        what = "force F0" if self.kind == "force" else "base motion A"
        return (f"{what} = {mpmath.nstr(self.amplitude, 6)} cos({mpmath.nstr(self.frequency, 6)} t + "
                f"{mpmath.nstr(self.phase, 6)})")
