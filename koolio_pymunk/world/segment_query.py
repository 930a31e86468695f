"""Chipmunk's segment query, compiled: the first wall a ray meets, in the walls' own numbers.

The sensors and the many-robot loop ask pymunk two geometric questions about the walls:
the first wall along a ray (``space.segment_query_first`` with radius 0) and whether a
wall is near a point (``space.point_query_nearest``). This module answers both in
numba-compiled loops over a ``(n_walls, 10)`` array (endpoints, unit normal, bounding
box: :func:`wall_array`) read once from pymunk's own wall shapes, so that the answers
are pymunk's, bit for bit:

* :func:`ray_wall` is Chipmunk's ``cpSegmentShapeSegmentQuery`` for a segment of
  radius 0, operation for operation (the same float64 expressions in the same order,
  with pymunk's stored unit normal), on scalars; :func:`first_hit` keeps the smallest
  ``alpha < 1`` over the walls as ``cpSpaceSegmentQueryFirst`` does;
* :func:`cast` and :func:`line_of_sight` are the rays of the sensors;
* :func:`hypot` is a double-double ``sqrt(dx^2 + dy^2)`` that reproduces CPython's
  correctly rounded ``math.hypot``;

Walls are culled by bounding box (:func:`walls_in_box`): a wall whose box the ray's box
does not meet cannot be hit, so the result does not change. The queries the readings
make on every step allocate nothing (their callers give the index lists), and the small
ones are compiled into their callers (``inline="always"``): an array passed across a
compiled call costs two atomic reference counts. A ray that *starts* on a
wall (Chipmunk returns alpha 0) is left out of :func:`first_hit`: a robot's centre never
is on a wall.

The query **with a radius** (a moving circle against a wall) is here too, for the swept
moves of :mod:`koolio_pymunk.world.swept_move`:

* :func:`segment_query_radius` is Chipmunk's ``cpShapeSegmentQuery`` for a thin wall and a
  query of radius ``r > 0``, operation for operation: first the nearest-point test
  (``cpSegmentShapePointQuery``, ``cpClosetPointOnSegment``: a query that starts within
  ``r`` of the wall answers alpha 0 and the normal from the nearest point), then
  ``cpSegmentShapeSegmentQuery`` (the wall's sides moved out by ``r``, and the end caps
  with ``CircleSegmentQuery``), ``cpvnormalize`` with its ``+ DBL_MIN`` and ``cpvlerp`` as
  Chipmunk writes them;
* :func:`first_contact` keeps the smallest alpha over the walls as
  ``cpSpaceSegmentQueryFirst`` does, and applies the world's rule for walls the circle
  starts touching (:meth:`koolio_pymunk.world.physics.World.first_contact`).

**Other robots** (a shared world, :mod:`koolio_pymunk.world.physics`): every robot is a
pymunk circle of the robots' radius, and a query meets it as Chipmunk's
``cpShapeSegmentQuery`` of a circle shape does (:func:`circle_shape_query`: the point
query of the start, then ``CircleSegmentQuery``). The robots are given as an ``(N, 2)``
array of centres with a flag per robot (in the arena or parked) and the index of the
robot asking (its own circle left out); nothing is allocated per query:

* :func:`robot_contact` is the moving circle's contact with the other robots, after the
  walls' (:meth:`World.robot_contact <koolio_pymunk.world.physics.World.robot_contact>`);
* :func:`first_robot_hit`, :func:`cast_among` and :func:`line_of_sight_among` are the
  sensors' rays against walls and robots, a hit's robot and normal included.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import pymunk

from ..store.kernel_cache import ensure_fresh
from .physics import ALONG, World

ensure_fresh()  # numba's cache, in step with every kernel's source (see there)

#: Dekker's splitting constant for float64 (2^27 + 1).
_SPLIT = 134217729.0


#: Extra reach (inches) when culling walls by bounding box: far above any rounding.
CULL_MARGIN = _CULL_MARGIN = 1.0


#: Chipmunk's ``CPFLOAT_MIN`` (``DBL_MIN``), added to a length before its reciprocal in
#: ``cpvnormalize``.
_DBL_MIN = 2.2250738585072014e-308


#: Columns of :func:`wall_array`.
WALL_COLUMNS = 10


def wall_row(shape: pymunk.Segment) -> tuple[float, ...]:
    """One row of :func:`wall_array`: the segment's endpoints and unit normal in world
    coordinates as Chipmunk caches them for its queries (``cpSegmentShapeCacheData``:
    ``ta``, ``tb``, ``tn``, the static body's identity transform applied with
    ``cpTransformPoint`` / ``cpTransformVect``, which can turn a -0.0 into 0.0), and its
    bounding box."""
    a, b, n = shape.a, shape.b, shape.normal
    ax = 1.0 * a.x + 0.0 * a.y + 0.0
    ay = 0.0 * a.x + 1.0 * a.y + 0.0
    bx = 1.0 * b.x + 0.0 * b.y + 0.0
    by = 0.0 * b.x + 1.0 * b.y + 0.0
    nx = 1.0 * n.x + 0.0 * n.y
    ny = 0.0 * n.x + 1.0 * n.y
    return (ax, ay, bx, by, nx, ny, min(ax, bx), min(ay, by), max(ax, bx), max(ay, by))


def wall_array(world: World, copy: int = 0) -> np.ndarray:
    """``(n_walls, 10)`` float64 rows ``[ax, ay, bx, by, nx, ny, xmin, ymin, xmax, ymax]``
    of the world's walls (endpoints, unit normal, bounding box: :func:`wall_row`): the
    arena's own, or those of robot ``copy``'s copy of the arena (shifted along x).

    The rows are read from pymunk's shapes, so the kernels use the very numbers
    Chipmunk uses.
    """
    rows = [wall_row(s) for s in world.copies[copy]]
    return np.ascontiguousarray(np.array(rows, dtype=np.float64).reshape(-1, WALL_COLUMNS))


@numba.njit(cache=True)
def _two_prod(a: float, b: float) -> tuple[float, float]:
    """``a * b`` as an exact double-double (Dekker), without fused multiply-add."""
    p = a * b
    c = _SPLIT * a
    ah = c - (c - a)
    al = a - ah
    c = _SPLIT * b
    bh = c - (c - b)
    bl = b - bh
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


@numba.njit(cache=True)
def _two_sum(a: float, b: float) -> tuple[float, float]:
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


@numba.njit(cache=True)
def hypot(dx: float, dy: float) -> float:
    """``sqrt(dx^2 + dy^2)`` with one Newton correction in double-double arithmetic.

    Matches CPython's ``math.hypot`` (itself correctly rounded in practice) on 2M random
    points; libm's ``hypot`` and the plain formula each differ in the last bit on
    0.3 % and 17 % of them.
    """
    dx = abs(dx)
    dy = abs(dy)
    p1, e1 = _two_prod(dx, dx)
    p2, e2 = _two_prod(dy, dy)
    s, es = _two_sum(p1, p2)
    lo = es + e1 + e2
    h = math.sqrt(s + lo)
    if h == 0.0:
        return 0.0
    hh, eh = _two_prod(h, h)
    r1, er = _two_sum(s, -hh)
    return h + (r1 + (er + lo - eh)) / (2.0 * h)


@numba.njit(cache=True, inline="always")
def ray_wall(
    x: float, y: float, dx: float, dy: float, ax: float, ay: float, bx: float, by: float,
    nx: float, ny: float,
) -> float:  # fmt: skip
    """The hit fraction of the ray ``(x, y) + alpha * (dx, dy)`` on the wall from ``(ax,
    ay)`` to ``(bx, by)`` with unit normal ``(nx, ny)``, when it crosses it (else
    infinity): Chipmunk's radius-0 segment query of one wall. Scalars only, so that the
    loops over walls (:func:`first_hit`, the sonars' rays) compile without reference
    counts."""
    d = (ax - x) * nx + (ay - y) * ny
    sax = ax - x
    say = ay - y
    sbx = bx - x
    sby = by - y
    if (dx * say - dy * sax) * (dx * sby - dy * sbx) <= 0.0:
        ad = -d
        bd = (dx * nx + dy * ny) - d
        if ad * bd < 0.0:
            return ad / (ad - bd)
    return math.inf


@numba.njit(cache=True, inline="always")
def first_hit(
    x: float, y: float, dx: float, dy: float, walls: np.ndarray, active: np.ndarray, n: int
) -> tuple[float, int]:
    """Smallest hit fraction ``alpha < 1`` of the ray ``(x, y) + alpha * (dx, dy)`` over
    walls ``active[:n]`` and the wall hit (1.0 and -1 when none is hit). Chipmunk's
    radius-0 segment query (:func:`ray_wall`)."""
    best = 1.0
    best_k = -1
    for j in range(n):
        k = active[j]
        t = ray_wall(x, y, dx, dy, walls[k, 0], walls[k, 1], walls[k, 2], walls[k, 3],
                     walls[k, 4], walls[k, 5])  # fmt: skip
        if t < best:
            best = t
            best_k = k
    return best, best_k


@numba.njit(cache=True, inline="always")
def first_alpha(
    x: float, y: float, dx: float, dy: float, walls: np.ndarray, active: np.ndarray, n: int
) -> float:
    """The hit fraction of :func:`first_hit` (1.0 when none is hit)."""
    return first_hit(x, y, dx, dy, walls, active, n)[0]


@numba.njit(cache=True, inline="always")
def first_alpha_all(x: float, y: float, dx: float, dy: float, walls: np.ndarray) -> float:
    """:func:`first_alpha` over every wall, in wall order (no index list to fill)."""
    best = 1.0
    for k in range(walls.shape[0]):
        t = ray_wall(x, y, dx, dy, walls[k, 0], walls[k, 1], walls[k, 2], walls[k, 3],
                     walls[k, 4], walls[k, 5])  # fmt: skip
        if t < best:
            best = t
    return best


@numba.njit(cache=True, inline="always")
def _box_meets(walls: np.ndarray, k: int, x0: float, y0: float, x1: float, y1: float) -> bool:
    """Wall ``k``'s bounding box, grown by the cull margin, meets ``[x0, x1] x [y0, y1]``."""
    if walls[k, 6] - _CULL_MARGIN > x1 or walls[k, 8] + _CULL_MARGIN < x0:
        return False
    return not (walls[k, 7] - _CULL_MARGIN > y1 or walls[k, 9] + _CULL_MARGIN < y0)


@numba.njit(cache=True, inline="always")
def walls_in_box(
    x0: float,
    y0: float,
    x1: float,
    y1: float,
    walls: np.ndarray,
    candidates: np.ndarray,
    n_candidates: int,
    active: np.ndarray,
) -> int:
    """Fill ``active`` with the walls among ``candidates[:n]`` whose bounding box meets
    the box ``[x0, x1] x [y0, y1]`` grown by the cull margin; returns how many. A ray
    lying inside the box cannot hit the others."""
    n = 0
    for j in range(n_candidates):
        k = candidates[j]
        if _box_meets(walls, k, x0, y0, x1, y1):
            active[n] = k
            n += 1
    return n


@numba.njit(cache=True)
def near_walls(x: float, y: float, reach: float, walls: np.ndarray, active: np.ndarray) -> int:
    """Fill ``active`` with the walls whose bounding box comes within ``reach`` of
    ``(x, y)`` in both x and y (:func:`walls_in_box` of every wall); returns how many."""
    n = 0
    for k in range(walls.shape[0]):
        if _box_meets(walls, k, x - reach, y - reach, x + reach, y + reach):
            active[n] = k
            n += 1
    return n


@numba.njit(cache=True)
def cast(x: float, y: float, dirs: np.ndarray, length: float, walls: np.ndarray) -> np.ndarray:
    """Centre distance of the first wall along each ray (``length`` when none); ray ``i``
    points along the unit vector ``(dirs[0][i], dirs[1][i])``."""
    active = np.empty(walls.shape[0], np.int64)
    n = near_walls(x, y, length, walls, active)
    cs = dirs[0].ravel()
    sn = dirs[1].ravel()
    out = np.empty(cs.size)
    for i in range(cs.size):
        ex = x + length * cs[i]
        ey = y + length * sn[i]
        out[i] = first_alpha(x, y, ex - x, ey - y, walls, active, n) * length
    return out.reshape(dirs[0].shape)


@numba.njit(cache=True)
def line_of_sight(x: float, y: float, tx: float, ty: float, walls: np.ndarray) -> bool:
    """No wall segment between ``(x, y)`` and ``(tx, ty)`` (the reference's tolerance)."""
    dist = hypot(tx - x, ty - y)
    if dist < 1e-9:
        return True
    alpha = first_alpha_all(x, y, tx - x, ty - y, walls)
    return alpha >= 1.0 or alpha * dist >= dist - 1e-7


# -- the query with a radius (a moving circle) ---------------------------------------------


@numba.njit(cache=True, error_model="numpy")
def _normalize(vx: float, vy: float) -> tuple[float, float]:
    """Chipmunk's ``cpvnormalize``: ``v * (1 / (|v| + DBL_MIN))`` (0 for the zero vector)."""
    inv = 1.0 / (math.sqrt(vx * vx + vy * vy) + _DBL_MIN)
    return vx * inv, vy * inv


@numba.njit(cache=True, error_model="numpy")
def circle_query(
    cx: float, cy: float, r1: float, x: float, y: float, ex: float, ey: float, r2: float
) -> tuple[bool, float, float, float]:
    """Chipmunk's ``CircleSegmentQuery``: a circle of radius ``r2`` moving from ``(x, y)``
    to ``(ex, ey)`` against a circle of radius ``r1`` at ``(cx, cy)``. Returns ``(hit,
    alpha, nx, ny)``; ``(False, 1.0, 0.0, 0.0)`` when it is not met. Divisions follow
    IEEE 754 as in C (numba's ``error_model="numpy"``): a move too short for ``qa`` to
    survive rounding gives Chipmunk's inf or NaN, not an exception."""
    dax = x - cx
    day = y - cy
    dbx = ex - cx
    dby = ey - cy
    rsum = r1 + r2
    dada = dax * dax + day * day
    dadb = dax * dbx + day * dby
    dbdb = dbx * dbx + dby * dby
    qa = dada - 2.0 * dadb + dbdb
    qb = dadb - dada
    det = qb * qb - qa * (dada - rsum * rsum)
    if det >= 0.0:
        t = (-qb - math.sqrt(det)) / qa
        if t >= 0.0 and t <= 1.0:
            s = 1.0 - t
            nx, ny = _normalize(dax * s + dbx * t, day * s + dby * t)
            return True, t, nx, ny
    return False, 1.0, 0.0, 0.0


@numba.njit(cache=True, error_model="numpy")
def segment_query_radius(
    ax: float,
    ay: float,
    bx: float,
    by: float,
    nx: float,
    ny: float,
    x: float,
    y: float,
    ex: float,
    ey: float,
    radius: float,
) -> tuple[bool, float, float, float]:
    """Chipmunk's ``cpShapeSegmentQuery`` of a circle of ``radius`` moving from ``(x, y)``
    to ``(ex, ey)`` against the thin wall ``a``-``b`` of unit normal ``n`` (pymunk's
    ``Segment.segment_query(start, end, radius)``). Returns ``(hit, alpha, nx, ny)``: the
    fraction of the move at the first contact and the unit normal from the wall towards
    the circle; a query that starts within ``radius`` of the wall answers alpha 0 and the
    normal from the wall's nearest point, whichever way it goes.
    """
    # cpSegmentShapePointQuery (cpClosetPointOnSegment) of the query's start
    ddx = ax - bx
    ddy = ay - by
    t = (ddx * (x - bx) + ddy * (y - by)) / (ddx * ddx + ddy * ddy)
    t = t if t < 1.0 else 1.0  # cpfclamp01 = cpfmax(0, cpfmin(t, 1))
    t = 0.0 if t < 0.0 else t
    px = bx + ddx * t
    py = by + ddy * t
    vx = x - px
    vy = y - py
    if math.sqrt(vx * vx + vy * vy) <= radius:
        gx, gy = _normalize(vx, vy)
        return True, 0.0, gx, gy
    # cpSegmentShapeSegmentQuery with r = seg->r + r2 = 0 + radius
    d = (ax - x) * nx + (ay - y) * ny
    r = 0.0 + radius
    fnx = -nx if d > 0.0 else nx
    fny = -ny if d > 0.0 else ny
    offx = fnx * r - x
    offy = fny * r - y
    sax = ax + offx
    say = ay + offy
    sbx = bx + offx
    sby = by + offy
    dx = ex - x
    dy = ey - y
    if (dx * say - dy * sax) * (dx * sby - dy * sbx) <= 0.0:
        d_offset = d + (-r if d > 0.0 else r)
        ad = -d_offset
        bd = (dx * nx + dy * ny) - d_offset
        if ad * bd < 0.0:
            return True, ad / (ad - bd), fnx, fny
        return False, 1.0, 0.0, 0.0
    if r != 0.0:
        hit1, t1, n1x, n1y = circle_query(ax, ay, 0.0, x, y, ex, ey, radius)
        hit2, t2, n2x, n2y = circle_query(bx, by, 0.0, x, y, ex, ey, radius)
        if t1 < t2:
            return hit1, t1, n1x, n1y
        return hit2, t2, n2x, n2y
    return False, 1.0, 0.0, 0.0


@numba.njit(cache=True)
def first_contact(
    x: float,
    y: float,
    dx: float,
    dy: float,
    radius: float,
    walls: np.ndarray,
    active: np.ndarray,
    n: int,
) -> tuple[float, float, float]:
    """The first of walls ``active[:n]`` that a circle of ``radius`` at ``(x, y)`` meets
    moving by ``(dx, dy)``: ``(alpha, nx, ny)``, ``(1.0, 0.0, 0.0)`` when none.

    :func:`segment_query_radius` for each wall in order, then :func:`circle_query` for
    each wall's ends (Chipmunk's segment query skips a wall's end caps when the query
    starts beside the wall's line past its end: the ends are discs of their own in the
    pymunk world); the smallest alpha below 1 wins, the first on a tie, as
    ``cpSpaceSegmentQueryFirst``. A wall the circle starts touching (alpha 0) is left out
    unless the move goes into it (``dx nx + dy ny < -ALONG * |d|``); an end's alpha 0
    is its wall's. :meth:`koolio_pymunk.world.physics.World.first_contact` is the
    reference.
    """
    ex = x + dx
    ey = y + dy
    length = math.sqrt(dx * dx + dy * dy)
    best = 1.0
    bnx = 0.0
    bny = 0.0
    for j in range(n):
        k = active[j]
        hit, alpha, nx, ny = segment_query_radius(
            walls[k, 0], walls[k, 1], walls[k, 2], walls[k, 3], walls[k, 4], walls[k, 5],
            x, y, ex, ey, radius,
        )  # fmt: skip
        if not hit:
            continue
        if alpha == 0.0 and dx * nx + dy * ny >= -ALONG * length:
            continue
        if alpha < best:
            best = alpha
            bnx = nx
            bny = ny
    for j in range(2 * n):
        k = active[j // 2]
        cx = walls[k, 2 * (j % 2)]
        cy = walls[k, 2 * (j % 2) + 1]
        vx = x - cx
        vy = y - cy
        if math.sqrt(vx * vx + vy * vy) - radius <= 0.0:
            continue  # cpCircleShapePointQuery: starts in the disc, alpha 0 (its wall's)
        hit, alpha, nx, ny = circle_query(cx, cy, radius, x, y, ex, ey, 0.0)
        if hit and alpha != 0.0 and alpha < best:
            best = alpha
            bnx = nx
            bny = ny
    return best, bnx, bny


# -- other robots (a shared world) ---------------------------------------------------------


@numba.njit(cache=True, error_model="numpy")
def circle_shape_query(
    cx: float, cy: float, r: float, x: float, y: float, ex: float, ey: float, radius: float
) -> tuple[bool, float, float, float]:
    """Chipmunk's ``cpShapeSegmentQuery`` of a circle shape of radius ``r`` at ``(cx,
    cy)`` (a robot's body) by a query of ``radius`` from ``(x, y)`` to ``(ex, ey)``:
    ``(hit, alpha, nx, ny)``. First ``cpCircleShapePointQuery`` of the start: within
    ``radius`` of the circle (``|start - c| - r <= radius``) it answers alpha 0 and the
    normal from the circle's nearest point towards the start (``cpvnormalize``; the
    circle's centre itself has none, 0); else :func:`circle_query` (``CircleSegmentQuery``,
    radii ``r + radius``)."""
    dx = x - cx
    dy = y - cy
    d = math.sqrt(dx * dx + dy * dy)
    r_over_d = r / d if d > 0.0 else r
    px = cx + dx * r_over_d
    py = cy + dy * r_over_d
    if d - r <= radius:
        nx, ny = _normalize(x - px, y - py)
        return True, 0.0, nx, ny
    return circle_query(cx, cy, r, x, y, ex, ey, radius)


@numba.njit(cache=True)
def robot_contact(
    x: float, y: float, dx: float, dy: float, radius: float, robots: np.ndarray,
    present: np.ndarray, me: int, box: tuple, best: float, bnx: float, bny: float,
) -> tuple[float, float, float]:  # fmt: skip
    """:func:`first_contact` continued over the other robots: the first robot ``j != me``
    with ``present[j]`` whose circle (radius ``radius``, centre ``robots[j]``) a circle of
    ``radius`` at ``(x, y)`` meets moving by ``(dx, dy)``, if it comes strictly before
    ``best`` (the walls' contact): ``(alpha, nx, ny)``.

    Each robot in index order is :func:`circle_shape_query` with the mover's radius (the
    other robot is a disc of twice the radius for the mover's centre); a robot the move
    starts touching (alpha 0) that the move does not go into (``dx nx + dy ny >= -ALONG
    * |d|``) is left out. Robots whose centre lies outside ``box`` = ``(x0, y0, x1, y1)``
    are skipped: the caller's box holds every centre the move can meet.
    :meth:`koolio_pymunk.world.physics.World.robot_contact` is the reference.
    """
    ex = x + dx
    ey = y + dy
    length = math.sqrt(dx * dx + dy * dy)
    x0, y0, x1, y1 = box
    for j in range(robots.shape[0]):
        if j == me or not present[j]:
            continue
        cx = robots[j, 0]
        cy = robots[j, 1]
        if cx < x0 or cx > x1 or cy < y0 or cy > y1:
            continue
        hit, alpha, nx, ny = circle_shape_query(cx, cy, radius, x, y, ex, ey, radius)
        if not hit:
            continue
        if alpha == 0.0 and dx * nx + dy * ny >= -ALONG * length:
            continue
        if alpha < best:
            best = alpha
            bnx = nx
            bny = ny
    return best, bnx, bny


@numba.njit(cache=True)
def robots_near(
    x: float, y: float, reach: float, robots: np.ndarray, present: np.ndarray, me: int,
    near: np.ndarray,
) -> int:  # fmt: skip
    """Fill ``near`` with the robots ``j != me`` in the arena whose centre lies within
    ``reach`` (plus the cull margin) of ``(x, y)`` in x and in y, in index order; returns
    how many. A ray of length ``L`` from ``(x, y)`` meets no robot beyond ``L + R``."""
    n = 0
    grow = reach + _CULL_MARGIN
    for j in range(robots.shape[0]):
        if j == me or not present[j]:
            continue
        if abs(robots[j, 0] - x) > grow or abs(robots[j, 1] - y) > grow:
            continue
        near[n] = j
        n += 1
    return n


@numba.njit(cache=True, inline="always")
def off_the_line(vx: float, vy: float, dx: float, dy: float, radius: float) -> bool:
    """A circle of ``radius`` centred ``(vx, vy)`` from a segment's start, the segment
    going ``(dx, dy)``: its centre lies farther than ``radius`` plus the cull margin from
    the segment's line, or that far behind its start, so no query along the segment can
    meet it (``|d|`` is bounded by ``|dx| + |dy|``, so no square root)."""
    reach = (radius + _CULL_MARGIN) * (abs(dx) + abs(dy))
    return abs(vx * dy - vy * dx) > reach or vx * dx + vy * dy < -reach


@numba.njit(cache=True)
def first_robot_hit(
    x: float, y: float, ex: float, ey: float, radius: float, robots: np.ndarray,
    near: np.ndarray, n: int, best: float,
) -> tuple[float, int, float, float]:  # fmt: skip
    """The ray from ``(x, y)`` to ``(ex, ey)`` against the circles (``radius``) of robots
    ``near[:n]``, after the walls' hit fraction ``best``: ``(alpha, robot, nx, ny)`` of the
    first robot met strictly before ``best`` (``(best, -1, 0.0, 0.0)``: none). Chipmunk's
    radius-0 ``cpShapeSegmentQuery`` of each robot's circle, in index order, as
    ``cpSpaceSegmentQueryFirst`` asks the robots' bodies after the static walls; a robot
    far off the ray's line (:func:`off_the_line`) is not asked."""
    who = -1
    bnx = 0.0
    bny = 0.0
    dx = ex - x
    dy = ey - y
    for q in range(n):
        j = near[q]
        cx = robots[j, 0]
        cy = robots[j, 1]
        if off_the_line(cx - x, cy - y, dx, dy, radius):
            continue
        hit, alpha, nx, ny = circle_shape_query(cx, cy, radius, x, y, ex, ey, 0.0)
        if hit and alpha < best:
            best = alpha
            who = j
            bnx = nx
            bny = ny
    return best, who, bnx, bny


@numba.njit(cache=True)
def cast_among(
    x: float, y: float, dirs: np.ndarray, length: float, walls: np.ndarray,
    robots: np.ndarray, present: np.ndarray, me: int, radius: float,
) -> np.ndarray:  # fmt: skip
    """:func:`cast` in a shared world: the centre distance of the first wall or other
    robot (``robots``, ``present``, ``me``: module doc) along each ray."""
    active = np.empty(walls.shape[0], np.int64)
    n = near_walls(x, y, length, walls, active)
    near = np.empty(robots.shape[0], np.int64)
    n_r = robots_near(x, y, length + radius, robots, present, me, near)
    cs = dirs[0].ravel()
    sn = dirs[1].ravel()
    out = np.empty(cs.size)
    for i in range(cs.size):
        ex = x + length * cs[i]
        ey = y + length * sn[i]
        alpha = first_alpha(x, y, ex - x, ey - y, walls, active, n)
        out[i] = first_robot_hit(x, y, ex, ey, radius, robots, near, n_r, alpha)[0] * length
    return out.reshape(dirs[0].shape)


@numba.njit(cache=True)
def line_of_sight_among(
    x: float, y: float, tx: float, ty: float, walls: np.ndarray, robots: np.ndarray,
    present: np.ndarray, me: int, radius: float,
) -> bool:  # fmt: skip
    """:func:`line_of_sight` in a shared world: no wall and no other robot in the arena
    (a circle of ``radius``) between ``(x, y)`` and ``(tx, ty)`` (the reference's
    tolerance)."""
    dist = hypot(tx - x, ty - y)
    if dist < 1e-9:
        return True
    alpha = first_alpha_all(x, y, tx - x, ty - y, walls)
    for j in range(robots.shape[0]):
        if j == me or not present[j]:
            continue
        cx = robots[j, 0]
        cy = robots[j, 1]
        if off_the_line(cx - x, cy - y, tx - x, ty - y, radius):
            continue
        hit, a, _, _ = circle_shape_query(cx, cy, radius, x, y, tx, ty, 0.0)
        if hit and a < alpha:
            alpha = a
    return alpha >= 1.0 or alpha * dist >= dist - 1e-7
