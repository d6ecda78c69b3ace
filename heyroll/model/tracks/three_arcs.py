"""The paper's three-arc track (section 5.1, Figs. 13-16).

Concave R, convex R0, concave R with central angles 3 pi/2 - beta,
pi - 2 beta, 3 pi/2 - beta, joined with continuous tangents; the hump's
centre is at the origin, so x = 0 is the axis of symmetry. An arc chain with
its own scene-file parameters.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import mpmath

from ...errors import SceneError
from .._numbers import Real, to_mpf, workprec
from .arc_chain import ArcChainTrack, Segment


@dataclass(frozen=True)
class ThreeArcTrack(ArcChainTrack):
    radius: mpmath.mpf = mpmath.mpf(1)
    hump_radius: mpmath.mpf = mpmath.mpf(1)
    beta: mpmath.mpf = mpmath.mpf(0)
    kind: ClassVar[str] = "three_arcs"

    @classmethod
    def make(cls, radius: Real, hump_radius: Real, beta: Real = 0, field: str = "track") -> "ThreeArcTrack":
        R, R0, b = (to_mpf(v) for v in (radius, hump_radius, beta))
        if not R > 0:
            raise SceneError(f"{field}.radius", f"must be > 0, got {radius}")
        if not R0 > 0:
            raise SceneError(f"{field}.hump_radius", f"must be > 0, got {hump_radius}")
        if not (0 <= b < mpmath.pi / 2):
            raise SceneError(f"{field}.beta", f"must be in [0, pi/2), got {beta}")
        with workprec():
            half = mpmath.pi / 2 - b
            d = R + R0
            segs = (
                Segment("arc", R, "concave", -mpmath.pi, half),
                Segment("arc", R0, "convex", -half, half),
                Segment("arc", R, "concave", -half, mpmath.pi),
            )
            chain = ArcChainTrack.make(segs, start_x=-d * mpmath.cos(b), start_y=d * mpmath.sin(b) + R, field=field)
        return cls(segments=chain.segments, start_x=chain.start_x, start_y=chain.start_y, radius=R,
                   hump_radius=R0, beta=b)

    def describe(self) -> str:
        return (f"three arcs R={mpmath.nstr(self.radius, 6)}, R0={mpmath.nstr(self.hump_radius, 6)}, "
                f"beta={mpmath.nstr(self.beta, 6)}")
