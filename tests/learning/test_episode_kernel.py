"""The compiled episode (learning/episode_kernel.py) held to the Python episode loop."""

from __future__ import annotations

import numpy as np
import pytest
from koolio_pymunk.learning.episode_agreement import compare_episodes

from koolio_pymunk.learning import episode_kernel
from koolio_pymunk.learning.algorithms import make_learner
from koolio_pymunk.learning.episodes import INTERRUPTED, Episodes
from koolio_pymunk.learning.qtable import QTable, QTableStore
from koolio_pymunk.learning.training import train
from koolio_pymunk.store.config import load_config
from koolio_pymunk.task.env import KoolioEnv

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
#: misread plates, a strong beam model. The models are compiled inline into the episode:
#: this holds that copy to the one the Python loop calls (``test_realism.py`` holds that
#: one to the reference).
EVERY_SENSOR_MODEL = {
    "realism": {
        "sonar": {"crosstalk": 0.3, "z_hit": 0.7, "z_short": 0.1, "z_max": 0.1, "z_rand": 0.1},
        "camera": {"misread": 0.4, "detect_far": 0.3},
    }
}


def stop_after(calls: int):
    """A ``stop`` callback for ``Episodes.run`` that says stop at its ``calls``-th call
    (the Python loop asks once a step, the compiled one once per chunk of steps)."""
    count = [0]

    def stop() -> bool:
        count[0] += 1
        return count[0] >= calls

    return stop


@pytest.mark.parametrize(
    ("arena", "world", "overrides"),
    [
        ("hallway", None, {}),
        ("hallway", "koolio-real", {}),
        ("hallway", "koolio-real-dr", {}),
        ("room", None, EAGER_RESCUE),
        ("obstacles", "koolio-real", EAGER_RESCUE),
        ("hallway", None, {"sensors": {"noise": {"model": "gaussian"}}}),
        ("hallway", "koolio-real", {"sensors": {"noise": {"model": "gaussian"}}}),
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
    ],
)
def test_compiled_episodes_match_the_python_loop(arena, world, overrides):
    """Row, pose, state and the whole table after every episode, bit for bit."""
    r = compare_episodes(arena, world, episodes=20, seed=3, max_steps=250, overrides=overrides)
    assert r.steps > 800  # the premise: episodes of some length ran
    assert (r.mismatches, r.first_mismatch) == (0, -1)


def test_rescues_and_truncations_happen_in_the_compared_runs():
    """The premise of the eager-rescue cases: rescues and step caps occur."""
    env = KoolioEnv("room", config=load_config(overrides=EAGER_RESCUE))
    env.config.episode.max_steps = 250
    agent = make_learner(QTable(env.layout), env.config.learner, None)
    loop = Episodes(env, agent, seed=3, compiled=True)
    assert loop.compiled is not None
    rescued = outcomes = 0
    for e in range(6):
        loop.begin(e)
        res = loop.run()
        rescued += res.rescued
        outcomes += res.outcome == "truncated"
    assert rescued >= 1 and outcomes >= 1


@pytest.mark.parametrize(
    ("name", "world", "overrides"),
    [
        (None, None, {}),
        (None, "koolio-real", {}),
        (None, None, QLAMBDA),
        ("paper-memory", None, {}),
        ("paper-memory", "koolio-real", {}),  # three pings per sonar
        ("paper-memory-qlambda", None, {}),  # Q(lambda) over the goal's bearing, forgetting
        (None, None, NO_UNDO_QLAMBDA),
        (None, "koolio-real", NO_UNDO),
    ],
)
def test_train_writes_the_same_files_compiled_and_in_python(tmp_path, name, world, overrides):
    """``train``'s table and log, byte for byte, with either loop."""
    files = {}
    for compiled in (True, False):
        cfg = load_config(name, world=world, overrides=overrides)
        env = KoolioEnv("hallway", config=cfg, max_steps=300)
        table, log = tmp_path / f"{compiled}.qtable", tmp_path / f"{compiled}.csv"
        res = train(env, QTableStore(table), 8, 1, log, report=None, compiled=compiled)
        assert res.steps > 300
        files[compiled] = (table.read_bytes(), log.read_bytes())
    assert files[True] == files[False]


@pytest.mark.parametrize(
    ("overrides", "learn", "reason"),
    [
        ({"learner": {"algorithm": "dyna"}}, True, "learner.algorithm dyna"),
        ({"sensors": {"backend": "pymunk"}}, True, "sensors.backend pymunk"),
        ({}, False, "without learning"),
    ],
)
def test_what_the_compiled_episode_does_not_run_falls_back_to_python(overrides, learn, reason):
    """The fallback is explicit: the reason is named and the Python steps run."""
    env = KoolioEnv("room", config=load_config(overrides=overrides), max_steps=20)
    agent = make_learner(QTable(env.layout), env.config.learner, None)
    loop = Episodes(env, agent, seed=0, learn=learn, compiled=True)
    assert loop.compiled is None and reason in str(loop.compiled_reason)
    loop.begin(0)
    assert loop.run().steps == 20


def test_qlambda_runs_compiled_and_learns_otherwise_than_one_step_q():
    """The premise of the Q(lambda) cases: its compiled episodes take the traced update
    (a table of its own, traces left in the agent as its Python steps leave them)."""
    tables = {}
    for overrides in ({}, QLAMBDA):
        env = KoolioEnv("hallway", config=load_config(overrides=overrides), max_steps=200)
        agent = make_learner(QTable(env.layout), env.config.learner, None)
        loop = Episodes(env, agent, seed=1, compiled=True)
        assert loop.compiled is not None and loop.compiled_reason is None
        for e in range(3):
            loop.begin(e)
            loop.run()
        tables[agent.name] = agent.table.rows
    assert tables["q"] != tables["qlambda"]


@pytest.mark.parametrize("overrides", [QLAMBDA, LONG_TRACES])
def test_qlambda_stopped_between_chunks_leaves_the_traces_of_the_python_steps(
    monkeypatch, overrides
):
    """A chunk boundary in the middle of an episode: the traces and the expected state
    carry over, and after the stop they are those the Python steps leave."""
    monkeypatch.setattr(episode_kernel, "CHUNK", 5)
    runs = {}
    for compiled in (True, False):
        env = KoolioEnv("hallway", config=load_config(overrides=overrides), max_steps=0)
        table = QTable(env.layout, {}, env.config.learner.q_init)
        agent = make_learner(table, env.config.learner, None)
        loop = Episodes(env, agent, seed=4, compiled=compiled)
        for e in range(2):
            loop.begin(e)
            res = loop.run(stop_after(12 if compiled else 60))  # 60 steps either way
        traces = list(agent.traces.items())
        runs[compiled] = (res.row(), env.state_key, table.rows, traces, agent._expect)
    assert len(runs[False][3]) > 1  # the premise: several entries traced
    assert runs[True] == runs[False]


def test_the_memory_runs_compiled_and_is_left_as_the_python_steps_leave_it():
    """The premise of the memory cases: ``paper-memory`` runs compiled, its keys hold the
    memory's codes, and after an episode the env's memory (``env.codes``) is the Python
    loop's."""
    runs = {}
    for compiled in (True, False):
        env = KoolioEnv("hallway", config=load_config(overrides=EVERY_MEMORY), max_steps=150)
        agent = make_learner(QTable(env.layout), env.config.learner, None)
        loop = Episodes(env, agent, seed=6, compiled=compiled)
        assert (loop.compiled is not None) == compiled
        loop.begin(0)
        loop.run()
        m = env.memory
        runs[compiled] = (env.codes, m.goal, m.eow, m.action, m._goal_age, m._eow_age)
        runs[compiled] += (env.state_key, sorted(agent.table.rows))
    assert runs[True] == runs[False]
    assert runs[True][3] > 0  # an action remembered


def test_one_step_q_runs_compiled():
    env = KoolioEnv("room", max_steps=20)
    agent = make_learner(QTable(env.layout), env.config.learner, None)
    loop = Episodes(env, agent, seed=0, compiled=True)
    assert loop.compiled is not None and loop.compiled_reason is None
    assert Episodes(env, agent, seed=0).compiled is None  # the Python loop unless asked


def test_stop_between_chunks_interrupts_with_the_updates_kept(monkeypatch):
    """``stop`` is asked between chunks; the steps made are in the table and the env,
    as the Python loop leaves them after the same number of steps."""
    monkeypatch.setattr(episode_kernel, "CHUNK", 7)
    runs = {}
    for compiled in (True, False):
        env = KoolioEnv("hallway", max_steps=0)
        table = QTable(env.layout, {}, env.config.learner.q_init)
        agent = make_learner(table, env.config.learner, None)
        loop = Episodes(env, agent, seed=2, compiled=compiled)
        loop.begin(0)
        res = loop.run(stop_after(3 if compiled else 21))  # 21 steps either way
        runs[compiled] = (res.row(), env.world.pose(0), env.state_key, table.rows)
    assert runs[True][0][4] == INTERRUPTED and runs[True][0][2] == "21"
    assert runs[True] == runs[False]


def test_the_generators_continue_as_the_python_loop_leaves_them():
    """After a compiled episode the env's and the agent's generators are where the
    Python steps leave them (the next draws agree)."""
    draws = {}
    for compiled in (True, False):
        env = KoolioEnv("room", max_steps=60)
        agent = make_learner(QTable(env.layout), env.config.learner, None)
        loop = Episodes(env, agent, seed=5, compiled=compiled)
        loop.begin(0)
        loop.run()
        draws[compiled] = (env.np_random.random(), agent.rng.random(), env.readings.sonar)
    assert draws[True][:2] == draws[False][:2]
    assert np.array_equal(draws[True][2], draws[False][2])


def test_ctrl_c_in_a_compiled_run_stops_between_episodes(tmp_path, monkeypatch):
    """A Ctrl-C during compiled episodes takes effect after the episode (shorter than a
    chunk): every logged episode is finished and saved, the table and log in step."""
    import os
    import signal

    from koolio_pymunk.learning import training
    from koolio_pymunk.learning.qtable import load_qtable

    real = training.RunFiles.finished

    def finished(self, res, save=False):
        real(self, res, save)
        if res.episode == 3:
            os.kill(os.getpid(), signal.SIGINT)

    monkeypatch.setattr(training.RunFiles, "finished", finished)
    env = KoolioEnv("room", max_steps=40)
    q, log = tmp_path / "c.qtable", tmp_path / "c.csv"
    res = train(env, QTableStore(q), 10, 0, log, report=None)
    assert res.interrupted and res.episodes_run == 4
    rows = log.read_text().splitlines()[1:]
    assert [r.split(",")[0] for r in rows] == ["0", "1", "2", "3"]
    assert "interrupted" not in log.read_text()
    assert int(load_qtable(q).meta["episodes"]) == 4
