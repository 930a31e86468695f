"""A learning session stepped from outside: the training loop of ``koolio-pm train``, one
step at a time, for the window (paper §5.4.9).

:class:`Session` uses the very pieces :func:`koolio_pymunk.training.train` uses --
:class:`~koolio_pymunk.qtable.QTableStore` (table saved at every episode end),
:class:`~koolio_pymunk.training.LogWriter`, :func:`~koolio_pymunk.training.episode_seeds`,
:func:`~koolio_pymunk.learner.make_learner` and ``KoolioEnv.transition`` -- in the same order,
so a window run of E episodes writes the same Q-table bytes and log rows as ``train
--episodes E`` with the same seed (as long as nobody forces a rescue or flips a toggle),
and the two can hand a table back and forth.

Exit (:meth:`Session.exit` with ``save=True``) folds the unfinished episode into the table
and saves it, logging an ``interrupted`` row, like Ctrl-C in ``train``; Exit Without Save
(``save=False``) leaves the table file as it was after the last finished episode.

With ``greedy=True`` the session only watches: epsilon 0, no updates, nothing written
(the table file must exist); its episodes are those of ``koolio-pm eval`` with the same
seed (the evaluation seed stream).

An episode that ends is saved at once, but the environment is reset lazily at the next
step, so a viewer can still draw the final state (robot black at the goal, purple past
the end of the world).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..arena import arena_record
from ..env import KoolioEnv
from ..episode_log import LogWriter, log_rows
from ..errors import KoolioError, located
from ..learner import QLearner, make_learner
from ..qtable import QTableStore, check_compatible, load_qtable
from ..training import (
    EVAL_STREAM,
    TRAIN_STREAM,
    EpisodeResult,
    episode_seeds,
    open_run,
    sensor_signature,
)


@dataclass
class Stats:
    """What the Stats panel shows: totals of this session and every episode's return."""

    episodes: int = 0
    goals: int = 0
    reward_sum: float = 0.0
    steps_sum: int = 0
    bumps_sum: int = 0
    returns: list[float] = field(default_factory=list)
    """Return of every finished episode: earlier ones from the log, then this session's."""
    at_goal: list[bool] = field(default_factory=list)
    """Whether each episode of :attr:`returns` ended at the goal."""
    run_start: int = 0
    """Index in ``returns`` of this session's first episode."""

    def add(self, r: EpisodeResult) -> None:
        self.episodes += 1
        self.goals += r.outcome == "goal"
        self.reward_sum += r.reward
        self.steps_sum += r.steps
        self.bumps_sum += r.bumps
        self.returns.append(r.reward)
        self.at_goal.append(r.outcome == "goal")

    def mean(self, total: float) -> float:
        return total / self.episodes if self.episodes else math.nan

    @property
    def goal_rate(self) -> float:
        return self.goals / self.episodes if self.episodes else math.nan


def read_returns(path: str | Path) -> list[float]:
    """Returns of the finished episodes of a training log (``interrupted`` rows skipped).

    A missing or empty file gives ``[]``; a malformed one (or not a log at all: a binary
    file, an arena) raises :class:`KoolioError`.
    """
    return read_history(path)[0]


def read_history(path: str | Path) -> tuple[list[float], list[bool]]:
    """Return of each finished episode of a training log, and whether it ended at the goal
    (``interrupted`` rows skipped). A missing or empty file gives ``([], [])``; a
    malformed one (or not a log at all: a binary file, an arena) raises
    :class:`KoolioError`."""
    out: list[float] = []
    goal: list[bool] = []
    for line, row in enumerate(log_rows(path), start=2):
        if row.get("outcome") == "interrupted":
            continue
        try:
            value = float(row["reward"])
        except (KeyError, TypeError, ValueError):
            value = math.nan
        if not math.isfinite(value):
            raise KoolioError(located(str(path), f"line {line}", "reward: not a number"))
        out.append(value)
        goal.append(row.get("outcome") == "goal")
    return out, goal


class Session:
    """Step-by-step episodic Q-learning (or greedy watching) on ``env``.

    ``episodes`` limits how many episodes this session runs (None: no limit); after the
    last one :attr:`done` is True and :meth:`step` does nothing.
    """

    def __init__(
        self,
        env: KoolioEnv,
        qtable: str | Path,
        *,
        seed: int = 0,
        episodes: int | None = None,
        log: str | Path | None = None,
        greedy: bool = False,
    ) -> None:
        self.env = env
        self.seed = seed
        self.learn = not greedy
        self.table_path = Path(qtable)
        """The Q-table file (written while learning, only read with ``greedy``)."""
        cfg = env.config
        self.store: QTableStore | None = None
        if self.learn:  # the table and the log locked while the window learns
            self.store = QTableStore(qtable, purpose="koolio-pm view")
            self.table, self.log = open_run(env, self.store, log, "koolio-pm view")
            self.first = int(self.table.meta.get("episodes", 0))
        else:
            if not Path(qtable).exists():
                raise KoolioError(located(str(qtable), "", "no such Q-table file (--greedy)"))
            self.table = load_qtable(qtable)
            check_compatible(
                self.table, env.layout, sensor_signature(cfg), str(qtable), arena_record(env.arena)
            )
            self.first = 0
            self.log = LogWriter(None)
        self.stats = Stats()
        if self.learn and log:
            self.stats.returns, self.stats.at_goal = read_history(log)
            self.stats.run_start = len(self.stats.returns)
        rng = np.random.default_rng(seed)
        if self.learn:
            self.agent = make_learner(self.table, cfg.learner, rng, str(qtable))
        else:
            self.agent = QLearner(self.table, cfg.learner, rng)
        self.episode = self.first
        self.last = None if episodes is None else self.first + episodes
        self.total_steps = 0
        self.results: list[EpisodeResult] = []
        self.done = self.last is not None and self.episode >= self.last
        self.closed = False
        self._pending_reset = True
        if not self.done:
            self._begin()

    # -- stepping ------------------------------------------------------------------------
    def _begin(self) -> None:
        stream = TRAIN_STREAM if self.learn else EVAL_STREAM
        env_seed, rng = episode_seeds(self.seed, self.episode, stream)
        self.agent.begin_episode(self.episode, rng)
        if not self.learn:
            self.agent.epsilon = 0.0
        self.env.reset(seed=env_seed)
        self._pending_reset = False

    @property
    def episode_over(self) -> bool:
        """The last step ended an episode (the env still shows its final state)."""
        return self._pending_reset

    def run(self, n: int) -> int:
        """Perform up to ``n`` steps (fewer when the session is done); returns how many."""
        if self.closed:
            return 0
        env, agent, learn = self.env, self.agent, self.learn
        act, observe, transition = agent.act, agent.observe, env.transition
        done = 0
        while done < n and not self.done:
            if self._pending_reset:
                self._begin()
            state = env.state_key
            action = act(state)
            nxt, reward, terminated, truncated = transition(action)
            if learn:  # from the state the action led to, before any rescue (§5.4.8)
                observe(state, action, reward, nxt, terminated)
            done += 1
            if terminated or truncated:
                outcome = env.judgement.event if terminated else "truncated"  # type: ignore[union-attr]
                self._finish(outcome)
        self.total_steps += done
        return done

    def step(self) -> bool:
        """One step; False when the session is done."""
        return self.run(1) == 1

    def _result(self, outcome: str, episode: int) -> EpisodeResult:
        env = self.env
        return EpisodeResult(
            episode,
            env.episode_reward,
            env.steps,
            env.bumps,
            outcome,
            env.has_been_rescued,
            self.agent.epsilon,
            env.goal_name,
        )

    def _finish(self, outcome: str) -> None:
        res = self._result(outcome, self.episode)
        if self.learn:
            assert self.store is not None
            self.table.meta["episodes"] = self.episode + 1
            self.store.save(self.table)
            self.log.write(res)
        self.results.append(res)
        self.stats.add(res)
        self.episode += 1
        self._pending_reset = True
        if self.last is not None and self.episode >= self.last:
            self.done = True

    # -- controls --------------------------------------------------------------------------
    def rescue(self) -> bool:
        """Force ``Rescue_Robot`` now (the Rescue button); False when there is no episode."""
        if self.closed or (self.done and self._pending_reset):
            return False
        if self._pending_reset:
            self._begin()
        self.env.rescue()
        return True

    @property
    def unfinished_steps(self) -> int:
        """Steps of the episode in progress (0 when none is)."""
        return 0 if self._pending_reset else self.env.steps

    def exit(self, save: bool = True) -> EpisodeResult | None:
        """End the session: Exit (``save``) or Exit Without Save.

        Exit folds the unfinished episode's updates into the table, saves it and logs an
        ``interrupted`` row (table ``episodes`` unchanged, as ``train`` does on Ctrl-C).
        Exit Without Save writes nothing: the file keeps the table of the last finished
        episode. Returns the folded episode's row, if any.
        """
        if self.closed:
            return None
        self.closed = True
        res = None
        if save and self.learn and self.unfinished_steps > 0:
            assert self.store is not None
            res = self._result("interrupted", int(self.table.meta.get("episodes", self.first)))
            self.store.save(self.table)
            self.log.write(res)
            self.results.append(res)
        self.log.close()
        if self.store is not None:
            self.store.close()
        return res
