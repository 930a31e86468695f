"""The window's panels and its floating control panel, headless: the control panel in a
window of its own (``pygame.Window`` works under the dummy driver: clicks posted to that
window press its buttons), hint lines instead of tool tips, text that scales with the
window, the live learning curve's axes, the BUMP flag naming its sonar, the plain red
robot without Show Sensors."""

from __future__ import annotations

import json
import math
import os

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

import numpy as np
import pytest

pygame = pytest.importorskip("pygame")
pytest.importorskip("pygame_gui")

from koolio_pymunk.apps.cli import main  # noqa: E402
from koolio_pymunk.apps.viewer import hud  # noqa: E402
from koolio_pymunk.apps.viewer.app import NO_HINT, ViewerApp  # noqa: E402
from koolio_pymunk.apps.viewer.session import Session  # noqa: E402
from koolio_pymunk.task import drawing as draw  # noqa: E402
from koolio_pymunk.task.env import KoolioEnv  # noqa: E402
from koolio_pymunk.world.physics import Action  # noqa: E402


@pytest.fixture
def config(tmp_path):
    path = tmp_path / "cfg.yaml"
    path.write_text("sensors: {noise: {model: none}}\nepisode: {max_steps: 30}\n")
    return path


def make_app(
    tmp_path, config, arena: str = "room", files: tuple[str, str] = ("q.qtable", "log.csv"), **kw
) -> ViewerApp:
    """A paused window learning into ``files`` (table, log) in ``tmp_path``; one learning
    window per table, which is locked while the window learns."""
    env = KoolioEnv(arena, config=config)
    session = Session(env, tmp_path / files[0], seed=1, log=tmp_path / files[1])
    kw.setdefault("running", False)
    app = ViewerApp(session, draw_fps=1e9, **kw)  # every frame redraws (and updates hover)
    pygame.event.clear()
    return app


def post(kind: int, window=None, **fields) -> None:
    if window is not None:
        fields["window"] = window
    pygame.event.post(pygame.event.Event(kind, **fields))


def click(element, window=None) -> None:
    """A left click at the centre of a pygame-gui element (in ``window``: the panel's)."""
    pos = element.rect.center
    post(pygame.MOUSEMOTION, window, pos=pos, rel=(0, 0), buttons=(0, 0, 0))
    post(pygame.MOUSEBUTTONDOWN, window, button=1, pos=pos)
    post(pygame.MOUSEBUTTONUP, window, button=1, pos=pos)


def colour_at(surface, p: tuple[int, int]) -> tuple[int, int, int]:
    return tuple(surface.get_at(p))[:3]


# -- the floating control panel ---------------------------------------------------------------
def test_control_panel_in_a_window_of_its_own(tmp_path, config) -> None:
    app = make_app(tmp_path, config, panel_window=True)
    win = app.panel_window
    assert isinstance(win, pygame.Window) and win.title == "Koolio controls"
    assert app.layout.controls is None and app.layout.main[2] == app.size[0]
    assert win.size == (app.style.px(230), app.size[1])
    # A click in the panel's window presses its button ...
    click(app.b_run, win)
    app.frame()
    assert app.running and app.steps_done == 1
    # ... the same pixel in the main window is the arena view: no button there.
    click(app.b_run)
    app.frame()
    assert app.running and app.steps_done == 2
    # Closing the panel's window docks the panel; P floats it again.
    post(pygame.WINDOWCLOSE, win)
    app.frame()
    assert app.panel_window is None and not app.quit
    assert app.layout.controls is not None and app.layout.main[2] == app.size[0] - 230
    post(pygame.KEYDOWN, key=pygame.K_p, mod=0, unicode="p")
    app.frame()
    assert isinstance(app.panel_window, pygame.Window) and app.b_panel.text == "Dock panel [P]"
    # Closing the main window is Exit, as with one window.
    post(pygame.WINDOWCLOSE)
    app.frame()
    assert app.quit and app.session.closed
    app.finish()
    assert app.panel_window is None


def test_panel_window_buttons_and_keys_from_both_windows(tmp_path, config) -> None:
    app = make_app(tmp_path, config, panel_window=True)
    win = app.panel_window
    post(pygame.KEYDOWN, win, key=pygame.K_s, mod=0, unicode="s")  # typed in the panel
    app.frame()
    assert not app.show_sensors and not app.checks["show_sensors"].get_state()
    click(app.checks["show_sensors"], win)
    app.frame()
    assert app.show_sensors
    click(app.b_panel, win)  # Dock panel
    app.frame()
    assert app.panel_window is None
    click(app.b_panel)  # Float panel, now in the main window
    app.frame()
    assert app.panel_window is not None


def test_screenshot_with_the_floating_panel_shows_both_windows(tmp_path, config) -> None:
    app = make_app(tmp_path, config, panel_window=True)
    app.draw()
    path = app.save_screenshot(tmp_path / "shot.png")
    img = pygame.image.load(str(path))
    w, h = app.size
    assert img.get_size() == (w + 8 + app.style.px(230), h)
    assert colour_at(img, (w + 3, h // 2)) == (255, 255, 255)  # the gap
    panel = app.panel_window.get_surface()
    x, y = app.b_exit.rect.center
    assert colour_at(img, (w + 8 + x, y)) == colour_at(panel, (x, y))


def test_cli_panel_window_flag(tmp_path, config, capsys) -> None:
    shot = tmp_path / "shot.png"
    argv = ["view", "--arena", "room", "--config", str(config), "--steps", "3", "--panel-window"]
    argv += ["--qtable", str(tmp_path / "q"), "--log", str(tmp_path / "l.csv")]
    assert main([*argv, "--screenshot", str(shot)]) == 0
    assert pygame.image.load(str(shot)).get_width() == 1280 + 8 + 230
    assert "view: 3 steps, 0 episodes finished" in capsys.readouterr().out


# -- hints instead of tool tips ----------------------------------------------------------------
@pytest.mark.parametrize("floating", [False, True], ids=["docked", "floating"])
def test_pointing_at_a_control_shows_its_hint_below_the_buttons(tmp_path, config, floating) -> None:
    app = make_app(tmp_path, config, panel_window=floating)
    win = app.panel_window
    app.frame()
    assert app.hint == NO_HINT
    post(pygame.MOUSEMOTION, win, pos=app.b_step.rect.center, rel=(0, 0), buttons=(0, 0, 0))
    app.frame()
    assert app.hint == "One step while paused."
    # No tool tip pops up over the buttons below Step (Rescue): the hint lines sit below
    # every control.
    assert all(getattr(e, "tool_tip_text", None) is None for e in app.hints)
    assert app.hint_labels[0].rect.top >= max(e.rect.bottom for e in app.hints)
    if floating:
        post(pygame.WINDOWLEAVE, win)
    else:
        post(pygame.MOUSEMOTION, pos=app.camera.to_screen((120, 96)), rel=(0, 0), buttons=(0,) * 3)
    app.frame()
    assert app.hint == NO_HINT


# -- text --------------------------------------------------------------------------------------
def test_text_scales_with_the_window_and_has_the_degree_sign(tmp_path, config) -> None:
    small = make_app(tmp_path, config)
    big = make_app(tmp_path, config, files=("big.qtable", "big.csv"), size=(1920, 1080))
    assert (small.style.ui, big.style.ui) == (1.0, 1.35)
    assert big.b_run.rect.h == 40 and small.b_run.rect.h == 30
    assert hud.text("Sonar1-2", big.style.row).get_height() > hud.text("Sonar1-2", 14).get_height()
    big.draw()
    assert big.drawn["hud"]["bump_flag"].h == 32
    # The panels' face has a degree sign (not the missing-glyph box).
    f = hud.font(14)
    assert f.metrics("°") != f.metrics("\ue000")
    assert [r.angles for r in hud.hud_rows(small.env)][:3] == ["0°", "+45°", "-45°"]


def _contrast(a, b) -> float:
    def lum(c):
        v = [x / 255 for x in c]
        v = [x / 12.92 if x <= 0.03928 else ((x + 0.055) / 1.055) ** 2.4 for x in v]
        return 0.2126 * v[0] + 0.7152 * v[1] + 0.0722 * v[2]

    hi, lo = sorted((lum(a), lum(b)), reverse=True)
    return (hi + 0.05) / (lo + 0.05)


def test_grey_values_are_readable() -> None:
    assert _contrast(hud.DIM, hud.PANEL_BG) >= 7.0  # WCAG AAA for small text
    assert _contrast(hud.INK, hud.PANEL_BG) >= 12.0


def test_clockless_says_the_clock_is_off(tmp_path, config) -> None:
    app = make_app(tmp_path, config, speed=10.0)
    assert app.speed_label.text == "Clock speed: 10 steps/s" and app.slider.is_enabled
    post(pygame.KEYDOWN, key=pygame.K_c, mod=0, unicode="c")
    app.frame()
    assert app.speed_label.text == "Clock: off (clockless)" and not app.slider.is_enabled
    post(pygame.KEYDOWN, key=pygame.K_c, mod=0, unicode="c")
    app.frame()
    assert app.speed_label.text == "Clock speed: 10 steps/s" and app.slider.is_enabled


def test_stats_say_episodes_not_eps(tmp_path, config) -> None:
    app = make_app(tmp_path, config, running=True, clockless=True)
    app.session.run(30)  # one episode (cap 30)
    rows = dict(hud.stats_rows(app.session, 0.0))
    assert rows["trained"] == "1 episode"
    assert rows["Q-table"].endswith(" states")


def test_panel_names_the_table_world_and_configuration(tmp_path, config) -> None:
    q = tmp_path / "q.qtable"
    assert (
        main(
            ["train", "--arena", "room", "--config", str(config), "--qtable", str(q)]
            + ["--episodes", "1", "--quiet", "--log", str(tmp_path / "t.csv")]
        )
        == 0
    )
    env = KoolioEnv("room", config=config)
    session = Session(env, q, seed=1, greedy=True)
    app = ViewerApp(session, config_name="cfg.yaml")
    lines = app.info_lines()
    assert lines[0] == "mode: greedy (read-only table)"
    assert lines[2:4] == ["world: ideal", "config: cfg.yaml"]
    assert lines[4] == f"table: {q}"
    assert lines[5] == "log: none"


# -- the BUMP flag -----------------------------------------------------------------------------
def test_bump_flag_names_the_single_sonar_that_bumped(tmp_path, config) -> None:
    """Along the north wall, 5.5 in to the left: sonar 2 (+80°) bumps on its own while the
    averaged pair 1-2 reads Close. The flag names sonar 2; the pair's row is marked."""
    app = make_app(tmp_path, config)
    app.env.world.place(0, (120.0, 176.5), 0.0)
    app.env.transition(Action.STOP)
    rows = {r.name: r for r in hud.hud_rows(app.env)}
    assert rows["Sonar1-2"].level == "Close" and rows["Sonar1-2"].bumped == (2,)
    assert all(r.level != "Bump" for r in rows.values())
    assert hud.bump_text(app.env) == "BUMP: sonar 2 (+80°) 5.5 in"
    app.draw()
    drawn = app.drawn["hud"]
    flag, mark = drawn["bump_flag"], drawn["bump_marks"][2]
    assert colour_at(app.screen, (flag.x + 2, flag.y + 2)) == hud.BUMP_ON
    assert colour_at(app.screen, (mark.x + 3, mark.centery)) == hud.BUMP_ON
    row_y = app.layout.hud[1] + app.style.head_h + 7 * app.style.row_h  # the 8th row: Sonar1-2
    assert mark.y == row_y


# -- the robot without Show Sensors --------------------------------------------------------------
def _robot_px(app: ViewerApp, cam) -> tuple[int, int]:
    x, y, h = app.env.world.pose(0)
    r = app.env.config.robot.radius / 2
    return cam.to_screen((x - r * math.sin(h), y + r * math.cos(h)))


def test_show_sensors_off_draws_the_robot_red_in_both_views(tmp_path, config) -> None:
    app = make_app(tmp_path, config, arena="hallway")
    app.env.world.place(0, (300.0, 11.0), 0.0)  # 1 in off the south wall: Bump (pink)
    app.env.transition(Action.STOP)
    app.draw()
    main_px, over_px = _robot_px(app, app.camera), _robot_px(app, app.overview_cam)
    assert colour_at(app.screen, main_px) == draw.ROBOT_BUMP
    assert colour_at(app.screen, over_px) == draw.ROBOT_BUMP
    post(pygame.KEYDOWN, key=pygame.K_s, mod=0, unicode="s")
    app.frame()
    assert colour_at(app.screen, main_px) == draw.ROBOT_NORMAL
    assert colour_at(app.screen, over_px) == draw.ROBOT_NORMAL


# -- the live learning curve -------------------------------------------------------------------
def _curve(returns, at_goal, size=(420, 320)):
    surf = pygame.Surface(size)
    drawn = hud.draw_curve(surf, pygame.Rect(0, 0, *size), returns, 0, 25, at_goal=at_goal)
    return surf, drawn


def _rows_of(surf, rect, colour) -> np.ndarray:
    arr = pygame.surfarray.array3d(surf)[rect.left : rect.right, rect.top : rect.bottom]
    return np.nonzero(np.all(arr == np.array(colour), axis=2))[1]


def test_one_disastrous_episode_does_not_squash_the_moving_average() -> None:
    returns = list(np.linspace(-300.0, 150.0, 200))
    returns[120] = -2282.0
    at_goal = [i > 100 for i in range(200)]
    surf, drawn = _curve(returns, at_goal)
    plot = drawn["plot"]
    ys = _rows_of(surf, plot, hud.CURVE_AVERAGE)
    assert ys.max() - ys.min() > 0.7 * plot.h  # the average uses most of the height
    assert drawn["off_scale"] == 1
    assert drawn["y_range"][0] > -400  # the outlier is off scale, drawn at the edge
    # The goal rate, on the right axis (0..100 %): 0 at the start, 100 % at the end.
    goal = _rows_of(surf, plot, hud.CURVE_GOAL)
    assert goal.max() >= plot.h - 3 and goal.min() <= 2
    assert drawn["goal_rate"] == 100.0


def test_curve_ticks_on_both_axes() -> None:
    returns = [float(v) for v in np.linspace(-500, 100, 1501)]
    surf, drawn = _curve(returns, [False] * 1501, size=(500, 320))
    plot = drawn["plot"]
    assert plot.w == 388  # the panel less the tick labels and the axis caption
    assert drawn["x_ticks"] == [250.0 * k for k in range(1, 7)]  # 388 // 56: at most 6 ticks
    assert drawn["y_ticks"][0] >= drawn["y_range"][0] and drawn["y_ticks"][-1] <= 100
    assert len(drawn["y_ticks"]) >= 4
    for e in drawn["x_ticks"]:  # a tick mark under the plot at each one
        x = plot.x + round((e - 1) / 1500 * (plot.w - 1))
        assert colour_at(surf, (x, plot.bottom + 1)) == hud.CURVE_AXES
    for v in drawn["y_ticks"]:  # a grid line across the plot at each one
        y = drawn["y_of"](v)
        row = [colour_at(surf, (x, y)) for x in range(plot.x + 1, plot.right - 1)]
        assert sum(c in (hud.CURVE_GRID, hud.CURVE_ZERO) for c in row) > plot.w // 2


def test_live_curve_reads_goal_history_from_the_log(tmp_path, config) -> None:
    log = tmp_path / "log.csv"
    assert (
        main(
            ["train", "--arena", "room", "--config", str(config), "--qtable"]
            + [str(tmp_path / "q.qtable"), "--log", str(log), "--episodes", "3", "--quiet"]
        )
        == 0
    )
    app = make_app(tmp_path, config)
    st = app.session.stats
    assert len(st.returns) == len(st.at_goal) == 3 and st.run_start == 3


@pytest.mark.parametrize("size", [(1280, 800), (1080, 700), (1920, 1080)])
@pytest.mark.parametrize("memory", [{}, {"goal_camera": True, "previous_action": True}, "all"])
def test_the_hud_shows_every_state_field_and_its_last_line(tmp_path, size, memory) -> None:
    """Memory fields lengthen the HUD: the window makes its panel taller, and where the
    window is too small the rows close up (and the compass line, not in the state, goes),
    never pushing a row or the last action's line out of the panel."""
    if memory == "all":
        memory = {"goal_camera": True, "eow_camera": True, "previous_action": True}
        memory |= {"goal_bearing": True}
    longest = "eow_camera" in memory  # and the compass in the state: 17 rows
    cfg = {"sensors": {"memory": memory, "compass": {"in_state": longest}}}
    path = tmp_path / "mem.yaml"
    path.write_text(json.dumps(cfg))
    app = make_app(tmp_path, str(path), size=size)
    for _ in range(3):
        app.session.step()
    app.draw()
    drawn = app.drawn["hud"]
    panel = drawn["panel"]
    assert len(hud.hud_rows(app.env)) == len(app.env.layout.bits)
    assert panel.contains(drawn["last_line"]) and panel.contains(drawn["bump_flag"])
    assert drawn["row_step"] >= hud.min_row_step(app.style)
    if size != (1080, 700) and not longest:  # every row at full height, the compass line too
        assert drawn["row_step"] == app.style.row_h and drawn["compass_line"]
