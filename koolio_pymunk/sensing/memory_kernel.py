"""The robot's memory, compiled: :class:`~koolio_pymunk.sensing.memory.Memory`'s twin.

:func:`remember` is :meth:`Memory.update` after a reading followed by :meth:`Memory.key`,
on one robot's memory held as eight integers (:data:`FIELDS`), for the compiled step
(:mod:`koolio_pymunk.task.step_kernel`). :func:`memory_group` gives its configuration
(the fields that are on, their bits, the cameras' and the turn's millidegrees);
:func:`save` and :func:`load` move a :class:`Memory` into and out of the eight integers.
``tests/learning/test_engine.py`` holds the compiled steps to the Python ones bit for bit
with every field on, forgetting and rescues included.

>>> from koolio_pymunk.store.config import MemoryConfig
>>> m = Memory(MemoryConfig(goal_camera=True, previous_action=True), n_camera=3, far=1e4)
>>> _ = m.update([1e4, 80.0, 1e4], [1e4] * 3, 3)
>>> row = np.zeros(len(FIELDS), np.int64)
>>> save(m, row); row.tolist()[:3]
[2, 0, 4]
"""

from __future__ import annotations

import numba
import numpy as np

from ..store.kernel_cache import ensure_fresh
from .inline_twins import inline_twin
from .memory import Memory, bearing_code, turned

ensure_fresh()  # numba's cache, in step with every kernel's source (see there)

#: One robot's memory as integers: the four fields' codes, then the ages of the goal,
#: end-of-world and bearing sightings and the bearing in millidegrees.
FIELDS = ("goal", "eow", "action", "bearing", "_goal_age", "_eow_age", "_bearing_age",
          "bearing_mdeg")  # fmt: skip

#: ``memory.bearing_code`` and ``memory.turned``, compiled from the same Python code.
_bearing_code = numba.njit(cache=True)(bearing_code)
_turned = numba.njit(cache=True)(turned)


def memory_group(memory: Memory, bits: list[int], n_sonar: int) -> tuple:
    """:func:`remember`'s configuration for ``memory`` whose fields take ``bits`` (the
    keyword layout's, after the sensors'): no fields when the memory is off."""
    cfg = memory.cfg
    on = np.array([cfg.goal_camera, cfg.eow_camera, cfg.previous_action, cfg.goal_bearing],
                  np.bool_)  # fmt: skip
    field_bits = np.array(bits if memory.on else [], np.int64)
    cameras = np.array(memory.camera_mdeg or [0], np.int64)
    return (int(n_sonar), int(memory.n_camera), float(memory.far), int(cfg.forget_after), on,
            field_bits, cameras, int(memory.turn_mdeg))  # fmt: skip


def save(memory: Memory, row: np.ndarray) -> None:
    """``memory``'s state into ``row`` (:data:`FIELDS`)."""
    row[:] = [getattr(memory, f) for f in FIELDS]


def load(memory: Memory, row: np.ndarray) -> None:
    """``row`` (:data:`FIELDS`) back into ``memory``, as the Python steps leave it."""
    for f, v in zip(FIELDS, row.tolist()):
        setattr(memory, f, int(v))


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


@numba.njit(cache=True)
def remember(key: int, action: int, out: np.ndarray, memory: tuple, mem: np.ndarray) -> int:
    """``Memory.update`` after a reading (``action`` -1: a reset's or a rescue's, no move
    of the robot's own) and ``Memory.key``: the state key with the memory's codes after
    ``key``. ``out`` is the reading (sonars, then the cameras' goal and end-of-world
    distances); ``mem`` one robot's :data:`FIELDS`; ``memory`` is :func:`memory_group`."""
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


#: :func:`remember` compiled into its callers (:func:`~.inline_twins.inline_twin`): the
#: compiled step's.
remember_inline = inline_twin(remember, _nearest=inline_twin(_nearest))
