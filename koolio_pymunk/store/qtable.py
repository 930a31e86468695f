"""The Q-table: Table 12 keywords, a sparse table, and its files (paper §5.4.8).

**Keyword.** Each state field (goal cameras, end-of-world cameras, sonar groups) takes
``ceil(log2(levels))`` bits, most significant first, and the action the low 3 bits. With
the paper's sensors this is exactly Table 12 (27 bits)::

    GoalCam0<<25 | GoalCam1<<23 | GoalCam2<<21 | EoWCam0<<19 | EoWCam1<<17 | EoWCam2<<15 |
    Sonar0<<13 | Sonar1-2<<11 | Sonar3<<9 | Sonar4<<7 | Sonar5-6<<5 | Sonar7<<3 | Action

The table stores one row of ``n_actions`` values per visited state: the state key is the
keyword without its action bits (``keyword >> 3``).

**File format** (``.qtable``, little-endian, version 1)::

    b"KOOLIOQT"                      8 bytes magic
    uint32 header_length             then that many bytes of UTF-8 JSON (sorted keys):
                                     format, layout {fields, action_bits, n_actions},
                                     sensors (the sensor configuration), episodes, q_init,
                                     arena {name, sha256} (where it was learned),
                                     goal, world (only when not the defaults), ...
    uint64 n_rows
    uint64 state_key[n_rows]         ascending
    float64 q[n_rows][n_actions]
    bytes   section[...]             only when the header lists ``sections``
    uint32 crc32                     of every byte before it

Reading checks everything, checksum first and then every header field and row (a file
with a valid checksum but ``episodes: -5`` or a key beyond its layout is refused with a
one-line :class:`~koolio_pymunk.store.errors.QTableError` naming the item).

**What a table records of its run**: the run identity and its provenance
(:mod:`koolio_pymunk.store.run_identity`, which makes, reads and checks them). ``goal``
is recorded only when the run's goal is not the arena's active goal (``random``, or
another door), ``world`` only when the run was not in the ideal world: an absent key means
the default. ``run_id`` and ``provenance`` (versions, commit, configuration, command line)
are written once, when the table is made; tables made before them load without them.

A table learned with an algorithm other than one-step Q records it in the header
(``algorithm``: its name and parameters) and may carry data sections after the values,
listed in the header as ``sections: [[name, length], ...]`` (e.g. the Dyna-Q model,
:mod:`koolio_pymunk.learning.dyna`), covered by the CRC like the rest. A one-step Q table has
neither key, so its bytes are those of a table written before they existed.

The paper keeps a table file and a backup file, both created empty when missing, read at
start and written at the end of every episode. :class:`QTableStore` writes each one
atomically (temporary file, flush, fsync, rename) and keeps the previous good table in
the backup, so a crash at any moment leaves a loadable table. A torn table (checksum
mismatch) falls back to the backup with a warning; an unreadable one (permissions, I/O
error) is refused, since its backup is one episode behind and resuming from it would
repeat episode numbers for ever. The store holds the table's lock
(:mod:`koolio_pymunk.store.locks`) from :meth:`QTableStore.load` to :meth:`QTableStore.close`.
"""

from __future__ import annotations

import contextlib
import itertools
import json
import os
import re
import struct
import sys
import zlib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..robot_runtime import MAX_Q, is_number, nonfinite_item
from . import table_journal
from .dyna_model import SECTION, Model
from .errors import FileError, QTableError, located, shown
from .files import (
    atomic_link,
    atomic_write,
    check_writable,
    file_error,
    fsync_dir,
    identity,
    read_bytes,
    remove_stale_temps,
    staged_write,
)
from .keyword import (
    MAX_ACTIONS,
    MAX_KEYWORD_BITS,
    MAX_LEVELS,
    KeywordLayout,
    base_layout,
    own_tables,
    robot_offset,
    table_robots,
)
from .locks import FileLock

MAGIC = b"KOOLIOQT"
FORMAT_VERSION = 1
#: Largest table file read (the paper's whole dense table would be 114 MiB).
MAX_TABLE_BYTES = 1 << 30


@dataclass
class QTable:
    """A sparse Q-table: a row of ``n_actions`` values per visited state key.

    >>> t = QTable(KeywordLayout((("A", 3), ("B", 4))))
    >>> t.row(5)[3] = 1.5
    >>> t.get(5, 3), t.get(6, 3), len(t)
    (1.5, 0.0, 1)
    """

    layout: KeywordLayout
    meta: dict[str, Any] = field(default_factory=dict)
    q_init: float = 0.0
    rows: dict[int, list[float]] = field(default_factory=dict)
    sections: dict[str, Any] = field(default_factory=dict)
    """Named data saved after the values: ``bytes``, or an object ``bytes()`` accepts
    (``__bytes__``), serialized at every save. Read back as ``bytes``, but for Dyna-Q's
    model (``dyna_model``): parsed and checked once, when the table is read, and kept as
    the :class:`~koolio_pymunk.store.dyna_model.Model` the learner goes on recording
    into."""

    def __len__(self) -> int:
        return len(self.rows)

    def row(self, key: int) -> list[float]:
        """The (mutable) row of ``key``, created at ``q_init`` when missing."""
        r = self.rows.get(key)
        if r is None:
            r = [self.q_init] * self.layout.n_actions
            self.rows[key] = r
        return r

    def peek(self, key: int) -> list[float] | None:
        """The row of ``key`` if visited, without creating it."""
        return self.rows.get(key)

    def get(self, key: int, action: int) -> float:
        """Q of ``(key, action)``; ``q_init`` for a state never visited (none created)."""
        r = self.rows.get(key)
        return self.q_init if r is None else r[action]

    @property
    def entries(self) -> int:
        return len(self.rows) * self.layout.n_actions

    def nbytes(self) -> int:
        """Bytes of this table in its file (keys + values)."""
        return len(self.rows) * (8 + 8 * self.layout.n_actions)

    def copy(self) -> QTable:
        """A deep copy: rows, header and sections are this table's no longer."""
        return QTable(
            self.layout,
            dict(self.meta),
            self.q_init,
            {k: list(v) for k, v in self.rows.items()},
            {k: _section_copy(k, v) for k, v in self.sections.items()},
        )

    def robot_table(self, robot: int) -> QTable:
        """Robot ``robot``'s own rows of a table that holds each robot's (``train --tables
        each``), as a table of one robot (the keyword without the robot field; its header
        this table's, with ``robot``: ``{"index", "of"}``; Dyna-Q's model, the pairs of
        the robot's own states). ``ValueError`` when the table holds no such robot's rows.

        >>> from koolio_pymunk.store.keyword import own_tables
        >>> t = QTable(own_tables(KeywordLayout((("A", 3),)), 2))
        >>> t.row(0b1_10)[1] = 2.5
        >>> one = t.robot_table(1)
        >>> one.layout.fields, one.rows, one.meta["robot"]
        ((('A', 3),), {2: [0.0, 2.5, 0.0, 0.0, 0.0]}, {'index': 1, 'of': 2})
        """
        own = table_robots(self.layout)
        if not 0 <= robot < own:
            held = f"the rows of robots 0..{own - 1}" if own else "no robot's own rows"
            raise ValueError(f"no robot {robot}'s own rows: the table holds {held}")
        model = self._model_by_robot()
        base = base_layout(self.layout)
        low = robot_offset(self.layout, 1) - 1
        mine = robot_offset(self.layout, robot)
        rows = {k & low: list(v) for k, v in self.rows.items() if k & ~low == mine}
        meta = dict(self.meta) | {"robot": {"index": robot, "of": own}}
        sections = {}
        if model is not None:  # a robot's transitions stay among its own states
            its = Model()
            for (state, action), outs in zip(model.pairs, model.outcomes):
                if state & ~low == mine:
                    its.add(state & low, action, [[o[0] & low, *o[1:]] for o in outs])
            sections[SECTION] = its
        return QTable(base, meta, self.q_init, rows, sections)

    def for_robots(self, robots: int) -> QTable:
        """This table as ``robots`` robots' own rows (``train --tables each --init-qtable``:
        every robot starts from these values): each row copied to every robot's rows, the
        header this table's (without a ``robot`` record), Dyna-Q's model copied to each
        robot's states. The inverse of :meth:`robot_table` for every robot. ``ValueError``
        when the table already holds robots' own rows, or the keyword would pass 64 bits.

        >>> t = QTable(KeywordLayout((("A", 3),)))
        >>> t.row(2)[1] = 2.5
        >>> both = t.for_robots(2)
        >>> both.layout.fields, sorted(both.rows), both.robot_table(1).rows == t.rows
        ((('Robot', 2), ('A', 3)), [2, 6], True)
        """
        if table_robots(self.layout):
            raise ValueError("the table holds robots' own rows already")
        model = self._model_by_robot()
        layout = own_tables(self.layout, robots)
        offsets = [robot_offset(layout, k) for k in range(robots)]
        rows = {k | off: list(v) for off in offsets for k, v in self.rows.items()}
        meta = {k: v for k, v in self.meta.items() if k != "robot"}
        sections = {}
        if model is not None:  # each robot's transitions among its own states
            theirs = Model()
            for off in offsets:
                for (state, action), outs in zip(model.pairs, model.outcomes):
                    theirs.add(state | off, action, [[o[0] | off, *o[1:]] for o in outs])
            sections[SECTION] = theirs
        return QTable(layout, meta, self.q_init, rows, sections)

    def _model_by_robot(self) -> Model | None:
        """Dyna-Q's model, for :meth:`robot_table` and :meth:`for_robots` to split or join
        by robot (None: the table has none; read, not parsed again, when the table was
        read); ``ValueError`` for any other data section, which neither can split."""
        others = sorted(set(self.sections) - {SECTION})
        if others:
            raise ValueError(f"data sections ({', '.join(others)}) are not split by robot")
        found = self.sections.get(SECTION)
        if found is None or isinstance(found, Model):
            return found
        return Model.from_bytes(bytes(found))  # bytes put in by hand

    # -- bytes ----------------------------------------------------------------------
    def to_bytes(self) -> bytes:
        """The ``.qtable`` file's bytes (:meth:`from_bytes` reads them back exactly)."""
        header = dict(self.meta)
        header.update(format=FORMAT_VERSION, layout=self.layout.header_json(), q_init=self.q_init)
        blobs = [(name, bytes(self.sections[name])) for name in sorted(self.sections)]
        if blobs:
            header["sections"] = [[name, len(blob)] for name, blob in blobs]
        hjson = json.dumps(header, sort_keys=True, separators=(",", ":")).encode()
        keys, values = self._arrays()
        body = b"".join(
            [
                MAGIC,
                struct.pack("<I", len(hjson)),
                hjson,
                struct.pack("<Q", len(keys)),
                keys.tobytes(),
                values.tobytes(),
                *(blob for _, blob in blobs),
            ]
        )
        return body + struct.pack("<I", zlib.crc32(body))

    def _arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """The state keys ascending and their rows, as the file holds them (read from the
        dict in one pass each, then put in key order)."""
        n, na = len(self.rows), self.layout.n_actions
        keys = np.fromiter(self.rows, dtype="<u8", count=n)
        flat = itertools.chain.from_iterable(self.rows.values())
        values = np.fromiter(flat, dtype="<f8", count=n * na).reshape(n, na)
        order = np.argsort(keys)
        return keys[order], values[order]

    @classmethod
    def from_bytes(cls, data: bytes, source: str = "<bytes>") -> QTable:
        """Parse and check a table file's bytes; :class:`QTableError` (one line) if bad."""

        def bad(problem: str, item: str = "") -> QTableError:
            return QTableError(located(source, item, problem))

        if len(data) < len(MAGIC) + 4 + 8 + 4 or data[: len(MAGIC)] != MAGIC:
            raise bad("not a koolio-pymunk Q-table file (bad magic or too short)")
        (crc,) = struct.unpack("<I", data[-4:])
        if zlib.crc32(data[:-4]) != crc:
            raise bad("corrupt or truncated (checksum mismatch)")
        pos = len(MAGIC)
        (hlen,) = struct.unpack_from("<I", data, pos)
        pos += 4
        if pos + hlen + 8 > len(data) - 4:
            raise bad("corrupt (header length beyond the end of the file)")
        try:
            header = json.loads(data[pos : pos + hlen], parse_constant=_no_constant)
        except (ValueError, RecursionError) as exc:
            raise bad(f"unreadable header ({_short(exc)})") from None
        layout, q_init = check_header(header, source)
        listed = header.pop("sections", [])
        if not isinstance(listed, list) or not all(
            isinstance(x, list) and len(x) == 2 and isinstance(x[0], str) and _count(x[1])
            for x in listed
        ):
            raise bad("must be [[name, length], ...]", "header.sections")
        pos += hlen
        (n,) = struct.unpack_from("<Q", data, pos)
        pos += 8
        na = layout.n_actions
        extra = sum(length for _, length in listed)
        if len(data) - 4 - pos != n * 8 * (1 + na) + extra:
            raise bad("corrupt or truncated (length does not match the row count)")
        keys = np.frombuffer(data, dtype="<u8", count=n, offset=pos)
        values = np.frombuffer(data, dtype="<f8", count=n * na, offset=pos + 8 * n)
        check_rows(keys, values, layout, source)
        rows = {int(k): values[i * na : (i + 1) * na].tolist() for i, k in enumerate(keys)}
        pos += n * 8 * (1 + na)
        sections = {}
        for name, length in listed:
            if name in sections:
                raise bad(f"section {name!r} listed twice", "header.sections")
            sections[name] = data[pos : pos + length]
            pos += length
        if SECTION in sections:  # refused with the table, before a run writes anything
            sections[SECTION] = Model.from_bytes(sections[SECTION], source, layout)
        return cls(layout, header, q_init, rows, sections)


def _section_copy(name: str, value: Any) -> Any:
    """A section of a copied table: Dyna-Q's model a model of its own, the others bytes."""
    if name == SECTION:
        return Model.from_bytes(bytes(value))
    return bytes(value)


def _count(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool) and v >= 0


def _no_constant(name: str) -> float:
    raise ValueError(f"{name} is not a number")


def _short(exc: BaseException, limit: int = 80) -> str:
    text = str(exc).replace("\n", " ") or type(exc).__name__
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


#: Header keys of what a table records of its run besides the arena, the sensors and the
#: algorithm (only when not the defaults; :mod:`~koolio_pymunk.store.run_identity`).
RECORD_KEYS = ("goal", "world")
_RUN_ID = re.compile(r"[0-9a-f]{16}")


def check_header(header: Any, source: str) -> tuple[KeywordLayout, float]:
    """Check every field of a table file's JSON header; pops ``format``, ``layout`` and
    ``q_init`` (the rest is the table's ``meta``). Returns the layout and ``q_init``."""

    def bad(item: str, problem: str) -> QTableError:
        return QTableError(located(source, f"header.{item}", problem))

    if not isinstance(header, dict):
        raise QTableError(located(source, "header", "not a JSON object"))
    if header.pop("format", None) != FORMAT_VERSION:
        raise QTableError(
            located(source, "", f"unsupported format version (this program reads {FORMAT_VERSION})")
        )
    layout = _check_layout(header.pop("layout", None), source)
    q_init = header.pop("q_init", 0.0)
    if not is_number(q_init) or abs(q_init) > MAX_Q:
        raise bad("q_init", f"must be a finite number within +-{MAX_Q:g}, got {shown(q_init)}")
    episodes = header.get("episodes", 0)
    if not _is_int(episodes) or episodes < 0:
        raise bad("episodes", f"must be an integer >= 0, got {shown(episodes)}")
    sensors = header.get("sensors", {})
    if not isinstance(sensors, dict):
        raise bad("sensors", f"must be a mapping, got {shown(sensors)}")
    arena = header.get("arena")
    if arena is not None and not (
        isinstance(arena, dict)
        and isinstance(arena.get("name"), str)
        and isinstance(arena.get("sha256"), str)
    ):
        raise bad("arena", f"must be {{name, sha256}}, got {shown(arena)}")
    for key in RECORD_KEYS:
        value = header.get(key)
        if value is not None and not (isinstance(value, str) and value):
            raise bad(key, f"must be a non-empty string, got {shown(value)}")
    run_id = header.get("run_id")
    if run_id is not None and not (isinstance(run_id, str) and _RUN_ID.fullmatch(run_id)):
        raise bad("run_id", f"must be 16 hexadecimal digits, got {shown(run_id)}")
    if not isinstance(header.get("provenance", {}), dict):
        raise bad("provenance", f"must be a mapping, got {shown(header['provenance'])}")
    item = nonfinite_item(header)
    if item is not None:  # 1e400 reads as infinity, which the next save writes as Infinity
        raise bad(item, "not a finite number (the table could not be saved again)")
    return layout, float(q_init)


def _check_layout(data: Any, source: str) -> KeywordLayout:
    def bad(item: str, problem: str) -> QTableError:
        return QTableError(located(source, f"header.layout{item}", problem))

    if not isinstance(data, dict):
        raise bad("", f"must be a mapping, got {shown(data)}")
    fields = data.get("fields")
    if not isinstance(fields, list) or not fields:
        raise bad(".fields", "must be a non-empty list of [name, levels]")
    out = []
    for i, f in enumerate(fields):
        ok = isinstance(f, list) and len(f) == 2 and isinstance(f[0], str) and _is_int(f[1])
        if not ok or not 1 <= f[1] <= MAX_LEVELS:
            raise bad(f".fields[{i}]", f"must be [name, levels 1..{MAX_LEVELS}], got {shown(f)}")
        out.append((f[0], f[1]))
    na = data.get("n_actions")
    if not _is_int(na) or not 1 <= na <= MAX_ACTIONS:
        raise bad(".n_actions", f"must be an integer 1..{MAX_ACTIONS}, got {shown(na)}")
    layout = KeywordLayout(tuple(out), na)
    if "action_bits" in data and data["action_bits"] != layout.action_bits:
        raise bad(".action_bits", f"{shown(data['action_bits'])}, expected {layout.action_bits}")
    if layout.total_bits > MAX_KEYWORD_BITS:
        raise bad("", f"a {layout.total_bits}-bit keyword does not fit {MAX_KEYWORD_BITS} bits")
    return layout


def check_rows(keys: np.ndarray, values: np.ndarray, layout: KeywordLayout, source: str) -> None:
    """Refuse rows that are not rows of ``layout``'s table, in one line naming
    ``source``: state keys ascending and within the layout's bits and levels, every Q
    value finite and within bounds."""
    if len(keys) == 0:
        return
    if len(keys) > 1 and not bool(np.all(keys[1:] > keys[:-1])):
        raise QTableError(located(source, "rows", "state keys not in ascending order"))
    state_bits = layout.total_bits - layout.action_bits
    if state_bits < 64 and int(keys[-1]) >> state_bits:
        raise QTableError(
            located(source, "rows", f"state key {int(keys[-1])} beyond the {state_bits}-bit layout")
        )
    _check_codes(keys, layout, source)
    if not bool(np.all(np.isfinite(values))):
        raise QTableError(located(source, "rows", "a Q value is not a finite number"))
    if len(values) and float(np.max(np.abs(values))) > MAX_Q:
        raise QTableError(
            located(source, "rows", f"a Q value is beyond +-{MAX_Q:g} (an update would overflow)")
        )


def _check_codes(keys: np.ndarray, layout: KeywordLayout, source: str) -> None:
    """Every field's code of every state key below its levels (as the robot runtime's
    :func:`~koolio_pymunk.robot_runtime.state_problem` checks one key)."""
    for (name, levels), bits, shift in zip(layout.fields, layout.bits, layout.shifts):
        codes = (keys >> np.uint64(shift - layout.action_bits)) & np.uint64((1 << bits) - 1)
        over = np.flatnonzero(codes >= np.uint64(levels))
        if len(over):
            key = int(keys[over[0]])
            raise QTableError(
                located(
                    source,
                    "rows",
                    f"state key {key}: code {int(codes[over[0]])} of {name} beyond its "
                    f"{levels} levels",
                )
            )


def backup_path(path: Path) -> Path:
    """The backup beside a table: ``X.qtable`` -> ``X.qtable.bak``."""
    return path.with_name(path.name + ".bak")


class QTableStore:
    """A Q-table file, its backup (``<file>.bak``) and its journal (``<file>.journal``).

    :meth:`load` locks the table (one writer at a time) and reads it, or makes a new
    empty one without writing (:attr:`fresh`); :meth:`create` writes a new table's files;
    :meth:`save` writes the whole table (a *snapshot*), :meth:`append`
    adds the rows one episode changed to the journal
    (:mod:`~koolio_pymunk.store.table_journal`); :meth:`close` releases the lock.
    A caller checks what must be checked before any file is written (the training log)
    between the two.

    **The two ways of keeping a table** (``fsync``; ``koolio-pm train --fsync``,
    docs/robustness.md). Every snapshot is written, fsynced (its folder too) and put in
    place atomically, and the previous good table becomes the backup; the table file is
    never replaced otherwise. ``episode`` (the paper's rule): every save is a snapshot.
    ``second``: the caller (``RunFiles``) asks for a snapshot at most once a second, at
    the end, on Ctrl-C and SIGTERM; the episodes between two snapshots go to the journal
    (:meth:`append`: written, not fsynced). A killed process loses no finished episode
    either way; a power loss at most the last second, and the table still loads.
    """

    def __init__(
        self, path: str | Path, warn=None, purpose: str = "koolio-pm", fsync: str = "episode"
    ) -> None:
        if fsync not in FSYNC_MODES:
            raise ValueError(f"fsync: one of {', '.join(FSYNC_MODES)}, got {fsync!r}")
        self.path = Path(path)
        self.backup = backup_path(self.path)
        self.journal = table_journal.journal_path(self.path)
        self.fsync = fsync
        """``episode`` or ``second`` (class doc)."""
        self.warn = warn or (lambda msg: print(f"warning: {msg}", file=sys.stderr))
        """Where the store's warnings go (a torn table, a table learned elsewhere)."""
        self._last: bytes | None = None
        """The bytes of the table file as last read or written (its snapshot)."""
        self._written: tuple[int, int, int, int] | None = None
        """:func:`~koolio_pymunk.store.files.identity` of the table file this store wrote
        last (None: none yet)."""
        self._journal_fd: int | None = None
        self._lock = FileLock(self.path, purpose)
        self.fresh = False
        """True when :meth:`load` found no table (a new one starts at episode 0)."""
        self.created = False
        """True from :meth:`create` (a new table, or one started from another with
        ``--init-qtable``) to :meth:`close`: the run holding the lock made it, so its log
        must be new too."""

    @property
    def locked(self) -> bool:
        """This store holds its table's lock (from :meth:`lock` to :meth:`close`)."""
        return self._lock.held

    def lock(self) -> None:
        """Take the table's lock (:class:`~koolio_pymunk.store.errors.InUseError` if another
        process writes it) and remove what interrupted writes of it left behind."""
        if self._lock.held:
            return
        self._lock.acquire()
        for p in (self.path, self.backup, self.journal):
            remove_stale_temps(p, owned=True)

    def load(
        self, new: Callable[[], QTable], check: Callable[[QTable], object] | None = None
    ) -> QTable:
        """Lock and read the table, judged by ``check`` (which raises to refuse it: a run's
        :func:`~koolio_pymunk.store.run_identity.check`), or make a new empty one,
        ``new()``, without writing it (``fresh``). On any error the lock is released
        again."""
        self.lock()
        try:
            for later in (self.backup, self.journal):  # written later: refused now
                check_writable(later)
            table = self._load_existing()
            self.fresh = table is None
            if table is None:
                return new()
            if check is not None:
                check(table)
        except BaseException:
            self.close()
            raise
        return table

    def peek(self, warn: bool = False) -> QTable | None:
        """The table :meth:`load` would read (the backup when the file is torn), read
        without the lock and without writing; None when there is none yet. A reader
        (``eval``) or a check before the lock is taken. Warns of a fallback to the
        backup only with ``warn``; an unusable table raises as in :meth:`load`."""
        saved, last, written = self.warn, self._last, self._written
        if not warn:
            self.warn = lambda msg: None
        try:
            return self._load_existing()
        finally:
            self.warn, self._last, self._written = saved, last, written

    def exists(self) -> bool:
        """True when the table file or its backup exists (a run would resume it)."""
        return self.path.exists() or self.backup.exists()

    def create(self, table: QTable) -> None:
        """Write a new table to the file and the backup (durably, in either mode)."""
        self.lock()
        self._close_journal()
        self._last = table.to_bytes()
        with staged_write(self.path, self._last) as written:
            pass
        self._written = identity(written)
        self._keep_backup()
        self._drop_journal()
        fsync_dir(self.path.parent)
        self.fresh = False
        self.created = True

    def save(self, table: QTable) -> None:
        """Write ``table`` whole (a snapshot), durably (the file and its folder fsynced):
        the previous good table becomes the backup once the new one is on disk, before it
        replaces the file (:meth:`_keep_backup`); the journal is then removed."""
        self.lock()
        data = table.to_bytes()
        self._close_journal()
        with staged_write(self.path, data) as written:
            if self._last is not None and self._last != data:
                self._keep_backup()
        self._written = identity(written)
        self._last = data
        self._drop_journal()
        fsync_dir(self.path.parent)

    def append(
        self, table: QTable, keys: np.ndarray | None = None, values: np.ndarray | None = None
    ) -> None:
        """Add a journal record (``second`` mode, between two snapshots): rows ``keys``
        hold ``values`` (the rows an episode changed) and the table
        ``table.meta["episodes"]`` episodes; without ``keys``, the whole table (a learner
        whose changes are not tracked, a table with data sections). Written, not fsynced:
        a killed process loses nothing (:mod:`~koolio_pymunk.store.table_journal`).
        The table file must hold the snapshot the journal continues (a :meth:`save` or a
        :meth:`load` since)."""
        self.lock()
        if self._last is None:
            raise ValueError("append: no snapshot yet (save or load the table first)")
        if keys is None:
            rec = table_journal.whole_record(table.to_bytes())
        else:
            rec = table_journal.record(int(table.meta.get("episodes", 0)), keys, values)
        try:
            if self._journal_fd is None:
                self._journal_fd = self._open_journal()
            os.write(self._journal_fd, rec)
        except OSError as exc:
            self._close_journal()
            raise file_error(self.journal, "write", exc) from None

    def _open_journal(self) -> int:
        """The journal opened for appending: the one on disk when it continues the table
        file (cut back to its whole records), else a new one."""
        head = table_journal.header(self._last)  # type: ignore[arg-type]
        try:
            data = self.journal.read_bytes()
        except OSError:
            data = b""
        if table_journal.continues(data, self._last):  # type: ignore[arg-type]
            fd = os.open(self.journal, os.O_WRONLY)
            os.ftruncate(fd, table_journal.good_length(data))
            os.lseek(fd, 0, os.SEEK_END)
            return fd
        atomic_write(self.journal, head)
        fd = os.open(self.journal, os.O_WRONLY)
        os.lseek(fd, 0, os.SEEK_END)
        return fd

    def _close_journal(self) -> None:
        if self._journal_fd is not None:
            with contextlib.suppress(OSError):
                os.close(self._journal_fd)
            self._journal_fd = None

    def _drop_journal(self) -> None:
        """Remove the journal: the table file holds everything now."""
        try:
            os.unlink(self.journal)
        except FileNotFoundError:
            pass
        except OSError as exc:
            raise file_error(self.journal, "remove", exc) from None

    def _keep_backup(self) -> None:
        """Make the backup hold the previous good table (``_last``): the table file itself
        given the backup's name (a hard link: no second write, no second fsync) when it is
        the file this store wrote, unchanged since; its bytes written otherwise (a table
        read from disk, a torn one replaced by its backup, a file system without links)."""
        try:
            same = identity(os.lstat(self.path)) == self._written
        except OSError:
            same = False
        if not (same and atomic_link(self.path, self.backup)):
            atomic_write(self.backup, self._last)

    def close(self) -> None:
        """Release the lock (the files stay as last saved). The session that created the
        table ends here: opened again, it is a table to resume like any other."""
        self._close_journal()
        self._lock.release()
        self.created = False

    def __enter__(self) -> QTableStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _load_existing(self) -> QTable | None:
        main_err: QTableError | None = None
        if self.path.exists():
            try:
                data = _read_table(self.path)
            except FileError as exc:  # unreadable: refused, never replaced by the backup
                raise FileError(
                    f"{exc} (fix it and run again; its backup is not used in its place)"
                ) from None
            try:
                table = QTable.from_bytes(data, str(self.path))
                self._last = data
            except QTableError as exc:
                main_err = exc
            else:
                with_journal(table, data, self.journal, self.warn)
                return table
        if self.backup.exists():
            try:
                data = _read_table(self.backup)
                table = QTable.from_bytes(data, str(self.backup))
            except (QTableError, FileError) as exc:
                why = str(exc)
                if main_err is not None:
                    raise QTableError(f"{main_err}; backup unusable too: {why}") from None
                raise QTableError(
                    located(str(self.path), "", f"missing, and its backup is unusable: {why}")
                ) from None
            why = main_err if main_err is not None else f"{self.path}: missing"
            self.warn(f"{why}; using the backup {self.backup}")
            self._last, self._written = data, None  # the file does not hold _last
            return table
        if main_err is not None:
            raise main_err
        return None


#: ``QTableStore``'s ways of keeping a table (its class doc).
FSYNC_MODES = ("episode", "second")


def with_journal(table: QTable, data: bytes, path: Path, warn=None) -> QTable:
    """``table`` (read from the snapshot ``data``) with the journal at ``path`` replayed
    (:mod:`~koolio_pymunk.store.table_journal`); a journal cut short is used up to its
    last whole record, with a warning."""
    try:
        journal = read_bytes(path, MAX_TABLE_BYTES, "journal")
    except FileError:
        if path.exists():
            raise
        return table
    found = table_journal.records(journal, data, table.layout.n_actions, str(path))
    for k, rec in enumerate(found.records, start=1):
        where = f"{path}: record {k}"
        if rec[0] == table_journal.WHOLE:
            whole = QTable.from_bytes(rec[1], where)
            if whole.layout != table.layout:
                raise QTableError(located(str(path), f"record {k}", "a table of another layout"))
            table.meta, table.rows, table.sections = whole.meta, whole.rows, whole.sections
            continue
        _, episodes, keys, values = rec
        check_rows(keys, values.reshape(-1), table.layout, where)
        rows = table.rows
        for key, row in zip(keys.tolist(), values.tolist()):
            rows[key] = row
        table.meta["episodes"] = episodes
    if found.torn and warn is not None:
        warn(
            f"{path}: its last record is cut short (a run killed while writing it, or a "
            f"power loss): the {len(found.records)} records before it are used"
        )
    return table


def _read_table(path: Path) -> bytes:
    """A table file's bytes (a regular file of at most :data:`MAX_TABLE_BYTES`; a FIFO
    or a device is refused before it is opened for reading:
    :func:`~koolio_pymunk.store.files.read_bytes`)."""
    return read_bytes(path, MAX_TABLE_BYTES, "Q-table file")


def load_qtable(path: str | Path) -> QTable:
    """Read a table file and its journal (no backup fallback); QTableError when missing
    or bad."""
    p = Path(path)
    try:
        data = _read_table(p)
    except FileError as exc:
        raise QTableError(str(exc)) from None
    try:
        return with_journal(QTable.from_bytes(data, str(p)), data, table_journal.journal_path(p))
    except FileError as exc:
        raise QTableError(str(exc)) from None


def human_bytes(n: float) -> str:
    """``1.5 KiB``-style size with one decimal (binary units, as the paper).

    >>> human_bytes(119439360), human_bytes(256000000000)
    ('113.9 MiB', '238.4 GiB')
    """
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if n < 1024 or unit == "TiB":
            return f"{n:.1f} {unit}" if unit != "B" else f"{int(n)} B"
        n /= 1024
    raise AssertionError("unreachable")
