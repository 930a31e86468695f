"""``koolio-pm``: the command line.

Every command prints a one-line ``koolio-pm: error: ...`` and exits with status 2 on bad
input (a malformed arena, a corrupt or mismatched Q-table, a wrong flag, a file that
cannot be read or written), never a traceback, and leaves existing files as they were.
Commands that need drawing (``view``, ``plot``, ``edit``) import pygame / matplotlib only
when they run; without the ``view`` extra they say which extra to install
(:mod:`koolio_pymunk.store.extras`) and exit 2.

Files: the Q-table and the log default to ``runs/<arena>.qtable`` and ``runs/<arena>.csv``
(``<arena>``: the built-in name, or the arena file's stem), so runs in different arenas
never share them.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import difflib
import importlib
import json
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import NoReturn

from .. import __version__
from ..store.errors import KoolioError, located
from ..store.interrupts import exit_status
from .flags import MAX_EPISODES, episodes_type, file_name, float_type, int_type, seed_type

DEFAULT_QTABLE = "runs/hallway.qtable"
DEFAULT_LOG = "runs/hallway.csv"
DEFAULT_EPISODES = 1500
#: Most robots of ``train --robots`` (each runs in its own copy of the arena).
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
    other error, and exit status 2; no abbreviated flags (``--episode`` is not
    ``--episodes``), and a did-you-mean for a mistyped flag or command."""

    def __init__(self, *args, **kwargs) -> None:
        kwargs["allow_abbrev"] = False  # every parser and subparser: whole flags only
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        sub = self.prog.removeprefix("koolio-pm").strip()
        where = f" (see koolio-pm {sub} --help)" if sub else " (see koolio-pm --help)"
        # "--seed: ..." as every other error names its item (argparse: "argument --seed:")
        message = " ".join(message.split()).removeprefix("argument ")
        self.exit(2, f"koolio-pm: error: {message}{where}\n")

    def parse_args(self, args=None, namespace=None):  # type: ignore[override]
        """As argparse's, with a did-you-mean on unknown flags, from the parser of the
        command they were given to."""
        ns, extras = self.parse_known_args(args, namespace)
        if extras:
            parser = self._command_parser(ns)
            message = f"unrecognized arguments: {' '.join(extras)}"
            parser.error(message + did_you_mean(extras, parser))
        return ns

    def _command_parser(self, ns: argparse.Namespace) -> argparse.ArgumentParser:
        for action in self._actions:
            if isinstance(action, argparse._SubParsersAction):
                return action.choices.get(getattr(ns, "command", None), self)
        return self

    def _check_value(self, action: argparse.Action, value) -> None:
        """An unknown command: argparse's message and the closest command."""
        try:
            super()._check_value(action, value)
        except argparse.ArgumentError as exc:
            close = difflib.get_close_matches(str(value), list(action.choices or ()), n=1)
            if not close:
                raise
            message = f"{exc.message}; did you mean {close[0]!r}?"
            raise argparse.ArgumentError(action, message) from None


def did_you_mean(words: Sequence[str], parser: argparse.ArgumentParser) -> str:
    """``; did you mean --episodes?`` for the first of ``words`` that looks like a
    mistyped flag of ``parser`` (empty when none does)."""
    flags = [o for a in parser._actions for o in a.option_strings if o.startswith("--")]
    for word in words:
        if not word.startswith("--"):
            continue
        name = word.split("=", 1)[0]
        started = [f for f in flags if f.startswith(name)]
        if len(started) == 1:  # a flag cut short: --epi -> --episodes
            return f"; did you mean {started[0]}?"
        close = difflib.get_close_matches(name, flags, n=1, cutoff=0.6)
        if close:
            return f"; did you mean {close[0]}?"
    return ""


def add_env_args(p: argparse.ArgumentParser, every_goal: bool = False) -> None:
    """``--arena``, ``--config``, ``--world``, ``--goal`` and ``--seed``; ``every_goal``:
    ``--goal all`` is taken too (``eval``: a table per door)."""
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
        help="goal name (default: the arena's active goal); 'random': a random goal per episode"
        + ("; 'all': each goal in turn, a row per door" if every_goal else ""),
    )
    p.add_argument("--seed", type=seed_type, default=0, help="run seed, 0..2**63-1 (default 0)")


def add_world_arg(p: argparse.ArgumentParser) -> None:
    """``--world``: a world profile (realism models, sensor noise) over the configuration."""
    p.add_argument(
        "--world",
        default=None,
        help="world profile name (e.g. koolio-real) or file laid over the configuration: "
        "realism models and sensor noise only (default, or 'ideal': none, the ideal world)",
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


def add_robots_args(p: argparse.ArgumentParser, robots_help: str) -> None:
    """``--robots N`` (``robots_help`` says what they do for the command) and
    ``--shared-arena`` (train, eval, view)."""
    p.add_argument("--robots", type=int_type(1, MAX_ROBOTS), default=1, help=robots_help)
    p.add_argument(
        "--shared-arena",
        action="store_true",
        help="with --robots N: the robots share one arena, bodies to each other "
        "(docs/multi-robot.md)",
    )


def add_tables_arg(p: argparse.ArgumentParser) -> None:
    """``--tables shared|each`` (train, view): with ``--robots N --shared-arena``, one
    table all robots learn into, or each robot its own rows of it."""
    p.add_argument(
        "--tables",
        choices=("shared", "each"),
        default="shared",
        help="with --robots N --shared-arena: one table all robots learn into (shared, the "
        "default) or each robot its own rows of it (each: the keyword leads with the "
        "robot's index; docs/multi-robot.md)",
    )


def check_shared_arena(args: argparse.Namespace, env) -> None:
    """``--shared-arena``'s combinations, before any file is touched: it needs --robots N
    with N >= 2, and the robots must fit their start areas (one line each)."""
    if not getattr(args, "shared_arena", False):
        if getattr(args, "tables", "shared") == "each":
            raise KoolioError(
                "--tables each: needs --robots N --shared-arena (robots alone in copies of "
                "the arena, each learning only its own rows, are N separate runs: run N "
                "trains)"
            )
        return
    if args.robots < 2:
        raise KoolioError(
            "--shared-arena: needs --robots N with N >= 2 (the robots that share the arena)"
        )
    from ..store.keyword import own_tables
    from ..task.shared_arena import SharedArena

    SharedArena(env.arena, env.config, args.robots)  # the start areas hold the robots
    if getattr(args, "tables", "shared") == "each":
        try:
            own_tables(env.layout, args.robots)
        except ValueError as e:
            raise KoolioError(
                f"--tables each: {e}: fewer robots or sensors, or --tables shared"
            ) from None


def resolve_files(args: argparse.Namespace) -> None:
    """Fill in the default ``--qtable`` / ``--log``, refuse empty names.

    For the commands that declare ``files_follow_arena`` (train, eval, view) the defaults
    follow the arena (:func:`default_files`); a ``--qtable`` given without
    ``--log`` takes the log beside it (``runs/back.qtable`` -> ``runs/back.csv``), so a new
    table never meets another run's log.
    """
    from ..store.files import check_path

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
        type=episodes_type(),
        default=DEFAULT_EPISODES,
        help=f"episodes the table holds when the run ends, 0..{MAX_EPISODES:,}: a total, not "
        "more; a resumed table (e.g. after Ctrl-C) trains only the rest, and one that holds "
        f"as many already is left as it is (default {DEFAULT_EPISODES})",
    )
    add_learning_files_args(p)
    p.add_argument(
        "--discard-unfinished",
        action="store_true",
        help="on Ctrl-C discard the unfinished episode (Exit Without Save)",
    )
    p.add_argument(
        "--save-every",
        type=int_type(1, MAX_EPISODES),
        default=None,
        metavar="K",
        help="save the table every K finished episodes instead of after each one (the "
        "default with one robot; --robots N: N), and always at the end, on Ctrl-C and on "
        "SIGTERM",
    )
    p.add_argument(
        "--tensorboard",
        type=file_name,
        default=None,
        metavar="DIR",
        help="also write the run's scalars (every episode's return, steps, bumps, goal, "
        "epsilon; the training goal rate; the checks of --eval-every) as TensorBoard event "
        "files in DIR, at the environment step each episode ended on",
    )
    p.add_argument(
        "--fsync",
        choices=("second", "episode"),
        default="second",
        help="how a save reaches the disk: 'second' (default) writes the table whole and "
        "fsynced at most once a second, the end, Ctrl-C and SIGTERM, and each finished "
        "episode's changes in between to its journal (a killed run loses no finished "
        "episode, a power loss at most the last second); 'episode', the paper's rule, "
        "writes and fsyncs it whole at every save",
    )
    p.add_argument(
        "--save-seconds",
        type=float_type(0.0, 1e9, low_open=True),
        default=None,
        metavar="T",
        help="also save when T seconds passed since the last save",
    )
    p.add_argument("--quiet", action="store_true", help="print nothing but errors and warnings")
    p.add_argument(
        "--verbose",
        action="store_true",
        help="also print the flags and the whole configuration before training",
    )
    add_robots_args(
        p,
        "robots learning into one shared table, each in its own copy of the arena (default 1; "
        "with --shared-arena all in one)",
    )
    add_tables_arg(p)
    p.add_argument(
        "--init-qtable",
        default=None,
        help="start from this table (e.g. one back from the robot) when --qtable "
        "does not exist yet",
    )
    p.add_argument(
        "--eval-every",
        type=int_type(1, MAX_EPISODES),
        default=None,
        metavar="N",
        help="a greedy check every N episodes (of the table's count): X.evals.csv beside "
        "the log, the best table kept as X.best.qtable (one robot only)",
    )
    p.add_argument(
        "--eval-episodes",
        type=int_type(1, MAX_EPISODES),
        default=None,
        metavar="M",
        help="greedy episodes per check (default 100; with --eval-every)",
    )

    p = sub.add_parser("eval", help="greedy evaluation of a Q-table")
    add_env_args(p, every_goal=True)
    p.add_argument(
        "--qtable",
        default=None,
        help="Q-table file (.qtable, or a policy exported for the robot; default "
        "runs/<arena>.qtable)",
    )
    p.set_defaults(files_follow_arena=True)
    p.add_argument(
        "--episodes",
        type=episodes_type(1),
        default=100,
        help="episodes per goal, at least 1 (default 100)",
    )
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    add_robots_args(
        p,
        "robots playing episodes at once, each in its own copy of the arena (the same scores "
        "as one after another; default 1), or with --shared-arena all in one",
    )
    p.add_argument(
        "--epsilon",
        type=float_type(0.0, 1.0),
        default=None,
        metavar="E",
        help="act epsilon-greedily with E in [0, 1], as the robot does (default 0: greedy)",
    )

    p = sub.add_parser("check-arena", help="validate an arena file")
    p.add_argument("file", type=file_name, help="arena file or built-in name")
    p.add_argument("--robot", default="koolio", help="robot profile for clearance checks")

    p = sub.add_parser("info", help="state-space sizes (paper §5.4.8) and table figures")
    p.add_argument(
        "--config", type=file_name, default=None, help="YAML configuration file or profile name"
    )
    p.add_argument("--qtable", type=file_name, default=None, help="also describe this Q-table file")

    for name, module in EXTRA_COMMANDS.items():
        mod = importlib.import_module(module)
        p = sub.add_parser(name, help=(mod.__doc__ or name).strip().splitlines()[0])
        mod.add_arguments(p)
    return parser


#: Commands that live in their own modules: each module has ``add_arguments(parser)`` and
#: ``run(args) -> int`` and imports heavy dependencies (pygame, matplotlib, ray) in ``run``.
EXTRA_COMMANDS: dict[str, str] = {
    "view": "koolio_pymunk.apps.viewer.app",
    "plot": "koolio_pymunk.apps.plotting",
    "export": "koolio_pymunk.apps.export",
    "sweep": "koolio_pymunk.apps.sweep",
    "edit": "koolio_pymunk.apps.editor.command",
    "transfer": "koolio_pymunk.apps.transfer",
}


def main(argv: Sequence[str] | None = None) -> int:
    """``koolio-pm``: the command's exit status (0 done, 2 bad input: one line said, 130
    interrupted by Ctrl-C, 143 stopped by SIGTERM: 128 + the signal, as a shell says).
    Run as a process (``argv`` None), Ctrl-C raises once and is ignored
    from then on (:func:`~koolio_pymunk.store.interrupts.raise_once`): a second Ctrl-C
    while the first is handled never ends in a traceback or cuts a save short."""
    from ..store import interrupts

    if argv is None:
        interrupts.command_line()
    interrupts.forget_signal()
    try:
        code = _main(argv)
    except KeyboardInterrupt:  # wherever it lands: parsing, imports, a command, a handler
        print("koolio-pm: interrupted", file=sys.stderr)
        code = interrupts.exit_status()
    if argv is None:  # the status is chosen: a Ctrl-C while Python shuts down changes nothing
        interrupts.ignore_from_now()
    return code


def _main(argv: Sequence[str] | None) -> int:
    from ..store import provenance

    provenance.COMMAND = list(sys.argv[1:] if argv is None else argv)  # a new table's record
    try:
        return _command(argv)
    finally:
        provenance.COMMAND = None  # tables made from Python afterwards record none


def _command(argv: Sequence[str] | None) -> int:
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as exc:  # --help, --version (0), or a bad flag (2: one line said)
        return exc.code if isinstance(exc.code, int) else 0 if exc.code is None else 2
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
        from ..store.extras import missing_extra

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
        from ..store.files import os_problem

        where = f"{exc.filename}: " if exc.filename else ""
        print(f"koolio-pm: error: {where}{one_line(os_problem(exc))}", file=sys.stderr)
        return 2
    except (RecursionError, MemoryError) as exc:
        what = "nested too deeply" if isinstance(exc, RecursionError) else "out of memory"
        print(f"koolio-pm: error: {args.command}: input too large ({what})", file=sys.stderr)
        return 2


def one_line(text: str, limit: int = 2000) -> str:
    """``text`` on one line, at most ``limit`` characters (an error message)."""
    text = " ".join(text.split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


# --- commands ---------------------------------------------------------------------------


def _make_env(args: argparse.Namespace):
    from ..task.env import KoolioEnv

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


def cmd_train(args: argparse.Namespace) -> int:
    from ..learning.training import train
    from ..store.qtable import QTableStore
    from ..store.run_files import RunFiles
    from ..store.run_identity import RunIdentity

    checks = _eval_every_args(args)
    board = Path(args.tensorboard) if args.tensorboard is not None else None
    if board is not None and board.exists() and not board.is_dir():
        raise KoolioError(located(args.tensorboard, "--tensorboard", "is a file, not a folder"))
    env = _make_env(args)
    say = (lambda s: None) if args.quiet else print
    fallbacks: list[str] = []  # the table's file damaged or missing: its backup is used
    store = QTableStore(args.qtable, purpose="koolio-pm train", warn=_warn_once(fallbacks))
    # Everything that reading can check comes first: an error is the only line printed,
    # and no file (not even a lock file) is left behind.
    if args.robots > 1 and args.discard_unfinished:
        check_discard(env, args.robots)
    check_shared_arena(args, env)
    own = args.robots if args.tables == "each" else 0
    run = RunIdentity.of_run(env, own)  # what the table and the log are checked against
    if args.init_qtable:
        start = _check_init_table(args.init_qtable, store, args.log, run)
    else:
        start = RunFiles.check(run, store, args.log)
        if start is not None:  # a warning (stderr, --quiet too) when the backup stands in
            store.peek(warn=True)
    done = 0 if start is None else int(start.meta.get("episodes", 0))
    more = max(0, args.episodes - done)
    say(_train_opening(args, env, start, done, more, store.backup if fallbacks else None))
    if args.verbose:
        _print_configuration(args, env, say)
    if args.init_qtable:
        _seed_table(args.init_qtable, store, args.log, run, args.seed)
    if more == 0:
        store.close()
        return 0
    if not args.quiet:
        announce_compile(env, robots=args.robots, training=True)
    report = None if args.quiet else (lambda line: print(label_progress(line)))
    result = train(
        env,
        store,
        more,
        args.seed,
        args.log,
        discard_unfinished=args.discard_unfinished,
        report=report,
        **checks,
        save_every=args.save_every,
        save_seconds=args.save_seconds,
        robots=args.robots,
        fsync=args.fsync,
        tensorboard=args.tensorboard,
        shared_arena=args.shared_arena,
        own_tables=bool(own),
    )
    if args.verbose and result.python_reason is not None:
        say(f"stepped in the Python loop: {result.python_reason}")
    rate = result.goals / max(1, result.episodes_run)
    say(
        f"done: {count(result.episodes_run, 'episode')} ({result.goals} at the goal: training goal "
        f"rate {rate:.1%}, exploring), {result.steps} steps in {result.seconds:.1f} s "
        f"({result.steps / max(1e-9, result.seconds):.0f} steps/s); {args.qtable} holds "
        f"{count(result.table.meta.get('episodes', 0), 'episode')}, {len(result.table)} states"
    )
    say(f"score the greedy policy (no exploration): {eval_command(args)}")
    return exit_status() if result.interrupted else 0


def _warn_once(seen: list[str]):
    """A table's warning function that prints each message once (to stderr: with
    ``--quiet`` too) and keeps them in ``seen``: ``train`` warns of a fallback to the
    backup before its first line, and the locked load that follows says it again."""

    def warn(message: str) -> None:
        if message not in seen:
            seen.append(message)
            print(f"warning: {message}", file=sys.stderr)

    return warn


def count(n: int, word: str) -> str:
    """``1 episode``, ``1500 episodes`` (no thousands separator: as the progress lines).

    >>> count(1, "episode"), count(0, "episode"), count(1500, "episode")
    ('1 episode', '0 episodes', '1500 episodes')
    """
    return f"{n} {word}" + ("" if n == 1 else "s")


def label_progress(line: str) -> str:
    """A progress line of ``train`` with its goal rate named for what it is: the share of
    recent *training* episodes at the goal, with exploration (``eval``'s is greedy).

    >>> label_progress("episode 5/9  goal rate (last 5)  40.0%  steps/s 9  epsilon 0.150")
    'episode 5/9  training goal rate (exploring; last 5)  40.0%  steps/s 9  epsilon 0.150'
    """
    return line.replace("goal rate (last ", "training goal rate (exploring; last ", 1)


def eval_command(args: argparse.Namespace) -> str:
    """The ``koolio-pm eval`` command line that scores the table ``train`` just wrote."""
    words = ["koolio-pm eval"]
    if args.arena != "hallway":
        words.append(f"--arena {args.arena}")
    if args.qtable != default_files(args.arena)[0]:
        words.append(f"--qtable {args.qtable}")
    for flag in ("config", "world"):
        if getattr(args, flag):
            words.append(f"--{flag} {getattr(args, flag)}")
    if args.goal:
        words.append("--goal " + ("all" if args.goal == "random" else args.goal))
    if getattr(args, "shared_arena", False):  # the robots scored as they learned: together
        words.append(f"--robots {args.robots} --shared-arena")
    return " ".join(words)


def describe_run(env) -> str:
    """``arena hallway, goal 311, the ideal world``: where a run learns or is scored."""
    goal = "a random goal per episode" if env.random_goal else f"goal {env.goal_name}"
    world = "the ideal world" if env.world_name == "ideal" else f"world {env.world_name}"
    return f"arena {env.arena.name}, {goal}, {world}"


def _train_opening(
    args: argparse.Namespace, env, start, done: int, more: int, backup: Path | None = None
) -> str:
    """``train``'s first line: the table it writes, new or resumed, and how many
    episodes it adds (``--episodes`` is the total the table reaches); ``backup``: the
    table's file is damaged or missing, and this backup holds the table."""
    log = f"; log {args.log}" if args.log else ""
    where = f"{describe_run(env)}, seed {args.seed}{log}"
    if args.init_qtable:
        head = (
            f"new table {args.qtable} from {args.init_qtable} ({len(start)} states, "
            f"{count(done, 'episode')})"
        )
    elif start is None:
        head = f"new table {args.qtable}"
    elif backup is not None:
        head = f"resuming {args.qtable} from its backup {backup}: {count(done, 'episode')} done"
    else:
        head = f"resuming {args.qtable}: {count(done, 'episode')} done"
    if more == 0 and start is None:
        return f"--episodes 0: nothing to train, no table written ({args.qtable} is new)"
    if more == 0 and args.init_qtable:
        return (
            f"{head}: nothing to train, --episodes {args.episodes} is the total and it "
            f"holds {done} already (give a larger --episodes to train further)"
        )
    if more == 0 and backup is not None:
        return (
            f"{args.qtable} is damaged or missing (see the warning); its backup {backup} "
            f"already holds {count(done, 'episode')}, and --episodes {args.episodes} is the "
            f"total to reach: nothing to train, nothing written ({args.qtable} is saved again "
            "by the next run that trains: give a larger --episodes)"
        )
    if more == 0:
        return (
            f"{args.qtable} already holds {count(done, 'episode')}, and --episodes {args.episodes} "
            "is the total to reach: nothing to train (give a larger --episodes to train "
            "further)"
        )
    if start is None:
        return f"{head}: {count(more, 'episode')}; {where}"
    return f"{head}, {more} more to reach --episodes {args.episodes}; {where}"


def config_label(name: str | None, flag: str = "--config") -> str:
    """A configuration (``--config``) or world (``--world``, ``--dr-world``) as it
    resolved: the built-in defaults, the ideal world, a shipped profile or a file.

    >>> config_label(None), config_label("paper"), config_label("my.yaml")
    ('the built-in defaults (no --config)', 'profile paper', 'file my.yaml')
    >>> config_label(None, "--world"), config_label("koolio-real", "--world")
    ('ideal (nothing laid over the configuration)', 'world profile koolio-real')
    """
    from ..store.config import PROFILE_DIR, config_path

    world = flag.endswith("world")
    if name is None or (world and str(name) == "ideal"):
        return (
            "ideal (nothing laid over the configuration)"
            if world
            else (f"the built-in defaults (no {flag})")
        )
    path = config_path(name, flag)
    if path.parent == PROFILE_DIR and path.stem == str(name):
        return f"{'world ' if world else ''}profile {name}"
    return f"file {path}"


def goal_label(env, asked: str | None) -> str:
    """The goal a run in ``env`` learns for, as it resolved (``asked``: ``--goal``)."""
    if env.random_goal:
        names = env.world_arena.goal_names()
        return f"random: one of {len(names)} doors per episode ({', '.join(names)})"
    where = f"{env.goal_name} at {env.world_arena.goal().at}"
    return where + (" (the arena's active goal)" if asked is None else "")


def _print_configuration(args: argparse.Namespace, env, say) -> None:
    """``train --verbose``: the run as it resolved (every default filled in, nothing
    ``None``), then the whole configuration."""
    every = args.save_every or args.robots
    saves = "every episode" if every == 1 else f"every {count(every, 'episode')}"
    if args.save_seconds is not None:
        saves += f", and when {args.save_seconds:g} s passed since the last save"
    exit_ = "discarded (Exit Without Save)" if args.discard_unfinished else "folded in (Exit)"
    rows = [
        ("arena", f"{env.arena.name} ({env.arena.source})"),
        ("goal", goal_label(env, args.goal)),
        ("episodes", f"{args.episodes} (the total the table reaches)"),
        ("seed", args.seed),
        ("qtable", args.qtable),
        ("log", args.log or "none (--log '')"),
        ("config", config_label(args.config)),
        ("world", config_label(args.world, "--world")),
        ("robots", f"{args.robots}, sharing one arena" if args.shared_arena else args.robots),
        ("tables", "each robot its own rows" if args.tables == "each" else "one, shared"),
    ]
    if args.init_qtable:
        rows.append(("init-qtable", f"{args.init_qtable} (the new table starts from it)"))
    if args.eval_every:
        check = count(args.eval_episodes, "episode")
        rows.append(("eval-every", f"a greedy check of {check} every {args.eval_every}"))
    rows += [("saves", saves), ("on Ctrl-C", f"the unfinished episode is {exit_}")]
    say("koolio-pm train")
    for key, value in rows:
        say(f"  {key}: {value}")
    say("configuration:")
    for line in resolved_yaml(env.config).splitlines():
        say("  " + line)


def resolved_yaml(cfg) -> str:
    """``cfg`` as YAML with its values as they resolve: the fields whose ``None`` means
    "another field's" (``robot.robot_radius``: the robot profile's radius;
    ``realism.sonar.max_range``: ``sensors.sonar.max_range``; ``rewards.robot_bump``:
    ``rewards.bump``) show that value.

    >>> from koolio_pymunk.store.config import load_config
    >>> "null" in resolved_yaml(load_config()), "null" in load_config().to_yaml()
    (False, True)
    """
    from ..store.yamlfile import dump_yaml

    data = cfg.to_dict()
    data["robot"]["robot_radius"] = cfg.robot.radius
    data["rewards"]["robot_bump"] = cfg.rewards.value("robot_bump")
    sonar = data.get("realism", {}).get("sonar", {})
    if sonar.get("max_range", 0) is None:
        sonar["max_range"] = cfg.sensors.sonar.max_range
    return dump_yaml(data, sort_keys=False, default_flow_style=None)


def _eval_every_args(args: argparse.Namespace) -> dict[str, int]:
    """``--eval-every`` / ``--eval-episodes`` checked, as ``train()``'s arguments."""
    from ..learning.evaluation import DEFAULT_EVAL_EPISODES

    if args.eval_every is None:
        if args.eval_episodes is not None:
            raise KoolioError("--eval-episodes: only with --eval-every N")
        return {}
    if args.eval_episodes is None:
        args.eval_episodes = DEFAULT_EVAL_EPISODES
    return {"eval_every": args.eval_every, "eval_episodes": args.eval_episodes}


def check_discard(env, robots: int) -> None:
    """``--discard-unfinished`` with several robots takes back the unfinished episodes'
    writes from the compiled engine's journal: refused, in one line, for a run that steps
    in Python (Dyna-Q, the pymunk reference backend)."""
    from ..learning.engine import why_not_config

    reason = why_not_config(env)
    if reason is not None:
        raise KoolioError(
            f"--discard-unfinished: with --robots {robots} it takes back the unfinished "
            f"episodes' writes from the compiled engine's journal, and this run steps in "
            f"Python ({reason})"
        )


def _check_init_table(init_path: str, store, log: str, run):
    """``--init-qtable``'s checks that need no lock: the table to start from is readable
    and made for the sensors of the run ``run`` (its identity), ``--qtable`` is new, and
    so is the log. Returns the table the new one starts from: with ``--tables each``, a
    shared table's rows copied to every robot's own (:meth:`QTable.for_robots
    <koolio_pymunk.store.qtable.QTable.for_robots>`)."""
    from ..store import run_identity
    from ..store.episode_log import check_log_path, log_rows
    from ..store.keyword import base_layout, table_robots
    from .export import load_any_table

    if store.exists():
        raise KoolioError(
            f"--init-qtable: {store.path} already exists; it would be resumed "
            "instead (choose a new --qtable)"
        )
    table = load_any_table(init_path)
    own = table_robots(run.layout)  # --tables each from a shared table: each its copy
    if own and not table_robots(table.layout) and table.layout == base_layout(run.layout):
        table = table.for_robots(own)
    run_identity.check(table, run, "start", init_path, warn=lambda msg: None)
    if log:
        check_log_path(log, store.path)
    if log and log_rows(log):
        raise KoolioError(
            located(log, "", "holds rows of another run: give --init-qtable a new --log")
        )
    return table


def _seed_table(init_path: str, store, log: str, run, seed: int) -> None:
    """``--init-qtable``: start a new table file from another table (either format): its
    Q values, this run's identity (algorithm, goal, world, arena) and provenance, which
    names the table it started from. The new table's log must be new too (its episodes
    continue the other table's count). The checks of :func:`_check_init_table` are made
    again under the lock."""
    from ..store import run_identity

    store.lock()
    try:
        table = _check_init_table(init_path, store, log, run)
        run_identity.check(table, run, "start", init_path)  # again, with its warnings
        origin = {"file": str(init_path), "run_id": table.meta.get("run_id")}
        origin["episodes"] = int(table.meta.get("episodes", 0))
        run_identity.stamp(table, run, new=True, seed=seed, origin=origin)
        store.create(table)
    except BaseException:
        store.close()
        raise


def cmd_eval(args: argparse.Namespace) -> int:
    from ..learning.evaluation import evaluate
    from ..store import run_identity

    eps = args.epsilon
    goal_all = args.goal == "all"
    if goal_all:
        args.goal = None
    env = _make_env(args)
    check_shared_arena(args, env)
    table = read_table(args.qtable)
    policy = is_policy_file(args.qtable)
    # --goal all scores every door: it asks what a random-goal run asks of the table
    asks = _make_env(argparse.Namespace(**{**vars(args), "goal": "random"})) if goal_all else env
    run_identity.check(table, played(asks, args, table), "score", args.qtable)
    goals = env.arena.goal_names() if goal_all else [None]
    announce_compile(env)
    epsilon = eps or 0.0
    results = [
        evaluate(
            env,
            table,
            args.episodes,
            args.seed,
            goal=g,
            epsilon=epsilon,
            robots=args.robots,
            shared_arena=args.shared_arena,
        )
        for g in goals
    ]
    if args.json:
        out = [r.as_dict() | {"epsilon": epsilon} for r in results]
        print(json.dumps(out if goal_all else out[0], sort_keys=True))
        return 0
    where = describe_run(env)
    if goal_all:
        where = where.replace(f"goal {env.goal_name}", "every goal")
    how = "greedy evaluation" if not epsilon else f"evaluation (epsilon {epsilon:g})"
    print(
        f"{how} of {args.qtable} ({count(table.meta.get('episodes', 0), 'episode')}, "
        f"{_trained_for(table, env, args.qtable, policy)})"
    )
    print(
        f"  scored in {where}: {count(args.episodes, 'episode')} per goal, seed {args.seed}, "
        f"epsilon {epsilon:g}, no learning"
        + (f", {args.robots} robots sharing the arena" if args.shared_arena else "")
    )
    rate = "greedy goal rate" if not epsilon else "goal rate"
    print(
        f"  {'goal':>6} {rate:>16} {'end of world':>13} {'wrong door':>11} "
        f"{'step cap':>9} {'mean steps':>11} {'mean bumps':>11} {'mean return':>12}"
    )
    for r in results:
        print(
            f"  {r.goal:>6} {r.goal_rate:>16.1%} {r.end_of_world_rate:>13.1%} "
            f"{r.wrong_door_rate:>11.1%} {r.truncated_rate:>9.1%} {r.mean_steps:>11.1f} "
            f"{r.mean_bumps:>11.1f} {r.mean_reward:>12.1f}"
        )
        if r.robot_goal_rates is not None:
            rates = ", ".join(
                f"robot {k} (goal {g}) {v:.1%}"
                for k, (g, v) in enumerate(zip(r.robot_goals or [], r.robot_goal_rates))
            )
            print(f"  {'':>6} by robot in the shared arena: {rates}")
    if goal_all:
        mean = sum(r.goal_rate for r in results) / len(results)
        print(f"  {'all':>6} {mean:>16.1%}")
    return 0


def played(env, args: argparse.Namespace, table):
    """The identity of ``eval``'s run in ``env`` with ``table`` (its robots sharing the
    arena play their own rows of a table that holds each robot's:
    :meth:`RunIdentity.of_robots <koolio_pymunk.store.run_identity.RunIdentity.of_robots>`)."""
    from ..store.run_identity import RunIdentity

    return RunIdentity.of_robots(env, args.robots if args.shared_arena else 1, table)


def read_table(path: str):
    """The table ``eval`` scores: a ``.qtable`` file (its backup when it is damaged or
    missing, with one warning line, as ``train`` does) or an exported policy."""
    from ..store.qtable import QTableStore
    from .export import load_any_table

    p = Path(path)
    if is_policy_file(p) or p.is_dir():
        return load_any_table(p)  # a policy; or its one-line error ("is a folder")
    table = QTableStore(p).peek(warn=True)
    if table is None:
        raise KoolioError(
            located(
                str(p),
                "",
                "no such Q-table yet: run koolio-pm train first (it writes "
                f"{DEFAULT_QTABLE} by default; --qtable names another)",
            )
        )
    return table


def is_policy_file(path: str | Path) -> bool:
    """True when ``path`` names an exported policy (``.json``, or JSON inside), not a
    ``.qtable``."""
    p = Path(path)
    return p.suffix == ".json" or _starts_with_brace(p)


def _starts_with_brace(p: Path) -> bool:
    """True when ``p`` is a file whose first non-blank byte is ``{`` (a policy file)."""
    try:
        with open(p, "rb") as fh:
            return fh.read(64).lstrip()[:1] == b"{"
    except OSError:
        return False


def _trained_for(table, env, source: str, policy: bool = False) -> str:
    """``trained for goal 311 in the ideal world``, from what the table (or policy file)
    records (:class:`~koolio_pymunk.store.run_identity.RunIdentity`). The goal is
    named by its number only when the table was learned in this arena (its name and
    content); a table of another arena names that arena and its goal
    as recorded: ``trained in arena hallway for its active goal, in the ideal world`` (a
    table records its goal only when it is not its arena's active one, and this arena's
    active goal is not that arena's)."""
    from ..store.errors import shown
    from ..store.run_identity import RunIdentity, describe_goal, describe_world

    theirs = RunIdentity.of_table(table, source, RunIdentity.of_run(env))
    if policy and theirs.arena is None:  # a policy from before policies recorded these
        return "a policy file that does not record its arena"
    world = describe_world(theirs.world)
    if theirs.home_goal is not None or theirs.arena is None:
        return f"trained for {describe_goal(theirs.goal, theirs.home_goal)} in {world}"
    name = theirs.arena[0]
    other = "another version of arena" if name == env.arena.name else "arena"
    if not (name.isprintable() and len(name) <= 60):
        name = shown(name, 60)  # a header's string, on the report's one line
    goal = "its active goal" if theirs.goal is None else describe_goal(theirs.goal)
    return f"trained in {other} {name} for {goal}, in {world}"


def cmd_check_arena(args: argparse.Namespace) -> int:
    from ..store.config import ROBOT_PROFILES
    from ..world.arena import load_arena

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
    """``info``: the state-space sizes of the paper's first design and of a layout, the
    layout's keyword, and a table's figures. The layout is the configuration's (``--config``,
    or the defaults); given a table and no ``--config``, it is the table's own (its
    header's). A table that is not the configuration's says so, in ``eval``'s words."""
    from ..store.config import load_config, state_fields
    from ..store.keyword import PAPER_ORIGINAL_FIELDS, KeywordLayout
    from ..store.qtable import human_bytes
    from .export import load_any_table

    cfg = load_config(args.config)
    table = load_any_table(args.qtable) if args.qtable else None  # a bad one: its line only
    paper = KeywordLayout(PAPER_ORIGINAL_FIELDS)
    now = KeywordLayout(tuple(state_fields(cfg.sensors)))
    own = table is not None and args.config is None  # the table's layout, not the defaults'
    title = f"this table ({args.qtable}: the layout in its header)" if own else "this configuration"
    shown = table.layout if own else now
    print("State space (paper §5.4.8; dense tables of 8-byte doubles):")
    for heading, lay in (
        ("paper's first design (compass, 6 cameras x 4, 8 sonars x 5)", paper),
        (title, shown),
    ):
        print(f"  {heading}:")
        print(f"    states  {lay.n_states:>16,}")
        print(f"    entries {lay.n_entries:>16,}  (x {lay.n_actions} actions)")
        print(f"    dense   {human_bytes(lay.dense_bytes()):>16}")
    print(f"Keyword ({shown.total_bits} bits, Table 12):")
    print(f"  {_keyword_line(shown)}")
    if table is not None:
        _describe_table(table, args.qtable, cfg, args.config, shown)
    return 0


def _keyword_line(layout) -> str:
    """``GoalCam0<<25 | ... | Sonar7<<3 | Action``: a layout's fields and their shifts."""
    return " | ".join(f"{n}<<{s}" for (n, _), s in zip(layout.fields, layout.shifts)) + " | Action"


def _describe_table(table, path: str, cfg, config: str | None, shown) -> None:
    """``info``'s lines on a table: its figures (the share of its own layout's dense
    table, the file's size), where and how it was learned, and whether ``cfg`` (the
    configuration ``config`` names, or the defaults) is the one it was made with."""
    from ..store import run_identity
    from ..store.keyword import own_tables, table_robots
    from ..store.qtable import human_bytes
    from ..store.run_identity import RunIdentity, describe_goal, describe_world

    share = table.entries / table.layout.n_entries
    size = os.stat(path).st_size
    in_file = f"{size:,} bytes" + (f" ({human_bytes(size)})" if size >= 1024 else "")
    print(
        f"Q-table {path}: {len(table):,} states visited, {table.entries:,} entries "
        f"({share:.3%} of its dense table), {in_file} in the file, "
        f"{table.meta.get('episodes', 0)} episodes"
    )
    theirs = RunIdentity.of_table(table, path)
    if theirs.arena is not None:
        print(
            f"  learned in arena {theirs.arena[0]} for {describe_goal(theirs.goal)}, "
            f"in {describe_world(theirs.world)}"
        )
    rec = table.meta.get("algorithm")
    if isinstance(rec, dict):
        params = ", ".join(f"{k} {v}" for k, v in rec.items() if k != "name")
        sections = ", ".join(f"{k} {human_bytes(len(v))}" for k, v in table.sections.items())
        print(
            f"  learned with {rec.get('name')} ({params})" + (f"; {sections}" if sections else "")
        )
    if table.layout != shown:
        print(f"  its keyword ({table.layout.total_bits} bits): {_keyword_line(table.layout)}")
    mine = RunIdentity.of_config(cfg)
    own = table_robots(table.layout)
    if own:
        print(
            f"  holds each of {own} robots' own rows (train --tables each; "
            "export --robot K takes robot K's alone)"
        )
        with contextlib.suppress(ValueError):  # too wide: the check says the layouts differ
            mine = dataclasses.replace(mine, layout=own_tables(mine.layout, own))
    try:
        run_identity.check(table, mine, "inspect", path)
    except KoolioError as exc:
        which = f"--config {config}" if config else "the default configuration (no --config)"
        problem = str(exc).removeprefix(f"{path}: ")
        print(f"  not a table of {which}: {problem}")
    for line in run_identity.describe_provenance(table, cfg):
        print(f"  {line}")


def _cached(dispatcher) -> bool:
    """True when numba's cache holds a compiled version of ``dispatcher`` that is valid for
    its source as it is now (numba's own index check; False when that cannot be told)."""
    try:
        return bool(dispatcher._cache._cache_file._load_index())
    except Exception:  # numba's internals moved: say it may compile
        return False


def kernels_to_compile(env, robots: int = 1, training: bool = False) -> bool:
    """True when a run in ``env`` will compile numba kernels first (a cold cache: the
    first run after installing or changing them): the entry points of the sensing a run
    uses and of the step engine when it runs the configuration, looked up in numba's
    cache index without compiling anything."""
    sensors = env.sensors
    if not getattr(sensors, "fused", False):  # the pymunk reference: nothing compiled
        return False
    if getattr(sensors.kernel, "real_on", False):
        from ..sensing import realism_kernel

        entries = [realism_kernel.sense_realism]
    else:
        from ..sensing import encoding_kernel, ray_kernel

        entries = [ray_kernel.sense_one, encoding_kernel.readout]
    from ..learning import engine

    if engine.why_not_config(env) is None:
        entries.append(engine.run)
    return not all(_cached(f) for f in entries)


def announce_compile(env, robots: int = 1, training: bool = False) -> None:
    """One line before the one-time compile of the kernels (sensing, moves, the episode),
    when it is due."""
    if kernels_to_compile(env, robots, training):
        print(
            "compiling the simulator's kernels (first run only, about a minute on 2 cores); "
            "later runs load them from the cache",
            file=sys.stderr,
            flush=True,
        )


COMMANDS = {
    "train": cmd_train,
    "eval": cmd_eval,
    "check-arena": cmd_check_arena,
    "info": cmd_info,
}


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
