"""The editing model: an arena document, undoable edits, snapping, validation, files.

:class:`EditorModel` holds the document as an immutable :class:`~koolio_pymunk.world.arena.Arena`
(which may be invalid while it is being edited). Every operation builds a new arena and
records an :class:`Edit` ``(label, before, after)``; undo and redo swap them. A mouse drag
previews its moves without recording them and records one edit when it ends.

Validation is the core's own :func:`~koolio_pymunk.world.arena.validate_arena`, run on the
document named after its file: the message is exactly what ``koolio-pm check-arena FILE``
prints after ``koolio-pm: error:``, and :class:`Problem` adds the item paths to highlight.

Saving (see :meth:`EditorModel.save`): a valid arena is written atomically. An invalid one
is not written unless the caller confirms; when it is confirmed and the file on disk
still holds a valid arena, that file is first copied to ``FILE.bak``, so the last good
version is never lost silently.

Example::

    >>> m = EditorModel.blank()
    >>> for p in [(0, 0), (240, 0), (240, 192), (0, 192)]:
    ...     _ = m.add_vertex(("walls",), p)
    >>> m.problem().message
    '<untitled>: goals: empty list: at least one goal is needed'
    >>> _ = m.add_goal("201", (100, 191)), m.add_marker((200, 100)), m.set_start((48, 48))
    >>> m.problem() is None
    True
    >>> m.undo()
    'move start to (48, 48)'
    >>> m.problem().message
    '<untitled>: start.at: point (0, 0) is outside the walls (or on them)'
    >>> m.problem().paths
    (('start',),)
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path as FilePath

from ...store.errors import ArenaError, KoolioError
from ...store.files import atomic_write, atomic_write_text, read_bytes, read_text
from ...world import geometry
from ...world.arena import (
    MAX_ARENA_BYTES,
    Arena,
    Goal,
    Marker,
    Point,
    Start,
    arena_to_yaml,
    load_arena,
    parse_arena,
    parse_yaml_text,
    validate_arena,
)
from ...world.hallway import build_hallway, load_door_table
from . import items, limits
from .items import EditError, Path

UNTITLED = "<untitled>"
"""The ``source`` of a document that has no file yet."""
DEFAULT_TILE_IN = 24.0
"""Ceiling tile side, inches (paper, Figure 3)."""
HISTORY_LIMIT = 1000
WALL_INSET = 1.0
"""A goal or marker placed on a wall goes this far inside it (inches; the plates' 1 in)."""
NEW_HEADER = "Made with tools/arena_editor.py. Units: inches (1 ceiling tile = 24 in)."


@dataclass(frozen=True)
class Edit:
    """One undoable edit: the document before and after."""

    label: str
    before: Arena
    after: Arena


@dataclass(frozen=True)
class Problem:
    """The first problem the core's validator finds, and what to highlight."""

    message: str
    """Exactly ``str(ArenaError)``: ``source: item: problem``."""
    item: str
    """The item named by the message (``walls[3]``, ``goals[1].at`` ...), or ``''``."""
    paths: tuple[Path, ...] = ()
    """Items to highlight: the offending item first, then items the problem mentions."""
    edges: tuple[tuple[Path, int], ...] = ()
    """Polygon edges the problem mentions: ``(polygon path, edge index)``."""


@dataclass(frozen=True)
class SaveResult:
    """What :meth:`EditorModel.save` did."""

    saved: bool
    path: FilePath
    message: str
    needs_confirmation: bool = False
    backup: FilePath | None = None


# =========================================================================================
# Files
# =========================================================================================
def read_header(text: str) -> str:
    """The leading ``#`` comment lines of an arena file (kept when the file is saved)."""
    lines = []
    for line in text.splitlines():
        if not line.startswith("#"):
            break
        lines.append(line)
    return "\n".join(lines)


def parse_unchecked(data: object, source: str) -> Arena:
    """The core parser without the geometry checks: keys and types are checked (a
    malformed file cannot be opened); an invalid geometry is returned to be fixed."""
    return parse_arena(data, source, validate=False)


def read_arena_file(path: str | FilePath) -> tuple[Arena, str]:
    """``(arena, header)`` of an arena file whose geometry may be invalid."""
    source = str(path)
    try:
        text = read_text(path, MAX_ARENA_BYTES, "arena file")
    except KoolioError as exc:
        raise ArenaError(str(exc)) from None
    return parse_unchecked(parse_yaml_text(text, source), source), read_header(text)


def _holds_valid_arena(path: FilePath, robot_radius: float) -> bool:
    try:
        load_arena(path, robot_radius)
    except KoolioError:
        return False
    return True


# =========================================================================================
# Problems: the validator's message and what it points at
# =========================================================================================
_POLY = r"(?:walls|obstacles\[\d+\]|end_of_world\[\d+\]\.zone)"
_EDGE_PAIR = re.compile(rf"({_POLY})\[(\d+)\]-\1\[(\d+)\]")
_EDGE_SINGLE = re.compile(rf"(?:edge|meets) ({_POLY})\[(\d+)\]")
_ITEM_REF = re.compile(r"(?:walls|obstacles|goals|end_of_world)(?:\[\d+\])+(?:\.zone(?:\[\d+\])?)?")
_ITEM = re.compile(r"^[A-Za-z_][\w\[\].]*$")
_KEEP_SUFFIXES = ("zone", "a", "b", "plate")


def _highlight_path(text: str) -> Path | None:
    """The editable item an item name in a message points at (``goals[1].name`` -> goal 1)."""
    try:
        path = items.parse_path(text)
    except EditError:
        return None
    while len(path) > 1 and isinstance(path[-1], str) and path[-1] not in _KEEP_SUFFIXES:
        path = path[:-1]
    if path[0] not in ("walls", "obstacles", "goals", "end_of_world", "start", "doors"):
        return None
    return None if path in (("goals",), ("end_of_world",), ("obstacles",)) else path


def parse_problem(message: str, source: str) -> Problem:
    """Split a validator message into its item and the items and edges to highlight."""
    rest = message[len(source) + 2 :] if message.startswith(f"{source}: ") else message
    item, _, text = rest.partition(": ")
    if not _ITEM.match(item) or not text:
        return Problem(message, "")
    paths: list[Path] = []
    main = _highlight_path(item)
    if main is not None:
        paths.append(main)
    edges: list[tuple[Path, int]] = []
    for m in _EDGE_PAIR.finditer(text):
        edges.append((items.parse_path(m.group(1)), int(m.group(2))))
    text = _EDGE_PAIR.sub(" ", text)
    for m in _EDGE_SINGLE.finditer(text):
        edges.append((items.parse_path(m.group(1)), int(m.group(2))))
    text = _EDGE_SINGLE.sub(" ", text)
    for m in _ITEM_REF.finditer(text):
        extra = _highlight_path(m.group(0))
        if extra is not None and extra not in paths:
            paths.append(extra)
    return Problem(message, item, tuple(paths), tuple(edges))


# =========================================================================================
# The model
# =========================================================================================
class EditorModel:
    """An arena document with undoable edits, snapping, validation and files."""

    def __init__(
        self,
        arena: Arena,
        path: str | FilePath | None = None,
        header: str = "",
        robot_radius: float = 10.0,
        tile: float = DEFAULT_TILE_IN,
    ) -> None:
        self.robot_radius = float(robot_radius)
        self.tile = DEFAULT_TILE_IN
        """Grid (ceiling tile) size in inches: drawn, and the default snap step
        (:data:`~koolio_pymunk.apps.editor.limits.MIN_GRID` to
        :data:`~koolio_pymunk.apps.editor.limits.MAX_GRID`; set it with :meth:`set_grid`)."""
        self.snap_step: float | None = self.tile
        """Snap positions to multiples of this many inches (None: 0.01 in; set it with
        :meth:`set_snap`)."""
        self.set_grid(tile)
        self._reset(arena, path, header)

    # -- construction -------------------------------------------------------------------
    @classmethod
    def blank(cls, name: str = "untitled", **kw) -> EditorModel:
        """A new empty document (no walls, goals or markers yet; start at the origin)."""
        model = cls(_blank_arena(limits.check_name(name, "name")), None, NEW_HEADER, **kw)
        return model

    @classmethod
    def from_file(cls, path: str | FilePath, **kw) -> EditorModel:
        arena, header = read_arena_file(path)
        return cls(arena, path, header, **kw)

    def _reset(self, arena: Arena, path: str | FilePath | None, header: str) -> None:
        self.path: FilePath | None = None if path is None else FilePath(path)
        self.source = UNTITLED if path is None else str(path)
        self.header = header
        self._arena = replace(arena, source=self.source)
        self._saved = self._arena if path is not None else None
        self.undo_stack: list[Edit] = []
        self.redo_stack: list[Edit] = []
        self._drag_before: Arena | None = None
        self._checked: tuple[Arena, Problem | None] | None = None
        self.last_label = ""

    def describe(self) -> str:
        """The document in a few words: its arena's name and its file.

        >>> EditorModel.blank("office").describe()
        "arena 'office' (not saved yet)"
        """
        where = "not saved yet" if self.path is None else str(self.path)
        return f"arena {self._arena.name!r} ({where})"

    def set_path(self, path: str | FilePath) -> None:
        """Name the document's file (without saving): messages then name it too."""
        self.path, self.source = FilePath(path), str(path)
        self._arena = replace(self._arena, source=self.source)
        self._checked = None

    def new(self, name: str = "untitled") -> None:
        """Start a new empty document (history cleared)."""
        self._reset(_blank_arena(limits.check_name(name, "name")), None, NEW_HEADER)

    def open(self, path: str | FilePath) -> None:
        """Open an arena file (its geometry may be invalid; a malformed file raises)."""
        arena, header = read_arena_file(path)
        self._reset(arena, path, header)

    def import_door_table(self, path: str | FilePath) -> None:
        """Build a hallway from a door table (:mod:`koolio_pymunk.world.hallway`) as a new document.

        The table is checked and built by :func:`~koolio_pymunk.world.hallway.build_hallway`
        (a bad table raises its one-line ArenaError); a hallway beyond the editor's ranges
        (:mod:`~koolio_pymunk.apps.editor.limits`: a point beyond +-1,000,000 in) is
        refused too, as the simulator would refuse the file. The document has no file yet.
        """
        table = load_door_table(path)
        arena = build_hallway(table, str(path), self.robot_radius)
        try:
            limits.check_arena(arena)
        except EditError as exc:
            raise ArenaError(f"{path}: the hallway it builds: {exc}") from None
        self._reset(arena, None, importer_header(path))

    # -- state ----------------------------------------------------------------------------
    @property
    def arena(self) -> Arena:
        """The document (``source`` is the file name, or ``<untitled>``)."""
        return self._arena

    @property
    def dirty(self) -> bool:
        """True when the document differs from the file it was opened from or saved to."""
        return self._saved is None or _content(self._arena) != _content(self._saved)

    def problem(self) -> Problem | None:
        """The validator's first problem with the document, or None when it is valid."""
        cached = self._checked
        if cached is not None and cached[0] is self._arena:
            return cached[1]
        try:
            validate_arena(self._arena, self.robot_radius)
            found = None
        except ArenaError as exc:
            found = parse_problem(str(exc), self.source)
        self._checked = (self._arena, found)
        return found

    # -- grid and snap ----------------------------------------------------------------------
    def set_grid(self, tile: float) -> None:
        """The grid (tile) size and snap step, inches (1 to 1,000: see
        :mod:`~koolio_pymunk.apps.editor.limits`)."""
        limits.check_range(tile, limits.MIN_GRID, limits.MAX_GRID, "grid", " in")
        self.tile = self.snap_step = float(tile)

    def set_snap(self, step: float | None) -> None:
        """The snap step, inches (0.01 to 1,000), or None: off (0.01 in)."""
        if step is not None:
            limits.check_range(step, limits.MIN_SNAP, limits.MAX_SNAP, "snap", " in")
            step = float(step)
        self.snap_step = step

    # -- history --------------------------------------------------------------------------
    def _apply(self, label: str, new: Arena) -> bool:
        """Record ``new`` as an edit (no-op when nothing changed). An edit that would
        leave the editor's ranges (:func:`~koolio_pymunk.apps.editor.limits.check_arena`:
        a point beyond the coordinate range, more points or entries than the simulator
        loads) raises :class:`EditError` and changes nothing."""
        self._end_drag_silently()
        new = replace(new, source=self.source)
        if new == self._arena:
            return False
        limits.check_arena(new, self._arena)
        self.undo_stack.append(Edit(label, self._arena, new))
        del self.undo_stack[:-HISTORY_LIMIT]
        self.redo_stack.clear()
        self._arena = new
        self.last_label = label
        return True

    def undo(self, times: int = 1) -> str | None:
        """Undo the last ``times`` edits (fewer when the history holds fewer: it stops
        at its start at once, whatever ``times``); the label of the last one undone, or
        None when there was nothing to undo."""
        self._end_drag_silently()
        n = min(max(times, 0), len(self.undo_stack))
        if n == 0:
            return None
        done = self.undo_stack[-n:]
        del self.undo_stack[-n:]
        self.redo_stack.extend(reversed(done))
        self._arena = replace(done[0].before, source=self.source)
        return done[0].label

    def redo(self, times: int = 1) -> str | None:
        """Redo the last ``times`` undone edits (fewer when there are fewer); the label of
        the last one redone, or None when there was nothing to redo."""
        self._end_drag_silently()
        n = min(max(times, 0), len(self.redo_stack))
        if n == 0:
            return None
        done = self.redo_stack[-n:]
        del self.redo_stack[-n:]
        self.undo_stack.extend(reversed(done))
        self._arena = replace(done[0].after, source=self.source)
        return done[0].label

    # -- drags: preview without history, one edit at the end -------------------------------
    def begin_drag(self) -> None:
        self._drag_before = self._arena

    def drag_move(self, path: Path, p: Point) -> None:
        """Preview moving point ``path`` to ``p`` (not recorded until :meth:`end_drag`)."""
        self._preview(_moved(self._drag_start(), path, p))

    def drag_translate(self, path: Path, dx: float, dy: float) -> None:
        """Preview moving ``path`` by ``(dx, dy)`` from where it was when the drag began."""
        self._preview(items.translated(self._drag_start(), path, dx, dy))

    def end_drag(self, label: str) -> bool:
        """Record the drag as one edit (nothing when nothing moved)."""
        before, self._drag_before = self._drag_before, None
        if before is None:
            return False
        after, self._arena = self._arena, before
        return self._apply(label, after)

    def cancel_drag(self) -> None:
        if self._drag_before is not None:
            self._arena, self._drag_before = self._drag_before, None

    def _drag_start(self) -> Arena:
        if self._drag_before is None:
            self.begin_drag()
        return self._drag_before

    def _preview(self, arena: Arena) -> None:
        self._arena = replace(arena, source=self.source)

    def _end_drag_silently(self) -> None:
        if self._drag_before is not None:
            self.end_drag("move")

    # -- snapping -------------------------------------------------------------------------
    def snap(self, p: Point, vertex_tol: float = 0.0, exclude: Path | None = None) -> Point:
        """An existing point within ``vertex_tol`` of ``p`` (not ``exclude``), else ``p``
        on the snap grid (multiples of :attr:`snap_step`; 0.01 in when snapping is off)."""
        if vertex_tol > 0:
            best, best_d = None, vertex_tol
            for path, q in items.all_vertices(self._drag_before or self._arena):
                if exclude is not None and path[: len(exclude)] == exclude:
                    continue
                d = math.hypot(q[0] - p[0], q[1] - p[1])
                if d <= best_d:
                    best, best_d = q, d
            if best is not None:
                return best
        return limits.clamp_point((self.snap_value(p[0]), self.snap_value(p[1])))

    def snap_inside(self, p: Point) -> Point:
        """Where a goal or end-of-world marker placed at ``p`` goes: ``p`` on the snap grid,
        unless that grid point lies on the walls or outside them (with the default 24 in
        snap a click near a wall lands on it, which the validator refuses). Then it goes
        :data:`WALL_INSET` inside the wall nearest ``p``, at the grid position along that
        wall, as the door plates sit 1 in off their wall."""
        q = self.snap(p)
        walls = self._arena.walls
        if len(walls) < 3 or geometry.point_in_polygon(q, walls):
            return q
        n = len(walls)
        i = min(
            range(n), key=lambda k: geometry.distance_point_segment(p, walls[k], walls[(k + 1) % n])
        )
        a, b = walls[i], walls[(i + 1) % n]
        foot = self._snap_along(items.closest_point(p, a, b), a, b)
        length = math.dist(a, b)
        if length == 0.0:
            return q
        side = 1.0 if geometry.polygon_area(walls) > 0 else -1.0  # interior on the left
        nx, ny = -(b[1] - a[1]) / length * side, (b[0] - a[0]) / length * side
        r = (round(foot[0] + nx * WALL_INSET, 6) + 0.0, round(foot[1] + ny * WALL_INSET, 6) + 0.0)
        return r if geometry.point_in_polygon(r, walls) else q

    def _snap_along(self, foot: Point, a: Point, b: Point) -> Point:
        """``foot`` (on edge ``a``-``b``) moved to the grid along an axis-aligned edge, kept
        :data:`WALL_INSET` from its ends."""
        for k in (0, 1):  # k: the coordinate that varies along the edge
            if a[1 - k] == b[1 - k] and a[k] != b[k]:
                lo, hi = sorted((a[k], b[k]))
                v = self.snap_value(foot[k])
                if hi - lo > 2 * WALL_INSET:
                    v = min(max(v, lo + WALL_INSET), hi - WALL_INSET)
                else:
                    v = foot[k]
                return (v, a[1]) if k == 0 else (a[0], v)
        return foot

    def snap_value(self, x: float) -> float:
        """``x`` rounded to the snap step (tidy floats: no ``96.00000000001``)."""
        step = self.snap_step or 0.01
        return round(round(x / step) * step, 6) + 0.0

    # -- vertices -------------------------------------------------------------------------
    def add_vertex(self, poly: Path, p: Point) -> Path:
        """Append ``p`` to polygon ``poly`` (``walls``, ``obstacles[k]``, a zone); its path."""
        pts = items.get_polygon(self._arena, poly)
        self._apply(
            f"add {items.path_str((*poly, len(pts)))} at {_fmt(p)}",
            items.with_polygon(self._arena, poly, (*pts, p)),
        )
        return (*poly, len(pts))

    def insert_vertex(self, poly: Path, edge: int, p: Point) -> Path:
        """Insert ``p`` on edge ``edge`` of ``poly`` (between vertices ``edge`` and
        ``edge + 1``): it becomes vertex ``edge + 1``. Returns its path."""
        pts = items.get_polygon(self._arena, poly)
        if not 0 <= edge < len(pts):
            raise EditError(f"{items.path_str(poly)}: no edge {edge} (there are {len(pts)} edges)")
        new = (*pts[: edge + 1], p, *pts[edge + 1 :])
        path = (*poly, edge + 1)
        self._apply(
            f"insert {items.path_str(path)} at {_fmt(p)}",
            items.with_polygon(self._arena, poly, new),
        )
        return path

    def move_point(self, path: Path, p: Point) -> None:
        """Move a vertex, goal, marker or the start to ``p``."""
        self._apply(f"move {items.path_str(path)} to {_fmt(p)}", _moved(self._arena, path, p))

    def translate(self, path: Path, dx: float, dy: float) -> None:
        """Move an item (a point, an obstacle or a zone) by ``(dx, dy)``."""
        if not items.is_movable(path):
            raise EditError(f"{items.path_str(path)}: cannot be moved as a whole")
        if items.is_polygon_path(path):
            new = items.translated(self._arena, path, dx, dy)
        else:
            x, y = items.get_point(self._arena, path)
            new = _moved(self._arena, path, (x + dx, y + dy))
        self._apply(f"move {items.path_str(path)} by {_fmt((dx, dy))}", new)

    def delete(self, path: Path) -> None:
        """Delete an item: a vertex, obstacle, goal, marker, zone (back to the default
        disc) or all the walls. The start cannot be deleted."""
        self._apply(f"delete {items.path_str(path)}", _deleted(self._arena, path))

    # -- obstacles --------------------------------------------------------------------------
    def add_obstacle(self, points: Sequence[Point]) -> Path:
        """Add an obstacle polygon (possibly unfinished: fewer than 3 points); its path."""
        k = len(self._arena.obstacles)
        poly = tuple((float(x), float(y)) for x, y in points)
        self._apply(
            f"add obstacles[{k}]", replace(self._arena, obstacles=(*self._arena.obstacles, poly))
        )
        return ("obstacles", k)

    # -- goals --------------------------------------------------------------------------------
    def goal_index(self, name: str) -> int:
        """The index of the goal called ``name``."""
        for i, g in enumerate(self._arena.goals):
            if g.name == name:
                return i
        raise EditError(f"goals: no goal named {name!r} (goals: {self._goal_list()})")

    def add_goal(self, name: str, p: Point) -> Path:
        """Add a goal (a room's number plate) called ``name``; its path."""
        name = self._new_goal_name(name)
        goal = Goal(name, (float(p[0]), float(p[1])))
        k = len(self._arena.goals)
        self._apply(
            f"add goal {name!r} at {_fmt(p)}",
            replace(self._arena, goals=(*self._arena.goals, goal)),
        )
        return ("goals", k)

    def rename_goal(self, old: str, new: str) -> None:
        """Rename a goal (and the door of the same name, and the active goal if it was)."""
        i = self.goal_index(old)
        new = self._new_goal_name(new, allow=old)
        goals = list(self._arena.goals)
        goals[i] = Goal(new, goals[i].at)
        doors = tuple(replace(d, name=new) if d.name == old else d for d in self._arena.doors)
        active = new if self._arena.active_goal == old else self._arena.active_goal
        self._apply(
            f"rename goal {old!r} to {new!r}",
            replace(self._arena, goals=tuple(goals), doors=doors, active_goal=active),
        )

    def set_active_goal(self, name: str) -> None:
        """Make ``name`` the active goal (the one the cameras see during an episode)."""
        self.goal_index(name)
        self._apply(f"active goal {name!r}", replace(self._arena, active_goal=name))

    def next_goal_name(self) -> str:
        """A default name for a new goal: one more than the largest room number."""
        numbers = [int(g.name) for g in self._arena.goals if g.name.isdigit()]
        n = max(numbers) + 1 if numbers else len(self._arena.goals) + 1
        while str(n) in self._arena.goal_names():
            n += 1
        return str(n)

    def _new_goal_name(self, name: str, allow: str | None = None) -> str:
        if not str(name).strip():
            raise EditError("goals: a goal needs a name (a room number)")
        name = limits.check_name(name, "goals")
        if name != allow and name in self._arena.goal_names():
            raise EditError(f"goals: there is already a goal named {name!r}")
        return name

    def _goal_list(self) -> str:
        return ", ".join(self._arena.goal_names()) or "none"

    # -- end-of-world markers and zones -------------------------------------------------------
    def add_marker(self, p: Point, zone: Sequence[Point] | None = None) -> Path:
        """Add an end-of-world marker (zone None: a disc of one robot diameter); its path."""
        k = len(self._arena.end_of_world)
        z = None if not zone else tuple((float(x), float(y)) for x, y in zone)
        marker = Marker((float(p[0]), float(p[1])), z)
        self._apply(
            f"add end_of_world[{k}] at {_fmt(p)}",
            replace(self._arena, end_of_world=(*self._arena.end_of_world, marker)),
        )
        return ("end_of_world", k)

    def set_zone(self, marker: int, points: Sequence[Point] | None) -> None:
        """Replace marker ``marker``'s zone (None or empty: the default disc)."""
        path = ("end_of_world", marker, "zone")
        pts = None if not points else tuple(points)
        what = "default disc" if pts is None else f"{len(pts)} points"
        self._apply(
            f"zone of end_of_world[{marker}]: {what}",
            items.with_polygon(self._arena, path, pts),
        )

    # -- start, name, rotation ------------------------------------------------------------------
    def set_start(self, p: Point) -> None:
        self.move_point(("start",), p)

    def set_heading(self, deg: float | None) -> None:
        """Fix the start heading (degrees, counter-clockwise from east) or None: random."""
        if deg is not None and not math.isfinite(deg):
            raise EditError("start.heading_deg: not a finite number")
        heading = None if deg is None else float(deg) % 360.0
        what = "random" if heading is None else f"{heading:g} deg"
        start = Start(self._arena.start.at, heading)
        self._apply(f"start heading {what}", replace(self._arena, start=start))

    def set_name(self, name: str) -> None:
        """Rename the arena (1 to 100 printable characters)."""
        if not str(name).strip():
            raise EditError("name: the arena needs a name")
        name = limits.check_name(name, "name")
        self._apply(f"name {name!r}", replace(self._arena, name=name))

    def set_rotate(self, deg: float) -> None:
        """The paper's ``rotate_deg`` (everything rotated clockwise in the simulator)."""
        if not math.isfinite(deg):
            raise EditError("rotate_deg: not a finite number")
        self._apply(f"rotate_deg {deg:g}", replace(self._arena, rotate_deg=float(deg)))

    # -- saving -------------------------------------------------------------------------------
    def save(self, path: str | FilePath | None = None, confirm: bool = False) -> SaveResult:
        """Save to ``path`` (default: the document's file) with the file's header comment.

        * A valid arena is written atomically; the file becomes the document's file.
        * An invalid arena is **not** written unless ``confirm``: the result then has
          ``needs_confirmation`` and the validator's message (ask the user, call again
          with ``confirm=True``).
        * Confirmed, if the file on disk still holds a valid arena it is first copied to
          ``FILE.bak``; then the invalid arena is written (the editor can reopen it; the
          core refuses it with the same message until it is fixed).
        """
        self._end_drag_silently()
        target = FilePath(path) if path is not None else self.path
        if target is None:
            raise EditError(f"{UNTITLED}: no file name yet: save as FILE")
        arena = replace(self._arena, source=str(target))
        problem = _first_problem(arena, self.robot_radius)
        if problem is not None and not confirm:
            return SaveResult(False, target, problem, needs_confirmation=True)
        backup = None
        if (
            problem is not None
            and target.exists()
            and _holds_valid_arena(target, self.robot_radius)
        ):
            backup = target.with_name(target.name + ".bak")
            atomic_write(backup, read_bytes(target, MAX_ARENA_BYTES, "arena file"))
        atomic_write_text(target, arena_to_yaml(arena, self.header))
        self.path, self.source = target, str(target)
        self._arena = self._saved = arena
        self._checked = None
        what = "invalid arena " if problem else ""
        kept = f" (the previous valid file is kept as {backup})" if backup else ""
        return SaveResult(True, target, f"saved {what}{target}{kept}", backup=backup)


# =========================================================================================
# Helpers
# =========================================================================================
def importer_header(table: str | FilePath) -> str:
    """Header comment of an arena built by the door-table importer."""
    return (
        f"Built from the door table {table} by the door-table importer of "
        "tools/arena_editor.py.\n"
        f"The same arena comes from: .venv/bin/python tools/make_hallway.py --doors {table}\n"
        "Units: inches (1 ceiling tile = 24 in)."
    )


def _blank_arena(name: str) -> Arena:
    return Arena(name=name, walls=(), goals=(), end_of_world=(), start=Start((0.0, 0.0), None))


def _content(arena: Arena) -> Arena:
    return replace(arena, source="")


def _first_problem(arena: Arena, robot_radius: float) -> str | None:
    try:
        validate_arena(arena, robot_radius)
    except ArenaError as exc:
        return str(exc)
    return None


def _moved(arena: Arena, path: Path, p: Point) -> Arena:
    """``arena`` with point ``path`` at ``p``; a goal takes its door's plate along when
    they coincide (as in the generated hallway)."""
    new = items.with_point(arena, path, p)
    if len(path) == 2 and path[0] == "goals":
        goal = arena.goals[path[1]]
        for k, door in enumerate(arena.doors):
            if door.name == goal.name and door.plate == goal.at:
                new = items.with_point(new, ("doors", k, "plate"), p)
    return new


def _deleted(arena: Arena, path: Path) -> Arena:
    """``arena`` without the item ``path``."""
    if path == ("start",):
        raise EditError("start: the start cannot be deleted (move it instead)")
    if path == ("walls",):
        return replace(arena, walls=())
    if items.is_vertex_path(path):
        poly_path, i = path[:-1], path[-1]
        pts = list(items.get_polygon(arena, poly_path))
        items.get_point(arena, path)
        del pts[i]
        if not pts and poly_path[0] == "obstacles":
            return _deleted(arena, poly_path)
        return items.with_polygon(arena, poly_path, tuple(pts) or None)
    if len(path) == 3 and path[0] == "end_of_world" and path[2] == "zone":
        return items.with_polygon(arena, path, None)
    if len(path) == 2 and path[0] in ("obstacles", "goals", "end_of_world", "doors"):
        seq = getattr(arena, path[0])
        if not isinstance(path[1], int) or not 0 <= path[1] < len(seq):
            raise EditError(f"{items.path_str(path)}: no such item (there are {len(seq)})")
        rest = seq[: path[1]] + seq[path[1] + 1 :]
        if path[0] == "goals" and arena.goals[path[1]].name == arena.active_goal:
            return replace(arena, goals=rest, active_goal=rest[0].name if rest else "")
        return replace(arena, **{path[0]: rest})
    raise EditError(f"{items.path_str(path)}: cannot be deleted")


def _fmt(p: Point) -> str:
    return f"({p[0]:g}, {p[1]:g})"
