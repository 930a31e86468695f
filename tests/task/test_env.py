"""KoolioEnv: Gymnasium API, spaces, info, events, rescue, determinism."""

from __future__ import annotations

import math
import os

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import koolio_pymunk  # noqa: F401  (registers the env)
from koolio_pymunk import KoolioEnv
from koolio_pymunk.store.config import Config
from koolio_pymunk.store.errors import KoolioError
from koolio_pymunk.task.rules import TERMS
from koolio_pymunk.world.physics import Action


def quiet_config(**episode) -> Config:
    cfg = Config()
    cfg.sensors.noise.model = "none"
    for k, v in episode.items():
        setattr(cfg.episode, k, v)
    return cfg


def test_check_env_passes() -> None:
    env = KoolioEnv("room")
    check_env(env, skip_render_check=True)


def test_check_env_of_the_registered_env_with_its_render_modes() -> None:
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    check_env(gym.make("koolio_pymunk/Hallway-v0").unwrapped)  # rebuilds it per render mode


def test_gym_make_registered_hallway() -> None:
    env = gym.make("koolio_pymunk/Hallway-v0")
    obs, info = env.reset(seed=1)
    assert env.action_space == gym.spaces.Discrete(5)
    assert env.observation_space == gym.spaces.MultiDiscrete([3] * 6 + [4] * 6)
    assert obs.shape == (12,) and env.observation_space.contains(obs)
    assert info["pose"][:2] == (72.0, 44.0)
    assert info["goal"] == env.unwrapped.arena.active_goal
    env.close()


def test_step_info_has_everything_the_issue_names() -> None:
    env = KoolioEnv("hallway")
    env.reset(seed=0)
    obs, reward, _, _, info = env.step(int(Action.FORWARD))
    for key in (
        "pose",
        "sonar",
        "goal_cam",
        "eow_cam",
        "state_key",
        "keyword",
        "event",
        "rescued",
        "has_been_rescued",
        "reward_terms",
    ):
        assert key in info
    assert len(info["pose"]) == 3 and len(info["sonar"]) == 8 and len(info["goal_cam"]) == 3
    assert set(info["reward_terms"]) == set(TERMS)
    assert info["reward_terms"][info["event"]] == reward
    assert env.layout.decode(info["keyword"])[1] == Action.FORWARD
    assert info["state_key"] == env.layout.state_key(tuple(obs))


def test_exploring_starts_random_heading_and_seeded() -> None:
    env = KoolioEnv("hallway")
    headings = set()
    for seed in range(5):
        _, info = env.reset(seed=seed)
        headings.add(round(info["pose"][2], 9))
    assert len(headings) == 5
    _, a = env.reset(seed=3)
    _, b = env.reset(seed=3)
    assert a["pose"] == b["pose"] and a["sonar"] == b["sonar"]


def test_same_seed_same_trajectory() -> None:
    def run() -> list:
        env = KoolioEnv("obstacles")
        env.reset(seed=11)
        rng = np.random.default_rng(0)
        out = []
        for _ in range(200):
            obs, r, te, tr, info = env.step(int(rng.integers(5)))
            out.append((tuple(obs), r, info["pose"]))
            if te or tr:
                env.reset()
        return out

    assert run() == run()


def test_goal_event_needs_stop_and_front_camera_close() -> None:
    env = KoolioEnv("hallway", config=quiet_config())
    gx, gy = env.world_arena.goal().at
    # Face the plate from 30 in away (edge distance 20 < 36: Close).
    env.reset(seed=0, options={"heading": -math.pi / 2})
    env.world.place(0, (gx, gy + 30), -math.pi / 2)
    _, r, te, _, info = env.step(int(Action.ROTATE_LEFT))
    assert not te and info["event"] == "turn"
    env.world.place(0, (gx, gy + 30), -math.pi / 2)
    _, r, te, _, info = env.step(int(Action.STOP))
    assert te and info["event"] == "goal" and r == env.config.rewards.goal
    assert info["goal_cam"][0] == pytest.approx(20.0)


def test_end_of_world_event() -> None:
    env = KoolioEnv("hallway", config=quiet_config())
    env.reset(seed=0)
    env.world.place(0, (6.0, 44.0), math.pi)  # 12 in forward crosses x = 0 into the zone
    _, r, te, _, info = env.step(int(Action.FORWARD))
    assert te and info["event"] == "end_of_world" and r == env.config.rewards.end_of_world


def test_bump_event_and_counter() -> None:
    env = KoolioEnv("hallway", config=quiet_config())
    env.reset(seed=0)
    env.world.place(0, (400.0, 20.0), -math.pi / 2)  # 10 in from the south wall's edge
    _, r, _, _, info = env.step(int(Action.FORWARD))
    assert info["event"] == "bump" and r == env.config.rewards.bump and info["bumps"] == 1


def test_truncation_at_step_cap() -> None:
    env = KoolioEnv("room", config=quiet_config(max_steps=5))
    env.reset(seed=0)
    flags = [env.step(int(Action.ROTATE_LEFT))[2:4] for _ in range(5)]
    assert flags == [(False, False)] * 4 + [(False, True)]


def test_forced_rescue_spins_and_marks_episode() -> None:
    env = KoolioEnv("hallway", config=quiet_config())
    env.reset(seed=0)
    env.world.place(0, (400.0, 44.0), 0.0)
    _, info = env.rescue()
    assert info["rescued"] and info["has_been_rescued"]
    assert info["pose"][2] != 0.0
    assert info["pose"][0] <= 400.0 + 1e-9  # only reverses along heading 0


def test_auto_rescue_fires_on_bump_past_limit() -> None:
    cfg = quiet_config()
    cfg.rescue.max_steps_before_rescue = 2
    cfg.rescue.rescue_chance = 1.0
    env = KoolioEnv("hallway", config=cfg)
    env.reset(seed=0)
    env.world.place(0, (400.0, 11.0), -math.pi / 2)  # touching the south wall
    events = [env.step(int(Action.FORWARD))[4] for _ in range(3)]
    assert [i["rescued"] for i in events] == [False, False, True]
    assert events[2]["event"] == "bump" and events[2]["has_been_rescued"]
    env.config.rescue.auto_rescue_toggle = False  # the env's own copy of the configuration
    env.reset(seed=0)
    env.world.place(0, (400.0, 11.0), -math.pi / 2)
    assert not any(env.step(int(Action.FORWARD))[4]["rescued"] for _ in range(4))


def test_goal_option_and_unknown_goal() -> None:
    env = KoolioEnv("hallway")
    names = env.arena.goal_names()
    _, info = env.reset(seed=0, options={"goal": names[0]})
    assert info["goal"] == names[0]
    with pytest.raises(KoolioError, match="no goal named 'nope'"):
        KoolioEnv("hallway", goal="nope")


def test_random_goal_draws_every_goal() -> None:
    env = KoolioEnv("hallway", goal="random")
    seen = {env.reset(seed=s)[1]["goal"] for s in range(200)}
    assert seen == set(env.arena.goal_names())


def test_core_does_not_import_pygame() -> None:
    import subprocess
    import sys

    code = (
        "import sys, koolio_pymunk; from koolio_pymunk.learning.training import train; "
        "from koolio_pymunk.apps import cli; cli.build_parser(); "
        "print('pygame' in sys.modules, 'matplotlib' in sys.modules)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.strip()
    assert out == "False False"


def test_default_goal_is_a_real_delivery() -> None:
    """>= 480 in (20 tiles) down the hallway and out of every camera's sight at the start."""
    env = KoolioEnv("hallway", config=quiet_config())
    start = env.world_arena.start.at
    goal = env.world_arena.goal().at
    assert goal[0] - start[0] >= 480
    for heading in np.linspace(0, 2 * math.pi, 72, endpoint=False):
        _, info = env.reset(seed=0, options={"heading": float(heading)})
        assert info["goal_cam"] == [env.config.sensors.really_long_distance] * 3


def test_tjpro_profile_is_17_cm() -> None:
    cfg = quiet_config()
    cfg.robot.profile = "tjpro"
    with pytest.raises(KoolioError, match="move_action_distance"):
        KoolioEnv("room", config=cfg)  # 12 in is more than its 6.7 in diameter
    cfg.actions.move_action_distance = 6.0
    env = KoolioEnv("room", config=cfg)
    assert env.world.radius == pytest.approx(17 / 2.54 / 2)
    env.reset(seed=0)
    env.step(int(Action.FORWARD))
    assert env.world.wall_clearance() > -0.1


def test_q_update_bootstraps_from_the_state_before_the_rescue() -> None:
    """Paper §5.4.8: update Q, then check for a rescue. ``transition`` returns the state
    the action led to; the env then stands in the rescued state."""
    envs = []
    for toggle in (True, False):
        cfg = Config()
        cfg.rescue.max_steps_before_rescue = 0
        cfg.rescue.rescue_chance = 1.0
        cfg.rescue.auto_rescue_toggle = toggle
        env = KoolioEnv("hallway", config=cfg)
        env.reset(seed=3)
        env.world.place(0, (400.0, 11.0), -math.pi / 2)  # touching the south wall
        envs.append(env)
    rescued, plain = envs
    next_key, reward, _, _ = rescued.transition(int(Action.FORWARD))
    plain_key, plain_reward, _, _ = plain.transition(int(Action.FORWARD))
    assert rescued.rescued and not plain.rescued
    assert (next_key, reward) == (plain_key, plain_reward)  # the same pre-rescue reading
    assert rescued.world.pose(0) != plain.world.pose(0)  # ... but the robot was moved
    assert plain.state_key == plain_key


def test_config_passed_in_is_not_changed() -> None:
    cfg = Config()
    env = KoolioEnv("room", config=cfg, max_steps=10)
    assert env.config.episode.max_steps == 10
    assert cfg.episode.max_steps == Config().episode.max_steps
    assert env.config is not cfg


def _types(value: object) -> object:
    """The type of an info value, with the types of a container's items."""
    if isinstance(value, dict):
        return ("dict", tuple(sorted((k, _types(v)) for k, v in value.items())))
    if isinstance(value, (list, tuple)):
        return (type(value).__name__, tuple(sorted({type(v).__name__ for v in value})))
    return type(value).__name__


def test_every_info_key_keeps_one_type_through_resets_steps_rescues_and_ends() -> None:
    cfg = Config()
    cfg.episode.max_steps = 25
    cfg.rescue.max_steps_before_rescue = 0
    cfg.rescue.rescue_chance = 0.5
    env = KoolioEnv("hallway", config=cfg, goal="random")
    _, first = env.reset(seed=4)
    assert first["keyword"] == -1 and first["event"] == "reset"
    assert set(first["reward_terms"].values()) == {0.0}
    seen = {k: {_types(v)} for k, v in first.items()}
    rng = np.random.default_rng(1)
    ends, rescues = set(), 0
    for _ in range(300):
        _, _, te, tr, info = env.step(int(rng.integers(5)))
        assert info.keys() == first.keys()
        for k, v in info.items():
            seen[k].add(_types(v))
        rescues += info["rescued"]
        if te or tr:
            ends.add("truncated" if tr else info["event"])
            _, info = env.reset()
            for k, v in info.items():
                seen[k].add(_types(v))
    assert rescues > 0 and "truncated" in ends  # the run went through both
    assert {k: len(v) for k, v in seen.items() if len(v) != 1} == {}
    assert seen["keyword"] == {"int"} and seen["event"] == {"str"}
    assert seen["pose"] == {("tuple", ("float",))}


def test_unknown_render_mode_is_refused() -> None:
    with pytest.raises(ValueError, match=r"render_mode: 'bogus' is not one of None, 'human'"):
        KoolioEnv("room", render_mode="bogus")
    with pytest.warns(UserWarning, match="bogus"), pytest.raises(ValueError, match="bogus"):
        gym.make("koolio_pymunk/Hallway-v0", render_mode="bogus")  # Gymnasium warns, we refuse


def test_registered_env_declares_the_step_cap_for_time_limit() -> None:
    """Gymnasium's convention: the registration's max_episode_steps and TimeLimit; the
    env's own cap (the configuration's, used without wrappers) agrees with it."""
    env = gym.make("koolio_pymunk/Hallway-v0")
    assert env.spec.max_episode_steps == Config().episode.max_steps == 1500
    assert env.unwrapped.config.episode.max_steps == 1500
    wrappers, inner = [], env
    while inner is not inner.unwrapped:
        wrappers.append(type(inner).__name__)
        inner = inner.env
    assert "TimeLimit" in wrappers


@pytest.mark.parametrize(
    ("kwargs", "cap"),
    [
        ({"max_episode_steps": 4}, 4),
        ({"max_steps": 3}, 3),
        ({"max_steps": 0, "max_episode_steps": 5}, 5),
    ],
)
def test_the_smaller_cap_truncates(kwargs: dict, cap: int) -> None:
    env = gym.make("koolio_pymunk/Hallway-v0", **kwargs)
    env.reset(seed=0)
    flags = [env.step(int(Action.ROTATE_LEFT))[2:4] for _ in range(cap)]
    assert flags == [(False, False)] * (cap - 1) + [(False, True)]
    env.close()


def _rotate(p: tuple[float, float], deg: float) -> tuple[float, float]:
    t = -math.radians(deg)
    return (math.cos(t) * p[0] - math.sin(t) * p[1], math.sin(t) * p[0] + math.cos(t) * p[1])


@pytest.mark.parametrize("world", [None, "koolio-real"])
@pytest.mark.parametrize("arena_name", ["hallway", "obstacles"])
def test_a_rotated_arena_is_the_same_task(arena_name: str, world: str | None) -> None:
    """The paper's 5-degree rotation (``rotate_deg``, swept by ``examples/experiments/
    rotation.yaml``) turns the start, the walls, every plate and zone with it: the same
    actions from the same relative heading give the same states, rewards and events,
    and poses that are the rotated ones, in the ideal world and with every realism model
    (misread plates, motion errors). Auto rescue is off: its spin draws a heading in the
    world's frame, a uniform draw either way but not the same number of degrees."""
    import dataclasses

    from koolio_pymunk.store.config import load_config
    from koolio_pymunk.world.arena import load_arena

    cfg = load_config(None, {"rescue": {"auto_rescue_toggle": False}})
    arena = load_arena(arena_name)
    envs = [
        KoolioEnv(arena=dataclasses.replace(arena, rotate_deg=deg), config=cfg, world=world)
        for deg in (0.0, 5.0)
    ]
    start = envs[1].world_arena.start.at
    assert start == pytest.approx(_rotate(arena.start.at, 5.0))
    assert envs[1].world_arena.goal().at == pytest.approx(_rotate(arena.goal().at, 5.0))
    for marker, turned in zip(arena.end_of_world, envs[1].world_arena.end_of_world):
        assert turned.at == pytest.approx(_rotate(marker.at, 5.0))
        assert envs[1].zones.contains(*turned.at)
    rng = np.random.default_rng(3)
    for seed in range(3):
        heading = float(rng.uniform(0.0, 2.0 * math.pi))
        actions = rng.choice(5, size=150, p=[0.02, 0.2, 0.2, 0.48, 0.1])
        runs = []
        for env, turn in zip(envs, (0.0, math.radians(5.0))):
            obs, info = env.reset(seed=seed, options={"heading": heading - turn})
            steps = [(obs.tolist(), 0.0, "reset", info["pose"])]
            for action in actions:
                obs, reward, term, trunc, info = env.step(int(action))
                steps.append((obs.tolist(), reward, info["event"], info["pose"]))
                if term or trunc:
                    break
            runs.append(steps)
        assert len(runs[0]) == len(runs[1])
        for (obs0, r0, ev0, pose0), (obs5, r5, ev5, pose5) in zip(*runs):
            assert (obs0, r0, ev0) == (obs5, r5, ev5)
            assert pose5[:2] == pytest.approx(_rotate(pose0[:2], 5.0), abs=1e-6)


def test_bad_actions_and_options_are_refused_before_anything_changes() -> None:
    """An action outside Discrete(5) and a reset option the env does not know raise
    ``ValueError`` before any draw or move (a 7 drew the sensor noise first, a 2.7 ran
    as 2, an unknown goal was a KeyError after the realism draw: API audit)."""
    env = KoolioEnv(config="koolio-real-dr")
    env.reset(seed=0)
    before = (env.np_random.bit_generator.state, env.world.pose(0), env.steps)
    for action in (7, -1, 2.7, "3"):
        with pytest.raises(ValueError, match=r"^action: .* is not an action \(0\.\.4\)$"):
            env.step(action)
    for options, words in (
        ({"hedding": 0.0}, "unknown key 'hedding'"),
        ({"goal": "nope"}, "goal: no goal named 'nope'"),
        ({"heading": float("nan")}, "heading: a finite number of radians"),
    ):
        with pytest.raises(ValueError, match=words):
            env.reset(options=options)
    assert (env.np_random.bit_generator.state, env.world.pose(0), env.steps) == before
    env.step(np.int64(3))  # numpy integers are actions
    assert env.steps == 1


def test_human_rendering_draws_at_every_step(monkeypatch) -> None:
    """``render_mode="human"`` draws in ``reset`` and ``step`` (Gymnasium's rule), so a
    window follows the robot without ``render()`` calls."""
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    drawn = []
    env = KoolioEnv(render_mode="human")
    monkeypatch.setattr(env, "render", lambda: drawn.append(env.steps))
    env.reset(seed=0)
    env.step(3)
    env.step(1)
    assert drawn == [0, 1, 2]
    plain = KoolioEnv(render_mode="rgb_array")
    monkeypatch.setattr(plain, "render", lambda: drawn.append("rgb"))
    plain.reset(seed=0)
    plain.step(3)
    assert "rgb" not in drawn  # rgb_array draws when asked


@pytest.mark.parametrize("world", [None, "koolio-real"])
@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
def test_a_copy_continues_exactly_as_the_original(world: str | None, how: str) -> None:
    import copy
    import pickle

    env = KoolioEnv("hallway", world=world)
    env.reset(seed=3)
    for a in [0, 1, 0, 0, 2, 0, 3]:
        env.step(a)
    twin = pickle.loads(pickle.dumps(env)) if how == "pickle" else copy.deepcopy(env)
    actions = [0, 0, 1, 0, 4, 2, 0, 0, 3, 0, 0, 0]
    ours = [env.step(a) for a in actions]
    theirs = [twin.step(a) for a in actions]
    for (o1, r1, t1, u1, i1), (o2, r2, t2, u2, i2) in zip(ours, theirs, strict=True):
        assert np.array_equal(o1, o2) and (r1, t1, u1) == (r2, t2, u2)
        assert i1["keyword"] == i2["keyword"] and i1["reward_terms"] == i2["reward_terms"]
    assert env.world.pose(0) == twin.world.pose(0)
    assert twin.world is not env.world


def test_a_rendered_env_pickles_without_its_window() -> None:
    import pickle

    pytest.importorskip("pygame")
    env = KoolioEnv("hallway", render_mode="rgb_array")
    env.reset(seed=0)
    picture = env.render()
    twin = pickle.loads(pickle.dumps(env))
    assert twin._renderer is None and env._renderer is not None
    assert np.array_equal(twin.render(), picture)


# -- what the project's learners know, in info (issue 33) -------------------------------


def rescuing_config(no_undo: bool = True, chance: float = 0.5) -> Config:
    """Rescues early and often, and the no-undo rule on: the cases of the mask."""
    cfg = Config()
    cfg.learner.no_undo = no_undo
    cfg.rescue.max_steps_before_rescue = 0
    cfg.rescue.rescue_chance = chance
    return cfg


def test_the_action_names_are_the_worlds() -> None:
    env = gym.make("koolio_pymunk/Room-v0")
    names = env.unwrapped.action_names
    assert names == ("Stop", "RotateLeft", "RotateRight", "Forward", "Reverse")
    assert len(names) == env.action_space.n
    assert [names[a] for a in Action] == [a.name.title().replace("_", "") for a in Action]


def test_the_action_mask_bars_the_last_actions_undo_under_the_rule_only() -> None:
    on = KoolioEnv("hallway", config={"learner": {"no_undo": True}})
    off = KoolioEnv("hallway", config={"learner": {"no_undo": False}})
    for env in (on, off):
        _, info = env.reset(seed=0)
        assert info["action_mask"].dtype == np.int8 and info["action_mask"].shape == (5,)
        assert info["action_mask"].tolist() == [1] * 5
    undo = {0: [1, 1, 1, 1, 1], 1: [1, 1, 0, 1, 1], 2: [1, 0, 1, 1, 1], 3: [1, 1, 1, 1, 0]}
    undo[4] = [1, 1, 1, 0, 1]
    for action in (1, 2, 0, 3, 4, 1, 1):
        info = on.step(action)[4]
        assert info["action_mask"].tolist() == undo[action], action
        assert np.array_equal(on.action_masks(), info["action_mask"])
        assert off.step(action)[4]["action_mask"].tolist() == [1] * 5


def test_the_mask_after_a_rescue_is_all_ones() -> None:
    env = KoolioEnv("hallway", config=rescuing_config(chance=1.0))
    env.reset(seed=0)
    env.world.place(0, (400.0, 11.0), -math.pi / 2)  # touching the south wall
    info = env.step(int(Action.FORWARD))[4]
    assert info["rescued"] and info["action_mask"].tolist() == [1] * 5
    env.reset(seed=0)
    info = env.step(int(Action.FORWARD))[4]
    assert not info["rescued"] and info["action_mask"].tolist() == [1, 1, 1, 1, 0]
    _, info = env.rescue()  # forced (the window's button)
    assert info["action_mask"].tolist() == [1] * 5


@pytest.mark.parametrize("no_undo", [True, False])
def test_the_mask_allows_exactly_what_the_learner_may_choose(no_undo: bool) -> None:
    """The env's mask against ``QLearner``'s own rule, step by step through episodes
    with auto rescues (where the learner's ``relocated`` frees the next action)."""
    from koolio_pymunk.learning.episodes import Episodes
    from koolio_pymunk.learning.qlearning import QLearner
    from koolio_pymunk.store.qtable import QTable
    from koolio_pymunk.task.action_rules import allowed

    cfg = rescuing_config(no_undo)
    cfg.episode.max_steps = 60
    env = KoolioEnv("hallway", config=cfg)
    agent = QLearner(QTable(env.layout), env.config.learner, None)
    episodes = Episodes(env, agent, seed=0)
    checked = rescues = barred = 0
    for episode in range(8):
        episodes.begin(episode)
        while True:
            mask = env.action_masks()
            assert [a for a in range(5) if mask[a]] == allowed(5, agent.bar)
            barred += int(mask.sum() == 4)
            checked += 1
            if episodes.step() is not None:
                break
            rescues += env.rescued
    assert checked > 300 and rescues > 10  # the premise: many steps, many rescues
    assert (barred > 200) == no_undo


def test_the_observation_before_a_rescue_is_where_the_action_led() -> None:
    """Two envs, one rescuing: the step's observation before the rescue is the plain
    env's observation, the state the Q update bootstraps from; the returned one is the
    rescued robot's."""
    envs = []
    for chance in (1.0, 0.0):
        env = KoolioEnv("hallway", config=rescuing_config(chance=chance))
        env.reset(seed=3)
        env.world.place(0, (400.0, 11.0), -math.pi / 2)  # touching the south wall
        envs.append(env)
    rescued, plain = envs
    obs, _, _, _, info = rescued.step(int(Action.FORWARD))
    plain_obs, _, _, _, plain_info = plain.step(int(Action.FORWARD))
    assert info["rescued"] and not plain_info["rescued"]
    before = info["observation_before_rescue"]
    assert before.dtype == np.int64 and before.shape == obs.shape
    np.testing.assert_array_equal(before, plain_obs)
    assert info["pose"] != plain_info["pose"]  # the rescue moved the robot ...
    assert not np.array_equal(obs, before)  # ... and it reads something else there
    assert rescued.layout.state_key(tuple(before)) == plain.state_key  # the update's next state
    np.testing.assert_array_equal(plain_info["observation_before_rescue"], plain_obs)
    assert plain_info["observation_before_rescue"] is not plain_obs  # a copy, not the same array
    reset_obs, reset_info = rescued.reset(seed=3)
    np.testing.assert_array_equal(reset_info["observation_before_rescue"], reset_obs)


def test_the_goal_door_is_in_info_and_optionally_in_the_observation() -> None:
    plain = KoolioEnv("hallway", goal="random")
    seen = set()
    for seed in range(60):
        _, info = plain.reset(seed=seed)
        assert plain.goal_names[info["goal_index"]] == info["goal"]
        seen.add(info["goal_index"])
    assert seen == set(range(len(plain.goal_names)))  # every door drawn
    assert plain.observation_space.shape == (12,)
    seeing = KoolioEnv("hallway", goal="random", observe_goal=True)
    n = len(seeing.goal_names)
    assert seeing.observation_space == gym.spaces.MultiDiscrete([3] * 6 + [4] * 6 + [n])
    for seed in range(5):
        obs, info = seeing.reset(seed=seed)
        reference = plain.reset(seed=seed)[0]
        assert obs[-1] == info["goal_index"] and np.array_equal(obs[:-1], reference)
        obs, *_, info = seeing.step(3)
        assert obs[-1] == info["goal_index"] == info["observation_before_rescue"][-1]
    obs, info = seeing.reset(seed=0, options={"goal": "302"})
    assert obs[-1] == info["goal_index"] == seeing.goal_names.index("302")
    check_env(seeing, skip_render_check=True)
    fixed = gym.make("koolio_pymunk/Room-v0", observe_goal=True)
    assert fixed.reset(seed=0)[0][-1] == 0 and fixed.observation_space.nvec[-1] == 1


def test_the_new_keys_change_no_draw() -> None:
    """Building ``info`` draws nothing: the same seed and actions give the same
    generator state as the learners' fast path (``reset_key`` / ``transition``)."""
    cfg = rescuing_config()
    fast, full = KoolioEnv("hallway", config=cfg), KoolioEnv("hallway", config=cfg)
    fast.reset(seed=5)
    fast.reset_key()
    full.reset(seed=5)
    full.reset()
    for a in [3, 3, 1, 3, 3, 4, 2, 3, 3, 3] * 5:
        key = fast.transition(a)[0]
        info = full.step(a)[4]
        assert full.layout.state_key(tuple(info["observation_before_rescue"])) == key
    assert fast.np_random.bit_generator.state == full.np_random.bit_generator.state
    assert fast.world.pose(0) == full.world.pose(0) and full.has_been_rescued
