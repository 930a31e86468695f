"""The fleet's ticks in one compiled call (``koolio-pm train --robots N``, :mod:`.fleet`).

:func:`run_ticks` runs whole ticks of :mod:`.fleet` (its module doc says what a tick is)
without Python between them: the tick's draws from the run generator, every robot's
choice (:func:`~.fleet_kernel.choose`), move (:func:`~.fleet_kernel.move_all`) and reading
(:func:`~koolio_pymunk.sensing.ray_kernel.sense_batch`,
:func:`~koolio_pymunk.sensing.encoding_kernel.readout_batch`), then in robot order the
judge and Table 11 update (:func:`~.fleet_kernel.learn`), a rescue (its update,
:func:`~.episode_kernel.rescue_moves` in the robot's copy of the arena and a new reading,
:func:`~.episode_kernel.sense_reading`), the end of an episode and the start of the next.
These are the pieces the one-robot compiled episode and the fleet share; nothing here
computes a step a second way.

**What Python keeps.** Everything that needs a file, a ``SeedSequence`` or the clock:

* *starts*: Python prepares the next episode starts ahead, one slot each (the
  episode's generator, its goal, start heading and epsilon, drawn as :mod:`.fleet` draws
  them); a start takes the next prepared slot, in start order, and draws its first
  reading's noise from that generator. The generators are objects made once (a robot's,
  a slot's), swapped at a start between the robot and the slot, whose state Python sets
  to the fresh generator's of the episode it prepares (a numba generator is one unboxing
  of the Python object: cheap to reuse, costly to make);
* *finished episodes*: recorded in ``records`` (robot, start, outcome, steps, bumps,
  rescued, return); Python logs them and saves the table. The call stops right after the
  finish that makes ``records`` reach ``ctl[C_STOP_AT]`` (the next save), in the middle of
  a tick if need be, and the next call goes on from the next robot;
* *room*: before a tick, the call stops when the shared table or the journal might
  overflow in it (:data:`NEED_ROOM`).

A robot whose episode ends starts its next one at the end of the tick (the robots after
it in that tick never read its row of state), in the order the episodes ended.
"""

from __future__ import annotations

import numba
import numpy as np
from numba.typed import List

from ..sensing.encoding_kernel import readout_batch
from ..sensing.ray_kernel import sense_batch
from ..store.kernel_cache import ensure_fresh
from .episode_kernel import TRUNCATED_CODE, rescue_moves, sense_reading
from .fleet_kernel import (
    AT_CAP,
    DONE,
    RESCUE_DRAW,
    TERMINAL,
    choose,
    learn,
    move_all,
    update_logged,
)

ensure_fresh()  # numba's cache, in step with every kernel's source (see there)

#: :func:`run_ticks`'s reasons to return: ``ctl[C_TICKS]`` reached the call's tick budget
#: (between two ticks); ``records`` reached ``ctl[C_STOP_AT]``; a start needs a slot
#: Python has not prepared yet (end of a tick); the table or journal needs room.
TICKS_DONE, RECORDS_DUE, NEED_STARTS, NEED_ROOM = 0, 1, 2, 3
#: ``ctl``: the next robot to judge in the tick under way (N: none under way), ticks run
#: in this series of calls, starts made, starts prepared, starts allowed (the budget),
#: finished episodes recorded, where to stop recording, the robots waiting for a start
#: (``pending[head:tail]``).
C_CURSOR, C_TICKS, C_STARTED, C_PREPARED, C_BUDGET, C_RECORDS, C_STOP_AT = range(7)
C_HEAD, C_TAIL = 7, 8
N_CTL = 9
#: ``records`` columns (integers): robot, start number (0, 1, ... in this run), outcome
#: (an :data:`~.fleet_kernel.EVENTS` index or ``TRUNCATED_CODE``), steps, bumps, rescued.
R_ROBOT, R_START, R_OUTCOME, R_STEPS, R_BUMPS, R_RESCUED = range(6)


@numba.njit(cache=True)
def generator_list(rng, n: int):
    """A typed list of ``n`` references to ``rng`` (:func:`set_generator` sets each)."""
    out = List()
    for _ in range(n):
        out.append(rng)
    return out


@numba.njit(cache=True)
def set_generator(slots, i: int, rng) -> None:
    """``slots[i] = rng`` (compiled: the list is numba's)."""
    slots[i] = rng


@numba.njit(cache=True)
def _reading(r: int, rng, sensing: tuple, xy: np.ndarray, headings: np.ndarray) -> int:
    """Robot ``r``'s state key read alone (after a start or a rescue), noise from ``rng``."""
    (geometry, encoding, goals, raw, rays, eow_k, trig, out, codes, _, _, plates, ray_cos, decoy,
     realism, noise, flags) = sensing  # fmt: skip
    # The fleet runs the ideal world only: the realism draws' buffer (the last) is unused.
    sense = (geometry, goals[r], plates, (raw[r], rays[r], eow_k[r], trig[r], ray_cos, decoy),
             encoding, realism, noise, out[r], codes[r], flags, noise)  # fmt: skip
    return sense_reading(xy[r, 0], xy[r, 1], headings[r], rng, sense)[0]


@numba.njit(cache=True)
def _new_tick(trng, sensing: tuple, motion: tuple, robots: tuple, index, q: np.ndarray) -> None:
    """The tick's draws (exploration, random actions, tie breaks, sensor noise), every
    robot's action, move and reading."""
    geometry, encoding, goals, raw, rays, eow_k, trig, out, codes, keys, flags = sensing[:11]
    n_raw, gaussian = raw.shape[1], sensing[16][1] == 1
    copy_xy, headings, walls, offsets, params, xy = motion
    state, active, epsilon, actions = robots[0], robots[1], robots[2], robots[3]
    n = state.shape[0]
    explore = trng.random(n)
    random_action = trng.integers(0, q.shape[1], n)
    tie = trng.random(n)
    draws = trng.standard_normal(n * n_raw) if gaussian else trng.uniform(-1.0, 1.0, n * n_raw)
    choose(index, q, state, active, epsilon, explore, random_action, tie, actions)
    move_all(actions, copy_xy, headings, walls, offsets, params, xy)
    sense_batch(xy[:, 0], xy[:, 1], headings, geometry, goals, raw, rays, eow_k, trig)
    readout_batch(raw, draws.reshape(n, n_raw), encoding, out, eow_k, codes, keys, flags)


@numba.njit(cache=True)
def _rescue_step(r: int, gens, sensing: tuple, motion: tuple, robots: tuple, counters: tuple,
                 rules: tuple, rescue: tuple, journal: tuple, index,
                 table: tuple) -> bool:  # fmt: skip
    """Robot ``r`` bumped past ``max_steps_before_rescue``: its update from the state the
    action led to, the rescue draw, maybe a rescue (``rescue_robot`` in its copy of the
    arena: the body back at ``pose + offset`` as ``World.place`` puts it) and a new
    reading. Returns whether the step cap ends its episode."""
    keys = sensing[9]
    copy_xy, headings, walls, offsets, params, xy = motion
    state, actions, rescued = robots[0], robots[3], robots[4]
    steps, event = counters[0], counters[3]
    reward, alpha, gamma, cap = rules[0], rules[1], rules[2], rules[5]
    chance, max_backup = rescue
    update_logged(index, table, alpha, gamma, state[r], actions[r], reward[event[r]], keys[r],
                  False, r, journal)  # fmt: skip
    nxt = keys[r]
    rng = gens[r]
    if rng.random() < chance:
        cx, cy, h = rescue_moves(copy_xy[r, 0], copy_xy[r, 1], headings[r], rng, walls[r],
                                 params[0], params[2], max_backup)  # fmt: skip
        cx = (cx - offsets[r]) + offsets[r]  # World.pose, then World.place
        copy_xy[r, 0], copy_xy[r, 1], headings[r] = cx, cy, h
        xy[r, 0], xy[r, 1] = cx - offsets[r], cy
        nxt = _reading(r, rng, sensing, xy, headings)
        rescued[r] = True
    state[r] = nxt
    return cap > 0 and steps[r] >= cap


@numba.njit(cache=True)
def _finish(r: int, outcome: int, ctl: np.ndarray, pending: np.ndarray, robots: tuple,
            counters: tuple, records: tuple) -> None:  # fmt: skip
    """Record robot ``r``'s finished episode; the robot waits for its next start."""
    ints, totals = records
    steps, bumps, total = counters[0], counters[1], counters[2]
    k = ctl[C_RECORDS]
    ints[k, R_ROBOT] = r
    ints[k, R_START] = robots[5][r]
    ints[k, R_OUTCOME] = outcome
    ints[k, R_STEPS] = steps[r]
    ints[k, R_BUMPS] = bumps[r]
    ints[k, R_RESCUED] = robots[4][r]
    totals[k] = total[r]
    ctl[C_RECORDS] = k + 1
    robots[1][r] = False
    pending[ctl[C_TAIL]] = r
    ctl[C_TAIL] += 1


@numba.njit(cache=True)
def _judge(ctl, pending, gens, sensing, motion, robots, counters, rules, rescue, records,
           journal, index, table) -> bool:  # fmt: skip
    """The tick's judge-learn part from robot ``ctl[C_CURSOR]`` on, in robot order; True
    when ``records`` reached ``ctl[C_STOP_AT]`` (``ctl[C_CURSOR]`` the next robot)."""
    keys, flags = sensing[9], sensing[10]
    xy = motion[5]
    state, active, actions = robots[0], robots[1], robots[3]
    event = counters[3]
    tick = (active, actions, state, keys, flags[:, 0], flags[:, 1], xy)
    n = state.shape[0]
    r = ctl[C_CURSOR]
    while r < n:
        r, why = learn(r, tick, rules, counters, journal, index, table)
        if why == DONE:
            break
        outcome = -1
        if why == RESCUE_DRAW:
            if _rescue_step(r, gens, sensing, motion, robots, counters, rules, rescue, journal,
                            index, table):  # fmt: skip
                outcome = TRUNCATED_CODE
        elif why == TERMINAL:
            outcome = event[r]
        elif why == AT_CAP:
            outcome = TRUNCATED_CODE
        r += 1
        if outcome >= 0:
            _finish(r - 1, outcome, ctl, pending, robots, counters, records)
            if ctl[C_RECORDS] >= ctl[C_STOP_AT]:
                ctl[C_CURSOR] = r
                return True
    ctl[C_CURSOR] = n
    return False


@numba.njit(cache=True)
def _start_pending(ctl, pending, gens, pool, starts, sensing, motion, robots, counters,
                   journal) -> bool:  # fmt: skip
    """Start the waiting robots' next episodes in order (or idle them once the budget is
    started); False when one needs a slot Python has not prepared yet."""
    goal_at, heading, eps, start_at = starts
    goals = sensing[2]
    copy_xy, headings, offsets, xy = motion[0], motion[1], motion[3], motion[5]
    state, active, epsilon, _, rescued, start_of = robots
    steps, bumps, total = counters[0], counters[1], counters[2]
    jn = journal[2]
    while ctl[C_HEAD] < ctl[C_TAIL]:
        r = pending[ctl[C_HEAD]]
        s = ctl[C_STARTED]
        if s < ctl[C_BUDGET]:
            if s >= ctl[C_PREPARED]:
                return False
            slot = s % len(pool)
            rng = pool[slot]
            pool[slot] = gens[r]  # the finished episode's generator: the slot's to refill
            gens[r] = rng
            goals[r, 0], goals[r, 1] = goal_at[slot, 0], goal_at[slot, 1]
            cx = start_at[0] + offsets[r]  # World.place
            copy_xy[r, 0], copy_xy[r, 1], headings[r] = cx, start_at[1], heading[slot]
            xy[r, 0], xy[r, 1] = cx - offsets[r], start_at[1]
            state[r] = _reading(r, rng, sensing, xy, headings)
            active[r] = True
            epsilon[r] = eps[slot]
            steps[r] = bumps[r] = 0
            total[r] = 0.0
            jn[r] = 0
            rescued[r] = False
            start_of[r] = s
            ctl[C_STARTED] = s + 1
        ctl[C_HEAD] += 1
    ctl[C_HEAD] = ctl[C_TAIL] = 0
    return True


@numba.njit(cache=True)
def _short_of_room(journal: tuple, table: tuple, n: int) -> bool:
    """The table might outgrow its arrays in a tick (``SharedTable.reserve(2 * N)``), or a
    robot's journal is full."""
    jint, jn = journal[0], journal[2]
    if table[3][0] + 2 * n > table[0].shape[0]:
        return True
    return jint.shape[1] > 0 and jn.max() >= jint.shape[1]


@numba.njit(cache=True)
def run_ticks(
    max_ticks: int, trng, gens, pool, ctl: np.ndarray, pending: np.ndarray, sensing: tuple,
    motion: tuple, robots: tuple, counters: tuple, rules: tuple, rescue: tuple, starts: tuple,
    records: tuple, journal: tuple, index, table: tuple,
) -> int:  # fmt: skip
    """Ticks of the fleet (module doc) until ``ctl[C_TICKS]`` reaches ``max_ticks`` or
    Python is needed; returns why (:data:`TICKS_DONE`, ...).

    ``trng`` is the run generator; ``gens`` (typed list) each robot's episode generator,
    ``pool`` the prepared starts' (slot ``s % len(pool)`` for start ``s``), with
    ``starts`` = ``(goal positions, start headings, epsilons`` by slot ``, the arena's
    start point)``; ``sensing`` = ``(geometry, encoding, goals, raw, rays, eow_k, trig,
    out, codes, keys, flags, plates, ray_cos, decoy, realism, noise, reading flags)``
    (the fleet's buffers by robot, :func:`sense_reading`'s groups); ``motion`` =
    :func:`move_all`'s ``(copy_xy, headings, walls, offsets, (distance, arc, radius),
    xy)``; ``robots`` = ``(state, active, epsilon, actions, rescued, start)`` and
    ``counters`` = ``(steps, bumps, return, event)`` per robot; ``rules`` is
    :func:`learn`'s, ``rescue`` = ``(rescue_chance, rescue_max_backup)``; ``records`` =
    ``(integers, returns)`` of the finished episodes (:data:`R_ROBOT`, ...); ``journal``,
    ``index`` and ``table`` as :func:`learn` takes them.
    """
    n = robots[0].shape[0]
    while True:
        if ctl[C_CURSOR] < n and _judge(ctl, pending, gens, sensing, motion, robots, counters,
                                        rules, rescue, records, journal, index, table):  # fmt: skip
            return RECORDS_DUE
        if not _start_pending(ctl, pending, gens, pool, starts, sensing, motion, robots,
                              counters, journal):  # fmt: skip
            return NEED_STARTS
        if ctl[C_TICKS] >= max_ticks:
            return TICKS_DONE
        if _short_of_room(journal, table, n):
            return NEED_ROOM
        _new_tick(trng, sensing, motion, robots, index, table[0])
        ctl[C_CURSOR] = 0
        ctl[C_TICKS] += 1
