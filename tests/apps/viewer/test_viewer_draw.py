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

from koolio_pymunk.apps.viewer import hud  # noqa: E402
from koolio_pymunk.store.config import Config  # noqa: E402
from koolio_pymunk.task import drawing as draw  # noqa: E402
from koolio_pymunk.task.env import KoolioEnv  # noqa: E402
from koolio_pymunk.task.render import EnvRenderer  # noqa: E402
from koolio_pymunk.task.viewport import Camera  # noqa: E402
from koolio_pymunk.world.physics import Action  # noqa: E402

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
    from koolio_pymunk.task.render import draw_env

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


# -- what the realism models hid -----------------------------------------------------------------
def real_env(arena: str = "room", **realism) -> KoolioEnv:
    """An env without noise and with the given realism settings (``section_name=value``)."""
    cfg = Config()
    cfg.sensors.noise.model = "none"
    for key, value in realism.items():
        section, name = key.split("_", 1)
        setattr(getattr(cfg.realism, section), name, value)
    env = KoolioEnv(arena, config=cfg, render_mode="rgb_array")
    env.reset(seed=0)
    return env


def along(start: tuple[int, int], end: tuple[int, int], t: int) -> tuple[int, int]:
    """The pixel ``t`` pixels from ``start`` towards ``end`` (an axis-aligned line)."""
    dx = (end[0] > start[0]) - (end[0] < start[0])
    dy = (end[1] > start[1]) - (end[1] < start[1])
    return start[0] + dx * t, start[1] + dy * t


def dash_pixels(img, start, end, first: int, colour) -> tuple[int, int]:
    """(pixels in the middle of a dash of ``colour``, pixels in the middle of a gap that
    are not ``colour``) from ``first`` pixels on to 4 pixels before ``end``."""
    on, period = draw.DASH[0], sum(draw.DASH)
    length = max(abs(end[0] - start[0]), abs(end[1] - start[1]))
    dashes = gaps = 0
    for t in range(first, length - 4):
        phase = t % period
        if 1 <= phase <= on - 2:
            dashes += pixel(img, along(start, end, t)) == colour
        elif on + 1 <= phase <= period - 2:
            gaps += pixel(img, along(start, end, t)) != colour
    return dashes, gaps


def test_sonar_ray_without_echo_is_dashed_orange_to_the_wall() -> None:
    """The rear sonar's middle ray meets the west wall head-on 110 in from the robot's
    edge, beyond a 30 in ranger: the ray hit, but no echo came back."""
    env = real_env(sonar_max_range=30.0)
    pose_then_stop(env, (120.0, 96.0), 0.0)
    rear, middle = 4, env.config.sensors.sonar.sub_arcs // 2
    assert env.readings.rays[rear, middle] == pytest.approx(120.0)
    assert not env.readings.echo[rear, middle]
    assert env.readings.sonar[rear] == env.sensors.far  # nothing heard
    renderer = EnvRenderer(env)
    img = renderer.render("rgb_array")
    cam = renderer.cameras[0]
    start, end = cam.to_screen((120.0, 96.0)), cam.to_screen((0.0, 96.0))
    robot_px = cam.scale(env.config.robot.radius)
    dashes, gaps = dash_pixels(img, start, end, robot_px + 20, draw.SONAR_NO_ECHO)
    length = start[0] - end[0] - robot_px - 24
    period = sum(draw.DASH)
    assert dashes >= (length // period) * (draw.DASH[0] - 2) > 10
    assert gaps >= (length // period) * (draw.DASH[1] - 2) > 5
    # With the ranger's full range the same ray echoes: black, solid.
    env = real_env(sonar_min_range=1.0)
    pose_then_stop(env, (120.0, 96.0), 0.0)
    assert env.readings.echo[rear, middle]
    img = EnvRenderer(env).render("rgb_array")
    for t in range(robot_px + 20, start[0] - end[0] - 4):
        assert pixel(img, along(start, end, t)) == draw.SONAR_LINE


def test_missed_camera_is_dashed_blue_and_marked_in_the_hud() -> None:
    """A camera that never detects (detection probability 0): the plate in view is drawn
    dashed, and the HUD marks GoalCam0 ``missed``."""
    env = real_env(camera_detect_near=0.0, camera_detect_far=0.0)
    pose_then_stop(env, (GOAL[0], 120.0), math.pi / 2)
    assert env.readings.goal[0] == env.sensors.far and env.readings.missed[0, 0]
    renderer = EnvRenderer(env)
    img = renderer.render("rgb_array")
    cam = renderer.cameras[0]
    start, end = cam.to_screen((GOAL[0], 120.0)), cam.to_screen(GOAL)
    robot_px = cam.scale(env.config.robot.radius)
    dashes, gaps = dash_pixels(img, start, end, robot_px + 2, draw.CAMERA_GOAL_LINE)
    assert dashes > 10 and gaps > 5
    rows = {r.name: r for r in hud.hud_rows(env)}
    assert rows["GoalCam0"].flags == ("missed",) and rows["GoalCam1"].flags == ()
    surface = pygame.Surface((420, 320))
    drawn = hud.draw_hud(surface, pygame.Rect(0, 0, 420, 320), env)
    mark = drawn["flag_marks"]["GoalCam0"]
    assert tuple(surface.get_at((mark.x + 2, mark.centery)))[:3] == hud.FLAG_COLOURS["missed"]
    assert set(drawn["flag_marks"]) == {"GoalCam0"}


def test_misread_plate_is_a_magenta_line_and_ring_and_marked_in_the_hud() -> None:
    """Facing door 306's plate with misread probability 1: the front camera takes it for
    goal 311's; a magenta line to that plate, a ring round it, ``misread`` in the HUD,
    and a Stop there is a wrong door."""
    env = real_env("hallway", camera_misread=1.0)
    plate = (402.0, 87.0)
    assert pose_then_stop(env, (plate[0], 50.0), math.pi / 2) == "wrong_door"
    assert env.readings.misread[0] and env.readings.goal[0] < 36.0
    renderer = EnvRenderer(env)
    img = renderer.render("rgb_array")
    cam = renderer.cameras[1]  # the view that follows the robot
    start, end = cam.to_screen((plate[0], 50.0)), cam.to_screen(plate)
    robot_px = cam.scale(env.config.robot.radius)
    for t in range(robot_px + 2, start[1] - end[1] - 8):
        assert pixel(img, along(start, end, t)) == draw.CAMERA_MISREAD
    ring = max(7, cam.scale(5.0))
    assert pixel(img, (end[0] - ring + 1, end[1])) == draw.CAMERA_MISREAD
    assert draw.CAMERA_GOAL_LINE not in {pixel(img, along(start, end, t)) for t in range(40)}
    rows = {r.name: r for r in hud.hud_rows(env)}
    assert rows["GoalCam0"].flags == ("misread",)


def test_deaf_sonar_is_marked_in_the_hud() -> None:
    """With a 30 in ranger in the middle of the room, sonars whose rays all meet walls
    beyond it hear nothing: their rows say ``no echo``."""
    env = real_env(sonar_max_range=30.0)
    pose_then_stop(env, (120.0, 96.0), 0.0)
    deaf = hud.deaf_sonars(env)
    assert 4 in deaf and all(env.readings.sonar[k] == env.sensors.far for k in deaf)
    rows = {r.name: r for r in hud.hud_rows(env)}
    assert rows["Sonar4"].flags == ("no echo",) and rows["Sonar4"].distance == "not seen"
    ideal = room_env()
    pose_then_stop(ideal, (120.0, 96.0), 0.0)
    assert hud.deaf_sonars(ideal) == [] and all(not r.flags for r in hud.hud_rows(ideal))
