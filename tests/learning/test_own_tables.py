"""``train --tables each``: robots sharing an arena, each learning into its own rows of the
table (the keyword leads with the robot's index), on the engine as in the Python loop."""

from __future__ import annotations

import agreement
import pytest
from inputs import expect_error, run

from koolio_pymunk.learning.algorithms import make_learner
from koolio_pymunk.learning.episodes import Robots
from koolio_pymunk.store.config import load_config
from koolio_pymunk.store.keyword import own_tables, robot_offset, table_robots
from koolio_pymunk.store.qtable import QTable, load_qtable
from koolio_pymunk.task.shared_arena import SharedArena


def _robot_of(layout, key: int) -> int:
    return key >> (robot_offset(layout, 1).bit_length() - 1)


def test_each_robot_learns_only_into_its_own_rows() -> None:
    """In the Python loop, every state robot ``k``'s learner acts in and learns from is one
    of its own rows, and every robot's rows are written (none left to the others)."""
    cfg = load_config(overrides={"episode": {"max_steps": 60}})
    envs = SharedArena.envs(3, "hallway", cfg)
    table = QTable(own_tables(envs[0].layout, 3), {}, cfg.learner.q_init)
    agents = [make_learner(table, cfg.learner, None) for _ in envs]
    seen: list[tuple[int, int]] = []
    for k, agent in enumerate(agents):
        act, observe = agent.act, agent.observe

        def watched_act(state, k=k, act=act):
            seen.append((k, state))
            return act(state)

        def watched_observe(state, action, reward, nxt, terminal, k=k, observe=observe):
            seen.extend([(k, state), (k, nxt)])
            return observe(state, action, reward, nxt, terminal)

        agent.act, agent.observe = watched_act, watched_observe
    loop = Robots(envs, agents, seed=0)
    for r in range(3):
        loop.begin(r, r)
    for e in range(3, 12):
        r = loop.advance()
        loop.begin(r, e)
    assert len(seen) > 500
    assert all(_robot_of(table.layout, s) == k for k, s in seen)
    assert {_robot_of(table.layout, key) for key in table.rows} == {0, 1, 2}


@pytest.mark.parametrize(
    ("world", "overrides", "n"),
    [
        (None, {}, 4),
        ("koolio-real", {"learner": {"algorithm": "q", "no_undo": False}}, 3),
    ],
)
def test_own_tables_on_the_engine_are_the_python_ticks(world, overrides, n) -> None:
    """The engine gives each robot its own rows exactly as the Python loop does: log rows,
    the table, every robot's state and generators, bit for bit."""
    r = agreement.compare_robots("hallway", world, 30, 1, n, overrides, 300, True, True)
    assert r["steps"] > 1000
    assert (r["mismatches"], r["first_mismatch"]) == (0, -1)


def test_train_eval_export_and_view_a_table_of_own_rows(here, capsys) -> None:
    """``train --tables each`` writes a table whose keyword leads with the robot; ``eval``
    and ``view`` play it with as many robots in the arena; ``export --robot K`` writes
    robot K's rows as one robot's table, which eval scores alone; ``info`` says so."""
    argv = ["train", "--robots", "3", "--shared-arena", "--tables", "each", "--episodes", "12"]
    checks = ["--eval-every", "6", "--eval-episodes", "3"]
    code, out, _ = run(capsys, *argv, *checks, "--config", "tiny.yaml")
    assert code == 0
    assert "koolio-pm eval --config tiny.yaml --robots 3 --shared-arena" in out  # how to score it
    table = load_qtable(here / "runs" / "hallway.qtable")
    assert table.layout.fields[0] == ("Robot", 3) and table_robots(table.layout) == 3
    assert {_robot_of(table.layout, key) for key in table.rows} == {0, 1, 2}
    best = load_qtable(here / "runs" / "hallway.best.qtable")  # checked with its 3 robots
    assert best.layout == table.layout and best.meta["best"]["episode"] in (6, 12)
    assert "check at episode 12: goal rate" in out
    eval_argv = ["eval", "--robots", "3", "--shared-arena", "--episodes", "6", "--config",
                 "tiny.yaml"]  # fmt: skip
    code, out, _ = run(capsys, *eval_argv)
    assert code == 0 and "by robot in the shared arena: robot 0 (goal 311)" in out
    view = ["view", "--robots", "3", "--shared-arena", "--greedy", "--episodes", "3",
            "--config", "tiny.yaml"]  # fmt: skip
    assert run(capsys, *view)[0] == 0
    code, out, _ = run(capsys, "export", "--qtable", "runs/hallway.qtable", "--robot", "1",
                       "--out", "one.qtable")  # fmt: skip
    assert code == 0
    one = load_qtable(here / "one.qtable")
    low = robot_offset(table.layout, 1) - 1
    assert one.layout.fields == table.layout.fields[1:]
    assert one.rows == {
        k & low: v for k, v in table.rows.items() if _robot_of(table.layout, k) == 1
    }
    code, out, _ = run(capsys, "eval", "--qtable", "one.qtable", "--episodes", "4",
                       "--config", "tiny.yaml")  # fmt: skip
    assert code == 0 and "greedy goal rate" in out
    code, out, _ = run(capsys, "info", "--qtable", "runs/hallway.qtable")
    assert "holds each of 3 robots' own rows" in out and "not a table of" not in out


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["train", "--robots", "3", "--tables", "each"], ["--tables each", "--shared-arena"]),
        (["eval", "--qtable", "runs/hallway.qtable"], ["own rows of 3 robots", "--robots 3"]),
        (
            ["eval", "--robots", "2", "--shared-arena", "--qtable", "runs/hallway.qtable"],
            ["own rows of 3 robots", "--robots 3 --shared-arena"],
        ),
        (
            ["train", "--robots", "3", "--shared-arena", "--episodes", "20"],
            ["own rows of 3 robots", "--tables each"],
        ),
        (
            ["export", "--qtable", "runs/hallway.qtable", "--out", "p.json"],
            ["own rows of 3 robots", "export --robot K"],
        ),
        (
            ["export", "--qtable", "runs/hallway.qtable", "--robot", "3", "--out", "p.json"],
            ["--robot", "no robot 3's own rows", "robots 0..2"],
        ),
        (
            ["view", "--greedy", "--episodes", "1", "--qtable", "runs/hallway.qtable"],
            ["own rows of 3 robots", "--robots 3 --shared-arena"],
        ),
    ],
)
def test_a_table_of_own_rows_used_otherwise_is_one_line(here, capsys, argv, words) -> None:
    made = ["train", "--robots", "3", "--shared-arena", "--tables", "each", "--episodes", "6"]
    assert run(capsys, *made, "--config", "tiny.yaml", "--quiet")[0] == 0
    expect_error(capsys, here, [*argv, "--config", "tiny.yaml"], *words)


def test_own_rows_whose_keyword_would_not_fit_64_bits_are_one_line(here, capsys) -> None:
    """12 cameras make a 63-bit keyword; 4 robots' index needs 2 more bits."""
    cams = ", ".join(["0.0"] * 12)
    (here / "wide.yaml").write_text(f"sensors: {{camera: {{camera_sensors_deg: [{cams}]}}}}\n")
    argv = ["train", "--robots", "4", "--shared-arena", "--tables", "each", "--config", "wide.yaml"]
    expect_error(capsys, here, argv, "--tables each", "would need 65 bits", "must fit 64")


def test_a_shared_table_is_not_resumed_as_own_rows(here, capsys) -> None:
    shared = ["train", "--robots", "3", "--shared-arena", "--episodes", "6", "--quiet"]
    assert run(capsys, *shared, "--config", "tiny.yaml")[0] == 0
    argv = ["train", "--robots", "3", "--shared-arena", "--tables", "each", "--episodes", "9"]
    expect_error(capsys, here, [*argv, "--config", "tiny.yaml"], "one table all robots share")


def test_export_of_one_robot_splits_dyna_models_by_robot(here, capsys) -> None:
    """A Dyna-Q table of own rows: ``export --robot K`` keeps the model's pairs of robot
    K's states (first-seen order), their next states under the plain keyword."""
    from koolio_pymunk.store.dyna_model import SECTION

    (here / "dyna.yaml").write_text("episode: {max_steps: 40}\nlearner: {algorithm: dyna}\n")
    made = ["train", "--robots", "2", "--shared-arena", "--tables", "each", "--episodes", "6"]
    assert run(capsys, *made, "--config", "dyna.yaml", "--quiet")[0] == 0
    table = load_qtable(here / "runs" / "hallway.qtable")
    whole = table.sections[SECTION]
    low = robot_offset(table.layout, 1) - 1
    for k in (0, 1):
        out = f"r{k}.qtable"
        argv = ["export", "--qtable", "runs/hallway.qtable", "--robot", str(k), "--out", out]
        assert run(capsys, *argv, "--config", "dyna.yaml")[0] == 0
        one = load_qtable(here / out)  # its model checked against the plain keyword
        its = one.sections[SECTION]
        mine = [i for i, (s, _) in enumerate(whole.pairs) if _robot_of(table.layout, s) == k]
        assert mine and its.pairs == [(whole.pairs[i][0] & low, whole.pairs[i][1]) for i in mine]
        assert [[o[0] for o in outs] for outs in its.outcomes] == [
            [o[0] & low for o in whole.outcomes[i]] for i in mine
        ]


def test_own_rows_start_from_a_shared_table_with_init_qtable(here, capsys) -> None:
    """``--tables each --init-qtable SHARED``: every robot's own rows start as the shared
    table's rows (and its Dyna-Q model as the shared model), then learn apart; a table of
    own rows does not start a shared run or one of another number of robots."""
    from koolio_pymunk.store.dyna_model import SECTION

    (here / "dyna.yaml").write_text("episode: {max_steps: 40}\nlearner: {algorithm: dyna}\n")
    two = ["--robots", "2", "--shared-arena", "--config", "dyna.yaml"]
    assert run(capsys, "train", *two, "--episodes", "6", "--quiet")[0] == 0
    shared = load_qtable(here / "runs" / "hallway.qtable")
    each = ["train", *two, "--tables", "each", "--qtable", "o.qtable", "--log", "o.csv"]
    code, out, _ = run(capsys, *each, "--episodes", "6", "--init-qtable", "runs/hallway.qtable")
    assert code == 0 and f"from runs/hallway.qtable ({2 * len(shared)} states" in out
    own = load_qtable(here / "o.qtable")
    assert table_robots(own.layout) == 2 and own.meta["episodes"] == 6
    for k in (0, 1):
        mine = own.robot_table(k)
        assert mine.rows == shared.rows and mine.sections[SECTION] == shared.sections[SECTION]
    assert run(capsys, *each, "--episodes", "9", "--quiet")[0] == 0
    after = load_qtable(here / "o.qtable")
    assert after.meta["episodes"] == 9 and after.robot_table(0).rows != after.robot_table(1).rows
    three = ["train", "--robots", "3", "--shared-arena", "--tables", "each"]
    for argv, words in (
        ([*three, "--qtable", "t.qtable", "--log", "t.csv"], ["own rows of 2 robots"]),
        (["train", *two, "--qtable", "s.qtable", "--log", "s.csv"], ["own rows of 2 robots"]),
    ):
        argv = [*argv, "--config", "dyna.yaml", "--init-qtable", "o.qtable"]
        expect_error(capsys, here, argv, *words)


def test_the_window_learns_own_rows_with_tables_each(here, capsys) -> None:
    """``view --robots N --shared-arena --tables each`` makes a new table of each robot's
    own rows, which ``train --tables each`` resumes; a shared table is not learned on as
    own rows in the window either."""
    two = ["--robots", "2", "--shared-arena", "--config", "tiny.yaml"]
    view = ["view", *two, "--tables", "each", "--episodes", "4", "--qtable", "v.qtable"]
    code, out, _ = run(capsys, *view)
    assert code == 0 and "learning into v.qtable (each robot its own rows), a new table" in out
    table = load_qtable(here / "v.qtable")
    assert table_robots(table.layout) == 2 and table.meta["episodes"] == 4
    assert {_robot_of(table.layout, key) for key in table.rows} == {0, 1}
    train = ["train", *two, "--tables", "each", "--episodes", "6", "--qtable", "v.qtable"]
    assert run(capsys, *train, "--quiet")[0] == 0
    assert load_qtable(here / "v.qtable").meta["episodes"] == 6
    assert run(capsys, "view", *two, "--episodes", "2", "--qtable", "s.qtable")[0] == 0
    learn = ["view", *two, "--tables", "each", "--learn", "--episodes", "2", "--qtable", "s.qtable"]
    expect_error(capsys, here, learn, "one table all robots share", "--tables each")
