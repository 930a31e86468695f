"""The episode loop: one robot, one episode, one step at a time (paper §5.4.6 and §5.4.8).

This is the reference of every loop that runs episodes: :class:`Episodes` (one robot;
the window's learning and watching, :mod:`koolio_pymunk.apps.viewer.session`, and the
robot runtime's episodes of ``koolio-pm transfer``) and :class:`Robots` (N robots in
tick order on one table). ``koolio-pm train`` and ``eval``
(:mod:`koolio_pymunk.learning.training`, :mod:`koolio_pymunk.learning.evaluation`) run
the same episodes on the compiled step engine (:mod:`koolio_pymunk.learning.engine`),
bit for bit, and take the seeds and the episode's row from here.

**One step** (:meth:`Episodes.step`), in the paper's order:

1. the agent chooses an action for the current state (epsilon-greedy for the learners);
2. the environment simulates it: move, sense, judge (reward and end of episode), step
   cap (:meth:`~koolio_pymunk.task.env.KoolioEnv.simulate`);
3. the agent learns from the step, bootstrapping from the state the action led to;
4. then, and only then, the auto-rescue check (§5.4.8:
   :meth:`~koolio_pymunk.task.env.KoolioEnv.rescue_check`); the next step starts from the
   rescued state.

**Seeding.** Episode ``e`` of a run with seed ``s`` resets the environment with a seed
derived from ``(s, e, stream)`` and gives the agent a generator derived from
``(s, e, stream, 1)`` (:func:`episode_seeds`). Training, evaluation and the robot's
episodes use different streams, so they never share starts. The same seed therefore gives
the same episodes, and a run resumed at episode ``e`` continues exactly like an
uninterrupted one.

**The agent** is anything with the learner interface
(:class:`~koolio_pymunk.learning.qlearning.QLearner`): ``epsilon``,
``begin_episode(episode, rng)``, ``act(state)``, ``observe(state, action, reward,
next_state, terminal)``; it may also have ``relocated(state)``, called after a rescue
moved the robot.

>>> from koolio_pymunk.learning.qlearning import QLearner
>>> from koolio_pymunk.store.qtable import QTable
>>> from koolio_pymunk.task.env import KoolioEnv
>>> env = KoolioEnv("room", max_steps=20)
>>> agent = QLearner(QTable(env.layout), env.config.learner, None)
>>> episodes = Episodes(env, agent, seed=0)
>>> episodes.begin(0)
>>> result = episodes.run()
>>> result.episode, result.steps, result.outcome in ("goal", "end_of_world", "truncated")
(0, 20, True)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from ..store.keyword import robot_offset, table_robots
from ..task.env import KoolioEnv

#: Seed streams: training, evaluation and robot episodes of one seed never share starts.
TRAIN_STREAM, EVAL_STREAM, ROBOT_STREAM = 0, 1, 2
#: The outcome of an episode stopped before its end (Ctrl-C, Exit).
INTERRUPTED = "interrupted"
#: The outcome of an episode cut by the step cap.
TRUNCATED = "truncated"


def episode_seeds(
    seed: int, episode: int, stream: int = TRAIN_STREAM
) -> tuple[int, np.random.Generator]:
    """The environment seed and the agent's generator for ``episode`` of run ``seed``.

    >>> episode_seeds(0, 0)[0] == episode_seeds(0, 0)[0] != episode_seeds(0, 1)[0]
    True
    """
    return env_seed(seed, episode, stream), np.random.default_rng([seed, episode, stream, 1])


def env_seed(seed: int, episode: int, stream: int = TRAIN_STREAM) -> int:
    """The environment seed of :func:`episode_seeds` alone (no agent generator made):
    ``SeedSequence([seed, episode, stream]).generate_state(1)[0]``
    (:func:`~koolio_pymunk.task.seeding.seed_of`)."""
    from ..task.seeding import seed_of  # numba: loaded when an episode starts

    return seed_of([seed, episode, stream])


@dataclass
class EpisodeResult:
    """One episode as the training log records it (one CSV row,
    :mod:`koolio_pymunk.store.episode_log`)."""

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
        """The log row: the columns of ``LOG_FIELDS``, then the ``realism.*`` draws."""
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


class Agent(Protocol):
    """What :class:`Episodes` asks of an agent (the learners of
    :mod:`koolio_pymunk.learning.algorithms`, or the robot runtime's learner)."""

    epsilon: float

    def begin_episode(self, episode: int, rng: np.random.Generator) -> None:
        """A new episode: ``rng`` owns its exploration draws (traces reset, epsilon
        from the schedule)."""

    def act(self, state: int) -> int:
        """The action in ``state`` (epsilon-greedy while learning)."""

    def observe(
        self, state: int, action: int, reward: float, next_state: int, terminal: bool
    ) -> None:
        """Learn from one step (``next_state``: where the action led, before any rescue)."""


class Episodes:
    """The episodes of one robot in ``env``, driven by ``agent`` (module doc): the
    reference of every loop that runs episodes.

    ``learn`` False only watches (no :meth:`Agent.observe`); ``epsilon``, when given,
    replaces the schedule's value at every episode start (0: the greedy policy).
    :meth:`begin` starts an episode, :meth:`step` makes one step and returns the outcome
    when the episode ended (``None`` while it runs), :meth:`run` steps to the end,
    :meth:`result` is the episode's log row. (:func:`koolio_pymunk.learning.engine.robots`
    runs many episodes of one robot or several on the compiled step engine, the same
    steps bit for bit.)
    """

    def __init__(
        self,
        env: KoolioEnv,
        agent: Agent,
        seed: int,
        stream: int = TRAIN_STREAM,
        learn: bool = True,
        epsilon: float | None = None,
        key_offset: int = 0,
    ) -> None:
        self.env = env
        self.agent = agent
        self.seed = seed
        self.stream = stream
        self.learn = learn
        self.epsilon = epsilon
        self.key_offset = key_offset
        """Added to every state key the agent sees: the robot's own rows in a table that
        holds each robot's (:func:`~koolio_pymunk.store.keyword.robot_offset`; 0: shared)."""
        self.episode = -1
        """The number of the episode begun last (-1: none yet)."""
        self.outcome: str | None = None
        """How the current episode ended (``None`` while it runs)."""

    def begin(self, episode: int, options: dict[str, Any] | None = None) -> None:
        """Start ``episode``: its seeds, the env's reset, the agent's episode start."""
        env_seed, rng = episode_seeds(self.seed, episode, self.stream)
        self.env.reset(seed=env_seed, options=options)
        self.agent.begin_episode(episode, rng)  # after the reset: it may read the start
        if self.epsilon is not None:
            self.agent.epsilon = self.epsilon
        self.episode = episode
        self.outcome = None

    def step(self) -> str | None:
        """One step: act -> simulate -> learn -> rescue check; the outcome at the end. In
        a shared arena (:mod:`koolio_pymunk.task.shared_arena`) a robot whose episode
        ended then leaves the arena, and a robot waiting for a free start spot spends its
        turn asking for one (:meth:`KoolioEnv.enter`) instead of stepping."""
        env, agent = self.env, self.agent
        if env.waiting:
            env.enter()
            return None
        own = self.key_offset
        state = env.state_key + own
        action = agent.act(state)
        nxt, reward, terminated, truncated = env.simulate(action)
        if self.learn:  # from the state the action led to, before any rescue (§5.4.8)
            agent.observe(state, action, reward, nxt + own, terminated)
        if env.rescue_check():
            relocated = getattr(agent, "relocated", None)
            if relocated is not None:
                relocated(env.state_key + own)
        if terminated:
            self.outcome = env.judgement.event  # type: ignore[union-attr]
        elif truncated:
            self.outcome = TRUNCATED
        if self.outcome is not None:
            env.leave()
        return self.outcome

    def run(self, stop: Callable[[], bool | None] | None = None) -> EpisodeResult:
        """Step to the end of the episode; ``stop`` is called after every step that did
        not end it, and a true result ends it as ``interrupted`` (it may also raise, as
        :meth:`~koolio_pymunk.store.interrupts.SafeInterrupt.check` does)."""
        step = self.step
        while step() is None:
            if stop is not None and stop():
                self.outcome = INTERRUPTED
                break
        return self.result()

    def result(self, outcome: str | None = None, episode: int | None = None) -> EpisodeResult:
        """The current episode's row: its outcome (or ``outcome``, e.g. ``interrupted``
        for an unfinished one) under its number (or ``episode``)."""
        env = self.env
        return EpisodeResult(
            self.episode if episode is None else episode,
            env.episode_reward,
            env.steps,
            env.bumps,
            outcome if outcome is not None else str(self.outcome),
            env.has_been_rescued,
            self.agent.epsilon,
            env.goal_name,
            realism_values(env),
        )


def robot_offsets(agents: list[Agent]) -> list[int]:
    """Each robot's :func:`~koolio_pymunk.store.keyword.robot_offset` in its learners'
    table (all 0 for a table all share, or learners without one). ``ValueError`` when the
    table holds fewer robots' own rows than there are robots."""
    layout = getattr(getattr(agents[0], "table", None), "layout", None)
    own = table_robots(layout) if layout is not None else 0
    if not own:
        return [0] * len(agents)
    if len(agents) > own:
        raise ValueError(f"a table of {own} robots' own rows, and {len(agents)} robots")
    return [robot_offset(layout, r) for r in range(len(agents))]


class Robots:
    """N robots' episodes stepped in tick order into one table, in Python: the reference
    of the compiled step engine (:class:`~koolio_pymunk.learning.engine.Engine`, the same
    interface and the same episodes bit for bit).

    Robot ``r`` has its env ``envs[r]`` and its learner ``agents[r]`` (the learners share
    one Q-table; a table that holds each robot's own rows, ``train --tables each``, gives
    robot ``r`` its own: :attr:`offsets`). A *tick* steps every running robot once, in index
    order, each a whole :meth:`Episodes.step` (act, simulate, learn, rescue): robot ``r``
    sees the table as the robots before it left it in that tick. :meth:`begin` starts robot
    ``r``'s episode number ``episode`` (its seeds are ``(seed, episode, stream)``'s,
    whatever the robot); :meth:`advance` steps until a robot finishes and returns it; the
    caller records the episode (:meth:`result`) and begins the robot's next one, which makes
    its first step in the next tick. With one robot this is :class:`Episodes`, step for
    step.
    """

    def __init__(
        self,
        envs: list[KoolioEnv],
        agents: list[Agent],
        seed: int,
        stream: int = TRAIN_STREAM,
        learn: bool = True,
        epsilon: float | None = None,
    ) -> None:
        if len(envs) != len(agents) or not envs:
            raise ValueError("one env and one learner per robot, at least one robot")
        self.envs, self.agents = envs, agents
        self.seed, self.stream, self.learn, self.epsilon = seed, stream, learn, epsilon
        self.offsets = robot_offsets(agents)
        """What robot ``r``'s state keys add in the table (all 0: one table all share)."""
        self.loops = [
            Episodes(e, a, seed, stream, learn, epsilon, own)
            for e, a, own in zip(envs, agents, self.offsets)
        ]
        self.episodes = [-1] * len(envs)
        """Each robot's current (or last) episode number."""
        self.running = [False] * len(envs)
        """Which robots have an episode under way."""
        self._cursor = 0
        self.python_reason: str | None = "the Python loop"
        """Why these episodes run in Python (None: on the compiled engine)."""

    def __len__(self) -> int:
        return len(self.envs)

    def begin(self, r: int, episode: int, options: dict[str, Any] | None = None) -> None:
        """Start robot ``r``'s episode ``episode`` (:meth:`Episodes.begin`)."""
        self.loops[r].begin(episode, options)
        self.episodes[r] = episode
        self.running[r] = True

    def advance(self, stop: Callable[[], bool | None] | None = None) -> int | None:
        """Step the running robots in tick order until one finishes its episode: its
        index; None when ``stop`` (asked after every tick) answered true, or when no robot
        is running."""
        loops, running, n = self.loops, self.running, len(self.loops)
        while any(running):
            for r in range(self._cursor, n):
                if running[r] and loops[r].step() is not None:
                    running[r] = False
                    self._cursor = r + 1
                    return r
            self._cursor = 0
            if stop is not None and stop():
                return None
        return None

    def outcome(self, r: int) -> str | None:
        """How robot ``r``'s last episode ended (None while it runs)."""
        return self.loops[r].outcome

    def result(
        self, r: int, outcome: str | None = None, episode: int | None = None
    ) -> EpisodeResult:
        """Robot ``r``'s episode row (:meth:`Episodes.result`)."""
        return self.loops[r].result(outcome, episode)

    def release(self, r: int) -> None:
        """Robot ``r`` starts no more episodes (its unfinished one, if any, is dropped)."""
        self.running[r] = False

    def sync_table(self) -> None:
        """The Q-table holds every update made (the Python learners write it directly)."""

    #: The Python learners write the table's rows in place: their changes are not tracked
    #: (a run's table is written whole between its durable snapshots).
    changed_rows = None

    def sync(self) -> None:
        """The table, the envs and the learners hold the state reached (they do)."""

    def discard(self, robots: list[int]) -> list[int]:
        """Taking back the unfinished episodes' writes needs the engine's journal."""
        raise ValueError("discard: the Python loop keeps no journal of the writes")
