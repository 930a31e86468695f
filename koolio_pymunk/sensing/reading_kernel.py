"""One whole reading, compiled: the draws, the rays and cameras, the realism models, the
read-out: :meth:`SensorSuite.sense <koolio_pymunk.sensing.suite.SensorSuite.sense>`'s twin.

:func:`sense_reading` is ``KernelInputs.sense_readout`` without Python between its parts,
for the compiled step (:mod:`koolio_pymunk.task.step_kernel`): the reading's noise draws
from the robot's generator (the same scalar draws, one by one, as the reference's calls
with a size make), :func:`~.ray_kernel.sense_one` and :func:`~.encoding_kernel.readout`,
or with realism models on :func:`~.realism_kernel.sense_realism`. Its inputs are one
suite's kernel groups and buffers (:func:`reading_group`).

:class:`ReadingArrays` holds the inputs of N robots' readings (N suites of one
configuration) for a compiled loop that steps them in turn: what every robot shares once
(the rays' and cameras' geometry, the walls, the read-out), and a row per robot of what
is its own (its goal and the other plates, its realism models' parameters, its working
buffers); :func:`robot_group` makes robot ``r``'s :func:`reading_group` from them in
compiled code. (A tuple of thirty arrays taken out of a container costs thirty atomic
reference counts each way, about 0.2 µs, at every step; rows of shared arrays cost
nothing.) :meth:`ReadingArrays.load` takes a suite's configuration after its reset;
:meth:`ReadingArrays.store` gives it the last reading made in the rows, so that the suite's
:meth:`~koolio_pymunk.sensing.suite.SensorSuite.last` reads it.

**A shared world** (robots that see each other): :func:`sense_reading_among` is
:func:`sense_reading` with one more group, ``others`` =
``(robots, present, me, ray_robot, sonar_robot)``
(:data:`~koolio_pymunk.sensing.sensor_arrays.OTHERS`; :func:`~.ray_kernel.sense_among`):
the ``(N, 2)`` centres of all the robots and their ``(N,)`` flags (in the arena or
parked), which the caller keeps current, the reading robot's index, and the two buffers
the reading writes (per ray and per sonar, the robot hit; -1: a wall or nothing).
:func:`robot_others` makes robot ``r``'s group from :attr:`ReadingArrays.robot_rows` in
compiled code, as :func:`robot_group` makes its reading group, and :func:`robot_bump`
says whether a reading's Bump came from a robot. The same draws, in the same order, as
:func:`sense_reading`: a shared world changes what the rays meet, not the generator's
stream.
"""

from __future__ import annotations

import numba
import numpy as np

from ..store.kernel_cache import ensure_fresh
from .encoding_kernel import readout_inline
from .ray_kernel import new_wall_lists, sense_among_inline, sense_one_inline
from .realism_kernel import new_work, sense_realism, sense_realism_among

ensure_fresh()  # numba's cache, in step with every kernel's source (see there)


def reading_group(suite) -> tuple:
    """:func:`sense_reading`'s inputs for ``suite`` (a compiled-backend
    :class:`~koolio_pymunk.sensing.suite.SensorSuite`) as it is configured now: a
    domain-randomization draw or a new goal may replace some of its arrays, so the group
    is made again after each reset."""
    k = suite.kernel
    n_draws = suite.realism.n_draws
    flags = np.array([int(k.real_on), int(k.gaussian), k.n_raw, n_draws], np.int64)
    u = np.empty(k.n_raw + n_draws)  # the realism path's draws
    return (k.geometry, k.goal, k.plates, k.buffers, k.encoding, k.realism, k.noise, k.out,
            k.codes, flags, u)  # fmt: skip


@numba.njit(cache=True, inline="always")
def _realism_draws(rng, gaussian: bool, n_raw: int, n_draws: int, noise, u) -> None:
    """A reading's draws with a realism model on, one by one, in the reference's order:
    gaussian noise then the realism uniforms, or (uniform noise) all as uniforms."""
    if gaussian:
        for i in range(n_raw):
            noise[i] = rng.standard_normal()
        for i in range(n_draws):
            u[i] = rng.random()
    else:
        for i in range(n_raw + n_draws):
            u[i] = rng.random()


@numba.njit(cache=True, inline="always")
def _noise_draws(rng, gaussian: bool, n_raw: int, noise) -> None:
    """An ideal reading's noise draws, one by one (the paper's model: uniform in [-1, 1])."""
    if gaussian:
        for i in range(n_raw):
            noise[i] = rng.standard_normal()
    else:
        for i in range(n_raw):
            noise[i] = rng.uniform(-1.0, 1.0)


@numba.njit(cache=True)
def sense_reading(x: float, y: float, h: float, rng, sense: tuple) -> tuple[int, bool, bool]:
    """``KernelInputs.sense_readout`` at ``(x, y, h)``: ``(state key, bump, goal close)``,
    the reading left in the group's buffers. The draws go one by one into the buffers
    ``noise`` and, with realism models on, ``u`` (the generator's stream is that of its
    calls with a size), so the draws allocate no array. ``sense`` is :func:`reading_group`."""
    geometry, goal, plates, buffers, encoding, realism, noise, out, codes, flags, u = sense
    real_on, gaussian, n_raw, n_draws = flags[0] == 1, flags[1] == 1, flags[2], flags[3]
    if real_on:
        _realism_draws(rng, gaussian, n_raw, n_draws, noise, u)
        return sense_realism(x, y, h, geometry, goal, plates, buffers, noise, u, not gaussian,
                             realism, encoding, out, codes)  # fmt: skip
    sense_one_inline(x, y, h, geometry, goal, plates, buffers)
    _noise_draws(rng, gaussian, n_raw, noise)
    return readout_inline(buffers[0], noise, encoding, out, buffers[2], codes)


@numba.njit(cache=True)
def sense_reading_among(
    x: float, y: float, h: float, rng, sense: tuple, others: tuple
) -> tuple[int, bool, bool]:
    """:func:`sense_reading` of robot ``others[2]`` in a shared world (the module doc):
    the other robots of ``others`` seen, each sonar's robot (-1: none) left in its
    ``sonar_robot``; the same draws."""
    geometry, goal, plates, buffers, encoding, realism, noise, out, codes, flags, u = sense
    real_on, gaussian, n_raw, n_draws = flags[0] == 1, flags[1] == 1, flags[2], flags[3]
    if real_on:
        _realism_draws(rng, gaussian, n_raw, n_draws, noise, u)
        return sense_realism_among(x, y, h, geometry, goal, plates, buffers, noise, u,
                                   not gaussian, realism, encoding, out, codes,
                                   others)  # fmt: skip
    sense_among_inline(x, y, h, geometry, goal, plates, buffers, others)
    _noise_draws(rng, gaussian, n_raw, noise)
    return readout_inline(buffers[0], noise, encoding, out, buffers[2], codes)


@numba.njit(cache=True, inline="always")
def robot_bump(sense: tuple, others: tuple) -> bool:
    """The last reading of ``sense`` (:func:`reading_group`) read Bump from a robot: a
    sonar whose noised reading is below the first sonar threshold (the Bump rule) read a
    robot's surface (``others``' ``sonar_robot``, :func:`sense_reading_among`)."""
    encoding, out = sense[4], sense[7]
    n_sonar, bump_below = encoding[1], encoding[3][0]
    sonar_robot = others[4]
    found = False
    for s in range(n_sonar):
        if out[s] < bump_below and sonar_robot[s] >= 0:
            found = True
    return found


class ReadingArrays:
    """The reading inputs of N sensor suites of one configuration, a row per robot
    (module doc): ``shared`` and ``rows`` are :func:`robot_group`'s arguments."""

    def __init__(self, suites: list) -> None:
        k = suites[0].kernel
        n = len(suites)
        real = suites[0].realism
        g = k.geometry
        work = new_work(k.ray_offsets.shape[0], real.params)
        self.shared = (g[0], g[1], g[3], g[4], g[5], k.encoding, real.neighbours,
                       new_wall_lists(g[5]), work)  # fmt: skip
        """Shared by every robot: ray offsets and units, camera directions, markers, walls;
        the read-out's group; the sonars' neighbours; the readings' working space (the
        lists of walls, the sonar models' values: the robots read one after another)."""
        n_plates = len(suites[0].plates)
        self.n_plates = np.zeros(n, np.int64)
        self.rows = (
            np.zeros((n, len(k.params))),  # the geometry's params (incidence on or off)
            np.zeros((n, 2)),  # goal
            np.zeros((n, n_plates, 2)),  # the other plates (misread model)
            self.n_plates,
            np.zeros((n, *k.raw.shape)),
            np.zeros((n, *k.rays.shape)),
            np.zeros((n, *k.eow_k.shape), np.int64),
            np.stack([k.trig] * n),
            np.zeros((n, *k.ray_cos.shape)),
            np.zeros((n, *k.decoy.shape)),
            np.zeros((n, len(real.params))),
            np.zeros((n, len(real.flags)), np.bool_),
            np.zeros((n, *k.echo.shape), np.bool_),
            np.zeros((n, *k.crossed.shape), np.bool_),
            np.zeros((n, *k.missed.shape), np.bool_),
            np.zeros((n, *k.misread.shape), np.bool_),
            np.zeros((n, k.n_raw)),  # noise
            np.zeros((n, *k.out.shape)),
            np.zeros((n, *k.codes.shape), np.int64),
            np.zeros((n, 4), np.int64),  # real on, gaussian, n_raw, n_draws
            np.zeros((n, k.n_raw + real.n_draws)),  # the realism path's draws
        )
        """Per robot: :func:`robot_group`'s rows."""
        self.robot_rows = (
            np.full((n, *k.ray_robot.shape), -1, np.int64),
            np.full((n, *k.sonar_robot.shape), -1, np.int64),
        )
        """Per robot, in a shared world: the robot each ray hit and each sonar read
        (-1: a wall or nothing): :func:`robot_others`' rows."""

    def load(self, r: int, suite) -> None:
        """Robot ``r``'s configuration from ``suite`` (after its reset: a
        domain-randomization draw or a new goal may have changed it), and its last
        reading (:meth:`take`)."""
        k, real = suite.kernel, suite.realism
        rows = self.rows
        rows[0][r] = k.params
        rows[1][r] = k.goal
        plates = k.plates
        self.n_plates[r] = len(plates)
        rows[2][r, : len(plates)] = plates
        rows[10][r] = real.params
        rows[11][r] = real.flags
        rows[19][r] = (int(k.real_on), int(k.gaussian), k.n_raw, real.n_draws)
        self.take(r, suite)

    def take(self, r: int, suite) -> None:
        """``suite``'s last reading (made in Python: a reset's) into robot ``r``'s rows."""
        for i, buf in self._buffers(suite):
            self.rows[i][r] = buf
        k = suite.kernel
        self.robot_rows[0][r] = k.ray_robot
        self.robot_rows[1][r] = k.sonar_robot

    def store(self, r: int, suite) -> None:
        """Robot ``r``'s last reading into ``suite``'s buffers (its :meth:`last` then
        reads it)."""
        for i, buf in self._buffers(suite):
            buf[...] = self.rows[i][r]
        k = suite.kernel
        k.ray_robot[...] = self.robot_rows[0][r]
        k.sonar_robot[...] = self.robot_rows[1][r]
        suite.forget_last()

    @staticmethod
    def _buffers(suite) -> tuple:
        """The suite's reading buffers with their row's index."""
        k = suite.kernel
        return ((4, k.raw), (5, k.rays), (6, k.eow_k), (7, k.trig), (8, k.ray_cos),
                (9, k.decoy), (12, k.echo), (13, k.crossed), (14, k.missed), (15, k.misread),
                (16, k.noise), (17, k.out), (18, k.codes))  # fmt: skip


@numba.njit(cache=True, inline="always")
def robot_group(r: int, shared: tuple, rows: tuple) -> tuple:
    """Robot ``r``'s :func:`reading_group` (:class:`ReadingArrays`)."""
    (ray_offsets, ray_units, camera_dirs, markers, walls, encoding, neighbours, wall_lists,
     work) = shared  # fmt: skip
    (params, goal, plates, n_plates, raw, rays, eow_k, trig, ray_cos, decoy, rparams, rflags,
     echo, crossed, missed, misread, noise, out, codes, flags, u) = rows  # fmt: skip
    geometry = (ray_offsets, ray_units, params[r], camera_dirs, markers, walls)
    buffers = (raw[r], rays[r], eow_k[r], trig[r], ray_cos[r], decoy[r], wall_lists)
    realism = (rparams[r], rflags[r], neighbours, echo[r], crossed[r], missed[r], misread[r],
               work)  # fmt: skip
    return (geometry, goal[r], plates[r, : n_plates[r]], buffers, encoding, realism, noise[r],
            out[r], codes[r], flags[r], u[r])  # fmt: skip


@numba.njit(cache=True, inline="always")
def robot_others(r: int, robots: np.ndarray, present: np.ndarray, robot_rows: tuple) -> tuple:
    """Robot ``r``'s ``others`` group for :func:`sense_reading_among`: every robot's
    centre ``robots`` (``(N, 2)`` float64) and flag ``present`` (``(N,)`` bool: in the
    arena), ``r`` itself, and its rows of :attr:`ReadingArrays.robot_rows`."""
    ray_robot, sonar_robot = robot_rows
    return (robots, present, r, ray_robot[r], sonar_robot[r])
