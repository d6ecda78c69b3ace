"""A curve given parametrically, x = X(u), y = Y(u), with limiters at both ends.

For tracks that are no graph y = f(x) in closed form: the cycloid
X = a (u - sin u), Y = a (1 + cos u) (the brachistochrone and tautochrone of
the paper's section 2 line of work), an ellipse X = a sin u, Y = -b cos u,
loops. The coordinate is the parameter u of the contact point P(u); the body
rolls on the left of the direction of travel (u increasing: on top where X
increases), its centre C = P + r n, n = (-Y', X')/|P'| the left normal. With the
track's signed curvature k = (X' Y'' - Y' X'')/|P'|^3 (> 0 where it turns
left, towards the body), dC/du = P' (1 - r k), so sigma = |P'| (1 - r k); the
equation of motion and the forces are the Lagrangian ones of
:func:`heyroll.model.tracks.base.lagrangian_terms` from C(u).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import heyoka as hy
import mpmath
import numpy as np

from ...errors import SceneError
from .. import expression as ex
from .._numbers import Real, is_finite, to_mpf
from ..bodies import Body
from .base import BodyTerms, Dynamics, heyoka_library, lagrangian_terms
from .curve import CURVE_CHECK_POINTS, _as_expression, numeric, sign_change


@dataclass(frozen=True)
class ParametricTrack:
    """x = X(u), y = Y(u) on [u_min, u_max], limiters at both ends; bodies on the left of increasing u."""

    text: str  # "X(u); Y(u)": what the compiled code depends on
    fx: ex.Node
    fy: ex.Node
    dfx: ex.Node
    dfy: ex.Node
    d2fx: ex.Node
    d2fy: ex.Node
    u_min: mpmath.mpf
    u_max: mpmath.mpf
    kind: ClassVar[str] = "parametric"
    coordinate: ClassVar[str] = "u"
    closed: ClassVar[bool] = False
    linear_gap: ClassVar[bool] = False
    constant_metric: ClassVar[bool] = False

    @classmethod
    def make(cls, x: str, y: str, u_min: Real, u_max: Real, field: str = "track") -> "ParametricTrack":
        nodes = {}
        for name, text in (("x", x), ("y", y)):
            node = ex.parse(text, f"{field}.{name}", variable="u")
            ex.check_differentiable(node, f"{field}.{name}")
            try:
                d1 = ex.derivative(node)
                nodes[name] = (node, d1, ex.derivative(d1))
            except (ZeroDivisionError, OverflowError, ValueError) as exc:
                raise SceneError(f"{field}.{name}", f"cannot be evaluated: {ex.evaluation_error(exc)} (in {text!r})") from None
        for name, value in (("u_min", u_min), ("u_max", u_max)):
            if not is_finite(value):
                raise SceneError(f"{field}.{name}", f"must be a finite number, got {value!r}")
        lo, hi = to_mpf(u_min), to_mpf(u_max)
        if not hi > lo:
            raise SceneError(f"{field}.u_max", f"must be > u_min, got u_min = {u_min}, u_max = {u_max}")
        track = cls(text=f"{x}; {y}", fx=nodes["x"][0], fy=nodes["y"][0], dfx=nodes["x"][1], dfy=nodes["y"][1],
                    d2fx=nodes["x"][2], d2fy=nodes["y"][2], u_min=lo, u_max=hi)
        us = track.check_grid()
        with np.errstate(all="ignore"):
            for node, what in ((track.fx, "x"), (track.fy, "y"), (track.dfx, "dx/du"), (track.dfy, "dy/du"),
                               (track.d2fx, "d2x/du2"), (track.d2fy, "d2y/du2")):
                try:
                    values = track.numeric(node, us)
                except (ZeroDivisionError, OverflowError, ValueError) as exc:
                    raise SceneError(f"{field}.{what[-1]}", f"{what} cannot be evaluated on [u_min, u_max]: "
                                     f"{ex.evaluation_error(exc)}") from None
                bad = ~np.isfinite(values)
                if bad.any():
                    raise SceneError(f"{field}.{'x' if 'x' in what else 'y'}",
                                     f"{what} is not finite at u = {us[bad][0]:.17g} (the curve must be smooth)")
            for node, name in ((track.fx, "x"), (track.fy, "y")):
                pole = sign_change(node, us)
                if pole is not None:
                    raise SceneError(f"{field}.{name}", f"has a pole between u = {pole[0]:.17g} and {pole[1]:.17g} "
                                     "(a denominator changes sign there; a 0/0 must be written without the division: "
                                     "the curve must be smooth)")
            x1, y1 = track.numeric(track.dfx, us), track.numeric(track.dfy, us)
            speed = np.hypot(x1, y1)
        # a cusp between samples: |dP/du| passes through 0 and the tangent turns back (x = cos^2 u, y = sin u at
        # u = 3 pi/2 was accepted and failed mid-run: acceptance test)
        back = np.flatnonzero(x1[:-1] * x1[1:] + y1[:-1] * y1[1:] <= 0)
        if not np.all(speed > 1e-12 * max(1.0, float(np.max(speed)))):
            n = int(np.argmin(speed))
            raise SceneError(f"{field}.u_min", f"the curve stops (|dP/du| = 0) at u = {us[n]:.17g}: a cusp or a "
                             "corner; keep [u_min, u_max] where it is regular")
        if back.size:
            n = int(back[0])
            raise SceneError(f"{field}.u_min", f"the tangent turns back between u = {us[n]:.17g} and "
                             f"{us[n + 1]:.17g}: a cusp (|dP/du| = 0), or the curve turns more than a quarter turn "
                             f"between the check's {CURVE_CHECK_POINTS} samples (a shorter [u_min, u_max])")
        return track

    def check_grid(self) -> np.ndarray:
        return np.linspace(float(self.u_min), float(self.u_max), CURVE_CHECK_POINTS)

    def numeric(self, node: ex.Node, u):
        return numeric(node, u)

    def curvature(self, u):
        """Signed curvature (X' Y'' - Y' X'')/|P'|^3, > 0 where the track turns towards the body."""
        x1, y1 = self.numeric(self.dfx, u), self.numeric(self.dfy, u)
        x2, y2 = self.numeric(self.d2fx, u), self.numeric(self.d2fy, u)
        return (x1 * y2 - y1 * x2) / np.hypot(x1, y1) ** 3

    def check_body(self, body: Body, field: str) -> None:
        """The body must fit every hollow on its side: radius of curvature > r (1 - r k > 0)."""
        if body.radius == 0:
            return
        us = self.check_grid()
        k = self.curvature(us)
        n = int(np.argmax(k))
        if k[n] * float(body.radius) >= 1:
            raise SceneError(f"{field}.radius", f"the curve's radius of curvature falls to {1 / k[n]:.6g} m at "
                             f"u = {us[n]:.6g}, below the body's radius {float(body.radius):.6g} m: it cannot roll there")

    # -- the Track strategy ------------------------------------------------

    def domain(self, body: Body):
        return self.u_min, self.u_max

    def junctions(self, body: Body) -> tuple:
        return ()

    def piece_parameters(self, body: Body, piece: int) -> tuple:
        return ()

    def terms(self, body: Body, q, v, dyn: Dynamics, piece_par) -> BodyTerms:
        lib = heyoka_library(dyn)
        x, y = (_as_expression(ex.evaluate(node, q, lib)) for node in (self.fx, self.fy))
        if body.radius:
            x1, y1 = (_as_expression(ex.evaluate(node, q, lib)) for node in (self.dfx, self.dfy))
            r_over = dyn.par(body.radius) / hy.sqrt(x1 * x1 + y1 * y1)
            x, y = x - r_over * y1, y + r_over * x1
        return lagrangian_terms(x, y, q, v, body.kappa, dyn)

    def centre(self, body: Body, q):
        u = np.asarray(q, dtype=float)
        x, y = self.numeric(self.fx, u), self.numeric(self.fy, u)
        r = float(body.radius)
        if r:
            x1, y1 = self.numeric(self.dfx, u), self.numeric(self.dfy, u)
            w = np.hypot(x1, y1)
            x, y = x - r * y1 / w, y + r * x1 / w
        return x, y

    def sigma(self, body: Body, q):
        u = np.asarray(q, dtype=float)
        speed = np.hypot(self.numeric(self.dfx, u), self.numeric(self.dfy, u))
        return speed * np.abs(1 - float(body.radius) * self.curvature(u))

    def describe(self) -> str:
        return (f"the curve x(u), y(u) = {self.text} on u in "
                f"[{mpmath.nstr(self.u_min, 6)}, {mpmath.nstr(self.u_max, 6)}]")

