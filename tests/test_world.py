"""pymunk motion: hand-built scenes with exact numbers, and random-action fuzzing."""

from __future__ import annotations

import math

import numpy as np
import pytest

from koolio_pymunk.arena import load_arena
from koolio_pymunk.geometry import point_in_polygon, segments_intersect
from koolio_pymunk.world import COLLISION_SLOP, Action, World

R = 10.0
MAX_OVERLAP = 0.1


def box(w: float, h: float) -> list:
    return [((0, 0), (w, 0)), ((w, 0), (w, h)), ((w, h), (0, h)), ((0, h), (0, 0))]


def forward(world: World, n: int, d: float = 12.0) -> None:
    for _ in range(n):
        world.act([Action.FORWARD], d, 0.0)


def test_free_move_is_exact() -> None:
    w = World(box(200, 200), R)
    w.place(0, (50, 50), math.radians(30))
    w.act([Action.FORWARD], 12.0, 0.0)
    x, y, _ = w.pose()
    assert x == pytest.approx(50 + 12 * math.cos(math.radians(30)), abs=1e-9)
    assert y == pytest.approx(50 + 12 * math.sin(math.radians(30)), abs=1e-9)
    w.act([Action.REVERSE], 12.0, 0.0)
    assert w.pose()[:2] == pytest.approx((50, 50), abs=1e-9)


def test_rotations_change_only_heading() -> None:
    w = World(box(200, 200), R)
    w.place(0, (50, 50), 0.0)
    w.act([Action.ROTATE_LEFT], 12.0, math.radians(15))
    assert w.pose() == pytest.approx((50, 50, math.radians(15)))
    w.act([Action.ROTATE_RIGHT], 12.0, math.radians(15))
    w.act([Action.ROTATE_RIGHT], 12.0, math.radians(15))
    assert w.pose()[2] == pytest.approx(2 * math.pi - math.radians(15))
    w.act([Action.STOP], 12.0, math.radians(15))
    assert w.pose()[:2] == (50, 50)


def test_stops_at_wall_within_slop() -> None:
    w = World(box(100, 100), R)
    w.place(0, (50, 50), 0.0)
    forward(w, 10)
    x, y, _ = w.pose()
    assert x == pytest.approx(90.0, abs=COLLISION_SLOP + 1e-9)
    assert y == pytest.approx(50.0, abs=1e-9)
    assert w.wall_clearance() >= -MAX_OVERLAP


def test_reverse_frees_from_contact() -> None:
    w = World(box(100, 100), R)
    w.place(0, (50, 50), 0.0)
    forward(w, 10)
    x0 = w.pose()[0]
    w.act([Action.REVERSE], 12.0, 0.0)
    assert w.pose()[0] == pytest.approx(x0 - 12.0, abs=1e-6)


def test_slides_along_wall_when_moving_obliquely() -> None:
    w = World(box(400, 100), R)
    w.place(0, (50, 89.99), math.radians(30))  # touching the top wall, heading into it
    forward(w, 5)
    x, y, _ = w.pose()
    assert y == pytest.approx(90.0, abs=0.02)
    # the normal component is removed: x advances by d*cos(30) per move
    assert x == pytest.approx(50 + 5 * 12 * math.cos(math.radians(30)), abs=0.05)


@pytest.mark.parametrize("distance", [1.0, 5.0, 9.9, 10.0, 15.0, 19.9, 20.0])
def test_no_tunnelling_through_thin_wall(distance: float) -> None:
    # A thin free-standing wall at x = 100 inside a big box.
    segs = box(300, 200) + [((100, 20), (100, 180))]
    w = World(segs, R)
    for start in np.linspace(70.0, 89.9, 9):
        w.place(0, (float(start), 100.0), 0.0)
        for _ in range(5):
            w.act([Action.FORWARD], distance, 0.0)
            assert w.pose()[0] < 100.0 - R + MAX_OVERLAP
        assert w.wall_clearance() >= -MAX_OVERLAP


def _gap_scene(gap: float) -> World:
    """A box 300 x 200 split at x = 150 by a wall with a centred gap of width ``gap``."""
    lo, hi = 100 - gap / 2, 100 + gap / 2
    segs = box(300, 200) + [((150, 0), (150, lo)), ((150, hi), (150, 200))]
    return World(segs, R)


@pytest.mark.parametrize("narrower", [1.0, 0.5, 0.1])
def test_cannot_enter_gap_narrower_than_diameter(narrower: float) -> None:
    """Blocked down to the overlap tolerance (0.1 in narrower than the diameter)."""
    w = _gap_scene(2 * R - narrower)
    for offset in np.linspace(-narrower / 2, narrower / 2, 5):
        w.place(0, (100, 100 + offset), 0.0)
        forward(w, 20)
        assert w.pose()[0] < 150.0  # stopped by the gap's end points
        assert w.wall_clearance() >= -MAX_OVERLAP


def test_passes_gap_one_inch_wider_than_diameter() -> None:
    w = _gap_scene(2 * R + 1.0)
    w.place(0, (100, 100), 0.0)
    forward(w, 10)
    assert w.pose()[0] > 200.0
    assert w.wall_clearance() >= -MAX_OVERLAP


@pytest.mark.parametrize("heading_deg", [0.0, 180.0, 3.0, 177.0])
def test_hugs_wall_around_convex_corner_both_directions(heading_deg: float) -> None:
    """The paper's known flaw: hugging a wall past a convex corner against wall order."""
    # A square obstacle 100..200 x 0..50 (clockwise and counter-clockwise walls alike).
    obstacle = [
        ((100, 0), (200, 0)),
        ((200, 0), (200, 50)),
        ((200, 50), (100, 50)),
        ((100, 50), (100, 0)),
    ]
    w = World(box(300, 150) + obstacle, R)
    # Tangent to the obstacle's top edge, heading slightly into it for 3 and 177 degrees.
    going_right = math.cos(math.radians(heading_deg)) > 0
    start_x = 120.0 if going_right else 180.0
    h = math.radians(-heading_deg if heading_deg in (3.0,) else heading_deg)
    if heading_deg == 177.0:
        h = math.radians(183.0)
    w.place(0, (start_x, 60.0), h)
    xs = []
    for _ in range(12):
        w.act([Action.FORWARD], 12.0, 0.0)
        xs.append(w.pose()[0])
        assert w.wall_clearance() >= -MAX_OVERLAP
    moves = np.diff([start_x, *xs])
    assert (np.abs(moves) > 1.0).all()  # never stuck
    assert (xs[-1] > 230) if going_right else (xs[-1] < 70)


def test_three_walls_at_once() -> None:
    """A dead-end slot 0.5 in wider than the robot: it touches three walls at the end."""
    segs = [
        ((0, 0), (300, 0)),
        ((300, 0), (300, 200)),
        ((300, 200), (0, 200)),
        ((0, 200), (0, 0)),
        ((200, 89.75), (300, 89.75)),
        ((200, 110.25), (300, 110.25)),
    ]
    w = World(segs, R)
    w.place(0, (150, 100), 0.0)
    forward(w, 20)
    x = w.pose()[0]
    assert x == pytest.approx(290.0, abs=0.05)
    assert w.wall_clearance() >= -MAX_OVERLAP
    for _ in range(3):  # jostle: rotate and push into the corners
        for a in (
            Action.ROTATE_LEFT,
            Action.FORWARD,
            Action.ROTATE_RIGHT,
            Action.ROTATE_RIGHT,
            Action.FORWARD,
            Action.ROTATE_LEFT,
        ):
            w.act([a], 12.0, math.radians(15))
            assert w.wall_clearance() >= -MAX_OVERLAP
    w.place(0, w.pose()[:2], 0.0)
    before = w.pose()[0]
    for _ in range(10):
        w.act([Action.REVERSE], 12.0, 0.0)
    assert w.pose()[0] < before - 100  # freed


def _crosses_wall(world: World, p: tuple, q: tuple) -> bool:
    return any(segments_intersect(p, q, a, b) for a, b in world.segments)


@pytest.mark.parametrize("name", ["hallway", "room", "obstacles"])
def test_fuzz_random_actions_in_shipped_arenas(name: str) -> None:
    arena = load_arena(name)
    w = World.from_arena(arena, R)
    rng = np.random.default_rng(7)
    w.place(0, arena.start.at, 0.0)
    worst = math.inf
    for _ in range(2500):
        action = int(rng.integers(5))
        dist = float(rng.uniform(0.5, 2 * R))
        before = w.pose()[:2]
        if rng.random() < 0.6:  # bias towards moving so walls get hit often
            action = Action.FORWARD
        w.act([action], dist, float(rng.uniform(0.05, 1.0)))
        after = w.pose()[:2]
        worst = min(worst, w.wall_clearance())
        assert not _crosses_wall(w, before, after), (before, after)
        assert point_in_polygon(after, arena.walls)
        assert not any(point_in_polygon(after, poly) for poly in arena.obstacles)
    assert worst >= -MAX_OVERLAP
    assert worst < 0.5  # the fuzz really did touch walls


def test_many_robots_do_not_collide_with_each_other() -> None:
    w = World(box(200, 100), R, n_robots=2)
    w.place(0, (50, 50), 0.0)
    w.place(1, (60, 50), math.pi)  # overlapping the first: allowed, separate arenas
    w.act([Action.FORWARD, Action.FORWARD], 12.0, 0.0)
    assert w.pose(0)[:2] == pytest.approx((62, 50), abs=1e-9)
    assert w.pose(1)[:2] == pytest.approx((48, 50), abs=1e-9)


def test_same_moves_same_trajectory() -> None:
    def run() -> list:
        w = World.from_arena(load_arena("obstacles"), R)
        w.place(0, (72, 216), 0.3)
        rng = np.random.default_rng(3)
        out = []
        for _ in range(300):
            w.act([int(rng.integers(5))], 12.0, 0.26)
            out.append(w.pose())
        return out

    assert run() == run()
