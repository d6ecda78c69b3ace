"""Tracks as strategies of one engine (see :mod:`.base` for the protocol).

One file a track, found by its name: ``circle`` (paper section 4),
``arc_chain`` and ``three_arcs`` (section 5.1), ``curve`` (section 5.3),
``parametric`` (any curve x(u), y(u): the cycloid, an ellipse; section 2).
"""

from .arc_chain import ArcChainTrack, PathPiece, Segment, piece_index
from .base import BodyTerms, Dynamics, Track, first_integral
from .circle import CircleTrack, mechanical_energy
from .curve import CurveTrack
from .parametric import ParametricTrack
from .three_arcs import ThreeArcTrack

#: Track types by their scene-file name.
TRACK_TYPES: dict[str, type] = {t.kind: t for t in (CircleTrack, CurveTrack, ArcChainTrack, ThreeArcTrack,
                                                    ParametricTrack)}

__all__ = [
    "ArcChainTrack", "BodyTerms", "CircleTrack", "CurveTrack", "Dynamics", "ParametricTrack", "PathPiece", "Segment",
    "ThreeArcTrack", "TRACK_TYPES", "Track", "first_integral", "mechanical_energy", "piece_index",
]
