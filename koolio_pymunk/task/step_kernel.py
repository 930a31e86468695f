"""One robot's step, compiled: the twin of ``KoolioEnv.simulate`` and ``rescue_check``.

(:meth:`~koolio_pymunk.task.env.KoolioEnv.simulate`,
:meth:`~koolio_pymunk.task.env.KoolioEnv.rescue_check`.)

The compiled step engine (:mod:`koolio_pymunk.learning.engine`) and the vector env
(:mod:`koolio_pymunk.task.vector_env`) step robots without Python between their steps;
this module is what a step is for them, robot ``r`` of a batch
(:class:`~koolio_pymunk.task.batch.EnvBatch` holds the arrays):

* :func:`simulate`: the action's move (:func:`koolio_pymunk.world.swept_move.act`, a real
  drive's errors included), the reading
  (:func:`koolio_pymunk.sensing.reading_kernel.sense_reading`, realism included), the
  memory (:func:`koolio_pymunk.sensing.memory_kernel.remember`), the judgement
  (``rules.judge``'s priority: goal > end of world > bump > the action's own reward, and a
  misread plate's ``wrong_door``), the counters and the step cap;
* :func:`rescue_check`: auto rescue after the step's update (paper §5.4.8): the draw when
  due, ``rescue_robot``'s reverses and spin (:func:`rescue_moves`), a new reading.

Every draw is the one the Python step makes, from the same generator, in the same order;
``tests/learning/test_engine.py`` and ``tools/agreement.py --episodes N`` hold the compiled
steps to the Python ones bit for bit, in every world.

**One robot's state** is a row of ``ints`` (:data:`I_STATE`, ...) and of ``floats``
(:data:`F_X`, ...), its memory a row of ``mem``
(:data:`~koolio_pymunk.sensing.memory_kernel.FIELDS`), its drive's errors a row of
``motion``. The arguments every robot shares: ``world`` = ``(walls, radius, move distance,
turn arc)``, ``task`` (:func:`task_group`), ``memory``
(:func:`~koolio_pymunk.sensing.memory_kernel.memory_group`).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ..sensing.inline_twins import inline_twin
from ..sensing.memory_kernel import remember, remember_inline
from ..sensing.reading_kernel import (
    robot_bump,
    robot_group,
    robot_others,
    sense_reading,
    sense_reading_among,
)
from ..store.config import Config, RewardConfig
from ..store.kernel_cache import ensure_fresh
from ..world.geometry import EPS
from ..world.physics import TWO_PI, Action
from ..world.segment_query import hypot
from ..world.swept_move import act, act_among, sweep_among, sweep_in
from .end_zones import EndZones
from .rules import ACTION_TERMS, TERMINAL_EVENTS, TERMS

ensure_fresh()  # numba's cache, in step with every kernel's source (see there)

#: Event codes: the index of the event in the reward rules' order (``rules.TERMS``: goal,
#: end of world, bump, then the action's own); rewards by code in :func:`reward_array`.
EVENTS = TERMS
#: Event code of each action when nothing else applies (Stop, Rotate x2, Forward, Reverse).
ACTION_EVENT = np.array([TERMS.index(ACTION_TERMS[a]) for a in Action], dtype=np.int64)
#: The codes of the rules that end an episode (goal and end of world come first).
N_TERMINAL = len(TERMINAL_EVENTS)
assert EVENTS[:N_TERMINAL] == TERMINAL_EVENTS and EVENTS[N_TERMINAL] == "bump"
#: Event code of a Bump read from another robot (robots sharing an arena); it comes after
#: the end of world and before the wall's Bump in the rules' order.
ROBOT_BUMP = TERMS.index("robot_bump")
#: Outcome codes beyond :data:`EVENTS`' indices: a Stop at a misread plate (it ends the
#: episode with the goal's reward), the step cap; and an episode still running.
WRONG_DOOR_CODE, TRUNCATED_CODE, RUNNING = len(EVENTS), len(EVENTS) + 1, -1

#: ``ints`` of a robot: state key, steps, bumps, has been rescued, rescued this step, the
#: rescue check due (the step bumped and did not end the episode), misread model on.
I_STATE, I_STEPS, I_BUMPS, I_HAS_BEEN_RESCUED, I_RESCUED, I_CHECK_RESCUE, I_MISREAD = range(7)
N_INTS = 7
#: ``floats`` of a robot: x, y, heading, the episode's return.
F_X, F_Y, F_H, F_RETURN = range(4)
N_FLOATS = 4


def reward_array(rewards: RewardConfig) -> np.ndarray:
    """The reward of each event code (:data:`EVENTS`)."""
    return np.array([rewards.value(event) for event in EVENTS], dtype=np.float64)


def zone_arrays(zones: EndZones) -> tuple:
    """:func:`in_zone`'s arguments after ``x, y`` for ``zones``."""
    discs = np.array(zones.discs, dtype=np.float64).reshape(-1, 2)
    polys = [np.array(p, dtype=np.float64).reshape(-1, 2) for p in zones.polygons]
    points = np.concatenate(polys) if polys else np.empty((0, 2))
    starts = np.cumsum([0] + [len(p) for p in polys]).astype(np.int64)
    boxes = np.array([b[:4] for b in zones.boxes], dtype=np.float64).reshape(-1, 4)
    return discs, float(zones.disc_radius), points, starts, boxes


def task_group(cfg: Config, zones: EndZones) -> tuple:
    """The task's rules for :func:`simulate` and :func:`rescue_check`: ``(rewards by event
    code, zone_arrays, auto rescue on, max_steps_before_rescue, rescue_chance,
    rescue_max_backup, step cap)``."""
    rescue = cfg.rescue
    return (reward_array(cfg.rewards), zone_arrays(zones), bool(rescue.auto_rescue_toggle),
            int(rescue.max_steps_before_rescue), float(rescue.rescue_chance),
            int(rescue.rescue_max_backup), int(cfg.episode.max_steps))  # fmt: skip


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


@numba.njit(cache=True)
def judge_code(
    action: int, close: bool, x: float, y: float, bump: bool, zones: tuple, robot_hit: bool
) -> int:
    """``rules.judge``'s event code (:data:`EVENTS`) of a step: goal (Stop with the goal
    close) > end of world > a Bump read from a robot (``robot_hit``) > bump > the
    action's own."""
    discs, disc_radius, points, starts, boxes = zones
    if action == 0 and close:
        return 0
    if in_zone(x, y, discs, disc_radius, points, starts, boxes):
        return 1
    if robot_hit:
        return ROBOT_BUMP
    if bump:
        return 2
    return ACTION_EVENT[action]


@numba.njit(cache=True)
def rescue_moves(
    x: float, y: float, h: float, rng, world: tuple, max_backup: int, others: tuple
) -> tuple[float, float, float]:
    """``rescue.rescue_robot``'s moves from ``(x, y, h)``: a random number of Reverse
    moves (each a :func:`~koolio_pymunk.world.swept_move.sweep` against the walls of
    ``world``, or in a shared arena :func:`~koolio_pymunk.world.swept_move.sweep_among` the
    other robots of ``others``), then a random heading; the draws from ``rng``. Returns
    the new pose."""
    walls, radius, distance = world[0], world[1], world[2]
    backups = rng.integers(0, max_backup + 1)
    for _ in range(backups):
        dx, dy = -distance * math.cos(h), -distance * math.sin(h)
        if others is None:
            x, y = sweep_in(walls, x, y, dx, dy, radius, world[4])
        else:
            x, y = sweep_among(walls, others[0], others[1], others[2], x, y, dx, dy, radius)
    return x, y, rng.uniform(0.0, TWO_PI) % TWO_PI


@numba.njit(cache=True)
def simulate(
    r: int, action: int, rng, sense: tuple, world: tuple, motion: np.ndarray, task: tuple,
    memory: tuple, ints: np.ndarray, floats: np.ndarray, mem: np.ndarray, others: tuple,
) -> tuple:  # fmt: skip
    """``KoolioEnv.simulate(action)`` for robot ``r`` (module doc), drawing from ``rng``
    (the env's generator) with ``sense`` (the robot's reading group). ``others`` is None
    for a robot alone, or in a shared arena the robot's group of
    :func:`~koolio_pymunk.sensing.reading_kernel.robot_others`: the move and the reading
    then meet the other robots, the robot's new centre is written into it and a Bump read
    from a robot is :data:`ROBOT_BUMP`. (numba compiles the two cases apart: None's
    branch is pruned, so a robot alone pays nothing for the shared arena.) Returns ``(next
    state, outcome code, reward, terminated, truncated)``: the code is an :data:`EVENTS`
    index, or :data:`WRONG_DOOR_CODE` for a Stop at a misread plate."""
    rewards, zones, cap = task[0], task[1], task[6]
    if others is None:
        x, y, h = act(action, floats[r, F_X], floats[r, F_Y], floats[r, F_H], rng, world,
                      motion[r])  # fmt: skip
        nxt, bump, close = sense_reading(x, y, h, rng, sense)
        hit = False
    else:
        robots = others[0]
        x, y, h = act_among(action, floats[r, F_X], floats[r, F_Y], floats[r, F_H], rng, world,
                            motion[r], robots, others[1], r)  # fmt: skip
        robots[r, 0], robots[r, 1] = x, y
        nxt, bump, close = sense_reading_among(x, y, h, rng, sense, others)
        hit = bump and robot_bump(sense, others)
    if len(memory[5]) > 0:
        nxt = remember(nxt, action, sense[7], memory, mem[r])
    code = judge_code(action, close, x, y, bump, zones, hit)
    reward = rewards[code]
    terminated = code < N_TERMINAL
    if code == 0 and ints[r, I_MISREAD] and sense[5][6][0]:
        code = WRONG_DOOR_CODE  # the goal's reward, the episode ends: KoolioEnv's WRONG_DOOR
    floats[r, F_X], floats[r, F_Y], floats[r, F_H] = x, y, h
    floats[r, F_RETURN] += reward
    ints[r, I_STATE] = nxt
    ints[r, I_STEPS] += 1
    ints[r, I_BUMPS] += bump
    ints[r, I_RESCUED] = 0
    ints[r, I_CHECK_RESCUE] = not terminated and bump
    truncated = not terminated and cap > 0 and ints[r, I_STEPS] >= cap
    return nxt, code, reward, terminated, truncated


@numba.njit(cache=True)
def rescue_check(
    r: int, rng, sense: tuple, world: tuple, task: tuple, memory: tuple, ints: np.ndarray,
    floats: np.ndarray, mem: np.ndarray, others: tuple,
) -> bool:  # fmt: skip
    """``KoolioEnv.rescue_check()`` for robot ``r``: once per :func:`simulate`, the auto
    rescue when due (``rescue.wants_rescue``: a draw only then), its moves and a new
    reading (the memory records it without aging); in a shared arena (``others`` not None,
    as :func:`simulate`'s) it backs out of the other robots too. Returns whether it rescued."""
    due = ints[r, I_CHECK_RESCUE] == 1
    ints[r, I_CHECK_RESCUE] = 0
    auto, after, chance, max_backup = task[2], task[3], task[4], task[5]
    if not (due and auto and ints[r, I_STEPS] > after):
        return False
    if not rng.random() < chance:
        return False
    x, y, h = rescue_moves(floats[r, F_X], floats[r, F_Y], floats[r, F_H], rng, world,
                           max_backup, others)  # fmt: skip
    floats[r, F_X], floats[r, F_Y], floats[r, F_H] = x, y, h
    if others is None:
        state = sense_reading(x, y, h, rng, sense)[0]
    else:
        robots = others[0]
        robots[r, 0], robots[r, 1] = x, y
        state = sense_reading_among(x, y, h, rng, sense, others)[0]
    if len(memory[5]) > 0:
        state = remember(state, -1, sense[7], memory, mem[r])
    ints[r, I_STATE] = state
    ints[r, I_RESCUED] = 1
    ints[r, I_HAS_BEEN_RESCUED] = 1
    return True


#: :func:`simulate` and :func:`rescue_check` with the small calls that pass arrays compiled
#: into them (:func:`~koolio_pymunk.sensing.inline_twins.inline_twin`), for the compiled
#: loops that step robots (each array passed across a call costs two atomic reference
#: counts). The reading stays one call: inlined twice (a step's, a rescue's), its code
#: would double the compile (minutes instead of seconds) for a few per cent.
_judge_code_inline = inline_twin(judge_code, in_zone=inline_twin(in_zone))
simulate_inline = inline_twin(
    simulate,
    act=inline_twin(act),
    remember=remember_inline,
    judge_code=_judge_code_inline,
)
rescue_check_inline = inline_twin(
    rescue_check,
    rescue_moves=inline_twin(rescue_moves),
    remember=remember_inline,
)


@numba.njit(cache=True, _nrt=False)
def simulate_robot(
    r: int, action: int, rng, readings: tuple, world: tuple, motion: np.ndarray, task: tuple,
    memory: tuple, ints: np.ndarray, floats: np.ndarray, mem: np.ndarray,
) -> tuple:  # fmt: skip
    """:func:`simulate` of robot ``r`` of a batch, alone in its arena, its reading group
    made here from ``readings`` (``(shared, rows)`` of
    :class:`~koolio_pymunk.sensing.reading_kernel.ReadingArrays`). Compiled without
    reference counting (nothing here allocates, keeps or returns an array, and the
    caller holds every array for the call): a step passes some fifty arrays through its
    functions, and numba's atomic reference counts on them cost more than the step's
    geometry."""
    sense = robot_group(r, readings[0], readings[1])
    return simulate_inline(r, action, rng, sense, world, motion, task, memory, ints, floats,
                           mem, None)  # fmt: skip


@numba.njit(cache=True)
def rescue_check_robot(
    r: int, rng, readings: tuple, world: tuple, task: tuple, memory: tuple, ints: np.ndarray,
    floats: np.ndarray, mem: np.ndarray, among: tuple,
) -> bool:  # fmt: skip
    """:func:`rescue_check` of robot ``r`` of a batch, its reading group (and in a shared
    arena, ``among`` not None, its ``others``) made here from ``readings``, as
    :func:`simulate_robot` makes it. Its callers call it only when ``ints[r,
    I_CHECK_RESCUE]`` says a rescue may be due (:func:`rescue_check`'s own first test):
    the groups are made, and the call paid, on those steps only."""
    sense = robot_group(r, readings[0], readings[1])
    if among is None:
        return rescue_check_inline(r, rng, sense, world, task, memory, ints, floats, mem, None)
    return rescue_check_inline(r, rng, sense, world, task, memory, ints, floats, mem,
                               robot_others(r, among[0], among[1], among[2]))  # fmt: skip
