"""Evaluating a table, and the best policy kept: ``koolio-pm eval`` and ``train --eval-every``.

:func:`evaluate` runs a table's policy without learning: greedy (epsilon 0, ``koolio-pm
eval``), or epsilon-greedy with a given epsilon, the acting policy as the robot runs it
(``eval --epsilon E``). Episode ``e`` of an evaluation with seed ``s`` starts from the
seeds of the evaluation stream (:data:`~koolio_pymunk.learning.episodes.EVAL_STREAM`),
which training never uses; the exploratory draws come from the episode's own generator.

**The periodic check** (:class:`PeriodicCheck`, ``koolio-pm train --eval-every N``): each
time the table's episode count reaches a multiple of N, the run evaluates the table
greedily for M episodes (``--eval-episodes``, 100 by default) with the run's seed, the
same episodes ``koolio-pm eval --seed S --episodes M`` would run, and goes on training.
A check reads the table and resets the environment with seeds of its own stream; training
draws nothing for it, so a run with checks writes the same table and log bytes as one
without. Each check is a row of the evaluations file (``X.evals.csv`` beside the log
``X.csv``; beside the table ``X.qtable`` when there is no log)::

    episode,eval_episodes,seed,goal_rate,end_of_world_rate,wrong_door_rate,truncated_rate,mean_steps,mean_bumps,mean_return,best,seconds

``episode`` is the number of training episodes the table held (the check follows the
log's row ``episode - 1``); the rates are shares (0..1) of the M episodes; ``best`` is 1
when the check's table is the kept best table when the check ends; ``seconds`` is the
check's wall time (the one column that differs between two runs of one seed).

**The best table** ``X.best.qtable`` (for ``--qtable X.qtable``) is a copy of the table
at its best check, a normal table file (``eval``, ``export``, ``view --greedy``,
``transfer --qtable`` and ``train --init-qtable`` read it) whose header records the check
under ``best``: ``{"episode", "goal_rate", "mean_return", "mean_steps", "eval_episodes",
"seed"}``. A check is better when its goal rate is higher, or equal with a higher mean
return; an exact tie keeps the earlier table. The best is the best over the table's whole
life: a session compares its checks with the best kept by the sessions before it and
keeps that one when its own are worse. The best table is written atomically with a
backup and locked like the table (:class:`~koolio_pymunk.store.qtable.QTableStore`).

**Stopped and resumed.** The table is saved before its check, the best table before the
check's row: a run stopped at any point (Ctrl-C, SIGKILL) and resumed continues exactly
like an uninterrupted one. A resumed run whose table count is a multiple of N and lacks
that check's row runs it first (the check of a saved table is exact, so it scores what
it scored); rows beyond the table's count (a table that fell back to its backup) move to
``<evals>.removed`` with a warning and run again. A check under way when Ctrl-C comes is
dropped (the run stops at once) and runs again on resume.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..store.check_files import CheckFiles
from ..store.qtable import QTable, QTableStore
from ..task.env import KoolioEnv
from .episodes import EVAL_STREAM, EpisodeResult
from .qlearning import QLearner

#: Greedy episodes per check when ``--eval-episodes`` is not given.
DEFAULT_EVAL_EPISODES = 100


@dataclass
class EvalResult:
    """The figures of an evaluation (``koolio-pm eval``, a periodic check)."""

    episodes: int
    goal_rate: float
    end_of_world_rate: float
    truncated_rate: float
    wrong_door_rate: float
    """Stops at another door whose plate a camera misread (realism ``camera.misread``)."""
    mean_steps: float
    mean_bumps: float
    mean_reward: float
    goal: str
    robot_goal_rates: list[float] | None = None
    """Robots sharing an arena (``shared_arena``): each robot's goal rate over the
    episodes it played (None: the robots were alone, and which robot played an episode
    does not matter)."""
    robot_goals: list[str] | None = None
    """Robots sharing an arena: each robot's goal (``shared.goals`` may give each its own;
    :attr:`goal` is robot 0's)."""

    def as_dict(self) -> dict[str, Any]:
        """The figures by name (``koolio-pm eval --json``)."""
        return dict(self.__dict__)


class EvaluationStopped(Exception):
    """An evaluation's ``stop`` asked it to end before its last episode."""


def evaluate(
    env: KoolioEnv,
    table: QTable,
    episodes: int,
    seed: int,
    goal: str | None = None,
    epsilon: float = 0.0,
    stop: Callable[[], bool] | None = None,
    robots: int = 1,
    compiled: bool = True,
    shared_arena: bool = False,
) -> EvalResult:
    """Run ``table``'s policy for ``episodes`` episodes without learning (module doc).

    ``goal`` scores that goal of the arena (it stays ``env``'s active goal afterwards, as
    ``reset``'s option does; ``ValueError`` for a name the arena lacks, ``random``
    included: score each goal in turn instead); None scores ``env``'s active goal, or, in
    an env made with ``goal="random"``, a door drawn per episode (the result's ``goal`` is
    then ``random``).
    ``epsilon`` 0 is the greedy policy; above 0 a uniform random action is taken with that
    probability, drawn from each episode's seeded generator. ``stop`` is asked before each
    episode; a true answer raises :class:`EvaluationStopped`.

    ``robots`` > 1 plays that many episodes at once (``env`` and its siblings, on the
    compiled step engine when it runs this configuration, ``compiled``): episode ``e``
    has its own seeds whichever robot plays it and the table is only read, so the scores
    are exactly those of one episode after another. With ``shared_arena`` the robots
    play in one arena, meeting each other (:mod:`koolio_pymunk.task.shared_arena`): an
    episode's course then depends on the others, and the result gives each robot's goal
    rate too.
    """
    from .engine import robots as make_robots  # numba: loaded when an evaluation starts

    options = {"goal": goal} if goal else None
    env.check_options(options)
    n = max(1, min(robots, episodes)) if not shared_arena else max(1, robots)
    agents = [QLearner(table, env.config.learner, None) for _ in range(n)]
    loop = make_robots(env, agents, seed, EVAL_STREAM, learn=False, epsilon=epsilon,
                       compiled=compiled, shared=shared_arena)  # fmt: skip
    results: list[EpisodeResult | None] = [None] * episodes
    players = [0] * episodes
    started = 0

    def start(r: int) -> None:
        nonlocal started
        if started == episodes:
            loop.release(r)
            return
        if stop is not None and stop():
            raise EvaluationStopped
        loop.begin(r, started, options)
        started += 1

    for r in range(n):
        start(r)
    for _ in range(episodes):
        r = loop.advance()
        if r is None:  # pragma: no cover (a robot runs while episodes are left)
            break
        res = loop.result(r)
        results[res.episode] = res
        players[res.episode] = r
        start(r)
    loop.sync()
    done = [res for res in results if res is not None]
    outcomes = [res.outcome for res in done]
    steps = [res.steps for res in done]
    bumps = [res.bumps for res in done]
    rewards = [res.reward for res in done]
    n_done = max(1, episodes)
    return EvalResult(
        episodes=episodes,
        goal_rate=outcomes.count("goal") / n_done,
        end_of_world_rate=outcomes.count("end_of_world") / n_done,
        truncated_rate=outcomes.count("truncated") / n_done,
        wrong_door_rate=outcomes.count("wrong_door") / n_done,
        mean_steps=float(np.mean(steps)) if steps else 0.0,
        mean_bumps=float(np.mean(bumps)) if bumps else 0.0,
        mean_reward=float(np.mean(rewards)) if rewards else 0.0,
        goal="random" if env.random_goal and not goal else env.goal_name,
        robot_goal_rates=_robot_goal_rates(done, players, n) if shared_arena else None,
        robot_goals=[("random" if e.random_goal else e.goal_name) for e in loop.envs]
        if shared_arena
        else None,
    )


def _robot_goal_rates(done: list[EpisodeResult], players: list[int], n: int) -> list[float]:
    """Each robot's goal rate over the episodes it played (0 for a robot that played none)."""
    played = [[res.outcome for res in done if players[res.episode] == r] for r in range(n)]
    return [p.count("goal") / len(p) if p else 0.0 for p in played]


def score(goal_rate: float, mean_return: float) -> tuple[float, float]:
    """What "better" compares: the goal rate, then the mean return (module doc)."""
    return (goal_rate, mean_return)


@dataclass
class Check:
    """One periodic check: the table at ``episode`` training episodes, evaluated."""

    episode: int
    result: EvalResult
    seed: int
    seconds: float
    best: bool = False
    """The check's table is the kept best table when the check ends."""

    @property
    def score(self) -> tuple[float, float]:
        return score(self.result.goal_rate, self.result.mean_reward)

    def record(self) -> dict[str, Any]:
        """The ``best`` record of the best table's header."""
        r = self.result
        return {
            "episode": self.episode,
            "goal_rate": r.goal_rate,
            "mean_return": r.mean_reward,
            "mean_steps": r.mean_steps,
            "eval_episodes": r.episodes,
            "seed": self.seed,
        }

    def row(self) -> list[str]:
        """The evaluations file's row (:data:`~koolio_pymunk.store.check_files.EVALS_FIELDS`)."""
        r = self.result
        return [
            str(self.episode),
            str(r.episodes),
            str(self.seed),
            *(
                f"{v:.6g}"
                for v in (
                    r.goal_rate,
                    r.end_of_world_rate,
                    r.wrong_door_rate,
                    r.truncated_rate,
                    r.mean_steps,
                    r.mean_bumps,
                    r.mean_reward,
                )
            ),
            str(int(self.best)),
            f"{self.seconds:.3f}",
        ]


class PeriodicCheck:
    """The periodic greedy check of a training run (module doc), writing through the
    run's :class:`~koolio_pymunk.store.check_files.CheckFiles` (opened, checked and
    locked before the run writes anything, and closed, by the run).

    :meth:`resume` brings the files in step with the run's table; :meth:`due` says
    whether a table of that many episodes is to be checked; :meth:`check` checks it.
    """

    def __init__(
        self,
        files: CheckFiles,
        every: int,
        episodes: int,
        seed: int,
        shared_robots: int = 0,
    ) -> None:
        if every < 1 or episodes < 1:
            raise ValueError(f"every and episodes: >= 1, got {every} and {episodes}")
        self.files = files
        """The evaluations file and the best table."""
        self.every = every
        self.episodes = episodes
        self.seed = seed
        self.last = 0
        """The ``episode`` of the last row of the evaluations file (0: none)."""
        self.shared_robots = shared_robots
        """Robots sharing the arena in the training run (0: none): each check then plays
        with that many robots in one arena, and a check's goal rate is its worst robot's
        (every robot must deliver; the kept best table is the one whose worst robot did
        best)."""
        self._env: KoolioEnv | None = None

    @property
    def kept(self) -> dict[str, Any] | None:
        """The kept best table's ``best`` record (None: no best yet)."""
        return self.files.kept

    @property
    def best(self) -> QTableStore:
        """The best table's store."""
        return self.files.best

    def resume(self, episodes: int, warn: Callable[[str], None]) -> None:
        """Bring the evaluations file in step with a table of ``episodes`` episodes: rows
        beyond it move to ``<evals>.removed`` (they run again), with ``warn``."""
        self.last = self.files.resume(episodes, warn)

    def due(self, episodes: int) -> bool:
        """Is the table at ``episodes`` episodes to be checked (a multiple of N not yet
        checked)?"""
        return episodes > 0 and episodes % self.every == 0 and episodes > self.last

    def check(
        self, env: KoolioEnv, table: QTable, stop: Callable[[], bool] | None = None
    ) -> Check | None:
        """Check ``table`` (its episode count from its header): evaluate it, keep it as
        the best table when better, append the row. None when ``stop`` ended it early
        (nothing written)."""
        episode = int(table.meta.get("episodes", 0))
        started = time.perf_counter()
        if self._env is None:  # the training robots' envs are busy: a robot of its own
            self._env = env.sibling()
        n = self.shared_robots
        try:
            result = evaluate(self._env, table, self.episodes, self.seed, stop=stop,
                              robots=max(1, n), shared_arena=n > 0)  # fmt: skip
        except EvaluationStopped:
            return None
        if result.robot_goal_rates:  # the worst robot's rate
            result = dataclasses.replace(result, goal_rate=min(result.robot_goal_rates))
        c = Check(episode, result, self.seed, time.perf_counter() - started)
        kept = self.kept
        if kept is None or c.score > score(kept["goal_rate"], kept["mean_return"]):
            self.files.keep(table, c.record())
        c.best = self.kept is not None and self.kept["episode"] == episode
        self.files.append(c.row())
        self.last = episode
        return c
