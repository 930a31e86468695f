"""Compiled read-out of one sensor reading: noise, camera limit, encoding and Table 12 key.

:func:`readout` turns the noise-free readings of :func:`koolio_pymunk.sensing.ray_kernel.sense_one`
(``[sonar..., goal cam..., end-of-world cam..., compass]``) and one draw per reading into
what the learner needs, in one call:

1. noise: ``raw * (1 + draw * frac)`` except readings at ``really_long_distance``; the
   compass (the last reading) is an angle: ``raw + draw * frac * 256`` (its noise is a
   fraction of a full turn, the same at every heading);
2. camera limit (paper order: noise first): unseen or beyond ``max_camera_view`` -> far;
3. compass units wrapped into [0, 256) (:func:`wrap_compass`);
4. codes (Tables 6 and 7: the number of thresholds at or below the value, as
   ``np.searchsorted(..., side="right")``), sonar groups averaged first;
5. the state key (Table 12 without the action bits), Bump (any single sonar below the
   first threshold) and goal-close (camera 0 below the first camera threshold).

It is the same arithmetic as ``SensorSuite.read`` + ``encode`` + ``bump`` +
``goal_close`` (numpy), operation for operation: the group mean reproduces numpy's
summation order (sequential below 8 values, numpy's 8-way pairwise blocks up to 128), so
the results are bit-identical; ``tests/sensing/test_ray_kernel.py`` checks it against that path.
"""

from __future__ import annotations

import numba
import numpy as np

from ..store.kernel_cache import ensure_fresh
from .inline_twins import inline_twin

ensure_fresh()  # numba's cache, in step with every kernel's source (see there)


@numba.njit(cache=True, inline="always")
def _numpy_sum(values: np.ndarray, members: np.ndarray, start: int, n: int) -> float:
    """``np.add.reduce`` of the ``n`` values ``values[members[start:start + n]]`` (float64,
    n <= 128), bit for bit: numpy's pairwise sum, its eight partial sums as scalars (no
    array to allocate)."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += values[members[start + i]]
        return res
    r0, r1 = values[members[start]], values[members[start + 1]]
    r2, r3 = values[members[start + 2]], values[members[start + 3]]
    r4, r5 = values[members[start + 4]], values[members[start + 5]]
    r6, r7 = values[members[start + 6]], values[members[start + 7]]
    i = 8
    while i < n - n % 8:
        b = start + i
        r0 += values[members[b]]
        r1 += values[members[b + 1]]
        r2 += values[members[b + 2]]
        r3 += values[members[b + 3]]
        r4 += values[members[b + 4]]
        r5 += values[members[b + 5]]
        r6 += values[members[b + 6]]
        r7 += values[members[b + 7]]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += values[members[start + i]]
        i += 1
    return res


@numba.njit(cache=True, inline="always")
def _code(value: float, thresholds: np.ndarray) -> int:
    """``np.searchsorted(thresholds, value, side="right")`` for increasing thresholds."""
    k = 0
    while k < thresholds.shape[0] and thresholds[k] <= value:
        k += 1
    return k


@numba.njit(cache=True)
def compass_code(units: float) -> int:
    """The compass code of ``units`` (0..255): East 0, North 1, West 2, South 3, with
    boundaries at NE / NW / SW / SE. The one implementation, compiled; Python code calls it
    too (``sensors.compass_code``)."""
    deg = (units / 256.0 * 360.0) % 360.0
    return int(((deg + 45.0) % 360.0) // 90.0)


@numba.njit(cache=True)
def wrap_compass(units: float) -> float:
    """Compass units wrapped into [0, 256): ``units % 256`` (a heading just below 0
    would round to 256.0 itself: that is 0). The one implementation, compiled.

    >>> wrap_compass(-1e-20), wrap_compass(300.0), wrap_compass(-64.0)
    (0.0, 44.0, 192.0)
    """
    w = units % 256.0
    return 0.0 if w >= 256.0 else w


@numba.njit(cache=True)
def readout(raw: np.ndarray, draws: np.ndarray, encoding: tuple, out: np.ndarray,
            eow_k: np.ndarray, codes: np.ndarray) -> tuple[int, bool, bool]:  # fmt: skip
    """Noise, limit and encode ``raw``; returns ``(state_key, bump, goal_close)``.

    ``encoding`` is the group of :data:`koolio_pymunk.sensing.sensor_arrays.ENCODING`:
    ``limits`` = ``[really_long_distance, max_camera_view]``; ``draws`` are the uniform
    (-1, 1) or standard-normal draws and ``fracs`` the matching noise fractions (halved
    for the gaussian model). Writes the noised readings to ``out``, clears ``eow_k[c]``
    to -1 when camera ``c`` ends up seeing no marker, and writes the state ``codes``.
    """
    (fracs, n_sonar, limits, sonar_thresholds, camera_thresholds, group_members, group_sizes,
     bits, compass_in_state) = encoding  # fmt: skip
    far = limits[0]
    max_view = limits[1]
    m = raw.shape[0]
    n_cam = (m - 1 - n_sonar) // 2
    for i in range(m - 1):
        v = raw[i]
        out[i] = v if v >= far else v * (1.0 + draws[i] * fracs[i])
    for i in range(n_sonar, n_sonar + 2 * n_cam):
        if raw[i] >= far or out[i] > max_view:
            out[i] = far
    out[m - 1] = wrap_compass(raw[m - 1] + draws[m - 1] * fracs[m - 1] * 256.0)
    for c in range(n_cam):
        if not out[n_sonar + n_cam + c] < far:
            eow_k[c] = -1
    n_codes = 0
    for i in range(n_sonar, n_sonar + 2 * n_cam):
        codes[n_codes] = _code(out[i], camera_thresholds)
        n_codes += 1
    start = 0
    for g in range(group_sizes.shape[0]):
        size = group_sizes[g]
        codes[n_codes] = _code(_numpy_sum(out, group_members, start, size) / size,
                               sonar_thresholds)  # fmt: skip
        n_codes += 1
        start += size
    if compass_in_state:
        codes[n_codes] = compass_code(out[m - 1])
        n_codes += 1
    key = 0
    for i in range(n_codes):
        key = (key << bits[i]) | codes[i]
    bump = False
    for s in range(n_sonar):
        if out[s] < sonar_thresholds[0]:
            bump = True
    return key, bump, out[n_sonar] < camera_thresholds[0]


#: :func:`readout` compiled into its callers (:func:`~.inline_twins.inline_twin`): for
#: compiled callers on a hot path (:func:`readout_batch`, the step engine's reading,
#: the realism kernel).
readout_inline = inline_twin(readout)


@numba.njit(cache=True)
def readout_batch(
    raw: np.ndarray, draws: np.ndarray, encoding: tuple, out: np.ndarray, eow_k: np.ndarray,
    codes: np.ndarray, keys: np.ndarray, flags: np.ndarray,
) -> None:  # fmt: skip
    """:func:`readout` of row ``r`` of ``raw``/``draws`` for every robot ``r``: writes
    ``keys[r]``, ``flags[r, 0]`` (Bump) and ``flags[r, 1]`` (goal close)."""
    for r in range(raw.shape[0]):
        key, bump, close = readout_inline(raw[r], draws[r], encoding, out[r], eow_k[r], codes[r])
        keys[r] = key
        flags[r, 0] = bump
        flags[r, 1] = close
