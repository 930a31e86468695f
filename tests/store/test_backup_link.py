"""The table's backup made by a hard link of the file being replaced: the same bytes as a
written copy, one fsync per save, and a written copy wherever a link would not do."""

from __future__ import annotations

import errno
import os
import random
import stat
import struct
import zlib

import numpy as np
import pytest
from inputs import open_table

from koolio_pymunk.store import files as files_mod
from koolio_pymunk.store.config import Config, state_fields
from koolio_pymunk.store.errors import FileError
from koolio_pymunk.store.keyword import KeywordLayout
from koolio_pymunk.store.qtable import QTable, QTableStore, load_qtable

LAYOUT = KeywordLayout(tuple(state_fields(Config().sensors)))
SENSORS = {"sonar_arc_deg": 55.0}


def _saves(store: QTableStore, table: QTable, n: int) -> list[bytes]:
    """``n`` saves of ``table``, a new row each; the bytes of each save."""
    out = []
    for i in range(n):
        table.row(100 + i)[i % 5] = float(i) + 0.5
        table.meta["episodes"] = i + 1
        store.save(table)
        out.append(store.path.read_bytes())
    return out


def _count_fsyncs(monkeypatch) -> list[int]:
    """The fsyncs of files (a save's folder is fsynced too, once: the rename's name)."""
    calls: list[int] = []
    real = files_mod.os.fsync

    def counting(fd: int) -> None:
        if stat.S_ISREG(os.fstat(fd).st_mode):
            calls.append(fd)
        real(fd)

    monkeypatch.setattr(files_mod.os, "fsync", counting)
    return calls


def test_backup_is_the_previous_file_linked_one_fsync_per_save(tmp_path, monkeypatch) -> None:
    store = QTableStore(tmp_path / "q.qtable")
    table = open_table(store, LAYOUT, SENSORS, 0.0)
    fsyncs = _count_fsyncs(monkeypatch)
    saved = _saves(store, table, 4)
    assert len(fsyncs) == 4  # the backup is not written again
    assert store.backup.read_bytes() == saved[-2]
    before = os.stat(store.path).st_ino
    _saves(store, table, 1)
    assert os.stat(store.backup).st_ino == before  # the replaced file, renamed
    assert os.stat(store.path).st_nlink == 1 and os.stat(store.backup).st_nlink == 1
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]
    store.close()


def test_a_table_read_from_disk_is_written_to_its_backup_once(tmp_path, monkeypatch) -> None:
    store = QTableStore(tmp_path / "q.qtable")
    table = open_table(store, LAYOUT, SENSORS, 0.0)
    saved = _saves(store, table, 2)
    store.close()
    again = QTableStore(store.path)
    table = open_table(again, LAYOUT, SENSORS, 0.0)
    fsyncs = _count_fsyncs(monkeypatch)
    table.row(7)[0] = 3.0
    again.save(table)
    assert len(fsyncs) == 2  # not the file this store wrote: its bytes are written
    assert again.backup.read_bytes() == saved[-1]
    newer = _saves(again, table, 2)
    assert len(fsyncs) == 4 and again.backup.read_bytes() == newer[0]
    again.close()


def test_a_table_changed_behind_the_store_is_not_linked(tmp_path) -> None:
    store = QTableStore(tmp_path / "q.qtable")
    table = open_table(store, LAYOUT, SENSORS, 0.0)
    saved = _saves(store, table, 2)
    os.utime(store.path, ns=(1, 1))  # another file now, for all the store knows
    _saves(store, table, 1)
    assert store.backup.read_bytes() == saved[-1]  # what the store saved, written
    store.close()


def test_torn_table_replaced_by_its_backup_then_saved(tmp_path) -> None:
    store = QTableStore(tmp_path / "q.qtable")
    table = open_table(store, LAYOUT, SENSORS, 0.0)
    saved = _saves(store, table, 3)
    store.close()
    store.path.write_bytes(saved[-1][:40])
    again = QTableStore(store.path, warn=lambda m: None)
    table = open_table(again, LAYOUT, SENSORS, 0.0)
    assert table.meta["episodes"] == 2
    table.row(9)[1] = 1.0
    again.save(table)
    assert again.backup.read_bytes() == saved[-2]  # the good table it resumed, not the torn
    assert load_qtable(again.path).rows[9][1] == 1.0
    again.close()


@pytest.mark.parametrize("err", [errno.EPERM, errno.EOPNOTSUPP, errno.EMLINK])
def test_without_hard_links_the_backup_is_written(tmp_path, monkeypatch, err) -> None:
    def no_links(src, dst, *a, **k):
        raise OSError(err, os.strerror(err))

    monkeypatch.setattr(files_mod.os, "link", no_links)
    store = QTableStore(tmp_path / "q.qtable")
    table = open_table(store, LAYOUT, SENSORS, 0.0)
    saved = _saves(store, table, 3)
    assert store.backup.read_bytes() == saved[-2]
    assert os.stat(store.backup).st_ino != os.stat(store.path).st_ino
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]
    store.close()


def test_a_backup_with_its_own_permissions_keeps_them(tmp_path) -> None:
    store = QTableStore(tmp_path / "q.qtable")
    table = open_table(store, LAYOUT, SENSORS, 0.0)
    _saves(store, table, 1)
    store.backup.chmod(0o600)
    saved = _saves(store, table, 2)
    assert store.backup.stat().st_mode & 0o777 == 0o600
    assert store.backup.read_bytes() == saved[-2]
    store.close()


def test_disk_full_at_the_table_leaves_both_files_as_they_were(tmp_path, monkeypatch) -> None:
    store = QTableStore(tmp_path / "q.qtable")
    table = open_table(store, LAYOUT, SENSORS, 0.0)
    saved = _saves(store, table, 3)

    def full(fd: int) -> None:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(files_mod.os, "fsync", full)
    table.row(50)[0] = 9.0
    with pytest.raises(FileError, match=r"q\.qtable: cannot write: disk full"):
        store.save(table)
    monkeypatch.undo()
    assert store.path.read_bytes() == saved[-1]
    assert store.backup.read_bytes() == saved[-2]  # still the table before the last good
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]
    store.close()


def test_a_failed_rename_of_the_backup_changes_nothing(tmp_path, monkeypatch) -> None:
    store = QTableStore(tmp_path / "q.qtable")
    table = open_table(store, LAYOUT, SENSORS, 0.0)
    saved = _saves(store, table, 2)
    real = os.replace

    def crash(src, dst):
        if str(dst).endswith(".bak"):
            raise OSError(errno.EIO, "input/output error")
        real(src, dst)

    monkeypatch.setattr(os, "replace", crash)
    table.row(60)[0] = 1.0
    with pytest.raises(FileError, match=r"q\.qtable\.bak: cannot write: input/output error"):
        store.save(table)
    monkeypatch.undo()
    assert store.path.read_bytes() == saved[-1] and store.backup.read_bytes() == saved[-2]
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]
    store.close()


def _reference_bytes(table: QTable) -> bytes:
    """The file's bytes as the format describes them, written the plain way."""
    import json

    header = dict(table.meta)
    header.update(format=1, layout=table.layout.header_json(), q_init=table.q_init)
    hjson = json.dumps(header, sort_keys=True, separators=(",", ":")).encode()
    keys = sorted(table.rows)
    body = b"".join(
        [
            b"KOOLIOQT",
            struct.pack("<I", len(hjson)),
            hjson,
            struct.pack("<Q", len(keys)),
            b"".join(struct.pack("<Q", k) for k in keys),
            b"".join(struct.pack("<d", float(v)) for k in keys for v in table.rows[k]),
        ]
    )
    return body + struct.pack("<I", zlib.crc32(body))


def test_table_bytes_are_the_formats_in_key_order() -> None:
    rng = random.Random(3)
    table = QTable(LAYOUT, {"episodes": 4}, 0.25)
    for _ in range(500):  # keys inserted in no order; rows of floats and ints
        row = table.row(rng.getrandbits(24))
        row[rng.randrange(5)] = rng.choice([rng.uniform(-5, 5), 3, -0.0, 1e-300])
    table.rows[(1 << 24) - 1] = list(np.arange(5, dtype=np.float64))
    assert table.to_bytes() == _reference_bytes(table)
    assert QTable(LAYOUT).to_bytes() == _reference_bytes(QTable(LAYOUT))
