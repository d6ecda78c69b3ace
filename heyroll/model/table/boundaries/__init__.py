"""Table boundaries (cushions): one file each, registered by the name a scene file gives."""

from __future__ import annotations

from .base import Boundary, sqrt, unit_normal
from .circle import CircleBoundary
from .ellipse import EllipseBoundary
from .polygon import PolygonBoundary
from .rectangle import RectangleBoundary

#: boundary = "..." in a table scene, and the keys each takes.
BOUNDARY_KEYS = {"ellipse": ("a", "b"), "rectangle": ("width", "height"), "polygon": ("vertices",),
                 "circle": ("radius",)}

__all__ = ["BOUNDARY_KEYS", "Boundary", "CircleBoundary", "EllipseBoundary", "PolygonBoundary", "RectangleBoundary",
           "sqrt", "unit_normal"]
