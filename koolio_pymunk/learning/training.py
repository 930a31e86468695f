"""``koolio-pm train``: many episodes of one robot or several, with the run's files.

The episodes themselves run in :mod:`koolio_pymunk.learning.episodes` (the episode loop,
the seeding, N robots in tick order) on the compiled step engine
(:mod:`koolio_pymunk.learning.engine`); this module adds what a run around them needs.
Evaluation (``eval``, and the periodic checks and best table of ``train --eval-every``) is
:mod:`koolio_pymunk.learning.evaluation`.

**Files.** A run's Q-table and log are a
:class:`~koolio_pymunk.store.run_files.RunFiles` (their format and what each finished
episode writes are in :mod:`koolio_pymunk.store.run_files`); the checks' files a
:class:`~koolio_pymunk.store.check_files.CheckFiles`. Both are opened, checked and locked
before anything is written, the checks' first.
"""

from __future__ import annotations

import sys
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from ..store.check_files import CheckFiles
from ..store.errors import KoolioError, located
from ..store.interrupts import SafeInterrupt
from ..store.qtable import (
    QTable,
    QTableStore,
    load_qtable,
)
from ..store.run_files import RunFiles
from ..store.run_identity import RunIdentity
from ..task.env import KoolioEnv
from .algorithms import make_learner
from .episodes import INTERRUPTED, TRAIN_STREAM, EpisodeResult, Robots
from .evaluation import DEFAULT_EVAL_EPISODES, Check, PeriodicCheck


@dataclass
class Progress:
    """Running figures of a training run, printed as progress lines.

    The line ends with the time left (``eta 0:12``) at the rate of the recent episodes
    (those of the moving window, so a run that speeds up as the robot learns is not
    judged by its slow start). ``clock`` times the episode ends (a test gives its own):

    >>> ticks = iter([10.0, 20.0, 30.0])
    >>> p = Progress(started=0.0, clock=lambda: next(ticks))
    >>> for _ in range(3):
    ...     p.add(EpisodeResult(0, 0.0, 100, 0, "goal", False, 0.1, "201"))
    >>> p.line(3, 9, 0.1).split("  ")[-1], p.eta_seconds(6)
    ('eta 1:00', 60.0)
    """

    window: int = 100
    recent: deque = field(default_factory=lambda: deque(maxlen=100))
    episodes: int = 0
    goals: int = 0
    steps: int = 0
    started: float = field(default_factory=time.perf_counter)
    clock: Callable[[], float] = field(default=time.perf_counter, repr=False)
    ends: deque = field(default_factory=lambda: deque(maxlen=101), repr=False)
    """When the recent episodes ended (``clock``): the rate of the last ``window``."""

    def add(self, r: EpisodeResult) -> None:
        """Count a finished episode."""
        self.episodes += 1
        self.goals += r.outcome == "goal"
        self.steps += r.steps
        self.recent.append(r.outcome == "goal")
        self.ends.append(self.clock())

    def eta_seconds(self, remaining: int) -> float | None:
        """Seconds ``remaining`` more episodes take at the recent rate, measured between
        episode ends (None before two have ended: the first episode's time holds the
        start, which on a first run is the kernels' compile, and would promise hours)."""
        if remaining <= 0:
            return 0.0
        if len(self.ends) < 2:
            return None
        span, n = self.ends[-1] - self.ends[0], len(self.ends) - 1
        return remaining * max(0.0, span) / n

    @property
    def goal_rate(self) -> float:
        """The share of the recent episodes (a moving window) at the goal."""
        return sum(self.recent) / len(self.recent) if self.recent else 0.0

    @property
    def steps_per_s(self) -> float:
        """Steps per wall-clock second since this counter started."""
        return self.steps / max(1e-9, time.perf_counter() - self.started)

    def line(self, episode: int, total: int, epsilon: float) -> str:
        """The progress line printed every few seconds (``episode`` done of ``total``)."""
        return (
            f"episode {episode:>6}/{total}  goal rate (last {len(self.recent)}) "
            f"{self.goal_rate:6.1%}  steps/s {self.steps_per_s:8.0f}  epsilon {epsilon:.3f}"
            f"  eta {clock_time(self.eta_seconds(total - episode))}"
        )


def clock_time(seconds: float | None) -> str:
    """``0:07``, ``12:30``, ``1:02:03`` (``-:--`` when unknown), as a clock shows it.

    >>> clock_time(7.4), clock_time(750), clock_time(3723), clock_time(None)
    ('0:07', '12:30', '1:02:03', '-:--')
    """
    if seconds is None or seconds != seconds or seconds == float("inf"):
        return "-:--"
    s = round(seconds)
    h, m = s // 3600, s // 60 % 60
    return f"{h}:{m:02d}:{s % 60:02d}" if h else f"{m}:{s % 60:02d}"


@dataclass
class TrainResult:
    """What a training run did."""

    table: QTable
    episodes_run: int
    goals: int
    steps: int
    seconds: float
    interrupted: bool
    results: list[EpisodeResult]
    checks: list[Check] = field(default_factory=list)
    """The periodic checks the run made (``eval_every``)."""
    python_reason: str | None = None
    """Why the run stepped in the Python loop (None: on the compiled engine)."""


def train(
    env: KoolioEnv,
    store: QTableStore,
    episodes: int,
    seed: int,
    log_path: str | Path | None = None,
    discard_unfinished: bool = False,
    report: Callable[[str], None] | None = print,
    report_every: float = 1.0,
    eval_every: int = 0,
    eval_episodes: int = DEFAULT_EVAL_EPISODES,
    save_every: int | None = None,
    save_seconds: float | None = None,
    compiled: bool = True,
    robots: int = 1,
    fsync: str = "second",
    tensorboard: str | Path | None = None,
    shared_arena: bool = False,
    own_tables: bool = False,
) -> TrainResult:
    """Train ``robots`` robots for ``episodes`` more episodes into one table (``koolio-pm
    train --episodes N`` is the total the table reaches: it passes N minus the episodes
    already held), saving the table after each finished episode (the paper's rule, the
    default with one robot), or every ``save_every`` episodes (default: ``robots``) and/or
    every ``save_seconds`` seconds, and always at the end.

    **Robots.** Each robot runs its own episodes in its own copy of the arena (``env`` is
    robot 0's; the others are its siblings), or with ``shared_arena`` all in one arena as
    bodies to each other (robots like ``env``: :mod:`koolio_pymunk.task.shared_arena`), and
    learns into the shared table (with ``own_tables``, ``--tables each``, each robot into
    its own rows of it: the table's layout leads with the robot's index,
    :func:`~koolio_pymunk.store.keyword.own_tables`; a shared arena only); the robots
    step in tick order (:class:`~koolio_pymunk.learning.episodes.Robots`). Episode starts
    are numbered from the table's count in the order they begin (robot order at first,
    then as robots finish), and a start's number gives its seeds and its epsilon; finished
    episodes are numbered in the order they finish, which is the log's order. With one
    robot both are the episode's number, and the run is the paper's loop exactly. A run
    resumed with several robots starts new episodes from the saved table: seeded, but not
    the uninterrupted run's continuation, whose robots were mid-episode at the save.

    Ctrl-C or SIGTERM (KeyboardInterrupt) is the paper's Exit: the unfinished episodes'
    updates are kept and the table saved, each logged ``interrupted`` (numbered as the
    episodes that follow); with ``discard_unfinished`` it is Exit Without Save: with one
    robot nothing more is written, the table file stays as it was at its last save (after
    the last finished episode with the default saving; with a longer cadence the log is
    then ahead of it, as after a SIGKILL, and resuming moves those rows aside and runs
    their episodes again, identically); with several, every write of an unfinished
    episode that no other robot wrote over since is taken back and the finished ones are
    saved. Ctrl-C takes effect between steps (:class:`SafeInterrupt`; compiled, between
    chunks of steps). The table and the log are locked while it runs
    (:meth:`RunFiles.open`); a failed write (disk full) stops it with a
    :class:`~koolio_pymunk.store.errors.FileError`, the files holding the last good table.

    ``compiled`` (the default) runs the steps on the compiled step engine when the learner
    and the world allow it (:mod:`koolio_pymunk.learning.engine`: the same steps, bit for
    bit); False always runs the Python loop (the reference). :attr:`TrainResult.python_reason`
    says why a run stepped in Python.

    ``fsync`` is how the table is kept (:class:`~koolio_pymunk.store.qtable.QTableStore`):
    ``second`` (the default) writes it whole and fsynced at most once a second (and at
    the end, on Ctrl-C and SIGTERM) and each episode's changes in between to its journal;
    ``episode``, the paper's rule, writes and fsyncs it whole at every save.

    ``tensorboard``: a folder for TensorBoard's event files of the run's scalars
    (:mod:`koolio_pymunk.learning.scalars`).

    ``eval_every`` N > 0: a greedy check of ``eval_episodes`` episodes each time the
    table's episode count reaches a multiple of N, and the best table kept
    (:mod:`koolio_pymunk.learning.evaluation`); the training itself is the same. With
    several robots a check reads the table as it stands when that episode finishes (the
    other robots' episodes under way included).
    """
    from .engine import robots as make_robots  # numba: loaded when a run starts

    n = max(1, min(robots, episodes)) if episodes > 0 else max(1, robots)
    cfg = env.config
    loop_reason = _python_reason(env, compiled)
    if robots > 1 and discard_unfinished and loop_reason is not None:
        raise KoolioError(
            located(
                f"--robots {robots}",
                "--discard-unfinished",
                f"taking back the unfinished episodes' writes needs the compiled engine's "
                f"journal, and this run steps in Python ({loop_reason})",
            )
        )
    store.fsync = fsync
    if own_tables and not shared_arena:
        raise ValueError("own tables: robots that share an arena (shared_arena)")
    if eval_every < 0 or (eval_every and eval_episodes < 1):
        raise ValueError(
            f"eval_every >= 0 and eval_episodes >= 1, got {eval_every}, {eval_episodes}"
        )
    # The run's files, checked before any is written: the checks' first, then the table's.
    run = RunIdentity.of_run(env, robots if own_tables else 0)  # what the files are checked against
    check_files = CheckFiles.open(run, store, log_path) if eval_every else None
    try:
        files = RunFiles.open(run, store, log_path, "koolio-pm train", seed)
    except BaseException:
        if check_files is not None:
            check_files.close()
        raise
    loop: Robots | None = None  # made below: the files are closed whatever fails first
    scalars = None
    try:
        files.save_every = max(1, save_every if save_every is not None else robots)
        files.save_seconds = save_seconds
        table, first = files.table, files.first
        agents = [make_learner(table, cfg.learner, None) for _ in range(n)]
        checker = None
        if check_files is not None:
            checker = PeriodicCheck(check_files, eval_every, eval_episodes, seed,
                                    shared_robots=n if shared_arena else 0)  # fmt: skip
        journal = discard_unfinished and n > 1
        loop = make_robots(
            env, agents, seed, TRAIN_STREAM, compiled=compiled, journal=journal, shared=shared_arena
        )
        files.before_save = loop.sync_table
        files.changed_rows = loop.changed_rows
        if tensorboard is not None:
            from .scalars import RunScalars, logged_steps

            scalars = RunScalars(tensorboard, logged_steps(log_path))
        progress = Progress()
        results: list[EpisodeResult] = []
        checks: list[Check] = []
        last_report = time.perf_counter()
        interrupted = False
        started = finished = 0
        tail = f"  robots {n}" if robots > 1 else ""

        def start(r: int) -> None:
            nonlocal started
            if started < episodes:
                loop.begin(r, first + started)
                started += 1
            else:
                loop.release(r)

        with SafeInterrupt() as guard:
            try:
                if checker is not None:
                    checker.resume(first, _warn)
                    # the check of a table saved at a multiple of N whose row is missing
                    interrupted = _check(checker, env, loop, first, guard, checks, report)
                if not interrupted and not guard.pending:
                    for r in range(n):
                        start(r)
                while finished < episodes and not interrupted:
                    if guard.pending:
                        if any(loop.running):
                            guard.check()  # Exit: the episodes under way are folded in
                        interrupted = True  # between episodes: nothing unfinished
                        if report:
                            report("interrupted between episodes: nothing unfinished")
                        break
                    r = loop.advance(stop=guard.check)
                    if r is None:  # no robot running (cannot happen with episodes left)
                        break
                    res = loop.result(r, episode=first + finished)
                    finished += 1
                    files.finished(res)
                    results.append(res)
                    progress.add(res)
                    if scalars is not None:
                        scalars.episode(res)
                    now = time.perf_counter()
                    if report and (now - last_report >= report_every or finished == episodes):
                        eps = loop.agents[r].epsilon
                        report(progress.line(first + finished, first + episodes, eps) + tail)
                        last_report = now
                    if checker is not None and checker.due(first + finished):
                        if files.unsaved:
                            files.save()  # a check row is never ahead of the table's file
                        interrupted = _check(
                            checker, env, loop, first + finished, guard, checks, report
                        )
                        done = checks and checks[-1].episode == first + finished
                        if scalars is not None and done:
                            scalars.check(checks[-1])
                    start(r)
                files.checkpoint()  # the end (or a stop between episodes): always durable
            except KeyboardInterrupt:
                interrupted = True
                table = _interrupted(loop, files, discard_unfinished, results, report, finished)
    finally:
        try:
            if loop is not None:
                loop.sync()  # the envs and learners as the Python steps would leave them
            if scalars is not None:
                scalars.close()
        finally:
            try:
                files.close()
            finally:
                if check_files is not None:
                    check_files.close()
    return TrainResult(
        table,
        progress.episodes,
        progress.goals,
        progress.steps,
        time.perf_counter() - progress.started,
        interrupted,
        results,
        checks,
        loop.python_reason,
    )


def _python_reason(env: KoolioEnv, compiled: bool) -> str | None:
    """Why a training run in ``env`` steps in the Python loop (None: on the engine)."""
    if not compiled:
        return "not asked for"
    from .engine import why_not_config

    return why_not_config(env)


def _warn(message: str) -> None:
    print(f"warning: {message}", file=sys.stderr)


def _check(
    checker: PeriodicCheck,
    env: KoolioEnv,
    loop: Robots,
    episodes: int,
    guard: SafeInterrupt,
    checks: list[Check],
    report: Callable[[str], None] | None,
) -> bool:
    """The periodic check of the table at ``episodes`` episodes, when due. A Ctrl-C
    drops it (it runs again on resume): True, and the loop stops before its next
    episode."""
    if not checker.due(episodes):
        return False
    loop.sync_table()
    c = checker.check(env, loop.agents[0].table, stop=lambda: guard.pending)
    if c is None:
        if report:
            report(f"interrupted: the check at episode {episodes} dropped (it runs on resume)")
        return True
    checks.append(c)
    if report:
        kept = checker.kept or {}
        r = c.result
        report(
            f"check at episode {episodes}: goal rate {r.goal_rate:.1%} (greedy, "
            f"{r.episodes} episodes), mean return {r.mean_reward:.1f}; best "
            f"{kept.get('goal_rate', 0.0):.1%} at episode {kept.get('episode')} "
            f"-> {checker.best.path}"
        )
    return False


def _interrupted(
    loop: Robots,
    files: RunFiles,
    discard: bool,
    results: list[EpisodeResult],
    report: Callable[[str], None] | None,
    finished: int,
) -> QTable:
    """Ctrl-C with episodes under way: Exit (fold them in, save, log each ``interrupted``)
    or Exit Without Save (one robot: the file still holds the table of the last finished
    episode; several: their writes taken back, the finished episodes saved)."""
    running = [r for r in range(len(loop)) if loop.running[r]]
    if discard:
        if len(loop) == 1:
            if report:
                report("interrupted: unfinished episode discarded (Exit Without Save)")
            return load_qtable(files.store.path)
        for key in loop.discard(running):
            files.table.rows.pop(key, None)
        loop.sync_table()
        files.save()
        if report:
            report(
                f"interrupted: {len(running)} unfinished episodes discarded, {finished} "
                "finished ones kept (Exit Without Save)"
            )
        return files.table
    loop.sync_table()
    first = int(files.table.meta.get("episodes", files.first))
    rows = [loop.result(r, INTERRUPTED, episode=first + k) for k, r in enumerate(running)]
    files.folded(*rows)
    results.extend(rows)
    if report:
        what = "unfinished episode" if len(loop) == 1 else "unfinished episodes"
        report(f"interrupted: {what} folded into the Q-table and saved (Exit)")
    return files.table
