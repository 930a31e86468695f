"""TensorBoard event files, written directly: scalars without TensorFlow or a writer library.

An :class:`EventWriter` makes one new event file in a log folder,
``events.out.tfevents.<time>.<host>.<pid>.<n>``, and appends scalars to it; ``tensorboard
--logdir DIR`` (or any TensorBoard reader) shows them. The format is TensorFlow's record
file of ``Event`` protocol buffers, of which a scalar needs five fields, so it is written
here in about a hundred lines (and read back in fifty) rather than taken from a dependency
(the README's Dependencies section says why):

* a record is ``uint64 length``, ``uint32 masked CRC-32C of those 8 bytes``, the data,
  ``uint32 masked CRC-32C of the data`` (little-endian; the mask is
  ``((crc >> 15 | crc << 17) + 0xa282ead8) mod 2**32``);
* the data is an ``Event``: ``wall_time`` (field 1, double), ``step`` (2, int64),
  ``file_version`` (3, string: ``brain.Event:2`` in the file's first record) or
  ``summary`` (5: a ``Summary`` of ``value`` (1) entries, each a ``tag`` (1, string) and a
  ``simple_value`` (2, float32)).

**What a crash leaves.** Records are kept in memory by :meth:`EventWriter.scalar` and
appended to the file by :meth:`~EventWriter.flush` (one ``write``, then ``fsync``), by
:meth:`~EventWriter.close`, and on their own once 64 KiB are waiting. The file is only
ever appended to, so a process killed at any point leaves every record flushed before it
whole (readers stop at a record cut short, as they do for a file still being written).
The file is created new (never over an existing file) and must stay a regular file.

Example (pass ``wall_time`` only to make files reproducible; the default is the time now):

>>> import tempfile
>>> logdir = tempfile.mkdtemp()
>>> with EventWriter(logdir) as tb:
...     for episode in (1, 2, 3):
...         tb.scalar("train/return", -10.0 * episode, step=episode, wall_time=1e9 + episode)
...     tb.scalar("train/goal_rate", 0.5, step=3)
>>> tb.path.name.startswith("events.out.tfevents.")
True
>>> [(s.step, s.tag, s.value) for s in read_scalars(tb.path)]  # doctest: +NORMALIZE_WHITESPACE
[(1, 'train/return', -10.0), (2, 'train/return', -20.0), (3, 'train/return', -30.0),
 (3, 'train/goal_rate', 0.5)]

:func:`read_scalars` reads such a file back (checking every CRC); it serves tests and a
look without TensorBoard. ``tests/store/test_tensorboard.py`` reads the files with
TensorBoard's own reader.
"""

from __future__ import annotations

import itertools
import math
import os
import socket
import struct
import time
from pathlib import Path
from typing import NamedTuple

from .errors import KoolioError, located
from .files import check_path, file_error, make_parent, read_bytes

FILE_VERSION = b"brain.Event:2"
"""The ``file_version`` of the first record: TensorBoard's current event format."""
AUTO_WRITE = 64 * 1024
"""Bytes of records kept in memory before they are appended without a :meth:`flush`."""
MAX_EVENT_FILE = 1 << 30
"""Largest event file :func:`read_scalars` reads (1 GiB)."""
_U64 = (1 << 64) - 1
_numbers = itertools.count()


def _crc32c_table() -> list[int]:
    table = []
    for n in range(256):
        c = n
        for _ in range(8):
            c = (c >> 1) ^ 0x82F63B78 if c & 1 else c >> 1
        table.append(c)
    return table


_CRC_TABLE = _crc32c_table()


def crc32c(data: bytes) -> int:
    """CRC-32C (Castagnoli) of ``data``, the checksum of TensorFlow's records.

    >>> hex(crc32c(b"123456789"))  # the standard check value
    '0xe3069283'
    """
    crc, table = 0xFFFFFFFF, _CRC_TABLE
    for b in data:
        crc = table[(crc ^ b) & 0xFF] ^ (crc >> 8)
    return crc ^ 0xFFFFFFFF


def masked_crc(data: bytes) -> int:
    """The masked CRC-32C a record stores."""
    crc = crc32c(data)
    return (((crc >> 15) | (crc << 17)) + 0xA282EAD8) & 0xFFFFFFFF


def record(data: bytes) -> bytes:
    """``data`` framed as one record of the file (length, its CRC, data, the data's CRC)."""
    head = struct.pack("<Q", len(data))
    return head + struct.pack("<I", masked_crc(head)) + data + struct.pack("<I", masked_crc(data))


def _varint(n: int) -> bytes:
    n &= _U64  # an int64 below zero: its two's complement, as protobuf writes it
    out = bytearray()
    while n > 0x7F:
        out.append(n & 0x7F | 0x80)
        n >>= 7
    out.append(n)
    return bytes(out)


def _field_bytes(number: int, data: bytes) -> bytes:
    """A length-delimited protobuf field (strings, messages)."""
    return _varint(number << 3 | 2) + _varint(len(data)) + data


def _float32(value: float) -> bytes:
    try:
        return struct.pack("<f", value)
    except OverflowError:  # beyond float32's range: its infinity, as a float32 cast gives
        return struct.pack("<f", math.copysign(math.inf, value))


def event(wall_time: float, step: int = 0, file_version: bytes = b"", scalars=()) -> bytes:
    """An ``Event``'s bytes: its time and step, and a ``file_version`` or a summary of
    ``scalars`` (``(tag, value)`` pairs)."""
    out = b"\x09" + struct.pack("<d", wall_time) + b"\x10" + _varint(step)
    if file_version:
        out += _field_bytes(3, file_version)
    if scalars:
        values = b"".join(
            _field_bytes(1, _field_bytes(1, tag.encode()) + b"\x15" + _float32(value))
            for tag, value in scalars
        )
        out += _field_bytes(5, values)
    return out


class EventWriter:
    """Scalars into a new TensorBoard event file in ``logdir`` (created if missing).

    :meth:`scalar` adds one value of a tag at a step; :meth:`flush` appends what waits
    to the file and syncs it; :meth:`close` (or the end of a ``with`` block) flushes and
    closes. File errors are one-line
    :class:`~koolio_pymunk.store.errors.FileError` s naming the file.
    """

    def __init__(self, logdir: str | Path, suffix: str = "") -> None:
        folder = check_path(logdir, "tensorboard log folder")
        now = time.time()
        host = socket.gethostname().replace(os.sep, "_") or "localhost"
        name = f"events.out.tfevents.{int(now):010d}.{host}.{os.getpid()}.{next(_numbers)}"
        self.path = folder / (name + suffix)
        """The event file."""
        self._waiting: list[bytes] = []
        self._size = 0
        make_parent(self.path)
        flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_APPEND
        flags |= getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
        try:
            self._fd: int | None = os.open(self.path, flags, 0o644)
        except OSError as exc:
            raise file_error(self.path, "create", exc) from None
        self._waiting.append(record(event(now, file_version=FILE_VERSION)))
        self.flush()

    def scalar(self, tag: str, value: float, step: int, wall_time: float | None = None) -> None:
        """Add ``value`` of ``tag`` at ``step`` (an int64; ``wall_time``: seconds since
        the epoch, default now). Written at the next :meth:`flush`."""
        self.scalars({tag: value}, step, wall_time)

    def scalars(self, values: dict[str, float], step: int, wall_time: float | None = None) -> None:
        """Several tags at one ``step``, in one record."""
        if self._fd is None:
            raise KoolioError(located(str(self.path), "", "closed: no more scalars"))
        if not -(1 << 63) <= int(step) < 1 << 63:
            raise KoolioError(located(str(self.path), "step", f"not an int64: {step}"))
        pairs = []
        for tag, value in values.items():
            if not isinstance(tag, str) or not tag:
                raise KoolioError(located(str(self.path), "tag", f"not a name: {tag!r}"))
            pairs.append((tag, float(value)))
        when = time.time() if wall_time is None else float(wall_time)
        data = record(event(when, int(step), scalars=pairs))
        self._waiting.append(data)
        self._size += len(data)
        if self._size >= AUTO_WRITE:
            self._append()

    def _append(self) -> None:
        """Append the waiting records to the file (whole, in one write as far as the
        system allows)."""
        if not self._waiting or self._fd is None:
            return
        data = memoryview(b"".join(self._waiting))
        self._waiting, self._size = [], 0
        try:
            while data:
                data = data[os.write(self._fd, data) :]
        except OSError as exc:
            raise file_error(self.path, "write", exc) from None

    def flush(self) -> None:
        """Append the waiting records and sync the file: a crash after this keeps them."""
        self._append()
        if self._fd is not None:
            try:
                os.fsync(self._fd)
            except OSError as exc:
                raise file_error(self.path, "write", exc) from None

    def close(self) -> None:
        """Flush and close (again: nothing)."""
        if self._fd is None:
            return
        try:
            self.flush()
        finally:
            os.close(self._fd)
            self._fd = None

    def __enter__(self) -> EventWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class Scalar(NamedTuple):
    """One scalar read back from an event file."""

    step: int
    tag: str
    value: float
    wall_time: float


def read_scalars(path: str | Path) -> list[Scalar]:
    """The scalars of an event file in file order; a record cut short at the end (a
    file being written) ends the list; a wrong checksum is a one-line
    :class:`~koolio_pymunk.store.errors.KoolioError`."""
    data = read_bytes(path, MAX_EVENT_FILE, "event file")
    out: list[Scalar] = []
    at = 0
    while at + 12 <= len(data):
        head = data[at : at + 8]
        (n,) = struct.unpack("<Q", head)
        if struct.unpack("<I", data[at + 8 : at + 12])[0] != masked_crc(head):
            raise KoolioError(located(str(path), f"byte {at}", "record length checksum wrong"))
        body = data[at + 12 : at + 12 + n]
        if at + 16 + n > len(data):
            break  # cut short: the end of what was written
        if struct.unpack("<I", data[at + 12 + n : at + 16 + n])[0] != masked_crc(body):
            raise KoolioError(located(str(path), f"byte {at}", "record data checksum wrong"))
        out += _event_scalars(body)
        at += 16 + n
    return out


def _fields(data: bytes):
    """``(field number, wire type, value)`` of a protobuf message's fields."""
    at = 0
    while at < len(data):
        key, at = _read_varint(data, at)
        number, wire = key >> 3, key & 7
        if wire == 0:
            value, at = _read_varint(data, at)
        elif wire == 1:
            value, at = data[at : at + 8], at + 8
        elif wire == 5:
            value, at = data[at : at + 4], at + 4
        elif wire == 2:
            n, at = _read_varint(data, at)
            value, at = data[at : at + n], at + n
        else:
            raise KoolioError(f"event: unknown protobuf wire type {wire}")
        yield number, wire, value


def _read_varint(data: bytes, at: int) -> tuple[int, int]:
    value = shift = 0
    while True:
        if at >= len(data) or shift > 63:
            raise KoolioError("event: bad protobuf varint")
        b = data[at]
        value |= (b & 0x7F) << shift
        at, shift = at + 1, shift + 7
        if not b & 0x80:
            return value, at


def _event_scalars(body: bytes) -> list[Scalar]:
    wall, step = 0.0, 0
    values: list[tuple[str, float]] = []
    for number, _, value in _fields(body):
        if number == 1:
            (wall,) = struct.unpack("<d", value)
        elif number == 2:
            step = value - (1 << 64) if value >> 63 else value
        elif number == 5:
            for vnum, _, v in _fields(value):
                if vnum == 1:
                    f = {k: x for k, _, x in _fields(v)}
                    if 1 in f and 2 in f:
                        values.append((f[1].decode(), struct.unpack("<f", f[2])[0]))
    return [Scalar(step, tag, x, wall) for tag, x in values]
