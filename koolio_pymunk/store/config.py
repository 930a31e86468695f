"""Configuration: typed dataclasses with the paper's names, units and defaults.

Every constant of the paper keeps a recognisable snake_case name (``RotateActionArc`` ->
``rotate_action_arc_deg``, ``MaxCameraView`` -> ``max_camera_view`` ...). Where the paper
gives a value it is the default; where it is silent the default is this project's choice
and the field's docstring says so.

A YAML configuration file holds any subset of the sections below, for example::

    actions: {move_action_distance: 12}
    rewards: {goal: 100, bump: -5}
    learner: {alpha: 0.2, epsilon: {start: 0.3, end: 0.02, decay_episodes: 500}}

Unknown sections or keys, a key given twice, wrong types and out-of-range values are
refused with a one-line :class:`~koolio_pymunk.store.errors.ConfigError`, and so is a sensor
layout whose keyword would not fit 64 bits (at load, not at the first save). Numbers are
read as YAML 1.2 reads them (``1e-9`` is a number). Values that would make a run
endless or huge have upper bounds (:data:`LIMITS`).

**Profiles.** A configuration may be named instead of given as a file: ``--config paper``
reads the profile shipped in ``koolio_pymunk/profiles/paper.yaml`` (:func:`profile_names`
lists them). A name that ends in ``.yaml``/``.yml`` or contains a path separator is a file.

**Worlds.** ``--world NAME|FILE`` lays a *world* over the configuration: the sections that
describe the world the robot meets rather than the robot's mind (:data:`WORLD_SECTIONS`:
the realism models and the sensor noise). A world never changes the sensor layout, so a
table learned in one world loads in another.
"""

from __future__ import annotations

import copy
import dataclasses
import difflib
import functools
import itertools
import math
import types
import typing
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..robot_runtime import SONAR_PINGS
from .errors import ConfigError, located, shown
from .keyword import COMPASS_LEVELS, MAX_KEYWORD_BITS, N_ACTIONS, KeywordLayout
from .realism_config import RealismConfig, validate_realism
from .yamlfile import dump_yaml, read_yaml

#: Robot profiles (paper §3): radius in inches.
ROBOT_PROFILES: dict[str, float] = {
    "koolio": 10.0,  # a small fridge on a round base, 20 in diameter
    "tjpro": 17.0 / 2.54 / 2.0,  # TJ Pro: 17 cm diameter
}


@dataclass
class RobotConfig:
    profile: str = "koolio"
    """Robot profile: ``koolio`` (20 in diameter) or ``tjpro`` (17 cm)."""
    robot_radius: float | None = None
    """``RobotRadius`` in inches, in [0.5, 60]; None takes the profile's radius (Koolio 10,
    TJ Pro 3.35). A robot 10 ft across would not fit the paper's hallway."""

    @property
    def radius(self) -> float:
        return self.robot_radius if self.robot_radius is not None else ROBOT_PROFILES[self.profile]


@dataclass
class ActionConfig:
    rotate_action_arc_deg: float = 30.0
    """``RotateActionArc`` in degrees, in (0, 360), added (RotateLeft) or subtracted
    (RotateRight).
    The paper gives no value; 30 degrees (12 steps per full turn) is this project's: with
    15, turning round costs twice as many steps and learning needs far more episodes."""
    move_action_distance: float = 12.0
    """``MoveActionDistance`` in inches per Forward / Reverse, in (0, robot diameter]. Not
    given by the paper; half a ceiling tile. Must not exceed the robot's diameter (the
    ``tjpro`` profile, 6.7 in across, needs a shorter move, e.g. 6)."""


@dataclass
class NoiseConfig:
    model: str = "uniform"
    """``uniform``: reading * (1 + U(-n, +n)); ``gaussian``: reading * (1 + N(0, n/2));
    ``none``: no noise at all. n is each sensor's own noise fraction."""
    scale: float = 1.0
    """Multiplies every sensor's noise fraction, in [0, 10] (0 turns noise off; 10 makes
    the paper's 10 % noise 100 %)."""


@dataclass
class SonarConfig:
    sonar_sensors_deg: list[float] = field(
        default_factory=lambda: [0.0, 40.0, 80.0, 135.0, 180.0, -40.0, -80.0, -135.0]
    )
    """``SonarSensors``: angle of each sonar relative to the front, degrees, left positive,
    each in [-360, 360]. The paper gives 1&2 at 40 and 80 front-left and 5&6 at the same
    angles front-right; 0 = front, 3 = rear-left (135), 4 = rear (180) and 7 = rear-right
    are this project's."""
    sonar_arc_deg: float = 55.0
    """``SonarArc``: viewing arc of each sonar, degrees, in (0, 360)."""
    sub_arcs: int = 11
    """Number of smaller arcs each sonar arc is split into, 1..360; one ray through each
    centre."""
    max_range: float = 240.0
    """Longest sonar ray from the robot's edge, inches, in (0, 10,000]; beyond it the
    reading is ``really_long_distance`` (encodes Far). Not in the paper (its rays were
    lines); ultrasonic rangers reach metres, not hundreds of them."""
    noise: float = 0.10
    """Noise fraction, in [0, 1) (paper: ten percent)."""
    pings: int = 1
    """Pings per sonar and reading, odd, 1..9; the sonar reads their median (not in the
    paper, whose simulated sonar is exact; the usual read-out of a real ranger, e.g.
    Arduino NewPing's ``ping_median``). Each ping draws the realism's beam model anew, so
    the median drops a lone wrong echo (``docs/reality-gap.md``); in the ideal world every
    ping hears the same echo and more pings change nothing. The paper's ``noise`` applies
    once, to the median."""
    groups: list[list[int]] = field(default_factory=lambda: [[0], [1, 2], [3], [4], [5, 6], [7]])
    """Sonars whose readings are averaged into one state value, in keyword order
    (paper: 1&2 and 5&6 averaged, leaving 6 values)."""
    thresholds: list[float] = field(default_factory=lambda: [6.0, 24.0, 60.0])
    """Table 6: Bump < 6 <= Close < 24 <= Medium < 60 <= Far (inches); increasing, each
    in [0, 10,000]."""


@dataclass
class CameraConfig:
    camera_sensors_deg: list[float] = field(default_factory=lambda: [0.0, 45.0, -45.0])
    """``CameraSensors``: front, left, right (degrees relative to the front, left positive,
    each in [-360, 360]).
    Camera 0 is the one whose Close goal reading allows the Goal reward. The paper gives
    no angles; +-45 makes the three 45-degree arcs one 135-degree field (at +-90 two blind
    sectors hide a door plate in the middle of the turn towards it)."""
    camera_arc_deg: float = 45.0
    """``CameraArc``: viewing arc, degrees, in (0, 360)."""
    max_camera_view: float = 240.0
    """``MaxCameraView``: farthest reading a camera reports, inches, in (0, 10,000] (not
    in the paper; 10 ceiling tiles)."""
    noise: float = 0.10
    """Noise fraction, in [0, 1) (paper: ten percent)."""
    thresholds: list[float] = field(default_factory=lambda: [36.0, 96.0])
    """Table 7: Close < 36 <= Medium < 96 <= Far (inches); not seen encodes Far.
    Increasing, each in [0, 10,000]."""


@dataclass
class CompassConfig:
    noise: float = 0.25
    """Noise as an angle, a fraction of a full turn, in [0, 1) (paper: 25 percent, why the compass
    was dropped from the state): uniform within +-noise turns (0.25: +-90 degrees) or
    gaussian with sigma noise/2 turns, the same at every heading."""
    in_state: bool = False
    """Add the N/E/S/W compass code to the state (the paper dropped it)."""


#: ``GoalBearing``'s codes: where the goal plate was last seen, from the robot now.
BEARINGS = ("none", "ahead", "left", "behind", "right")


@dataclass
class MemoryConfig:
    """A few bits of the robot's own recent history added to the state (not in the paper;
    off by default). With the paper's side cameras at +-90 degrees the 27-bit state
    aliases: in the blind sectors between the cameras' arcs the robot cannot tell a
    plate it has just passed from one it has not seen yet. Each field added here is one
    more keyword field after the sensors' (:mod:`koolio_pymunk.sensing.memory`)."""

    goal_camera: bool = False
    """Add the camera that last saw the goal plate (none, or camera 0, 1, ...; the
    nearest reading when several see it): ``GoalMemory``, ``n_camera + 1`` levels."""
    eow_camera: bool = False
    """Add the camera that last saw an end-of-world marker: ``EoWMemory``, ``n_camera +
    1`` levels."""
    forget_after: int = 0
    """Forget a camera's sighting after this many steps without one, 0..10,000 (0:
    never)."""
    previous_action: bool = False
    """Add the action taken last (none at the start of an episode, then Stop ...
    Reverse): ``LastAction``, 6 levels."""
    goal_bearing: bool = False
    """Add where the goal plate was last seen, turned with the robot's own turns (dead
    reckoning on the commanded turns): none, ahead, left, behind or right of the robot
    now: ``GoalBearing``, 5 levels. Forgotten like the cameras' sightings
    (``forget_after``)."""

    @property
    def on(self) -> bool:
        """Any memory field in the state."""
        return self.goal_camera or self.eow_camera or self.previous_action or self.goal_bearing


@dataclass
class SensorConfig:
    sonar: SonarConfig = field(default_factory=SonarConfig)
    camera: CameraConfig = field(default_factory=CameraConfig)
    compass: CompassConfig = field(default_factory=CompassConfig)
    memory: MemoryConfig = field(default_factory=MemoryConfig)
    """The robot's memory in the state (off by default: the paper's 27-bit keyword)."""
    noise: NoiseConfig = field(default_factory=NoiseConfig)
    really_long_distance: float = 10_000.0
    """``ReallyLongDistance``: the reading of a sensor that sees nothing, inches, in
    (max(``max_range``, ``max_camera_view``), 1,000,000] (the arenas' coordinate bound)."""
    backend: str = "fast"
    """Ray engine: ``fast`` (a compiled kernel; the same readings, bit for bit on the
    shipped arenas) or ``pymunk`` (pymunk segment queries, the reference). ``cone`` is the
    fast kernel with an exact-cone sonar instead of the paper's sub-arcs (each sonar reads
    the nearest wall point anywhere in its arc; not the paper's model, and its Q-tables
    are kept apart). See ``docs/speed.md``."""


@dataclass
class RewardConfig:
    """Reward values; the first that applies wins (paper §5.4.7). The paper gives none.
    Each is within +-1e15 (every number of a configuration is): Q values then stay
    finite, and a robot's policy file can hold them."""

    goal: float = 100.0
    """The action was Stop and the front camera reads the goal Close."""
    end_of_world: float = -100.0
    """The robot's centre entered an end-of-world zone."""
    bump: float = -5.0
    """Any sonar reads Bump."""
    stop: float = -5.0
    """Stop anywhere else (as dear as a bump: stopping is only for deliveries)."""
    reverse: float = -10.0
    """Dearer than the turn-around it would replace: facing the start's end-of-world
    marker, Reverse - Forward - Reverse... is otherwise a cheap loop between an aliased
    state and the marker's (measured: 89 % greedy goal rate for seed 1 with -2)."""
    turn: float = -1.0
    """RotateLeft or RotateRight."""
    forward: float = -0.5
    """The cheapest action: the task is a long drive down a hallway."""
    robot_bump: float | None = None
    """A sonar reads Bump from another robot's surface (a shared arena, ``--shared-arena``;
    it comes before the wall's ``bump``). None, the default: the ``bump`` value (the
    paper's rule sees no difference between a wall and a robot; docs/multi-robot.md)."""

    def value(self, event: str) -> float:
        """The reward of ``event`` (a term of ``task.rules.TERMS``)."""
        if event == "robot_bump" and self.robot_bump is None:
            return float(self.bump)
        return float(getattr(self, event))


@dataclass
class SharedArenaConfig:
    """Robots sharing one arena (``--shared-arena``; docs/multi-robot.md). Ignored when
    each robot has an arena of its own."""

    start_spread: float = 96.0
    """Start spots lie within this many inches of a robot's start point (0..1000), on a
    square grid one robot diameter plus ``start_gap`` apart, each ``start_gap`` clear of
    the walls and outside the end-of-world zones: a robot starts on a spot drawn from those
    no other robot covers. 96 in gives the hallway's start 6 spots in a row."""
    start_gap: float = 8.0
    """Inches between a spot's robot and the walls, and between the robots of two
    neighbouring spots (0..100): more than the sonar's Bump distance (6 in) with its noise
    (10 %), so no robot starts reading Bump."""
    starts: list[list[float]] = field(default_factory=list)
    """Robot ``k``'s start point ``[x, y]`` (inches, arena coordinates) is ``starts[k]``;
    robots beyond the list (and every robot when it is empty, the default) start from the
    arena's start point. The heading is the arena's (or a random one)."""
    goals: list[str] = field(default_factory=list)
    """Robot ``k``'s goal is ``goals[k]`` (a goal name of the arena); robots beyond the
    list take the run's goal (``--goal``). The crossing example
    (``examples/crossing.yaml``) gives two robots their own starts and goals."""


@dataclass
class RescueConfig:
    auto_rescue_toggle: bool = True
    """``Auto_Rescue_Toggle``."""
    max_steps_before_rescue: int = 200
    """``MaxStepsBeforeRescue``: auto rescue only after this many steps of an episode,
    0..10,000,000 (the step cap's range)."""
    rescue_chance: float = 0.1
    """``Rescue_Chance``: probability of a rescue on a Bump step past the limit, [0, 1]."""
    rescue_max_backup: int = 5
    """``Rescue_Max_Backup``: a rescue backs up 0..this many Reverse moves, 0..100."""


@dataclass
class EpisodeConfig:
    max_steps: int = 1500
    """Step cap, 0..10,000,000; reaching it truncates the episode (not a failure).
    0 = no cap (a warning: a policy that never reaches the goal runs for ever)."""
    clockless_loop_count: int = 100
    """``Clockless_Loop_Count``: steps per timer tick in clockless mode (viewer),
    1..1,000,000."""


@dataclass
class EpsilonSchedule:
    start: float = 0.15
    """Epsilon of the first episode, in [0, 1]."""
    end: float = 0.01
    """Epsilon after ``decay_episodes`` episodes and from then on, in [0, 1]."""
    decay_episodes: int = 600
    """Episodes of linear decay from start to end, 0..1,000,000,000 (0 = constant
    ``start``)."""

    def at(self, episode: int) -> float:
        """Epsilon for ``episode`` (0-based)."""
        if self.decay_episodes <= 0 or episode >= self.decay_episodes:
            return self.end if self.decay_episodes > 0 else self.start
        return self.start + (self.end - self.start) * episode / self.decay_episodes


#: Learning algorithms (``learner.algorithm``); see ``docs/learning.md``.
ALGORITHMS: tuple[str, ...] = ("q", "qlambda", "dyna")
#: Parameters of each algorithm a Q-table's header records (none for ``q``):
#: :func:`~koolio_pymunk.store.run_identity.algorithm_record`.
PARAMETERS: dict[str, tuple[str, ...]] = {
    "q": (),
    "qlambda": ("trace_decay", "trace_cutoff"),
    "dyna": ("planning_steps",),
}


def _default_epsilon() -> EpsilonSchedule:
    """The default learner's exploration: 0.15 to 0.01 over 150 episodes."""
    return EpsilonSchedule(decay_episodes=150)


@dataclass
class LearnerConfig:
    """The learner. The default is Watkins's Q(lambda) (lambda 0.7, alpha 0.1, epsilon
    0.15 to 0.01 over 150 episodes) with the no-undo rule: on ten seeds (0-9) it is
    competent (a greedy goal rate of 90 % on a 100-episode check every 25 episodes) after
    a median 75 episodes, against 325 for the paper's one-step Q with this project's
    earlier default settings (the ``one-step-q`` profile), and 3.29 times fewer episodes
    on ten seeds it was not tuned on (10-19; ``docs/learning.md``). The ``paper``
    profiles keep the paper's learner: one-step Q choosing among all five actions."""

    algorithm: str = "qlambda"
    """``q``: one-step Q-learning, the paper's Table 11 (:mod:`koolio_pymunk.learning.qlearning`);
    ``qlambda`` (the default): Watkins's Q(lambda) with replacing traces
    (:mod:`koolio_pymunk.learning.qlambda`); ``dyna``: Dyna-Q, ``planning_steps`` simulated
    updates per real step from a model of the transitions seen
    (:mod:`koolio_pymunk.learning.dyna`). Not in the paper, which uses one-step Q; the other
    two learn from fewer episodes (``docs/learning.md``)."""
    alpha: float = 0.1
    """Learning rate of the Table 11 update, in (0, 1]. 0.1 with Q(lambda) (the earlier
    search of docs/learning.md); one-step Q learned best with 0.2."""
    gamma: float = 0.98
    """Discount factor, in [0, 1]."""
    epsilon: EpsilonSchedule = field(default_factory=_default_epsilon)
    """Exploration: probability of a uniform random action. The default decays over 150
    episodes, the exploration phase that suits Q(lambda)'s traces, cut at every
    exploratory action (one-step Q did best with 600)."""
    q_init: float = -30.0
    """Value of a Q entry never updated, within +-1e15. Pessimistic on purpose: the greedy
    policy never prefers an action it has not tried over a tried one worth more than -30 (with 0, a
    never-tried Stop wins for ever in a rarely seen state), and an action that loops
    (RotateLeft / RotateRight between two aliased states) sinks below -30 until the
    untried alternative gets its turn (measured with 15-degree turns, seed 0: 96 % greedy
    goal rate after 800 episodes with -30, 72 % with 0)."""
    trace_decay: float = 0.7
    """``qlambda``: lambda in [0, 1], the decay of the eligibility traces per step (with gamma):
    0 is one-step Q, 1 credits every step back to the last exploratory action. 0.7 measured
    best with the default's epsilon (``docs/learning.md``)."""
    trace_cutoff: float = 0.01
    """``qlambda``: a trace below this is dropped, so a step updates a few dozen entries
    (with gamma 0.98 a trace lives 13 steps with lambda 0.7, 37 with lambda 0.9). In
    [1e-6, 1): with lambda 1 a trace of cutoff 1e-6 lives 684 steps; smaller, every step
    would update thousands."""
    planning_steps: int = 10
    """``dyna``: simulated updates from the model after every real step (n in Sutton and
    Barto's Dyna-Q), 0..10,000; 0 is one-step Q that also records the model."""
    no_undo: bool = True
    """Never choose the action that undoes the last one (RotateRight right after
    RotateLeft and back, Reverse right after Forward and back), greedy or exploring, in
    training, evaluation and on the robot (:mod:`koolio_pymunk.task.action_rules`).
    Not in the paper (its learner chooses among all five actions: the ``paper``
    profiles): it breaks the two-step loops of aliased states. On by default."""


@dataclass
class Config:
    """The whole configuration (printed at the start of every command)."""

    robot: RobotConfig = field(default_factory=RobotConfig)
    actions: ActionConfig = field(default_factory=ActionConfig)
    sensors: SensorConfig = field(default_factory=SensorConfig)
    rewards: RewardConfig = field(default_factory=RewardConfig)
    rescue: RescueConfig = field(default_factory=RescueConfig)
    episode: EpisodeConfig = field(default_factory=EpisodeConfig)
    learner: LearnerConfig = field(default_factory=LearnerConfig)
    realism: RealismConfig = field(default_factory=RealismConfig)
    """The realism models (:mod:`koolio_pymunk.sensing.realism`): off unless a world sets them."""
    shared: SharedArenaConfig = field(default_factory=SharedArenaConfig)
    """Robots sharing one arena (``--shared-arena``): their start spots, starts and goals."""

    def validate(self, source: str = "<config>") -> Config:
        """Check ranges; raise ConfigError naming the item. Returns self."""
        _validate(self, source)
        return self

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)

    def to_yaml(self) -> str:
        return dump_yaml(self.to_dict(), sort_keys=False, default_flow_style=None)


#: Shipped configuration profiles: ``<name>.yaml`` in this folder.
PROFILE_DIR = Path(__file__).resolve().parents[1] / "profiles"
#: What a world (``--world``) may set: section -> the keys allowed in it (None: all).
WORLD_SECTIONS: dict[str, tuple[str, ...] | None] = {"realism": None, "sensors": ("noise",)}


def profile_names() -> list[str]:
    """Names of the shipped profiles (``--config NAME`` or ``--world NAME``)."""
    return sorted(p.stem for p in PROFILE_DIR.glob("*.yaml"))


@functools.lru_cache(maxsize=1)
def world_names() -> tuple[str, ...]:
    """Names of the shipped profiles that are worlds (set only :data:`WORLD_SECTIONS`;
    read once).

    >>> world_names()
    ('koolio-real', 'koolio-real-dr')
    """
    out = []
    for name in profile_names():
        data = read_yaml(PROFILE_DIR / f"{name}.yaml", name, ConfigError, MAX_CONFIG_BYTES)
        if isinstance(data, dict) and all(
            _outside_world(str(k), v) is None for k, v in data.items()
        ):
            out.append(name)
    return tuple(out)


def config_path(name: str | Path, flag: str = "--config") -> Path:
    """The file of a profile name, or ``name`` itself when it looks like a path (ends in
    ``.yaml`` or ``.yml``, has a ``/``, or names no profile and an existing file); a name
    that is none of these is one line naming ``flag`` and the profiles it takes. A
    shipped profile's name wins over a file of the working folder of the same name.

    >>> config_path("paper").name, str(config_path("my.yaml"))
    ('paper.yaml', 'my.yaml')
    >>> config_path("koolio-rea", "--world")
    Traceback (most recent call last):
    koolio_pymunk.store.errors.ConfigError: --world: koolio-rea: no such world profile (did you...
    """
    text = str(name)
    if isinstance(name, Path) or text.lower().endswith((".yaml", ".yml")) or "/" in text:
        return Path(name)
    candidate = PROFILE_DIR / f"{text}.yaml"
    world = flag.endswith("world")  # --world, --dr-world
    names = world_names() if world else profile_names()
    if candidate.is_file() and text in names:
        return candidate
    if candidate.is_file():  # a configuration profile given as a world
        raise ConfigError(
            f"{flag}: {text}: a configuration profile, not a world: give it as --config "
            f"{text} (worlds: {', '.join(names)})"
        )
    if Path(text).is_file():  # a file of the working folder named without .yaml
        return Path(text)
    names = ["ideal", *names] if world else names
    close = difflib.get_close_matches(text, names, n=1)
    hint = f" (did you mean '{close[0]}'?)" if close else ""
    what, listed = ("world profile", "worlds") if world else ("profile", "profiles")
    raise ConfigError(
        f"{flag}: {text}: no such {what}{hint} ({listed}: {', '.join(names)}; "
        "a file name ends in .yaml)"
    )


#: Largest configuration or world file read.
MAX_CONFIG_BYTES = 256 * 1024


def read_config_file(path: str | Path, flag: str = "--config") -> tuple[dict, str]:
    """The mapping in a configuration file or profile (``flag``: ``--config`` or
    ``--world``), and the name to report it by."""
    file = config_path(path, flag)
    source = str(path)
    data = read_yaml(file, source, ConfigError, MAX_CONFIG_BYTES, "configuration file")
    return ({} if data is None else data), source


def load_config(
    path: str | Path | None = None,
    overrides: dict | None = None,
    world: str | Path | None = None,
) -> Config:
    """Defaults, then the file or profile ``path`` (if any), then ``overrides``, then the
    world ``world`` (:func:`apply_world`); validated."""
    cfg = Config()
    source = "<defaults>"
    if path is not None:
        data, source = read_config_file(path)
        cfg = _merge(cfg, data, source, "")
    if overrides:
        cfg = _merge(cfg, overrides, source, "")
    cfg.validate(source)
    return apply_world(cfg, world) if world is not None else cfg


def apply_world(cfg: Config, world: str | Path, flag: str = "--world") -> Config:
    """A copy of ``cfg`` with the world file or profile ``world`` laid over it (``flag``
    names where it was given, in errors).

    Only :data:`WORLD_SECTIONS` may appear in a world; anything else is refused, since it
    would change the robot (its sensors' layout, its learner or rewards), not its world.
    ``ideal`` lays nothing over it (the same as no ``--world``).

    >>> apply_world(load_config(), "ideal") == load_config()
    True
    """
    if str(world) == "ideal":
        return copy.deepcopy(cfg)
    data, source = read_config_file(world, flag)
    if not isinstance(data, dict):
        raise ConfigError(located(source, "(top level)", "must be a mapping"))
    allowed = ", ".join(
        k if keys is None else ", ".join(f"{k}.{x}" for x in keys)
        for k, keys in WORLD_SECTIONS.items()
    )
    for key, value in data.items():
        bad = _outside_world(str(key), value)
        if bad is not None:
            raise ConfigError(
                located(source, bad, f"not a world setting (a world sets only: {allowed})")
            )
    return _merge(copy.deepcopy(cfg), data, source, "").validate(source)


def config_from_dict(data: dict, source: str = "<config>") -> Config:
    """A validated Config from a nested mapping (e.g. ``Config().to_dict()``)."""
    return _merge(Config(), data, source, "").validate(source)


def as_config(
    config: Config | Mapping | str | Path | None,
    overrides: Mapping | None = None,
    source: str = "config",
) -> Config:
    """A configuration of its own from what a caller gives (``KoolioEnv(config=...,
    overrides=...)``): a :class:`Config` (copied, never changed), a mapping laid over the
    defaults as a file's sections are (unknown keys and bad values refused in one line
    naming the key, with a did-you-mean), a profile name or a file (:func:`load_config`),
    or None (the defaults); then the mapping ``overrides`` laid over that, the same way.

    >>> as_config({"learner": {"no_undo": True}}).learner.no_undo
    True
    >>> cfg = as_config("paper", {"learner": {"no_undo": True}})
    >>> cfg.learner.no_undo, cfg.rewards.bump
    (True, -12.0)
    >>> as_config({"learner": {"alpah": 0.1}})
    Traceback (most recent call last):
    koolio_pymunk.store.errors.ConfigError: config: learner.alpah: unknown key (did you mean...
    """
    if isinstance(config, Config):
        cfg = copy.deepcopy(config)
    elif isinstance(config, Mapping):
        cfg = config_from_dict(dict(config), source)
    elif config is None or isinstance(config, (str, Path)):
        cfg = load_config(config)
    else:
        raise ConfigError(
            located(
                source, "", f"a profile name, a file, a mapping or a Config, got {shown(config)}"
            )
        )
    if overrides is None:
        return cfg
    if not isinstance(overrides, Mapping):
        raise ConfigError(located("overrides", "", f"a mapping, got {shown(overrides)}"))
    return _merge(cfg, dict(overrides), "overrides", "").validate("overrides")


def _outside_world(key: str, value: Any) -> str | None:
    """The first item of a world's section ``key`` that is not a world setting, if any."""
    if key not in WORLD_SECTIONS:
        return key
    keys = WORLD_SECTIONS[key]
    if keys is None:
        return None
    if not isinstance(value, dict):
        return key
    return next((f"{key}.{k}" for k in value if k not in keys), None)


# --- merging ------------------------------------------------------------------------


#: Keys people write for a setting named otherwise here: the did-you-mean of an unknown key.
KEY_SYNONYMS = {"lambda": "trace_decay", "lamda": "trace_decay", "lam": "trace_decay"}


def _merge(obj: Any, data: Any, source: str, path: str) -> Any:
    if not isinstance(data, dict):
        raise ConfigError(located(source, path or "(top level)", "must be a mapping"))
    hints = typing.get_type_hints(type(obj))
    names = [f.name for f in dataclasses.fields(obj)]
    changes: dict[str, Any] = {}
    for key, value in data.items():
        item = f"{path}.{key}" if path else str(key)
        if key not in names:
            close = [KEY_SYNONYMS[key]] if KEY_SYNONYMS.get(key) in names else []
            close = close or difflib.get_close_matches(str(key), names, n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else f" (valid: {', '.join(names)})"
            raise ConfigError(located(source, item, "unknown key" + hint))
        current = getattr(obj, key)
        if dataclasses.is_dataclass(current):
            changes[key] = _merge(current, value, source, item)
        else:
            changes[key] = _coerce(value, hints[key], source, item)
    return dataclasses.replace(obj, **changes)


def _coerce(value: Any, hint: Any, source: str, item: str) -> Any:
    origin = typing.get_origin(hint)
    args = typing.get_args(hint)
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        inner = [a for a in args if a is not type(None)]
        return _coerce(value, inner[0], source, item)
    if hint is bool:
        if not isinstance(value, bool):
            raise ConfigError(located(source, item, f"expected true or false, got {value!r}"))
        return value
    if hint in (int, float):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(located(source, item, f"expected a number, got {shown(value)}"))
        try:
            number = float(value)
        except OverflowError:  # an integer beyond the float range
            number = math.inf
        if not math.isfinite(number) or abs(number) > MAX_NUMBER:
            raise ConfigError(
                located(source, item, f"must be finite and at most 1e15, got {shown(value)}")
            )
        if hint is int and not number.is_integer():
            raise ConfigError(located(source, item, f"expected an integer, got {shown(value)}"))
        return int(value) if hint is int else number
    if hint is str:
        if not isinstance(value, str):
            raise ConfigError(located(source, item, f"expected a string, got {shown(value)}"))
        return value
    if origin is list:
        if not isinstance(value, list):
            raise ConfigError(located(source, item, f"expected a list, got {shown(value)}"))
        if len(value) > MAX_LIST:
            raise ConfigError(
                located(source, item, f"{len(value):,} entries (the limit is {MAX_LIST})")
            )
        return [_coerce(v, args[0], source, f"{item}[{i}]") for i, v in enumerate(value)]
    if origin is dict and len(args) == 2:  # e.g. realism.randomize: name -> [low, high]
        if not isinstance(value, dict):
            raise ConfigError(located(source, item, f"expected a mapping, got {shown(value)}"))
        if len(value) > MAX_LIST:
            raise ConfigError(
                located(source, item, f"{len(value):,} entries (the limit is {MAX_LIST})")
            )
        return {
            _coerce(k, args[0], source, item): _coerce(v, args[1], source, f"{item}.{k}")
            for k, v in value.items()
        }
    return value


#: Largest magnitude of a number in a configuration (beyond it, floats lose integers).
MAX_NUMBER = 1e15
#: Most entries of a list in a configuration (sensor angles, groups, thresholds).
MAX_LIST = 64


# --- validation -----------------------------------------------------------------------


def _check(ok: bool, source: str, item: str, problem: str) -> None:
    if not ok:
        raise ConfigError(located(source, item, problem))


def _validate(cfg: Config, src: str) -> None:
    _check(
        cfg.robot.profile in ROBOT_PROFILES,
        src,
        "robot.profile",
        f"unknown profile {cfg.robot.profile!r} (valid: {', '.join(ROBOT_PROFILES)})",
    )
    _check(
        MIN_RADIUS <= cfg.robot.radius <= MAX_RADIUS,
        src,
        "robot.robot_radius",
        f"must be in [{MIN_RADIUS:g}, {MAX_RADIUS:g}] inches, got {cfg.robot.radius:g}",
    )
    a = cfg.actions
    _check(
        0 < a.rotate_action_arc_deg < 360,
        src,
        "actions.rotate_action_arc_deg",
        "must be in (0, 360)",
    )
    _check(
        0 < a.move_action_distance <= 2 * cfg.robot.radius,
        src,
        "actions.move_action_distance",
        f"must be in (0, robot diameter {2 * cfg.robot.radius:g}]",
    )
    s = cfg.sensors
    _check(
        s.noise.model in ("uniform", "gaussian", "none"),
        src,
        "sensors.noise.model",
        f"unknown model {s.noise.model!r} (valid: uniform, gaussian, none)",
    )
    _check(s.noise.scale >= 0, src, "sensors.noise.scale", "must be >= 0")
    _check(
        s.backend in ("pymunk", "fast", "cone"),
        src,
        "sensors.backend",
        f"unknown backend {s.backend!r} (valid: fast, pymunk, cone)",
    )
    so = s.sonar
    _check(len(so.sonar_sensors_deg) >= 1, src, "sensors.sonar.sonar_sensors_deg", "empty")
    _check(0 < so.sonar_arc_deg < 360, src, "sensors.sonar.sonar_arc_deg", "must be in (0, 360)")
    _check(so.sub_arcs >= 1, src, "sensors.sonar.sub_arcs", "must be >= 1")
    _check(so.max_range > 0, src, "sensors.sonar.max_range", "must be > 0")
    _check(0 <= so.noise < 1, src, "sensors.sonar.noise", "must be in [0, 1)")
    _check(
        so.pings in SONAR_PINGS,  # the runtime's list, which checks encoding.sonar_pings
        src,
        "sensors.sonar.pings",
        "must be odd, 1 to 9 (the median is read)",
    )
    _check(
        _increasing(so.thresholds) and len(so.thresholds) >= 1,
        src,
        "sensors.sonar.thresholds",
        "must be increasing and non-empty",
    )
    used: list[int] = [i for g in so.groups for i in g]
    _check(
        len(so.groups) >= 1 and all(len(g) >= 1 for g in so.groups),
        src,
        "sensors.sonar.groups",
        "need at least one non-empty group",
    )
    for i in used:
        _check(
            0 <= i < len(so.sonar_sensors_deg),
            src,
            "sensors.sonar.groups",
            f"sonar {i} does not exist (there are {len(so.sonar_sensors_deg)})",
        )
    _check(len(set(used)) == len(used), src, "sensors.sonar.groups", "a sonar is in two groups")
    ca = s.camera
    _check(len(ca.camera_sensors_deg) >= 1, src, "sensors.camera.camera_sensors_deg", "empty")
    _check(0 < ca.camera_arc_deg < 360, src, "sensors.camera.camera_arc_deg", "must be in (0, 360)")
    _check(ca.max_camera_view > 0, src, "sensors.camera.max_camera_view", "must be > 0")
    _check(0 <= ca.noise < 1, src, "sensors.camera.noise", "must be in [0, 1)")
    _check(
        _increasing(ca.thresholds) and len(ca.thresholds) >= 1,
        src,
        "sensors.camera.thresholds",
        "must be increasing and non-empty",
    )
    _check(0 <= s.compass.noise < 1, src, "sensors.compass.noise", "must be in [0, 1)")
    _check(
        s.really_long_distance > max(so.max_range, ca.max_camera_view),
        src,
        "sensors.really_long_distance",
        "must exceed max_range and max_camera_view",
    )
    r = cfg.rescue
    _check(r.max_steps_before_rescue >= 0, src, "rescue.max_steps_before_rescue", "must be >= 0")
    _check(0 <= r.rescue_chance <= 1, src, "rescue.rescue_chance", "must be in [0, 1]")
    _check(r.rescue_max_backup >= 0, src, "rescue.rescue_max_backup", "must be >= 0")
    _check(cfg.episode.max_steps >= 0, src, "episode.max_steps", "must be >= 0 (0 = no cap)")
    _check(
        cfg.episode.clockless_loop_count >= 1, src, "episode.clockless_loop_count", "must be >= 1"
    )
    le = cfg.learner
    _check(0 < le.alpha <= 1, src, "learner.alpha", f"must be in (0, 1], got {le.alpha:g}")
    _check(0 <= le.gamma <= 1, src, "learner.gamma", f"must be in [0, 1], got {le.gamma:g}")
    for name in ("start", "end"):
        value = getattr(le.epsilon, name)
        _check(0 <= value <= 1, src, f"learner.epsilon.{name}", f"must be in [0, 1], got {value:g}")
    _check(le.epsilon.decay_episodes >= 0, src, "learner.epsilon.decay_episodes", "must be >= 0")
    _check(
        le.algorithm in ALGORITHMS,
        src,
        "learner.algorithm",
        f"unknown algorithm {le.algorithm!r} (valid: {', '.join(ALGORITHMS)})",
    )
    _check(
        0 <= le.trace_decay <= 1,
        src,
        "learner.trace_decay",
        f"must be in [0, 1] (lambda), got {le.trace_decay:g}",
    )
    _check(
        MIN_TRACE_CUTOFF <= le.trace_cutoff < 1,
        src,
        "learner.trace_cutoff",
        f"must be in [{MIN_TRACE_CUTOFF:g}, 1)",
    )
    _check(le.planning_steps >= 0, src, "learner.planning_steps", "must be >= 0")
    forget = cfg.sensors.memory.forget_after
    _check(forget >= 0, src, "sensors.memory.forget_after", "must be >= 0 (0: never)")
    validate_realism(cfg.realism, src)
    _check_limits(cfg, src)
    me = cfg.sensors.memory
    _check(
        forget == 0 or me.goal_camera or me.eow_camera or me.goal_bearing,
        src,
        "sensors.memory.forget_after",
        f"{forget} forgets nothing: no sighting is in the state (turn on goal_camera, "
        "eow_camera or goal_bearing, or leave it 0)",
    )
    _check_lists(cfg, src)
    _check_keyword_bits(cfg, src)
    _check_shared(cfg.shared, src)


def _check_shared(sh: SharedArenaConfig, src: str) -> None:
    """The shared arena's section (its points are checked against the arena where the
    robots are placed: :mod:`koolio_pymunk.task.shared_arena`)."""
    _check(0 <= sh.start_spread <= 1000, src, "shared.start_spread", "must be in [0, 1000] inches")
    _check(0 <= sh.start_gap <= 100, src, "shared.start_gap", "must be in [0, 100] inches")
    for k, point in enumerate(sh.starts):
        _check(
            len(point) == 2 and all(math.isfinite(v) for v in point),
            src,
            f"shared.starts[{k}]",
            f"must be a point [x, y] of finite inches, got {point!r}",
        )
    for k, name in enumerate(sh.goals):
        _check(bool(name), src, f"shared.goals[{k}]", "must be a goal name")


#: Upper bounds of values that would otherwise make a run endless or huge:
#: item -> (largest value, why).
LIMITS: dict[str, tuple[float, str]] = {
    "rescue.rescue_max_backup": (100, "each backup is a move; 100 is 100 moves per rescue"),
    "sensors.sonar.sub_arcs": (360, "one ray per sub-arc and sonar at every step"),
    "episode.clockless_loop_count": (1_000_000, "steps per timer tick of the window"),
    "learner.planning_steps": (10_000, "simulated updates of Dyna-Q at every real step"),
    "learner.epsilon.decay_episodes": (10**9, "episodes"),
    "episode.max_steps": (10_000_000, "steps of one episode"),
    "rescue.max_steps_before_rescue": (10_000_000, "steps of one episode"),
    "sensors.noise.scale": (10, "times each sensor's noise fraction"),
    "sensors.memory.forget_after": (10_000, "steps; more than any episode's cap"),
}
#: Upper bounds of the sensors' ranges, inches (checked with the ranges' own order:
#: ``really_long_distance`` above both).
MAX_SENSOR_RANGE = 10_000.0
MAX_REALLY_LONG = 1_000_000.0
#: The robot's radius, inches (see ``RobotConfig.robot_radius``).
MIN_RADIUS, MAX_RADIUS = 0.5, 60.0
#: Smallest ``learner.trace_cutoff`` (see its docstring).
MIN_TRACE_CUTOFF = 1e-6
#: Largest sensor angle and threshold (degrees, inches).
MAX_ANGLE, MAX_THRESHOLD = 360.0, 10_000.0


def _check_limits(cfg: Config, src: str) -> None:
    for item, (most, why) in LIMITS.items():
        value = cfg
        for part in item.split("."):
            value = getattr(value, part)
        shown = f"{int(value):,}" if float(value).is_integer() else f"{value:g}"
        _check(value <= most, src, item, f"must be <= {most:,} ({why}), got {shown}")


def _check_lists(cfg: Config, src: str) -> None:
    """Sensor ranges at most 10,000 inches (``really_long_distance`` 1,000,000), angles in
    [-360, 360] degrees, thresholds in [0, 10,000] inches."""
    s = cfg.sensors
    for item, value, most in (
        ("sensors.sonar.max_range", s.sonar.max_range, MAX_SENSOR_RANGE),
        ("sensors.camera.max_camera_view", s.camera.max_camera_view, MAX_SENSOR_RANGE),
        ("sensors.really_long_distance", s.really_long_distance, MAX_REALLY_LONG),
    ):
        _check(value <= most, src, item, f"must be <= {most:,g} inches, got {value:,g}")
    for item, values, lo, hi in (
        ("sensors.sonar.sonar_sensors_deg", s.sonar.sonar_sensors_deg, -MAX_ANGLE, MAX_ANGLE),
        ("sensors.camera.camera_sensors_deg", s.camera.camera_sensors_deg, -MAX_ANGLE, MAX_ANGLE),
        ("sensors.sonar.thresholds", s.sonar.thresholds, 0.0, MAX_THRESHOLD),
        ("sensors.camera.thresholds", s.camera.thresholds, 0.0, MAX_THRESHOLD),
    ):
        for i, v in enumerate(values):
            _check(lo <= v <= hi, src, f"{item}[{i}]", f"must be in [{lo:g}, {hi:g}], got {v:g}")


def _check_keyword_bits(cfg: Config, src: str) -> None:
    """The sensors' state fields and the action must fit a 64-bit keyword (Table 12)."""
    layout = KeywordLayout(tuple(state_fields(cfg.sensors)), N_ACTIONS)
    _check(
        layout.total_bits <= MAX_KEYWORD_BITS,
        src,
        "sensors",
        f"the keyword would need {layout.total_bits} bits ({len(layout.fields)} state fields); "
        f"it must fit {MAX_KEYWORD_BITS}: use fewer cameras, sonar groups or thresholds",
    )


def _increasing(xs: list[float]) -> bool:
    return all(b > a for a, b in itertools.pairwise(xs))


def state_fields(cfg: SensorConfig) -> list[tuple[str, int]]:
    """``(name, levels)`` of each state field in keyword order (Table 12): the sensors'
    fields (:func:`sensor_fields`), then the memory's (:func:`memory_fields`)."""
    return sensor_fields(cfg) + memory_fields(cfg)


def memory_fields(cfg: SensorConfig) -> list[tuple[str, int]]:
    """``(name, levels)`` of the memory's state fields (:class:`MemoryConfig`).

    >>> cfg = SensorConfig(memory=MemoryConfig(goal_camera=True, previous_action=True))
    >>> memory_fields(cfg)
    [('GoalMemory', 4), ('LastAction', 6)]
    """
    mem, n_cam = cfg.memory, len(cfg.camera.camera_sensors_deg)
    fields = [("GoalMemory", n_cam + 1)] if mem.goal_camera else []
    fields += [("EoWMemory", n_cam + 1)] if mem.eow_camera else []
    fields += [("LastAction", N_ACTIONS + 1)] if mem.previous_action else []
    fields += [("GoalBearing", len(BEARINGS))] if mem.goal_bearing else []
    return fields


def sensor_fields(cfg: SensorConfig) -> list[tuple[str, int]]:
    """``(name, levels)`` of the sensors' state fields: goal cameras, end-of-world cameras,
    sonar groups, then the compass when it is in the state."""
    n_cam = len(cfg.camera.camera_sensors_deg)
    cam_levels = len(cfg.camera.thresholds) + 1
    son_levels = len(cfg.sonar.thresholds) + 1
    fields = [(f"GoalCam{c}", cam_levels) for c in range(n_cam)]
    fields += [(f"EoWCam{c}", cam_levels) for c in range(n_cam)]
    fields += [("Sonar" + "-".join(str(i) for i in g), son_levels) for g in cfg.sonar.groups]
    if cfg.compass.in_state:
        fields.append(("Compass", len(COMPASS_LEVELS)))
    return fields
