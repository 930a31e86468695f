"""Clipping what the editor draws to the canvas, so that a frame costs the same at any zoom.

pygame draws a line or fills a polygon by walking its pixels, on the canvas or not: a
wall a million inches long at 20 pixels per inch is 20 million pixels and takes the
better part of a second, every frame. The editor therefore hands pygame only what lies
near the canvas:

* :func:`drawable_arena` -- the arena for the viewer's ``draw_arena``: unchanged when
  every point is within :data:`SAFE_PIXELS` of the canvas (every shipped arena at every
  zoom), else with its polygons and doors cut to the canvas and a margin (the cuts run
  outside the canvas, so what shows is the same);
* :func:`clip_segment` -- a screen segment cut to a rectangle (the editor's own lines).

Pure geometry: no pygame.

>>> clip_segment((-10, 5), (30, 5), (0, 0, 20, 10))
((0.0, 5.0), (20.0, 5.0))
>>> clip_segment((-10, -5), (-1, -1), (0, 0, 20, 10)) is None
True
>>> clip_polygon([(-10, -10), (30, -10), (30, 30), (-10, 30)], (0, 0, 20, 10))
((0.0, 10.0), (0.0, 0.0), (20.0, 0.0), (20.0, 10.0))
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

from ...world.arena import Arena, Door, Marker, Point

Rect = tuple[float, float, float, float]
"""``(xmin, ymin, xmax, ymax)``."""

SAFE_PIXELS = 32_768
"""A drawing that stays within this many pixels of the canvas is drawn as it is (a line
of 65,000 pixels costs pygame well under a millisecond)."""
MARGIN_PIXELS = 16
"""Cut polygons run this far outside the canvas (beyond the widest line drawn)."""


def inside(p: Point, rect: Rect) -> bool:
    """True when ``p`` lies in ``rect`` (edges included)."""
    return rect[0] <= p[0] <= rect[2] and rect[1] <= p[1] <= rect[3]


def clip_segment(a: Point, b: Point, rect: Rect) -> tuple[Point, Point] | None:
    """The part of segment ``a``-``b`` inside ``rect`` (Liang-Barsky), or None."""
    x0, y0 = float(a[0]), float(a[1])
    dx, dy = float(b[0]) - x0, float(b[1]) - y0
    t0, t1 = 0.0, 1.0
    for p, q in (
        (-dx, x0 - rect[0]),
        (dx, rect[2] - x0),
        (-dy, y0 - rect[1]),
        (dy, rect[3] - y0),
    ):
        if p == 0.0:
            if q < 0.0:
                return None
            continue
        t = q / p
        if p < 0.0:
            t0 = max(t0, t)
        else:
            t1 = min(t1, t)
        if t0 > t1:
            return None
    return (x0 + t0 * dx, y0 + t0 * dy), (x0 + t1 * dx, y0 + t1 * dy)


def clip_polygon(points: Sequence[Point], rect: Rect) -> tuple[Point, ...]:
    """Polygon ``points`` cut to ``rect`` (Sutherland-Hodgman): the same area inside
    ``rect``; new edges run along its sides. Empty when nothing is inside."""
    out = [(float(x), float(y)) for x, y in points]
    x0, y0, x1, y1 = (float(v) for v in rect)
    for axis, bound, keep_above in ((0, x0, True), (0, x1, False), (1, y0, True), (1, y1, False)):
        if not out:
            break
        out = _clip_side(out, axis, bound, keep_above)
    return tuple(out)


def _clip_side(pts: list[Point], axis: int, bound: float, keep_above: bool) -> list[Point]:
    def keep(p: Point) -> bool:
        return p[axis] >= bound if keep_above else p[axis] <= bound

    def cross(p: Point, q: Point) -> Point:
        t = (bound - p[axis]) / (q[axis] - p[axis])
        other = p[1 - axis] + t * (q[1 - axis] - p[1 - axis])
        return (bound, other) if axis == 0 else (other, bound)

    out: list[Point] = []
    prev = pts[-1]
    for cur in pts:
        if keep(cur):
            if not keep(prev):
                out.append(cross(prev, cur))
            out.append(cur)
        elif keep(prev):
            out.append(cross(prev, cur))
        prev = cur
    return out


def drawable_arena(arena: Arena, safe: Rect, cut: Rect) -> Arena:
    """``arena`` as it may be handed to pygame: itself when every polygon and door lies
    in ``safe`` (world rectangle), else with the polygons that leave it cut to ``cut``
    (the canvas and a margin) and the doors cut to ``cut`` (dropped when outside)."""

    def fits(points: Sequence[Point]) -> bool:
        return all(inside(p, safe) for p in points)

    door_points = [p for d in arena.doors for p in (d.a, d.b)]
    zones = [m.zone for m in arena.end_of_world if m.zone]
    if all(fits(poly) for poly in (arena.walls, *arena.obstacles, *zones, door_points)):
        return arena

    # What is cut away entirely becomes a speck at a corner of ``cut``, off the canvas (an
    # empty zone would be drawn as the default disc; empty walls have no bounds).
    speck = ((cut[0], cut[1]),) * 3

    def cut_poly(poly: tuple[Point, ...]) -> tuple[Point, ...]:
        if fits(poly):
            return poly
        if len(poly) == 2:  # an unfinished polygon: drawn as a line
            return clip_segment(poly[0], poly[1], cut) or speck
        out = clip_polygon(poly, cut)
        return out if len(out) >= 3 else speck

    markers = tuple(m if not m.zone else Marker(m.at, cut_poly(m.zone)) for m in arena.end_of_world)
    doors = []
    for d in arena.doors:
        part = clip_segment(d.a, d.b, cut)
        if part is not None:
            doors.append(Door(d.name, part[0], part[1], d.plate))
    return replace(
        arena,
        walls=cut_poly(arena.walls) if arena.walls else (),
        obstacles=tuple(cut_poly(p) for p in arena.obstacles),
        end_of_world=markers,
        doors=tuple(doors),
    )
