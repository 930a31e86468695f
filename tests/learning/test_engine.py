"""The step engine (learning/engine.py) held to its reference, the Python loop
(learning/episodes.py: ``Episodes``, ``Robots``), for one robot and for several."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from koolio_pymunk.learning import engine
from koolio_pymunk.learning.algorithms import make_learner
from koolio_pymunk.learning.engine import Engine, robots, trace_capacity
from koolio_pymunk.learning.episodes import INTERRUPTED, Robots
from koolio_pymunk.learning.evaluation import evaluate
from koolio_pymunk.learning.training import train
from koolio_pymunk.store import run_identity
from koolio_pymunk.store.config import load_config
from koolio_pymunk.store.episode_log import LOG_FIELDS, log_rows
from koolio_pymunk.store.qtable import QTable, QTableStore, load_qtable
from koolio_pymunk.task.env import KoolioEnv

_spec = importlib.util.spec_from_file_location(
    "agreement", Path(__file__).resolve().parents[2] / "tools" / "agreement.py"
)
agreement = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(agreement)

#: Rescues at almost every bump after a few steps: the rescue path runs often.
EAGER_RESCUE = {
    "rescue": {"auto_rescue_toggle": True, "max_steps_before_rescue": 3, "rescue_chance": 0.7}
}
#: Q(lambda) as configured by default, and with traces that live hundreds of steps.
QLAMBDA = {"learner": {"algorithm": "qlambda"}}
LONG_TRACES = {"learner": {"algorithm": "qlambda", "trace_decay": 1.0, "trace_cutoff": 1e-6}}
#: The no-undo rule, with one-step Q and with Q(lambda) (its cut over the allowed actions).
NO_UNDO = {"learner": {"no_undo": True}}
NO_UNDO_QLAMBDA = {"learner": {"algorithm": "qlambda", "no_undo": True, "trace_decay": 0.7}}
#: The ``paper-memory`` profile's sensors (side cameras at +-90, the goal camera and the
#: action in the state), and every memory field with sightings forgotten after 3 steps.
PAPER_MEMORY = {
    "sensors": {
        "camera": {"camera_sensors_deg": [0.0, 90.0, -90.0]},
        "memory": {"goal_camera": True, "previous_action": True},
    }
}
EVERY_MEMORY = {
    "sensors": {
        "memory": {
            "goal_camera": True,
            "eow_camera": True,
            "previous_action": True,
            "forget_after": 3,
            "goal_bearing": True,
        }
    }
}
#: The paper's cameras with the goal's bearing in the state (turns of 30 and 45 degrees).
PAPER_BEARING = {
    "sensors": {
        "camera": {"camera_sensors_deg": [0.0, 90.0, -90.0]},
        "memory": {"goal_bearing": True},
    }
}
BEARING_45 = {**PAPER_BEARING, "actions": {"rotate_action_arc_deg": 45.0}}
#: koolio-real with the sensor models it leaves off or rare made frequent: crosstalk,
#: misread plates, a strong beam model.
EVERY_SENSOR_MODEL = {
    "realism": {
        "sonar": {"crosstalk": 0.3, "z_hit": 0.7, "z_short": 0.1, "z_max": 0.1, "z_rand": 0.1},
        "camera": {"misread": 0.4, "detect_far": 0.3},
    }
}
GAUSSIAN = {"sensors": {"noise": {"model": "gaussian"}}}

CASES = [
    ("hallway", None, {}),
    ("hallway", "koolio-real", {}),
    ("hallway", "koolio-real-dr", {}),
    ("room", None, EAGER_RESCUE),
    ("obstacles", "koolio-real", EAGER_RESCUE),
    ("hallway", None, GAUSSIAN),
    ("hallway", "koolio-real", GAUSSIAN),
    ("room", None, {"sensors": {"backend": "cone"}}),
    ("hallway", None, QLAMBDA),
    ("room", None, {**QLAMBDA, **EAGER_RESCUE}),
    ("hallway", "koolio-real", LONG_TRACES),
    ("hallway", None, PAPER_MEMORY),
    ("room", "koolio-real", {**EVERY_MEMORY, **EAGER_RESCUE}),
    ("hallway", None, {**PAPER_MEMORY, **QLAMBDA}),
    ("hallway", None, PAPER_BEARING),
    ("hallway", "koolio-real", BEARING_45),
    ("hallway", "koolio-real", EVERY_SENSOR_MODEL),
    ("hallway", None, NO_UNDO),
    ("room", "koolio-real", {**NO_UNDO_QLAMBDA, **EAGER_RESCUE}),
    ("hallway", None, {**NO_UNDO_QLAMBDA, **PAPER_MEMORY}),
]


@pytest.mark.parametrize(("arena", "world", "overrides"), CASES)
def test_one_robot_on_the_engine_is_the_python_loop(arena, world, overrides):
    """Row, table and the robot's pose, state, memory, generators and learner after every
    episode, bit for bit."""
    r = agreement.compare_robots(arena, world, 20, 3, 1, overrides, max_steps=250)
    assert r["steps"] > 800  # the premise: episodes of some length ran
    assert (r["mismatches"], r["first_mismatch"]) == (0, -1)


@pytest.mark.parametrize(
    ("arena", "world", "overrides", "n"),
    [
        ("hallway", None, {}, 3),
        ("room", "koolio-real-dr", EAGER_RESCUE, 4),
        ("obstacles", "koolio-real", {**LONG_TRACES, **EAGER_RESCUE}, 3),
        ("room", "koolio-real", {**EVERY_MEMORY, **NO_UNDO_QLAMBDA, **EAGER_RESCUE}, 5),
        ("hallway", None, {**PAPER_MEMORY, **QLAMBDA}, 2),
    ],
)
def test_several_robots_on_the_engine_are_the_python_ticks(arena, world, overrides, n):
    """N robots in tick order, one table: the engine against ``episodes.Robots``."""
    r = agreement.compare_robots(arena, world, 24, 5, n, overrides, max_steps=250)
    assert r["steps"] > 800
    assert (r["mismatches"], r["first_mismatch"]) == (0, -1)


def test_the_comparison_catches_a_difference(monkeypatch):
    """The agreement check can fail: an engine whose learner's alpha is off by one ulp
    differs from the Python loop."""
    real = Engine.__init__

    def off(self, *a, **k):
        real(self, *a, **k)
        alpha = self.learner[0]
        self.learner = (np.nextafter(alpha, 1.0), *self.learner[1:])

    monkeypatch.setattr(Engine, "__init__", off)
    r = agreement.compare_robots("room", None, 6, 3, 2, EAGER_RESCUE, max_steps=100)
    assert r["mismatches"] > 0


def test_rescues_and_truncations_happen_in_the_compared_runs():
    """The premise of the eager-rescue cases: rescues and step caps occur."""
    env = KoolioEnv("room", config=load_config(overrides=EAGER_RESCUE), max_steps=250)
    loop = robots(env, [make_learner(QTable(env.layout), env.config.learner, None)], seed=3)
    results = []
    for e in range(6):
        loop.begin(0, e)
        loop.advance()
        results.append(loop.result(0))
    assert sum(r.rescued for r in results) >= 1
    assert any(r.outcome == "truncated" for r in results)


def _train_files(tmp_path, name, world, overrides, compiled, robots_=1, episodes=8):
    cfg = load_config(name, world=world, overrides=overrides)
    env = KoolioEnv("hallway", config=cfg, max_steps=300)
    tag = f"{name}-{world}-{compiled}-{robots_}"
    table, log = tmp_path / f"{tag}.qtable", tmp_path / f"{tag}.csv"
    res = train(env, QTableStore(table), episodes, 1, log, report=None, compiled=compiled,
                robots=robots_)  # fmt: skip
    assert res.steps > 300
    assert (res.python_reason is None) == compiled
    backup = table.with_name(table.name + ".bak")
    return table.read_bytes(), log.read_bytes(), backup.read_bytes()


@pytest.mark.parametrize(
    ("name", "world", "overrides", "n"),
    [
        (None, None, {}, 1),
        (None, "koolio-real", {}, 1),
        (None, None, QLAMBDA, 1),
        ("paper-memory", None, {}, 1),
        ("paper-memory", "koolio-real", {}, 1),  # three pings per sonar
        ("paper-memory-qlambda", None, {}, 1),  # Q(lambda) over the goal's bearing
        (None, None, NO_UNDO_QLAMBDA, 1),
        (None, "koolio-real", NO_UNDO, 1),
        (None, None, {}, 3),
        ("qlambda-no-undo", "koolio-real-dr", {}, 4),
    ],
)
def test_train_writes_the_same_files_on_the_engine_and_in_python(tmp_path, name, world, overrides,
                                                                 n):  # fmt: skip
    """``train``'s table, backup and log, byte for byte, on either loop."""
    a = _train_files(tmp_path, name, world, overrides, True, n)
    b = _train_files(tmp_path, name, world, overrides, False, n)
    assert a == b


@pytest.mark.parametrize(
    ("overrides", "reason"),
    [
        ({"learner": {"algorithm": "dyna"}}, "learner.algorithm dyna"),
        ({"sensors": {"backend": "pymunk"}}, "sensors.backend pymunk"),
    ],
)
def test_what_the_engine_does_not_run_steps_in_python_and_says_why(overrides, reason):
    """The fallback is explicit: the reason is named and the Python steps run, for one
    robot and several."""
    for n in (1, 3):
        env = KoolioEnv("room", config=load_config(overrides=overrides), max_steps=20)
        table = QTable(env.layout, {}, env.config.learner.q_init)
        agents = [make_learner(table, env.config.learner, None) for _ in range(n)]
        loop = robots(env, agents, seed=0)
        assert type(loop) is Robots and reason in str(loop.python_reason)
        loop.begin(0, 0)
        assert loop.advance() == 0 and loop.result(0).steps == 20


def test_qlearner_and_qlambda_run_on_the_engine_and_learn_apart():
    """The premise of the Q(lambda) cases: its steps take the traced update."""
    tables = {}
    for overrides in ({"learner": {"algorithm": "q"}}, QLAMBDA):
        env = KoolioEnv("hallway", config=load_config(overrides=overrides), max_steps=200)
        table = QTable(env.layout, {}, env.config.learner.q_init)
        loop = robots(env, [make_learner(table, env.config.learner, None)], seed=1)
        assert type(loop) is Engine and loop.python_reason is None
        for e in range(3):
            loop.begin(0, e)
            loop.advance()
        loop.sync()
        tables[env.config.learner.algorithm] = table.rows
    assert tables["q"] != tables["qlambda"]


def stop_after(calls: int):
    """A ``stop`` callback that says stop at its ``calls``-th call (the Python loop asks
    once a tick, the engine once per chunk of robot-steps)."""
    count = [0]

    def stop() -> bool:
        count[0] += 1
        return count[0] >= calls

    return stop


@pytest.mark.parametrize(("overrides", "n"), [(QLAMBDA, 1), (LONG_TRACES, 1), (LONG_TRACES, 3)])
def test_stopped_between_chunks_the_robots_are_the_python_steps(monkeypatch, overrides, n):
    """A chunk boundary in the middle of episodes: after the stop every robot's env,
    traces and expected state, and the table, are those the Python steps leave."""
    monkeypatch.setattr(engine, "CHUNK", 5 * n)
    runs = {}
    for compiled in (True, False):
        env = KoolioEnv("hallway", config=load_config(overrides=overrides), max_steps=0)
        table = QTable(env.layout, {}, env.config.learner.q_init)
        agents = [make_learner(table, env.config.learner, None) for _ in range(n)]
        loop = robots(env, agents, seed=2, compiled=compiled)
        for r in range(n):
            loop.begin(r, r)
        assert loop.advance(stop_after(12 if compiled else 60)) is None  # 60 ticks either way
        loop.sync()
        runs[compiled] = (
            [loop.result(r, INTERRUPTED).row() for r in range(n)],
            [(e.world.pose(0), e.state_key, e.codes) for e in loop.envs],
            table.rows,
            [(list(a.traces.items()), a._expect, a.last) for a in agents],
        )
    assert any(len(t[0]) > 1 for t in runs[False][3])  # the premise: several entries traced
    assert runs[True] == runs[False]
    assert runs[True][0][0][2] == "60"


def test_the_generators_continue_as_the_python_loop_leaves_them():
    """After episodes on the engine the env's and the learner's generators are where the
    Python steps leave them (the next draws agree), and so is the last reading."""
    draws = {}
    for compiled in (True, False):
        env = KoolioEnv("room", max_steps=60)
        agent = make_learner(QTable(env.layout), env.config.learner, None)
        loop = robots(env, [agent], seed=5, compiled=compiled)
        loop.begin(0, 0)
        loop.advance()
        loop.sync()
        draws[compiled] = (env.np_random.random(), agent.rng.random(), env.readings.sonar)
    assert draws[True][:2] == draws[False][:2]
    assert np.array_equal(draws[True][2], draws[False][2])


def test_trace_capacity_bounds_the_traces():
    """The bound holds: Q(lambda) in the Python loop never traces more entries."""
    decay, cutoff = 0.98 * 0.9, 0.01
    cap = trace_capacity(decay, cutoff)
    assert decay ** (cap - 2) < cutoff <= decay ** (cap - 3)
    lam = {"learner": {"algorithm": "qlambda", "trace_decay": 0.9}}
    env = KoolioEnv("hallway", config=load_config(overrides=lam), max_steps=300)
    table = QTable(env.layout, {}, env.config.learner.q_init)
    agent = make_learner(table, env.config.learner, None)
    loop = Robots([env], [agent], seed=0)
    most = 0
    for e in range(4):
        loop.begin(0, e)
        while loop.advance(lambda: True) is None and loop.running[0]:
            most = max(most, len(agent.traces))
    assert 20 < most <= cap


# -- several robots: numbering, saving, Ctrl-C ----------------------------------------------


def small_env(**overrides) -> KoolioEnv:
    return KoolioEnv("room", config=load_config(overrides=overrides), max_steps=60)


def run(tmp_path, name: str, episodes: int = 7, seed: int = 0, robots_: int = 3, **kw):
    q, log = tmp_path / f"{name}.qtable", tmp_path / f"{name}.csv"
    res = train(small_env(), QTableStore(q), episodes, seed, log, report=None, robots=robots_,
                **kw)  # fmt: skip
    return q, log, res


def test_seeded_run_with_robots_is_reproducible_and_seed_matters(tmp_path) -> None:
    qa, la, _ = run(tmp_path, "a")
    qb, lb, _ = run(tmp_path, "b")
    qc, _, _ = run(tmp_path, "c", seed=1)
    assert qa.read_bytes() == qb.read_bytes()
    assert la.read_bytes() == lb.read_bytes()
    assert qa.read_bytes() != qc.read_bytes()


def test_a_resumed_run_with_robots_is_seeded_but_not_the_straight_run(tmp_path) -> None:
    """Resuming is reproducible (the same two commands, the same bytes); it is not the
    uninterrupted run, whose robots were mid-episode at the save (docs/robustness.md)."""
    for name in ("a", "b"):  # 5 of 3 robots: the third robot is idle at the save
        run(tmp_path, name, episodes=5, robots_=3)
        run(tmp_path, name, episodes=5, robots_=3)
    straight, _, _ = run(tmp_path, "c", episodes=10, robots_=3)
    a, b = (tmp_path / "a.qtable").read_bytes(), (tmp_path / "b.qtable").read_bytes()
    assert a == b
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    assert a != straight.read_bytes()


def test_episodes_numbered_in_completion_order_and_logged(tmp_path) -> None:
    q, log, res = run(tmp_path, "a", episodes=7, robots_=3)
    rows = log_rows(log)
    assert list(rows[0]) == list(LOG_FIELDS)
    assert [int(r["episode"]) for r in rows] == list(range(7))
    assert res.episodes_run == 7 and res.steps == sum(int(r["steps"]) for r in rows)
    assert all(int(r["steps"]) <= 60 for r in rows)
    table = load_qtable(q)
    assert table.meta["episodes"] == 7 and len(table) > 0
    # Resume: the next run continues the numbering from the table's count.
    _, _, res2 = run(tmp_path, "a", episodes=2, robots_=2)
    assert [r.episode for r in res2.results] == [7, 8]


def test_save_every_with_robots(tmp_path, monkeypatch) -> None:
    saves = []
    original = QTableStore.save

    def counting(self, table):
        saves.append(table.meta["episodes"])
        original(self, table)

    monkeypatch.setattr(QTableStore, "save", counting)
    run(tmp_path, "a", episodes=5, robots_=2, save_every=1, fsync="episode")
    assert saves == [1, 2, 3, 4, 5]
    saves.clear()
    run(tmp_path, "b", episodes=5, robots_=2, fsync="episode")  # every `robots` and the last
    assert saves == [2, 4, 5]


@pytest.mark.parametrize("n", [1, 2, 5])
def test_any_robot_count_trains(tmp_path, n: int) -> None:
    _, _, res = run(tmp_path, f"r{n}", episodes=3, robots_=n)
    assert res.episodes_run == 3 and res.python_reason is None


def test_ctrl_c_folds_every_unfinished_episode(tmp_path, monkeypatch) -> None:
    calls = {"n": 0}
    advance = Engine.advance

    def interrupting(self, stop=None):
        calls["n"] += 1
        if calls["n"] == 30:
            raise KeyboardInterrupt
        return advance(self, stop)

    monkeypatch.setattr(Engine, "advance", interrupting)
    q, log, res = run(tmp_path, "a", episodes=50, robots_=3)
    assert res.interrupted
    rows = log_rows(log)
    cut = [r for r in rows if r["outcome"] == "interrupted"]
    assert len(cut) == 3 and [int(r["episode"]) for r in cut] == [29, 30, 31]
    assert load_qtable(q).rows == res.table.rows


def test_the_pymunk_backend_learns_the_same_with_robots(tmp_path) -> None:
    """Several robots with the pymunk reference backend step in Python and read what
    the compiled backend reads: the same table either way."""
    tables = []
    for backend in ("fast", "pymunk"):
        env = small_env(sensors={"backend": backend})
        q = tmp_path / f"{backend}.qtable"
        res = train(env, QTableStore(q), 4, 3, None, report=None, robots=2)
        assert (res.python_reason is None) == (backend == "fast")
        tables.append(run_identity.learned_digest(load_qtable(q)))  # the configurations differ
    assert tables[0] == tables[1]


def test_eval_every_with_robots_checks_the_table_as_it_stands(tmp_path) -> None:
    """Checks with several robots: due at every multiple of N finished episodes, the
    same checks as a run on the Python loop."""
    out = {}
    for compiled in (True, False):
        q = tmp_path / f"{compiled}.qtable"
        res = train(small_env(), QTableStore(q), 12, 0, tmp_path / f"{compiled}.csv",
                    report=None, robots=3, eval_every=4, eval_episodes=5,
                    compiled=compiled)  # fmt: skip
        out[compiled] = [(c.episode, c.result) for c in res.checks]
    assert [e for e, _ in out[True]] == [4, 8, 12]
    assert out[True] == out[False]


# -- evaluation, batched -------------------------------------------------------------------


@pytest.mark.parametrize(("world", "epsilon"), [(None, 0.0), ("koolio-real-dr", 0.2)])
def test_a_batch_of_robots_scores_what_one_episode_after_another_scores(tmp_path, world, epsilon):
    """Each evaluation episode has its own seeds and the table is only read: 1 robot, 7
    robots and the Python loop give the same figures."""
    env = KoolioEnv("room", config=load_config(world=world), max_steps=80)
    q = tmp_path / "t.qtable"
    train(env, QTableStore(q), 30, 0, None, report=None)
    table = load_qtable(q)
    results = [
        evaluate(env, table, 23, 4, epsilon=epsilon, robots=n, compiled=c)
        for n, c in ((1, True), (7, True), (1, False), (5, False))
    ]
    assert all(r == results[0] for r in results)
    assert 0 < results[0].goal_rate < 1 or results[0].end_of_world_rate > 0  # premise
    assert load_qtable(q).rows == table.rows  # nothing learned
