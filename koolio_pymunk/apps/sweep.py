"""Run a sweep of training runs over seeds and parameters, locally or on a Ray cluster.

``koolio-pm sweep SPEC.yaml`` trains one run per (configuration, seed), in parallel on
local processes (``--workers N``) or as Ray tasks (``--ray [ADDRESS]``), and writes to
``--out`` (default ``sweeps/<spec name>``)::

    results.csv            one row per finished run (written atomically after each run)
    configs.csv            per configuration: mean and spread over seeds
    curves.png             learning curves: mean and min-max band over seeds
    spec.yaml              the spec as given
    runs/<config>/seed<N>/ qtable.qtable, train.csv (per-episode log, koolio-pm train's
                           format), evals.csv (greedy checkpoints), config.yaml (loadable
                           with --config), run.json, result.json (written last)

**Spec** (YAML; every key optional except ``episodes``)::

    name: alpha-vs-gamma       # default: the file's stem
    episodes: 600              # training episodes per run
    seeds: 3                   # a count (0, 1, 2) or a list of seeds
    arena: hallway             # built-in name or file (relative to the spec)
    goal: null                 # goal name, 'random', or null (the arena's active goal)
    rotate_deg: null           # the arena's rotation (clockwise, degrees; the paper's 5);
                               #  null keeps the arena file's own rotate_deg
    config: base.yaml          # optional configuration file (relative to the spec) or
                               #  profile name (paper)
    world: koolio-real         # optional world profile or file laid over every run
    base: {episode: {max_steps: 600}}      # configuration overrides for every run
    grid:                      # every combination of these (dotted config paths,
      learner.alpha: [0.1, 0.3]            #  or arena / goal)
      learner.gamma: [0.9, 0.97]   #  (world: [null, koolio-real] compares worlds;
                                   #  rotate_deg: [0, 5] the arena's rotation)
    runs:                      # and/or a list of named override sets (each combined
      - {name: soft-bumps, rewards.bump: -2}   #  with every grid combination)
    eval_every: 100            # greedy check every K episodes (default episodes/10)
    eval_episodes: 20          # episodes per greedy check
    competence: 0.9            # goal rate that counts as competent

**Results.** ``final_goal_rate``, ``final_mean_steps``, ``final_mean_bumps`` and
``final_mean_return`` come from the greedy evaluation after the last episode;
``late_goal_rate`` is the mean greedy goal rate of the checkpoints in the last third of
the episodes (one evaluation is a snapshot: a greedy policy still learning can swing
from one checkpoint to the next);
``competence_episode`` is the first checkpoint whose greedy goal rate reaches
``competence`` (empty: not reached) and ``competence_seconds`` the training time until
then; ``train_*`` summarise the training episodes themselves; ``table_sha256`` identifies
what the final Q-table learned
(:func:`~koolio_pymunk.store.run_identity.learned_digest`: its values and identity,
not its provenance, so the same run on another machine or checkout has the same one).
``run.json`` holds the task and its provenance (versions, commit, command line:
:mod:`koolio_pymunk.store.provenance`).

**Checkpoints.** A run's greedy evaluations are the periodic checks of ``koolio-pm train
--eval-every K --eval-episodes M`` (:class:`~koolio_pymunk.learning.evaluation.PeriodicCheck`,
with the run's seed): a run and ``train --seed s --eval-every K`` check the same tables on
the same episodes. A last stretch shorter than ``eval_every`` ends with the same
evaluation of the final table.

**Reproducibility.** A run depends only on its configuration and seed ``s``, never on
scheduling: local processes and Ray give identical rows apart from the two timing
columns (``competence_seconds``, ``train_seconds``). A run works in a private temporary
directory and returns its files to the driver, which writes them, so Ray workers need no
shared filesystem (but need ``koolio-pymunk`` installed).

**Resume.** Running the same command again skips every run that has a row in
``results.csv`` (or a ``result.json``); an interrupted run is redone from its start. A
run's id includes a hash of its full resolved configuration, so changing a setting (or a
default) makes new runs rather than mixing results. An output folder holds one spec's
runs (:func:`check_out`): a spec that only adds runs (more seeds) resumes into it, a spec
with runs the folder's finished ones are not (another value, ``--world``, defaults) is
refused, and so is a folder that is neither empty nor a sweep's.

**Faults.** A sweep holds a lock on its output folder (``.sweep.lock``): a second sweep
into the same folder is refused. Local workers are standard-library process pools of one
process each (:func:`run_pool`): a worker that dies (killed, out of memory) fails only
the run it was running, which is reported, and a new worker takes the remaining runs (as
on Ray, where a lost task fails alone). Each run works in a temporary folder named after
its process (``koolio-sweep-<pid>-...``); folders of processes that no longer run (a
killed worker) are removed when the next run starts. Stopped (Ctrl-C, SIGTERM), a sweep
stops its workers' runs and ends; killed (SIGKILL), its workers end within a second.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import dataclasses
import difflib
import hashlib
import io
import itertools
import json
import math
import os
import re
import shutil
import tempfile
import time
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from ..store import provenance
from ..store.errors import ConfigError, KoolioError, located, shown
from ..store.interrupts import exit_status, terminate_as_interrupt

SPEC_KEYS = (
    "name",
    "episodes",
    "seeds",
    "arena",
    "goal",
    "rotate_deg",
    "config",
    "world",
    "base",
    "grid",
    "runs",
    "eval_every",
    "eval_episodes",
    "competence",
)
RESULT_COLUMNS = (
    "run_id",
    "config_id",
    "label",
    "seed",
    "arena",
    "goal",
    "episodes",
    "final_goal_rate",
    "final_mean_steps",
    "final_mean_bumps",
    "final_mean_return",
    "late_goal_rate",
    "late_low_goal_rate",
    "best_goal_rate",
    "competence_episode",
    "competence_seconds",
    "train_goal_rate",
    "train_mean_steps",
    "train_mean_bumps",
    "states",
    "train_seconds",
    "table_sha256",
)
#: Most runs (configurations x seeds) one spec may plan.
MAX_RUNS = 10_000
#: Most parallel processes of ``--workers``.
MAX_WORKERS = 1024
#: Most episodes of a run (``episodes``, ``eval_every``, ``eval_episodes``), as the flags.
MAX_EPISODES = 10**9
#: Seeds are below 2**63, as the flags'.
SEED_LIMIT = 1 << 63
#: Largest spec file read.
MAX_SPEC_BYTES = 256 * 1024
#: Largest file of a run read back (its result.json, its evaluation log).
MAX_RUN_FILE_BYTES = 64 * 1024 * 1024


# --- command line ---------------------------------------------------------------------
def add_arguments(p: argparse.ArgumentParser) -> None:
    from .flags import file_name, int_type

    p.add_argument("spec", type=file_name, help="sweep spec (YAML; see docs/sweeps.md)")
    p.add_argument(
        "--out", type=file_name, default=None, help="output folder (default sweeps/<spec name>)"
    )

    p.add_argument(
        "--workers",
        type=int_type(1, MAX_WORKERS),
        default=None,
        help="parallel local processes (default: CPU count); with --ray, the CPUs of a "
        "local Ray instance",
    )
    p.add_argument(
        "--ray",
        nargs="?",
        const="",
        default=None,
        metavar="ADDRESS",
        help="run on Ray: alone, a new local instance; 'auto' or ray://HOST:PORT, an "
        "existing cluster (needs pip install 'koolio-pymunk[ray]')",
    )
    p.add_argument(
        "--world",
        type=file_name,
        default=None,
        help="world profile or file laid over every run (overrides the spec's world)",
    )
    p.add_argument("--no-plot", action="store_true", help="do not draw curves.png")
    p.add_argument("--dry-run", action="store_true", help="list the runs and exit")


#: How a run's checkpoints are made, in every configuration's digest: the periodic checks
#: of ``koolio-pm train --eval-every`` (the run's seed). Sweeps made before evaluated with
#: seed ``1,000,000 + s``; their folders are refused rather than mixed with new runs.
CHECKS = "train --eval-every"


def run(args: argparse.Namespace) -> int:
    spec = load_spec(args.spec)
    if args.world is not None:
        from ..store.config import apply_world, load_config

        apply_world(load_config(), args.world)  # a bad name or file: one line naming --world
        spec.world = args.world
    out = Path(args.out) if args.out else Path("sweeps") / spec.name
    tasks = plan(spec)
    if args.dry_run:
        configs = {t["config_id"]: t["label"] for t in tasks}
        print(f"{spec.source}: {len(configs)} configurations x {len(spec.seeds)} seeds")
        for cid, label in configs.items():
            print(f"  {cid}  {label}")
        return 0
    outcome = run_sweep(
        spec, out, workers=args.workers, ray_address=args.ray, plot=not args.no_plot
    )
    print_summary(outcome.rows, tasks)
    if outcome.interrupted:
        print("interrupted: finished runs are saved; run the same command to resume")
        return exit_status()  # 130 after Ctrl-C, 143 after SIGTERM
    return 1 if outcome.failed else 0


# --- the spec -------------------------------------------------------------------------
@dataclasses.dataclass
class SweepSpec:
    name: str
    source: str
    episodes: int
    seeds: list[int]
    arena: str
    goal: str | None
    config_path: str | None
    world: str | None
    base: dict[str, Any]
    grid: dict[str, list[Any]]
    runs: list[dict[str, Any]]
    eval_every: int
    eval_episodes: int
    competence: float
    text: str = ""
    rotate_deg: float | None = None
    """The arena's rotation for every run (None: the arena file's own ``rotate_deg``)."""


def load_spec(path: str | Path) -> SweepSpec:
    """Read and check a sweep spec; ConfigError (one line) on any problem."""
    from ..store.files import read_text
    from ..store.yamlfile import parse_yaml

    p = Path(path)
    src = str(p)
    try:
        text = read_text(p, MAX_SPEC_BYTES, "sweep spec")
    except KoolioError as exc:
        raise ConfigError(str(exc)) from None
    data = parse_yaml(text, src, ConfigError)
    return parse_spec(data, src, p.parent, default_name=p.stem, text=text)


def parse_spec(
    data: Any, src: str, folder: Path = Path("."), default_name: str = "sweep", text: str = ""
) -> SweepSpec:
    if not isinstance(data, dict):
        raise ConfigError(located(src, "(top level)", "must be a mapping"))
    for key in data:
        if key not in SPEC_KEYS:
            close = difflib.get_close_matches(str(key), SPEC_KEYS, n=1)
            hint = (
                f" (did you mean '{close[0]}'?)" if close else f" (valid: {', '.join(SPEC_KEYS)})"
            )
            raise ConfigError(located(src, str(key), "unknown key" + hint))
    if "episodes" not in data:
        raise ConfigError(located(src, "episodes", "missing"))
    episodes = _int(data["episodes"], src, "episodes", 1, MAX_EPISODES)
    seeds = _seeds(data.get("seeds", 1), src)
    eval_every = _int(
        data.get("eval_every", max(1, episodes // 10)), src, "eval_every", 1, MAX_EPISODES
    )
    eval_episodes = _int(data.get("eval_episodes", 20), src, "eval_episodes", 1, MAX_EPISODES)
    competence = data.get("competence", 0.9)
    if isinstance(competence, bool) or not isinstance(competence, (int, float)):
        raise ConfigError(located(src, "competence", f"expected a number, got {competence!r}"))
    if not 0 < competence <= 1:
        raise ConfigError(located(src, "competence", "must be in (0, 1]"))
    grid = data.get("grid") or {}
    if not isinstance(grid, dict):
        raise ConfigError(located(src, "grid", "must map parameters to lists of values"))
    for key, values in grid.items():
        if not isinstance(values, list) or not values:
            raise ConfigError(located(src, f"grid.{key}", "must be a non-empty list"))
    runs = data.get("runs") or []
    if not isinstance(runs, list) or not all(isinstance(r, dict) for r in runs):
        raise ConfigError(located(src, "runs", "must be a list of mappings"))
    base = data.get("base") or {}
    if not isinstance(base, dict):
        raise ConfigError(located(src, "base", "must be a mapping of configuration overrides"))
    config_path = data.get("config")
    if config_path is not None:
        config_path = _config_ref(str(config_path), folder)
    world = data.get("world")
    if world is not None:
        world = _config_ref(str(world), folder)
    arena = str(data.get("arena", "hallway"))
    goal = data.get("goal")
    rotate = data.get("rotate_deg")
    rotate = None if rotate is None else _rotation(rotate, src, "rotate_deg")
    name = str(data.get("name") or default_name)
    if not re.fullmatch(r"[A-Za-z0-9._-]+", name):
        raise ConfigError(located(src, "name", f"use letters, digits, . _ - only: {name!r}"))
    return SweepSpec(
        name=name,
        source=src,
        episodes=episodes,
        seeds=seeds,
        arena=_arena_ref(arena, folder),
        goal=None if goal is None else str(goal),
        config_path=config_path,
        world=world,
        base=base,
        grid=grid,
        runs=runs,
        eval_every=eval_every,
        eval_episodes=eval_episodes,
        competence=float(competence),
        text=text,
        rotate_deg=rotate,
    )


def _int(value: Any, src: str, item: str, minimum: int, maximum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise ConfigError(located(src, item, f"expected an integer, got {shown(value)}"))
    if value < minimum:
        raise ConfigError(located(src, item, f"must be >= {minimum}, got {value}"))
    if value > maximum:
        raise ConfigError(located(src, item, f"must be <= {maximum:,}, got {shown(value)}"))
    return value


def _rotation(value: Any, src: str, item: str) -> float:
    """An arena rotation in degrees: a finite number."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ConfigError(located(src, item, f"expected a finite number of degrees, got {value!r}"))
    return float(value)


def _seeds(value: Any, src: str) -> list[int]:
    if isinstance(value, int) and not isinstance(value, bool):
        return list(range(_int(value, src, "seeds", 1, MAX_RUNS)))
    if not isinstance(value, list) or not value:
        raise ConfigError(located(src, "seeds", "expected a count or a non-empty list"))
    if len(value) > MAX_RUNS:
        raise ConfigError(
            located(src, "seeds", f"{len(value):,} seeds (the limit is {MAX_RUNS:,})")
        )
    seeds = [_int(v, src, f"seeds[{i}]", 0, SEED_LIMIT - 1) for i, v in enumerate(value)]
    if len(set(seeds)) != len(seeds):
        raise ConfigError(located(src, "seeds", "a seed is listed twice"))
    return seeds


def _relative(name: str, folder: Path) -> Path:
    p = Path(name)
    return p if p.is_absolute() or (folder / p) == p else folder / p


def _config_ref(name: str, folder: Path) -> str:
    """A profile name stays as is; a file name is taken relative to the spec's folder."""
    if name.lower().endswith((".yaml", ".yml")) or "/" in name:
        return str(_relative(name, folder))
    return name


def _arena_ref(arena: str, folder: Path) -> str:
    """A built-in name stays as is; a file name is taken relative to the spec's folder."""
    if arena.lower().endswith((".yaml", ".yml")) or "/" in arena:
        return str(_relative(arena, folder))
    return arena


def expand_dotted(overrides: dict[str, Any]) -> dict[str, Any]:
    """``{"learner.alpha": 0.1, "rewards": {"bump": -5}}`` -> nested mapping (merged).

    >>> expand_dotted({"learner.alpha": 0.1, "learner": {"gamma": 0.9}})
    {'learner': {'alpha': 0.1, 'gamma': 0.9}}
    """
    out: dict[str, Any] = {}
    for key, value in overrides.items():
        parts = str(key).split(".")
        node = out
        for part in parts[:-1]:
            node = node.setdefault(part, {})
            if not isinstance(node, dict):
                raise ConfigError(f"{key}: conflicts with another override")
        leaf = parts[-1]
        if isinstance(value, dict) and isinstance(node.get(leaf), dict):
            node[leaf] = _deep_merge(node[leaf], expand_dotted(value))
        elif isinstance(value, dict):
            node[leaf] = expand_dotted(value)
        else:
            node[leaf] = value
    return out


def _deep_merge(a: dict[str, Any], b: dict[str, Any]) -> dict[str, Any]:
    out = dict(a)
    for k, v in b.items():
        out[k] = (
            _deep_merge(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
        )
    return out


# --- the plan -------------------------------------------------------------------------
def plan(spec: SweepSpec) -> list[dict[str, Any]]:
    """Every run of the sweep as a picklable task (configuration resolved and checked)."""
    from ..store.config import load_config
    from ..world.arena import load_arena

    variants = spec.runs or [{}]
    n_runs = len(variants) * len(spec.seeds)
    for values in spec.grid.values():
        n_runs *= len(values)
    if n_runs > MAX_RUNS:
        raise ConfigError(
            located(spec.source, "grid", f"{n_runs:,} runs (the limit is {MAX_RUNS:,})")
        )
    combos = [dict(zip(spec.grid, values)) for values in itertools.product(*spec.grid.values())]
    tasks: list[dict[str, Any]] = []
    seen: dict[str, str] = {}
    arenas: dict[tuple[str, float], Any] = {}
    for v_index, variant in enumerate(variants):
        for combo in combos:
            params = {k: val for k, val in variant.items() if k != "name"}
            params.update(combo)
            where = f"runs[{v_index}]" if spec.runs else "grid"
            label = _label(variant.get("name"), combo if variant.get("name") else params)
            arena = str(params.pop("arena", spec.arena))
            goal_item = f"{where}: goal" if "goal" in params else "goal"
            goal = params.pop("goal", spec.goal)
            rotate = params.pop("rotate_deg", spec.rotate_deg)
            if rotate is not None:
                rotate = _rotation(rotate, spec.source, f"{where}: rotate_deg")
            goal = None if goal is None else str(goal)
            world = spec.world
            world_item = "world"
            if "world" in params:  # a grid or runs value: relative to the spec, like arena
                given = params.pop("world")
                world = None if given is None else _config_ref(str(given), Path(spec.source).parent)
                world_item = f"{where}: world"
            overrides = _deep_merge(expand_dotted(spec.base), expand_dotted(params))
            try:
                cfg = load_config(spec.config_path, overrides, world=world)
            except KoolioError as exc:
                why = str(exc).removeprefix("<defaults>: ")
                item = where
                for flag, named in (("--world: ", world_item), ("--config: ", "config")):
                    if why.startswith(flag):  # a profile name: the spec's key, not a flag
                        why, item = why.removeprefix(flag), named
                raise ConfigError(f"{spec.source}: {item}: {why}") from None
            key = (arena, cfg.robot.radius)
            if key not in arenas:
                try:
                    arenas[key] = load_arena(arena, cfg.robot.radius)
                except KoolioError as exc:
                    named = "arena" if arena == str(spec.arena) else f"{where}: arena"
                    raise ConfigError(f"{spec.source}: {named}: {exc}") from None
            arena_obj = arenas[key]
            if rotate is not None:  # the paper's trick, swept without a copy of the file
                arena_obj = dataclasses.replace(arena_obj, rotate_deg=rotate)
            if goal is not None and goal != "random" and goal not in arena_obj.goal_names():
                raise ConfigError(
                    f"{spec.source}: {goal_item}: no goal named {goal!r} in {arena} "
                    f"(goals: {', '.join(arena_obj.goal_names())})"
                )
            settings = {
                "arena": arena,
                "goal": goal,
                "world": world,
                "config": cfg.to_dict(),
                "episodes": spec.episodes,
                "eval_every": spec.eval_every,
                "eval_episodes": spec.eval_episodes,
                "competence": spec.competence,
            }
            hashed = {**settings, "arena_content": repr(arena_obj), "checks": CHECKS}
            digest = hashlib.sha256(
                json.dumps(hashed, sort_keys=True, default=str).encode()
            ).hexdigest()[:8]
            config_id = f"{_slug(label)}-{digest}"
            if config_id in seen:
                raise ConfigError(
                    f"{spec.source}: {where}: '{label}' repeats the configuration of "
                    f"'{seen[config_id]}'"
                )
            seen[config_id] = label
            for seed in spec.seeds:
                tasks.append(
                    {
                        **settings,
                        "arena_obj": arena_obj,
                        "rotate_deg": arena_obj.rotate_deg,
                        "seed": seed,
                        "config_id": config_id,
                        "run_id": f"{config_id}/seed{seed}",
                        "label": label,
                        "command": provenance.COMMAND,
                        "params": {
                            **{k: v for k, v in variant.items() if k != "name"},
                            **combo,
                        },
                    }
                )
    return tasks


def _label(name: Any, params: dict[str, Any]) -> str:
    """``name`` (of a ``runs`` entry) then ``param=value`` of the grid (last dotted part)."""
    parts = [str(name)] if name else []
    parts += [f"{k.split('.')[-1]}={_fmt(v)}" for k, v in params.items()]
    return " ".join(parts) or "base"


def _fmt(v: Any) -> str:
    return json.dumps(v, separators=(",", ":")) if isinstance(v, (dict, list)) else str(v)


def _slug(label: str) -> str:
    return re.sub(r"[^A-Za-z0-9.=_-]+", "_", label).strip("_")[:60] or "run"


# --- one run (in a worker process or a Ray task) -------------------------------------
def run_one(task: dict[str, Any]) -> dict[str, Any]:
    """Train and evaluate one run in a private temporary folder.

    The checkpoints are ``koolio-pm train --eval-every``'s checks
    (:class:`~koolio_pymunk.learning.evaluation.PeriodicCheck`: the run's seed, so a run
    and ``train --seed S --eval-every K`` check the same tables on the same episodes); a
    last stretch shorter than ``eval_every`` ends with the same evaluation of the final
    table. Returns ``{"row": result row, "files": {name: bytes}}``; the driver writes the
    files. Depends only on the task (never on the process or node).
    """
    from ..learning.evaluation import evaluate
    from ..learning.training import train
    from ..store.config import config_from_dict
    from ..store.files import read_bytes
    from ..store.qtable import QTableStore
    from ..store.run_identity import learned_digest
    from ..store.worlds import world_name
    from ..task.env import KoolioEnv

    provenance.COMMAND = task.get("command")  # the sweep's, whichever process runs it
    cfg = config_from_dict(task["config"], task["run_id"])
    env = KoolioEnv(arena=task["arena_obj"], config=cfg, goal=task["goal"])
    if task.get("world") is not None:  # its realism is in cfg; the table records its name
        env.world_name = world_name(cfg, task["world"])
    seed = int(task["seed"])
    episodes, every = int(task["episodes"]), int(task["eval_every"])
    checked = int(task["eval_episodes"])
    checkpoints: list[dict[str, Any]] = []
    competence: tuple[int, float] | None = None
    train_seconds = 0.0
    results = []
    remove_stale_run_folders()
    with tempfile.TemporaryDirectory(prefix=f"{RUN_FOLDER_PREFIX}{os.getpid()}-") as tmp:
        store = QTableStore(Path(tmp) / "qtable.qtable", warn=lambda msg: None)
        log = Path(tmp) / "train.csv"
        done = 0
        while done < episodes:  # a stretch of eval_every episodes, ending in its check
            n = min(every, episodes - done)
            res = train(
                env, store, n, seed, log, report=None, eval_every=every, eval_episodes=checked
            )
            if res.interrupted:
                raise KeyboardInterrupt
            results.extend(res.results)
            train_seconds += res.seconds - sum(c.seconds for c in res.checks)
            done += n
            # the stretch's check; after a last stretch shorter than eval_every, the same
            # evaluation of the final table (the check train would make at a multiple)
            ev = res.checks[-1].result if res.checks else evaluate(env, res.table, checked, seed)
            checkpoints.append(
                {
                    "episode": done,
                    "goal_rate": ev.goal_rate,
                    "mean_steps": ev.mean_steps,
                    "mean_bumps": ev.mean_bumps,
                    "mean_return": ev.mean_reward,
                    "train_seconds": round(train_seconds, 3),
                }
            )
            if competence is None and ev.goal_rate >= float(task["competence"]):
                competence = (done, train_seconds)
        table_bytes = read_bytes(store.path)
        digest = learned_digest(res.table)
        log_bytes = read_bytes(log)
    final = checkpoints[-1]
    n = max(1, len(results))
    row = {
        "run_id": task["run_id"],
        "config_id": task["config_id"],
        "label": task["label"],
        "seed": seed,
        "arena": task["arena"],
        "goal": task["goal"] if task["goal"] is not None else env.arena.active_goal,
        "episodes": episodes,
        "final_goal_rate": final["goal_rate"],
        "final_mean_steps": final["mean_steps"],
        "final_mean_bumps": final["mean_bumps"],
        "final_mean_return": final["mean_return"],
        "late_goal_rate": late_goal_rate(checkpoints, episodes),
        "late_low_goal_rate": late_goal_rate(checkpoints, episodes, lowest=True),
        "best_goal_rate": max(c["goal_rate"] for c in checkpoints),
        "competence_episode": competence[0] if competence else "",
        "competence_seconds": round(competence[1], 3) if competence else "",
        "train_goal_rate": sum(r.outcome == "goal" for r in results) / n,
        "train_mean_steps": sum(r.steps for r in results) / n,
        "train_mean_bumps": sum(r.bumps for r in results) / n,
        "states": len(res.table),
        "train_seconds": round(train_seconds, 3),
        "table_sha256": digest,
    }
    for key, value in task["params"].items():
        row[key] = _fmt(value)
    return {
        "row": row,
        "files": {
            "qtable.qtable": table_bytes,
            "train.csv": log_bytes,
            "evals.csv": _csv_bytes(checkpoints),
            "config.yaml": cfg.to_yaml().encode(),
        },
    }


def late_goal_rate(checkpoints: list[dict[str, Any]], episodes: int, lowest: bool = False) -> float:
    """Mean (``lowest``: the lowest) greedy goal rate of the checkpoints after two thirds
    of ``episodes`` (the last checkpoint alone when there is no other): whether a policy
    is held, not only touched.

    >>> checks = [{"episode": e, "goal_rate": e / 10} for e in (1, 2, 3, 4, 5, 6)]
    >>> late_goal_rate(checks, 6), late_goal_rate(checks, 6, lowest=True)
    (0.55, 0.5)
    """
    late = [c["goal_rate"] for c in checkpoints if 3 * c["episode"] > 2 * episodes]
    late = late or [checkpoints[-1]["goal_rate"]]
    return min(late) if lowest else sum(late) / len(late)


#: Temporary run folders: ``<tmp>/koolio-sweep-<pid>-<random>``.
RUN_FOLDER_PREFIX = "koolio-sweep-"


def remove_stale_run_folders(base: str | None = None) -> list[str]:
    """Remove the temporary run folders of processes that no longer run (killed workers,
    interrupted sweeps); returns their names."""
    from ..store.files import process_alive

    base = base or tempfile.gettempdir()
    pattern = re.compile(rf"^{re.escape(RUN_FOLDER_PREFIX)}(\d+)-")
    removed = []
    try:
        names = os.listdir(base)
    except OSError:
        return removed
    for name in names:
        m = pattern.match(name)
        if m is None or int(m.group(1)) == os.getpid() or process_alive(int(m.group(1))):
            continue
        shutil.rmtree(os.path.join(base, name), ignore_errors=True)
        removed.append(name)
    return removed


def _csv_bytes(rows: list[dict[str, Any]], columns: Iterable[str] | None = None) -> bytes:
    cols = list(columns) if columns is not None else (list(rows[0]) if rows else [])
    buf = io.StringIO()
    w = csv.DictWriter(buf, cols, lineterminator="\n", extrasaction="ignore", restval="")
    w.writeheader()
    for r in rows:
        w.writerow({k: _cell(v) for k, v in r.items()})
    return buf.getvalue().encode()


def _cell(v: Any) -> str:
    return repr(v) if isinstance(v, float) else str(v)


# --- the driver -----------------------------------------------------------------------
@dataclasses.dataclass
class SweepOutcome:
    rows: dict[str, dict[str, str]]
    ran: int
    skipped: int
    failed: list[str]
    interrupted: bool
    seconds: float
    out: Path


class Results:
    """``results.csv``: one row per finished run, rewritten atomically after each run."""

    def __init__(self, path: Path) -> None:
        from ..store.files import read_text

        self.path = path
        self.rows: dict[str, dict[str, str]] = {}
        if path.exists():
            text = read_text(path, 256 * 1024 * 1024, "results file")
            try:
                reader = csv.DictReader(io.StringIO(text))
                if text and "run_id" not in (reader.fieldnames or []):
                    raise KoolioError(
                        located(str(path), "line 1", "not a sweep's results.csv (no run_id column)")
                    )
                for row in reader:
                    if row.get("run_id"):
                        self.rows[row["run_id"]] = row
            except csv.Error as exc:  # e.g. a field over the CSV reader's 128 KiB
                raise KoolioError(
                    located(str(path), f"line {reader.line_num}", f"not a CSV row ({exc})")
                ) from None

    def add(self, row: dict[str, Any]) -> None:
        self.rows[str(row["run_id"])] = {k: _cell(v) for k, v in row.items()}

    def save(self, order: list[str]) -> None:
        """Rewrite the file: runs in ``order`` first, then any others (none: a folder with
        another spec's runs is refused, :func:`check_out`)."""
        from ..store.qtable import atomic_write

        cols = list(RESULT_COLUMNS)
        for row in self.rows.values():
            cols += [k for k in row if k not in cols]
        rank = {run_id: i for i, run_id in enumerate(order)}
        ids = sorted(self.rows, key=lambda r: (rank.get(r, len(rank)), r))
        atomic_write(self.path, _csv_bytes([self.rows[i] for i in ids], cols))


def run_sweep(
    spec: SweepSpec,
    out: Path,
    workers: int | None = None,
    ray_address: str | None = None,
    plot: bool = True,
    report: Callable[[str], None] | None = print,
) -> SweepOutcome:
    """Run every unfinished run of ``spec`` into ``out``; see the module docstring.

    ``ray_address`` None runs on local processes; ``""`` on Ray (the running instance if
    ``ray.init`` was called, else a new local one); otherwise on the cluster at that
    address. Local workers are started with ``spawn``: a script calling this must do so
    under ``if __name__ == "__main__":``.
    """
    from ..store.locks import FileLock

    say = report or (lambda s: None)
    started = time.perf_counter()
    tasks = plan(spec)
    lock = FileLock(out, "koolio-pm sweep", path=out / LOCK_NAME)
    if out.exists() and not out.is_dir():
        raise KoolioError(located(str(out), "", "is a file, not a folder (--out)"))
    check_out(out, spec, tasks)  # before the lock: a refused folder gets no lock file
    lock.acquire()
    try:
        check_out(out, spec, tasks)  # again: another sweep may have written it since
        return _run_locked(spec, out, tasks, workers, ray_address, plot, say, started)
    finally:
        lock.release()


#: The lock file of a sweep's output folder.
LOCK_NAME = ".sweep.lock"


def check_out(out: Path, spec: SweepSpec, tasks: list[dict[str, Any]]) -> None:
    """Refuse an output folder whose results a sweep of ``spec`` would mix with its own:
    a folder that is not new, not empty and not a sweep's (no ``spec.yaml`` or
    ``results.csv``: e.g. ``transfer``'s), or a sweep's holding finished runs (rows of
    ``results.csv``, ``runs/*/*/result.json``) that ``spec`` does not plan: another spec's,
    or this one's with another ``--world`` or other defaults. The same spec resumes, and so
    does one that only adds runs (more seeds, another grid value)."""
    if not out.is_dir():
        return
    names = sorted(p.name for p in out.iterdir() if p.name != LOCK_NAME)
    if not names:
        return
    if "spec.yaml" not in names and "results.csv" not in names:
        shown_names = ", ".join(shown(n, 40) for n in names[:3]) + (", ..." * (len(names) > 3))
        raise KoolioError(
            located(
                str(out),
                "--out",
                f"not a sweep's folder (it holds {shown_names}; no spec.yaml or results.csv): "
                "give a new or empty --out",
            )
        )
    done = set(Results(out / "results.csv").rows) if "results.csv" in names else set()
    done |= {f"{p.parent.parent.name}/{p.parent.name}" for p in out.glob("runs/*/*/result.json")}
    others = sorted(done - {t["run_id"] for t in tasks})
    if others:
        raise KoolioError(
            located(
                str(out),
                "--out",
                f"holds {len(others)} finished run{'s' if len(others) > 1 else ''} of another "
                f"spec ({shown(others[0], 80)}{', ...' if len(others) > 1 else ''}; "
                f"{_spec_change(out / 'spec.yaml', spec.text)}), which this spec's would be "
                "mixed with: give a new --out",
            )
        )


def _spec_change(path: Path, text: str) -> str:
    """What differs between the spec in ``path`` (a folder's ``spec.yaml``) and ``text``:
    the first line that does, for a message.
    """
    from ..store.files import read_text

    try:
        old = read_text(path, MAX_SPEC_BYTES, "sweep spec").splitlines()
    except KoolioError:
        return "its spec.yaml is missing or unreadable"
    new = text.splitlines()
    for i, (a, b) in enumerate(itertools.zip_longest(old, new, fillvalue=None), 1):
        if a != b:
            was = "nothing" if a is None else shown(a.strip(), 60)
            now = "nothing" if b is None else shown(b.strip(), 60)
            return f"spec.yaml line {i} was {was}, now {now}"
    return (
        "the same spec.yaml: its runs had another --world, other defaults (an earlier "
        "version's) or arena path"
    )


def _run_locked(
    spec: SweepSpec,
    out: Path,
    tasks: list[dict[str, Any]],
    workers: int | None,
    ray_address: str | None,
    plot: bool,
    say: Callable[[str], None],
    started: float,
) -> SweepOutcome:
    from ..store.files import atomic_write

    remove_stale_run_folders()
    atomic_write(out / "spec.yaml", spec.text.encode())
    results = Results(out / "results.csv")
    order = [t["run_id"] for t in tasks]
    for t in tasks:  # a run whose files were written but whose row was not
        if t["run_id"] not in results.rows:
            adopted = _read_result(out / "runs" / t["run_id"] / "result.json")
            if adopted is not None:
                results.add(adopted)
    todo = [t for t in tasks if t["run_id"] not in results.rows]
    skipped = len(tasks) - len(todo)
    engine = "ray" if ray_address is not None else "local"
    say(
        f"sweep {spec.name}: {len(tasks)} runs ({skipped} already done, {len(todo)} to run) "
        f"on {engine} -> {out}"
    )
    failed: list[str] = []
    interrupted = False
    done = 0

    def finish(task: dict[str, Any], result: dict[str, Any] | BaseException) -> None:
        nonlocal done
        done += 1
        if isinstance(result, BaseException):
            failed.append(task["run_id"])
            say(f"[{done}/{len(todo)}] {task['run_id']}: FAILED: {result!r}")
            return
        _write_run(out / "runs" / task["run_id"], task, result)
        results.add(result["row"])
        results.save(order)
        r = result["row"]
        comp = r["competence_episode"]
        say(
            f"[{done}/{len(todo)}] {task['run_id']}: final goal rate {r['final_goal_rate']:.1%}, "
            f"competent {'at episode ' + str(comp) if comp != '' else 'not reached'}, "
            f"{r['train_seconds']:.1f} s"
        )

    try:
        with terminate_as_interrupt():  # SIGTERM stops a sweep as Ctrl-C does
            if todo:
                if ray_address is not None:
                    _run_ray(todo, ray_address, workers, finish)
                else:
                    _run_local(todo, workers, finish)
    except KeyboardInterrupt:
        interrupted = True
    results.save(order)
    rows = {t["run_id"]: results.rows[t["run_id"]] for t in tasks if t["run_id"] in results.rows}
    _write_configs(out / "configs.csv", tasks, rows)
    if plot and rows:
        _plot_or_note(out, tasks, rows, spec.name, say)
    seconds = time.perf_counter() - started
    say(f"sweep {spec.name}: {len(todo) - len(failed)} runs in {seconds:.1f} s -> {out}")
    return SweepOutcome(rows, len(todo), skipped, failed, interrupted, seconds, out)


def _read_result(path: Path) -> dict[str, Any] | None:
    from ..store.files import read_text

    if not path.exists():
        return None
    try:
        return json.loads(read_text(path, MAX_RUN_FILE_BYTES, "run result"))
    except (KoolioError, ValueError, RecursionError):
        return None


def _write_run(folder: Path, task: dict[str, Any], result: dict[str, Any]) -> None:
    from ..store.files import atomic_write

    for name, data in result["files"].items():
        atomic_write(folder / name, data)
    info = {k: v for k, v in task.items() if k not in ("arena_obj", "config", "command")}
    info["provenance"] = provenance.of_run(task["config"], task.get("command"))
    atomic_write(folder / "run.json", json.dumps(info, indent=2, default=str).encode())
    atomic_write(folder / "result.json", json.dumps(result["row"], indent=2).encode())


def _default_workers(n_tasks: int) -> int:
    return max(1, min(os.cpu_count() or 1, n_tasks))


def _run_local(
    todo: list[dict[str, Any]],
    workers: int | None,
    finish: Callable[[dict[str, Any], Any], None],
) -> None:
    """Local processes (``spawn``: a fresh interpreter per worker, no inherited state)."""
    n = workers or _default_workers(len(todo))
    if n == 1:
        for t in todo:
            try:
                result: Any = run_one(t)
            except KeyboardInterrupt:
                raise
            except Exception as exc:
                result = exc
            finish(t, result)
        return
    run_pool(todo, min(n, len(todo)), finish)


class WorkerDied(RuntimeError):
    """A local worker process ended while it ran a run (killed, out of memory ...)."""


def run_pool(
    todo: list[dict[str, Any]],
    size: int,
    finish: Callable[[dict[str, Any], Any], None],
    target: Callable[[dict[str, Any]], Any] = run_one,
) -> None:
    """Run ``target`` (a module-level function: it is pickled) on every task in ``size``
    worker processes, in order, calling ``finish(task, result)`` as each ends; ``result``
    is what ``target`` returned or the exception it raised.

    Each worker is the standard library's ``concurrent.futures.ProcessPoolExecutor`` of
    one process: a pool whose process dies fails every future it holds
    (``BrokenProcessPool``), so with one pool per worker a death fails only the run that
    worker held (:class:`WorkerDied`, its exit status said), and a new worker takes the
    tasks left. A run interrupted in its worker (SIGTERM) stops the sweep as Ctrl-C does;
    on Ctrl-C or SIGTERM of the sweep the workers are stopped (their runs lost: a resumed
    sweep redoes them). Workers ignore Ctrl-C (the sweep stops them) and end at once,
    quietly, when the sweep is gone (killed)."""
    import concurrent.futures

    queue = list(todo)
    workers: list[_Worker] = []
    try:
        while True:
            for w in workers:
                if w.future is None and queue:
                    w.start(queue.pop(0))
            while queue and len(workers) < size:
                workers.append(_Worker(target))
                workers[-1].start(queue.pop(0))
            busy = {w.future: w for w in workers if w.future is not None}
            if not busy:
                return
            done, _ = concurrent.futures.wait(busy, return_when="FIRST_COMPLETED")
            for future in done:
                w = busy[future]
                task, result = w.task, w.result()
                if isinstance(result, WorkerDied):
                    w.close()
                    workers.remove(w)
                finish(task, result)
    finally:
        for w in workers:  # all at once: each run stops at its next safe point
            w.stop()
        for w in workers:
            w.close()


class _Worker:
    """One worker process of :func:`run_pool`: a ``ProcessPoolExecutor`` of one, started
    with ``spawn`` by a context that keeps the process (its pid and exit status for
    :class:`WorkerDied`; stopped at once on an interrupt)."""

    def __init__(self, target: Callable[[dict[str, Any]], Any]) -> None:
        import concurrent.futures
        import multiprocessing.context

        class Spawn(multiprocessing.context.SpawnContext):
            process: Any = None

            def Process(self, *args: Any, **kwargs: Any) -> Any:
                self.process = super().Process(*args, **kwargs)
                return self.process

        self.spawn = Spawn()
        self.pool = concurrent.futures.ProcessPoolExecutor(
            1, mp_context=self.spawn, initializer=_worker_start, initargs=(os.getpid(),)
        )
        self.target = target
        self.task: dict[str, Any] | None = None
        self.future: Any = None

    def start(self, task: dict[str, Any]) -> None:
        self.task = task
        self.future = self.pool.submit(self.target, task)

    def result(self) -> Any:
        """The finished run's result or exception (:class:`WorkerDied` when the process
        died); a run interrupted in the worker raises ``KeyboardInterrupt`` here."""
        from concurrent.futures.process import BrokenProcessPool

        future, self.future, self.task = self.future, None, None
        try:
            return future.result()
        except BrokenProcessPool:
            proc = self.spawn.process
            deadline = time.monotonic() + 5
            while proc.exitcode is None and time.monotonic() < deadline:
                time.sleep(0.01)  # the pool's own thread reaps it
            return WorkerDied(f"worker process {proc.pid} died ({_exit_reason(proc.exitcode)})")
        except Exception as exc:
            return exc

    def stop(self) -> None:
        """Stop the run the worker holds, if any (SIGTERM: ``train`` stops at its next
        safe point, and the run ends as interrupted)."""
        proc = self.spawn.process
        if self.future is not None and proc is not None and proc.is_alive():
            proc.terminate()

    def close(self) -> None:
        """End the worker, after its stopped run (SIGKILL if that takes over 5 s)."""
        import concurrent.futures

        if self.future is not None:
            _, late = concurrent.futures.wait([self.future], timeout=5)
            if late and self.spawn.process.is_alive():
                self.spawn.process.kill()
        self.pool.shutdown(wait=True, cancel_futures=True)


def _exit_reason(code: int | None) -> str:
    import signal

    if code is not None and code < 0:
        with contextlib.suppress(ValueError):
            return f"killed by {signal.Signals(-code).name}"
    return f"exit status {code}"


def _worker_start(sweep: int) -> None:
    """A worker's start (:func:`run_pool`): Ctrl-C is the sweep's to handle (it stops its
    workers), and a watch that ends the worker, quietly, when the sweep ``sweep`` (a pid)
    is gone: killed, its worker would otherwise wait for tasks for ever."""
    import signal
    import threading

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    threading.Thread(target=_watch_sweep, args=(sweep,), daemon=True).start()


def _watch_sweep(sweep: int) -> None:
    while os.getppid() == sweep:
        time.sleep(0.5)
    os._exit(0)


def _run_ray(
    todo: list[dict[str, Any]],
    address: str,
    workers: int | None,
    finish: Callable[[dict[str, Any], Any], None],
) -> None:
    try:
        import ray
    except ImportError:
        raise KoolioError(
            "--ray: Ray is not installed (pip install 'koolio-pymunk[ray]')"
        ) from None
    started = False
    if not ray.is_initialized():
        if address:
            ray.init(address=address, log_to_driver=False)
        else:
            ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False)
        started = True
    remote = ray.remote(num_cpus=1, max_retries=0)(run_one)
    pending: dict[Any, dict[str, Any]] = {}
    try:
        pending = {remote.remote(t): t for t in todo}
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            for ref in ready:
                task = pending.pop(ref)
                try:
                    result: Any = ray.get(ref)
                except Exception as exc:
                    result = exc
                finish(task, result)
    except KeyboardInterrupt:
        for ref in pending:
            with contextlib.suppress(Exception):
                ray.cancel(ref, force=True)
        raise
    finally:
        if started:
            ray.shutdown()


# --- summaries and plots --------------------------------------------------------------
def _configs(tasks: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    out: dict[str, dict[str, Any]] = {}
    for t in tasks:
        out.setdefault(t["config_id"], {"label": t["label"], "runs": []})["runs"].append(t)
    return out


def _stats(values: list[float]) -> tuple[float, float]:
    if not values:
        return float("nan"), float("nan")
    mean = sum(values) / len(values)
    var = sum((v - mean) ** 2 for v in values) / len(values)
    return mean, var**0.5


def config_summary(
    tasks: list[dict[str, Any]], rows: dict[str, dict[str, str]]
) -> list[dict[str, Any]]:
    """Per configuration: seeds finished, mean and std of the final figures (and the
    lowest and highest final goal rate), competence, and the table's size: ``states``
    visited (mean and std over seeds) out of ``state_space``, the number of states the
    sensor layout can encode (the paper's dense table has 5 entries per state)."""
    out = []
    for cid, c in _configs(tasks).items():
        got = [rows[t["run_id"]] for t in c["runs"] if t["run_id"] in rows]
        entry: dict[str, Any] = {"config_id": cid, "label": c["label"], "seeds": len(got)}
        for col in (
            "final_goal_rate",
            "late_goal_rate",
            "late_low_goal_rate",
            "best_goal_rate",
            "final_mean_steps",
            "final_mean_bumps",
            "states",
        ):
            mean, std = _stats([float(r[col]) for r in got if r.get(col, "") != ""])
            entry[f"{col}_mean"], entry[f"{col}_std"] = mean, std
            if col in ("final_goal_rate", "late_low_goal_rate", "best_goal_rate"):
                rates = [float(r[col]) for r in got if r.get(col, "") != ""]
                entry[f"{col}_min"] = min(rates) if rates else float("nan")
                entry[f"{col}_max"] = max(rates) if rates else float("nan")
        comp = [int(r["competence_episode"]) for r in got if r["competence_episode"] != ""]
        entry["competent_seeds"] = len(comp)
        entry["competence_episode_mean"] = sum(comp) / len(comp) if comp else ""
        entry["state_space"] = _state_space(c["runs"][0]["config"])
        out.append(entry)
    return out


def _state_space(config: dict[str, Any]) -> int:
    """States the configuration's sensor layout can encode (a dense table's rows)."""
    from ..store.config import config_from_dict, state_fields

    return math.prod(levels for _, levels in state_fields(config_from_dict(config).sensors))


def _write_configs(path: Path, tasks: list[dict[str, Any]], rows: dict[str, Any]) -> None:
    from ..store.qtable import atomic_write

    summary = config_summary(tasks, rows)
    if summary:
        atomic_write(path, _csv_bytes(summary))


def print_summary(rows: dict[str, dict[str, str]], tasks: list[dict[str, Any]]) -> None:
    """Per configuration: final greedy goal rate (mean ± std and min-max over seeds),
    late goal rate, competent seeds @ their mean episode of competence, steps, bumps,
    states visited."""
    print(
        f"  {'configuration':<36} {'seeds':>5} {'goal rate':>15} {'min-max':>11} "
        f"{'late':>6} {'competent':>11} {'steps':>7} {'bumps':>6} {'states':>7}"
    )
    for e in config_summary(tasks, rows):
        if not e["seeds"]:
            print(f"  {e['label'][:36]:<36} {0:>5}  (not run)")
            continue
        comp = (
            f"{e['competent_seeds']}/{e['seeds']} @{e['competence_episode_mean']:.0f}"
            if e["competent_seeds"]
            else f"0/{e['seeds']}"
        )
        rate = f"{e['final_goal_rate_mean']:.1%} ±{e['final_goal_rate_std']:.1%}"
        spread = f"{e['final_goal_rate_min']:.0%}-{e['final_goal_rate_max']:.0%}"
        print(
            f"  {e['label'][:36]:<36} {e['seeds']:>5} {rate:>15} {spread:>11} "
            f"{e['late_goal_rate_mean']:>6.1%} {comp:>11} "
            f"{e['final_mean_steps_mean']:>7.1f} {e['final_mean_bumps_mean']:>6.1f} "
            f"{e['states_mean']:>7.0f}"
        )


def _plot_or_note(
    out: Path,
    tasks: list[dict[str, Any]],
    rows: dict[str, Any],
    title: str,
    say: Callable[[str], None],
) -> None:
    """:func:`plot_curves`, or a note naming the extra when matplotlib is not installed:
    the runs are done and saved, a missing plot is no reason to fail the sweep."""
    from ..store.extras import MissingExtra, view_extra

    try:
        with view_extra("sweep: curves.png"):
            plot_curves(out, tasks, rows, title)
    except MissingExtra as exc:
        say(f"note: {exc}; curves.png skipped")


def _rolling_goal_rate(log: Path, window: int) -> list[float]:
    from .plotting import outcome_rate, read_log

    return outcome_rate(read_log(log).outcome, "goal", window).tolist()


def _read_evals(path: Path) -> tuple[list[int], list[float]]:
    from ..store.files import read_text

    rows = list(csv.DictReader(io.StringIO(read_text(path, MAX_RUN_FILE_BYTES, "evaluation log"))))
    return [int(r["episode"]) for r in rows], [float(r["goal_rate"]) for r in rows]


def plot_curves(
    out: Path, tasks: list[dict[str, Any]], rows: dict[str, Any], title: str = ""
) -> Path:
    """``curves.png``: per configuration, mean (line) and min-max (band) over seeds of the
    training goal rate (rolling window) and of the greedy checkpoint goal rate."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..store.qtable import atomic_write

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.8), constrained_layout=True)
    for k, (_, c) in enumerate(_configs(tasks).items()):
        runs = [t for t in c["runs"] if t["run_id"] in rows]
        if not runs:
            continue
        color = f"C{k % 10}"
        window = max(1, runs[0]["episodes"] // 20)
        curves = [
            _rolling_goal_rate(out / "runs" / t["run_id"] / "train.csv", window) for t in runs
        ]
        _band(ax1, range(1, len(curves[0]) + 1), curves, color, f"{c['label']} ({len(runs)})")
        evals = [_read_evals(out / "runs" / t["run_id"] / "evals.csv") for t in runs]
        _band(ax2, evals[0][0], [e[1] for e in evals], color, c["label"], marker="o")
    ax1.set(
        title="training: goal rate (rolling)",
        xlabel="episode",
        ylabel="fraction of episodes at the goal",
        ylim=(-0.02, 1.02),
    )
    ax2.set(title="greedy evaluation checkpoints", xlabel="episode", ylim=(-0.02, 1.02))
    ax1.legend(fontsize="small", title="configuration (seeds)", loc="lower right")
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
    fig.suptitle(f"{title or out.name}: mean over seeds, band = min..max")
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    plt.close(fig)
    path = out / "curves.png"
    atomic_write(path, buf.getvalue())
    return path


def _band(ax, xs, curves: list[list[float]], color: str, label: str, marker=None) -> None:
    n = min(len(c) for c in curves)
    xs = list(xs)[:n]
    cols = list(zip(*(c[:n] for c in curves)))
    mean = [sum(c) / len(c) for c in cols]
    ax.plot(xs, mean, color=color, label=label, marker=marker, markersize=3)
    if len(curves) > 1:
        ax.fill_between(xs, [min(c) for c in cols], [max(c) for c in cols], color=color, alpha=0.2)
