"""The step engine: N >= 1 robots' episodes on one compiled step, one shared table.

(A table of ``train --tables each`` gives each robot its own rows of it: the robot's
state keys carry its index, ``lints[r, L_OWN]``, as
:attr:`Robots.offsets <koolio_pymunk.learning.episodes.Robots.offsets>` does.)

:class:`Engine` runs the episodes of :class:`~koolio_pymunk.learning.episodes.Robots` (N
robots, each with its own env and learner, one Q-table, stepped in tick order) without
Python between the steps: :func:`run` makes, robot after robot in index order, the step
of :meth:`Episodes.step <koolio_pymunk.learning.episodes.Episodes.step>`:

1. act: the robot's epsilon-greedy choice (:func:`~.table_kernel.choose`, with the no-undo
   rule and Q(lambda)'s cut), drawing from its learner's generator;
2. simulate: :func:`koolio_pymunk.task.step_kernel.simulate` (move, sense, memory, judge,
   step cap), drawing from its env's generator;
3. learn: Table 11 (:func:`~.table_kernel.update`) or Q(lambda)
   (:func:`~.table_kernel.lambda_update`) into the shared table, bootstrapping from the
   state the action led to; nothing when only playing (``learn`` False);
4. rescue: :func:`koolio_pymunk.task.step_kernel.rescue_check` (paper §5.4.8: after the
   update).

Robot ``r``'s step in a tick sees the table as the robots before it left it in that tick.
Python does what happens between episodes, exactly as the Python loop does it: the reset
(the seeds, :meth:`KoolioEnv.reset_key <koolio_pymunk.task.env.KoolioEnv.reset_key>`, the
learner's episode start), the log row, saving, the checks; :func:`run` returns at every
finished episode (the caller records it and starts the robot's next one) and after
:data:`CHUNK` robot-steps (the caller looks for Ctrl-C), then goes on from the next robot.

**What runs here**: one-step Q (``learner.algorithm: q``) and Watkins's Q(lambda)
(``qlambda``), learning or playing (greedy or with a fixed epsilon: ``eval``, the periodic
checks), the no-undo rule, a compiled sensor backend (``fast``, ``cone``), the memory, every
realism model and domain randomization (drawn at the reset, in Python), rescue, any
number of robots. What does not (:func:`why_not`): Dyna-Q, whose model (every outcome of
every pair, in first-seen order, saved with the table) lives in Python and whose planning
updates are a Python loop over it, and the pymunk reference backend; both run the Python
loop, :class:`~koolio_pymunk.learning.episodes.Robots`, which is this engine's reference.

``tests/learning/test_engine.py`` holds the engine to the Python loop bit for bit (tables,
log rows, the envs and learners it leaves) for one robot and for several, in every world,
with every learner it runs; ``tools/agreement.py --episodes N`` does it for long runs.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numba
import numpy as np

from ..sensing.reading_kernel import robot_group, robot_others
from ..store.kernel_cache import ensure_fresh
from ..task.batch import EnvBatch, Generators
from ..task.env import WRONG_DOOR, KoolioEnv
from ..task.shared_arena import SharedArena
from ..task.step_kernel import (
    EVENTS,
    F_RETURN,
    I_BUMPS,
    I_CHECK_RESCUE,
    I_HAS_BEEN_RESCUED,
    I_STATE,
    I_STEPS,
    RUNNING,
    TRUNCATED_CODE,
    WRONG_DOOR_CODE,
    rescue_check_robot,
    simulate_inline,
    simulate_robot,
)
from .episodes import (
    TRAIN_STREAM,
    TRUNCATED,
    Agent,
    EpisodeResult,
    Robots,
    env_seed,
    realism_values,
)
from .qlambda import QLambda
from .qlearning import QLearner
from .table_kernel import (
    SharedTable,
    _barred,
    choose_inline,
    grow_journal,
    learn_step,
    new_journal,
    not_greedy_inline,
    undo_writes,
)

ensure_fresh()  # numba's cache, in step with every kernel's source (see there)

#: Robot-steps per compiled call at most (Python looks for Ctrl-C between calls).
CHUNK = 4096
#: :func:`run`'s answers: a robot finished its episode (``ctl[C_ROBOT]``,
#: ``ctl[C_OUTCOME]``); the budget of robot-steps is spent; a robot's journal needs room;
#: no robot is running; a robot waiting outside a shared arena has its turn
#: (``ctl[C_ROBOT]``: Python draws its start spot, :meth:`EnvBatch.enter`).
FINISHED, BUDGET, NEED_ROOM, IDLE, ENTER = 0, 1, 2, 3, 4
#: ``ctl``: the next robot to step, the robot that finished and its outcome code.
C_CURSOR, C_ROBOT, C_OUTCOME = range(3)
#: ``lints`` of a robot: running an episode, its last action (the no-undo rule; -1: none),
#: waiting outside a shared arena for a free start spot, what its state keys add in the
#: table (:attr:`Robots.offsets <koolio_pymunk.learning.episodes.Robots.offsets>`).
L_ACTIVE, L_LAST, L_WAITING, L_OWN = range(4)


def why_not_config(env: KoolioEnv) -> str | None:
    """Why learning with ``env``'s configuration (its ``learner.algorithm``, its sensor
    backend) cannot run on the engine (None: it can)."""
    algorithm = env.config.learner.algorithm
    if algorithm not in ("q", "qlambda"):
        return f"learner.algorithm {algorithm}: its model and planning run in the Python loop"
    if not env.sensors.fused:
        return f"sensors.backend {env.sensors.backend}: the pymunk reference runs in Python"
    return None


def why_not(env: KoolioEnv, agent: object) -> str | None:
    """Why ``agent``'s episodes in ``env`` cannot run on the engine (None: they can)."""
    if type(agent) not in (QLearner, QLambda):
        name = getattr(agent, "name", type(agent).__name__)
        return f"learner.algorithm {name}: its model and planning run in the Python loop"
    if not env.sensors.fused:
        return f"sensors.backend {env.sensors.backend}: the pymunk reference runs in Python"
    return None


@numba.njit(cache=True)
def run(
    budget: int, ctl: np.ndarray, gens, agens, readings: tuple, world: tuple, motion: np.ndarray,
    task: tuple, memory: tuple, ints: np.ndarray, floats: np.ndarray, mem: np.ndarray,
    among: tuple, learner: tuple, lints: np.ndarray, epsilon: np.ndarray, index, table: tuple,
    lam: tuple, traces: tuple, journal: tuple, writes: int,
) -> int:  # fmt: skip
    """At most ``budget`` robot-steps from robot ``ctl[C_CURSOR]`` on, in tick order
    (module doc); returns :data:`FINISHED` at the first finished episode, else
    :data:`BUDGET`, :data:`NEED_ROOM` (a running robot's journal lacks room for
    ``writes`` more entries), :data:`IDLE`, or :data:`ENTER` at the turn of a robot
    waiting outside a shared arena (``among``:
    :attr:`~koolio_pymunk.task.batch.EnvBatch.among`).

    Per robot: ``gens``/``agens`` its env's and learner's generators, its row of
    ``readings`` (``(shared, rows)`` of
    :class:`~koolio_pymunk.sensing.reading_kernel.ReadingArrays`),
    ``ints``/``floats``/``mem``/``motion`` its env's state (the
    :mod:`~koolio_pymunk.task.step_kernel`'s), ``lints`` (:data:`L_ACTIVE`, :data:`L_LAST`)
    and ``epsilon`` its learner's; ``traces`` = ``(rows, actions, e, meta)``, Q(lambda)'s
    traces by robot (:func:`~.table_kernel.lambda_update`). Shared: ``world``, ``task``,
    ``memory`` (:mod:`~koolio_pymunk.task.step_kernel`), ``learner`` = ``(alpha, gamma,
    n_actions, no_undo, learn)``, ``lam`` = ``(Q(lambda) on, gamma * lambda, trace
    cutoff)``, the table (``index``, ``table``: :class:`~.table_kernel.SharedTable`) and
    the ``journal`` (:func:`~.table_kernel.new_journal`)."""
    n = ints.shape[0]
    room = journal[0].shape[1]
    jn = journal[2]
    alpha, gamma, n_actions, no_undo, learn = learner
    lambda_on = lam[0]
    any_active = False
    for r in range(n):
        any_active = any_active or lints[r, L_ACTIVE] == 1
    if not any_active:
        return IDLE
    r = ctl[C_CURSOR]
    done = 0
    while done < budget:
        if r >= n:
            r = 0
        if lints[r, L_ACTIVE]:
            if lints[r, L_WAITING]:
                ctl[C_CURSOR] = r + 1
                ctl[C_ROBOT] = r
                return ENTER
            if room > 0 and jn[r] + writes > room:
                ctl[C_CURSOR] = r
                return NEED_ROOM
            # Robot r's step (module doc), written here rather than in a function of its own:
            # numba would bind every array of the groups to the function's arguments at
            # each step, each binding an atomic reference count (docs/speed.md).
            own = lints[r, L_OWN]  # its own rows' offset (0: one table all share)
            state = ints[r, I_STATE] + own
            if lambda_on and state != traces[3][r, 1]:  # not where the last step ended
                traces[3][r, 0] = 0  # no traces
            bar = _barred(lints[r, L_LAST]) if no_undo else -1
            action, explored = choose_inline(state, epsilon[r], agens[r], n_actions, index,
                                             table[0], bar)  # fmt: skip
            if lambda_on and explored and not_greedy_inline(index, table[0], state, action, bar):
                traces[3][r, 0] = 0  # Watkins's cut
            lints[r, L_LAST] = action
            rng = gens[r]
            if among is None:  # a robot alone (numba prunes the other branch)
                nxt, code, reward, terminated, truncated = simulate_robot(
                    r, action, rng, readings, world, motion, task, memory, ints, floats, mem
                )
            else:
                nxt, code, reward, terminated, truncated = simulate_inline(
                    r, action, rng, robot_group(r, readings[0], readings[1]), world, motion,
                    task, memory, ints, floats, mem, robot_others(r, among[0], among[1], among[2]),
                )  # fmt: skip
            nxt += own
            if learn:
                learn_step(r, index, table, alpha, gamma, state, action, reward, nxt, terminated,
                           lam, traces, journal)  # fmt: skip
            # rescue_check's own first test (no rescue due) made here: its group is made only
            # when one is due
            if ints[r, I_CHECK_RESCUE] != 0 and rescue_check_robot(
                r, rng, readings, world, task, memory, ints, floats, mem, among
            ):
                lints[r, L_LAST] = -1  # QLearner.relocated
            outcome = code if terminated else (TRUNCATED_CODE if truncated else RUNNING)
            done += 1
            if outcome != RUNNING:
                lints[r, L_ACTIVE] = 0
                ctl[C_CURSOR] = r + 1
                ctl[C_ROBOT] = r
                ctl[C_OUTCOME] = outcome
                return FINISHED
        r += 1
    ctl[C_CURSOR] = r
    return BUDGET


def outcome_name(code: int) -> str:
    """An outcome code of :func:`run` as the log writes it."""
    if code == TRUNCATED_CODE:
        return TRUNCATED
    return WRONG_DOOR if code == WRONG_DOOR_CODE else EVENTS[code]


def trace_capacity(decay: float, cutoff: float) -> int | None:
    """The most entries Q(lambda) can trace at once (a trace lives while ``decay ** k``
    stays at or above ``cutoff``), plus the one a step adds; None when unbounded.

    >>> trace_capacity(0.98 * 0.9, 0.01), trace_capacity(1.0, 0.01), trace_capacity(0.5, 0.0)
    (39, None, None)
    """
    if decay <= 0.0:
        return 2
    if decay >= 1.0 or cutoff <= 0.0:
        return None
    return math.floor(math.log(cutoff) / math.log(decay)) + 3


class Engine(Robots):
    """:class:`~koolio_pymunk.learning.episodes.Robots` on the compiled step (module doc):
    the same interface, the same episodes bit for bit.

    ``journal`` True records every write of a running episode so that :meth:`discard`
    can take back those of the unfinished ones (``--discard-unfinished`` with several
    robots)."""

    def __init__(
        self,
        batch: EnvBatch,
        agents: list,
        seed: int,
        stream: int,
        learn: bool = True,
        epsilon: float | None = None,
        journal: bool = False,
    ) -> None:
        super().__init__(batch.envs, agents, seed, stream, learn, epsilon)
        for env, agent in zip(batch.envs, agents):
            reason = why_not(env, agent)
            if reason is not None:
                raise ValueError(reason)
        self.batch = batch
        self.python_reason = None
        n = len(batch)
        first = agents[0]
        self.shared = SharedTable(first.table)
        self.ctl = np.zeros(3, np.int64)
        self.lints = np.zeros((n, 4), np.int64)
        self.lints[:, L_LAST] = -1
        self.epsilon_of = np.zeros(n)
        """Each robot's epsilon for its episode."""
        self.codes = np.full(n, RUNNING, np.int64)
        """Each robot's last outcome code (:data:`RUNNING` while its episode runs)."""
        self.learner = (float(first.alpha), float(first.gamma), int(first.n_actions),
                        bool(first.no_undo), bool(learn))  # fmt: skip
        self.lam = (False, 0.0, 0.0)
        self._trace_bound: int | None = 1
        if learn and isinstance(first, QLambda):
            self.lam = (True, float(first.decay), float(first.cutoff))
            self._trace_bound = trace_capacity(first.decay, first.cutoff)
        self.traces = self._new_traces(1)
        self.agent_gens = Generators(n)
        self.journal = new_journal(n, 1024 if journal else 0)

    # -- episodes -----------------------------------------------------------------------
    def begin(self, r: int, episode: int, options: dict | None = None) -> None:
        """Start robot ``r``'s episode ``episode``: the seeds of ``(seed, episode,
        stream)``, the env's reset, the learner's episode start (as
        :meth:`Episodes.begin <koolio_pymunk.learning.episodes.Episodes.begin>`)."""
        env, agent = self.envs[r], self.agents[r]
        env.check_options(options)
        self.batch.reset(r, env_seed(self.seed, episode, self.stream), options)
        rng = self.agent_gens.seeded(r, [self.seed, episode, self.stream, 1])
        agent.begin_episode(episode, rng)
        if self.epsilon is not None:
            agent.epsilon = self.epsilon
        self.epsilon_of[r] = agent.epsilon
        self.lints[r] = (1, agent.last, int(env.waiting), self.offsets[r])
        self.traces[3][r] = (0, -1)
        self.journal[2][r] = 0
        self.episodes[r] = episode
        self.codes[r] = RUNNING
        self.running[r] = True

    def advance(self, stop: Callable[[], bool | None] | None = None) -> int | None:
        """Step the running robots in tick order until one finishes its episode: its
        index; None when ``stop`` (asked between chunks of :data:`CHUNK` robot-steps)
        answered true, or when no robot is running."""
        sh, b = self.shared, self.batch
        writes = 1 if not self.lam[0] else self.traces[0].shape[1]
        while True:
            sh.reserve(CHUNK + 1)
            self._trace_room()
            why = run(CHUNK, self.ctl, b.generators.typed, self.agent_gens.typed, b.reading_args,
                      b.world, b.motion, b.task, b.memory, b.ints, b.floats, b.mem, b.among,
                      self.learner, self.lints, self.epsilon_of, sh.index, sh.args(), self.lam,
                      self.traces, self.journal, writes)  # fmt: skip
            if why == FINISHED:
                r = int(self.ctl[C_ROBOT])
                self.codes[r] = self.ctl[C_OUTCOME]
                self.running[r] = False
                self.envs[r].leave()  # it leaves the arena before any other robot steps
                return r
            if why == ENTER:
                r = int(self.ctl[C_ROBOT])
                self.lints[r, L_WAITING] = int(not b.enter(r))
                continue
            if why == IDLE:
                return None
            if why == NEED_ROOM:
                self.journal = grow_journal(self.journal)
                continue
            if stop is not None and stop():
                return None

    def outcome(self, r: int) -> str | None:
        code = int(self.codes[r])
        return None if code == RUNNING else outcome_name(code)

    def result(self, r: int, outcome: str | None = None, episode: int | None = None):
        ints, floats = self.batch.ints[r], self.batch.floats[r]
        env = self.envs[r]
        return EpisodeResult(
            self.episodes[r] if episode is None else episode,
            float(floats[F_RETURN]),
            int(ints[I_STEPS]),
            int(ints[I_BUMPS]),
            outcome if outcome is not None else str(self.outcome(r)),
            bool(ints[I_HAS_BEEN_RESCUED]),
            float(self.epsilon_of[r]),
            env.goal_name,
            realism_values(env),
        )

    def release(self, r: int) -> None:
        self.lints[r, L_ACTIVE] = 0
        self.running[r] = False

    # -- the table, the envs and the learners as the Python steps leave them ------------
    def sync_table(self) -> None:
        """The shared table's changed rows into the Q-table (before a save or a check)."""
        self.shared.sync()

    def changed_rows(self) -> tuple[np.ndarray, np.ndarray]:
        """The keys and values of the table's rows written since the last call."""
        return self.shared.changed()

    def sync(self) -> None:
        """The table, every env and every learner as the Python steps would have left
        them (the end of a run, a stop)."""
        self.shared.sync()
        for r in range(len(self.envs)):
            self.batch.store(r)
            agent = self.agents[r]
            agent.last = int(self.lints[r, L_LAST])
            if self.lam[0]:
                self._traces_out(r, agent)

    def discard(self, robots: list[int]) -> list[int]:
        """Take back every write of ``robots``' running episodes that no other robot has
        written over since (:func:`~.table_kernel.undo_writes`); returns the keys of the
        rows they alone created (the caller drops them). Needs ``journal``."""
        if self.journal[0].shape[1] == 0:
            raise ValueError("discard: this engine keeps no journal")
        return undo_writes(self.shared, self.journal, robots)

    # -- Q(lambda)'s traces ---------------------------------------------------------------
    def _new_traces(self, capacity: int) -> tuple:
        n = len(self.envs)
        meta = np.zeros((n, 2), np.int64)
        meta[:, 1] = -1
        return (np.zeros((n, capacity), np.int64), np.zeros((n, capacity), np.int64),
                np.zeros((n, capacity)), meta)  # fmt: skip

    def _trace_room(self) -> None:
        """Room for every robot's traces in the next chunk: the most a trace can hold, or
        (unbounded) a trace on every row the table may reach."""
        if not self.lam[0]:
            return
        need = self._trace_bound or self.shared.capacity
        old = self.traces
        if old[0].shape[1] >= need:
            return
        new = self._new_traces(need)
        cap = old[0].shape[1]
        for a, b in zip(new[:3], old[:3]):
            a[:, :cap] = b
        new[3][:] = old[3]
        self.traces = new

    def _traces_out(self, r: int, agent: QLambda) -> None:
        """Robot ``r``'s traces back into its learner, in their order."""
        rows, acts, e, meta = (t[r] for t in self.traces)
        n = int(meta[0])
        keys = self.shared.keys
        agent.traces = {
            int(keys[i]): [int(a), float(v)]
            for i, a, v in zip(rows[:n].tolist(), acts[:n].tolist(), e[:n].tolist())
        }
        agent._expect = None if meta[1] < 0 else int(meta[1])


def robots(
    envs: list[KoolioEnv] | KoolioEnv,
    agents: list[Agent],
    seed: int,
    stream: int = TRAIN_STREAM,
    learn: bool = True,
    epsilon: float | None = None,
    compiled: bool = True,
    journal: bool = False,
    shared: bool = False,
) -> Robots:
    """The episodes of ``len(agents)`` robots (``envs``: one per robot, or one env and
    the batch is made of it and its siblings, or with ``shared`` of robots like it sharing
    one arena, :meth:`SharedArena.of <koolio_pymunk.task.shared_arena.SharedArena.of>`):
    on the compiled step engine
    (:class:`~koolio_pymunk.learning.engine.Engine`) when ``compiled`` and it runs them,
    else the Python loop (:class:`~.episodes.Robots`); its ``python_reason`` says why
    the Python loop (None: the engine)."""
    n = len(agents)
    if isinstance(envs, KoolioEnv) and shared:
        envs = SharedArena.of(envs, n)
    elif isinstance(envs, KoolioEnv):
        envs = [envs] + [envs.sibling() for _ in range(n - 1)]
    reason = "not asked for" if not compiled else None
    if reason is None:
        reason = next((w for w in (why_not(e, a) for e, a in zip(envs, agents)) if w), None)
    if reason is not None:
        loop = Robots(envs, agents, seed, stream, learn, epsilon)
    else:
        loop = Engine(EnvBatch(envs), agents, seed, stream, learn, epsilon, journal)
    loop.python_reason = reason
    return loop
