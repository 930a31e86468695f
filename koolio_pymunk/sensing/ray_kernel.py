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
from ..world.segment_query import first_hit, hypot, line_of_sight, near_walls, walls_in_box
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


# -- kernels -------------------------------------------------------------------------------


@numba.njit(cache=True)
def camera_reading(
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
    so few readings turn the rays (the values are the same either way).
    """
    ray_offsets, ray_units, params, camera_dirs, markers, walls = geometry
    raw, rays, eow_k, trig, ray_cos, decoy = buffers
    length = params[0]
    radius = params[1]
    far = params[2]
    half_arc = params[3]
    n_sonar = ray_offsets.shape[0]
    n_cam = camera_dirs.shape[0]
    near = np.empty(walls.shape[0], np.int64)
    n_near = near_walls(x, y, length, walls, near)
    if params[4] == 1.0:
        _sense_cones(x, y, h, ray_offsets, params, walls, near, n_near, raw, rays)
    else:
        directions = _ray_directions(h, ray_units, trig)
        _sense_sub_arcs(x, y, ray_offsets, params, walls, near, n_near, raw, rays, directions,
                        ray_cos)  # fmt: skip
    goal2 = goal.reshape(1, 2)
    for c in range(n_cam):
        direction = h + camera_dirs[c]
        raw[n_sonar + c] = camera_reading(x, y, direction, goal2, half_arc, radius, far, walls)[0]
        d, k = camera_reading(x, y, direction, markers, half_arc, radius, far, walls)
        raw[n_sonar + n_cam + c] = d
        eow_k[c] = k
        if plates.shape[0] > 0:
            decoy[c] = camera_reading(x, y, direction, plates, half_arc, radius, far, walls)[0]
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
        n = walls_in_box(x0, y0, x1, y1, walls, near, n_near, active)
        nearest = np.inf
        for i in range(n_sub):
            alpha, k = first_hit(x, y, ends[i, 0] - x, ends[i, 1] - y, walls, active, n)
            d = alpha * length
            rays[s, i] = d
            nearest = min(nearest, d)
            if incidence:
                c = trig[1 + s * n_sub + i]
                sn = trig[1 + n_rays + s * n_sub + i]
                ray_cos[s, i] = abs(c * walls[k, 4] + sn * walls[k, 5]) if k >= 0 else 0.0
        raw[s] = far if nearest > length - 1e-9 else nearest - radius


#: :func:`camera_reading` and :func:`sense_one` with every call that passes arrays compiled
#: into them (:func:`~.inline_twins.inline_twin`): for compiled callers on a hot path (this
#: module's :func:`sense_batch`, the compiled episode's reading, the realism kernel).
camera_reading_inline = inline_twin(camera_reading, line_of_sight=inline_twin(line_of_sight))
sense_one_inline = inline_twin(
    sense_one, near_walls=inline_twin(near_walls), camera_reading=camera_reading_inline
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
    for r in range(xs.shape[0]):
        buffers = (raw[r], rays[r], eow_k[r], trig[r], no_cos, no_decoy)
        sense_one_inline(xs[r], ys[r], hs[r], geometry, goals[r], no_plates, buffers)


# -- engines -------------------------------------------------------------------------------
