"""A scene on an arc chain or a curve y = f(x), possibly in a rotating plane.

Bodies are numbered 1..N in the order they sit along the track (increasing
coordinate: arc length s on an arc chain, contact abscissa x on a curve).
On such an open track, with limiters at both ends, only neighbours can touch.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Union

import mpmath
import numpy as np

from ..errors import SceneError
from ._numbers import Real, is_finite, to_mpf
from .bodies import Body
from .laws import CollisionLaw, HedrihRollingLaw
from .laws.base import check_restitution
from .paths import STATIONARY, ArcChainTrack, CurveTrack, Frame
from .scene import INCONSISTENCY_POLICIES, RunSettings

PathTrack = Union[ArcChainTrack, CurveTrack]


@dataclass(frozen=True)
class PathScene:
    track: PathTrack
    bodies: tuple[Body, ...]
    q: tuple[mpmath.mpf, ...]
    dq: tuple[mpmath.mpf, ...]
    law: CollisionLaw
    limiter_restitution: mpmath.mpf
    frame: Frame
    g: mpmath.mpf
    run: RunSettings
    name: str = "scene"
    on_inconsistent: str = "newton"
    #: two: the track guides the body on both sides (a normal force that changes
    #: sign is a warning); one: the body rests on the track and the run stops
    #: where it would leave it
    track_sides: str = "two"

    @classmethod
    def make(cls, track: PathTrack, bodies, q, dq, *, law: CollisionLaw | None = None,
             limiter_restitution: Real | None = None, frame: Frame = STATIONARY, g: Real = "9.81",
             run: RunSettings | None = None, name: str = "scene", on_inconsistent: str = "newton",
             track_sides: str = "two") -> "PathScene":
        bodies = tuple(bodies)
        if not bodies:
            raise SceneError("bodies", "at least one body is required")
        if len(q) != len(bodies) or len(dq) != len(bodies):
            raise SceneError("bodies", "one initial position and rate per body")
        law = law or HedrihRollingLaw()
        k_lim = law.restitution if limiter_restitution is None else limiter_restitution
        try:
            k_lim = check_restitution(k_lim)
        except SceneError as exc:
            raise SceneError("track.limiter_restitution", exc.rule) from None
        if not is_finite(g) or not to_mpf(g) > 0:
            raise SceneError("g", f"must be a finite number > 0, got {g}")
        if on_inconsistent not in INCONSISTENCY_POLICIES:
            raise SceneError("collision.on_inconsistent", f"unknown policy {on_inconsistent!r}; expected newton | error")
        if track_sides not in ("one", "two"):
            raise SceneError("track.sides", f"must be one or two, got {track_sides!r}")
        for n, body in enumerate(bodies, start=1):
            track.check_body(body, f"bodies[{n}]")
            if body.is_particle and law.name == "hedrih":
                raise SceneError("collision.law", "'hedrih' needs rolling bodies (r > 0); use 'newton' or 'newton_generalized'")
        q = tuple(to_mpf(v) for v in q)
        dq = tuple(to_mpf(v) for v in dq)
        scene = cls(track=track, bodies=bodies, q=q, dq=dq, law=law, limiter_restitution=k_lim, frame=frame,
                    g=to_mpf(g), run=run or RunSettings.make(), name=name, on_inconsistent=on_inconsistent,
                    track_sides=track_sides)
        scene._check_positions()
        return scene

    @property
    def coordinate(self) -> str:
        return "x" if isinstance(self.track, CurveTrack) else "s"

    def domain(self, n: int) -> tuple[float, float]:
        """Where body n's coordinate may go: [x_min, x_max] or [0, path length]."""
        if isinstance(self.track, CurveTrack):
            return float(self.track.x_min), float(self.track.x_max)
        return 0.0, self.track.path_length(self.bodies[n])

    def centre(self, n: int, q):
        """Centre (x_C, y_C) of body n at coordinate q (arrays allowed)."""
        body = self.bodies[n]
        if isinstance(self.track, CurveTrack):
            return self.track.centre(np.asarray(q, dtype=float), float(body.radius))
        pieces = self.track.pieces(body)
        q = np.asarray(q, dtype=float)
        idx = piece_index(pieces, q)
        xs, ys = np.empty(q.shape), np.empty(q.shape)
        for k, piece in enumerate(pieces):
            sel = idx == k
            if np.any(sel):
                xs[sel], ys[sel] = piece.centre(q[sel])
        return xs, ys

    def gap(self, i: int, q_i, q_j) -> np.ndarray:
        """Distance between the surfaces of bodies i and i+1 (0-based i)."""
        xi, yi = self.centre(i, q_i)
        xj, yj = self.centre(i + 1, q_j)
        return np.hypot(xj - xi, yj - yi) - float(self.bodies[i].radius + self.bodies[i + 1].radius)

    def _check_positions(self) -> None:
        for n in range(len(self.bodies)):
            lo, hi = self.domain(n)
            if not lo <= float(self.q[n]) <= hi:
                raise SceneError(f"bodies[{n + 1}].{self.coordinate}",
                                 f"must be on the track: [{lo:.17g}, {hi:.17g}], got {float(self.q[n]):.17g}")
        for n in range(len(self.bodies) - 1):
            if not self.q[n] < self.q[n + 1]:
                raise SceneError(f"bodies[{n + 2}].{self.coordinate}",
                                 "bodies must be listed in order along the track (increasing coordinate)")
            gap = float(self.gap(n, float(self.q[n]), float(self.q[n + 1])))
            if gap < 0:
                raise SceneError(f"bodies[{n + 2}].{self.coordinate}",
                                 f"body {n + 2} overlaps body {n + 1} (gap {gap:.3g} m)")


def piece_index(pieces, s) -> np.ndarray:
    """Index of the piece holding each s (a junction belongs to the piece after it)."""
    starts = np.array([p.s0 for p in pieces[1:]])
    return np.searchsorted(starts, np.asarray(s, dtype=float), side="right")
