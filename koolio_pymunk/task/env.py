"""``KoolioEnv``: the paper's delivery task as a Gymnasium environment."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Protocol

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from ..sensing.memory import Memory
from ..sensing.suite import Readings, SensorSuite
from ..store.config import Config, apply_world, as_config, state_fields
from ..store.errors import ConfigError
from ..store.keyword import KeywordLayout
from ..store.realism_config import Randomizer, RealismConfig, motion_on
from ..store.worlds import world_name
from ..world.arena import Arena, Point, load_arena
from ..world.motion_errors import MotionErrors
from ..world.physics import ACTION_NAMES, Action, World
from ..world.start_area import StartArea
from .action_rules import barred
from .end_zones import EndZones
from .rescue import rescue_robot, wants_rescue
from .rules import TERMS, Judgement, judge

#: The event of a Stop in front of a misread plate (realism ``camera.misread``): the robot
#: believes it delivered (the goal reward, the episode ends) at another door.
WRONG_DOOR = "wrong_door"

NO_KEYWORD = -1
"""``info["keyword"]`` after ``reset``: no action taken yet (keywords are >= 0)."""
RESET_EVENT = "reset"
"""``info["event"]`` after ``reset``: no reward rule judged yet."""


class ArenaShare(Protocol):
    """What a robot's env needs of an arena it shares with other robots
    (:class:`~koolio_pymunk.task.shared_arena.SharedArena`): the world they all stand in,
    and each robot's start area."""

    world: World
    areas: list[StartArea]


class KoolioEnv(gym.Env):
    """Koolio, a round delivery robot, must stop in front of an office door's number plate.

    **Arena.** A YAML arena (``arenas/hallway.yaml`` by default: the paper's 1632 x 88 in
    hallway; a built-in name, a file or an :class:`~koolio_pymunk.world.arena.Arena`):
    walls, optional obstacles, named goals (one active), end-of-world markers with zones,
    a start point. Units are inches. ``goal`` makes another of its goals the active one;
    ``goal="random"`` draws one per episode (the cameras see only its plate).

    **Configuration.** ``config`` is a :class:`~koolio_pymunk.store.config.Config`, a dict
    laid over the defaults as a configuration file's sections are (``{"learner":
    {"no_undo": True}}``), a shipped profile's name (``"paper"``) or a YAML file; None is
    the defaults. It is copied, never changed. ``overrides``, a dict of the same form, is
    laid over it: ``gym.make("koolio_pymunk/HallwayPaper-v0", overrides={...})`` keeps
    the id's profile, where ``config=`` would replace it. An unknown key or a bad value is
    refused with one line naming it (``ConfigError``: ``config: learner.alpah: unknown key
    (did you mean 'alpha'?)``). The registered ids (:mod:`koolio_pymunk.task.registry`,
    docs/envs.md) are arenas, worlds and profiles of these arguments.

    **Action space** ``Discrete(5)``: 0 Stop, 1 RotateLeft (+``rotate_action_arc_deg``),
    2 RotateRight, 3 Forward, 4 Reverse (``move_action_distance``); :attr:`action_names`
    names them. pymunk resolves every move against the walls. Every action may be taken;
    ``info["action_mask"]`` says which ones the project's learners would choose among.

    **Action mask** (``info["action_mask"]``, :meth:`action_masks`: int8, one per action).
    With ``learner.no_undo`` (the no-undo rule, :mod:`koolio_pymunk.task.action_rules`) the
    action that undoes the last one is 0: RotateRight after RotateLeft and back, Reverse
    after Forward and back. All ones without the rule, after a reset and after a rescue
    (the first action of an episode and the first after a rescue are free). The env
    enforces nothing: a learner that follows the mask chooses among the actions
    ``koolio-pm train``'s learner chooses among.

    **Observation space** ``MultiDiscrete``: the encoded readings in keyword order. With
    the paper's sensors, 12 values: goal distance seen by the front, left and right cameras
    and end-of-world distance seen by the same three (0 Close < 36 in, 1 Medium < 96,
    2 Far or not seen), then six sonar values (sonars 0, 1&2 averaged, 3, 4, 5&6
    averaged, 7; 0 Bump < 6 in, 1 Close < 24, 2 Medium < 60, 3 Far); int64. With
    ``sensors.compass.in_state`` the compass follows, and with ``sensors.memory`` the
    memory fields (:attr:`codes`; e.g. ``paper-memory``: the camera that last saw the
    goal, 0-3, and the previous action, 0-5: 14 values). With ``observe_goal=True`` one more
    value ends it: the active goal's index in :attr:`goal_names` (as many levels as the
    arena has goals; the paper's robot does not see it, so it is off by default: the
    project's learners never use it).

    **Rewards** (first that applies, values in ``Config.rewards``; the defaults: goal 100,
    end_of_world -100, bump -5, stop -5, reverse -10, turn -1, forward -0.5): goal (Stop
    with the front camera reading the goal Close) > end_of_world > robot_bump (a Bump read
    from another robot, robots sharing an arena only; the bump's value unless set) > bump
    (any sonar Bump) > stop / reverse / turn / forward by action. ``info["reward_terms"]``
    names them (a ``wrong_door`` step's reward is under ``goal``: its ``event`` tells them
    apart).

    **Episode end.** ``terminated`` at the goal or in an end-of-world zone; ``truncated``
    after ``episode.max_steps`` steps (1500 by default; 0: no cap). With the misread-plate
    model on, a Stop whose front camera reads another door's plate as the goal Close gets
    the goal reward and ends the episode as the robot would, but its event is
    ``wrong_door``, not ``goal``. Each episode starts at the arena's start point with a
    uniformly random heading unless the arena fixes it (exploring starts).

    **Step cap and** ``TimeLimit``. The cap belongs to the simulator's configuration:
    ``koolio-pm train``, ``eval`` and ``view`` drive the class directly, without
    wrappers, and their logs record the truncations. Every registered id
    (``koolio_pymunk/Hallway-v0`` and the others) also declares it, as Gymnasium does, with
    ``max_episode_steps=1500``: ``gym.make`` wraps the env in ``TimeLimit`` and
    ``env.spec.max_episode_steps`` is 1500. Both caps then count the same steps and by
    default end the episode on the same step, with the same ``truncated``; when they
    differ the smaller one wins. ``gym.make(id, max_steps=N)`` lowers the env's own cap
    only; for longer episodes raise both (``max_steps=N, max_episode_steps=N``), or pass
    ``max_steps=0`` and let ``max_episode_steps`` alone decide.

    **Rescue.** With ``rescue.auto_rescue_toggle`` on, a bumping robot past
    ``max_steps_before_rescue`` steps is rescued with probability ``rescue_chance``
    (random reverses, random spin) after the step's reward is found and its Q update made
    (paper §5.4.8: the update bootstraps from the state the action led to); the
    observation returned is the one after the rescue and the step's reward stays the Bump
    reward. ``info["observation_before_rescue"]`` is the observation the action led to,
    before the rescue: a learner that follows the paper updates from it and chooses its
    next action from the returned one. The key is in every ``info``, equal to the
    observation when no rescue happened (after a reset too), so every ``info`` has the
    same keys with the same types and vector envs stack it. :meth:`rescue` forces one.

    **info** (the same keys, each with one type, after ``reset`` and after every step, so
    vector envs can stack them through staggered autoresets): ``pose`` (tuple of 3 floats:
    x, y, heading radians), ``sonar`` / ``goal_cam`` / ``eow_cam`` (lists of floats: noised
    distances, inches), ``compass`` (float), ``state_key`` (int), ``keyword`` (int: Table
    12 keyword of the previous state and this action, the Q entry the step updates; -1
    after ``reset``), ``event`` (str: the winning reward rule; ``"reset"`` after
    ``reset``), ``rescued`` and ``has_been_rescued`` (bool), ``reward_terms`` (dict of the
    eight named terms of ``rules.TERMS``, floats; all 0.0 after ``reset``), ``steps`` and
    ``bumps`` (int), ``goal`` (str: the active goal's name), ``goal_index`` (int: its index in
    :attr:`goal_names`, the arena file's order; with ``goal="random"`` the door drawn for
    this episode), ``action_mask`` (int8 array of 5, above), ``observation_before_rescue``
    (int64 array like the observation, above).

    **Rendering.** ``render_mode`` is ``None``, ``"human"`` (a window) or ``"rgb_array"``
    (the window's picture as an array); any other value is refused with ``ValueError``.
    Drawing needs the ``[view]`` extra (pygame-ce); without it :meth:`render` raises
    Gymnasium's ``DependencyNotInstalled`` naming the extra to install.

    **World.** ``world`` (a profile name such as ``koolio-real``, or a file) lays the
    realism models and sensor noise of a world over the configuration
    (:func:`~koolio_pymunk.store.config.apply_world`); the default is the ideal world,
    unless the configuration's own ``realism`` section is on (``config="koolio-real"``).
    :attr:`world_name` names the world either way, as a table learned here records it. The
    realism models (:mod:`koolio_pymunk.sensing.realism`) act on every reading and move; with
    ``realism.randomize`` each reset draws the episode's parameters
    (:attr:`realism_draw`). :attr:`readings` holds what a real robot's driver would hand
    to ``robot_runtime.py`` (``sonar``, ``goal``, ``eow``: inches from the robot's edge,
    ``really_long_distance`` when nothing is seen) and what the models did (``echo`` per
    sonar sub-arc ray, ``missed`` and ``misread`` per camera).

    **Sharing an arena** (``share`` and ``robot``: made by
    :class:`~koolio_pymunk.task.shared_arena.SharedArena`, ``--shared-arena``, the
    PettingZoo env): the env is robot ``robot`` of a world it shares with other robots'
    envs; the others are bodies to its moves and sensors, it starts on a free start spot
    (:meth:`enter`; :attr:`waiting` while none is free) and leaves the arena when its
    episode ends (:meth:`leave`, called by its episode loop). Alone (the default) it is
    the paper's single robot.

    All randomness (start headings and spots, sensor noise, realism, rescues) comes from
    ``self.np_random``, seeded by ``reset(seed=...)``.

    **Copies.** An env pickles and copies (:mod:`pickle`, :func:`copy.deepcopy`) with its
    generator, pose, counters and memory; the copy continues exactly as the original
    would. The window is not copied: a copy opens its own at its first render.
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 30}
    action_names: tuple[str, ...] = ACTION_NAMES
    """The actions by index (``Discrete(5)``): Stop, RotateLeft, RotateRight, Forward,
    Reverse (``world.physics.ACTION_NAMES``)."""

    def __init__(
        self,
        arena: str | Path | Arena = "hallway",
        config: Config | dict[str, Any] | str | Path | None = None,
        goal: str | None = None,
        render_mode: str | None = None,
        max_steps: int | None = None,
        world: str | Path | None = None,
        observe_goal: bool = False,
        overrides: dict[str, Any] | None = None,
        share: ArenaShare | None = None,
        robot: int = 0,
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            modes = ", ".join(repr(m) for m in self.metadata["render_modes"])
            raise ValueError(f"render_mode: {render_mode!r} is not one of None, {modes}")
        # A configuration passed in is copied, never changed (``max_steps``, ``world``).
        own = as_config(config, overrides)
        cfg = apply_world(own, world) if world is not None else own
        self.world_name = world_name(cfg, world, own.realism)
        """The world the env runs in, however its realism was turned on: ``ideal``, the
        world laid over the configuration (``--world``), a shipped world profile's name, or
        ``realism-`` and a hash of other realism
        (:func:`~koolio_pymunk.store.worlds.world_name`); a table learned here records it."""
        self.config = cfg
        if max_steps is not None:
            self.config.episode.max_steps = int(max_steps)
        self.config.validate("config")
        realism = self.config.realism
        self.realism: RealismConfig = realism
        """The realism models of the current episode (a draw when randomized)."""
        self.randomizer = Randomizer(realism)
        self.realism_draw: dict[str, float] = {}
        """The parameters domain randomization drew for this episode (empty: none)."""
        erring = motion_on(realism) or any(k.startswith("motion.") for k in realism.randomize)
        radius = self.config.robot.radius
        self.arena = arena if isinstance(arena, Arena) else load_arena(arena, radius)
        self.home_goal = self.arena.active_goal
        """The arena's own active goal (the one its file names; ``goal`` makes another
        one active): the goal of a table that records none (a sibling keeps it)."""
        if goal is not None and goal != "random":
            if goal not in self.arena.goal_names():
                raise ConfigError(
                    f"{self.arena.source}: goal: no goal named {goal!r} "
                    f"(goals: {', '.join(self.arena.goal_names())})"
                )
            self.arena = self.arena.with_active_goal(goal)
        self.random_goal = goal == "random"
        self.observe_goal = bool(observe_goal)
        """The observation ends with :attr:`goal_index` (``observe_goal=True``)."""
        self.world_arena = self.arena.to_world()
        self.share = share
        """The arena this robot shares with others (None: it is alone in its own)."""
        self.robot = robot
        """This robot's index in :attr:`world` (0 unless it shares the arena)."""
        self.world = share.world if share is not None else World.from_arena(self.arena, radius)
        self.motion = MotionErrors(realism.motion) if erring else None
        """How the robot's moves err (None: the motion model is off and domain
        randomization never switches it on)."""
        self.waiting = False
        """A shared arena's robot whose episode began while every start spot was covered:
        it is outside the arena until :meth:`enter` finds one free."""
        self.zones = EndZones(self.world_arena, radius)
        self.sensors = SensorSuite(
            self.config.sensors,
            self.world,
            self.world_arena.goal().at,
            [m.at for m in self.world_arena.end_of_world],
            realism=realism,
            plates=self._other_plates(),
            robot=robot,
        )
        fields = state_fields(self.config.sensors)
        self.layout = KeywordLayout(tuple(fields))
        self.memory = Memory(
            self.config.sensors.memory,
            self.sensors.n_camera,
            self.sensors.far,
            camera_deg=self.config.sensors.camera.camera_sensors_deg,
            turn_deg=self.config.actions.rotate_action_arc_deg,
        )
        """What the robot remembers in its state (``sensors.memory``; off by default)."""
        self._memory_bits = self.layout.bits[len(self.sensors.levels) :]
        self.action_space = spaces.Discrete(len(ACTION_NAMES))
        levels = [lv for _, lv in fields]
        if self.observe_goal:
            levels.append(len(self.arena.goals))
        self.observation_space = spaces.MultiDiscrete(levels)
        self.render_mode = render_mode
        self._renderer: Any = None
        self.turn_arc = math.radians(self.config.actions.rotate_action_arc_deg)
        """RotateLeft / RotateRight turn by this many radians (``rotate_action_arc_deg``)."""
        self.move_distance = self.config.actions.move_action_distance
        """Forward / Reverse move this many inches (``move_action_distance``)."""
        self.goal_name = self.world_arena.active_goal
        self.goal_index = self.goal_names.index(self.goal_name)
        """The active goal's index in :attr:`goal_names` (``info["goal_index"]``)."""
        self._before_rescue: tuple[int, ...] | None = None
        self._reset_counters()

    # -- Gymnasium API ---------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start an episode. ``options`` may hold ``goal`` (a goal name of the arena: it
        becomes the active goal, for this and later episodes, until another ``goal``
        option) and ``heading`` (radians, counter-clockwise from +x; the start's own or
        a random one otherwise); any other key, or a goal the arena lacks, is refused with
        ``ValueError`` before anything changes."""
        self.check_options(options)
        super().reset(seed=seed)
        self.reset_key(options)
        if self.render_mode == "human":
            self.render()
        return self.observe()

    def step(self, action: int) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """One step (class doc). An action outside ``Discrete(5)`` (e.g. 7, or 2.7) is
        refused with ``ValueError`` before anything moves or any draw is made."""
        if not self.action_space.contains(action):
            raise ValueError(f"action: {action!r} is not an action (0..4)")
        _, reward, terminated, truncated = self.transition(int(action))
        if self.render_mode == "human":
            self.render()
        obs, info = self.observe()
        return obs, reward, terminated, truncated, info

    def observe(self) -> tuple[np.ndarray, dict[str, Any]]:
        """The observation and ``info`` of the state now, as :meth:`reset` and :meth:`step`
        return them (for a loop that steps with :meth:`transition`, such as the shared
        arena's PettingZoo env)."""
        obs = self._obs()
        return obs, self._info(obs)

    def action_masks(self) -> np.ndarray:
        """``info["action_mask"]`` now: 1 for each action the no-undo rule
        (``learner.no_undo``) allows after the last action, int8. All ones without the
        rule, after a reset and after a rescue (the robot was moved: its next action undoes
        nothing); with it, the last action's undo is 0 (:mod:`.action_rules`). The name is
        the one sb3-contrib's ``MaskablePPO`` calls."""
        mask = np.ones(len(ACTION_NAMES), dtype=np.int8)
        if self.config.learner.no_undo and not self.rescued and self.last_action is not None:
            bar = barred(self.last_action)
            if bar >= 0:
                mask[bar] = 0
        return mask

    def check_options(self, options: dict[str, Any] | None) -> None:
        """``reset``'s options (and ``reset_key``'s, whose callers check them here):
        known keys, a goal of this arena, a finite heading; else ``ValueError``."""
        if not options:
            return
        unknown = sorted(str(k) for k in options if k not in ("goal", "heading"))
        if unknown:
            raise ValueError(f"options: unknown key {unknown[0]!r} (known: goal, heading)")
        goal = options.get("goal")
        if goal is not None and goal not in self.world_arena.goal_names():
            raise ValueError(
                f"options: goal: no goal named {goal!r} "
                f"(goals: {', '.join(self.world_arena.goal_names())})"
            )
        heading = options.get("heading")
        if heading is not None and not (
            isinstance(heading, (int, float, np.number)) and math.isfinite(heading)
        ):
            raise ValueError(f"options: heading: a finite number of radians, got {heading!r}")

    def render(self) -> np.ndarray | None:
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode")
            return None
        if self._renderer is None:
            from ..store.extras import view_extra

            with view_extra("render"):
                from .render import EnvRenderer  # pygame only when drawing

            self._renderer = EnvRenderer(self)
        return self._renderer.render(self.render_mode)

    def __getstate__(self) -> dict[str, Any]:
        """Everything but the window: a copy (:func:`copy.deepcopy`, :mod:`pickle`, a
        vector env's worker) continues exactly as the original would, generators and
        learned memory included, and opens its own window at its first render."""
        state = self.__dict__.copy()
        state["_renderer"] = None
        return state

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def sibling(self) -> KoolioEnv:
        """A new env of this one's arena, configuration, world and goal (``random``
        included), with a world, sensors, memory and generator of its own: another robot
        of a batch (:class:`~koolio_pymunk.task.batch.EnvBatch`). No window."""
        goal = "random" if self.random_goal else None
        other = KoolioEnv(self.arena, config=self.config, goal=goal, observe_goal=self.observe_goal)
        other.world_name = self.world_name
        other.home_goal = self.home_goal
        if other.goal_name != self.goal_name:  # a reset option made another goal active
            other.set_goal(self.goal_name)
        return other

    # -- fast path (used by the learner; no observation array, no info dict) ----------
    def reset_key(self, options: dict[str, Any] | None = None) -> int:
        """Reset without building obs/info; returns the state key. Call ``reset`` first
        once (or seed ``np_random``) to own a seeded generator."""
        options = options or {}
        rng = self.np_random
        if self.randomizer:
            self.realism, self.realism_draw = self.randomizer.draw(rng)
            self.sensors.set_realism(self.realism)
            if self.motion is not None:
                self.motion.configure(self.realism.motion)
        goal = options.get("goal")
        if goal is None and self.random_goal:
            names = self.world_arena.goal_names()
            goal = names[int(rng.integers(len(names)))]
        if goal is not None:
            self.set_goal(goal)
        self._reset_counters()
        self.memory.reset()
        if not self.enter(options.get("heading")) and not hasattr(self, "state_key"):
            # Never read yet: a reading where it waits, with draws of a generator of its
            # own (the robot's stream is untouched), so that the observation exists.
            self._pose = self.world.pose(self.robot)
            self.state_key = self.sensors.sense(self._pose, np.random.default_rng(0))[0]
        return self.state_key

    def enter(self, heading: float | None = None) -> bool:
        """Put the robot at its start with ``heading`` (radians; None: the arena's, or a
        random one) and read its sensors: the start point, or in a shared arena a free
        start spot drawn first (:class:`~koolio_pymunk.world.start_area.StartArea`).
        When every spot is covered the robot stays out (:attr:`waiting`, no draw made)
        and its episode loop asks again at its next turn. Returns whether it entered."""
        rng = self.np_random
        start = self.world_arena.start
        at: Point | None = start.at
        if self.share is not None:
            at = self.share.areas[self.robot].draw(self.robot, rng)
            self.waiting = at is None
            if at is None:
                return False
        if heading is None:
            heading = (
                math.radians(start.heading_deg)
                if start.heading_deg is not None
                else float(rng.uniform(0.0, 2.0 * math.pi))
            )
        self.world.place(self.robot, at, float(heading))
        self._sense()
        return True

    def leave(self) -> None:
        """A shared arena's robot whose episode ended leaves the arena (no obstacle, no
        sensor target) until its next episode enters it; alone, nothing happens."""
        if self.share is not None:
            self.world.park(self.robot)

    def transition(self, action: int) -> tuple[int, float, bool, bool]:
        """One whole step: :meth:`simulate`, then :meth:`rescue_check` (the Gymnasium
        :meth:`step` without its observation and ``info``).

        Returns ``(next_key, reward, terminated, truncated)``. ``next_key`` is the state the
        action led to, *before* any rescue: the paper applies the Q update first and then
        checks for a rescue (§5.4.8), so the update bootstraps from ``next_key``.
        :attr:`state_key` is the state after the rescue, where the next step starts (the
        same as ``next_key`` when no rescue happened). A learner that must see the step
        before the rescue (the episode loop, :mod:`koolio_pymunk.learning.episodes`) calls
        the two halves itself, with its update between them.
        """
        out = self.simulate(action)
        self.rescue_check()
        return out

    def simulate(self, action: int) -> tuple[int, float, bool, bool]:
        """Simulate -> observe -> reward -> terminated -> truncated, without the rescue
        check: returns ``(next_key, reward, terminated, truncated)``."""
        prev_key = self.state_key
        if self.motion is None:
            self.world.act_robot(self.robot, action, self.move_distance, self.turn_arc)
        else:
            self._act_with_errors(action)
        bump, goal_close = self._sense(action)
        x, y, _ = self._pose
        robot_bump = bump and self.share is not None and self.sensors.robot_bump(self.readings)
        j = judge(
            action, goal_close, self.zones.contains(x, y), bump, self.config.rewards, robot_bump
        )
        if j.event == "goal" and self.sensors.goal_misread():
            j = Judgement(WRONG_DOOR, j.reward, True, j.terms)
        self.steps += 1
        self.bumps += int(bump)
        self.episode_reward += j.reward
        self.judgement = j
        self.last_action = action
        self.keyword = (prev_key << self.layout.action_bits) | action
        self.rescued = False
        self._check_rescue = not j.terminated and bump
        cap = self.config.episode.max_steps
        truncated = not j.terminated and cap > 0 and self.steps >= cap
        return self.state_key, j.reward, j.terminated, truncated

    def rescue_check(self) -> bool:
        """Auto rescue after the step's update (paper §5.4.8): with the toggle on, a robot
        that bumped past ``max_steps_before_rescue`` steps is rescued with probability
        ``rescue_chance``. Once per :meth:`simulate`; returns whether it rescued."""
        due, self._check_rescue = self._check_rescue, False
        if due and wants_rescue(self.config.rescue, self.steps, True, self.np_random):
            self._rescue()
            return True
        return False

    def adopt(
        self,
        pose: tuple[float, float, float],
        state_key: int,
        counters: tuple[int, int, float],
        rescued: tuple[bool, bool],
    ) -> None:
        """Take the state reached by steps run outside :meth:`simulate` with this env's
        generator, sensors and world (the step engine,
        :mod:`koolio_pymunk.learning.engine`): the robot's pose, the state key,
        ``(steps, bumps, episode_reward)`` and ``(has_been_rescued, rescued)``. The
        last reading is then read from the sensor kernel's buffers."""
        parked = self.share is not None and not self.world.present[self.robot]
        self.world.place(self.robot, pose[:2], pose[2])
        if parked:  # its episode ended: it stays out of the arena
            self.world.park(self.robot)
        self._pose = self.world.pose(self.robot)
        self.state_key = state_key
        self.steps, self.bumps, self.episode_reward = counters
        self.has_been_rescued, self.rescued = rescued
        self._check_rescue = False
        self._before_rescue = None  # not known: ``info`` gives the observation itself
        self.sensors.forget_last()

    def rescue(self) -> tuple[np.ndarray, dict[str, Any]]:
        """Force ``Rescue_Robot`` now (the viewer's Rescue button)."""
        self._rescue()
        return self.observe()

    # -- internals ---------------------------------------------------------------------
    def set_goal(self, name: str) -> None:
        """Make ``name`` the active goal (the cameras see only its plate)."""
        self.world_arena = self.world_arena.with_active_goal(name)
        self.sensors.set_goal(self.world_arena.goal().at, self._other_plates())
        self.goal_name = name
        self.goal_index = self.goal_names.index(name)

    @property
    def goal_names(self) -> list[str]:
        """The arena's goals in its file's order: ``info["goal_index"]`` indexes it."""
        return self.world_arena.goal_names()

    def _other_plates(self) -> list[Point]:
        """The plates of every goal but the active one (a misread takes one for it)."""
        active = self.world_arena.active_goal
        return [g.at for g in self.world_arena.goals if g.name != active]

    def _act_with_errors(self, action: int) -> None:
        """The action as a real differential drive does it (:class:`MotionErrors`)."""
        motion, rng = self.motion, self.np_random
        assert motion is not None
        if action in (Action.FORWARD, Action.REVERSE):
            sign = 1.0 if action == Action.FORWARD else -1.0
            self.world.drive(self.robot, *motion.move(sign, self.move_distance, rng))
        elif action == Action.ROTATE_LEFT:
            self.world.drive(self.robot, 0.0, motion.turn(self.turn_arc, rng))
        elif action == Action.ROTATE_RIGHT:
            self.world.drive(self.robot, 0.0, -motion.turn(self.turn_arc, rng))

    def _rescue(self) -> None:
        self._before_rescue = self.codes  # ``info["observation_before_rescue"]``
        rescue_robot(self.world, self.robot, self.config.rescue, self.move_distance, self.np_random)
        self._sense()
        self.rescued = True
        self.has_been_rescued = True

    def _reset_counters(self) -> None:
        self.steps = 0
        self.bumps = 0
        self.episode_reward = 0.0
        self.has_been_rescued = False
        self.rescued = False
        self.judgement: Judgement | None = None
        self.last_action: int | None = None
        self.keyword: int | None = None
        self._check_rescue = False

    def _sense(self, action: int | None = None) -> tuple[bool, bool]:
        """Read the sensors after ``action`` (None: a reset or a rescue), update the memory;
        sets ``state_key`` and returns ``(bump, goal_close)``."""
        self._pose = self.world.pose(self.robot)
        key, bump, goal_close = self.sensors.sense(self._pose, self.np_random)
        if self.memory.on:
            self.memory.update(*self.sensors.sightings(), action)
            key = self.memory.key(key, self._memory_bits)
        self.state_key = key
        return bump, goal_close

    @property
    def readings(self) -> Readings:
        """The last reading of every sensor (noised distances, rays, markers seen)."""
        return self.sensors.last()[0]

    @property
    def codes(self) -> tuple[int, ...]:
        """The state in keyword order (the observation): the encoded last reading, then
        the memory's codes when it is on."""
        return self.sensors.last()[1] + self.memory.codes

    def _obs(self, codes: tuple[int, ...] | None = None) -> np.ndarray:
        """The observation of ``codes`` (the state now by default), with the goal's index
        when :attr:`observe_goal` is on."""
        codes = self.codes if codes is None else codes
        if self.observe_goal:
            codes = (*codes, self.goal_index)
        return np.array(codes, dtype=np.int64)

    def _info(self, obs: np.ndarray) -> dict[str, Any]:
        r = self.readings
        j = self.judgement
        rescued = self.rescued and self._before_rescue is not None
        return {
            "pose": self.world.pose(self.robot),
            "sonar": r.sonar.tolist(),
            "goal_cam": r.goal.tolist(),
            "eow_cam": r.eow.tolist(),
            "compass": r.compass,
            "state_key": self.state_key,
            "keyword": NO_KEYWORD if self.keyword is None else self.keyword,
            "event": RESET_EVENT if j is None else j.event,
            "rescued": self.rescued,
            "has_been_rescued": self.has_been_rescued,
            "reward_terms": dict(j.terms) if j is not None else dict.fromkeys(TERMS, 0.0),
            "steps": self.steps,
            "bumps": self.bumps,
            "goal": self.goal_name,
            "goal_index": self.goal_index,
            "action_mask": self.action_masks(),
            "observation_before_rescue": self._obs(self._before_rescue) if rescued else obs.copy(),
        }
