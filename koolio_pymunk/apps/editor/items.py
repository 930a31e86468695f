"""Item paths: how the editor names the parts of an arena (pure, no pygame).

The editor uses the core validator's own item names, so that a validation message
points straight at the thing to highlight and a scripted session can name what it edits:

=============================  ==================================================
``walls``                      the wall polygon
``walls[3]``                   wall vertex 3
``obstacles[1]``               obstacle 1 (a polygon; moving it translates it)
``obstacles[1][2]``            vertex 2 of obstacle 1
``goals[0]`` / ``goals[0].at``  goal 0 (its point)
``end_of_world[1]``            end-of-world marker 1 (its point ``.at``)
``end_of_world[1].zone``       its zone polygon (moving it translates it)
``end_of_world[1].zone[2]``    vertex 2 of that zone
``start`` / ``start.at``       the start point
``doors[0].plate``             a door's plate (also ``.a``, ``.b``: highlight only)
=============================  ==================================================

A path is parsed into a tuple such as ``("obstacles", 1, 2)`` or
``("end_of_world", 1, "zone", 2)``; :func:`path_str` turns it back into text.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator
from dataclasses import replace

from ...store.errors import KoolioError
from ...world.arena import Arena, Goal, Marker, Point, Start

Path = tuple
"""A parsed item path, e.g. ``("walls", 3)``."""

_TOKEN = re.compile(r"\[(-?\d+)\]|\.?([A-Za-z_]+)")
_POINT_SUFFIXES = ("at",)


class EditError(KoolioError):
    """An editing operation that cannot be done (bad item path, index, name ...)."""


# -- parsing and formatting ---------------------------------------------------------------
def parse_path(text: str) -> Path:
    """``"obstacles[0][2]"`` -> ``("obstacles", 0, 2)``; ``.at`` suffixes are dropped.

    >>> parse_path("end_of_world[1].zone[2]")
    ('end_of_world', 1, 'zone', 2)
    >>> parse_path("goals[3].at")
    ('goals', 3)
    """
    text = text.strip()
    parts: list = []
    pos = 0
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if m is None:
            raise EditError(f"{text}: not an item path (like walls[3] or obstacles[0][2])")
        parts.append(int(m.group(1)) if m.group(1) is not None else m.group(2))
        pos = m.end()
    if not parts or not isinstance(parts[0], str):
        raise EditError(f"{text}: not an item path (like walls[3] or obstacles[0][2])")
    while len(parts) > 1 and parts[-1] in _POINT_SUFFIXES:
        parts.pop()
    return tuple(parts)


def path_str(path: Path) -> str:
    """``("obstacles", 0, 2)`` -> ``"obstacles[0][2]"``.

    >>> path_str(("end_of_world", 1, "zone", 2))
    'end_of_world[1].zone[2]'
    """
    out = ""
    for part in path:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else part)
    return out


def is_polygon_path(path: Path) -> bool:
    """True for ``walls``, ``obstacles[k]`` and ``end_of_world[i].zone``."""
    return (
        path == ("walls",)
        or (len(path) == 2 and path[0] == "obstacles")
        or (len(path) == 3 and path[0] == "end_of_world" and path[2] == "zone")
    )


def is_vertex_path(path: Path) -> bool:
    """True for a vertex of a polygon (``walls[i]``, ``obstacles[k][i]``, ``...zone[j]``)."""
    return len(path) >= 2 and is_polygon_path(path[:-1]) and isinstance(path[-1], int)


# -- polygons -------------------------------------------------------------------------------
def get_polygon(arena: Arena, path: Path) -> tuple[Point, ...]:
    """The points of the polygon ``path`` names (a zone that is None gives ``()``)."""
    if path == ("walls",):
        return arena.walls
    if len(path) == 2 and path[0] == "obstacles":
        return _index(arena.obstacles, path[1], path)
    if len(path) == 3 and path[0] == "end_of_world" and path[2] == "zone":
        zone = _index(arena.end_of_world, path[1], path).zone
        return () if zone is None else zone
    raise EditError(f"{path_str(path)}: not a polygon (walls, obstacles[k], end_of_world[i].zone)")


def with_polygon(arena: Arena, path: Path, points: tuple[Point, ...] | None) -> Arena:
    """A copy of ``arena`` whose polygon ``path`` is ``points`` (None: a zone's default).
    Points that already are pairs of floats are kept as they are (an edit of one vertex
    of a 10,000-point wall shares the other 9,999 with the arena before it)."""
    pts = None if points is None else tuple(_float_pair(p) for p in points)
    if path == ("walls",):
        return replace(arena, walls=pts or ())
    if len(path) == 2 and path[0] == "obstacles":
        return replace(arena, obstacles=_set(arena.obstacles, path[1], pts or (), path))
    if len(path) == 3 and path[0] == "end_of_world" and path[2] == "zone":
        marker = _index(arena.end_of_world, path[1], path)
        zone = Marker(marker.at, pts if pts else None)
        return replace(arena, end_of_world=_set(arena.end_of_world, path[1], zone, path))
    raise EditError(f"{path_str(path)}: not a polygon (walls, obstacles[k], end_of_world[i].zone)")


def polygon_paths(arena: Arena) -> list[Path]:
    """Every polygon of the arena: walls, obstacles, then zones that are polygons."""
    out: list[Path] = [("walls",)]
    out += [("obstacles", k) for k in range(len(arena.obstacles))]
    out += [("end_of_world", i, "zone") for i, m in enumerate(arena.end_of_world) if m.zone]
    return out


# -- points ---------------------------------------------------------------------------------
def get_point(arena: Arena, path: Path) -> Point:
    """The point an item path names (a vertex, goal, marker, start or door point)."""
    if path == ("start",):
        return arena.start.at
    if is_vertex_path(path):
        return _index(get_polygon(arena, path[:-1]), path[-1], path)
    if len(path) == 2 and path[0] == "goals":
        return _index(arena.goals, path[1], path).at
    if len(path) == 2 and path[0] == "end_of_world":
        return _index(arena.end_of_world, path[1], path).at
    if len(path) == 3 and path[0] == "doors" and path[2] in ("a", "b", "plate"):
        return getattr(_index(arena.doors, path[1], path), path[2])
    raise EditError(f"{path_str(path)}: not a point")


def with_point(arena: Arena, path: Path, p: Point) -> Arena:
    """A copy of ``arena`` with the point ``path`` moved to ``p``."""
    p = (float(p[0]), float(p[1]))
    if path == ("start",):
        return replace(arena, start=Start(p, arena.start.heading_deg))
    if is_vertex_path(path):
        poly = list(get_polygon(arena, path[:-1]))
        _index(poly, path[-1], path)
        poly[path[-1]] = p
        return with_polygon(arena, path[:-1], tuple(poly))
    if len(path) == 2 and path[0] == "goals":
        goal = _index(arena.goals, path[1], path)
        return replace(arena, goals=_set(arena.goals, path[1], Goal(goal.name, p), path))
    if len(path) == 2 and path[0] == "end_of_world":
        m = _index(arena.end_of_world, path[1], path)
        markers = _set(arena.end_of_world, path[1], Marker(p, m.zone), path)
        return replace(arena, end_of_world=markers)
    if len(path) == 3 and path[0] == "doors" and path[2] in ("a", "b", "plate"):
        door = _index(arena.doors, path[1], path)
        doors = _set(arena.doors, path[1], replace(door, **{path[2]: p}), path)
        return replace(arena, doors=doors)
    raise EditError(f"{path_str(path)}: not a point")


def is_movable(path: Path) -> bool:
    """Points and the polygons that move as a whole (obstacles and zones, not the walls)."""
    if is_polygon_path(path):
        return path != ("walls",)
    return path == ("start",) or is_vertex_path(path) or path[0] in ("goals", "end_of_world")


def translated(arena: Arena, path: Path, dx: float, dy: float) -> Arena:
    """A copy with the item ``path`` moved by ``(dx, dy)`` (a point or a whole polygon)."""
    if is_polygon_path(path):
        poly = get_polygon(arena, path)
        return with_polygon(arena, path, tuple((x + dx, y + dy) for x, y in poly))
    x, y = get_point(arena, path)
    return with_point(arena, path, (x + dx, y + dy))


def all_vertices(arena: Arena, prefer: Path | None = None) -> Iterator[tuple[Path, Point]]:
    """Every editable point with its path, in picking priority order.

    The vertices of polygon ``prefer`` (e.g. the selected zone) come first, then the
    start, goals, markers, and the vertices of the walls, obstacles and zones.
    """
    polys = polygon_paths(arena)
    if prefer is not None and prefer in polys:
        polys.remove(prefer)
        for j, p in enumerate(get_polygon(arena, prefer)):
            yield (*prefer, j), p
    yield ("start",), arena.start.at
    for i, g in enumerate(arena.goals):
        yield ("goals", i), g.at
    for i, m in enumerate(arena.end_of_world):
        yield ("end_of_world", i), m.at
    for poly_path in polys:
        for j, p in enumerate(get_polygon(arena, poly_path)):
            yield (*poly_path, j), p


# -- hit testing ------------------------------------------------------------------------------
def pick_point(arena: Arena, p: Point, tol: float, prefer: Path | None = None) -> Path | None:
    """The editable point nearest ``p`` within ``tol`` (ties: the first of :func:`all_vertices`)."""
    best, best_d = None, tol
    for path, q in all_vertices(arena, prefer):
        d = math.hypot(q[0] - p[0], q[1] - p[1])
        if d <= best_d and (best is None or d < best_d):
            best, best_d = path, d
    return best


def pick_segment(arena: Arena, p: Point, tol: float) -> tuple[Path, int, Point] | None:
    """The polygon edge nearest ``p`` within ``tol``: ``(polygon path, edge, foot point)``.

    Edge ``i`` runs from vertex ``i`` to vertex ``i + 1`` (the last one back to 0).
    """
    best, best_d = None, tol
    for poly_path in polygon_paths(arena):
        poly = get_polygon(arena, poly_path)
        n = len(poly)
        for i in range(n if n >= 3 else n - 1):
            a, b = poly[i], poly[(i + 1) % n]
            foot = closest_point(p, a, b)
            d = math.hypot(foot[0] - p[0], foot[1] - p[1])
            if d <= best_d:
                best, best_d = (poly_path, i, foot), d
    return best


def pick_area(arena: Arena, p: Point) -> Path | None:
    """The obstacle (or else the polygon zone) whose inside holds ``p``."""
    from ...world.geometry import point_in_polygon

    for k, poly in enumerate(arena.obstacles):
        if len(poly) >= 3 and point_in_polygon(p, poly):
            return ("obstacles", k)
    for i, m in enumerate(arena.end_of_world):
        if m.zone and len(m.zone) >= 3 and point_in_polygon(p, m.zone):
            return ("end_of_world", i, "zone")
    return None


def closest_point(p: Point, a: Point, b: Point) -> Point:
    """The point of segment ``a``-``b`` nearest ``p``."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    len2 = dx * dx + dy * dy
    if len2 == 0.0:
        return a
    t = max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2))
    return (a[0] + t * dx, a[1] + t * dy)


# -- helpers ----------------------------------------------------------------------------------
def _float_pair(p) -> Point:
    if type(p) is tuple and len(p) == 2 and type(p[0]) is float and type(p[1]) is float:
        return p
    return (float(p[0]), float(p[1]))


def _index(items, i: int, path: Path):
    if not isinstance(i, int) or not 0 <= i < len(items):
        raise EditError(f"{path_str(path)}: no such item (there are {len(items)})")
    return items[i]


def _set(items: tuple, i: int, value, path: Path) -> tuple:
    _index(items, i, path)
    return items[:i] + (value,) + items[i + 1 :]
