"""``KoolioEnv.render()``: the arena, robot and sensors as a picture or in a window.

:class:`EnvRenderer` draws the environment's current state with the functions of
:mod:`koolio_pymunk.task.drawing`: for ``rgb_array`` it returns an ``H x W x 3`` uint8
array; for ``human`` it shows the same picture in a pygame window. A long arena (the
1632 x 88 hallway) gets two views: the whole arena on top and a zoomed view that follows
the robot below; a compact arena gets one view. A status line at the bottom gives the
episode's reward, steps, bumps and last event.

:func:`draw_env` (arena + sensor lines + robot, in one camera's viewport) is shared with
the interactive viewer (``viewer/app.py``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import pygame

from ..world.physics import ACTION_NAMES
from .display import init_display
from .drawing import (
    BACKGROUND,
    ROBOT_NORMAL,
    ROBOT_STATES,
    draw_arena,
    draw_numbered_robot,
    draw_robot,
    draw_sensors,
    robot_state,
    text,
)
from .viewport import Camera

if TYPE_CHECKING:  # the env imports this module when it first draws
    from .env import KoolioEnv

#: Arenas whose height / width is below this get an overview plus a follow view.
LONG_ARENA = 0.35
STATUS_H = 26


def robot_colour(env: KoolioEnv) -> tuple[int, int, int]:
    """The paper's robot colour for ``env``'s current state."""
    event = env.judgement.event if env.judgement is not None else None
    return ROBOT_STATES[robot_state(event, env.sensors.bump(env.readings))]


def draw_env(
    surface: pygame.Surface,
    camera: Camera,
    env: KoolioEnv,
    *,
    show_sensors: bool = True,
    labels: bool = True,
    lines: bool = True,
    layer: ArenaLayer | None = None,
    label_size: int = 16,
) -> None:
    """Arena, then (with ``show_sensors``) the sensor lines, then the robot, in the
    camera's viewport. With ``show_sensors`` the robot has the paper's state colour (and
    ``lines=False`` leaves the sensor lines out, for a small overview); without it the
    robot is the paper's plain red. With a ``layer`` the arena comes from its cache."""
    kw = {"labels": labels, "robot_radius": env.config.robot.radius, "label_size": label_size}
    (layer.draw if layer is not None else draw_arena)(surface, env.world_arena, camera, **kw)
    clip = surface.get_clip()
    surface.set_clip(pygame.Rect(camera.viewport))
    radius = env.config.robot.radius
    world, me = env.world, env.robot
    if env.share is not None:  # the other robots of a shared arena, in their colours
        for k in range(world.n_robots):
            if k != me and world.present[k]:
                draw_numbered_robot(surface, camera, world.pose(k), radius, k)
    pose = world.pose(me)
    if show_sensors:
        if lines and (env.share is None or world.present[me]):
            draw_sensors(surface, camera, pose, env.sensors, env.readings)
        colour = robot_colour(env)
    else:
        colour = ROBOT_NORMAL
    if env.share is None:
        draw_robot(surface, camera, pose, radius, colour)
    elif world.present[me]:
        draw_numbered_robot(surface, camera, pose, radius, me, colour)
    surface.set_clip(clip)


class ArenaLayer:
    """The arena drawn once per zoom level, then blitted every frame.

    Walls, zones, doors and their labels do not move, so the window draws them into an
    off-screen surface covering the whole arena at the camera's zoom and copies the
    visible part; the surface is redrawn when the zoom or the arena (its active goal)
    changes. The cache surface has its own :class:`Camera` with the same zoom, so the
    picture matches a direct :func:`draw_arena` to within a pixel of rounding. Beyond
    :attr:`MAX_PIXELS` (deep zoom on a long arena) it draws directly instead.
    """

    MAX_PIXELS = 6_000_000

    def __init__(self) -> None:
        self._key: tuple | None = None
        self._arena: object = None
        self._surface: pygame.Surface | None = None
        self._camera: Camera | None = None

    def draw(
        self,
        surface: pygame.Surface,
        arena,
        camera: Camera,
        *,
        labels: bool = True,
        robot_radius: float = 10.0,
        label_size: int = 16,
    ) -> None:
        """Copy the part of the arena ``camera`` sees onto ``surface`` (rebuilt first when
        the zoom, the labels or the arena changed)."""
        key = (camera.zoom, labels, robot_radius, label_size)
        if key != self._key or arena is not self._arena:
            self._build(arena, camera.zoom, key)
            self._key, self._arena = key, arena
        view = pygame.Rect(camera.viewport)
        if self._surface is None or self._camera is None:
            draw_arena(
                surface,
                arena,
                camera,
                labels=labels,
                robot_radius=robot_radius,
                label_size=label_size,
            )
            return
        clip = surface.get_clip()
        surface.set_clip(view)
        surface.fill(BACKGROUND, view)
        cx, cy = camera.to_screen(self._camera.center)
        w, h = self._surface.get_size()
        surface.blit(self._surface, (cx - w // 2, cy - h // 2))
        surface.set_clip(clip)

    def _build(self, arena, zoom: float, key: tuple) -> None:
        _, labels, robot_radius, label_size = key
        xmin, ymin, xmax, ymax = arena.bounds()
        margin = max(4.0 * robot_radius, 48.0 / zoom)  # zone discs, outside labels
        w = 2 * (round((xmax - xmin + 2 * margin) * zoom) // 2 + 1)
        h = 2 * (round((ymax - ymin + 2 * margin) * zoom) // 2 + 1)
        if w * h > self.MAX_PIXELS:
            self._surface = self._camera = None
            return
        self._camera = Camera((0, 0, w, h), ((xmin + xmax) / 2.0, (ymin + ymax) / 2.0), zoom)
        self._camera.min_zoom = self._camera.max_zoom = zoom
        self._surface = pygame.Surface((w, h))
        draw_arena(
            self._surface,
            arena,
            self._camera,
            labels=labels,
            robot_radius=robot_radius,
            label_size=label_size,
        )


def arena_bounds(env: KoolioEnv) -> tuple[float, float, float, float]:
    """``(xmin, ymin, xmax, ymax)`` of the arena the env runs in, inches."""
    return env.world_arena.bounds()


def is_long(bounds: tuple[float, float, float, float]) -> bool:
    """A hallway-like arena, much longer than wide (drawn with an overview strip)."""
    xmin, ymin, xmax, ymax = bounds
    return (ymax - ymin) / max(1e-9, xmax - xmin) < LONG_ARENA


def status_line(env: KoolioEnv) -> str:
    """The frame's one status line: goal, reward, steps, bumps, the last action and event."""
    j = env.judgement
    last = (
        f"{ACTION_NAMES[env.last_action]} -> {j.event}"
        if j is not None and env.last_action is not None
        else "start"
    )
    return (
        f"goal {env.goal_name}   reward {env.episode_reward:g}   steps {env.steps}   "
        f"bumps {env.bumps}   last {last}" + ("   RESCUED" if env.has_been_rescued else "")
    )


class EnvRenderer:
    """Draws a :class:`KoolioEnv` for ``render_mode`` ``rgb_array`` or ``human``."""

    def __init__(self, env: KoolioEnv, width: int = 1200) -> None:
        pygame.font.init()
        self.env = env
        bounds = arena_bounds(env)
        xmin, ymin, xmax, ymax = bounds
        aspect = (ymax - ymin) / max(1e-9, xmax - xmin)
        self.cameras: list[Camera] = []
        if is_long(bounds):
            top_h = max(60, round(width * aspect * 1.1) + 10)
            follow_h = 280
            overview = Camera((0, 0, width, top_h))
            overview.fit(bounds, margin=0.02)
            follow = Camera((0, top_h, width, follow_h))
            follow.fit(bounds, margin=0.05)
            follow.zoom = follow_h / ((ymax - ymin) * 1.15)
            self.follow: Camera | None = follow
            self.cameras = [overview, follow]
            height = top_h + follow_h + STATUS_H
        else:
            width = min(width, 720)
            view_h = round(width * aspect)
            main = Camera((0, 0, width, view_h))
            main.fit(bounds, margin=0.04)
            self.follow = None
            self.cameras = [main]
            height = view_h + STATUS_H
        self.size = (width, height)
        self.surface = pygame.Surface(self.size)
        self._window: pygame.Surface | None = None
        self._clock: pygame.time.Clock | None = None

    def draw(self) -> pygame.Surface:
        """Draw the current state onto :attr:`surface` and return it."""
        env = self.env
        if self.follow is not None:
            x, _, _ = env.world.pose(0)
            _, ymin, _, ymax = arena_bounds(env)
            self.follow.follow((x, (ymin + ymax) / 2.0))
        for i, cam in enumerate(self.cameras):
            overview = self.follow is not None and i == 0
            draw_env(self.surface, cam, env, lines=not overview)
            pygame.draw.rect(self.surface, (90, 90, 100), pygame.Rect(cam.viewport), width=1)
        w, h = self.size
        strip = pygame.Rect(0, h - STATUS_H, w, STATUS_H)
        self.surface.fill((243, 244, 247), strip)
        self.surface.blit(text(status_line(env), 20, (25, 25, 25)), (8, strip.y + 5))
        return self.surface

    def render(self, mode: str):
        """``rgb_array``: an H x W x 3 uint8 array; ``human``: draw in a window."""
        surf = self.draw()
        if mode == "rgb_array":
            return pygame.surfarray.array3d(surf).transpose(1, 0, 2).copy()
        if mode == "human":
            if self._window is None:
                init_display()  # without libwayland's line on a machine with no display
                self._window = pygame.display.set_mode(self.size)
                pygame.display.set_caption("Koolio (pymunk)")
                self._clock = pygame.time.Clock()
            self._window.blit(surf, (0, 0))
            pygame.event.pump()
            pygame.display.flip()
            assert self._clock is not None
            self._clock.tick(self.env.metadata.get("render_fps", 30))
            return None
        raise ValueError(f"render mode {mode!r} is not supported (human, rgb_array)")

    def close(self) -> None:
        """Close the window, if one was opened (``human`` mode)."""
        if self._window is not None:
            pygame.display.quit()
            self._window = None
