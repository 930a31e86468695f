"""The per-episode training log: one CSV row per episode, kept in step with its Q-table.

``koolio-pm train`` and ``koolio-pm view`` append one row per finished (or interrupted)
episode to the log (``--log``, default ``runs/<arena>.csv``)::

    episode,reward,steps,bumps,outcome,rescued,epsilon,goal

``outcome`` is ``goal``, ``end_of_world``, ``wrong_door`` (a Stop before a misread
plate, in a realistic world), ``truncated`` (step cap) or ``interrupted`` (Ctrl-C / Exit:
the unfinished episode was folded into the table; its number is run again when training
resumes). With domain randomization the draw of each episode follows in extra columns
named ``realism.<section>.<name>`` (:mod:`koolio_pymunk.realism`).

**Which files may be a log.** A log that exists must start with that header line (and a
run appending to it must write the same extra columns): any other file (an arena, a
Q-table, a binary file) is refused with a one-line error and left untouched, and the log
must not be the Q-table, its backup or a lock file. While a run writes a log it holds
the log's lock (:mod:`koolio_pymunk.locks`).

**Agreement with the table.** The table is saved before an episode's row is written, so
the log and the table can disagree after a stop:

* a row is missing when the process was killed between the two writes (at most one row,
  or the rows of one save with ``--robots N``); resuming warns and goes on;
* rows are ahead when the table holds fewer episodes than the log: ``--robots N`` saves
  every N episodes, and a torn table falls back to its backup. Those episodes' learning
  is not in the table and their numbers will be run again, so resuming **moves** those
  rows (and the interrupted rows after them) out of the log into ``<log>.removed`` (a log
  too, so nothing is lost), with a warning, before appending: episode numbers never
  repeat (except after an ``interrupted`` row, by design);
* a new table (no table file, no backup) with a log that already holds rows is refused:
  that log belongs to another run.

A torn last row (no line end) is moved the same way.
"""

from __future__ import annotations

import contextlib
import csv
import io
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .errors import FileError, KoolioError, located
from .files import atomic_write, check_path, file_error, make_parent, read_text
from .locks import FileLock, lock_path

LOG_FIELDS = ("episode", "reward", "steps", "bumps", "outcome", "rescued", "epsilon", "goal")
HEADER = ",".join(LOG_FIELDS)
#: Largest log read back (a million episodes is about 40 MiB).
MAX_LOG_BYTES = 1 << 30


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
    if p.exists() and p.stat().st_size > 0:
        _check_header(p, _read(p), extra_fields)
    return p


def _same_file(a: Path, b: Path) -> bool:
    with contextlib.suppress(OSError):
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
    return os.path.abspath(a) == os.path.abspath(b)


def _read(p: Path) -> str:
    return read_text(p, MAX_LOG_BYTES, "training log")


def _check_header(p: Path, text: str, extra_fields: tuple[str, ...] | None = None) -> None:
    """A log's header: :data:`LOG_FIELDS`, then only ``realism.*`` columns; a writer's
    ``extra_fields`` must be exactly the log's extra columns."""
    first = text.split("\n", 1)[0].rstrip("\r")
    extra = first[len(HEADER) + 1 :].split(",") if first.startswith(HEADER + ",") else []
    if first != HEADER and (not extra or not all(c.startswith("realism.") for c in extra)):
        shown = first if len(first) <= 40 else first[:37] + "..."
        raise KoolioError(
            located(
                str(p),
                "line 1",
                f"not a training log (its first line is {shown!r}, a log's is {HEADER!r}); "
                "nothing was written",
            )
        )
    if extra_fields is not None and tuple(extra) != tuple(extra_fields):
        mine = ", ".join(extra_fields) or "none"
        raise KoolioError(
            located(
                str(p),
                "line 1",
                f"its extra columns ({', '.join(extra) or 'none'}) are not this run's "
                f"({mine}): domain randomization differs; give another --log",
            )
        )


def log_rows(path: str | Path) -> list[dict[str, str]]:
    """The rows of a log (header checked), as mappings; ``[]`` when missing or empty."""
    p = Path(path)
    if not p.exists() or p.stat().st_size == 0:
        return []
    text = _read(p)
    _check_header(p, text)
    return list(csv.DictReader(io.StringIO(text)))


class LogWriter:
    """Appends CSV rows to the log (header once), flushing every row.

    With ``episodes`` (the Q-table's episode count) the existing log is first brought in
    step with the table (module doc); ``fresh`` says the table is new. The log's lock is
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
    ) -> None:
        self.path = Path(path) if path is not None and str(path) != "" else None
        self.extra_fields = tuple(extra_fields)
        """Columns after :data:`LOG_FIELDS` (the ``realism.*`` draws)."""
        self._fh: io.TextIOBase | None = None
        self._warn = warn or (lambda msg: print(f"warning: {msg}", file=sys.stderr))
        self._lock: FileLock | None = None
        if self.path is None:
            return
        check_log_path(self.path, table, self.extra_fields)
        self._lock = FileLock(self.path, purpose).acquire()
        try:
            if episodes is not None and self.path.exists():
                self._reconcile(episodes, fresh, table)
        except OSError as exc:
            self.close()
            raise file_error(self.path, "write", exc) from None
        except BaseException:
            self.close()
            raise

    # -- agreement with the table -----------------------------------------------------------
    def _reconcile(self, episodes: int, fresh: bool, table: str | Path | None) -> None:
        assert self.path is not None
        p = self.path
        text = _read(p)
        if not text:
            return
        _check_header(p, text, self.extra_fields)
        lines = text.split("\n")
        if len(lines) == 1:  # the header without its line end
            atomic_write(p, (lines[0] + "\n").encode("utf-8"))
            return
        torn = lines[-1] != ""  # the last row has no line end: a write was cut short
        rows = [ln for ln in lines[1:-1] if ln.strip()]
        if fresh and (rows or torn):
            raise KoolioError(
                located(
                    str(p),
                    "",
                    f"holds {len(rows)} rows of another run, and the Q-table "
                    f"{table or ''} is new: give a new --log (or move this one away)",
                )
            )
        cut, last = _cut_line(p, lines, episodes)
        if cut is None and not torn:
            if rows and last < episodes - 1:
                self._warn(
                    f"{p}: lacks the rows of episodes {last + 1}..{episodes - 1} (the run "
                    "stopped after saving the table and before writing them)"
                )
            return
        keep = len(lines) - 1 if cut is None else cut
        removed = lines[keep:-1] + ([lines[-1]] if torn else [])
        numbers = _numbers(removed)
        kept = removed_path(p)
        _append_rows(kept, lines[0], removed)  # first: a crash between the two writes loses nothing
        atomic_write(p, ("\n".join(lines[:keep]) + "\n").encode("utf-8"))
        if not numbers:
            span = "a torn row"
        elif numbers[0] == numbers[-1]:
            span = f"episode {numbers[0]}"
        else:
            span = f"episodes {numbers[0]}..{numbers[-1]}"
        rows = "1 row" if len(removed) == 1 else f"{len(removed)} rows"
        self._warn(
            f"{p}: moved {rows} ({span}) to {kept}: the Q-table {table or ''} holds "
            f"{episodes} episodes (it was saved before them); they run again"
        )

    # -- writing -------------------------------------------------------------------------
    def _open(self) -> io.TextIOBase:
        """The file, opened at the first row (a run that fails before its first episode
        ends creates no log); a new or empty log gets the header first."""
        assert self.path is not None
        if self._fh is None:
            make_parent(self.path)
            new = not self.path.exists() or self.path.stat().st_size == 0
            self._fh = open(self.path, "a", newline="", encoding="utf-8")  # noqa: SIM115
            if new:
                self._fh.write(header_line(self.extra_fields) + "\n")
        return self._fh

    def write(self, result: Any) -> None:
        """Append ``result.row()`` (an :class:`~koolio_pymunk.training.EpisodeResult`)."""
        if self.path is None:
            return
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


def _row_fields(p: Path, n: int, line: str, columns: int) -> list[str]:
    fields = next(csv.reader([line]))
    if len(fields) != columns:
        raise KoolioError(
            located(str(p), f"line {n}", f"{len(fields)} columns, this log's rows have {columns}")
        )
    return fields


def _cut_line(p: Path, lines: list[str], episodes: int) -> tuple[int | None, int]:
    """Index of the first line to remove (the first finished row numbered ``episodes`` or
    more), or None; and the last finished episode number kept (-1: none)."""
    last = -1
    for k in range(1, len(lines) - 1):
        if not lines[k].strip():
            continue
        fields = _row_fields(p, k + 1, lines[k], lines[0].count(",") + 1)
        try:
            number = int(fields[0])
        except ValueError:
            raise KoolioError(
                located(str(p), f"line {k + 1}", f"episode: not an integer: {fields[0]!r}")
            ) from None
        if fields[4] == "interrupted":
            continue
        if number >= episodes:
            return k, last
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
    return None, last


def _numbers(lines: list[str]) -> list[int]:
    out = []
    for ln in lines:
        head = ln.split(",", 1)[0]
        if head.isdigit():
            out.append(int(head))
    return sorted(out)
