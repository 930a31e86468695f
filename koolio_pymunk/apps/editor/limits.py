"""The editor's ranges: every number (and name) a user can give the editor, and why.

An arena is a building floor measured in inches (the paper's hallway is 1,728 x 184 in);
the ranges follow from that, not from what the arithmetic would survive. Each is checked
where the value is read: a flag (:mod:`~koolio_pymunk.apps.editor.launch`) or a script
line (:mod:`~koolio_pymunk.apps.editor.script`) out of range is refused with one line and
nothing is done; a value typed or clicked in the window is clamped (zoom, pan, wheel,
click positions) or refused with a message in the status bar (a typed position, an edit
that would leave the range). Pure: no pygame.

=====================  ===========================  ==========================================
value                  range                        why
=====================  ===========================  ==========================================
coordinate             -1,000,000 to 1,000,000 in   the simulator's own limit (25.4 km, far
                                                    beyond any building); a file the editor
                                                    writes must load in the simulator
snap step              0.01 to 1,000 in             0.01 in is the editor's resolution (snap
                                                    off); the robot's sonars resolve about an
                                                    inch, so finer positions only add digits
grid (tile)            1 to 1,000 in                finer lines than 1 in say nothing on a
                                                    building floor (the snap step gives finer
                                                    positions); a coarser grid than 1,000 in
                                                    (83 ft) leaves a line or two on a floor
zoom                   0.05 to 20 px/in             0.05 shows 18,800 in (480 m) across the
                                                    default canvas; 20 fills it with 47 in,
                                                    about two robots
wheel                  -100 to 100 clicks a line    1.2 a click: 33 clicks cross the whole
                                                    zoom range
window (--size)        400x300 to 7680x4320         an 8K screen; a window is 4 bytes a pixel
heading, rotate_deg    -360 to 360 deg              one turn either way
drive N                1 to 10,000 steps            more than an episode (1,500 steps by
                                                    default); about 0.3 s of stepping
undo / redo N          1 and up                     stops at the history's end at once (the
                                                    history holds the last 1,000 edits)
names                  1 to 100 printable chars     a room number or a short label; control
                                                    characters would break logs (one row a
                                                    line) and the simulator refuses them
typed text             up to 1,000 characters       a text line in a question or a script
script                 1 MiB, 10,000 commands,      a session, not a data file; each command
                       65,536 characters a line     draws a frame (a few ms)
polygons, entries      as the simulator's loader    10,000 points a polygon, 20,000 in all,
                                                    1,000 obstacles, goals, markers or doors
=====================  ===========================  ==========================================

>>> check_range(0.001, MIN_GRID, MAX_GRID, "grid", " in")
Traceback (most recent call last):
...
koolio_pymunk.apps.editor.items.EditError: grid: 0.001 in is out of range (1 to 1,000 in)
>>> clamp(1e300, -MAX_COORDINATE, MAX_COORDINATE)
1000000.0
"""

from __future__ import annotations

import math

from ...world.arena import (
    MAX_COORDINATE,
    MAX_ENTRIES,
    MAX_POLYGON_POINTS,
    MAX_TOTAL_POINTS,
    Arena,
    Point,
)
from . import items
from .items import EditError

MAX_MOVE = 2 * MAX_COORDINATE
"""Largest displacement of one move (``move_by``), inches: across the whole range."""
MIN_SNAP = 0.01
"""Smallest snap step, inches (also the step when snapping is off)."""
MAX_SNAP = 1000.0
"""Largest snap step, inches."""
MIN_GRID = 1.0
"""Smallest grid (tile) size, inches."""
MAX_GRID = 1000.0
"""Largest grid (tile) size, inches."""
MIN_ZOOM = 0.05
"""Smallest zoom, pixels per inch."""
MAX_ZOOM = 20.0
"""Largest zoom, pixels per inch."""
MAX_WHEEL_CLICKS = 100
"""Most wheel clicks in one script line or one wheel event (either way)."""
MIN_WINDOW = (400, 300)
"""Smallest window, pixels."""
MAX_WINDOW = (7680, 4320)
"""Largest window, pixels (an 8K screen)."""
MAX_ANGLE = 360.0
"""Largest heading or rotation given, degrees (either way)."""
MAX_DRIVE_STEPS = 10_000
"""Most test-drive steps in one script line."""
MAX_NAME = 100
"""Longest goal or arena name given in the editor, characters."""
MAX_TYPED = 1000
"""Longest text typed into a question (or by a script's ``type``), characters."""
MAX_SCRIPT_BYTES = 1024 * 1024
"""Largest script file."""
MAX_SCRIPT_COMMANDS = 10_000
"""Most commands in a script."""
MAX_SCRIPT_LINE = 65_536
"""Longest script line, characters."""


def _g(x: float, sep: str = ",") -> str:
    """``1,000`` / ``1,000,000.5`` / ``0.05`` / ``1e+300``: a number as the messages show
    it (``sep``: the thousands separator; none in points).

    >>> _g(1000000.5), _g(1e-12), _g(1e300), _g(2400000000, "")
    ('1,000,000.5', '1e-12', '1e+300', '2400000000')
    """
    if math.isfinite(x) and abs(x) < 1e15:
        if x == int(x):
            return f"{int(x):{sep}}" if sep else str(int(x))
        return f"{x:{sep}.10g}" if sep else f"{x:.10g}"
    return f"{x:g}"


def range_problem(x: float, lo: float, hi: float, unit: str = "") -> str | None:
    """``x is out of range (lo to hi)``, or None when ``lo <= x <= hi`` (NaN is out).

    >>> range_problem(1e300, -10, 10, " in")
    '1e+300 in is out of range (-10 to 10 in)'
    """
    if lo <= x <= hi:
        return None
    return f"{_g(x)}{unit} is out of range ({_g(lo)} to {_g(hi)}{unit})"


def check_range(x: float, lo: float, hi: float, what: str, unit: str = "") -> float:
    """``x`` when ``lo <= x <= hi``, else :class:`EditError` ``what: x is out of range
    (lo to hi)``."""
    problem = range_problem(x, lo, hi, unit)
    if problem is not None:
        raise EditError(f"{what}: {problem}")
    return x


def clamp(x: float, lo: float, hi: float) -> float:
    """``x`` held to ``[lo, hi]`` (NaN becomes ``lo``)."""
    return min(hi, max(lo, x)) if x == x else lo


def clamp_point(p: Point) -> Point:
    """A point held to the coordinate range (interactive input: clicks and drags)."""
    m = MAX_COORDINATE
    return (clamp(p[0], -m, m), clamp(p[1], -m, m))


def check_point(p: Point, what: str) -> Point:
    """``p`` when both coordinates are in range, else :class:`EditError`."""
    for x in p:
        if not (-MAX_COORDINATE <= x <= MAX_COORDINATE):
            raise EditError(
                f"{what}: ({_g(p[0], '')}, {_g(p[1], '')}) is out of range "
                f"(coordinates -{_g(MAX_COORDINATE)} to {_g(MAX_COORDINATE)} in)"
            )
    return p


def check_name(name: str, what: str) -> str:
    """A goal or arena name: 1 to :data:`MAX_NAME` printable characters (stripped)."""
    name = str(name).strip()
    if not name:
        raise EditError(f"{what}: a name is needed")
    if len(name) > MAX_NAME:
        raise EditError(f"{what}: a name of {len(name):,} characters (at most {MAX_NAME})")
    if not name.isprintable():
        raise EditError(f"{what}: control characters in the name {name!r}")
    return name


def check_arena(arena: Arena, before: Arena | None = None) -> None:
    """The document an edit would make: every point in range and no more points or
    entries than the simulator loads; :class:`EditError` on the first that is not.
    Polygons shared with ``before`` (the document before the edit, already checked) are
    not looked at again."""
    for key in ("obstacles", "goals", "end_of_world", "doors"):
        n = len(getattr(arena, key))
        if n > MAX_ENTRIES:
            raise EditError(f"{key}: {n:,} entries (the limit is {MAX_ENTRIES:,})")
    old = set() if before is None else {id(p) for p in _polygons(before)}
    total = 0
    for poly_path in items.polygon_paths(arena):
        poly = items.get_polygon(arena, poly_path)
        total += len(poly)
        if id(poly) in old:
            continue
        if len(poly) > MAX_POLYGON_POINTS:
            where = items.path_str(poly_path)
            raise EditError(f"{where}: {len(poly):,} points (the limit is {MAX_POLYGON_POINTS:,})")
        if not _all_in_range(poly):
            for i, p in enumerate(poly):
                check_point(p, items.path_str((*poly_path, i)))
    if total > MAX_TOTAL_POINTS:
        raise EditError(
            f"{total:,} points in walls, obstacles and zones (the limit is {MAX_TOTAL_POINTS:,})"
        )
    check_point(arena.start.at, "start")
    for i, g in enumerate(arena.goals):
        check_point(g.at, f"goals[{i}]")
    for i, m in enumerate(arena.end_of_world):
        check_point(m.at, f"end_of_world[{i}]")
    for k, door in enumerate(arena.doors):
        for part in ("a", "b", "plate"):
            check_point(getattr(door, part), f"doors[{k}].{part}")


def _polygons(arena: Arena) -> list[tuple[Point, ...]]:
    return [items.get_polygon(arena, p) for p in items.polygon_paths(arena)]


def _all_in_range(points: tuple[Point, ...]) -> bool:
    m = MAX_COORDINATE
    return all(-m <= x <= m and -m <= y <= m for x, y in points)
