"""The sonar and camera realism models, compiled: the hot-path copy of
:func:`koolio_pymunk.sensing.realism.apply_reference`.

:func:`apply_realism` does, operation for operation and with the same uniform draws,
what the reference does (echo of every sub-arc ray, crosstalk, the four-part beam model,
the minimum range, misread plates and missed detections), so both give the same
readings bit for bit; ``tests/sensing/test_realism.py`` and ``tools/agreement.py`` check it.
:func:`sense_realism` is the learner's hot path in a realistic world: the sensing kernel
(:func:`~.ray_kernel.sense_one`), the models and the read-out
(:func:`~.encoding_kernel.readout`) in
one call, finding the other plates in view only for a camera whose misread draw fired
(the reference finds them for every camera; only those are used).
The parameter layout (``params``, ``flags``) is
:class:`koolio_pymunk.sensing.realism.SensorRealism`'s.

In a shared world :func:`sense_realism_among` is the same reading with the other robots
(:func:`~.ray_kernel.sense_among`) and :func:`sonar_sources`, the compiled
:func:`~koolio_pymunk.sensing.realism.robot_sources`: which robot each sonar's reading
came from once the echo and crosstalk models chose it.

**One compiled function per reading.** A numba call that passes arrays increments and
decrements each array's reference count, an atomic operation: with the models in
functions of their own, a third of a realistic reading's perf samples were in
``NRT_incref``/``NRT_decref`` (``docs/speed.md``). So the models' helpers are compiled inline
into their caller (``inline="always"``), and :func:`sense_realism` calls the inline twins
of :func:`~.ray_kernel.sense_one` and :func:`~.encoding_kernel.readout` (the same Python
functions compiled a second time, with the functions they call that take arrays:
:mod:`~.inline_twins`; the cameras stay a call of :func:`~.ray_kernel.camera_readings`);
the draws are read at an offset (``base``) instead of through a view. The arithmetic is
the same operations in the same order (no fastmath), so the readings are the same bits.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ..store.kernel_cache import ensure_fresh
from .encoding_kernel import readout_inline
from .ray_kernel import (
    camera_readings,
    camera_readings_among,
    sense_among_inline,
    sense_one_inline,
)
from .realism import (
    F_BEAM,
    F_CAMERA,
    F_CROSSTALK,
    F_DETECT,
    F_INCIDENCE,
    F_MISREAD,
    F_RANGE,
    F_SONAR,
    P_COS_LIMIT,
    P_CROSSTALK,
    P_DETECT_FAR,
    P_DETECT_NEAR,
    P_FAR,
    P_LAMBDA,
    P_LENGTH,
    P_MIN_RANGE,
    P_MISREAD,
    P_PING_DRAWS,
    P_PINGS,
    P_RADIUS,
    P_RANGE,
    P_SIGMA,
    P_VIEW,
    P_Z_HIT,
    P_Z_MAX,
    P_Z_SHORT,
)

ensure_fresh()  # numba's cache, in step with every kernel's source (see there)


@numba.njit(cache=True, inline="always")
def _gaussian(u1: float, u2: float) -> float:
    return math.sqrt(-2.0 * math.log(1.0 - u1)) * math.cos(2.0 * math.pi * u2)


@numba.njit(cache=True, inline="always")
def _beam(z: float, u0: float, u1: float, u2: float, p: np.ndarray) -> float:
    far = p[P_FAR]
    top_range = p[P_RANGE]
    c_hit = p[P_Z_HIT]
    c_short = c_hit + p[P_Z_SHORT]
    c_max = c_short + p[P_Z_MAX]
    if u0 < c_hit:
        if z < far:
            z = z + p[P_SIGMA] * _gaussian(u1, u2)
            if z >= top_range:
                z = far
        return z
    if u0 < c_short:
        top = z if z < far else top_range
        lam = p[P_LAMBDA]
        return -math.log(1.0 - u1 * (1.0 - math.exp(-lam * top))) / lam
    if u0 < c_max:
        return far
    return u1 * top_range


@numba.njit(cache=True, inline="always")
def _detect(d: float, p: np.ndarray) -> float:
    near = p[P_DETECT_NEAR]
    return near + (p[P_DETECT_FAR] - near) * min(d / p[P_VIEW], 1.0)


@numba.njit(cache=True)
def new_work(n_sonar: int, params: np.ndarray) -> np.ndarray:
    """Room for the sonar models' working values (:func:`_sonar`: the readings before
    crosstalk, a sonar's pings' echoes) for the models' ``params``: the reading allocates
    nothing."""
    return np.zeros(n_sonar + max(1, int(params[P_PINGS])))


@numba.njit(cache=True, inline="always")
def _sonar(
    raw: np.ndarray,
    rays: np.ndarray,
    ray_cos: np.ndarray,
    draws: np.ndarray,
    base: int,
    p: np.ndarray,
    f: np.ndarray,
    neighbours: np.ndarray,
    echo: np.ndarray,
    crossed: np.ndarray,
    work: np.ndarray,
) -> None:
    """The sonar models; sonar ``s``'s draws are ``draws[base + 4 s : base + 4 s + 4]``.
    The nearest echo goes straight into ``raw`` (only when a sonar model is on).
    ``work`` (:func:`new_work`) holds the readings before crosstalk and each sonar's
    pings."""
    n, n_sub = rays.shape
    far = p[P_FAR]
    radius = p[P_RADIUS]
    reach = p[P_LENGTH] - 1e-9
    top, cos_limit = p[P_RANGE], p[P_COS_LIMIT]
    in_range, incidence, sonar_on = f[F_RANGE], f[F_INCIDENCE], f[F_SONAR]
    for s in range(n):
        best = np.inf
        for i in range(n_sub):
            d = rays[s, i]
            e = d <= reach
            if e and in_range:
                e = (d - radius) < top
            if e and incidence:
                e = ray_cos[s, i] >= cos_limit
            echo[s, i] = e
            if e and d < best:
                best = d
        if sonar_on:
            raw[s] = far if best == np.inf else best - radius
        crossed[s] = False
    if not sonar_on:
        return
    if f[F_CROSSTALK]:
        chance = p[P_CROSSTALK]
        before = work[:n]
        for s in range(n):
            before[s] = raw[s]
        for s in range(n):
            u = draws[base + 4 * s + 3]
            if u < chance:
                nb = neighbours[s, 0] if u < chance * 0.5 else neighbours[s, 1]
                if before[nb] < raw[s]:
                    raw[s] = before[nb]
                    crossed[s] = True
    beam, min_range = f[F_BEAM], p[P_MIN_RANGE]
    pings = int(p[P_PINGS])
    extra = base + int(p[P_PING_DRAWS])
    heard = work[n : n + pings]
    for s in range(n):
        v = raw[s]
        if beam:
            k = base + 4 * s
            v0 = v
            v = _beam(v0, draws[k], draws[k + 1], draws[k + 2], p)
            if pings > 1:
                heard[0] = v
                for j in range(1, pings):
                    k = extra + 3 * ((j - 1) * n + s)
                    _insert(heard, j, _beam(v0, draws[k], draws[k + 1], draws[k + 2], p))
                v = heard[pings // 2]
        if min_range > 0.0 and v < min_range:
            v = min_range
        raw[s] = v


@numba.njit(cache=True, inline="always")
def _insert(sorted_head: np.ndarray, j: int, v: float) -> None:
    """Insert ``v`` into the sorted ``sorted_head[:j]`` (insertion sort's step)."""
    i = j
    while i > 0 and sorted_head[i - 1] > v:
        sorted_head[i] = sorted_head[i - 1]
        i -= 1
    sorted_head[i] = v


@numba.njit(cache=True, inline="always")
def _cameras(
    raw: np.ndarray,
    n: int,
    decoy: np.ndarray,
    draws: np.ndarray,
    base: int,
    p: np.ndarray,
    f: np.ndarray,
    missed: np.ndarray,
    misread: np.ndarray,
) -> None:
    m = decoy.shape[0]
    far = p[P_FAR]
    for c in range(m):
        missed[c, 0] = False
        missed[c, 1] = False
        misread[c] = False
        if not f[F_CAMERA]:
            continue
        k = base + 4 * n + 3 * c
        goal = raw[n + c]
        if f[F_MISREAD] and decoy[c] < far and draws[k] < p[P_MISREAD]:
            goal = decoy[c]
            misread[c] = True
        eow = raw[n + m + c]
        if f[F_DETECT]:
            if goal < far and draws[k + 1] >= _detect(goal, p):
                goal = far
                missed[c, 0] = True
                misread[c] = False
            if eow < far and draws[k + 2] >= _detect(eow, p):
                eow = far
                missed[c, 1] = True
        raw[n + c] = goal
        raw[n + m + c] = eow


@numba.njit(cache=True)
def apply_realism(
    raw: np.ndarray,
    rays: np.ndarray,
    ray_cos: np.ndarray,
    decoy: np.ndarray,
    draws: np.ndarray,
    params: np.ndarray,
    flags: np.ndarray,
    neighbours: np.ndarray,
    echo: np.ndarray,
    crossed: np.ndarray,
    missed: np.ndarray,
    misread: np.ndarray,
) -> None:
    """The sonar and camera models on the noise-free reading ``raw`` (in place).

    Writes every sub-arc ray's ``echo``, the sonars that took a neighbour's echo
    (``crossed``), the cameras' missed detections (``missed[c] = [goal, marker]``) and
    misread plates; the sonar entries of ``raw`` are only rewritten when a sonar model
    is on, the camera entries when a camera model is on (see the reference).

    Why it ships though only the tests call it: it is the models alone, compiled, the
    same model functions that :func:`sense_realism` runs inline between the reading and
    the read-out, so ``tests/sensing/test_realism.py`` can hold them to the reference
    :func:`~koolio_pymunk.sensing.realism.apply_reference` reading by reading, on the
    same draws.
    """
    n = rays.shape[0]
    work = new_work(n, params)
    _sonar(raw, rays, ray_cos, draws, 0, params, flags, neighbours, echo, crossed, work)
    _cameras(raw, n, decoy, draws, 0, params, flags, missed, misread)


@numba.njit(cache=True, inline="always")
def sense_realism(x: float, y: float, h: float, geometry: tuple, goal: np.ndarray,
                  plates: np.ndarray, buffers: tuple, noise: np.ndarray, u: np.ndarray,
                  noise_from_u: bool, realism: tuple, encoding: tuple, out: np.ndarray,
                  codes: np.ndarray) -> tuple[int, bool, bool]:  # fmt: skip
    """One reading in a realistic world: ``(state_key, bump, goal_close)``.

    :func:`~.ray_kernel.sense_one` (without other plates), then, per camera whose misread
    draw ``u[4 n + 3 c] < misread``, the nearest of ``plates`` in its arc and in sight
    (``decoy``; far for the others), :func:`apply_realism`'s models with the uniforms
    ``u``, and :func:`~.encoding_kernel.readout` with the noise draws ``noise``. With
    ``noise_from_u`` (the uniform noise model) ``u`` holds both, from one generator call
    (or as many scalar draws: the same values): first the readings' uniforms, turned into
    ``noise`` as ``rng.uniform(-1, 1)`` turns them (``-1 + 2 u``), then the realism
    uniforms."""
    params, camera_dirs, walls = geometry[2], geometry[3], geometry[5]
    raw, rays, eow_k, _, ray_cos, decoy, _ = buffers
    rparams, rflags, neighbours, echo, crossed, missed, misread, work = realism
    n_sonar = encoding[1]
    m = raw.shape[0]
    base = 0  # where the realism uniforms start in u
    if noise_from_u:
        for i in range(m):
            noise[i] = -1.0 + 2.0 * u[i]
        base = m
    sense_one_inline(x, y, h, geometry, goal, plates[:0], buffers)
    far = params[2]
    misread_on, misread_chance = rflags[F_MISREAD], rparams[P_MISREAD]
    for c in range(camera_dirs.shape[0]):
        decoy[c] = far
        if misread_on and u[base + 4 * n_sonar + 3 * c] < misread_chance:
            camera_readings(x, y, h, camera_dirs[c : c + 1], plates, params[3], params[1], far,
                            walls, decoy[c : c + 1], eow_k[:0])  # fmt: skip
    _sonar(raw, rays, ray_cos, u, base, rparams, rflags, neighbours, echo, crossed, work)
    _cameras(raw, n_sonar, decoy, u, base, rparams, rflags, missed, misread)
    return readout_inline(raw, noise, encoding, out, eow_k, codes)


@numba.njit(cache=True, inline="always")
def sonar_sources(
    rays: np.ndarray, echo: np.ndarray, crossed: np.ndarray, ray_robot: np.ndarray,
    draws: np.ndarray, base: int, p: np.ndarray, f: np.ndarray, neighbours: np.ndarray,
    sonar_robot: np.ndarray,
) -> None:  # fmt: skip
    """:func:`~koolio_pymunk.sensing.realism.robot_sources` in place: ``sonar_robot``
    (the noise-free reading's sources) rewritten, when a sonar model is on, from the
    echoes and the crosstalk :func:`_sonar` left (its draws at ``base``)."""
    if not f[F_SONAR]:
        return
    n, n_sub = rays.shape
    for s in range(n):
        best = np.inf
        who = -1
        for i in range(n_sub):
            if echo[s, i] and rays[s, i] < best:
                best = rays[s, i]
                who = ray_robot[s, i]
        sonar_robot[s] = who
    if f[F_CROSSTALK]:
        before = sonar_robot.copy()
        chance = p[P_CROSSTALK]
        for s in range(n):
            if crossed[s]:
                u = draws[base + 4 * s + 3]
                nb = neighbours[s, 0] if u < chance * 0.5 else neighbours[s, 1]
                sonar_robot[s] = before[nb]


@numba.njit(cache=True, inline="always")
def sense_realism_among(x: float, y: float, h: float, geometry: tuple, goal: np.ndarray,
                        plates: np.ndarray, buffers: tuple, noise: np.ndarray, u: np.ndarray,
                        noise_from_u: bool, realism: tuple, encoding: tuple, out: np.ndarray,
                        codes: np.ndarray, others: tuple) -> tuple[int, bool, bool]:  # fmt: skip
    """:func:`sense_realism` in a shared world: the reading with the other robots of
    ``others`` (:func:`~.ray_kernel.sense_among`; they block the misread model's other
    plates too), the models, then each sonar's source (:func:`sonar_sources`) into
    ``others``' ``sonar_robot``."""
    params, camera_dirs, walls = geometry[2], geometry[3], geometry[5]
    raw, rays, eow_k, _, ray_cos, decoy, _ = buffers
    rparams, rflags, neighbours, echo, crossed, missed, misread, work = realism
    robots, present, me, ray_robot, sonar_robot = others
    n_sonar = encoding[1]
    m = raw.shape[0]
    base = 0  # where the realism uniforms start in u
    if noise_from_u:
        for i in range(m):
            noise[i] = -1.0 + 2.0 * u[i]
        base = m
    sense_among_inline(x, y, h, geometry, goal, plates[:0], buffers, others)
    far = params[2]
    misread_on, misread_chance = rflags[F_MISREAD], rparams[P_MISREAD]
    scene = (walls, robots, present, me, params[1])
    for c in range(camera_dirs.shape[0]):
        decoy[c] = far
        if misread_on and u[base + 4 * n_sonar + 3 * c] < misread_chance:
            camera_readings_among(x, y, h, camera_dirs[c : c + 1], plates, params[3], params[1],
                                  far, scene, decoy[c : c + 1], eow_k[:0])  # fmt: skip
    _sonar(raw, rays, ray_cos, u, base, rparams, rflags, neighbours, echo, crossed, work)
    sonar_sources(rays, echo, crossed, ray_robot, u, base, rparams, rflags, neighbours,
                  sonar_robot)  # fmt: skip
    _cameras(raw, n_sonar, decoy, u, base, rparams, rflags, missed, misread)
    return readout_inline(raw, noise, encoding, out, eow_k, codes)
