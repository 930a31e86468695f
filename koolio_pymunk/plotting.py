"""Plot the learning curve of a training log (return, outcomes, steps per episode).

``koolio-pm plot --log runs/hallway.csv --out curve.png`` reads the per-episode CSV that
``koolio-pm train`` and ``koolio-pm view`` append to (see :mod:`koolio_pymunk.training`)
and draws, against the episode number:

1. the return of each episode (sum of its rewards) and its moving average -- the paper's
   "graph ... showing the growth of the return as the policy approaches optimal";
2. the share of the last ``--window`` episodes that ended at the goal, off the end of the
   world, or at the step cap, with epsilon on a second axis;
3. steps per episode and its moving average, with the moving average of bumps.

``interrupted`` rows (an Exit folded into the table) are left out: that episode is run
again from its start when training resumes. Several ``--log`` files are overlaid
(moving averages only) to compare runs.

matplotlib (Agg backend, no display) is imported only when the command runs.
"""

from __future__ import annotations

import argparse
import csv
import io
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .episode_log import MAX_LOG_BYTES
from .errors import KoolioError, located
from .files import atomic_write, read_text

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

    def __len__(self) -> int:
        return len(self.episode)


def _field(row: dict, name: str, kind, source: str, line: int):
    value = row.get(name)
    if value is None or value == "":
        if name in REQUIRED:
            raise KoolioError(located(source, f"line {line}", f"{name}: missing"))
        return kind(0)
    try:
        number = kind(value)
    except ValueError:
        number = None
    if number is None or abs(number) > 2**53 or not math.isfinite(number):
        shown = value if len(value) <= 30 else value[:27] + "..."
        raise KoolioError(located(source, f"line {line}", f"{name}: not a number: {shown!r}"))
    return number


def read_log(path: str | Path) -> Log:
    """Read a training log; every problem is a one-line :class:`KoolioError`."""
    p = Path(path)
    source = str(p)
    text = read_text(p, MAX_LOG_BYTES, "training log")
    reader = csv.DictReader(io.StringIO(text))
    missing = [c for c in REQUIRED if c not in (reader.fieldnames or [])]
    if missing:
        raise KoolioError(
            located(source, "line 1", f"not a training log (missing columns: {', '.join(missing)})")
        )
    cols: dict[str, list] = {k: [] for k in ("episode", "reward", "steps", "bumps", "epsilon")}
    outcomes: list[str] = []
    skipped = 0
    for line, row in enumerate(reader, start=2):
        if row.get("outcome") == "interrupted":
            skipped += 1
            continue
        cols["episode"].append(_field(row, "episode", int, source, line))
        cols["reward"].append(_field(row, "reward", float, source, line))
        cols["steps"].append(_field(row, "steps", int, source, line))
        cols["bumps"].append(_field(row, "bumps", int, source, line))
        cols["epsilon"].append(_field(row, "epsilon", float, source, line))
        outcomes.append(row["outcome"])
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
    )


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


def plot_logs(logs: list[Log], out: str | Path, window: int = 50, title: str | None = None) -> Path:
    """Draw the learning curve of ``logs`` into the PNG ``out`` (written atomically)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    single = len(logs) == 1
    fig, axes = plt.subplots(3, 1, figsize=(10, 8.5), sharex=True, constrained_layout=True)
    ax_ret, ax_out, ax_steps = axes
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, log in enumerate(logs):
        x = log.episode + 1
        name = log.path.name
        colour = "tab:blue" if single else colours[i % len(colours)]
        if single:
            ax_ret.plot(x, log.reward, color="tab:blue", alpha=0.3, lw=0.8, label="return")
        label = f"moving average ({window} episodes)" if single else f"{name}: return"
        ax_ret.plot(x, moving_average(log.reward, window), color=colour, lw=2.2, label=label)
        for key, text, c in OUTCOMES if single else OUTCOMES[:1]:
            rate = 100.0 * outcome_rate(log.outcome, key, window)
            ax_out.plot(
                x, rate, color=c if single else colour, lw=2, label=text if single else name
            )
        if single:
            ax_steps.plot(x, log.steps, color="tab:orange", alpha=0.3, lw=0.8, label="steps")
        ax_steps.plot(
            x,
            moving_average(log.steps, window),
            color="tab:orange" if single else colour,
            lw=2.2,
            label="steps, moving average" if single else f"{name}: steps",
        )
        if single:
            ax_steps.plot(
                x,
                moving_average(log.bumps, window),
                color="tab:red",
                lw=1.6,
                label="bumps, moving average",
            )
    handles_extra: list = []
    if single:
        eps = ax_out.twinx()
        x0, e0 = logs[0].episode + 1, logs[0].epsilon
        (line,) = eps.plot(x0, e0, color="black", ls=":", lw=1.4, label="epsilon (right axis)")
        handles_extra.append(line)
        eps.set_ylabel("epsilon (dotted)")
        eps.set_ylim(0, max(0.05, float(logs[0].epsilon.max()) * 1.1))
    ax_ret.set_ylabel("return per episode\n(sum of rewards)")
    ax_out.set_ylabel(f"share of episodes\n(% of last {window})")
    ax_out.set_ylim(-2, 102)
    ax_steps.set_ylabel("steps and bumps\nper episode")
    ax_steps.set_xlabel("episode")
    ax_steps.xaxis.set_major_locator(MaxNLocator(integer=True))
    for ax in axes:
        ax.grid(True, alpha=0.3)
        handles, _ = ax.get_legend_handles_labels()
        if ax is ax_out:
            handles += handles_extra
        # One row of legend above each panel: it never hides the data.
        ax.legend(
            handles=handles,
            loc="lower left",
            bbox_to_anchor=(0.0, 1.0),
            ncol=4,
            fontsize=9,
            frameon=False,
            borderaxespad=0.2,
        )
    if title is None:
        first = logs[0]
        extra = f", {first.skipped} interrupted rows left out" if first.skipped else ""
        title = (
            f"Learning curve: {first.path.name} ({len(first)} episodes{extra})"
            if single
            else "Learning curves: " + ", ".join(log.path.name for log in logs)
        )
    fig.suptitle(title)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    out = Path(out)
    atomic_write(out, buf.getvalue())
    return out


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--log",
        action="append",
        default=None,
        help="training log CSV (default runs/hallway.csv); repeat to compare runs",
    )
    p.add_argument("--out", default="curve.png", help="PNG to write (default curve.png)")
    p.add_argument(
        "--window", type=int, default=50, help="moving-average window, episodes (default 50)"
    )
    p.add_argument("--title", default=None, help="figure title")


def run(args: argparse.Namespace) -> int:
    """``koolio-pm plot``."""
    from .cli import DEFAULT_LOG

    if args.window < 1:
        raise KoolioError(f"--window: must be >= 1, got {args.window}")
    if not str(args.out).lower().endswith(".png"):
        raise KoolioError(f"--out: {args.out}: must end in .png")
    if Path(args.out).is_dir():
        raise KoolioError(f"--out: {args.out}: is a folder, not a file")
    logs = [read_log(p) for p in (args.log or [DEFAULT_LOG])]
    out = plot_logs(logs, args.out, args.window, args.title)
    n = sum(len(log) for log in logs)
    print(f"plot: {n} episodes from {len(logs)} log(s) -> {out}")
    return 0
