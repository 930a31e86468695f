"""Start spots: where a robot of a shared arena may start an episode.

An arena has one start point; robots sharing it (``--shared-arena``) cannot all stand
there. A :class:`StartArea` lays *spots* around a start point: the points of a square
grid, one robot diameter plus ``gap`` apart, within ``spread`` inches of the start point,
each in sight of the start point (no wall between them), clear of every wall by ``gap``
and accepted by ``keep`` (the task keeps them out of
the end-of-world zones), so robots standing on two spots are ``gap`` apart.
A robot starts on a spot that no other robot in the arena covers (its centre closer than
a diameter plus ``gap``): :meth:`StartArea.free` lists them, nearest the start point
first, and the robot's generator draws one (:meth:`StartArea.draw`, one draw). When none is
free the robot waits outside the arena and asks again at its next turn.

:attr:`StartArea.capacity` is how many robots the area holds at once: a run that would
start more robots from one start point than it holds is refused before anything starts.

>>> from koolio_pymunk.world.physics import World
>>> box = [((0, 0), (200, 0)), ((200, 0), (200, 100)), ((200, 100), (0, 100)), ((0, 100), (0, 0))]
>>> world = World(box, radius=10, n_robots=2, shared=True)
>>> area = StartArea(world, (50.0, 50.0), spread=36.0, gap=2.0)
>>> area.capacity, area.spots[0].tolist()
(9, [50.0, 50.0])
>>> world.place(0, (50.0, 50.0), 0.0)
>>> len(area.free(1))   # robot 0 on the first spot covers it alone
8
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from .arena import Point
from .geometry import segments_intersect
from .physics import World


class StartArea:
    """The start spots around ``start`` in ``world`` (a shared
    :class:`~koolio_pymunk.world.physics.World`), module doc."""

    def __init__(
        self,
        world: World,
        start: Point,
        spread: float,
        gap: float,
        keep: Callable[[Point], bool] | None = None,
    ) -> None:
        self.world = world
        self.start = (float(start[0]), float(start[1]))
        self.spacing = 2.0 * world.radius + gap
        """Centre to centre, inches: neighbouring spots' robots are ``gap`` apart."""
        sx, sy = self.start
        m = int(spread // self.spacing)
        spots = [
            (sx + i * self.spacing, sy + j * self.spacing)
            for i in range(-m, m + 1)
            for j in range(-m, m + 1)
            if math.hypot(i, j) * self.spacing <= spread
        ]
        spots.sort(key=lambda p: (math.hypot(p[0] - sx, p[1] - sy), p[0], p[1]))
        walls = [(tuple(w.a), tuple(w.b)) for w in world.walls]
        clear = [
            p
            for p in spots
            if not any(segments_intersect(self.start, p, a, b) for a, b in walls)
            and world.wall_clearance(0, p) >= gap
            and (keep is None or keep(p))
        ]
        self.spots = np.array(clear, dtype=np.float64).reshape(-1, 2)
        """The spots, ``(n, 2)``, nearest the start point first."""

    @property
    def capacity(self) -> int:
        """How many robots the area holds at once (its spots)."""
        return len(self.spots)

    def free(self, robot: int) -> list[int]:
        """The spots robot ``robot`` may start on now: none of the other robots in the
        arena has its centre within :attr:`spacing` of it. Reads the world's
        :attr:`~koolio_pymunk.world.physics.World.xy` and ``present`` (the compiled steps
        keep them current)."""
        w = self.world
        others = [j for j in range(w.n_robots) if j != robot and w.present[j]]
        if not others:
            return list(range(len(self.spots)))
        d = np.hypot(
            self.spots[:, None, 0] - w.xy[None, others, 0],
            self.spots[:, None, 1] - w.xy[None, others, 1],
        )
        return np.flatnonzero((d >= self.spacing).all(axis=1)).tolist()

    def draw(self, robot: int, rng: np.random.Generator) -> Point | None:
        """A free spot for ``robot`` drawn uniformly (one ``integers`` draw), or None when
        every spot is covered (no draw)."""
        free = self.free(robot)
        if not free:
            return None
        x, y = self.spots[free[int(rng.integers(len(free)))]]
        return (float(x), float(y))
