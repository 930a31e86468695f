"""Drawing, headless: the robot's colour in its four states and the sensor-line colours,
checked on pixels at positions computed with the renderer's Camera (paper §5.4.5)."""

from __future__ import annotations

import math
import os

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

import numpy as np
import pytest

pygame = pytest.importorskip("pygame")

from koolio_pymunk.config import Config  # noqa: E402
from koolio_pymunk.env import KoolioEnv  # noqa: E402
from koolio_pymunk.viewer import draw  # noqa: E402
from koolio_pymunk.viewer.camera import Camera  # noqa: E402
from koolio_pymunk.viewer.render import EnvRenderer  # noqa: E402
from koolio_pymunk.world import Action  # noqa: E402

# The room arena: 240 x 192 with a 48 in stub (the end-of-world zone, marker at
# (264, 96)) in the east wall; goal 201's plate at (102, 191) on the north wall.
GOAL = (102.0, 191.0)
MARKER = (264.0, 96.0)


def room_env() -> KoolioEnv:
    cfg = Config()
    cfg.sensors.noise.model = "none"
    env = KoolioEnv("room", config=cfg, render_mode="rgb_array")
    env.reset(seed=0)
    return env


def pose_then_stop(env: KoolioEnv, at: tuple[float, float], heading: float) -> str:
    """Put the robot at ``at`` and perform Stop: the env judges the new state."""
    env.world.place(0, at, heading)
    env.transition(Action.STOP)
    assert env.judgement is not None
    return env.judgement.event


def pixel(img: np.ndarray, screen: tuple[int, int]) -> tuple[int, int, int]:
    x, y = screen
    return tuple(int(v) for v in img[y, x])


def body_pixel(env: KoolioEnv, cam: Camera) -> tuple[int, int]:
    """A point inside the robot's disc, half a radius off the (white) heading line."""
    x, y, h = env.world.pose(0)
    r = env.config.robot.radius / 2.0
    return cam.to_screen((x - r * math.sin(h), y + r * math.cos(h)))


@pytest.mark.parametrize(
    ("at", "heading", "event", "colour"),
    [
        ((120.0, 96.0), 0.0, "stop", draw.ROBOT_NORMAL),
        ((50.0, 15.0), 0.0, "bump", draw.ROBOT_BUMP),
        (MARKER, 0.0, "end_of_world", draw.ROBOT_END_OF_WORLD),
        ((GOAL[0], 160.0), math.pi / 2, "goal", draw.ROBOT_GOAL),
    ],
    ids=["red", "pink-bump", "purple-end-of-world", "black-goal"],
)
def test_robot_colour_in_each_state(at, heading, event, colour) -> None:
    env = room_env()
    assert pose_then_stop(env, at, heading) == event
    renderer = EnvRenderer(env)
    img = renderer.render("rgb_array")
    assert img.shape == (renderer.size[1], renderer.size[0], 3) and img.dtype == np.uint8
    cam = renderer.cameras[0]
    assert pixel(img, body_pixel(env, cam)) == colour
    # The heading line is white, from the centre towards the heading.
    x, y, h = env.world.pose(0)
    r = env.config.robot.radius
    assert pixel(img, cam.to_screen((x + 0.6 * r * math.cos(h), y + 0.6 * r * math.sin(h)))) == (
        draw.HEADING
    )


def test_camera_sees_goal_blue_line() -> None:
    env = room_env()
    pose_then_stop(env, (GOAL[0], 120.0), math.pi / 2)
    assert env.readings.goal[0] < env.sensors.far  # the front camera sees the plate
    renderer = EnvRenderer(env)
    img = renderer.render("rgb_array")
    cam = renderer.cameras[0]
    # Between the robot's edge (y = 130) and the plate (y = 191), on the sight line.
    for wy in (140.0, 160.0, 180.0):
        assert pixel(img, cam.to_screen((GOAL[0], wy))) == draw.CAMERA_GOAL_LINE


def test_camera_sees_marker_yellow_line_and_sonar_black() -> None:
    env = room_env()
    pose_then_stop(env, (200.0, 96.0), 0.0)
    assert env.readings.eow_target[0] == 0  # the front camera sees the stub's marker
    renderer = EnvRenderer(env)
    img = renderer.render("rgb_array")
    cam = renderer.cameras[0]
    for wx in (220.0, 240.0, 255.0):
        assert pixel(img, cam.to_screen((wx, 96.0))) == draw.CAMERA_EOW_LINE
    # The rear sonar's middle sub-arc ray runs straight back to the west wall: black.
    for wx in (60.0, 120.0, 170.0):
        assert pixel(img, cam.to_screen((wx, 96.0))) == draw.SONAR_LINE


def test_no_sensor_lines_and_plain_robot_when_sensors_hidden() -> None:
    env = room_env()
    pose_then_stop(env, (200.0, 96.0), 0.0)
    surface = pygame.Surface((720, 600))
    cam = Camera((0, 0, 720, 600))
    cam.fit(env.world_arena.bounds())
    from koolio_pymunk.viewer.render import draw_env

    draw_env(surface, cam, env, show_sensors=False)
    assert tuple(surface.get_at(cam.to_screen((252.0, 96.0))))[:3] == draw.ZONE
    assert tuple(surface.get_at(cam.to_screen((120.0, 96.0))))[:3] == draw.FLOOR
    assert tuple(surface.get_at(body_pixel(env, cam)))[:3] == draw.ROBOT_NORMAL


def test_draw_arena_colours_at_world_points() -> None:
    env = room_env()
    arena = env.world_arena
    pygame.font.init()
    surface = pygame.Surface((600, 500))
    cam = Camera((0, 0, 600, 500))
    cam.fit(arena.bounds())
    draw.draw_arena(surface, arena, cam, labels=True)
    at = lambda p: tuple(surface.get_at(cam.to_screen(p)))[:3]  # noqa: E731
    assert at((120.0, 96.0)) == draw.FLOOR
    assert at((-8.0, 96.0)) == draw.BACKGROUND
    assert at(MARKER) == draw.MARKER
    assert at(GOAL) == draw.GOAL
    assert at((120.0, 0.0)) == draw.WALL
    assert at((276.0, 110.0)) == draw.ZONE


def test_rgb_array_of_the_hallway_has_overview_and_follow_views() -> None:
    env = KoolioEnv("hallway", render_mode="rgb_array")
    env.reset(seed=3)
    img = env.render()
    assert img.shape == (457, 1200, 3)
    # The robot appears in both views in the paper's colours (red at the start).
    renderer = env._renderer
    for cam in renderer.cameras:
        assert pixel(img, body_pixel(env, cam)) == draw.ROBOT_NORMAL
    env.close()


def test_human_render_mode_draws_in_a_window() -> None:
    env = KoolioEnv("room", render_mode="human")
    env.reset(seed=0)
    assert env.render() is None
    shown = pygame.display.get_surface()
    assert shown is not None and shown.get_size() == env._renderer.size
    env.close()
    assert env._renderer is None
