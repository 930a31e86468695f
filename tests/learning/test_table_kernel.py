"""The step engine's table in arrays (learning/table_kernel.py): its index and row_max."""

from __future__ import annotations

import numpy as np

from koolio_pymunk.learning.table_kernel import SharedTable, find_row, row_max
from koolio_pymunk.store.keyword import KeywordLayout
from koolio_pymunk.store.qtable import QTable


def _table(keys: list[int]) -> QTable:
    layout = KeywordLayout((("A", 3), ("B", 4)))
    return QTable(layout, rows={k: [float(k)] * layout.n_actions for k in keys})


def test_the_index_finds_every_row_and_no_other_key() -> None:
    keys = [int(k) for k in np.random.default_rng(0).choice(1 << 27, 3000, replace=False)]
    shared = SharedTable(_table(keys), reserve=16)
    assert shared.index[0].shape[0] >= 2 * shared.capacity  # at most half full
    for i, k in enumerate(keys):
        assert shared.row_of(k) == i and shared.keys[i] == k
    absent = set(range(1 << 12)) - set(keys)
    assert all(shared.row_of(k) == -1 for k in absent)


def test_keys_that_share_a_slot_are_found_past_each_other() -> None:
    mask = SharedTable(_table([]), reserve=8).index[0].shape[0] - 1  # 16 slots

    def start(k: int) -> int:  # where the search for k starts (Fibonacci hashing)
        return ((k * 0x9E3779B97F4A7C15) % (1 << 64)) >> 32 & mask

    same = [k for k in range(10_000) if start(k) == start(0)][:4]
    shared = SharedTable(_table(same), reserve=8)
    assert [shared.row_of(k) for k in same] == [0, 1, 2, 3]
    assert sorted(int(r) for r in shared.index[1] if r >= 0) == [0, 1, 2, 3]


def test_growing_the_table_keeps_every_row_findable() -> None:
    keys = list(range(5, 5 + 40 * 7, 7))
    shared = SharedTable(_table(keys), reserve=8)
    before = shared.index[0].shape[0]
    shared.reserve(1000)
    assert shared.capacity >= len(keys) + 1000
    assert shared.index[0].shape[0] >= 2 * shared.capacity > before
    assert [int(find_row(shared.index, k)) for k in keys] == list(range(len(keys)))
    assert find_row(shared.index, 6) == -1


def test_row_max_is_numpys_max_with_its_nan() -> None:
    q = np.array([[1.0, -2.0, 3.5, 3.5, 0.0], [-1.0, np.nan, 2.0, -5.0, 1.0]])
    assert row_max(q, 0) == q[0].max() == 3.5
    assert np.isnan(row_max(q, 1)) and np.isnan(q[1].max())
