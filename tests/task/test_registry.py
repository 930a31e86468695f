"""The registered ids (koolio_pymunk/task/registry.py): one per shipped arena, world and
profile, found by Gymnasium's registry and through the ``gymnasium.envs`` entry point;
bad ids and bad configurations refused in one line."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import koolio_pymunk  # noqa: F401  (registers the ids)
from koolio_pymunk import KoolioEnv
from koolio_pymunk.store.config import Config, profile_names, world_names
from koolio_pymunk.store.errors import ConfigError
from koolio_pymunk.task.registry import ENVS, MAX_EPISODE_STEPS, NAMESPACE, env_id
from koolio_pymunk.world.arena import BUILTIN_ARENAS

REPO = Path(__file__).resolve().parents[2]
IDS = [env_id(name) for name in ENVS]


def run_python(code: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=300, cwd=REPO
    )


def test_every_shipped_arena_world_and_profile_has_an_id() -> None:
    rows = list(ENVS.values())
    arenas = {r["arena"] for r in rows if set(r) == {"arena"}}
    worlds = {r["world"] for r in rows if "world" in r}
    profiles = {r["config"] for r in rows if "config" in r}
    assert arenas == set(BUILTIN_ARENAS)
    assert worlds == set(world_names())
    assert profiles == set(profile_names()) - set(world_names())
    assert any(r.get("goal") == "random" for r in rows)
    assert len(IDS) == len(set(IDS)) == 11


def test_the_first_id_keeps_its_registration() -> None:
    spec = gym.spec("koolio_pymunk/Hallway-v0")
    assert spec.entry_point == "koolio_pymunk.task.env:KoolioEnv"
    assert spec.kwargs == {"arena": "hallway"} and spec.max_episode_steps == 1500


@pytest.mark.parametrize("name", list(ENVS))
def test_each_id_makes_the_env_of_its_row(name: str) -> None:
    env = gym.make(env_id(name))
    inner = env.unwrapped
    direct = KoolioEnv(**ENVS[name])
    assert env.spec.max_episode_steps == MAX_EPISODE_STEPS == inner.config.episode.max_steps
    assert inner.config == direct.config and inner.world_name == direct.world_name
    assert inner.arena.name == direct.arena.name and inner.random_goal == direct.random_goal
    obs, info = env.reset(seed=0)
    assert env.observation_space.contains(obs) and obs.shape == direct.observation_space.shape
    obs, *_, info = env.step(3)
    assert env.observation_space.contains(obs)
    np.testing.assert_array_equal(info["observation_before_rescue"], obs)
    env.close()


def test_the_ids_are_what_their_names_say() -> None:
    made = {name: gym.make(env_id(name)).unwrapped for name in ENVS}
    assert made["Room-v0"].arena.name == "room"
    assert made["Obstacles-v0"].arena.name == "obstacles"
    assert made["HallwayAnyDoor-v0"].random_goal
    assert made["HallwayReal-v0"].world_name == "koolio-real"
    assert made["HallwayRealDR-v0"].world_name == "koolio-real-dr"
    assert made["HallwayReal-v0"].config.realism != Config().realism
    paper = made["HallwayPaper-v0"].config
    assert paper.sensors.camera.camera_sensors_deg == [0.0, 90.0, -90.0]
    assert made["HallwayPaperMemory-v0"].observation_space.shape == (14,)
    assert made["HallwayQLambdaNoUndo-v0"].config.learner.no_undo
    assert made["Hallway-v0"].config == Config()


def test_pprint_registry_lists_every_id_after_the_import() -> None:
    code = "import gymnasium as gym, koolio_pymunk\nprint(gym.pprint_registry(disable_print=True))"
    p = run_python(code)
    assert p.returncode == 0, p.stderr
    assert f"===== {NAMESPACE} =====" in p.stdout
    for full in IDS:
        assert full in p.stdout.split(), full


def test_the_entry_point_registers_every_id_as_a_plugin_loader_calls_it() -> None:
    """Gymnasium 0.26-0.29's ``load_env_plugins``: each entry point of the group
    ``gymnasium.envs`` is loaded and called inside ``namespace(entry point's name)``.
    Gymnasium 1.x has no loader; this does what it did, in a fresh interpreter."""
    code = (
        "import importlib.metadata, warnings\n"
        "import gymnasium as gym\n"
        "from gymnasium.envs.registration import namespace\n"
        "warnings.simplefilter('error')\n"
        "before = [k for k in gym.registry if k.startswith('koolio_pymunk/')]\n"
        "(ep,) = [e for e in importlib.metadata.entry_points(group='gymnasium.envs')\n"
        "         if e.value.startswith('koolio_pymunk.')]\n"
        "with namespace(ep.name):\n"
        "    ep.load()()\n"
        "print(ep.name, len(before), *sorted(k for k in gym.registry if k.startswith(ep.name)))"
    )
    p = run_python(code)
    assert p.returncode == 0, p.stderr
    assert p.stdout.split() == [NAMESPACE, "0", *sorted(IDS)]


def test_an_id_naming_its_module_needs_no_import() -> None:
    code = (
        "import sys, gymnasium as gym\n"
        "env = gym.make('koolio_pymunk:koolio_pymunk/Room-v0')\n"
        "print(env.unwrapped.arena.name, env.spec.max_episode_steps)"
    )
    p = run_python(code)
    assert p.returncode == 0, p.stderr
    assert p.stdout.split() == ["room", "1500"]


@pytest.mark.parametrize(
    ("bad", "error", "says"),
    [
        ("koolio_pymunk/Rooom-v0", gym.error.NameNotFound, "Did you mean: `Room`?"),
        ("koolio_pymunk/Room-v1", gym.error.VersionNotFound, "[ `v0` ]"),
        ("koolio_pymunk/HallwayReel-v0", gym.error.NameNotFound, "`HallwayReal`"),
        ("koolio_pimunk/Room-v0", gym.error.NamespaceNotFound, "`koolio_pymunk`"),
    ],
)
def test_a_bad_id_is_one_line_with_a_suggestion(bad: str, error: type, says: str) -> None:
    with pytest.raises(error) as caught:
        gym.make(bad)
    message = str(caught.value)
    assert "\n" not in message and says in message


@pytest.mark.parametrize(
    ("config", "message"),
    [
        ({"learner": {"alpah": 0.1}}, "config: learner.alpah: unknown key (did you mean 'alpha'?)"),
        ({"lerner": {"alpha": 0.1}}, "config: lerner: unknown key (did you mean 'learner'?)"),
        ({"rewards": {"goal": "lots"}}, "config: rewards.goal: expected a number, got 'lots'"),
        ({"learner": 3}, "config: learner: must be a mapping"),
        ({"episode": {"max_steps": -1}}, "config: episode.max_steps: "),
        (42, "config: a profile name, a file, a mapping or a Config, got 42"),
        ("papr", "--config: papr: no such profile (did you mean 'paper'?)"),
    ],
)
def test_a_bad_config_is_one_line_naming_the_key(config: object, message: str) -> None:
    with pytest.raises(ConfigError) as caught:
        gym.make("koolio_pymunk/Room-v0", config=config)
    assert str(caught.value).startswith(message) and "\n" not in str(caught.value)


def test_a_config_dict_is_laid_over_the_defaults_and_left_unchanged() -> None:
    data = {"learner": {"no_undo": True}, "sensors": {"camera": {"camera_sensors_deg": [0, 90]}}}
    snapshot = repr(data)
    env = gym.make("koolio_pymunk/Room-v0", config=data).unwrapped
    expected = Config()
    expected.learner.no_undo = True
    expected.sensors.camera.camera_sensors_deg = [0.0, 90.0]
    assert env.config == expected and repr(data) == snapshot
    assert env.observation_space.shape == (2 + 2 + 6,)  # two cameras: goal and end of world
    check_env(env, skip_render_check=True)


def test_overrides_keep_the_ids_profile_where_config_replaces_it() -> None:
    rule = {"learner": {"no_undo": True}}
    kept = gym.make("koolio_pymunk/HallwayPaper-v0", overrides=rule).unwrapped.config
    replaced = gym.make("koolio_pymunk/HallwayPaper-v0", config=rule).unwrapped.config
    assert kept.learner.no_undo and replaced.learner.no_undo
    assert kept.rewards.bump == -12.0 and kept.sensors.camera.camera_sensors_deg[1] == 90.0
    assert replaced.rewards.bump == Config().rewards.bump  # the profile is gone


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"learner": {"alpah": 0.1}}, "overrides: learner.alpah: unknown key (did you mean"),
        ({"episode": {"max_steps": 1.5}}, "overrides: episode.max_steps: expected an integer"),
        ("paper", "overrides: a mapping, got 'paper'"),
    ],
)
def test_bad_overrides_are_one_line_naming_the_key(overrides: object, message: str) -> None:
    with pytest.raises(ConfigError) as caught:
        gym.make("koolio_pymunk/HallwayPaper-v0", overrides=overrides)
    assert str(caught.value).startswith(message) and "\n" not in str(caught.value)
