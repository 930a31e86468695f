"""One robot's episode, compiled: act, move, sense, judge, learn, rescue in one numba call.

:class:`CompiledEpisode` runs the steps of an episode of :class:`~.episodes.Episodes`
(``koolio-pm train``'s loop) without Python between them; Python keeps what happens
between episodes (the reset and its draws, the agent's episode start, the log row, saving,
Ctrl-C). :func:`run_steps` is the step of :meth:`Episodes.step` written out, in the same
order and with the same draws from the same generators (numba's ``np.random.Generator``
methods draw as numpy's do, from the very generator objects):

1. act: one-step Q's epsilon-greedy choice with the agent's generator
   (:meth:`QLearner.act <koolio_pymunk.learning.qlearning.QLearner.act>`: one uniform for
   exploration, one integer for the action or a tie);
2. move: Forward and Reverse through :func:`koolio_pymunk.world.swept_move.sweep` (the
   pymunk world's swept move, bit for bit), rotations as :meth:`World.act`; with the
   realism motion model, :class:`~koolio_pymunk.world.motion_errors.MotionErrors`'s draws
   and :meth:`World.drive`'s chord;
3. sense: :func:`~koolio_pymunk.sensing.ray_kernel.sense_one` and
   :func:`~koolio_pymunk.sensing.encoding_kernel.readout` (or, with realism models on,
   :func:`~koolio_pymunk.sensing.realism_kernel.sense_realism`) with the env's generator,
   then the memory's update and codes when it is on (:func:`_remember`; the env's
   :class:`~koolio_pymunk.sensing.memory.Memory` is read before and written after every
   call);
4. judge: ``rules.judge``'s priority (:data:`~.fleet_kernel.EVENTS` codes), a misread
   plate's ``wrong_door``, the step cap;
5. learn: Table 11 (:func:`~.fleet_kernel.update` on :class:`~.fleet_kernel.SharedTable`,
   synced into the Q-table after every call), or Q(lambda)'s traced update
   (:func:`lambda_update`; the traces go back into the agent after every call);
6. rescue: ``rescue.wants_rescue`` and ``rescue_robot``'s reverses and spin, then a new
   reading.

**What runs here.** One-step Q (``learner.algorithm: q``) and Watkins's Q(lambda)
(``qlambda``: :func:`lambda_update`, :class:`~koolio_pymunk.learning.qlambda.QLambda`'s
replacing traces, its cut at a non-greedy exploratory action and at a step that does not
start where the last one ended, its cutoff) learning with a compiled sensor backend
(``fast``, ``cone``), with or without a memory in the state (``sensors.memory``:
:func:`_remember` is :class:`~koolio_pymunk.sensing.memory.Memory`'s update and key), in
any world (the realism models and domain randomization included: the draw is made at the
reset, in Python). Anything else (Dyna-Q, the pymunk reference, watching) runs the
Python loop: :func:`why_not` names the reason (``Episodes.compiled_reason``).

**Granularity.** A call runs at most ``budget`` steps (:data:`CHUNK`); Python then looks
for a Ctrl-C (``stop``), so a run without a step cap still stops, between two chunks
rather than two steps.

``tests/learning/test_episode_kernel.py`` holds seeded runs of this path to the Python
loop bit for bit (tables and log rows) in the ideal world and in ``koolio-real``, with
one-step Q and Q(lambda), with and without the memory;
``tools/agreement.py --episodes N`` does it for long runs.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numba
import numpy as np

from ..sensing.encoding_kernel import readout_inline
from ..sensing.memory import bearing_code, turned
from ..sensing.ray_kernel import sense_one_inline
from ..sensing.realism_kernel import sense_realism
from ..store.kernel_cache import ensure_fresh
from ..task.action_rules import allowed_action, barred
from ..task.env import WRONG_DOOR, KoolioEnv
from ..world.segment_query import wall_array
from ..world.swept_move import sweep
from .fleet_kernel import (
    ACTION_EVENT,
    EVENTS,
    N_TERMINAL,
    SharedTable,
    in_zone,
    reward_array,
    row_of,
    td_target,
    zone_arrays,
)
from .fleet_kernel import update as td_update
from .qlambda import QLambda
from .qlearning import QLearner

ensure_fresh()  # numba's cache, in step with every kernel's source (see there)

#: Steps per compiled call at most (Python checks for Ctrl-C between calls).
CHUNK = 4096
#: :func:`run_steps`'s outcome codes beyond :data:`EVENTS`' indices.
RUNNING, WRONG_DOOR_CODE, TRUNCATED_CODE = -1, len(EVENTS), len(EVENTS) + 1
#: ``ints`` of an episode: state key, steps, bumps, has been rescued, rescued this step,
#: the last action (``QLearner.last``, for ``learner.no_undo``).
I_STATE, I_STEPS, I_BUMPS, I_HAS_BEEN_RESCUED, I_RESCUED, I_LAST = range(6)
#: ``action_rules.barred`` and ``allowed_action``, compiled from the same Python code.
_barred = numba.njit(cache=True)(barred)
_allowed_action = numba.njit(cache=True)(allowed_action)
#: ``floats`` of an episode: x, y, heading, return.
F_X, F_Y, F_H, F_RETURN = range(4)
_TWO_PI = 2.0 * math.pi  # physics.TWO_PI


def why_not(env: KoolioEnv, agent: object, learn: bool = True) -> str | None:
    """Why ``agent``'s episodes in ``env`` cannot run compiled (None: they can)."""
    if type(agent) not in (QLearner, QLambda):
        name = getattr(agent, "name", type(agent).__name__)
        return f"learner.algorithm {name}: only one-step Q (q) and Q(lambda) run compiled"
    if not learn:
        return "watching without learning runs the Python loop"
    if not env.sensors.fused:
        return f"sensors.backend {env.sensors.backend}: the pymunk reference runs in Python"
    return None


@numba.njit(cache=True)
def sense_reading(x: float, y: float, h: float, rng, sense: tuple) -> tuple[int, bool, bool]:
    """``KernelInputs.sense_readout``: the reading's draws from ``rng``, the kernels
    (``sense``: :meth:`CompiledEpisode.sense_group`; the fleet builds one per robot). The
    draws go one by one into the buffers ``noise`` and, with realism models on, ``u`` (the
    generator's stream is that of its calls with a size: each value is the next scalar
    draw), so the draws allocate no array."""
    geometry, goal, plates, buffers, encoding, realism, noise, out, codes, flags, u = sense
    real_on, gaussian, n_raw, n_draws = flags[0] == 1, flags[1] == 1, flags[2], flags[3]
    if real_on:
        if gaussian:
            for i in range(n_raw):
                noise[i] = rng.standard_normal()
            for i in range(n_draws):
                u[i] = rng.random()
        else:
            for i in range(n_raw + n_draws):
                u[i] = rng.random()
        return sense_realism(x, y, h, geometry, goal, plates, buffers, noise, u, not gaussian,
                             realism, encoding, out, codes)  # fmt: skip
    sense_one_inline(x, y, h, geometry, goal, plates, buffers)
    if gaussian:
        for i in range(n_raw):
            noise[i] = rng.standard_normal()
    else:
        for i in range(n_raw):
            noise[i] = rng.uniform(-1.0, 1.0)
    return readout_inline(buffers[0], noise, encoding, out, buffers[2], codes)


@numba.njit(cache=True)
def _any_action(arng, n_actions: int, bar: int) -> int:
    """``QLearner._any_action``: a uniform random action, not ``bar`` (-1: none barred)."""
    if bar < 0:
        return arng.integers(0, n_actions)
    return _allowed_action(arng.integers(0, n_actions - 1), bar)


@numba.njit(cache=True)
def _best(q: np.ndarray, i: int, n_actions: int, bar: int) -> float:
    """The highest Q of row ``i`` over the actions but ``bar``."""
    best = -np.inf
    for a in range(n_actions):
        if a != bar and q[i, a] > best:
            best = q[i, a]
    return best


@numba.njit(cache=True)
def _act(state: int, epsilon: float, arng, n_actions: int, index, q: np.ndarray,
         bar: int = -1) -> tuple:  # fmt: skip
    """``QLearner.act``: explore with probability epsilon, else greedy, ties at random;
    never ``bar`` (``learner.no_undo``; -1: none barred). Returns the action and whether
    it was the exploratory choice."""
    if epsilon > 0.0 and arng.random() < epsilon:
        return _any_action(arng, n_actions, bar), True
    i = -1
    if state in index:
        i = index[state]
    if i < 0:
        return _any_action(arng, n_actions, bar), False
    best = _best(q, i, n_actions, bar)
    ties = 0
    for a in range(n_actions):
        ties += a != bar and q[i, a] == best
    pick = 0 if ties == 1 else arng.integers(0, ties)
    for a in range(n_actions):
        if a != bar and q[i, a] == best:
            if pick == 0:
                return a, False
            pick -= 1
    return 0, False


@numba.njit(cache=True)
def _nearest(out: np.ndarray, first: int, memory: tuple) -> int:
    """``Memory._nearest``: the camera that sees the target nearest (``out[first:]``, the
    cameras' readings; 0: none, else ``1 + c``)."""
    n_camera, far = memory[1], memory[2]
    best, best_d = 0, far
    for c in range(n_camera):
        d = out[first + c]
        if d < best_d:
            best, best_d = 1 + c, d
    return best


@numba.njit(cache=True)
def _sighting(seen: int, forget: int, held: int, age: int, moved: bool):
    """``Memory._sighting``: the camera that sees the target now, else the held one aged
    by a move of the robot's own."""
    if seen:
        return seen, 0
    if not moved or not held:
        return held, age
    age += 1
    if forget > 0 and age >= forget:
        return 0, 0
    return held, age


#: ``memory.bearing_code`` and ``memory.turned``, compiled from the same Python code.
_bearing_code = numba.njit(cache=True)(bearing_code)
_turned = numba.njit(cache=True)(turned)


@numba.njit(cache=True)
def _remember(key: int, action: int, out: np.ndarray, memory: tuple, mem: np.ndarray) -> int:
    """``Memory.update`` after a reading (``action`` -1: a rescue's, no move of the
    robot's own) and ``Memory.key``: the state key with the memory's codes after
    ``key``. ``mem`` = goal, end of world, action, bearing (codes), then the goal's, end
    of world's and bearing's ages and the bearing in millidegrees; ``memory`` =
    ``(n_sonar, n_camera, far, forget_after, fields on, their bits, cameras'
    millidegrees, turn millidegrees)``."""
    n_sonar, n_camera, forget, on, bits = memory[0], memory[1], memory[3], memory[4], memory[5]
    moved = action >= 0
    seen = _nearest(out, n_sonar, memory)
    mem[0], mem[4] = _sighting(seen, forget, mem[0], mem[4], moved)
    eow = _nearest(out, n_sonar + n_camera, memory)
    mem[1], mem[5] = _sighting(eow, forget, mem[1], mem[5], moved)
    if on[3]:
        if seen:
            mem[7] = memory[6][seen - 1]
        elif moved and mem[3]:
            mem[7] = _turned(mem[7], action, memory[7])
        held, mem[6] = _sighting(seen, forget, mem[3], mem[6], moved)
        mem[3] = _bearing_code(mem[7]) if held else 0
    if moved:
        mem[2] = 1 + action
    k = 0
    for field in range(4):
        if on[field]:
            key = (key << bits[k]) | mem[field]
            k += 1
    return key


@numba.njit(cache=True)
def _not_greedy(index, q: np.ndarray, state: int, action: int, bar: int = -1) -> bool:
    """``QLambda.explore``'s cut: ``action`` is below the best of ``state``'s row over the
    actions allowed (all but ``bar``; a state never visited has no row: no cut)."""
    if state not in index:
        return False
    i = index[state]
    return q[i, action] < _best(q, i, q.shape[1], bar)


@numba.njit(cache=True)
def lambda_update(
    index, table: tuple, alpha: float, gamma: float, state: int, action: int, reward: float,
    nxt: int, terminal: bool, lam: tuple, traces: tuple,
) -> None:  # fmt: skip
    """``QLambda.observe``: the TD error of Table 11's target, the replacing trace of
    ``(state, action)``, every traced entry moved by it and decayed, those below the
    cutoff dropped (in order: the Python dict's order). ``traces`` = ``(rows, actions,
    e, meta)``: the traced entries by table row, ``meta[0]`` their count, ``meta[1]`` the
    state the next step is expected to start from (-1: none)."""
    q, dirty = table[0], table[2]
    decay, cutoff = lam[1], lam[2]
    t_row, t_act, t_e, meta = traces
    i = row_of(index, table, state)
    target = td_target(index, table, gamma, reward, nxt, terminal)
    step = alpha * (target - q[i, action])
    n = meta[0]
    k = 0
    while k < n and t_row[k] != i:
        k += 1
    t_row[k] = i
    t_act[k] = action
    t_e[k] = 1.0
    if k == n:
        n += 1
    kept = 0
    for k in range(n):
        r = t_row[k]
        q[r, t_act[k]] += step * t_e[k]
        dirty[r] = True
        e = t_e[k] * decay
        if not e < cutoff:
            t_row[kept] = r
            t_act[kept] = t_act[k]
            t_e[kept] = e
            kept += 1
    meta[0] = kept
    meta[1] = -1 if terminal else nxt


@numba.njit(cache=True)
def _move(action: int, x: float, y: float, h: float, rng, world: tuple) -> tuple:
    """``World.act`` (or, with motion errors, ``KoolioEnv._act_with_errors``): the pose
    after ``action``."""
    walls, radius, distance, arc, motion = world
    on, drift, drift_sigma, slip_sigma, turn_sigma = motion
    if action == 0:
        return x, y, h
    if on == 0.0:
        if action == 1:
            return x, y, (h + arc) % _TWO_PI
        if action == 2:
            return x, y, (h - arc) % _TWO_PI
        d = distance if action == 3 else -distance
        x, y = sweep(walls, x, y, d * math.cos(h), d * math.sin(h), radius)
        return x, y, h
    if action == 1 or action == 2:
        turn = arc + turn_sigma * rng.standard_normal() if turn_sigma > 0.0 else arc
        return x, y, (h + (turn if action == 1 else -turn)) % _TWO_PI
    sign = 1.0 if action == 3 else -1.0
    turn = sign * drift
    if drift_sigma > 0.0 or slip_sigma > 0.0:
        e0 = rng.standard_normal()  # MotionErrors.move's standard_normal(2), one by one
        e1 = rng.standard_normal()
        turn += drift_sigma * e0
        distance = max(0.0, distance * (1.0 + slip_sigma * e1))
    d = sign * distance
    if d != 0.0:
        half = 0.5 * turn
        chord = d if half == 0.0 else d * (math.sin(half) / half)
        mid = h + half
        x, y = sweep(walls, x, y, chord * math.cos(mid), chord * math.sin(mid), radius)
    return x, y, (h + turn) % _TWO_PI


@numba.njit(cache=True)
def rescue_moves(x: float, y: float, h: float, rng, walls: np.ndarray, distance: float,
                 radius: float, max_backup: int) -> tuple[float, float, float]:  # fmt: skip
    """``rescue.rescue_robot``'s moves from ``(x, y, h)``: a random number of Reverse
    moves (each a :func:`~koolio_pymunk.world.swept_move.sweep` against ``walls``), then a
    random heading; the draws from ``rng``. Returns the new pose."""
    backups = rng.integers(0, max_backup + 1)
    for _ in range(backups):
        x, y = sweep(walls, x, y, -distance * math.cos(h), -distance * math.sin(h), radius)
    return x, y, rng.uniform(0.0, _TWO_PI) % _TWO_PI


@numba.njit(cache=True)
def run_steps(
    budget: int, rng, arng, epsilon: float, sense: tuple, world: tuple, task: tuple,
    learner: tuple, index, table: tuple, ints: np.ndarray, floats: np.ndarray,
    lam: tuple, traces: tuple, memory: tuple, mem: np.ndarray,
) -> int:  # fmt: skip
    """At most ``budget`` steps of one robot's episode (module doc); the episode's state
    in ``ints`` and ``floats`` (:data:`I_STATE`, :data:`F_X`, ...). Returns the outcome
    code: an :data:`EVENTS` index that ended it, :data:`WRONG_DOOR_CODE`,
    :data:`TRUNCATED_CODE`, or :data:`RUNNING` (the budget ran out first).

    ``task`` = ``(rewards by event code, zone_arrays, auto_rescue_toggle,
    max_steps_before_rescue, rescue_chance, rescue_max_backup, step cap, misread model
    on)``; ``learner`` =
    ``(alpha, gamma, n_actions, no_undo)``; ``lam`` = ``(Q(lambda) on, gamma * lambda, trace
    cutoff)`` with its ``traces`` (:func:`lambda_update`); ``memory`` (empty fields: off)
    and ``mem`` are :func:`_remember`'s; ``world`` = ``(walls, radius,
    move distance, turn arc, (motion on, drift, drift sigma, slip sigma, turn sigma))``;
    ``sense`` is built by :meth:`CompiledEpisode.sense_group`."""
    rewards, zones, auto_rescue, rescue_after, chance, max_backup, cap, misread_on = task
    alpha, gamma, n_actions, no_undo = learner
    walls, radius, distance = world[0], world[1], world[2]
    discs, disc_radius, points, starts, boxes = zones
    misread = sense[5][6]
    q = table[0]
    state, last = ints[I_STATE], ints[I_LAST]
    x, y, h = floats[F_X], floats[F_Y], floats[F_H]
    outcome = RUNNING
    lambda_on, t_meta = lam[0], traces[3]
    memory_on, out = len(memory[5]) > 0, sense[7]
    for _ in range(budget):
        if lambda_on and state != t_meta[1]:  # not where the last step ended: no traces
            t_meta[0] = 0
        bar = _barred(last) if no_undo else -1
        action, explored = _act(state, epsilon, arng, n_actions, index, q, bar)
        if lambda_on and explored and _not_greedy(index, q, state, action, bar):
            t_meta[0] = 0  # Watkins's cut
        last = action
        x, y, h = _move(action, x, y, h, rng, world)
        nxt, bump, close = sense_reading(x, y, h, rng, sense)
        if memory_on:
            nxt = _remember(nxt, action, out, memory, mem)
        if action == 0 and close:
            code = 0
        elif in_zone(x, y, discs, disc_radius, points, starts, boxes):
            code = 1
        elif bump:
            code = 2
        else:
            code = ACTION_EVENT[action]
        reward = rewards[code]
        terminated = code < N_TERMINAL
        ints[I_STEPS] += 1
        ints[I_BUMPS] += bump
        floats[F_RETURN] += reward
        ints[I_RESCUED] = 0
        steps = ints[I_STEPS]
        truncated = not terminated and cap > 0 and steps >= cap
        if lambda_on:
            lambda_update(index, table, alpha, gamma, state, action, reward, nxt, terminated,
                          lam, traces)  # fmt: skip
        else:
            td_update(index, table, alpha, gamma, state, action, reward, nxt, terminated)
        state = nxt
        due = not terminated and auto_rescue and bump and steps > rescue_after
        if due and rng.random() < chance:  # rescue.wants_rescue: a draw only when due
            x, y, h = rescue_moves(x, y, h, rng, walls, distance, radius, max_backup)
            state = sense_reading(x, y, h, rng, sense)[0]
            if memory_on:
                state = _remember(state, -1, out, memory, mem)
            ints[I_RESCUED] = 1
            ints[I_HAS_BEEN_RESCUED] = 1
            last = -1  # QLearner.relocated
        if terminated:
            outcome = WRONG_DOOR_CODE if code == 0 and misread_on and misread[0] else code
            break
        if truncated:
            outcome = TRUNCATED_CODE
            break
    ints[I_STATE] = state
    ints[I_LAST] = last
    floats[F_X] = x
    floats[F_Y] = y
    floats[F_H] = h
    return outcome


def _empty_traces(capacity: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`lambda_update`'s traces: none, room for ``capacity``, no expected state."""
    return (
        np.zeros(capacity, np.int64),
        np.zeros(capacity, np.int64),
        np.zeros(capacity, np.float64),
        np.array([0, -1], np.int64),
    )


class CompiledEpisode:
    """The compiled steps of ``env``'s episodes for a one-step Q ``agent`` (module doc)."""

    def __init__(self, env: KoolioEnv, agent: QLearner) -> None:
        self.env = env
        self.agent = agent
        self.shared: SharedTable | None = None
        self.walls = wall_array(env.world)
        cfg = env.config
        rescue = cfg.rescue
        self.rewards = reward_array(cfg.rewards)
        self.zones = zone_arrays(env.zones)
        self.rescue = (
            bool(rescue.auto_rescue_toggle),
            int(rescue.max_steps_before_rescue),
            float(rescue.rescue_chance),
            int(rescue.rescue_max_backup),
        )
        self.ints = np.zeros(6, np.int64)
        self.floats = np.zeros(4)
        self.lam = (False, 0.0, 0.0)
        if isinstance(agent, QLambda):
            self.lam = (True, float(agent.decay), float(agent.cutoff))
        self.traces = _empty_traces(0)
        self.memory = self._memory_group()
        self.mem = np.zeros(8, np.int64)

    def table(self) -> SharedTable:
        """The agent's table as arrays, rebuilt if the table changed size behind it."""
        table = self.agent.table
        sh = self.shared
        if sh is None or sh.table is not table or int(sh.count[0]) != len(table.rows):
            sh = self.shared = SharedTable(table)
        return sh

    def sense_group(self) -> tuple:
        """:func:`sense_reading`'s inputs: the suite's kernel groups and buffers, as configured
        for this episode (a domain-randomization draw may change them at every reset)."""
        k = self.env.sensors.kernel
        n_draws = self.env.sensors.realism.n_draws
        flags = np.array([int(k.real_on), int(k.gaussian), k.n_raw, n_draws])
        u = np.empty(k.n_raw + n_draws)  # the realism path's draws
        return (k.geometry, k.goal, k.plates, k.buffers, k.encoding, k.realism, k.noise, k.out,
                k.codes, flags, u)  # fmt: skip

    def world_group(self) -> tuple:
        """:func:`_move`'s inputs: walls, radius, move distance, turn arc, motion errors."""
        env = self.env
        m = env.motion
        motion = (0.0, 0.0, 0.0, 0.0, 0.0)
        if m is not None:
            motion = (1.0, m.drift, m.drift_sigma, m.slip_sigma, m.turn_sigma)
        return (self.walls, env.world.radius, float(env.move_distance), float(env.turn_arc),
                motion)  # fmt: skip

    def run(self, stop: Callable[[], bool | None] | None = None) -> str | None:
        """The current episode's steps to its end: its outcome, or None when ``stop``
        (called between chunks of :data:`CHUNK` steps) asked to stop first. The table
        holds every update made and the env the counters and the pose, whatever happens."""
        env, agent = self.env, self.agent
        sh = self.table()
        x, y, h = env.world.pose(0)
        ints, floats = self.ints, self.floats
        ints[:] = (env.state_key, env.steps, env.bumps, int(env.has_been_rescued), 0, agent.last)
        floats[:] = (x, y, h, env.episode_reward)
        cfg = env.config
        misread = bool(env.sensors.realism.misread)
        task = (self.rewards, self.zones, *self.rescue, int(cfg.episode.max_steps), misread)
        learner = (float(agent.alpha), float(agent.gamma), int(agent.n_actions), agent.no_undo)
        sense, world = self.sense_group(), self.world_group()
        outcome = RUNNING
        self._traces_in(sh)
        self._memory_in()
        try:
            while outcome == RUNNING:
                sh.reserve(CHUNK + 1)
                self._trace_room(sh)
                outcome = run_steps(CHUNK, env.np_random, agent.rng, float(agent.epsilon),
                                    sense, world, task, learner, sh.index, sh.args(), ints,
                                    floats, self.lam, self.traces, self.memory,
                                    self.mem)  # fmt: skip
                if outcome == RUNNING and stop is not None and stop():
                    break
        finally:
            sh.sync()
            self._write_back()
            self._traces_out(sh)
            self._memory_out()
        if outcome == RUNNING:
            return None
        if outcome == TRUNCATED_CODE:
            return "truncated"
        return WRONG_DOOR if outcome == WRONG_DOOR_CODE else EVENTS[outcome]

    def _memory_group(self) -> tuple:
        """:func:`_remember`'s configuration: no fields when the memory is off."""
        env = self.env
        cfg = env.memory.cfg
        on = np.array(
            [cfg.goal_camera, cfg.eow_camera, cfg.previous_action, cfg.goal_bearing], np.bool_
        )
        bits = np.array(env.layout.bits[len(env.sensors.levels) :], np.int64)
        if not env.memory.on:
            bits = bits[:0]
        sensors = env.sensors
        cameras = np.array(env.memory.camera_mdeg or [0], np.int64)
        return (int(sensors.n_sonar), int(sensors.n_camera), float(sensors.far),
                int(cfg.forget_after), on, bits, cameras, int(env.memory.turn_mdeg))  # fmt: skip

    def _memory_in(self) -> None:
        m = self.env.memory
        self.mem[:] = (m.goal, m.eow, m.action, m.bearing, m._goal_age, m._eow_age,
                       m._bearing_age, m.bearing_mdeg)  # fmt: skip

    def _memory_out(self) -> None:
        """The memory as the Python steps leave it (``env.codes`` reads it)."""
        m = self.env.memory
        (m.goal, m.eow, m.action, m.bearing, m._goal_age, m._eow_age, m._bearing_age,
         m.bearing_mdeg) = (int(v) for v in self.mem)  # fmt: skip

    def _traces_in(self, sh: SharedTable) -> None:
        """Q(lambda)'s traces and expected state from the agent (empty at an episode's
        start), by table row."""
        if not self.lam[0]:
            return
        agent: QLambda = self.agent  # type: ignore[assignment]
        self.traces = _empty_traces(sh.q.shape[0])
        rows, acts, e, meta = self.traces
        for k, (state, (action, trace)) in enumerate(agent.traces.items()):
            rows[k], acts[k], e[k] = sh.row_of(state), action, trace
        meta[0] = len(agent.traces)
        meta[1] = -1 if agent._expect is None else agent._expect

    def _trace_room(self, sh: SharedTable) -> None:
        """Room for a trace on every row the table may reach in the next chunk (with a
        small cutoff and lambda 1 a trace lives hundreds of steps)."""
        if not self.lam[0] or len(self.traces[0]) >= sh.q.shape[0]:
            return
        old = self.traces
        self.traces = _empty_traces(sh.q.shape[0])
        n = int(old[3][0])
        for new, was in zip(self.traces[:3], old[:3]):
            new[:n] = was[:n]
        self.traces[3][:] = old[3]

    def _traces_out(self, sh: SharedTable) -> None:
        """The traces back into the agent, in their order, as its own steps leave them."""
        if not self.lam[0]:
            return
        agent: QLambda = self.agent  # type: ignore[assignment]
        rows, acts, e, meta = self.traces
        n = int(meta[0])
        agent.traces = {
            int(sh.keys[r]): [int(a), float(v)]
            for r, a, v in zip(rows[:n].tolist(), acts[:n].tolist(), e[:n].tolist())
        }
        agent._expect = None if meta[1] < 0 else int(meta[1])

    def _write_back(self) -> None:
        """The env after the steps run: pose, state, counters, the last reading."""
        ints, floats = self.ints, self.floats
        x, y, h, total = (float(v) for v in floats)
        self.agent.last = int(ints[I_LAST])
        self.env.adopt(
            (x, y, h),
            int(ints[I_STATE]),
            (int(ints[I_STEPS]), int(ints[I_BUMPS]), total),
            (bool(ints[I_HAS_BEEN_RESCUED]), bool(ints[I_RESCUED])),
        )
