"""Configuration of the realism models (the ``realism`` section) and domain randomization.

The models themselves live where they act: the sonar and camera models in
:mod:`koolio_pymunk.sensing.realism`, the motion errors in
:mod:`koolio_pymunk.world.motion_errors`. Here are their parameters (one dataclass per
model, a docstring with the unit and meaning under every field), their validation with
one-line errors, the predicates that say which models are on, and the per-episode draw
of domain randomization (:class:`Randomizer`). Every model is off by default.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from .errors import ConfigError, located


@dataclass
class SonarRealism:
    """Ultrasonic ranger physics (all off by default)."""

    max_incidence_deg: float = 90.0
    """Incidence limit, degrees from the wall's normal, in (0, 90]: a sub-arc ray meeting
    a wall more obliquely gets no echo (specular reflection). 90 = off. Webots' sonar
    model uses 22.5 (``cyberbotics/webots``, ``docs/reference/distancesensor.md``)."""
    min_range: float = 0.0
    """Minimum range, inches, in [0, 120]: a reading below it reads it. 0 = off.
    Devantech SRF04: 3 cm (1.2 in); no ranger is blind for 10 ft."""
    max_range: float | None = None
    """Maximum range, inches from the robot's edge, in (min_range, 10,000]: a wall farther
    away gives no echo. None = ``sensors.sonar.max_range`` (off). Devantech SRF04: 3 m
    (118 in)."""
    z_hit: float = 1.0
    """Beam model weight of a correct reading (Gaussian around the true range). The four
    weights are in [0, 1] and sum to 1; ``z_hit`` 1 with ``sigma_hit`` 0 is the ideal
    sonar (off)."""
    z_short: float = 0.0
    """Beam model weight of an unexpected near echo (exponential, ``lambda_short``), in [0, 1]."""
    z_max: float = 0.0
    """Beam model weight of a dropout: no echo, the sonar reads nothing seen, in [0, 1]."""
    z_rand: float = 0.0
    """Beam model weight of a random reading, uniform over the sonar's range, in [0, 1]."""
    sigma_hit: float = 0.0
    """Standard deviation of a correct reading, inches, in [0, 120]. ROS amcl: 0.2 m
    (7.9 in); a 40 kHz ranger: a fraction of an inch."""
    lambda_short: float = 0.00254
    """Rate of the short-echo exponential, 1/inch, in [1e-6, 1] (a mean short echo
    between 1 in and 16 miles). ROS amcl: 0.1 per metre."""
    crosstalk: float = 0.0
    """Probability in [0, 1] per sonar and reading of hearing a ring neighbour's echo
    (sonars fired together). 0 = off (sonars fired in sequence)."""


@dataclass
class CameraRealism:
    """Plate and marker detection by the cameras (off by default)."""

    detect_near: float = 1.0
    """Probability in [0, 1] of detecting a target in view at 0 in."""
    detect_far: float = 1.0
    """Probability in [0, 1] of detecting a target in view at ``max_camera_view``; linear
    in between. ``detect_near`` = ``detect_far`` = 1 is off."""
    misread: float = 0.0
    """Probability in [0, 1] that a camera with another door's plate in view takes it for
    the goal (the arena's other goals are the other plates). 0 = off."""


@dataclass
class MotionRealism:
    """Motor and wheel errors of a differential drive (off by default)."""

    drift_deg: float = 0.0
    """Systematic heading change per Forward move, degrees, left positive, in [-30, 30]
    (a Reverse move retraces the arc: the opposite change). The paper (§5.3): "one motor
    will always be faster than the other, causing the robot to travel in an arc";
    ``koolio-real``: 0.43 (1 % wheel speed difference). 30 is a robot driving circles."""
    drift_sigma_deg: float = 0.0
    """Standard deviation of a random heading change per move, degrees, in [0, 30]."""
    slip_sigma: float = 0.0
    """Standard deviation of the distance error per move, a fraction of the move, in
    [0, 0.5]: a slip of a few per cent is realistic (``koolio-real``: 2 %); 0.5 is a robot
    whose moves often halve or double. (A slip of 1e6 once made one move a million inches,
    which hung ``train`` when a move was driven in 0.25-inch sub-steps.)"""
    turn_sigma_deg: float = 0.0
    """Standard deviation of the rotation error per turn, degrees, in [0, 30] (a turn's
    own size: ``koolio-real`` 1.5, 5 % of a 30 degree turn)."""


@dataclass
class RealismConfig:
    """The realism models (``realism`` section; set by worlds such as ``koolio-real``)."""

    sonar: SonarRealism = field(default_factory=SonarRealism)
    """Ultrasonic ranger physics."""
    camera: CameraRealism = field(default_factory=CameraRealism)
    """Camera detection."""
    motion: MotionRealism = field(default_factory=MotionRealism)
    """Motion errors."""
    randomize: dict[str, list[float]] = field(default_factory=dict)
    """Domain randomization: ``{"sonar.sigma_hit": [0, 8], ...}``: each episode draws
    every listed parameter uniformly from ``[low, high]`` (keys: :data:`RANDOMIZABLE`).
    Drawing ``z_short``, ``z_max`` or ``z_rand`` sets ``z_hit`` to what remains."""


#: Parameters domain randomization may draw (``section.name``).
RANDOMIZABLE: tuple[str, ...] = tuple(
    f"{section}.{f.name}"
    for section, cls in (
        ("sonar", SonarRealism),
        ("camera", CameraRealism),
        ("motion", MotionRealism),
    )
    for f in dataclasses.fields(cls)
    if f.name != "z_hit"
)


_WEIGHTS = ("z_hit", "z_short", "z_max", "z_rand")


def validate_realism(cfg: RealismConfig, src: str) -> None:
    """Check ranges and the randomization table; raise ConfigError naming the item."""
    for item, problem in model_problems(cfg):
        raise ConfigError(located(src, f"realism.{item}", problem))
    _check_randomize(cfg, src)


#: Upper bounds of the realism parameters (docstrings above): item -> (largest, why).
REALISM_LIMITS: dict[str, tuple[float, str]] = {
    "sonar.min_range": (120.0, "inches: no ranger is blind for 10 ft"),
    "sonar.max_range": (10_000.0, "inches"),
    "sonar.sigma_hit": (120.0, "inches"),
    "sonar.lambda_short": (1.0, "per inch"),
    "motion.drift_deg": (30.0, "degrees per move"),
    "motion.drift_sigma_deg": (30.0, "degrees per move"),
    "motion.slip_sigma": (0.5, "of a move: a few per cent is realistic"),
    "motion.turn_sigma_deg": (30.0, "degrees per turn"),
}


def model_problems(cfg: RealismConfig) -> list[tuple[str, str]]:
    """``(item, problem)`` of every out-of-range parameter (items relative to realism)."""
    so, ca, mo = cfg.sonar, cfg.camera, cfg.motion
    out: list[tuple[str, str]] = []
    if not 0.0 < so.max_incidence_deg <= 90.0:
        out.append(("sonar.max_incidence_deg", "must be in (0, 90]"))
    for name in ("min_range", "sigma_hit", *_WEIGHTS):
        if getattr(so, name) < 0.0:
            out.append((f"sonar.{name}", f"must be >= 0, got {getattr(so, name)!r}"))
    if so.max_range is not None and so.max_range <= so.min_range:
        out.append(("sonar.max_range", "must exceed min_range"))
    for item, (most, why) in REALISM_LIMITS.items():
        section, name = item.split(".")
        value = getattr(getattr(cfg, section), name)
        if value is not None and abs(value) > most:
            bound = f"in [-{most:g}, {most:g}]" if name == "drift_deg" else f"<= {most:g}"
            out.append((item, f"must be {bound} ({why}), got {value:g}"))
    total = sum(getattr(so, w) for w in _WEIGHTS)
    if abs(total - 1.0) > 1e-9:
        problem = f"the weights z_hit + z_short + z_max + z_rand must sum to 1, got {total:.6g}"
        out.append(("sonar.z_hit", problem))
    if so.lambda_short < 1e-6:
        out.append(("sonar.lambda_short", f"must be >= 1e-06 (per inch), got {so.lambda_short:g}"))
    for item, value in (
        ("sonar.crosstalk", so.crosstalk),
        ("camera.detect_near", ca.detect_near),
        ("camera.detect_far", ca.detect_far),
        ("camera.misread", ca.misread),
    ):
        if not 0.0 <= value <= 1.0:
            out.append((item, f"a probability must be in [0, 1], got {value!r}"))
    for name in ("drift_sigma_deg", "slip_sigma", "turn_sigma_deg"):
        if getattr(mo, name) < 0.0:
            out.append((f"motion.{name}", f"must be >= 0, got {getattr(mo, name)!r}"))
    return out


def _check_randomize(cfg: RealismConfig, src: str) -> None:
    table = cfg.randomize
    if not isinstance(table, dict):
        _fail(src, "realism.randomize", "must be a mapping of parameter: [low, high]")
    for key, span in table.items():
        item = f"realism.randomize.{key}"
        if key not in RANDOMIZABLE:
            hint = "z_hit is what the other weights leave" if key == "sonar.z_hit" else ""
            _fail(
                src,
                item,
                f"not a randomizable parameter ({hint or 'valid: ' + ', '.join(RANDOMIZABLE)})",
            )
        ok = (
            isinstance(span, list)
            and len(span) == 2
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in span)
            and all(math.isfinite(v) for v in span)
        )
        if not ok:
            _fail(src, item, f"expected [low, high] (two numbers), got {span!r}")
        if span[0] > span[1]:
            _fail(src, item, f"low {span[0]:g} exceeds high {span[1]:g}")
        for end, value in zip(("low", "high"), span):  # every bound is monotone: ends suffice
            for _, problem in model_problems(with_values(cfg, {key: value})):
                _fail(src, item, f"{end} end {value:g}: {problem}")
    weights = [k for k in table if k.split(".")[-1] in _WEIGHTS]
    if weights:  # all weights drawn at their high ends: z_hit must not go negative
        top = with_values(cfg, {k: table[k][1] for k in weights})
        if top.sonar.z_hit < 0.0:
            _fail(
                src,
                f"realism.randomize.{weights[0]}",
                "the high ends of z_short + z_max + z_rand exceed 1 (z_hit would be < 0)",
            )


def _fail(src: str, item: str, problem: str) -> None:
    raise ConfigError(located(src, item, problem))


def with_values(cfg: RealismConfig, values: dict[str, float]) -> RealismConfig:
    """A copy of ``cfg`` with ``values`` (``section.name`` -> value) set; drawing a beam
    weight other than ``z_hit`` sets ``z_hit`` to what the weights leave."""
    out = copy.deepcopy(cfg)
    out.randomize = {}
    for key, value in values.items():
        section, name = key.split(".")
        setattr(getattr(out, section), name, float(value))
    if any(f"sonar.{w}" in values for w in _WEIGHTS[1:]):
        so = out.sonar
        so.z_hit = 1.0 - (so.z_short + so.z_max + so.z_rand)
    return out


def sonar_on(cfg: RealismConfig) -> bool:
    """Any sonar model on (a reading then goes through :func:`apply_reference`)."""
    so = cfg.sonar
    return (
        so.max_incidence_deg < 90.0
        or so.min_range > 0.0
        or so.max_range is not None
        or beam_on(cfg)
        or so.crosstalk > 0.0
    )


def beam_on(cfg: RealismConfig) -> bool:
    """The beam model is not the ideal sonar (hit-only with sigma 0)."""
    so = cfg.sonar
    return so.z_hit != 1.0 or so.sigma_hit > 0.0


def camera_on(cfg: RealismConfig) -> bool:
    ca = cfg.camera
    return ca.detect_near < 1.0 or ca.detect_far < 1.0 or ca.misread > 0.0


def motion_on(cfg: RealismConfig) -> bool:
    mo = cfg.motion
    return any(
        v != 0.0 for v in (mo.drift_deg, mo.drift_sigma_deg, mo.slip_sigma, mo.turn_sigma_deg)
    )


def realism_on(cfg: RealismConfig) -> bool:
    """Any model on, or domain randomization (which may switch models on)."""
    return sonar_on(cfg) or camera_on(cfg) or motion_on(cfg) or bool(cfg.randomize)


class Randomizer:
    """Draws each episode's realism parameters (``realism.randomize``).

    :meth:`draw` makes one ``rng.uniform(lows, highs)`` call over the keys in sorted
    order and returns the episode's :class:`RealismConfig` and the values drawn.
    """

    def __init__(self, cfg: RealismConfig) -> None:
        self.base = cfg
        self.keys = sorted(cfg.randomize)
        self.lows = np.array([cfg.randomize[k][0] for k in self.keys], dtype=float)
        self.highs = np.array([cfg.randomize[k][1] for k in self.keys], dtype=float)

    def __bool__(self) -> bool:
        return bool(self.keys)

    @property
    def columns(self) -> list[str]:
        """Log columns of the draw: ``realism.<key>``."""
        return [f"realism.{k}" for k in self.keys]

    def draw(self, rng: np.random.Generator) -> tuple[RealismConfig, dict[str, float]]:
        values = rng.uniform(self.lows, self.highs)
        drawn = {k: float(v) for k, v in zip(self.keys, values)}
        return with_values(self.base, drawn), drawn
