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
``dyna_model`` of the ``.qtable`` file (:mod:`koolio_pymunk.store.qtable`), written with the
table at every episode end and covered by its CRC, so a resumed run draws from the same
model as an uninterrupted one and continues exactly. Pairs and outcomes keep their
first-seen order (the draws depend on it). Section layout, little-endian::

    uint64 n_pairs, n_outcomes
    uint64 state[n_pairs], action[n_pairs], outcomes[n_pairs]   (outcomes of each pair)
    uint64 next_state[n_outcomes]; float64 reward[n_outcomes];
    uint64 terminal[n_outcomes], count[n_outcomes]              pair by pair

The section is checked when the table is read (:mod:`koolio_pymunk.store.dyna_model`:
states inside the layout, actions in the action set, finite bounded rewards, counts in
1..2**53), so a bad model is refused with the table, before anything is written.

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

import numpy as np

from ..store.config import LearnerConfig
from ..store.dyna_model import SECTION, Model
from ..store.qtable import QTable
from .qlearning import QLearner


class DynaQ(QLearner):
    """Dyna-Q: Table 11 on each real step, then ``planning_steps`` updates from the model."""

    name = "dyna"
    sections = (SECTION,)

    def __init__(self, table: QTable, cfg: LearnerConfig, rng: np.random.Generator) -> None:
        super().__init__(table, cfg, rng)
        self.planning_steps = cfg.planning_steps
        # The table's model, read and checked with the table (QTable.from_bytes), or a
        # new one; it stays in the table, which serializes it at every save.
        model = table.sections.setdefault(SECTION, Model())
        if not isinstance(model, Model):
            raise TypeError(
                f"the table's {SECTION} section is {type(model).__name__}, not a Model "
                "(QTable.from_bytes parses it when it reads a table)"
            )
        self.model = model

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
