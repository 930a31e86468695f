"""Chipmunk's segment query with a radius, compiled, and the compiled swept move: exact
numbers on hand-built scenes, and pymunk's own answers bit for bit on random queries and
random moves in every shipped arena and in generated ones."""

from __future__ import annotations

import math

import numpy as np
import pymunk
import pytest
from move_agreement import compare_moves, generated_arenas

from koolio_pymunk.world.arena import load_arena
from koolio_pymunk.world.physics import MOTION_ONLY, SKIN, WALL_ONLY, World
from koolio_pymunk.world.segment_query import (
    circle_query,
    first_contact,
    segment_query_radius,
    wall_array,
    wall_row,
)
from koolio_pymunk.world.swept_move import move, sweep

R = 10.0
SHIPPED = ("hallway", "room", "obstacles")
#: Spaces of the walls made by :func:`thin_wall` (a shape's space must outlive its queries).
SPACES: list[pymunk.Space] = []


def bits(values: tuple) -> tuple:
    """Floats as their bit patterns (so -0.0 and 0.0, or NaNs, compare as they are)."""
    return tuple(np.float64(v).view(np.int64) if isinstance(v, float) else v for v in values)


def thin_wall(a: tuple, b: tuple) -> pymunk.Segment:
    space = pymunk.Space()
    seg = pymunk.Segment(space.static_body, a, b, 0.0)
    space.add(seg)  # caches the shape's world coordinates, as the World's walls
    SPACES.append(space)
    return seg


def pymunk_answer(seg: pymunk.Shape, start: tuple, end: tuple, radius: float) -> tuple:
    info = seg.segment_query(start, end, radius)
    if info is None:
        return (False, 1.0, 0.0, 0.0)
    return (True, info.alpha, info.normal.x, info.normal.y)


def compiled_answer(seg: pymunk.Segment, start: tuple, end: tuple, radius: float) -> tuple:
    return segment_query_radius(*wall_row(seg)[:6], *start, *end, radius)


# -- hand-built scenes ---------------------------------------------------------------------


def test_face_hit_exact() -> None:
    """A circle of radius 10 falling from y = 30 to 0 onto the wall y = 0 touches it at
    y = 10: two thirds of the way, normal straight up."""
    hit, alpha, nx, ny = segment_query_radius(0, 0, 100, 0, 0, -1, 50, 30, 50, 0, R)
    assert hit and alpha == pytest.approx(2 / 3, abs=1e-15) and (nx, ny) == (0.0, 1.0)


def test_end_cap_hit_exact() -> None:
    """Passing the end (100, 0) of the wall (100, 0)-(200, 0) 5 in above its line: the
    circle touches the end point when (x - 100)^2 + 5^2 = 10^2."""
    hit, alpha, nx, ny = segment_query_radius(100, 0, 200, 0, 0, -1, 80, 5, 120, 5, R)
    x = 100 - math.sqrt(75)
    assert hit and alpha == pytest.approx((x - 80) / 40, abs=1e-15)
    assert (nx, ny) == pytest.approx(((x - 100) / R, 0.5), abs=1e-15)


def test_start_touching_answers_alpha_zero_and_nearest_point_normal() -> None:
    """Chipmunk's answer for a query that starts within the radius, whichever way it
    goes: alpha 0 and the normal from the wall's nearest point."""
    for end in ((50, 30), (50, 0), (80, 8)):
        assert segment_query_radius(0, 0, 100, 0, 0, -1, 50, 8, *end, R) == (True, 0.0, 0.0, 1.0)
    hit, alpha, nx, ny = segment_query_radius(0, 0, 100, 0, 0, -1, 106, 8, 200, 8, R)
    assert (hit, alpha) == (True, 0.0) and (nx, ny) == pytest.approx((0.6, 0.8), abs=1e-15)


def test_miss() -> None:
    assert segment_query_radius(0, 0, 100, 0, 0, -1, 50, 30, 50, 11, R) == (False, 1.0, 0.0, 0.0)
    assert segment_query_radius(0, 0, 100, 0, 0, -1, 120, 5, 111, 5, R)[0] is False


def test_chipmunk_space_query_with_radius_misses_walls() -> None:
    """Why the world keeps walls of the robot's radius: with several walls, Chipmunk's
    spatial index tests the query's centre line only against the walls' boxes, so a
    radius-10 query from (50, 20) to (50, 5) misses the wall y = 0 it touches. The
    world's query (radius-0 against the walls of radius 10) finds it."""
    segs = [((0, 0), (100, 0)), ((0, 200), (100, 200)), ((200, 0), (200, 100))]
    w = World(segs, R)
    assert w.space.segment_query_first((50, 20), (50, 5), R, WALL_ONLY) is None
    hit = w.motion[0].segment_query_first((50, 20), (50, 5), 0.0, MOTION_ONLY)
    assert hit is not None and hit.alpha == pytest.approx(2 / 3)
    assert w.first_contact(0, 50, 20, 0, -15) == pytest.approx((2 / 3, 0.0, 1.0))


def test_chipmunk_segment_query_skips_end_caps_beside_the_line() -> None:
    """Why the world keeps discs at the wall ends: a query that starts beside a wall's
    line past its end (within the radius of the line, not of the wall) and crosses the
    line's offset inside the wall's span never asks the end cap: both walls of an acute
    spike miss the circle that runs into its tip. The compiled query repeats the miss
    (it is Chipmunk's), the disc of the tip finds the contact."""
    tip = (40.22887503801658, 6.492451036040616)
    a, c = (220.5162524687252, 18.398737149094718), (235.91047538371546, 61.55564880828371)
    start = (31.01358610277688, 2.554906995762967)
    end = (start[0] + 12 * math.cos(6.276227700394423), start[1] + 12 * math.sin(6.276227700394423))
    for seg in (thin_wall(a, tip), thin_wall(tip, c)):
        assert pymunk_answer(seg, start, end, R)[0] is False
        assert compiled_answer(seg, start, end, R)[0] is False
    hit, alpha, _, _ = circle_query(*tip, R, *start, *end, 0.0)
    assert hit and 0 < alpha < 0.01
    walls = wall_array(World([(a, tip), (tip, c), (c, a)], R))
    active = np.arange(3)
    assert (
        first_contact(*start, end[0] - start[0], end[1] - start[1], R, walls, active, 3)[0] == alpha
    )


def test_compiled_move_exact_numbers() -> None:
    w = World([((0, 0), (100, 0)), ((100, 0), (100, 100)), ((100, 100), (0, 100)),
               ((0, 100), (0, 0))], R)  # fmt: skip
    walls = wall_array(w)
    assert move(walls, 50.0, 50.0, 0.0, 12.0, R) == (62.0, 50.0)
    assert move(walls, 85.0, 50.0, 0.0, 12.0, R) == pytest.approx((90 - SKIN, 50), abs=1e-12)
    x, y = move(walls, 50.0, 85.0, math.radians(30), 12.0, R)
    assert (x, y) == pytest.approx((50 + 12 * math.cos(math.radians(30)), 90 - SKIN), abs=1e-12)
    assert sweep(walls, 80.0, 80.0, 20.0, 20.0, R) == pytest.approx((90 - SKIN, 90 - SKIN))
    assert move(walls, 85.0, 50.0, 0.0, -12.0, R) == (73.0, 50.0)
    assert move(walls, 50.0, 50.0, 1.0, 0.0, R) == (50.0, 50.0)


# -- pymunk's answers, bit for bit ---------------------------------------------------------


def _random_walls(rng: np.random.Generator, n: int) -> list[pymunk.Segment]:
    out = []
    for _ in range(n):
        a = rng.uniform(-60, 60, 2)
        if rng.random() < 0.3:  # axis-aligned, as most shipped walls
            b = a.copy()
            b[int(rng.integers(2))] += rng.choice([-1, 1]) * rng.uniform(0.5, 120)
        else:
            b = rng.uniform(-60, 60, 2)
        out.append(thin_wall(tuple(map(float, a)), tuple(map(float, b))))
    return out


def test_radius_query_equals_pymunk_per_wall() -> None:
    """``segment_query_radius`` is ``Segment.segment_query(start, end, radius)``: the same
    hit, alpha and normal bits on 20,000 random queries, which meet walls by their
    faces, by their end caps, from a start touching them, and miss them."""
    rng = np.random.default_rng(11)
    walls = _random_walls(rng, 200)
    kinds = {"touching": 0, "face": 0, "cap": 0, "miss": 0}
    for i in range(20_000):
        seg = walls[i % len(walls)]
        p = seg.a + (seg.b - seg.a) * float(rng.uniform(-0.3, 1.3))
        start = p + pymunk.Vec2d(*rng.uniform(-25, 25, 2))
        end = start + pymunk.Vec2d(*rng.uniform(-40, 40, 2))
        start, end = tuple(start), tuple(end)
        want = pymunk_answer(seg, start, end, R)
        assert bits(compiled_answer(seg, start, end, R)) == bits(want), (seg.a, seg.b, start, end)
        n = seg.normal
        if not want[0]:
            kinds["miss"] += 1
        elif want[1] == 0.0:
            kinds["touching"] += 1
        elif abs(abs(want[2] * n.x + want[3] * n.y) - 1.0) < 1e-12:
            kinds["face"] += 1
        else:
            kinds["cap"] += 1
    assert min(kinds.values()) > 1000, kinds


def test_circle_query_equals_pymunk_disc() -> None:
    """``circle_query`` is a pymunk disc's ``segment_query`` (radius 0) for starts
    outside the disc (inside, pymunk answers alpha 0 before asking)."""
    rng = np.random.default_rng(12)
    space = pymunk.Space()
    hits = 0
    for _ in range(5_000):
        c = tuple(map(float, rng.uniform(-50, 50, 2)))
        disc = pymunk.Circle(space.static_body, R, c)
        space.add(disc)
        start = tuple(map(float, np.array(c) + rng.uniform(-30, 30, 2)))
        end = tuple(map(float, np.array(start) + rng.uniform(-40, 40, 2)))
        want = pymunk_answer(disc, start, end, 0.0)
        if math.dist(start, c) - R <= 0.0:
            assert want[:2] == (True, 0.0)
            continue
        assert bits(circle_query(*c, R, *start, *end, 0.0)) == bits(want)
        hits += want[0]
        space.remove(disc)
    assert hits > 300


@pytest.mark.parametrize("name", SHIPPED)
def test_first_contact_equals_the_world(name: str) -> None:
    """The compiled first contact over an arena's walls is the world's (pymunk's space
    query, or each wall and end alone from a start touching one): 5,000 random moves,
    a third of them from a start touching a wall."""
    w = World.from_arena(load_arena(name), R)
    walls = wall_array(w)
    active = np.arange(walls.shape[0])
    rng = np.random.default_rng(13)
    xs = [p[0] for s in w.segments for p in s]
    ys = [p[1] for s in w.segments for p in s]
    touching = 0
    for i in range(5_000):
        k = int(rng.integers(walls.shape[0]))
        if i % 3 == 0:  # start within a few skins of a wall's side or end
            a, b = walls[k, 0:2], walls[k, 2:4]
            p = a + (b - a) * rng.uniform(-0.1, 1.1)
            side = rng.choice([-1.0, 1.0]) * walls[k, 4:6]
            x, y = p + side * (R + rng.uniform(-3, 3) * SKIN)
        else:
            x, y = rng.uniform(min(xs), max(xs)), rng.uniform(min(ys), max(ys))
        dx, dy = rng.uniform(-30, 30, 2)
        x, y, dx, dy = float(x), float(y), float(dx), float(dy)
        want = w.first_contact(0, x, y, dx, dy)
        touching += w._cp.first(0, x, y, x + dx, y + dy)[0] == 0.0
        got = first_contact(x, y, dx, dy, R, walls, active, walls.shape[0])
        assert bits(got) == bits(want), (x, y, dx, dy)
    assert touching > 500


@pytest.mark.parametrize("name", SHIPPED)
def test_compiled_move_equals_pymunk_move(name: str) -> None:
    """5,000 random moves (see ``move_agreement``): the same end positions, bit for bit,
    with contacts, slides and starts touching walls among them, and no overlap beyond
    the few skins the walk's nudges put a robot into a wall."""
    r = compare_moves(name, 5_000, seed=1)
    assert r.mismatches == 0, r
    assert r.contacts > 1_000 and r.touching > 50, r
    assert r.min_clearance >= -5 * SKIN, r


def test_compiled_move_equals_pymunk_move_in_a_far_copy() -> None:
    """The 64th robot's copy of the hallway (x shifted by 63 copies): still bit for bit."""
    r = compare_moves("hallway", 2_000, seed=2, robots=64)
    assert r.mismatches == 0 and r.contacts > 400, r


@pytest.mark.parametrize("k", range(12))
def test_compiled_move_equals_pymunk_move_in_generated_arenas(k: int) -> None:
    """Jittered and turned shipped arenas, star-shaped rooms with acute corners and
    random obstacles (``generated_arenas``)."""
    arena = generated_arenas(12, seed=3)[k]
    r = compare_moves(arena, 1_500, seed=k)
    assert r.mismatches == 0, r
    assert r.contacts > 200, r
    assert r.min_clearance >= -5 * SKIN, r


def test_agreement_check_can_fail() -> None:
    """The comparison sees a wall moved by 1e-9 in: the compiled moves then differ."""
    w = World.from_arena(load_arena("room"), R)
    walls = wall_array(w)
    moved = walls.copy()
    moved[:, [0, 2]] += 1e-9
    rng = np.random.default_rng(4)
    differ = 0
    x, y = 100.0, 100.0
    for _ in range(500):
        h = float(rng.uniform(0, 2 * math.pi))
        w.place(0, (x, y), h)
        w.move(0, 30.0)
        want = w.pose()[:2]
        assert move(walls, x, y, w.heading[0], 30.0, R) == want
        differ += move(moved, x, y, w.heading[0], 30.0, R) != want
        x, y = want
    assert differ > 50
