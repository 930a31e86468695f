"""robot_runtime.py: standard library only, exact round trips, same maths and log as train."""

from __future__ import annotations

import json
import os
import random
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from koolio_pymunk import robot_runtime as rt
from koolio_pymunk.apps.export import policy_document, write_policy
from koolio_pymunk.learning.episodes import EpisodeResult
from koolio_pymunk.learning.qlearning import QLearner
from koolio_pymunk.store.config import (
    Config,
    LearnerConfig,
    RewardConfig,
    SensorConfig,
    state_fields,
)
from koolio_pymunk.store.episode_log import LOG_FIELDS, LogWriter
from koolio_pymunk.store.keyword import KeywordLayout
from koolio_pymunk.store.qtable import QTable
from koolio_pymunk.store.run_identity import sensor_signature
from koolio_pymunk.task.rules import judge

RUNTIME = Path(rt.__file__)


def _table(n_states: int = 200, seed: int = 0) -> QTable:
    """A table with random (awkward) float values over valid states of the paper layout."""
    layout = KeywordLayout(tuple(state_fields(SensorConfig())))
    rng = np.random.default_rng(seed)
    table = QTable(layout, {"sensors": sensor_signature(Config()), "episodes": 7})
    for _ in range(n_states):
        codes = [int(rng.integers(lv)) for _, lv in layout.fields]
        table.row(layout.state_key(codes))[:] = (rng.normal(size=5) * 37.1).tolist()
    return table


@pytest.fixture
def policy_file(tmp_path) -> Path:
    path = tmp_path / "policy.json"
    write_policy(policy_document(_table()), path)
    return path


def test_runtime_imports_with_the_standard_library_only(policy_file, tmp_path):
    """An isolated interpreter without site-packages (-I -S) loads and runs the file."""
    script = f"""
import importlib.util, json, random, sys
spec = importlib.util.spec_from_file_location("robot_runtime", {str(RUNTIME)!r})
rt = importlib.util.module_from_spec(spec)
sys.modules["robot_runtime"] = rt
spec.loader.exec_module(rt)
p = rt.Policy.load({str(policy_file)!r})
codes = p.encode([30.0] * 8, [None, 50.0, 200.0], [None] * 3)
s = p.state_key(codes)
learner = rt.RobotLearner(p, save_path={str(tmp_path / "saved.json")!r},
                          log_path={str(tmp_path / "robot.csv")!r}, seed=1, goal="302")
learner.begin(codes)
a = learner.choose()
learner.step(a, -1.0, codes, False)
learner.end("truncated")
foreign = sorted(m for m in sys.modules
                 if m.split(".")[0] not in sys.stdlib_module_names
                 and m not in ("__main__", "robot_runtime"))
print(json.dumps({{"codes": codes, "foreign": foreign, "numpy": "numpy" in sys.modules,
                  "path": [x for x in sys.path if "site-packages" in x]}}))
"""
    out = subprocess.run(
        [sys.executable, "-I", "-S", "-c", script],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout)
    assert result == {
        "codes": [2, 1, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2],
        "foreign": [],
        "numpy": False,
        "path": [],
    }
    assert (tmp_path / "saved.json").exists() and (tmp_path / "robot.csv").exists()
    # and the source names no third-party or package import
    src = RUNTIME.read_text()
    assert "import numpy" not in src and "koolio_pymunk" not in src.split('"""', 2)[2]


def test_round_trip_load_update_save_load_is_exact(policy_file, tmp_path):
    p = rt.Policy.load(str(policy_file))
    rng = random.Random(4)
    states = list(p.rows)
    for _ in range(500):
        s, s2 = rng.choice([*states, 0]), rng.choice([*states, 1])
        p.update(s, rng.randrange(5), rng.uniform(-10, 10) / 3, s2, rng.random() < 0.1)
    p.episodes += 1
    out = tmp_path / "saved.json"
    p.save(str(out))
    q = rt.Policy.load(str(out))
    assert q.rows == p.rows and len(q.rows) == len(states) + 1
    assert (q.episodes, q.q_init, q.sensors, q.learner, q.rewards) == (
        p.episodes,
        p.q_init,
        p.sensors,
        p.learner,
        p.rewards,
    )
    q.save(str(tmp_path / "again.json"))
    assert (tmp_path / "again.json").read_text() == out.read_text()


def test_save_is_atomic_and_keeps_a_backup(policy_file):
    before = policy_file.read_text()
    p = rt.Policy.load(str(policy_file))
    p.update(next(iter(p.rows)), 0, 1.0, 0, True)
    p.save(str(policy_file))
    assert Path(str(policy_file) + ".bak").read_text() == before
    assert policy_file.read_text() != before
    assert sorted(x.name for x in policy_file.parent.iterdir()) == [
        "policy.json",
        "policy.json.bak",
    ]


def test_update_is_bit_identical_to_the_simulators_learner(policy_file):
    table = _table()
    p = rt.Policy.load(str(policy_file))
    assert p.rows == table.rows
    agent = QLearner(table, LearnerConfig(alpha=0.2, gamma=0.97), np.random.default_rng(0))
    rng = random.Random(9)
    states = [*list(table.rows), 99, 100]
    for _ in range(2000):
        args = (rng.choice(states), rng.randrange(5), rng.uniform(-20, 20), rng.choice(states))
        term = rng.random() < 0.05
        assert p.update(*args, term, alpha=0.2, gamma=0.97) == agent.update(*args, term)
    assert p.rows == table.rows


def test_judge_matches_the_simulators_rules(policy_file):
    p = rt.Policy.load(str(policy_file))
    for action in range(5):
        for goal in (None, 10.0, 35.99, 36.0, 500.0):
            for eow in (False, True):
                for sonar0 in (5.0, 6.0, 100.0):
                    sonar = [sonar0] + [80.0] * 7
                    event, reward, term = p.judge(action, sonar, [goal, None, None], eow)
                    j = judge(
                        action, goal is not None and goal < 36, eow, sonar0 < 6, RewardConfig()
                    )
                    assert (event, reward, term) == (j.event, j.reward, j.terminated)


def test_episode_log_has_the_train_log_format(policy_file, tmp_path):
    p = rt.Policy.load(str(policy_file))
    learner = rt.RobotLearner(p, log_path=str(tmp_path / "robot.csv"), epsilon=0.05, goal="304")
    codes = (0,) * 12
    learner.begin(codes)
    for k in range(3):
        learner.step(learner.choose(), -1.25, codes, k == 2, bump=k == 1)
    learner.end("goal")
    sim = tmp_path / "sim.csv"
    w = LogWriter(sim)
    w.write(EpisodeResult(7, -3.75, 3, 1, "goal", False, 0.05, "304"))
    w.close()
    assert rt.LOG_FIELDS == LOG_FIELDS
    assert (tmp_path / "robot.csv").read_text() == sim.read_text()
    assert p.episodes == 8


def test_greedy_learner_does_not_update_or_save(policy_file, tmp_path):
    p = rt.Policy.load(str(policy_file))
    before = {k: list(v) for k, v in p.rows.items()}
    learner = rt.RobotLearner(p, save_path=str(tmp_path / "x.json"), learn=False)
    assert learner.epsilon == 0.0
    state = next(iter(p.rows))
    learner.begin(p.layout.decode(state << 3)[0])
    a = learner.choose()
    assert a in p.greedy_actions(state)
    learner.step(a, 50.0, p.layout.decode(state << 3)[0], True)
    learner.end("goal")
    assert p.rows == before and not (tmp_path / "x.json").exists()


def test_moved_continues_from_the_new_state_without_an_update(policy_file, tmp_path):
    """A rescue by hand: the episode goes on from the new state, nothing is learned from
    the move, and the log row says rescued."""
    p = rt.Policy.load(str(policy_file))
    a_state, b_state = sorted(p.rows)[:2]
    a_codes, b_codes = p.layout.decode(a_state << 3)[0], p.layout.decode(b_state << 3)[0]
    learner = rt.RobotLearner(p, log_path=str(tmp_path / "robot.csv"), seed=1)
    with pytest.raises(rt.PolicyError, match="moved: call begin"):
        learner.moved(b_codes)
    learner.begin(a_codes)
    learner.step(3, -0.5, a_codes, False)
    before = {k: list(v) for k, v in p.rows.items()}
    learner.moved(b_codes)
    assert learner.state == b_state and p.rows == before
    learner.step(3, -0.5, a_codes, False)  # the update is of the state moved to
    assert p.rows[b_state][3] != before[b_state][3] and p.rows[a_state] == before[a_state]
    learner.end("truncated")
    row = (tmp_path / "robot.csv").read_text().splitlines()[1].split(",")
    assert row[4:6] == ["truncated", "1"]


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda p: p.encode([1.0] * 7, [None] * 3, [None] * 3), "sonar: expected 8 readings"),
        (lambda p: p.encode([1.0] * 8, [None, "x", 1], [None] * 3), "goal_cam[1]: not a number"),
        (lambda p: p.encode([float("nan")] * 8, [None] * 3, [None] * 3), "sonar[0]: not a"),
        (lambda p: p.state_key((0, 1)), "state: expected 12 codes, got 2"),
        (lambda p: p.update(0, 5, 1.0, 0, True), "action: 5 is not an action (0..4)"),
        (lambda p: p.learner.clear() or p.update(0, 1, 1.0, 0, True), "learner.alpha: not in"),
    ],
)
def test_bad_arguments_raise_policy_errors(policy_file, call, message):
    p = rt.Policy.load(str(policy_file))
    with pytest.raises(rt.PolicyError) as info:
        call(p)
    assert message in str(info.value)


def test_summary_command(policy_file, capsys):
    assert rt.main([str(policy_file)]) == 0
    out = capsys.readouterr().out
    assert "koolio-policy version 1, 200 states, 7 episodes" in out
    assert "GoalCam0<<25" in out and "Sonar7<<3 | Action" in out
    assert rt.main([str(policy_file) + ".missing"]) == 2


def test_the_sonar_pings_travel_to_the_robot(tmp_path, capsys):
    """A policy exported with ``sensors.sonar.pings: 3`` tells the robot's driver to read
    each sonar as the median of three pings; one exported with 1 says nothing (the file
    is as before); a bad count is one line."""
    cfg = Config()
    plain = policy_document(_table(), cfg=cfg)
    assert "sonar_pings" not in plain["encoding"]
    cfg.sensors.sonar.pings = 3
    doc = policy_document(_table(), cfg=cfg)
    assert doc["encoding"]["sonar_pings"] == 3
    write_policy(doc, tmp_path / "p.json")
    p = rt.Policy.load(str(tmp_path / "p.json"))
    assert p.encoder.sonar_pings == 3
    assert rt.Encoder.median([118.0, 3.5, 40.25]) == 40.25
    assert p.to_document()["encoding"] == doc["encoding"]  # kept by the robot's saves
    assert rt.main([str(tmp_path / "p.json")]) == 0
    assert "each sonar read as the median of 3 pings" in capsys.readouterr().out
    for bad in (2, 0, 11, "3", True):
        doc["encoding"]["sonar_pings"] = bad
        with pytest.raises(rt.PolicyError, match=r"encoding\.sonar_pings: must be odd, 1 to 9"):
            rt.Policy(json.loads(json.dumps(doc)), "p.json")
    with pytest.raises(rt.PolicyError, match="2 pings"):
        rt.Encoder.median([1.0, 2.0])


def test_the_check_refuses_what_would_fail_on_the_robot(tmp_path, capsys):
    """``python robot_runtime.py POLICY`` is the check before the robot runs: a policy
    without a reward it needs fails there, not at the goal mid-episode; an action given
    to ``encode`` is checked (a bad one made another valid state); ``--help`` is help
    (API audit)."""
    doc = policy_document(_table(), cfg=Config())
    del doc["rewards"]["goal"]
    path = tmp_path / "p.json"
    path.write_text(json.dumps(doc))
    assert rt.main([str(path)]) == 2
    assert capsys.readouterr().err == (
        f"robot_runtime: error: {path}: rewards.goal: missing (the rewards of goal, "
        "end_of_world, bump, stop, reverse, turn, forward)\n"
    )
    cfg = Config()
    cfg.sensors.memory.goal_camera = True
    cfg.sensors.memory.previous_action = True
    layout = KeywordLayout(tuple(state_fields(cfg.sensors)))
    mem_table = QTable(layout, {"sensors": sensor_signature(cfg), "episodes": 0})
    mem_doc = policy_document(mem_table, cfg=cfg)
    p = rt.Policy(json.loads(json.dumps(mem_doc)), "m.json")
    m = p.new_memory()
    p.encode([100.0] * 8, [None] * 3, [None] * 3, memory=m)
    for bad in (9, 5, -1, 2.0, True):
        with pytest.raises(rt.PolicyError, match=r"^action: .* is not an action \(0\.\.4"):
            p.encode([100.0] * 8, [None] * 3, [None] * 3, memory=m, action=bad)
    p.encode([100.0] * 8, [None] * 3, [None] * 3, memory=m, action=4)
    assert rt.main(["--help"]) == 0
    out, err = capsys.readouterr()
    assert out.startswith("usage: python robot_runtime.py [--] POLICY\n") and err == ""
    assert rt.main([]) == 2
    assert capsys.readouterr().err.startswith("robot_runtime: error: usage: ")


@pytest.mark.parametrize(
    ("edit", "problem"),
    [
        (
            lambda d: d["greedy"][0].update(action=9),
            "greedy[0].action: action 9 is not an action (0..4)",
        ),
        (lambda d: d["layout"].update(total_bits=99), "layout.total_bits: 99, expected 27"),
        (lambda d: d.update(n_states=7), "n_states: 7, expected 200 (the states of entries)"),
    ],
)
def test_both_readers_refuse_a_policy_whose_derived_items_disagree(tmp_path, capsys, edit, problem):
    """The robot's check (``python robot_runtime.py``, standard library only) and the
    package's loader (``koolio-pm export``/``eval``/``info --qtable``) refuse the same
    file in the same words (audit: all three loaded without complaint)."""
    from inputs import expect_error

    doc = policy_document(_table())
    assert doc["n_states"] == 200  # the premise of the expected counts
    edit(doc)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    p = subprocess.run(
        [sys.executable, "-I", "-S", str(RUNTIME), str(bad)],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert (p.returncode, p.stdout) == (2, "")
    assert p.stderr == f"robot_runtime: error: {bad}: {problem}\n"
    for argv in (["export", "--out", str(tmp_path / "o.json")], ["info"]):
        line = expect_error(capsys, tmp_path, [*argv, "--qtable", str(bad)])
        assert line == f"koolio-pm: error: {bad}: {problem}"


def test_a_reader_that_leaves_early_ends_the_check_quietly(policy_file):
    """``python robot_runtime.py policy.json | head -2``: the reader closes the pipe, and
    the check ends as ``koolio-pm`` does, exit 0 and nothing on stderr (audit: a
    BrokenPipeError traceback). The pipe is closed before the process starts, so every
    write to it fails, at once."""
    root = Path(__file__).resolve().parent.parent
    env = {**os.environ, "PYTHONPATH": str(root)}
    for argv in (
        [sys.executable, "-I", "-S", str(RUNTIME), str(policy_file)],
        [sys.executable, "-I", "-S", str(RUNTIME), "--help"],
        [sys.executable, "-m", "koolio_pymunk", "info"],  # the behaviour it matches
    ):
        read, write = os.pipe()
        os.close(read)
        try:
            p = subprocess.run(
                argv, stdout=write, stderr=subprocess.PIPE, text=True, timeout=60, env=env
            )
        finally:
            os.close(write)
        assert (p.returncode, p.stderr) == (0, ""), (argv, p.stderr)
    p = subprocess.run(  # the premise: the same check, read to the end, prints 4 lines
        [sys.executable, "-I", "-S", str(RUNTIME), str(policy_file)],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert p.returncode == 0 and len(p.stdout.splitlines()) == 4, p.stdout
