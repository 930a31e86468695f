"""Golden runs: one seeded run per engine, its table and log against recorded hashes.

The agreement tests hold the step engine to the Python loop, and a seeded run to itself;
neither fails when both change their draws together (a reordered draw, a changed default,
a new operation in the shared arithmetic). These runs do: 20 episodes of the default
hallway run, seed 0, with one robot and with four, on the compiled step engine and in the
Python loop (the reference), each against the hash of what its table learned
(:func:`~koolio_pymunk.store.run_identity.learned_digest`: provenance and run id aside)
and of its log's rows. A commit that changes them on purpose records the new hashes and
says so (CONTRIBUTING.md). Recorded at 6db549c on Linux x86-64 (numba 0.68, numpy 2.4);
a platform whose libm rounds ``sin``/``cos`` differently may give other values.
"""

from __future__ import annotations

import hashlib

import pytest

from koolio_pymunk.learning.training import train
from koolio_pymunk.store import run_identity
from koolio_pymunk.store.qtable import QTableStore, load_qtable
from koolio_pymunk.task.env import KoolioEnv

#: robots -> (learned_digest of the table, sha256 of the log's rows)
GOLDEN = {
    1: ("8f2501794eccbcb0", "3573c572969257988069efbb76d603f97576a157676b4f5933c8cc9023fc0ad7"),
    4: ("9a4a23c877efc3eb", "c2ff01e93aa3b6aad5f64485bc5246b446d99f8f7f98dcab58151bcfeaba8d5d"),
}


@pytest.mark.parametrize("robots", [1, 4])
@pytest.mark.parametrize("compiled", [True, False], ids=["engine", "python-loop"])
def test_a_seeded_default_run_has_its_recorded_bytes(tmp_path, robots, compiled) -> None:
    q, log = tmp_path / "q.qtable", tmp_path / "q.csv"
    res = train(KoolioEnv("hallway"), QTableStore(q), 20, 0, log, report=None,
                compiled=compiled, robots=robots)  # fmt: skip
    assert (res.python_reason is None) == compiled  # the engine asked for is the one that ran
    rows = "".join(line for line in log.read_text().splitlines(True) if not line.startswith("#"))
    got = (run_identity.learned_digest(load_qtable(q)), hashlib.sha256(rows.encode()).hexdigest())
    assert got == GOLDEN[robots]
