"""Robots of one task whose steps run compiled: :class:`EnvBatch`.

An :class:`EnvBatch` holds ``N`` :class:`~koolio_pymunk.task.env.KoolioEnv` of one arena
and configuration (one per robot; each with its own world, sensors, memory and
generator) and mirrors their state in the arrays of the compiled step
(:mod:`koolio_pymunk.task.step_kernel`): the pose, the state key and the episode's
counters, the memory, the drive's errors, the reading's inputs and buffers
(:class:`~koolio_pymunk.sensing.reading_kernel.ReadingArrays`) and the generator of each
robot, a row each. Python resets a robot's env exactly as the Python loop does
(:meth:`KoolioEnv.reset_key <koolio_pymunk.task.env.KoolioEnv.reset_key>`: the
domain-randomization draw, the goal, the start heading, the first reading) and
:meth:`EnvBatch.load` takes it into the arrays; the compiled steps move it on;
:meth:`EnvBatch.store` writes the arrays back into the env, which is then what the Python
steps would have left.

**Generators.** Each robot's env draws from one generator object for the batch's whole
life (``env.np_random``); a reset with a seed (:meth:`EnvBatch.reseed`) gives it the state
``reset(seed=...)`` would give a new one (Gymnasium's ``PCG64(SeedSequence(seed))``,
computed in one compiled call: :func:`~.seeding.pcg64_state`), so
the draws are the same and the compiled code, which holds the object, never has to take a
new one (taking a generator into compiled code costs more than a whole step).
"""

from __future__ import annotations

import numba
import numpy as np
from numba.typed import List

from ..sensing import memory_kernel
from ..sensing.memory_kernel import FIELDS, memory_group
from ..sensing.reading_kernel import ReadingArrays
from ..store.kernel_cache import ensure_fresh
from ..world.segment_query import wall_array
from ..world.swept_move import world_group
from .env import KoolioEnv
from .seeding import pcg64_state
from .step_kernel import N_FLOATS, N_INTS, task_group

ensure_fresh()  # numba's cache, in step with every kernel's source (see there)


@numba.njit(cache=True)
def typed_list(item, n: int):
    """A numba list of ``n`` references to ``item`` (:func:`set_item` replaces them)."""
    out = List()
    for _ in range(n):
        out.append(item)
    return out


@numba.njit(cache=True)
def set_item(items, i: int, item) -> None:
    """``items[i] = item`` in compiled code (from Python a numba list's item costs 20 times
    more to set)."""
    items[i] = item


class Generators:
    """One generator object per robot, their states set for each episode
    (:func:`~.seeding.pcg64_state`), and the numba list of the same objects."""

    def __init__(self, n: int) -> None:
        self.items = [np.random.Generator(np.random.PCG64(i)) for i in range(n)]
        self.typed = typed_list(self.items[0], n)
        for i, g in enumerate(self.items):
            set_item(self.typed, i, g)

    def seeded(self, r: int, seed) -> np.random.Generator:
        """Robot ``r``'s generator, its state that of ``default_rng(seed)``."""
        g = self.items[r]
        g.bit_generator.state = pcg64_state(seed)
        return g


class EnvBatch:
    """``envs`` (one per robot: an arena, a configuration, a world) mirrored in the
    compiled step's arrays (module doc). The envs must run a compiled sensor backend."""

    def __init__(self, envs: list[KoolioEnv]) -> None:
        if not envs:
            raise ValueError("an EnvBatch needs at least one env")
        first = envs[0]
        if not first.sensors.fused:
            raise ValueError(
                f"sensors.backend {first.sensors.backend}: the pymunk reference runs in Python"
            )
        self.envs = envs
        n = len(envs)
        self.ints = np.zeros((n, N_INTS), np.int64)
        """Per robot: :data:`~.step_kernel.I_STATE`, ... (:mod:`.step_kernel`)."""
        self.floats = np.zeros((n, N_FLOATS))
        """Per robot: :data:`~.step_kernel.F_X`, ..."""
        self.mem = np.zeros((n, len(FIELDS)), np.int64)
        """Per robot: the memory (:data:`~koolio_pymunk.sensing.memory_kernel.FIELDS`)."""
        self.motion = np.zeros((n, 5))
        """Per robot: the drive's errors ``(on, drift, drift sigma, slip sigma, turn
        sigma)`` (radians)."""
        self.world = world_group(wall_array(first.world), first.world.radius,
                                 first.move_distance, first.turn_arc)  # fmt: skip
        """``(walls, radius, move distance, turn arc, room)``, shared by the robots
        (:func:`~koolio_pymunk.world.swept_move.world_group`)."""
        self.task = task_group(first.config, first.zones)
        """The rewards, end zones, rescue and step cap (:func:`~.step_kernel.task_group`)."""
        levels = len(first.sensors.levels)
        self.memory = memory_group(first.memory, list(first.layout.bits[levels:]),
                                   first.sensors.n_sonar)  # fmt: skip
        """The memory's configuration
        (:func:`~koolio_pymunk.sensing.memory_kernel.memory_group`)."""
        self.generators = Generators(n)
        for g, env in zip(self.generators.items, envs):
            g.bit_generator.state = env.np_random.bit_generator.state
            env.np_random = g
        self.readings = ReadingArrays([env.sensors for env in envs])
        """The robots' reading inputs
        (:class:`~koolio_pymunk.sensing.reading_kernel.ReadingArrays`)."""
        self.reading_args = (self.readings.shared, self.readings.rows)
        """:func:`~koolio_pymunk.sensing.reading_kernel.robot_group`'s arguments."""
        self.shared = first.share is not None
        """The robots share one arena (:mod:`.shared_arena`): bodies to each other."""
        world = first.world
        self.among = (world.xy, world.present, self.readings.robot_rows) if self.shared else None
        """:func:`~koolio_pymunk.sensing.reading_kernel.robot_others`' arguments after the
        robot: the shared world's centres and presence flags (its own arrays, which the
        compiled steps keep current: Python's start spots read them), and the rows the
        readings write the robots hit into. None: the robots are alone."""
        for r, env in enumerate(envs):
            if hasattr(env, "state_key"):  # an env reset before: its state as it stands
                self.load(r)

    def __len__(self) -> int:
        return len(self.envs)

    @classmethod
    def of(cls, env: KoolioEnv, n: int) -> EnvBatch:
        """A batch of ``env`` and ``n - 1`` siblings (:meth:`KoolioEnv.sibling`)."""
        return cls([env] + [env.sibling() for _ in range(n - 1)])

    def reseed(self, r: int, seed: int) -> None:
        """Robot ``r``'s env generator in the state ``reset(seed=seed)`` gives its env."""
        self.generators.seeded(r, seed)

    def reset(self, r: int, seed: int | None, options: dict | None = None) -> int:
        """``envs[r].reset(seed=seed, options=options)``'s draws and state (without its
        observation and ``info``), taken into the arrays; returns the state key."""
        env = self.envs[r]
        if seed is not None:
            self.reseed(r, seed)
        key = env.reset_key(options)
        self.load(r)
        return key

    def enter(self, r: int) -> bool:
        """A waiting robot of a shared arena tries to enter it
        (:meth:`KoolioEnv.enter <koolio_pymunk.task.env.KoolioEnv.enter>`); when it did,
        its state is taken into the arrays. Returns whether it entered."""
        if not self.envs[r].enter():
            return False
        self.load(r)
        return True

    def load(self, r: int) -> None:
        """Take ``envs[r]``'s state (after a reset or Python steps) into the arrays."""
        env = self.envs[r]
        x, y, h = env.world.pose(env.robot)
        misread = bool(env.sensors.realism.misread)
        self.ints[r] = (env.state_key, env.steps, env.bumps, env.has_been_rescued, env.rescued,
                        env._check_rescue, misread)  # fmt: skip
        self.floats[r] = (x, y, h, env.episode_reward)
        memory_kernel.save(env.memory, self.mem[r])
        m = env.motion
        self.motion[r] = (0.0,) * 5 if m is None else (
            1.0, m.drift, m.drift_sigma, m.slip_sigma, m.turn_sigma)  # fmt: skip
        self.readings.load(r, env.sensors)

    def store(self, r: int) -> None:
        """Write robot ``r``'s arrays back into ``envs[r]``: its pose, state, counters,
        memory and last reading are then what the Python steps would have left."""
        ints, floats = self.ints[r].tolist(), self.floats[r].tolist()
        self.readings.store(r, self.envs[r].sensors)
        self.envs[r].adopt(
            (floats[0], floats[1], floats[2]),
            ints[0],
            (ints[1], ints[2], floats[3]),
            (bool(ints[3]), bool(ints[4])),
        )
        memory_kernel.load(self.envs[r].memory, self.mem[r])
