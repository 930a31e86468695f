"""A Q-table's journal: the episodes learned since its file was last written whole.

Writing the whole table at every episode end costs more than the episode (a table of
7,500 states is 360 KB, 1.4 ms to lay out), and an fsync at every episode end costs more
again. With ``--fsync second`` (the default; :class:`~koolio_pymunk.store.qtable.QTableStore`)
a run writes the table file (the *snapshot*) at most once a second, durably (fsynced,
its folder too; the previous snapshot becomes the backup), and at every other episode
end appends to ``X.qtable.journal`` the rows the episode changed (written, not fsynced:
a killed process loses nothing, the operating system has the bytes); a learner whose
changes are not tracked (the Python loop) or a table with data sections (Dyna-Q's model)
appends the whole table instead. A reader takes the snapshot and replays the journal.
What each failure loses (docs/robustness.md): a killed process, nothing finished; a power
loss, at most the last second (the journal's unflushed tail; the snapshot is durable and
loads, and the table file is only ever replaced durably).

**Format** (little-endian)::

    b"KOOLIOQJ"            8 bytes magic
    uint32 version          1
    uint32 base_crc         the snapshot's own CRC (its last 4 bytes) ...
    uint64 base_length      ... and length: the journal continues that snapshot only
    records, each:
      uint32 body_length
      body:  uint32 kind, then
             kind 1 (rows):  uint64 episodes, uint64 n, uint64 key[n], float64 q[n][n_actions]
             kind 2 (whole): a whole .qtable file
      uint32 crc32          of body_length and body

A rows record sets the ``n`` rows (in key order) to those values and the table's episode
count to ``episodes``; a whole record replaces the table. Replay stops at the first record
that is cut short or fails its CRC (a process killed in the middle of an append, or a
power loss): every record before it is applied. A journal of another snapshot (a crash
between a snapshot and the journal's removal) is ignored: the snapshot already holds it.
A record whose CRC holds but whose rows are not the table's (a key beyond the layout, a
value that is not finite) is refused like a bad table.

>>> base = b"a snapshot's bytes, its CRC last"
>>> data = header(base) + record(3, np.array([5]), np.array([[1.0, 2.0, 3.0, 4.0, 5.0]]))
>>> found = records(data + b"torn", base, 5, "t.qtable.journal")
>>> [(kind, e, k.tolist(), v.tolist()) for kind, e, k, v in found.records], found.torn
([(1, 3, [5], [[1.0, 2.0, 3.0, 4.0, 5.0]])], True)
>>> records(data, b"another snapshot", 5, "t.qtable.journal").records
[]
"""

from __future__ import annotations

import struct
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import QTableError, located

MAGIC = b"KOOLIOQJ"
VERSION = 1
HEADER = struct.Struct("<8sIIQ")
_LEN = struct.Struct("<I")
_COUNTS = struct.Struct("<QQ")
#: Record kinds: rows changed, a whole table.
ROWS, WHOLE = 1, 2


def journal_path(table: str | Path) -> Path:
    """The journal beside a table: ``X.qtable`` -> ``X.qtable.journal``."""
    p = Path(table)
    return p.with_name(p.name + ".journal")


def header(base: bytes) -> bytes:
    """A journal's header for the snapshot whose bytes are ``base``."""
    crc = struct.unpack("<I", base[-4:])[0]
    return HEADER.pack(MAGIC, VERSION, crc, len(base))


def record(episodes: int, keys: np.ndarray, values: np.ndarray) -> bytes:
    """One record: rows ``keys`` now hold ``values``; the table holds ``episodes``
    (the rows are written in key order, as the table file holds them)."""
    order = np.argsort(keys)
    return _framed(
        _LEN.pack(ROWS),
        _COUNTS.pack(int(episodes), len(keys)),
        np.ascontiguousarray(keys[order], dtype="<u8").tobytes(),
        np.ascontiguousarray(values[order], dtype="<f8").tobytes(),
    )


def whole_record(table_bytes: bytes) -> bytes:
    """One record holding a whole table file's bytes."""
    return _framed(_LEN.pack(WHOLE), table_bytes)


def _framed(*parts: bytes) -> bytes:
    body = b"".join(parts)
    head = _LEN.pack(len(body))
    return head + body + _LEN.pack(zlib.crc32(head + body))


@dataclass
class Replay:
    """A journal's whole records (:func:`records`)."""

    records: list[tuple]
    """In order: ``(ROWS, episodes, keys, values)`` or ``(WHOLE, table bytes)``."""
    torn: bool
    """A record was cut short or failed its CRC (it and what follows are not taken)."""


def continues(data: bytes, base: bytes) -> bool:
    """Does the journal ``data`` continue the snapshot ``base``?"""
    return len(data) >= HEADER.size and data[: HEADER.size] == header(base)


def good_length(data: bytes) -> int:
    """The length of ``data``'s header and whole records (where an append must start)."""
    return _scan(data)[1]


def _scan(data: bytes) -> tuple[list[tuple[int, int]], int, bool]:
    """The whole records' bodies ``(start, end)``, the good length, and whether a torn
    record follows them."""
    pos, out = HEADER.size, []
    while pos < len(data):
        if pos + _LEN.size > len(data):
            return out, pos, True
        (n,) = _LEN.unpack_from(data, pos)
        end = pos + _LEN.size + n + _LEN.size
        if n < _LEN.size or end > len(data):
            return out, pos, True
        (crc,) = _LEN.unpack_from(data, end - _LEN.size)
        if zlib.crc32(data[pos : end - _LEN.size]) != crc:
            return out, pos, True
        out.append((pos + _LEN.size, end - _LEN.size))
        pos = end
    return out, pos, False


def records(data: bytes, base: bytes, n_actions: int, source: str) -> Replay:
    """The journal ``data``'s whole records (module doc), for the snapshot ``base``: none
    for a journal of another snapshot. One-line :class:`QTableError` for a whole record
    that is not a record of such a table (a whole table's bytes are checked by its
    reader)."""
    if not continues(data, base):
        return Replay([], False)
    found, _, torn = _scan(data)
    out: list[tuple] = []
    episodes = -1
    for k, (start, end) in enumerate(found, start=1):
        where = f"record {k}"
        (kind,) = _LEN.unpack_from(data, start)
        start += _LEN.size
        if kind == WHOLE:
            out.append((WHOLE, data[start:end]))
            episodes = -1
            continue
        if kind != ROWS or end - start < _COUNTS.size:
            raise QTableError(located(source, where, f"unknown record kind {kind}"))
        count, n = _COUNTS.unpack_from(data, start)
        if end - start != _COUNTS.size + n * 8 * (1 + n_actions):
            raise QTableError(located(source, where, "length does not match its row count"))
        if count < episodes:
            raise QTableError(located(source, where, f"episodes {count} after {episodes}"))
        keys = np.frombuffer(data, "<u8", n, start + _COUNTS.size)
        values = np.frombuffer(data, "<f8", n * n_actions, start + _COUNTS.size + 8 * n)
        out.append((ROWS, count, keys, values.reshape(n, n_actions)))
        episodes = count
    return Replay(out, torn)
