"""Ray engines for the sensors: pymunk segment queries (the reference) and a compiled kernel.

The sensors need two geometric answers (see :mod:`koolio_pymunk.sensors`):

* ``cast(x, y, angles, length)``: for each ray from ``(x, y)`` along ``angles`` (radians),
  the distance from ``(x, y)`` to the first wall segment, or ``length`` when none is hit
  within ``length``;
* ``line_of_sight(x, y, tx, ty)``: no wall segment crosses the sight line from ``(x, y)``
  to ``(tx, ty)`` (a wall whose *line* crosses it beyond the segment's ends does not block).

:class:`PymunkRays` answers with ``space.segment_query_first`` (radius 0, walls only): the
reference. :class:`FastRays` answers with numba-compiled loops over a ``(n_walls, 10)``
array (endpoints, unit normal, bounding box: :func:`wall_array`) built once per world from
pymunk's own wall shapes.

**What the kernel computes.** :func:`_first_alpha` is Chipmunk's
``cpSegmentShapeSegmentQuery`` for a segment of radius 0, operation for operation (the
same float64 expressions in the same order, with pymunk's stored unit normal), and keeps
the smallest ``alpha < 1`` over all walls, as ``cpSpaceSegmentQueryFirst`` does. Ray ends
are ``x + length * cos(angle)`` as the reference computes them, and :func:`hypot` is a
double-double ``sqrt(dx^2 + dy^2)`` that reproduces CPython's correctly rounded
``math.hypot``. Walls are culled by bounding box (they cannot be hit, so the result
does not change): first those beyond the sonar range, then, per sonar, those outside the
box of its rays (grown by 1 in).
:func:`sense_one` fuses a whole sensor reading (every sonar sub-arc ray, every camera's
arc test and line of sight, the compass) into one call; :func:`sense_batch` does it for
many robots at once.

**How it was checked.** ``tests/test_raycast.py`` compares both engines and the fused
kernel with the pymunk path on random poses in every shipped arena (identical encoded
states, distances within 1e-6 in); ``tools/agreement.py`` does it on 100k poses per
arena and prints the mismatch counts (0 on this machine; distances agreed bit for bit,
see ``docs/speed.md``). Two cases of Chipmunk's query are left out because a robot's
centre never meets them: a ray that *starts* on a wall (Chipmunk returns alpha 0) and
rays with a radius.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .world import WALL_ONLY, World

TWO_PI = 2.0 * math.pi
#: Dekker's splitting constant for float64 (2^27 + 1).
_SPLIT = 134217729.0
#: Extra reach (inches) when culling walls by bounding box: far above any rounding.
_CULL_MARGIN = 1.0
#: Columns of :func:`wall_array`.
WALL_COLUMNS = 10


def wall_array(world: World) -> np.ndarray:
    """``(n_walls, 10)`` float64 rows ``[ax, ay, bx, by, nx, ny, xmin, ymin, xmax, ymax]``
    of the world's walls (endpoints, unit normal, bounding box).

    Endpoints and unit normals are read from pymunk's shapes, so the kernel uses the very
    numbers Chipmunk uses (walls sit on the static body: world and body frames agree).
    """
    rows = [
        (
            s.a.x,
            s.a.y,
            s.b.x,
            s.b.y,
            s.normal.x,
            s.normal.y,
            min(s.a.x, s.b.x),
            min(s.a.y, s.b.y),
            max(s.a.x, s.b.x),
            max(s.a.y, s.b.y),
        )
        for s in world.walls
    ]
    return np.ascontiguousarray(np.array(rows, dtype=np.float64).reshape(-1, WALL_COLUMNS))


#: Headings whose ray directions a robot's trigonometry cache keeps (round robin). A
#: learning robot often turns back to a heading it just had: 4 catch most of them.
TRIG_SLOTS = 4


def new_trig(n_rays: int, n_robots: int | None = None) -> np.ndarray:
    """An empty trigonometry cache for :func:`sense_one` (one per robot with ``n_robots``).

    Rows ``0 .. TRIG_SLOTS - 1`` each hold a heading and the ``cos`` and ``sin`` of every
    ray at that heading; element 0 of the last row is the slot to fill next.
    """
    shape = (TRIG_SLOTS + 1, 1 + 2 * n_rays)
    if n_robots is not None:
        shape = (n_robots, *shape)
    out = np.zeros(shape)
    out[..., :TRIG_SLOTS, 0] = np.nan  # no heading cached yet (NaN equals nothing)
    return out


# -- kernels -------------------------------------------------------------------------------


@numba.njit(cache=True)
def any_near_wall(xy: np.ndarray, robots: np.ndarray, reach: float, walls: np.ndarray) -> bool:
    """Whether a wall is nearer than ``reach`` to any of the points ``xy[robots]``.

    The test of Chipmunk's nearest-point query for a segment (``cpClosetPointOnSegment``,
    distance below the query's maximum), in arena coordinates: what
    ``space.point_query_nearest`` answers for each point (up to rounding at exactly
    ``reach``), without a Python call per point. ``multi`` uses it to choose the
    sub-step of a move (``World.act``'s ``near_wall``).
    """
    for r in robots:
        px, py = xy[r, 0], xy[r, 1]
        for k in range(walls.shape[0]):
            ax, ay, bx, by = walls[k, 0], walls[k, 1], walls[k, 2], walls[k, 3]
            dx, dy = ax - bx, ay - by
            t = min(max((dx * (px - bx) + dy * (py - by)) / (dx * dx + dy * dy), 0.0), 1.0)
            cx, cy = px - (bx + dx * t), py - (by + dy * t)
            if math.sqrt(cx * cx + cy * cy) < reach:
                return True
    return False


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


@numba.njit(cache=True)
def _first_hit(
    x: float, y: float, dx: float, dy: float, walls: np.ndarray, active: np.ndarray, n: int
) -> tuple[float, int]:
    """Smallest hit fraction ``alpha < 1`` of the ray ``(x, y) + alpha * (dx, dy)`` over
    walls ``active[:n]`` and the wall hit (1.0 and -1 when none is hit). Chipmunk's
    radius-0 segment query."""
    best = 1.0
    best_k = -1
    for j in range(n):
        k = active[j]
        ax = walls[k, 0]
        ay = walls[k, 1]
        nx = walls[k, 4]
        ny = walls[k, 5]
        d = (ax - x) * nx + (ay - y) * ny
        sax = ax - x
        say = ay - y
        sbx = walls[k, 2] - x
        sby = walls[k, 3] - y
        if (dx * say - dy * sax) * (dx * sby - dy * sbx) <= 0.0:
            ad = -d
            bd = (dx * nx + dy * ny) - d
            if ad * bd < 0.0:
                t = ad / (ad - bd)
                if t < best:
                    best = t
                    best_k = k
    return best, best_k


@numba.njit(cache=True)
def _first_alpha(
    x: float, y: float, dx: float, dy: float, walls: np.ndarray, active: np.ndarray, n: int
) -> float:
    """The hit fraction of :func:`_first_hit` (1.0 when none is hit)."""
    return _first_hit(x, y, dx, dy, walls, active, n)[0]


@numba.njit(cache=True)
def _walls_in_box(
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
        if walls[k, 6] - _CULL_MARGIN > x1 or walls[k, 8] + _CULL_MARGIN < x0:
            continue
        if walls[k, 7] - _CULL_MARGIN > y1 or walls[k, 9] + _CULL_MARGIN < y0:
            continue
        active[n] = candidates[j]
        n += 1
    return n


@numba.njit(cache=True)
def _near_walls(x: float, y: float, reach: float, walls: np.ndarray, active: np.ndarray) -> int:
    """Fill ``active`` with the walls whose bounding box comes within ``reach`` of
    ``(x, y)`` in both x and y; returns how many."""
    everything = np.arange(walls.shape[0])
    return _walls_in_box(
        x - reach, y - reach, x + reach, y + reach, walls, everything, walls.shape[0], active
    )


@numba.njit(cache=True)
def _all_walls(walls: np.ndarray, active: np.ndarray) -> int:
    for j in range(walls.shape[0]):
        active[j] = j
    return walls.shape[0]


@numba.njit(cache=True)
def cast(x: float, y: float, angles: np.ndarray, length: float, walls: np.ndarray) -> np.ndarray:
    """Centre distance of the first wall along each ray (``length`` when none)."""
    active = np.empty(walls.shape[0], np.int64)
    n = _near_walls(x, y, length, walls, active)
    flat = angles.ravel()
    out = np.empty(flat.size)
    for i in range(flat.size):
        ex = x + length * math.cos(flat[i])
        ey = y + length * math.sin(flat[i])
        out[i] = _first_alpha(x, y, ex - x, ey - y, walls, active, n) * length
    return out.reshape(angles.shape)


@numba.njit(cache=True)
def line_of_sight(x: float, y: float, tx: float, ty: float, walls: np.ndarray) -> bool:
    """No wall segment between ``(x, y)`` and ``(tx, ty)`` (the reference's tolerance)."""
    dist = hypot(tx - x, ty - y)
    if dist < 1e-9:
        return True
    active = np.empty(walls.shape[0], np.int64)
    n = _all_walls(walls, active)
    alpha = _first_alpha(x, y, tx - x, ty - y, walls, active, n)
    return alpha >= 1.0 or alpha * dist >= dist - 1e-7


@numba.njit(cache=True)
def _camera(
    x: float,
    y: float,
    direction: float,
    targets: np.ndarray,
    half_arc: float,
    radius: float,
    far: float,
    walls: np.ndarray,
) -> tuple[float, int]:
    """Edge distance to the nearest target inside the arc and in sight (far, -1: none)."""
    best = far
    best_k = -1
    for k in range(targets.shape[0]):
        tx = targets[k, 0]
        ty = targets[k, 1]
        dx = tx - x
        dy = ty - y
        rel = (math.atan2(dy, dx) - direction + math.pi) % TWO_PI - math.pi
        if abs(rel) > half_arc:
            continue
        d = max(0.0, hypot(dx, dy) - radius)
        if d < best and line_of_sight(x, y, tx, ty, walls):
            best = d
            best_k = k
    return best, best_k


@numba.njit(cache=True)
def _clip(t0: float, t1: float, c0: float, c1: float) -> tuple[float, float]:
    """Narrow ``[t0, t1]`` to the ``t`` where ``c0 + t * c1 <= 0`` (empty: t0 > t1)."""
    if c1 > 0.0:
        t1 = min(t1, -c0 / c1)
    elif c1 < 0.0:
        t0 = max(t0, -c0 / c1)
    elif c0 > 0.0:
        t0 = 2.0
    return t0, t1


@numba.njit(cache=True)
def cone_nearest(
    x: float, y: float, theta: float, half: float, walls: np.ndarray, active: np.ndarray, n: int
) -> float:
    """Distance from ``(x, y)`` to the nearest wall point inside the cone of directions
    ``theta +- half`` (``half`` < 90 degrees); infinity when no wall enters the cone.

    Each wall is clipped to the cone (two half-planes through the apex) and the point of
    the clipped piece nearest to the apex is taken. That point is never hidden by another
    wall: a wall in front of it would itself have a nearer point in the cone. So this is
    the exact reading of a sonar whose every direction in the cone is a ray.
    """
    lx, ly = math.cos(theta + half), math.sin(theta + half)
    rx, ry = math.cos(theta - half), math.sin(theta - half)
    best = np.inf
    for j in range(n):
        k = active[j]
        ax = walls[k, 0] - x
        ay = walls[k, 1] - y
        dx = walls[k, 2] - walls[k, 0]
        dy = walls[k, 3] - walls[k, 1]
        # inside: right of the left edge (cross(l, p) <= 0), left of the right edge
        t0, t1 = _clip(0.0, 1.0, lx * ay - ly * ax, lx * dy - ly * dx)
        t0, t1 = _clip(t0, t1, -(rx * ay - ry * ax), -(rx * dy - ry * dx))
        if t0 > t1:
            continue
        dd = dx * dx + dy * dy
        t = -(ax * dx + ay * dy) / dd if dd > 0.0 else 0.0
        t = min(max(t, t0), t1)
        px = ax + t * dx
        py = ay + t * dy
        best = min(best, math.sqrt(px * px + py * py))
    return best


@numba.njit(cache=True)
def sense_one(
    x: float,
    y: float,
    h: float,
    ray_offsets: np.ndarray,
    params: np.ndarray,
    camera_dirs: np.ndarray,
    goal: np.ndarray,
    markers: np.ndarray,
    walls: np.ndarray,
    raw: np.ndarray,
    rays: np.ndarray,
    eow_k: np.ndarray,
    trig: np.ndarray,
    plates: np.ndarray,
    ray_cos: np.ndarray,
    decoy: np.ndarray,
) -> None:
    """One noise-free reading of every sensor of a robot at ``(x, y, h)``.

    ``params`` = ``[ray_length, radius, really_long_distance, camera_half_arc,
    sonar_model, sonar_half_arc, incidence]``; ``sonar_model`` 0 is the paper's sub-arc
    rays, 1 the exact cone (:func:`cone_nearest` around the mean of each sonar's ray
    offsets). Writes ``raw`` = sonar edge distances, goal per camera, end-of-world per
    camera, compass units (what ``SensorSuite`` noises next), ``rays`` = every sub-arc
    ray's centre distance and ``eow_k`` = the marker each camera sees (-1: none).
    For the realism models (:mod:`koolio_pymunk.realism`): with ``incidence`` 1 also
    ``ray_cos`` = the cosine of each ray's incidence on the wall it hits (0: no hit), and
    with ``plates`` not empty ``decoy`` = per camera the nearest of ``plates`` (the other
    doors' plates) in its arc and in sight (far: none).
    ``trig`` (:func:`new_trig`) caches every ray's ``cos`` and ``sin`` for the last few
    headings: moves and stops keep the heading and turns often come back to one, so few
    readings pay for the trigonometry (the values are the same either way).
    """
    length = params[0]
    radius = params[1]
    far = params[2]
    half_arc = params[3]
    n_sonar = ray_offsets.shape[0]
    n_cam = camera_dirs.shape[0]
    near = np.empty(walls.shape[0], np.int64)
    n_near = _near_walls(x, y, length, walls, near)
    if params[4] == 1.0:
        _sense_cones(x, y, h, ray_offsets, params, walls, near, n_near, raw, rays)
    else:
        directions = _ray_directions(h, ray_offsets, trig)
        _sense_sub_arcs(x, y, ray_offsets, params, walls, near, n_near, raw, rays, directions,
                        ray_cos)  # fmt: skip
    goal2 = goal.reshape(1, 2)
    for c in range(n_cam):
        direction = h + camera_dirs[c]
        raw[n_sonar + c] = _camera(x, y, direction, goal2, half_arc, radius, far, walls)[0]
        d, k = _camera(x, y, direction, markers, half_arc, radius, far, walls)
        raw[n_sonar + n_cam + c] = d
        eow_k[c] = k
        if plates.shape[0] > 0:
            decoy[c] = _camera(x, y, direction, plates, half_arc, radius, far, walls)[0]
    raw[n_sonar + 2 * n_cam] = (h / TWO_PI) * 256.0


@numba.njit(cache=True)
def _ray_directions(h: float, ray_offsets: np.ndarray, trig: np.ndarray) -> np.ndarray:
    """The row of ``trig`` holding ``cos`` and ``sin`` of every ray at heading ``h``
    (``cos(h + offset)``, as the reference computes them), filled if not cached."""
    slots = trig.shape[0] - 1
    for k in range(slots):
        if trig[k, 0] == h:
            return trig[k]
    k = int(trig[slots, 0])
    trig[slots, 0] = (k + 1) % slots
    row = trig[k]
    n_sonar, n_sub = ray_offsets.shape
    n_rays = n_sonar * n_sub
    for s in range(n_sonar):
        for i in range(n_sub):
            angle = h + ray_offsets[s, i]
            row[1 + s * n_sub + i] = math.cos(angle)
            row[1 + n_rays + s * n_sub + i] = math.sin(angle)
    row[0] = h
    return row


@numba.njit(cache=True)
def _sense_cones(
    x: float,
    y: float,
    h: float,
    ray_offsets: np.ndarray,
    params: np.ndarray,
    walls: np.ndarray,
    near: np.ndarray,
    n_near: int,
    raw: np.ndarray,
    rays: np.ndarray,
) -> None:
    """Cone model: every sonar reads its :func:`cone_nearest` (rays all get that value)."""
    length, radius, far, half = params[0], params[1], params[2], params[5]
    n_sonar, n_sub = ray_offsets.shape
    for s in range(n_sonar):
        theta = h + 0.5 * (ray_offsets[s, 0] + ray_offsets[s, n_sub - 1])
        nearest = min(cone_nearest(x, y, theta, half, walls, near, n_near), length)
        rays[s, :] = nearest
        raw[s] = far if nearest > length - 1e-9 else nearest - radius


@numba.njit(cache=True)
def _sense_sub_arcs(
    x: float,
    y: float,
    ray_offsets: np.ndarray,
    params: np.ndarray,
    walls: np.ndarray,
    near: np.ndarray,
    n_near: int,
    raw: np.ndarray,
    rays: np.ndarray,
    trig: np.ndarray,
    ray_cos: np.ndarray,
) -> None:
    """The paper's model: the nearest hit over each sonar's sub-arc rays (``trig``: one
    cache row of :func:`_ray_directions`). With ``params[6]`` 1 (the realism incidence
    model) also each ray's incidence cosine ``|cos(angle) nx + sin(angle) ny|`` on the
    wall it hits (its unit normal; 0 when nothing is hit) in ``ray_cos``."""
    length, radius, far = params[0], params[1], params[2]
    incidence = params[6] == 1.0
    n_sonar, n_sub = ray_offsets.shape
    n_rays = n_sonar * n_sub
    active = np.empty(walls.shape[0], np.int64)
    ends = np.empty((n_sub, 2))
    for s in range(n_sonar):
        x0 = x1 = x
        y0 = y1 = y
        for i in range(n_sub):
            ex = x + length * trig[1 + s * n_sub + i]
            ey = y + length * trig[1 + n_rays + s * n_sub + i]
            ends[i, 0] = ex
            ends[i, 1] = ey
            x0 = min(x0, ex)
            x1 = max(x1, ex)
            y0 = min(y0, ey)
            y1 = max(y1, ey)
        n = _walls_in_box(x0, y0, x1, y1, walls, near, n_near, active)
        nearest = np.inf
        for i in range(n_sub):
            alpha, k = _first_hit(x, y, ends[i, 0] - x, ends[i, 1] - y, walls, active, n)
            d = alpha * length
            rays[s, i] = d
            nearest = min(nearest, d)
            if incidence:
                c = trig[1 + s * n_sub + i]
                sn = trig[1 + n_rays + s * n_sub + i]
                ray_cos[s, i] = abs(c * walls[k, 4] + sn * walls[k, 5]) if k >= 0 else 0.0
        raw[s] = far if nearest > length - 1e-9 else nearest - radius


@numba.njit(cache=True)
def sense_batch(
    xs: np.ndarray,
    ys: np.ndarray,
    hs: np.ndarray,
    ray_offsets: np.ndarray,
    params: np.ndarray,
    camera_dirs: np.ndarray,
    goals: np.ndarray,
    markers: np.ndarray,
    walls: np.ndarray,
    raw: np.ndarray,
    rays: np.ndarray,
    eow_k: np.ndarray,
    trig: np.ndarray,
) -> None:
    """:func:`sense_one` for robot ``r`` at ``(xs[r], ys[r], hs[r])`` with goal
    ``goals[r]``, writing row ``r`` of ``raw``, ``rays``, ``eow_k`` and ``trig`` (the
    ideal world: ``params[6]`` must be 0, no plates)."""
    no_plates = np.empty((0, 2))
    no_cos = np.empty((0, 0))
    no_decoy = np.empty(0)
    for r in range(xs.shape[0]):
        sense_one(
            xs[r],
            ys[r],
            hs[r],
            ray_offsets,
            params,
            camera_dirs,
            goals[r],
            markers,
            walls,
            raw[r],
            rays[r],
            eow_k[r],
            trig[r],
            no_plates,
            no_cos,
            no_decoy,
        )


# -- engines -------------------------------------------------------------------------------


class PymunkRays:
    """The reference engine: one ``space.segment_query_first`` per ray (walls only)."""

    name = "pymunk"

    def __init__(self, world: World) -> None:
        self.world = world

    def cast(self, x: float, y: float, angles: np.ndarray, length: float) -> np.ndarray:
        ends_x = x + length * np.cos(angles)
        ends_y = y + length * np.sin(angles)
        query = self.world.space.segment_query_first
        out = np.full(angles.shape, length)
        start = (x, y)
        for idx in np.ndindex(angles.shape):
            hit = query(start, (float(ends_x[idx]), float(ends_y[idx])), 0.0, WALL_ONLY)
            if hit is not None:
                out[idx] = hit.alpha * length
        return out

    def cast_incidence(
        self, x: float, y: float, angles: np.ndarray, length: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`cast` and each ray's incidence cosine ``|cos(a) nx + sin(a) ny|`` on the
        wall it hits, with pymunk's reported normal (0 where nothing is hit)."""
        cos_a, sin_a = np.cos(angles), np.sin(angles)
        ends_x = x + length * cos_a
        ends_y = y + length * sin_a
        query = self.world.space.segment_query_first
        out = np.full(angles.shape, length)
        inc = np.zeros(angles.shape)
        for idx in np.ndindex(angles.shape):
            hit = query((x, y), (float(ends_x[idx]), float(ends_y[idx])), 0.0, WALL_ONLY)
            if hit is not None:
                out[idx] = hit.alpha * length
                inc[idx] = abs(cos_a[idx] * hit.normal.x + sin_a[idx] * hit.normal.y)
        return out, inc

    def line_of_sight(self, x: float, y: float, tx: float, ty: float) -> bool:
        dist = math.hypot(tx - x, ty - y)
        if dist < 1e-9:
            return True
        hit = self.world.space.segment_query_first((x, y), (tx, ty), 0.0, WALL_ONLY)
        return hit is None or hit.alpha * dist >= dist - 1e-7


class FastRays:
    """The compiled engine over the world's walls (taken once: walls never move)."""

    name = "fast"

    def __init__(self, world: World) -> None:
        self.world = world
        self.walls = wall_array(world)

    def cast(self, x: float, y: float, angles: np.ndarray, length: float) -> np.ndarray:
        return cast(float(x), float(y), np.ascontiguousarray(angles, float), length, self.walls)

    def line_of_sight(self, x: float, y: float, tx: float, ty: float) -> bool:
        return bool(line_of_sight(float(x), float(y), float(tx), float(ty), self.walls))


ENGINES = {"pymunk": PymunkRays, "fast": FastRays, "cone": FastRays}


def make_engine(name: str, world: World) -> PymunkRays | FastRays:
    """The ray engine called ``name`` (``sensors.backend``) for ``world``."""
    return ENGINES[name](world)
