"""The arena checks' fast paths give the every-pair answers: the sort-and-sweep of edge
boxes, the numpy filter of candidate pairs and numpy point location, on seeded random
polygons full of the awkward cases (collinear edges, shared points, touching corners).

The exact tests (:func:`geometry._edges_meet_badly`, :func:`geometry.segments_intersect`)
are the reference; the fast paths must find the same first pair as a double loop."""

from __future__ import annotations

import math
import random

import numpy as np

from koolio_pymunk.world import geometry as g


def brute_self_intersection(poly: list[g.Point]) -> tuple[int, int] | None:
    """Every pair of edges, in order: the reference."""
    n = len(poly)
    edges = [(poly[i], poly[(i + 1) % n]) for i in range(n)]
    for i in range(n):
        for j in range(i + 1, n):
            if g._edges_meet_badly(edges, i, j, n):
                return (i, j)
    return None


def brute_polygons_intersect(p: list[g.Point], q: list[g.Point]) -> tuple[int, int] | None:
    for i in range(len(p)):
        for j in range(len(q)):
            if g.segments_intersect(p[i], p[(i + 1) % len(p)], q[j], q[(j + 1) % len(q)]):
                return (i, j)
    return None


def grid_polygon(rng: random.Random, n: int, grid: int, star: bool) -> list[g.Point]:
    """Distinct grid points, in random order or by angle (mostly simple, many collinear)."""
    pts = list({(float(rng.randint(0, grid)), float(rng.randint(0, grid))) for _ in range(n)})
    if star:
        cx = sum(p[0] for p in pts) / len(pts) + 0.01
        cy = sum(p[1] for p in pts) / len(pts) + 0.013
        pts.sort(key=lambda p: (math.atan2(p[1] - cy, p[0] - cx), math.hypot(p[0] - cx, p[1] - cy)))
    else:
        rng.shuffle(pts)
    return pts


def test_self_intersection_is_the_first_pair_of_every_pair() -> None:
    """Small polygons (every candidate pair tested) and large ones (the numpy filter)."""
    rng = random.Random(11)
    valid = {True: 0, False: 0}
    for trial in range(600):
        big = trial % 4 == 0
        n = rng.randint(40, 100) if big else rng.randint(3, 30)
        poly = grid_polygon(rng, n, rng.choice([20, 40] if big else [4, 8, 20]), trial % 2 == 0)
        if len(poly) < 3:
            continue
        expected = brute_self_intersection(poly)
        assert g.polygon_self_intersection(poly) == expected, poly
        valid[expected is None] += 1
    assert min(valid.values()) > 100  # both outcomes well represented


def test_one_vertex_moved_onto_another_edge() -> None:
    """Valid polygons with a single touching: a vertex on an edge (or on its corner)."""
    rng = random.Random(5)
    checked = 0
    while checked < 300:
        poly = grid_polygon(rng, rng.randint(4, 60), rng.choice([8, 20, 40]), star=True)
        n = len(poly)
        if n < 4 or brute_self_intersection(poly) is not None:
            continue
        v, e = rng.randrange(n), rng.randrange(n)
        if e in (v, (v - 1) % n):
            continue
        (ax, ay), (bx, by) = poly[e], poly[(e + 1) % n]
        t = rng.choice([0.0, 0.25, 0.5, 1.0])
        poly[v] = (ax + t * (bx - ax), ay + t * (by - ay))
        if any(poly[i] == poly[(i + 1) % n] for i in range(n)):
            continue
        expected = brute_self_intersection(poly)
        assert expected is not None
        assert g.polygon_self_intersection(poly) == expected, poly
        checked += 1


def test_polygons_intersect_is_the_first_pair_of_every_pair() -> None:
    """Including polygons that only share a corner point (both edges end or start there)."""
    rng = random.Random(3)
    outcomes = {True: 0, False: 0}
    for trial in range(1200):
        big = trial % 4 == 0
        n = (20, 60) if big else (3, 8)
        p, q = (
            grid_polygon(rng, rng.randint(*n), rng.choice([20] if big else [4, 8]), star=True)
            for _ in "pq"
        )
        if min(len(p), len(q)) < 3:
            continue
        expected = brute_polygons_intersect(p, q)
        assert g.polygons_intersect(p, q) == expected, (p, q)
        outcomes[expected is not None] += 1
    assert min(outcomes.values()) > 100
    # a shared corner where the edges of one end and those of the other start
    assert g.polygons_intersect([(4, 2), (8, 2), (8, 8)], [(4, 1), (4, 2), (2, 4)]) is not None


def test_the_numpy_filter_keeps_every_pair_that_meets() -> None:
    """``_may_meet`` on every pair: whatever it drops, the exact test finds apart."""
    rng = random.Random(8)
    for trial in range(300):
        p = grid_polygon(rng, rng.randint(12, 40), rng.choice([4, 8, 20]), trial % 2 == 0)
        q = grid_polygon(rng, rng.randint(12, 40), rng.choice([4, 8, 20]), trial % 3 == 0)
        n, m = len(p), len(q)
        edges = [(p[i], p[(i + 1) % n]) for i in range(n)]
        pairs = np.array([(i, j) for i in range(n) for j in range(i + 1, n)], dtype=np.int64)
        kept = {tuple(x) for x in g._may_meet(p, p, pairs, adjacent_in=n).tolist()}
        for i, j in pairs.tolist():
            assert (i, j) in kept or not g._edges_meet_badly(edges, i, j, n), (p, i, j)
        pairs = np.array([(i, j) for i in range(n) for j in range(m)], dtype=np.int64)
        kept = {tuple(x) for x in g._may_meet(p, q, pairs).tolist()}
        for i, j in pairs.tolist():
            meet = g.segments_intersect(p[i], p[(i + 1) % n], q[j], q[(j + 1) % m])
            assert (i, j) in kept or not meet, (p, q, i, j)


def test_overlapping_pairs_are_exactly_the_overlapping_boxes() -> None:
    rng = random.Random(6)
    for _ in range(100):
        a = _boxes(rng, rng.randint(1, 60))
        b = _boxes(rng, rng.randint(1, 60))
        every = [
            (i, j)
            for i in range(len(a))
            for j in range(len(b))
            if a[i, 0] <= b[j, 2]
            and b[j, 0] <= a[i, 2]
            and a[i, 1] <= b[j, 3]
            and b[j, 1] <= a[i, 3]
        ]
        assert g.overlapping_pairs(a, b).tolist() == [list(x) for x in every]
        own = [(i, j) for i, j in _pairs_within(a)]
        assert g.overlapping_pairs(a).tolist() == [list(x) for x in own]


def _boxes(rng: random.Random, n: int) -> np.ndarray:
    lo = np.array([[rng.randint(0, 20), rng.randint(0, 20)] for _ in range(n)], dtype=float)
    size = np.array([[rng.randint(0, 5), rng.randint(0, 5)] for _ in range(n)], dtype=float)
    return np.hstack([lo, lo + size])


def _pairs_within(a: np.ndarray) -> list[tuple[int, int]]:
    return [
        (i, j)
        for i in range(len(a))
        for j in range(i + 1, len(a))
        if a[i, 0] <= a[j, 2] and a[j, 0] <= a[i, 2] and a[i, 1] <= a[j, 3] and a[j, 1] <= a[i, 3]
    ]


def test_large_polygons() -> None:
    n = 5000
    circle = [(math.cos(2 * math.pi * k / n), math.sin(2 * math.pi * k / n)) for k in range(n)]
    assert g.polygon_self_intersection(circle) is None
    crossed = [*circle[:-2], (0.0, 2.0), (0.0, -2.0)]
    i, j = g.polygon_self_intersection(crossed)
    edges = [(crossed[k], crossed[(k + 1) % n]) for k in range(n)]
    assert g._edges_meet_badly(edges, i, j, n)


def test_numpy_point_location_agrees_with_the_loop() -> None:
    """``_locate_point_many_edges`` (polygons of more than 64 edges) against the plain
    loop of :func:`locate_point` on small polygons: vertices, points on edges, grid points."""
    rng = random.Random(9)
    for trial in range(400):
        n = rng.randint(3, 25)
        if trial % 2:
            poly = [(rng.uniform(0, 10), rng.uniform(0, 10)) for _ in range(n)]
        else:
            poly = [(float(rng.randint(0, 6)), float(rng.randint(0, 6))) for _ in range(n)]
        for _ in range(25):
            i = rng.randrange(n)
            (ax, ay), (bx, by) = poly[i], poly[(i + 1) % n]
            t = rng.random()
            p = rng.choice(
                [
                    poly[i],
                    (ax + t * (bx - ax), ay + t * (by - ay)),
                    (float(rng.randint(-1, 7)), float(rng.randint(-1, 7))),
                    (rng.uniform(-1, 11), rng.uniform(-1, 11)),
                ]
            )
            assert g._locate_point_many_edges(p, poly) == g.locate_point(p, poly), (p, poly)
