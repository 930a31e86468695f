"""``koolio-pm``: the command line.

Every command prints a one-line ``koolio-pm: error: ...`` and exits with status 2 on bad
input (a malformed arena, a corrupt or mismatched Q-table, a wrong flag, a file that
cannot be read or written), never a traceback, and leaves existing files as they were.
Commands that need drawing (``view``, ``plot``, ``edit``) import pygame / matplotlib only
when they run; without the ``view`` extra they say which extra to install
(:mod:`koolio_pymunk.extras`) and exit 2.

Files: the Q-table and the log default to ``runs/<arena>.qtable`` and ``runs/<arena>.csv``
(``<arena>``: the built-in name, or the arena file's stem), so runs in different arenas
never share them.
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import NoReturn

from . import __version__
from .errors import KoolioError, located

DEFAULT_QTABLE = "runs/hallway.qtable"
DEFAULT_LOG = "runs/hallway.csv"
DEFAULT_EPISODES = 1500
#: Most robots of ``train --robots`` (each is a copy of the arena in one pymunk space).
MAX_ROBOTS = 1024


def default_files(arena: str) -> tuple[str, str]:
    """The default Q-table and log of runs in ``arena`` (a built-in name or a file).

    >>> default_files("room"), default_files("arenas/lab.yaml")
    (('runs/room.qtable', 'runs/room.csv'), ('runs/lab.qtable', 'runs/lab.csv'))
    """
    stem = Path(arena).stem or "arena"
    return f"runs/{stem}.qtable", f"runs/{stem}.csv"


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (no usage block), ``koolio-pm: error: ...`` like every
    other error, and exit status 2."""

    def error(self, message: str) -> NoReturn:
        sub = self.prog.removeprefix("koolio-pm").strip()
        where = f" (see koolio-pm {sub} --help)" if sub else " (see koolio-pm --help)"
        self.exit(2, f"koolio-pm: error: {' '.join(message.split())}{where}\n")


def seed_type(text: str) -> int:
    """``--seed``: an integer >= 0 (numpy seeds are non-negative)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text[:40]!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {value}")
    return value


def add_env_args(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--arena", default="hallway", help="arena file or built-in name (hallway, room, obstacles)"
    )
    p.add_argument(
        "--config",
        default=None,
        help="YAML configuration file, or a shipped profile name (paper, ...; see config.py)",
    )
    add_world_arg(p)
    p.add_argument(
        "--goal",
        default=None,
        help="goal name (default: the arena's active goal); 'random': a random goal per episode",
    )
    p.add_argument("--seed", type=seed_type, default=0, help="run seed, >= 0 (default 0)")


def add_world_arg(p: argparse.ArgumentParser) -> None:
    """``--world``: a world profile (realism models, sensor noise) over the configuration."""
    p.add_argument(
        "--world",
        default=None,
        help="world profile name (e.g. koolio-real) or file laid over the configuration: "
        "realism models and sensor noise only (default: the ideal world)",
    )


def add_learning_files_args(p: argparse.ArgumentParser) -> None:
    """``--qtable`` and ``--log``, shared by ``train`` and ``view`` (:func:`resolve_files`)."""
    p.add_argument(
        "--qtable",
        default=None,
        help="Q-table file, resumed if present; backup beside it (default runs/<arena>.qtable)",
    )
    p.add_argument(
        "--log",
        default=None,
        help="per-episode CSV log (default runs/<arena>.csv, or beside a given --qtable: "
        "X.qtable -> X.csv; '' for none)",
    )
    p.set_defaults(files_follow_arena=True)


def resolve_files(args: argparse.Namespace) -> None:
    """Fill in the default ``--qtable`` / ``--log``, refuse empty names.

    For the commands that declare ``files_follow_arena`` (train, eval, view) the defaults
    follow the arena (:func:`default_files`); a ``--qtable`` given without
    ``--log`` takes the log beside it (``runs/back.qtable`` -> ``runs/back.csv``), so a new
    table never meets another run's log.
    """
    from .files import check_path

    check_path(args.arena, "--arena")
    if getattr(args, "files_follow_arena", False):  # train, eval, view (not transfer)
        table, log = default_files(args.arena)
        if getattr(args, "log", "") is None:
            given = args.qtable
            beside = given is not None and Path(given).name
            args.log = str(Path(given).with_suffix(".csv")) if beside else log
        if args.qtable is None:
            args.qtable = table
    for flag in ("qtable", "init_qtable", "config", "world"):  # --log '': no log
        value = getattr(args, flag, None)
        if value is not None:
            check_path(value, "--" + flag.replace("_", "-"))


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="koolio-pm",
        description="Koolio, the FCRAR 2008 delivery robot, learning by Q-learning on pymunk.",
    )
    parser.add_argument("--version", action="version", version=f"koolio-pm {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    p = sub.add_parser("train", help="headless episodic Q-learning")
    add_env_args(p)
    p.add_argument(
        "--episodes",
        type=int,
        default=DEFAULT_EPISODES,
        help=f"episodes to run (default {DEFAULT_EPISODES})",
    )
    add_learning_files_args(p)
    p.add_argument(
        "--discard-unfinished",
        action="store_true",
        help="on Ctrl-C discard the unfinished episode (Exit Without Save)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.add_argument(
        "--robots",
        type=int,
        default=1,
        help="robots learning into one shared table, each in its own copy of the arena (default 1)",
    )
    p.add_argument(
        "--init-qtable",
        default=None,
        help="start from this table (e.g. one back from the robot) when --qtable "
        "does not exist yet",
    )

    p = sub.add_parser("eval", help="greedy evaluation of a Q-table")
    add_env_args(p)
    p.add_argument(
        "--qtable",
        default=None,
        help="Q-table file (.qtable, or a policy exported for the robot; default "
        "runs/<arena>.qtable)",
    )
    p.set_defaults(files_follow_arena=True)
    p.add_argument("--episodes", type=int, default=100, help="episodes (default 100)")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")

    p = sub.add_parser("check-arena", help="validate an arena file")
    p.add_argument("file", help="arena file or built-in name")
    p.add_argument("--robot", default="koolio", help="robot profile for clearance checks")

    p = sub.add_parser("info", help="state-space sizes (paper §5.4.8) and table figures")
    p.add_argument("--config", default=None, help="YAML configuration file")
    p.add_argument("--qtable", default=None, help="also describe this Q-table file")

    for name, module in EXTRA_COMMANDS.items():
        mod = importlib.import_module(module)
        p = sub.add_parser(name, help=(mod.__doc__ or name).strip().splitlines()[0])
        mod.add_arguments(p)
    return parser


#: Commands that live in their own modules: each module has ``add_arguments(parser)`` and
#: ``run(args) -> int`` and imports heavy dependencies (pygame, matplotlib, ray) in ``run``.
EXTRA_COMMANDS: dict[str, str] = {
    "view": "koolio_pymunk.viewer.app",
    "plot": "koolio_pymunk.plotting",
    "export": "koolio_pymunk.export",
    "sweep": "koolio_pymunk.sweep",
    "edit": "koolio_pymunk.editor.command",
    "transfer": "koolio_pymunk.transfer",
}


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        if hasattr(args, "arena"):
            resolve_files(args)
        if args.command in EXTRA_COMMANDS:
            return int(importlib.import_module(EXTRA_COMMANDS[args.command]).run(args) or 0)
        return int(COMMANDS[args.command](args) or 0)
    except KoolioError as exc:
        print(f"koolio-pm: error: {one_line(str(exc))}", file=sys.stderr)
        return 2
    except ModuleNotFoundError as exc:  # pygame / matplotlib without the [view] extra
        from .extras import missing_extra

        missing = missing_extra(exc, args.command)
        if missing is None:
            raise
        print(f"koolio-pm: error: {missing}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # e.g. `koolio-pm info | head -1`: the reader left, not an error
        # Python's documented recipe: point stdout at devnull so the exit flush is quiet.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as exc:  # a file error no command turned into a KoolioError itself
        from .files import os_problem

        where = f"{exc.filename}: " if exc.filename else ""
        print(f"koolio-pm: error: {where}{one_line(os_problem(exc))}", file=sys.stderr)
        return 2
    except (RecursionError, MemoryError) as exc:
        what = "nested too deeply" if isinstance(exc, RecursionError) else "out of memory"
        print(f"koolio-pm: error: {args.command}: input too large ({what})", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("koolio-pm: interrupted", file=sys.stderr)
        return 130


def one_line(text: str, limit: int = 2000) -> str:
    """``text`` on one line, at most ``limit`` characters (an error message)."""
    text = " ".join(text.split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


# --- commands ---------------------------------------------------------------------------


def _make_env(args: argparse.Namespace):
    from .env import KoolioEnv

    env = KoolioEnv(arena=args.arena, config=args.config, goal=args.goal, world=args.world)
    warn_endless(env.config)
    return env


def warn_endless(cfg) -> None:
    """A warning when episodes may never end (no step cap)."""
    if cfg.episode.max_steps == 0:
        print(
            "warning: episode.max_steps is 0 (no step cap): an episode ends only at the goal "
            "or off the end of the world, and a policy that never gets there runs for ever",
            file=sys.stderr,
        )


def _positive(value: int, flag: str) -> None:
    if value < 0:
        raise KoolioError(f"{flag}: must be >= 0, got {value}")


def cmd_train(args: argparse.Namespace) -> int:
    from .qtable import QTableStore
    from .training import train

    _positive(args.episodes, "--episodes")
    if not 1 <= args.robots <= MAX_ROBOTS:
        raise KoolioError(f"--robots: must be in 1..{MAX_ROBOTS}, got {args.robots}")
    env = _make_env(args)
    say = (lambda s: None) if args.quiet else print
    say("koolio-pm train")
    for key in (
        "arena",
        "goal",
        "episodes",
        "seed",
        "qtable",
        "log",
        "config",
        "world",
        "robots",
        "init_qtable",
        "discard_unfinished",
    ):
        say(f"  {key}: {getattr(args, key)}")
    say(f"  active goal: {env.goal_name} at {env.world_arena.goal().at}")
    say("configuration:")
    for line in env.config.to_yaml().splitlines():
        say("  " + line)
    store = QTableStore(args.qtable, purpose="koolio-pm train")
    if args.init_qtable:
        _seed_table(args.init_qtable, store, args.log, env, say)
    report = None if args.quiet else print
    if args.robots > 1:
        from .multi import train_many

        result = train_many(
            env,
            store,
            args.episodes,
            args.seed,
            args.log,
            robots=args.robots,
            discard_unfinished=args.discard_unfinished,
            report=report,
        )
    else:
        result = train(
            env,
            store,
            args.episodes,
            args.seed,
            args.log,
            discard_unfinished=args.discard_unfinished,
            report=report,
        )
    rate = result.goals / max(1, result.episodes_run)
    say(
        f"done: {result.episodes_run} episodes, {result.goals} at the goal ({rate:.1%}), "
        f"{result.steps} steps in {result.seconds:.1f} s "
        f"({result.steps / max(1e-9, result.seconds):.0f} steps/s); "
        f"table {len(result.table)} states -> {args.qtable}"
    )
    return 130 if result.interrupted else 0


def _seed_table(init_path: str, store, log: str, env, say) -> None:
    """``--init-qtable``: start a new table file from another table (either format). The
    new table's log must be new too (its episodes continue the other table's count)."""
    from .arena import arena_record
    from .episode_log import check_log_path, log_rows
    from .export import load_any_table
    from .learner import adopt
    from .qtable import check_compatible
    from .training import sensor_signature

    store.lock()
    if store.path.exists() or store.backup.exists():
        store.close()
        raise KoolioError(
            f"--init-qtable: {store.path} already exists; it would be resumed "
            "instead (choose a new --qtable)"
        )
    try:
        if log:
            check_log_path(log, store.path)
        if log and log_rows(log):
            raise KoolioError(
                located(log, "", "holds rows of another run: give --init-qtable a new --log")
            )
        table = load_any_table(init_path)
        check_compatible(
            table, env.layout, sensor_signature(env.config), init_path, arena_record(env.arena)
        )
        adopt(table, env.config.learner, init_path)  # its Q values, this run's algorithm
        store.create(table)
    except BaseException:
        store.close()
        raise
    say(
        f"  starting from {init_path}: {len(table)} states, "
        f"{table.meta.get('episodes', 0)} episodes"
    )


def cmd_eval(args: argparse.Namespace) -> int:
    from .arena import arena_record
    from .export import load_any_table
    from .qtable import check_compatible
    from .training import evaluate, sensor_signature

    _positive(args.episodes, "--episodes")
    goal_all = args.goal == "all"
    if goal_all:
        args.goal = None
    env = _make_env(args)
    table = load_any_table(args.qtable)
    check_compatible(
        table, env.layout, sensor_signature(env.config), args.qtable, arena_record(env.arena)
    )
    goals = env.arena.goal_names() if goal_all else [None]
    results = [evaluate(env, table, args.episodes, args.seed, goal=g) for g in goals]
    if args.json:
        out = [r.as_dict() for r in results]
        print(json.dumps(out if goal_all else out[0], sort_keys=True))
        return 0
    print(
        f"greedy evaluation of {args.qtable} on {env.arena.name}, {args.episodes} "
        f"episodes per goal, seed {args.seed}"
    )
    print(
        f"  {'goal':>6} {'goal rate':>10} {'end of world':>13} {'truncated':>10} "
        f"{'mean steps':>11} {'mean bumps':>11} {'mean return':>12}"
    )
    for r in results:
        print(
            f"  {r.goal:>6} {r.goal_rate:>10.1%} {r.end_of_world_rate:>13.1%} "
            f"{r.truncated_rate:>10.1%} {r.mean_steps:>11.1f} {r.mean_bumps:>11.1f} "
            f"{r.mean_reward:>12.1f}"
        )
    if goal_all:
        mean = sum(r.goal_rate for r in results) / len(results)
        print(f"  {'all':>6} {mean:>10.1%}")
    return 0


def cmd_check_arena(args: argparse.Namespace) -> int:
    from .arena import load_arena
    from .config import ROBOT_PROFILES

    if args.robot not in ROBOT_PROFILES:
        raise KoolioError(
            f"--robot: unknown profile {args.robot!r} (valid: {', '.join(ROBOT_PROFILES)})"
        )
    arena = load_arena(args.file, ROBOT_PROFILES[args.robot])
    xmin, ymin, xmax, ymax = arena.bounds()
    print(
        f"{arena.source}: ok: '{arena.name}', {len(arena.walls)} wall points, "
        f"{len(arena.obstacles)} obstacles, {len(arena.goals)} goals "
        f"(active {arena.active_goal}), {len(arena.end_of_world)} end-of-world markers, "
        f"{xmax - xmin:g} x {ymax - ymin:g} in"
    )
    return 0


def cmd_info(args: argparse.Namespace) -> int:
    from .config import load_config
    from .export import load_any_table
    from .qtable import PAPER_ORIGINAL_FIELDS, KeywordLayout, human_bytes
    from .sensors import state_fields

    cfg = load_config(args.config)
    paper = KeywordLayout(PAPER_ORIGINAL_FIELDS)
    now = KeywordLayout(tuple(state_fields(cfg.sensors)))
    print("State space (paper §5.4.8; dense tables of 8-byte doubles):")
    for title, lay in (
        ("paper's first design (compass, 6 cameras x 4, 8 sonars x 5)", paper),
        ("this configuration", now),
    ):
        print(f"  {title}:")
        print(f"    states  {lay.n_states:>16,}")
        print(f"    entries {lay.n_entries:>16,}  (x {lay.n_actions} actions)")
        print(f"    dense   {human_bytes(lay.dense_bytes()):>16}")
    print(f"Keyword ({now.total_bits} bits, Table 12):")
    print("  " + " | ".join(f"{n}<<{s}" for (n, _), s in zip(now.fields, now.shifts)) + " | Action")
    if args.qtable:
        table = load_any_table(args.qtable)
        share = table.entries / table.layout.n_entries
        print(
            f"Q-table {args.qtable}: {len(table):,} states visited, {table.entries:,} entries "
            f"({share:.3%} of dense), {human_bytes(table.nbytes())} in the file, "
            f"{table.meta.get('episodes', 0)} episodes"
        )
        rec = table.meta.get("algorithm")
        if isinstance(rec, dict):
            params = ", ".join(f"{k} {v}" for k, v in rec.items() if k != "name")
            sections = ", ".join(f"{k} {human_bytes(len(v))}" for k, v in table.sections.items())
            print(
                f"  learned with {rec.get('name')} ({params})"
                + (f"; {sections}" if sections else "")
            )
    return 0


COMMANDS = {
    "train": cmd_train,
    "eval": cmd_eval,
    "check-arena": cmd_check_arena,
    "info": cmd_info,
}


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
