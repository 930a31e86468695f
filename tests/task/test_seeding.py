"""The compiled seeding (task/seeding.py) against numpy's SeedSequence and PCG64."""

import random

import numpy as np
import pytest

from koolio_pymunk.task.seeding import entropy_words, pcg64_state, seed_of, state_words

EDGES = [0, 1, 2**31, 2**32 - 1, 2**32, 2**63 - 1, 2**64 + 5, 3 * 2**96 + 7]


def _entropies(count: int) -> list:
    """The project's shapes of entropy (one seed; seed, episode, stream; with the learner's
    1; seed, robot), with edge values and random ones of 1 to 130 bits."""
    rnd = random.Random(20261129)
    out: list = [0, 12345, [0, 0, 0], [0, 7, 0, 1], [3, 2**32 - 1], EDGES]
    for _ in range(count):
        size = rnd.choice([1, 2, 3, 4, 6])
        words = [
            rnd.choice(EDGES) if rnd.random() < 0.3 else rnd.getrandbits(rnd.randint(1, 130))
            for _ in range(size)
        ]
        out.append(words[0] if size == 1 and rnd.random() < 0.5 else words)
    return out


@pytest.mark.parametrize("n", [1, 4, 8, 9])
def test_state_words_are_numpys_generate_state(n: int) -> None:
    for entropy in _entropies(300):
        want = np.random.SeedSequence(entropy).generate_state(n).tolist()
        assert state_words(entropy, n) == want, entropy


def test_seed_of_is_numpys_first_word() -> None:
    for entropy in _entropies(500):
        want = int(np.random.SeedSequence(entropy).generate_state(1)[0])
        assert seed_of(entropy) == want, entropy


def test_pcg64_state_is_numpys() -> None:
    for entropy in _entropies(500):
        assert pcg64_state(entropy) == np.random.PCG64(np.random.SeedSequence(entropy)).state


def test_a_generator_given_the_state_draws_what_default_rng_draws() -> None:
    g = np.random.Generator(np.random.PCG64(999))
    for entropy in ([0, 5, 0, 1], 4_000_000_000, [2**40, 3]):
        g.bit_generator.state = pcg64_state(entropy)
        ref = np.random.default_rng(entropy)
        assert g.random(5).tolist() == ref.random(5).tolist()
        assert g.integers(5, size=7).tolist() == ref.integers(5, size=7).tolist()
        assert g.standard_normal(3).tolist() == ref.standard_normal(3).tolist()


def test_entropy_words_split_large_integers_least_significant_first() -> None:
    assert entropy_words(0).tolist() == [0]
    assert entropy_words([2**32 + 3, 0, 7]).tolist() == [3, 1, 0, 7]
    assert entropy_words(2**64).tolist() == [0, 0, 1]


def test_negative_entropy_is_refused_as_numpy_refuses_it() -> None:
    with pytest.raises(ValueError):
        np.random.SeedSequence([1, -1])
    with pytest.raises(ValueError, match="non-negative"):
        seed_of([1, -1])
