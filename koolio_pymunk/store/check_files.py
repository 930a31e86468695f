"""The files of ``train --eval-every``'s checks: the evaluations file and the kept best table.

What a check *does* (play the table greedily, compare, keep) is
:class:`~koolio_pymunk.learning.evaluation.PeriodicCheck`'s; this module owns what it
*writes*, as :mod:`~koolio_pymunk.store.qtable` owns the table's files and
:mod:`~koolio_pymunk.store.episode_log` the log: the paths beside a run's table and log,
the checks made before the run writes anything, the locks, the rows, and the ``best``
record in the best table's header. The formats are in the evaluation module's doc.

>>> str(best_path("runs/hallway.qtable")), str(evals_path("runs/hallway.csv", "t.qtable"))
('runs/hallway.best.qtable', 'runs/hallway.evals.csv')
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

from . import run_identity
from .episode_log import csv_fields, split_log
from .errors import KoolioError, QTableError, located
from .files import atomic_write, check_path, file_error, read_text
from .locks import FileLock
from .qtable import QTable, QTableStore

#: Columns of the evaluations file (the evaluation module's doc).
EVALS_FIELDS = (
    "episode",
    "eval_episodes",
    "seed",
    "goal_rate",
    "end_of_world_rate",
    "wrong_door_rate",
    "truncated_rate",
    "mean_steps",
    "mean_bumps",
    "mean_return",
    "best",
    "seconds",
)
EVALS_HEADER = ",".join(EVALS_FIELDS)
#: Largest evaluations file read.
MAX_EVALS_BYTES = 1 << 26


def best_path(table: str | Path) -> Path:
    """The kept best table of the table file ``table``.

    >>> str(best_path("runs/hallway.qtable")), str(best_path("runs/t"))
    ('runs/hallway.best.qtable', 'runs/t.best.qtable')
    """
    p = Path(table)
    stem = p.stem if p.suffix == ".qtable" else p.name
    return p.with_name(stem + ".best.qtable")


def evals_path(log: str | Path | None, table: str | Path) -> Path:
    """The evaluations file of a run: beside its log (``X.csv`` -> ``X.evals.csv``), or
    beside its table when it has no log.

    >>> str(evals_path("runs/hallway.csv", "t.qtable")), str(evals_path("", "runs/t.qtable"))
    ('runs/hallway.evals.csv', 'runs/t.evals.csv')
    """
    base = Path(log) if log is not None and str(log) != "" else Path(table)
    return base.with_name(base.stem + ".evals.csv")


def best_record(table: QTable, source: str) -> dict[str, Any]:
    """The ``best`` record of a kept best table's header, checked (one-line error)."""
    rec = table.meta.get("best")

    def bad(item: str, problem: str) -> QTableError:
        return QTableError(located(source, f"header.best{item}", problem))

    if not isinstance(rec, dict):
        raise bad("", "missing or not a mapping (not a best table of train --eval-every)")
    ep = rec.get("episode")
    if not isinstance(ep, int) or isinstance(ep, bool) or ep < 0:
        raise bad(".episode", f"must be an integer >= 0, got {ep!r}"[:120])
    for key in ("goal_rate", "mean_return"):
        v = rec.get(key)
        if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
            raise bad(f".{key}", f"must be a finite number, got {v!r}"[:120])
    return rec


def read_evals(path: str | Path) -> list[list[str]]:
    """The rows of an evaluations file (header checked), ``[]`` when missing or empty."""
    p = Path(path)
    if not p.exists() or p.stat().st_size == 0:
        return []
    text = read_text(p, MAX_EVALS_BYTES, "evaluations file")
    first = text.split("\n", 1)[0].rstrip("\r")
    if first != EVALS_HEADER:
        shown = first if len(first) <= 40 else first[:37] + "..."
        raise KoolioError(
            located(
                str(p),
                "line 1",
                f"not an evaluations file (its first line is {shown!r}); nothing was written",
            )
        )
    lines, _ = split_log(text)  # a torn last row is a row (resuming moves it away)
    rows = (csv_fields(str(p), n, line) for n, line in enumerate(lines[1:], start=2))
    return [row for row in rows if row]


class CheckFiles:
    """A run's evaluations file and kept best table, checked and locked.

    :meth:`open` checks and locks both before the run writes anything; :meth:`resume`
    brings the evaluations file in step with the run's table; :meth:`keep` writes a new
    best table; :meth:`append` adds a check's row; :meth:`close` releases the locks.
    """

    def __init__(
        self, path: Path, best: QTableStore, lock: FileLock, kept: dict[str, Any] | None
    ) -> None:
        self.path = path
        """The evaluations file."""
        self.best = best
        """The best table's store (locked)."""
        self._lock = lock
        self.kept = kept
        """The kept best table's ``best`` record (None: no best yet)."""

    @classmethod
    def open(
        cls,
        run: run_identity.RunIdentity,
        store: QTableStore,
        log_path: str | Path | None,
        purpose: str = "koolio-pm train",
    ) -> CheckFiles:
        """Check and lock the evaluations file and the best table of ``store``'s run
        ``run`` (``log_path``: its log) before anything is written. A new table (no file, no
        backup) refuses an evaluations file with rows or a best table: they belong to
        another run; a best table must be of the run (its identity, purpose ``keep``)."""
        path = check_path(evals_path(log_path, store.path))
        best = QTableStore(best_path(store.path), purpose=purpose)
        _distinct(store.path, log_path, path, best.path)
        new_table = not (store.path.exists() or store.backup.exists())
        lock = FileLock(path, purpose).acquire()
        try:
            rows, _ = _checked_rows(path)
            if new_table and rows:
                raise KoolioError(
                    located(
                        str(path),
                        "",
                        f"holds {len(rows)} checks of another run, and the Q-table "
                        f"{store.path} is new: move it away",
                    )
                )
            if new_table and (best.path.exists() or best.backup.exists()):
                raise KoolioError(
                    located(
                        str(best.path),
                        "",
                        f"the best table of another run (the Q-table {store.path} is new): "
                        "move it away",
                    )
                )
            own = store.peek()  # the run's table: the best one must be of its run
            rid = own.meta.get("run_id") if own is not None else None
            source = str(best.path)
            table = best.load(
                lambda: run_identity.new_table(run),
                lambda t: run_identity.check(t, run, "keep", source, best.warn, run_id=rid),
            )
            kept = None if best.fresh else best_record(table, str(best.path))
        except BaseException:
            lock.release()
            best.close()
            raise
        return cls(path, best, lock, kept)

    def resume(self, episodes: int, warn: Callable[[str], None]) -> int:
        """Bring the evaluations file in step with a table of ``episodes`` episodes: rows
        beyond it move to ``<evals>.removed`` (they run again), with ``warn``. Returns
        the ``episode`` of the last row kept (0: none)."""
        rows, body = _checked_rows(self.path)
        keep = [r for r in body if int(r[0]) <= episodes]
        if len(keep) < len(rows):
            self._move_out(keep, rows[len(keep) :], episodes, warn)
        return int(keep[-1][0]) if keep else 0

    def _move_out(
        self, keep: list[list[str]], gone: list[list[str]], episodes: int, warn: Callable
    ) -> None:
        removed = self.path.with_name(self.path.name + ".removed")
        old = read_evals(removed)
        atomic_write(removed, _csv([*old, *gone]))  # first: a crash between loses nothing
        atomic_write(self.path, _csv(keep))
        warn(
            f"{self.path}: moved {len(gone)} checks to {removed}: the Q-table holds "
            f"{episodes} episodes (the checks beyond it run again)"
        )

    def keep(self, table: QTable, record: dict[str, Any]) -> None:
        """Keep a copy of ``table`` as the best table, ``record`` its header's ``best``."""
        best = table.copy()
        best.meta["best"] = record
        self.best.save(best)
        self.kept = record

    def append(self, row: list[str]) -> None:
        """Add a check's row (:data:`EVALS_FIELDS`), the header first in a new file."""
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerow(row)
        if not self.path.exists() or self.path.stat().st_size == 0:  # header and row at once
            atomic_write(self.path, (EVALS_HEADER + "\n" + buf.getvalue()).encode("utf-8"))
            return
        try:
            with open(self.path, "a", newline="", encoding="utf-8") as fh:
                fh.write(buf.getvalue())
        except OSError as exc:
            raise file_error(self.path, "write", exc) from None

    def close(self) -> None:
        """Release the evaluations file's and the best table's locks."""
        try:
            self._lock.release()
        finally:
            self.best.close()


def _checked_rows(path: Path) -> tuple[list[list[str]], list[list[str]]]:
    """The rows of an evaluations file, and those of them that are whole (all but a last
    row cut short by a kill, which runs again); one-line error on a bad row."""
    rows = read_evals(path)
    torn = bool(rows) and not path.read_bytes().endswith(b"\n")
    body = rows[:-1] if torn else rows
    last = -1
    for n, row in enumerate(body, start=2):
        if len(row) != len(EVALS_FIELDS) or not row[0].isdigit():
            raise KoolioError(located(str(path), f"line {n}", "not a row of an evaluations file"))
        if int(row[0]) <= last:
            raise KoolioError(located(str(path), f"line {n}", f"episode {row[0]} after {last}"))
        last = int(row[0])
    return rows, body


def _csv(rows: list[list[str]]) -> bytes:
    buf = io.StringIO()
    buf.write(EVALS_HEADER + "\n")
    csv.writer(buf, lineterminator="\n").writerows(rows)
    return buf.getvalue().encode("utf-8")


def _distinct(table: Path, log: str | Path | None, evals: Path, best: Path) -> None:
    """The evaluations file and the best table are none of the run's other files."""
    others = {
        "the Q-table": table,
        "the Q-table's backup": table.with_name(table.name + ".bak"),
    }
    if log is not None and str(log) != "":
        others["the log"] = Path(log)
    for path in (evals, best):
        for what, other in others.items():
            if path.resolve() == other.resolve():
                raise KoolioError(located(str(path), "", f"is {what}: give another --qtable/--log"))
