"""Small pure-Python plane geometry used to validate arenas.

Points are ``(x, y)`` tuples; polygons are sequences of points in order, closed
implicitly (the last point joins the first). Tests that could be fooled by rounding use
a tiny absolute tolerance :data:`EPS` on cross products and distances, which is ample
for arenas measured in inches.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

Point = tuple[float, float]
Polygon = Sequence[Point]

EPS = 1e-9

INSIDE = 1
BOUNDARY = 0
OUTSIDE = -1


def cross(o: Point, a: Point, b: Point) -> float:
    """The z component of ``(a - o) x (b - o)``: > 0 when o, a, b turn counter-clockwise."""
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def _sign(v: float) -> int:
    return 0 if abs(v) <= EPS else (1 if v > 0 else -1)


def polygon_area(poly: Polygon) -> float:
    """Signed area (shoelace): positive for counter-clockwise, negative for clockwise."""
    n = len(poly)
    s = 0.0
    for i in range(n):
        x0, y0 = poly[i]
        x1, y1 = poly[(i + 1) % n]
        s += x0 * y1 - x1 * y0
    return s / 2.0


def is_ccw(poly: Polygon) -> bool:
    """True when the polygon winds counter-clockwise (positive signed area)."""
    return polygon_area(poly) > 0.0


def distance_point_segment(p: Point, a: Point, b: Point) -> float:
    """Euclidean distance from ``p`` to the closed segment ``a``-``b``."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    len2 = dx * dx + dy * dy
    if len2 == 0.0:
        return math.hypot(p[0] - a[0], p[1] - a[1])
    t = ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2
    t = max(0.0, min(1.0, t))
    return math.hypot(p[0] - (a[0] + t * dx), p[1] - (a[1] + t * dy))


def point_on_segment(p: Point, a: Point, b: Point) -> bool:
    """True when ``p`` lies on the closed segment ``a``-``b`` (within :data:`EPS`)."""
    return distance_point_segment(p, a, b) <= EPS


def locate_point(p: Point, poly: Polygon) -> int:
    """:data:`INSIDE`, :data:`BOUNDARY` or :data:`OUTSIDE` of a simple polygon."""
    n = len(poly)
    inside = False
    for i in range(n):
        a, b = poly[i], poly[(i + 1) % n]
        if point_on_segment(p, a, b):
            return BOUNDARY
        if (a[1] > p[1]) != (b[1] > p[1]):
            x_at = a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1])
            if x_at > p[0]:
                inside = not inside
    return INSIDE if inside else OUTSIDE


def point_in_polygon(p: Point, poly: Polygon) -> bool:
    """True when ``p`` is strictly inside the polygon (the boundary counts as outside)."""
    return locate_point(p, poly) == INSIDE


def segments_cross(a: Point, b: Point, c: Point, d: Point) -> bool:
    """Proper intersection: the open segments cross at one point that is no endpoint."""
    d1, d2 = _sign(cross(a, b, c)), _sign(cross(a, b, d))
    d3, d4 = _sign(cross(c, d, a)), _sign(cross(c, d, b))
    return d1 * d2 < 0 and d3 * d4 < 0


def segments_intersect(a: Point, b: Point, c: Point, d: Point) -> bool:
    """True when the closed segments share any point (crossing, touching or overlapping)."""
    if segments_cross(a, b, c, d):
        return True
    return (
        point_on_segment(c, a, b)
        or point_on_segment(d, a, b)
        or point_on_segment(a, c, d)
        or point_on_segment(b, c, d)
    )


def _folds_back(shared: Point, p: Point, q: Point) -> bool:
    """Adjacent edges ``shared``-``p`` and ``shared``-``q`` overlap beyond their joint."""
    if _sign(cross(shared, p, q)) != 0:
        return False
    dot = (p[0] - shared[0]) * (q[0] - shared[0]) + (p[1] - shared[1]) * (q[1] - shared[1])
    return dot > 0.0


def polygon_self_intersection(poly: Polygon) -> tuple[int, int] | None:
    """The first pair of edge indices ``(i, j)`` that meet improperly, else None.

    Edge ``i`` runs from ``poly[i]`` to ``poly[i + 1]`` (wrapping). Non-adjacent edges
    must not share any point; adjacent edges must not fold back over each other.
    Zero-length edges (repeated consecutive points) are reported as meeting their
    neighbour.
    """
    n = len(poly)
    edges = [(poly[i], poly[(i + 1) % n]) for i in range(n)]
    for i in range(n):
        for j in range(i + 1, n):
            if _edges_meet_badly(edges, i, j, n):
                return (i, j)
    return None


def _edges_meet_badly(edges: list[tuple[Point, Point]], i: int, j: int, n: int) -> bool:
    (a, b), (c, d) = edges[i], edges[j]
    if a == b or c == d:
        return j == i + 1 or (i == 0 and j == n - 1)
    if j == i + 1 and n > 2:
        return _folds_back(b, a, d)
    if i == 0 and j == n - 1 and n > 2:
        return _folds_back(a, b, c)
    return segments_intersect(a, b, c, d)


def is_simple_polygon(poly: Polygon) -> bool:
    """At least 3 points, non-zero area and no self-intersection."""
    return (
        len(poly) >= 3 and abs(polygon_area(poly)) > EPS and polygon_self_intersection(poly) is None
    )


def disc_polygon(center: Point, radius: float, n: int = 24) -> tuple[Point, ...]:
    """A regular ``n``-gon inscribed in the circle (counter-clockwise, first point east)."""
    if n < 3:
        raise ValueError("a disc polygon needs at least 3 points")
    cx, cy = center
    return tuple(
        (cx + radius * math.cos(2 * math.pi * k / n), cy + radius * math.sin(2 * math.pi * k / n))
        for k in range(n)
    )


def polygons_intersect(p: Polygon, q: Polygon) -> tuple[int, int] | None:
    """The first pair of edge indices ``(i, j)`` (edge i of p, edge j of q) that meet."""
    np_, nq = len(p), len(q)
    for i in range(np_):
        a, b = p[i], p[(i + 1) % np_]
        for j in range(nq):
            if segments_intersect(a, b, q[j], q[(j + 1) % nq]):
                return (i, j)
    return None
