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
                                     sensors (the sensor configuration), episodes, ...
    uint64 n_rows
    uint64 state_key[n_rows]         ascending
    float64 q[n_rows][n_actions]
    bytes   section[...]             only when the header lists ``sections``
    uint32 crc32                     of every byte before it

A table learned with an algorithm other than one-step Q records it in the header
(``algorithm``: its name and parameters) and may carry data sections after the values,
listed in the header as ``sections: [[name, length], ...]`` (e.g. the Dyna-Q model,
:mod:`koolio_pymunk.dyna`), covered by the CRC like the rest. A one-step Q table has
neither key, so its bytes are those of a table written before they existed.

The paper keeps a table file and a backup file, both created empty when missing, read at
start and written at the end of every episode. :class:`QTableStore` writes each one
atomically (temporary file, flush, fsync, rename) and keeps the previous good table in
the backup, so a crash at any moment leaves a loadable table.
"""

from __future__ import annotations

import json
import math
import struct
import sys
import zlib
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .errors import QTableError, located
from .files import atomic_write

MAGIC = b"KOOLIOQT"
FORMAT_VERSION = 1
N_ACTIONS = 5


@dataclass(frozen=True)
class KeywordLayout:
    """Bit layout of the keyword: state fields (name, levels), most significant first."""

    fields: tuple[tuple[str, int], ...]
    n_actions: int = N_ACTIONS

    @property
    def bits(self) -> tuple[int, ...]:
        return tuple(max(1, math.ceil(math.log2(levels))) for _, levels in self.fields)

    @property
    def action_bits(self) -> int:
        return max(1, math.ceil(math.log2(self.n_actions)))

    @property
    def shifts(self) -> tuple[int, ...]:
        """Shift of each field within the keyword (Table 12's ``<<`` numbers)."""
        out, pos = [], self.action_bits
        for b in reversed(self.bits):
            out.append(pos)
            pos += b
        return tuple(reversed(out))

    @property
    def total_bits(self) -> int:
        return sum(self.bits) + self.action_bits

    @property
    def n_states(self) -> int:
        return math.prod(levels for _, levels in self.fields)

    @property
    def n_entries(self) -> int:
        return self.n_states * self.n_actions

    def dense_bytes(self, value_bytes: int = 8) -> int:
        """Bytes of a dense table of doubles (paper: 113.9 MiB)."""
        return self.n_entries * value_bytes

    def state_key(self, codes: Sequence[int]) -> int:
        key = 0
        for code, b in zip(codes, self.bits):
            key = (key << b) | code
        return key

    def keyword(self, codes: Sequence[int], action: int) -> int:
        """The Table 12 keyword of ``codes`` and ``action``."""
        return (self.state_key(codes) << self.action_bits) | action

    def decode(self, keyword: int) -> tuple[tuple[int, ...], int]:
        """``(codes, action)`` of a keyword."""
        action = keyword & ((1 << self.action_bits) - 1)
        key = keyword >> self.action_bits
        codes = []
        for b in reversed(self.bits):
            codes.append(key & ((1 << b) - 1))
            key >>= b
        return tuple(reversed(codes)), action

    def to_json(self) -> dict[str, Any]:
        return {
            "fields": [[n, lv] for n, lv in self.fields],
            "action_bits": self.action_bits,
            "n_actions": self.n_actions,
        }

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> KeywordLayout:
        return cls(tuple((str(n), int(lv)) for n, lv in data["fields"]), int(data["n_actions"]))


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
    (``__bytes__``), serialized at every save. Read back as ``bytes``."""

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
        r = self.rows.get(key)
        return self.q_init if r is None else r[action]

    @property
    def entries(self) -> int:
        return len(self.rows) * self.layout.n_actions

    def nbytes(self) -> int:
        """Bytes of this table in its file (keys + values)."""
        return len(self.rows) * (8 + 8 * self.layout.n_actions)

    def copy(self) -> QTable:
        return QTable(
            self.layout,
            dict(self.meta),
            self.q_init,
            {k: list(v) for k, v in self.rows.items()},
            {k: bytes(v) for k, v in self.sections.items()},
        )

    # -- bytes ----------------------------------------------------------------------
    def to_bytes(self) -> bytes:
        header = dict(self.meta)
        header.update(format=FORMAT_VERSION, layout=self.layout.to_json(), q_init=self.q_init)
        blobs = [(name, bytes(self.sections[name])) for name in sorted(self.sections)]
        if blobs:
            header["sections"] = [[name, len(blob)] for name, blob in blobs]
        hjson = json.dumps(header, sort_keys=True, separators=(",", ":")).encode()
        keys = np.fromiter(sorted(self.rows), dtype="<u8", count=len(self.rows))
        values = np.array([self.rows[int(k)] for k in keys], dtype="<f8").reshape(
            len(keys), self.layout.n_actions
        )
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

    @classmethod
    def from_bytes(cls, data: bytes, source: str = "<bytes>") -> QTable:
        def bad(problem: str) -> QTableError:
            return QTableError(located(source, "", problem))

        if len(data) < len(MAGIC) + 4 + 8 + 4 or data[: len(MAGIC)] != MAGIC:
            raise bad("not a koolio-pymunk Q-table file (bad magic or too short)")
        (crc,) = struct.unpack("<I", data[-4:])
        if zlib.crc32(data[:-4]) != crc:
            raise bad("corrupt or truncated (checksum mismatch)")
        pos = len(MAGIC)
        (hlen,) = struct.unpack_from("<I", data, pos)
        pos += 4
        try:
            header = json.loads(data[pos : pos + hlen])
            layout = KeywordLayout.from_json(header.pop("layout"))
        except (ValueError, KeyError, TypeError) as exc:
            raise bad(f"unreadable header ({exc})") from None
        if header.pop("format", None) != FORMAT_VERSION:
            raise bad(f"unsupported format version (this program reads {FORMAT_VERSION})")
        q_init = float(header.pop("q_init", 0.0))
        listed = header.pop("sections", [])
        if not isinstance(listed, list) or not all(
            isinstance(x, list) and len(x) == 2 and isinstance(x[0], str) and _count(x[1])
            for x in listed
        ):
            raise bad("unreadable header (sections must be [[name, length], ...])")
        pos += hlen
        (n,) = struct.unpack_from("<Q", data, pos)
        pos += 8
        na = layout.n_actions
        extra = sum(length for _, length in listed)
        if len(data) - 4 - pos != n * 8 * (1 + na) + extra:
            raise bad("corrupt or truncated (length does not match the row count)")
        keys = np.frombuffer(data, dtype="<u8", count=n, offset=pos)
        values = np.frombuffer(data, dtype="<f8", count=n * na, offset=pos + 8 * n)
        rows = {int(k): values[i * na : (i + 1) * na].tolist() for i, k in enumerate(keys)}
        pos += n * 8 * (1 + na)
        sections = {}
        for name, length in listed:
            sections[name] = data[pos : pos + length]
            pos += length
        return cls(layout, header, q_init, rows, sections)


def _count(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool) and v >= 0


def backup_path(path: Path) -> Path:
    return path.with_name(path.name + ".bak")


class QTableStore:
    """A Q-table file and its backup (``<file>.bak``), as the paper keeps them.

    ``open`` reads the table (creating both files empty when missing); ``save`` writes
    the previous good table to the backup and the new one to the file, each atomically.
    """

    def __init__(self, path: str | Path, warn=None) -> None:
        self.path = Path(path)
        self.backup = backup_path(self.path)
        self._warn = warn or (lambda msg: print(f"warning: {msg}", file=sys.stderr))
        self._last: bytes | None = None

    def open(self, layout: KeywordLayout, sensors: dict[str, Any], q_init: float) -> QTable:
        """Load the table, checking it was made for ``layout`` and ``sensors``."""
        table = self._load_existing()
        if table is None:
            table = QTable(layout, {"sensors": sensors, "episodes": 0}, q_init)
            self._last = table.to_bytes()
            self._ensure_dir()
            atomic_write(self.path, self._last)
            atomic_write(self.backup, self._last)
            return table
        check_compatible(table, layout, sensors, str(self.path))
        return table

    def save(self, table: QTable) -> None:
        """Write ``table``: the previous good table goes to the backup first."""
        data = table.to_bytes()
        self._ensure_dir()
        if self._last is not None and self._last != data:
            atomic_write(self.backup, self._last)
        atomic_write(self.path, data)
        self._last = data

    def _ensure_dir(self) -> None:
        if not self.path.parent.exists():
            self.path.parent.mkdir(parents=True, exist_ok=True)

    def _load_existing(self) -> QTable | None:
        main_err: QTableError | None = None
        if self.path.exists():
            try:
                data = self.path.read_bytes()
                table = QTable.from_bytes(data, str(self.path))
                self._last = data
                return table
            except QTableError as exc:
                main_err = exc
            except OSError as exc:
                main_err = QTableError(located(str(self.path), "", f"cannot read: {exc}"))
        if self.backup.exists():
            try:
                data = self.backup.read_bytes()
                table = QTable.from_bytes(data, str(self.backup))
            except (QTableError, OSError) as exc:
                if main_err is not None:
                    raise QTableError(f"{main_err}; backup unusable too: {exc}") from None
                raise QTableError(
                    located(str(self.path), "", f"missing, and its backup is unusable: {exc}")
                ) from None
            why = main_err if main_err is not None else f"{self.path}: missing"
            self._warn(f"{why}; using the backup {self.backup}")
            self._last = data
            return table
        if main_err is not None:
            raise main_err
        return None


def load_qtable(path: str | Path) -> QTable:
    """Read a table file (no backup fallback); QTableError when missing or bad."""
    p = Path(path)
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise QTableError(located(str(p), "", f"cannot read: {exc.strerror}")) from None
    return QTable.from_bytes(data, str(p))


def check_compatible(
    table: QTable, layout: KeywordLayout, sensors: dict[str, Any], source: str
) -> None:
    """Refuse a table made for another keyword layout or sensor configuration."""
    if table.layout != layout:
        raise QTableError(
            located(
                source,
                "layout",
                f"table made for {_fmt_layout(table.layout)}, this run uses {_fmt_layout(layout)}",
            )
        )
    theirs = table.meta.get("sensors", {})
    for key in sorted(set(theirs) | set(sensors)):
        if theirs.get(key) != sensors.get(key):
            raise QTableError(
                located(
                    source,
                    f"sensors.{key}",
                    f"table made for {theirs.get(key)!r}, this run uses {sensors.get(key)!r}",
                )
            )


def _fmt_layout(layout: KeywordLayout) -> str:
    return (
        f"{layout.total_bits}-bit keyword ["
        + ", ".join(f"{n}:{lv}" for n, lv in layout.fields)
        + "]"
    )


#: The paper's first design (§5.4.8): compass (4 values), 6 cameras (4 values: Close,
#: Medium, Far, Very Far) and 8 sonars (5 values), before it was cut down.
PAPER_ORIGINAL_FIELDS: tuple[tuple[str, int], ...] = (
    (("Compass", 4),)
    + tuple((f"Camera{c}", 4) for c in range(6))
    + tuple((f"Sonar{s}", 5) for s in range(8))
)


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
