"""koolio-pm export, the koolio-policy format, load_any_table and --init-qtable."""

from __future__ import annotations

import json

import numpy as np
import pytest
from inputs import expect_error, open_table, table_file

from koolio_pymunk import robot_runtime as rt
from koolio_pymunk.apps import cli
from koolio_pymunk.apps.export import load_any_table, policy_document, write_policy
from koolio_pymunk.learning.qlearning import QLearner
from koolio_pymunk.learning.training import train
from koolio_pymunk.store import run_identity
from koolio_pymunk.store.config import load_config
from koolio_pymunk.store.errors import QTableError
from koolio_pymunk.store.locks import FileLock
from koolio_pymunk.store.qtable import (
    QTableStore,
    load_qtable,
)
from koolio_pymunk.store.run_identity import sensor_signature
from koolio_pymunk.task.env import KoolioEnv


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    """A small table trained on the hallway (a few short episodes), and its env."""
    d = tmp_path_factory.mktemp("trained")
    env = KoolioEnv(max_steps=120)
    store = QTableStore(d / "t.qtable")
    result = train(env, store, episodes=4, seed=3, report=None)
    return env, result.table, d / "t.qtable"


def test_runtime_greedy_matches_simulator_for_every_state(trained, tmp_path):
    env, table, _ = trained
    out = tmp_path / "p.json"
    write_policy(policy_document(table), out)
    policy = rt.Policy.load(str(out))
    agent = QLearner(table, env.config.learner, np.random.default_rng(0))
    assert len(policy.rows) == len(table) > 50
    unique = 0
    for state, row in table.rows.items():
        best = max(row)
        sim_ties = [a for a, q in enumerate(row) if q == best]
        assert policy.greedy_actions(state) == sim_ties
        assert agent.greedy(state) in sim_ties
        if len(sim_ties) == 1:
            unique += 1
            assert policy.greedy(state) == agent.greedy(state) == sim_ties[0]
        # keyword encoding and decoding agree with qtable.KeywordLayout
        codes, _ = env.layout.decode(state << env.layout.action_bits)
        for a in range(5):
            assert policy.layout.keyword(codes, a) == env.layout.keyword(codes, a)
        assert policy.layout.decode((state << 3) | 4) == (codes, 4)
    assert unique > 8  # the premise: many states with one greedy action
    doc = json.loads(out.read_text())
    greedy = {g["state"]: g["action"] for g in doc["greedy"]}
    assert all(
        greedy[s] == max(range(5), key=lambda a, r=r: (r[a], -a)) for s, r in table.rows.items()
    )


def test_export_header_fields(trained, tmp_path):
    env, table, path = trained
    out = tmp_path / "p.json"
    assert cli.main(["export", "--qtable", str(path), "--out", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert (doc["format"], doc["version"]) == ("koolio-policy", 1)
    lay = doc["layout"]
    assert lay["total_bits"] == 27 and lay["action_bits"] == 3
    assert [f["shift"] for f in lay["fields"]] == [25, 23, 21, 19, 17, 15, 13, 11, 9, 7, 5, 3]
    assert doc["encoding"]["thresholds"] == {"sonar": [6.0, 24.0, 60.0], "camera": [36.0, 96.0]}
    assert doc["encoding"]["sonar_groups"] == [[0], [1, 2], [3], [4], [5, 6], [7]]
    assert doc["sensors"] == sensor_signature(env.config)
    assert doc["episodes"] == 4 and doc["n_states"] == len(table)
    assert len(doc["entries"]) == 5 * len(table)
    kws = [e["keyword"] for e in doc["entries"]]
    assert kws == sorted(kws)
    state, row = next(iter(sorted(table.rows.items())))
    assert doc["entries"][:5] == [{"keyword": (state << 3) | a, "q": row[a]} for a in range(5)]


def test_runtime_encoding_matches_simulator(tmp_path):
    """Raw readings of 300 random steps encode to the simulator's codes (also None=unseen)."""
    cfg = load_config(overrides={"sensors": {"compass": {"in_state": True}}})
    env = KoolioEnv(config=cfg, max_steps=300)
    table = open_table(QTableStore(tmp_path / "c.qtable"), env.layout, sensor_signature(cfg), 0.0)
    write_policy(policy_document(table, cfg), tmp_path / "c.json")
    policy = rt.Policy.load(str(tmp_path / "c.json"))
    assert len(policy.layout.levels) == 13
    rng = np.random.default_rng(5)
    env.reset(seed=11)
    seen_codes = set()
    for _ in range(300):
        r = env.readings
        far = env.config.sensors.really_long_distance
        unseen = [[None if v >= far else float(v) for v in cam] for cam in (r.goal, r.eow)]
        for goal, eow in ((r.goal.tolist(), r.eow.tolist()), unseen):
            codes = policy.encode(r.sonar.tolist(), goal, eow, compass=r.compass)
            assert codes == env.codes
            assert policy.state_key(codes) == env.state_key
        seen_codes.update(env.codes[:12])
        _, _, term, trunc, _ = env.step(int(rng.integers(5)))
        if term or trunc:
            env.reset()
    assert seen_codes == {0, 1, 2, 3}


def test_encoding_boundaries_match_searchsorted(trained, tmp_path):
    _, table, _ = trained
    write_policy(policy_document(table), tmp_path / "p.json")
    enc = rt.Policy.load(str(tmp_path / "p.json")).encoder
    for v in (0.0, 5.999, 6.0, 23.9, 24.0, 59.99, 60.0, 1e4):
        codes = enc.encode([v] * 8, [v] * 3, [v] * 3)
        son = int(np.searchsorted([6.0, 24.0, 60.0], v, side="right"))
        cam = 2 if v > 240 else int(np.searchsorted([36.0, 96.0], v, side="right"))
        assert codes == (cam,) * 6 + (son,) * 6


def test_qtable_policy_qtable_round_trip_is_byte_exact(trained, tmp_path):
    _, _, path = trained
    pol, back = tmp_path / "p.json", tmp_path / "back.qtable"
    assert cli.main(["export", "--qtable", str(path), "--out", str(pol)]) == 0
    assert cli.main(["export", "--qtable", str(pol), "--out", str(back)]) == 0
    assert back.read_bytes() == path.read_bytes()
    assert load_any_table(pol).rows == load_qtable(path).rows


def test_a_policy_carries_the_tables_goal_and_world(tmp_path):
    """A table trained for every door in koolio-real: its policy says so (``goal``,
    ``world``), the robot runtime keeps both, and the table made back from the policy
    is the table's bytes (so `eval` and `--init-qtable` see what it was trained for)."""
    env = KoolioEnv(goal="random", world="koolio-real", max_steps=60)
    path, pol, back = tmp_path / "t.qtable", tmp_path / "p.json", tmp_path / "back.qtable"
    train(env, QTableStore(path), episodes=2, seed=0, report=None)
    meta = load_qtable(path).meta
    assert (meta["goal"], meta["world"]) == ("random", "koolio-real")  # the premise
    assert cli.main(["export", "--qtable", str(path), "--out", str(pol)]) == 0
    doc = json.loads(pol.read_text())
    assert (doc["goal"], doc["world"]) == ("random", "koolio-real")
    policy = rt.Policy(doc)
    assert (policy.extra["goal"], policy.extra["world"]) == ("random", "koolio-real")
    assert cli.main(["export", "--qtable", str(pol), "--out", str(back)]) == 0
    assert back.read_bytes() == path.read_bytes()


def test_init_qtable_from_policy_continues_learning(trained, tmp_path):
    env, table, _ = trained
    pol = tmp_path / "p.json"
    write_policy(policy_document(table), pol)
    loaded = load_any_table(pol)
    run_identity.check(loaded, env, "start", str(pol))
    cfg = tmp_path / "short.yaml"
    cfg.write_text("episode: {max_steps: 30}\n")
    new = tmp_path / "new.qtable"
    # --episodes is the total: the policy's 4 episodes, then 1 more
    argv = ["train", "--config", str(cfg), "--episodes", "5", "--quiet", "--log", ""]
    code = cli.main([*argv, "--qtable", str(new), "--init-qtable", str(pol)])
    assert code == 0
    after = load_qtable(new)
    assert after.meta["episodes"] == 5
    assert set(table.rows) <= set(after.rows)


def test_init_qtable_refuses_other_sensor_layout(trained, tmp_path, capsys):
    _, table, _ = trained
    pol = tmp_path / "p.json"
    write_policy(policy_document(table), pol)
    cfg = tmp_path / "other.yaml"
    cfg.write_text("sensors: {sonar: {sub_arcs: 5}}\n")
    argv = ["train", "--config", str(cfg), "--episodes", "1", "--quiet", "--log", ""]
    code = cli.main([*argv, "--qtable", str(tmp_path / "n.qtable"), "--init-qtable", str(pol)])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1
    assert "sensors.sub_arcs: table made for 11, this run uses 5" in err


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d.update(version=2), "version: unsupported version 2 (this reader knows 1)"),
        (lambda d: d.update(format="other"), "format: not a koolio-policy file"),
        (lambda d: d["entries"].append(dict(d["entries"][0])), "repeated"),
        (lambda d: d["entries"][0].update(keyword=1 << 27), "out of range"),
        (lambda d: d["entries"][0].update(keyword=(d["entries"][0]["keyword"] | 7)), "range"),
        (lambda d: d["entries"][0].update(q="x"), "entries[0]: needs an integer keyword"),
        (lambda d: d["layout"]["fields"][0].update(shift=24), "fields[0].shift: 24, expected 25"),
        (lambda d: d["encoding"]["thresholds"].update(sonar=[6, 5]), "must be increasing"),
        (lambda d: d.pop("sensors"), "sensors: missing"),
        (lambda d: d["greedy"][0].update(action=9), "greedy[0].action: action 9 is not an action"),
        (lambda d: d["greedy"][1].update(action=True), "greedy[1]: needs an integer state and"),
        (lambda d: d["greedy"].pop(), "greedy: {n-1} items, expected {n} (one per state of"),
        (lambda d: d["greedy"].reverse(), "greedy[0].state: "),
        (lambda d: d["layout"].update(total_bits=99), "layout.total_bits: 99, expected 27"),
        (lambda d: d["layout"].update(total_bits="27"), "layout.total_bits: '27', expected 27"),
        (lambda d: d.update(n_states=d["n_states"] + 1), "n_states: {n+1}, expected {n} (the st"),
        (lambda d: d.update(n_states=None), "n_states: None, expected {n}"),
    ],
)
def test_bad_policy_files_are_refused_in_one_line(trained, tmp_path, edit, message):
    _, table, _ = trained
    n = len(table)
    message = message.replace("{n-1}", str(n - 1)).replace("{n+1}", str(n + 1))
    message = message.replace("{n}", str(n))
    doc = policy_document(table)
    edit(doc)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    with pytest.raises(QTableError) as info:
        load_any_table(bad)
    assert message in str(info.value)
    assert str(info.value).startswith(str(bad))
    assert "\n" not in str(info.value)


def test_the_greedy_list_is_the_entries_greedy_actions(trained, tmp_path):
    """``greedy`` is checked against the entries: an action that is in range but not the
    state's greedy one is refused (a reader acting on ``greedy`` alone would do otherwise
    than the robot); a file without the derived items still loads."""
    _, table, _ = trained
    doc = policy_document(table)
    state, row = next((s, r) for s, r in sorted(table.rows.items()) if len(set(r)) > 1)
    i = sorted(table.rows).index(state)
    best = row.index(max(row))
    other = next(a for a in range(5) if row[a] != row[best])
    doc["greedy"][i]["action"] = other
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    message = (
        f"{bad}: greedy[{i}].action: {other} is not the greedy action of state {state} "
        f"(expected {best})"
    )
    with pytest.raises(QTableError) as info:
        load_any_table(bad)
    assert str(info.value) == message
    for key in ("greedy", "n_states"):
        del doc[key]
    del doc["layout"]["total_bits"]
    bad.write_text(json.dumps(doc))
    assert load_any_table(bad).rows == table.rows


def test_non_table_files_are_refused(tmp_path, capsys):
    junk = tmp_path / "junk.txt"
    junk.write_text("hello")
    nan = tmp_path / "nan.json"
    nan.write_text('{"format": "koolio-policy", "q": NaN}')
    with pytest.raises(QTableError, match=r"neither a \.qtable file nor a koolio-policy"):
        load_any_table(junk)
    with pytest.raises(QTableError, match="invalid JSON"):
        load_any_table(nan)
    code = cli.main(["export", "--qtable", str(tmp_path / "missing"), "--out", "x.json"])
    assert code == 2
    assert "missing: cannot read" in capsys.readouterr().err


def test_out_replaces_only_a_file_of_its_kind(trained, tmp_path, capsys):
    """``--out`` replaces an earlier policy file, never another file, and never one a
    running command holds (a training run's log: newcomer audit)."""
    _, _, path = trained
    work = tmp_path / "w"
    work.mkdir()
    log = work / "run.csv"
    log.write_text("episode,steps,outcome\n0,12,goal\n")
    notes = work / "notes.json"
    notes.write_text('{"todo": ["calibrate the sonar"]}')
    table_like = work / "other.qtable"
    table_like.write_text("not a table")
    export = ["export", "--qtable", str(path), "--out"]
    expect_error(capsys, work, [*export, str(log)], "run.csv: --out: exists and is not a")
    expect_error(capsys, work, [*export, str(notes)], "notes.json: --out: exists and is not a")
    expect_error(capsys, work, [*export, str(table_like)], "other.qtable: --out: exists, and")
    pol = work / "p.json"
    for _ in range(2):  # an earlier policy file is replaced
        assert cli.main([*export, str(pol)]) == 0
    capsys.readouterr()
    with FileLock(pol, "koolio-pm train"):  # in use: refused, left as it was
        expect_error(capsys, work, [*export, str(pol)], "p.json: in use by process")


def test_out_never_replaces_a_table(trained, tmp_path, capsys):
    """A trained Q-table is never replaced (audit: ``--out t.qtable`` wrote another
    table over it, exit 0, its ``.bak`` one episode behind), whatever its name; nor is a
    table's backup taken over. A ``.qtable`` output is a new file, and a policy file is
    still replaced by the next export."""
    _, _, path = trained
    work = tmp_path / "w"
    work.mkdir()
    other = work / "other.json"
    assert cli.main(["export", "--qtable", str(path), "--out", str(other)]) == 0
    mine = work / "t.qtable"
    mine.write_bytes(path.read_bytes())
    (work / "t.qtable.bak").write_bytes(path.read_bytes())
    (work / "gone.qtable.bak").write_bytes(path.read_bytes())
    (work / "raw").write_bytes(path.read_bytes())  # a table under another name
    capsys.readouterr()
    from_other = ["export", "--qtable", str(other), "--out"]
    line = expect_error(capsys, work, [*from_other, str(mine)], "t.qtable: --out: exists, and")
    assert line == (
        f"koolio-pm: error: {mine}: --out: exists, and export writes a .qtable file only "
        "under a new name (it never replaces a Q-table): choose another name or remove it"
    )
    expect_error(
        capsys,
        work,
        [*from_other, str(work / "gone.qtable")],
        f"gone.qtable: --out: a table's backup {work / 'gone.qtable.bak'} exists beside it",
    )
    expect_error(capsys, work, [*from_other, str(work / "raw")], "raw: --out: exists and is not")
    expect_error(capsys, work, [*from_other, str(mine) + ".bak"], "t.qtable.bak: --out: exists")
    new = work / "new.qtable"
    assert cli.main([*from_other, str(new)]) == 0
    assert new.read_bytes() == path.read_bytes()
    expect_error(capsys, work, [*from_other, str(new)], "new.qtable: --out: exists, and")
    assert cli.main(["export", "--qtable", str(new), "--out", str(other)]) == 0  # a policy


def test_export_checks_the_table_against_the_configuration(tmp_path, capsys):
    """export refuses a table its configuration did not make, in the line ``eval`` gives
    (audit: a paper-memory-qlambda table exported without --config became a one-step Q
    policy with the default alpha, epsilon and rewards; a 27-bit table exported with the
    32-bit paper-memory configuration was accepted); with its own --config the policy
    carries that configuration's learner and rewards."""
    mem_cfg = load_config("paper-memory-qlambda")
    qlambda = {"name": "qlambda", "trace_cutoff": 0.01, "trace_decay": 0.9}
    mem = table_file(tmp_path / "mem.qtable", mem_cfg, qlambda)
    plain = table_file(tmp_path / "plain.qtable", load_config())
    dyna = table_file(
        tmp_path / "dyna.qtable", load_config(), {"name": "dyna", "planning_steps": 5}
    )
    out = str(tmp_path / "x.json")
    line = expect_error(
        capsys, tmp_path, ["export", "--qtable", str(mem), "--out", out], "mem.qtable: layout:"
    )
    assert line.endswith(
        "(it was made with the shipped profile 'paper-memory-qlambda': add --config "
        "paper-memory-qlambda)"
    )
    evals = ["eval", "--qtable", str(mem), "--episodes", "1"]
    assert expect_error(capsys, tmp_path, evals) == line  # the same refusal as eval's
    line = expect_error(
        capsys,
        tmp_path,
        ["export", "--qtable", str(plain), "--config", "paper-memory", "--out", out],
        "plain.qtable: layout: table made for 27-bit keyword",
    )
    assert "this run uses 32-bit keyword" in line
    assert line.endswith("(it was made with the default configuration: leave out --config)")
    expect_error(
        capsys,
        tmp_path,
        ["export", "--qtable", str(plain), "--config", "paper", "--out", out],
        "plain.qtable: sensors.camera_sensors_deg: table made for [0.0, 45.0, -45.0], this "
        "run uses [0.0, 90.0, -90.0]",
    )
    line = expect_error(capsys, tmp_path, ["export", "--qtable", str(dyna), "--out", out])
    assert line == (
        f"koolio-pm: error: {dyna}: algorithm: table learned with dyna, this run uses qlambda "
        "(give export the --config it was learned with)"
    )
    argv = ["export", "--qtable", str(mem), "--config", "paper-memory-qlambda", "--out", out]
    assert cli.main(argv) == 0
    doc = json.loads((tmp_path / "x.json").read_text())
    assert doc["learner"] == {
        "alpha": 0.07,
        "gamma": mem_cfg.learner.gamma,
        "epsilon": 0.01,
        "algorithm": "qlambda",
        "trace_decay": 0.9,
        "trace_cutoff": mem_cfg.learner.trace_cutoff,
    }
    assert doc["rewards"]["bump"] == -12.0 and doc["layout"]["total_bits"] == 35
