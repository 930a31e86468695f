"""The compiled swept move against pymunk's, on random moves in shipped and generated arenas.

:func:`compare_moves` walks a robot through ``moves`` random moves in an arena, each
made twice from the same start: by the pymunk world (:meth:`World.move
<koolio_pymunk.world.physics.World.move>`, Chipmunk's queries) and by the compiled
:func:`koolio_pymunk.world.swept_move.move`, and counts the moves whose end positions
are not bit-identical. The walk is built to meet walls often and in awkward ways:

* each move starts where the last ended (so the robot slides along walls, pushes into
  corners and backs out of them), except for a restart at a random free point now and
  then (3 %);
* headings are kept, drawn at random, or multiples of 15 degrees (moves exactly along
  and across axis-aligned walls, into corners at exactly 45 degrees);
* distances are the actions' 12 in either way, up to 40 in, or up to 10 robot diameters;
* after a move that met a wall, the next start is sometimes nudged by a few skins (so it
  starts touching the wall, or just off it: Chipmunk's alpha-0 answers).

It also records the smallest clearance between the robot's edge and a wall after any
move (negative: an overlap) and how many moves met a wall.

:func:`compare_shared_moves` does the same in a shared world (``World(...,
shared=True)``) with ``others`` more robots in the arena, walking a robot drawn at
random each move against the compiled :func:`~koolio_pymunk.world.swept_move.move_among`:
besides the walk above, a move starts now and then with the mover put against another
robot (its centre ``2R`` from the other's, give or take a few skins: Chipmunk's alpha-0
answers for robots), and a robot is parked or put back in the arena now and then, so
that parked robots are crossed. It counts the moves a robot changed (their end is not
the walls-only move's), the starts touching a robot, and the smallest clearance between
two robots' edges. :func:`generated_arenas`
makes valid arenas to run it in besides the shipped ones: shipped arenas with every
point moved a little and turned by a random angle, and star-shaped rooms with many
walls (acute corners, narrow pockets) and random obstacles.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from koolio_pymunk.store.errors import KoolioError
from koolio_pymunk.world.arena import Arena, load_arena, parse_arena
from koolio_pymunk.world.geometry import distance_point_segment, point_in_polygon
from koolio_pymunk.world.physics import SKIN, TWO_PI, World
from koolio_pymunk.world.segment_query import wall_array
from koolio_pymunk.world.swept_move import move, move_among

#: Probability that a move starts at a new random free point.
RESTART = 0.03
#: Probability that a move after a contact starts nudged by up to 3 skins.
NUDGE = 0.15
#: In a shared world: probability that a move starts with the mover against another robot.
AGAINST = 0.1
#: In a shared world: probability that a move first parks a robot, or puts one back.
PARK = 0.02


@dataclass
class MoveAgreement:
    """Figures of one :func:`compare_moves` run."""

    arena: str
    moves: int
    mismatches: int
    """Moves whose compiled end position differs from pymunk's (in any bit)."""
    contacts: int
    """Moves that met a wall (the end is not the start plus the move)."""
    touching: int
    """Moves that started within the robot's radius of a wall (Chipmunk's alpha 0)."""
    max_abs_diff: float
    """Largest coordinate difference between the two ends, inches."""
    min_clearance: float
    """Smallest distance from the robot's edge to a wall after a move (negative: overlap)."""
    seconds: float

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def free_points(arena: Arena, radius: float, n: int, rng: np.random.Generator) -> np.ndarray:
    """``(n, 2)`` random points of ``arena`` (rotation applied) where a robot of
    ``radius`` fits: inside the walls, outside the obstacles, ``radius`` from every wall."""
    world = arena.to_world()
    segs = world.segments()
    xmin, ymin, xmax, ymax = world.bounds()
    out: list[tuple[float, float]] = []
    while len(out) < n:
        p = (float(rng.uniform(xmin, xmax)), float(rng.uniform(ymin, ymax)))
        if not point_in_polygon(p, world.walls):
            continue
        if any(point_in_polygon(p, ob) for ob in world.obstacles):
            continue
        if min(distance_point_segment(p, a, b) for a, b in segs) < radius:
            continue
        out.append(p)
    return np.array(out).reshape(-1, 2)


def _heading(rng: np.random.Generator, h: float) -> float:
    u = rng.random()
    if u < 0.4:
        return h
    if u < 0.8:
        return float(rng.uniform(0.0, TWO_PI))
    return math.radians(15.0 * int(rng.integers(24)))


def _distance(rng: np.random.Generator, radius: float) -> float:
    u = rng.random()
    if u < 0.5:
        return 12.0 if rng.random() < 0.7 else -12.0
    reach = 40.0 if u < 0.8 else 20.0 * radius
    return float(rng.uniform(-reach, reach))


def compare_moves(
    arena: str | Arena, moves: int, seed: int = 0, radius: float = 10.0, robots: int = 1
) -> MoveAgreement:
    """Make ``moves`` random moves (see the module doc) with pymunk and with the compiled
    move and compare their end positions. With ``robots`` > 1 the walk is the last
    robot's, in its own copy of the arena (coordinates shifted far along x)."""
    if isinstance(arena, str):
        arena = load_arena(arena, radius)
    t0 = time.perf_counter()
    world = World.from_arena(arena, radius, robots)
    i = robots - 1
    walls = wall_array(world, i)
    body = world.bodies[i]
    rng = np.random.default_rng(seed)
    starts = free_points(arena, radius, 64, rng)
    mismatches = contacts = touching = 0
    worst = 0.0
    lowest = math.inf
    x, y = starts[0]
    h = 0.0
    world.place(i, (x, y), h)
    met = False
    for _ in range(moves):
        if rng.random() < RESTART:
            x, y = starts[int(rng.integers(len(starts)))]
            world.place(i, (x, y), h)
        elif met and rng.random() < NUDGE:
            x, y, _h = world.pose(i)
            nudge = rng.uniform(-3.0 * SKIN, 3.0 * SKIN, 2)
            world.place(i, (x + float(nudge[0]), y + float(nudge[1])), h)
        h = _heading(rng, h)
        d = _distance(rng, radius)
        x, y, _h = world.pose(i)
        world.place(i, (x, y), h)
        sx, sy = body.position
        touching += world.wall_clearance(i) <= 0.0
        world.move(i, d)
        got = move(walls, sx, sy, world.heading[i], d, radius)
        want = tuple(body.position)
        if got != want:
            mismatches += 1
            worst = max(worst, abs(got[0] - want[0]), abs(got[1] - want[1]))
        hd = world.heading[i]
        met = want != (sx + d * math.cos(hd), sy + d * math.sin(hd))
        contacts += met
        lowest = min(lowest, world.wall_clearance(i))
    seconds = round(time.perf_counter() - t0, 1)
    return MoveAgreement(arena.name, moves, mismatches, contacts, touching, worst, lowest, seconds)


@dataclass
class SharedMoveAgreement:
    """Figures of one :func:`compare_shared_moves` run."""

    arena: str
    robots: int
    moves: int
    mismatches: int
    """Moves whose compiled end position differs from pymunk's (in any bit)."""
    robot_contacts: int
    """Moves another robot changed (their end is not the walls-only move's)."""
    touching_robot: int
    """Moves that started with the mover's centre within ``2R`` of another's."""
    parked_crossed: int
    """Moves that ended within ``2R`` of a parked robot's centre (it was no obstacle)."""
    max_abs_diff: float
    min_clearance: float
    """Smallest distance from the mover's edge to a wall after a move."""
    min_robot_clearance: float
    """Smallest distance between two robots' edges after a move (negative: overlap)."""
    seconds: float

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def _free_spot(world: World, i: int, spots: np.ndarray, rng: np.random.Generator) -> tuple:
    """A point of ``spots`` where robot ``i`` overlaps no other robot in the arena (its own
    position when 50 draws find none)."""
    for _ in range(50):
        x, y = spots[int(rng.integers(len(spots)))]
        if world.robot_clearance(i, (x, y)) > 0.0:
            return float(x), float(y)
    return world.pose(i)[:2]


def _against(world: World, i: int, rng: np.random.Generator) -> tuple | None:
    """A point with robot ``i``'s centre ``2R`` (give or take 3 skins) from another robot
    in the arena, in a random direction, overlapping no third robot (None: none found)."""
    others = [j for j in range(world.n_robots) if j != i and world.present[j]]
    if not others:
        return None
    j = others[int(rng.integers(len(others)))]
    a = float(rng.uniform(0.0, TWO_PI))
    r = 2.0 * world.radius + float(rng.uniform(-3.0, 3.0)) * SKIN
    x, y = world.xy[j, 0] + r * math.cos(a), world.xy[j, 1] + r * math.sin(a)
    if world.robot_clearance(i, (x, y)) < -4.0 * SKIN or world.wall_clearance(i, (x, y)) < 0.0:
        return None
    return x, y


def compare_shared_moves(
    arena: str | Arena, moves: int, seed: int = 0, radius: float = 10.0, others: int = 7
) -> SharedMoveAgreement:
    """Make ``moves`` random moves of ``1 + others`` robots sharing ``arena`` (see the
    module doc) with pymunk and with the compiled :func:`move_among`, and compare their
    end positions."""
    if isinstance(arena, str):
        arena = load_arena(arena, radius)
    t0 = time.perf_counter()
    n = 1 + others
    world = World.from_arena(arena, radius, n, shared=True)
    walls = wall_array(world)
    rng = np.random.default_rng(seed)
    spots = free_points(arena, radius, 256, rng)
    for i in range(n):
        world.place(i, _free_spot(world, i, spots, rng), 0.0)
    mismatches = contacts = touching = crossed = 0
    worst = 0.0
    lowest = lowest_robot = math.inf
    met = False
    for _ in range(moves):
        if rng.random() < PARK:
            j = int(rng.integers(n))
            if world.present[j] and world.present.sum() > 1:
                world.park(j)
            elif not world.present[j]:
                world.place(j, _free_spot(world, j, spots, rng), world.heading[j])
        movers = np.flatnonzero(world.present)
        i = int(movers[int(rng.integers(len(movers)))])
        h = _heading(rng, world.heading[i])
        u = rng.random()
        if u < RESTART:
            world.place(i, _free_spot(world, i, spots, rng), h)
        elif u < RESTART + AGAINST:
            at = _against(world, i, rng)
            world.place(i, world.pose(i)[:2] if at is None else at, h)
        elif met and u < RESTART + AGAINST + NUDGE:
            x, y, _h = world.pose(i)
            nudge = rng.uniform(-3.0 * SKIN, 3.0 * SKIN, 2)
            world.place(i, (x + float(nudge[0]), y + float(nudge[1])), h)
        else:
            world.place(i, world.pose(i)[:2], h)
        d = _distance(rng, radius)
        sx, sy = world.copy_position(i)
        touching += world.robot_clearance(i) <= 0.0
        got = move_among(walls, world.xy, world.present, i, sx, sy, h, d, radius)
        alone = move(walls, sx, sy, h, d, radius)
        world.move(i, d)
        want = world.copy_position(i)
        if got != want:
            mismatches += 1
            worst = max(worst, abs(got[0] - want[0]), abs(got[1] - want[1]))
        contacts += want != alone
        met = want != (sx + d * math.cos(h), sy + d * math.sin(h))
        lowest = min(lowest, world.wall_clearance(i))
        lowest_robot = min(lowest_robot, world.robot_clearance(i))
        parked = np.flatnonzero(~world.present)
        crossed += any(
            math.hypot(want[0] - world.xy[j, 0], want[1] - world.xy[j, 1]) < 2.0 * radius
            for j in parked
        )
    seconds = round(time.perf_counter() - t0, 1)
    return SharedMoveAgreement(arena.name, n, moves, mismatches, contacts, touching, crossed,
                               worst, lowest, lowest_robot, seconds)  # fmt: skip


def _jittered(base: Arena, rng: np.random.Generator, name: str) -> dict:
    """A shipped arena's data with every point moved up to 3 in and a random turn."""

    def moved(poly: tuple) -> list:
        return [[p[0] + float(rng.uniform(-3, 3)), p[1] + float(rng.uniform(-3, 3))] for p in poly]

    return {
        "name": name,
        "walls": moved(base.walls),
        "obstacles": [moved(ob) for ob in base.obstacles],
        "goals": [{"name": g.name, "at": list(g.at)} for g in base.goals],
        "start": {"at": list(base.start.at)},
        "rotate_deg": float(rng.uniform(-180, 180)),
    }


def _star(rng: np.random.Generator, name: str, radius: float) -> dict:
    """A star-shaped room of 5 to 40 walls round the origin, with up to 4 obstacles."""
    k = int(rng.integers(5, 41))
    angles = np.sort(rng.uniform(0.0, TWO_PI, k))
    radii = rng.uniform(4.0 * radius, 30.0 * radius, k)
    walls = [[float(r * math.cos(a)), float(r * math.sin(a))] for a, r in zip(angles, radii)]
    obstacles = []
    for _ in range(int(rng.integers(0, 5))):
        cx, cy = rng.uniform(-15.0 * radius, 15.0 * radius, 2)
        n = int(rng.integers(3, 6))
        corners = np.sort(rng.uniform(0.0, TWO_PI, n))
        size = rng.uniform(0.5 * radius, 4.0 * radius, n)
        obstacles.append([[float(cx + s * math.cos(a)), float(cy + s * math.sin(a))]
                          for a, s in zip(corners, size)])  # fmt: skip
    return {
        "name": name,
        "walls": walls,
        "obstacles": obstacles,
        "goals": [{"name": "g", "at": [0.0, 0.0]}],
        "start": {"at": [0.0, 0.0]},
    }


def generated_arenas(count: int, seed: int = 0, radius: float = 10.0) -> list[Arena]:
    """``count`` valid arenas (:func:`~koolio_pymunk.world.arena.parse_arena`'s checks,
    the start ``radius`` from every wall): half jittered and turned shipped arenas, half
    star-shaped rooms with obstacles (see the module doc). Drafts that fail the checks
    are drawn again."""
    rng = np.random.default_rng(seed)
    shipped = [load_arena(name, radius) for name in ("hallway", "room", "obstacles")]
    out: list[Arena] = []
    while len(out) < count:
        name = f"generated-{len(out)}"
        if len(out) % 2 == 0:
            data = _jittered(shipped[len(out) // 2 % len(shipped)], rng, name)
        else:
            data = _star(rng, name, radius)
        try:
            out.append(parse_arena(data, name, radius))
        except KoolioError:
            continue
    return out
