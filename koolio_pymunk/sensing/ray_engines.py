"""Ray engines for the sensors: pymunk segment queries (the reference) and the compiled twin.

The sensors need two geometric answers (see :mod:`koolio_pymunk.sensing.suite`):

* ``cast(x, y, dirs, length)``: for each ray from ``(x, y)`` along the unit vector
  ``(dirs[0][i], dirs[1][i])``, the distance from ``(x, y)`` to the first wall segment, or
  ``length`` when none is hit within ``length``;
* ``line_of_sight(x, y, tx, ty)``: no wall segment crosses the sight line from ``(x, y)``
  to ``(tx, ty)`` (a wall whose *line* crosses it beyond the segment's ends does not block).

:class:`PymunkRays` answers with ``space.segment_query_first`` (radius 0, walls only): the
reference. :class:`FastRays` answers with :mod:`koolio_pymunk.world.segment_query`, the
compiled twin of the same Chipmunk query. ``sensors.backend`` picks one
(:func:`make_engine`).

The rays' directions come from the sensor suite (:func:`~.suite.turned`).

**A shared world** (:class:`~koolio_pymunk.world.physics.World` with ``shared=True``):
an engine made for robot ``robot`` sees the walls and every *other* robot in the arena
(their circles: :meth:`World.sensor_filter
<koolio_pymunk.world.physics.World.sensor_filter>`), never its own body nor a parked
robot. A ray ends on the nearest surface, wall or robot; a robot blocks a sight line as a
wall does. :meth:`PymunkRays.cast_hits` also says which robot each ray hit (-1: a wall or
nothing) and the incidence on it (the circle's normal at the hit point, as pymunk reports
it). :class:`FastRays` answers with the compiled twins
(:func:`~koolio_pymunk.world.segment_query.cast_among`,
:func:`~koolio_pymunk.world.segment_query.line_of_sight_among`) over the world's
:attr:`~koolio_pymunk.world.physics.World.xy` and
:attr:`~koolio_pymunk.world.physics.World.present` as they stand at each call.
"""

from __future__ import annotations

import math

import numpy as np

from ..world.physics import World
from ..world.segment_query import cast, cast_among, line_of_sight, line_of_sight_among, wall_array


class PymunkRays:
    """The reference engine: one ``space.segment_query_first`` per ray (the walls; in a
    shared world also the other robots in the arena) for robot ``robot``."""

    name = "pymunk"

    def __init__(self, world: World, robot: int = 0) -> None:
        self.world = world
        self.robot = robot
        self.filter = world.sensor_filter(robot)
        """What the rays see (:meth:`World.sensor_filter
        <koolio_pymunk.world.physics.World.sensor_filter>`)."""

    def cast(self, x: float, y: float, dirs: np.ndarray, length: float) -> np.ndarray:
        ends_x = x + length * dirs[0]
        ends_y = y + length * dirs[1]
        query = self.world.space.segment_query_first
        out = np.full(ends_x.shape, length)
        start = (x, y)
        for idx in np.ndindex(ends_x.shape):
            hit = query(start, (float(ends_x[idx]), float(ends_y[idx])), 0.0, self.filter)
            if hit is not None:
                out[idx] = hit.alpha * length
        return out

    def cast_incidence(
        self, x: float, y: float, dirs: np.ndarray, length: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`cast` and each ray's incidence cosine ``|cos(a) nx + sin(a) ny|`` on the
        wall it hits, with pymunk's reported normal (0 where nothing is hit)."""
        cos_a, sin_a = dirs[0], dirs[1]
        ends_x = x + length * cos_a
        ends_y = y + length * sin_a
        query = self.world.space.segment_query_first
        out = np.full(ends_x.shape, length)
        inc = np.zeros(ends_x.shape)
        for idx in np.ndindex(ends_x.shape):
            hit = query((x, y), (float(ends_x[idx]), float(ends_y[idx])), 0.0, self.filter)
            if hit is not None:
                out[idx] = hit.alpha * length
                inc[idx] = abs(cos_a[idx] * hit.normal.x + sin_a[idx] * hit.normal.y)
        return out, inc

    def cast_hits(
        self, x: float, y: float, dirs: np.ndarray, length: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`cast_incidence` and, per ray, the robot it hit (:meth:`World.robot_of
        <koolio_pymunk.world.physics.World.robot_of>`; -1: a wall, or nothing hit)."""
        cos_a, sin_a = dirs[0], dirs[1]
        ends_x = x + length * cos_a
        ends_y = y + length * sin_a
        query = self.world.space.segment_query_first
        out = np.full(ends_x.shape, length)
        inc = np.zeros(ends_x.shape)
        robot = np.full(ends_x.shape, -1, np.int64)
        for idx in np.ndindex(ends_x.shape):
            hit = query((x, y), (float(ends_x[idx]), float(ends_y[idx])), 0.0, self.filter)
            if hit is not None:
                out[idx] = hit.alpha * length
                inc[idx] = abs(cos_a[idx] * hit.normal.x + sin_a[idx] * hit.normal.y)
                robot[idx] = self.world.robot_of(hit.shape)
        return out, inc, robot

    def line_of_sight(self, x: float, y: float, tx: float, ty: float) -> bool:
        dist = math.hypot(tx - x, ty - y)
        if dist < 1e-9:
            return True
        hit = self.world.space.segment_query_first((x, y), (tx, ty), 0.0, self.filter)
        return hit is None or hit.alpha * dist >= dist - 1e-7


class FastRays:
    """The compiled engine over the world's walls (taken once: walls never move) and, in a
    shared world, the other robots where they are at each call."""

    name = "fast"

    def __init__(self, world: World, robot: int = 0) -> None:
        self.world = world
        self.robot = robot
        self.walls = wall_array(world)

    def cast(self, x: float, y: float, dirs: np.ndarray, length: float) -> np.ndarray:
        dirs = np.ascontiguousarray(dirs, float)
        w = self.world
        if w.shared:
            return cast_among(float(x), float(y), dirs, length, self.walls, w.xy, w.present,
                              self.robot, w.radius)  # fmt: skip
        return cast(float(x), float(y), dirs, length, self.walls)

    def line_of_sight(self, x: float, y: float, tx: float, ty: float) -> bool:
        w = self.world
        if w.shared:
            return bool(line_of_sight_among(float(x), float(y), float(tx), float(ty), self.walls,
                                            w.xy, w.present, self.robot, w.radius))  # fmt: skip
        return bool(line_of_sight(float(x), float(y), float(tx), float(ty), self.walls))


ENGINES = {"pymunk": PymunkRays, "fast": FastRays, "cone": FastRays}


def make_engine(name: str, world: World, robot: int = 0) -> PymunkRays | FastRays:
    """The ray engine called ``name`` (``sensors.backend``) for robot ``robot`` of
    ``world``."""
    return ENGINES[name](world, robot)
