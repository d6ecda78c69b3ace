"""The track strategy: what the one engine asks of every track.

A body on a track has one generalized coordinate q (phi on a circle, the
arc length s of its centre's path on an arc chain, the contact abscissa x on
a curve). A track gives, for a body on it:

* the centre C(q) = (x_C, y_C) in the vertical plane, as heyoka expressions
  (:meth:`Track.terms`) and as numbers (:meth:`Track.centre`);
* the metric sigma = |dC/dq|, which the collision laws read at the contact
  point (omega_P = sigma q'/r, v_C = sigma q', generalized mass kappa m sigma^2;
  paper eqs. 22-24, 98, 100);
* the equation of motion. The default comes from the Lagrangian in a plane
  turning at Omega about the vertical line x = a (paper section 5.3, derived
  for any body):

      L = 1/2 kappa m F q'^2 + 1/2 m Omega^2 (x_C - a)^2 - m g y_C,  F = sigma^2,
      F q'' + 1/2 F' q'^2 - Omega^2/kappa (x_C - a) x_C' + g/kappa y_C' = 0,

  and a track may give a closed form instead (the circle's eq. 25);
* the normal force of the track per unit mass, N/m = [(x_C' y_C'' - y_C' x_C'') q'^2
  + g x_C' + Omega^2 (x_C - a) y_C'] / sigma, and the tangential driving force
  per unit mass (-g y_C' + Omega^2 (x_C - a) x_C') / sigma, of which a rolling body needs
  the share 1 - 1/kappa as friction;
* its pieces and junctions (runtime parameters that the engine switches at
  junction events, so no Taylor step crosses a jump of curvature), and its
  ends: limiters at both ends of an open track, or a closed coordinate with a
  wrap-around pair of neighbours;
* the gap between neighbours: the distance between the centres minus
  r_i + r_j by default (a signed coordinate difference for two particles).

Properties let the engine keep fast paths without a second engine:
``closed`` (a wrap-around pair), ``linear_gap`` (the gap is q_j - q_i - const:
rigid clusters in persistent contact, cheap guards) and ``constant_metric``
(sigma does not depend on q: collision maps compiled once per pair).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Protocol, runtime_checkable

import heyoka as hy
import mpmath
import numpy as np

from .._numbers import workprec
from ..bodies import Body
from ..frame import Frame


@dataclass(frozen=True)
class BodyTerms:
    """heyoka expressions of one body on a track, in its coordinate q and rate v."""

    x_c: object
    y_c: object
    acceleration: object
    #: N/m: the track's normal force per unit mass (> 0: pressing on the track)
    normal: object
    #: |dC/dq|
    sigma: object
    #: tangential driving force per unit mass (gravity and the centrifugal force)
    driving: object


@dataclass(frozen=True)
class Dynamics:
    """What the equations of motion need besides the geometry: gravity and the frame.

    ``par(value)`` turns a model number into a runtime parameter of the
    integrator (so scenes of one shape share compiled code).
    """

    g: mpmath.mpf
    frame: Frame
    par: object


@runtime_checkable
class Track(Protocol):
    #: The scene file's track type.
    kind: ClassVar[str]
    #: Name of the generalized coordinate: phi, s or x.
    coordinate: ClassVar[str]
    closed: ClassVar[bool]
    linear_gap: ClassVar[bool]
    constant_metric: ClassVar[bool]

    def check_body(self, body: Body, field: str) -> None:
        """SceneError if ``body`` cannot roll on this track."""

    def domain(self, body: Body) -> tuple[mpmath.mpf, mpmath.mpf] | None:
        """Where the body's coordinate may go (limiters at both ends); None on a closed track."""

    def junctions(self, body: Body) -> tuple[mpmath.mpf, ...]:
        """Coordinates where one piece of the track meets the next (empty: one piece)."""

    def piece_parameters(self, body: Body, piece: int) -> tuple:
        """Runtime parameters of a body on ``piece`` (model numbers), in the order terms() reads them."""

    def terms(self, body: Body, q, v, dyn: Dynamics, piece_par) -> BodyTerms:
        """heyoka expressions; ``piece_par(k)`` is the k-th piece parameter of this body."""

    def centre(self, body: Body, q) -> tuple[np.ndarray, np.ndarray]:
        """Centre (x_C, y_C) at coordinate(s) q, float64."""

    def sigma(self, body: Body, q) -> np.ndarray:
        """|dC/dq| at coordinate(s) q, float64."""

    def describe(self) -> str:
        ...


def heyoka_library(dyn: "Dynamics"):
    """How a track's formula becomes a heyoka expression: its numbers runtime parameters (rounded once to the
    run's type from their decimal text), sin cos exp sqrt heyoka's, whole powers products."""
    from .. import expression as ex

    return ex.Library(number=lambda t: dyn.par(mpmath.mpf(t)),
                      functions={"sin": hy.sin, "cos": hy.cos, "exp": hy.exp, "sqrt": hy.sqrt},
                      whole_power=ex.power_by_products)


def lagrangian_terms(x_c, y_c, q, v, kappa, dyn: Dynamics) -> BodyTerms:
    """The default equation of motion and forces from the centre's path C(q) (see the module doc)."""
    dx, dy = _by_coordinate(x_c, q), _by_coordinate(y_c, q)
    ddx, ddy = _by_coordinate(dx, q), _by_coordinate(dy, q)
    F = dx * dx + dy * dy
    sigma = hy.sqrt(F)
    g = dyn.par(dyn.g)
    g_k = dyn.par(dyn.g / kappa)
    force = -(dx * ddx + dy * ddy) * v * v - g_k * dy
    normal = (dx * ddy - dy * ddx) * v * v + g * dx
    driving = -g * dy
    if dyn.frame.rotating:
        with workprec():
            om2, om2_k = dyn.frame.omega**2, dyn.frame.omega**2 / kappa
        arm = x_c - dyn.par(dyn.frame.axis_x)
        force = force + dyn.par(om2_k) * arm * dx
        normal = normal + dyn.par(om2) * arm * dy
        driving = driving + dyn.par(om2) * arm * dx
    return BodyTerms(x_c=x_c, y_c=y_c, acceleration=force / F, normal=normal / sigma, sigma=sigma,
                     driving=driving / sigma)


def _by_coordinate(f, q):
    """df/dq. q is a state variable, or a cluster member's coordinate psi + o (o a parameter): heyoka
    differentiates by variables only (a turning circle's cluster raised 'Derivatives are currently supported
    only with respect to variables and parameters': acceptance test), so by psi, through dq/dpsi (= 1)."""
    names = hy.get_variables(q)
    if len(names) != 1 or str(q) == names[0]:
        return hy.diff(f, q)
    psi = hy.make_vars(names[0])
    return hy.diff(f, psi) / hy.diff(q, psi)


def first_integral(track: Track, body: Body, q, dq, g, frame: Frame) -> np.ndarray:
    """H = 1/2 kappa m sigma^2 q'^2 - 1/2 m Omega^2 (x_C - a)^2 + m g y_C (paper eq. 92), float64.

    The total mechanical energy when the plane does not turn; the Jacobi
    integral of the relative motion when it does.
    """
    q, dq = np.asarray(q, dtype=float), np.asarray(dq, dtype=float)
    x_c, y_c = track.centre(body, q)
    s = track.sigma(body, q)
    m, kappa = float(body.mass), float(body.kappa)
    h = 0.5 * kappa * m * s * s * dq * dq + m * float(g) * y_c
    if frame.rotating:
        h = h - 0.5 * m * float(frame.omega) ** 2 * (x_c - float(frame.axis_x)) ** 2
    return h
