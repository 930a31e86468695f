"""``KoolioVectorEnv``: N copies of the task stepped in one compiled call (Gymnasium's
``VectorEnv``).

``gymnasium.make_vec("koolio_pymunk/Hallway-v0", num_envs=64)`` returns this class (the
registered ``vector_entry_point``); ``vectorization_mode="sync"`` or ``"async"`` still
gives Gymnasium's own vector envs of :class:`~koolio_pymunk.task.env.KoolioEnv`.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numba
import numpy as np
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space

from ..sensing.memory_kernel import FIELDS
from ..sensing.reading_kernel import robot_group
from ..store.kernel_cache import ensure_fresh
from .action_rules import UNDO as UNDO_ACTIONS
from .batch import EnvBatch
from .env import NO_KEYWORD, RESET_EVENT, WRONG_DOOR, KoolioEnv
from .rules import TERMS
from .step_kernel import (
    EVENTS,
    F_H,
    F_X,
    F_Y,
    I_BUMPS,
    I_CHECK_RESCUE,
    I_HAS_BEEN_RESCUED,
    I_RESCUED,
    I_STATE,
    I_STEPS,
    WRONG_DOOR_CODE,
    rescue_check_robot,
    simulate_robot,
)

ensure_fresh()  # numba's cache, in step with every kernel's source (see there)

#: ``events`` of an env that was reset (no step judged yet).
RESET_CODE = -2
#: Event names by code (:data:`~.step_kernel.EVENTS`, then ``wrong_door``), for ``info``.
EVENT_NAMES = np.array([*EVENTS, WRONG_DOOR], dtype=object)

#: The undo of each action (-1: none), as an array.
UNDO = np.array(UNDO_ACTIONS, np.int64)


@numba.njit(cache=True)
def step_batch(
    actions: np.ndarray, skip: np.ndarray, gens, readings: tuple, world: tuple,
    motion: np.ndarray, task: tuple, memory: tuple, ints: np.ndarray, floats: np.ndarray,
    mem: np.ndarray, out: tuple,
) -> None:  # fmt: skip
    """``KoolioEnv.step(actions[r])`` (simulate, then the rescue check) for every env ``r``
    not in ``skip``, in index order, each drawing from its own generator. ``out`` =
    ``(rewards, terminated, truncated, events, keywords, codes before rescue, action
    bits, TimeLimit's cap (0: none), the memory's fields in the observation)``; each env
    alone in its arena."""
    rewards, terminated, truncated, events, keywords, before, action_bits, cap, fields = out
    for r in range(ints.shape[0]):
        if skip[r]:
            continue
        a = actions[r]
        state = ints[r, I_STATE]
        rng = gens[r]
        _, code, reward, term, trunc = simulate_robot(r, a, rng, readings, world, motion, task,
                                                      memory, ints, floats, mem)  # fmt: skip
        codes = robot_group(r, readings[0], readings[1])[8]
        n = codes.shape[0]
        before[r, :n] = codes  # the state the action led to: the reading, the memory
        for k in range(fields.shape[0]):
            before[r, n + k] = mem[r, fields[k]]
        if ints[r, I_CHECK_RESCUE] == 1:  # rescue_check's first test (nothing else is due)
            rescue_check_robot(r, rng, readings, world, task, memory, ints, floats, mem, None)
        rewards[r] = reward
        terminated[r] = term
        truncated[r] = trunc or (cap > 0 and ints[r, I_STEPS] >= cap)
        events[r] = code
        keywords[r] = (state << action_bits) | a


class KoolioVectorEnv(gym.vector.VectorEnv):
    """``num_envs`` copies of :class:`~koolio_pymunk.task.env.KoolioEnv` (same arguments:
    ``arena``, ``config``, ``goal``, ``max_steps``, ``world``), stepped in one compiled call
    per :meth:`step` (:mod:`~koolio_pymunk.task.step_kernel`: the same steps as the
    env's, bit for bit).

    It behaves as Gymnasium's ``SyncVectorEnv`` of ``gym.make`` envs: the same
    observations, rewards, terminations and truncations for the same seeds
    (``reset(seed=s)`` seeds env ``i`` with ``s + i``, or a list gives each its seed),
    ``max_episode_steps`` as the ``TimeLimit`` wrapper counts it (the registered ids pass
    theirs: 1500), next-step autoreset (``metadata["autoreset_mode"]``: the step after an
    episode's end resets that env, with reward 0 and neither flag), ``options`` with a
    ``reset_mask``. ``info`` holds the env's keys, each an array over the envs with its
    ``_key`` mask: numbers as arrays of numbers (``pose`` ``(n, 3)``, ``sonar`` ``(n,
    n_sonar)``, ``goal_cam`` and ``eow_cam`` ``(n, cameras)``: where ``SyncVectorEnv`` gives
    object arrays of tuples and lists), names (``event``, ``goal``) as object arrays, and
    ``reward_terms`` a dict of arrays.

    ``render_mode="rgb_array"`` renders each env (a tuple of frames), as ``SyncVectorEnv``.
    The observations returned are copies.
    """

    metadata = {"render_modes": ["rgb_array"], "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(
        self,
        num_envs: int = 1,
        arena: Any = "hallway",
        config: Any = None,
        goal: str | None = None,
        render_mode: str | None = None,
        max_steps: int | None = None,
        world: Any = None,
        max_episode_steps: int | None = None,
        observe_goal: bool = False,
        overrides: dict[str, Any] | None = None,
    ) -> None:
        if not isinstance(num_envs, int) or num_envs < 1:
            raise ValueError(f"num_envs: a whole number >= 1, got {num_envs!r}")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode: {render_mode!r} is not one of None, 'rgb_array'")
        first = KoolioEnv(
            arena, config, goal, render_mode, max_steps, world, observe_goal, overrides
        )
        envs = [first] + [first.sibling() for _ in range(num_envs - 1)]
        for env in envs[1:]:
            env.render_mode = render_mode
        self.batch = EnvBatch(envs)
        self.envs = envs
        self.num_envs = num_envs
        self.render_mode = render_mode
        self.single_observation_space = first.observation_space
        self.single_action_space = first.action_space
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self.max_episode_steps = int(max_episode_steps or 0)
        """``TimeLimit``'s cap (0: none); the env's own is ``episode.max_steps``."""
        n = num_envs
        width = len(first.codes)
        self._codes = np.zeros((n, width + int(first.observe_goal)), np.int64)
        self._last = np.full(n, -1, np.int64)
        """Each env's last action (-1: none since its reset), for ``action_mask``."""
        self._out = (
            np.zeros(n),
            np.zeros(n, np.bool_),
            np.zeros(n, np.bool_),
            np.full(n, RESET_CODE, np.int64),
            np.full(n, NO_KEYWORD, np.int64),
            np.zeros((n, width), np.int64),  # the observation before a rescue
            int(first.layout.action_bits),
            self.max_episode_steps,
            np.zeros(0, np.int64),  # the memory's fields: below
        )
        self._autoreset = np.zeros(n, np.bool_)
        self._n_sensor = len(first.sensors.levels)
        on = first.memory.cfg
        self._memory_fields = [
            i
            for i, flag in enumerate(
                (on.goal_camera, on.eow_camera, on.previous_action, on.goal_bearing)
            )
            if flag and first.memory.on
        ]
        assert len(FIELDS) >= 4
        self._out = (*self._out[:-1], np.array(self._memory_fields, np.int64))
        self._no_undo = bool(first.config.learner.no_undo)
        self._observe_goal = bool(first.observe_goal)
        self._n_sonar = first.sensors.n_sonar
        self._n_camera = first.sensors.n_camera

    # -- Gymnasium API ---------------------------------------------------------------
    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset every env (or those of ``options["reset_mask"]``), as ``SyncVectorEnv``."""
        n = self.num_envs
        if seed is None:
            seeds: list[int | None] = [None] * n
        elif isinstance(seed, (int, np.integer)):
            seeds = [int(seed) + i for i in range(n)]
        else:
            seeds = list(seed)
            if len(seeds) != n:
                raise ValueError(f"seed: {len(seeds)} seeds for {n} envs")
        options = dict(options or {})
        mask = options.pop("reset_mask", None)
        if mask is None:
            mask = np.ones(n, np.bool_)
        elif not (isinstance(mask, np.ndarray) and mask.dtype == np.bool_ and mask.shape == (n,)):
            raise ValueError(f"options: reset_mask: a bool array of shape ({n},)")
        self.envs[0].check_options(options or None)
        for r in np.flatnonzero(mask).tolist():
            self._reset(r, seeds[r], options or None)
        self._autoreset[mask] = False
        return self._observations(), self._info(mask)

    def step(
        self, actions: Any
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """One step of every env (module doc); envs whose episode ended on the last step
        are reset instead (next-step autoreset)."""
        acts = np.asarray(actions)
        if acts.shape != (self.num_envs,) or not np.issubdtype(acts.dtype, np.integer):
            raise ValueError(f"actions: {self.num_envs} integer actions, got {actions!r}")
        if acts.min() < 0 or acts.max() >= self.single_action_space.n:
            raise ValueError(f"actions: each must be an action (0..4), got {actions!r}")
        acts = acts.astype(np.int64)
        rewards, terminated, truncated = self._out[0], self._out[1], self._out[2]
        resets = self._autoreset.copy()
        for r in np.flatnonzero(resets).tolist():
            self._reset(r, None, None)
        b = self.batch
        step_batch(acts, resets, b.generators.typed, b.reading_args, b.world, b.motion, b.task,
                   b.memory, b.ints, b.floats, b.mem, self._out)  # fmt: skip
        rewards[resets] = 0.0
        terminated[resets] = False
        truncated[resets] = False
        self._autoreset = terminated | truncated
        self._last = np.where(resets, -1, acts)
        ones = np.ones(self.num_envs, np.bool_)
        return (self._observations(), rewards.copy(), terminated.copy(), truncated.copy(),
                self._info(ones))  # fmt: skip

    def render(self) -> tuple[np.ndarray, ...] | None:
        """Each env's picture (``render_mode="rgb_array"``), as ``SyncVectorEnv`` gives."""
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode")
            return None
        for r in range(self.num_envs):
            self.batch.store(r)
        return tuple(env.render() for env in self.envs)

    def close_extras(self, **kwargs: Any) -> None:
        for env in self.envs:
            env.close()

    # -- internals ---------------------------------------------------------------------
    def _reset(self, r: int, seed: int | None, options: dict | None) -> None:
        self.batch.reset(r, seed, options)
        self._last[r] = -1
        self._out[3][r] = RESET_CODE
        self._out[4][r] = NO_KEYWORD

    def _observations(self) -> np.ndarray:
        """Every env's observation: the reading's codes, then the memory's."""
        rows = self.batch.readings.rows
        obs = self._codes
        obs[:, : self._n_sensor] = rows[18]
        for k, field in enumerate(self._memory_fields):
            obs[:, self._n_sensor + k] = self.batch.mem[:, field]
        if self._observe_goal:
            obs[:, -1] = self._goal_index()
        return obs.copy()

    def _goal_index(self) -> np.ndarray:
        return np.array([env.goal_index for env in self.envs], np.int64)

    def _action_mask(self, rescued: np.ndarray) -> np.ndarray:
        """``KoolioEnv.action_masks`` of every env: the last action's undo barred under
        the no-undo rule, none after a reset or a rescue."""
        mask = np.ones((self.num_envs, self.single_action_space.n), np.int8)
        if self._no_undo:
            bar = UNDO[np.maximum(self._last, 0)]
            on = (self._last >= 0) & ~rescued & (bar >= 0)
            mask[np.flatnonzero(on), bar[on]] = 0
        return mask

    def _info(self, mask: np.ndarray) -> dict[str, Any]:
        """The envs' ``info`` as vector envs give it: each key an array, with its mask."""
        b = self.batch
        out = b.readings.rows[17]
        n_s, n_c = self._n_sonar, self._n_camera
        events = self._out[3]
        reset = events == RESET_CODE
        names = EVENT_NAMES[np.where(reset, 0, events)]
        names[reset] = RESET_EVENT
        rewards = self._out[0]
        judged = np.where(events == WRONG_DOOR_CODE, 0, events)
        terms = {t: np.where(~reset & (judged == i), rewards, 0.0) for i, t in enumerate(TERMS)}
        rescued = b.ints[:, I_RESCUED].astype(np.bool_)
        obs = self._observations()
        before = obs.copy()
        width = self._out[5].shape[1]
        before[rescued, :width] = self._out[5][rescued]
        info: dict[str, Any] = {
            "pose": b.floats[:, [F_X, F_Y, F_H]].copy(),
            "sonar": out[:, :n_s].copy(),
            "goal_cam": out[:, n_s : n_s + n_c].copy(),
            "eow_cam": out[:, n_s + n_c : n_s + 2 * n_c].copy(),
            "compass": out[:, -1].copy(),
            "state_key": b.ints[:, I_STATE].copy(),
            "keyword": self._out[4].copy(),
            "event": names,
            "rescued": rescued,
            "has_been_rescued": b.ints[:, I_HAS_BEEN_RESCUED].astype(np.bool_),
            "reward_terms": {**terms, **{f"_{t}": mask.copy() for t in TERMS}},
            "steps": b.ints[:, I_STEPS].copy(),
            "bumps": b.ints[:, I_BUMPS].copy(),
            "goal": np.array([env.goal_name for env in self.envs], dtype=object),
            "goal_index": self._goal_index(),
            "action_mask": self._action_mask(rescued),
            "observation_before_rescue": before,
        }
        for key in list(info):
            if not key.startswith("_"):
                info[f"_{key}"] = mask.copy()
        return info
