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
backup and locked like the table (:class:`~koolio_pymunk.learning.qtable.QTableStore`).

**Stopped and resumed.** The table is saved before its check, the best table before the
check's row: a run stopped at any point (Ctrl-C, SIGKILL) and resumed continues exactly
like an uninterrupted one. A resumed run whose table count is a multiple of N and lacks
that check's row runs it first (the check of a saved table is exact, so it scores what
it scored); rows beyond the table's count (a table that fell back to its backup) move to
``<evals>.removed`` with a warning and run again. A check under way when Ctrl-C comes is
dropped (the run stops at once) and runs again on resume.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..store.episode_log import csv_fields, split_log
from ..store.errors import KoolioError, QTableError, located
from ..store.files import atomic_write, check_path, file_error, read_text
from ..store.locks import FileLock
from ..task.env import KoolioEnv
from . import run_identity
from .episodes import EVAL_STREAM, EpisodeResult
from .qlearning import QLearner
from .qtable import QTable, QTableStore

#: Columns of the evaluations file (module doc).
EVALS_FIELDS = (
    "episode",
    "eval_episodes",
    "seed",
    "goal_rate",
    "end_of_world_rate",
    "wrong_door_rate",
    "truncated_rate",
    "mean_steps",
    "mean_bumps",
    "mean_return",
    "best",
    "seconds",
)
EVALS_HEADER = ",".join(EVALS_FIELDS)
#: Greedy episodes per check when ``--eval-episodes`` is not given.
DEFAULT_EVAL_EPISODES = 100
#: Largest evaluations file read.
MAX_EVALS_BYTES = 1 << 26


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


def best_path(table: str | Path) -> Path:
    """The kept best table of the table file ``table``.

    >>> str(best_path("runs/hallway.qtable")), str(best_path("runs/t"))
    ('runs/hallway.best.qtable', 'runs/t.best.qtable')
    """
    p = Path(table)
    stem = p.stem if p.suffix == ".qtable" else p.name
    return p.with_name(stem + ".best.qtable")


def evals_path(log: str | Path | None, table: str | Path) -> Path:
    """The evaluations file of a run: beside its log (``X.csv`` -> ``X.evals.csv``), or
    beside its table when it has no log.

    >>> str(evals_path("runs/hallway.csv", "t.qtable")), str(evals_path("", "runs/t.qtable"))
    ('runs/hallway.evals.csv', 'runs/t.evals.csv')
    """
    base = Path(log) if log is not None and str(log) != "" else Path(table)
    return base.with_name(base.stem + ".evals.csv")


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
        """The evaluations file's row (:data:`EVALS_FIELDS`)."""
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


def best_record(table: QTable, source: str) -> dict[str, Any]:
    """The ``best`` record of a kept best table's header, checked (one-line error)."""
    rec = table.meta.get("best")

    def bad(item: str, problem: str) -> QTableError:
        return QTableError(located(source, f"header.best{item}", problem))

    if not isinstance(rec, dict):
        raise bad("", "missing or not a mapping (not a best table of train --eval-every)")
    ep = rec.get("episode")
    if not isinstance(ep, int) or isinstance(ep, bool) or ep < 0:
        raise bad(".episode", f"must be an integer >= 0, got {ep!r}"[:120])
    for key in ("goal_rate", "mean_return"):
        v = rec.get(key)
        if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
            raise bad(f".{key}", f"must be a finite number, got {v!r}"[:120])
    return rec


def read_evals(path: str | Path) -> list[list[str]]:
    """The rows of an evaluations file (header checked), ``[]`` when missing or empty."""
    p = Path(path)
    if not p.exists() or p.stat().st_size == 0:
        return []
    text = read_text(p, MAX_EVALS_BYTES, "evaluations file")
    first = text.split("\n", 1)[0].rstrip("\r")
    if first != EVALS_HEADER:
        shown = first if len(first) <= 40 else first[:37] + "..."
        raise KoolioError(
            located(
                str(p),
                "line 1",
                f"not an evaluations file (its first line is {shown!r}); nothing was written",
            )
        )
    lines, _ = split_log(text)  # a torn last row is a row (resuming moves it away)
    rows = (csv_fields(str(p), n, line) for n, line in enumerate(lines[1:], start=2))
    return [row for row in rows if row]


class PeriodicCheck:
    """The periodic greedy check of a training run and its kept best table (module doc).

    :meth:`open` checks and locks the evaluations file and the best table before the run
    writes anything; :meth:`resume` brings them in step with the run's table;
    :meth:`due` says whether a table of that many episodes is to be checked;
    :meth:`check` checks it; :meth:`close` releases the locks.
    """

    def __init__(
        self,
        every: int,
        episodes: int,
        seed: int,
        path: Path,
        best: QTableStore,
        lock: FileLock,
        kept: dict[str, Any] | None,
        shared_robots: int = 0,
    ) -> None:
        self.every = every
        self.episodes = episodes
        self.seed = seed
        self.path = path
        """The evaluations file."""
        self.best = best
        """The best table's store (locked)."""
        self._lock = lock
        self.kept = kept
        """The kept best table's ``best`` record (None: no best yet)."""
        self.last = 0
        """The ``episode`` of the last row of the evaluations file (0: none)."""
        self.shared_robots = shared_robots
        """Robots sharing the arena in the training run (0: none): each check then plays
        with that many robots in one arena, and a check's goal rate is its worst robot's
        (every robot must deliver; the kept best table is the one whose worst robot did
        best)."""
        self._env: KoolioEnv | None = None

    @classmethod
    def open(
        cls,
        run: run_identity.RunIdentity,
        store: QTableStore,
        log_path: str | Path | None,
        every: int,
        episodes: int,
        seed: int,
        purpose: str = "koolio-pm train",
        shared_robots: int = 0,
    ) -> PeriodicCheck:
        """Check and lock the evaluations file and the best table of ``store``'s run
        ``run`` (``log_path``: its log) before anything is written. A new table (no file, no
        backup) refuses an evaluations file with rows or a best table: they belong to
        another run. ``shared_robots``: :attr:`shared_robots`."""
        if every < 1:
            raise KoolioError(f"--eval-every: must be >= 1, got {every}")
        if episodes < 1:
            raise KoolioError(f"--eval-episodes: must be >= 1, got {episodes}")
        path = check_path(evals_path(log_path, store.path))
        best = QTableStore(best_path(store.path), purpose=purpose)
        _distinct(store.path, log_path, path, best.path)
        new_table = not (store.path.exists() or store.backup.exists())
        lock = FileLock(path, purpose).acquire()
        try:
            rows, _ = _checked_rows(path)
            if new_table and rows:
                raise KoolioError(
                    located(
                        str(path),
                        "",
                        f"holds {len(rows)} checks of another run, and the Q-table "
                        f"{store.path} is new: move it away",
                    )
                )
            if new_table and (best.path.exists() or best.backup.exists()):
                raise KoolioError(
                    located(
                        str(best.path),
                        "",
                        f"the best table of another run (the Q-table {store.path} is new): "
                        "move it away",
                    )
                )
            own = store.peek()  # the run's table: the best one must be of its run
            rid = own.meta.get("run_id") if own is not None else None
            source = str(best.path)
            table = best.load(
                lambda: run_identity.new_table(run),
                lambda t: run_identity.check(t, run, "keep", source, best.warn, run_id=rid),
            )
            kept = None if best.fresh else best_record(table, str(best.path))
        except BaseException:
            lock.release()
            best.close()
            raise
        return cls(every, episodes, seed, path, best, lock, kept, shared_robots)

    def resume(self, episodes: int, warn: Callable[[str], None]) -> None:
        """Bring the evaluations file in step with a table of ``episodes`` episodes: rows
        beyond it move to ``<evals>.removed`` (they run again), with ``warn``."""
        rows, body = _checked_rows(self.path)
        keep = [r for r in body if int(r[0]) <= episodes]
        if len(keep) < len(rows):
            self._move_out(keep, rows[len(keep) :], episodes, warn)
        self.last = int(keep[-1][0]) if keep else 0

    def _move_out(
        self, keep: list[list[str]], gone: list[list[str]], episodes: int, warn: Callable
    ) -> None:
        removed = self.path.with_name(self.path.name + ".removed")
        old = read_evals(removed)
        atomic_write(removed, _csv([*old, *gone]))  # first: a crash between loses nothing
        atomic_write(self.path, _csv(keep))
        warn(
            f"{self.path}: moved {len(gone)} checks to {removed}: the Q-table holds "
            f"{episodes} episodes (the checks beyond it run again)"
        )

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
            best = table.copy()
            best.meta["best"] = c.record()
            self.best.save(best)
            self.kept = c.record()
        c.best = self.kept is not None and self.kept["episode"] == episode
        self._append(c)
        self.last = episode
        return c

    def _append(self, c: Check) -> None:
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerow(c.row())
        if not self.path.exists() or self.path.stat().st_size == 0:  # header and row at once
            atomic_write(self.path, (EVALS_HEADER + "\n" + buf.getvalue()).encode("utf-8"))
            return
        try:
            with open(self.path, "a", newline="", encoding="utf-8") as fh:
                fh.write(buf.getvalue())
        except OSError as exc:
            raise file_error(self.path, "write", exc) from None

    def close(self) -> None:
        """Release the evaluations file's and the best table's locks."""
        try:
            self._lock.release()
        finally:
            self.best.close()


def _checked_rows(path: Path) -> tuple[list[list[str]], list[list[str]]]:
    """The rows of an evaluations file, and those of them that are whole (all but a last
    row cut short by a kill, which runs again); one-line error on a bad row."""
    rows = read_evals(path)
    torn = bool(rows) and not path.read_bytes().endswith(b"\n")
    body = rows[:-1] if torn else rows
    last = -1
    for n, row in enumerate(body, start=2):
        if len(row) != len(EVALS_FIELDS) or not row[0].isdigit():
            raise KoolioError(located(str(path), f"line {n}", "not a row of an evaluations file"))
        if int(row[0]) <= last:
            raise KoolioError(located(str(path), f"line {n}", f"episode {row[0]} after {last}"))
        last = int(row[0])
    return rows, body


def _csv(rows: list[list[str]]) -> bytes:
    buf = io.StringIO()
    buf.write(EVALS_HEADER + "\n")
    csv.writer(buf, lineterminator="\n").writerows(rows)
    return buf.getvalue().encode("utf-8")


def _distinct(table: Path, log: str | Path | None, evals: Path, best: Path) -> None:
    """The evaluations file and the best table are none of the run's other files."""
    others = {
        "the Q-table": table,
        "the Q-table's backup": table.with_name(table.name + ".bak"),
    }
    if log is not None and str(log) != "":
        others["the log"] = Path(log)
    for path in (evals, best):
        for what, other in others.items():
            if path.resolve() == other.resolve():
                raise KoolioError(located(str(path), "", f"is {what}: give another --qtable/--log"))
