"""The robot's memory in the state: hand-built sequences, the env's keys, the runtime twin."""

from __future__ import annotations

import numpy as np
import pytest
from inputs import open_table

from koolio_pymunk import robot_runtime as rt
from koolio_pymunk.apps.cli import main
from koolio_pymunk.apps.export import policy_document
from koolio_pymunk.learning.episodes import Episodes
from koolio_pymunk.learning.qlearning import QLearner
from koolio_pymunk.learning.training import train
from koolio_pymunk.sensing.memory import Memory
from koolio_pymunk.store import run_identity
from koolio_pymunk.store.config import Config, MemoryConfig, load_config
from koolio_pymunk.store.errors import ConfigError, QTableError
from koolio_pymunk.store.qtable import (
    QTable,
    QTableStore,
    load_qtable,
)
from koolio_pymunk.store.run_identity import RunIdentity, sensor_signature
from koolio_pymunk.task.env import KoolioEnv

FAR = 10_000.0
NONE = [FAR, FAR, FAR]
ALL = {"goal_camera": True, "eow_camera": True, "previous_action": True}


def test_nearest_camera_wins_ties_to_the_lower_one() -> None:
    mem = Memory(MemoryConfig(goal_camera=True, eow_camera=True), 3, FAR)
    mem.reset()
    assert mem.update([FAR, 50.0, 40.0], [30.0, 30.0, FAR], None).codes == (3, 1)
    assert mem.update(NONE, NONE, 3).codes == (3, 1)  # kept: never forgotten
    assert mem.update([FAR, FAR, FAR - 1e-9], NONE, 3).codes == (3, 1)  # just below far: seen


def test_forgetting_counts_steps_without_a_sighting() -> None:
    mem = Memory(MemoryConfig(goal_camera=True, forget_after=3), 3, FAR)
    mem.reset()
    assert mem.update([20.0, FAR, FAR], NONE, None).codes == (1,)
    codes = [mem.update(NONE, NONE, 3).codes for _ in range(3)]
    assert codes == [(1,), (1,), (0,)]
    mem.update([FAR, 70.0, FAR], NONE, 1)
    mem.update(NONE, NONE, None)  # a rescue's reading: records, does not age
    assert [mem.update(NONE, NONE, 2).codes for _ in range(3)] == [(2,), (2,), (0,)]


def test_previous_action_and_reset() -> None:
    mem = Memory(MemoryConfig(previous_action=True), 3, FAR)
    mem.reset()
    assert mem.update(NONE, NONE, None).codes == (0,)
    assert mem.update(NONE, NONE, 4).codes == (5,)
    assert mem.update(NONE, NONE, None).codes == (5,)  # a rescue keeps it
    mem.reset()
    assert mem.codes == (0,)


def test_bearing_turns_with_the_robot_and_is_forgotten() -> None:
    """A plate seen by the right camera (-90), then turns and moves: the quarters of
    -90, -60, -30 (right, right, ahead), a Forward keeps it, RotateRight turns it back."""
    cfg = MemoryConfig(goal_bearing=True, forget_after=5)
    mem = Memory(cfg, 3, FAR, camera_deg=[0.0, 90.0, -90.0], turn_deg=30.0)
    mem.reset()
    assert mem.update(NONE, NONE, None).codes == (0,)  # nothing seen: none
    assert mem.update(NONE, NONE, 2).codes == (0,)  # turning turns nothing
    assert mem.update([FAR, FAR, 40.0], NONE, 3).codes == (4,)
    assert mem.bearing_mdeg == -90_000
    assert [mem.update(NONE, NONE, 2).codes for _ in range(2)] == [(4,), (1,)]
    assert mem.bearing_mdeg == -30_000
    assert mem.update(NONE, NONE, 3).codes == (1,)
    assert mem.update(NONE, NONE, None).codes == (1,)  # a rescue: no turn, no ageing
    assert mem.update(NONE, NONE, 1).codes == (4,)  # RotateLeft: -60
    assert mem.update(NONE, NONE, 1).codes == (0,)  # the fifth step unseen: forgotten
    assert mem.update([30.0, FAR, FAR], NONE, 1).codes == (1,)  # the front camera
    keeps = Memory(MemoryConfig(goal_bearing=True), 3, FAR, [0.0, 90.0, -90.0], 30.0)
    keeps.reset()
    keeps.update([30.0, FAR, FAR], NONE, None)
    for _ in range(6):
        keeps.update(NONE, NONE, 2)  # six right turns of 30: +180 wraps to -180, behind
    assert keeps.bearing_mdeg == -180_000 and keeps.codes == (3,)


def test_bearing_needs_the_cameras_angles() -> None:
    with pytest.raises(ValueError, match="camera_deg"):
        Memory(MemoryConfig(goal_bearing=True), 3, FAR, camera_deg=[0.0, 90.0])


def test_bearing_field_and_signature() -> None:
    over = {"sensors": {"memory": {"goal_bearing": True}}, "actions": {"rotate_action_arc_deg": 45}}
    cfg = load_config(overrides=over)
    env = KoolioEnv("room", config=cfg)
    assert env.layout.fields[-1] == ("GoalBearing", 5)
    assert sensor_signature(cfg)["memory"]["goal_bearing"] is True
    assert sensor_signature(cfg)["memory"]["turn_deg"] == 45.0
    paper = sensor_signature(load_config("paper-memory"))["memory"]
    assert "goal_bearing" not in paper and "turn_deg" not in paper  # older tables' bytes


def test_memory_fields_follow_the_sensors_in_the_keyword() -> None:
    cfg = load_config(overrides={"sensors": {"memory": ALL}})
    env = KoolioEnv("room", config=cfg)
    names = [n for n, _ in env.layout.fields]
    assert names[-3:] == ["GoalMemory", "EoWMemory", "LastAction"]
    assert env.layout.total_bits == 27 + 2 + 2 + 3
    assert env.observation_space.nvec.tolist()[-3:] == [4, 4, 6]
    plain = KoolioEnv("room")
    obs, _ = env.reset(seed=3)
    plain.reset(seed=3)
    assert env.state_key >> 7 == plain.state_key  # the same sensors, then 7 memory bits
    assert tuple(obs[-3:]) == env.memory.codes and obs[-1] == 0
    for action in (3, 1, 3, 0):
        env.step(action)
        plain.step(action)
        assert env.state_key >> 7 == plain.state_key
        assert env.state_key & 0b111 == 1 + action


def test_a_table_of_one_memory_is_refused_under_another() -> None:
    mem = load_config(overrides={"sensors": {"memory": {"goal_camera": True}}})
    env = KoolioEnv("room", config=mem)
    table = QTable(env.layout, {"sensors": sensor_signature(mem)})
    with pytest.raises(QTableError, match="GoalMemory") as err:
        run_identity.check(table, RunIdentity.of_config(Config()), "inspect", "t.qtable")
    assert str(err.value).startswith("t.qtable: layout: table made for")
    forgets = {"goal_camera": True, "forget_after": 5}
    forget = load_config(overrides={"sensors": {"memory": forgets}})
    with pytest.raises(QTableError, match=r"sensors\.memory: table made for .*forget_after.*0"):
        run_identity.check(table, RunIdentity.of_config(forget), "inspect", "t.qtable")


def test_memoryless_signature_is_unchanged() -> None:
    assert "memory" not in sensor_signature(Config())


@pytest.mark.parametrize(
    ("memory", "message"),
    [
        ("{forget_after: -1}", "sensors.memory.forget_after: must be >= 0"),
        ("{forget_after: 10001}", "sensors.memory.forget_after: must be <= 10,000"),
        ('{goal_camera: "yes"}', "sensors.memory.goal_camera: expected true or false"),
        ("{last_seen: true}", "sensors.memory.last_seen"),
        ("{forget_after: 5}", "sensors.memory.forget_after: 5 forgets nothing"),
        ("{previous_action: true, forget_after: 5}", "forget_after: 5 forgets nothing"),
    ],
)
def test_bad_memory_options_are_one_line(tmp_path, capsys, memory, message) -> None:
    cfg = tmp_path / "m.yaml"
    cfg.write_text(f"sensors: {{memory: {memory}}}\n")
    table = tmp_path / "t.qtable"
    assert main(["train", "--arena", "room", "--config", str(cfg), "--qtable", str(table)]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err and err.startswith("koolio-pm: error:")
    assert not table.exists()


def test_many_robots_learn_with_a_memory(tmp_path, capsys) -> None:
    """The step engine runs the memory for any number of robots (it was refused before
    the engine): the table's states carry the memory's codes."""
    cfg = tmp_path / "m.yaml"
    cfg.write_text("sensors: {memory: {previous_action: true}}\n")
    args = ["train", "--arena", "room", "--config", str(cfg), "--robots", "2", "--episodes", "4"]
    assert main([*args, "--qtable", str(tmp_path / "t.qtable"), "--quiet"]) == 0
    table = load_qtable(tmp_path / "t.qtable")
    assert table.meta["episodes"] == 4
    assert {key & 0b111 for key in table.rows} - {0} != set()  # the last action in the key


@pytest.mark.parametrize("bearing", [False, True])
def test_runtime_memory_gives_the_simulators_keys(tmp_path, bearing) -> None:
    """An episode with every memory field on, forgetting after 4 steps: the runtime's
    memory, fed the env's raw readings, gives the env's state key at every step, rescues
    included; a policy exported from a memory table keeps its memory settings."""
    fields = ALL | {"forget_after": 4} | ({"goal_bearing": True} if bearing else {})
    overrides = {
        "sensors": {"memory": fields},
        "episode": {"max_steps": 150},
        "rescue": {"max_steps_before_rescue": 0, "rescue_chance": 0.3},
    }
    cfg = load_config(overrides=overrides)
    env = KoolioEnv("room", config=cfg)
    store = QTableStore(tmp_path / "m.qtable")
    train(env, store, 2, seed=1, report=None)
    doc = policy_document(open_table(store, env.layout, sensor_signature(cfg), -30.0), cfg)
    extra = {"turn_deg": 30.0, "camera_deg": [0.0, 45.0, -45.0]} if bearing else {}
    assert doc["encoding"]["memory"] == fields | extra
    policy = rt.Policy(doc)
    mem = policy.new_memory()
    rng = np.random.default_rng(0)
    seen = {"goal": 0, "rescues": 0, "bearings": set()}
    for step in range(600):
        if step % 150 == 0:
            env.reset(seed=5 + step)
            mem.reset()
            r = env.readings
            codes = policy.encode(r.sonar, r.goal, r.eow, memory=mem)
            assert policy.state_key(codes) == env.state_key
        action = int(rng.choice([0, 1, 2, 3, 3, 3, 3]))
        env.simulate(action)
        r = env.readings
        codes = policy.encode(r.sonar, r.goal, r.eow, memory=mem, action=action)
        assert policy.state_key(codes) == env.state_key
        seen["goal"] += mem.goal > 0
        seen["bearings"].add(mem.bearing)
        if env.rescue_check():
            seen["rescues"] += 1
            r = env.readings
            codes = policy.encode(r.sonar, r.goal, r.eow, memory=mem)
            assert policy.state_key(codes) == env.state_key
    assert seen["rescues"] > 0 and seen["goal"] > 0  # the premise: both were exercised
    if bearing:
        assert len(seen["bearings"]) >= 4  # none and at least three quarters
    with pytest.raises(rt.PolicyError, match="memory"):
        policy.encode(r.sonar, r.goal, r.eow)


def test_memory_runs_byte_identical_twice(tmp_path) -> None:
    cfg = load_config(overrides={"sensors": {"memory": ALL}, "episode": {"max_steps": 60}})
    outs = []
    for name in ("a", "b"):
        env = KoolioEnv("room", config=cfg)
        train(env, QTableStore(tmp_path / f"{name}.qtable"), 4, seed=2,
              log_path=tmp_path / f"{name}.csv", report=None)  # fmt: skip
        outs.append((tmp_path / f"{name}.qtable").read_bytes())
    assert outs[0] == outs[1]


def test_the_loop_learns_with_memory() -> None:
    cfg = load_config(overrides={"sensors": {"memory": ALL}, "episode": {"max_steps": 40}})
    env = KoolioEnv("room", config=cfg)
    table = QTable(env.layout)
    loop = Episodes(env, QLearner(table, cfg.learner, None), seed=0)
    loop.begin(0)
    loop.run()
    keys = list(table.rows)
    assert keys and all(k & 0b111 <= 5 for k in keys)
    assert any(k & 0b111 == 0 for k in keys)  # the start: no action yet


def test_config_error_names_the_item() -> None:
    with pytest.raises(ConfigError, match=r"sensors\.memory\.forget_after"):
        load_config(overrides={"sensors": {"memory": {"forget_after": -2}}})


@pytest.mark.parametrize(
    ("change", "item"),
    [
        ({"turn_deg": 0}, "encoding.memory.turn_deg"),
        ({"turn_deg": "30"}, "encoding.memory.turn_deg"),
        ({"camera_deg": [0.0, 90.0]}, "encoding.memory.camera_deg"),
        ({"camera_deg": [0.0, 90.0, float("nan")]}, "encoding.memory.camera_deg"),
        ({"goal_bearing": 1}, "encoding.memory.goal_bearing"),
        ({"bearing_size": 4}, "encoding.memory"),
    ],
)
def test_a_bad_bearing_in_a_policy_is_one_line(tmp_path, change, item) -> None:
    """The runtime refuses a policy whose bearing settings it could not follow."""
    over = {"sensors": {"memory": {"goal_bearing": True}}, "episode": {"max_steps": 30}}
    cfg = load_config(overrides=over)
    env = KoolioEnv("room", config=cfg)
    store = QTableStore(tmp_path / "b.qtable")
    train(env, store, 1, seed=0, report=None)
    doc = policy_document(open_table(store, env.layout, sensor_signature(cfg), -30.0), cfg)
    rt.Policy(doc)  # the premise: the exported policy loads
    doc["encoding"]["memory"].update(change)
    with pytest.raises(rt.PolicyError) as err:
        rt.Policy(doc)
    assert item in str(err.value) and "\n" not in str(err.value)
