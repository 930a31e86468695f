"""Drawing the editor: the arena (the viewer's :func:`~koolio_pymunk.task.drawing.draw_arena`)
and the editor's own things over it: grid, handles, selection, the validator's highlight,
segment lengths, the test-drive robot and its sensors, the side panel and the status bar.

Every world <-> screen conversion goes through the app's
:class:`~koolio_pymunk.apps.editor.camera.EditorCamera`, and everything is clipped to the
canvas before pygame draws it (:mod:`~koolio_pymunk.apps.editor.clip`), so a frame costs
the same at any zoom and for any arena. Labels never cover one another: the edge lengths
keep clear of the door labels, the plates, the goal and marker dots and the start, and
the goal names keep clear of all of these and of the lengths.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import pygame

from ...task import drawing as draw
from ...task.viewport import Camera
from ...world import geometry
from ...world.arena import Arena, Point
from . import clip, items
from .items import Path

if TYPE_CHECKING:
    from .app import EditorApp

# -- palette (the arena's own colours are the viewer's) --------------------------------------
PANEL_BG = (36, 40, 48)
PANEL_TEXT = (226, 230, 236)
PANEL_DIM = (150, 158, 170)
PANEL_HOT = (255, 214, 90)
STATUS_BG = (246, 246, 242)
STATUS_TEXT = (30, 34, 40)
OK = (0, 130, 60)
ERROR = (205, 0, 0)
SELECT = (0, 170, 210)
HOVER = (60, 120, 255)
HANDLE_WALL = (40, 44, 52)
HANDLE_OBSTACLE = (90, 94, 104)
HANDLE_ZONE = (150, 80, 190)
LENGTH_BG = (255, 255, 255)
LENGTH_TEXT = (70, 70, 90)
GRID_MINOR = (0, 0, 0, 26)
GRID_MAJOR = (0, 0, 0, 52)
GRID_AXIS = (0, 0, 200, 90)
RUBBER = (0, 150, 200)

FONT = 20
SMALL = 17
LINE = 21
DOOR_LABEL = 16
"""The door labels' font size: the viewer's ``draw_arena`` default, which the editor uses."""
MAX_TEXT = 300
"""Characters of one line of text drawn at most (a name read from a file may be longer)."""
MAX_LABEL = 40
"""Characters of a goal or door name drawn on the canvas at most."""


def text(surface: pygame.Surface, s: str, pos: tuple[int, int], colour, size: int = FONT) -> int:
    """Blit one line of text (its first :data:`MAX_TEXT` characters); returns its width."""
    img = draw.font(size).render(s[:MAX_TEXT], True, colour)
    surface.blit(img, pos)
    return img.get_width()


def fmt_len(inches: float, tile: float) -> str:
    """``96 in = 4 tiles`` (tiles to 2 decimals)."""
    return f"{inches:.4g} in = {_num(inches / tile)} tiles"


def _num(x: float) -> str:
    return f"{x:.2f}".rstrip("0").rstrip(".")


def short(name: str, limit: int = MAX_LABEL) -> str:
    """``name`` cut to ``limit`` characters (``...`` at the end) for drawing.

    >>> short("312"), short("x" * 50, 10)
    ('312', 'xxxxxxx...')
    """
    return name if len(name) <= limit else name[: limit - 3] + "..."


# =========================================================================================
# Lines clipped to the canvas
# =========================================================================================
def _safe_box(cam: Camera) -> clip.Rect:
    left, top, w, h = cam.viewport
    m = clip.SAFE_PIXELS
    return (left - m, top - m, left + w + m, top + h + m)


def _cut_box(cam: Camera) -> clip.Rect:
    left, top, w, h = cam.viewport
    m = clip.MARGIN_PIXELS
    return (left - m, top - m, left + w + m, top + h + m)


def line(surface: pygame.Surface, cam: Camera, colour, a, b, width: int = 1) -> None:
    """A line between screen points ``a`` and ``b``, cut to the canvas when it is long."""
    safe = _safe_box(cam)
    if not (clip.inside(a, safe) and clip.inside(b, safe)):
        part = clip.clip_segment(a, b, _cut_box(cam))
        if part is None:
            return
        a, b = (round(part[0][0]), round(part[0][1])), (round(part[1][0]), round(part[1][1]))
    pygame.draw.line(surface, colour, a, b, width=width)


def lines(surface: pygame.Surface, cam: Camera, colour, closed: bool, pts, width: int = 1) -> None:
    """``pygame.draw.lines`` through screen points ``pts``, cut to the canvas when long."""
    safe = _safe_box(cam)
    if all(clip.inside(p, safe) for p in pts):
        pygame.draw.lines(surface, colour, closed, pts, width=width)
        return
    ends = len(pts) if closed else len(pts) - 1
    for i in range(ends):
        line(surface, cam, colour, pts[i], pts[(i + 1) % len(pts)], width)


def _world_box(cam: Camera, box: clip.Rect) -> clip.Rect:
    """A screen rectangle as a world rectangle."""
    (x0, y1), (x1, y0) = cam.to_world((box[0], box[1])), cam.to_world((box[2], box[3]))
    return (x0, y0, x1, y1)


# =========================================================================================
# Frame
# =========================================================================================
def draw_frame(app: EditorApp) -> None:
    """Draw the whole window; an open question (a pygame-gui window) on top."""
    draw_canvas(app)
    draw_panel(app)
    draw_status(app)
    app.ui.draw_ui(app.screen)


def draw_canvas(app: EditorApp) -> None:
    surface, cam = app.screen, app.camera
    arena = app.model.arena
    drive = app.drive
    shown = arena.to_world() if drive is not None else arena
    drawable = clip.drawable_arena(
        _drawable(shown), _world_box(cam, _safe_box(cam)), _world_box(cam, _cut_box(cam))
    )
    draw.draw_arena(surface, drawable, cam, robot_radius=app.model.robot_radius)
    old_clip = surface.get_clip()
    surface.set_clip(pygame.Rect(cam.viewport))
    try:
        draw_grid(surface, cam, app.model.tile)
        if drive is not None:
            draw_drive(surface, cam, app)
        else:
            draw_editing(surface, cam, app, arena, door_label_rects(drawable, cam))
    finally:
        surface.set_clip(old_clip)


def _drawable(arena: Arena) -> Arena:
    """What the viewer's ``draw_arena`` may draw: it places doors relative to the walls'
    bounds (no walls, no doors), and draws door names whole (long ones are cut)."""
    from dataclasses import replace

    if not arena.walls:
        return replace(arena, doors=())
    if any(len(d.name) > MAX_LABEL for d in arena.doors):
        return replace(arena, doors=tuple(replace(d, name=short(d.name)) for d in arena.doors))
    return arena


def door_label_rects(arena: Arena, cam: Camera) -> list[pygame.Rect]:
    """Where the viewer's ``draw_arena`` (:mod:`koolio_pymunk.task.drawing`) puts each
    door's label and its number plate, computed as it does (the tests check this against
    the drawn pixels): the label just outside the wall, beside the plate, away from the
    centre of the walls' bounds."""
    out = []
    if not arena.doors or not arena.walls:
        return out
    xmin, ymin, xmax, ymax = arena.bounds()
    cx, cy = (xmin + xmax) / 2.0, (ymin + ymax) / 2.0
    font = draw.font(DOOR_LABEL)
    for d in arena.doors:
        plate = cam.to_screen(d.plate)
        out.append(pygame.Rect(plate[0] - 3, plate[1] - 3, 6, 6))
        dx, dy = d.b[0] - d.a[0], d.b[1] - d.a[1]
        n = math.hypot(dx, dy) or 1.0
        nx, ny = -dy / n, dx / n
        mx, my = (d.a[0] + d.b[0]) / 2.0, (d.a[1] + d.b[1]) / 2.0
        if nx * (mx - cx) + ny * (my - cy) < 0:
            nx, ny = -nx, -ny
        w, h = font.size(d.name)
        off = 4 + max(w, h) / 2.0
        centre = (round(plate[0] + nx * off), round(plate[1] - ny * off))
        out.append(pygame.Rect(0, 0, w, h).inflate(6, 2))
        out[-1].center = centre
    return out


def draw_grid(surface: pygame.Surface, cam: Camera, tile: float) -> None:
    """Ceiling-tile grid (every tile, or every 2, 5, 10 ... when zoomed out), axes bluish."""
    left, top, width, height = cam.viewport
    steps = (1, 2, 5, 10, 20, 50, 100, 200, 500, 1000)
    k = next((m for m in steps if tile * m * cam.zoom >= 9), steps[-1])
    step = tile * k
    (x0, y1), (x1, y0) = cam.to_world((left, top)), cam.to_world((left + width, top + height))
    overlay = pygame.Surface((width, height), pygame.SRCALPHA)
    for i in range(math.floor(x0 / step), math.ceil(x1 / step) + 1):
        sx = cam.to_screen((i * step, 0))[0] - left
        colour = GRID_AXIS if i == 0 else GRID_MAJOR if (i * k) % 5 == 0 else GRID_MINOR
        pygame.draw.line(overlay, colour, (sx, 0), (sx, height))
    for j in range(math.floor(y0 / step), math.ceil(y1 / step) + 1):
        sy = cam.to_screen((0, j * step))[1] - top
        colour = GRID_AXIS if j == 0 else GRID_MAJOR if (j * k) % 5 == 0 else GRID_MINOR
        pygame.draw.line(overlay, colour, (0, sy), (width, sy))
    surface.blit(overlay, (left, top))


# =========================================================================================
# Editing overlay
# =========================================================================================
def draw_editing(
    surface: pygame.Surface,
    cam: Camera,
    app: EditorApp,
    arena: Arena,
    doors: list[pygame.Rect] | None = None,
) -> None:
    """The editing overlay; ``doors`` are the door labels and plates the viewer drew
    (:func:`door_label_rects`), which no other label may cover."""
    doors = doors or []
    marks = doors + dot_rects(cam, arena, app.model.robot_radius)
    lengths = draw_lengths(surface, cam, arena, app.model.tile, marks) if app.show_lengths else []
    draw_start(surface, cam, arena, app.model.robot_radius)
    goals = draw_goal_labels(surface, cam, arena, doors + lengths)
    app.drawn_labels = {"lengths": lengths, "goals": goals, "doors": doors}
    draw_handles(surface, cam, arena)
    draw_rubber_band(surface, cam, app, arena)
    if app.hover_edge is not None:
        poly, i, _ = app.hover_edge
        _draw_edge(surface, cam, arena, poly, i, HOVER, 4)
    if app.hover is not None and app.hover != app.selection:
        _draw_item(surface, cam, arena, app.hover, HOVER, 2)
    if app.selection is not None:
        _draw_item(surface, cam, arena, app.selection, SELECT, 3)
    problem = app.model.problem()
    if problem is not None:
        for poly, i in problem.edges:
            _draw_edge(surface, cam, arena, poly, i, ERROR, 4)
        for path in problem.paths:
            _draw_item(surface, cam, arena, path, ERROR, 3, big=True)


def dot_rects(cam: Camera, arena: Arena, radius: float) -> list[pygame.Rect]:
    """The goal and marker dots and the start's footprint on the canvas (what a label
    must not cover)."""
    canvas = pygame.Rect(cam.viewport).inflate(200, 200)
    out = []
    for p in [g.at for g in arena.goals] + [m.at for m in arena.end_of_world]:
        s = cam.to_screen(p)
        if canvas.collidepoint(s):
            out.append(pygame.Rect(s[0] - 7, s[1] - 7, 15, 15))
    s, r = cam.to_screen(arena.start.at), cam.scale(radius)
    if canvas.collidepoint(s) and r < 400:
        out.append(pygame.Rect(s[0] - r, s[1] - r, 2 * r + 1, 2 * r + 1))
    return out


def draw_lengths(
    surface: pygame.Surface,
    cam: Camera,
    arena: Arena,
    tile: float,
    avoid: list[pygame.Rect] | None = None,
) -> list[pygame.Rect]:
    """Each wall and obstacle edge's length beside the edge on its outer side (outside
    the walls, outside an obstacle), so that it covers no goal or marker: at the middle,
    or the nearest place along the edge where it covers none of ``avoid`` (door labels,
    plates, dots) and no other length; on the inner side when the outer one has no such
    place on the canvas. Edges shorter than 80 pixels get none. Returns the labels'
    rectangles."""
    out: list[pygame.Rect] = []
    taken = list(avoid or [])
    canvas = pygame.Rect(cam.viewport)
    near = _cut_box(cam)
    near = (near[0] - 200, near[1] - 200, near[2] + 200, near[3] + 200)
    font = draw.font(SMALL)
    for poly_path in items.polygon_paths(arena)[: 1 + len(arena.obstacles)]:
        poly = items.get_polygon(arena, poly_path)
        n = len(poly)
        ccw = n >= 3 and geometry.polygon_area(poly) > 0
        for i in range(n if n >= 3 else n - 1):
            a, b = poly[i], poly[(i + 1) % n]
            sa, sb = cam.to_screen(a), cam.to_screen(b)
            if math.hypot(sb[0] - sa[0], sb[1] - sa[1]) < 80:
                continue
            if clip.clip_segment(sa, sb, near) is None:
                continue  # nowhere near the canvas
            length = math.hypot(b[0] - a[0], b[1] - a[1])
            label = f"{length:.4g} in"
            tiles = length / tile
            if abs(tiles - round(tiles)) < 1e-9:
                label += f" ({round(tiles)} t)"
            w, h = font.size(label)
            box = pygame.Rect(0, 0, w, h).inflate(4, 0)
            _place_length(box, sa, sb, ccw if n >= 3 else None, canvas, taken)
            pygame.draw.rect(surface, LENGTH_BG, box)
            img = font.render(label, True, LENGTH_TEXT)
            surface.blit(img, img.get_rect(center=box.center))
            out.append(box)
            taken.append(box)
    return out


SLIDE_PIXELS = 8
"""Step of the search for a free place for a length label along its edge, pixels."""
GAP = 3
"""Least gap between a length label and what it keeps clear of, pixels."""


def _place_length(
    box: pygame.Rect,
    sa: tuple[int, int],
    sb: tuple[int, int],
    ccw: bool | None,
    canvas: pygame.Rect,
    taken: list[pygame.Rect],
) -> None:
    """Centre ``box`` beside screen edge ``sa``-``sb``: the outer side first (the inner
    one for an open polyline, ``ccw`` None: on the edge), at the middle or slid along the
    edge by the least that clears ``taken`` and keeps it on the canvas; the middle of the
    outer side (or the inner one when that is off the canvas) when nothing is clear."""
    length = math.dist(sa, sb)
    ux, uy = (sb[0] - sa[0]) / length, (sb[1] - sa[1]) / length
    along = abs(ux) * box.w / 2.0 + abs(uy) * box.h / 2.0  # the box's half-extent along
    reach = min(max(0.0, length / 2.0 - along), 100 * SLIDE_PIXELS)
    slides = [0.0]
    for k in range(1, int(reach // SLIDE_PIXELS) + 1):
        slides += [k * SLIDE_PIXELS, -k * SLIDE_PIXELS]
    sides = [ccw] if ccw is None else [ccw, not ccw]
    for side in sides:
        for d in slides:
            box.center = _beside(sa, sb, box, side, d)
            if canvas.contains(box) and box.inflate(2 * GAP, 2 * GAP).collidelist(taken) < 0:
                return
    box.center = _beside(sa, sb, box, ccw)
    if ccw is not None and not canvas.contains(box):
        box.center = _beside(sa, sb, box, not ccw)  # off the canvas: inside


def _beside(
    sa: tuple[int, int],
    sb: tuple[int, int],
    box: pygame.Rect,
    ccw: bool | None,
    slide: float = 0.0,
) -> tuple[int, int]:
    """Centre for ``box`` by the middle of screen edge ``sa``-``sb`` (moved ``slide``
    pixels along it, towards ``sb``): on the edge's right in world terms (outside a
    counter-clockwise polygon), left for a clockwise one, on the edge for an open
    polyline (``ccw`` None)."""
    dx, dy = sb[0] - sa[0], sb[1] - sa[1]
    d = math.hypot(dx, dy) or 1.0
    mx, my = (sa[0] + sb[0]) / 2.0 + slide * dx / d, (sa[1] + sb[1]) / 2.0 + slide * dy / d
    if ccw is None:
        return round(mx), round(my)
    # The world's right of a->b, (dy, -dx) in world terms, is (-dy, dx) on the screen
    # (whose y points down).
    nx, ny = -dy / d, dx / d
    if not ccw:
        nx, ny = -nx, -ny
    off = 3 + abs(nx) * box.w / 2.0 + abs(ny) * box.h / 2.0
    return round(mx + nx * off), round(my + ny * off)


def draw_start(surface: pygame.Surface, cam: Camera, arena: Arena, radius: float) -> None:
    """The robot's footprint at the start, and its heading (or ``?`` when random)."""
    c = cam.to_screen(arena.start.at)
    r = cam.scale(radius)
    pygame.draw.circle(surface, draw.START, c, r, width=2)
    heading = arena.start.heading_deg
    if heading is None:
        img = draw.font(SMALL).render("?", True, draw.START)
        surface.blit(img, img.get_rect(center=(c[0] + r + 6, c[1] - r - 2)))
        return
    h = math.radians(heading)
    x, y = arena.start.at
    tip = cam.to_screen((x + 1.6 * radius * math.cos(h), y + 1.6 * radius * math.sin(h)))
    line(surface, cam, draw.START, c, tip, width=2)


def draw_goal_labels(
    surface: pygame.Surface, cam: Camera, arena: Arena, avoid: list[pygame.Rect] | None = None
) -> list[pygame.Rect]:
    """Names of the goals that have no door of their own (doors are labelled by the
    viewer), each beside its dot where it overlaps neither ``avoid`` (the edge lengths,
    the door labels) nor another name; long names are cut (:func:`short`). Returns the
    names' rectangles."""
    doors = {d.name for d in arena.doors}
    taken = list(avoid or [])
    out = []
    canvas = pygame.Rect(cam.viewport)
    for g in arena.goals:
        if g.name in doors:
            continue
        s = cam.to_screen(g.at)
        if not canvas.inflate(400, 400).collidepoint(s):
            continue  # no name of it can show
        colour = draw.GOAL if g.name == arena.active_goal else (80, 120, 90)
        img = draw.font(FONT).render(short(g.name), True, colour)
        rect = _free_spot(s, img.get_size(), taken, canvas)
        surface.blit(img, rect)
        taken.append(rect)
        out.append(rect)
    return out


def _free_spot(
    at: tuple[int, int], size: tuple[int, int], taken: list[pygame.Rect], area: pygame.Rect
) -> pygame.Rect:
    """A rectangle of ``size`` beside point ``at`` that overlaps none of ``taken`` (and
    lies in ``area``): above right, below right, above left, below left, then further
    out; the first place when every one is taken."""
    w, h = size
    spots = []
    for reach in (1, 2, 3):
        d = 7 + (reach - 1) * (h + 2)
        spots += [
            (at[0] + d, at[1] - h - d + 5),
            (at[0] + d, at[1] + d - 5),
            (at[0] - w - d, at[1] - h - d + 5),
            (at[0] - w - d, at[1] + d - 5),
        ]
    rects = [pygame.Rect(x, y, w, h) for x, y in spots]
    for r in rects:
        if area.contains(r) and r.collidelist(taken) < 0:
            return r
    return rects[0]


def draw_handles(surface: pygame.Surface, cam: Camera, arena: Arena) -> None:
    """Small squares on every polygon vertex on the canvas (walls dark, obstacles grey,
    zones purple)."""
    canvas = pygame.Rect(cam.viewport).inflate(8, 8)
    for poly_path in items.polygon_paths(arena):
        colour = {"walls": HANDLE_WALL, "obstacles": HANDLE_OBSTACLE}.get(poly_path[0], HANDLE_ZONE)
        for p in items.get_polygon(arena, poly_path):
            s = cam.to_screen(p)
            if not canvas.collidepoint(s):
                continue
            rect = pygame.Rect(s[0] - 3, s[1] - 3, 7, 7)
            pygame.draw.rect(surface, (255, 255, 255), rect)
            pygame.draw.rect(surface, colour, rect, width=2)


def draw_rubber_band(surface: pygame.Surface, cam: Camera, app: EditorApp, arena: Arena) -> None:
    """While adding vertices: the would-be edges from the last vertex to the cursor."""
    poly = app.building if app.building is not None else ("walls",) if app.tool == "wall" else None
    if poly is None or app.cursor is None:
        return
    try:
        pts = items.get_polygon(arena, poly)
    except items.EditError:
        return
    if not pts:
        return
    cursor = cam.to_screen(app.cursor)
    line(surface, cam, RUBBER, cam.to_screen(pts[-1]), cursor, width=2)
    if len(pts) >= 2:
        line(surface, cam, (150, 200, 220), cursor, cam.to_screen(pts[0]), width=1)


def _draw_edge(
    surface: pygame.Surface, cam: Camera, arena: Arena, poly: Path, i: int, colour, width: int
) -> None:
    try:
        pts = items.get_polygon(arena, poly)
    except items.EditError:
        return
    if len(pts) >= 2 and 0 <= i < len(pts):
        a, b = pts[i], pts[(i + 1) % len(pts)]
        line(surface, cam, colour, cam.to_screen(a), cam.to_screen(b), width=width)


def _draw_item(
    surface: pygame.Surface,
    cam: Camera,
    arena: Arena,
    path: Path,
    colour,
    width: int,
    big: bool = False,
) -> None:
    """Outline a polygon or ring a point (``big``: a larger ring, for problems)."""
    try:
        if items.is_polygon_path(path):
            pts = [cam.to_screen(p) for p in items.get_polygon(arena, path)]
            if len(pts) >= 2:
                lines(surface, cam, colour, len(pts) >= 3, pts, width=width)
            canvas = pygame.Rect(cam.viewport).inflate(12, 12)
            for s in pts:
                if canvas.collidepoint(s):
                    pygame.draw.circle(surface, colour, s, 5, width=2)
            return
        s = cam.to_screen(items.get_point(arena, path))
    except items.EditError:
        return
    pygame.draw.circle(surface, colour, s, 14 if big else 9, width=width)


# =========================================================================================
# Test drive
# =========================================================================================
def draw_drive(surface: pygame.Surface, cam: Camera, app: EditorApp) -> None:
    """Show Sensors: the viewer's sensor lines and the robot in the paper's colours."""
    drive = app.drive
    pose = drive.pose
    draw.draw_sensors(surface, cam, pose, drive.env.sensors, drive.readings)
    colour = draw.ROBOT_STATES[drive.robot_state()]
    draw.draw_robot(surface, cam, pose, drive.env.world.radius, colour)


# =========================================================================================
# Side panel and status bar
# =========================================================================================
TOOLS_HELP = (
    ("select", "V"),
    ("wall", "W"),
    ("insert", "I"),
    ("obstacle", "O"),
    ("goal", "G"),
    ("marker", "E"),
    ("zone", "Z"),
    ("start", "S"),
)
EDIT_KEYS = (
    "Del delete   R rename goal   A active goal",
    "Tab next active   P type x y   N arena name",
    "H heading fixed/random   [ ] turn 15 deg",
    "D default zone   X snap   L lengths   F fit",
    "Ctrl+Z undo   Ctrl+Y redo",
    "Ctrl+S save   Ctrl+Shift+S save as",
    "Ctrl+O open   Ctrl+N new   Ctrl+D door table",
    "F5 test drive   F12 screenshot   Ctrl+Q quit",
    "wheel/+ - zoom   right-drag/arrows pan",
)
DRIVE_KEYS = (
    "Up forward    Down reverse",
    "Left rotate left   Right rotate right",
    "Space stop   Enter back to start",
    "Esc or F5: back to editing",
)


class _Writer:
    """Writes lines down the panel."""

    def __init__(self, surface: pygame.Surface, x: int, y: int) -> None:
        self.surface, self.x, self.y = surface, x, y

    def line(self, s: str, colour=PANEL_TEXT, size: int = FONT, indent: int = 0) -> pygame.Rect:
        w = text(self.surface, s, (self.x + indent, self.y), colour, size)
        rect = pygame.Rect(self.x + indent, self.y, w, LINE)
        self.y += LINE if size >= FONT else LINE - 3
        return rect

    def gap(self, n: int = 6) -> None:
        self.y += n


def draw_panel(app: EditorApp) -> None:
    surface = app.screen
    rect = pygame.Rect(app.panel_rect)
    surface.fill(PANEL_BG, rect)
    w = _Writer(surface, rect.x + 12, rect.y + 10)
    m, arena = app.model, app.model.arena
    w.line("Koolio arena editor", PANEL_HOT, 22)
    w.line(f"file: {m.path or '(not saved yet)'}{'  *modified*' if m.dirty else ''}", PANEL_DIM)
    size = ""
    if arena.walls:
        xmin, ymin, xmax, ymax = arena.bounds()
        size = f"   {xmax - xmin:g} x {ymax - ymin:g} in"
    w.line(f"arena: {arena.name}{size}", PANEL_TEXT)
    if arena.rotate_deg:
        frame = "simulator's frame" if app.drive is not None else "drawn unrotated"
        w.line(f"rotate_deg {arena.rotate_deg:g} ({frame})", PANEL_DIM)
    w.gap()
    if app.drive is not None:
        _panel_drive(w, app)
    else:
        _panel_tools(w, app)
        _panel_selection(w, app)
        app.goal_rows = _panel_goals(w, app)
        w.gap()
        for s in EDIT_KEYS:
            w.line(s, PANEL_DIM, SMALL)


def _panel_tools(w: _Writer, app: EditorApp) -> None:
    w.line("Tools (click on the canvas):", PANEL_DIM)
    x0, y0 = w.x, w.y
    for k, (name, key) in enumerate(TOOLS_HELP):
        colour = PANEL_HOT if name == app.tool else PANEL_TEXT
        label = f"[{key}] {name}"
        if name == app.tool:
            label += " <"
        text(w.surface, label, (x0 + (k % 2) * 140, y0 + (k // 2) * LINE), colour)
    w.y = y0 + 4 * LINE + 4
    snap = f"{m:g} in" if (m := app.model.snap_step) else "off (0.01 in)"
    w.line(f"snap {snap}   grid {app.model.tile:g} in (1 tile)", PANEL_TEXT)
    w.gap()


def _panel_selection(w: _Writer, app: EditorApp) -> None:
    sel = app.selection
    if sel is None:
        w.line("nothing selected", PANEL_DIM)
        return
    arena, tile = app.model.arena, app.model.tile
    try:
        if items.is_polygon_path(sel):
            pts = items.get_polygon(arena, sel)
            w.line(f"selected {items.path_str(sel)}: {len(pts)} points", SELECT)
        else:
            p = items.get_point(arena, sel)
            w.line(f"selected {items.path_str(sel)} ({p[0]:g}, {p[1]:g})", SELECT)
    except items.EditError:
        w.line("nothing selected", PANEL_DIM)
        return
    if items.is_vertex_path(sel):
        for a, b, name in app.adjacent_edges(sel):
            short = name.replace(items.path_str(sel[:-1]), "")
            w.line(f"{short}: {fmt_len(math.dist(a, b), tile)}", PANEL_TEXT, SMALL, 10)
    elif sel[0] == "goals":
        w.line("A: make active   R: rename", PANEL_DIM, SMALL, 10)
    elif sel == ("start",):
        h = arena.start.heading_deg
        w.line(f"heading {'random' if h is None else f'{h:g} deg'}", PANEL_TEXT, SMALL, 10)


def _panel_goals(w: _Writer, app: EditorApp) -> list[tuple[pygame.Rect, str]]:
    arena = app.model.arena
    w.gap()
    w.line(f"Goals ({len(arena.goals)}; click one to make it active):", PANEL_DIM)
    rows = []
    x0, y0 = w.x, w.y
    n = len(arena.goals)
    cols = 1 if n <= 6 else 2 if n <= 20 else 3
    per_col = max(1, math.ceil(n / cols))
    for k, g in enumerate(arena.goals):
        col, row = divmod(k, per_col)
        active = g.name == arena.active_goal
        label = f"{'>' if active else ' '} {g.name}"
        pos = (x0 + col * (300 // cols), y0 + row * LINE)
        width = text(
            w.surface, _fit(label, 300 // cols - 8), pos, PANEL_HOT if active else PANEL_TEXT
        )
        rows.append((pygame.Rect(pos[0], pos[1], max(width, 60), LINE), g.name))
    w.y = y0 + (per_col if n else 0) * LINE
    n = len(arena.end_of_world)
    h = arena.start.heading_deg
    w.line(f"end-of-world markers: {n}   obstacles: {len(arena.obstacles)}", PANEL_TEXT)
    sx, sy = arena.start.at
    w.line(f"start ({sx:g}, {sy:g}) heading {'random' if h is None else f'{h:g}'}", PANEL_TEXT)
    return rows


def _panel_drive(w: _Writer, app: EditorApp) -> None:
    w.line("TEST DRIVE (Show Sensors)", PANEL_HOT, 22)
    for s in app.drive.hud_lines():
        w.line(s, PANEL_TEXT, SMALL)
    w.gap()
    state = app.drive.robot_state()
    w.line(f"robot: {state.replace('_', ' ')}", PANEL_HOT)
    w.gap()
    for s in DRIVE_KEYS:
        w.line(s, PANEL_DIM)
    w.gap()
    w.line("black: sonar rays   blue: camera sees goal", PANEL_DIM, SMALL)
    w.line("yellow: camera sees end of world", PANEL_DIM, SMALL)
    w.line("robot red / pink bump / purple off the", PANEL_DIM, SMALL)
    w.line("end of the world / black at the goal", PANEL_DIM, SMALL)


def draw_status(app: EditorApp) -> None:
    surface = app.screen
    rect = pygame.Rect(app.status_rect)
    surface.fill(STATUS_BG, rect)
    pygame.draw.line(surface, (180, 180, 180), rect.topleft, rect.topright)
    x, y = rect.x + 10, rect.y + 5
    text(surface, app.ruler_text(), (x, y), STATUS_TEXT)
    problem = app.model.problem()
    if problem is None:
        text(surface, f"valid: {app.model.describe()}", (x, y + LINE), OK)
    else:
        for k, part in enumerate(_wrap(problem.message, rect.width - 20)[:2]):
            text(surface, part, (x, y + LINE * (1 + k)), ERROR)
    y3 = y + 3 * LINE
    if app.prompt is not None:
        keys = PROMPT_KEYS[app.prompt.kind]
        pygame.draw.rect(
            surface, (255, 240, 170), pygame.Rect(rect.x, y3 - 3, rect.width, LINE + 4)
        )
        text(surface, _fit(keys, rect.width - 20), (x, y3), STATUS_TEXT)
    elif app.message:
        colour = ERROR if app.message_is_error else STATUS_TEXT
        text(surface, _fit(app.message, rect.width - 20), (x, y3), colour)


PROMPT_KEYS = {
    "text": "a question is open: type the answer (it replaces the selection), Enter OK, Esc cancel",
    "confirm": "a question is open: Y yes, N or Esc no",
    "file": "choose a file, or type its path (it replaces the selection); Enter OK, Esc cancel",
}


def _wrap(s: str, width: int, size: int = FONT) -> list[str]:
    """``s`` broken into lines of at most ``width`` pixels (at spaces); a long ``s`` is
    cut first (:data:`MAX_TEXT` characters: more never shows)."""
    f = draw.font(size)
    rows, cur = [], ""
    for word in s[:MAX_TEXT].split(" "):
        trial = f"{cur} {word}" if cur else word
        if cur and f.size(trial)[0] > width:
            rows.append(cur)
            cur = word
        else:
            cur = trial
    return [*rows, cur]


def _fit(s: str, width: int, size: int = FONT) -> str:
    """``s`` shortened with ``...`` to fit ``width`` pixels."""
    f = draw.font(size)
    if len(s) <= width // 2 and f.size(s)[0] <= width:  # no character is under 2 pixels
        return s
    s = s[: max(1, width // 2)]
    lo, hi = 0, len(s)  # the longest prefix that fits with "..."
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if f.size(s[:mid] + "...")[0] <= width:
            lo = mid
        else:
            hi = mid - 1
    return s[:lo] + "..."


def world_label(p: Point, tile: float) -> str:
    """``(120, 88) in = (5, 3.67) tiles``."""
    return f"({p[0]:.4g}, {p[1]:.4g}) in = ({_num(p[0] / tile)}, {_num(p[1] / tile)}) tiles"
