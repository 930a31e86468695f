"""The transfer experiment: learn in simulation, hand the policy to the robot, learn on.

``koolio-pm transfer`` runs the paper's whole process as one measured, reproducible
command, with a realistic world (``--world``, default ``koolio-real``) standing in for the
real robot. For every seed, and for two tables (``ideal``: trained in the ideal world;
``dr``: trained with domain randomization, ``--dr-world``):

1. **train** the table in simulation (``--episodes``), or load it (``--qtable``,
   ``--dr-qtable``);
2. **evaluate** its greedy policy in the ideal world and in the realistic world
   (:func:`~koolio_pymunk.learning.evaluation.evaluate`, the figures of ``koolio-pm eval``);
3. **hand it to the robot and keep learning there**: the table is exported
   (:func:`~koolio_pymunk.apps.export.policy_document`), loaded with ``robot_runtime.Policy``
   and driven by ``robot_runtime.RobotLearner`` from raw readings, exactly as on the
   robot: the episode loop of every other command
   (:class:`~koolio_pymunk.learning.episodes.Episodes`) drives the simulated robot with a
   :class:`RobotAgent`, which hands the runtime what a driver would (sonar and camera
   distances in inches, ``env.readings``) and whether the robot is off the end of the
   world; the runtime encodes, chooses, judges rewards (``Policy.judge``), updates, logs
   and saves. Every ``--eval-every`` robot episodes the runtime's greedy policy is
   evaluated in the realistic world (``--eval-episodes`` episodes, through the runtime
   too); counted: the robot episodes until that greedy goal rate reaches ``--target``.

The agent (:class:`RobotAgent`) calls ``RobotLearner`` methods only (``begin``,
``choose``, ``step``, ``moved``, ``end``): how the robot learns is the runtime's
business.

**What the simulator adds as the world.** The episode's truth: an episode the runtime
ends with the goal reward may be a ``wrong_door`` (a misread plate); the log and the
goal rates count it as such. A step cap (``episode.max_steps``) ends an endless episode
(``truncated``, as a person would stop the robot), and the auto rescue of the
configuration moves a stuck robot (the runtime is told with ``moved``), with the same
draws as in the simulator's own episodes. At every step the runtime's judgement is
compared with the simulator's (``judge_mismatches`` in the JSON: 0 expected).

**Evaluation.** 100 greedy episodes (the same starts and seeds at every check, so that
successive checks differ by what was learned, not by the draw of the episodes), every 10
robot episodes: a goal rate of 90 % on 100 episodes is known within about +-3 points
(binomial standard error).

**Seeding.** Training episode ``e`` of seed ``s`` uses the seeds of ``koolio-pm train``
``(s, e)``; greedy evaluation episode ``e`` those of ``koolio-pm eval``; robot episode
``k`` the stream ``(s, k, 2)``, and the runtime's generator ``(s, 2)``. The same command
gives the same JSON apart from its ``timing`` section, and the same tables and logs.

**Outputs** (``--out``, a new or empty folder): ``transfer.json``, ``transfer.png`` (the
curves; skipped with a note without matplotlib) and per seed ``seed-S/``: the trained
tables and their training logs (``ideal.qtable``, ``ideal.csv``, ``dr.qtable``,
``dr.csv``), the policy files the runtime learned into (``ideal-robot.policy.json``,
``dr-robot.policy.json``, saved after every robot episode as on the robot) and the
robot's logs (``ideal-robot.csv``, ``dr-robot.csv``, in ``koolio-pm train``'s format).
"""

from __future__ import annotations

import argparse
import copy
import io
import json
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from .. import robot_runtime as rt
from ..learning.episodes import EVAL_STREAM, ROBOT_STREAM, Episodes
from ..learning.evaluation import evaluate
from ..learning.training import train
from ..store import run_identity
from ..store.config import Config, apply_world
from ..store.errors import KoolioError, QTableError
from ..store.files import atomic_write, atomic_write_text
from ..store.qtable import QTable, QTableStore
from ..task.env import WRONG_DOOR, KoolioEnv
from .export import load_any_table, policy_document, write_policy

FORMAT = "koolio-transfer"
VERSION = 1
SOURCES = ("ideal", "dr")
"""The two tables handed to the robot: trained in the ideal world, and with domain
randomization."""

Report = Callable[[str], None]


@dataclass
class TransferConfig:
    """Settings of one transfer experiment (the flags of ``koolio-pm transfer``)."""

    arena: str = "hallway"
    """Arena file or built-in name."""
    config: str | None = None
    """Configuration file or profile: the robot, its sensors, learner and rewards."""
    goal: str | None = None
    """Goal (door) name; default the arena's active goal."""
    world: str = "koolio-real"
    """The realistic world that stands in for the robot (a profile name or a world file)."""
    dr_world: str = "koolio-real-dr"
    """The world of the domain-randomized training (the ``dr`` table)."""
    seeds: tuple[int, ...] = (0,)
    """Run seeds; each one repeats the whole experiment."""
    episodes: int = 1500
    """Training episodes in simulation, for each table that is not loaded."""
    qtable: str | None = None
    """Load the ``ideal`` table from this file (``.qtable`` or policy) instead of training;
    ``{seed}`` in the name stands for the run seed (a table per seed)."""
    dr_qtable: str | None = None
    """Load the ``dr`` table from this file instead of training (``{seed}`` as above)."""

    def table_file(self, source: str, seed: int) -> str | None:
        """The file to load the ``source`` table from for ``seed`` (None: train it)."""
        given = self.qtable if source == "ideal" else self.dr_qtable
        return None if given is None else given.replace("{seed}", str(seed))

    robot_episodes: int = 100
    """Learning episodes on the (simulated) robot, through the runtime."""
    eval_episodes: int = 100
    """Episodes of each greedy evaluation."""
    eval_every: int = 10
    """Robot episodes between two greedy evaluations in the realistic world."""
    target: float = 0.9
    """Greedy goal rate counted as recovered."""
    robot_alpha: float | None = None
    """The runtime's learning rate (default: the configuration's ``learner.alpha``)."""
    robot_epsilon: float | None = None
    """The runtime's exploration (default: what ``koolio-pm export`` writes, the epsilon
    schedule's value at the table's episode count)."""

    def validate(self) -> None:
        """Check what the flags' types cannot (each number's range is checked once, where
        argparse reads the flag: :mod:`koolio_pymunk.apps.flags`); :class:`KoolioError`
        (one line) naming the flag."""
        if not self.seeds:
            raise KoolioError("--seed: needs at least one seed")
        if len(set(self.seeds)) != len(self.seeds):
            raise KoolioError("--seed: repeated seed")
        if self.goal == "random":
            raise KoolioError("--goal: random: the experiment delivers to one door (name it)")


# -- the robot ---------------------------------------------------------------------------------
def raw_readings(env: KoolioEnv) -> tuple[list[float], list[float], list[float]]:
    """``(sonar, goal_cam, eow_cam)``: what a robot's driver hands ``Policy.encode``, the
    distances in inches from the robot's edge after the world's realism models and noise
    (``really_long_distance``, which encodes Far, when nothing is seen)."""
    r = env.readings
    return r.sonar.tolist(), r.goal.tolist(), r.eow.tolist()


class RobotAgent:
    """The robot runtime's learner as the agent of the episode loop, fed raw readings.

    :class:`~koolio_pymunk.learning.episodes.Episodes` drives the simulated robot (its
    moves, realism models, step cap and auto rescue, with the draws of every other
    episode loop); this agent gives the runtime what a real Koolio's driver would: the
    raw readings (:func:`raw_readings`) and whether the robot is off the end of the world
    (the env's zones). The runtime encodes them, chooses, judges the reward
    (``Policy.judge``) and learns when its ``learn`` flag says so; after a rescue it is
    told with ``moved``. It calls ``RobotLearner`` methods only (``begin``, ``choose``,
    ``step``, ``moved``): how the robot learns is the runtime's business. The runtime's
    judgement of every step is compared with the simulator's (:attr:`mismatches`).
    """

    def __init__(self, env: KoolioEnv, policy: rt.Policy, learner: rt.RobotLearner) -> None:
        self.env = env
        self.policy = policy
        self.learner = learner
        self.memory = policy.new_memory()
        """The runtime's memory of the episode (used when the policy's state has one)."""
        self.mismatches = 0
        """Steps of this episode where the runtime's (reward, terminal) differed."""

    @property
    def epsilon(self) -> float:
        """The runtime's exploration rate."""
        return self.learner.epsilon

    @epsilon.setter
    def epsilon(self, value: float) -> None:
        self.learner.epsilon = value

    def begin_episode(self, episode: int, rng: np.random.Generator) -> None:
        """A new episode: the runtime encodes the first reading (it has its own
        generator: ``rng`` is not used)."""
        self.memory.reset()
        self.learner.begin(self._encode(None))
        self.mismatches = 0

    def act(self, state: int) -> int:
        """The runtime's choice."""
        return self.learner.choose()

    def observe(
        self, state: int, action: int, reward: float, next_state: int, terminal: bool
    ) -> None:
        """The runtime judges the step from raw readings and learns from it."""
        policy = self.policy
        sonar, goal, _ = raw_readings(self.env)
        x, y, _ = self.env.world.pose(0)
        off_the_end = self.env.zones.contains(x, y)
        _, r, term = policy.judge(action, sonar, goal, end_of_world=off_the_end)
        self.mismatches += (r, term) != (reward, terminal)
        bump = policy.bump(sonar)
        self.learner.step(action, r, self._encode(action), term, bump=bump)

    def relocated(self, state: int) -> None:
        """A rescue moved the robot: the runtime reads where it now is."""
        self.learner.moved(self._encode(None))

    def _encode(self, action: int | None) -> tuple[int, ...]:
        """The runtime's state codes of the current raw readings (its memory updated)."""
        return self.policy.encode(*raw_readings(self.env), memory=self.memory, action=action)


@dataclass
class RobotEpisode:
    """One episode of the runtime on the simulated robot."""

    outcome: str
    """True outcome: ``goal``, ``wrong_door``, ``end_of_world`` or ``truncated``."""
    steps: int
    bumps: int
    reward: float
    """Sum of the rewards the runtime judged."""
    rescued: bool
    mismatches: int = 0
    """Steps where the runtime's (reward, terminal) differed from the simulator's."""


def drive_episode(loop: Episodes, episode: int, finish: bool = True) -> RobotEpisode:
    """Episode ``episode`` of ``loop`` (whose agent is a :class:`RobotAgent`), as the
    runtime runs one on the robot; ``finish`` ends it with ``learner.end`` (its log row and
    the atomic save), which a greedy check leaves out."""
    agent = loop.agent
    assert isinstance(agent, RobotAgent)
    loop.begin(episode)
    outcome = loop.run().outcome
    learner = agent.learner
    result = RobotEpisode(
        outcome, learner.steps, learner.bumps, learner.reward, learner.rescued, agent.mismatches
    )
    if finish:
        learner.end(outcome)
    return result


# -- greedy checks and the robot's learning ------------------------------------------------------
@dataclass
class Check:
    """A greedy evaluation through the runtime, after ``episode`` robot episodes."""

    episode: int
    goal_rate: float
    wrong_door_rate: float
    end_of_world_rate: float
    truncated_rate: float
    mean_steps: float
    mean_bumps: float
    mean_reward: float


def _int_seed(*words: int) -> int:
    return int(np.random.SeedSequence(list(words)).generate_state(1)[0])


def greedy_check(
    env: KoolioEnv, policy: rt.Policy, episodes: int, seed: int, after: int = 0
) -> Check:
    """The runtime's greedy goal rate on ``episodes`` episodes (the starts and seeds of
    ``koolio-pm eval --seed seed``; ties broken by a generator seeded per episode)."""
    runs = []
    for e in range(episodes):
        learner = rt.RobotLearner(policy, learn=False, seed=_int_seed(seed, e, EVAL_STREAM, 2))
        loop = Episodes(env, RobotAgent(env, policy, learner), seed, EVAL_STREAM)
        runs.append(drive_episode(loop, e, finish=False))
    n = max(1, len(runs))
    outcomes = [r.outcome for r in runs]
    return Check(
        episode=after,
        goal_rate=outcomes.count("goal") / n,
        wrong_door_rate=outcomes.count(WRONG_DOOR) / n,
        end_of_world_rate=outcomes.count("end_of_world") / n,
        truncated_rate=outcomes.count("truncated") / n,
        mean_steps=float(np.mean([r.steps for r in runs])),
        mean_bumps=float(np.mean([r.bumps for r in runs])),
        mean_reward=float(np.mean([r.reward for r in runs])),
    )


@dataclass
class RobotPhase:
    """Learning on the (simulated) robot through the runtime, with its greedy checks."""

    alpha: float
    epsilon: float
    checks: list[Check]
    episodes: list[RobotEpisode]
    recovered_at: int | None
    """Robot episodes until the first check at or above the target (None: not within the
    budget)."""
    seconds: float = 0.0

    def as_dict(self) -> dict[str, Any]:
        eps = self.episodes
        return {
            "alpha": self.alpha,
            "epsilon": self.epsilon,
            "recovered_at": self.recovered_at,
            "checks": [asdict(c) for c in self.checks],
            "learning": {
                "episodes": len(eps),
                "goal_rate": _share(eps, "goal"),
                "wrong_door_rate": _share(eps, WRONG_DOOR),
                "mean_steps": _mean([e.steps for e in eps]),
                "mean_bumps": _mean([e.bumps for e in eps]),
                "judge_mismatches": sum(e.mismatches for e in eps),
                "outcomes": [e.outcome for e in eps],
                "steps": [e.steps for e in eps],
                "bumps": [e.bumps for e in eps],
            },
        }


def _share(eps: list[RobotEpisode], outcome: str) -> float:
    return sum(e.outcome == outcome for e in eps) / max(1, len(eps))


def _mean(values: list[int]) -> float:
    return float(np.mean(values)) if values else 0.0


def robot_learning(
    env: KoolioEnv,
    policy_path: Path,
    cfg: TransferConfig,
    seed: int,
    log_path: Path | None = None,
    say: Report | None = None,
) -> RobotPhase:
    """Load the exported policy with the runtime and learn ``cfg.robot_episodes`` episodes
    on ``robot``, saving it after each one (as the robot does); a greedy check at the
    start and every ``cfg.eval_every`` episodes."""
    started = time.perf_counter()
    policy = rt.Policy.load(str(policy_path))
    learner = rt.RobotLearner(
        policy,
        save_path=str(policy_path),
        log_path=None if log_path is None else str(log_path),
        seed=_int_seed(seed, ROBOT_STREAM),
        goal=env.goal_name,
    )
    loop = Episodes(env, RobotAgent(env, policy, learner), seed, ROBOT_STREAM)
    checks = [greedy_check(env, policy, cfg.eval_episodes, seed)]
    _say_check(say, checks[-1], cfg, 0, started)
    episodes: list[RobotEpisode] = []
    for k in range(cfg.robot_episodes):
        episodes.append(drive_episode(loop, k))
        if (k + 1) % cfg.eval_every == 0 or k + 1 == cfg.robot_episodes:
            checks.append(greedy_check(env, policy, cfg.eval_episodes, seed, after=k + 1))
            _say_check(say, checks[-1], cfg, sum(e.outcome == "goal" for e in episodes), started)
    recovered = next((c.episode for c in checks if c.goal_rate >= cfg.target), None)
    alpha = float(policy.learner["alpha"])
    return RobotPhase(
        alpha, learner.epsilon, checks, episodes, recovered, time.perf_counter() - started
    )


def _say_check(say: Report | None, c: Check, cfg: TransferConfig, goals: int, t0: float) -> None:
    if say is not None:
        say(
            f"robot episode {c.episode:>4}/{cfg.robot_episodes}: greedy goal rate "
            f"{c.goal_rate:6.1%} in {cfg.world} ({cfg.eval_episodes} episodes, "
            f"{c.mean_bumps:.1f} bumps/ep); {goals} learning episodes at the goal; "
            f"{time.perf_counter() - t0:.0f} s"
        )


# -- one table, one seed -----------------------------------------------------------------------
def make_env(cfg: TransferConfig, world: str | None) -> KoolioEnv:
    """The experiment's environment in ``world`` (None: the ideal world)."""
    return KoolioEnv(arena=cfg.arena, config=cfg.config, goal=cfg.goal, world=world)


def robot_config(config: Config, cfg: TransferConfig) -> Config:
    """The configuration exported with the policy: the runtime's alpha and epsilon."""
    out = copy.deepcopy(config)
    if cfg.robot_alpha is not None:
        out.learner.alpha = cfg.robot_alpha
    if cfg.robot_epsilon is not None:
        out.learner.epsilon.start = out.learner.epsilon.end = cfg.robot_epsilon
        out.learner.epsilon.decay_episodes = 0
    return out


def obtain_table(
    cfg: TransferConfig, source: str, seed: int, folder: Path, say: Report | None
) -> tuple[QTable, str, float]:
    """Step 1: the ``source`` table, trained (seed ``seed``) or loaded; its file name
    (relative to the output folder when trained) and the training seconds."""
    world = None if source == "ideal" else cfg.dr_world
    env = make_env(cfg, world)
    given = cfg.table_file(source, seed)
    if given is not None:
        return load_any_table(given), given, 0.0  # checked by preflight
    name = f"{source}.qtable"
    report = None if say is None else (lambda line: say(f"training: {line}"))
    result = train(
        env,
        QTableStore(folder / name),
        cfg.episodes,
        seed,
        folder / f"{source}.csv",
        report=report,
        report_every=10.0,
    )
    if result.interrupted:  # Ctrl-C or SIGTERM, taken by train: its files saved; stop here
        raise KeyboardInterrupt
    return result.table, f"{folder.name}/{name}", result.seconds


def run_source(
    cfg: TransferConfig, source: str, seed: int, folder: Path, say: Report | None = None
) -> tuple[dict[str, Any], dict[str, float]]:
    """Steps 1-3 for one table and one seed; returns its JSON record and its timing."""
    table, table_name, train_seconds = obtain_table(cfg, source, seed, folder, say)
    ideal_env, real_env = make_env(cfg, None), make_env(cfg, cfg.world)
    greedy = {
        "ideal": evaluate(ideal_env, table, cfg.eval_episodes, seed).as_dict(),
        "real": evaluate(real_env, table, cfg.eval_episodes, seed).as_dict(),
    }
    if say is not None:
        say(
            f"greedy goal rate (simulator, {cfg.eval_episodes} episodes): ideal "
            f"{greedy['ideal']['goal_rate']:.1%}, {cfg.world} {greedy['real']['goal_rate']:.1%}"
        )
    policy_path = folder / f"{source}-robot.policy.json"
    doc = policy_document(table, robot_config(real_env.config, cfg), source=table_name)
    doc["world"] = cfg.world
    write_policy(doc, policy_path)
    robot_env = make_env(cfg, cfg.world)
    log_path = folder / f"{source}-robot.csv"
    try:
        phase = robot_learning(robot_env, policy_path, cfg, seed, log_path, say)
    except rt.PolicyError as exc:  # pragma: no cover - the export validated the document
        raise QTableError(str(exc)) from None
    record = {
        "seed": seed,
        "source": source,
        "trained_in": "ideal" if source == "ideal" else cfg.dr_world,
        "table": table_name,
        "table_episodes": int(table.meta.get("episodes", 0)),
        "table_states": len(table),
        "greedy": greedy,
        "robot": {
            "policy": f"{folder.name}/{policy_path.name}",
            "log": f"{folder.name}/{log_path.name}",
            **phase.as_dict(),
        },
    }
    timing = {"train_seconds": train_seconds, "robot_seconds": phase.seconds}
    return record, timing


# -- the whole experiment ----------------------------------------------------------------------
@dataclass
class TransferResult:
    """Everything ``transfer.json`` holds."""

    cfg: TransferConfig
    runs: list[dict[str, Any]] = field(default_factory=list)
    timing: list[dict[str, Any]] = field(default_factory=list)
    seconds: float = 0.0

    def as_dict(self) -> dict[str, Any]:
        return {
            "format": FORMAT,
            "version": VERSION,
            "settings": {f.name: _plain(getattr(self.cfg, f.name)) for f in fields(self.cfg)},
            "summary": summary(self.runs),
            "runs": self.runs,
            "timing": {"seconds": self.seconds, "runs": self.timing},
        }


def _plain(v: Any) -> Any:
    return list(v) if isinstance(v, tuple) else v


def opening_line(cfg: TransferConfig, out: Path) -> str:
    """``transfer``'s first line: what it trains or loads, where the robot learns, the
    output folder."""
    loaded = [s for s in SOURCES if cfg.table_file(s, cfg.seeds[0]) is not None]
    tables = "tables" if not loaded else f"tables ({', '.join(loaded)} loaded)"
    seeds = ", ".join(str(s) for s in cfg.seeds)
    return (
        f"transfer: seed{'s' if len(cfg.seeds) > 1 else ''} {seeds}: {tables} from the ideal "
        f"world and {cfg.dr_world}, each handed to the robot in {cfg.world} for "
        f"{cfg.robot_episodes} episodes; -> {out} (--verbose: every setting)"
    )


def settings(cfg: TransferConfig, out: Path) -> list[tuple[str, str]]:
    """``transfer --verbose``: every setting as it resolved (a default named by its
    value, never ``None``)."""
    from .cli import config_label, count, goal_label

    env = make_env(cfg, None)
    learner = env.config.learner

    def table(source: str) -> str:
        given = cfg.table_file(source, cfg.seeds[0])
        world = "the ideal world" if source == "ideal" else cfg.dr_world
        if given is None:
            return f"trained for {cfg.episodes} episodes in {world} (seed-S/{source}.qtable)"
        return f"loaded from {cfg.qtable if source == 'ideal' else cfg.dr_qtable}"

    alpha = cfg.robot_alpha
    epsilon = cfg.robot_epsilon
    trained_eps = learner.epsilon.at(cfg.episodes)
    return [
        ("arena", f"{env.arena.name} ({env.arena.source})"),
        ("config", config_label(cfg.config)),
        ("goal", goal_label(env, cfg.goal)),
        ("world (the robot's)", config_label(cfg.world, "--world")),
        ("dr-world", config_label(cfg.dr_world, "--dr-world")),
        ("seeds", ", ".join(str(s) for s in cfg.seeds)),
        ("ideal table", table("ideal")),
        ("dr table", table("dr")),
        ("robot episodes", str(cfg.robot_episodes)),
        (
            "greedy checks",
            f"{count(cfg.eval_episodes, 'episode')} every {count(cfg.eval_every, 'robot episode')}",
        ),
        ("target", f"{cfg.target:g} (greedy goal rate counted as recovered)"),
        ("robot alpha", f"{alpha:g}" if alpha is not None else f"{learner.alpha:g} (config's)"),
        (
            "robot epsilon",
            f"{epsilon:g}"
            if epsilon is not None
            else f"the schedule's at the table's episode count ({trained_eps:g} after "
            f"{cfg.episodes})",
        ),
        ("out", str(out)),
    ]


def check_output(out: Path) -> None:
    """Refuse an output folder that holds anything (never overwrite an earlier run)."""
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise KoolioError(
            f"{out}: --out: not a new or empty folder (an earlier run?): choose another --out"
        )


def preflight(cfg: TransferConfig, out: Path) -> None:
    """Every input checked before anything is written: flags, worlds, goal, the tables to
    load (:func:`~koolio_pymunk.store.run_identity.check`, purpose ``transfer``), the
    output folder."""
    cfg.validate()
    env = make_env(cfg, None)
    for world, flag in ((cfg.world, "--world"), (cfg.dr_world, "--dr-world")):
        apply_world(env.config, world, flag)  # a bad name or file: one line naming its flag
        make_env(cfg, world)
    for seed in cfg.seeds:
        for source in SOURCES:
            given = cfg.table_file(source, seed)
            if given is not None:  # checked for the run that would have trained it
                trained_in = make_env(cfg, None if source == "ideal" else cfg.dr_world)
                run_identity.check(load_any_table(given), trained_in, "transfer", given)
    check_output(out)


def run_transfer(cfg: TransferConfig, out: Path, say: Report | None = print) -> TransferResult:
    """The whole experiment into ``out`` (see the module docstring); writes
    ``transfer.json`` and returns its content."""
    preflight(cfg, out)
    started = time.perf_counter()
    result = TransferResult(cfg)
    for seed in cfg.seeds:
        folder = out / f"seed-{seed}"
        folder.mkdir(parents=True, exist_ok=True)
        for source in SOURCES:
            label = f"seed {seed}, {source} table"
            line = None if say is None else (lambda s, label=label: say(f"[{label}] {s}"))
            record, timing = run_source(cfg, source, seed, folder, line)
            result.runs.append(record)
            result.timing.append({"seed": seed, "source": source, **timing})
    result.seconds = time.perf_counter() - started
    write_json(result, out / "transfer.json")
    return result


def write_json(result: TransferResult, path: Path) -> None:
    atomic_write_text(path, json.dumps(result.as_dict(), indent=1) + "\n")


def summary(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Per table, over seeds: greedy goal rates, the ideal-to-real drop, recoveries."""
    out: dict[str, Any] = {}
    for source in SOURCES:
        rs = [r for r in runs if r["source"] == source]
        if not rs:
            continue
        ideal = [r["greedy"]["ideal"]["goal_rate"] for r in rs]
        real = [r["greedy"]["real"]["goal_rate"] for r in rs]
        after = [r["robot"]["checks"][-1]["goal_rate"] for r in rs]
        recovered = [r["robot"]["recovered_at"] for r in rs]
        out[source] = {
            "ideal_goal_rate": _mean_f(ideal),
            "real_goal_rate": _mean_f(real),
            "drop": _mean_f(ideal) - _mean_f(real),
            "after_robot_goal_rate": _mean_f(after),
            "recovered": sum(x is not None for x in recovered),
            "recovered_within_budget": all(x is not None for x in recovered),
            "recovered_at": recovered,
            "seeds": len(rs),
        }
    return out


def _mean_f(values: list[float]) -> float:
    return float(np.mean(values)) if values else 0.0


# -- table and curves ------------------------------------------------------------------------
def table_lines(result: dict[str, Any]) -> list[str]:
    """The printed table: one row per seed and table."""
    s = result["settings"]
    world, n = s["world"], s["robot_episodes"]
    head = (
        f"{'seed':>4}  {'trained in':<16} {'ideal':>6} {world[:12]:>12} "
        f"{'recovered':>10} {'after ' + str(n):>10} {'bumps/ep greedy':>16} "
        f"{'bumps/ep learning':>18}"
    )
    lines = [
        f"greedy goal rates ({s['eval_episodes']} episodes; ideal and {world} by the simulator, "
        f"then through robot_runtime every {s['eval_every']} robot episodes); "
        f"recovered: robot episodes to >= {s['target']:.0%}",
        head,
    ]
    for r in result["runs"]:
        checks = r["robot"]["checks"]
        rec = r["robot"]["recovered_at"]
        bumps = f"{checks[0]['mean_bumps']:.1f} -> {checks[-1]['mean_bumps']:.1f}"
        lines.append(
            f"{r['seed']:>4}  {r['trained_in'][:16]:<16} {r['greedy']['ideal']['goal_rate']:>6.0%} "
            f"{r['greedy']['real']['goal_rate']:>12.0%} "
            f"{('not in ' + str(n)) if rec is None else str(rec):>10} "
            f"{checks[-1]['goal_rate']:>10.0%} {bumps:>16} "
            f"{r['robot']['learning']['mean_bumps']:>18.1f}"
        )
    for source, sm in result["summary"].items():
        trained = "the ideal world" if source == "ideal" else s["dr_world"]
        lines.append(
            f"trained in {trained}: greedy {sm['ideal_goal_rate']:.1%} in the ideal world, "
            f"{sm['real_goal_rate']:.1%} in {world} (ideal minus real: "
            f"{100 * sm['drop']:.1f} points); >= {s['target']:.0%} in {world} within {n} robot "
            f"episodes for {sm['recovered']} of {sm['seeds']} seeds"
        )
    return lines


COLOURS = {"ideal": "tab:red", "dr": "tab:blue"}


def plot_transfer(result: dict[str, Any], out: Path) -> Path:
    """``transfer.png``: the greedy goal rate and bumps per episode in the realistic world
    against the robot episodes learned, one line per seed, one colour per table."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = result["settings"]
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 5.2), layout="constrained")
    before = -max(1.0, 0.06 * s["robot_episodes"])
    seen: set[str] = set()
    for r in result["runs"]:
        xs = [c["episode"] for c in r["robot"]["checks"]]
        colour = COLOURS.get(r["source"], "tab:gray")
        label = None if r["source"] in seen else f"trained in {r['trained_in']}"
        seen.add(r["source"])
        for ax, key, scale in ((ax1, "goal_rate", 100.0), (ax2, "mean_bumps", 1.0)):
            ys = [scale * c[key] for c in r["robot"]["checks"]]
            ax.plot(xs, ys, color=colour, marker="o", markersize=3, alpha=0.8, label=label)
        ideal = 100.0 * r["greedy"]["ideal"]["goal_rate"]
        ax1.plot([before, 0], [ideal, ys_at_0(r)], color=colour, linestyle=":", alpha=0.8)
        ax1.plot([before], [ideal], color=colour, marker="o", markerfacecolor="white")
    ax1.plot([], [], color="gray", marker="o", markerfacecolor="white", linestyle=":",
             label="the same table in the ideal world")  # fmt: skip
    ax1.axvline(0, color="gray", linewidth=0.8)
    ax1.axhline(100.0 * s["target"], color="black", linestyle="--", linewidth=1, label="target")
    ax1.set(
        title=f"greedy goal rate in {s['world']} (through robot_runtime)",
        xlabel="robot learning episodes",
        ylabel=f"% of {s['eval_episodes']} greedy episodes at the goal",
        ylim=(-2, 102),
    )
    ax2.set(
        title=f"bumps per greedy episode in {s['world']}",
        xlabel="robot learning episodes",
        ylabel="mean bumps per episode",
    )
    ax2.set_yscale("log")
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
    fig.legend(*ax1.get_legend_handles_labels(), loc="outside lower center", ncols=4)
    seeds = ", ".join(str(x) for x in s["seeds"])
    fig.suptitle(
        f"transfer to {s['world']}: {s['arena']}, seeds {seeds}, one line per seed "
        f"(robot alpha and epsilon: {_robot_settings(result)})"
    )
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    plt.close(fig)
    atomic_write(out, buf.getvalue())
    return out


def ys_at_0(run: dict[str, Any]) -> float:
    """The greedy goal rate (%) of a run's first check, before any robot learning."""
    return 100.0 * run["robot"]["checks"][0]["goal_rate"]


def _robot_settings(result: dict[str, Any]) -> str:
    pairs = sorted({(r["robot"]["alpha"], r["robot"]["epsilon"]) for r in result["runs"]})
    return "; ".join(f"{a:g}, {e:g}" for a, e in pairs)


def plot_or_note(result: dict[str, Any], out: Path, say: Report) -> None:
    """:func:`plot_transfer`, or a note naming the extra when matplotlib is not installed
    (the runs are done and saved: a missing plot is no reason to fail)."""
    from ..store.extras import MissingExtra, view_extra

    try:
        with view_extra("transfer"):
            plot_transfer(result, out)
    except MissingExtra as exc:
        say(f"note: {exc}; {out.name} skipped")
        return
    say(f"curves -> {out}")


# -- command line ------------------------------------------------------------------------------
def add_arguments(p: argparse.ArgumentParser) -> None:
    from .flags import MAX_EPISODES, file_name, float_type, int_type, seed_type

    d = TransferConfig()
    episodes, probability = int_type(0, MAX_EPISODES), float_type(0.0, 1.0)
    p.add_argument("--arena", type=file_name, default=d.arena, help="arena file or built-in name")
    p.add_argument(
        "--config", type=file_name, default=None, help="YAML configuration file or profile name"
    )
    p.add_argument("--goal", default=None, help="goal (door) name (default: the arena's)")
    p.add_argument(
        "--world",
        type=file_name,
        default=d.world,
        help=f"the realistic world standing in for the robot (default {d.world})",
    )
    p.add_argument(
        "--dr-world",
        type=file_name,
        default=d.dr_world,
        help=f"world of the domain-randomized training (default {d.dr_world})",
    )
    p.add_argument(
        "--seed",
        type=seed_type,
        nargs="+",
        default=[0],
        help="run seeds, 0..2**63-1 (default 0), e.g. --seed 0 1 2",
    )
    p.add_argument(
        "--episodes",
        type=episodes,
        default=d.episodes,
        help=f"training episodes in simulation per table (default {d.episodes})",
    )
    p.add_argument(
        "--qtable",
        type=file_name,
        default=None,
        help="load the ideal-world table instead of training ({seed}: the run seed)",
    )
    p.add_argument(
        "--dr-qtable",
        type=file_name,
        default=None,
        help="load the randomized table instead of training",
    )
    p.add_argument(
        "--robot-episodes",
        type=episodes,
        default=d.robot_episodes,
        help=f"learning episodes on the robot, through robot_runtime (default {d.robot_episodes})",
    )
    p.add_argument(
        "--eval-episodes",
        type=int_type(1, MAX_EPISODES),
        default=d.eval_episodes,
        help=f"episodes per greedy evaluation (default {d.eval_episodes})",
    )
    p.add_argument(
        "--eval-every",
        type=int_type(1, MAX_EPISODES),
        default=d.eval_every,
        help=f"robot episodes between greedy evaluations (default {d.eval_every})",
    )
    p.add_argument(
        "--target",
        type=probability,
        default=d.target,
        help=f"greedy goal rate counted as recovered (default {d.target})",
    )
    p.add_argument(
        "--robot-alpha",
        type=float_type(0.0, 1.0, low_open=True),
        default=None,
        help="the runtime's alpha, (0, 1] (default: config's)",
    )
    p.add_argument(
        "--robot-epsilon",
        type=probability,
        default=None,
        help="the runtime's epsilon (default: the exported one, the schedule's at the table's "
        "episode count)",
    )
    p.add_argument(
        "--out",
        type=file_name,
        default="runs/transfer",
        help="new or empty output folder (default runs/transfer)",
    )
    p.add_argument("--no-plot", action="store_true", help="do not draw transfer.png")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.add_argument(
        "--verbose",
        action="store_true",
        help="also print the experiment's settings as they resolved, before it starts",
    )


def config_from_args(args: argparse.Namespace) -> TransferConfig:
    return TransferConfig(
        arena=args.arena,
        config=args.config,
        goal=args.goal,
        world=args.world,
        dr_world=args.dr_world,
        seeds=tuple(args.seed),
        episodes=args.episodes,
        qtable=args.qtable,
        dr_qtable=args.dr_qtable,
        robot_episodes=args.robot_episodes,
        eval_episodes=args.eval_episodes,
        eval_every=args.eval_every,
        target=args.target,
        robot_alpha=args.robot_alpha,
        robot_epsilon=args.robot_epsilon,
    )


def run(args: argparse.Namespace) -> int:
    cfg = config_from_args(args)
    out = Path(args.out)
    say: Report | None = None if args.quiet else print
    preflight(cfg, out)  # an error is the only line printed
    if say is not None:
        say(opening_line(cfg, out))
        if args.verbose:
            for key, value in settings(cfg, out):
                say(f"  {key}: {value}")
    result = run_transfer(cfg, out, say).as_dict()
    for line in table_lines(result):
        print(line)
    print(f"-> {out / 'transfer.json'} ({result['timing']['seconds']:.0f} s)")
    if not args.no_plot:
        plot_or_note(result, out / "transfer.png", print)
    return 0
