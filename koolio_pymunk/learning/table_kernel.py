"""The learners' compiled pieces: one Q-table shared by the robots of the step engine.

:class:`SharedTable` mirrors a :class:`~koolio_pymunk.store.qtable.QTable` in arrays a
compiled loop can use: an index from state key to row (a hash table in two arrays,
:func:`_build_index`), a ``(capacity, n_actions)``
array of values and, per row, the *era* of its last write (``stamp``: the value of
``count[1]`` when a kernel wrote it; Python starts a new era with :meth:`SharedTable.mark`).
:meth:`SharedTable.sync` writes the rows written since its last call back into the
``QTable`` (before every snapshot of the table and every check);
:meth:`SharedTable.changed` gives the rows written since its own last call (a journal
record of the table's file, :meth:`~koolio_pymunk.store.qtable.QTableStore.append`).
The kernels, each the compiled twin of the Python code it names (same float64 operations
in the same order, the same draws from the same generators):

* :func:`choose`: ``QLearner.act``'s epsilon-greedy choice with random tie-breaking and
  the no-undo rule (``learner.no_undo``, :mod:`~koolio_pymunk.task.action_rules`);
* :func:`update`: Table 11 (``qlearning.td_target``/``td_step``, ``QLearner.update``);
* :func:`lambda_update`: Watkins's Q(lambda)'s traced update (``QLambda.observe``), with
  :func:`not_greedy`, its cut; :func:`learn_step`, the step engine's call of one or the
  other, compiled without reference counts;
* the *journal* (:func:`new_journal`): every write of a robot's running episode (row,
  action, order, value before and after), so that the writes of episodes still running
  can be taken back (``--discard-unfinished`` with many robots: :func:`undo_writes`).

``tests/learning/test_engine.py`` holds them to the Python learners bit for bit.
"""

from __future__ import annotations

import numba
import numpy as np

from ..sensing.inline_twins import inline_twin
from ..store.kernel_cache import ensure_fresh
from ..store.qtable import QTable
from ..task.action_rules import allowed_action, barred

ensure_fresh()  # numba's cache, in step with every kernel's source (see there)

#: ``action_rules.barred`` and ``allowed_action``, compiled from the same Python code.
_barred = numba.njit(cache=True)(barred)
_allowed_action = numba.njit(cache=True)(allowed_action)


class SharedTable:
    """A QTable's rows as arrays and an index in arrays (see the module doc)."""

    def __init__(self, table: QTable, reserve: int = 1024) -> None:
        self.table = table
        self.n_actions = table.layout.n_actions
        self.q_init = table.q_init
        n = len(table.rows)
        cap = max(reserve, 2 * n)
        self.q = np.empty((cap, self.n_actions))
        self.keys = np.empty(cap, np.int64)
        self.dirty = np.zeros(cap, np.int64)
        """Per row: the era of its last write (module doc)."""
        self.count = np.array([n, 1], np.int64)
        """The rows in use, and the current era."""
        self._synced = self._changed = 1  # the first era either has not seen
        if n:
            self.keys[:n] = np.fromiter(table.rows, np.int64, n)
            self.q[:n] = np.array(list(table.rows.values()), dtype=np.float64)
        self.index = _build_index(self.keys, n, cap)

    @property
    def capacity(self) -> int:
        """Rows the arrays hold before :meth:`reserve` must grow them."""
        return int(self.q.shape[0])

    def reserve(self, extra: int) -> None:
        """Room for ``extra`` more rows (the kernels never grow the arrays)."""
        n, cap = int(self.count[0]), self.q.shape[0]
        if n + extra <= cap:
            return
        new = max(2 * cap, n + extra)
        q = np.empty((new, self.n_actions))
        q[:n] = self.q[:n]
        keys = np.empty(new, np.int64)
        keys[:n] = self.keys[:n]
        dirty = np.zeros(new, np.int64)
        dirty[:n] = self.dirty[:n]
        self.q, self.keys, self.dirty = q, keys, dirty
        self.index = _build_index(keys, n, new)

    def mark(self) -> int:
        """Start a new era of writes; returns the era that ends."""
        era = int(self.count[1])
        self.count[1] = era + 1
        return era

    def _since(self, era: int) -> np.ndarray:
        """The rows written in ``era`` or later."""
        return np.flatnonzero(self.dirty[: int(self.count[0])] >= era)

    def sync(self) -> None:
        """Write the rows changed since the last sync into the QTable."""
        rows = self.table.rows
        for i in self._since(self._synced).tolist():
            rows[int(self.keys[i])] = self.q[i].tolist()
        self._synced = self.mark() + 1

    def changed(self) -> tuple[np.ndarray, np.ndarray]:
        """The keys and values of the rows written since the last call (the first call:
        since the table was mirrored)."""
        idx = self._since(self._changed)
        self._changed = self.mark() + 1
        return self.keys[idx], self.q[idx]

    def row_of(self, key: int) -> int:
        """The row of state ``key`` (-1: none)."""
        return int(find_row(self.index, key))

    def args(self) -> tuple:
        """The kernels' table group ``(q, keys, dirty (the stamps), count, q_init)``; the
        :attr:`index` (its arrays are replaced when :meth:`reserve` grows the table) goes
        beside it."""
        return (self.q, self.keys, self.dirty, self.count, self.q_init)


#: Fibonacci hashing's multiplier (2^64 / the golden ratio): a state key's slot in the index.
_MULTIPLIER = np.uint64(0x9E3779B97F4A7C15)


def _build_index(keys: np.ndarray, n: int, capacity: int) -> tuple[np.ndarray, np.ndarray]:
    """The index of the first ``n`` of ``keys`` for a table of ``capacity`` rows: an open
    addressing hash table in two arrays ``(slot keys, slot rows)`` of a power of two at
    least twice ``capacity`` slots (-1: an empty slot), so at most half full. Arrays, not
    numba's typed dict: the step's compiled code looks a key up without a call and without
    reference counts."""
    slots = 1 << max(4, int(2 * capacity - 1).bit_length())
    index = (np.zeros(slots, np.int64), np.full(slots, -1, np.int64))
    _fill_index(index, keys, n)
    return index


@numba.njit(cache=True)
def _fill_index(index: tuple, keys: np.ndarray, n: int) -> None:
    """Put rows ``0 .. n - 1`` (keys ``keys[:n]``) into the empty ``index``."""
    for i in range(n):
        _insert(index, keys[i], i)


@numba.njit(cache=True, inline="always")
def _slot(index: tuple, key: int) -> int:
    """Where the search for ``key`` starts (linear probing from there)."""
    mask = index[0].shape[0] - 1
    return np.int64((np.uint64(key) * _MULTIPLIER) >> np.uint64(32)) & mask


@numba.njit(cache=True, inline="always")
def _insert(index: tuple, key: int, row: int) -> None:
    """Put ``key -> row`` into ``index`` (``key`` is not in it; a slot is free)."""
    slot_keys, slot_rows = index
    mask = slot_keys.shape[0] - 1
    i = _slot(index, key)
    while slot_rows[i] >= 0:
        i = (i + 1) & mask
    slot_keys[i] = key
    slot_rows[i] = row


@numba.njit(cache=True, inline="always")
def find_row(index: tuple, key: int) -> int:
    """The row of ``key``, -1 when missing."""
    slot_keys, slot_rows = index
    mask = slot_keys.shape[0] - 1
    i = _slot(index, key)
    while True:
        row = slot_rows[i]
        if row < 0 or slot_keys[i] == key:
            return row
        i = (i + 1) & mask


@numba.njit(cache=True)
def row_of(index, table: tuple, key: int) -> int:
    """The row of ``key``, created at ``q_init`` when missing (``QTable.row``);
    ``table`` is :meth:`SharedTable.args`."""
    q, keys, dirty, count, q_init = table
    i = find_row(index, key)
    if i < 0:
        i = count[0]
        _insert(index, key, i)
        keys[i] = key
        for a in range(q.shape[1]):
            q[i, a] = q_init
        dirty[i] = count[1]
        count[0] += 1
    return i


@numba.njit(cache=True)
def td_target(index, table: tuple, gamma: float, reward: float, nxt: int, terminal: bool) -> float:
    """``qlearning.td_target``: the reward alone after a terminal step, else ``reward +
    gamma * max`` of ``nxt``'s row (``q_init`` for a state never visited)."""
    if terminal:
        return reward
    j = find_row(index, nxt)
    return reward + gamma * (row_max(table[0], j) if j >= 0 else table[4])


@numba.njit(cache=True, inline="always")
def row_max(q: np.ndarray, i: int) -> float:
    """``q[i].max()`` (a NaN wins, as numpy's does), without numba's ``max``, which needs
    reference counting."""
    best = q[i, 0]
    for a in range(1, q.shape[1]):
        v = q[i, a]
        if v > best or v != v:
            best = v
    return best


def new_journal(robots: int, capacity: int) -> tuple[np.ndarray, ...]:
    """Empty journal arrays (``capacity`` 0: no journal): ``jint[r, k]`` = row, action,
    order, created; ``jf[r, k]`` = before, after; ``jn[r]`` entries of robot ``r``;
    ``seq[0]`` the next order number."""
    return (
        np.zeros((robots, capacity, 4), np.int64),
        np.zeros((robots, capacity, 2), np.float64),
        np.zeros(robots, np.int64),
        np.zeros(1, np.int64),
    )


def grow_journal(journal: tuple) -> tuple:
    """``journal`` with twice the room per robot, its entries kept."""
    jint, jf, jn, seq = journal
    cap = jint.shape[1]
    grown = new_journal(jint.shape[0], 2 * cap)
    grown[0][:, :cap] = jint
    grown[1][:, :cap] = jf
    return (grown[0], grown[1], jn, seq)


@numba.njit(cache=True)
def _journal(journal: tuple, r: int, i: int, a: int, before: float, after: float,
             created: bool) -> None:  # fmt: skip
    """Record robot ``r``'s write of ``(i, a)`` (a journal of capacity 0: none)."""
    jint, jf, jn, seq = journal
    if jint.shape[1] == 0:
        return
    k = jn[r]
    jint[r, k, 0] = i
    jint[r, k, 1] = a
    jint[r, k, 2] = seq[0]
    jint[r, k, 3] = 1 if created else 0
    jf[r, k, 0] = before
    jf[r, k, 1] = after
    jn[r] = k + 1
    seq[0] += 1


@numba.njit(cache=True)
def update(index, table: tuple, alpha: float, gamma: float, state: int, action: int,
           reward: float, nxt: int, terminal: bool, r: int, journal: tuple) -> None:  # fmt: skip
    """``QLearner.update``: Table 11, no bootstrap from a terminal step (``table``:
    :meth:`SharedTable.args`); the write journaled as robot ``r``'s."""
    q, dirty, count = table[0], table[2], table[3]
    before = count[0]
    i = row_of(index, table, state)
    old = q[i, action]
    target = td_target(index, table, gamma, reward, nxt, terminal)
    q[i, action] += alpha * (target - q[i, action])
    dirty[i] = count[1]
    _journal(journal, r, i, action, old, q[i, action], count[0] > before)


@numba.njit(cache=True)
def lambda_update(
    index, table: tuple, alpha: float, gamma: float, state: int, action: int, reward: float,
    nxt: int, terminal: bool, lam: tuple, traces: tuple, r: int, journal: tuple,
) -> None:  # fmt: skip
    """``QLambda.observe``: the TD error of Table 11's target, the replacing trace of
    ``(state, action)``, every traced entry moved by it and decayed, those below the
    cutoff dropped (in order: the Python dict's order). ``traces`` = ``(rows, actions,
    e, meta)`` of robot ``r``: the traced entries by table row, ``meta[0]`` their count,
    ``meta[1]`` the state the next step is expected to start from (-1: none)."""
    q, dirty, count = table[0], table[2], table[3]
    decay, cutoff = lam[1], lam[2]
    t_row, t_act, t_e, meta = traces
    before = count[0]
    i = row_of(index, table, state)
    created = count[0] > before
    target = td_target(index, table, gamma, reward, nxt, terminal)
    step = alpha * (target - q[i, action])
    n = meta[0]
    k = 0
    while k < n and t_row[k] != i:
        k += 1
    t_row[k] = i
    t_act[k] = action
    t_e[k] = 1.0
    if k == n:
        n += 1
    kept = 0
    for k in range(n):
        row, a = t_row[k], t_act[k]
        old = q[row, a]
        q[row, a] += step * t_e[k]
        dirty[row] = count[1]
        _journal(journal, r, row, a, old, q[row, a], created and row == i)
        e = t_e[k] * decay
        if not e < cutoff:
            t_row[kept] = row
            t_act[kept] = a
            t_e[kept] = e
            kept += 1
    meta[0] = kept
    meta[1] = -1 if terminal else nxt


def undo_writes(shared: SharedTable, journal: tuple, robots: list[int]) -> list[int]:
    """Take back the journaled writes of ``robots`` (their episodes are discarded), newest
    first: an entry still holding the value the robot wrote gets its value from before;
    one that another robot wrote over since keeps that robot's value. Returns the keys of
    rows those robots created that are back at ``q_init`` in every action (the caller
    drops them from the table: they were never visited by a kept episode)."""
    jint, jf, jn, _ = journal
    entries = sorted(
        ((int(jint[r, k, 2]), r, k) for r in robots for k in range(int(jn[r]))), reverse=True
    )
    created = []
    q = shared.q
    for _, r, k in entries:
        i, a = int(jint[r, k, 0]), int(jint[r, k, 1])
        if q[i, a] == jf[r, k, 1]:
            q[i, a] = jf[r, k, 0]
            shared.dirty[i] = shared.count[1]
        if jint[r, k, 3]:
            created.append(i)
    return [int(shared.keys[i]) for i in created if bool(np.all(q[i] == shared.q_init))]


@numba.njit(cache=True)
def _any_action(arng, n_actions: int, bar: int) -> int:
    """``QLearner._any_action``: a uniform random action, not ``bar`` (-1: none barred)."""
    if bar < 0:
        return arng.integers(0, n_actions)
    return _allowed_action(arng.integers(0, n_actions - 1), bar)


@numba.njit(cache=True)
def best_value(q: np.ndarray, i: int, n_actions: int, bar: int) -> float:
    """The highest Q of row ``i`` over the actions but ``bar``."""
    best = -np.inf
    for a in range(n_actions):
        if a != bar and q[i, a] > best:
            best = q[i, a]
    return best


@numba.njit(cache=True)
def choose(state: int, epsilon: float, arng, n_actions: int, index, q: np.ndarray,
           bar: int = -1) -> tuple:  # fmt: skip
    """``QLearner.act``: explore with probability epsilon, else greedy, ties at random;
    never ``bar`` (``learner.no_undo``; -1: none barred). Returns the action and whether
    it was the exploratory choice."""
    if epsilon > 0.0 and arng.random() < epsilon:
        return _any_action(arng, n_actions, bar), True
    i = find_row(index, state)
    if i < 0:
        return _any_action(arng, n_actions, bar), False
    best = best_value(q, i, n_actions, bar)
    ties = 0
    for a in range(n_actions):
        ties += a != bar and q[i, a] == best
    pick = 0 if ties == 1 else arng.integers(0, ties)
    for a in range(n_actions):
        if a != bar and q[i, a] == best:
            if pick == 0:
                return a, False
            pick -= 1
    return 0, False


@numba.njit(cache=True)
def not_greedy(index, q: np.ndarray, state: int, action: int, bar: int = -1) -> bool:
    """``QLambda.explore``'s cut: ``action`` is below the best of ``state``'s row over the
    actions allowed (all but ``bar``; a state never visited has no row: no cut)."""
    i = find_row(index, state)
    if i < 0:
        return False
    return q[i, action] < best_value(q, i, q.shape[1], bar)


#: The learners' kernels with every call that passes arrays compiled into them
#: (:func:`~koolio_pymunk.sensing.inline_twins.inline_twin`), for the step engine's loop.
_row_of_inline = inline_twin(row_of)
_td_target_inline = inline_twin(td_target)
_journal_inline = inline_twin(_journal)
update_inline = inline_twin(
    update, row_of=_row_of_inline, td_target=_td_target_inline, _journal=_journal_inline
)
lambda_update_inline = inline_twin(
    lambda_update, row_of=_row_of_inline, td_target=_td_target_inline, _journal=_journal_inline
)
_best_value_inline = inline_twin(best_value)
choose_inline = inline_twin(choose, _any_action=inline_twin(_any_action),
                            best_value=_best_value_inline)  # fmt: skip
not_greedy_inline = inline_twin(not_greedy, best_value=_best_value_inline)


@numba.njit(cache=True, _nrt=False)
def learn_step(
    r: int, index: tuple, table: tuple, alpha: float, gamma: float, state: int, action: int,
    reward: float, nxt: int, terminal: bool, lam: tuple, traces: tuple, journal: tuple,
) -> None:  # fmt: skip
    """Robot ``r``'s update of one step: :func:`lambda_update` with its rows of ``traces``
    when Q(lambda) is on (``lam[0]``), else :func:`update`. Compiled without reference
    counting, as the step engine's move and reading are
    (:func:`~koolio_pymunk.task.step_kernel.simulate_robot`): nothing in it allocates,
    keeps or returns an array."""
    if lam[0]:
        mine = (traces[0][r], traces[1][r], traces[2][r], traces[3][r])
        lambda_update_inline(index, table, alpha, gamma, state, action, reward, nxt, terminal,
                             lam, mine, r, journal)  # fmt: skip
    else:
        update_inline(index, table, alpha, gamma, state, action, reward, nxt, terminal, r,
                      journal)  # fmt: skip
