"""Build the paper's hallway arena (Figure 3) from a door table.

The hallway is a long corridor, ``length_tiles`` x ``width_tiles`` ceiling tiles of
``tile_in`` inches (the paper: 68 x 3 2/3 tiles of 24 in = 1632 x 88 in). The *stairs
end* is x = 0 (west), the *corner end* is x = length (east); y = 0 is the south wall and
y = width the north wall. At each end a T-shaped opening: a cross corridor
``t_depth_in`` deep, reaching ``t_overhang_in`` beyond each hallway wall. The centre of
each cross corridor is an end-of-world marker whose zone is the whole cross corridor.

Doors follow the paper's numbering: even rooms are on the north wall and count tiles
from the stairs end (x = 0) to the door's leading edge (the edge nearer that end); odd
rooms are on the south wall and count tiles from the corner end. Each door has a number
plate on its ``left`` or ``right`` as seen facing the door from the hallway, 6 in beyond
the door edge and 1 in off the wall; that plate point is the room's goal (goal name =
room number as a string).

Door table format (YAML)::

    name: hallway                 # optional, default "hallway"
    hallway:
      length_tiles: 68
      width_tiles: 3 2/3          # a number, or a fraction string "11/3" / "3 2/3"
      tile_in: 24
      t_depth_in: 48              # depth of each end's cross corridor (along x)
      t_overhang_in: 48           # how far it reaches beyond each hallway wall (along y)
    start:                        # exactly one of at_tiles_from_stairs / at
      at_tiles_from_stairs: 3     # centred across the hallway; or  at: [x, y]
      heading_deg: null           # optional; null = random heading every episode
    active_goal: 311              # a room number from the doors list
    rotate_deg: 0                 # optional (the paper used 5)
    doors:
      - {room: 302, side: north, tiles: 4, width_in: 36, plate: right}
      - {room: 311, side: south, tiles: 35, width_in: 36, plate: left}

Each door gives its distance from its end of the hallway either in ceiling tiles
(``tiles``, as the paper's Figure 3 counts them) or in inches (``inches``), exactly one of
the two: ``{room: 305, side: south, inches: 432, plate: right}`` is the same door as
``tiles: 18``. ``width_in`` is optional (default 36 = 1 1/2 tiles). Every problem with a
table is an :class:`~koolio_pymunk.store.errors.ArenaError` with a one-line message naming the
file, the item and the problem.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import NoReturn

from ..store.errors import ArenaError, located, shown
from .arena import (
    Arena,
    Door,
    Goal,
    Marker,
    Point,
    Start,
    check_keys,
    list_of,
    mapping_of,
    point_of,
    read_yaml,
    validate_arena,
)

TABLE_KEYS = ("name", "hallway", "start", "active_goal", "rotate_deg", "doors")
TABLE_REQUIRED = ("hallway", "start", "active_goal", "doors")
HALLWAY_KEYS = ("length_tiles", "width_tiles", "tile_in", "t_depth_in", "t_overhang_in")
START_KEYS = ("at_tiles_from_stairs", "at", "heading_deg")
DOOR_KEYS = ("room", "side", "tiles", "inches", "width_in", "plate")
DOOR_REQUIRED = ("room", "side", "plate")
DEFAULT_DOOR_WIDTH_IN = 36.0
PLATE_BEYOND_DOOR_IN = 6.0
PLATE_OFF_WALL_IN = 1.0


@dataclass(frozen=True)
class HallwayShape:
    """Hallway dimensions in inches."""

    length: float
    width: float
    tile: float
    t_depth: float
    t_overhang: float


@dataclass(frozen=True)
class DoorSpec:
    """One row of the door table, resolved to inches along x."""

    room: str
    side: str
    x0: float
    x1: float
    plate: Point


def _fail(source: str, item: str, problem: str) -> NoReturn:
    raise ArenaError(located(source, item, problem).replace("\n", " "))


def _positive(value: object, source: str, item: str, allow_zero: bool = False) -> float:
    """A finite number > 0 (or >= 0 with ``allow_zero``); fraction strings are accepted."""
    return float(_positive_fraction(value, source, item, allow_zero))


def _positive_fraction(value: object, source: str, item: str, allow_zero: bool = False) -> Fraction:
    x = _fraction(value, source, item)
    if x < 0 or (x == 0 and not allow_zero):
        _fail(source, item, f"must be {'>= 0' if allow_zero else '> 0'}: {shown(value)}")
    return x


def _fraction(value: object, source: str, item: str) -> Fraction:
    """A number, or a string like ``"11/3"`` or ``"3 2/3"``, as an exact Fraction."""
    if isinstance(value, bool):
        _fail(source, item, f"not a number: {shown(value)}")
    if isinstance(value, (int, float)):
        if not math.isfinite(value):
            _fail(source, item, f"not a finite number: {shown(value)}")
        return Fraction(value).limit_denominator(10**6)
    if isinstance(value, str):
        try:
            return sum((Fraction(part) for part in value.split()), Fraction(0))
        except (ValueError, ZeroDivisionError):
            pass
    _fail(source, item, f"not a number: {shown(value)}")


def _shape(table: dict, source: str) -> HallwayShape:
    data = mapping_of(table["hallway"], source, "hallway", "expected {length_tiles, ...}")
    check_keys(data, HALLWAY_KEYS, HALLWAY_KEYS, source, "hallway.")
    tile = _positive_fraction(data["tile_in"], source, "hallway.tile_in")
    length = _positive_fraction(data["length_tiles"], source, "hallway.length_tiles")
    width = _positive_fraction(data["width_tiles"], source, "hallway.width_tiles")
    return HallwayShape(
        length=float(length * tile),
        width=float(width * tile),
        tile=float(tile),
        t_depth=_positive(data["t_depth_in"], source, "hallway.t_depth_in"),
        t_overhang=_positive(data["t_overhang_in"], source, "hallway.t_overhang_in"),
    )


def hallway_walls(shape: HallwayShape) -> tuple[Point, ...]:
    """The counter-clockwise wall polygon: the corridor with a T at each end."""
    ln, w, d, o = shape.length, shape.width, shape.t_depth, shape.t_overhang
    return (
        (0.0, 0.0),
        (ln, 0.0),
        (ln, -o),
        (ln + d, -o),
        (ln + d, w + o),
        (ln, w + o),
        (ln, w),
        (0.0, w),
        (0.0, w + o),
        (-d, w + o),
        (-d, -o),
        (0.0, -o),
    )


def hallway_markers(shape: HallwayShape) -> tuple[Marker, ...]:
    """End-of-world markers at the centre of each cross corridor, zone = that corridor."""
    ln, w, d, o = shape.length, shape.width, shape.t_depth, shape.t_overhang
    west = ((-d, -o), (0.0, -o), (0.0, w + o), (-d, w + o))
    east = ((ln, -o), (ln + d, -o), (ln + d, w + o), (ln, w + o))
    return (
        Marker((-d / 2, w / 2), west),
        Marker((ln + d / 2, w / 2), east),
    )


def _start(table: dict, shape: HallwayShape, source: str) -> Start:
    data = mapping_of(table["start"], source, "start", "expected {at_tiles_from_stairs: n}")
    check_keys(data, START_KEYS, (), source, "start.")
    has_tiles, has_at = "at_tiles_from_stairs" in data, "at" in data
    if has_tiles == has_at:
        _fail(source, "start", "give exactly one of at_tiles_from_stairs or at")
    if has_at:
        at = point_of(data["at"], source, "start.at")
    else:
        tiles = _positive(data["at_tiles_from_stairs"], source, "start.at_tiles_from_stairs")
        at = (tiles * shape.tile, shape.width / 2)
    heading = data.get("heading_deg")
    if heading is not None:
        if isinstance(heading, bool) or not isinstance(heading, (int, float)):
            _fail(source, "start.heading_deg", f"not a number or null: {shown(heading)}")
        if not math.isfinite(heading):
            _fail(source, "start.heading_deg", f"not a finite number: {shown(heading)}")
        heading = float(heading)
    return Start(at, heading)


def _room(value: object, source: str, item: str) -> str:
    if isinstance(value, bool) or not isinstance(value, (int, str)) or not str(value).isdigit():
        _fail(source, item, f"not a room number: {shown(value)}")
    return str(value)


def _choice(value: object, choices: tuple[str, ...], source: str, item: str) -> str:
    if value not in choices:
        _fail(source, item, f"must be one of {', '.join(choices)}: {shown(value)}")
    return str(value)


def _door(value: object, shape: HallwayShape, source: str, item: str) -> DoorSpec:
    expected = "expected {room, side, tiles or inches, width_in, plate}"
    data = mapping_of(value, source, item, expected)
    check_keys(data, DOOR_KEYS, DOOR_REQUIRED, source, f"{item}.")
    room = _room(data["room"], source, f"{item}.room")
    side = _choice(data["side"], ("north", "south"), source, f"{item}.side")
    wanted = "north" if int(room) % 2 == 0 else "south"
    if side != wanted:
        parity = "even" if wanted == "north" else "odd"
        _fail(
            source, f"{item}.side", f"room {room} is {parity}, so its door is on the {wanted} wall"
        )
    distance = _door_distance(data, shape, source, item)
    width = _positive(data.get("width_in", DEFAULT_DOOR_WIDTH_IN), source, f"{item}.width_in")
    plate_side = _choice(data["plate"], ("left", "right"), source, f"{item}.plate")
    if side == "north":
        x0 = distance
        x1 = x0 + width
    else:
        x1 = shape.length - distance
        x0 = x1 - width
    return DoorSpec(room, side, x0, x1, _plate(side, plate_side, x0, x1, shape))


def _door_distance(data: dict, shape: HallwayShape, source: str, item: str) -> float:
    """Inches from the door's end of the hallway: ``tiles`` x tile size, or ``inches``."""
    if ("tiles" in data) == ("inches" in data):
        _fail(source, item, "give exactly one of tiles or inches (distance from the hallway's end)")
    if "tiles" in data:
        return _positive(data["tiles"], source, f"{item}.tiles", allow_zero=True) * shape.tile
    return _positive(data["inches"], source, f"{item}.inches", allow_zero=True)


def _plate(side: str, plate_side: str, x0: float, x1: float, shape: HallwayShape) -> Point:
    """The plate point: 6 in beyond the door edge on its side, 1 in off the wall."""
    # Facing north (+y) from the hallway, left is west (-x); facing south, left is east.
    west = (plate_side == "left") == (side == "north")
    x = x0 - PLATE_BEYOND_DOOR_IN if west else x1 + PLATE_BEYOND_DOOR_IN
    y = shape.width - PLATE_OFF_WALL_IN if side == "north" else PLATE_OFF_WALL_IN
    return (x, y)


def _extent(door: DoorSpec) -> tuple[float, float]:
    """The stretch of wall a door and its plate occupy."""
    return min(door.x0, door.plate[0]), max(door.x1, door.plate[0])


def _check_door_places(doors: list[DoorSpec], shape: HallwayShape, source: str) -> None:
    for k, door in enumerate(doors):
        item = f"doors[{k}]"
        lo, hi = _extent(door)
        if lo < shape.tile or hi > shape.length - shape.tile:
            _fail(
                source,
                item,
                f"room {door.room} (door and plate x {lo:g}..{hi:g}) is closer than 1 tile "
                f"({shape.tile:g} in) to an end of the hallway (0..{shape.length:g})",
            )
        for m, other in enumerate(doors[:k]):
            if other.room == door.room:
                _fail(source, f"{item}.room", f"duplicate room {door.room}, same as doors[{m}]")
            olo, ohi = _extent(other)
            if other.side == door.side and lo < ohi and olo < hi:
                _fail(
                    source,
                    item,
                    f"room {door.room} (x {lo:g}..{hi:g}) overlaps doors[{m}] room "
                    f"{other.room} (x {olo:g}..{ohi:g}) on the {door.side} wall",
                )


def _doors(table: dict, shape: HallwayShape, source: str) -> list[DoorSpec]:
    rows = list_of(table["doors"], source, "doors", "expected a list of doors")
    if not rows:
        _fail(source, "doors", "empty list: at least one door is needed")
    doors = [_door(row, shape, source, f"doors[{k}]") for k, row in enumerate(rows)]
    _check_door_places(doors, shape, source)
    return doors


def _arena_door(door: DoorSpec, shape: HallwayShape) -> Door:
    y = shape.width if door.side == "north" else 0.0
    return Door(door.room, (door.x0, y), (door.x1, y), door.plate)


def _name(table: dict, source: str) -> str:
    name = table.get("name", "hallway")
    if not isinstance(name, str) or not name.strip():
        _fail(source, "name", f"not a non-empty string: {shown(name)}")
    return name.strip()


def _rotate(table: dict, source: str) -> float:
    raw = table.get("rotate_deg", 0)
    if isinstance(raw, bool) or not isinstance(raw, (int, float)) or not math.isfinite(raw):
        _fail(source, "rotate_deg", f"not a finite number: {shown(raw)}")
    return float(raw)


def _active(table: dict, source: str) -> str:
    return _room(table["active_goal"], source, "active_goal")


def build_hallway(table: dict, source: str = "<door table>", robot_radius: float = 10.0) -> Arena:
    """The hallway :class:`Arena` described by a door table (see the module docstring)."""
    table = mapping_of(table, source, "", "expected a door table with hallway, start, doors")
    check_keys(table, TABLE_KEYS, TABLE_REQUIRED, source, "")
    shape = _shape(table, source)
    doors = _doors(table, shape, source)
    arena = Arena(
        name=_name(table, source),
        walls=hallway_walls(shape),
        goals=tuple(Goal(d.room, d.plate) for d in doors),
        end_of_world=hallway_markers(shape),
        start=_start(table, shape, source),
        active_goal=_active(table, source),
        doors=tuple(_arena_door(d, shape) for d in doors),
        rotate_deg=_rotate(table, source),
        source=source,
    )
    validate_arena(arena, robot_radius)
    return arena


def load_door_table(path: str | Path) -> dict:
    """Read a door table file and check it (a bad table raises a one-line ArenaError)."""
    source = str(path)
    data = read_yaml(Path(path), source)
    if data is None:
        _fail(source, "", "empty file (expected a door table with hallway, start, doors)")
    build_hallway(data, source)
    return data
