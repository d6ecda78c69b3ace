"""A curve y = f(x) with limiters at both ends (paper section 5.3, eqs. 91-95).

The coordinate is the abscissa x of the contact point; the body rolls on top
(the left of the direction of travel, x increasing); its centre is the
contact point plus r times the unit normal (-f', 1)/sqrt(1 + f'^2).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import heyoka as hy
import mpmath
import numpy as np

from ...errors import SceneError
from .. import expression as ex
from .._numbers import Real, is_finite, to_mpf, workprec
from ..bodies import Body
from .base import BodyTerms, Dynamics, heyoka_library

NUMPY = ex.Library(number=float, functions={"sin": np.sin, "cos": np.cos, "exp": np.exp, "sqrt": np.sqrt})
MPMATH = ex.Library(number=lambda t: mpmath.mpf(t), functions={
    "sin": mpmath.sin, "cos": mpmath.cos, "exp": mpmath.exp, "sqrt": mpmath.sqrt})

#: Points at which a curve is checked (curvature, finiteness) before a run.
CURVE_CHECK_POINTS = 20001


@dataclass(frozen=True)
class CurveTrack:
    """y = f(x) on [x_min, x_max], limiters at both ends; bodies roll on top."""

    text: str
    f: ex.Node
    df: ex.Node
    d2f: ex.Node
    d3f: ex.Node
    x_min: mpmath.mpf
    x_max: mpmath.mpf
    kind: ClassVar[str] = "curve"
    coordinate: ClassVar[str] = "x"
    closed: ClassVar[bool] = False
    linear_gap: ClassVar[bool] = False
    constant_metric: ClassVar[bool] = False

    @classmethod
    def make(cls, y: str, x_min: Real, x_max: Real, field: str = "track") -> "CurveTrack":
        f = ex.parse(y, f"{field}.y")
        ex.check_differentiable(f, f"{field}.y")
        for name, value in (("x_min", x_min), ("x_max", x_max)):
            if not is_finite(value):
                raise SceneError(f"{field}.{name}", f"must be a finite number, got {value!r}")
        lo, hi = to_mpf(x_min), to_mpf(x_max)
        if not hi > lo:
            raise SceneError(f"{field}.x_max", f"must be > x_min, got x_min = {x_min}, x_max = {x_max}")
        try:
            df = ex.derivative(f)
            d2f = ex.derivative(df)
            d3f = ex.derivative(d2f)
        except (ZeroDivisionError, OverflowError, ValueError) as exc:  # constants folded while differentiating
            raise SceneError(f"{field}.y", f"cannot be evaluated: {ex.evaluation_error(exc)} (in {y!r})") from None
        track = cls(text=y, f=f, df=df, d2f=d2f, d3f=d3f, x_min=lo, x_max=hi)
        xs = track.check_grid()
        with np.errstate(all="ignore"):
            for node, what in ((f, "y"), (df, "dy/dx"), (d2f, "d2y/dx2")):
                try:
                    values = track.numeric(node, xs)
                except (ZeroDivisionError, OverflowError, ValueError) as exc:  # e.g. 1/0, 2**10000
                    raise SceneError(f"{field}.y", f"{what} cannot be evaluated on [x_min, x_max]: {ex.evaluation_error(exc)} "
                                     f"(in {y!r})") from None
                bad = ~np.isfinite(values)
                if bad.any():
                    raise SceneError(f"{field}.y", f"{what} is not finite at x = {xs[bad][0]:.17g} "
                                     f"(the curve must be smooth on [x_min, x_max])")
            pole = sign_change(f, xs)
            if pole is not None:
                raise SceneError(f"{field}.y", f"has a pole between x = {pole[0]:.17g} and {pole[1]:.17g} (a "
                                 "denominator changes sign there; a 0/0 such as sin(x)/x must be written without "
                                 "the division: the curve must be smooth on [x_min, x_max])")
        return track

    def check_grid(self) -> np.ndarray:
        return np.linspace(float(self.x_min), float(self.x_max), CURVE_CHECK_POINTS)

    def numeric(self, node: ex.Node, x):
        return numeric(node, x)

    def curvature(self, x):
        """Signed curvature f'' / (1 + f'^2)^(3/2), > 0 where the curve is concave up."""
        d1, d2 = self.numeric(self.df, x), self.numeric(self.d2f, x)
        return d2 / (1 + d1 * d1) ** 1.5

    def check_body(self, body: Body, field: str) -> None:
        """The body on top must fit every hollow: curvature radius > r (eq. 94's 1 - r k > 0)."""
        if body.radius == 0:
            return
        xs = self.check_grid()
        k = self.curvature(xs)
        n = int(np.argmax(k))
        # refine the worst point on a finer grid around it
        h = xs[1] - xs[0]
        fine = np.linspace(max(xs[0], xs[n] - h), min(xs[-1], xs[n] + h), 2001)
        kf = self.curvature(fine)
        m = int(np.argmax(kf))
        r = float(body.radius)
        if kf[m] * r >= 1:
            raise SceneError(
                f"{field}.radius",
                f"the curve's radius of curvature falls to {1 / kf[m]:.6g} m at x = {fine[m]:.6g} "
                f"(concave side), below the body's radius {r:.6g} m: it cannot roll there",
            )

    def centre_at(self, x, r: float):
        """Centre of a body of radius r touching at abscissa x (eq. 95 and its x part)."""
        d1 = self.numeric(self.df, x)
        w = np.sqrt(1 + d1 * d1)
        return x - r * d1 / w, self.numeric(self.f, x) + r / w

    # -- the Track strategy ------------------------------------------------

    def domain(self, body: Body):
        return self.x_min, self.x_max

    def junctions(self, body: Body) -> tuple:
        return ()

    def piece_parameters(self, body: Body, piece: int) -> tuple:
        return ()

    def terms(self, body: Body, q, v, dyn: Dynamics, piece_par) -> BodyTerms:
        """Eqs. (93)-(95) for any body, with F = |dC/dx|^2 of eq. (94) written out.

        The curve's numbers become runtime parameters, rounded once to the
        run's type from their decimal text.
        """
        lib = heyoka_library(dyn)
        f0, f1, f2, f3 = (_as_expression(ex.evaluate(node, q, lib)) for node in (self.f, self.df, self.d2f, self.d3f))
        g_k = dyn.par(dyn.g / body.kappa)
        g = dyn.par(dyn.g)
        w2 = 1.0 + f1 * f1
        w = hy.sqrt(w2)
        curv = f2 / (w2 * w)  # signed curvature of the track
        if body.radius:
            r = dyn.par(body.radius)
            one = 1.0 - r * curv  # |dC/dx| / |dP/dx|: > 0 by the track check
            dcurv = f3 / (w2 * w) - 3.0 * f1 * f2 * f2 / (w2 * w2 * w)
            F = w2 * one * one
            dF = 2.0 * f1 * f2 * one * one - 2.0 * r * w2 * one * dcurv
            x_c, y_c = q - r * f1 / w, f0 + r / w
        else:
            one = hy.expression(1.0)
            F, dF = w2, 2.0 * f1 * f2
            x_c, y_c = q, f0
        force = -0.5 * dF * v * v - g_k * f1 * one
        # the centre path's curvature k/(1 - r k) times the centre speed^2 F v^2, plus
        # gravity and the centrifugal force along the normal (-f', 1)/sqrt(1 + f'^2)
        normal = curv * w2 * one * v * v + g / w
        driving = -g * f1 / w
        if dyn.frame.rotating:
            with workprec():
                om2, om2_k = dyn.frame.omega**2, dyn.frame.omega**2 / body.kappa
            arm = x_c - dyn.par(dyn.frame.axis_x)
            force = force + dyn.par(om2_k) * arm * one
            normal = normal + dyn.par(om2) * arm * f1 / w
            driving = driving + dyn.par(om2) * arm / w
        return BodyTerms(x_c=x_c, y_c=y_c, acceleration=force / F, normal=normal, sigma=w * one, driving=driving)

    def sigma(self, body: Body, q):
        return np.sqrt(self.metric(q, float(body.radius)))

    def centre(self, body: Body, q):
        return self.centre_at(np.asarray(q, dtype=float), float(body.radius))

    def describe(self) -> str:
        return f"the curve y = {self.text} on [{mpmath.nstr(self.x_min, 6)}, {mpmath.nstr(self.x_max, 6)}]"

    def metric(self, x, r: float):
        """F(x, r) = (1 + f'^2)(1 - r f''/(1 + f'^2)^(3/2))^2 (eq. 94): |dC/dx|^2."""
        d1, d2 = self.numeric(self.df, x), self.numeric(self.d2f, x)
        w2 = 1 + d1 * d1
        return w2 * (1 - r * d2 / w2**1.5) ** 2


def sign_change(node: ex.Node, grid: np.ndarray):
    """(a, b), neighbours of ``grid`` between which a denominator of ``node`` changes sign (a pole the
    samples straddle: y = 1/x on [-2, 2.2] was accepted and a body ran to y = -778 m, acceptance test), or
    None."""
    for den in ex.denominators(node):
        sign = np.sign(numeric(den, grid))
        flips = np.flatnonzero(sign[:-1] * sign[1:] < 0)
        if flips.size:
            return float(grid[flips[0]]), float(grid[flips[0] + 1])
    return None


def numeric(node: ex.Node, x) -> np.ndarray:
    """A track expression's values at x (float64 array of x's shape; a constant broadcast)."""
    value = ex.evaluate(node, np.asarray(x, dtype=float), NUMPY)
    return np.broadcast_to(value, np.shape(x)).astype(float)


def _as_expression(value):
    return value if isinstance(value, hy.expression) else hy.expression(float(value))
