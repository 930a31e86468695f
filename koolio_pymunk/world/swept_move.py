"""A robot's move against the walls, compiled: the pymunk world's swept move without Python.

:meth:`koolio_pymunk.world.physics.World.shift` moves a robot as a swept circle, asking
pymunk (Chipmunk) for each contact; :func:`sweep` here is the same move in one numba
call, for compiled loops that move robots themselves (the step engine's):

* the same steps in the same floating-point operations (contact, push-out by
  :data:`~koolio_pymunk.world.physics.SKIN`, the rest projected on the wall's tangent,
  at most :data:`~koolio_pymunk.world.physics.MAX_QUERIES` queries, a slide back into the
  wall met before or shorter than :data:`~koolio_pymunk.world.physics.MIN_SLIDE` ending
  the move) as :func:`koolio_pymunk.world.physics.sweep`;
* each contact from :func:`koolio_pymunk.world.segment_query.first_contact`, Chipmunk's
  segment query with the robot's radius written out operation for operation, on the
  walls pymunk holds (:func:`~koolio_pymunk.world.segment_query.wall_array`);
* walls are culled once per move to those whose box comes within the move's length plus
  the radius of the start (no position of the move is farther: slides are projections,
  never longer than what remains), which cannot change the answer.

:func:`move` is a Forward / Reverse of ``distance`` along ``heading``, as
:meth:`~koolio_pymunk.world.physics.World.move` computes it; :func:`act` is any of the
five actions, with a real drive's errors when they are on, as
:meth:`~koolio_pymunk.world.physics.World.act` and
:meth:`~koolio_pymunk.world.physics.World.drive` (with
:class:`~koolio_pymunk.world.motion_errors.MotionErrors`' draws) leave the robot.
``tests/world/test_segment_query.py`` and ``tools/agreement.py --moves N`` hold both to
pymunk's answers: the same end position, bit for bit, over random moves in every shipped
arena and in generated ones.

**A shared world** (robots that are bodies to each other): :func:`sweep_among`,
:func:`move_among` and :func:`act_among` are the same moves against the walls *and* the
other robots in the arena, :meth:`World.shift
<koolio_pymunk.world.physics.World.shift>` of a shared world bit for bit. The robots come
as ``robots`` (``(N, 2)`` float64: every robot's centre, the mover's own row included and
ignored), ``present`` (``(N,)`` bool: in the arena; a parked robot is no obstacle) and
``me`` (the mover's index); nothing is allocated for them, and a robot is asked only
when its centre lies within the move's reach plus twice the radius of the start
(:func:`~koolio_pymunk.world.segment_query.robot_contact`). The push-out, the slide and
the corner rule are :func:`sweep`'s own code (:func:`_slide`). A rescue's Reverse is
``move_among(..., -distance, ...)``.

Example::

    >>> from koolio_pymunk.world.physics import World
    >>> from koolio_pymunk.world.segment_query import wall_array
    >>> w = World([((0, 0), (100, 0)), ((100, 0), (100, 100)),
    ...            ((100, 100), (0, 100)), ((0, 100), (0, 0))], radius=10)
    >>> walls = wall_array(w)
    >>> move(walls, 50.0, 50.0, 0.0, 12.0, 10.0)
    (62.0, 50.0)
    >>> x, y = move(walls, 85.0, 50.0, 0.0, 12.0, 10.0)     # stops tangent to x = 100
    >>> w.place(0, (85.0, 50.0), 0.0); w.move(0, 12.0)
    >>> (x, y) == w.pose()[:2], round(x, 6)
    (True, 90.0)
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ..store.kernel_cache import ensure_fresh
from .physics import ALONG, MAX_QUERIES, MIN_SLIDE, SKIN, TWO_PI
from .segment_query import _CULL_MARGIN, first_contact, robot_contact

ensure_fresh()  # numba's cache, in step with every kernel's source (see there)

# numba bakes these module-level constants into the compiled (and disk-cached) code; the
# cache is keyed on this file, so a change of them in physics.py needs this file touched
# (or the __pycache__ cleared). The agreement tests catch a stale cache.


@numba.njit(cache=True)
def _walls_near(x: float, y: float, reach: float, walls: np.ndarray, active: np.ndarray) -> int:
    """Fill ``active`` with the walls whose box comes within ``reach`` (plus the cull
    margin) of ``(x, y)`` in x and in y, in wall order; returns how many."""
    x0 = x - reach - _CULL_MARGIN
    x1 = x + reach + _CULL_MARGIN
    y0 = y - reach - _CULL_MARGIN
    y1 = y + reach + _CULL_MARGIN
    n = 0
    for k in range(walls.shape[0]):
        if walls[k, 6] > x1 or walls[k, 8] < x0 or walls[k, 7] > y1 or walls[k, 9] < y0:
            continue
        active[n] = k
        n += 1
    return n


@numba.njit(cache=True, inline="always")
def _slide(
    x: float, y: float, dx: float, dy: float, alpha: float, nx: float, ny: float, k: int,
    pnx: float, pny: float,
) -> tuple[float, float, float, float, bool]:  # fmt: skip
    """One contact of a sweep: the robot goes ``alpha`` of the move and :data:`SKIN`
    along the normal ``n``; the rest, its normal part removed, is the next move. Returns
    ``(x, y, rest x, rest y, go on)``: a slide shorter than :data:`MIN_SLIDE` or (after
    the first query, ``k > 0``) back into the contact met before (normal ``pn``) ends the
    move."""
    x = x + alpha * dx + SKIN * nx
    y = y + alpha * dy + SKIN * ny
    rest = 1.0 - alpha
    rx = rest * dx
    ry = rest * dy
    dn = rx * nx + ry * ny
    rx = rx - dn * nx
    ry = ry - dn * ny
    slide = math.sqrt(rx * rx + ry * ry)
    if slide < MIN_SLIDE:
        return x, y, rx, ry, False
    if k > 0 and rx * pnx + ry * pny < -ALONG * slide:
        return x, y, rx, ry, False
    return x, y, rx, ry, True


@numba.njit(cache=True)
def sweep(
    walls: np.ndarray, x: float, y: float, dx: float, dy: float, radius: float
) -> tuple[float, float]:
    """Where a robot of ``radius`` at ``(x, y)`` ends after a move by ``(dx, dy)`` against
    ``walls`` (:func:`~koolio_pymunk.world.segment_query.wall_array`): stopped by the
    first wall, sliding along it. :func:`koolio_pymunk.world.physics.sweep` with the
    walls' pymunk queries, bit for bit."""
    return sweep_in(walls, x, y, dx, dy, radius, np.empty(walls.shape[0], np.int64))


@numba.njit(cache=True)
def sweep_in(
    walls: np.ndarray, x: float, y: float, dx: float, dy: float, radius: float,
    active: np.ndarray,
) -> tuple[float, float]:  # fmt: skip
    """:func:`sweep` with ``active`` as room for the list of walls near the move
    (``n_walls`` int64): the steps' moves allocate nothing (:func:`world_group`)."""
    n = _walls_near(x, y, abs(dx) + abs(dy) + radius, walls, active)
    pnx = 0.0
    pny = 0.0
    for k in range(MAX_QUERIES):
        if dx == 0.0 and dy == 0.0:
            break
        alpha, nx, ny = first_contact(x, y, dx, dy, radius, walls, active, n)
        if alpha >= 1.0:
            return x + dx, y + dy
        x, y, dx, dy, more = _slide(x, y, dx, dy, alpha, nx, ny, k, pnx, pny)
        if not more:
            break
        pnx = nx
        pny = ny
    return x, y


@numba.njit(cache=True)
def sweep_among(
    walls: np.ndarray, robots: np.ndarray, present: np.ndarray, me: int, x: float, y: float,
    dx: float, dy: float, radius: float,
) -> tuple[float, float]:  # fmt: skip
    """:func:`sweep` of robot ``me`` in a shared world: stopped by the first wall or
    other robot in the arena (``robots``, ``present``: the module doc), sliding along it.
    A shared :class:`~koolio_pymunk.world.physics.World`'s :meth:`shift`, bit for bit."""
    active = np.empty(walls.shape[0], np.int64)
    reach = abs(dx) + abs(dy) + radius
    n = _walls_near(x, y, reach, walls, active)
    grow = reach + radius + _CULL_MARGIN  # a robot met is 2R from a point of the move
    box = (x - grow, y - grow, x + grow, y + grow)
    pnx = 0.0
    pny = 0.0
    for k in range(MAX_QUERIES):
        if dx == 0.0 and dy == 0.0:
            break
        alpha, nx, ny = first_contact(x, y, dx, dy, radius, walls, active, n)
        alpha, nx, ny = robot_contact(x, y, dx, dy, radius, robots, present, me, box, alpha,
                                      nx, ny)  # fmt: skip
        if alpha >= 1.0:
            return x + dx, y + dy
        x, y, dx, dy, more = _slide(x, y, dx, dy, alpha, nx, ny, k, pnx, pny)
        if not more:
            break
        pnx = nx
        pny = ny
    return x, y


@numba.njit(cache=True)
def move(
    walls: np.ndarray, x: float, y: float, heading: float, distance: float, radius: float
) -> tuple[float, float]:
    """A robot of ``radius`` at ``(x, y)`` moves ``distance`` inches along ``heading``
    (radians; a negative distance backs up): its end position, as
    :meth:`~koolio_pymunk.world.physics.World.move` (and :meth:`~World.act`'s Forward and
    Reverse) leave it."""
    return sweep(walls, x, y, distance * math.cos(heading), distance * math.sin(heading), radius)


@numba.njit(cache=True)
def move_among(
    walls: np.ndarray, robots: np.ndarray, present: np.ndarray, me: int, x: float, y: float,
    heading: float, distance: float, radius: float,
) -> tuple[float, float]:  # fmt: skip
    """:func:`move` of robot ``me`` in a shared world (:func:`sweep_among`); with a
    negative ``distance``, a rescue's Reverse."""
    dx = distance * math.cos(heading)
    dy = distance * math.sin(heading)
    return sweep_among(walls, robots, present, me, x, y, dx, dy, radius)


#: :func:`act`'s ``motion`` when the drive has no errors: ``(on, drift, drift sigma, slip
#: sigma, turn sigma)``.
NO_MOTION_ERRORS = (0.0, 0.0, 0.0, 0.0, 0.0)


@numba.njit(cache=True, inline="always")
def _drive(action: int, h: float, rng, distance: float, arc: float, motion) -> tuple:
    """What ``action`` does from heading ``h`` (:func:`act`'s doc): ``(moves, dx, dy,
    heading after)``, the displacement to sweep when ``moves``; a real drive's draws
    (``motion[0]`` on) from ``rng``."""
    on, drift, drift_sigma, slip_sigma, turn_sigma = (motion[0], motion[1], motion[2],
                                                      motion[3], motion[4])  # fmt: skip
    if action == 0:
        return False, 0.0, 0.0, h
    if on == 0.0:
        if action == 1:
            return False, 0.0, 0.0, (h + arc) % TWO_PI
        if action == 2:
            return False, 0.0, 0.0, (h - arc) % TWO_PI
        d = distance if action == 3 else -distance
        return True, d * math.cos(h), d * math.sin(h), h
    if action == 1 or action == 2:
        turn = arc + turn_sigma * rng.standard_normal() if turn_sigma > 0.0 else arc
        return False, 0.0, 0.0, (h + (turn if action == 1 else -turn)) % TWO_PI
    sign = 1.0 if action == 3 else -1.0
    turn = sign * drift
    if drift_sigma > 0.0 or slip_sigma > 0.0:
        e0 = rng.standard_normal()  # MotionErrors.move's standard_normal(2), one by one
        e1 = rng.standard_normal()
        turn += drift_sigma * e0
        distance = max(0.0, distance * (1.0 + slip_sigma * e1))
    d = sign * distance
    if d != 0.0:
        half = 0.5 * turn
        chord = d if half == 0.0 else d * (math.sin(half) / half)
        mid = h + half
        return True, chord * math.cos(mid), chord * math.sin(mid), (h + turn) % TWO_PI
    return False, 0.0, 0.0, (h + turn) % TWO_PI


def world_group(walls: np.ndarray, radius: float, distance: float, arc: float) -> tuple:
    """:func:`act`'s ``world``: the walls (:func:`~.segment_query.wall_array`), the robot's
    radius, the move distance and turn arc, and room for the list of walls near a move
    (so that a move allocates nothing; robots moved one after another may share it)."""
    return (walls, float(radius), float(distance), float(arc),
            np.zeros(walls.shape[0], np.int64))  # fmt: skip


@numba.njit(cache=True)
def act(action: int, x: float, y: float, h: float, rng, world: tuple, motion) -> tuple:
    """The pose after ``action`` (0 Stop, 1 RotateLeft, 2 RotateRight, 3 Forward, 4
    Reverse): :meth:`World.act`, or with a real drive's errors (``motion[0]`` on; the
    draws from ``rng``) ``KoolioEnv._act_with_errors`` (:class:`MotionErrors`' turn and
    move, :meth:`World.drive`'s chord). ``world`` = ``(walls, radius, move distance, turn
    arc, room for the walls near a move)`` (:func:`world_group`); ``motion`` = ``(on,
    drift, drift sigma, slip sigma, turn sigma)``."""
    walls, radius, distance, arc = world[0], world[1], world[2], world[3]
    moves, dx, dy, h = _drive(action, h, rng, distance, arc, motion)
    if moves:
        x, y = sweep_in(walls, x, y, dx, dy, radius, world[4])
    return x, y, h


@numba.njit(cache=True)
def act_among(
    action: int, x: float, y: float, h: float, rng, world: tuple, motion, robots: np.ndarray,
    present: np.ndarray, me: int,
) -> tuple:  # fmt: skip
    """:func:`act` of robot ``me`` in a shared world: the same draws and heading, the move
    :func:`sweep_among` the other robots in the arena (``robots``, ``present``: the module
    doc). The caller writes the new centre into ``robots[me]``."""
    walls, radius, distance, arc = world[0], world[1], world[2], world[3]
    moves, dx, dy, h = _drive(action, h, rng, distance, arc, motion)
    if moves:
        x, y = sweep_among(walls, robots, present, me, x, y, dx, dy, radius)
    return x, y, h
