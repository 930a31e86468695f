"""The no-undo rule (``learner.no_undo``): the barred action is never chosen, greedy or
exploring; off, every choice and draw is the rule-free one."""

from __future__ import annotations

import numpy as np
import pytest

from koolio_pymunk.learning.algorithms import make_learner
from koolio_pymunk.learning.episodes import Episodes
from koolio_pymunk.store.config import LearnerConfig, load_config
from koolio_pymunk.store.qtable import KeywordLayout, QTable
from koolio_pymunk.task.action_rules import NONE, UNDO, barred
from koolio_pymunk.task.env import KoolioEnv

LEFT, RIGHT, FORWARD, REVERSE = 1, 2, 3, 4


def agent(no_undo: bool, algorithm: str = "q", seed: int = 0):
    table = QTable(KeywordLayout((("A", 4),)))
    cfg = LearnerConfig(algorithm=algorithm, no_undo=no_undo)
    return make_learner(table, cfg, np.random.default_rng(seed))


def test_undo_pairs() -> None:
    assert [barred(a) for a in range(5)] == [-1, RIGHT, LEFT, REVERSE, FORWARD]
    assert barred(NONE) == -1 and all(UNDO[UNDO[a]] == a for a in range(1, 5))


def test_greedy_takes_the_best_allowed_action() -> None:
    on, off = agent(True), agent(False)
    for a in (on, off):
        a.table.row(0)[:] = [-5.0, -3.0, -1.0, -2.0, -4.0]  # RotateRight best, then Forward
        a.epsilon = 0.0
        a.last = LEFT
    assert off.act(0) == RIGHT
    assert on.act(0) == FORWARD  # RotateRight would undo RotateLeft
    assert on.act(0) == RIGHT  # after Forward, RotateRight is allowed again
    on.last = FORWARD
    on.table.row(0)[:] = [-5.0, -3.0, -3.0, -9.0, -1.0]  # Reverse best: barred; a tie
    assert {on.act(0) for _ in range(40) if not on.__setattr__("last", FORWARD)} == {LEFT, RIGHT}


@pytest.mark.parametrize("algorithm", ["q", "qlambda"])
def test_exploring_never_undoes_and_tries_every_other_action(algorithm) -> None:
    a = agent(True, algorithm)
    a.epsilon = 1.0
    seen = set()
    for _ in range(400):
        a.last = FORWARD
        seen.add(a.act(0))
    assert seen == {0, LEFT, RIGHT, FORWARD}  # never Reverse, the other four all tried


def test_a_new_episode_and_a_rescue_free_the_next_action() -> None:
    a = agent(True)
    a.last = LEFT
    a.begin_episode(0, np.random.default_rng(1))
    assert a.last == NONE and a.bar == -1
    a.last = LEFT
    a.relocated(0)
    assert a.last == NONE


def test_no_episode_step_undoes_the_one_before() -> None:
    """Training episodes in the hallway: no two consecutive actions undo each other
    (rescues excepted), and the rule changes the run (the premise)."""
    actions = {}
    for no_undo in (True, False):
        cfg = load_config(overrides={"learner": {"no_undo": no_undo}})
        env = KoolioEnv("hallway", config=cfg, max_steps=200)
        learner = make_learner(QTable(env.layout), cfg.learner, None)
        chosen: list[tuple[int, int]] = []
        real_act = learner.act

        def act(state, real_act=real_act, chosen=chosen, learner=learner):
            before = learner.last
            action = real_act(state)
            chosen.append((before, action))
            return action

        learner.act = act
        loop = Episodes(env, learner, seed=2)
        for e in range(6):
            loop.begin(e)
            loop.run()
        actions[no_undo] = chosen
    undone = [(b, a) for b, a in actions[True] if b != NONE and barred(b) == a]
    assert undone == [] and len(actions[True]) > 300
    assert any(b != NONE and barred(b) == a for b, a in actions[False])  # the premise


def test_nothing_barred_draws_as_the_rule_off() -> None:
    """With nothing barred (an episode's first action) the rule's learner makes the draws
    and choices of the rule-free one, exploring and greedy, ties included."""
    a, b = agent(False, seed=5), agent(True, seed=5)
    for x in (a, b):
        x.epsilon = 0.5
        x.table.row(1)[:] = [-1.0, -1.0, -2.0, -1.0, -3.0]  # a three-way tie
    picks = []
    for k in range(200):
        b.last = NONE
        picks.append((a.act(k % 2), b.act(k % 2)))
    assert all(x == y for x, y in picks) and len({x for x, _ in picks}) == 5


# -- on the robot: robot_runtime.py repeats the rule ------------------------------------------
def _policy(no_undo: bool):
    from koolio_pymunk import robot_runtime as rt
    from koolio_pymunk.apps.export import policy_document
    from koolio_pymunk.store.config import Config
    from koolio_pymunk.store.run_identity import sensor_signature

    cfg = Config()
    cfg.learner.no_undo = no_undo
    env = KoolioEnv("hallway", config=cfg)
    table = QTable(env.layout, {"episodes": 3, "sensors": sensor_signature(cfg)})
    table.row(0)[:] = [-5.0, -3.0, -1.0, -2.0, -4.0]  # RotateRight best, then Forward
    doc = policy_document(table, cfg)
    return rt, doc, rt.Policy(doc)


def test_the_runtime_keeps_the_simulators_undo_pairs() -> None:
    from koolio_pymunk import robot_runtime as rt

    assert rt.UNDO == UNDO


def test_the_policy_file_carries_the_rule_and_the_robot_follows_it() -> None:
    import random

    rt, doc, policy = _policy(True)
    assert doc["learner"]["no_undo"] is True and policy.no_undo
    learner = rt.RobotLearner(policy, epsilon=0.0, seed=1, learn=False)
    learner.begin(policy.layout.decode(0)[0])
    assert learner.choose() == RIGHT  # nothing barred at the start
    learner.last = LEFT
    assert learner.choose() == FORWARD  # RotateRight would undo RotateLeft
    learner.moved(policy.layout.decode(0)[0])  # a rescue: free again
    assert learner.choose() == RIGHT
    rng = random.Random(3)
    assert {policy.act(0, 1.0, rng, last=FORWARD) for _ in range(300)} == {0, 1, 2, 3}
    _, doc_off, off = _policy(False)
    assert "no_undo" not in doc_off["learner"] and not off.no_undo
    assert off.act(0, 0.0, rng, last=LEFT) == RIGHT  # the rule off: the best action


def test_a_policy_with_a_bad_rule_value_is_one_line() -> None:
    rt, doc, _ = _policy(True)
    doc["learner"]["no_undo"] = "yes"
    with pytest.raises(rt.PolicyError, match=r"learner\.no_undo: must be true or false"):
        rt.Policy(doc)


def test_many_robots_learn_under_the_rule(tmp_path, capsys) -> None:
    """The step engine runs the rule for any number of robots (it was refused before the
    engine); the table records it."""
    from koolio_pymunk.apps.cli import main
    from koolio_pymunk.store.qtable import load_qtable
    from koolio_pymunk.store.run_identity import RunIdentity

    cfg = tmp_path / "n.yaml"
    cfg.write_text("learner: {no_undo: true}\n")
    argv = ["train", "--arena", "room", "--config", str(cfg), "--robots", "2", "--episodes", "3"]
    assert main([*argv, "--qtable", str(tmp_path / "t.qtable"), "--quiet"]) == 0
    assert RunIdentity.of_table(load_qtable(tmp_path / "t.qtable"), "t.qtable").no_undo


def test_a_table_is_read_only_under_the_rule_it_was_learned_with(tmp_path, capsys) -> None:
    """The table's header records the rule; eval and view refuse the other rule in one
    line, an export carries it into the policy, and a run without the rule records none
    (its header as before the rule existed)."""
    from koolio_pymunk.apps.cli import main
    from koolio_pymunk.store.qtable import load_qtable

    cfg = tmp_path / "n.yaml"
    cfg.write_text("episode: {max_steps: 60}\nlearner: {algorithm: q, no_undo: true}\n")
    plain = tmp_path / "p.yaml"
    plain.write_text("episode: {max_steps: 60}\nlearner: {algorithm: q, no_undo: false}\n")
    t, u = tmp_path / "t.qtable", tmp_path / "u.qtable"
    room = ["--arena", "room", "--episodes", "3"]
    assert main(["train", *room, "--config", str(cfg), "--qtable", str(t), "--quiet"]) == 0
    assert main(["train", *room, "--config", str(plain), "--qtable", str(u), "--quiet"]) == 0
    assert load_qtable(t).meta["algorithm"] == {"name": "q", "no_undo": True}
    assert "algorithm" not in load_qtable(u).meta
    capsys.readouterr()
    for table, config, words in (
        (t, plain, "table learned with the no-undo rule, this run chooses among all actions"),
        (u, cfg, "table learned choosing among all actions, this run has the no-undo rule"),
    ):
        for cmd in (["eval", "--episodes", "1"], ["view", "--greedy", "--steps", "1"]):
            argv = [*cmd, "--arena", "room", "--config", str(config), "--qtable", str(table)]
            assert main(argv) == 2
            err = capsys.readouterr().err
            assert f"{table}: learner.no_undo: {words}" in err and err.count("\n") == 1
    out = tmp_path / "t.json"
    assert main(["export", "--qtable", str(t), "--config", str(cfg), "--out", str(out)]) == 0
    assert '"no_undo": true' in out.read_text()
    assert main(["eval", "--arena", "room", "--config", str(cfg), "--qtable", str(out),
                 "--episodes", "1"]) == 0  # fmt: skip


def test_transfer_refuses_a_table_of_the_other_rule(tmp_path, capsys) -> None:
    from koolio_pymunk.apps.cli import main

    cfg = tmp_path / "n.yaml"  # the default learner without the rule (the default has it)
    cfg.write_text("episode: {max_steps: 40}\nlearner: {no_undo: false}\n")
    t = tmp_path / "t.qtable"
    argv = ["train", "--episodes", "2", "--config", str(cfg), "--qtable", str(t), "--quiet"]
    assert main(argv) == 0
    capsys.readouterr()
    out = tmp_path / "out"
    argv = ["transfer", "--qtable", str(t), "--dr-qtable", str(t), "--out", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"{t}: learner.no_undo: table learned choosing among all actions" in err
    assert err.count("\n") == 1 and not out.exists()
