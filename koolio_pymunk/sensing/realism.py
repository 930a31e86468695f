"""Realism models: what a real Koolio meets that the paper's ideal simulator leaves out.

The paper's simulator "assume[s] that the model is perfect" (§5.3): every sonar sub-arc
ray returns the nearest wall at any angle, a straight move is straight, a camera always
sees and always reads the right plate. This module describes the *reality gap* as
configuration (the ``realism`` section, which a world such as ``--world koolio-real``
sets) and holds the reference implementation of every model. Each model is **off by
default** (its neutral value), and a model that is off costs nothing and draws nothing
from the generator, so the ideal world stays byte-identical.

**Sonar** (ultrasonic physics, :class:`SonarRealism`), applied to each reading before
the paper's noise, in this order:

1. *echo*: a sub-arc ray echoes when it hits a wall within the ray length, within the
   ranger's maximum range ``max_range`` (edge distance), and no more than
   ``max_incidence_deg`` from the wall's normal (a smooth wall met at a grazing angle
   reflects the pulse away: specular reflection). The sonar reads the nearest echo, or
   ``really_long_distance`` (nothing seen, encodes Far) when no ray echoes;
2. *crosstalk*: with probability ``crosstalk`` a sonar hears a neighbour's echo (its
   left or right neighbour on the ring, equally likely) and reads it if it is nearer;
3. *beam model* (*Probabilistic Robotics*, ch. 6.3): the reading is drawn from a mixture
   with weights ``z_hit`` (Gaussian around the true range, ``sigma_hit``), ``z_short``
   (an unexpected near echo: exponential with rate ``lambda_short``, truncated at the
   true range), ``z_max`` (a dropout: no echo) and ``z_rand`` (uniform over the range);
   with ``sensors.sonar.pings`` k > 1 the robot pings k times and reads the median of
   k such draws (a lone wrong echo is dropped);
4. *minimum range*: a reading below ``min_range`` reads ``min_range``.

**Cameras** (:class:`CameraRealism`): a camera with another door's plate in view takes
it for the goal with probability ``misread``; then each target in view (the goal plate,
the nearest end-of-world marker) is detected with a probability falling linearly from
``detect_near`` at 0 in to ``detect_far`` at ``max_camera_view``; a missed detection
reads "not seen".

**Motion** (:class:`MotionRealism`, :class:`MotionErrors`): a Forward or Reverse move
drifts by ``drift_deg`` (plus a Gaussian ``drift_sigma_deg``) and travels
``1 + N(0, slip_sigma)`` of its distance; a turn is off by ``N(0, turn_sigma_deg)``.
The move is given to pymunk as one velocity along the chord of the arc it drives, so
pymunk still resolves every contact (:meth:`World.drive`).

**Domain randomization** (``randomize``): each episode draws the listed parameters
uniformly from their ranges (:class:`Randomizer`); the draw is logged.

Every random number comes from the environment's generator. A reading with any sonar
or camera model on draws ``4 * n_sonar + 3 * n_camera`` uniforms in one call (and
``3 * n_sonar`` more per extra ping, after those), after the paper's noise draws
(:func:`realism_draw_count`), and the compiled kernel
(:mod:`koolio_pymunk.sensing.realism_kernel`) uses them exactly as :func:`apply_reference`
does here, so both give the same readings bit for bit (``tests/sensing/test_realism.py``).

Example (the reference on one sonar of two rays and one camera; off models change
nothing)::

    >>> import numpy as np
    >>> cfg = RealismConfig()
    >>> cfg.sonar.max_incidence_deg = 40.0
    >>> model = SensorRealism(cfg, sonar_deg=[0.0], n_camera=1, radius=10.0,
    ...                       ray_length=250.0, far=10_000.0, max_camera_view=240.0)
    >>> raw = np.array([20.0, 50.0, 10_000.0, 64.0])   # sonar, goal, eow, compass
    >>> rays = np.array([[30.0, 45.0]])                 # centre distances of the 2 rays
    >>> cos = np.cos(np.radians([[80.0, 10.0]]))        # incidence 80 and 10 degrees
    >>> out = apply_reference(model, raw, rays, cos, np.full(1, 10_000.0),
    ...                       np.zeros(model.n_draws))
    >>> float(out.raw[0]), out.echo.tolist()
    (35.0, [[False, True]])
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..store.realism_config import RealismConfig, beam_on, camera_on, sonar_on

# --- configuration -------------------------------------------------------------------


# --- validation ----------------------------------------------------------------------


# --- what is on ----------------------------------------------------------------------


def realism_draw_count(n_sonar: int, n_camera: int, pings: int = 1) -> int:
    """Uniform draws of one reading with a sonar or camera model on: per sonar the beam
    component, two values and the crosstalk draw; per camera the misread, goal detection
    and marker detection draws; then per extra ping and sonar the beam's three draws
    (:func:`ping_draw`).

    >>> realism_draw_count(8, 3), realism_draw_count(8, 3, pings=3)
    (41, 89)
    """
    return 4 * n_sonar + 3 * n_camera + 3 * (pings - 1) * n_sonar


def ping_draw(n_sonar: int, n_camera: int, sonar: int, ping: int) -> int:
    """Index of the first of the beam model's three draws for ``ping`` (0-based) of
    ``sonar``: ping 0 uses the sonar's own four (``4 * sonar``), so one ping draws as
    before pings existed; the others come after the cameras', ping by ping.

    >>> ping_draw(8, 3, sonar=2, ping=0), ping_draw(8, 3, sonar=2, ping=1)
    (8, 47)
    """
    if ping == 0:
        return 4 * sonar
    return 4 * n_sonar + 3 * n_camera + 3 * ((ping - 1) * n_sonar + sonar)


# --- sensor models: parameters and the reference --------------------------------------

#: Indices of :attr:`SensorRealism.params` (shared with the compiled kernel).
P_COS_LIMIT, P_RANGE, P_MIN_RANGE, P_CROSSTALK = 0, 1, 2, 3
P_Z_HIT, P_Z_SHORT, P_Z_MAX, P_Z_RAND, P_SIGMA, P_LAMBDA = 4, 5, 6, 7, 8, 9
P_DETECT_NEAR, P_DETECT_FAR, P_VIEW, P_MISREAD = 10, 11, 12, 13
P_RADIUS, P_FAR, P_LENGTH = 14, 15, 16
P_PINGS, P_PING_DRAWS = 17, 18  # pings per reading; where the extra pings' draws start
N_PARAMS = 19
#: Indices of :attr:`SensorRealism.flags`.
F_SONAR, F_INCIDENCE, F_RANGE, F_CROSSTALK, F_BEAM, F_CAMERA, F_DETECT, F_MISREAD = range(8)
N_FLAGS = 8


class SensorRealism:
    """The sonar and camera models of one sensor suite, as arrays for both implementations.

    ``params`` (:data:`N_PARAMS` floats) and ``flags`` (:data:`N_FLAGS` booleans) are
    refreshed in place by :meth:`configure` (domain randomization does it each episode),
    so a compiled caller can keep references to them.
    """

    def __init__(
        self,
        cfg: RealismConfig,
        sonar_deg: Sequence[float],
        n_camera: int,
        radius: float,
        ray_length: float,
        far: float,
        max_camera_view: float,
        pings: int = 1,
    ) -> None:
        self.n_sonar = len(sonar_deg)
        self.pings = int(pings)
        self.n_camera = int(n_camera)
        self.radius = float(radius)
        self.ray_length = float(ray_length)
        self.far = float(far)
        self.max_camera_view = float(max_camera_view)
        self.sensor_range = self.ray_length - self.radius
        self.neighbours = ring_neighbours(sonar_deg)
        self.params = np.zeros(N_PARAMS)
        self.flags = np.zeros(N_FLAGS, np.bool_)
        self.configure(cfg)

    def configure(self, cfg: RealismConfig) -> None:
        """Take the model parameters of ``cfg`` (in place)."""
        so, ca = cfg.sonar, cfg.camera
        p, f = self.params, self.flags
        rng_max = (
            self.sensor_range if so.max_range is None else min(so.max_range, self.sensor_range)
        )
        p[P_COS_LIMIT] = math.cos(math.radians(so.max_incidence_deg))
        p[P_RANGE] = rng_max
        p[P_MIN_RANGE] = so.min_range
        p[P_CROSSTALK] = so.crosstalk
        p[P_Z_HIT], p[P_Z_SHORT], p[P_Z_MAX], p[P_Z_RAND] = (
            so.z_hit,
            so.z_short,
            so.z_max,
            so.z_rand,
        )
        p[P_SIGMA] = so.sigma_hit
        p[P_LAMBDA] = so.lambda_short
        p[P_DETECT_NEAR], p[P_DETECT_FAR] = ca.detect_near, ca.detect_far
        p[P_VIEW] = self.max_camera_view
        p[P_MISREAD] = ca.misread
        p[P_RADIUS], p[P_FAR], p[P_LENGTH] = self.radius, self.far, self.ray_length
        p[P_PINGS] = self.pings
        p[P_PING_DRAWS] = realism_draw_count(self.n_sonar, self.n_camera)
        f[F_SONAR] = sonar_on(cfg)
        f[F_INCIDENCE] = so.max_incidence_deg < 90.0
        f[F_RANGE] = so.max_range is not None
        f[F_CROSSTALK] = so.crosstalk > 0.0
        f[F_BEAM] = beam_on(cfg)
        f[F_CAMERA] = camera_on(cfg)
        f[F_DETECT] = ca.detect_near < 1.0 or ca.detect_far < 1.0
        f[F_MISREAD] = ca.misread > 0.0

    @property
    def on(self) -> bool:
        """A reading goes through the models (draws are made)."""
        return bool(self.flags[F_SONAR] or self.flags[F_CAMERA])

    @property
    def incidence(self) -> bool:
        """Rays need their incidence (the ray engine reports it)."""
        return bool(self.flags[F_INCIDENCE])

    @property
    def misread(self) -> bool:
        """Cameras need the nearest other plate in view."""
        return bool(self.flags[F_MISREAD])

    @property
    def n_draws(self) -> int:
        """Uniform draws per reading (:func:`realism_draw_count`)."""
        return realism_draw_count(self.n_sonar, self.n_camera, self.pings)


def ring_neighbours(sonar_deg: Sequence[float]) -> np.ndarray:
    """``(n, 2)``: each sonar's neighbours on the ring, by angle (clockwise, then
    anticlockwise; a sonar alone is its own neighbour).

    >>> ring_neighbours([0.0, 40.0, 80.0, 135.0, 180.0, -40.0, -80.0, -135.0]).tolist()[:2]
    [[5, 1], [0, 2]]
    """
    angles = [((a + 180.0) % 360.0) - 180.0 for a in sonar_deg]
    order = sorted(range(len(angles)), key=lambda k: (angles[k], k))
    out = np.empty((len(angles), 2), np.int64)
    for pos, k in enumerate(order):
        out[k, 0] = order[pos - 1]
        out[k, 1] = order[(pos + 1) % len(order)]
    return out


@dataclass
class RealReading:
    """What the sensor models made of one noise-free reading."""

    raw: np.ndarray
    """The readings after the models (before the paper's noise)."""
    echo: np.ndarray
    """Per sonar sub-arc ray: it got an echo."""
    crosstalk: np.ndarray
    """Per sonar: it read a neighbour's echo."""
    missed: np.ndarray
    """Per camera ``[goal, end-of-world]``: a target in view was not detected."""
    misread: np.ndarray
    """Per camera: its goal reading is another door's plate."""


def gaussian(u1: float, u2: float) -> float:
    """A standard normal value from two uniforms in [0, 1) (Box-Muller, cosine branch)."""
    return math.sqrt(-2.0 * math.log(1.0 - u1)) * math.cos(2.0 * math.pi * u2)


def apply_reference(
    model: SensorRealism,
    raw: np.ndarray,
    rays: np.ndarray,
    ray_cos: np.ndarray,
    decoy: np.ndarray,
    draws: np.ndarray,
) -> RealReading:
    """The sonar and camera models on one noise-free reading (the reference).

    ``raw`` = ``[sonar..., goal cam..., end-of-world cam..., compass]`` (edge distances);
    ``rays`` the centre distance of every sub-arc ray (``ray_length`` when it hits
    nothing), ``ray_cos`` the cosine of each ray's incidence, ``decoy`` per camera the
    nearest other plate in view (far: none), ``draws`` :attr:`SensorRealism.n_draws`
    uniforms in [0, 1). Returns a new array; the inputs are left alone.
    """
    p, f = model.params, model.flags
    n = rays.shape[0]
    m = decoy.shape[0]
    far = p[P_FAR]
    out = raw.copy()
    echo = rays <= p[P_LENGTH] - 1e-9
    if f[F_RANGE]:
        echo &= (rays - p[P_RADIUS]) < p[P_RANGE]
    if f[F_INCIDENCE]:
        echo &= ray_cos >= p[P_COS_LIMIT]
    crossed = np.zeros(n, np.bool_)
    if f[F_SONAR]:
        nearest = np.where(echo, rays, np.inf).min(axis=1)
        z = np.where(np.isinf(nearest), far, nearest - p[P_RADIUS])
        if f[F_CROSSTALK]:
            z, crossed = _crosstalk(z, draws, model.neighbours, p[P_CROSSTALK])
        for s in range(n):
            if f[F_BEAM]:
                pings = [
                    _beam(float(z[s]), draws[k : k + 3], p)
                    for k in (ping_draw(n, m, s, j) for j in range(model.pings))
                ]
                z[s] = sorted(pings)[len(pings) // 2]
            if p[P_MIN_RANGE] > 0.0 and z[s] < p[P_MIN_RANGE]:
                z[s] = p[P_MIN_RANGE]
        out[:n] = z
    missed = np.zeros((m, 2), np.bool_)
    misread = np.zeros(m, np.bool_)
    if f[F_CAMERA]:
        for c in range(m):
            _camera_models(
                out,
                n,
                m,
                c,
                decoy[c],
                draws[4 * n + 3 * c : 4 * n + 3 * c + 3],
                p,
                f,
                missed,
                misread,
            )
    return RealReading(out, echo, crossed, missed, misread)


def robot_sources(
    model: SensorRealism,
    rays: np.ndarray,
    echo: np.ndarray,
    crossed: np.ndarray,
    ray_robot: np.ndarray,
    draws: np.ndarray,
    ideal: np.ndarray,
) -> np.ndarray:
    """Per sonar, the robot whose surface its reading comes from after the sonar models
    (a shared world; -1: a wall, or no echo): the reference.

    ``ideal`` is the noise-free reading's (the nearest ray's robot), kept when no sonar
    model is on. With one on, a sonar reads its nearest *echoing* ray (the first at the
    least distance among those :func:`apply_reference` says echoed: ``echo``), so its
    source is that ray's robot (``ray_robot``), -1 when none echoed; a sonar that took a
    neighbour's echo (``crossed``, crosstalk) takes the neighbour's source, the neighbour
    its draw chose. The beam model, the minimum range and the paper's noise change the
    distance read, not where the echo came from.
    """
    if not model.flags[F_SONAR]:
        return ideal.copy()
    n = rays.shape[0]
    masked = np.where(echo, rays, np.inf)
    first = masked.argmin(axis=1)
    source = np.where(np.isinf(masked.min(axis=1)), -1, ray_robot[np.arange(n), first])
    out = source.copy()
    chance = model.params[P_CROSSTALK]
    for s in np.flatnonzero(crossed):
        u = draws[4 * s + 3]
        nb = model.neighbours[s, 0] if u < chance * 0.5 else model.neighbours[s, 1]
        out[s] = source[nb]
    return out


def _crosstalk(
    z: np.ndarray, draws: np.ndarray, neighbours: np.ndarray, chance: float
) -> tuple[np.ndarray, np.ndarray]:
    """Each sonar may take its left or right neighbour's (pre-crosstalk) echo."""
    out = z.copy()
    crossed = np.zeros(z.shape[0], np.bool_)
    for s in range(z.shape[0]):
        u = draws[4 * s + 3]
        if u < chance:
            nb = neighbours[s, 0] if u < chance * 0.5 else neighbours[s, 1]
            if z[nb] < out[s]:
                out[s] = z[nb]
                crossed[s] = True
    return out, crossed


def _beam(z: float, u: np.ndarray, p: np.ndarray) -> float:
    """One reading of the four-part beam model around the true range ``z`` (far: none)."""
    far, top_range = p[P_FAR], p[P_RANGE]
    c_hit = p[P_Z_HIT]
    c_short = c_hit + p[P_Z_SHORT]
    c_max = c_short + p[P_Z_MAX]
    if u[0] < c_hit:
        if z < far:
            z = z + p[P_SIGMA] * gaussian(u[1], u[2])
            if z >= top_range:
                z = far
        return z
    if u[0] < c_short:
        top = z if z < far else top_range
        lam = p[P_LAMBDA]
        return -math.log(1.0 - u[1] * (1.0 - math.exp(-lam * top))) / lam
    if u[0] < c_max:
        return far
    return u[1] * top_range


def detect_probability(d: float, p: np.ndarray) -> float:
    """Probability of detecting a target at edge distance ``d`` (linear fall-off)."""
    near = p[P_DETECT_NEAR]
    return near + (p[P_DETECT_FAR] - near) * min(d / p[P_VIEW], 1.0)


def _camera_models(
    out: np.ndarray,
    n: int,
    m: int,
    c: int,
    decoy: float,
    u: np.ndarray,
    p: np.ndarray,
    f: np.ndarray,
    missed: np.ndarray,
    misread: np.ndarray,
) -> None:
    far = p[P_FAR]
    goal = out[n + c]
    if f[F_MISREAD] and decoy < far and u[0] < p[P_MISREAD]:
        goal = decoy
        misread[c] = True
    eow = out[n + m + c]
    if f[F_DETECT]:
        if goal < far and u[1] >= detect_probability(goal, p):
            goal = far
            missed[c, 0] = True
            misread[c] = False
        if eow < far and u[2] >= detect_probability(eow, p):
            eow = far
            missed[c, 1] = True
    out[n + c] = goal
    out[n + m + c] = eow


# --- motion ----------------------------------------------------------------------------


# --- domain randomization ----------------------------------------------------------------
