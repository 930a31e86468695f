"""The per-episode training log: one CSV row per episode, kept in step with its Q-table.

``koolio-pm train`` and ``koolio-pm view`` append one row per finished (or interrupted)
episode to the log (``--log``, default ``runs/<arena>.csv``)::

    episode,reward,steps,bumps,outcome,rescued,epsilon,goal

``outcome`` is ``goal``, ``end_of_world``, ``wrong_door`` (a Stop before a misread
plate, in a realistic world), ``truncated`` (step cap) or ``interrupted`` (Ctrl-C / Exit:
the unfinished episode was folded into the table; its number is run again when training
resumes). With domain randomization the draw of each episode follows in extra columns
named ``realism.<section>.<name>`` (:mod:`koolio_pymunk.sensing.realism`).

**Which files may be a log.** A log that exists must start with that header line (and a
run appending to it must write the same extra columns): any other file (an arena, a
Q-table, a binary file) is refused with a one-line error and left untouched, and the log
must not be the Q-table, its backup or a lock file. While a run writes a log it holds
the log's lock (:mod:`koolio_pymunk.store.locks`).

**Agreement with the table.** The table is saved before an episode's row is written, so
the log and the table can disagree after a stop:

* a row is missing when the process was killed between the two writes (at most one row,
  or the rows of one save with ``--robots N``); resuming warns and goes on. A log that
  is missing, empty or only its header beside a table of N > 0 episodes lacks the rows
  of episodes 0..N-1: the same warning (not for a table the run made itself: a new one,
  or one started with ``--init-qtable``, whose log starts at its count). These warnings
  come with the first new row: a run that fails before it says only its error;
* rows are ahead when the table holds fewer episodes than the log: ``--save-every K``,
  ``--save-seconds T`` and ``--robots N`` save less often than they log, and a torn table
  falls back to its backup. Those episodes' learning is not in the table and their
  numbers will be run again, so resuming **moves** those rows (and the interrupted rows
  after them) out of the log into ``<log>.removed`` (a log too, so nothing is lost), with
  a warning, before appending: episode numbers never repeat (except after an
  ``interrupted`` row, by design);
* a torn last row (no line end: a write cut short) is moved the same way, whatever it
  holds. Its episode number, when it has one (the digits before its first comma), says
  what it was: an episode the table does not hold runs again (it is counted with the
  rows ahead, in their warning); one the table holds keeps its learning, and the warning
  says that its row is lost.

**The run line.** The log of a table that has a run id
(:mod:`koolio_pymunk.store.run_identity`: every table made since version 0.2) starts
with ``# koolio-pymunk run <id>`` (:data:`RUN_LINE`), then the header. CSV readers take it
as a comment (``pandas.read_csv(path, comment="#")``); the robot's logs and the logs of
earlier tables have none.

**Another run's log** is refused in one line before any file is written, when it
evidently does not belong to the table:

* a log whose run line names another run than the table's (or names one, beside a table
  made before run ids);
* a new table (no table file, no backup) with a log that already holds rows (a new
  table's log without rows gets this run's first line and header);
* a table that records a goal (``--goal`` other than the arena's active one, not
  ``random``, kept for the table's whole life) and a row that names another goal;
* for a log without a run line only: a row the run would move as ahead of the table
  whose ``epsilon`` is no value of the run's exploration schedule (``learner.epsilon``)
  at any episode number (one robot logs the value of the episode's own number, many
  robots that of its start's number).

Without a run line, only the rows ahead are held to the schedule: they were written by
the run that saved the table last, and resuming it with its configuration writes the same
values; rows the table holds may have been written under other learner parameters. So a
log of another run without a run line that is not ahead of the table (and has the same
goal) is taken as the table's, with the warning that rows are missing if any are.

**What a row may hold.** Every line of at most :data:`MAX_LOG_LINE` characters (longer
ones are refused before the CSV reader sees them), the header's number of columns,
``episode``, ``steps`` and ``bumps`` integers >= 0 in ASCII digits, ``reward``,
``epsilon`` and the ``realism.*`` draws finite decimal numbers in ASCII (:func:`ascii_int`,
:func:`ascii_float`: Python's ``int`` and ``float`` would take ``²``, ``١٢``, ``1_0``,
`` 7`` or ``nan``), ``rescued`` 0 or 1. A complete row that breaks a rule is refused with
one line naming it; a torn last row is moved to ``<log>.removed`` (above); readers
(:func:`log_rows`, ``koolio-pm plot``) leave a torn last row out (it may be a row being
written).
"""

from __future__ import annotations

import contextlib
import csv
import functools
import io
import math
import os
import re
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..robot_runtime import LOG_FIELDS, open_append
from .errors import FileError, KoolioError, located
from .files import (
    atomic_write,
    check_path,
    check_regular,
    file_error,
    make_parent,
    not_regular,
    read_text,
)
from .locks import FileLock, check_lock_file, lock_path

if TYPE_CHECKING:
    from .config import EpsilonSchedule

#: The log's columns are :data:`~koolio_pymunk.robot_runtime.LOG_FIELDS`: the robot writes
#: the same log.
HEADER = ",".join(LOG_FIELDS)
#: The first line of the log of a table that has a run id
#: (:mod:`koolio_pymunk.store.run_identity`), before the header: ``# koolio-pymunk run
#: <id>`` (module doc, "Another run's log"). CSV readers skip it as a comment
#: (``pandas.read_csv(path, comment="#")``).
RUN_LINE = "# koolio-pymunk run "
_RUN_ID = re.compile(r"[0-9a-f]{16}")
#: Largest log read back (a million episodes is about 40 MiB).
MAX_LOG_BYTES = 1 << 30
#: Longest line of a log, characters (a row is under 200 plus 30 per ``realism.*``
#: column, a goal name at most 200; the CSV reader's own limit is 128 KiB per field).
MAX_LOG_LINE = 64 * 1024
#: Columns holding integers >= 0, and finite numbers (plus every ``realism.*`` column).
INT_FIELDS = ("episode", "steps", "bumps")
FLOAT_FIELDS = ("reward", "epsilon")

#: ``open()``'s opener of the log: appending, never waiting (a FIFO with no reader is an
#: error, not a hang), a regular file only (the robot's opener, with this package's error).
_APPEND = functools.partial(open_append, refuse=not_regular)
_INT = re.compile(r"[0-9]{1,18}")
_FLOAT = re.compile(
    r"[-+]?(?:[0-9]{1,400}(?:\.[0-9]{0,400})?|\.[0-9]{1,400})(?:[eE][-+]?[0-9]{1,4})?"
)


def ascii_int(text: str) -> int | None:
    """An integer >= 0 in ASCII digits (at most 18: below 2**63), else None.

    >>> ascii_int("42"), ascii_int("²"), ascii_int("1_0"), ascii_int(" 7"), ascii_int("-1")
    (42, None, None, None, None)
    """
    return int(text) if _INT.fullmatch(text) else None


def ascii_float(text: str) -> float | None:
    """A finite decimal number in ASCII (``-5``, ``0.15``, ``1e-05``), else None.

    >>> ascii_float("-1.5e+06"), ascii_float("nan"), ascii_float("١"), ascii_float("1e999")
    (-1500000.0, None, None, None)
    """
    if not _FLOAT.fullmatch(text):
        return None
    value = float(text)
    return value if math.isfinite(value) else None


def run_line(run_id: str) -> str:
    """The line a log of run ``run_id`` starts with.

    >>> run_line("0123456789abcdef")
    '# koolio-pymunk run 0123456789abcdef'
    """
    return RUN_LINE + run_id


def header_index(lines: list[str]) -> int:
    """Where the header is among a log's ``lines``: 1 after a run line (any first line
    starting with ``#``, checked by :func:`log_run_id`), else 0."""
    return 1 if lines and lines[0].startswith("#") else 0


def log_run_id(source: str, lines: list[str]) -> str | None:
    """The run id a log's first line names (None: a log without one, as logs before run
    ids and the robot's are); a first line starting with ``#`` that is not a run line is
    refused in one line."""
    if not header_index(lines):
        return None
    first = lines[0].rstrip("\r")
    rid = first[len(RUN_LINE) :]
    if not first.startswith(RUN_LINE) or not _RUN_ID.fullmatch(rid):
        shown = first if len(first) <= 40 else first[:37] + "..."
        raise KoolioError(
            located(
                source,
                "line 1",
                f"not a training log (its first line is {shown!r}: a log starts with its "
                f"header or with {RUN_LINE!r} and a run id); nothing was written",
            )
        )
    return rid


def split_log(text: str) -> tuple[list[str], bool]:
    """The lines of a log's text without the final line end, and whether the last one is
    torn (the text does not end with a line end): ``lines[-1]`` is then that torn row."""
    lines = text.split("\n")
    torn = lines[-1] != ""
    return (lines if torn else lines[:-1]), torn


def csv_fields(source: str, n: int, line: str) -> list[str]:
    """The fields of line ``n`` of a log (at most :data:`MAX_LOG_LINE` characters, one
    CSV record); one-line :class:`KoolioError` otherwise."""
    if len(line) > MAX_LOG_LINE:
        raise KoolioError(
            located(
                source,
                f"line {n}",
                f"{len(line):,} characters (a log line has at most "
                f"{MAX_LOG_LINE:,}): not a log row",
            )
        )
    try:
        records = list(csv.reader([line.rstrip("\r")]))
    except csv.Error as exc:
        raise KoolioError(located(source, f"line {n}", f"not a CSV row ({exc})")) from None
    return records[0] if records else []


def check_row(source: str, n: int, row: dict[str, str]) -> None:
    """The rules of a row (module doc) for the columns ``row`` has."""
    for name, value in row.items():
        if name in INT_FIELDS:
            ok = ascii_int(value) is not None
            want = "an integer >= 0 in digits 0-9"
        elif name in FLOAT_FIELDS or name.startswith("realism."):
            ok = ascii_float(value) is not None
            want = "a finite decimal number"
        elif name == "rescued":
            ok = value in ("0", "1")
            want = "0 or 1"
        else:
            continue
        if not ok:
            shown = value if len(value) <= 30 else value[:27] + "..."
            raise KoolioError(located(source, f"line {n}", f"{name}: not {want}: {shown!r}"))


def header_line(extra_fields: tuple[str, ...] = ()) -> str:
    """The header of a log with ``extra_fields`` after :data:`LOG_FIELDS`.

    >>> header_line(("realism.sonar.hit_sigma",)).split(",")[-2:]
    ['goal', 'realism.sonar.hit_sigma']
    """
    return ",".join((*LOG_FIELDS, *extra_fields))


def check_log_path(
    path: str | Path,
    table: str | Path | None = None,
    extra_fields: tuple[str, ...] | None = None,
) -> Path:
    """Refuse a log path that cannot be a log (module doc), before anything is written;
    ``extra_fields`` are the columns a writer will append (None: a reader)."""
    p = check_path(path, "--log")
    if p.is_dir():
        raise FileError(located(str(p), "", "is a folder, not a file (--log needs a file name)"))
    check_regular(p)  # a FIFO would block the writer (and a reader) for ever
    if table is not None:
        t = Path(table)
        for other, what in (
            (t, "the Q-table"),
            (t.with_name(t.name + ".bak"), "the Q-table's backup"),
            (lock_path(t), "the Q-table's lock file"),
        ):
            if _same_file(p, other):
                raise KoolioError(
                    located(str(p), "", f"is {what} ({other}): give the log its own file")
                )
    if p.name.endswith(".lock"):
        raise KoolioError(located(str(p), "", "is a lock file: give the log its own file"))
    check_lock_file(p)  # before the table is read: one line, not a warning and then one
    if p.exists() and p.stat().st_size > 0:
        text = _read(p)
        _check_header(p, text, extra_fields)
        if extra_fields is not None:  # a writer: every complete row, before the table is read
            _check_rows(p, text)
    if extra_fields is not None:
        _check_appendable(p)
    return p


def _check_appendable(p: Path) -> None:
    """A writer's log can take its first row, which comes after the first save of the
    table (a log that cannot would leave the two out of step): an existing log opens for
    appending, a dangling link is refused, a new log's folder can be made."""
    if p.is_symlink() and not p.exists():
        raise FileError(
            located(str(p), "", f"is a link to a missing file ({os.readlink(p)}): give a real file")
        )
    if p.exists():
        try:
            os.close(os.open(p, os.O_WRONLY | os.O_APPEND | getattr(os, "O_NONBLOCK", 0)))
        except OSError as exc:
            raise file_error(p, "write", exc) from None
        return
    folder = p.absolute().parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    if not folder.is_dir():
        raise FileError(
            located(str(p), "", f"cannot create the folder {p.parent}: a file is in the way")
        )
    if not os.access(folder, os.W_OK | os.X_OK):
        why = "read-only file system" if _read_only(folder) else "permission denied"
        raise FileError(located(str(p), "", f"cannot write: {why} ({folder})"))


def _read_only(folder: Path) -> bool:
    """``folder`` is on a file system mounted read-only (what a write would say: EROFS,
    not EACCES; False where that cannot be asked)."""
    try:
        return bool(os.statvfs(folder).f_flag & os.ST_RDONLY)
    except (AttributeError, OSError):  # no statvfs (Windows), or unreachable
        return False


def _check_rows(p: Path, text: str) -> None:
    """Every complete row of the log text (module doc); a torn last row is not one."""
    lines, torn = split_log(text)
    h = header_index(lines)
    header = csv_fields(str(p), h + 1, lines[h])
    for k, line in enumerate(lines[h + 1 : -1] if torn else lines[h + 1 :], start=h + 2):
        if line.strip():
            _row(p, k, line, header)


def _same_file(a: Path, b: Path) -> bool:
    """One file under two names: the same file, or (one is missing) the same place once
    links are followed (two dangling links to one name are one file to be)."""
    with contextlib.suppress(OSError):
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
    return os.path.realpath(a) == os.path.realpath(b)


def _read(p: Path) -> str:
    return read_text(p, MAX_LOG_BYTES, "training log")


def _check_header(p: Path, text: str, extra_fields: tuple[str, ...] | None = None) -> None:
    """A log's header: :data:`LOG_FIELDS`, then only ``realism.*`` columns; a writer's
    ``extra_fields`` must be exactly the log's extra columns."""
    lines = text.split("\n", 2)
    h = header_index(lines)
    log_run_id(str(p), lines)
    first = lines[h].rstrip("\r") if h < len(lines) else ""
    extra = first[len(HEADER) + 1 :].split(",") if first.startswith(HEADER + ",") else []
    if first != HEADER and (not extra or not all(c.startswith("realism.") for c in extra)):
        shown = first if len(first) <= 40 else first[:37] + "..."
        raise KoolioError(
            located(
                str(p),
                f"line {h + 1}",
                f"not a training log (its {'second' if h else 'first'} line is {shown!r}, a "
                f"log's header is {HEADER!r}); nothing was written",
            )
        )
    if extra_fields is not None and tuple(extra) != tuple(extra_fields):
        mine = ", ".join(extra_fields) or "none"
        raise KoolioError(
            located(
                str(p),
                f"line {h + 1}",
                f"its extra columns ({', '.join(extra) or 'none'}) are not this run's "
                f"({mine}): domain randomization differs; give another --log",
            )
        )


def log_rows(path: str | Path) -> list[dict[str, str]]:
    """The rows of a log (header and every complete row checked: module doc), as
    mappings; ``[]`` when missing or empty. A torn last row is left out."""
    p = Path(path)
    if not p.exists():
        return []
    text = _read(p)  # a FIFO or a device is refused here, before it is opened
    if not text:
        return []
    _check_header(p, text)
    lines, torn = split_log(text)
    h = header_index(lines)
    header = csv_fields(str(p), h + 1, lines[h])
    body = lines[h + 1 : -1] if torn else lines[h + 1 :]
    rows = []
    for k, line in enumerate(body, start=h + 2):
        if line.strip():
            rows.append(_row(p, k, line, header))
    return rows


def _row(p: Path, n: int, line: str, header: list[str]) -> dict[str, str]:
    """Line ``n`` of the log ``p`` as a checked mapping of ``header`` to its fields."""
    fields = csv_fields(str(p), n, line)
    if len(fields) != len(header):
        raise KoolioError(
            located(
                str(p), f"line {n}", f"{len(fields)} columns, this log's rows have {len(header)}"
            )
        )
    row = dict(zip(header, fields))
    check_row(str(p), n, row)
    return row


@dataclass(frozen=True)
class RowRules:
    """What the rows of a table's log can hold, from the run and the table (module doc,
    "Another run's log"); None: not checked."""

    epsilon: EpsilonSchedule | None = None
    """The run's exploration schedule: a row ahead of the table has one of its values."""
    goal: str | None = None
    """The goal every row names (a table that records one, other than ``random``)."""
    run_id: str | None = None
    """The table's run id: a log that names another is another run's, and a new log
    starts with it (:func:`run_line`). None: a table made before run ids."""


def schedule_gives(schedule: EpsilonSchedule, logged: str) -> bool:
    """Does ``schedule`` give the epsilon ``logged`` (as a log writes it: 6 significant
    digits) at some episode number >= 0? Exact for any number of decay episodes: the
    schedule is linear, so only the episode numbers next to where its line crosses the
    value can give it.

    >>> from koolio_pymunk.store.config import EpsilonSchedule
    >>> s = EpsilonSchedule(start=0.15, end=0.01, decay_episodes=600)
    >>> [schedule_gives(s, v) for v in ("0.15", "0.149767", "0.01", "0.1497", "0.2")]
    [True, True, True, False, False]
    >>> schedule_gives(EpsilonSchedule(0.01, 0.01, 0), "0.149767")
    False
    """
    value = ascii_float(logged)
    if value is None:
        return False
    want = f"{value:.6g}"
    start, end, n = schedule.start, schedule.end, schedule.decay_episodes
    numbers = {0}
    if n > 0:
        numbers.add(n)  # ``end`` from then on
        if end != start:
            x = (value - start) * n / (end - start)
            if math.isfinite(x) and -2 <= x <= n + 2:
                k = math.floor(x)
                numbers.update(j for j in range(k - 1, k + 3) if 0 <= j <= n)
    return any(f"{schedule.at(k):.6g}" == want for k in numbers)


class LogWriter:
    """Appends CSV rows to the log (header once), flushing every row.

    With ``episodes`` (the Q-table's episode count) the existing log is first brought in
    step with the table (module doc); ``fresh`` says the table is new (made by this run),
    ``rules`` what its rows can hold (another run's log is refused). The log's lock is
    held until :meth:`close`.
    """

    def __init__(
        self,
        path: str | Path | None,
        episodes: int | None = None,
        fresh: bool = False,
        table: str | Path | None = None,
        purpose: str = "koolio-pm",
        warn: Callable[[str], None] | None = None,
        extra_fields: tuple[str, ...] = (),
        rules: RowRules | None = None,
    ) -> None:
        self.path = Path(path) if path is not None and str(path) != "" else None
        self.extra_fields = tuple(extra_fields)
        """Columns after :data:`LOG_FIELDS` (the ``realism.*`` draws)."""
        self._fh: io.TextIOBase | None = None
        self._warn = warn or (lambda msg: print(f"warning: {msg}", file=sys.stderr))
        self._lock: FileLock | None = None
        self.run_id = rules.run_id if rules is not None else None
        """The run id a new log starts with (None: none)."""
        self._later: list[str] = []
        """Warnings of missing rows, given with the first new row: they change no file, and
        a run that fails before it (at its first save) says only its error."""
        if self.path is None:
            return
        check_log_path(self.path, table, self.extra_fields)
        self._lock = FileLock(self.path, purpose).acquire()
        try:
            if episodes is not None:
                self._reconcile(episodes, fresh, table, rules)
        except OSError as exc:
            self.close()
            raise file_error(self.path, "write", exc) from None
        except BaseException:
            self.close()
            raise

    # -- agreement with the table -----------------------------------------------------------
    def _reconcile(
        self, episodes: int, fresh: bool, table: str | Path | None, rules: RowRules | None
    ) -> None:
        assert self.path is not None
        p = self.path
        text = _read(p) if p.exists() else None
        if not text:
            if not fresh and episodes > 0:
                why = "it is missing" if text is None else "it is empty"
                self._later.append(_lacks(p, 0, episodes, table, why))
            return
        _check_header(p, text, self.extra_fields)
        plan = _plan(p, text, episodes, fresh, table, rules)
        h = header_index(plan.lines)
        if fresh and log_run_id(str(p), plan.lines) != self.run_id:  # no rows (else refused)
            atomic_write(p, b"")  # a new table's log: this run's first line and header
            return
        if plan.header_only:  # the header without its line end
            atomic_write(p, ("\n".join(plan.lines[: h + 1]) + "\n").encode("utf-8"))
        if plan.again or plan.torn is not None:
            kept = removed_path(p)
            removed = plan.lines[plan.keep : -1] + ([plan.torn] if plan.torn is not None else [])
            # first: a crash between the two writes loses nothing (the rows of any run: a
            # header and no run line)
            _append_rows(kept, plan.lines[h], removed)
            atomic_write(p, ("\n".join(plan.lines[: plan.keep]) + "\n").encode("utf-8"))
            if plan.again:
                self._warn(_moved(p, plan.again, kept, table, episodes))
            if plan.lost is not None:
                t = plan.lost
                whose = ", whose row is lost" if t > plan.last else ""
                self._warn(
                    f"{p}: its last row was cut short (episode {t}, a write interrupted): "
                    f"moved to {kept}; the Q-table {table or ''} holds episode {t}{whose}"
                )
        if plan.cut or fresh:  # rows ahead: none is missing; a new table: none yet
            return
        first = plan.last + 1
        if plan.lost is not None and plan.lost == first:
            first += 1  # said above
        if first < episodes:
            them = "it" if first == episodes - 1 else "them"
            why = (
                f"the run stopped after saving the table and before writing {them}"
                if plan.rows
                else "it holds no rows"
            )
            self._later.append(_lacks(p, first, episodes, table, why))

    # -- writing -------------------------------------------------------------------------
    def _open(self) -> io.TextIOBase:
        """The file, opened at the first row (a run that fails before its first episode
        ends creates no log); a new or empty log gets the header first."""
        assert self.path is not None
        if self._fh is None:
            make_parent(self.path)
            self._fh = open(  # noqa: SIM115
                self.path, "a", newline="", encoding="utf-8", opener=_APPEND
            )
            if os.fstat(self._fh.fileno()).st_size == 0:  # new or empty: the header first
                if self.run_id is not None:
                    self._fh.write(run_line(self.run_id) + "\n")
                self._fh.write(header_line(self.extra_fields) + "\n")
        return self._fh

    def write(self, result: Any) -> None:
        """Append ``result.row()`` (an :class:`~koolio_pymunk.learning.episodes.EpisodeResult`)."""
        if self.path is None:
            return
        for message in self._later:
            self._warn(message)
        self._later = []
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerow(result.row())
        try:
            fh = self._open()
            fh.write(buf.getvalue())
            fh.flush()
        except OSError as exc:
            raise file_error(self.path, "write", exc) from None

    def close(self) -> None:
        if self._fh is not None:
            with contextlib.suppress(OSError):
                self._fh.close()
            self._fh = None
        if self._lock is not None:
            self._lock.release()
            self._lock = None


def removed_path(log: Path) -> Path:
    """Where rows taken out of ``log`` are kept: ``<log>.removed`` (a log too)."""
    return log.with_name(log.name + ".removed")


def _append_rows(path: Path, header: str, lines: list[str]) -> None:
    """Append ``lines`` to the log ``path`` (created with ``header``), atomically."""
    old = read_text(path, MAX_LOG_BYTES, "training log") if path.exists() else ""
    if not old:
        old = header + "\n"
    elif not old.endswith("\n"):
        old += "\n"
    atomic_write(path, (old + "".join(ln + "\n" for ln in lines)).encode("utf-8"))


@dataclass
class _Plan:
    """How a log is brought in step with a table of ``episodes`` episodes (module doc)."""

    lines: list[str]
    """The log's text split at line ends (the last item: after the last one)."""
    keep: int
    """``lines[:keep]`` stay in the log (the header included)."""
    cut: bool
    """Complete rows are ahead of the table (``lines[keep:-1]`` move)."""
    last: int
    """The last finished episode kept (-1: none)."""
    rows: int
    """Complete rows of the log."""
    torn: str | None
    """The torn last line (no line end), moved too; None: none."""
    again: list[str]
    """The lines moved whose episodes run again (with the torn line when its episode is
    not the table's, or unknown)."""
    lost: int | None
    """The torn line's episode when the table holds it (its row is lost)."""
    header_only: bool = False
    """The log is its header without a line end."""


def _plan(
    p: Path,
    text: str,
    episodes: int,
    fresh: bool,
    table: str | Path | None,
    rules: RowRules | None,
) -> _Plan:
    """What bringing the log text ``text`` in step with a table of ``episodes`` episodes
    does; a one-line :class:`KoolioError` when the log is another run's (module doc).
    Reads only."""
    lines = text.split("\n")
    h = header_index(lines)
    _check_run(p, lines, rules, table)
    if len(lines) == h + 1:  # the header without its line end
        return _Plan([*lines, ""], h + 1, False, -1, 0, None, [], None, header_only=True)
    torn = lines[-1] if lines[-1] != "" else None
    rows = sum(1 for ln in lines[h + 1 : -1] if ln.strip())
    if fresh and (rows or torn is not None):
        raise KoolioError(
            located(
                str(p),
                "",
                f"holds {rows} rows of another run, and the Q-table "
                f"{table or ''} is new: give a new --log (or move this one away)",
            )
        )
    cut, last = _cut_line(p, lines, episodes, rules, table)
    keep = len(lines) - 1 if cut is None else cut
    named = rules is not None and rules.run_id is not None and h == 1  # the same id: checked
    if rules is not None and rules.epsilon is not None and cut is not None and not named:
        _check_ahead(p, lines, keep, episodes, rules.epsilon, table)
    again = lines[keep:-1]
    t = _torn_number(torn) if torn is not None else None
    lost = t if t is not None and t < episodes else None
    if torn is not None and lost is None:
        again.append(torn)
    return _Plan(lines, keep, cut is not None, last, rows, torn, again, lost)


def check_in_step(
    path: str | Path,
    episodes: int,
    table: str | Path | None = None,
    rules: RowRules | None = None,
) -> None:
    """Refuse, reading only, the log at ``path`` that a run on a table of ``episodes``
    episodes would refuse (another run's log: module doc); a missing or empty log
    passes. The header and rows are checked first (:func:`check_log_path`)."""
    p = Path(path)
    if not p.exists() or rules is None:
        return
    text = _read(p)
    if not text:
        return
    _check_header(p, text)
    lines = text.split("\n")
    _check_run(p, lines, rules, table)
    body = lines[header_index(lines) + 1 : -1]
    if rules.goal is None and all((_torn_number(ln) or 0) < episodes for ln in body):
        return  # no row ahead (a pass without the CSV reader: a long log is read once more)
    _plan(p, text, episodes, False, table, rules)


def _check_run(p: Path, lines: list[str], rules: RowRules | None, table: str | Path | None) -> None:
    """A log that names a run id is the log of the table with that id only (module doc)."""
    theirs = log_run_id(str(p), lines)
    mine = rules.run_id if rules is not None else None
    if theirs is None or theirs == mine:
        return
    what = f"run {mine}" if mine is not None else "a table made before run ids"
    raise KoolioError(
        located(
            str(p),
            "line 1",
            f"the log of run {theirs}, and the Q-table {table or ''} is {what}: a log of "
            "another run; give another --log",
        )
    )


def _check_ahead(
    p: Path,
    lines: list[str],
    keep: int,
    episodes: int,
    schedule: EpsilonSchedule,
    table: str | Path | None,
) -> None:
    """The complete rows ``lines[keep:-1]`` (ahead of the table) have epsilons the run's
    ``schedule`` gives (module doc)."""
    h = header_index(lines)
    header = csv_fields(str(p), h + 1, lines[h])
    for k in range(keep, len(lines) - 1):
        if not lines[k].strip():
            continue
        row = _row(p, k + 1, lines[k], header)
        if not schedule_gives(schedule, row["epsilon"]):
            raise KoolioError(
                located(
                    str(p),
                    f"line {k + 1}",
                    f"episode {row['episode']} has epsilon {row['epsilon']}, which this "
                    "run's learner.epsilon never gives: a row of another run, ahead of the "
                    f"Q-table {table or ''} ({_count(episodes)}); give another --log, or "
                    "resume with the configuration that wrote it",
                )
            )


def _cut_line(
    p: Path,
    lines: list[str],
    episodes: int,
    rules: RowRules | None = None,
    table: str | Path | None = None,
) -> tuple[int | None, int]:
    """Index of the first line to remove (the first finished row numbered ``episodes`` or
    more), or None; and the last finished episode number kept (-1: none). Every row
    before it is checked (module doc), and with ``rules.goal`` every row names it."""
    last = -1
    cut = None
    goal = rules.goal if rules is not None else None
    h = header_index(lines)
    header = csv_fields(str(p), h + 1, lines[h])
    for k in range(h + 1, len(lines) - 1):
        if not lines[k].strip() or (cut is not None and goal is None):
            continue
        row = _row(p, k + 1, lines[k], header)
        number = int(row["episode"])
        if goal is not None and row["goal"] != goal:
            raise KoolioError(
                located(
                    str(p),
                    f"line {k + 1}",
                    f"episode {number} was logged for goal {row['goal']}, and the Q-table "
                    f"{table or ''} is trained for goal {goal}: a row of another run; give "
                    "another --log",
                )
            )
        if cut is not None or row["outcome"] == "interrupted":
            continue
        if number >= episodes:
            cut = k
            continue
        if number <= last:
            raise KoolioError(
                located(
                    str(p),
                    f"line {k + 1}",
                    f"episode numbers go back ({number} after {last}): not the log of one "
                    "run; give another --log",
                )
            )
        last = number
    return cut, last


def _torn_number(line: str) -> int | None:
    """The episode number of a row, torn or not: its digits before its first comma (None
    when the row was cut before that comma, or does not start with a number)."""
    head, comma, _ = line[:20].partition(",")
    return ascii_int(head) if comma else None


def _span(numbers: list[int]) -> str:
    """``episode 4``, ``episodes 4..5``, or ``a torn row`` (no number)."""
    if not numbers:
        return "a torn row"
    if numbers[0] == numbers[-1]:
        return f"episode {numbers[0]}"
    return f"episodes {numbers[0]}..{numbers[-1]}"


def _moved(p: Path, lines: list[str], kept: Path, table: str | Path | None, episodes: int) -> str:
    """The warning of rows moved out of the log ``p`` whose episodes run again."""
    rows = "1 row" if len(lines) == 1 else f"{len(lines)} rows"
    return (
        f"{p}: moved {rows} ({_span(_numbers(lines))}) to {kept}: the Q-table {table or ''} "
        f"holds {_count(episodes)} (it was saved before them); they run again"
    )


def _lacks(p: Path, first: int, episodes: int, table: str | Path | None, why: str) -> str:
    """The warning of a log lacking the rows of episodes ``first``..``episodes - 1``."""
    if first == episodes - 1:
        which = f"the row of episode {first}"
    else:
        which = f"the rows of episodes {first}..{episodes - 1}"
    if first == 0:
        return (
            f"{p}: lacks {which} ({why}; the Q-table {table or ''} holds "
            f"{_count(episodes)}); new rows start at episode {episodes}"
        )
    return f"{p}: lacks {which} ({why})"


def _count(episodes: int) -> str:
    """``1 episode``, ``6 episodes``."""
    return f"{episodes} episode" + ("" if episodes == 1 else "s")


def _numbers(lines: list[str]) -> list[int]:
    """Episode numbers of the rows ``lines`` (:func:`_torn_number`: a row cut before its
    first comma, or malformed, has none)."""
    return sorted(n for n in map(_torn_number, lines) if n is not None)
