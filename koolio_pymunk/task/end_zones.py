"""End-of-world zones (paper §5.4.7): where an episode ends off the end of the world.

A zone is a polygon of the arena's ``end_of_world`` markers, or, for a marker without a
polygon, a disc of one robot diameter around the marker. The boundary of a polygon
counts as outside (:func:`~koolio_pymunk.world.geometry.point_in_polygon`).

>>> from koolio_pymunk.world.arena import load_arena
>>> zones = EndZones(load_arena("hallway"), radius=10.0)
>>> zones.contains(72.0, 44.0), zones.contains(-24.0, 44.0)
(False, True)
"""

from __future__ import annotations

import math

from ..world.arena import Arena
from ..world.geometry import EPS, point_in_polygon


class EndZones:
    """End-of-world zones: polygons, or discs of one robot diameter around a marker."""

    def __init__(self, arena: Arena, radius: float) -> None:
        self.polygons = [m.zone for m in arena.end_of_world if m.zone is not None]
        self.discs = [m.at for m in arena.end_of_world if m.zone is None]
        self.disc_radius = 2.0 * radius
        self.boxes = [
            (
                min(p[0] for p in poly) - EPS,
                min(p[1] for p in poly) - EPS,
                max(p[0] for p in poly) + EPS,
                max(p[1] for p in poly) + EPS,
                poly,
            )
            for poly in self.polygons
        ]
        """``(xmin, ymin, xmax, ymax, polygon)`` per polygon, grown by the boundary
        tolerance: a point outside a box is outside its polygon (no edge within EPS, and an
        even number of crossings), so the exact test runs only near a zone."""

    def contains(self, x: float, y: float) -> bool:
        """``(x, y)`` is inside an end-of-world zone (class doc: a boundary is outside)."""
        for cx, cy in self.discs:
            if math.hypot(x - cx, y - cy) <= self.disc_radius:
                return True
        for x0, y0, x1, y1, poly in self.boxes:
            if x0 <= x <= x1 and y0 <= y <= y1 and point_in_polygon((x, y), poly):
                return True
        return False
