"""The pymunk world: static wall segments and the robot's circle body (paper §5.4.2, §5.4.4).

**A move is a swept circle.** A move of the robot's centre by ``(dx, dy)`` asks pymunk
for the first wall the moving circle meets: Chipmunk's segment query with the robot's
radius (``cpSpaceSegmentQueryFirst``) answers the fraction ``alpha`` of the move done and
the contact normal. The robot goes to that point and is pushed :data:`SKIN` along the
normal (so it is never closer than tangent, and the next query does not start touching);
what remains of the move is projected on the wall's tangent (zero friction: the normal
part is removed) and queried again, at most :data:`MAX_QUERIES` times. A slide that would
go into the wall met just before (a corner, or the two sides of a gap narrower than the
robot) ends the move. So the robot stops at a wall, slides along it, never overlaps it,
never tunnels (the query sweeps the whole move) and never squeezes through a gap
narrower than its diameter; a move away from a wall is never held by it. One query for
a free move, two or three near walls. Rotations set the heading directly (a circle's
contacts do not depend on it).

**Why the walls are in pymunk twice.** Two flaws of Chipmunk's segment query with a
radius (Chipmunk 7 / Munk2D, ``cpSpaceQuery.c``, ``cpShape.c``) would let a robot into a
wall:

* the spatial index tests the query against the shapes' bounding boxes with its centre
  line only, not grown by the radius: ``space.segment_query_first(a, b, R)`` misses a
  wall whose box the centre line does not cross, which is every wall the robot stops
  short of. The segment query itself uses only the sum of the two radii
  (``cpSegmentShapeSegmentQuery``: ``r = seg->r + r2``), so each wall is also a segment
  of radius ``R``, asked with a radius-0 query: the same numbers as a radius-``R`` query
  against the thin wall, with a box that holds every point the centre can touch;
* ``cpSegmentShapeSegmentQuery`` asks a wall's end caps only when the query's line does
  not pass between the wall's moved-out ends: a circle that starts beside the wall's
  line, past its end, and runs into that end is missed (the tip of an acute corner), so
  every wall end is also a disc of radius ``R`` (``CircleSegmentQuery``, the very
  function the caps use).

Those segments and discs (:data:`MOTION_CATEGORY`) sit in a pymunk space of their own
per robot (:attr:`World.motion`: a query walks one copy's shapes only, and the robots'
circles make no pairs with them); the thin walls (:data:`WALL_CATEGORY`) and the robots'
bodies are in :attr:`World.space`, where the sensors look.

**Touching walls.** Chipmunk answers ``alpha = 0`` with the normal from the wall's nearest
point when the query *starts* within the radius of a wall, whichever way it goes. That
happens only after :meth:`World.place` puts a robot against a wall (or overlapping one),
or in an acute corner where the push-out along one wall's normal comes within the skin
of the other. Then each of the robot's walls is asked alone (``cpShapeSegmentQuery``), a
touching wall holds the move only if the move goes into it (:data:`ALONG`), and the
smallest ``alpha`` of the others is the contact (:meth:`World.first_contact`).

``koolio_pymunk.world.swept_move`` repeats all of this, Chipmunk's query included,
operation for operation in compiled code; ``tests/world/test_segment_query.py`` and
``tools/agreement.py --moves`` hold the two to the same end positions bit for bit.

**Several robots, isolated** (``n_robots``, the default): each has its own circle body in
the same space and lives in its own copy of the arena: robot ``k``'s walls are the
arena's shifted by ``k * spacing`` along x (a power of two wider than the arena), and its
moves ask only its own motion space. :meth:`pose`, :meth:`place`, :attr:`x` and
:meth:`wall_clearance` speak the arena's own coordinates; robot 0's copy is the arena
itself (``walls``). The robots' bodies are pymunk bodies whose positions the moves set
and whose shapes they reindex (the space is never stepped), so the viewer and pymunk's
own queries see them where they are.

**Several robots sharing the arena** (``shared=True``): one copy of the walls, and every
robot's circle body in the one space, each a body to the others:

* *In the arena or parked.* A robot of a shared world is in the arena from
  :meth:`place` until :meth:`park` (its episode ended and it left): :attr:`present`
  says which, :attr:`xy` holds every robot's centre (both numpy arrays, kept current,
  what the compiled twins take). A parked robot is no obstacle and no sensor target
  (its shape's filter has no category, so no query sees it); a new world's robots are
  all parked until placed.
* *A move stops at another robot as at a wall.* Another robot is, for the mover's
  centre, a disc of radius ``2R`` at its centre (the Minkowski sum of two circles of
  radius ``R``): Chipmunk's ``cpShapeSegmentQuery`` of the other robot's own circle
  (radius ``R``) with a query of radius ``R`` (``CircleSegmentQuery`` with ``r1 + r2 =
  2R``: the same numbers as a radius-0 query of a ``2R`` disc, and the normal from the
  other robot's surface towards the mover when the move starts touching it). Each
  present robot is asked in index order after the walls' contact
  (:meth:`first_contact`): the smallest alpha wins, the walls on a tie, then the lower
  index. The push-out (:data:`SKIN`), the slide along the tangent and the corner rule of
  :func:`sweep` are the walls'. So a robot driving into another stops with the centres
  ``2R + SKIN`` apart and slides along it, never overlaps it beyond rounding, and never
  squeezes between two robots, or a robot and a wall, closer than its diameter.
* *Touching a robot* is the walls' rule mirrored: a move that starts with the centres
  within ``2R`` (Chipmunk answers alpha 0 and the normal from the other robot's nearest
  surface point) is held by that robot only if it goes into it (:data:`ALONG`); a move
  away from it or along it is free. (Centres closer than ``R``, which no move makes,
  turn that normal round; centres at the same point have none, and pass.)
* *Sensors see other robots* (:meth:`sensor_filter`): the robot's circle is in the
  robots' category and in a group of its own (``i + 1``: :meth:`robot_of` reads the index
  back from a hit), so a robot's rays see the walls and the other robots, never itself.

Example::

    >>> from koolio_pymunk.world.physics import World, Action
    >>> w = World([((0, 0), (100, 0)), ((100, 0), (100, 100)),
    ...            ((100, 100), (0, 100)), ((0, 100), (0, 0))], radius=10)
    >>> w.place(0, (50, 50), 0.0)
    >>> w.act([Action.FORWARD], distance=12, arc=0.1)
    >>> w.x[0], w.y[0]
    (62.0, 50.0)
    >>> for _ in range(4):
    ...     w.act([Action.FORWARD], distance=12, arc=0.1)
    >>> round(w.x[0], 6), 90.0 - w.x[0] - SKIN < 1e-12   # tangent to the east wall
    (90.0, True)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from enum import IntEnum

import numpy as np
import pymunk

from .arena import Arena, Point

#: Collision categories (bit masks) for shape filters: the walls the sensors see.
WALL_CATEGORY = 0b01
#: The robots' circles.
ROBOT_CATEGORY = 0b10
#: The walls again, as segments and wall-end discs of the robot's radius (in each robot's
#: motion space): what a move's query sees.
MOTION_CATEGORY = 0b100
#: Filter for sensor rays: walls only (never the robot's own circle).
WALL_ONLY = pymunk.ShapeFilter(mask=WALL_CATEGORY)
#: Filter of a move's query: the walls of the robot's radius only.
MOTION_ONLY = pymunk.ShapeFilter(mask=MOTION_CATEGORY)
#: Non-zero group shared by all robots: shapes in one group never collide.
ROBOT_GROUP = 1
#: A robot's filter: in the robots' group, meeting nothing (the space is never stepped).
SOLID = pymunk.ShapeFilter(group=ROBOT_GROUP, categories=ROBOT_CATEGORY, mask=0)
#: Tolerance (inches) on a robot's overlap with a wall when poses are sampled or checked
#: (the old contact solver's allowed overlap, kept for those checks); a move itself
#: never overlaps a wall by more than rounding (see :data:`SKIN`).
COLLISION_SLOP = 0.01
TWO_PI = 2.0 * math.pi
#: Clearance (inches) a contact leaves between the robot's edge and the wall: the robot
#: is pushed this far along the contact normal, so the next query starts outside the wall
#: (Chipmunk answers alpha 0 for any query that starts touching). Far above rounding
#: (positions of 1e5 in have a last bit of 1.5e-11 in), far below anything a robot or a
#: sensor resolves.
SKIN = 1e-7
#: Segment queries per move at most: the first contact, a slide, a second slide. A free
#: move takes one, a move into a wall two, a move along a wall into a corner or round an
#: obstacle three; what remains after the last is dropped.
MAX_QUERIES = 3
#: A slide shorter than this (inches) is dropped: Chipmunk's circle query computes the
#: squared length of a move as a difference of squares of about the robot's radius, which
#: leaves nothing of a move of 1e-7 in (and 1 % of one of 1e-6 in).
MIN_SLIDE = 1e-6
#: A wall the robot starts touching holds a move only if the move goes into it by more
#: than this fraction of its length (the move's part along the wall's normal: the sine
#: of its angle to the wall, about that angle in radians): a slide along it whose normal
#: part is rounding is not held. The same tolerance decides whether a slide goes back
#: into the wall met before (a corner).
ALONG = 1e-9


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

#: ``contact(x, y, dx, dy) -> (alpha, nx, ny)``: the first contact of a move (alpha 1.0:
#: none). See :meth:`World.first_contact`.
Contact = Callable[[float, float, float, float], tuple[float, float, float]]


def sweep(x: float, y: float, dx: float, dy: float, contact: Contact) -> tuple[float, float]:
    """Where a circle at ``(x, y)`` ends after a move by ``(dx, dy)`` against the walls
    that ``contact`` answers for: contact, push-out by :data:`SKIN`, slide along the wall
    (the rest projected on the wall's tangent), at most :data:`MAX_QUERIES` queries; a
    slide back into the wall met before (a corner) or shorter than :data:`MIN_SLIDE` ends
    the move.

    ``koolio_pymunk.world.swept_move.sweep`` is the same function, compiled, with the same
    floating-point operations in the same order.

    >>> wall = lambda x, y, dx, dy: (min(1.0, (90.0 - x) / dx), -1.0, 0.0) if dx > 0 \\
    ...     and x + dx > 90.0 else (1.0, 0.0, 0.0)     # a wall at x = 100, radius 10
    >>> sweep(50.0, 50.0, 12.0, 0.0, wall), sweep(85.0, 50.0, 12.0, 0.0, wall)
    ((62.0, 50.0), (89.9999999, 50.0))
    """
    pnx = pny = 0.0
    for k in range(MAX_QUERIES):
        if dx == 0.0 and dy == 0.0:
            break
        alpha, nx, ny = contact(x, y, dx, dy)
        if alpha >= 1.0:
            return x + dx, y + dy
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
            break
        if k > 0 and rx * pnx + ry * pny < -ALONG * slide:
            break
        dx, dy, pnx, pny = rx, ry, nx, ny
    return x, y


class _Chipmunk:
    """The few Chipmunk calls a move makes, without pymunk's Python wrappers around them
    (the same C functions on the same objects); pymunk's public API if its internals are
    not where pymunk 7 keeps them."""

    def __init__(self, space: pymunk.Space, motion: list[pymunk.Space]) -> None:
        self.space = space
        self.motion = motion
        try:
            from pymunk._chipmunk import ffi, lib

            self.info = ffi.new("cpSegmentQueryInfo *")
            self.lib = lib
            self.cmotion = [m._space for m in motion]
        except (ImportError, AttributeError):  # pragma: no cover - other pymunk layouts
            self.lib = None

    def __getstate__(self) -> tuple:
        """The spaces only: the C handles are made again on unpickling (pymunk pickles
        its spaces; a cffi struct does not pickle), so a world copies with
        :func:`copy.deepcopy` and :mod:`pickle`."""
        return (self.space, self.motion)

    def __setstate__(self, state: tuple) -> None:
        self.__init__(*state)

    def first(self, k: int, x: float, y: float, ex: float, ey: float) -> tuple[float, float, float]:
        """``cpSpaceSegmentQueryFirst`` from ``(x, y)`` to ``(ex, ey)``, radius 0, in the
        motion space of copy ``k``: ``(alpha, nx, ny)``, ``(1.0, 0.0, 0.0)`` if none."""
        if self.lib is None:  # pragma: no cover - other pymunk layouts
            hit = self.motion[k].segment_query_first((x, y), (ex, ey), 0.0, MOTION_ONLY)
            return (1.0, 0.0, 0.0) if hit is None else (hit.alpha, *hit.normal)
        info = self.info
        self.lib.cpSpaceSegmentQueryFirst(self.cmotion[k], (x, y), (ex, ey), 0.0, MOTION_ONLY, info)
        n = info.normal
        return info.alpha, n.x, n.y

    def shape_query(
        self, shape: pymunk.Shape, x: float, y: float, ex: float, ey: float, radius: float
    ) -> tuple[bool, float, float, float]:
        """``cpShapeSegmentQuery`` of ``shape`` alone from ``(x, y)`` to ``(ex, ey)`` with
        ``radius``: ``(hit, alpha, nx, ny)``, ``(False, 1.0, 0.0, 0.0)`` if none
        (pymunk's ``Shape.segment_query``)."""
        if self.lib is None:  # pragma: no cover - other pymunk layouts
            hit = shape.segment_query((x, y), (ex, ey), radius)
            return (False, 1.0, 0.0, 0.0) if hit is None else (True, hit.alpha, *hit.normal)
        info = self.info
        if not self.lib.cpShapeSegmentQuery(shape._shape, (x, y), (ex, ey), radius, info):
            return False, 1.0, 0.0, 0.0
        n = info.normal
        return True, info.alpha, n.x, n.y

    def position(self, body: pymunk.Body) -> tuple[float, float]:
        if self.lib is None:  # pragma: no cover - other pymunk layouts
            return tuple(body.position)
        p = self.lib.cpBodyGetPosition(body._body)
        return p.x, p.y

    def set_position(self, body: pymunk.Body, x: float, y: float) -> None:
        """Set the body's position and refresh its shapes' boxes in the spatial index."""
        if self.lib is None:  # pragma: no cover - other pymunk layouts
            body.position = (x, y)
            self.space.reindex_shapes_for_body(body)
            return
        self.lib.cpBodySetPosition(body._body, (x, y))
        self.lib.cpSpaceReindexShapesForBody(self.space._space, body._body)


def copy_spacing(segments: Sequence[tuple[Point, Point]], radius: float) -> float:
    """A power of two wider than the arena plus two robot diameters and a margin."""
    xs = [p[0] for seg in segments for p in seg]
    return float(2 ** math.ceil(math.log2(max(xs) - min(xs) + 4.0 * radius + 64.0)))


class World:
    """Walls as static segments and ``n_robots`` circle bodies in one pymunk space: each
    robot in its own copy of the arena, or all in one (``shared``: see the module doc)."""

    def __init__(
        self,
        segments: Sequence[tuple[Point, Point]],
        radius: float,
        n_robots: int = 1,
        shared: bool = False,
    ) -> None:
        self.radius = float(radius)
        self.segments = [(tuple(map(float, a)), tuple(map(float, b))) for a, b in segments]
        self.shared = bool(shared)
        """The robots share one copy of the arena and are bodies to each other."""
        copies = 1 if self.shared else n_robots
        self.space = pymunk.Space()
        """The thin walls (what the sensors see) and the robots' bodies."""
        self.spacing = copy_spacing(self.segments, self.radius) if copies > 1 else 0.0
        """x distance between the arena copies of successive robots (0: one copy)."""
        self.offsets = [k * self.spacing for k in range(copies)]
        self.motion = [pymunk.Space() for _ in range(copies)]
        """Per robot, its copy's walls as segments of its radius and its wall-end discs,
        in a space of their own: what the robot's moves ask (a shared world's robots
        all ask the one copy's)."""
        added = [self._add_walls(k) for k in range(copies)]
        self.copies = [walls for walls, _ in added]
        """Thin wall shapes of each robot's copy of the arena, in :attr:`segments` order."""
        self.ends = [discs for _, discs in added]
        """Discs of the robot's radius at the wall ends of each robot's copy."""
        if self.shared:  # one copy, every robot's
            self.offsets = self.offsets * n_robots
            self.motion = self.motion * n_robots
            self.copies = self.copies * n_robots
            self.ends = self.ends * n_robots
        self._cp = _Chipmunk(self.space, self.motion)
        self.walls = self.copies[0]
        """Wall shapes of robot 0's copy: the arena's own coordinates."""
        self.present = np.full(n_robots, not self.shared, np.bool_)
        """Per robot: it is in the arena (a shared world's robots from :meth:`place` to
        :meth:`park`; an isolated world's always, each in its own copy)."""
        self.xy = np.zeros((n_robots, 2)) if self.shared else None
        """A shared world's robots' centres, ``(n_robots, 2)``, as their bodies hold them
        (a parked robot's where it was parked); None in an isolated world."""
        self.bodies: list[pymunk.Body] = []
        self.shapes: list[pymunk.Circle] = []
        for i in range(n_robots):
            self._add_robot(i)
        self.heading = [0.0] * n_robots

    @classmethod
    def from_arena(
        cls, arena: Arena, radius: float, n_robots: int = 1, shared: bool = False
    ) -> World:
        """A world holding ``arena``'s walls and obstacles (``rotate_deg`` applied)."""
        return cls(arena.to_world().segments(), radius, n_robots, shared)

    def _add_walls(self, k: int) -> tuple[list[pymunk.Segment], list[pymunk.Circle]]:
        """Add robot ``k``'s copy of the walls (shifted by its offset along x): thin
        segments to :attr:`space` for the sensors; segments of the robot's radius and a
        disc of the robot's radius at every wall end (each point once, in the order the
        walls first name them) to its motion space. Returns the thin walls and the discs."""
        dx = self.offsets[k]
        motion = self.motion[k]
        walls, thick = [], []
        for (ax, ay), (bx, by) in self.segments:
            for space, thickness, category, shapes in (
                (self.space, 0.0, WALL_CATEGORY, walls),
                (motion, self.radius, MOTION_CATEGORY, thick),
            ):
                seg = pymunk.Segment(space.static_body, (ax + dx, ay), (bx + dx, by), thickness)
                seg.friction = 0.0
                seg.elasticity = 0.0
                seg.filter = pymunk.ShapeFilter(categories=category)
                shapes.append(seg)
        discs = []
        for x, y in dict.fromkeys(p for seg in self.segments for p in seg):
            disc = pymunk.Circle(motion.static_body, self.radius, (x + dx, y))
            disc.filter = pymunk.ShapeFilter(categories=MOTION_CATEGORY)
            discs.append(disc)
        self.space.add(*walls)
        motion.add(*thick, *discs)
        return walls, discs

    def _add_robot(self, i: int) -> None:
        body = pymunk.Body(1.0, math.inf)
        shape = pymunk.Circle(body, self.radius)
        shape.friction = 0.0
        shape.elasticity = 0.0
        shape.filter = self._robot_filter(i) if self.shared else SOLID
        self.space.add(body, shape)
        self.bodies.append(body)
        self.shapes.append(shape)

    def _robot_filter(self, i: int) -> pymunk.ShapeFilter:
        """Robot ``i``'s circle's filter in a shared world: its own group (``i + 1``: its
        own rays skip it), the robots' category while it is in the arena, none parked."""
        category = ROBOT_CATEGORY if self.present[i] else 0
        return pymunk.ShapeFilter(i + 1, category, pymunk.ShapeFilter.ALL_MASKS())

    def sensor_filter(self, i: int = 0) -> pymunk.ShapeFilter:
        """The filter of robot ``i``'s sensor rays: the walls only in an isolated world
        (:data:`WALL_ONLY`); in a shared world the walls and the robots in the arena,
        robot ``i``'s own circle left out (its group)."""
        if not self.shared:
            return WALL_ONLY
        return pymunk.ShapeFilter(group=i + 1, mask=WALL_CATEGORY | ROBOT_CATEGORY)

    @staticmethod
    def robot_of(shape: pymunk.Shape) -> int:
        """The index of the robot whose circle ``shape`` is in a shared world, -1 for a
        wall (a sensor ray's hit: :meth:`sensor_filter` shows nothing else)."""
        return shape.filter.group - 1

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
        x, y = self._cp.position(self.bodies[i])
        if i == 0:
            return (x, y, self.heading[0])
        return (x - self.offsets[i], y, self.heading[i])

    def place(self, i: int, at: Point, heading: float) -> None:
        """Put robot ``i`` at ``at`` (arena coordinates) with ``heading`` (radians); in a
        shared world it is then in the arena (:attr:`present`), wherever it was."""
        x, y = float(at[0]) + self.offsets[i], float(at[1])
        self._cp.set_position(self.bodies[i], x, y)
        self.heading[i] = heading % TWO_PI
        if self.shared:
            self.xy[i] = x, y
            if not self.present[i]:
                self.present[i] = True
                self.shapes[i].filter = self._robot_filter(i)

    def park(self, i: int) -> None:
        """Take robot ``i`` of a shared world out of the arena (its episode ended): no
        obstacle, no sensor target until :meth:`place` puts it back. Its body keeps its
        position; moving it is an error until then."""
        if not self.shared:
            raise ValueError("only a shared world's robots leave the arena")
        self.present[i] = False
        self.shapes[i].filter = self._robot_filter(i)

    def copy_position(self, i: int) -> tuple[float, float]:
        """Robot ``i``'s centre in its own copy's coordinates, exactly as its body holds it
        (what a compiled move of the copy's walls starts from)."""
        return self._cp.position(self.bodies[i])

    def set_copy_position(self, i: int, x: float, y: float) -> None:
        """Put robot ``i``'s body at ``(x, y)`` in its copy's coordinates (a compiled
        move's end, handed back), the heading unchanged."""
        self._cp.set_position(self.bodies[i], float(x), float(y))
        if self.shared:
            self.xy[i] = x, y

    # -- actions --------------------------------------------------------------------
    def act(self, actions: Sequence[int], distance: float, arc: float) -> None:
        """Perform one action per robot: rotations by ``arc`` radians, moves by ``distance``
        along the heading (Forward) or against it (Reverse), each a swept move
        (:func:`sweep`)."""
        for i, action in enumerate(actions):
            self.act_robot(i, action, distance, arc)

    def act_robot(self, i: int, action: int, distance: float, arc: float) -> None:
        """Robot ``i``'s action alone (:meth:`act`): in a shared world the robots act one
        after another, each against the others where they stand."""
        heading = self.heading
        if action == _ROTATE_LEFT:
            heading[i] = (heading[i] + arc) % TWO_PI
        elif action == _ROTATE_RIGHT:
            heading[i] = (heading[i] - arc) % TWO_PI
        elif action in (_FORWARD, _REVERSE):
            d = distance if action == _FORWARD else -distance
            h = heading[i]
            self.shift(i, d * math.cos(h), d * math.sin(h))

    def drive(self, i: int, distance: float, turn: float) -> None:
        """Robot ``i`` drives ``distance`` inches (negative: backwards) while its heading
        turns by ``turn`` radians: the arc of a differential drive whose wheels differ
        (the realism motion model, :class:`~koolio_pymunk.world.motion_errors.MotionErrors`).

        The robot moves along the arc's chord (length ``distance * sin(turn/2) /
        (turn/2)``, direction the heading plus ``turn / 2``) as a swept move, contacts
        included; the heading then turns by ``turn``. With ``turn`` 0 this is exactly
        :meth:`act`'s Forward / Reverse; ``distance`` 0 is a pure turn. (The chord's
        ends are the arc's; the arc bulges from it by about ``distance * turn / 8``: 0.04 in
        for a 12-inch move whose heading drifts 1.5 degrees, koolio-real's drift being
        0.43 +- 0.5 degrees, far below what the sonars resolve. The robot's circle does
        not depend on its heading, so the chord loses only that bulge.)
        """
        h = self.heading[i]
        if distance != 0.0:
            half = 0.5 * turn
            chord = distance if half == 0.0 else distance * (math.sin(half) / half)
            mid = h + half
            self.shift(i, chord * math.cos(mid), chord * math.sin(mid))
        self.heading[i] = (h + turn) % TWO_PI

    def move(self, i: int, distance: float) -> None:
        """Move robot ``i`` alone by ``distance`` along its heading (negative: backwards)."""
        h = self.heading[i]
        self.shift(i, distance * math.cos(h), distance * math.sin(h))

    def shift(self, i: int, dx: float, dy: float) -> None:
        """Move robot ``i``'s centre by ``(dx, dy)`` inches as a swept circle: stopped by
        the first wall (or, in a shared world, another robot in the arena), sliding along
        it (:func:`sweep`); the heading is unchanged."""
        if self.shared and not self.present[i]:
            raise ValueError(f"robot {i} is parked: place it before it moves")
        body = self.bodies[i]
        x, y = self._cp.position(body)
        x, y = sweep(x, y, dx, dy, lambda x, y, dx, dy: self.first_contact(i, x, y, dx, dy))
        self._cp.set_position(body, x, y)
        if self.shared:
            self.xy[i] = x, y

    def first_contact(
        self, i: int, x: float, y: float, dx: float, dy: float
    ) -> tuple[float, float, float]:
        """The first wall (or other robot) robot ``i`` (centre ``(x, y)`` in its copy's
        coordinates) meets moving by ``(dx, dy)``: ``(alpha, nx, ny)``, the fraction of the
        move done and the unit normal from the wall towards the robot; ``(1.0, 0.0, 0.0)``
        when none.

        One ``cpSpaceSegmentQueryFirst`` against the walls and wall-end discs of the
        robot's radius. If it answers ``alpha = 0`` (the move starts touching a wall),
        each of the robot's walls is asked alone (``cpShapeSegmentQuery``, a thin wall
        and the robot's radius): a touching wall (alpha 0) that the move does not go into
        (``dx nx + dy ny >= -ALONG * |d|``) is left out; then each wall-end disc (alpha 0
        there is a touching wall's end, answered by the wall). The smallest alpha wins,
        the first asked on a tie (``cpSpaceSegmentQueryFirst``'s strict ``<``).

        In a shared world each other robot in the arena is asked next, in index order
        (:meth:`robot_contact`); it wins only with a strictly smaller alpha.
        """
        ex = x + dx
        ey = y + dy
        hit = self._cp.first(i, x, y, ex, ey)
        if hit[0] == 0.0:
            hit = self._touching_walls(i, x, y, dx, dy)
        if self.shared:
            return self.robot_contact(i, x, y, dx, dy, hit)
        return hit

    def _touching_walls(
        self, i: int, x: float, y: float, dx: float, dy: float
    ) -> tuple[float, float, float]:
        """:meth:`first_contact` of a move that starts touching a wall: each wall and
        wall-end disc asked alone."""
        ex = x + dx
        ey = y + dy
        length = math.sqrt(dx * dx + dy * dy)
        best, bnx, bny = 1.0, 0.0, 0.0
        for seg in self.copies[i]:
            info = seg.segment_query((x, y), (ex, ey), self.radius)
            if info is None:
                continue
            alpha = info.alpha
            nx, ny = info.normal
            if alpha == 0.0 and dx * nx + dy * ny >= -ALONG * length:
                continue
            if alpha < best:
                best, bnx, bny = alpha, nx, ny
        for disc in self.ends[i]:
            info = disc.segment_query((x, y), (ex, ey), 0.0)
            if info is not None and info.alpha != 0.0 and info.alpha < best:
                best = info.alpha
                bnx, bny = info.normal
        return best, bnx, bny

    def robot_contact(
        self, i: int, x: float, y: float, dx: float, dy: float,
        best: tuple[float, float, float] = (1.0, 0.0, 0.0),
    ) -> tuple[float, float, float]:  # fmt: skip
        """The first other robot of a shared world that robot ``i`` at ``(x, y)`` meets
        moving by ``(dx, dy)``, if it comes before ``best`` (a contact found already):
        ``(alpha, nx, ny)`` as :meth:`first_contact`.

        Each robot ``j != i`` in the arena, in index order: ``cpShapeSegmentQuery`` of its
        circle (radius ``R``) with a query of radius ``R`` (module doc). A robot the move
        starts touching (alpha 0) that the move does not go into (``dx nx + dy ny >=
        -ALONG * |d|``) is left out, as a touching wall is; a robot wins with a strictly
        smaller alpha than the best so far."""
        ex = x + dx
        ey = y + dy
        alpha_best, bnx, bny = best
        length = math.sqrt(dx * dx + dy * dy)
        present, shapes, query = self.present, self.shapes, self._cp.shape_query
        for j in range(len(shapes)):
            if j == i or not present[j]:
                continue
            hit, alpha, nx, ny = query(shapes[j], x, y, ex, ey, self.radius)
            if not hit:
                continue
            if alpha == 0.0 and dx * nx + dy * ny >= -ALONG * length:
                continue
            if alpha < alpha_best:
                alpha_best, bnx, bny = alpha, nx, ny
        return alpha_best, bnx, bny

    # -- geometry queries (for tests and the viewer) ----------------------------------
    def wall_clearance(self, i: int = 0, at: Point | None = None) -> float:
        """Distance from robot ``i``'s edge (at its position, or centred at ``at``, arena
        coordinates) to the nearest wall (negative = overlap)."""
        p = self.bodies[i].position - (self.offsets[i], 0.0) if at is None else at
        best = math.inf
        for seg in self.walls:
            info = seg.point_query(p)
            best = min(best, info.distance)
        return best - self.radius

    def robot_clearance(self, i: int = 0, at: Point | None = None) -> float:
        """Distance from robot ``i``'s edge (at its position, or centred at ``at``) to the
        nearest other robot's edge in a shared world's arena (negative: they overlap;
        infinity: no other robot is in the arena, or the world is not shared): where a
        robot may be placed, and how close two robots came."""
        if not self.shared:
            return math.inf
        x, y = self._cp.position(self.bodies[i]) if at is None else (at[0], at[1])
        best = math.inf
        for j in range(len(self.bodies)):
            if j != i and self.present[j]:
                best = min(best, math.hypot(x - self.xy[j, 0], y - self.xy[j, 1]))
        return best - 2.0 * self.radius

    def overlaps(self, i: int = 0, slop: float = COLLISION_SLOP) -> list[int]:
        """The robots in a shared world's arena that robot ``i`` overlaps by more than
        ``slop`` inches (centres closer than ``2R - slop``)."""
        if not self.shared:
            return []
        x, y = self._cp.position(self.bodies[i])
        return [
            j
            for j in range(len(self.bodies))
            if j != i
            and self.present[j]
            and math.hypot(x - self.xy[j, 0], y - self.xy[j, 1]) < 2.0 * self.radius - slop
        ]
