"""Dyna-Q: learning from a model of the transitions seen (``learner.algorithm: dyna``).

After every real step's Table 11 update, the step is recorded in the model and
``learner.planning_steps`` more Table 11 updates are made from transitions drawn from the
model (Sutton and Barto, *Reinforcement Learning*, 2nd ed., §8.2). Planning spreads a
reward found at the door plate over the states that lead there without driving the
robot again: on the real robot, where an episode costs minutes, that is the point.

**The model.** The simulated world is not deterministic for the learner: sensor noise,
and aliasing (one keyword stands for many poses), make the same state and action lead to
different next states and rewards. The model therefore keeps, for every (state, action)
pair seen, every distinct outcome ``(next_state, reward, terminal)`` with the number of
times it happened: the empirical distribution of the pair's outcomes. A planning update
draws a pair uniformly among the pairs seen, then one of its outcomes with probability
proportional to its count, and applies Table 11 to it. Two uniform draws in [0, 1) per
update, from the episode's generator: ``pair = int(u1 * n_pairs)``; the outcome is the
first whose cumulative count exceeds ``u2 * total``. The model records the state an action
led to before any auto rescue, as the real update bootstraps from it (paper §5.4.8).

**Saved between sessions.** The model is part of the Q-table: the section
``dyna_model`` of the ``.qtable`` file (:mod:`koolio_pymunk.qtable`), written with the
table at every episode end and covered by its CRC, so a resumed run draws from the same
model as an uninterrupted one and continues exactly. Pairs and outcomes keep their
first-seen order (the draws depend on it). Section layout, little-endian::

    uint64 n_pairs, n_outcomes
    uint64 state[n_pairs], action[n_pairs], outcomes[n_pairs]   (outcomes of each pair)
    uint64 next_state[n_outcomes]; float64 reward[n_outcomes];
    uint64 terminal[n_outcomes], count[n_outcomes]              pair by pair

>>> model = Model()
>>> model.record(5, 3, -0.5, 6, False)
>>> model.record(5, 3, -0.5, 6, False)
>>> model.record(5, 3, -5.0, 7, False)
>>> model.pairs, model.outcomes[0]
([(5, 3)], [[6, -0.5, False, 2], [7, -5.0, False, 1]])
>>> model.sample(0.0, 0.5), model.sample(0.0, 0.7)
((5, 3, -0.5, 6, False), (5, 3, -5.0, 7, False))
>>> Model.from_bytes(bytes(model)).outcomes == model.outcomes
True
"""

from __future__ import annotations

import struct

import numpy as np

from .config import LearnerConfig
from .errors import QTableError, located
from .learner import QLearner
from .qtable import QTable

#: Name of the model's section in the Q-table file.
SECTION = "dyna_model"


class Model:
    """Every (state, action) pair seen, with the counted outcomes of each (module doc)."""

    def __init__(self) -> None:
        self.pairs: list[tuple[int, int]] = []
        """``(state, action)`` in first-seen order."""
        self.outcomes: list[list[list]] = []
        """Per pair: ``[next_state, reward, terminal, count]`` in first-seen order."""
        self.totals: list[int] = []
        """Per pair: the sum of its counts."""
        self._pair: dict[tuple[int, int], int] = {}
        self._outcome: list[dict[tuple[int, float, bool], list]] = []

    def __len__(self) -> int:
        return len(self.pairs)

    def record(self, state: int, action: int, reward: float, nxt: int, terminal: bool) -> None:
        """Count one real transition."""
        i = self._pair.get((state, action))
        if i is None:
            i = len(self.pairs)
            self._pair[(state, action)] = i
            self.pairs.append((state, action))
            self.outcomes.append([])
            self.totals.append(0)
            self._outcome.append({})
        key = (nxt, reward, terminal)
        out = self._outcome[i].get(key)
        if out is None:
            out = [nxt, reward, terminal, 0]
            self._outcome[i][key] = out
            self.outcomes[i].append(out)
        out[3] += 1
        self.totals[i] += 1

    def sample(self, u1: float, u2: float) -> tuple[int, int, float, int, bool]:
        """``(state, action, reward, next_state, terminal)`` for draws ``u1, u2`` in [0, 1)."""
        i = int(u1 * len(self.pairs))
        x = u2 * self.totals[i]
        seen = 0
        for out in self.outcomes[i]:
            seen += out[3]
            if x < seen:
                break
        state, action = self.pairs[i]
        return state, action, out[1], out[0], out[2]

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
    def from_bytes(cls, data: bytes, source: str = "<model>") -> Model:
        """The model of a ``dyna_model`` section; QTableError when malformed."""
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
        if sum(sizes) != m or any(s < 1 for s in sizes) or any(c < 1 for c in counts):
            raise bad
        k = 0
        for i, (state, action, size) in enumerate(zip(states, actions, sizes)):
            model._pair[(state, action)] = i
            model.pairs.append((state, action))
            outs = [
                [nexts[j], rewards[j], bool(terminals[j]), counts[j]] for j in range(k, k + size)
            ]
            model.outcomes.append(outs)
            model.totals.append(sum(counts[k : k + size]))
            model._outcome.append({(o[0], o[1], o[2]): o for o in outs})
            k += size
        if len(model._pair) != n or any(
            len(d) != len(o) for d, o in zip(model._outcome, model.outcomes)
        ):
            raise bad
        return model


class DynaQ(QLearner):
    """Dyna-Q: Table 11 on each real step, then ``planning_steps`` updates from the model."""

    name = "dyna"
    sections = (SECTION,)

    def __init__(
        self,
        table: QTable,
        cfg: LearnerConfig,
        rng: np.random.Generator,
        source: str = "<table>",
    ) -> None:
        super().__init__(table, cfg, rng)
        self.planning_steps = cfg.planning_steps
        found = table.sections.get(SECTION, b"")
        self.model = found if isinstance(found, Model) else Model.from_bytes(bytes(found), source)
        table.sections[SECTION] = self.model  # serialized with the table at every save

    def observe(
        self, state: int, action: int, reward: float, next_state: int, terminal: bool
    ) -> None:
        self.update(state, action, reward, next_state, terminal)
        model = self.model
        model.record(state, action, reward, next_state, terminal)
        n = self.planning_steps
        if n:
            draws = self.rng.random(2 * n).tolist()
            update = self.update
            for k in range(0, 2 * n, 2):
                s, a, r, s2, t = model.sample(draws[k], draws[k + 1])
                update(s, a, r, s2, t)
