"""Hand-built cases for koolio_pymunk.world.geometry."""

from __future__ import annotations

import math

import pytest

from koolio_pymunk.world import geometry as g

SQUARE = ((0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0))
L_SHAPE = ((0, 0), (20, 0), (20, 10), (10, 10), (10, 30), (0, 30))


def test_area_and_orientation() -> None:
    assert g.polygon_area(SQUARE) == 100.0
    assert g.is_ccw(SQUARE)
    assert g.polygon_area(tuple(reversed(SQUARE))) == -100.0
    assert not g.is_ccw(tuple(reversed(SQUARE)))
    assert g.polygon_area(L_SHAPE) == 20 * 10 + 10 * 20
    assert g.polygon_area(((0, 0), (4, 0), (0, 3))) == 6.0


@pytest.mark.parametrize(
    ("p", "expected"),
    [
        ((5, 5), g.INSIDE),
        ((0, 5), g.BOUNDARY),
        ((10, 10), g.BOUNDARY),
        ((5, 0), g.BOUNDARY),
        ((11, 5), g.OUTSIDE),
        ((-0.001, 5), g.OUTSIDE),
        ((5, 10.5), g.OUTSIDE),
    ],
)
def test_locate_point_square(p: tuple[float, float], expected: int) -> None:
    assert g.locate_point(p, SQUARE) == expected


def test_point_in_polygon_non_convex() -> None:
    assert g.point_in_polygon((5, 25), L_SHAPE)
    assert g.point_in_polygon((15, 5), L_SHAPE)
    assert not g.point_in_polygon((15, 20), L_SHAPE)  # the notch of the L
    assert not g.point_in_polygon((10, 20), L_SHAPE)  # on the inner edge
    assert not g.point_in_polygon((0, 0), L_SHAPE)  # a vertex is boundary


def test_point_in_polygon_ray_through_vertex() -> None:
    diamond = ((0, -5), (5, 0), (0, 5), (-5, 0))
    assert g.point_in_polygon((0, 0), diamond)
    assert not g.point_in_polygon((-6, 0), diamond)
    assert not g.point_in_polygon((6, 0), diamond)


def test_distance_point_segment() -> None:
    assert g.distance_point_segment((5, 3), (0, 0), (10, 0)) == 3.0
    assert g.distance_point_segment((-3, 4), (0, 0), (10, 0)) == 5.0  # past end a
    assert g.distance_point_segment((13, 4), (0, 0), (10, 0)) == 5.0  # past end b
    assert g.distance_point_segment((3, 4), (0, 0), (0, 0)) == 5.0  # degenerate
    assert math.isclose(g.distance_point_segment((0, 2), (0, 0), (2, 2)), math.sqrt(2))


def test_segments_cross_is_proper_only() -> None:
    assert g.segments_cross((0, 0), (10, 10), (0, 10), (10, 0))
    assert not g.segments_cross((0, 0), (10, 0), (5, 0), (5, 5))  # T touch
    assert not g.segments_cross((0, 0), (10, 0), (10, 0), (20, 5))  # shared endpoint
    assert not g.segments_cross((0, 0), (10, 0), (5, 0), (15, 0))  # collinear overlap
    assert not g.segments_cross((0, 0), (10, 0), (0, 1), (10, 1))  # parallel


def test_segments_intersect_closed() -> None:
    assert g.segments_intersect((0, 0), (10, 10), (0, 10), (10, 0))
    assert g.segments_intersect((0, 0), (10, 0), (5, 0), (5, 5))
    assert g.segments_intersect((0, 0), (10, 0), (10, 0), (20, 5))
    assert g.segments_intersect((0, 0), (10, 0), (5, 0), (15, 0))
    assert not g.segments_intersect((0, 0), (10, 0), (11, 0), (15, 0))
    assert not g.segments_intersect((0, 0), (10, 0), (0, 1), (10, 1))
    assert not g.segments_intersect((0, 0), (10, 0), (5, 1), (5, 5))


def test_polygon_self_intersection() -> None:
    assert g.polygon_self_intersection(SQUARE) is None
    assert g.polygon_self_intersection(L_SHAPE) is None
    bowtie = ((0, 0), (10, 10), (10, 0), (0, 10))
    assert g.polygon_self_intersection(bowtie) == (0, 2)
    # a vertex touching a non-adjacent edge
    touching = ((0, 0), (10, 0), (10, 10), (5, 0.0), (0, 10))
    assert g.polygon_self_intersection(touching) is not None
    # folding back along a line: (0,0)->(10,0)->(5,0)
    assert g.polygon_self_intersection(((0, 0), (10, 0), (5, 0))) is not None
    # collinear points in a straight edge are fine
    assert g.polygon_self_intersection(((0, 0), (5, 0), (10, 0), (10, 10))) is None
    # zero-length edge
    assert g.polygon_self_intersection(((0, 0), (0, 0), (10, 0), (10, 10))) == (0, 1)


def test_polygons_intersect() -> None:
    other = ((5, 5), (15, 5), (15, 15), (5, 15))
    assert g.polygons_intersect(SQUARE, other) is not None
    far = ((20, 20), (30, 20), (30, 30))
    assert g.polygons_intersect(SQUARE, far) is None
    inner = ((2, 2), (4, 2), (4, 4))
    assert g.polygons_intersect(SQUARE, inner) is None  # containment is not an edge hit
