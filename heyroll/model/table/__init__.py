"""Billiards (paper section 7): boundaries, balls and impact laws of a horizontal table."""

from .boundaries import BOUNDARY_KEYS, CircleBoundary, EllipseBoundary, PolygonBoundary, RectangleBoundary
from .laws import BALL_LAWS, CUSHION_LAWS, make_ball_law, make_cushion_law
from .scene import SIMULTANEOUS_POLICIES, TableBall, TableScene, is_table

__all__ = ["BALL_LAWS", "BOUNDARY_KEYS", "CUSHION_LAWS", "CircleBoundary", "EllipseBoundary", "PolygonBoundary",
           "RectangleBoundary", "SIMULTANEOUS_POLICIES", "TableBall", "TableScene", "is_table", "make_ball_law",
           "make_cushion_law"]
