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
"""

from __future__ import annotations

import math

import numpy as np

from ..world.physics import WALL_ONLY, World
from ..world.segment_query import cast, line_of_sight, wall_array


class PymunkRays:
    """The reference engine: one ``space.segment_query_first`` per ray (walls only)."""

    name = "pymunk"

    def __init__(self, world: World) -> None:
        self.world = world

    def cast(self, x: float, y: float, dirs: np.ndarray, length: float) -> np.ndarray:
        ends_x = x + length * dirs[0]
        ends_y = y + length * dirs[1]
        query = self.world.space.segment_query_first
        out = np.full(ends_x.shape, length)
        start = (x, y)
        for idx in np.ndindex(ends_x.shape):
            hit = query(start, (float(ends_x[idx]), float(ends_y[idx])), 0.0, WALL_ONLY)
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

    def cast(self, x: float, y: float, dirs: np.ndarray, length: float) -> np.ndarray:
        return cast(float(x), float(y), np.ascontiguousarray(dirs, float), length, self.walls)

    def line_of_sight(self, x: float, y: float, tx: float, ty: float) -> bool:
        return bool(line_of_sight(float(x), float(y), float(tx), float(ty), self.walls))


ENGINES = {"pymunk": PymunkRays, "fast": FastRays, "cone": FastRays}


def make_engine(name: str, world: World) -> PymunkRays | FastRays:
    """The ray engine called ``name`` (``sensors.backend``) for ``world``."""
    return ENGINES[name](world)
