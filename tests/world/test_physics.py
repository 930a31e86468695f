"""Swept-circle motion: hand-built scenes with exact numbers, and random-action fuzzing."""

from __future__ import annotations

import math

import numpy as np
import pytest
from move_agreement import generated_arenas

from koolio_pymunk.world.arena import Arena, load_arena
from koolio_pymunk.world.geometry import point_in_polygon, segments_intersect
from koolio_pymunk.world.physics import MAX_QUERIES, SKIN, Action, World

R = 10.0
#: Rounding allowance on positions of a few hundred inches.
EXACT = 1e-9
#: The most a move may leave a robot overlapping a wall: rounding (the motion never
#: overlaps; the old contact solver allowed 0.01 in).
MAX_OVERLAP = 1e-9
SHIPPED = ("hallway", "room", "obstacles")
GENERATED = generated_arenas(8, seed=5)


def box(w: float, h: float) -> list:
    return [((0, 0), (w, 0)), ((w, 0), (w, h)), ((w, h), (0, h)), ((0, h), (0, 0))]


def forward(world: World, n: int, d: float = 12.0) -> None:
    for _ in range(n):
        world.act([Action.FORWARD], d, 0.0)


def queries(world: World, monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """Count ``first_contact`` calls (segment queries) into the returned one-item list."""
    count = [0]
    inner = world.first_contact

    def counted(*args: float) -> tuple[float, float, float]:
        count[0] += 1
        return inner(*args)

    monkeypatch.setattr(world, "first_contact", counted)
    return count


def test_free_move_is_exact() -> None:
    w = World(box(200, 200), R)
    w.place(0, (50, 50), math.radians(30))
    w.act([Action.FORWARD], 12.0, 0.0)
    x, y, _ = w.pose()
    assert (x, y) == (50 + 12 * math.cos(math.radians(30)), 50 + 12 * math.sin(math.radians(30)))
    w.act([Action.REVERSE], 12.0, 0.0)
    assert w.pose()[:2] == pytest.approx((50, 50), abs=1e-12)


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


def test_move_into_wall_at_right_angle_stops_tangent() -> None:
    """From 5 in short of contact, a 12-inch move goes 5 in less the skin, and stays."""
    w = World(box(100, 100), R)
    w.place(0, (85, 50), 0.0)
    w.act([Action.FORWARD], 12.0, 0.0)
    assert w.pose()[:2] == pytest.approx((90.0 - SKIN, 50.0), abs=1e-12)
    assert w.wall_clearance() == pytest.approx(SKIN, abs=1e-12)
    forward(w, 5)
    assert w.pose()[:2] == pytest.approx((90.0 - SKIN, 50.0), abs=1e-12)


def test_reverse_frees_from_contact() -> None:
    w = World(box(100, 100), R)
    w.place(0, (50, 50), 0.0)
    forward(w, 10)
    x0 = w.pose()[0]
    w.act([Action.REVERSE], 12.0, 0.0)
    assert w.pose()[0] == pytest.approx(x0 - 12.0, abs=1e-12)


@pytest.mark.parametrize("gap", [5.0, 0.0])
def test_oblique_move_slides_by_the_tangential_part(gap: float) -> None:
    """At 30 degrees into the top wall from ``gap`` in below contact: the normal part of
    the move is removed after contact, so x advances by 12 cos 30 exactly."""
    w = World(box(400, 100), R)
    w.place(0, (50, 90 - gap), math.radians(30))
    w.act([Action.FORWARD], 12.0, 0.0)
    assert w.pose()[:2] == pytest.approx(
        (50 + 12 * math.cos(math.radians(30)), 90 - SKIN), abs=EXACT
    )
    forward(w, 4)
    assert w.pose()[:2] == pytest.approx(
        (50 + 60 * math.cos(math.radians(30)), 90 - SKIN), abs=EXACT
    )


def test_robot_placed_overlapping_a_wall_slides_and_backs_out() -> None:
    """Placed 0.01 in into the top wall (a query that starts touching): a move along it
    slides, a move into it is held, a move away is free."""
    w = World(box(400, 100), R)
    w.place(0, (50, 90.01), 0.0)
    w.act([Action.FORWARD], 12.0, 0.0)
    assert w.pose()[:2] == pytest.approx((62, 90.01), abs=EXACT)
    w.place(0, (62, 90.01), math.radians(30))
    w.act([Action.FORWARD], 12.0, 0.0)
    slid = (62 + 12 * math.cos(math.radians(30)), 90.01 - SKIN)  # pushed out by the skin
    assert w.pose()[:2] == pytest.approx(slid, abs=EXACT)
    w.act([Action.REVERSE], 12.0, 0.0)
    assert w.pose()[:2] == pytest.approx((slid[0] - 12 * math.cos(math.radians(30)), slid[1] - 6))


@pytest.mark.parametrize("heading_deg", [45.0, 60.0, 30.0])
def test_corner_stops_the_move(heading_deg: float) -> None:
    """Into the north-east corner: along one wall into the other, then no further."""
    w = World(box(100, 100), R)
    w.place(0, (80, 80), math.radians(heading_deg))
    forward(w, 4)
    assert w.pose()[:2] == pytest.approx((90 - SKIN, 90 - SKIN), abs=EXACT)
    assert w.wall_clearance() >= 0.0
    w.act([Action.REVERSE], 12.0, 0.0)
    assert w.wall_clearance() > 5.0  # Reverse frees it


def test_queries_per_move(monkeypatch: pytest.MonkeyPatch) -> None:
    """A free move is one query, a move into a wall two, into a corner three at most."""
    w = World(box(100, 100), R)
    count = queries(w, monkeypatch)
    w.place(0, (50, 50), 0.0)
    w.act([Action.FORWARD], 12.0, 0.0)
    assert count[0] == 1
    w.place(0, (85, 50), math.radians(30))
    count[0] = 0
    w.act([Action.FORWARD], 12.0, 0.0)
    assert count[0] == 2
    for h in np.linspace(0, 2 * math.pi, 37):
        w.place(0, (82, 82), float(h))
        count[0] = 0
        w.act([Action.FORWARD], 12.0, 0.0)
        assert count[0] <= MAX_QUERIES == 3


@pytest.mark.parametrize("distance", [1.0, 5.0, 9.9, 10.0, 15.0, 19.9, 20.0, 50.0, 100.0, 200.0])
@pytest.mark.parametrize("heading_deg", [0.0, 10.0, -40.0])
def test_no_tunnelling_through_thin_wall(distance: float, heading_deg: float) -> None:
    """A thin free-standing wall at x = 500: no move up to 10 diameters crosses it."""
    segs = box(1000, 2000) + [((500, 100), (500, 1900))]
    w = World(segs, R)
    for start in np.linspace(300.0, 489.9, 9):
        w.place(0, (float(start), 1000.0), math.radians(heading_deg))
        for _ in range(5):
            w.act([Action.FORWARD], distance, 0.0)
            assert w.pose()[0] <= 490.0
            assert w.wall_clearance() >= -MAX_OVERLAP


def test_no_tunnelling_past_the_tip_of_an_acute_spike() -> None:
    """The tip of a 10-degree spike passed within the radius, beside its walls' lines:
    Chipmunk's segment query skips the walls' end caps there (test_segment_query.py),
    the world's wall-end discs do not."""
    tip = (40.22887503801658, 6.492451036040616)
    a, c = (220.5162524687252, 18.398737149094718), (235.91047538371546, 61.55564880828371)
    segs = [((p[0] - 300, p[1] - 300), (q[0] - 300, q[1] - 300)) for p, q in box(600, 600)]
    segs += [(a, tip), (tip, c), (c, a)]
    w = World(segs, R)
    w.place(0, (31.01358610277688, 2.554906995762967), 6.276227700394423)
    w.act([Action.FORWARD], 12.0, 0.0)
    assert w.wall_clearance() >= 0.0
    x, y, _ = w.pose()
    assert x < tip[0] and math.dist((x, y), tip) >= R  # deflected by the tip, not past it


def _gap_scene(gap: float) -> World:
    """A box 300 x 200 split at x = 150 by a wall with a centred gap of width ``gap``."""
    lo, hi = 100 - gap / 2, 100 + gap / 2
    segs = box(300, 200) + [((150, 0), (150, lo)), ((150, hi), (150, 200))]
    return World(segs, R)


@pytest.mark.parametrize("narrower", [1.0, 0.1, 0.01])
def test_cannot_enter_gap_narrower_than_diameter(narrower: float) -> None:
    """Blocked however it comes: centred or not, straight or at an angle."""
    w = _gap_scene(2 * R - narrower)
    for offset in np.linspace(-3.0, 3.0, 13):
        for heading in (-10.0, -1.0, 0.0, 1.0, 10.0):
            w.place(0, (120, 100 + offset), math.radians(heading))
            forward(w, 10)
            # stopped by the gap's end points: at best touching both
            assert w.pose()[0] <= 150.0 - math.sqrt(R**2 - (R - narrower / 2) ** 2)
            assert w.wall_clearance() >= 0.0


@pytest.mark.parametrize("offset", [0.0, 0.3, -0.45])
def test_passes_gap_one_inch_wider_than_diameter(offset: float) -> None:
    w = _gap_scene(2 * R + 1.0)
    w.place(0, (100, 100 + offset), 0.0)
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
    assert w.pose()[:2] == pytest.approx((290.0 - SKIN, 100.0), abs=1e-12)
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


def _can_get_away(world: World) -> bool:
    """Some 12-inch move (16 headings) takes the robot at least 1 in from where it is."""
    x, y, h = world.pose()
    best = 0.0
    for k in range(16):
        world.place(0, (x, y), 2 * math.pi * k / 16)
        world.move(0, 12.0)
        best = max(best, math.dist((x, y), world.pose()[:2]))
    world.place(0, (x, y), h)
    return best >= 1.0


@pytest.mark.parametrize("arena", [*SHIPPED, *range(len(GENERATED))])
def test_fuzz_random_actions(arena: str | int) -> None:
    """Every shipped and generated arena: random actions and distances up to a diameter,
    no escape from the arena or into an obstacle, no crossing of a wall, no overlap,
    never stuck for good (checked every 100 actions)."""
    a: Arena = load_arena(arena) if isinstance(arena, str) else GENERATED[arena]
    w = World.from_arena(a, R)
    laid = a.to_world()
    rng = np.random.default_rng(7)
    w.place(0, laid.start.at, 0.0)
    worst = math.inf
    for k in range(2500):
        action = int(rng.integers(5))
        dist = float(rng.uniform(0.5, 2 * R))
        before = w.pose()[:2]
        if rng.random() < 0.6:  # bias towards moving so walls get hit often
            action = Action.FORWARD
        w.act([action], dist, float(rng.uniform(0.05, 1.0)))
        after = w.pose()[:2]
        worst = min(worst, w.wall_clearance())
        assert not _crosses_wall(w, before, after), (before, after)
        assert point_in_polygon(after, laid.walls)
        assert not any(point_in_polygon(after, poly) for poly in laid.obstacles)
        if k % 100 == 99:
            assert _can_get_away(w), after
    assert worst >= -MAX_OVERLAP
    assert worst < 1e-6  # the fuzz really did touch walls


def test_many_robots_each_in_its_own_copy() -> None:
    w = World(box(200, 100), R, n_robots=3)
    w.place(0, (50, 50), 0.0)
    w.place(1, (60, 50), math.pi)  # overlapping the first: allowed, separate arenas
    w.place(2, (185, 50), 0.0)
    w.act([Action.FORWARD, Action.FORWARD, Action.FORWARD], 12.0, 0.0)
    assert w.pose(0)[:2] == (62, 50)
    assert w.pose(1)[:2] == pytest.approx((48, 50), abs=1e-12)
    assert w.pose(2)[:2] == pytest.approx((190 - SKIN, 50), abs=1e-9)  # its own east wall
    body = w.bodies[2].position  # pymunk's body holds the position
    assert (body.x - w.offsets[2], body.y) == pytest.approx(w.pose(2)[:2], abs=1e-9)


def test_drive_moves_along_the_chord_and_turns() -> None:
    w = World(box(200, 200), R)
    w.place(0, (50, 50), 0.0)
    w.drive(0, 12.0, 0.2)
    chord = 12.0 * math.sin(0.1) / 0.1
    assert w.pose() == pytest.approx((50 + chord * math.cos(0.1), 50 + chord * math.sin(0.1), 0.2))
    w.place(0, (185, 50), 0.0)
    w.drive(0, 12.0, 0.2)  # into the east wall: stops tangent, slides
    assert w.pose()[0] == pytest.approx(190 - SKIN, abs=1e-9)
    assert w.wall_clearance() >= 0.0


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
