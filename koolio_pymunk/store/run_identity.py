"""What a Q-table is, where it came from, and who may use it: one identity, checked once.

A table records the run it was learned by (its header, :mod:`~koolio_pymunk.store.qtable`):
the keyword layout, the sensors it read (:func:`sensor_signature`), the arena, the goal
and the world, the learning algorithm and the no-undo rule; since this module also its
*provenance* (package and library versions, the checkout's commit, the resolved
configuration, the command line of the run that made it) and a *run id* (the log of that
table names it on its first line). :class:`RunIdentity` is that record, made from a
run's env (:meth:`RunIdentity.of_run`) or from a table (:meth:`RunIdentity.of_table`);
:func:`check` compares the two for a *purpose* and, field by field, refuses (one line,
:class:`~koolio_pymunk.store.errors.QTableError`, with what to do instead) or warns, from
one table of rules, :data:`RULES` (docs/robustness.md shows it):

=========  ======  =====  ====  =====  =====  ======  ========  =======
field      resume  start  keep  score  watch  export  transfer  inspect
=========  ======  =====  ====  =====  =====  ======  ========  =======
best       refuse  .      .     .      .      .       .         .
run        .       .      refuse .     .      .       .         .
layout     refuse  refuse refuse refuse refuse refuse refuse    refuse
sensors    refuse  refuse refuse refuse refuse refuse refuse    refuse
algorithm  refuse  .      refuse .     .      refuse  refuse    .
no_undo    refuse  .      refuse refuse refuse refuse refuse    .
goal       refuse  .      refuse warn  warn   warn    warn      .
world      refuse  .      refuse warn  warn   warn    .         .
arena      warn    warn   .     warn   warn   warn    warn      .
empty      .       .      .     warn   warn   warn    warn      .
=========  ======  =====  ====  =====  =====  ======  ========  =======

Purposes: ``resume`` (``train`` on an existing table, ``view --learn``), ``start``
(``train --init-qtable``: a new table from another's Q values, in any algorithm, goal or
world), ``keep`` (the best table ``train --eval-every`` keeps beside its table: the same
run's, ``run``), ``score`` (``eval``), ``watch`` (``view`` of an existing table),
``export`` (a policy for the robot), ``transfer`` (``koolio-pm transfer --qtable``, which
scores a table in both worlds and keeps learning on the robot), ``inspect`` (``info``:
is it a table of this configuration). ``best``: a kept best table (``X.best.qtable``) is
not trained in place. ``empty``: a table of no episodes (its greedy policy is
arbitrary). A run that knows no arena (``export``, ``info``) compares no goal or arena.

>>> from koolio_pymunk.task.env import KoolioEnv
>>> env = KoolioEnv("room")
>>> run = RunIdentity.of_run(env)
>>> run.goal, run.world, run.algorithm["name"]
(None, 'ideal', 'qlambda')
>>> sorted(PURPOSES) == sorted(RULES["layout"])
True
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import re
import shlex
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from . import provenance
from .config import (
    PARAMETERS,
    Config,
    LearnerConfig,
    MemoryConfig,
    load_config,
    profile_names,
    state_fields,
)
from .episode_log import RowRules
from .errors import KoolioError, QTableError, located, shown
from .keyword import KeywordLayout, base_layout, table_robots
from .keyword import own_tables as own_layout
from .qtable import QTable
from .worlds import IDEAL, world_label


class RunEnv(Protocol):
    """What :meth:`RunIdentity.of_run` reads of a run's env (a
    :class:`~koolio_pymunk.task.env.KoolioEnv`, which this floor never imports)."""

    config: Config
    layout: KeywordLayout
    arena: Any
    """Its :attr:`record` is what a table records of the arena."""
    goal_name: str
    home_goal: str
    random_goal: bool
    world_name: str
    randomizer: Any
    """Its ``columns`` are the log's realism columns."""


#: What a table is used for (module doc).
PURPOSES = ("resume", "start", "keep", "score", "watch", "export", "transfer", "inspect")
REFUSE, WARN = "refuse", "warn"
#: Per field, per purpose: refuse or warn (absent: not checked). Module doc.
_USE = ("score", "watch", "export", "transfer")  # a table's policy is used, not changed
RULES: dict[str, dict[str, str]] = {
    "best": {"resume": REFUSE},
    "run": {"keep": REFUSE},
    "layout": dict.fromkeys(PURPOSES, REFUSE),
    "sensors": dict.fromkeys(PURPOSES, REFUSE),
    "algorithm": dict.fromkeys(("resume", "keep", "export", "transfer"), REFUSE),
    "no_undo": dict.fromkeys(("resume", "keep", *_USE), REFUSE),
    "goal": {"resume": REFUSE, "keep": REFUSE} | dict.fromkeys(_USE, WARN),
    "world": {"resume": REFUSE, "keep": REFUSE, "score": WARN, "watch": WARN, "export": WARN},
    "arena": dict.fromkeys(("resume", "start", *_USE), WARN),
    "empty": dict.fromkeys(_USE, WARN),
}
#: What to do instead, in a refusal's last words, per purpose (``{source}``: the table).
REMEDIES = {
    "resume": "start a new table from its Q values: --init-qtable {source} --qtable NEW",
    "keep": "move it away, or give the run its own --qtable",
    "inspect": "",
    "start": "give train the --config of the table it starts from",
    "score": "give eval the --config it was learned with",
    "watch": "give view the --config it was learned with",
    "export": "give export the --config it was learned with",
    "transfer": "give transfer its --config",
}


@dataclass(frozen=True)
class RunIdentity:
    """What a table is (module doc). ``goal`` None is the arena's active goal (the one of
    ``home_goal``, when known); ``world`` a label (``ideal``, ``koolio-real``, a file's
    name); ``algorithm`` the header's record (None: one-step Q without the rule)."""

    layout: KeywordLayout
    sensors: str
    """The sensor signature, as sorted JSON (comparable, hashable)."""
    arena: tuple[str, str] | None
    """The arena's name and content hash (:func:`~koolio_pymunk.world.arena.arena_record`)."""
    goal: str | None
    world: str
    algorithm_json: str | None
    home_goal: str | None = None
    """The active goal of the arena file the run is in (what ``goal`` None means)."""
    best: int | None = None
    """A kept best table: the episode of its check (None: not one)."""
    episodes: int = 0
    run_id: str | None = None
    """The run id a table records (None: a run's identity, or a table made before run
    ids)."""
    config: Config | None = dataclasses.field(default=None, compare=False, repr=False)
    """A run's configuration (None: a table's identity), for what a new table records."""
    log_columns: tuple[str, ...] = dataclasses.field(default=(), compare=False)
    """The extra columns of a run's log (its domain randomization's draws)."""

    @property
    def q_init(self) -> float:
        return 0.0 if self.config is None else self.config.learner.q_init

    @property
    def algorithm(self) -> dict[str, Any] | None:
        return None if self.algorithm_json is None else json.loads(self.algorithm_json)

    @property
    def algorithm_name(self) -> str:
        rec = self.algorithm
        return "q" if rec is None else str(rec["name"])

    @property
    def no_undo(self) -> bool:
        rec = self.algorithm
        return isinstance(rec, dict) and rec.get("no_undo") is True

    @classmethod
    def of_run(cls, env: RunEnv, own_tables: int = 0) -> RunIdentity:
        """The identity of a run in ``env`` (its configuration, arena, goal and world),
        from what the env holds: the arena it loaded (its file is not read again), its
        goal, its world. ``own_tables`` N > 0: N robots each with its own rows of the
        table (``train --tables each``: the layout leads with
        :data:`~koolio_pymunk.store.keyword.ROBOT_FIELD`)."""
        cfg = env.config
        goal = "random" if env.random_goal else env.goal_name
        sensors, algorithm = sensor_signature(cfg), algorithm_record(cfg.learner)
        rec = env.arena.record
        return cls(
            layout=own_layout(env.layout, own_tables) if own_tables else env.layout,
            sensors=_frozen(sensors),
            arena=(rec["name"], rec["sha256"]),
            goal=None if goal == env.home_goal else goal,
            world=world_label(env.world_name),
            algorithm_json=_frozen(algorithm),
            home_goal=env.home_goal,
            config=cfg,
            log_columns=tuple(env.randomizer.columns),
        )

    @classmethod
    def of_robots(
        cls, env: RunEnv, robots: int, table: QTable | None, each: bool = False
    ) -> RunIdentity:
        """The identity of ``robots`` robots sharing ``env``'s arena (1: a robot alone)
        that play or learn ``table`` (``eval``, ``view``; None: a new table, one all
        share unless ``each``, ``view --tables each``): they have their own rows when
        the table holds each robot's (``train --tables each``) or ``each`` asks for them,
        so the check compares their number with the table's."""
        held = table is not None and table_robots(table.layout) > 0
        own = robots > 1 and (held or each)
        return cls.of_run(env, robots if own else 0)

    @classmethod
    def of_config(cls, cfg: Config, world: str | None = None) -> RunIdentity:
        """The identity of a run of ``cfg`` that knows no arena (``export``, ``info``):
        its goal and arena are not compared. ``world``: ``--world``'s name (None: the
        configuration's own)."""
        from .worlds import world_name

        return cls(
            layout=KeywordLayout(tuple(state_fields(cfg.sensors))),
            sensors=_frozen(sensor_signature(cfg)),
            arena=None,
            goal=None,
            world=world_label(world_name(cfg, world)),
            algorithm_json=_frozen(algorithm_record(cfg.learner)),
            config=cfg,
        )

    @classmethod
    def of_table(cls, table: QTable, source: str, run: RunIdentity | None = None) -> RunIdentity:
        """The identity ``table`` records (read from ``source``; ``run``: the run that
        asks, to name the table's default goal when it was learned in the same arena)."""
        meta = table.meta
        sensors = meta.get("sensors", {})
        if not isinstance(sensors, dict):
            raise QTableError(located(source, "sensors", f"not a mapping: {shown(sensors)}"))
        arena = meta.get("arena")
        arena_t = (
            (str(arena.get("name")), str(arena.get("sha256"))) if isinstance(arena, dict) else None
        )
        home = None
        if run is not None and arena_t is not None and arena_t == run.arena:
            home = run.home_goal
        best = meta.get("best")
        return cls(
            layout=table.layout,
            sensors=_frozen(sensors),
            arena=arena_t,
            goal=meta.get("goal"),
            world=meta.get("world", IDEAL),
            algorithm_json=_frozen(_algorithm_of(table, source)),
            home_goal=home,
            best=best.get("episode", -1) if isinstance(best, dict) else None,
            episodes=int(meta.get("episodes", 0)),
            run_id=meta.get("run_id"),
        )

    def header(self) -> dict[str, Any]:
        """The header keys a new table of this run records (absent: the defaults, so a
        default run's table keeps the bytes of tables made before those keys existed)."""
        out: dict[str, Any] = {"sensors": json.loads(self.sensors), "episodes": 0}
        if self.arena is not None:
            out["arena"] = {"name": self.arena[0], "sha256": self.arena[1]}
        if self.goal is not None:
            out["goal"] = self.goal
        if self.world != IDEAL:
            out["world"] = self.world
        if self.algorithm_json is not None:
            out["algorithm"] = self.algorithm
        return out

    def describe(self) -> str:
        """``goal 311 in the ideal world``: what a run is for, for a message."""
        return f"{describe_goal(self.goal, self.home_goal)} in {describe_world(self.world)}"


def _frozen(value: Any) -> str | None:
    return None if value is None else json.dumps(value, sort_keys=True)


# -- the checks ---------------------------------------------------------------------------


def check(
    table: QTable,
    run: RunEnv | RunIdentity,
    purpose: str,
    source: str,
    warn: Callable[[str], None] | None = None,
    run_id: str | None = None,
) -> RunIdentity:
    """Check ``table`` (read from ``source``) for ``purpose`` by a run in ``run`` (an env,
    or the identity of a run that knows no arena, :meth:`RunIdentity.of_config`; module
    doc): the first refusal raises :class:`QTableError` (one line), each warning goes to
    ``warn`` (stderr by default). ``run_id``: the run id the table must record (``keep``:
    the run's own table's). Returns the table's identity.

    >>> from koolio_pymunk.store.config import Config
    >>> from koolio_pymunk.task.env import KoolioEnv
    >>> env = KoolioEnv("room")
    >>> table = QTable(env.layout, RunIdentity.of_config(Config()).header())
    >>> check(table, env, "resume", "t.qtable").algorithm_name
    'qlambda'
    >>> check(table, env, "score", "t.qtable", warn=print).episodes
    t.qtable: holds 0 episodes (an empty table: its greedy policy is arbitrary); train it first
    0
    """
    if purpose not in PURPOSES:
        raise ValueError(f"purpose: one of {', '.join(PURPOSES)}, got {purpose!r}")
    say = warn or _stderr
    mine = run if isinstance(run, RunIdentity) else RunIdentity.of_run(run)
    if run_id is not None:
        mine = dataclasses.replace(mine, run_id=run_id)
    theirs = RunIdentity.of_table(table, source, mine)
    for field, rules in RULES.items():
        rule = rules.get(purpose)
        if rule is None:
            continue
        problem = _COMPARE[field](theirs, mine, table, source, purpose)
        if problem is None:
            continue
        item, text = problem
        if rule == REFUSE:
            remedy = REMEDIES[purpose].format(source=source)
            raise QTableError(located(source, item, text.replace("{remedy}", remedy)))
        message = f"{source}: {text}"
        if (say, message) not in _warned:  # a run may check its table more than once
            _warned.add((say, message))
            say(message)
    return theirs


_warned: set[tuple[Callable[[str], None], str]] = set()
"""The warnings given, per receiver: each once per process."""


def _stderr(message: str) -> None:
    print(f"warning: {message}", file=sys.stderr)


def _best(theirs, mine, table, source, purpose):
    if theirs.best is None or not Path(source).name.endswith(".best.qtable"):
        return None
    episode = theirs.best if theirs.best >= 0 else "?"
    return "", (
        f"the best table kept by train --eval-every (its check at episode {episode}): "
        "training it would change it in place; start a new table from it: "
        f"koolio-pm train --init-qtable {source} --qtable NEW.qtable"
    )


def _run(theirs, mine, table, source, purpose):
    if theirs.run_id is None or mine.run_id is None or theirs.run_id == mine.run_id:
        return None
    return "run_id", (
        f"a table of run {theirs.run_id}, and this run is {mine.run_id}: the best table of "
        "another run ({remedy})"
    )


def _layout(theirs, mine, table, source, purpose):
    if theirs.layout == mine.layout:
        return None
    own, asked = table_robots(theirs.layout), table_robots(mine.layout)
    if own != asked and base_layout(theirs.layout) == base_layout(mine.layout):
        if not own:
            fix = ": give a new --qtable" if purpose == "resume" else ""
            return "layout", (
                f"one table all robots share, this run gives {asked} robots their own rows "
                f"(--tables each){fix}"
            )
        how = f"--robots {own} --shared-arena"
        if purpose == "resume":
            how += " --tables each"
        elif purpose in ("export", "transfer", "inspect"):
            how = "export --robot K --out ROBOT.qtable takes robot K's rows alone"
            return "layout", f"holds the own rows of {own} robots (train --tables each): {how}"
        return "layout", (
            f"holds the own rows of {own} robots (train --tables each): run it with {how}"
        )
    return "layout", (
        f"table made for {_fmt_layout(theirs.layout)}, this run uses "
        f"{_fmt_layout(mine.layout)}{_profile_hint(table)}"
    )


def _sensors(theirs, mine, table, source, purpose):
    a, b = json.loads(theirs.sensors), json.loads(mine.sensors)
    for key in sorted(set(a) | set(b), key=str):
        if a.get(key) != b.get(key):
            return f"sensors.{key}", (
                f"table made for {_recorded(a, key)}, this run uses {_recorded(b, key)}"
                f"{_profile_hint(table)}"
            )
    return None


def _algorithm(theirs, mine, table, source, purpose):
    learned = bool(table.rows) or theirs.episodes > 0
    if learned and theirs.algorithm_name != mine.algorithm_name:
        return "algorithm", (
            f"table learned with {theirs.algorithm_name}, this run uses "
            f"{mine.algorithm_name} ({{remedy}})"
        )
    return None


def _no_undo(theirs, mine, table, source, purpose):
    learned = bool(table.rows) or theirs.episodes > 0
    if not learned or theirs.no_undo == mine.no_undo:
        return None
    if theirs.no_undo:
        what = "table learned with the no-undo rule, this run chooses among all actions"
    else:
        what = "table learned choosing among all actions, this run has the no-undo rule"
    return "learner.no_undo", f"{what} ({{remedy}})"


def _goal(theirs, mine, table, source, purpose):
    if theirs.goal == mine.goal or mine.arena is None:
        return None
    was = describe_goal(theirs.goal, theirs.home_goal)
    now = describe_goal(mine.goal, mine.home_goal)
    if purpose in _VERBS:
        return "", f"trained for {was}, {_VERBS[purpose]} here for {now}"
    if purpose != "resume":
        return "goal", f"trained for {was}, this run asks for {now} ({{remedy}})"
    same = f"--goal {theirs.goal}" if theirs.goal is not None else "no --goal"
    return "goal", (
        f"trained for {was}, this run asks for {now}: run with {same} to continue it, or "
        f"give a new --qtable (with --init-qtable {source} to start from it)"
    )


def _world(theirs, mine, table, source, purpose):
    if theirs.world == mine.world:
        return None
    was, now = describe_world(theirs.world), describe_world(mine.world)
    if purpose in _VERBS:
        return "", f"trained in {was}, {_VERBS[purpose]} here in {now}"
    if purpose != "resume":
        return "world", f"trained for {was}, this run asks for {now} ({{remedy}})"
    return "world", (
        f"trained for {was}, this run asks for {now}: run with {_same_world(theirs.world)} "
        f"to continue it, or give a new --qtable (with --init-qtable {source} to start "
        "from it)"
    )


def _arena(theirs, mine, table, source, purpose):
    if theirs.arena is None or mine.arena is None or theirs.arena == mine.arena:
        return None
    return "", (
        f"learned in arena {theirs.arena[0]!r} (content {theirs.arena[1]}), used in arena "
        f"{mine.arena[0]!r} (content {mine.arena[1]}); it loads (same sensors), but its "
        "policy was learned elsewhere"
    )


def _empty(theirs, mine, table, source, purpose):
    if theirs.episodes > 0 or table.meta.get("policy"):
        return None
    return "", "holds 0 episodes (an empty table: its greedy policy is arbitrary); train it first"


_VERBS = {"score": "scored", "watch": "watched", "export": "exported",
          "transfer": "handed to the robot"}  # fmt: skip
_COMPARE = {
    "best": _best,
    "run": _run,
    "layout": _layout,
    "sensors": _sensors,
    "algorithm": _algorithm,
    "no_undo": _no_undo,
    "goal": _goal,
    "world": _world,
    "arena": _arena,
    "empty": _empty,
}
assert set(_COMPARE) == set(RULES)


# -- what a run records --------------------------------------------------------------------


def new_table(run: RunIdentity, seed: int | None = None) -> QTable:
    """An empty table of the run ``run`` (its identity and provenance, :func:`stamp`)."""
    table = QTable(run.layout, {}, run.q_init)
    stamp(table, run, new=True, seed=seed)
    return table


def stamp(
    table: QTable,
    run: RunIdentity,
    new: bool = False,
    seed: int | None = None,
    origin: dict[str, Any] | None = None,
) -> None:
    """Record this run's learner in ``table``, which the run learns into (its algorithm
    record: the parameters may change on resume; a kept best table's record goes) and,
    for a ``new`` table (made empty, or started from another's Q values: ``origin`` says
    which, ``--init-qtable``), the whole run identity, its provenance
    (:func:`koolio_pymunk.store.provenance.of_run`) and the run id. A table made by
    another algorithm drops that algorithm's data (a Dyna model). ``table`` is new or
    checked for this run already (:func:`check`): its record is not judged again."""
    mine = run
    theirs = table.meta.get("algorithm")  # None: one-step Q without the rule
    if isinstance(theirs, dict) and theirs.get("name") != mine.algorithm_name:
        table.sections.clear()  # another algorithm's data does not carry over
    if new:
        episodes = int(table.meta.get("episodes", 0))
        for key in ("goal", "world", "algorithm", "provenance", "run_id", "best"):
            table.meta.pop(key, None)
        table.meta.update(mine.header())
        table.meta["episodes"] = episodes
        config = mine.config.to_dict() if mine.config is not None else None
        table.meta["provenance"] = provenance.of_run(config) | (
            {"started_from": origin} if origin is not None else {}
        )
        table.meta["run_id"] = run_id(table.meta, seed)
    table.meta.pop("best", None)  # a best table trained on is no longer its check's
    rec = mine.algorithm
    if rec is None:
        table.meta.pop("algorithm", None)
    else:
        table.meta["algorithm"] = rec


def learned_digest(table: QTable) -> str:
    """A hash of what ``table`` learned (its Q values, data sections, episode count and
    the identity it learned for) without where it came from (its provenance and run id):
    two runs of the same seeded configuration have the same digest whatever command line,
    checkout or machine made them (``koolio-pm info --qtable`` shows it; sweeps record it).
    """
    meta = {k: v for k, v in table.meta.items() if k not in ("provenance", "run_id")}
    copy = QTable(table.layout, meta, table.q_init, table.rows, dict(table.sections))
    return hashlib.sha256(copy.to_bytes()).hexdigest()[:16]


def run_id(meta: dict[str, Any], seed: int | None) -> str:
    """A new table's run id: a hash of what the run is (its header at creation, its
    resolved configuration, the table it started from) and its seed, and not of where it
    ran (versions, checkout, command line): a seeded run is reproducible, so two runs with
    one id write the same rows, and a log names the run it belongs to
    (:mod:`koolio_pymunk.store.episode_log`).

    >>> run_id({"sensors": {}, "episodes": 0}, 3) == run_id({"sensors": {}, "episodes": 0}, 3)
    True
    >>> run_id({"sensors": {}, "episodes": 0}, 3) == run_id({"sensors": {}, "episodes": 0}, 4)
    False
    """
    prov = meta.get("provenance", {})
    what = {k: v for k, v in meta.items() if k not in ("provenance", "run_id")}
    what["configuration"] = prov.get("configuration")
    what["started_from"] = prov.get("started_from")
    text = json.dumps({"run": what, "seed": seed}, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def describe_provenance(table: QTable, cfg: Config | None = None) -> list[str]:
    """``koolio-pm info``'s lines on where ``table`` came from: its run id and learned
    digest, the versions and commit that made it, its command line, the table it started
    from, and the settings where its recorded configuration differs from ``cfg``."""
    meta = table.meta
    lines = [f"learned content {learned_digest(table)} (its values and identity, hashed)"]
    rid = meta.get("run_id")
    prov = meta.get("provenance")
    if not isinstance(prov, dict) or not prov:
        return [*lines, "provenance: not recorded (a table made before tables recorded it)"]
    lines[0] = f"run id {rid}, " + lines[0]
    libs = ", ".join(
        f"{k} {prov[k]}" for k in ("numpy", "pymunk", "numba", "gymnasium") if prov.get(k)
    )
    git = prov.get("git")
    commit = ""
    if isinstance(git, dict) and isinstance(git.get("commit"), str):
        changed = ", with uncommitted changes" if git.get("changed") else ""
        commit = f" (commit {git['commit'][:12]}{changed})"
    lines.append(
        f"made by koolio-pymunk {prov.get('koolio_pymunk')}{commit}, Python "
        f"{prov.get('python')}, {libs}"
    )
    command = prov.get("command")
    if isinstance(command, list) and command:
        lines.append("command: koolio-pm " + shlex.join(str(a) for a in command))
    else:
        lines.append("command: none recorded (made from Python)")
    start = prov.get("started_from")
    if isinstance(start, dict):
        lines.append(
            f"started from {start.get('file')} (run {start.get('run_id')}, "
            f"{start.get('episodes')} episodes)"
        )
    recorded = prov.get("configuration")
    if isinstance(recorded, dict) and cfg is not None:
        diff = _differences(recorded, cfg.to_dict())
        if not diff:
            lines.append("configuration: the one given here, setting for setting")
        else:
            more = f" and {len(diff) - 6} more" if len(diff) > 6 else ""
            lines.append(
                "configuration: differs from the one given here in " + ", ".join(diff[:6]) + more
            )
    return lines


def _differences(a: Any, b: Any, prefix: str = "") -> list[str]:
    """The dotted keys where two configuration mappings differ.

    >>> _differences({"learner": {"alpha": 0.1, "gamma": 0.9}}, {"learner": {"alpha": 0.2}})
    ['learner.alpha', 'learner.gamma']
    """
    if isinstance(a, dict) and isinstance(b, dict):
        out: list[str] = []
        for key in sorted(set(a) | set(b), key=str):
            out += _differences(a.get(key), b.get(key), f"{prefix}{key}.")
        return out
    return [] if a == b else [prefix.rstrip(".")]


# -- the algorithm's record ------------------------------------------------------------------


def algorithm_record(cfg: LearnerConfig) -> dict[str, Any] | None:
    """What a Q-table header records of ``cfg``'s algorithm: None for one-step Q without
    the no-undo rule (the paper's learner: its tables' bytes are those of tables made
    before these records existed).

    >>> algorithm_record(LearnerConfig())  # the default learner
    {'name': 'qlambda', 'trace_decay': 0.7, 'trace_cutoff': 0.01, 'no_undo': True}
    >>> algorithm_record(LearnerConfig(algorithm="dyna", planning_steps=5, no_undo=False))
    {'name': 'dyna', 'planning_steps': 5}
    >>> algorithm_record(LearnerConfig(algorithm="q", no_undo=False)) is None
    True
    """
    rule = {"no_undo": True} if cfg.no_undo else {}  # absent when off: tables as before
    if cfg.algorithm == "q" and not rule:
        return None
    params = {k: getattr(cfg, k) for k in PARAMETERS[cfg.algorithm]}
    return {"name": cfg.algorithm} | params | rule


def _algorithm_of(table: QTable, source: str) -> dict[str, Any] | None:
    """The table's algorithm record, checked (None: one-step Q without the rule)."""
    rec = table.meta.get("algorithm")
    if rec is None:
        return None
    name = rec.get("name") if isinstance(rec, dict) else None
    if not isinstance(name, str) or name not in PARAMETERS:
        text = shown(rec, 60)
        raise QTableError(located(source, "algorithm", f"unknown learning algorithm {text}"))
    return rec


# -- the sensors, the goal, the world ---------------------------------------------------------


def sensor_signature(cfg: Config) -> dict[str, Any]:
    """What a Q-table depends on: the sensor layout (noise settings excluded)."""
    s = cfg.sensors
    so, ca = s.sonar, s.camera
    model = {"sonar_model": "cone"} if s.backend == "cone" else {}  # sub-arcs: no key
    return (
        model
        | {
            "sonar_sensors_deg": list(so.sonar_sensors_deg),
            "sonar_arc_deg": so.sonar_arc_deg,
            "sub_arcs": so.sub_arcs,
            "sonar_max_range": so.max_range,
            "sonar_groups": [list(g) for g in so.groups],
            "sonar_thresholds": list(so.thresholds),
            "camera_sensors_deg": list(ca.camera_sensors_deg),
            "camera_arc_deg": ca.camera_arc_deg,
            "max_camera_view": ca.max_camera_view,
            "camera_thresholds": list(ca.thresholds),
            "compass_in_state": s.compass.in_state,
        }
        | _memory_signature(s.memory, cfg.actions.rotate_action_arc_deg)
    )


def _memory_signature(mem: MemoryConfig, turn_deg: float) -> dict[str, Any]:
    """The memory's part of a sensor signature: nothing when it is off (the tables of
    memoryless runs stay as they were); with ``goal_bearing`` also the rotation's arc
    ``turn_deg`` it turns by."""
    if not mem.on:
        return {}
    fields = dataclasses.asdict(mem)
    if mem.goal_bearing:
        fields["turn_deg"] = turn_deg
    else:  # a field added later: tables without it keep their bytes
        del fields["goal_bearing"]
    return {"memory": fields}


def describe_goal(goal: str | None, default: str | None = None) -> str:
    """The goal a table (or a run) is for, for a message; ``default``: the arena's active
    goal, when known.

    >>> describe_goal(None), describe_goal(None, "311"), describe_goal("random")
    ("the arena's active goal", 'goal 311', 'a random goal per episode')
    """
    if goal is None:
        return "the arena's active goal" if default is None else f"goal {default}"
    return "a random goal per episode" if goal == "random" else f"goal {goal}"


def describe_world(world: str | None) -> str:
    """The world a table was trained in, for a message.

    >>> describe_world(None), describe_world("ideal"), describe_world("koolio-real")
    ('the ideal world', 'the ideal world', 'world koolio-real')
    """
    return "the ideal world" if world in (None, IDEAL) else f"world {world}"


def _same_world(world: str | None) -> str:
    """How to run in the world a table records again (``--world`` or ``--config``, which
    name it alike: :mod:`koolio_pymunk.store.worlds`).

    >>> _same_world(IDEAL), _same_world("koolio-real")
    ('no --world and no realism in --config', '--world koolio-real (or --config koolio-real)')
    >>> _same_world("realism-0123abcd")
    'a --config (and --world) with the same realism section'
    """
    if world in (None, IDEAL):
        return "no --world and no realism in --config"
    if re.fullmatch(r"realism-[0-9a-f]{8}", world):
        return "a --config (and --world) with the same realism section"
    return f"--world {world} (or --config {world})"


def _profile_hint(table: QTable) -> str:
    """`` (made with --config NAME: add it)`` when ``table``'s sensors match a shipped
    profile's (or the default configuration's), else ``""``."""
    theirs = table.meta.get("sensors")
    for name in (None, *profile_names()):
        try:
            cfg = load_config(name)
        except KoolioError:  # an unreadable profile: no hint from it
            continue
        fields = tuple(state_fields(cfg.sensors))
        if sensor_signature(cfg) == theirs and KeywordLayout(fields) == table.layout:
            if name is None:
                return " (it was made with the default configuration: leave out --config)"
            return f" (it was made with the shipped profile {name!r}: add --config {name})"
    return ""


def _recorded(sensors: dict[str, Any], key: str) -> str:
    """The value of ``key`` in a sensor signature, for a message."""
    return shown(sensors[key], 80) if key in sensors else "none (not recorded)"


def _fmt_layout(layout: KeywordLayout) -> str:
    return (
        f"{layout.total_bits}-bit keyword ["
        + ", ".join(f"{n}:{lv}" for n, lv in layout.fields)
        + "]"
    )


# -- the log ------------------------------------------------------------------------------------


def log_rules(run: RunIdentity, table: QTable) -> RowRules:
    """What the rows of ``table``'s log can hold in the run ``run``
    (:mod:`koolio_pymunk.store.episode_log`): the table's run id (a log that names
    another is another table's), and for a log of a table made before run ids, rows ahead
    of the table an epsilon of the run's schedule, every row the goal the table records."""
    goal = table.meta.get("goal")
    fixed = goal if isinstance(goal, str) and goal != "random" else None
    rid = table.meta.get("run_id")
    epsilon = run.config.learner.epsilon if run.config is not None else None
    return RowRules(epsilon=epsilon, goal=fixed, run_id=rid if isinstance(rid, str) else None)


__all__: Sequence[str] = (
    "PURPOSES",
    "RULES",
    "RunIdentity",
    "algorithm_record",
    "check",
    "sensor_signature",
    "stamp",
)
