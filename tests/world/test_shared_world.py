"""Robots sharing one arena (``World(..., shared=True)``): a move stops at another robot
and slides along it as at a wall. Hand-built scenes with exact numbers, the compiled
twin (``swept_move.sweep_among``, ``move_among``, ``act_among``) against pymunk's moves
bit for bit on random scenes, and a fuzz of 8 robots in every shipped arena."""

from __future__ import annotations

import math

import numpy as np
import pytest
from move_agreement import (
    compare_shared_moves,
    free_points,
    generated_arenas,
)

from koolio_pymunk.world.arena import load_arena
from koolio_pymunk.world.geometry import point_in_polygon, segments_intersect
from koolio_pymunk.world.physics import COLLISION_SLOP, SKIN, Action, World
from koolio_pymunk.world.segment_query import wall_array
from koolio_pymunk.world.swept_move import (
    act,
    act_among,
    move_among,
    sweep,
    sweep_among,
    world_group,
)

R = 10.0
#: Rounding allowance on positions of a few hundred inches.
EXACT = 1e-9
SHIPPED = ("hallway", "room", "obstacles")


def box(w: float, h: float) -> list:
    return [((0, 0), (w, 0)), ((w, 0), (w, h)), ((w, h), (0, h)), ((0, h), (0, 0))]


def shared(n: int, *places: tuple, w: float = 300.0, h: float = 100.0) -> World:
    """A shared ``w`` x ``h`` box with ``n`` robots, robot ``i`` placed at ``places[i]``
    (``(x, y)`` or ``(x, y, heading)``); the rest parked."""
    world = World(box(w, h), R, n, shared=True)
    for i, p in enumerate(places):
        world.place(i, p[:2], p[2] if len(p) > 2 else 0.0)
    return world


def centres(world: World, i: int, j: int) -> float:
    return math.dist(world.pose(i)[:2], world.pose(j)[:2])


# -- hand-built scenes ---------------------------------------------------------------------


def test_drive_into_a_robot_stops_tangent() -> None:
    """From 30 in short of contact (centres 50 apart), a 40-inch move goes 30 in less the
    skin: the centres end 2R + SKIN apart, and further moves into it go nowhere."""
    w = shared(2, (50, 50), (100, 50))
    w.move(0, 40.0)
    assert w.pose(0)[:2] == (80.0 - SKIN, 50.0)
    assert centres(w, 0, 1) == pytest.approx(2 * R + SKIN, abs=1e-12)
    for _ in range(3):
        w.move(0, 12.0)
    assert w.pose(0)[:2] == pytest.approx((80.0 - SKIN, 50.0), abs=1e-12)
    assert w.pose(1)[:2] == (100.0, 50.0)  # the robot met is not pushed


def test_oblique_into_a_robot_slides_by_the_tangential_part() -> None:
    """Along y = 50 into a robot at (100, 60): contact where (x - 100)^2 + 10^2 = 20^2,
    normal n from the other centre; the rest of the move, its part along n removed,
    carries the robot along the tangent (which leaves the circle: no second contact)."""
    w = shared(2, (50, 50), (100, 60))
    w.move(0, 40.0)
    xc = 100.0 - math.sqrt(300.0)
    nx, ny = (xc - 100.0) / 20.0, -0.5
    rest = 40.0 - (xc - 50.0)
    want = (xc + SKIN * nx + rest * (1 - nx * nx), 50.0 + SKIN * ny - rest * nx * ny)
    assert w.pose(0)[:2] == pytest.approx(want, abs=EXACT)
    assert centres(w, 0, 1) > 2 * R


@pytest.mark.parametrize("gap", [0.0, -0.005])
def test_a_robot_touching_another_moves_away_and_along_it_but_not_into_it(gap: float) -> None:
    """Placed touching (centres 2R + ``gap`` apart: Chipmunk answers alpha 0): a move away
    is free, a move along the tangent is not held, a move into it is held (pushed out by
    the skin), as at a wall (``test_physics``)."""
    start = (100.0 - 2 * R - gap, 50.0)
    w = shared(2, start, (100, 50))
    w.move(0, 12.0)  # into it
    assert w.pose(0)[:2] == (start[0] - SKIN, 50.0)
    w.place(0, start, math.pi / 2)  # along the tangent
    w.move(0, 12.0)
    assert w.pose(0)[:2] == (start[0], 62.0)
    w.place(0, start, math.pi)  # away
    w.move(0, 12.0)
    assert w.pose(0)[:2] == (start[0] - 12.0, 50.0)


def test_squeezed_between_a_wall_and_a_robot() -> None:
    """A robot 19 in above the floor (a gap narrower than the diameter) stops a robot
    driving along the floor: it slides off the robot into the floor and stays left of
    it, overlapping neither. With a gap of 21 in it slides through."""
    for gap, passes in ((19.0, False), (21.0, True)):
        w = shared(2, (100, 12), (150, R + gap))
        for _ in range(10):
            w.move(0, 12.0)
            assert w.wall_clearance(0) >= -EXACT and w.robot_clearance(0) >= -EXACT
        x = w.pose(0)[0]
        assert (x > 200.0) if passes else (x < 150.0), (gap, w.pose(0))
        if not passes:  # wedged: touching the floor and the robot
            assert w.wall_clearance(0) < 1e-6 and w.robot_clearance(0) < 1e-6


def test_a_parked_robot_is_no_obstacle() -> None:
    w = shared(3, (50, 50), (100, 50), (200, 50))
    w.park(1)
    assert not w.present[1] and w.present[0] and w.present[2]
    w.move(0, 100.0)
    assert w.pose(0)[:2] == (150.0, 50.0)  # through robot 1's place, up to robot 2
    assert w.robot_clearance(0) == 30.0
    w.move(0, 40.0)
    assert w.pose(0)[0] == pytest.approx(180.0 - SKIN, abs=1e-12)
    w.place(1, (100, 50), 0.0)  # back in the arena
    assert w.present[1] and w.overlaps(1) == []
    with pytest.raises(ValueError):
        w.park(1) or w.move(1, 12.0)  # a parked robot does not move


def test_a_new_shared_world_has_every_robot_parked() -> None:
    w = World(box(100, 100), R, 3, shared=True)
    assert not w.present.any()
    w.place(0, (50, 50), 0.0)
    w.move(0, 12.0)  # the others, at the origin, are not in the arena
    assert w.pose(0)[:2] == (62.0, 50.0) and w.robot_clearance(0) == math.inf


def test_an_isolated_world_is_not_shared() -> None:
    w = World(box(200, 100), R, 2)
    assert not w.shared and w.present.all() and w.xy is None
    with pytest.raises(ValueError):
        w.park(0)
    assert w.robot_clearance(0) == math.inf and w.overlaps(0) == []


def test_robot_clearance_and_overlaps() -> None:
    w = shared(3, (50, 50), (69.995, 50), (50, 75))
    assert w.robot_clearance(0) == pytest.approx(-0.005, abs=1e-12)
    assert w.overlaps(0) == [] and w.overlaps(0, slop=0.001) == [1]
    assert w.robot_clearance(2) == pytest.approx(5.0)
    assert w.robot_clearance(2, at=(50, 90)) == pytest.approx(20.0)


# -- the compiled twin ---------------------------------------------------------------------


def test_compiled_moves_exact_numbers() -> None:
    w = shared(3, (50, 50), (100, 50), (100, 60))
    walls = wall_array(w)
    w.park(2)
    assert move_among(walls, w.xy, w.present, 0, 50.0, 50.0, 0.0, 40.0, R) == (80.0 - SKIN, 50.0)
    assert sweep_among(walls, w.xy, w.present, 0, 50.0, 50.0, -60.0, 0.0, R) == (10.0 + SKIN, 50.0)
    assert sweep_among(walls, w.xy, w.present, 1, 100.0, 50.0, -60.0, 0.0, R) == (70.0 + SKIN,
                                                                                  50.0)  # fmt: skip
    w.park(1)  # nobody in the way: the walls-only sweep, bit for bit
    assert sweep_among(walls, w.xy, w.present, 0, 50.0, 50.0, 300.0, 7.0, R) == sweep(
        walls, 50.0, 50.0, 300.0, 7.0, R
    )


def test_act_among_draws_as_act() -> None:
    """``act_among`` turns and draws a real drive's errors exactly as ``act``; with the
    other robots parked it ends where ``act`` does, with them in the way it stops."""
    w = shared(2, (50, 50), (80, 52))
    walls = wall_array(w)
    world = world_group(walls, R, 12.0, math.radians(15))
    motion = np.array([1.0, 0.01, 0.02, 0.05, 0.03])
    for action in range(5):
        a, b = np.random.default_rng(action), np.random.default_rng(action)
        w.park(1)
        want = act(action, 50.0, 50.0, 0.3, a, world, motion)
        assert act_among(action, 50.0, 50.0, 0.3, b, world, motion, w.xy, w.present, 0) == want
        assert a.random() == b.random()  # the same draws taken
        w.place(1, (80, 52), 0.0)
    rng = np.random.default_rng(0)
    w.place(1, (80, 50), 0.0)
    x, y, _ = act_among(3, 50.0, 50.0, 0.0, rng, world, np.zeros(5), w.xy, w.present, 0)
    assert (x, y) == (60.0 - SKIN, 50.0)


@pytest.mark.parametrize("name", SHIPPED)
def test_compiled_move_equals_pymunk_move_among_robots(name: str) -> None:
    """8 robots: 6,000 random moves (``compare_shared_moves``: starts against robots and
    nudged into walls, parked robots crossed), the same end positions bit for bit."""
    r = compare_shared_moves(name, 6_000, seed=1)
    assert r.mismatches == 0, r
    assert r.robot_contacts > 500 and r.touching_robot > 150 and r.parked_crossed > 100, r
    assert r.min_robot_clearance >= -5 * SKIN and r.min_clearance >= -5 * SKIN, r


@pytest.mark.parametrize("k", range(4))
def test_compiled_move_equals_pymunk_move_among_robots_in_generated_arenas(k: int) -> None:
    arena = generated_arenas(4, seed=3)[k]
    r = compare_shared_moves(arena, 1_500, seed=k, others=5 + k)
    assert r.mismatches == 0 and r.robot_contacts > 100, r


def test_shared_agreement_can_fail() -> None:
    """The comparison sees another robot moved by 1e-9 in: the compiled moves then
    differ from pymunk's."""
    arena = load_arena("room")
    w = World.from_arena(arena, R, 8, shared=True)
    walls = wall_array(w)
    rng = np.random.default_rng(5)
    spots = free_points(arena, R, 400, rng)
    k = 0
    for p in spots:
        if k < 8 and w.robot_clearance(k, p) > 0.0:
            w.place(k, p, 0.0)
            k += 1
    assert k == 8
    differ = met = 0
    for _ in range(1_500):
        i = int(rng.integers(8))
        h = float(rng.uniform(0, 2 * math.pi))
        sx, sy = w.pose(i)[:2]
        d = 40.0
        shifted = move_among(walls, w.xy + 1e-9, w.present, i, sx, sy, h, d, R)
        alone = move_among(walls, w.xy, w.present * (np.arange(8) == i), i, sx, sy, h, d, R)
        w.place(i, (sx, sy), h)
        w.move(i, d)
        want = w.pose(i)[:2]
        assert move_among(walls, w.xy, w.present, i, sx, sy, h, d, R) == want
        met += want != alone
        differ += shifted != want
    assert met > 100 and differ > 30, (met, differ)


# -- fuzz ----------------------------------------------------------------------------------


def _crosses_wall(world: World, p: tuple, q: tuple) -> bool:
    return any(segments_intersect(p, q, a, b) for a, b in world.segments)


@pytest.mark.parametrize("name", SHIPPED)
def test_fuzz_eight_robots(name: str) -> None:
    """8 robots in one shipped arena, 1,500 ticks of random actions each (distances up to
    a diameter, mostly Forward): no robot leaves the arena, enters an obstacle or crosses
    a wall; no two overlap by more than the wall slop (none by more than two skins, in
    fact); none stuck for good (every robot moves 1 in or more in every 300 ticks)."""
    arena = load_arena(name)
    laid = arena.to_world()
    w = World.from_arena(arena, R, 8, shared=True)
    rng = np.random.default_rng(11)
    spots = iter(free_points(arena, R, 400, rng))
    for i in range(8):
        p = next(spots)
        while w.robot_clearance(i, p) <= 0.0:
            p = next(spots)
        w.place(i, p, float(rng.uniform(0, 2 * math.pi)))
    worst_wall = worst_robot = math.inf
    window = [w.pose(i)[:2] for i in range(8)]
    moved = [0.0] * 8
    for tick in range(1, 1_501):
        for i in range(8):
            action = Action.FORWARD if rng.random() < 0.6 else int(rng.integers(5))
            before = w.pose(i)[:2]
            actions = [Action.STOP] * 8
            actions[i] = action
            w.act(actions, float(rng.uniform(0.5, 2 * R)), float(rng.uniform(0.05, 1.0)))
            after = w.pose(i)[:2]
            assert not _crosses_wall(w, before, after), (i, before, after)
            assert point_in_polygon(after, laid.walls)
            assert not any(point_in_polygon(after, ob) for ob in laid.obstacles)
            worst_wall = min(worst_wall, w.wall_clearance(i))
            worst_robot = min(worst_robot, w.robot_clearance(i))
            moved[i] = max(moved[i], math.dist(window[i], after))
        if tick % 300 == 0:
            assert min(moved) >= 1.0, moved
            window = [w.pose(i)[:2] for i in range(8)]
            moved = [0.0] * 8
    assert worst_robot >= -COLLISION_SLOP and worst_robot >= -2 * SKIN, worst_robot
    assert worst_wall >= -2 * SKIN, worst_wall
    assert worst_robot < 1e-6  # the robots did meet
