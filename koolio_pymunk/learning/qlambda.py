"""Watkins's Q(lambda) with replacing traces (``learner.algorithm: qlambda``).

One-step Q (Table 11) moves one entry per step: a reward found at the door plate climbs
back down the hallway one state per episode. Q(lambda) keeps an *eligibility trace* for
the entries of the recent steps and moves all of them by the step's TD error (Sutton and
Barto, *Reinforcement Learning*, 2nd ed., §12.10; Watkins 1989)::

    delta = reward + gamma * max(Q(next_state)) - Q(state, action)   (reward alone at the end)
    e(state, .) = 0; e(state, action) = 1                              replacing trace
    for every traced (s, a):  Q(s, a) += alpha * delta * e(s, a);  e(s, a) *= gamma * lambda

* **Watkins's cut**: the traces are about the greedy policy, so they are cleared when the
  action chosen is not greedy (an exploratory action whose Q is below the state's best);
  they are cleared too when the next step does not start where the last one ended (an
  auto rescue moved the robot) and at every episode start.
* **Cheap steps**: a trace below ``learner.trace_cutoff`` is dropped; with gamma 0.98,
  lambda 0.9 and cutoff 0.01 at most 37 entries are traced.
* With replacing traces a state has at most one traced action (a visit clears the
  others), so the traces are a dict ``state -> [action, e]`` in first-traced order.
* Lambda 0 is one-step Q exactly: the same Q values, bit for bit
  (``tests/learning/test_algorithms.py``).

Traces live within an episode: nothing is saved between sessions but the Q values.
Aliased sensor states (a 27-bit keyword cannot tell two stretches of hallway apart) make
the task non-Markov; traces soften that too, since the value reaching a state comes from
the steps really taken after it rather than only from the next state's estimate.

>>> import numpy as np
>>> from koolio_pymunk.store.config import LearnerConfig
>>> from koolio_pymunk.store.qtable import KeywordLayout, QTable
>>> table = QTable(KeywordLayout((("A", 8),)))
>>> cfg = LearnerConfig(algorithm="qlambda", alpha=0.5, gamma=1.0, trace_decay=0.5)
>>> agent = QLambda(table, cfg, np.random.default_rng(0))
>>> agent.observe(0, 3, 0.0, 1, terminal=False)
>>> agent.observe(1, 3, 8.0, 2, terminal=True)   # delta 8: Q(1,3) += 4, Q(0,3) += 2
>>> table.get(1, 3), table.get(0, 3)
(4.0, 2.0)
"""

from __future__ import annotations

import numpy as np

from ..store.config import LearnerConfig
from ..store.qtable import QTable
from ..task.action_rules import allowed
from .qlearning import QLearner, td_step, td_target


class QLambda(QLearner):
    """Watkins's Q(lambda), replacing traces, traces cut after a non-greedy action."""

    name = "qlambda"

    def __init__(self, table: QTable, cfg: LearnerConfig, rng: np.random.Generator) -> None:
        super().__init__(table, cfg, rng)
        self.decay = cfg.gamma * cfg.trace_decay
        self.cutoff = cfg.trace_cutoff
        self.traces: dict[int, list] = {}
        """``state -> [action, e]``: the traced entries, first traced first."""
        self._expect: int | None = None

    def begin_episode(self, episode: int, rng: np.random.Generator) -> None:
        super().begin_episode(episode, rng)
        self.traces.clear()
        self._expect = None

    def act(self, state: int) -> int:
        if state != self._expect:  # not where the last step ended: a rescue moved it
            self.traces.clear()
        return super().act(state)

    def explore(self, state: int) -> int:
        """A uniform random action; Watkins's cut when it is not a greedy one."""
        bar = self.bar  # before the choice: act() moves ``last`` after it
        action = super().explore(state)
        row = self.table.peek(state)
        if row is not None and row[action] < max(row[a] for a in allowed(self.n_actions, bar)):
            self.traces.clear()
        return action

    def observe(
        self, state: int, action: int, reward: float, next_state: int, terminal: bool
    ) -> None:
        rows = self.table.rows
        row = self.table.row(state)
        target = td_target(reward, rows.get(next_state), self.table.q_init, self.gamma, terminal)
        step = td_step(row[action], target, self.alpha)
        traces = self.traces
        traces[state] = [action, 1.0]
        decay, cutoff = self.decay, self.cutoff
        dropped = []
        for s, tr in traces.items():
            rows[s][tr[0]] += step * tr[1]
            tr[1] *= decay
            if tr[1] < cutoff:
                dropped.append(s)
        for s in dropped:
            del traces[s]
        self._expect = None if terminal else next_state
