"""Small plane geometry used to validate arenas.

Points are ``(x, y)`` tuples; polygons are sequences of points in order, closed
implicitly (the last point joins the first). Tests that could be fooled by rounding use
a tiny absolute tolerance :data:`EPS` on cross products and distances, which is ample
for arenas measured in inches.

The exact tests are plain Python. Which pairs of edges to test comes from a broad phase
(:func:`overlapping_pairs`: sort and sweep of the edges' bounding boxes in numpy), so
checking a polygon of ``n`` edges costs ``O(n log n)`` plus the pairs whose boxes overlap
(a few per edge in any sensible arena) instead of ``n^2 / 2`` exact tests. A shape whose
boxes overlap pairwise by the million is refused (:class:`TooComplex`) rather than
checked for minutes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

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
    if n > _VECTOR_FROM:
        return _locate_point_many_edges(p, poly)
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


#: Polygons with more edges than this are located in numpy (:func:`_locate_point_many_edges`).
_VECTOR_FROM = 64
_arrays: dict[int, tuple[Polygon, np.ndarray]] = {}


def _edge_array(poly: Polygon) -> np.ndarray:
    """``(n, 4)`` edges ``ax, ay, bx, by`` of ``poly``, cached for the last few polygons."""
    hit = _arrays.get(id(poly))
    if hit is not None and hit[0] is poly:
        return hit[1]
    pts = np.asarray(poly, dtype=np.float64).reshape(-1, 2)
    edges = np.hstack([pts, np.roll(pts, -1, axis=0)])
    if len(_arrays) >= 8:
        _arrays.clear()
    _arrays[id(poly)] = (poly, edges)
    return edges


def _locate_point_many_edges(p: Point, poly: Polygon) -> int:
    """:func:`locate_point` with the edges in numpy, same answer: the crossing test uses
    the same float operations, and edges numpy puts within 2 EPS of ``p`` (its hypot may
    differ from ``math.hypot`` in the last bit) are settled by :func:`point_on_segment`."""
    e = _edge_array(poly)
    px, py = float(p[0]), float(p[1])
    ax, ay, bx, by = e[:, 0], e[:, 1], e[:, 2], e[:, 3]
    dx, dy = bx - ax, by - ay
    len2 = dx * dx + dy * dy
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.clip(((px - ax) * dx + (py - ay) * dy) / len2, 0.0, 1.0)
        t = np.where(len2 == 0.0, 0.0, t)
        dist = np.hypot(px - (ax + t * dx), py - (ay + t * dy))
        for i in np.flatnonzero(dist <= 2 * EPS).tolist():
            if point_on_segment(p, (ax[i], ay[i]), (bx[i], by[i])):
                return BOUNDARY
        crosses = (ay > py) != (by > py)
        x_at = ax[crosses] + (py - ay[crosses]) * (bx[crosses] - ax[crosses]) / (
            by[crosses] - ay[crosses]
        )
    inside = int(np.count_nonzero(x_at > px)) % 2 == 1
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
    neighbour. "First" is in the order ``i``, then ``j`` (as a double loop would find it).
    """
    n = len(poly)
    edges = [(poly[i], poly[(i + 1) % n]) for i in range(n)]
    pairs = overlapping_pairs(edge_boxes(poly))
    for i, j in _may_meet(poly, poly, pairs, adjacent_in=n).tolist():
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


def polygons_intersect(p: Polygon, q: Polygon) -> tuple[int, int] | None:
    """The first pair of edge indices ``(i, j)`` (edge i of p, edge j of q) that meet."""
    np_, nq = len(p), len(q)
    for i, j in _may_meet(p, q, overlapping_pairs(edge_boxes(p), edge_boxes(q))).tolist():
        if segments_intersect(p[i], p[(i + 1) % np_], q[j], q[(j + 1) % nq]):
            return (i, j)
    return None


def _may_meet(p: Polygon, q: Polygon, pairs: np.ndarray, adjacent_in: int = 0) -> np.ndarray:
    """The pairs (edge i of p, edge j of q) that the exact tests must look at, in order.

    Computed in numpy: a proper crossing (the same float operations as
    :func:`segments_cross`) or an endpoint within 2 EPS of the other edge (a margin over
    :func:`point_on_segment`'s EPS). Pairs of neighbouring or zero-length edges of one
    polygon (``adjacent_in``: its size) always stay: their test is another one.
    """
    if len(pairs) < 64:
        return pairs
    pa = np.asarray(p, dtype=np.float64).reshape(-1, 2)
    qa = np.asarray(q, dtype=np.float64).reshape(-1, 2)
    out = []
    for start in range(0, len(pairs), 100_000):  # bounded memory
        chunk = pairs[start : start + 100_000]
        out.append(chunk[_may_meet_rows(pa, qa, chunk[:, 0], chunk[:, 1], adjacent_in)])
    return np.concatenate(out)


def _may_meet_rows(
    pa: np.ndarray, qa: np.ndarray, i: np.ndarray, j: np.ndarray, adjacent_in: int
) -> np.ndarray:
    a, b = pa[i], pa[(i + 1) % len(pa)]
    c, d = qa[j], qa[(j + 1) % len(qa)]
    d1, d2 = _signs(a, b, c), _signs(a, b, d)
    d3, d4 = _signs(c, d, a), _signs(c, d, b)
    keep = (d1 * d2 < 0) & (d3 * d4 < 0)
    for pt, s0, s1 in ((c, a, b), (d, a, b), (a, c, d), (b, c, d)):
        keep |= _distances(pt, s0, s1) <= 2 * EPS
    if adjacent_in:
        n = adjacent_in
        keep |= (j == i + 1) | ((i == 0) & (j == n - 1))
        keep |= np.all(a == b, axis=1) | np.all(c == d, axis=1)
    return keep


def _signs(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """:func:`_sign` of :func:`cross` for rows of points, the same float operations."""
    v = (a[:, 0] - o[:, 0]) * (b[:, 1] - o[:, 1]) - (a[:, 1] - o[:, 1]) * (b[:, 0] - o[:, 0])
    return np.where(np.abs(v) <= EPS, 0, np.sign(v)).astype(np.int64)


def _distances(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """:func:`distance_point_segment` for rows of points (numpy's hypot)."""
    dx, dy = b[:, 0] - a[:, 0], b[:, 1] - a[:, 1]
    len2 = dx * dx + dy * dy
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.clip(((p[:, 0] - a[:, 0]) * dx + (p[:, 1] - a[:, 1]) * dy) / len2, 0.0, 1.0)
    t = np.where(len2 == 0.0, 0.0, t)
    return np.hypot(p[:, 0] - (a[:, 0] + t * dx), p[:, 1] - (a[:, 1] + t * dy))


# -- broad phase ----------------------------------------------------------------------------
#: Most pairs of overlapping edge boxes :func:`overlapping_pairs` hands to the exact tests,
#: and most pairs overlapping in x alone it looks at (bounded time and memory).
MAX_PAIRS = 2_000_000
MAX_X_PAIRS = 100_000_000
_CHUNK = 250_000


class TooComplex(ValueError):
    """A shape whose edges' bounding boxes overlap in too many pairs to check."""


def edge_boxes(poly: Polygon) -> np.ndarray:
    """``(n, 4)`` bounding boxes ``xmin, ymin, xmax, ymax`` of the edges, grown by EPS."""
    pts = np.asarray(poly, dtype=np.float64).reshape(-1, 2)
    nxt = np.roll(pts, -1, axis=0)
    lo = np.minimum(pts, nxt) - EPS
    hi = np.maximum(pts, nxt) + EPS
    return np.hstack([lo, hi])


def overlapping_pairs(a: np.ndarray, b: np.ndarray | None = None) -> np.ndarray:
    """Pairs ``(i, j)`` of boxes of ``a`` and ``b`` that overlap (touching counts), sorted
    by ``i`` then ``j``, as a ``(k, 2)`` array.

    With ``b`` None, pairs of ``a`` with itself, ``i < j``. Every pair of edges that can
    meet is listed (a superset: the exact test decides). :class:`TooComplex` when more
    than :data:`MAX_PAIRS` pairs would be listed.

    >>> boxes = edge_boxes([(0, 0), (10, 0), (10, 10), (0, 10)])
    >>> overlapping_pairs(boxes).tolist()
    [[0, 1], [0, 3], [1, 2], [2, 3]]
    """
    self_pairs = b is None
    b = a if b is None else b
    if len(a) == 0 or len(b) == 0:
        return np.empty((0, 2), np.int64)
    # Two x intervals overlap exactly when one starts inside the other: find, for each box
    # of one set, the boxes of the other set that start within it (sorted starts), and
    # keep those whose y intervals overlap too.
    found = _starting_within(a, b) + [(i, j) for j, i in _starting_within(b, a, strict=True)]
    i = np.concatenate([p[0] for p in found]) if found else np.empty(0, np.int64)
    j = np.concatenate([p[1] for p in found]) if found else np.empty(0, np.int64)
    if self_pairs:
        i, j = np.minimum(i, j), np.maximum(i, j)
        keep = i != j
        i, j = i[keep], j[keep]
    m = len(b)
    keys = np.unique(i.astype(np.int64) * m + j)  # sorted by i, then j
    return np.stack([keys // m, keys % m], axis=1)


def _starting_within(
    a: np.ndarray, b: np.ndarray, strict: bool = False
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Index pairs ``(i, j)``, in chunks: box ``j`` of ``b`` starts (xmin) inside box ``i``
    of ``a``'s x interval (after its start when ``strict``) and their y intervals meet."""
    order = np.argsort(b[:, 0], kind="stable")
    starts = b[order, 0]
    lo = np.searchsorted(starts, a[:, 0], side="right" if strict else "left")
    hi = np.searchsorted(starts, a[:, 2], side="right")
    counts = np.maximum(hi - lo, 0)
    if int(counts.sum()) > MAX_X_PAIRS:
        raise TooComplex(f"{int(counts.sum()):,} pairs of edges overlap in x: use fewer points")
    out: list[tuple[np.ndarray, np.ndarray]] = []
    kept = 0
    ends = np.cumsum(counts)
    first = 0
    while first < len(a):  # rows [first, last) hold about _CHUNK pairs
        base = ends[first - 1] if first else 0
        last = max(first + 1, int(np.searchsorted(ends, base + _CHUNK, side="right")))
        c = counts[first:last]
        total = int(c.sum())
        i = np.repeat(np.arange(first, last), c)
        offsets = np.arange(total) - np.repeat(np.cumsum(c) - c, c)
        j = order[np.repeat(lo[first:last], c) + offsets]
        meet = (a[i, 1] <= b[j, 3]) & (b[j, 1] <= a[i, 3])
        i, j = i[meet], j[meet]
        kept += len(i)
        if kept > MAX_PAIRS:
            raise TooComplex(
                f"more than {MAX_PAIRS:,} pairs of edges overlap in their bounding boxes: "
                "use fewer points"
            )
        out.append((i, j))
        first = last
    return out
