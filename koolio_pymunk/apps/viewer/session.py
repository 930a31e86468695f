"""The window's hold on the episode loop: learning (or watching) one step at a time.

:class:`Session` drives :class:`~koolio_pymunk.learning.episodes.Episodes`, the episode
loop of ``koolio-pm train``, one step per call as the window asks (paper §5.4.9), and
records every finished episode through :class:`~koolio_pymunk.store.run_files.RunFiles`
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

:class:`SharedSession` is the same for N robots sharing one arena (``view --robots N
--shared-arena``): they step in tick order through
:class:`~koolio_pymunk.learning.episodes.Robots` (the Python reference of the engine that
``train --robots N --shared-arena`` runs) into one table, and a window run of E episodes
writes the table and log rows of ``train --robots N --shared-arena --episodes E`` with
the same seed. One of the robots is *selected*: :attr:`Session.env` and
:attr:`Session.agent` are its own, for the HUD and the Stats panel.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from ...learning.algorithms import make_learner
from ...learning.episodes import (
    EVAL_STREAM,
    INTERRUPTED,
    TRAIN_STREAM,
    EpisodeResult,
    Episodes,
    Robots,
)
from ...learning.qlearning import QLearner
from ...store import run_identity
from ...store.episode_log import log_rows
from ...store.errors import KoolioError, located
from ...store.qtable import QTable, QTableStore
from ...store.run_files import RunFiles
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


def watched_table(env: KoolioEnv, qtable: str | Path, warn: bool = True, robots: int = 1) -> QTable:
    """The table a greedy session of ``robots`` robots watches, checked for ``env``
    (purpose ``watch`` of :func:`~koolio_pymunk.store.run_identity.check`, as
    :meth:`RunIdentity.of_robots <koolio_pymunk.store.run_identity.RunIdentity.of_robots>`
    plays it); its backup when the file is damaged or missing, with a warning unless not
    ``warn``, as ``train`` and ``eval`` read it."""
    table = QTableStore(qtable).peek(warn=warn)
    if table is None:
        raise KoolioError(
            located(str(qtable), "", "no such Q-table file (--greedy): run koolio-pm train first")
        )
    run = run_identity.RunIdentity.of_robots(env, robots, table)
    run_identity.check(table, run, "watch", str(qtable))  # its warnings once per process
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
        self.files: RunFiles | None = None
        if self.learn:  # the table and the log locked while the window learns
            store = QTableStore(qtable, purpose="koolio-pm view")
            run = run_identity.RunIdentity.of_robots(
                env, self.asked_robots, store.peek(), each=self.each
            )
            self.files = RunFiles.open(run, store, log, "koolio-pm view", seed)
            self.table = self.files.table
            self.first = self.files.first
        else:
            self.table = watched_table(env, qtable, robots=self.asked_robots)
            self.first = 0
        self._make_loop(self.learn)
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

    n_robots = asked_robots = 1
    """Robots in the window (:class:`SharedSession`: several), and how many were asked
    for (the window runs no more robots than episodes)."""
    each = False
    """A new table holds each robot's own rows (``view --tables each``)."""
    selected = 0
    """The robot the panels show."""

    def _make_loop(self, learn: bool) -> None:
        """The learner and the episode loop (learning or greedy)."""
        cfg = self.env.config
        if learn:
            self.agent = make_learner(self.table, cfg.learner, None)
            self.loop = Episodes(self.env, self.agent, self.seed, TRAIN_STREAM)
        else:
            self.agent = QLearner(self.table, cfg.learner, None)
            self.loop = Episodes(
                self.env, self.agent, self.seed, EVAL_STREAM, learn=False, epsilon=0.0
            )

    def select(self, robot: int) -> None:
        """Show robot ``robot`` in the panels (one robot: only 0)."""
        if robot != 0:
            raise ValueError(f"no robot {robot} (one robot: 0)")

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


class SharedSession(Session):
    """:class:`Session` for ``robots`` robots sharing one arena (module doc), ``robots``
    >= 2 robots like ``env``.

    A step of this session is a *tick*: every running robot makes one step, in index
    order (a robot waiting for a free start spot spends its turn asking for one). A robot
    whose episode ends has it recorded at once (table saved, log row, in the order the
    episodes finish, numbered as ``train`` numbers them) and begins its next episode
    there and then, as ``train`` does: it left the arena and enters it again at a free
    start spot (or waits outside for one). As in ``train``, ``episodes`` E < ``robots``
    runs E robots. :attr:`selected` is the robot the panels show (:meth:`select`).

    Exit folds every episode under way (that made a step) into the table and logs an
    ``interrupted`` row for each, as Ctrl-C in ``train`` does. Exit Without Save writes
    nothing: the file stays as saved at the last episode end (with the other robots'
    updates of their episodes under way as they stood then, as ``train``'s saves hold
    them).
    """

    def __init__(
        self,
        env: KoolioEnv,
        qtable: str | Path,
        *,
        robots: int,
        seed: int = 0,
        episodes: int | None = None,
        log: str | Path | None = None,
        greedy: bool = False,
        each: bool = False,
    ) -> None:
        from ...task.shared_arena import SharedArena

        if robots < 2:
            raise ValueError("a shared arena's session needs at least two robots")
        n = robots if not episodes else max(1, min(robots, episodes))  # train's count
        self.n_robots, self.asked_robots, self.each = n, robots, each
        self.envs = SharedArena.of(env, n)
        self.selected = 0
        self.started = 0
        """Episodes begun (their number gives their seeds, as ``train``'s starts)."""
        self.robot_stats = [Stats() for _ in range(n)]
        """Each robot's own totals."""
        self.robot_episodes = [0] * n
        """How many episodes each robot has begun in this window."""
        # robot 0's env is the session's env (it is like ``env``: the same arena,
        # configuration, world and goal); :meth:`select` makes another robot's the one shown
        super().__init__(self.envs[0], qtable, seed=seed, episodes=episodes, log=log, greedy=greedy)

    # -- the robots -----------------------------------------------------------------------
    def select(self, robot: int) -> None:
        """Show robot ``robot`` (0 .. n-1) in the panels: :attr:`env` and :attr:`agent`
        are its own."""
        if not 0 <= robot < self.n_robots:
            raise ValueError(f"no robot {robot} (robots 0..{self.n_robots - 1})")
        self.selected = robot
        self.env, self.agent = self.envs[robot], self.agents[robot]

    def _make_loop(self, learn: bool) -> None:
        cfg = self.envs[0].config
        if learn:
            self.agents = [
                make_learner(self.table, cfg.learner, None) for _ in range(self.n_robots)
            ]
            self.robots = Robots(self.envs, self.agents, self.seed, TRAIN_STREAM)
        else:
            self.agents = [QLearner(self.table, cfg.learner, None) for _ in range(self.n_robots)]
            self.robots = Robots(
                self.envs, self.agents, self.seed, EVAL_STREAM, learn=False, epsilon=0.0
            )
        self.agent = self.agents[self.selected]

    # -- stepping ------------------------------------------------------------------------
    def _begin(self) -> None:
        """Every robot's first episode (shown even when there is nothing to run)."""
        for r in range(self.n_robots):
            self._start(r, force=True)
        self._pending_reset = False

    def _start(self, r: int, force: bool = False) -> None:
        """Robot ``r``'s next episode, numbered as ``train`` numbers its starts; none when
        the session's episodes are all begun (``force``: begin it anyway, to be drawn, as
        the one robot of ``view --episodes 0`` is)."""
        if self.last is None or self.first + self.started < self.last or force:
            self.robots.begin(r, self.first + self.started)
            self.started += 1
            self.robot_episodes[r] += 1
            if self.done:  # drawn only: nothing of it runs
                self.robots.release(r)
        else:
            self.robots.release(r)

    @property
    def episode_over(self) -> bool:
        """The selected robot has no episode under way."""
        return not self.robots.running[self.selected]

    def run(self, n: int) -> int:
        """Perform up to ``n`` ticks (fewer when the session is done); returns how many."""
        if self.closed:
            return 0
        done = 0
        advance = self.robots.advance
        while done < n and not self.done:
            r = advance(stop=lambda: True)  # to the tick's end, or a robot's episode's
            if r is None:
                done += 1
            else:
                self._finish_robot(r)
                if self.done:  # the tick's other robots stepped no further: none run
                    done += 1
        self.total_steps += done
        return done

    def _finish_robot(self, r: int) -> None:
        res = self.robots.result(r, episode=self.episode)
        if self.files is not None:
            self.files.finished(res)
        self.results.append(res)
        self.stats.add(res)
        self.robot_stats[r].add(res)
        self.episode += 1
        if self.last is not None and self.episode >= self.last:
            self.done = True
        else:
            self._start(r)

    # -- controls --------------------------------------------------------------------------
    def rescue(self) -> bool:
        """Force ``Rescue_Robot`` on the selected robot now; False when it has no episode
        under way or is outside the arena."""
        env = self.env
        if self.closed or self.episode_over or env.waiting:
            return False
        if not env.world.present[env.robot]:
            return False
        env.rescue()
        return True

    @property
    def unfinished_steps(self) -> int:
        """Steps of the selected robot's episode in progress (0 when none is)."""
        return 0 if self.episode_over else self.env.steps

    def exit(self, save: bool = True) -> EpisodeResult | None:
        """End the session: Exit (``save``) or Exit Without Save (class doc). Returns the
        first folded episode's row, if any."""
        if self.closed:
            return None
        self.closed = True
        files = self.files
        if files is None:
            return None
        rows: list[EpisodeResult] = []
        try:
            if save:
                running = [
                    r
                    for r in range(self.n_robots)
                    if self.robots.running[r] and self.envs[r].steps > 0
                ]
                episode = int(self.table.meta.get("episodes", self.first))
                rows = [
                    self.robots.result(r, INTERRUPTED, episode=episode + k)
                    for k, r in enumerate(running)
                ]
                if rows:
                    files.folded(*rows)
                    self.results.extend(rows)
        finally:
            files.close()
        return rows[0] if rows else None
