"""The rules every input file follows, at their exact boundaries: the YAML reader's limits
and number rule (and the writer that keeps names names), the configuration's bounds, and
the table header's checks."""

from __future__ import annotations

import itertools
from pathlib import Path

import pytest
from inputs import small_table

from koolio_pymunk.apps import cli
from koolio_pymunk.apps.export import check_sensor_signature
from koolio_pymunk.robot_runtime import field_bits
from koolio_pymunk.store.config import LIMITS, MAX_CONFIG_BYTES, MAX_NUMBER, config_from_dict
from koolio_pymunk.store.errors import ConfigError
from koolio_pymunk.store.keyword import MAX_KEYWORD_BITS, KeywordLayout
from koolio_pymunk.store.qtable import QTable, load_qtable
from koolio_pymunk.store.run_identity import sensor_signature
from koolio_pymunk.store.yamlfile import MAX_DEPTH, dump_yaml, parse_yaml, read_yaml


# -- the YAML reader and writer ---------------------------------------------------------------
def nested(depth: int) -> str:
    return "[" * depth + "]" * depth


def test_nesting_limit_is_exact() -> None:
    assert parse_yaml(nested(MAX_DEPTH), "f.yaml", ConfigError) is not None
    with pytest.raises(ConfigError, match=f"f.yaml: line 1: .*more than {MAX_DEPTH} levels"):
        parse_yaml(nested(MAX_DEPTH + 1), "f.yaml", ConfigError)


@pytest.mark.parametrize(
    ("text", "value"),
    [
        ("1e-9", 1e-9),
        ("5E3", 5000.0),
        ("-2e+3", -2000.0),
        (".5e1", 5.0),
        ("1.0e9", 1e9),
        ("10", 10),
        ("1_000", 1000),
        ("0x10", 16),
        ("1.5", 1.5),
        ("1e", "1e"),
        ("e5", "e5"),
        ("1e-9x", "1e-9x"),
    ],
)
def test_exponent_numbers(text: str, value: object) -> None:
    """YAML 1.2's numbers on top of YAML 1.1's: nothing YAML 1.1 reads changes."""
    assert parse_yaml(f"v: {text}", "c.yaml", ConfigError) == {"v": value}


@pytest.mark.parametrize(
    "name",
    ["1e3", "5E-1", "-2e+3", ".5", "1_000", "0x1f", "+12", "-.inf", ".NaN", "1:20", "yes",
     "null", "~", "2008-05-15", "317", "1e", "e5", "a: b", "- x", "#1", "'q'"],
)  # fmt: skip
def test_written_strings_read_back_as_strings(name: str) -> None:
    assert parse_yaml(dump_yaml({"name": name}), "a.yaml") == {"name": name}


def test_duplicate_keys_even_nested() -> None:
    with pytest.raises(ConfigError, match="line 2: not valid YAML: duplicate key 'a'"):
        parse_yaml("x:\n  {a: 1, a: 2}\n", "f.yaml", ConfigError)


def test_size_limit_is_exact(tmp_path: Path) -> None:
    path = tmp_path / "f.yaml"
    path.write_bytes(b"#" * MAX_CONFIG_BYTES)
    assert read_yaml(path, None, ConfigError, MAX_CONFIG_BYTES) is None
    with open(path, "ab") as fh:
        fh.write(b"\n")
    with pytest.raises(ConfigError, match=r"too large: 256 KiB \(the limit for .* is 256 KiB\)"):
        read_yaml(path, None, ConfigError, MAX_CONFIG_BYTES)


# -- configuration bounds -------------------------------------------------------------------
def test_the_widest_keyword_that_fits_and_the_first_that_does_not() -> None:
    """6 sonar groups x 2 bits + 3 action bits, and 2 + 2 bits per camera."""

    def cameras(n: int) -> dict:
        return {"sensors": {"camera": {"camera_sensors_deg": [0.0] * n}}}

    n = (MAX_KEYWORD_BITS - 12 - 3) // 4
    assert len(config_from_dict(cameras(n)).sensors.camera.camera_sensors_deg) == n
    with pytest.raises(ConfigError, match="sensors: the keyword would need 67 bits"):
        config_from_dict(cameras(n + 1))


@pytest.mark.parametrize("item", sorted(LIMITS))
def test_bounds_that_keep_a_run_finite(item: str) -> None:
    section, *sub, key = item.split(".")
    most = int(LIMITS[item][0])

    def at(value: int) -> dict:
        inner: dict = {key: value}
        if key == "forget_after":  # forgets a sighting only where one is remembered
            inner["goal_camera"] = True
        for part in reversed(sub):
            inner = {part: inner}
        return {section: inner}

    config_from_dict(at(most))
    with pytest.raises(ConfigError, match=rf"{item}: must be <= {most:,} \(.*got {most + 1:,}$"):
        config_from_dict(at(most + 1))


@pytest.mark.parametrize(
    ("section", "key"),
    [("rewards", "forward"), ("learner", "q_init"), ("rewards", "goal")],
)
def test_numbers_are_bounded(section: str, key: str) -> None:
    for good in (int(MAX_NUMBER), -int(MAX_NUMBER)):
        assert getattr(getattr(config_from_dict({section: {key: good}}), section), key) == good
    for bad in (int(MAX_NUMBER) + 1, 2**63, 10**400, -1.0000001e15, -1e308):
        with pytest.raises(ConfigError, match=rf"{section}.{key}: must be finite and at most"):
            config_from_dict({section: {key: bad}})


def test_extreme_rewards_keep_q_values_finite(tmp_path: Path, capsys) -> None:
    """Rewards and q_init at the bound, no discount: training saves finite Q values (a
    reward of -1e308 once overflowed them to -inf, then NaN)."""
    big = f"{MAX_NUMBER:.0e}"
    rewards = ", ".join(f"{k}: -{big}" for k in ("end_of_world", "bump", "stop", "reverse"))
    (tmp_path / "c.yaml").write_text(
        f"rewards: {{goal: {big}, turn: -{big}, forward: -{big}, {rewards}}}\n"
        f"learner: {{q_init: -{big}, gamma: 1, alpha: 1}}\nepisode: {{max_steps: 200}}\n"
    )
    table = tmp_path / "t.qtable"
    argv = ["train", "--arena", "room", "--config", str(tmp_path / "c.yaml"), "--quiet"]
    assert cli.main([*argv, "--episodes", "3", "--qtable", str(table)]) == 0, capsys.readouterr()
    assert len(load_qtable(table)) > 10  # loading checks that every Q value is finite


# -- table headers ------------------------------------------------------------------------------
@pytest.mark.parametrize("backend", ["fast", "cone", "pymunk"])
def test_every_sensor_signature_exports(backend: str) -> None:
    """A key added to ``run_identity.sensor_signature`` keeps what export reads of it."""
    cfg = config_from_dict({"sensors": {"backend": backend}})
    check_sensor_signature(sensor_signature(cfg), "t.qtable")


def test_unknown_header_keys_are_kept() -> None:
    """A later version's header key (e.g. the learner) is kept as it is."""
    table = small_table()
    table.meta["learner"] = {"x": 1}
    again = QTable.from_bytes(table.to_bytes(), "t.qtable")
    assert again.meta["learner"] == {"x": 1} and again.layout == table.layout


@pytest.mark.parametrize("levels", [2, 3, 4, 5, 2**16, 2**53, 2**53 + 1, 2**62 + 1])
def test_field_bits_are_exact(levels: int) -> None:
    """A field gets the fewest bits that hold its largest code, counted in integers even
    where a float log2 would round (2**53 + 1 levels need 54 bits, ``ceil(log2)`` says
    53), and that code comes back out of a keyword. (The table's layout is the robot's,
    :class:`~koolio_pymunk.robot_runtime.Layout`: one count for both.)"""
    fewest = next(b for b in itertools.count(1) if 1 << b >= levels)
    assert KeywordLayout((("A", levels),)).bits == (fewest,)
    assert field_bits(levels) == fewest
    lay = KeywordLayout((("A", levels), ("B", 3)))
    assert lay.decode(lay.keyword((levels - 1, 2), 4)) == ((levels - 1, 2), 4)
