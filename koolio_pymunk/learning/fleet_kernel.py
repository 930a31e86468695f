"""Compiled learning loop for many robots sharing one Q-table (used by :mod:`.fleet`).

:class:`SharedTable` mirrors a :class:`~koolio_pymunk.learning.qtable.QTable` in arrays a
compiled loop can use: a typed dict from state key to row, a ``(capacity, n_actions)``
array of values and a dirty flag per row; :meth:`SharedTable.sync` writes the dirty rows
back into the ``QTable`` (before every save). The kernels:

* :func:`choose`: every active robot's epsilon-greedy action, from the per-tick draws
  (exploration, random action, tie-break), exactly as ``fleet`` describes;
* :func:`learn`: in robot index order, each robot's reward (paper §5.4.7: goal >
  end of world > bump > action), episode counters and Table 11 update; it stops at a
  robot that needs Python (an auto-rescue draw, or the end of its episode) and returns
  its index, and is called again from the next robot;
* :func:`update`: one Table 11 update; :func:`update_logged` also records it in the
  per-robot *journal* (row, action, order, value before and after), so that the writes of
  episodes still running can be taken back (``--discard-unfinished`` with many robots:
  :func:`undo_writes`);
* :func:`in_zone`: ``env.EndZones.contains`` (discs, and polygons with the boundary
  outside), the same arithmetic.

Same float64 operations in the same order as the Python code they replace (QTable.row /
peek, QLearner.update, rules.judge, EndZones.contains, geometry.locate_point);
``tests/learning/test_fleet.py`` holds each kernel to the Python code it replaces
(choose and update to the learner, learn to the rules, in_zone to ``EndZones``,
``move_all`` to the pymunk world); a whole many-robot run has no Python twin (its
seeded bytes are checked run to run).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import types
from numba.typed import Dict

from ..store.config import RewardConfig
from ..store.kernel_cache import ensure_fresh
from ..task.end_zones import EndZones
from ..task.rules import ACTION_TERMS, TERMINAL_EVENTS, TERMS
from ..world.geometry import EPS
from ..world.physics import TWO_PI, Action
from ..world.segment_query import hypot
from ..world.swept_move import sweep
from .qtable import QTable

ensure_fresh()  # numba's cache, in step with every kernel's source (see there)

#: :func:`learn`'s reasons to stop at a robot.
DONE, RESCUE_DRAW, TERMINAL, AT_CAP = 0, 1, 2, 3
#: Event codes: the index of the event in the reward rules' order (``rules.TERMS``: goal,
#: end of world, bump, then the action's own); rewards by code in :func:`reward_array`.
EVENTS = TERMS
#: Event code of each action when nothing else applies (Stop, Rotate x2, Forward, Reverse).
ACTION_EVENT = np.array([TERMS.index(ACTION_TERMS[a]) for a in Action], dtype=np.int64)
#: The codes of the rules that end an episode (goal and end of world come first).
N_TERMINAL = len(TERMINAL_EVENTS)
assert EVENTS[:N_TERMINAL] == TERMINAL_EVENTS and EVENTS[N_TERMINAL] == "bump"


def reward_array(rewards: RewardConfig) -> np.ndarray:
    """The reward of each event code (:data:`EVENTS`)."""
    return np.array([float(getattr(rewards, event)) for event in EVENTS], dtype=np.float64)


class SharedTable:
    """A QTable's rows as a typed dict + arrays (see the module doc)."""

    def __init__(self, table: QTable, reserve: int = 1024) -> None:
        self.table = table
        self.n_actions = table.layout.n_actions
        self.q_init = table.q_init
        n = len(table.rows)
        cap = max(reserve, 2 * n)
        self.q = np.empty((cap, self.n_actions))
        self.keys = np.empty(cap, np.int64)
        self.dirty = np.zeros(cap, np.bool_)
        self.count = np.array([n], np.int64)
        if n:
            self.keys[:n] = np.fromiter(table.rows, np.int64, n)
            self.q[:n] = np.array(list(table.rows.values()), dtype=np.float64)
        self.index = _build_index(self.keys, n)  # compiled: no typed-dict calls from Python

    def reserve(self, extra: int) -> None:
        """Room for ``extra`` more rows (the kernels never grow the arrays)."""
        n, cap = int(self.count[0]), self.q.shape[0]
        if n + extra <= cap:
            return
        new = max(2 * cap, n + extra)
        q = np.empty((new, self.n_actions))
        q[:n] = self.q[:n]
        keys = np.empty(new, np.int64)
        keys[:n] = self.keys[:n]
        dirty = np.zeros(new, np.bool_)
        dirty[:n] = self.dirty[:n]
        self.q, self.keys, self.dirty = q, keys, dirty

    def sync(self) -> None:
        """Write the rows changed since the last sync into the QTable."""
        rows = self.table.rows
        for i in np.flatnonzero(self.dirty[: int(self.count[0])]).tolist():
            rows[int(self.keys[i])] = self.q[i].tolist()
        self.dirty[:] = False

    def row_of(self, key: int) -> int:
        """The row of state ``key`` (-1: none)."""
        return int(find_row(self.index, key))

    def args(self) -> tuple:
        """The kernels' table group ``(q, keys, dirty, count, q_init)``; the typed dict
        :attr:`index` goes beside it (a tuple holding a typed dict costs numba's slow
        argument typing at every call)."""
        return (self.q, self.keys, self.dirty, self.count, self.q_init)


@numba.njit(cache=True)
def _build_index(keys: np.ndarray, n: int):
    """Typed dict ``keys[i] -> i`` for the first ``n`` keys."""
    index = Dict.empty(key_type=types.int64, value_type=types.int64)
    for i in range(n):
        index[keys[i]] = i
    return index


@numba.njit(cache=True)
def find_row(index, key: int) -> int:
    """The row of ``key``, -1 when missing."""
    if key in index:
        return index[key]
    return -1


@numba.njit(cache=True)
def row_of(index, table: tuple, key: int) -> int:
    """The row of ``key``, created at ``q_init`` when missing (``QTable.row``);
    ``table`` is :meth:`SharedTable.args`."""
    q, keys, dirty, count, q_init = table
    i = find_row(index, key)
    if i < 0:
        i = count[0]
        index[key] = i
        keys[i] = key
        for a in range(q.shape[1]):
            q[i, a] = q_init
        dirty[i] = True
        count[0] += 1
    return i


@numba.njit(cache=True)
def td_target(index, table: tuple, gamma: float, reward: float, nxt: int, terminal: bool) -> float:
    """``qlearning.td_target``: the reward alone after a terminal step, else ``reward +
    gamma * max`` of ``nxt``'s row (``q_init`` for a state never visited)."""
    if terminal:
        return reward
    j = find_row(index, nxt)
    return reward + gamma * (table[0][j].max() if j >= 0 else table[4])


@numba.njit(cache=True)
def update(index, table: tuple, alpha: float, gamma: float, state: int, action: int, reward: float,
           nxt: int, terminal: bool) -> None:  # fmt: skip
    """``QLearner.update``: Table 11, no bootstrap from a terminal step (``table``:
    :meth:`SharedTable.args`)."""
    q, dirty = table[0], table[2]
    i = row_of(index, table, state)
    target = td_target(index, table, gamma, reward, nxt, terminal)
    q[i, action] += alpha * (target - q[i, action])
    dirty[i] = True


def new_journal(robots: int, capacity: int) -> tuple[np.ndarray, ...]:
    """Empty journal arrays for :func:`update_logged` (``capacity`` 0: no journal):
    ``jint[r, k]`` = row, action, order, created; ``jf[r, k]`` = before, after; ``jn[r]``
    entries of robot ``r``; ``seq[0]`` the next order number."""
    return (
        np.zeros((robots, capacity, 4), np.int64),
        np.zeros((robots, capacity, 2), np.float64),
        np.zeros(robots, np.int64),
        np.zeros(1, np.int64),
    )


@numba.njit(cache=True)
def update_logged(
    index, table: tuple, alpha: float, gamma: float, state: int, action: int, reward: float,
    nxt: int, terminal: bool, r: int, journal: tuple,
) -> None:  # fmt: skip
    """:func:`update`, recorded in robot ``r``'s journal (:func:`new_journal`) when it has
    room (``jn[r]`` counts every update, so an overflow shows)."""
    jint, jf, jn, seq = journal
    if jint.shape[1] == 0:
        update(index, table, alpha, gamma, state, action, reward, nxt, terminal)
        return
    q, count = table[0], table[3]
    before = count[0]
    i = row_of(index, table, state)
    old = q[i, action]
    update(index, table, alpha, gamma, state, action, reward, nxt, terminal)
    k = jn[r]
    if k < jint.shape[1]:
        jint[r, k, 0] = i
        jint[r, k, 1] = action
        jint[r, k, 2] = seq[0]
        jint[r, k, 3] = 1 if count[0] > before else 0
        jf[r, k, 0] = old
        jf[r, k, 1] = q[i, action]
    jn[r] = k + 1
    seq[0] += 1


def undo_writes(shared: SharedTable, journal: tuple, robots: list[int]) -> list[int]:
    """Take back the journaled writes of ``robots`` (their episodes are discarded), newest
    first: an entry still holding the value the robot wrote gets its value from before;
    one that another robot wrote over since keeps that robot's value. Returns the keys of
    rows those robots created that are back at ``q_init`` in every action (the caller
    drops them from the table: they were never visited by a kept episode)."""
    jint, jf, jn, _ = journal
    entries = sorted(
        ((int(jint[r, k, 2]), r, k) for r in robots for k in range(int(jn[r]))), reverse=True
    )
    created = []
    q = shared.q
    for _, r, k in entries:
        i, a = int(jint[r, k, 0]), int(jint[r, k, 1])
        if q[i, a] == jf[r, k, 1]:
            q[i, a] = jf[r, k, 0]
            shared.dirty[i] = True
        if jint[r, k, 3]:
            created.append(i)
    return [int(shared.keys[i]) for i in created if bool(np.all(q[i] == shared.q_init))]


@numba.njit(cache=True)
def choose(
    index, q, state: np.ndarray, active: np.ndarray, epsilon: np.ndarray,
    explore: np.ndarray, random_action: np.ndarray, tie: np.ndarray, actions: np.ndarray,
) -> None:  # fmt: skip
    """Epsilon-greedy action of every active robot (inactive robots: Stop)."""
    n_actions = q.shape[1]
    for r in range(state.shape[0]):
        if not active[r]:
            actions[r] = 0
            continue
        if explore[r] < epsilon[r]:
            actions[r] = random_action[r]
            continue
        i = find_row(index, state[r])
        if i < 0:  # an unvisited state: a random action too
            actions[r] = random_action[r]
            continue
        best = q[i].max()
        count = 0
        for a in range(n_actions):
            count += q[i, a] == best
        pick = 0 if count == 1 else int(tie[r] * count)
        for a in range(n_actions):
            if q[i, a] == best:
                if pick == 0:
                    actions[r] = a
                    break
                pick -= 1


@numba.njit(cache=True)
def move_all(
    actions: np.ndarray, copy_xy: np.ndarray, headings: np.ndarray, walls: np.ndarray,
    offsets: np.ndarray, motion: tuple, xy: np.ndarray,
) -> None:  # fmt: skip
    """``World.act`` for every robot, compiled: rotations turn ``headings``, Forward and
    Reverse are :func:`~koolio_pymunk.world.swept_move.sweep` of robot ``r`` from
    ``copy_xy[r]`` (its body's position in its copy of the arena) against ``walls[r]``
    (its copy's walls, ``wall_array(world, r)``), as the pymunk world computes them;
    ``xy[r]`` = the position in the arena's coordinates (``World.pose``).
    ``motion`` = ``(move distance, turn arc, radius)``."""
    distance, arc, radius = motion
    for r in range(actions.shape[0]):
        a = actions[r]
        if a == 1:
            headings[r] = (headings[r] + arc) % TWO_PI
        elif a == 2:
            headings[r] = (headings[r] - arc) % TWO_PI
        elif a == 3 or a == 4:
            d = distance if a == 3 else -distance
            h = headings[r]
            x, y = sweep(walls[r], copy_xy[r, 0], copy_xy[r, 1], d * math.cos(h), d * math.sin(h),
                         radius)  # fmt: skip
            copy_xy[r, 0] = x
            copy_xy[r, 1] = y
        xy[r, 0] = copy_xy[r, 0] - offsets[r]
        xy[r, 1] = copy_xy[r, 1]


@numba.njit(cache=True)
def _on_segment(px: float, py: float, ax: float, ay: float, bx: float, by: float) -> bool:
    """``geometry.point_on_segment``: distance to the closed segment at most EPS."""
    dx, dy = bx - ax, by - ay
    len2 = dx * dx + dy * dy
    if len2 == 0.0:
        return hypot(px - ax, py - ay) <= EPS
    t = ((px - ax) * dx + (py - ay) * dy) / len2
    t = max(0.0, min(1.0, t))
    return hypot(px - (ax + t * dx), py - (ay + t * dy)) <= EPS


@numba.njit(cache=True)
def _inside(px: float, py: float, poly: np.ndarray) -> bool:
    """``geometry.point_in_polygon``: strictly inside (the boundary counts as outside)."""
    n = poly.shape[0]
    inside = False
    for i in range(n):
        ax, ay = poly[i, 0], poly[i, 1]
        bx, by = poly[(i + 1) % n, 0], poly[(i + 1) % n, 1]
        if _on_segment(px, py, ax, ay, bx, by):
            return False
        if (ay > py) != (by > py):
            x_at = ax + (py - ay) * (bx - ax) / (by - ay)
            if x_at > px:
                inside = not inside
    return inside


@numba.njit(cache=True)
def in_zone(
    x: float, y: float, discs: np.ndarray, disc_radius: float,
    points: np.ndarray, starts: np.ndarray, boxes: np.ndarray,
) -> bool:  # fmt: skip
    """``EndZones.contains``: polygon ``k`` is ``points[starts[k]:starts[k + 1]]``."""
    for k in range(discs.shape[0]):
        if hypot(x - discs[k, 0], y - discs[k, 1]) <= disc_radius:
            return True
    for k in range(boxes.shape[0]):
        b = boxes[k]
        inside_box = b[0] <= x <= b[2] and b[1] <= y <= b[3]
        if inside_box and _inside(x, y, points[starts[k] : starts[k + 1]]):
            return True
    return False


def zone_arrays(zones: EndZones) -> tuple:
    """:func:`in_zone`'s arguments after ``x, y`` for ``zones``."""
    discs = np.array(zones.discs, dtype=np.float64).reshape(-1, 2)
    polys = [np.array(p, dtype=np.float64).reshape(-1, 2) for p in zones.polygons]
    points = np.concatenate(polys) if polys else np.empty((0, 2))
    starts = np.cumsum([0] + [len(p) for p in polys]).astype(np.int64)
    boxes = np.array([b[:4] for b in zones.boxes], dtype=np.float64).reshape(-1, 4)
    return discs, float(zones.disc_radius), points, starts, boxes


@numba.njit(cache=True)
def learn(start: int, tick: tuple, rules: tuple, counters: tuple, journal: tuple, index,
          table: tuple) -> tuple[int, int]:  # fmt: skip
    """Judge and learn the step of robots ``start, start + 1, ...`` (module doc).

    ``tick`` = ``(active, actions, state, nxt, bumps, closes, xy)``: per robot, the tick's
    action, state before and after, Bump and goal-close flags and position; ``rules`` =
    ``(reward, alpha, gamma, zones, rescue_after, cap)``: ``reward`` holds the reward of
    each event code, ``zones`` is :func:`zone_arrays`, ``rescue_after`` is
    ``max_steps_before_rescue`` (-1: auto rescue off), ``cap`` the step cap (0: none);
    ``counters`` = ``(steps, n_bumps, total, event)`` per robot; ``journal`` is
    :func:`new_journal`'s (:func:`update_logged`), ``index`` and ``table`` the shared
    table's (:meth:`SharedTable.args`).
    Returns ``(robot, reason)``: ``RESCUE_DRAW`` before the robot's update (Python
    updates, then draws and maybe rescues), ``TERMINAL`` / ``AT_CAP`` after it;
    ``(n, DONE)``.
    """
    active, actions, state, nxt, bumps, closes, xy = tick
    reward, alpha, gamma, zones, rescue_after, cap = rules
    steps, n_bumps, total, event = counters
    discs, disc_radius, points, starts, boxes = zones
    for r in range(start, state.shape[0]):
        if not active[r]:
            continue
        a = actions[r]
        if a == 0 and closes[r]:  # the order of rules.judge
            code = 0
        elif in_zone(xy[r, 0], xy[r, 1], discs, disc_radius, points, starts, boxes):
            code = 1
        elif bumps[r]:
            code = 2
        else:
            code = ACTION_EVENT[a]
        event[r] = code
        terminal = code < N_TERMINAL
        steps[r] += 1
        n_bumps[r] += bumps[r]
        total[r] += reward[code]
        if not terminal and rescue_after >= 0 and bumps[r] and steps[r] > rescue_after:
            return r, RESCUE_DRAW
        update_logged(index, table, alpha, gamma, state[r], a, reward[code], nxt[r], terminal, r,
                      journal)  # fmt: skip
        state[r] = nxt[r]
        if terminal:
            return r, TERMINAL
        if cap > 0 and steps[r] >= cap:
            return r, AT_CAP
    return state.shape[0], DONE
