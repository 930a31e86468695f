"""Dyna-Q's model of the transitions seen, and its section of the Q-table file.

The model itself (what it keeps, how it is drawn from) is described in
:mod:`koolio_pymunk.learning.dyna`; here it is read and written. It lives below the
Q-table (:mod:`koolio_pymunk.store.qtable` checks a table's ``dyna_model`` section
with :meth:`Model.from_bytes` when it reads the file, so a bad model is refused with the
table, before a run writes anything).

**Checks** (the robot runtime's ``Model.from_json`` makes the same ones, with the same
functions: :func:`~koolio_pymunk.robot_runtime.state_problem`,
:func:`~koolio_pymunk.robot_runtime.action_problem`,
:func:`~koolio_pymunk.robot_runtime.outcome_problem`): every state and next state inside
the table's keyword layout (its bits, and each field's code below its levels), every
action in the action set, rewards finite and at most 1e15 in size (the configuration's
bound), terminal flags 0 or 1, counts in 1..2**53 and each pair's total too, no pair or
outcome twice. A reward of NaN, a state beyond the layout or a count of 2**64 - 1 was
accepted and poisoned the next save.
"""

from __future__ import annotations

import struct

import numpy as np

from .. import robot_runtime as rt
from .errors import QTableError, located
from .keyword import KeywordLayout

#: Name of the model's section in the Q-table file.
SECTION = "dyna_model"


class Model(rt.Model):
    """Every (state, action) pair seen, with the counted outcomes of each (module doc):
    the robot runtime's :class:`~koolio_pymunk.robot_runtime.Model` (one recording and
    one :meth:`~koolio_pymunk.robot_runtime.Model.sample` for the simulator and the
    robot), read and written as the Q-table file's section."""

    def __eq__(self, other: object) -> bool:
        """The same pairs and outcomes, in the same order (the same bytes)."""
        return isinstance(other, Model) and bytes(self) == bytes(other)

    __hash__ = None  # type: ignore[assignment]  # recorded into: not hashable

    def __bytes__(self) -> bytes:
        n = len(self.pairs)
        flat = [o for outs in self.outcomes for o in outs]
        parts = [
            struct.pack("<QQ", n, len(flat)),
            np.array([p[0] for p in self.pairs], "<u8").tobytes(),
            np.array([p[1] for p in self.pairs], "<u8").tobytes(),
            np.array([len(outs) for outs in self.outcomes], "<u8").tobytes(),
            np.array([o[0] for o in flat], "<u8").tobytes(),
            np.array([o[1] for o in flat], "<f8").tobytes(),
            np.array([int(o[2]) for o in flat], "<u8").tobytes(),
            np.array([o[3] for o in flat], "<u8").tobytes(),
        ]
        return b"".join(parts)

    @classmethod
    def from_bytes(
        cls, data: bytes, source: str = "<model>", layout: KeywordLayout | None = None
    ) -> Model:
        """The model of a ``dyna_model`` section; QTableError when malformed. With
        ``layout`` (the table's), every state and action is checked against it too
        (module doc)."""
        model = cls()
        if not data:
            return model
        bad = QTableError(located(source, SECTION, "malformed Dyna-Q model"))
        if len(data) < 16:
            raise bad
        n, m = struct.unpack_from("<QQ", data)
        if len(data) != 16 + 8 * (3 * n + 4 * m):
            raise bad
        arrays = []
        pos = 16
        for count, dtype in ((n, "<u8"),) * 3 + ((m, "<u8"), (m, "<f8"), (m, "<u8"), (m, "<u8")):
            arrays.append(np.frombuffer(data, dtype, count, pos).tolist())
            pos += 8 * count
        states, actions, sizes, nexts, rewards, terminals, counts = arrays
        if sum(sizes) != m or any(s < 1 for s in sizes):
            raise bad
        _check_entries(arrays, source, layout)
        k = 0
        for state, action, size in zip(states, actions, sizes):
            outs = [
                [nexts[j], rewards[j], bool(terminals[j]), counts[j]] for j in range(k, k + size)
            ]
            if (state, action) in model or len({(o[0], o[1], o[2]) for o in outs}) != size:
                raise bad  # a pair, or an outcome of a pair, twice
            model.add(state, action, outs)
            k += size
        return model


def _check_entries(arrays: list[list], source: str, layout: KeywordLayout | None) -> None:
    """The checks of the module doc on the section's arrays, pair by pair."""
    states, actions, sizes, nexts, rewards, terminals, counts = arrays
    k = 0
    for i, (state, action, size) in enumerate(zip(states, actions, sizes)):
        problem = None
        if layout is not None:
            problem = rt.state_problem(state, layout) or rt.action_problem(action, layout)
        for j in range(k, k + size):
            if problem:
                break
            if terminals[j] > 1:
                problem = f"terminal {terminals[j]} is not 0 or 1"
            else:
                problem = rt.outcome_problem(rewards[j], bool(terminals[j]), counts[j])
            if problem is None and layout is not None:
                problem = rt.state_problem(nexts[j], layout)
        if problem is None and sum(counts[k : k + size]) > rt.MAX_COUNT:
            problem = "its counts sum to more than 2**53"
        if problem:
            raise QTableError(located(source, SECTION, f"pair {i}: {problem}"))
        k += size
