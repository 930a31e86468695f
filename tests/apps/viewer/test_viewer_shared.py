"""The window with robots sharing one arena (``view --robots N --shared-arena``): the same
episodes and files as ``train --robots N --shared-arena``, the selected robot (Tab, a
click) in the HUD and Stats, Exit's folded episodes, the refused combinations."""

from __future__ import annotations

import os

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

import pytest
from inputs import same_run

pygame = pytest.importorskip("pygame")
pytest.importorskip("pygame_gui")

from koolio_pymunk.apps.cli import main  # noqa: E402
from koolio_pymunk.apps.viewer import hud  # noqa: E402
from koolio_pymunk.apps.viewer.app import HELP_LINES, ViewerApp  # noqa: E402
from koolio_pymunk.apps.viewer.session import SharedSession  # noqa: E402
from koolio_pymunk.learning.training import train  # noqa: E402
from koolio_pymunk.store.episode_log import log_rows  # noqa: E402
from koolio_pymunk.store.qtable import QTableStore, load_qtable  # noqa: E402
from koolio_pymunk.task.drawing import ROBOT_PALETTE  # noqa: E402
from koolio_pymunk.task.env import KoolioEnv  # noqa: E402

CAP = 80  # hallway episodes: most truncated at the cap, some end earlier (end of world)


@pytest.fixture
def config(tmp_path):
    path = tmp_path / "cfg.yaml"
    path.write_text(f"episode: {{max_steps: {CAP}, clockless_loop_count: 12}}\n")
    return path


def make_app(tmp_path, config, robots: int = 3, **kw) -> ViewerApp:
    env = KoolioEnv("hallway", config=config)
    session = SharedSession(
        env, tmp_path / "q.qtable", robots=robots, seed=1, log=tmp_path / "log.csv"
    )
    app = ViewerApp(session, running=False, **kw)
    pygame.event.clear()
    return app


def key(k: int, mod: int = 0) -> None:
    pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=k, mod=mod, unicode=""))


def click_at(pos: tuple[int, int]) -> None:
    pygame.event.post(pygame.event.Event(pygame.MOUSEBUTTONDOWN, button=1, pos=pos))
    pygame.event.post(pygame.event.Event(pygame.MOUSEBUTTONUP, button=1, pos=pos))


def shown_robot(app: ViewerApp) -> int:
    """The robot the panels show, as drawn: the tag over the arena, the HUD's title and
    the Stats panel's heading agree on it."""
    app.draw()
    tags = [t for t in app.drawn["tags"] if t.startswith("ROBOT ")]
    assert len(tags) == 1
    k = int(tags[0].split()[1])
    box = app.drawn["tags"][tags[0]]
    assert tuple(app.screen.get_at((box.x + 3, box.y + 3)))[:3] == ROBOT_PALETTE[k]
    assert app.drawn["hud"]["title"] == f"HUD: robot {k}'s encoded readings"
    heading = hud.stats_rows(app.session, 0.0)[0][1]
    assert heading.startswith(f"Robot {k}"), heading
    assert app.env is app.session.envs[k] and app.env.robot == k
    return k


def test_shared_view_learns_like_train_and_writes_a_screenshot(tmp_path, config, capsys) -> None:
    """4 robots, 10 episodes in the window: the table and log of ``train --robots 4
    --shared-arena --episodes 10`` with the same seed (episodes finish out of robot
    order: the rows are numbered in the order they finish, as ``train`` numbers them)."""
    a = tmp_path / "a"
    env = KoolioEnv("hallway", config=config)
    store = QTableStore(a / "q.qtable")
    train(env, store, 10, seed=3, log_path=a / "log.csv", report=None, robots=4, shared_arena=True)
    b = tmp_path / "b"
    shot = b / "shot.png"
    argv = ["view", "--arena", "hallway", "--config", str(config), "--seed", "3"]
    argv += ["--robots", "4", "--shared-arena", "--episodes", "10"]
    argv += ["--qtable", str(b / "q.qtable"), "--log", str(b / "log.csv")]
    assert main([*argv, "--clockless", "--screenshot", str(shot), "--size", "1100x720"]) == 0
    assert same_run(b / "q.qtable", a / "q.qtable")
    assert (b / "log.csv").read_text() == (a / "log.csv").read_text()
    outcomes = [row["outcome"] for row in log_rows(b / "log.csv")]
    assert len(outcomes) == 10 and len(set(outcomes)) > 1  # not all ended at the cap
    assert pygame.image.load(str(shot)).get_size() == (1100, 720)
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("view: 4 robots sharing the arena, learning into")
    assert " ticks of 4 robots, 10 episodes finished" in out[-1]


def test_a_step_is_a_tick_of_every_robot(tmp_path, config) -> None:
    app = make_app(tmp_path, config)
    key(pygame.K_n)
    app.frame()
    assert app.steps_done == 1 and [e.steps for e in app.envs] == [1, 1, 1]
    app.set_flag("clockless", True)
    app.toggle_running()
    app.frame()  # clockless: about clockless_loop_count robot steps a frame
    assert app.steps_done == 1 + 12 // 3
    app.set_flag("auto_rescue", False)  # a toggle of every robot
    assert not any(e.config.rescue.auto_rescue_toggle for e in app.envs)


def test_select_a_robot_by_key_and_by_click(tmp_path, config) -> None:
    app = make_app(tmp_path, config)
    for _ in range(3):
        key(pygame.K_n)
    app.frame()
    assert shown_robot(app) == 0
    key(pygame.K_TAB)
    app.frame()
    assert shown_robot(app) == 1
    key(pygame.K_TAB, pygame.KMOD_SHIFT)
    key(pygame.K_TAB, pygame.KMOD_SHIFT)
    app.frame()
    assert shown_robot(app) == 2  # round the robots
    world = app.env.world
    for k in (1, 0, 2):
        click_at(app.camera.to_screen(world.pose(k)[:2]))
        app.frame()
        assert shown_robot(app) == k
    x, y, _, h = app.layout.main
    empty = (x + 3, y + h - 3)  # a corner of the view: no robot there
    assert app.robot_at(empty) is None
    click_at(empty)
    app.frame()
    assert shown_robot(app) == 2


def test_help_names_the_selection_keys() -> None:
    keys = dict(HELP_LINES)
    assert "Tab / Shift+Tab" in keys and "click a robot" in keys


def test_rescue_moves_the_selected_robot_only(tmp_path, config) -> None:
    app = make_app(tmp_path, config)
    key(pygame.K_n)
    key(pygame.K_TAB)
    app.frame()
    world = app.env.world
    before = [world.pose(k) for k in range(3)]
    key(pygame.K_r)
    app.frame()
    after = [world.pose(k) for k in range(3)]
    assert after[1] != before[1] and after[0] == before[0] and after[2] == before[2]
    assert app.session.envs[1].has_been_rescued and "RESCUED" in app.tags()


def test_exit_folds_every_episode_under_way(tmp_path, config) -> None:
    """Exit mid-episode: one ``interrupted`` row per robot, numbered after the table's
    episodes, the table saved with its count unchanged; Exit Without Save writes
    nothing."""
    app = make_app(tmp_path, config)
    app.session.run(CAP + 5)  # every robot finished an episode and is 5 steps into one
    finished = app.session.stats.episodes
    assert finished >= 3 and all(e.steps > 0 for e in app.envs)
    saved = (tmp_path / "q.qtable").read_bytes()
    app.exit(save=True)
    rows = list(log_rows(tmp_path / "log.csv"))
    outcomes = [r["outcome"] for r in rows]
    assert "interrupted" not in outcomes[:finished]
    assert outcomes[finished:] == ["interrupted"] * 3
    assert [int(r["episode"]) for r in rows] == list(range(finished + 3))
    assert (tmp_path / "q.qtable").read_bytes() != saved
    assert load_qtable(tmp_path / "q.qtable").meta["episodes"] == finished
    other = make_app(tmp_path / "nosave", config)
    other.session.run(CAP + 5)
    log = (tmp_path / "nosave" / "log.csv").read_bytes()
    table = (tmp_path / "nosave" / "q.qtable").read_bytes()
    other.exit(save=False)
    assert (tmp_path / "nosave" / "log.csv").read_bytes() == log
    assert (tmp_path / "nosave" / "q.qtable").read_bytes() == table


def test_greedy_shared_view_leaves_the_table_alone(tmp_path, config, capsys) -> None:
    q = tmp_path / "q.qtable"
    argv = ["--arena", "hallway", "--config", str(config), "--qtable", str(q)]
    assert main(["train", *argv, "--episodes", "2", "--quiet"]) == 0
    before = q.read_bytes()
    view = ["view", *argv, "--robots", "3", "--shared-arena", "--steps", "30"]
    assert main([*view, "--screenshot", str(tmp_path / "g.png")]) == 0
    assert q.read_bytes() == before
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("view: 3 robots sharing the arena, watching")
    assert out[-1].startswith("view: 30 ticks of 3 robots")


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        (["--robots", "3"], "needs --shared-arena"),
        (["--shared-arena"], "needs --robots N with N >= 2"),
        (["--shared-arena", "--robots", "1"], "needs --robots N with N >= 2"),
        (["--shared-arena", "--robots", "500"], "start area holds"),
        (["--robots", "0", "--shared-arena"], "--robots"),
    ],
)
def test_bad_combinations_one_line_exit_2(tmp_path, capsys, extra, words) -> None:
    argv = ["view", "--arena", "room", "--steps", "3"]
    argv += ["--qtable", str(tmp_path / "q.qtable"), "--log", str(tmp_path / "l.csv")]
    with pytest.raises(SystemExit) as exc:
        raise SystemExit(main([*argv, *extra]))
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "error" in err and words in err, err
    assert not (tmp_path / "q.qtable").exists()
