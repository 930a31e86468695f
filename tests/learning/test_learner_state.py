"""Learner state read from disk is validated as strictly as the Q-table, and the robot
runtime's twin checks agree with the package's (issue #21).

The same bad Dyna-Q models go to the package (a ``dyna_model`` section of a ``.qtable``,
:meth:`~koolio_pymunk.store.dyna_model.Model.from_bytes`) and to the robot
(``model`` of a policy, ``robot_runtime.Model.from_json``): both refuse every one, both
accept the good ones with the same content. Q values and rewards have the same bounds in
tables and policies. A bad file is refused with one line and nothing is written.
"""

from __future__ import annotations

import json
import math
import struct

import numpy as np
import pytest
from inputs import expect_error, small_table

from koolio_pymunk import robot_runtime as rt
from koolio_pymunk.apps.export import policy_document
from koolio_pymunk.store.config import LearnerConfig
from koolio_pymunk.store.dyna_model import SECTION
from koolio_pymunk.store.errors import QTableError
from koolio_pymunk.store.qtable import QTable

TABLE = small_table()
LAYOUT = TABLE.layout
STATE = LAYOUT.state_key((1, 0, 2, 1, 0, 2, 3, 0, 1, 2, 3, 0))
NEXT = LAYOUT.state_key((0,) * 12)
BITS = LAYOUT.total_bits - LAYOUT.action_bits
OUT = (NEXT, -0.5, 0, 3)  # next state, reward, terminal, count

#: Models as [(state, action, [(next, reward, terminal, count), ...]), ...] that both
#: formats can hold, and what the refusal says.
BAD = [
    ([(1 << BITS, 3, [OUT])], "beyond the 24-bit layout"),
    ([(2**64 - 1, 3, [OUT])], "beyond the 24-bit layout"),
    ([(LAYOUT.state_key((3,) + (0,) * 11), 3, [OUT])], "code 3 of GoalCam0 beyond its 3 levels"),
    ([(STATE, 5, [OUT])], "action 5 is not an action (0..4)"),
    ([(STATE, 7, [OUT])], "action 7 is not an action"),
    ([(STATE, 2**63, [OUT])], "is not an action"),
    ([(STATE, 3, [(1 << BITS, -0.5, 0, 1)])], "beyond the 24-bit layout"),
    ([(STATE, 3, [(NEXT, math.nan, 0, 1)])], "reward nan is not a finite number"),
    ([(STATE, 3, [(NEXT, math.inf, 0, 1)])], "reward inf is not a finite number"),
    ([(STATE, 3, [(NEXT, -math.inf, 0, 1)])], "reward -inf"),
    ([(STATE, 3, [(NEXT, 1e308, 0, 1)])], "reward 1e+308 is not a finite number within +-1e+15"),
    ([(STATE, 3, [(NEXT, -1.0000001e15, 0, 1)])], "within +-1e+15"),
    ([(STATE, 3, [(NEXT, -0.5, 0, 0)])], "count 0 is not an integer in 1..2**53"),
    ([(STATE, 3, [(NEXT, -0.5, 0, 2**64 - 1)])], "count 18446744073709551615 is not"),
    ([(STATE, 3, [(NEXT, -0.5, 0, 2**53 + 1)])], "is not an integer in 1..2**53"),
    ([(STATE, 3, [(NEXT, -0.5, 0, 2**52), (NEXT, -1.0, 0, 2**52 + 1)])], "more than 2**53"),
    ([(STATE, 3, [OUT, OUT])], ""),  # an outcome twice
    ([(STATE, 3, [OUT]), (STATE, 3, [OUT])], ""),  # a pair twice
]
GOOD = [
    [],
    [(STATE, 3, [OUT])],
    [(STATE, 3, [OUT, (NEXT, 100.0, 1, 1)]), (NEXT, 0, [(STATE, -1e15, 0, 2**53 - 1)])],
    [(STATE, 4, [(NEXT, 1e15, 1, 2**52), (STATE, 1e15, 1, 2**52)])],
]


def section_bytes(model: list) -> bytes:
    """The ``dyna_model`` section of ``model`` (module doc of ``dyna``), values unchecked."""
    outs = [o for _, _, os in model for o in os]
    return b"".join(
        [
            struct.pack("<QQ", len(model), len(outs)),
            np.array([p[0] for p in model], "<u8").tobytes(),
            np.array([p[1] for p in model], "<u8").tobytes(),
            np.array([len(p[2]) for p in model], "<u8").tobytes(),
            np.array([o[0] for o in outs], "<u8").tobytes(),
            np.array([o[1] for o in outs], "<f8").tobytes(),
            np.array([o[2] for o in outs], "<u8").tobytes(),
            np.array([o[3] for o in outs], "<u8").tobytes(),
        ]
    )


def model_json(model: list) -> dict:
    return {"pairs": [[s, a, [[n, r, bool(t), c] for n, r, t, c in os]] for s, a, os in model]}


def dyna_table(section: bytes) -> bytes:
    table = small_table()
    table.meta["algorithm"] = {"name": "dyna", "planning_steps": 3}
    table.sections[SECTION] = section
    return table.to_bytes()


def dyna_policy(model: dict | None) -> dict:
    doc = policy_document(small_table(), None)
    doc["learner"].update(algorithm="dyna", planning_steps=3)
    if model is not None:
        doc["model"] = model
    return json.loads(json.dumps(doc))


@pytest.mark.parametrize(("model", "words"), BAD, ids=[str(i) for i in range(len(BAD))])
def test_both_readers_refuse_the_same_bad_models(model, words):
    with pytest.raises(QTableError) as pkg:
        QTable.from_bytes(dyna_table(section_bytes(model)), "t.qtable")
    assert str(pkg.value).startswith("t.qtable: dyna_model: ") and words in str(pkg.value)
    with pytest.raises(rt.PolicyError) as robot:
        rt.Policy(dyna_policy(model_json(model)), "p.json")
    message = str(robot.value)
    infinite = message.endswith("not a finite number (JSON could not write it back)")
    assert message.startswith("p.json: model") and (words in message or infinite), message
    with pytest.raises(rt.PolicyError) as direct:
        rt.Model.from_json(model_json(model), LAYOUT)
    assert words in str(direct.value)


@pytest.mark.parametrize("model", GOOD)
def test_both_readers_accept_the_same_good_models(model):
    table = QTable.from_bytes(dyna_table(section_bytes(model)), "t.qtable")
    ours = table.sections[SECTION]  # read and checked with the table
    theirs = rt.Policy(dyna_policy(model_json(model)), "p.json").model
    assert ours.pairs == theirs.pairs and ours.totals == theirs.totals
    assert ours.outcomes == theirs.outcomes
    assert bytes(ours) == section_bytes(model)  # read back exactly


@pytest.mark.parametrize(
    ("model", "words"),
    [
        ({"pairs": [[-1, 3, [[NEXT, -0.5, False, 1]]]]}, "state -1 is not an integer >= 0"),
        ({"pairs": [[STATE, -1, [[NEXT, -0.5, False, 1]]]]}, "action -1 is not an action"),
        ({"pairs": [[STATE, 3, [[-5, -0.5, False, 1]]]]}, "state -5 is not an integer >= 0"),
        ({"pairs": [[STATE, 3, [[NEXT, -0.5, 1, 1]]]]}, "terminal 1 is not true or false"),
        ({"pairs": [[STATE, 3, [[NEXT, -0.5, False, True]]]]}, "count True is not"),
        ({"pairs": [[STATE, 3, [[NEXT, 10**400, False, 1]]]]}, "is not a finite number"),
    ],
)
def test_the_robot_refuses_what_json_alone_can_hold(model, words):
    with pytest.raises(rt.PolicyError, match=r"^p\.json: model: pairs\[0\]: ") as info:
        rt.Policy(dyna_policy(model), "p.json")
    assert words in str(info.value)


def test_a_terminal_flag_other_than_0_or_1_is_refused():
    section = section_bytes([(STATE, 3, [(NEXT, -0.5, 2, 1)])])
    with pytest.raises(QTableError, match="terminal 2 is not 0 or 1"):
        QTable.from_bytes(dyna_table(section), "t.qtable")


@pytest.mark.parametrize("value", [1.0000001e300, -1e301, 1.7e308])
def test_q_values_have_the_same_bound_in_tables_and_policies(value):
    table = small_table()
    next(iter(table.rows.values()))[2] = value
    with pytest.raises(QTableError, match="a Q value is beyond"):
        QTable.from_bytes(table.to_bytes(), "t.qtable")
    doc = dyna_policy(None)
    doc["entries"][0]["q"] = value
    with pytest.raises(rt.PolicyError, match=r"entries\[0\]: q .* beyond \+-1e\+300"):
        rt.Policy(doc, "p.json")
    table = small_table()
    table.q_init = value
    with pytest.raises(QTableError, match=r"header\.q_init: must be a finite number within"):
        QTable.from_bytes(table.to_bytes(), "t.qtable")
    doc = dyna_policy(None)
    doc["q_init"] = value
    with pytest.raises(rt.PolicyError, match="q_init: must be a finite number within"):
        rt.Policy(doc, "p.json")


def test_table_state_keys_must_be_inside_the_layout():
    table = small_table()
    table.row(LAYOUT.state_key((0,) * 11 + (3,)))  # Sonar7 has 4 levels: fine
    QTable.from_bytes(table.to_bytes(), "t.qtable")
    table.row(LAYOUT.state_key((0, 3) + (0,) * 10))  # GoalCam1 has 3
    with pytest.raises(QTableError, match="code 3 of GoalCam1 beyond its 3 levels"):
        QTable.from_bytes(table.to_bytes(), "t.qtable")


@pytest.mark.parametrize(
    ("change", "words"),
    [
        ({"alpha": 0}, "learner.alpha: must be in (0, 1]"),
        ({"alpha": 1e300}, "learner.alpha: must be in (0, 1]"),
        ({"gamma": 1.5}, "learner.gamma: must be in [0, 1]"),
        ({"epsilon": -0.1}, "learner.epsilon: must be in [0, 1]"),
        ({"planning_steps": 10**12}, "learner.planning_steps: must be an integer in 0..10,000"),
        ({"planning_steps": 10_001}, "learner.planning_steps: must be an integer in 0..10,000"),
    ],
)
def test_policy_learner_settings_have_the_configuration_ranges(change, words):
    doc = dyna_policy(None)
    doc["learner"].update(change)
    with pytest.raises(rt.PolicyError, match=r"^p\.json: ") as info:
        rt.Policy(doc, "p.json")
    assert words in str(info.value)
    assert (
        rt.MAX_PLANNING_STEPS
        == 10_000
        == int(
            __import__("koolio_pymunk.store.config").store.config.LIMITS["learner.planning_steps"][
                0
            ]
        )
    )


def test_policy_rewards_are_bounded_so_json_can_write_what_is_learned():
    doc = dyna_policy(None)
    doc["rewards"]["goal"] = 1e308
    with pytest.raises(rt.PolicyError, match="rewards: must map names to finite numbers within"):
        rt.Policy(doc, "p.json")
    doc["rewards"]["goal"] = 1e15  # the bound: learning from it saves a writable file
    policy = rt.Policy(doc, "p.json")
    for _ in range(50):
        policy.update(STATE, 3, 1e15, STATE, False, alpha=1.0, gamma=1.0)
    assert json.loads(rt.dump_document(policy.to_document()))


# -- end to end: one line, nothing written --------------------------------------------------
@pytest.fixture
def work(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "dyna.yaml").write_text(
        "learner: {algorithm: dyna, planning_steps: 3}\nepisode: {max_steps: 30}\n"
    )
    return tmp_path


@pytest.mark.parametrize(("model", "words"), [BAD[7], BAD[2], BAD[5], BAD[13]])
@pytest.mark.parametrize("command", ["train", "init", "eval", "export"])
def test_a_bad_model_in_a_table_is_one_line_and_nothing_is_written(
    work, capsys, command, model, words
):
    (work / "t.qtable").write_bytes(dyna_table(section_bytes(model)))
    argv = {
        "train": ["train", "--qtable", "t.qtable", "--log", "t.csv", "--episodes", "1"],
        "init": ["train", "--init-qtable", "t.qtable", "--qtable", "n.qtable", "--log", "n.csv"],
        "eval": ["eval", "--qtable", "t.qtable", "--episodes", "1"],
        "export": ["export", "--qtable", "t.qtable", "--out", "p.json"],
    }[command]
    if command != "export":
        argv += ["--arena", "room", "--config", "dyna.yaml"]
    expect_error(capsys, work, argv, "t.qtable", "dyna_model: pair 0: ", words)


def test_a_bad_model_in_a_policy_is_one_line_on_the_robot(work, capsys):
    (work / "p.json").write_text(json.dumps(dyna_policy(model_json(BAD[10][0]))))
    expect_error(
        capsys, work, ["p.json"], "model: pairs[0]: reward 1e+308", run=rt.main, prefix="robot_"
    )
    assert LearnerConfig().planning_steps <= rt.MAX_PLANNING_STEPS


def test_a_number_json_reads_as_infinity_is_refused_everywhere(tmp_path):
    """JSON's 1e400 reads as infinity: kept in a table's header or a policy it made the
    next save unloadable (a table's header) or a traceback (the robot's JSON writer)."""
    from inputs import header_of, with_header

    data = small_table().to_bytes()
    raw = json.dumps(header_of(data)).replace('"episodes": 3', '"episodes": 3, "x": [1e400]')
    with pytest.raises(QTableError, match=r"header\.x\[0\]: not a finite number"):
        QTable.from_bytes(with_header(data, raw.encode()), "t.qtable")
    text = json.dumps(dyna_policy(None))
    for old, new in (
        ('"sensors": {', '"sensors": {"y": 1e400, '),
        ('{"format"', '{"z": -1e999, "format"'),
    ):
        assert old in text
        with pytest.raises(rt.PolicyError, match=r"p\.json: (sensors\.y|z): not a finite number"):
            rt.Policy.loads(text.replace(old, new, 1), "p.json")


def test_an_algorithm_that_is_not_a_name_is_refused():
    """Found by the fuzzer: a list as the algorithm's name was a TypeError (unhashable)."""
    from koolio_pymunk.store.run_identity import RunIdentity

    doc = dyna_policy(None)
    doc["learner"]["algorithm"] = ["dyna"]
    with pytest.raises(rt.PolicyError, match=r"learner\.algorithm: unknown algorithm \['dyna'\]"):
        rt.Policy(doc, "p.json")
    table = small_table()
    table.meta["algorithm"] = {"name": ["dyna"]}
    with pytest.raises(QTableError, match="algorithm: unknown learning algorithm"):
        RunIdentity.of_table(table, "t.qtable")
