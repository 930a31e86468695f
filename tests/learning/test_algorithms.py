"""Learning algorithms (learner.algorithm): Q(lambda), Dyna-Q, their files and loops."""

from __future__ import annotations

import json

import numpy as np
import pytest

from koolio_pymunk.apps.cli import main
from koolio_pymunk.apps.viewer.session import Session
from koolio_pymunk.learning.algorithms import make_learner
from koolio_pymunk.learning.dyna import DynaQ
from koolio_pymunk.learning.qlambda import QLambda
from koolio_pymunk.learning.qlearning import QLearner
from koolio_pymunk.learning.training import train
from koolio_pymunk.store.config import Config, LearnerConfig, load_config
from koolio_pymunk.store.dyna_model import SECTION, Model
from koolio_pymunk.store.errors import ConfigError, QTableError
from koolio_pymunk.store.keyword import KeywordLayout
from koolio_pymunk.store.qtable import QTable, QTableStore, load_qtable
from koolio_pymunk.task.env import KoolioEnv

LAYOUT = KeywordLayout((("A", 8),))


class Script:
    """A scripted generator: each draw is the next number of ``values`` (in [0, 1)),
    integer draws are ``int(u * n)``. Has numpy's and the standard library's methods."""

    def __init__(self, values) -> None:
        self.values = list(values)
        self.used = 0

    def _next(self) -> float:
        self.used += 1
        return self.values.pop(0)

    def random(self, size=None):
        if size is None:
            return self._next()
        return np.array([self._next() for _ in range(size)])

    def integers(self, n: int) -> int:
        return int(self._next() * n)

    randrange = integers


def learner(algorithm: str, **kw) -> tuple[QLearner, QTable]:
    table = QTable(LAYOUT)
    cfg = LearnerConfig(algorithm=algorithm, alpha=0.5, gamma=1.0, **kw)
    return make_learner(table, cfg, np.random.default_rng(0)), table


# -- configuration --------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("learner_cfg", "message"),
    [
        ({"trace_decay": 1.5}, "learner.trace_decay: must be in [0, 1] (lambda)"),
        ({"trace_decay": -0.1}, "learner.trace_decay: must be in [0, 1] (lambda)"),
        ({"planning_steps": -1}, "learner.planning_steps: must be >= 0"),
        ({"algorithm": "sarsa"}, "learner.algorithm: unknown algorithm 'sarsa' (valid: q,"),
        ({"trace_cutoff": 0}, "learner.trace_cutoff: must be in [1e-06, 1)"),
    ],
)
def test_bad_learner_configuration_is_one_line(tmp_path, capsys, learner_cfg, message) -> None:
    with pytest.raises(ConfigError) as info:
        load_config(overrides={"learner": learner_cfg})
    assert str(info.value).startswith(f"<defaults>: {message}")
    cfg = tmp_path / "bad.yaml"
    cfg.write_text(json.dumps({"learner": learner_cfg}))
    q = tmp_path / "q.qtable"
    argv = ["train", "--arena", "room", "--config", str(cfg), "--qtable", str(q), "--quiet"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"koolio-pm: error: {cfg}: {message}")
    assert not q.exists()


# -- Q(lambda) ------------------------------------------------------------------------------


def test_qlambda_traces_by_hand() -> None:
    """gamma 1, lambda 0.5, alpha 0.5: a chain 0 -> 1 -> 0 -> 2 (goal, reward 8)."""
    agent, t = learner("qlambda", trace_decay=0.5, trace_cutoff=0.1)
    assert isinstance(agent, QLambda)
    agent.observe(0, 3, 0.0, 1, False)  # delta 0; trace {0: 0.5}
    agent.observe(1, 3, 0.0, 0, False)  # delta 0; traces {0: 0.25, 1: 0.5}
    agent.observe(0, 1, 8.0, 2, True)  # replacing: state 0 now traces action 1 only
    # delta = 8 - Q(0,1) = 8: Q(0,1) += 4 (e 1), Q(1,3) += 4 * 0.5 = 2; Q(0,3) untouched
    assert t.rows == {0: [0.0, 4.0, 0.0, 0.0, 0.0], 1: [0.0, 0.0, 0.0, 2.0, 0.0]}
    assert agent.traces == {0: [1, 0.5], 1: [3, 0.25]}
    agent.begin_episode(1, np.random.default_rng(0))
    assert agent.traces == {}


def test_qlambda_cutoff_and_decay() -> None:
    agent, _ = learner("qlambda", trace_decay=0.5, trace_cutoff=0.2)
    agent.observe(0, 3, 0.0, 1, False)
    agent.observe(1, 3, 0.0, 2, False)
    assert agent.traces == {0: [3, 0.25], 1: [3, 0.5]}
    agent.observe(2, 3, 0.0, 3, False)  # 0.125 < 0.2: state 0 dropped
    assert agent.traces == {1: [3, 0.25], 2: [3, 0.5]}


def test_watkins_cut_after_a_non_greedy_action_only() -> None:
    agent, t = learner("qlambda", trace_decay=0.9)
    agent.epsilon = 0.5
    t.row(1)[:] = [0.0, 0.0, 5.0, 0.0, 5.0]
    agent.observe(0, 3, 0.0, 1, False)
    agent.rng = Script([0.1, 0.9])  # explore, action int(0.9 * 5) = 4: a greedy one
    assert agent.act(1) == 4 and len(agent.traces) == 1
    agent.rng = Script([0.1, 0.0])  # explore, action 0: below the best, cut
    assert agent.act(1) == 0 and agent.traces == {}


def test_qlambda_cut_when_the_next_step_does_not_start_where_the_last_ended() -> None:
    agent, _ = learner("qlambda")
    agent.epsilon = 0.0
    agent.observe(0, 3, 0.0, 1, False)
    agent.rng = Script([0.0, 0.0])
    agent.act(1)
    assert len(agent.traces) == 1
    agent.act(5)  # a rescue moved the robot to state 5
    assert agent.traces == {}


def _train(tmp_path, name: str, episodes: int, config: Config, seed: int = 0):
    q = tmp_path / f"{name}.qtable"
    log = tmp_path / f"{name}.csv"
    env = KoolioEnv("room", config=config)
    train(env, QTableStore(q), episodes, seed, log, report=None)
    return q, log


def small(**learner_cfg) -> Config:
    """One-step Q's settings (the ``one-step-q`` profile) with ``learner_cfg`` over them."""
    over = {"learner": learner_cfg, "episode": {"max_steps": 60}}
    return load_config("one-step-q", overrides=over)


def test_lambda_zero_is_one_step_q_bit_for_bit(tmp_path) -> None:
    q, _ = _train(tmp_path, "q", 5, small())
    ql, _ = _train(tmp_path, "ql", 5, small(algorithm="qlambda", trace_decay=0.0))
    a, b = load_qtable(q), load_qtable(ql)
    assert a.rows == b.rows and len(a) > 20
    assert "algorithm" not in a.meta
    assert b.meta["algorithm"] == {"name": "qlambda", "trace_decay": 0.0, "trace_cutoff": 0.01}
    ql9, _ = _train(tmp_path, "ql9", 5, small(algorithm="qlambda"))
    assert load_qtable(ql9).rows != a.rows


# -- Dyna-Q ---------------------------------------------------------------------------------


def test_dyna_planning_by_hand() -> None:
    agent, t = learner("dyna", planning_steps=2)
    assert isinstance(agent, DynaQ)
    agent.rng = Script([0.0, 0.0, 0.0, 0.0])
    agent.observe(0, 3, -1.0, 1, False)
    # real: 0 + 0.5 * (-1 + 0 - 0) = -0.5; planned twice from the only transition:
    # -0.5 + 0.5 * (-1 + 0.5) = -0.75; -0.75 + 0.5 * (-1 + 0.75) = -0.875
    assert t.rows[0][3] == -0.875 and agent.rng.used == 4
    assert agent.model.outcomes == [[[1, -1.0, False, 1]]]


def test_dyna_model_counts_and_draws_in_proportion() -> None:
    m = Model()
    for nxt, reward in [(6, -0.5), (6, -0.5), (7, -5.0), (6, -0.5)]:
        m.record(5, 3, reward, nxt, False)
    m.record(2, 0, 100.0, 9, True)
    assert m.pairs == [(5, 3), (2, 0)] and m.totals == [4, 1]
    assert m.outcomes[0] == [[6, -0.5, False, 3], [7, -5.0, False, 1]]
    assert [m.sample(0.49, u)[3] for u in (0.0, 0.74, 0.75, 0.99)] == [6, 6, 7, 7]
    assert m.sample(0.5, 0.3) == (2, 0, 100.0, 9, True)
    back = Model.from_bytes(bytes(m))
    assert (back.pairs, back.outcomes, back.totals) == (m.pairs, m.outcomes, m.totals)
    back.record(5, 3, -5.0, 7, False)  # the index is rebuilt too
    assert back.outcomes[0][1][3] == 2


def test_dyna_model_is_saved_in_the_table_file_under_its_crc(tmp_path) -> None:
    q, _ = _train(tmp_path, "d", 3, small(algorithm="dyna", planning_steps=3))
    table = load_qtable(q)
    model = table.sections[SECTION]  # read and checked with the table
    assert len(model) > 20 and sum(model.totals) > 60
    data = bytearray(q.read_bytes())
    data[-20] ^= 1  # a byte of the model section
    q.write_bytes(bytes(data))
    with pytest.raises(QTableError, match="checksum mismatch"):
        load_qtable(q)
    with pytest.raises(QTableError, match="dyna_model: malformed"):
        Model.from_bytes(bytes(model)[:-8])


def test_dyna_model_is_parsed_once_when_the_table_is_read(tmp_path, monkeypatch) -> None:
    """The learner records into the model the table's reader parsed (no second parse);
    a copy of the table has a model of its own; bytes put in by hand are refused."""
    q, _ = _train(tmp_path, "d", 2, small(algorithm="dyna", planning_steps=3))
    table = load_qtable(q)
    parsed = table.sections[SECTION]
    assert isinstance(parsed, Model) and len(parsed) > 0
    calls = []
    monkeypatch.setattr(Model, "from_bytes", classmethod(lambda *a, **k: calls.append(a)))
    cfg = LearnerConfig(algorithm="dyna", planning_steps=3)
    agent = make_learner(table, cfg, np.random.default_rng(0))
    assert agent.model is parsed and calls == []
    monkeypatch.undo()
    copy = table.copy()
    assert copy.sections[SECTION] == parsed and copy.sections[SECTION] is not parsed
    copy.sections[SECTION].record(1, 2, -0.5, 3, False)
    assert copy.sections[SECTION] != parsed  # recording into the copy leaves the table's
    by_hand = QTable(table.layout, dict(table.meta), sections={SECTION: bytes(parsed)})
    with pytest.raises(TypeError, match="dyna_model section is bytes, not a Model"):
        make_learner(by_hand, cfg, np.random.default_rng(0))


def test_one_step_q_table_has_no_new_header_keys(tmp_path) -> None:
    q, _ = _train(tmp_path, "q", 2, small())
    meta = load_qtable(q).meta
    assert "algorithm" not in meta and "sections" not in meta


@pytest.mark.parametrize("algorithm", ["qlambda", "dyna"])
def test_resume_continues_exactly(tmp_path, algorithm) -> None:
    cfg = small(algorithm=algorithm, planning_steps=4)
    q_full, log_full = _train(tmp_path, "full", 7, cfg)
    q_part, log_part = _train(tmp_path, "part", 4, cfg)
    _train(tmp_path, "part", 3, cfg)
    assert q_part.read_bytes() == q_full.read_bytes()
    assert log_part.read_bytes() == log_full.read_bytes()


@pytest.mark.parametrize("algorithm", ["qlambda", "dyna"])
def test_window_session_learns_exactly_like_train(tmp_path, algorithm) -> None:
    cfg = small(algorithm=algorithm)
    q, log = _train(tmp_path, "train", 3, cfg, seed=4)
    env = KoolioEnv("room", config=cfg)
    session = Session(env, tmp_path / "w.qtable", seed=4, episodes=3, log=tmp_path / "w.csv")
    while session.run(50):
        pass
    session.exit()
    assert (tmp_path / "w.qtable").read_bytes() == q.read_bytes()
    assert (tmp_path / "w.csv").read_bytes() == log.read_bytes()


def test_algorithm_mismatch_on_resume_is_refused_and_init_qtable_converts(tmp_path, capsys):
    dyna = tmp_path / "dyna.yaml"
    dyna.write_text("learner: {algorithm: dyna, planning_steps: 2}\nepisode: {max_steps: 60}\n")
    plain = tmp_path / "q.yaml"
    plain.write_text("episode: {max_steps: 60}\n")
    q = tmp_path / "t.qtable"
    base = ["train", "--arena", "room", "--quiet", "--episodes", "2"]
    assert main([*base, "--config", str(dyna), "--qtable", str(q)]) == 0
    before = q.read_bytes()
    assert main([*base, "--config", str(plain), "--qtable", str(q)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        f"koolio-pm: error: {q}: algorithm: table learned with dyna, this run uses qlambda "
        f"(start a new table from its Q values: --init-qtable {q} --qtable NEW)"
    ]
    assert q.read_bytes() == before
    new = tmp_path / "new.qtable"
    argv = [*base, "--config", str(plain), "--qtable", str(new), "--init-qtable", str(q)]
    argv[argv.index("--episodes") + 1] = "4"  # a total: the 2 of t.qtable, then 2 more
    assert main(argv) == 0
    table = load_qtable(new)  # the default learner's record, the Dyna model dropped
    assert table.meta["algorithm"]["name"] == "qlambda" and table.sections == {}
    assert table.meta["episodes"] == 4


@pytest.mark.parametrize("algorithm", ["qlambda", "dyna"])
def test_many_robots_learn_with_every_algorithm(tmp_path, capsys, algorithm) -> None:
    """Q(lambda) on the step engine, Dyna-Q on the Python loop (its model is Python's):
    several robots learn with either (``--verbose`` says where Dyna-Q stepped)."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text(f"learner: {{algorithm: {algorithm}}}\n")
    q = tmp_path / "t.qtable"
    argv = ["train", "--arena", "room", "--config", str(cfg), "--robots", "2", "--episodes", "3"]
    assert main([*argv, "--qtable", str(q), "--verbose"]) == 0
    out = capsys.readouterr().out
    assert load_qtable(q).meta["algorithm"]["name"] == algorithm
    python = "stepped in the Python loop: learner.algorithm dyna" in out
    assert python == (algorithm == "dyna")


def test_discarding_with_robots_in_the_python_loop_is_refused(tmp_path, capsys) -> None:
    """Exit Without Save with several robots takes their writes back from the engine's
    journal: a Dyna-Q run (the Python loop) is refused in one line, before any file."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text("learner: {algorithm: dyna}\n")
    q = tmp_path / "t.qtable"
    argv = ["train", "--arena", "room", "--config", str(cfg), "--robots", "2"]
    assert main([*argv, "--qtable", str(q), "--discard-unfinished"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("koolio-pm: error: --discard-unfinished: ")
    assert "learner.algorithm dyna" in err[0] and not list(tmp_path.glob("t.*"))


# -- the robot runtime's standard-library copies ----------------------------------------------


def _policy_pair(algorithm: str, **learner_cfg):
    """A table with random values, its exported policy, and the configuration."""
    from koolio_pymunk import robot_runtime as rt
    from koolio_pymunk.apps.export import policy_document
    from koolio_pymunk.store.config import state_fields
    from koolio_pymunk.store.run_identity import sensor_signature

    cfg = load_config(
        overrides={
            "learner": {"algorithm": algorithm, "epsilon": {"start": 0.3, "end": 0.3}} | learner_cfg
        }
    )
    layout = KeywordLayout(tuple(state_fields(cfg.sensors)))
    rng = np.random.default_rng(3)
    table = QTable(layout, {"sensors": sensor_signature(cfg), "episodes": 0}, cfg.learner.q_init)
    states = [
        layout.state_key([int(rng.integers(lv)) for _, lv in layout.fields]) for _ in range(40)
    ]
    for s in states[:25]:
        table.row(s)[:] = (rng.normal(size=5) * 20.0).tolist()
    policy = rt.Policy(json.loads(json.dumps(policy_document(table, cfg))))
    return table, policy, cfg, states


@pytest.mark.parametrize(
    ("algorithm", "params"),
    [("q", {}), ("qlambda", {"trace_decay": 0.8}), ("dyna", {"planning_steps": 3})],
)
def test_robot_runtime_learns_bit_for_bit_like_the_simulator(tmp_path, algorithm, params):
    """Same transitions, rescues (the robot moved between two steps) and random draws:
    the same actions, Q values, traces and model, and a save/load of the policy file in
    the middle changes nothing."""
    import random

    from koolio_pymunk import robot_runtime as rt

    table, policy, cfg, states = _policy_pair(algorithm, **params)
    assert policy.algorithm == algorithm
    source = random.Random(11)
    draws = [source.random() for _ in range(60_000)]
    ref_rng, rob_rng = Script(draws), Script(draws)
    ref = make_learner(table, cfg.learner, ref_rng)
    rob = rt.RobotLearner(policy, epsilon=0.3, seed=0)
    rob.rng = rob_rng
    world = random.Random(5)
    codes = lambda s: policy.layout.decode(s << policy.layout.action_bits)[0]  # noqa: E731
    steps = 0
    for episode in range(80):
        s = world.choice(states)
        ref.begin_episode(episode, ref_rng)
        rob.begin(codes(s))
        for _ in range(world.randrange(1, 60)):
            a = ref.act(s)
            assert rob.choose() == a
            s2, reward, end = world.choice(states), world.choice((-0.5, -1.0, -5.0)), False
            if world.random() < 0.05:
                reward, end = world.choice((100.0, -100.0)), True
            ref.observe(s, a, reward, s2, end)
            rob.step(a, reward, codes(s2), end)
            s, steps = s2, steps + 1
            if end:
                break
            if world.random() < 0.1:  # a rescue: the robot moved (sometimes where it was)
                s = world.choice([s, *states])
                ref.relocated(s)
                rob.moved(codes(s))
        rob.end("goal")
        if episode == 40:  # the robot's file round trip keeps everything it learns from
            path = tmp_path / "p.json"
            policy.save(str(path))
            policy = rt.Policy.load(str(path))
            rob.policy = policy
    assert steps > 1000 and ref_rng.used == rob_rng.used
    assert policy.rows == table.rows
    if algorithm == "qlambda":
        assert rob.traces.entries == ref.traces and ref.traces
    if algorithm == "dyna":
        assert policy.model.pairs == ref.model.pairs and policy.model.outcomes == ref.model.outcomes


def test_policy_file_learner_algorithm_is_validated(tmp_path) -> None:
    from koolio_pymunk import robot_runtime as rt

    _, policy, _, _ = _policy_pair("dyna", planning_steps=2)
    doc = policy.to_document()
    assert doc["learner"]["algorithm"] == "dyna" and doc["learner"]["planning_steps"] == 2
    assert "model" not in doc  # the simulator's model is not exported
    for change, message in [
        ({"algorithm": "sarsa"}, "learner.algorithm: unknown algorithm 'sarsa'"),
        ({"planning_steps": -2}, "learner.planning_steps: must be an integer in 0..10,000"),
        ({"planning_steps": 1.5}, "learner.planning_steps: must be an integer in 0..10,000"),
        ({"algorithm": "qlambda"}, "learner.trace_decay: missing (needed by qlambda)"),
    ]:
        bad = json.loads(json.dumps(doc))
        bad["learner"].update(change)
        with pytest.raises(rt.PolicyError) as info:
            rt.Policy(bad, "p.json")
        assert str(info.value).startswith(f"p.json: {message}")
    bad = json.loads(json.dumps(doc))
    bad["model"] = {"pairs": [[1, 0, [[2, -1.0, False, 0]]]]}
    with pytest.raises(
        rt.PolicyError,
        match=r"^p\.json: model: pairs\[0\]: count 0 is not an integer in 1..2\*\*53",
    ):
        rt.Policy(bad, "p.json")
    bad["learner"] = {"alpha": 0.2}
    with pytest.raises(rt.PolicyError, match=r"^p\.json: model: only a dyna policy has a model"):
        rt.Policy(bad, "p.json")


def test_table_sections_round_trip_and_are_checked() -> None:
    import struct
    import zlib

    t = QTable(LAYOUT, {"episodes": 1}, -3.0)
    t.row(2)[1] = 4.5
    t.sections = {"b": b"\x01\x02", "a": b"xyz"}
    data = t.to_bytes()
    back = QTable.from_bytes(data)
    assert back.sections == {"a": b"xyz", "b": b"\x01\x02"} and back.rows == t.rows
    assert back.to_bytes() == data
    # a header that lists one byte too many, with a valid checksum: refused
    bad = data[:-4].replace(b'["b",2]', b'["b",3]')  # same header length
    with pytest.raises(QTableError, match="length does not match"):
        QTable.from_bytes(bad + struct.pack("<I", zlib.crc32(bad)))
    bad = data[:-4].replace(b'["b",2]', b'["b",-2]')  # one byte longer header
    bad = bad[:8] + struct.pack("<I", struct.unpack_from("<I", bad, 8)[0] + 1) + bad[12:]
    with pytest.raises(QTableError, match=r"header\.sections: must be \[\[name, length\]"):
        QTable.from_bytes(bad + struct.pack("<I", zlib.crc32(bad)))
