"""A run's Q-table and log, opened together: checked, locked, and kept in step.

:class:`RunFiles` holds a run's Q-table (:class:`~koolio_pymunk.store.qtable.QTableStore`)
and its per-episode CSV log (:mod:`koolio_pymunk.store.episode_log`): both locked against
a second writer, the log checked before anything is written and brought in step with the
table. Every finished episode is recorded the same way by every loop (``train``, the
window, many robots): the table's episode count, the table kept (every ``save_every``
episodes; the paper's cadence, 1, by default), then the log row appended and flushed::

    episode,reward,steps,bumps,outcome,rescued,epsilon,goal

``outcome`` is ``goal``, ``end_of_world``, ``wrong_door``, ``truncated`` (step cap) or
``interrupted`` (Ctrl-C / Exit: the unfinished episode was folded into the table). With
domain randomization (``realism.randomize``) every row ends with the parameters drawn for
its episode, one column per parameter, named ``realism.<section>.<name>`` (sorted),
written with ``repr`` so that they round-trip exactly.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from . import run_identity
from .episode_log import LogWriter, check_in_step, check_log_path, log_rows
from .errors import KoolioError, located
from .locks import check_lock_file
from .qtable import QTable, QTableStore
from .run_identity import RunIdentity

#: With ``--fsync second``: the longest time between two durable snapshots of the table
#: (what a power loss can lose), seconds.
CHECKPOINT_SECONDS = 1.0


class RunFiles:
    """A run's Q-table and log, locked, in step, and recorded the same way by every loop.

    :meth:`open` locks and opens them (the log checked before any file is written, a new
    table created only then, the log brought in step with the table). :meth:`finished`
    records a finished episode, :meth:`folded` an unfinished one kept in the table (Exit,
    Ctrl-C), :meth:`close` releases both. ``save_every`` > 1 saves the table every that
    many finished episodes (and always on :meth:`save`); ``before_save`` runs before each
    save (many robots copy their compiled table into the Q-table there).
    """

    def __init__(
        self,
        store: QTableStore,
        table: QTable,
        log: LogWriter,
        save_every: int = 1,
        before_save: Callable[[], None] | None = None,
        save_seconds: float | None = None,
    ) -> None:
        self.store = store
        self.table = table
        self.log = log
        self.save_every = max(1, save_every)
        self.save_seconds = save_seconds
        """Also save when this many seconds passed since the last save (None: never by
        time)."""
        self.before_save = before_save
        """Runs before each snapshot (the engine copies its compiled table into the
        Q-table there)."""
        self.changed_rows: Callable[[], tuple] | None = None
        """The rows changed since its last call, as ``(keys, values)`` arrays (the
        engine's): with ``--fsync second`` they go to the table's journal between two
        snapshots. None: the changes are not tracked (the Python loop), and the journal
        gets the whole table."""
        self._saved_at = self._durable_at = time.monotonic()
        self.first = int(table.meta.get("episodes", 0))
        """Episodes the table held when the run opened it."""
        self.unsaved = 0
        """Finished episodes recorded since the last save."""
        self.undurable = 0
        """Finished episodes saved in the journal since the last snapshot."""

    @classmethod
    def open(
        cls,
        run: RunIdentity,
        store: QTableStore,
        log_path: str | Path | None,
        purpose: str = "koolio-pm",
        seed: int | None = None,
    ) -> RunFiles:
        """Lock and open ``store``'s table and the log at ``log_path`` for the run ``run``
        (:meth:`RunIdentity.of_run <koolio_pymunk.store.run_identity.RunIdentity.of_run>`;
        ``None`` or ``""``: no log; ``seed``: the run's, recorded in a new table's run id).
        The caller closes them (:meth:`close`).

        Everything that can be checked by reading is checked before the lock is taken
        (:meth:`check`), so a refused run leaves no file behind, not even a lock file.
        """
        source = str(store.path)
        try:
            cls.check(run, store, log_path)
            table = store.load(
                lambda: run_identity.new_table(run, seed),
                lambda t: run_identity.check(t, run, "resume", source, store.warn),
            )
            run_identity.stamp(table, run)  # the run's learner parameters
            rules = run_identity.log_rules(run, table)
            log = LogWriter(
                log_path,
                int(table.meta.get("episodes", 0)),
                store.fresh or store.created,  # made by this run (--init-qtable): a new log
                store.path,
                purpose,
                extra_fields=run.log_columns,
                rules=rules,
            )
            try:
                if store.fresh:
                    store.create(table)
            except BaseException:
                log.close()
                raise
        except BaseException:
            store.close()
            raise
        return cls(store, table, log)

    @staticmethod
    def check(
        run: RunIdentity,
        store: QTableStore,
        log_path: str | Path | None,
    ) -> QTable | None:
        """The checks of :meth:`open` that need no lock, by reading only: the log's path
        and header, the table (the backup when torn) one this run may resume
        (:func:`~koolio_pymunk.store.run_identity.check`, purpose ``resume``), a log
        that is not another run's (a new table's without rows; its run id, and
        :class:`~koolio_pymunk.store.episode_log.RowRules`). Returns the table a run
        would resume (None: a new one)."""
        logged = log_path is not None and str(log_path) != ""
        if not store.locked:  # in use by another: that, before a line about the table
            check_lock_file(store.path)
        if logged:
            check_log_path(log_path, store.path, run.log_columns)
        table = store.peek()
        if table is None:
            rows = log_rows(log_path) if logged else []
            if rows:
                raise KoolioError(
                    located(
                        str(log_path),
                        "",
                        f"holds {len(rows)} rows of another run, and the Q-table "
                        f"{store.path} is new: give a new --log (or move this one away)",
                    )
                )
            return None
        run_identity.check(table, run, "resume", str(store.path), store.warn)
        rules = run_identity.log_rules(run, table)
        if logged and not store.created:  # a table this run made has a new log (checked)
            check_in_step(log_path, int(table.meta.get("episodes", 0)), store.path, rules)
        return table

    def finished(self, res: Any, save: bool = False) -> None:
        """Record finished episode ``res`` (an
        :class:`~koolio_pymunk.learning.episodes.EpisodeResult`): the table's count, the
        table kept when due (:meth:`keep`; ``save``: a snapshot now), the row."""
        self.table.meta["episodes"] = res.episode + 1
        self.unsaved += 1
        late = self.save_seconds is not None and (
            time.monotonic() - self._saved_at >= self.save_seconds
        )
        if save:
            self.save()
        elif late or self.unsaved >= self.save_every:
            self.keep()
        self.log.write(res)

    def keep(self) -> None:
        """The episodes finished since the last save into the table's files, as the
        store's ``fsync`` mode keeps them (:class:`~koolio_pymunk.store.qtable.QTableStore`):
        ``episode``, a durable snapshot; ``second``, a durable snapshot when
        :data:`CHECKPOINT_SECONDS` passed since the last one, else a journal record of
        the rows changed (untracked changes, or a table with data sections: the whole
        table)."""
        now = time.monotonic()
        if self.store.fsync == "episode" or now - self._durable_at >= CHECKPOINT_SECONDS:
            self.save()
            return
        if self.changed_rows is not None and not self.table.sections:
            keys, values = self.changed_rows()
            self.store.append(self.table, keys, values)
        else:  # untracked changes, or data sections (Dyna-Q's model): the whole table
            if self.before_save is not None:
                self.before_save()
            self.store.append(self.table)
        self.undurable += self.unsaved
        self.unsaved = 0
        self._saved_at = now

    def checkpoint(self) -> None:
        """A durable snapshot when anything finished since the last one (the end of a
        run, or a stop between episodes)."""
        if self.unsaved or self.undurable:
            self.save()

    def folded(self, *results: Any) -> None:
        """Record unfinished episodes whose updates stay in the table (Exit): the table
        saved (its episode count unchanged), each row logged ``interrupted``."""
        self.save()
        for res in results:
            self.log.write(res)

    def save(self) -> None:
        """Write the table whole and durably now (with its backup; its journal is then
        empty): the end of a run, Ctrl-C, SIGTERM, a check, a checkpoint."""
        if self.before_save is not None:
            self.before_save()
        if self.changed_rows is not None:
            self.changed_rows()  # the snapshot holds them: the next record starts after
        self.store.save(self.table)
        self.unsaved = self.undurable = 0
        self._saved_at = self._durable_at = time.monotonic()

    def close(self) -> None:
        """Release the log and the table (their locks)."""
        try:
            self.log.close()
        finally:
            self.store.close()
