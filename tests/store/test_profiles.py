"""Configuration profiles (``--config NAME``) and worlds (``--world NAME|FILE``)."""

from __future__ import annotations

import pytest

from koolio_pymunk.apps.cli import main
from koolio_pymunk.store.config import (
    Config,
    apply_world,
    load_config,
    profile_names,
    state_fields,
)
from koolio_pymunk.store.errors import ConfigError
from koolio_pymunk.task.env import KoolioEnv


def test_paper_profile_loads_by_name() -> None:
    assert "paper" in profile_names()
    cfg = load_config("paper")
    assert cfg.sensors.camera.camera_sensors_deg == [0.0, 90.0, -90.0]
    assert cfg.learner.epsilon.at(0) == cfg.learner.epsilon.at(10_000)  # a fixed epsilon


def test_paper_memory_profile_is_the_paper_plus_memory() -> None:
    """``paper-memory`` differs from ``paper`` in ``sensors.memory`` and the sonar's pings
    only (a read-out that changes nothing in the ideal world)."""
    paper, mem = load_config("paper"), load_config("paper-memory")
    assert mem.sensors.memory.goal_camera and mem.sensors.memory.previous_action
    assert not (mem.sensors.memory.eow_camera or mem.sensors.memory.forget_after)
    assert [name for name, _ in state_fields(mem.sensors)][-2:] == ["GoalMemory", "LastAction"]
    assert (paper.sensors.sonar.pings, mem.sensors.sonar.pings) == (1, 3)
    mem.sensors.memory = paper.sensors.memory
    mem.sensors.sonar.pings = 1
    assert mem == paper


def test_paper_memory_qlambda_profile_is_paper_memory_with_its_memory_and_learner() -> None:
    """``paper-memory-qlambda`` differs from ``paper-memory`` in the memory (the goal's
    bearing too, sightings forgotten after 60 steps) and the learner (Q(lambda), alpha
    0.07) only."""
    mem, lam = load_config("paper-memory"), load_config("paper-memory-qlambda")
    m = lam.sensors.memory
    assert m.goal_camera and m.previous_action and m.goal_bearing and m.forget_after == 60
    assert not m.eow_camera
    assert [name for name, _ in state_fields(lam.sensors)][-3:] == [
        "GoalMemory",
        "LastAction",
        "GoalBearing",
    ]
    assert (lam.learner.algorithm, lam.learner.alpha, lam.learner.trace_decay) == (
        "qlambda",
        0.07,
        0.9,
    )
    lam.sensors.memory = mem.sensors.memory
    lam.learner.algorithm, lam.learner.alpha = mem.learner.algorithm, mem.learner.alpha
    lam.learner.trace_decay = mem.learner.trace_decay  # one-step Q: no trace
    assert lam == mem


def test_qlambda_no_undo_profile_is_the_default_named() -> None:
    """``qlambda-no-undo`` is the default (Q(lambda) with lambda 0.7, alpha 0.1, epsilon
    over 150 episodes, and the no-undo rule), named; ``one-step-q`` is the default robot
    with the learner the default had before: the paper's one-step Q with this project's
    settings for it."""
    fast, default, before = load_config("qlambda-no-undo"), load_config(), load_config("one-step-q")
    le = fast.learner
    assert (le.algorithm, le.trace_decay, le.alpha, le.no_undo) == ("qlambda", 0.7, 0.1, True)
    assert le.epsilon.decay_episodes == 150 and fast == default
    lo = before.learner
    assert (lo.algorithm, lo.alpha, lo.no_undo, lo.epsilon.decay_episodes) == ("q", 0.2, False, 600)
    before.learner = default.learner
    assert before == default


def test_unknown_profile_is_one_line_error() -> None:
    with pytest.raises(
        ConfigError, match=r"^--config: papr: no such profile \(did you mean 'paper'\?\)"
    ):
        load_config("papr")


def test_world_sets_only_world_sections(tmp_path) -> None:
    world = tmp_path / "w.yaml"
    world.write_text("sensors: {noise: {scale: 0.5}}\n")
    cfg = apply_world(Config(), world)
    assert cfg.sensors.noise.scale == 0.5
    world.write_text("learner: {alpha: 0.5}\n")
    with pytest.raises(ConfigError, match=r"w\.yaml: learner: not a world setting"):
        apply_world(Config(), world)
    world.write_text("sensors: {sonar: {max_range: 100}}\n")
    with pytest.raises(ConfigError, match=r"w\.yaml: sensors\.sonar: not a world setting"):
        apply_world(Config(), world)
    with pytest.raises(ConfigError, match=r"^--world: paper: a configuration profile, not a w"):
        apply_world(Config(), "paper")


def test_world_applies_to_a_copy_and_env_names_it(tmp_path) -> None:
    world = tmp_path / "w.yaml"
    world.write_text("sensors: {noise: {model: none}}\n")
    cfg = Config()
    env = KoolioEnv("room", config=cfg, world=world)
    assert env.config.sensors.noise.model == "none"
    assert cfg.sensors.noise.model == "uniform"
    assert env.world_name == str(world)
    assert KoolioEnv("room").world_name == "ideal"


def test_cli_world_flag_and_profile(tmp_path, capsys) -> None:
    world = tmp_path / "w.yaml"
    world.write_text("learner: {alpha: 0.5}\n")
    args = ["train", "--arena", "room", "--episodes", "1", "--quiet"]
    args += ["--qtable", str(tmp_path / "t.qtable"), "--log", str(tmp_path / "t.csv")]
    assert main([*args, "--world", str(world)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        f"koolio-pm: error: {world}: learner: not a world setting "
        "(a world sets only: realism, sensors.noise)"
    ]
    assert not (tmp_path / "t.qtable").exists()
    assert main([*args, "--config", "paper"]) == 0
