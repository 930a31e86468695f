"""Pure drawing functions: arena, robot and sensors onto a pygame surface (paper §5.4.5).

Every function takes the target ``surface`` and a :class:`~koolio_pymunk.task.viewport.Camera`
(the only world-to-screen conversion) and draws; none owns a window, an event loop or any
state beyond a font cache. The app (``viewer/app.py``), ``KoolioEnv.render`` (via
``viewer/render.py``) and the arena editor (``tools/arena_editor.py``) all draw with them.

Colours follow the paper: robot red, pink when a sonar reads Bump, purple past the end of
the world, black at the goal; black sonar lines, blue lines from cameras that see the
goal, yellow lines from cameras that see an end-of-world marker; goal and end-of-world
markers are coloured dots. What the realism models hid is dashed: a sonar ray that meets a
wall but hears no echo (orange), a camera that has its target in view but misses it (its
own colour); a camera that misreads another door's plate as the goal draws a magenta
line to that plate and rings it.

Drawing on a plain ``pygame.Surface`` needs no display; :func:`font` initialises
``pygame.font`` on first use.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pygame

from ..sensing.suite import Readings, SensorSuite
from ..world.arena import Arena, Point
from .viewport import Camera

Color = tuple[int, int, int]

# -- palette -----------------------------------------------------------------------------
BACKGROUND: Color = (208, 212, 218)
"""Outside the walls."""
FLOOR: Color = (250, 250, 246)
WALL: Color = (40, 44, 52)
OBSTACLE: Color = (120, 124, 134)
DOOR: Color = (176, 120, 64)
PLATE: Color = (255, 236, 160)
PLATE_TEXT: Color = (60, 40, 10)
GOAL: Color = (0, 170, 60)
"""The active goal's dot."""
OTHER_GOAL: Color = (150, 200, 160)
"""Goals that are not active this episode."""
MARKER: Color = (230, 120, 0)
"""End-of-world marker dots."""
ZONE: Color = (236, 214, 244)
"""End-of-world zone fill."""
ZONE_EDGE: Color = (170, 110, 200)
START: Color = (120, 160, 220)

ROBOT_NORMAL: Color = (220, 0, 0)
"""Paper: red."""
ROBOT_BUMP: Color = (255, 105, 180)
"""Paper: pink when a sonar reads Bump."""
ROBOT_END_OF_WORLD: Color = (128, 0, 160)
"""Paper: purple past the end of the world."""
ROBOT_GOAL: Color = (0, 0, 0)
"""Paper: black at the goal."""
HEADING: Color = (255, 255, 255)
SONAR_LINE: Color = (0, 0, 0)
SONAR_MISS: Color = (205, 205, 205)
"""A sonar sub-arc ray that hits nothing within range (drawn to its full length)."""
SONAR_NO_ECHO: Color = (240, 110, 0)
"""A sonar sub-arc ray that meets a wall but gets no echo (realism: a grazing angle, or
beyond the ranger's range): dashed, to the wall."""
CAMERA_GOAL_LINE: Color = (0, 70, 255)
"""Paper: blue from a camera that sees the goal."""
CAMERA_EOW_LINE: Color = (235, 200, 0)
"""Paper: yellow from a camera that sees an end-of-world marker."""
CAMERA_MISREAD: Color = (210, 0, 210)
"""A camera that takes another door's plate for the goal (realism misread): a line to
that plate, and a ring round it."""
DASH = (7, 5)
"""Dashed lines: pixels drawn, pixels skipped (from the robot outwards)."""

ROBOT_STATES: dict[str, Color] = {
    "normal": ROBOT_NORMAL,
    "bump": ROBOT_BUMP,
    "end_of_world": ROBOT_END_OF_WORLD,
    "goal": ROBOT_GOAL,
}
"""Robot colour by state (see :func:`robot_state`)."""

_FONTS: dict[int, pygame.font.Font] = {}


def font(size: int) -> pygame.font.Font:
    """The bundled pygame font at ``size`` pixels (cached; initialises pygame.font)."""
    f = _FONTS.get(size)
    if f is None:
        if not pygame.font.get_init():
            pygame.font.init()
        f = _FONTS[size] = pygame.font.Font(None, size)
    return f


def _poly(camera: Camera, points: Sequence[Point]) -> list[tuple[int, int]]:
    return [camera.to_screen(p) for p in points]


# -- arena -------------------------------------------------------------------------------
def draw_arena(
    surface: pygame.Surface,
    arena: Arena,
    camera: Camera,
    *,
    labels: bool = True,
    robot_radius: float = 10.0,
    show_start: bool = True,
    label_size: int = 16,
) -> None:
    """Draw ``arena`` as given (pass ``arena.to_world()`` for the simulator's frame).

    Draws, back to front: the floor inside the walls, end-of-world zones (a polygon, or a
    disc of one robot diameter around a marker without one), obstacles, the walls, doors
    with their number plates (room numbers, when ``labels``), the start point, goals as
    dots (the active one larger and darker) and end-of-world markers as orange dots.
    ``robot_radius`` sizes the default zone discs; ``label_size`` is the room numbers'
    font size in pixels (the window scales it with its size). Nothing outside the viewport is
    touched except through pygame's clipping of ``surface``.
    """
    clip = surface.get_clip()
    surface.set_clip(pygame.Rect(camera.viewport))
    try:
        surface.fill(BACKGROUND, pygame.Rect(camera.viewport))
        walls = _poly(camera, arena.walls)
        if len(walls) >= 3:
            pygame.draw.polygon(surface, FLOOR, walls)
        _draw_zones(surface, arena, camera, robot_radius)
        for poly in arena.obstacles:
            pts = _poly(camera, poly)
            if len(pts) >= 3:
                pygame.draw.polygon(surface, OBSTACLE, pts)
                pygame.draw.polygon(surface, WALL, pts, width=2)
        if len(walls) >= 2:
            pygame.draw.lines(surface, WALL, True, walls, width=3)
        _draw_doors(surface, arena, camera, label_size if labels else 0)
        if show_start:
            s = camera.to_screen(arena.start.at)
            pygame.draw.circle(surface, START, s, max(3, camera.scale(3)), width=2)
        for g in arena.goals:
            active = g.name == arena.active_goal
            colour = GOAL if active else OTHER_GOAL
            pygame.draw.circle(surface, colour, camera.to_screen(g.at), 6 if active else 3)
        for m in arena.end_of_world:
            pygame.draw.circle(surface, MARKER, camera.to_screen(m.at), 6)
            pygame.draw.circle(surface, WALL, camera.to_screen(m.at), 6, width=1)
    finally:
        surface.set_clip(clip)


def _draw_zones(surface: pygame.Surface, arena: Arena, camera: Camera, radius: float) -> None:
    for m in arena.end_of_world:
        if m.zone is not None and len(m.zone) >= 3:
            pts = _poly(camera, m.zone)
            pygame.draw.polygon(surface, ZONE, pts)
            pygame.draw.polygon(surface, ZONE_EDGE, pts, width=1)
        else:
            c = camera.to_screen(m.at)
            r = camera.scale(2.0 * radius)
            pygame.draw.circle(surface, ZONE, c, r)
            pygame.draw.circle(surface, ZONE_EDGE, c, r, width=1)


def _outward(arena: Arena, a: Point, b: Point) -> tuple[float, float]:
    """Unit normal of door span ``a``-``b`` pointing away from the walls' centre."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    n = math.hypot(dx, dy) or 1.0
    nx, ny = -dy / n, dx / n
    xmin, ymin, xmax, ymax = arena.bounds()
    cx, cy = (xmin + xmax) / 2.0, (ymin + ymax) / 2.0
    mx, my = (a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0
    if nx * (mx - cx) + ny * (my - cy) < 0:
        nx, ny = -nx, -ny
    return nx, ny


def _draw_doors(surface: pygame.Surface, arena: Arena, camera: Camera, label_size: int) -> None:
    """Doors, their plates and (``label_size`` > 0) the room numbers beside the plates."""
    for d in arena.doors:
        pygame.draw.line(
            surface,
            DOOR,
            camera.to_screen(d.a),
            camera.to_screen(d.b),
            width=max(4, camera.scale(2)),
        )
        plate = camera.to_screen(d.plate)
        pygame.draw.rect(surface, PLATE_TEXT, pygame.Rect(plate[0] - 3, plate[1] - 3, 6, 6))
        if label_size <= 0:
            continue
        text = font(label_size).render(d.name, True, PLATE_TEXT)
        nx, ny = _outward(arena, d.a, d.b)
        # Centre of the label: just outside the wall, beside the plate (screen y is down).
        off = 4 + max(text.get_width(), text.get_height()) / 2.0
        cx = plate[0] + nx * off
        cy = plate[1] - ny * off
        box = text.get_rect(center=(round(cx), round(cy))).inflate(6, 2)
        pygame.draw.rect(surface, PLATE, box)
        pygame.draw.rect(surface, PLATE_TEXT, box, width=1)
        surface.blit(text, text.get_rect(center=box.center))


# -- text ----------------------------------------------------------------------------------
_TEXT: dict[tuple[str, int, Color], pygame.Surface] = {}


def text(s: str, size: int = 18, colour: Color = (20, 20, 20)) -> pygame.Surface:
    """A rendered label, cached (labels repeat from frame to frame)."""
    key = (s, size, colour)
    surf = _TEXT.get(key)
    if surf is None:
        if len(_TEXT) > 4000:
            _TEXT.clear()
        surf = _TEXT[key] = font(size).render(s, True, colour)
    return surf


# -- robot and sensors -------------------------------------------------------------------
def robot_state(event: str | None, bump: bool) -> str:
    """The paper's colour state: ``goal`` > ``end_of_world`` > ``bump`` > ``normal``.

    ``event`` is the last step's judgement event (``KoolioEnv.judgement.event``), ``bump``
    whether any sonar reads Bump now.

    >>> robot_state("goal", True), robot_state("bump", True), robot_state(None, False)
    ('goal', 'bump', 'normal')
    """
    if event in ("goal", "end_of_world"):
        return event
    return "bump" if bump else "normal"


def draw_robot(
    surface: pygame.Surface,
    camera: Camera,
    pose: tuple[float, float, float],
    radius: float,
    colour: Color = ROBOT_NORMAL,
) -> None:
    """The robot: a filled circle of ``radius`` inches and a white heading line."""
    x, y, h = pose
    c = camera.to_screen((x, y))
    r = camera.scale(radius)
    pygame.draw.circle(surface, colour, c, r)
    pygame.draw.circle(surface, WALL, c, r, width=1)
    tip = camera.to_screen((x + radius * math.cos(h), y + radius * math.sin(h)))
    pygame.draw.line(surface, HEADING, c, tip, width=max(2, camera.scale(radius / 5.0)))


#: The colours of robots sharing an arena, by index (robot ``k`` takes ``k % 8``): the
#: other robots are drawn in these with their number; the selected robot keeps the
#: paper's state colours.
ROBOT_PALETTE: tuple[Color, ...] = (
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (148, 103, 189),
    (140, 86, 75),
    (23, 190, 207),
    (188, 189, 34),
    (127, 127, 127),
)


def draw_numbered_robot(
    surface: pygame.Surface,
    camera: Camera,
    pose: tuple[float, float, float],
    radius: float,
    number: int,
    colour: Color | None = None,
) -> None:
    """Robot ``number`` of a shared arena: :func:`draw_robot` in its palette colour (or
    ``colour``), its number on it."""
    draw_robot(surface, camera, pose, radius, colour or ROBOT_PALETTE[number % len(ROBOT_PALETTE)])
    size = max(10, camera.scale(radius * 1.2))
    label = text(str(number), size, (255, 255, 255))
    c = camera.to_screen(pose[:2])
    surface.blit(label, label.get_rect(center=c))


def dashed_line(
    surface: pygame.Surface,
    colour: Color,
    a: tuple[int, int],
    b: tuple[int, int],
    width: int = 1,
    dash: tuple[int, int] = DASH,
) -> None:
    """A dashed line from ``a`` to ``b``: ``dash[0]`` pixels drawn, ``dash[1]`` skipped,
    starting with a dash at ``a``."""
    (ax, ay), (bx, by) = a, b
    length = math.hypot(bx - ax, by - ay)
    if length < 1.0:
        return
    ux, uy = (bx - ax) / length, (by - ay) / length
    on, period = dash[0], dash[0] + dash[1]
    t = 0.0
    while t < length:
        e = min(t + on - 1, length)
        pygame.draw.line(
            surface,
            colour,
            (round(ax + ux * t), round(ay + uy * t)),
            (round(ax + ux * e), round(ay + uy * e)),
            width,
        )
        t += period


def draw_sensors(
    surface: pygame.Surface,
    camera: Camera,
    pose: tuple[float, float, float],
    suite: SensorSuite,
    readings: Readings,
) -> None:
    """Sensor lines (paper §5.4.5): the sonar sub-arc rays, then the cameras' lines (see
    :func:`draw_sonar_rays`, :func:`draw_camera_lines`). Draw the robot afterwards, on top."""
    draw_sonar_rays(surface, camera, pose, suite, readings)
    draw_camera_lines(surface, camera, pose, suite, readings)


def draw_sonar_rays(
    surface: pygame.Surface,
    camera: Camera,
    pose: tuple[float, float, float],
    suite: SensorSuite,
    readings: Readings,
) -> None:
    """Every sonar sub-arc ray: black to the wall it hit when it got an echo, dashed
    orange to the wall when it got none (realism: a grazing angle, or out of the
    ranger's range), light grey to full length when it hit nothing."""
    x, y, h = pose
    c = camera.to_screen((x, y))
    dirs = suite.ray_dirs(h)
    dist = readings.rays
    ex, ey = x + dist * dirs[0], y + dist * dirs[1]
    hit = dist < suite.ray_length - 1e-9
    echo = readings.echo if readings.echo.shape == dist.shape else hit
    for idx in np.ndindex(dist.shape):
        end = camera.to_screen((float(ex[idx]), float(ey[idx])))
        if echo[idx]:
            pygame.draw.line(surface, SONAR_LINE, c, end, width=1)
        elif hit[idx]:
            dashed_line(surface, SONAR_NO_ECHO, c, end)
        else:
            pygame.draw.line(surface, SONAR_MISS, c, end, width=1)


def draw_camera_lines(
    surface: pygame.Surface,
    camera: Camera,
    pose: tuple[float, float, float],
    suite: SensorSuite,
    readings: Readings,
) -> None:
    """Per camera: a blue line to the goal it sees, a yellow one to the end-of-world
    marker it sees; dashed in the same colour to a target in view that it missed
    (realism detection); magenta to another door's plate it takes for the goal, ringed
    (realism misread)."""
    x, y, _ = pose
    c = camera.to_screen((x, y))
    width = max(2, camera.scale(1.0))
    n = suite.n_camera
    missed = readings.missed if readings.missed.shape == (n, 2) else np.zeros((n, 2), bool)
    misread = readings.misread if readings.misread.shape == (n,) else np.zeros(n, bool)
    for cam in range(n):
        if misread[cam]:
            _misread_line(surface, camera, pose, suite, cam, width)
        elif readings.goal[cam] < suite.far:
            pygame.draw.line(surface, CAMERA_GOAL_LINE, c, camera.to_screen(suite.goal), width)
        elif missed[cam, 0]:
            _missed_goal_line(surface, camera, pose, suite, cam, width)
        k = readings.eow_target[cam]
        if k >= 0:
            pygame.draw.line(surface, CAMERA_EOW_LINE, c, camera.to_screen(suite.markers[k]), width)
        elif missed[cam, 1]:
            k = suite.camera_target(pose, cam, suite.markers)
            if k >= 0:
                end = camera.to_screen(suite.markers[k])
                dashed_line(surface, CAMERA_EOW_LINE, c, end, width)


def _misread_line(
    surface: pygame.Surface,
    camera: Camera,
    pose: tuple[float, float, float],
    suite: SensorSuite,
    cam: int,
    width: int,
) -> None:
    """The plate camera ``cam`` reads as the goal: a magenta line to it and a ring."""
    k = suite.camera_target(pose, cam, suite.plates)
    if k < 0:
        return
    end = camera.to_screen(suite.plates[k])
    pygame.draw.line(surface, CAMERA_MISREAD, camera.to_screen(pose[:2]), end, width)
    pygame.draw.circle(surface, CAMERA_MISREAD, end, max(7, camera.scale(5.0)), width=2)


def _missed_goal_line(
    surface: pygame.Surface,
    camera: Camera,
    pose: tuple[float, float, float],
    suite: SensorSuite,
    cam: int,
    width: int,
) -> None:
    """Camera ``cam`` had a plate in view and did not detect it: dashed blue to the goal
    (dashed magenta to another door's plate when that was the one it missed)."""
    start = camera.to_screen(pose[:2])
    if suite.camera_target(pose, cam, [suite.goal]) == 0:
        dashed_line(surface, CAMERA_GOAL_LINE, start, camera.to_screen(suite.goal), width)
        return
    k = suite.camera_target(pose, cam, suite.plates)
    if k >= 0:
        dashed_line(surface, CAMERA_MISREAD, start, camera.to_screen(suite.plates[k]), width)
