"""Plot the learning curve of a training log (return, outcomes, steps per episode).

``koolio-pm plot --log runs/hallway.csv`` reads the per-episode CSV that ``koolio-pm
train`` and ``koolio-pm view`` append to (see :mod:`koolio_pymunk.learning.training`)
and draws, against the episode number (``--x steps``: against the environment steps taken
since the log's first row, the steps of ``interrupted`` rows included):

1. the return of each episode (sum of its rewards) and its moving average -- the paper's
   "graph ... showing the growth of the return as the policy approaches optimal";
2. the share of the last ``--window`` episodes that ended at the goal, off the end of the
   world, or at the step cap, with epsilon on a second axis;
3. steps per episode and its moving average, with the moving average of bumps on a
   right axis (dashed).

With ``train --eval-every N`` the run's greedy checks (``X.evals.csv`` beside the log
``X.csv``, found on its own, or named with ``--evals``) are drawn on the curve: their goal
rate as black diamonds on panel 2, their mean return on panel 1, and the check whose
table is kept as the best table (``X.best.qtable``) as a gold star.

``interrupted`` rows (an Exit folded into the table) are left out: that episode is run
again from its start when training resumes. Several logs (``--log a --log b``, or
``koolio-pm plot a.csv b.csv``) are overlaid to compare runs, one colour each: moving
averages only, and of the outcomes only the share at the goal.

**Episode numbers.** Episodes are numbered from 1, as everywhere people read them
(``train``'s progress, the window, the checks of ``--eval-every``): the log's ``episode``
column is 0-based (the episode's index, which seeds it), so its row ``episode = k`` is
drawn at episode ``k + 1``, and a check after N episodes at N.

**Where the picture goes.** ``--out PNG``; without it, beside the log and named after it
(:func:`default_out`: ``runs/hallway.csv`` -> ``runs/hallway.png``; several logs:
``runs/a.compared.png`` beside the first). The command's line names the file it wrote.

matplotlib (Agg backend, no display) is imported only when the command runs.
"""

from __future__ import annotations

import argparse
import io
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..store.episode_log import (
    MAX_LOG_BYTES,
    ascii_float,
    ascii_int,
    csv_fields,
    header_index,
    log_run_id,
    split_log,
)
from ..store.errors import KoolioError, located
from ..store.files import atomic_write, read_text

REQUIRED = ("episode", "reward", "steps", "outcome")
OUTCOMES = (
    ("goal", "at the goal", "tab:green"),
    ("end_of_world", "off the end of the world", "tab:purple"),
    ("truncated", "step cap (truncated)", "tab:gray"),
)


@dataclass
class Log:
    """The finished episodes of one training log."""

    path: Path
    episode: np.ndarray
    reward: np.ndarray
    steps: np.ndarray
    bumps: np.ndarray
    outcome: list[str]
    epsilon: np.ndarray
    skipped: int = 0
    """``interrupted`` rows left out."""
    extra: dict = field(default_factory=dict)
    evals: Evals | None = None
    """The run's greedy checks (``train --eval-every``), when it has some."""
    steps_done: np.ndarray | None = None
    """Environment steps from the log's first row to the end of each finished episode
    (``interrupted`` rows' steps included: they were taken); None: the sum of ``steps``."""

    def __len__(self) -> int:
        return len(self.episode)

    def x(self, axis: str = "episodes") -> np.ndarray:
        """Each finished episode's place on the x axis: its number from 1 (``episodes``)
        or the environment steps taken up to its end (``steps``)."""
        if axis == "steps":
            done = self.steps_done
            return np.cumsum(self.steps) if done is None else done
        return self.episode + 1

    def check_x(self, ev: Evals, axis: str = "episodes") -> np.ndarray:
        """The x of each greedy check (made after ``ev.episode`` episodes)."""
        if axis != "steps":
            return ev.episode
        return np.interp(ev.episode, self.episode + 1, self.x("steps"))


@dataclass
class Evals:
    """The greedy checks of a run (its evaluations file, ``train --eval-every``)."""

    path: Path
    episode: np.ndarray
    """Training episodes the table held at each check."""
    goal_rate: np.ndarray
    mean_return: np.ndarray
    best: np.ndarray
    """True where the check was the best so far (its table kept)."""
    eval_episodes: np.ndarray

    def __len__(self) -> int:
        return len(self.episode)

    @property
    def kept(self) -> int | None:
        """Index of the check whose table is kept as the best table (the last flagged)."""
        flagged = np.flatnonzero(self.best)
        return int(flagged[-1]) if len(flagged) else None


EVALS_REQUIRED = ("episode", "eval_episodes", "goal_rate", "mean_return", "best")


def _field(row: dict, name: str, kind, source: str, line: int, required=REQUIRED):
    value = row.get(name)
    if value is None or value == "":
        if name in required:
            raise KoolioError(located(source, f"line {line}", f"{name}: missing"))
        return kind(0)
    number = ascii_int(value) if kind is int else ascii_float(value)
    if number is None or abs(number) > 2**53:
        shown = value if len(value) <= 30 else value[:27] + "..."
        raise KoolioError(located(source, f"line {line}", f"{name}: not a number: {shown!r}"))
    return number


def read_log(path: str | Path) -> Log:
    """Read a training log; every problem is a one-line :class:`KoolioError`. Numbers
    are ASCII (:func:`~koolio_pymunk.store.episode_log.ascii_float`), lines at most
    :data:`~koolio_pymunk.store.episode_log.MAX_LOG_LINE` characters, and a torn last
    row (no line end: perhaps a row being written) is left out."""
    p = Path(path)
    source = str(p)
    text = read_text(p, MAX_LOG_BYTES, "training log")
    lines, torn = split_log(text)
    if torn and len(lines) > 1:
        lines = lines[:-1]
    log_run_id(source, lines)  # a run line first (checked), then the header
    h = header_index(lines)
    fieldnames = csv_fields(source, h + 1, lines[h]) if len(lines) > h else []
    missing = [c for c in REQUIRED if c not in fieldnames]
    if missing:
        raise KoolioError(
            located(source, "line 1", f"not a training log (missing columns: {', '.join(missing)})")
        )
    cols: dict[str, list] = {k: [] for k in ("episode", "reward", "steps", "bumps", "epsilon")}
    outcomes: list[str] = []
    skipped = 0
    steps_done: list[int] = []
    taken = 0
    for line, text_line in enumerate(lines[h + 1 :], start=h + 2):
        if not text_line.strip():
            continue
        row = dict(zip(fieldnames, csv_fields(source, line, text_line)))
        taken += _field(row, "steps", int, source, line)
        if row.get("outcome") == "interrupted":
            skipped += 1
            continue
        steps_done.append(taken)
        cols["episode"].append(_field(row, "episode", int, source, line))
        cols["reward"].append(_field(row, "reward", float, source, line))
        cols["steps"].append(_field(row, "steps", int, source, line))
        cols["bumps"].append(_field(row, "bumps", int, source, line))
        cols["epsilon"].append(_field(row, "epsilon", float, source, line))
        outcomes.append(row["outcome"] if row.get("outcome") is not None else "")
    if not outcomes:
        raise KoolioError(located(source, "", "no finished episode to plot"))
    return Log(
        p,
        np.asarray(cols["episode"]),
        np.asarray(cols["reward"], dtype=float),
        np.asarray(cols["steps"], dtype=float),
        np.asarray(cols["bumps"], dtype=float),
        outcomes,
        np.asarray(cols["epsilon"], dtype=float),
        skipped,
        steps_done=np.asarray(steps_done, dtype=float),
    )


def read_evals_file(path: str | Path) -> Evals | None:
    """Read an evaluations file (``X.evals.csv``); None when it holds no check yet. Every
    problem is a one-line :class:`KoolioError`."""
    p = Path(path)
    source = str(p)
    text = read_text(p, MAX_LOG_BYTES, "evaluations file")
    lines, torn = split_log(text)
    if torn and len(lines) > 1:  # a check being written: left out, as a log's torn row
        lines = lines[:-1]
    fieldnames = csv_fields(source, 1, lines[0]) if lines else []
    missing = [c for c in EVALS_REQUIRED if c not in fieldnames]
    if missing:
        raise KoolioError(
            located(
                source,
                "line 1",
                f"not an evaluations file of train --eval-every (missing columns: "
                f"{', '.join(missing)})",
            )
        )
    cols: dict[str, list] = {k: [] for k in EVALS_REQUIRED}
    for line, text_line in enumerate(lines[1:], start=2):
        row = dict(zip(fieldnames, csv_fields(source, line, text_line)))
        for name in EVALS_REQUIRED:
            kind = float if name in ("goal_rate", "mean_return") else int
            cols[name].append(_field(row, name, kind, source, line, EVALS_REQUIRED))
    if not cols["episode"]:
        return None
    return Evals(
        p,
        np.asarray(cols["episode"]),
        np.asarray(cols["goal_rate"], dtype=float),
        np.asarray(cols["mean_return"], dtype=float),
        np.asarray(cols["best"]) == 1,
        np.asarray(cols["eval_episodes"]),
    )


def evals_beside(log: str | Path) -> Path:
    """The evaluations file a run writes beside its log ``X.csv``: ``X.evals.csv``.

    >>> str(evals_beside("runs/hallway.csv"))
    'runs/hallway.evals.csv'
    """
    p = Path(log)
    return p.with_name(p.stem + ".evals.csv")


def moving_average(values: np.ndarray, window: int) -> np.ndarray:
    """Trailing mean over the last ``window`` values (fewer at the start).

    >>> moving_average(np.array([1.0, 2.0, 3.0, 4.0]), 2).tolist()
    [1.0, 1.5, 2.5, 3.5]
    """
    values = np.asarray(values, dtype=float)
    c = np.concatenate([[0.0], np.cumsum(values)])
    idx = np.arange(1, len(values) + 1)
    lo = np.maximum(0, idx - window)
    return (c[idx] - c[lo]) / (idx - lo)


def outcome_rate(outcomes: list[str], name: str, window: int) -> np.ndarray:
    """Moving share (0..1) of episodes whose outcome is ``name``."""
    return moving_average(np.array([o == name for o in outcomes], dtype=float), window)


def _count(n: int, word: str) -> str:
    """``1 episode``, ``50 episodes``."""
    return f"{n} {word}" + ("" if n == 1 else "s")


def run_labels(logs: list[Log]) -> list[str]:
    """A short name per log: the file name, with as many parent folders as it takes to
    tell the logs apart.

    >>> from pathlib import Path
    >>> def log(p):
    ...     return Log(Path(p), *([np.zeros(0)] * 4), [], np.zeros(0))
    >>> run_labels([log("runs/a/train.csv"), log("runs/b/train.csv")])
    ['a/train.csv', 'b/train.csv']
    >>> run_labels([log("x/one.csv"), log("x/two.csv")])
    ['one.csv', 'two.csv']
    """
    parts = [log.path.parts for log in logs]
    for k in range(1, max((len(p) for p in parts), default=1) + 1):
        names = ["/".join(p[-k:]) for p in parts]
        if len(set(names)) == len(names):
            return names
    return [str(log.path) for log in logs]


def default_out(logs: list[str | Path]) -> Path:
    """``plot``'s picture when no ``--out`` is given: beside the first log, named after
    it (the name of several logs' comparison says so; a log whose name ends in ``.png``
    keeps it, so its picture is never the log itself).

    >>> [str(default_out(logs)) for logs in (["runs/hallway.csv"], ["a/x.csv", "b/y.csv"])]
    ['runs/hallway.png', 'a/x.compared.png']
    >>> str(default_out(["odd.png"]))
    'odd.png.png'
    """
    first = Path(logs[0])
    stem = first.name if first.suffix.lower() == ".png" else first.stem
    return first.with_name(stem + (".compared.png" if len(logs) > 1 else ".png"))


def plot_logs(
    logs: list[Log],
    out: str | Path,
    window: int = 50,
    title: str | None = None,
    x: str = "episodes",
) -> Path:
    """Draw the learning curve of ``logs`` into the PNG ``out`` (written atomically),
    against episodes or environment steps (``x``: :data:`X_AXES`)."""
    import matplotlib.pyplot as plt

    fig = make_figure(logs, window, title, x)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    out = Path(out)
    atomic_write(out, buf.getvalue())
    return out


#: ``plot --x``: what the x axis counts, and its caption.
X_AXES = {
    "episodes": "episode (numbered from 1)",
    "steps": "environment steps (from the log's first row)",
}


def make_figure(logs: list[Log], window: int = 50, title: str | None = None, x: str = "episodes"):
    """The learning-curve figure of ``logs`` (matplotlib, Agg), three panels.

    One log: return and its moving average; the shares of the last ``window`` episodes at
    the goal, off the end of the world and at the step cap, with epsilon; steps and bumps
    per episode. Several logs: the same panels with one colour per run, moving averages
    only, and only the share at the goal (the panel says so). ``x``: the x axis counts
    episodes (from 1) or environment steps (:data:`X_AXES`)."""
    if x not in X_AXES:
        raise KoolioError(f"--x: {x!r}: not one of {', '.join(X_AXES)}")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    fig, axes = plt.subplots(3, 1, figsize=(10, 8.5), sharex=True, constrained_layout=True)
    ax_ret, ax_out, ax_steps = axes
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    names = run_labels(logs)
    if len(logs) == 1:
        extra = _plot_single(axes, logs[0], window, x)
    else:
        extra = _plot_several(axes, logs, names, window, colours, x)
    ax_ret.set_ylabel("return per episode\n(sum of rewards)")
    ax_out.set_ylim(-2, 102)
    ax_steps.set_xlabel(X_AXES[x])
    ax_steps.xaxis.set_major_locator(MaxNLocator(integer=True))
    _short_axes(axes, logs, x)
    for ax in axes:
        ax.grid(True, alpha=0.3)
        handles, _ = ax.get_legend_handles_labels()
        handles += extra.get(ax, [])
        # A row or two of legend above each panel: it never hides the data.
        ax.legend(
            handles=handles,
            loc="lower left",
            bbox_to_anchor=(0.0, 1.0),
            ncol=4 if len(handles) <= 4 else 3,
            fontsize=9,
            frameon=False,
            borderaxespad=0.2,
        )
    fig.suptitle(title or _title(logs, names))
    return fig


def _short_axes(axes, logs: list[Log], axis: str = "episodes") -> None:
    """Logs of a single episode: an episode axis one episode wider on each side (whole
    episodes as ticks, not 0.945 to 1.05; a steps axis from 0), and return and step axes
    that reach zero (not 45 to 47 steps around one dot)."""
    ax_ret, _, ax_steps = axes
    if any(len(log) > 1 for log in logs) or not any(len(log) for log in logs):
        return
    x = [float(log.x(axis)[0]) for log in logs if len(log)]
    if axis == "steps":
        ax_steps.set_xlim(0, max(x) * 1.1 + 1)
    else:
        ax_steps.set_xlim(min(x) - 1, max(x) + 1)
    for ax, values in (
        (ax_ret, [float(log.reward[0]) for log in logs if len(log)]),
        (ax_steps, [float(log.steps[0]) for log in logs if len(log)]),
    ):
        lo, hi = min(0.0, *values), max(0.0, *values)
        pad = 0.1 * (hi - lo) or 1.0
        ax.set_ylim(lo - pad if lo < 0 else 0.0, hi + pad)


def _dots(log: Log) -> dict:
    """Plot keywords that show a run of a single episode as dots (a line of one point
    draws nothing)."""
    return {"marker": "o", "markersize": 5} if len(log) < 2 else {}


def _title(logs: list[Log], names: list[str]) -> str:
    if len(logs) > 1:
        return "Learning curves: " + ", ".join(names)
    first = logs[0]
    extra = f", {first.skipped} interrupted rows left out" if first.skipped else ""
    if first.evals is not None:
        extra += f", {_count(len(first.evals), 'greedy check')}"
    return f"Learning curve: {first.path.name} ({_count(len(first), 'episode')}{extra})"


def _plot_single(axes, log: Log, window: int, axis: str = "episodes") -> dict:
    """One run: every panel in full. Returns extra legend handles per axis."""
    ax_ret, ax_out, ax_steps = axes
    x = log.x(axis)
    dots = _dots(log)
    ax_ret.plot(x, log.reward, color="tab:blue", alpha=0.3, lw=0.8, label="return")
    ax_ret.plot(
        x,
        moving_average(log.reward, window),
        color="tab:blue",
        lw=2.2,
        label=f"moving average ({_count(window, 'episode')})",
        **dots,
    )
    for key, text, c in OUTCOMES:
        rate = 100.0 * outcome_rate(log.outcome, key, window)
        ax_out.plot(x, rate, color=c, lw=2, label=text, **dots)
    ax_out.set_ylabel(f"share of episodes\n(% of last {window})")
    eps = ax_out.twinx()
    (line,) = eps.plot(
        x, log.epsilon, color="black", ls=":", lw=1.4, label="epsilon (right axis)", **dots
    )
    eps.set_ylabel("epsilon (dotted)")
    eps.set_ylim(0, max(0.05, float(log.epsilon.max()) * 1.1))
    ax_steps.plot(x, log.steps, color="tab:orange", alpha=0.3, lw=0.8, label="steps")
    ax_steps.plot(
        x,
        moving_average(log.steps, window),
        color="tab:orange",
        lw=2.2,
        label="steps, average",
        **dots,
    )
    ax_steps.set_ylabel("steps per episode")
    bumps = _bumps_axis(ax_steps, "tab:red")
    (b,) = bumps.plot(
        x,
        moving_average(log.bumps, window),
        color="tab:red",
        lw=1.6,
        ls="--",
        label="bumps, average (right axis)",
        **dots,
    )
    bumps.set_ylim(bottom=0)
    if log.evals is not None:
        _draw_checks(ax_ret, ax_out, log.evals, "black", x=log.check_x(log.evals, axis))
    return {ax_out: [line], ax_steps: [b]}


def _draw_checks(
    ax_ret, ax_out, ev: Evals, colour: str, labels: bool = True, x: np.ndarray | None = None
) -> None:
    """The greedy checks: goal rate on the outcomes panel, mean return on the return
    panel, the kept best table's check as a gold star on both (at ``x``: default their
    episode counts)."""
    x = ev.episode if x is None else x
    m = int(ev.eval_episodes[-1])
    ax_out.plot(
        x,
        100.0 * ev.goal_rate,
        color=colour,
        marker="D",
        ms=5,
        lw=1.1,
        zorder=4,
        label=f"greedy check, at the goal ({m} episodes)" if labels else None,
    )
    ax_ret.plot(
        x,
        ev.mean_return,
        color=colour,
        marker="D",
        ms=4,
        lw=1.0,
        zorder=4,
        label="greedy check, mean return" if labels else None,
    )
    k = ev.kept
    if k is None:
        return
    star = {"marker": "*", "ms": 16, "color": "gold", "mec": "black", "mew": 1.0, "zorder": 5}
    text = f"kept best: {ev.goal_rate[k]:.0%} at episode {ev.episode[k]}"
    ax_out.plot([x[k]], [100.0 * ev.goal_rate[k]], ls="", **star,
                label=text if labels else None)  # fmt: skip
    ax_ret.plot([x[k]], [ev.mean_return[k]], ls="", **star)


def _plot_several(
    axes, logs: list[Log], names: list[str], window: int, colours, axis: str = "episodes"
) -> dict:
    """Several runs, one colour each: moving averages of the return, the share at the
    goal, steps (solid) and bumps (dashed, right axis)."""
    ax_ret, ax_out, ax_steps = axes
    bumps = _bumps_axis(ax_steps)
    for i, (log, name) in enumerate(zip(logs, names)):
        x, colour, dots = log.x(axis), colours[i % len(colours)], _dots(log)
        ret = moving_average(log.reward, window)
        ax_ret.plot(x, ret, color=colour, lw=2.2, label=name, **dots)
        rate = 100.0 * outcome_rate(log.outcome, "goal", window)
        ax_out.plot(x, rate, color=colour, lw=2, label=name, **dots)
        steps = moving_average(log.steps, window)
        ax_steps.plot(x, steps, color=colour, lw=2.2, label=name, **dots)
        bumps.plot(x, moving_average(log.bumps, window), color=colour, lw=1.4, ls="--", **dots)
        if log.evals is not None:
            x_checks = log.check_x(log.evals, axis)
            _draw_checks(ax_ret, ax_out, log.evals, colour, labels=False, x=x_checks)
    bumps.set_ylim(bottom=0)
    checks = any(log.evals is not None for log in logs)
    ax_ret.set_title(
        f"moving average of the return ({_count(window, 'episode')})"
        + ("; diamonds: greedy checks' mean return" if checks else ""),
        fontsize=9,
        loc="right",
    )
    ax_out.set_ylabel(f"episodes at the goal\n(% of last {window})")
    ax_out.set_title(
        "share at the goal" + (" (diamonds: greedy checks, star: kept best)" if checks else ""),
        fontsize=9,
        loc="right",
    )
    ax_steps.set_ylabel("steps per episode\n(solid)")
    ax_steps.set_title(
        f"steps (solid) and bumps (dashed), moving averages ({_count(window, 'episode')})",
        fontsize=9,
        loc="right",
    )
    return {}


def _bumps_axis(ax_steps, colour: str = "black"):
    """Bumps on a right axis of the steps panel (they are 10 to 100 times fewer)."""
    bumps = ax_steps.twinx()
    bumps.set_ylabel("bumps per episode\n(dashed)", color=colour)
    return bumps


def _window_type(text: str) -> int:
    """``--window``: 1..10**9 episodes (argparse type)."""
    from .flags import MAX_EPISODES, int_type

    return int_type(1, MAX_EPISODES)(text)


def add_arguments(p: argparse.ArgumentParser) -> None:
    from .flags import file_name

    p.add_argument(
        "logs",
        nargs="*",
        type=file_name,
        metavar="LOG",
        help="training log CSV files (the same as --log LOG)",
    )
    p.add_argument(
        "--log",
        action="append",
        type=file_name,
        default=None,
        help="training log CSV (default runs/hallway.csv); repeat to compare runs",
    )
    p.add_argument(
        "--out",
        type=file_name,
        default=None,
        help="PNG to write (default: beside the first log, named after it: runs/hallway.csv "
        "-> runs/hallway.png; several logs: runs/a.compared.png)",
    )
    p.add_argument(
        "--x",
        choices=tuple(X_AXES),
        default="episodes",
        help="what the x axis counts: episodes (numbered from 1; the default) or the "
        "environment steps taken since the log's first row",
    )
    p.add_argument(
        "--window",
        type=_window_type,
        default=50,
        help="moving-average window, episodes (1..1,000,000,000; default 50)",
    )
    p.add_argument("--title", default=None, help="figure title")
    p.add_argument(
        "--evals",
        action="append",
        type=file_name,
        default=None,
        metavar="FILE",
        help="greedy checks of train --eval-every to draw, one per log in order (default: "
        "X.evals.csv beside each log X.csv, when present)",
    )


def run(args: argparse.Namespace) -> int:
    """``koolio-pm plot``."""
    from .cli import DEFAULT_LOG
    from .flags import check_png

    paths = [*args.logs, *(args.log or [])] or [DEFAULT_LOG]
    out = Path(args.out) if args.out is not None else default_out(paths)
    check_png(out, "--out")
    logs = [read_log(p) for p in paths]
    attach_evals(logs, args.evals)
    _not_an_input(out, logs)
    out = plot_logs(logs, out, args.window, args.title, args.x)
    n = sum(len(log) for log in logs)
    checks = sum(len(log.evals) for log in logs if log.evals is not None)
    also = f" and {_count(checks, 'greedy check')}" if checks else ""
    print(f"plot: {_count(n, 'episode')}{also} from {len(logs)} log(s) -> {out}")
    return 0


def _not_an_input(out: Path, logs: list[Log]) -> None:
    """Refuse a picture that would replace one of the files it is drawn from."""
    inputs = [log.path for log in logs] + [log.evals.path for log in logs if log.evals]
    for p in inputs:
        if out.resolve() == p.resolve():
            raise KoolioError(f"--out: {out}: is {p}, a file being plotted: choose another name")


def attach_evals(logs: list[Log], named: list[str] | None) -> None:
    """Each log's greedy checks: the files ``--evals`` names (one per log), or the
    evaluations file beside each log when there is one."""
    if named is not None and len(named) != len(logs):
        raise KoolioError(
            f"--evals: {_count(len(named), 'file')} for {_count(len(logs), 'log')} "
            "(one per log, in order)"
        )
    for i, log in enumerate(logs):
        path = Path(named[i]) if named is not None else evals_beside(log.path)
        if named is not None or path.exists():
            log.evals = read_evals_file(path)
