"""The window's hold on the episode loop: learning (or watching) one step at a time.

:class:`Session` drives :class:`~koolio_pymunk.learning.episodes.Episodes`, the episode
loop of ``koolio-pm train``, one step per call as the window asks (paper §5.4.9), and
records every finished episode through :class:`~koolio_pymunk.learning.training.RunFiles`
as ``train`` does (table saved at every episode end, then the log row, with the same
columns in every world). A window run of E episodes therefore writes the same Q-table
bytes and log rows as ``train --episodes E`` with the same seed (as long as nobody forces
a rescue or flips a toggle), and the two can hand a table back and forth.

Exit (:meth:`Session.exit` with ``save=True``) folds the unfinished episode into the table
and saves it, logging an ``interrupted`` row, like Ctrl-C in ``train``; Exit Without Save
(``save=False``) leaves the table file as it was after the last finished episode.

With ``greedy=True`` the session only watches: epsilon 0, no updates, nothing written
(the table file, or its backup, must exist: :func:`watched_table`); its episodes are those
of ``koolio-pm eval`` with the same seed (the evaluation seed stream).

An episode that ends is saved at once, but the environment is reset lazily at the next
step, so a viewer can still draw the final state (robot black at the goal, purple past
the end of the world). :class:`Stats` is what the Stats panel shows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from ...learning import run_identity
from ...learning.algorithms import make_learner
from ...learning.episodes import EVAL_STREAM, INTERRUPTED, TRAIN_STREAM, EpisodeResult, Episodes
from ...learning.qlearning import QLearner
from ...learning.qtable import QTable, QTableStore
from ...learning.training import RunFiles
from ...store.episode_log import log_rows
from ...store.errors import KoolioError, located
from ...task.env import KoolioEnv


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


def watched_table(env: KoolioEnv, qtable: str | Path, warn: bool = True) -> QTable:
    """The table a greedy session watches, checked for ``env`` (purpose ``watch`` of
    :func:`~koolio_pymunk.learning.run_identity.check`); its backup when the file is
    damaged or missing, with a warning unless not ``warn``, as ``train`` and ``eval`` read
    it."""
    table = QTableStore(qtable).peek(warn=warn)
    if table is None:
        raise KoolioError(
            located(str(qtable), "", "no such Q-table file (--greedy): run koolio-pm train first")
        )
    run_identity.check(table, env, "watch", str(qtable))  # its warnings once per process
    return table


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
        self.files: RunFiles | None = None
        if self.learn:  # the table and the log locked while the window learns
            store = QTableStore(qtable, purpose="koolio-pm view")
            run = run_identity.RunIdentity.of_run(env)
            self.files = RunFiles.open(run, store, log, "koolio-pm view", seed)
            self.table = self.files.table
            self.first = self.files.first
            self.agent = make_learner(self.table, cfg.learner, None, str(qtable))
            self.loop = Episodes(env, self.agent, seed, TRAIN_STREAM)
        else:
            self.table = watched_table(env, qtable)
            self.first = 0
            self.agent = QLearner(self.table, cfg.learner, None)
            self.loop = Episodes(env, self.agent, seed, EVAL_STREAM, learn=False, epsilon=0.0)
        self.stats = Stats()
        if self.learn and log:
            self.stats.returns, self.stats.at_goal = read_history(log)
            self.stats.run_start = len(self.stats.returns)
        self.episode = self.first
        self.last = None if episodes is None else self.first + episodes
        self.total_steps = 0
        self.results: list[EpisodeResult] = []
        self.done = self.last is not None and self.episode >= self.last
        self.closed = False
        self._pending_reset = True
        # The next episode's start is shown even when there is nothing to run (``view
        # --episodes 0``): an env that was never reset has no reading to draw.
        self._begin()

    # -- stepping ------------------------------------------------------------------------
    def _begin(self) -> None:
        self.loop.begin(self.episode)
        self._pending_reset = False

    @property
    def log_path(self) -> Path | None:
        """The log this session writes (None: none, or watching)."""
        files = self.files
        return None if files is None or not files.log.path else Path(files.log.path)

    @property
    def episode_over(self) -> bool:
        """The last step ended an episode (the env still shows its final state)."""
        return self._pending_reset

    def run(self, n: int) -> int:
        """Perform up to ``n`` steps (fewer when the session is done); returns how many."""
        if self.closed:
            return 0
        step = self.loop.step
        done = 0
        while done < n and not self.done:
            if self._pending_reset:
                self._begin()
            outcome = step()
            done += 1
            if outcome is not None:
                self._finish()
        self.total_steps += done
        return done

    def step(self) -> bool:
        """One step; False when the session is done."""
        return self.run(1) == 1

    def _finish(self) -> None:
        res = self.loop.result()
        if self.files is not None:
            self.files.finished(res)
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
        files = self.files
        if files is None:
            return None
        try:
            if save and self.unfinished_steps > 0:
                episode = int(self.table.meta.get("episodes", self.first))
                res = self.loop.result(INTERRUPTED, episode=episode)
                files.folded(res)
                self.results.append(res)
        finally:
            files.close()
        return res
