"""Every number of a configuration has a documented range, checked where it is read
(issue #21): each bound is accepted and the next value beyond it is one line naming the
item. The ranges follow physics and the paper (``docs/robustness.md`` lists them)."""

from __future__ import annotations

import ast
import inspect
import itertools
import re

import pytest

from koolio_pymunk.store.config import config_from_dict
from koolio_pymunk.store.errors import ConfigError

#: item -> (a value at the bound, a value just beyond it, words of the refusal).
BOUNDS = {
    "robot.robot_radius": (60.0, 60.5, "must be in [0.5, 60] inches"),
    "robot.robot_radius ": (0.5, 0.4, "must be in [0.5, 60] inches"),
    "sensors.noise.scale": (10.0, 10.5, "must be <= 10"),
    "sensors.sonar.max_range": (9_000.0, 10_001.0, "must be <= 10,000 inches"),
    "sensors.camera.max_camera_view": (9_000.0, 10_001.0, "must be <= 10,000 inches"),
    "sensors.really_long_distance": (1e6, 1.5e6, "must be <= 1e+06 inches"),
    "episode.max_steps": (10_000_000, 10_000_001, "must be <= 10,000,000"),
    "rescue.max_steps_before_rescue": (10_000_000, 10_000_001, "must be <= 10,000,000"),
    "learner.epsilon.decay_episodes": (10**9, 10**9 + 1, "must be <= 1,000,000,000"),
    "learner.trace_cutoff": (1e-6, 9e-7, "must be in [1e-06, 1)"),
    "learner.planning_steps": (10_000, 10_001, "must be <= 10,000"),
    "realism.sonar.min_range": (120.0, 121.0, "must be <= 120"),
    "realism.sonar.max_range": (10_000.0, 10_001.0, "must be <= 10000"),
    "realism.sonar.sigma_hit": (120.0, 130.0, "must be <= 120"),
    "realism.sonar.lambda_short": (1.0, 1.5, "must be <= 1 (per inch)"),
    "realism.sonar.lambda_short ": (1e-6, 1e-7, "must be >= 1e-06 (per inch)"),
    "realism.motion.drift_deg": (-30.0, -31.0, "must be in [-30, 30]"),
    "realism.motion.drift_sigma_deg": (30.0, 31.0, "must be <= 30"),
    "realism.motion.slip_sigma": (0.5, 0.51, "must be <= 0.5"),
    "realism.motion.turn_sigma_deg": (30.0, 31.0, "must be <= 30"),
}


def _at(item: str, value: float) -> dict:
    *path, key = item.strip().split(".")
    inner: dict = {key: value}
    for part in reversed(path):
        inner = {part: inner}
    if item.startswith("sensors.sonar.max_range") or item.startswith("sensors.camera"):
        inner["sensors"]["really_long_distance"] = 20_000.0
    if item == "robot.robot_radius ":
        inner["actions"] = {"move_action_distance": 1.0}
    if item.strip() == "realism.sonar.max_range":
        inner.setdefault("sensors", {})["sonar"] = {"max_range": 9_000.0}
    return inner


@pytest.mark.parametrize("item", sorted(BOUNDS))
def test_each_bound_is_accepted_and_the_next_value_refused(item: str) -> None:
    good, bad, words = BOUNDS[item]
    config_from_dict(_at(item, good))
    with pytest.raises(ConfigError) as info:
        config_from_dict(_at(item, bad))
    message = str(info.value)
    assert message.startswith(f"<config>: {item.strip()}: ") and words in message, message
    assert "\n" not in message


def test_the_issue_s_slip_is_refused_and_a_realistic_one_runs() -> None:
    with pytest.raises(ConfigError, match=r"realism\.motion\.slip_sigma: must be <= 0\.5"):
        config_from_dict({"realism": {"motion": {"slip_sigma": 1e6}}})
    with pytest.raises(ConfigError, match=r"realism\.randomize\.motion\.slip_sigma: high end"):
        config_from_dict({"realism": {"randomize": {"motion.slip_sigma": [0.0, 1e6]}}})
    assert config_from_dict({"realism": {"motion": {"slip_sigma": 0.05}}})


@pytest.mark.parametrize(
    ("item", "value", "words"),
    [
        ("sensors.sonar.sonar_sensors_deg", [0.0, 400.0] + [0.0] * 6, "sonar_sensors_deg[1]: must"),
        ("sensors.camera.camera_sensors_deg", [-361.0], "camera_sensors_deg[0]: must be in"),
        ("sensors.sonar.thresholds", [-1.0, 5.0], "sonar.thresholds[0]: must be in [0, 10000]"),
        ("sensors.camera.thresholds", [36.0, 20_000.0], "camera.thresholds[1]: must be in"),
    ],
)
def test_list_entries_have_ranges(item: str, value: list, words: str) -> None:
    with pytest.raises(ConfigError, match=r"^<config>: ") as info:
        config_from_dict(_at(item, value))
    assert words in str(info.value)


def _numeric_fields(module) -> list[tuple[str, str, str]]:
    """``(class, field, docstring)`` of every int or float field of ``module``'s classes."""
    tree = ast.parse(inspect.getsource(module))
    out = []
    for cls in (n for n in tree.body if isinstance(n, ast.ClassDef)):
        for node, doc in itertools.pairwise(cls.body):
            if not isinstance(node, ast.AnnAssign):
                continue
            kind = ast.unparse(node.annotation)
            if kind.startswith("list[list") or not any(t in kind for t in ("float", "int")):
                continue
            text = doc.value.value if isinstance(doc, ast.Expr) else ""
            out.append((cls.name, ast.unparse(node.target), str(text)))
    return out


#: How a docstring names a range: an interval with both ends (``[0.5, 60]``, ``(0, 360)``,
#: ``(0, robot diameter]``, ``(max(a, b), 1,000,000]``), a span of integers (``1..360``,
#: ``0..10,000``), or the bound every number shares (``within +-1e15``).
RANGE = re.compile(
    r"[\[(][^\[\]()]*?(?:\([^()]*\)[^\[\]()]*?)?,\s*[^\[\]()]+[\])]"
    r"|\b\d[\d,]*\.\.\d[\d,]*\b"
    r"|within \+-1e15"
)


@pytest.mark.parametrize(
    ("text", "names"),
    [
        ("``RobotRadius`` in inches, in [0.5, 60]; None takes the profile's", True),
        ("in (max(``max_range``, ``max_camera_view``), 1,000,000] (the arenas'", True),
        ("in (0, robot diameter]. Not given by the paper", True),
        ("Forget a sighting after this many steps, 0..10,000 (0: never).", True),
        ("Value of a Q entry never updated, within +-1e15.", True),
        ("Bump < 6 <= Close < 24 <= Medium (inches) [Table 6].", False),
        ("The count of things [sic], see (paper) §5.", False),
        ("Steps per tick [of the window], 30 by default.", False),
    ],
)
def test_what_names_a_range(text: str, names: bool) -> None:
    """The rule of the test below, on docstrings that name a range and on some that hold
    brackets but no range (which once passed: any ``[`` did)."""
    assert bool(RANGE.search(text)) is names


def test_every_field_has_a_docstring_naming_its_range() -> None:
    """The documented ranges: every numeric field's docstring says its range
    (:data:`RANGE`); the rewards share theirs, in their class docstring."""
    from koolio_pymunk.store import config, realism_config

    fields = _numeric_fields(config) + _numeric_fields(realism_config)
    assert len(fields) > 50
    missing = [
        f"{cls}.{name}"
        for cls, name, text in fields
        if cls != "RewardConfig" and not RANGE.search(" ".join(text.split()))
    ]
    assert missing == [], missing
    assert RANGE.search(" ".join(config.RewardConfig.__doc__.split()))
