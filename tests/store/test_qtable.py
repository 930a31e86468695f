"""Q-table: Table 12 keywords, file format, backup, atomic writes, layout checks."""

from __future__ import annotations

import os

import pytest
from inputs import made_for, open_table

from koolio_pymunk.store import run_identity
from koolio_pymunk.store.config import Config, state_fields
from koolio_pymunk.store.errors import FileError, QTableError
from koolio_pymunk.store.keyword import PAPER_ORIGINAL_FIELDS, KeywordLayout
from koolio_pymunk.store.qtable import (
    QTable,
    QTableStore,
    human_bytes,
    load_qtable,
)

LAYOUT = KeywordLayout(tuple(state_fields(Config().sensors)))
SENSORS = {"sonar_arc_deg": 55.0}


def test_table12_shifts() -> None:
    assert LAYOUT.shifts == (25, 23, 21, 19, 17, 15, 13, 11, 9, 7, 5, 3)
    assert LAYOUT.total_bits == 27
    assert LAYOUT.action_bits == 3


def test_table12_keyword_hand_computed() -> None:
    codes = (1, 2, 0, 2, 1, 0, 3, 2, 1, 0, 3, 1)
    expected = (
        1 << 25
        | 2 << 23
        | 0 << 21
        | 2 << 19
        | 1 << 17
        | 0 << 15
        | 3 << 13
        | 2 << 11
        | 1 << 9
        | 0 << 7
        | 3 << 5
        | 1 << 3
        | 4
    )
    assert expected == 51540588  # worked by hand
    assert LAYOUT.keyword(codes, 4) == 51540588
    assert LAYOUT.decode(51540588) == (codes, 4)
    assert LAYOUT.keyword((0,) * 12, 0) == 0
    # Far cameras are 0b10, Far sonars 0b11, Reverse 0b100:
    assert LAYOUT.keyword((2,) * 6 + (3,) * 6, 4) == int("10" * 6 + "11" * 6 + "100", 2)


def test_state_space_sizes_of_the_paper() -> None:
    assert LAYOUT.n_states == 2_985_984
    assert LAYOUT.n_entries == 14_929_920
    assert human_bytes(LAYOUT.dense_bytes()) == "113.9 MiB"
    paper = KeywordLayout(PAPER_ORIGINAL_FIELDS)
    assert paper.n_states == 6_400_000_000
    assert paper.n_entries == 32_000_000_000
    assert human_bytes(paper.dense_bytes()) == "238.4 GiB"


def _table() -> QTable:
    t = QTable(LAYOUT, {"sensors": SENSORS, "episodes": 3})
    t.row(4153)[:] = [0.5, -1.25, 3.0, 1e-300, -7.0]
    t.row(7)[2] = 2.0 / 3.0
    return t


def test_bytes_round_trip_exact_and_canonical() -> None:
    t = _table()
    data = t.to_bytes()
    back = QTable.from_bytes(data)
    assert back.rows == t.rows and back.layout == LAYOUT and back.meta == t.meta
    # insertion order does not matter: rows are written sorted
    u = QTable(LAYOUT, {"sensors": SENSORS, "episodes": 3})
    u.row(7)[2] = 2.0 / 3.0
    u.row(4153)[:] = [0.5, -1.25, 3.0, 1e-300, -7.0]
    assert u.to_bytes() == data


@pytest.mark.parametrize("cut", [1, 10, 100])
def test_truncated_file_is_reported(tmp_path, cut: int) -> None:
    p = tmp_path / "q.qtable"
    p.write_bytes(_table().to_bytes()[:-cut])
    with pytest.raises(QTableError, match=r"q\.qtable"):
        load_qtable(p)


def test_flipped_byte_is_reported(tmp_path) -> None:
    data = bytearray(_table().to_bytes())
    data[-20] ^= 0xFF
    p = tmp_path / "q.qtable"
    p.write_bytes(bytes(data))
    with pytest.raises(QTableError, match="checksum"):
        load_qtable(p)


def test_not_a_table(tmp_path) -> None:
    p = tmp_path / "q.qtable"
    p.write_text("hello world, not a table at all")
    with pytest.raises(QTableError, match="not a koolio-pymunk Q-table"):
        load_qtable(p)


def test_store_creates_both_files_empty(tmp_path) -> None:
    store = QTableStore(tmp_path / "runs" / "q.qtable")
    t = open_table(store, LAYOUT, SENSORS, 0.0)
    assert len(t) == 0
    assert load_qtable(store.path).rows == {}
    assert load_qtable(store.backup).rows == {}


def test_store_backup_holds_previous_table(tmp_path) -> None:
    store = QTableStore(tmp_path / "q.qtable")
    t = open_table(store, LAYOUT, SENSORS, 0.0)
    t.row(1)[0] = 1.0
    store.save(t)
    first = store.path.read_bytes()
    t.row(2)[0] = 2.0
    store.save(t)
    assert store.backup.read_bytes() == first
    assert load_qtable(store.path).rows == {1: [1.0, 0, 0, 0, 0], 2: [2.0, 0, 0, 0, 0]}


def test_corrupt_main_falls_back_to_backup_with_warning(tmp_path) -> None:
    store = QTableStore(tmp_path / "q.qtable")
    t = open_table(store, LAYOUT, SENSORS, 0.0)
    t.row(1)[0] = 1.0
    store.save(t)
    t.row(2)[0] = 2.0
    store.save(t)
    store.close()
    store.path.write_bytes(store.path.read_bytes()[:50])  # a torn file
    warnings: list[str] = []
    again = QTableStore(store.path, warn=warnings.append)
    t2 = open_table(again, LAYOUT, SENSORS, 0.0)
    assert t2.rows == {1: [1.0, 0, 0, 0, 0]}
    assert len(warnings) == 1 and "backup" in warnings[0] and "q.qtable" in warnings[0]


def test_corrupt_main_and_backup_is_an_error(tmp_path) -> None:
    store = QTableStore(tmp_path / "q.qtable")
    open_table(store, LAYOUT, SENSORS, 0.0)
    store.close()
    store.path.write_bytes(b"junk")
    store.backup.write_bytes(b"junk")
    with pytest.raises(QTableError, match="backup unusable"):
        open_table(QTableStore(store.path, warn=lambda m: None), LAYOUT, SENSORS, 0.0)


def test_layout_mismatch_is_refused_not_overwritten(tmp_path) -> None:
    store = QTableStore(tmp_path / "q.qtable")
    open_table(store, LAYOUT, SENSORS, 0.0)
    store.close()
    before = store.path.read_bytes()
    other = KeywordLayout(LAYOUT.fields[:-1])
    with pytest.raises(QTableError, match="layout: table made for 27-bit keyword"):
        open_table(QTableStore(store.path), other, SENSORS, 0.0)
    with pytest.raises(QTableError, match=r"sensors\.sonar_arc_deg"):
        open_table(QTableStore(store.path), LAYOUT, {"sonar_arc_deg": 60.0}, 0.0)
    assert store.path.read_bytes() == before


def test_an_identity_refusal_is_one_line() -> None:
    t = _table()
    with pytest.raises(QTableError) as exc:
        run_identity.check(t, made_for(LAYOUT, {"sonar_arc_deg": 45.0}), "inspect", "x.qtable")
    assert "\n" not in str(exc.value) and str(exc.value).startswith("x.qtable: sensors.")


def test_atomic_write_keeps_old_file_when_replace_fails(tmp_path, monkeypatch) -> None:
    store = QTableStore(tmp_path / "q.qtable")
    t = open_table(store, LAYOUT, SENSORS, 0.0)
    t.row(1)[0] = 1.0
    store.save(t)
    good = store.path.read_bytes()

    def crash(src, dst):
        raise OSError("disk gone")

    monkeypatch.setattr(os, "replace", crash)
    t.row(2)[0] = 2.0
    with pytest.raises(FileError, match="cannot write: disk gone"):
        store.save(t)
    monkeypatch.undo()
    assert store.path.read_bytes() == good
    assert [p.name for p in tmp_path.iterdir() if ".tmp" in p.name] == []


def test_saved_files_get_normal_permissions(tmp_path) -> None:
    store = QTableStore(tmp_path / "q.qtable")
    open_table(store, LAYOUT, SENSORS, 0.0)
    umask = os.umask(0)
    os.umask(umask)
    assert store.path.stat().st_mode & 0o777 == 0o666 & ~umask
    store.path.chmod(0o640)
    store.save(_table())
    assert store.path.stat().st_mode & 0o777 == 0o640  # an existing file keeps its mode
