"""Seeds: numpy's ``SeedSequence`` and ``PCG64`` seeding, computed in one compiled call.

Every episode starts from seeds (:func:`~koolio_pymunk.learning.episodes.episode_seeds`):
the env's ``reset(seed=...)`` (Gymnasium's ``PCG64(SeedSequence(seed))``), the env seed
itself (``SeedSequence([seed, episode, stream]).generate_state(1)[0]``) and the learner's
``default_rng([seed, episode, stream, 1])``. numpy computes each in 7-17 us of Python,
about 50 us per episode start: with the step engine running a 250-step episode in about
500 us, that was a tenth of a run. This module gives the same numbers for a few us:

* :func:`state_words` is ``SeedSequence(entropy).generate_state(n)`` (numpy's entropy
  pool of four 32-bit words, its hash and mix functions, then its output hash), compiled;
* :func:`seed_of` is its first word (``generate_state(1)[0]``);
* :func:`pcg64_state` is ``PCG64(SeedSequence(entropy)).state``: the generator's 128-bit
  state and increment from ``generate_state(4, np.uint64)`` by PCG's seeding (``state =
  0``, ``inc = 2 * initseq + 1``, one step, ``state += initstate``, one step), in
  Python's integers.

numpy is the reference: ``tests/task/test_seeding.py`` holds all three to it on every
entropy this project makes (one seed, three words, four words; zeros, 32-bit edges,
seeds of several words) and on thousands of random ones. Only non-negative integers and
flat sequences of them are taken (numpy also takes strings of digits, arrays and nested
sequences; the project never seeds with those).

>>> import numpy as np
>>> seed_of([0, 7, 0]) == int(np.random.SeedSequence([0, 7, 0]).generate_state(1)[0])
True
>>> pcg64_state(12345) == np.random.PCG64(np.random.SeedSequence(12345)).state
True
"""

from __future__ import annotations

from collections.abc import Sequence

import numba
import numpy as np

from ..store.kernel_cache import ensure_fresh

ensure_fresh()  # numba's cache, in step with every kernel's source (see there)

# numpy's SeedSequence constants (numpy/random/bit_generator.pyx)
_POOL = 4
_INIT_A = np.uint64(0x43B0D7E5)
_MULT_A = np.uint64(0x931E8875)
_INIT_B = np.uint64(0x8B51F9DD)
_MULT_B = np.uint64(0x58F38DED)
_MIX_L = np.uint64(0xCA01F9DD)
_MIX_R = np.uint64(0x4973F715)
_SHIFT = np.uint64(16)
_WORD = np.uint64(0xFFFFFFFF)

#: PCG64's 128-bit multiplier (numpy's ``PCG_DEFAULT_MULTIPLIER_128``).
PCG_MULTIPLIER = (2549297995355413924 << 64) + 4865540595714422341
_BITS128 = (1 << 128) - 1
_BITS32 = (1 << 32) - 1


@numba.njit(cache=True)
def _hashmix(value: np.uint64, const: np.uint64) -> tuple[np.uint64, np.uint64]:
    """SeedSequence's ``hashmix``: the hashed word and the next hash constant."""
    value ^= const
    const = (const * _MULT_A) & _WORD
    value = (value * const) & _WORD
    value ^= value >> _SHIFT
    return value, const


@numba.njit(cache=True)
def _mix(x: np.uint64, y: np.uint64) -> np.uint64:
    """SeedSequence's ``mix`` of two words (32-bit wrap-around arithmetic)."""
    result = (_MIX_L * x - _MIX_R * y) & _WORD
    return result ^ (result >> _SHIFT)


@numba.njit(cache=True)
def generate_state(entropy: np.ndarray, out: np.ndarray) -> None:
    """``out[:] = SeedSequence(entropy).generate_state(len(out))`` for ``entropy`` the
    32-bit words numpy assembles from the seed (:func:`entropy_words`); ``out`` uint32."""
    pool = np.zeros(_POOL, np.uint64)
    const = _INIT_A
    n = entropy.shape[0]
    for i in range(_POOL):
        word = np.uint64(entropy[i]) if i < n else np.uint64(0)
        pool[i], const = _hashmix(word, const)
    for src in range(_POOL):
        for dst in range(_POOL):
            if src != dst:
                hashed, const = _hashmix(pool[src], const)
                pool[dst] = _mix(pool[dst], hashed)
    for src in range(_POOL, n):
        for dst in range(_POOL):
            hashed, const = _hashmix(np.uint64(entropy[src]), const)
            pool[dst] = _mix(pool[dst], hashed)
    const = _INIT_B
    for i in range(out.shape[0]):
        value = pool[i % _POOL] ^ const
        const = (const * _MULT_B) & _WORD
        value = (value * const) & _WORD
        out[i] = value ^ (value >> _SHIFT)


def entropy_words(entropy: int | Sequence[int]) -> np.ndarray:
    """The 32-bit words numpy's ``SeedSequence`` assembles from ``entropy`` (a
    non-negative integer or a flat sequence of them): each integer's words, least
    significant first, 0 giving one word.

    >>> entropy_words([5, 0, 2**32 + 3]).tolist()
    [5, 0, 3, 1]
    """
    values = [entropy] if isinstance(entropy, (int, np.integer)) else entropy
    words: list[int] = []
    for value in values:
        v = int(value)
        if v < 0:
            raise ValueError(f"expected non-negative integer, got {v}")
        if v <= _BITS32:
            words.append(v)
            continue
        while v > 0:
            words.append(v & _BITS32)
            v >>= 32
    return np.array(words, np.uint32)


def state_words(entropy: int | Sequence[int], n: int) -> list[int]:
    """``SeedSequence(entropy).generate_state(n)`` (uint32 words) as Python integers."""
    out = np.empty(n, np.uint32)
    generate_state(entropy_words(entropy), out)
    return out.tolist()


def seed_of(entropy: int | Sequence[int]) -> int:
    """``int(SeedSequence(entropy).generate_state(1)[0])``: one 32-bit seed."""
    return state_words(entropy, 1)[0]


def pcg64_state(entropy: int | Sequence[int]) -> dict:
    """``np.random.PCG64(np.random.SeedSequence(entropy)).state``: the state to give a
    generator's bit generator so that it draws what ``np.random.default_rng(entropy)``
    draws."""
    w = state_words(entropy, 8)
    # generate_state(4, np.uint64): the eight words read as four little-endian uint64
    initstate = (w[0] | w[1] << 32) << 64 | (w[2] | w[3] << 32)
    initseq = (w[4] | w[5] << 32) << 64 | (w[6] | w[7] << 32)
    inc = (initseq << 1 | 1) & _BITS128
    state = ((inc + initstate) * PCG_MULTIPLIER + inc) & _BITS128
    return {
        "bit_generator": "PCG64",
        "state": {"state": state, "inc": inc},
        "has_uint32": 0,
        "uinteger": 0,
    }
