"""The window, headless: posted pygame events drive the controls; Exit / Exit Without
Save and the Q-table file; screenshots; the CLI of ``koolio-pm view``."""

from __future__ import annotations

import math
import os

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

import numpy as np
import pytest
from inputs import same_run

pygame = pytest.importorskip("pygame")
pytest.importorskip("pygame_gui")

from koolio_pymunk.apps.cli import main  # noqa: E402
from koolio_pymunk.apps.viewer import hud  # noqa: E402
from koolio_pymunk.apps.viewer.app import ViewerApp  # noqa: E402
from koolio_pymunk.apps.viewer.session import Session  # noqa: E402
from koolio_pymunk.learning.training import train  # noqa: E402
from koolio_pymunk.store.episode_log import log_rows  # noqa: E402
from koolio_pymunk.store.qtable import QTableStore, load_qtable  # noqa: E402
from koolio_pymunk.task import drawing as draw  # noqa: E402
from koolio_pymunk.task.env import KoolioEnv  # noqa: E402
from koolio_pymunk.world.physics import Action  # noqa: E402

CAP = 30  # step cap of the test configuration: episode 0 ends (truncated) at step 30
TICK = 15  # clockless steps per tick


@pytest.fixture
def config(tmp_path):
    path = tmp_path / "cfg.yaml"
    path.write_text(
        "sensors: {noise: {model: none}}\n"
        f"episode: {{max_steps: {CAP}, clockless_loop_count: {TICK}}}\n"
    )
    return path


def make_app(tmp_path, config, **kw) -> ViewerApp:
    env = KoolioEnv("room", config=config)
    session = Session(
        env,
        tmp_path / "q.qtable",
        seed=1,
        log=tmp_path / "log.csv",
        episodes=kw.pop("episodes", None),
    )
    app = ViewerApp(session, **kw)
    pygame.event.clear()
    return app


def key(k: int, mod: int = 0) -> None:
    pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=k, mod=mod, unicode=""))


def click(element) -> None:
    """A left click at the centre of a pygame-gui element."""
    pos = element.rect.center
    pygame.event.post(pygame.event.Event(pygame.MOUSEBUTTONDOWN, button=1, pos=pos))
    pygame.event.post(pygame.event.Event(pygame.MOUSEBUTTONUP, button=1, pos=pos))


def screen_pixel(app: ViewerApp, p: tuple[int, int]) -> tuple[int, int, int]:
    return tuple(app.screen.get_at(p))[:3]


# -- stepping and pausing -----------------------------------------------------------------------
def test_pause_stops_stepping_and_begin_resumes(tmp_path, config) -> None:
    app = make_app(tmp_path, config, clockless=True)
    app.frame()
    assert app.steps_done == TICK
    key(pygame.K_SPACE)
    app.frame()
    app.frame()
    assert not app.running and app.steps_done == TICK
    assert "PAUSED" in app.tags()
    key(pygame.K_n)  # one step while paused
    app.frame()
    assert app.steps_done == TICK + 1
    click(app.b_run)  # Begin, with the mouse
    app.frame()
    assert app.running and app.steps_done == 2 * TICK + 1
    click(app.b_run)  # Pause, with the mouse
    app.frame()
    assert not app.running and app.steps_done == 2 * TICK + 1
    assert app.b_run.text.startswith("Begin")


def test_rescue_key_and_button_rescue(tmp_path, config) -> None:
    app = make_app(tmp_path, config, running=False)
    env = app.env
    assert not env.has_been_rescued
    before = env.world.pose(0)
    key(pygame.K_r)
    app.frame()
    assert env.has_been_rescued and env.world.pose(0) != before
    assert "RESCUED" in app.tags()
    app.draw()
    box = app.drawn["tags"]["RESCUED"]
    assert screen_pixel(app, (box.x + 2, box.y + 2)) == hud.TAG_COLOURS["RESCUED"]
    heading = env.world.pose(0)[2]
    click(app.b_rescue)
    app.frame()
    assert env.world.pose(0)[2] != heading


@pytest.mark.parametrize(
    ("name", "k"),
    [
        ("show_sensors", pygame.K_s),
        ("show_hud", pygame.K_h),
        ("show_stats", pygame.K_t),
        ("auto_rescue", pygame.K_a),
        ("clockless", pygame.K_c),
        ("follow", pygame.K_f),
    ],
)
def test_toggles_by_key_and_by_check_box(tmp_path, config, name, k) -> None:
    app = make_app(tmp_path, config, running=False)

    def state() -> bool:
        return app.auto_rescue if name == "auto_rescue" else getattr(app, name)

    start = state()
    key(k)
    app.frame()
    assert state() is (not start)
    assert app.checks[name].get_state() is (not start)
    click(app.checks[name])
    app.frame()
    assert state() is start
    assert app.checks[name].get_state() is start
    if name == "auto_rescue":
        assert app.env.config.rescue.auto_rescue_toggle is start


def test_clock_speed_slider_arrow(tmp_path, config) -> None:
    from koolio_pymunk.apps.viewer.app import slider_to_speed, speed_to_slider

    app = make_app(tmp_path, config, running=False, speed=10.0)
    click(app.slider.right_button)
    app.frame()
    assert app.speed == slider_to_speed(speed_to_slider(10.0) + 5)
    assert app.speed > 10.0 and f"{app.speed:g} steps/s" in app.speed_label.text


def test_speed_keys_and_help_overlay(tmp_path, config) -> None:
    app = make_app(tmp_path, config, running=False, speed=10.0)
    key(pygame.K_RIGHTBRACKET)
    app.frame()
    assert app.speed == pytest.approx(15.0)
    assert "15" in app.speed_label.text
    key(pygame.K_F1)
    app.frame()
    app.draw()
    assert app.help and "help" in app.drawn
    key(pygame.K_ESCAPE)
    app.frame()
    assert not app.help


def test_mouse_wheel_zooms_and_drag_scrolls_the_arena(tmp_path, config) -> None:
    app = make_app(tmp_path, config, running=False)
    x, y, w, h = app.layout.main
    centre = (x + w // 2, y + h // 2)
    zoom = app.camera.zoom
    pygame.event.post(
        pygame.event.Event(pygame.MOUSEMOTION, pos=centre, rel=(0, 0), buttons=(0, 0, 0))
    )
    pygame.event.post(pygame.event.Event(pygame.MOUSEWHEEL, x=0, y=2))
    app.frame()
    assert app.camera.zoom == pytest.approx(zoom * 1.15**2)
    world = app.camera.to_world(centre)
    pygame.event.post(pygame.event.Event(pygame.MOUSEBUTTONDOWN, button=1, pos=centre))
    moved = (centre[0] + 40, centre[1])
    pygame.event.post(
        pygame.event.Event(pygame.MOUSEMOTION, pos=moved, rel=(40, 0), buttons=(1, 0, 0))
    )
    pygame.event.post(pygame.event.Event(pygame.MOUSEBUTTONUP, button=1, pos=moved))
    app.frame()
    assert not app.follow  # dragging stops following the robot
    assert app.camera.to_world(moved) == pytest.approx(world)


# -- pixels in the window -------------------------------------------------------------------------
def robot_pixel(app: ViewerApp) -> tuple[int, int]:
    x, y, h = app.env.world.pose(0)
    r = app.env.config.robot.radius / 2
    return app.camera.to_screen((x - r * math.sin(h), y + r * math.cos(h)))


@pytest.mark.parametrize(
    ("at", "heading", "colour"),
    [
        ((120.0, 96.0), 0.0, draw.ROBOT_NORMAL),
        ((50.0, 15.0), 0.0, draw.ROBOT_BUMP),
        ((264.0, 96.0), 0.0, draw.ROBOT_END_OF_WORLD),
        ((102.0, 160.0), math.pi / 2, draw.ROBOT_GOAL),
    ],
    ids=["red", "pink", "purple", "black"],
)
def test_robot_colour_in_the_window(tmp_path, config, at, heading, colour) -> None:
    app = make_app(tmp_path, config, running=False)
    app.env.world.place(0, at, heading)
    app.env.transition(Action.STOP)
    app.draw()
    assert screen_pixel(app, robot_pixel(app)) == colour
    key(pygame.K_s)  # Show Sensors off: no state colour
    app.frame()
    app.draw()
    assert screen_pixel(app, robot_pixel(app)) == draw.ROBOT_NORMAL


def test_hud_and_stats_present_and_hidden(tmp_path, config) -> None:
    app = make_app(tmp_path, config, running=False)
    app.env.world.place(0, (50.0, 15.0), 0.0)  # against the south wall: Bump
    app.env.transition(Action.STOP)
    app.draw()
    flag = app.drawn["hud"]["bump_flag"]
    assert screen_pixel(app, (flag.x + 2, flag.y + 2)) == hud.BUMP_ON
    stats_rect = pygame.Rect(app.layout.stats)
    dark = _dark_pixels(app, stats_rect)
    assert dark > 300  # text rows
    assert _dark_pixels(app, pygame.Rect(app.layout.hud)) > 300
    key(pygame.K_h)
    key(pygame.K_t)
    app.frame()
    app.draw()
    assert "hud" not in app.drawn and "stats" not in app.drawn
    body = stats_rect.inflate(-4, -4).move(0, 30).clip(stats_rect.inflate(-4, -34))
    assert _dark_pixels(app, body) == 0
    # Back on, away from the wall: the flag reads "no bump".
    key(pygame.K_h)
    app.frame()
    app.env.world.place(0, (120.0, 96.0), 0.0)
    app.env.transition(Action.STOP)
    app.draw()
    flag = app.drawn["hud"]["bump_flag"]
    assert screen_pixel(app, (flag.x + 2, flag.y + 2)) == hud.BUMP_OFF


def _dark_pixels(app: ViewerApp, rect: pygame.Rect) -> int:
    arr = pygame.surfarray.pixels3d(app.screen)
    sub = np.asarray(arr[rect.left : rect.right, rect.top : rect.bottom]).astype(int)
    del arr
    return int((sub.sum(axis=2) < 200).sum())


def test_stats_and_learning_curve_after_episodes(tmp_path, config) -> None:
    app = make_app(tmp_path, config, clockless=True)
    for _ in range(5):  # 75 steps: two finished episodes (cap 30)
        app.frame()
    st = app.session.stats
    assert st.episodes == 2 and len(st.returns) == 2
    app.draw()
    curve = app.layout.curve
    arr = pygame.surfarray.pixels3d(app.screen)
    sub = np.asarray(arr[curve[0] : curve[0] + curve[2], curve[1] : curve[1] + curve[3]])
    del arr
    avg = np.all(sub == np.array(hud.CURVE_AVERAGE), axis=2).sum()
    assert avg > 50  # the moving-average line (and its legend) are drawn
    rows = dict(hud.stats_rows(app.session, 0.0))
    assert rows["episodes"] == "2"
    assert rows["avg steps / ep"] == f"{CAP:.1f}"


# -- Exit and Exit Without Save -------------------------------------------------------------------
def _one_and_a_half_episodes(tmp_path, config) -> tuple[ViewerApp, bytes]:
    app = make_app(tmp_path, config, clockless=True)
    for _ in range(3):  # 45 steps: episode 0 finished (saved) at 30, episode 1 at step 15
        app.frame()
    assert app.session.stats.episodes == 1 and app.env.steps == 15
    saved = (tmp_path / "q.qtable").read_bytes()
    assert load_qtable(tmp_path / "q.qtable").meta["episodes"] == 1
    return app, saved


def test_exit_without_save_leaves_the_table_file_byte_identical(tmp_path, config) -> None:
    app, saved = _one_and_a_half_episodes(tmp_path, config)
    backup = (tmp_path / "q.qtable.bak").read_bytes()
    click(app.b_exit_nosave)
    app.frame()
    assert app.quit and app.session.closed
    assert (tmp_path / "q.qtable").read_bytes() == saved
    assert (tmp_path / "q.qtable.bak").read_bytes() == backup
    assert [r["outcome"] for r in log_rows(tmp_path / "log.csv")] == ["truncated"]


def test_exit_without_save_by_key(tmp_path, config) -> None:
    app, saved = _one_and_a_half_episodes(tmp_path, config)
    key(pygame.K_q, pygame.KMOD_LSHIFT)
    app.frame()
    assert app.quit and (tmp_path / "q.qtable").read_bytes() == saved


def test_exit_folds_the_unfinished_episode_and_saves(tmp_path, config) -> None:
    app, saved = _one_and_a_half_episodes(tmp_path, config)
    in_memory = app.session.table.to_bytes()
    assert in_memory != saved  # episode 1's 15 updates are not in the file yet
    click(app.b_exit)
    app.frame()
    assert app.quit
    assert (tmp_path / "q.qtable").read_bytes() == in_memory
    assert (tmp_path / "q.qtable.bak").read_bytes() == saved
    rows = log_rows(tmp_path / "log.csv")
    assert [(r["episode"], r["steps"], r["outcome"]) for r in rows] == [
        ("0", str(CAP), "truncated"),
        ("1", "15", "interrupted"),
    ]
    # The table still counts one finished episode: training resumes with episode 1.
    assert load_qtable(tmp_path / "q.qtable").meta["episodes"] == 1


def test_window_close_is_exit(tmp_path, config) -> None:
    app, saved = _one_and_a_half_episodes(tmp_path, config)
    pygame.event.post(pygame.event.Event(pygame.QUIT))
    app.frame()
    assert app.quit and (tmp_path / "q.qtable").read_bytes() != saved


# -- the command line -----------------------------------------------------------------------------
def test_view_learns_exactly_like_train_and_writes_a_screenshot(tmp_path, config, capsys) -> None:
    """Same seed, same episodes: the window's table and log equal ``train``'s, byte for byte."""
    a = tmp_path / "a"
    env = KoolioEnv("room", config=config)
    train(env, QTableStore(a / "q.qtable"), 3, seed=5, log_path=a / "log.csv", report=None)
    b = tmp_path / "b"
    shot = b / "shot.png"
    argv = ["view", "--arena", "room", "--config", str(config), "--seed", "5"]
    argv += ["--episodes", "3", "--qtable", str(b / "q.qtable"), "--log", str(b / "log.csv")]
    assert main([*argv, "--clockless", "--screenshot", str(shot), "--size", "1100x720"]) == 0
    assert same_run(b / "q.qtable", a / "q.qtable")  # the same run from another command
    assert (b / "log.csv").read_text() == (a / "log.csv").read_text()
    img = pygame.image.load(str(shot))
    assert img.get_size() == (1100, 720)
    assert "3 episodes finished" in capsys.readouterr().out


def test_view_with_no_episode_to_run_shows_the_start(tmp_path, config) -> None:
    """``--episodes 0`` draws the next episode's start (it once drew uninitialised
    readings and crashed) and changes no file."""
    argv = ["--arena", "room", "--config", str(config), "--seed", "2"]
    table = tmp_path / "q.qtable"
    assert main(["train", *argv, "--qtable", str(table), "--episodes", "1", "--quiet"]) == 0
    before = table.read_bytes()
    for mode in ([], ["--learn"]):
        shot = tmp_path / f"shot{len(mode)}.png"
        view = ["view", *argv, *mode, "--qtable", str(table), "--episodes", "0"]
        assert main([*view, "--screenshot", str(shot)]) == 0
        assert pygame.image.load(str(shot)).get_size()[0] > 0
        assert table.read_bytes() == before


LEFT_ALIVE = """
import gc, sys
import pymunk
from koolio_pymunk.apps.cli import main
code = main(sys.argv[1:])
gc.collect()
print(code, sum(isinstance(o, pymunk.Space) for o in gc.get_objects()))
"""


def test_view_lets_its_world_go_when_it_returns(tmp_path, config) -> None:
    """After ``view`` returns, nothing holds its world: pygame_gui's default manager (a
    module global) held the window and so the world's pymunk spaces until the
    interpreter's last garbage collection, where pymunk's finalizers run without their
    cffi callbacks and removed bodies from a freed space (``view --episodes 0`` segfaulted
    at exit). A fresh interpreter, so that no other test's world is counted; the real
    process then exits 0."""
    import subprocess
    import sys

    argv = ["--arena", "room", "--config", str(config)]
    table = tmp_path / "q.qtable"
    assert main(["train", *argv, "--qtable", str(table), "--episodes", "1", "--quiet"]) == 0
    view = ["view", *argv, "--greedy", "--qtable", str(table), "--episodes", "0", "--steps", "3"]
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy"}
    left = subprocess.run(
        [sys.executable, "-c", LEFT_ALIVE, *view], capture_output=True, text=True, env=env
    )
    assert left.stdout.splitlines()[-1] == "0 0", left.stdout + left.stderr
    p = subprocess.run([sys.executable, "-m", "koolio_pymunk", *view], capture_output=True, env=env)
    assert p.returncode == 0, p.stderr


def test_train_resumes_a_table_from_the_window(tmp_path, config) -> None:
    """Hand a table from the window to ``train``: 2 + 1 episodes == 3 in one go."""
    argv = ["--arena", "room", "--config", str(config), "--seed", "2"]
    one = ["--qtable", str(tmp_path / "one.qtable"), "--log", str(tmp_path / "one.csv")]
    two = ["--qtable", str(tmp_path / "two.qtable"), "--log", str(tmp_path / "two.csv")]
    assert main(["train", *argv, *one, "--episodes", "3", "--quiet"]) == 0
    assert main(["view", *argv, *two, "--episodes", "2", "--clockless"]) == 0
    assert main(["train", *argv, *two, "--episodes", "3", "--quiet"]) == 0  # 3 in all
    assert same_run(tmp_path / "two.qtable", tmp_path / "one.qtable")


def test_screenshot_every_writes_a_numbered_sequence(tmp_path, config) -> None:
    frames = tmp_path / "frames"
    argv = ["view", "--arena", "room", "--config", str(config), "--steps", "6"]
    argv += ["--qtable", str(tmp_path / "q.qtable"), "--log", str(tmp_path / "l.csv")]
    assert main([*argv, "--screenshot-every", "2", str(frames)]) == 0
    assert sorted(p.name for p in frames.iterdir()) == [
        "frame_00001.png",
        "frame_00002.png",
        "frame_00003.png",
    ]


def test_greedy_view_leaves_the_table_alone(tmp_path, config) -> None:
    q = tmp_path / "q.qtable"
    argv = ["--arena", "room", "--config", str(config), "--qtable", str(q)]
    assert (
        main(["train", *argv, "--episodes", "2", "--quiet", "--log", str(tmp_path / "l.csv")]) == 0
    )
    before = q.read_bytes()
    log2 = tmp_path / "greedy.csv"
    assert main(["view", *argv, "--greedy", "--steps", "40", "--log", str(log2)]) == 0
    assert q.read_bytes() == before and not log2.exists()


@pytest.mark.parametrize(
    "extra",
    [
        ["--size", "10x10"],
        ["--size", "big"],
        ["--screenshot-every", "0", "d"],
        ["--screenshot", "out.jpg", "--steps", "1"],
        ["--steps", "-1"],
        ["--speed", "0"],
        ["--paused", "--steps", "5"],
        [],  # headless needs --steps or --episodes
    ],
)
def test_bad_flags_one_line_error_exit_2(tmp_path, capsys, extra) -> None:
    argv = [
        "view",
        "--arena",
        "room",
        "--qtable",
        str(tmp_path / "q"),
        "--log",
        str(tmp_path / "l"),
    ]
    with pytest.raises(SystemExit) as exc:
        raise SystemExit(main([*argv, *extra]))
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "error" in err


def test_greedy_session_watches_the_episodes_of_eval(tmp_path, config) -> None:
    """``view --greedy`` shows the very episodes ``koolio-pm eval`` scores (same seed)."""
    from koolio_pymunk.learning.evaluation import evaluate

    q = tmp_path / "q.qtable"
    env = KoolioEnv("room", config=config)
    train(env, QTableStore(q), 3, seed=0, log_path=None, report=None)
    table = load_qtable(q)
    ev = evaluate(KoolioEnv("room", config=config), table, 3, seed=4)
    session = Session(KoolioEnv("room", config=config), q, seed=4, episodes=3, greedy=True)
    session.run(10 * CAP)
    assert session.done and session.stats.episodes == 3
    steps = [r.steps for r in session.results]
    assert sum(steps) / 3 == pytest.approx(ev.mean_steps)
    assert session.stats.reward_sum / 3 == pytest.approx(ev.mean_reward)
    assert session.stats.goals / 3 == pytest.approx(ev.goal_rate)


def test_world_profile_in_the_panel_and_over_the_arena(tmp_path, config) -> None:
    """A realistic world is named over the arena view (a tag) and in the control panel
    with the models it turns on; the ideal world adds neither."""
    env = KoolioEnv("room", config=config, world="koolio-real-dr")
    app = ViewerApp(Session(env, tmp_path / "q.qtable", seed=1, log=tmp_path / "log.csv"))
    app.draw()
    assert "WORLD: KOOLIO-REAL-DR" in app.drawn["tags"]
    lines = app.info_lines()
    i = lines.index("world: koolio-real-dr")
    assert lines[i + 1 : i + 4] == [
        "realism: sonar, camera, motion",
        "randomized: 11 parameters per episode",
        "config: default",
    ]
    ideal = make_app(tmp_path / "ideal", config)
    ideal.draw()
    assert not any(t.startswith("WORLD") for t in ideal.drawn["tags"])
    assert not any(line.startswith(("realism", "randomized")) for line in ideal.info_lines())
