"""The pymunk world: static wall segments and the robot's circle body (paper §5.4.2, §5.4.4).

Design (measured with pymunk 7): a kinematic body gets no collision response
from static walls, so the robot is a **dynamic** circle body, with infinite moment (contacts
never spin it) and zero friction (it slides along walls). A move of ``d`` inches sets the
body's velocity once to ``d`` per unit time and steps the space for one time unit in
sub-steps that move the robot at most ``radius / 4`` each, with ``collision_bias = 0`` and
``collision_slop = 0.01``: pymunk's contact solver removes the velocity into walls, so the
robot stops at (or slides along) a wall, never overlapping it by more than the slop and
never tunnelling. When a wall is within reach of the move (pymunk's nearest-point query),
the sub-steps shrink to ``FINE_STEP``: a deep sub-step past the saddle of a gap narrower
than the robot would let the two push-outs cancel and squeeze it through. Contacts are
found after positions are integrated, so the last sub-step can leave an overlap; two
zero-velocity settle steps (bias 0 = remove all overlap beyond the slop in one step) push
it out. The velocity is then zeroed: a move is an action, not momentum. Rotations set
the heading directly (a circle's contacts do not depend on it).

Several robots may share the world (``n_robots``): each is its own circle in the same
space, in one non-colliding shape group, and each lives in its own copy of the arena:
robot ``k``'s walls are the arena's shifted by ``k * spacing`` along x (a power of two
wider than the arena), so robots are never even near each other in pymunk's broad phase
(crowds of robots around the start point would otherwise cost every sub-step a pair test
per neighbour). :meth:`pose`, :meth:`place`, :attr:`x` and :meth:`wall_clearance` speak
the arena's own coordinates; robot 0's copy is the arena itself (``walls``). While some
robots move, the others sleep (see :meth:`_wake_only`).

Example::

    >>> from koolio_pymunk.world import World, Action
    >>> w = World.from_segments([((0, 0), (100, 0)), ((100, 0), (100, 100)),
    ...                          ((100, 100), (0, 100)), ((0, 100), (0, 0))], radius=10)
    >>> w.place(0, (50, 50), 0.0)
    >>> w.act([Action.FORWARD], distance=12, arc=0.1)
    >>> round(w.x[0], 6), round(w.y[0], 6)
    (62.0, 50.0)
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from enum import IntEnum

import pymunk

from .arena import Arena, Point

#: Collision categories (bit masks) for shape filters.
WALL_CATEGORY = 0b01
ROBOT_CATEGORY = 0b10
#: Filter for sensor rays: walls only (never the robot's own circle).
WALL_ONLY = pymunk.ShapeFilter(mask=WALL_CATEGORY)
#: Non-zero group shared by all robots: shapes in one group never collide.
ROBOT_GROUP = 1
#: A robot's filter: it collides with walls only.
SOLID = pymunk.ShapeFilter(group=ROBOT_GROUP, categories=ROBOT_CATEGORY, mask=WALL_CATEGORY)
#: With several robots, sleeping is enabled with this threshold: nothing falls asleep by
#: itself; :meth:`World.act` puts the robots that do not move to sleep (see there).
NEVER_AUTO_SLEEP = 1e300
#: pymunk's allowed overlap: the most a robot may sink into a wall, inches.
COLLISION_SLOP = 0.01
TWO_PI = 2.0 * math.pi
#: Zero-velocity steps after each move that push out the last sub-step's overlap.
SETTLE_STEPS = 2
#: Sub-step travel (inches) when a wall is within reach: the deepest a robot can sink into
#: a wall before the solver stops it, which decides how narrow a gap it can squeeze
#: through. Measured: 0.25 blocks every gap 0.1 in (the overlap tolerance) or more
#: narrower than the robot's diameter (0.5: only from 0.5 in; 0.05: from 0.02 in, but
#: 3.3x slower).
FINE_STEP = 0.25


class Action(IntEnum):
    """The paper's five actions (the low 3 bits of the Q keyword)."""

    STOP = 0
    ROTATE_LEFT = 1
    ROTATE_RIGHT = 2
    FORWARD = 3
    REVERSE = 4


_ROTATE_LEFT = int(Action.ROTATE_LEFT)
_ROTATE_RIGHT = int(Action.ROTATE_RIGHT)
_FORWARD = int(Action.FORWARD)
_REVERSE = int(Action.REVERSE)

ACTION_NAMES = ("Stop", "RotateLeft", "RotateRight", "Forward", "Reverse")


def chipmunk_step(space: pymunk.Space) -> Callable[[float], None]:
    """``space.step`` without pymunk's Python bookkeeping around Chipmunk's step.

    ``Space.step`` wraps ``cpSpaceStep`` with work for shapes added or removed during a
    step, post-step callbacks and a mass check of newly added bodies; a :class:`World`
    never uses any of these while it moves, so calling ``cpSpaceStep`` itself is the same
    step (the same C call on the same space) for about a third of the Python cost. Falls
    back to ``space.step`` if pymunk's internals are not where pymunk 7 keeps them.
    """
    try:
        from pymunk._chipmunk import lib

        return functools.partial(lib.cpSpaceStep, space._space)
    except (ImportError, AttributeError):  # pragma: no cover - other pymunk layouts
        return space.step


def chipmunk_set_velocity() -> Callable[[pymunk.Body, tuple[float, float]], None]:
    """``body.velocity = v`` as the bare ``cpBodySetVelocity`` call it makes (pymunk's
    attribute hooks around it cost more than the call); ``setattr`` if not pymunk 7."""
    try:
        from pymunk._chipmunk import lib

        set_v = lib.cpBodySetVelocity
        return lambda body, v: set_v(body._body, v)
    except (ImportError, AttributeError):  # pragma: no cover - other pymunk layouts
        return lambda body, v: setattr(body, "velocity", v)


def copy_spacing(segments: Sequence[tuple[Point, Point]], radius: float) -> float:
    """A power of two wider than the arena plus two robot diameters and a margin."""
    xs = [p[0] for seg in segments for p in seg]
    return float(2 ** math.ceil(math.log2(max(xs) - min(xs) + 4.0 * radius + 64.0)))


class World:
    """Walls as static segments and ``n_robots`` circle bodies in one pymunk space."""

    def __init__(
        self, segments: Sequence[tuple[Point, Point]], radius: float, n_robots: int = 1
    ) -> None:
        self.radius = float(radius)
        self.segments = [(tuple(map(float, a)), tuple(map(float, b))) for a, b in segments]
        self.space = pymunk.Space()
        self._step = chipmunk_step(self.space)
        self._set_velocity = chipmunk_set_velocity()
        self.space.collision_bias = 0.0
        self.space.collision_slop = COLLISION_SLOP
        self.space.iterations = 20
        self.spacing = copy_spacing(self.segments, self.radius) if n_robots > 1 else 0.0
        """x distance between the arena copies of successive robots (0: one robot)."""
        self.offsets = [k * self.spacing for k in range(n_robots)]
        self.walls = self._add_walls(0.0)
        """Wall shapes of robot 0's copy: the arena's own coordinates."""
        for off in self.offsets[1:]:
            self._add_walls(off)
        self.bodies: list[pymunk.Body] = []
        self.shapes: list[pymunk.Circle] = []
        for _ in range(n_robots):
            self._add_robot()
        self.heading = [0.0] * n_robots
        self.awake = list(range(n_robots))
        """Robots whose bodies are awake (all of them with one robot)."""
        if n_robots > 1:
            self.space.sleep_time_threshold = NEVER_AUTO_SLEEP

    @classmethod
    def from_arena(cls, arena: Arena, radius: float, n_robots: int = 1) -> World:
        """A world holding ``arena``'s walls and obstacles (``rotate_deg`` applied)."""
        return cls(arena.to_world().segments(), radius, n_robots)

    @classmethod
    def from_segments(
        cls, segments: Sequence[tuple[Point, Point]], radius: float, n_robots: int = 1
    ) -> World:
        return cls(segments, radius, n_robots)

    def _add_walls(self, dx: float) -> list[pymunk.Segment]:
        """Add one copy of the walls, shifted by ``dx`` along x."""
        walls = []
        for (ax, ay), (bx, by) in self.segments:
            seg = pymunk.Segment(self.space.static_body, (ax + dx, ay), (bx + dx, by), 0.0)
            seg.friction = 0.0
            seg.elasticity = 0.0
            seg.filter = pymunk.ShapeFilter(categories=WALL_CATEGORY)
            walls.append(seg)
        self.space.add(*walls)
        return walls

    def _add_robot(self) -> None:
        body = pymunk.Body(1.0, math.inf)
        shape = pymunk.Circle(body, self.radius)
        shape.friction = 0.0
        shape.elasticity = 0.0
        shape.filter = SOLID
        self.space.add(body, shape)
        self.bodies.append(body)
        self.shapes.append(shape)

    # -- state ----------------------------------------------------------------------
    @property
    def n_robots(self) -> int:
        return len(self.bodies)

    @property
    def x(self) -> list[float]:
        return [b.position.x - off for b, off in zip(self.bodies, self.offsets)]

    @property
    def y(self) -> list[float]:
        return [b.position.y for b in self.bodies]

    def pose(self, i: int = 0) -> tuple[float, float, float]:
        """``(RobotLocation x, y, RobotOrientation)`` of robot ``i`` in the arena's
        coordinates (its own copy's offset removed); heading in [0, 2pi)."""
        p = self.bodies[i].position
        if i == 0:
            return (p.x, p.y, self.heading[0])
        return (p.x - self.offsets[i], p.y, self.heading[i])

    def place(self, i: int, at: Point, heading: float) -> None:
        """Put robot ``i`` at ``at`` (arena coordinates) with ``heading`` (radians), at rest."""
        body = self.bodies[i]
        body.position = (float(at[0]) + self.offsets[i], float(at[1]))
        body.velocity = (0.0, 0.0)
        self.heading[i] = heading % TWO_PI
        self.space.reindex_shapes_for_body(body)
        if len(self.bodies) > 1 and i not in self.awake:
            body.sleep()  # setting the position woke it: keep it out of others' moves

    # -- actions --------------------------------------------------------------------
    def act(
        self,
        actions: Sequence[int],
        distance: float,
        arc: float,
        near_wall: Callable[[list[int], float], bool] | None = None,
    ) -> None:
        """Perform one action per robot: rotations by ``arc`` radians, moves by ``distance``.

        All moving robots move together through the same pymunk sub-steps.
        ``near_wall(movers, reach)`` may answer whether a wall is within ``reach`` of a
        moving robot (which picks the sub-step; see :meth:`_integrate`) when the caller
        knows the positions; by default pymunk's nearest-point query answers.
        """
        movers: list[int] = []
        heading = self.heading
        set_velocity = self._set_velocity
        for i, action in enumerate(actions):
            if action == _ROTATE_LEFT:
                heading[i] = (heading[i] + arc) % TWO_PI
            elif action == _ROTATE_RIGHT:
                heading[i] = (heading[i] - arc) % TWO_PI
            elif action in (_FORWARD, _REVERSE):
                sign = 1.0 if action == _FORWARD else -1.0
                h = heading[i]
                set_velocity(
                    self.bodies[i], (sign * distance * math.cos(h), sign * distance * math.sin(h))
                )
                movers.append(i)
        if movers:
            self._wake_only(movers)
            self._integrate(distance, movers, near_wall)

    def drive(self, i: int, distance: float, turn: float) -> None:
        """Robot ``i`` drives ``distance`` inches (negative: backwards) while its heading
        turns by ``turn`` radians: the arc of a differential drive whose wheels differ
        (the realism motion model, :class:`~koolio_pymunk.realism.MotionErrors`).

        pymunk gets one velocity along the arc's chord (length ``distance *
        sin(turn/2) / (turn/2)``, direction the heading plus ``turn / 2``) and resolves
        every contact as in any move; the heading then turns by ``turn``. With ``turn`` 0
        this is exactly :meth:`act`'s Forward / Reverse; ``distance`` 0 is a pure turn.
        """
        h = self.heading[i]
        if distance != 0.0:
            half = 0.5 * turn
            chord = distance if half == 0.0 else distance * (math.sin(half) / half)
            mid = h + half
            self._set_velocity(self.bodies[i], (chord * math.cos(mid), chord * math.sin(mid)))
            self._wake_only([i])
            self._integrate(abs(chord), [i])
        self.heading[i] = (h + turn) % TWO_PI

    def move(self, i: int, distance: float) -> None:
        """Move robot ``i`` alone by ``distance`` along its heading (negative: backwards)."""
        h = self.heading[i]
        self._set_velocity(self.bodies[i], (distance * math.cos(h), distance * math.sin(h)))
        self._wake_only([i])
        self._integrate(abs(distance), [i])

    def _wake_only(self, movers: list[int]) -> None:
        """With several robots, only the robots that move are awake during a move.

        A robot that does not move is at rest (zero velocity, no forces): stepping it
        would leave it exactly where it is, so it sleeps instead (Chipmunk then neither
        integrates it nor solves its wall contacts, which are kept for when it wakes).
        Robots never touch each other (one shape group), so each sleeps alone. Only the
        robots whose role changes are switched. One robot: nothing to do.
        """
        if len(self.bodies) == 1:
            return
        bodies, awake = self.bodies, set(movers)
        for i in self.awake:
            if i not in awake:
                bodies[i].sleep()
        # The movers are awake already: setting a velocity activates a body.
        self.awake = movers

    def _integrate(
        self,
        distance: float,
        movers: list[int],
        near_wall: Callable[[list[int], float], bool] | None = None,
    ) -> None:
        """Step the space one time unit in equal sub-steps, then settle at rest.

        The sub-step is ``radius / 4`` of travel when no wall is within reach of a moving
        robot (pymunk's nearest-point query), else ``FINE_STEP``. The step size stays
        constant within a move because Chipmunk warm-starts each contact with its last
        impulse scaled by the ratio of successive time steps: a change of step would kick
        the robot off the wall it slides along.
        """
        if distance <= 0.0:
            return
        travel = self.radius / 4.0
        reach = distance + self.radius + travel
        if near_wall is not None:
            if near_wall(movers, reach):
                travel = FINE_STEP
        else:
            query = self.space.point_query_nearest
            bodies = self.bodies
            for i in movers:
                if query(bodies[i].position, reach, WALL_ONLY):
                    travel = FINE_STEP
                    break
        n = max(1, math.ceil(distance / travel))
        dt = 1.0 / n
        step = self._step
        for _ in range(n):
            step(dt)
        self._stop()
        # Chipmunk detects contacts after integrating positions, so the last sub-step may
        # leave an overlap; with collision_bias 0 the next step removes all overlap beyond
        # the slop. Settle with the robots at rest.
        for _ in range(SETTLE_STEPS):
            step(dt)
        self._stop()

    def _stop(self) -> None:
        """Zero the velocity of every awake robot (sleeping ones are at rest)."""
        bodies, set_velocity = self.bodies, self._set_velocity
        for i in self.awake:
            set_velocity(bodies[i], (0.0, 0.0))

    # -- geometry queries (for tests and the viewer) ----------------------------------
    def wall_clearance(self, i: int = 0) -> float:
        """Distance from robot ``i``'s edge to the nearest wall (negative = overlap)."""
        p = self.bodies[i].position - (self.offsets[i], 0.0)
        best = math.inf
        for seg in self.walls:
            info = seg.point_query(p)
            best = min(best, info.distance)
        return best - self.radius
