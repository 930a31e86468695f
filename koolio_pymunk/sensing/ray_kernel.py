"""The whole geometric reading of a robot's sensors in one compiled call.

:func:`sense_one` fuses what the sensor suite (:mod:`koolio_pymunk.sensing.suite`) asks
of the walls for one pose: every sonar sub-arc ray (or, with ``sensors.backend: cone``,
the exact nearest wall inside each sonar's cone: :func:`cone_nearest`), every camera's
arc test and line of sight to the goal plate and the end-of-world markers, and the
compass. :func:`sense_batch` does it for many robots at once. The rays are
:mod:`koolio_pymunk.world.segment_query`'s (Chipmunk's radius-0 segment query, compiled):
ray ends are ``x + length * c`` with ``(c, s)`` each ray's unit vector turned by the heading as
the reference turns it (:func:`~koolio_pymunk.sensing.suite.turned`), and walls
are culled by bounding box, first those beyond the sonar range, then, per sonar, those
outside the box of its rays (grown by 1 in); a culled wall cannot be hit.

**A shared world** (robots that are bodies to each other: :mod:`koolio_pymunk.world.physics`):
:func:`sense_among` is :func:`sense_one` with the other robots in the arena as surfaces,
given as the group ``others`` = ``(robots, present, me, ray_robot, sonar_robot)``
(:data:`~koolio_pymunk.sensing.sensor_arrays.OTHERS`): every robot's centre ``(N, 2)``,
whether it is in the arena, the reading robot's index (its own body is not seen), and
two buffers it writes, per ray the robot it hit and per sonar the robot whose surface it
read (-1: a wall, or nothing). What a robot sees of another:

* a sonar ray ends on the nearest surface, a wall or another robot's circle (radius
  ``R``): Chipmunk's radius-0 ``cpShapeSegmentQuery`` of the circle
  (:func:`~koolio_pymunk.world.segment_query.first_robot_hit`), asked after the walls
  and winning only when strictly nearer; its incidence cosine (the realism incidence
  model) is taken on the circle's normal at the hit point;
* with the cone model, the nearest point of each robot's circle inside the cone
  (:func:`cone_circle`) next to the walls' (:func:`cone_nearest`);
* a sonar's reading comes from a robot when its nearest ray (the first of its rays at
  the least distance; with the cone model, a robot strictly nearer than every wall) hit
  one within range: that robot's index goes to ``sonar_robot`` (the task floor's
  ``robot_bump``);
* another robot blocks a camera's sight line to the goal plate, a marker or another
  plate as a wall does (a radius-0 segment against its circle:
  :func:`~koolio_pymunk.world.segment_query.line_of_sight_among`).

The pymunk reference of all this is :class:`~koolio_pymunk.sensing.ray_engines.PymunkRays`
over a shared world's space; ``tests/sensing/test_shared_sensing.py`` holds the two to the
same readings bit for bit. An isolated world's readings never pass here
(:func:`sense_one` is unchanged).

**How it was checked.** ``tests/sensing/test_ray_kernel.py`` compares the fused kernel
with the pymunk path on random poses in every shipped arena (identical encoded states,
distances within 1e-6 in); ``tools/agreement.py`` does it on 100k poses per arena and
prints the mismatch counts (0 in every shipped arena: distances agree bit for bit, see
``docs/speed.md``).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ..store.kernel_cache import ensure_fresh
from ..world.segment_query import (
    CULL_MARGIN,
    circle_shape_query,
    first_hit,
    hypot,
    line_of_sight,
    line_of_sight_among,
    near_walls,
    off_the_line,
    robots_near,
    walls_in_box,
)
from .inline_twins import inline_twin

ensure_fresh()  # numba's cache, in step with every kernel's source (see there)

TWO_PI = 2.0 * math.pi


#: Headings whose ray directions a robot's trigonometry cache keeps (round robin). A
#: learning robot often turns back to a heading it just had: 4 catch most of them.
TRIG_SLOTS = 4


def new_trig(n_rays: int, n_robots: int | None = None) -> np.ndarray:
    """An empty trigonometry cache for :func:`sense_one` (one per robot with ``n_robots``).

    Rows ``0 .. TRIG_SLOTS - 1`` each hold a heading and the unit vector (``cos``, then
    ``sin``) of every ray at that heading; element 0 of the last row is the slot to fill
    next.
    """
    shape = (TRIG_SLOTS + 1, 1 + 2 * n_rays)
    if n_robots is not None:
        shape = (n_robots, *shape)
    out = np.zeros(shape)
    out[..., :TRIG_SLOTS, 0] = np.nan  # no heading cached yet (NaN equals nothing)
    return out


def new_wall_lists(walls: np.ndarray) -> np.ndarray:
    """Room for :func:`sense_one`'s two lists of walls (near the robot, near one sonar's
    rays) for the ``(n_walls, 10)`` ``walls``: working space, its contents never read
    across readings (robots read one after another may share it)."""
    return np.zeros((2, walls.shape[0]), np.int64)


# -- kernels -------------------------------------------------------------------------------


@numba.njit(cache=True, inline="always")
def _wrap(a: float) -> float:
    """``a % TWO_PI`` (Python's float modulo) without ``fmod`` for ``-TWO_PI < a < 2 *
    TWO_PI``, where it is exact: ``a`` itself, ``a + TWO_PI`` (one rounding, as Python's
    ``%`` adds it) or ``a - TWO_PI`` (exact by Sterbenz's lemma, as ``fmod`` is)."""
    if 0.0 < a < TWO_PI:
        return a
    if TWO_PI <= a < 2.0 * TWO_PI:
        return a - TWO_PI
    if -TWO_PI < a < 0.0:
        return a + TWO_PI
    return a % TWO_PI


@numba.njit(cache=True)
def camera_readings(
    x: float,
    y: float,
    h: float,
    camera_dirs: np.ndarray,
    targets: np.ndarray,
    half_arc: float,
    radius: float,
    far: float,
    walls: np.ndarray,
    dist: np.ndarray,
    which: np.ndarray,
) -> None:
    """Each camera ``c`` (direction ``h + camera_dirs[c]``): ``dist[c]`` the edge distance
    to the nearest of ``targets`` inside its arc and in sight (``far``: none), and, when
    ``which`` is not empty, ``which[c]`` that target's index (-1: none).

    Targets are taken in order and a camera keeps the first at the least distance. A
    target's bearing, distance and line of sight are the same for every camera: each is
    computed once per reading (the sight line only when a camera needs it), not once per
    camera."""
    n_cam = camera_dirs.shape[0]
    for c in range(n_cam):
        dist[c] = far
        if which.shape[0] > 0:
            which[c] = -1
    for k in range(targets.shape[0]):
        tx = targets[k, 0]
        ty = targets[k, 1]
        dx = tx - x
        dy = ty - y
        bearing = math.atan2(dy, dx)
        d = -1.0  # not computed yet
        sight = -1  # not asked yet
        for c in range(n_cam):
            direction = h + camera_dirs[c]
            rel = _wrap(bearing - direction + math.pi) - math.pi
            if abs(rel) > half_arc:
                continue
            if d < 0.0:
                d = max(0.0, hypot(dx, dy) - radius)
            if d < dist[c]:
                if sight < 0:
                    sight = 1 if line_of_sight(x, y, tx, ty, walls) else 0
                if sight == 1:
                    dist[c] = d
                    if which.shape[0] > 0:
                        which[c] = k


@numba.njit(cache=True)
def _camera_reads(x: float, y: float, h: float, cameras: tuple, goal: np.ndarray,
                  markers: np.ndarray, plates: np.ndarray, walls: np.ndarray, raw: np.ndarray,
                  n_sonar: int, eow_k: np.ndarray, decoy: np.ndarray) -> None:  # fmt: skip
    """Every camera's reading (:func:`camera_readings`, ``cameras`` = ``(camera_dirs,
    half_arc, radius, far)``): of the goal plate into ``raw[n_sonar:]``, of the
    end-of-world markers after it (the marker each sees into ``eow_k``), and with
    ``plates`` (the other doors' plates) into ``decoy``."""
    camera_dirs, half_arc, radius, far = cameras
    n_cam = camera_dirs.shape[0]
    none = eow_k[:0]
    camera_readings(x, y, h, camera_dirs, goal.reshape(1, 2), half_arc, radius, far, walls,
                    raw[n_sonar : n_sonar + n_cam], none)  # fmt: skip
    camera_readings(x, y, h, camera_dirs, markers, half_arc, radius, far, walls,
                    raw[n_sonar + n_cam : n_sonar + 2 * n_cam], eow_k)  # fmt: skip
    if plates.shape[0] > 0:
        camera_readings(x, y, h, camera_dirs, plates, half_arc, radius, far, walls, decoy, none)


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
def sense_one(x: float, y: float, h: float, geometry: tuple, goal: np.ndarray, plates: np.ndarray,
              buffers: tuple) -> None:  # fmt: skip
    """One noise-free reading of every sensor of a robot at ``(x, y, h)``.

    ``geometry`` and ``buffers`` are the groups of :mod:`koolio_pymunk.sensing.sensor_arrays`.
    ``params`` = ``[ray_length, radius, really_long_distance, camera_half_arc,
    sonar_model, sonar_half_arc, incidence]``; ``sonar_model`` 0 is the paper's sub-arc
    rays, 1 the exact cone (:func:`cone_nearest` around the mean of each sonar's ray
    offsets). Writes ``raw`` = sonar edge distances, goal per camera, end-of-world per
    camera, compass units (what ``SensorSuite`` noises next), ``rays`` = every sub-arc
    ray's centre distance and ``eow_k`` = the marker each camera sees (-1: none).
    For the realism models (:mod:`koolio_pymunk.sensing.realism`): with ``incidence`` 1 also
    ``ray_cos`` = the cosine of each ray's incidence on the wall it hits (0: no hit), and
    with ``plates`` not empty ``decoy`` = per camera the nearest of ``plates`` (the other
    doors' plates) in its arc and in sight (far: none).
    ``trig`` (:func:`new_trig`) caches every ray's unit vector for the last few headings:
    in the ideal world moves and stops keep the heading and turns often come back to one,
    so few readings turn the rays (the values are the same either way). ``wall_lists``
    (``(2, n_walls)`` int64, :func:`new_wall_lists`) is where the reading lists the walls
    near the robot and near each sonar's rays: the reading allocates nothing.
    """
    ray_offsets, ray_units, params, camera_dirs, markers, walls = geometry
    raw, rays, eow_k, trig, ray_cos, decoy, wall_lists = buffers
    length = params[0]
    radius = params[1]
    far = params[2]
    half_arc = params[3]
    n_sonar = ray_offsets.shape[0]
    n_cam = camera_dirs.shape[0]
    near = wall_lists[0]
    n_near = near_walls(x, y, length, walls, near)
    if params[4] == 1.0:
        _sense_cones(x, y, h, ray_offsets, params, walls, near, n_near, raw, rays)
    else:
        directions = _ray_directions(h, ray_units, trig)
        _sense_sub_arcs(x, y, ray_offsets, params, walls, near, n_near, raw, rays, directions,
                        ray_cos, wall_lists[1])  # fmt: skip
    cameras = (camera_dirs, half_arc, radius, far)
    _camera_reads(x, y, h, cameras, goal, markers, plates, walls, raw, n_sonar, eow_k, decoy)
    raw[n_sonar + 2 * n_cam] = (h / TWO_PI) * 256.0


@numba.njit(cache=True, inline="always")
def _ray_directions(h: float, ray_units: np.ndarray, trig: np.ndarray) -> np.ndarray:
    """The row of ``trig`` holding every ray's unit vector at heading ``h`` (``cos``s,
    then ``sin``s: ``ray_units`` turned by ``h`` as the reference
    :func:`~koolio_pymunk.sensing.suite.turned` turns them), filled if not cached."""
    slots = trig.shape[0] - 1
    for k in range(slots):
        if trig[k, 0] == h:
            return trig[k]
    k = int(trig[slots, 0])
    trig[slots, 0] = (k + 1) % slots
    row = trig[k]
    n_sonar, n_sub = ray_units.shape[1], ray_units.shape[2]
    n_rays = n_sonar * n_sub
    ch = math.cos(h)
    sh = math.sin(h)
    for s in range(n_sonar):
        for i in range(n_sub):
            c = ray_units[0, s, i]
            sn = ray_units[1, s, i]
            row[1 + s * n_sub + i] = ch * c - sh * sn
            row[1 + n_rays + s * n_sub + i] = sh * c + ch * sn
    row[0] = h
    return row


@numba.njit(cache=True, inline="always")
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


@numba.njit(cache=True, inline="always")
def _ray_end(
    x: float, y: float, s: int, i: int, n_sub: int, n_rays: int, length: float,
    trig: np.ndarray,
) -> tuple[float, float]:  # fmt: skip
    """The end of sonar ``s``'s sub-arc ray ``i`` from ``(x, y)`` (``trig``: a cache row of
    :func:`_ray_directions`)."""
    return x + length * trig[1 + s * n_sub + i], y + length * trig[1 + n_rays + s * n_sub + i]


@numba.njit(cache=True, inline="always")
def _fan_box(
    x: float, y: float, s: int, n_sub: int, n_rays: int, length: float, trig: np.ndarray
) -> tuple[float, float, float, float]:
    """The box ``(x0, y0, x1, y1)`` around the robot at ``(x, y)`` and the ends of sonar
    ``s``'s sub-arc rays (:func:`_ray_end`)."""
    x0 = x1 = x
    y0 = y1 = y
    for i in range(n_sub):
        ex, ey = _ray_end(x, y, s, i, n_sub, n_rays, length, trig)
        x0 = min(x0, ex)
        x1 = max(x1, ex)
        y0 = min(y0, ey)
        y1 = max(y1, ey)
    return x0, y0, x1, y1


@numba.njit(cache=True, inline="always")
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
    active: np.ndarray,
) -> None:
    """The paper's model: the nearest hit over each sonar's sub-arc rays (``trig``: one
    cache row of :func:`_ray_directions`; ``active``: room for the walls near a sonar's
    rays). With ``params[6]`` 1 (the realism incidence model) also each ray's incidence
    cosine ``|cos(angle) nx + sin(angle) ny|`` on the wall it hits (its unit normal; 0
    when nothing is hit) in ``ray_cos``."""
    length, radius, far = params[0], params[1], params[2]
    incidence = params[6] == 1.0
    n_sonar, n_sub = ray_offsets.shape
    n_rays = n_sonar * n_sub
    for s in range(n_sonar):
        x0, y0, x1, y1 = _fan_box(x, y, s, n_sub, n_rays, length, trig)
        n = walls_in_box(x0, y0, x1, y1, walls, near, n_near, active)
        nearest = np.inf
        for i in range(n_sub):
            ex, ey = _ray_end(x, y, s, i, n_sub, n_rays, length, trig)
            alpha, k = first_hit(x, y, ex - x, ey - y, walls, active, n)
            d = alpha * length
            rays[s, i] = d
            nearest = min(nearest, d)
            if incidence:
                c = trig[1 + s * n_sub + i]
                sn = trig[1 + n_rays + s * n_sub + i]
                ray_cos[s, i] = abs(c * walls[k, 4] + sn * walls[k, 5]) if k >= 0 else 0.0
        raw[s] = far if nearest > length - 1e-9 else nearest - radius


#: :func:`sense_one` with the calls that pass arrays compiled into it
#: (:func:`~.inline_twins.inline_twin`): for compiled callers on a hot path (this module's
#: :func:`sense_batch`, the step engine's reading, the realism kernel). The cameras stay a
#: call of :func:`camera_readings` (three per reading): inlined, their nested loops made
#: the step's first compile half as long again and 230 MB larger, for no step time measured.
sense_one_inline = inline_twin(
    sense_one, near_walls=inline_twin(near_walls), _camera_reads=inline_twin(_camera_reads)
)


@numba.njit(cache=True)
def sense_batch(
    xs: np.ndarray, ys: np.ndarray, hs: np.ndarray, geometry: tuple, goals: np.ndarray,
    raw: np.ndarray, rays: np.ndarray, eow_k: np.ndarray, trig: np.ndarray,
) -> None:  # fmt: skip
    """:func:`sense_one` for robot ``r`` at ``(xs[r], ys[r], hs[r])`` with goal
    ``goals[r]``, writing row ``r`` of ``raw``, ``rays``, ``eow_k`` and ``trig`` (the
    ideal world: ``params[6]`` must be 0, no plates)."""
    no_plates = np.empty((0, 2))
    no_cos = np.empty((0, 0))
    no_decoy = np.empty(0)
    wall_lists = np.empty((2, geometry[5].shape[0]), np.int64)
    for r in range(xs.shape[0]):
        buffers = (raw[r], rays[r], eow_k[r], trig[r], no_cos, no_decoy, wall_lists)
        sense_one_inline(xs[r], ys[r], hs[r], geometry, goals[r], no_plates, buffers)


# -- a shared world: the other robots as surfaces --------------------------------------------


@numba.njit(cache=True)
def cone_circle(
    x: float, y: float, theta: float, half: float, cx: float, cy: float, r: float
) -> float:
    """Distance from ``(x, y)`` to the nearest point of the circle of radius ``r`` at
    ``(cx, cy)`` (another robot) inside the cone ``theta +- half`` (``half`` < 90
    degrees): :func:`cone_nearest` for a circle. Infinity when the circle does not enter
    the cone, 0 when ``(x, y)`` is inside it.

    The circle's nearest point overall lies towards its centre: when the centre's
    direction is in the cone, ``|c - p| - r``. Else the distance grows away from that
    point along the circle, so the nearest point in the cone is where the circle first
    crosses an edge of the cone: ``p - sqrt(r^2 - q^2)`` along an edge ray of unit ``u``
    (``p``, ``q``: the centre's offset along and across ``u``), the smaller over the two.

    >>> cone_circle(0.0, 0.0, 0.0, 0.5, 30.0, 0.0, 10.0)                # straight ahead
    20.0
    >>> round(cone_circle(0.0, 0.0, 0.0, math.pi / 4, 30.0, 30.0, 10.0), 9)  # on an edge
    32.426406871
    >>> cone_circle(0.0, 0.0, 0.0, 0.1, 0.0, 30.0, 10.0)                # beside the cone
    inf
    """
    vx = cx - x
    vy = cy - y
    d = math.sqrt(vx * vx + vy * vy)
    if d <= r:
        return 0.0
    lx, ly = math.cos(theta + half), math.sin(theta + half)
    rx, ry = math.cos(theta - half), math.sin(theta - half)
    if lx * vy - ly * vx <= 0.0 and rx * vy - ry * vx >= 0.0:  # cone_nearest's inside
        return d - r
    best = np.inf
    for e in range(2):
        ux = lx if e == 0 else rx
        uy = ly if e == 0 else ry
        along = ux * vx + uy * vy
        across = ux * vy - uy * vx
        if along > 0.0 and across * across <= r * r:
            best = min(best, along - math.sqrt(r * r - across * across))
    return best


@numba.njit(cache=True, inline="always")
def _los_scene(x: float, y: float, tx: float, ty: float, scene: tuple) -> bool:
    """:func:`~koolio_pymunk.world.segment_query.line_of_sight_among` with its walls and
    robots as one ``scene`` = ``(walls, robots, present, me, radius)``: what
    :func:`camera_readings_among` passes where :func:`camera_readings` passes the walls."""
    walls, robots, present, me, radius = scene
    return _line_of_sight_among(x, y, tx, ty, walls, robots, present, me, radius)


_line_of_sight_among = inline_twin(line_of_sight_among)
#: :func:`camera_readings` in a shared world: the same code, compiled inline, its
#: ``walls`` argument the scene of :func:`_los_scene` (walls and other robots), so that a
#: robot blocks a sight line as a wall does.
camera_readings_among = inline_twin(camera_readings, line_of_sight=_los_scene)
_camera_reads_among = inline_twin(_camera_reads, camera_readings=camera_readings_among)


@numba.njit(cache=True, inline="always")
def _sense_cones_among(
    x: float, y: float, h: float, ray_offsets: np.ndarray, params: np.ndarray,
    walls: np.ndarray, near: np.ndarray, n_near: int, raw: np.ndarray, rays: np.ndarray,
    robots: np.ndarray, near_r: np.ndarray, n_r: int, ray_robot: np.ndarray,
    sonar_robot: np.ndarray,
) -> None:  # fmt: skip
    """:func:`_sense_cones` with the robots ``near_r[:n_r]``: a sonar reads the nearest
    of the walls' and the robots' cone distances; a robot strictly nearer than every
    wall, within range, is the reading's source."""
    length, radius, far, half = params[0], params[1], params[2], params[5]
    n_sonar, n_sub = ray_offsets.shape
    for s in range(n_sonar):
        theta = h + 0.5 * (ray_offsets[s, 0] + ray_offsets[s, n_sub - 1])
        best = cone_nearest(x, y, theta, half, walls, near, n_near)
        who = -1
        for q in range(n_r):
            j = near_r[q]
            d = cone_circle(x, y, theta, half, robots[j, 0], robots[j, 1], radius)
            if d < best:
                best = d
                who = j
        nearest = min(best, length)
        hitless = nearest > length - 1e-9
        who = -1 if hitless else who
        rays[s, :] = nearest
        ray_robot[s, :] = who
        raw[s] = far if hitless else nearest - radius
        sonar_robot[s] = who


@numba.njit(cache=True, inline="always")
def _sense_sub_arcs_among(
    x: float, y: float, ray_offsets: np.ndarray, params: np.ndarray, walls: np.ndarray,
    near: np.ndarray, n_near: int, raw: np.ndarray, rays: np.ndarray, trig: np.ndarray,
    ray_cos: np.ndarray, active: np.ndarray, robots: np.ndarray, near_r: np.ndarray, n_r: int,
    ray_robot: np.ndarray, sonar_robot: np.ndarray,
) -> None:  # fmt: skip
    """:func:`_sense_sub_arcs` with the robots ``near_r[:n_r]``: each ray's first wall,
    then the robots' circles (a robot wins when strictly nearer: the reference asks the
    static walls first); the robot each ray hit, and the one the sonar's nearest ray (the
    first at the least distance) hit, -1 for a wall, nothing, or a reading out of range.
    The incidence cosine on a robot is taken on its circle's normal. Robots are culled
    per sonar to those whose circle reaches the fan of its rays (the sonar arc is below
    180 degrees: a point no farther than ``R`` plus the cull margin from the fan), and per
    ray by their distance from its line
    (:func:`~koolio_pymunk.world.segment_query.off_the_line`), as
    :func:`~koolio_pymunk.world.segment_query.first_robot_hit` asks them."""
    length, radius, far = params[0], params[1], params[2]
    incidence = params[6] == 1.0
    n_sonar, n_sub = ray_offsets.shape
    n_rays = n_sonar * n_sub
    active_r = np.empty(n_r, np.int64)
    for s in range(n_sonar):
        x0, y0, x1, y1 = _fan_box(x, y, s, n_sub, n_rays, length, trig)
        n = walls_in_box(x0, y0, x1, y1, walls, near, n_near, active)
        # the robots whose circle reaches the fan between the first and last rays (the
        # half-planes of their lines and the one ahead, grown by R and the cull margin)
        fx = trig[1 + s * n_sub]
        fy = trig[1 + n_rays + s * n_sub]
        lx = trig[n_sub + s * n_sub]
        ly = trig[n_rays + n_sub + s * n_sub]
        grow = radius + CULL_MARGIN
        m = 0
        for q in range(n_r):
            jj = near_r[q]
            vx = robots[jj, 0] - x
            vy = robots[jj, 1] - y
            if fx * vy - fy * vx < -grow or lx * vy - ly * vx > grow:
                continue
            if (fx + lx) * vx + (fy + ly) * vy < -2.0 * grow:
                continue
            active_r[m] = jj
            m += 1
        nearest = np.inf
        who = -1
        for i in range(n_sub):
            ex, ey = _ray_end(x, y, s, i, n_sub, n_rays, length, trig)
            alpha, k = first_hit(x, y, ex - x, ey - y, walls, active, n)
            j = -1  # first_robot_hit written out: an array passed per ray costs its refcounts
            nx = 0.0
            ny = 0.0
            for q in range(m):
                jj = active_r[q]
                cx = robots[jj, 0]
                cy = robots[jj, 1]
                if off_the_line(cx - x, cy - y, ex - x, ey - y, radius):
                    continue
                hit, a, cnx, cny = circle_shape_query(cx, cy, radius, x, y, ex, ey, 0.0)
                if hit and a < alpha:
                    alpha = a
                    j = jj
                    nx = cnx
                    ny = cny
            d = alpha * length
            rays[s, i] = d
            ray_robot[s, i] = j
            if d < nearest:
                nearest = d
                who = j
            if incidence:
                c = trig[1 + s * n_sub + i]
                sn = trig[1 + n_rays + s * n_sub + i]
                if j >= 0:
                    ray_cos[s, i] = abs(c * nx + sn * ny)
                else:
                    ray_cos[s, i] = abs(c * walls[k, 4] + sn * walls[k, 5]) if k >= 0 else 0.0
        hitless = nearest > length - 1e-9
        raw[s] = far if hitless else nearest - radius
        sonar_robot[s] = -1 if hitless else who


@numba.njit(cache=True)
def sense_among(x: float, y: float, h: float, geometry: tuple, goal: np.ndarray,
                plates: np.ndarray, buffers: tuple, others: tuple) -> None:  # fmt: skip
    """:func:`sense_one` in a shared world: the other robots of ``others`` (module doc)
    are surfaces to the sonars and block the cameras' sight lines; also writes
    ``others``' ``ray_robot`` and ``sonar_robot``."""
    ray_offsets, ray_units, params, camera_dirs, markers, walls = geometry
    raw, rays, eow_k, trig, ray_cos, decoy, wall_lists = buffers
    robots, present, me, ray_robot, sonar_robot = others
    length = params[0]
    radius = params[1]
    far = params[2]
    half_arc = params[3]
    n_sonar = ray_offsets.shape[0]
    n_cam = camera_dirs.shape[0]
    near = wall_lists[0]
    n_near = near_walls(x, y, length, walls, near)
    near_r = np.empty(robots.shape[0], np.int64)
    n_r = robots_near(x, y, length + radius, robots, present, me, near_r)
    if params[4] == 1.0:
        _sense_cones_among(x, y, h, ray_offsets, params, walls, near, n_near, raw, rays, robots,
                           near_r, n_r, ray_robot, sonar_robot)  # fmt: skip
    else:
        directions = _ray_directions(h, ray_units, trig)
        _sense_sub_arcs_among(x, y, ray_offsets, params, walls, near, n_near, raw, rays,
                              directions, ray_cos, wall_lists[1], robots, near_r, n_r,
                              ray_robot, sonar_robot)  # fmt: skip
    scene = (walls, robots, present, me, radius)
    cameras = (camera_dirs, half_arc, radius, far)
    _camera_reads_among(x, y, h, cameras, goal, markers, plates, scene, raw, n_sonar, eow_k,
                        decoy)  # fmt: skip
    raw[n_sonar + 2 * n_cam] = (h / TWO_PI) * 256.0


#: :func:`sense_among` compiled into its hot callers (:func:`sense_one_inline`'s twin).
sense_among_inline = inline_twin(
    sense_among, near_walls=inline_twin(near_walls), robots_near=inline_twin(robots_near)
)
