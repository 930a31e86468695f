"""Inline twins: the same Python code compiled into its caller, with chosen callees."""

from __future__ import annotations

import numba
import numpy as np
import pytest

from koolio_pymunk.sensing.inline_twins import inline_twin


@numba.njit
def _scale(v: np.ndarray) -> float:
    return 2.0 * v[0]


@numba.njit
def _halve(v: np.ndarray) -> float:
    return 0.5 * v[0]


@numba.njit
def _total(v: np.ndarray) -> float:
    return _scale(v) + v[1]


def test_twin_gives_the_original_results_and_uses_the_callees_it_is_given() -> None:
    v = np.array([3.0, 0.25])
    same = inline_twin(_total)
    other = inline_twin(_total, _scale=_halve)

    @numba.njit
    def caller(v: np.ndarray) -> tuple[float, float]:
        return same(v), other(v)

    assert caller(v) == (_total(v), 1.5 + 0.25)
    assert _total(v) == 6.25  # the original keeps its own callee


def test_a_callee_the_function_does_not_call_is_an_error() -> None:
    with pytest.raises(ValueError, match="does not call"):
        inline_twin(_total, _nothing=_halve)


def test_the_reading_twins_are_inlined_into_their_compiled_callers() -> None:
    from koolio_pymunk.sensing.encoding_kernel import readout, readout_inline
    from koolio_pymunk.sensing.ray_kernel import sense_one, sense_one_inline

    assert sense_one_inline.py_func.__code__ is sense_one.py_func.__code__
    assert readout_inline.py_func.__code__ is readout.py_func.__code__
    assert sense_one_inline.targetoptions.get("inline") == "always"
