"""Headless training and greedy evaluation loops, the per-episode log, and seeding.

**Seeding.** Episode ``e`` of a run with seed ``s`` resets the environment with a seed
derived from ``(s, e)`` and gives the learner a generator derived from ``(s, e, 1)``.
The same seed and configuration therefore give byte-identical Q-table files and logs,
and a run resumed from its table file continues exactly as an uninterrupted one would
(as long as no episode was interrupted).

**Files.** :func:`open_run` opens a run's Q-table (:class:`~koolio_pymunk.qtable.QTableStore`)
and its per-episode CSV log (:mod:`koolio_pymunk.episode_log`): both locked against a
second writer, the log checked before anything is written and brought in step with the
table. One CSV row per finished (or interrupted) episode is appended and flushed::

    episode,reward,steps,bumps,outcome,rescued,epsilon,goal

``outcome`` is ``goal``, ``end_of_world``, ``truncated`` (step cap) or ``interrupted``
(Ctrl-C / Exit: the unfinished episode was folded into the table). With domain
randomization (``realism.randomize``) every row ends with the parameters drawn for its
episode, one column per parameter, named ``realism.<section>.<name>`` (sorted), written
with ``repr`` so that they round-trip exactly.
"""

from __future__ import annotations

import signal
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .arena import arena_record
from .config import Config
from .env import KoolioEnv
from .episode_log import LOG_FIELDS as LOG_FIELDS  # the log's columns, re-exported
from .episode_log import LogWriter, check_log_path
from .learner import QLearner, attach, make_learner
from .qtable import QTable, QTableStore, load_qtable

#: Seed streams: training and evaluation episodes of the same seed never share starts.
TRAIN_STREAM, EVAL_STREAM = 0, 1


def episode_seeds(
    seed: int, episode: int, stream: int = TRAIN_STREAM
) -> tuple[int, np.random.Generator]:
    """The environment seed and the learner's generator for ``episode`` of run ``seed``."""
    env_seed = int(np.random.SeedSequence([seed, episode, stream]).generate_state(1)[0])
    return env_seed, np.random.default_rng([seed, episode, stream, 1])


def sensor_signature(cfg: Config) -> dict[str, Any]:
    """What a Q-table depends on: the sensor layout (noise settings excluded)."""
    s = cfg.sensors
    so, ca = s.sonar, s.camera
    model = {"sonar_model": "cone"} if s.backend == "cone" else {}  # sub-arcs: no key
    return model | {
        "sonar_sensors_deg": list(so.sonar_sensors_deg),
        "sonar_arc_deg": so.sonar_arc_deg,
        "sub_arcs": so.sub_arcs,
        "sonar_max_range": so.max_range,
        "sonar_groups": [list(g) for g in so.groups],
        "sonar_thresholds": list(so.thresholds),
        "camera_sensors_deg": list(ca.camera_sensors_deg),
        "camera_arc_deg": ca.camera_arc_deg,
        "max_camera_view": ca.max_camera_view,
        "camera_thresholds": list(ca.thresholds),
        "compass_in_state": s.compass.in_state,
    }


@dataclass
class EpisodeResult:
    episode: int
    reward: float
    steps: int
    bumps: int
    outcome: str
    rescued: bool
    epsilon: float
    goal: str
    realism: tuple[float, ...] = ()
    """The realism parameters drawn for the episode (domain randomization), in the order
    of the log's ``realism.*`` columns."""

    def row(self) -> list[str]:
        return [
            str(self.episode),
            f"{self.reward:.6g}",
            str(self.steps),
            str(self.bumps),
            self.outcome,
            str(int(self.rescued)),
            f"{self.epsilon:.6g}",
            self.goal,
            *(repr(v) for v in self.realism),
        ]


def realism_values(env: KoolioEnv) -> tuple[float, ...]:
    """The episode's domain-randomization draw, in log column order (empty: none)."""
    return tuple(env.realism_draw[k] for k in env.randomizer.keys)


def run_episode(
    env: KoolioEnv,
    agent: QLearner,
    learn: bool,
    stop: Callable[[], bool | None] | None = None,
) -> tuple[float, int, str]:
    """Run one episode from a reset env; returns ``(reward, steps, outcome)``.

    ``stop`` is called after every step: a true result ends the episode as
    ``interrupted`` (it may also raise, e.g. :meth:`SafeInterrupt.check`)."""
    state = env.state_key
    while True:
        action = agent.act(state)
        nxt, reward, terminated, truncated = env.transition(action)
        if learn:  # paper §5.4.8: update, then the rescue check (done by the env)
            agent.observe(state, action, reward, nxt, terminated)
        state = env.state_key
        if terminated:
            return env.episode_reward, env.steps, env.judgement.event  # type: ignore[union-attr]
        if truncated:
            return env.episode_reward, env.steps, "truncated"
        if stop is not None and stop():
            return env.episode_reward, env.steps, "interrupted"


class SafeInterrupt:
    """Ctrl-C at a safe point: while active, SIGINT only sets :attr:`pending`; the loops
    check it between steps and raise ``KeyboardInterrupt`` there, so an interrupt never
    lands between saving the table and writing the episode's log row. A second Ctrl-C
    interrupts at once. Does nothing outside the main thread (signals go there only).

    >>> with SafeInterrupt() as guard:
    ...     guard.pending
    False
    """

    def __init__(self) -> None:
        self.pending = False
        self._previous: Any = None
        self._installed = False

    def _handle(self, signum: int, frame: Any) -> None:
        if self.pending:
            raise KeyboardInterrupt
        self.pending = True

    def check(self) -> None:
        """Raise ``KeyboardInterrupt`` if a Ctrl-C is pending."""
        if self.pending:
            self.pending = False
            raise KeyboardInterrupt

    def __enter__(self) -> SafeInterrupt:
        if threading.current_thread() is threading.main_thread():
            self._previous = signal.getsignal(signal.SIGINT)
            if self._previous is signal.default_int_handler:  # only replace Python's own
                signal.signal(signal.SIGINT, self._handle)
                self._installed = True
        return self

    def __exit__(self, *exc: object) -> None:
        if self._installed:
            signal.signal(signal.SIGINT, self._previous)
            self._installed = False


@dataclass
class Progress:
    """Running figures of a training run, printed as progress lines."""

    window: int = 100
    recent: deque = field(default_factory=lambda: deque(maxlen=100))
    episodes: int = 0
    goals: int = 0
    steps: int = 0
    started: float = field(default_factory=time.perf_counter)

    def add(self, r: EpisodeResult) -> None:
        self.episodes += 1
        self.goals += r.outcome == "goal"
        self.steps += r.steps
        self.recent.append(r.outcome == "goal")

    @property
    def goal_rate(self) -> float:
        return sum(self.recent) / len(self.recent) if self.recent else 0.0

    @property
    def steps_per_s(self) -> float:
        return self.steps / max(1e-9, time.perf_counter() - self.started)

    def line(self, episode: int, total: int, epsilon: float) -> str:
        return (
            f"episode {episode:>6}/{total}  goal rate (last {len(self.recent)}) "
            f"{self.goal_rate:6.1%}  steps/s {self.steps_per_s:8.0f}  epsilon {epsilon:.3f}"
        )


@dataclass
class TrainResult:
    table: QTable
    episodes_run: int
    goals: int
    steps: int
    seconds: float
    interrupted: bool
    results: list[EpisodeResult]


def open_run(
    env: KoolioEnv,
    store: QTableStore,
    log_path: str | Path | None,
    purpose: str = "koolio-pm",
) -> tuple[QTable, LogWriter]:
    """Lock and open a run's table and log: the log is checked before any file is written
    (a new table is created only then) and brought in step with the table
    (:mod:`koolio_pymunk.episode_log`). The caller closes both."""
    cfg = env.config
    try:
        if log_path is not None and str(log_path) != "":
            check_log_path(log_path, store.path, tuple(env.randomizer.columns))
        table = store.load(
            env.layout, sensor_signature(cfg), cfg.learner.q_init, arena_record(env.arena)
        )
        attach(table, cfg.learner, str(store.path))  # the run's learning algorithm
        log = LogWriter(
            log_path,
            int(table.meta.get("episodes", 0)),
            store.fresh,
            store.path,
            purpose,
            extra_fields=tuple(env.randomizer.columns),
        )
        try:
            if store.fresh:
                store.create(table)
        except BaseException:
            log.close()
            raise
    except BaseException:
        store.close()
        raise
    return table, log


def train(
    env: KoolioEnv,
    store: QTableStore,
    episodes: int,
    seed: int,
    log_path: str | Path | None = None,
    discard_unfinished: bool = False,
    report: Callable[[str], None] | None = print,
    report_every: float = 1.0,
) -> TrainResult:
    """Train for ``episodes`` more episodes, saving the table after each one.

    Ctrl-C (KeyboardInterrupt) is the paper's Exit: the unfinished episode's updates are
    kept and the table saved; with ``discard_unfinished`` it is Exit Without Save: the
    table file stays as it was after the last finished episode. Ctrl-C takes effect
    between steps (:class:`SafeInterrupt`). The table and the log are locked while it
    runs (:func:`open_run`); a failed write (disk full) stops it with a
    :class:`~koolio_pymunk.errors.FileError`, the files holding the last good table.
    """
    cfg = env.config
    table, log = open_run(env, store, log_path, "koolio-pm train")
    first = int(table.meta.get("episodes", 0))
    progress = Progress()
    results: list[EpisodeResult] = []
    agent = make_learner(table, cfg.learner, np.random.default_rng(seed), str(store.path))
    last_report = time.perf_counter()
    interrupted = False
    try:
        with SafeInterrupt() as guard:
            try:
                for e in range(first, first + episodes):
                    if guard.pending:  # between episodes: nothing unfinished
                        interrupted = True
                        if report:
                            report("interrupted between episodes: nothing unfinished")
                        break
                    env_seed, rng = episode_seeds(seed, e)
                    agent.begin_episode(e, rng)
                    env.reset(seed=env_seed)
                    reward, steps, outcome = run_episode(env, agent, True, stop=guard.check)
                    res = EpisodeResult(
                        e,
                        reward,
                        steps,
                        env.bumps,
                        outcome,
                        env.has_been_rescued,
                        agent.epsilon,
                        env.goal_name,
                        realism_values(env),
                    )
                    table.meta["episodes"] = e + 1
                    store.save(table)
                    log.write(res)
                    results.append(res)
                    progress.add(res)
                    now = time.perf_counter()
                    if report and (now - last_report >= report_every or e == first + episodes - 1):
                        report(progress.line(e + 1, first + episodes, agent.epsilon))
                        last_report = now
            except KeyboardInterrupt:
                interrupted = True
                table = _interrupted(
                    env, agent, store, table, log, first, discard_unfinished, results, report
                )
    finally:
        log.close()
        store.close()
    return TrainResult(
        table,
        progress.episodes,
        progress.goals,
        progress.steps,
        time.perf_counter() - progress.started,
        interrupted,
        results,
    )


def _interrupted(
    env: KoolioEnv,
    agent: QLearner,
    store: QTableStore,
    table: QTable,
    log: LogWriter,
    first: int,
    discard: bool,
    results: list[EpisodeResult],
    report: Callable[[str], None] | None,
) -> QTable:
    """Ctrl-C in an episode: Exit (fold it in, save, log it ``interrupted``) or Exit Without
    Save (the file still holds the table of the last finished episode)."""
    if discard:
        if report:
            report("interrupted: unfinished episode discarded (Exit Without Save)")
        return load_qtable(store.path)
    res = EpisodeResult(
        table.meta.get("episodes", first),
        env.episode_reward,
        env.steps,
        env.bumps,
        "interrupted",
        env.has_been_rescued,
        agent.epsilon,
        env.goal_name,
        realism_values(env),
    )
    store.save(table)
    log.write(res)
    results.append(res)
    if report:
        report("interrupted: unfinished episode folded into the Q-table and saved (Exit)")
    return table


@dataclass
class EvalResult:
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

    def as_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


def evaluate(
    env: KoolioEnv, table: QTable, episodes: int, seed: int, goal: str | None = None
) -> EvalResult:
    """Greedy policy (epsilon 0, no updates), random start headings, ``episodes`` runs."""
    agent = QLearner(table, env.config.learner, np.random.default_rng(seed))
    agent.epsilon = 0.0
    outcomes: list[str] = []
    steps: list[int] = []
    bumps: list[int] = []
    rewards: list[float] = []
    options = {"goal": goal} if goal else None
    for e in range(episodes):
        env_seed, agent.rng = episode_seeds(seed, e, EVAL_STREAM)
        env.reset(seed=env_seed, options=options)
        reward, n, outcome = run_episode(env, agent, learn=False)
        outcomes.append(outcome)
        steps.append(n)
        bumps.append(env.bumps)
        rewards.append(reward)
    n = max(1, episodes)
    return EvalResult(
        episodes=episodes,
        goal_rate=outcomes.count("goal") / n,
        end_of_world_rate=outcomes.count("end_of_world") / n,
        truncated_rate=outcomes.count("truncated") / n,
        wrong_door_rate=outcomes.count("wrong_door") / n,
        mean_steps=float(np.mean(steps)) if steps else 0.0,
        mean_bumps=float(np.mean(bumps)) if bumps else 0.0,
        mean_reward=float(np.mean(rewards)) if rewards else 0.0,
        goal=env.goal_name,
    )
