"""Arenas: walls, obstacles, goals, end-of-world markers and the start (paper §5.4.1).

An arena is read from a YAML file whose units are inches (1 unit = 1 inch = 1 pixel of
the paper's simulator)::

    name: hallway
    walls: [[x, y], ...]              # closed polygon in order; the last point joins the first
    obstacles: [[[x, y], ...], ...]   # optional free-standing closed polygons inside the walls
    goals:                            # one or more named goals (office doors)
      - {name: "317", at: [x, y]}
    active_goal: "317"                # optional; default the first goal
    end_of_world:                     # optional: markers the cameras see, each with the zone
      - {at: [x, y], zone: [[x, y], ...]}   # that ends the episode; zone optional (Marker)
    start: {at: [x, y], heading_deg: null}  # null = random heading every episode
    doors:                            # optional, drawing only: door span and its number plate
      - {name: "317", a: [x, y], b: [x, y], plate: [x, y]}
    rotate_deg: 0                     # rotate everything clockwise (the paper used 5)

:class:`Arena` keeps the file's coordinates (so that load -> save -> load is exact);
:meth:`Arena.to_world` applies ``rotate_deg`` and is what the simulator uses.
"""

from __future__ import annotations

import difflib
import hashlib
import json
import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import NoReturn

from ..store import yamlfile
from ..store.errors import ArenaError, located, shown
from ..store.files import atomic_write_text
from . import geometry

Point = tuple[float, float]


@dataclass(frozen=True)
class Goal:
    """A goal point (``GoalPoint``): the number plate of one office door."""

    name: str
    at: Point


@dataclass(frozen=True)
class Marker:
    """An end-of-world marker (one of ``EndOfWorldPoints``).

    Cameras see ``at``. The episode ends when the robot's centre enters ``zone``; when the
    zone is ``None`` it is a disc around ``at`` whose radius is one robot diameter.
    """

    at: Point
    zone: tuple[Point, ...] | None = None


@dataclass(frozen=True)
class Door:
    """A door drawn on a wall (span ``a``-``b``) with its number plate; drawing only."""

    name: str
    a: Point
    b: Point
    plate: Point


@dataclass(frozen=True)
class Start:
    """Start area: centre ``at``; ``heading_deg`` None means a random heading per episode."""

    at: Point
    heading_deg: float | None = None


@dataclass(frozen=True)
class Arena:
    """A validated arena. Build one with :func:`koolio_pymunk.world.arena.load_arena`."""

    name: str
    walls: tuple[Point, ...]
    goals: tuple[Goal, ...]
    end_of_world: tuple[Marker, ...]
    start: Start
    active_goal: str = ""
    obstacles: tuple[tuple[Point, ...], ...] = ()
    doors: tuple[Door, ...] = ()
    rotate_deg: float = 0.0
    source: str = "<arena>"
    extras: dict = field(default_factory=dict, compare=False, hash=False)

    def __post_init__(self) -> None:
        if not self.active_goal and self.goals:
            object.__setattr__(self, "active_goal", self.goals[0].name)

    # -- queries -------------------------------------------------------------------
    def goal(self, name: str | None = None) -> Goal:
        """The goal called ``name`` (default: the active goal)."""
        wanted = self.active_goal if name is None else name
        for g in self.goals:
            if g.name == wanted:
                return g
        raise KeyError(wanted)

    def goal_names(self) -> list[str]:
        return [g.name for g in self.goals]

    @property
    def record(self) -> dict[str, str]:
        """What a Q-table records of this arena (:func:`arena_record`)."""
        return arena_record(self)

    def with_active_goal(self, name: str) -> Arena:
        """A copy whose active goal is ``name`` (KeyError if there is no such goal)."""
        self.goal(name)
        return replace(self, active_goal=name)

    def segments(self) -> list[tuple[Point, Point]]:
        """Every wall and obstacle edge as ``(a, b)``, walls first, in file order."""
        segs = _ring(self.walls)
        for poly in self.obstacles:
            segs.extend(_ring(poly))
        return segs

    def bounds(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` of the walls."""
        xs = [p[0] for p in self.walls]
        ys = [p[1] for p in self.walls]
        return min(xs), min(ys), max(xs), max(ys)

    # -- rotation (the paper's 5-degree trick) ---------------------------------------
    def to_world(self) -> Arena:
        """The arena with ``rotate_deg`` applied (clockwise, about the origin)."""
        if not self.rotate_deg:
            return self
        rot = _rotator(-math.radians(self.rotate_deg))
        start_heading = self.start.heading_deg
        if start_heading is not None:
            start_heading = (start_heading - self.rotate_deg) % 360.0
        return replace(
            self,
            walls=tuple(rot(p) for p in self.walls),
            obstacles=tuple(tuple(rot(p) for p in poly) for poly in self.obstacles),
            goals=tuple(replace(g, at=rot(g.at)) for g in self.goals),
            end_of_world=tuple(
                Marker(rot(m.at), None if m.zone is None else tuple(rot(p) for p in m.zone))
                for m in self.end_of_world
            ),
            start=Start(rot(self.start.at), start_heading),
            doors=tuple(Door(d.name, rot(d.a), rot(d.b), rot(d.plate)) for d in self.doors),
            rotate_deg=0.0,
        )


def arena_record(arena: Arena) -> dict[str, str]:
    """What a Q-table records of the arena it was learned in: the name and a hash of the
    content that matters to learning (walls, obstacles, goals, end-of-world markers and
    zones, start, rotation; not the active goal, the doors' drawing or comments).

    >>> rec = arena_record(load_arena("room"))
    >>> rec["name"], len(rec["sha256"])
    ('room', 16)
    """
    data = arena_to_dict(arena)
    for key in ("name", "active_goal", "doors"):
        data.pop(key, None)
    text = json.dumps(data, sort_keys=True, separators=(",", ":"))
    return {"name": arena.name, "sha256": hashlib.sha256(text.encode()).hexdigest()[:16]}


def _ring(points: tuple[Point, ...]) -> list[tuple[Point, Point]]:
    return [(points[i], points[(i + 1) % len(points)]) for i in range(len(points))]


def _rotator(theta: float):
    c, s = math.cos(theta), math.sin(theta)

    def rot(p: Point) -> Point:
        return (c * p[0] - s * p[1], s * p[0] + c * p[1])

    return rot


# =====================================================================================
# Loading, validating and saving arena files
# =====================================================================================

TOP_KEYS = (
    "name",
    "walls",
    "obstacles",
    "goals",
    "active_goal",
    "end_of_world",
    "start",
    "doors",
    "rotate_deg",
)
REQUIRED_TOP_KEYS = ("name", "walls", "goals", "start")
GOAL_KEYS = ("name", "at")
MARKER_KEYS = ("at", "zone")
START_KEYS = ("at", "heading_deg")
DOOR_KEYS = ("name", "a", "b", "plate")
BUILTIN_ARENAS = ("hallway", "room", "obstacles")


def _fail(source: str, item: str, problem: str) -> NoReturn:
    """Raise the one-line :class:`ArenaError` ``source: item: problem``."""
    raise ArenaError(located(source, item, problem).replace("\n", " "))


def _fmt_num(x: float) -> str:
    return str(_num_out(x))


def _fmt_point(p: Point) -> str:
    return f"({_fmt_num(p[0])}, {_fmt_num(p[1])})"


def _num_out(x: float) -> int | float:
    """An integral float as an int (so files read ``10``, not ``10.0``)."""
    x = float(x)
    return int(x) if x.is_integer() and abs(x) < 1e15 else x


def _suggest(word: str, choices: Sequence[str]) -> str:
    """`` (did you mean 'x'?)`` when a close match exists, else ``''``."""
    close = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


# -- file and name resolution ---------------------------------------------------------
def builtin_arena_dirs() -> list[Path]:
    """Where built-in arenas live: the wheel's ``_arenas`` first, then the repo's."""
    here = Path(__file__).resolve().parents[1]  # the package
    return [here / "_arenas", here.parent / "arenas"]


def _looks_like_path(name: str) -> bool:
    return name.lower().endswith((".yaml", ".yml")) or "/" in name or os.sep in name


def arena_path(name: str | Path) -> Path:
    """Resolve a built-in arena name (``hallway``, ``room``, ``obstacles``) or a path."""
    if not str(name).strip():
        _fail("''", "", "empty file name")
    if isinstance(name, Path) or _looks_like_path(name):
        return Path(name)
    for folder in builtin_arena_dirs():
        for ext in (".yaml", ".yml"):
            candidate = folder / f"{name}{ext}"
            if candidate.is_file():
                return candidate
    if Path(name).is_file():
        return Path(name)
    known = ", ".join(BUILTIN_ARENAS)
    _fail(
        str(name),
        "",
        f"no such arena file or built-in arena{_suggest(name, BUILTIN_ARENAS)} (built-in: {known})",
    )


#: Largest arena file read (the hallway is 2 KiB; a wall of 10,000 points about 250 KiB).
MAX_ARENA_BYTES = 1024 * 1024
#: Longest arena, goal or door name (a goal's name goes into every row of a log).
MAX_NAME_CHARS = 200
#: Most points of one polygon (walls, an obstacle or a zone), and of all of them together.
MAX_POLYGON_POINTS = 10_000
MAX_TOTAL_POINTS = 20_000
#: Most entries of each list (obstacles, goals, end-of-world markers, doors).
MAX_ENTRIES = 1_000


def read_yaml(path: Path, source: str) -> object:
    """Read and parse a YAML file; every failure is a one-line :class:`ArenaError`."""
    return yamlfile.read_yaml(path, source, ArenaError, MAX_ARENA_BYTES, "arena file")


def parse_yaml_text(text: str, source: str) -> object:
    """Safe-load YAML (:mod:`koolio_pymunk.store.yamlfile`); errors become ``source: line N: not
    valid YAML: ...``. Unlike ``yaml.safe_load``, a key repeated in one mapping is an error.
    """
    return yamlfile.parse_yaml(text, source, ArenaError)


def load_arena(path_or_name: str | Path, robot_radius: float = 10.0) -> Arena:
    """Load and validate an arena file, or a built-in arena by name.

    ``source`` of the result (and the prefix of every error) is the path as given, or for
    a built-in name the file it resolved to.
    """
    path = arena_path(path_or_name)
    given = str(path_or_name)
    source = given if _looks_like_path(given) or isinstance(path_or_name, Path) else str(path)
    data = read_yaml(path, source)
    return parse_arena(data, source, robot_radius)


# -- parsing (types and shape) ----------------------------------------------------------
def check_keys(
    data: dict, allowed: Sequence[str], required: Sequence[str], source: str, prefix: str
) -> None:
    for key in data:
        if key not in allowed:
            hint = _suggest(str(key), allowed) or f" (valid keys: {', '.join(allowed)})"
            _fail(source, f"{prefix}{key}", f"unknown key{hint}")
    for key in required:
        if key not in data:
            _fail(source, f"{prefix}{key}", "missing required key")


def mapping_of(value: object, source: str, item: str, what: str) -> dict:
    if not isinstance(value, dict):
        _fail(source, item, f"not a mapping ({what}): {shown(value)}")
    return value


def list_of(value: object, source: str, item: str, what: str) -> list:
    if not isinstance(value, list):
        _fail(source, item, f"not a list ({what}): {shown(value)}")
    return value


#: Largest coordinate accepted, inches (25 km: far beyond any building).
MAX_COORDINATE = 1_000_000.0


def _number(value: object, source: str, item: str) -> float:
    """A finite int or float (not a bool, not a string)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        _fail(source, item, f"not a number: {shown(value)}")
    try:
        x = float(value)
    except OverflowError:  # an integer beyond the float range
        x = math.inf
    if not math.isfinite(x):
        _fail(source, item, f"not a finite number: {shown(value)}")
    return x


def _coordinate(value: object, source: str, item: str) -> float:
    x = _number(value, source, item)
    if abs(x) > MAX_COORDINATE:
        _fail(source, item, f"coordinate {shown(value)} beyond +-{MAX_COORDINATE:,.0f} in")
    return x


def point_of(value: object, source: str, item: str) -> Point:
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        _fail(source, item, f"not a point [x, y]: {shown(value)}")
    return (_coordinate(value[0], source, item), _coordinate(value[1], source, item))


def _points(value: object, source: str, item: str) -> tuple[Point, ...]:
    items = list_of(value, source, item, "expected a list of points [[x, y], ...]")
    if len(items) > MAX_POLYGON_POINTS:
        _fail(source, item, f"{len(items):,} points (the limit is {MAX_POLYGON_POINTS:,})")
    return tuple(point_of(p, source, f"{item}[{i}]") for i, p in enumerate(items))


def _goal_name(value: object, source: str, item: str) -> str:
    """A goal or door name: a non-empty string, or an int (room number) made a string."""
    if isinstance(value, bool) or not isinstance(value, (str, int)):
        _fail(source, item, f"not a name (string or room number): {shown(value)}")
    name = str(value).strip()
    if not name:
        _fail(source, item, "empty name")
    if not name.isprintable():  # names go into logs, one row per line
        _fail(source, item, f"control characters in the name: {shown(name)}")
    if len(name) > MAX_NAME_CHARS:  # and a log line is bounded
        _fail(source, item, f"{len(name):,} characters (a name has at most {MAX_NAME_CHARS})")
    return name


def _parse_goal(value: object, source: str, item: str) -> Goal:
    data = mapping_of(value, source, item, "expected {name: ..., at: [x, y]}")
    check_keys(data, GOAL_KEYS, GOAL_KEYS, source, f"{item}.")
    return Goal(
        _goal_name(data["name"], source, f"{item}.name"), point_of(data["at"], source, f"{item}.at")
    )


def _parse_marker(value: object, source: str, item: str) -> Marker:
    data = mapping_of(value, source, item, "expected {at: [x, y], zone: [[x, y], ...]}")
    check_keys(data, MARKER_KEYS, ("at",), source, f"{item}.")
    zone = data.get("zone")
    return Marker(
        point_of(data["at"], source, f"{item}.at"),
        None if zone is None else _points(zone, source, f"{item}.zone"),
    )


def _parse_start(value: object, source: str) -> Start:
    data = mapping_of(value, source, "start", "expected {at: [x, y], heading_deg: ...}")
    check_keys(data, START_KEYS, ("at",), source, "start.")
    heading = data.get("heading_deg")
    if heading is not None:
        if isinstance(heading, bool) or not isinstance(heading, (int, float)):
            _fail(source, "start.heading_deg", f"not a number or null: {shown(heading)}")
        heading = _number(heading, source, "start.heading_deg")
    return Start(point_of(data["at"], source, "start.at"), heading)


def _parse_door(value: object, source: str, item: str) -> Door:
    data = mapping_of(value, source, item, "expected {name, a: [x, y], b: [x, y], plate: [x, y]}")
    check_keys(data, DOOR_KEYS, DOOR_KEYS, source, f"{item}.")
    return Door(
        _goal_name(data["name"], source, f"{item}.name"),
        point_of(data["a"], source, f"{item}.a"),
        point_of(data["b"], source, f"{item}.b"),
        point_of(data["plate"], source, f"{item}.plate"),
    )


def _entries(data: dict, key: str, source: str, what: str) -> list:
    raw = data.get(key)
    if raw is None:
        return []
    entries = list_of(raw, source, key, what)
    if len(entries) > MAX_ENTRIES:
        _fail(source, key, f"{len(entries):,} entries (the limit is {MAX_ENTRIES:,})")
    return entries


def _parse_entries(data: dict, key: str, source: str, parse: Callable) -> tuple:
    entries = _entries(data, key, source, f"expected a list of {key} entries")
    return tuple(parse(v, source, f"{key}[{i}]") for i, v in enumerate(entries))


def _parse_obstacles(data: dict, source: str) -> tuple[tuple[Point, ...], ...]:
    polys = _entries(data, "obstacles", source, "expected a list of polygons")
    return tuple(_points(p, source, f"obstacles[{i}]") for i, p in enumerate(polys))


def _check_total_points(arena: Arena, source: str) -> None:
    total = len(arena.walls) + sum(len(p) for p in arena.obstacles)
    total += sum(len(m.zone) for m in arena.end_of_world if m.zone is not None)
    if total > MAX_TOTAL_POINTS:
        _fail(
            source,
            "",
            f"{total:,} points in walls, obstacles and zones (the limit is {MAX_TOTAL_POINTS:,})",
        )


def _parse_active(data: dict, source: str) -> str:
    raw = data.get("active_goal")
    if raw is None or raw == "":
        return ""
    return _goal_name(raw, source, "active_goal")


def _parse_rotate(data: dict, source: str) -> float:
    raw = data.get("rotate_deg", 0)
    if raw is None:
        return 0.0
    if isinstance(raw, bool) or not isinstance(raw, (int, float)):
        _fail(source, "rotate_deg", f"not a finite number: {shown(raw)}")
    return _number(raw, source, "rotate_deg")


def _parse_name(data: dict, source: str) -> str:
    name = data["name"]
    if isinstance(name, bool) or not isinstance(name, (str, int)) or not str(name).strip():
        _fail(source, "name", f"not a non-empty string: {shown(name)}")
    if not str(name).strip().isprintable():
        _fail(source, "name", f"control characters in the name: {shown(name)}")
    if len(str(name).strip()) > MAX_NAME_CHARS:
        _fail(source, "name", f"more than {MAX_NAME_CHARS} characters")
    return str(name).strip()


def parse_arena(
    data: object, source: str, robot_radius: float = 10.0, validate: bool = True
) -> Arena:
    """Build a validated :class:`Arena` from a parsed YAML object (a mapping).

    Keys and types are always checked; ``validate=False`` skips the geometry checks of
    :func:`validate_arena` (the editor opens an invalid arena to show and fix it).
    """
    if data is None:
        _fail(source, "", "empty file (expected a mapping with name, walls, goals, ...)")
    data = mapping_of(data, source, "", "expected keys name, walls, goals, end_of_world, start")
    if "hallway" in data and "doors" in data and "walls" not in data:
        _fail(
            source,
            "",
            "a door table, not an arena (koolio-pm edit --doors FILE or tools/make_hallway.py "
            "makes an arena of it; the built-in hallway is --arena hallway)",
        )
    check_keys(data, TOP_KEYS, REQUIRED_TOP_KEYS, source, "")
    arena = Arena(
        name=_parse_name(data, source),
        walls=_points(data["walls"], source, "walls"),
        goals=_parse_entries(data, "goals", source, _parse_goal),
        end_of_world=_parse_entries(data, "end_of_world", source, _parse_marker),
        start=_parse_start(data["start"], source),
        active_goal=_parse_active(data, source),
        obstacles=_parse_obstacles(data, source),
        doors=_parse_entries(data, "doors", source, _parse_door),
        rotate_deg=_parse_rotate(data, source),
        source=source,
    )
    _check_total_points(arena, source)
    if validate:
        validate_arena(arena, robot_radius)
    return arena


# -- validation (geometry and cross references) ------------------------------------------
def validate_arena(arena: Arena, robot_radius: float = 10.0) -> None:
    """Check an arena's geometry; raise a one-line :class:`ArenaError` on the first problem."""
    src = arena.source
    _check_polygon(arena.walls, "walls", src)
    boxes = [_bbox(poly) for poly in arena.obstacles]
    for k, poly in enumerate(arena.obstacles):
        _check_polygon(poly, f"obstacles[{k}]", src)
        _check_obstacle_placement(arena, k, src, boxes)
    _check_goals(arena, src, boxes)
    _check_markers(arena, src, boxes)
    _check_start(arena, robot_radius, src)
    for k, door in enumerate(arena.doors):
        _check_finite_point(door.a, f"doors[{k}].a", src)
        _check_finite_point(door.b, f"doors[{k}].b", src)
        _check_free_point(arena, door.plate, f"doors[{k}].plate", src, boxes)
    if not math.isfinite(arena.rotate_deg):
        _fail(src, "rotate_deg", f"not a finite number: {shown(arena.rotate_deg)}")


def _check_finite_point(p: Point, item: str, src: str) -> None:
    if len(p) != 2 or not all(math.isfinite(float(c)) for c in p):
        _fail(src, item, f"not a finite point: {shown(p)}")


def _check_polygon(poly: tuple[Point, ...], item: str, src: str) -> None:
    """At least 3 distinct finite points, no zero-length edge, no self-intersection."""
    if len(poly) < 3:
        _fail(src, item, f"fewer than 3 points ({len(poly)}): not a closed polygon")
    seen: dict[Point, int] = {}
    for i, p in enumerate(poly):
        _check_finite_point(p, f"{item}[{i}]", src)
        if p in seen:
            j = seen[p]
            kind = " (zero-length edge)" if i == j + 1 else ""
            _fail(src, f"{item}[{i}]", f"repeated point {_fmt_point(p)}, same as {item}[{j}]{kind}")
        seen[p] = i
    try:
        bad = geometry.polygon_self_intersection(poly)
    except geometry.TooComplex as exc:
        _fail(src, item, f"too complex to check: {exc}")
    if bad is not None:
        i, j = bad
        n = len(poly)
        _fail(
            src,
            f"{item}[{j}]",
            f"self-intersecting polygon: edge {item}[{j}]-{item}[{(j + 1) % n}] meets edge "
            f"{item}[{i}]-{item}[{(i + 1) % n}]",
        )
    if abs(geometry.polygon_area(poly)) <= geometry.EPS:
        _fail(src, item, "zero-area polygon (all points on one line)")


Box = tuple[float, float, float, float]


def _bbox(poly: tuple[Point, ...]) -> Box:
    """``(xmin, ymin, xmax, ymax)`` grown by EPS (empty polygons give an empty box)."""
    if not poly:
        return (math.inf, math.inf, -math.inf, -math.inf)
    xs = [p[0] for p in poly]
    ys = [p[1] for p in poly]
    e = geometry.EPS
    return (min(xs) - e, min(ys) - e, max(xs) + e, max(ys) + e)


def _boxes_meet(a: Box, b: Box) -> bool:
    return a[0] <= b[2] and b[0] <= a[2] and a[1] <= b[3] and b[1] <= a[3]


def _in_box(p: Point, box: Box) -> bool:
    return box[0] <= p[0] <= box[2] and box[1] <= p[1] <= box[3]


def _intersect(p: tuple[Point, ...], q: tuple[Point, ...], src: str, item: str):
    try:
        return geometry.polygons_intersect(p, q)
    except geometry.TooComplex as exc:
        _fail(src, item, f"too complex to check: {exc}")


def _check_obstacle_placement(arena: Arena, k: int, src: str, boxes: list[Box]) -> None:
    """Obstacle ``k`` lies strictly inside the walls and apart from earlier obstacles."""
    poly = arena.obstacles[k]
    item = f"obstacles[{k}]"
    hit = _intersect(poly, arena.walls, src, item)
    # With no edge meeting the walls, the obstacle is wholly inside or wholly outside, so
    # one point decides (and it is the first outside point when all are outside).
    points = range(len(poly)) if hit is not None else range(1)
    for i in points:
        p = poly[i]
        if not geometry.point_in_polygon(p, arena.walls):
            _fail(src, f"{item}[{i}]", f"point {_fmt_point(p)} is outside the walls (or on them)")
    if hit is not None:
        _fail(
            src, item, f"crosses or touches the walls (edge {item}[{hit[0]}] meets walls[{hit[1]}])"
        )
    for m in range(k):
        if _boxes_meet(boxes[m], boxes[k]):
            _check_obstacle_pair(arena.obstacles[m], poly, m, k, src)


def _check_obstacle_pair(
    earlier: tuple[Point, ...], later: tuple[Point, ...], m: int, k: int, src: str
) -> None:
    item = f"obstacles[{k}]"
    if _intersect(later, earlier, src, item) is not None:
        _fail(src, item, f"crosses or touches obstacles[{m}]")
    if geometry.point_in_polygon(later[0], earlier):
        _fail(src, item, f"lies inside obstacles[{m}]")
    if geometry.point_in_polygon(earlier[0], later):
        _fail(src, item, f"contains obstacles[{m}]")


def _check_free_point(
    arena: Arena, p: Point, item: str, src: str, boxes: list[Box] | None = None
) -> None:
    """``p`` strictly inside the walls and not inside (or on) any obstacle (``boxes``: the
    obstacles' :func:`_bbox`, computed when not given)."""
    _check_finite_point(p, item, src)
    if not geometry.point_in_polygon(p, arena.walls):
        _fail(src, item, f"point {_fmt_point(p)} is outside the walls (or on them)")
    if boxes is None:
        boxes = [_bbox(poly) for poly in arena.obstacles]
    for k, poly in enumerate(arena.obstacles):
        if not _in_box(p, boxes[k]):
            continue
        if geometry.locate_point(p, poly) != geometry.OUTSIDE:
            _fail(src, item, f"point {_fmt_point(p)} is inside obstacles[{k}]")


def _check_goals(arena: Arena, src: str, boxes: list[Box]) -> None:
    if not arena.goals:
        _fail(src, "goals", "empty list: at least one goal is needed")
    seen: dict[str, int] = {}
    for i, goal in enumerate(arena.goals):
        if not goal.name:
            _fail(src, f"goals[{i}].name", "empty name")
        if len(goal.name) > MAX_NAME_CHARS:
            _fail(src, f"goals[{i}].name", f"more than {MAX_NAME_CHARS} characters")
        if goal.name in seen:
            _fail(
                src,
                f"goals[{i}].name",
                f"duplicate goal name {goal.name!r}, same as goals[{seen[goal.name]}]",
            )
        seen[goal.name] = i
        _check_free_point(arena, goal.at, f"goals[{i}].at", src, boxes)
    if arena.active_goal not in seen:
        _fail(
            src,
            "active_goal",
            f"unknown goal {arena.active_goal!r}"
            f"{_suggest(arena.active_goal, list(seen))} (goals: {', '.join(seen)})",
        )


def _check_markers(arena: Arena, src: str, boxes: list[Box]) -> None:
    """Any number of markers (the paper's "any number"; none: a closed arena)."""
    for i, marker in enumerate(arena.end_of_world):
        item = f"end_of_world[{i}]"
        _check_free_point(arena, marker.at, f"{item}.at", src, boxes)
        if marker.zone is None:
            continue
        _check_polygon(marker.zone, f"{item}.zone", src)
        for j, p in enumerate(marker.zone):
            if geometry.locate_point(p, arena.walls) == geometry.OUTSIDE:
                _fail(src, f"{item}.zone[{j}]", f"point {_fmt_point(p)} is outside the walls")


def _check_start(arena: Arena, robot_radius: float, src: str) -> None:
    start = arena.start
    check_start_point(arena, start.at, robot_radius, src, "start.at")
    if start.heading_deg is not None and not math.isfinite(start.heading_deg):
        _fail(src, "start.heading_deg", f"not a number or null: {shown(start.heading_deg)}")


def check_start_point(arena: Arena, p: Point, robot_radius: float, src: str, item: str) -> None:
    """A robot of ``robot_radius`` may start at ``p``: strictly inside the walls, in no
    obstacle, touching no edge; else the one-line :class:`ArenaError` ``src: item: ...``
    (the arena's own ``start.at``, and a shared arena's ``shared.starts[k]``)."""
    _check_free_point(arena, p, item, src)
    names = _segment_names(arena)
    for (a, b), name in zip(arena.segments(), names, strict=True):
        d = geometry.distance_point_segment(p, a, b)
        if d <= robot_radius + geometry.EPS:
            _fail(
                src,
                item,
                f"the robot (radius {_fmt_num(robot_radius)}) at "
                f"{_fmt_point(p)} overlaps or touches edge {name} "
                f"(distance {d:.3g})",
            )


def _segment_names(arena: Arena) -> list[str]:
    """Names of :meth:`Arena.segments` in the same order, e.g. ``walls[0]-walls[1]``."""
    names = []
    for item, poly in [("walls", arena.walls)] + [
        (f"obstacles[{k}]", p) for k, p in enumerate(arena.obstacles)
    ]:
        n = len(poly)
        names.extend(f"{item}[{i}]-{item}[{(i + 1) % n}]" for i in range(n))
    return names


# -- saving -----------------------------------------------------------------------------
def _point_out(p: Point) -> list[int | float]:
    return [_num_out(p[0]), _num_out(p[1])]


def _poly_out(poly: tuple[Point, ...]) -> list[list[int | float]]:
    return [_point_out(p) for p in poly]


def _marker_out(marker: Marker) -> dict:
    out: dict = {"at": _point_out(marker.at)}
    if marker.zone is not None:
        out["zone"] = _poly_out(marker.zone)
    return out


def arena_to_dict(arena: Arena) -> dict:
    """The arena as plain YAML-ready data, keys in the documented order."""
    heading = arena.start.heading_deg
    out: dict = {"name": arena.name, "walls": _poly_out(arena.walls)}
    if arena.obstacles:
        out["obstacles"] = [_poly_out(p) for p in arena.obstacles]
    out["goals"] = [{"name": g.name, "at": _point_out(g.at)} for g in arena.goals]
    out["active_goal"] = arena.active_goal
    out["end_of_world"] = [_marker_out(m) for m in arena.end_of_world]
    out["start"] = {
        "at": _point_out(arena.start.at),
        "heading_deg": None if heading is None else _num_out(heading),
    }
    if arena.doors:
        out["doors"] = [
            {
                "name": d.name,
                "a": _point_out(d.a),
                "b": _point_out(d.b),
                "plate": _point_out(d.plate),
            }
            for d in arena.doors
        ]
    out["rotate_deg"] = _num_out(arena.rotate_deg)
    return out


def arena_to_yaml(arena: Arena, header: str = "") -> str:
    """YAML text for the arena, preceded by ``header`` as ``#`` comment lines."""
    body = yamlfile.dump_yaml(
        arena_to_dict(arena),
        sort_keys=False,
        default_flow_style=None,
        allow_unicode=True,
        width=100,
    )
    lines = [ln if ln.startswith("#") else f"# {ln}".rstrip() for ln in header.splitlines()]
    return "\n".join(lines) + ("\n" if lines else "") + body


def save_arena(arena: Arena, path: str | Path, header: str = "") -> None:
    """Save the arena as YAML, atomically (the old file survives any failure)."""
    text = arena_to_yaml(arena, header)
    atomic_write_text(path, text)
