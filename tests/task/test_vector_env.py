"""Gymnasium vector environments and render_mode="rgb_array"."""

from __future__ import annotations

import math
import os

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

import gymnasium as gym
import numpy as np
import pytest

import koolio_pymunk  # noqa: F401  (registers koolio_pymunk/Hallway-v0)
from koolio_pymunk.task.rules import TERMS

ENV_ID = "koolio_pymunk/Hallway-v0"
ACTIONS = [3, 1, 3, 3, 2, 4, 0, 3]


def _single_run(seed: int, max_steps: int) -> list[np.ndarray]:
    env = gym.make(ENV_ID, max_steps=max_steps)
    obs, _ = env.reset(seed=seed)
    out = [obs]
    for a in ACTIONS[:max_steps]:
        obs, *_ = env.step(a)
        out.append(obs)
    env.close()
    return out


def _vector_run(mode: str, seeds: list[int], max_steps: int) -> list[np.ndarray]:
    venv = gym.make_vec(ENV_ID, num_envs=len(seeds), vectorization_mode=mode, max_steps=max_steps)
    try:
        obs, _ = venv.reset(seed=seeds)
        out = [obs]
        for a in ACTIONS[:max_steps]:
            obs, *_ = venv.step(np.full(len(seeds), a))
            out.append(obs)
        return out
    finally:
        venv.close()


def test_sync_and_async_vector_envs_match_single_envs():
    seeds = [3, 4]
    singles = [_single_run(s, 6) for s in seeds]
    expected = [np.stack([singles[0][t], singles[1][t]]) for t in range(7)]
    for mode in ("sync", "async"):
        got = _vector_run(mode, seeds, 6)
        assert len(got) == 7
        for t in range(7):
            assert got[t].shape == (2, 12) and got[t].dtype == np.int64
            np.testing.assert_array_equal(got[t], expected[t])
    assert not np.array_equal(expected[0][0], expected[0][1]) or not np.array_equal(
        expected[6][0], expected[6][1]
    )


def test_vector_env_truncates_and_autoresets_with_goal_kwarg():
    venv = gym.make_vec(ENV_ID, num_envs=2, vectorization_mode="sync", max_steps=3, goal="302")
    try:
        assert venv.single_action_space == gym.spaces.Discrete(5)
        venv.reset(seed=[0, 1])
        for step in range(1, 4):
            _, reward, term, trunc, info = venv.step(np.array([1, 2]))
            assert reward.shape == (2,) and not term.any()
            assert list(info["steps"]) == [step, step]
        assert trunc.all()
        assert list(info["goal"]) == ["302", "302"]
        _, reward, _, trunc, info = venv.step(np.array([1, 2]))  # next-step autoreset
        assert list(info["steps"]) == [0, 0] and list(reward) == [0.0, 0.0]
        assert not trunc.any()
    finally:
        venv.close()


# Staggered episodes: every env faces the near end of the hallway; env 0 drives into the
# end-of-world zone (terminated at step 7) while the others turn or dither until the step
# cap of 9, so env 0 autoresets while the others are in mid-episode, then at step 10 the
# others autoreset while env 0 is in its second episode.
STAGGER_SEEDS = [5, 6, 7, 8]
STAGGER_CAP = 9
STAGGER_STEPS = 14


def _stagger_action(env: int, t: int) -> int:
    return [3, 1, 2, 3 if t % 2 else 4][env]


def _single_with_autoreset(seed: int, env: int) -> list[tuple]:
    """What one env of the vector does: Gymnasium's next-step autoreset by hand."""
    single = gym.make(ENV_ID, max_steps=STAGGER_CAP)
    obs, info = single.reset(seed=seed, options={"heading": math.pi})
    out, done = [], False
    for t in range(STAGGER_STEPS):
        if done:
            obs, info = single.reset()
            reward, term, trunc = 0.0, False, False
        else:
            obs, reward, term, trunc, info = single.step(_stagger_action(env, t))
        done = term or trunc
        out.append((obs, reward, term, trunc, info["keyword"], info["event"], info["steps"]))
    single.close()
    return out


def test_vector_envs_survive_staggered_autoresets():
    expected = [_single_with_autoreset(s, i) for i, s in enumerate(STAGGER_SEEDS)]
    for mode in ("sync", "async", "vector_entry_point"):
        venv = gym.make_vec(ENV_ID, num_envs=4, vectorization_mode=mode, max_steps=STAGGER_CAP)
        try:
            venv.reset(seed=STAGGER_SEEDS, options={"heading": math.pi})
            resets_at = []
            for t in range(STAGGER_STEPS):
                actions = np.array([_stagger_action(i, t) for i in range(4)])
                obs, reward, term, trunc, info = venv.step(actions)
                assert info["keyword"].dtype == np.int64 and info["steps"].dtype == np.int64
                assert all(isinstance(e, str) for e in info["event"])
                assert all(len(p) == 3 for p in info["pose"])
                terms = {k for k in info["reward_terms"] if not k.startswith("_")}
                assert terms == set(TERMS)
                assert all(info["reward_terms"][k].dtype == np.float64 for k in terms)
                resets_at.append([i for i in range(4) if info["event"][i] == "reset"])
                for i in range(4):
                    e_obs, e_reward, e_term, e_trunc, e_key, e_event, e_steps = expected[i][t]
                    np.testing.assert_array_equal(obs[i], e_obs)
                    assert (reward[i], term[i], trunc[i]) == (e_reward, e_term, e_trunc)
                    assert (info["keyword"][i], info["event"][i]) == (e_key, e_event)
                    assert info["steps"][i] == e_steps
                    if e_event == "reset":
                        assert e_key == -1 and e_steps == 0
            assert resets_at[7] == [0] and resets_at[9] == [1, 2, 3], (mode, resets_at)
        finally:
            venv.close()


def test_rgb_array_render_returns_the_viewers_picture():
    env = gym.make(ENV_ID, render_mode="rgb_array")
    try:
        env.reset(seed=0, options={"heading": 0.0})
        first = env.render()
        assert isinstance(first, np.ndarray)
        assert first.dtype == np.uint8 and first.ndim == 3 and first.shape[2] == 3
        assert first.shape[1] >= 600 and first.shape[0] >= 100
        assert len(np.unique(first.reshape(-1, 3), axis=0)) > 8  # walls, robot, sensors, text
        for _ in range(3):
            env.step(3)
        second = env.render()
        assert second.shape == first.shape and not np.array_equal(first, second)
    finally:
        env.close()
    venv = gym.make_vec(ENV_ID, num_envs=2, vectorization_mode="sync", render_mode="rgb_array")
    try:
        venv.reset(seed=[0, 1])
        frames = venv.render()
        assert len(frames) == 2 and all(f.shape == first.shape for f in frames)
    finally:
        venv.close()


# -- the native vector env: one compiled call per step ---------------------------------------


def test_make_vec_gives_the_compiled_vector_env_by_default():
    from koolio_pymunk.task.vector_env import KoolioVectorEnv

    for mode, kind in ((None, KoolioVectorEnv), ("sync", gym.vector.SyncVectorEnv),
                       ("async", gym.vector.AsyncVectorEnv)):  # fmt: skip
        venv = gym.make_vec(ENV_ID, num_envs=3, vectorization_mode=mode)
        try:
            assert type(venv.unwrapped) is kind and venv.num_envs == 3
            assert venv.metadata["autoreset_mode"] == gym.vector.AutoresetMode.NEXT_STEP
            assert venv.single_observation_space == gym.make(ENV_ID).observation_space
        finally:
            venv.close()


def _rollout(mode: str, n: int, seed, steps: int, **kw):
    venv = gym.make_vec(ENV_ID, num_envs=n, vectorization_mode=mode, **kw)
    try:
        obs, info = venv.reset(seed=seed)
        rng = np.random.default_rng(1)
        out = [(obs, None, None, None, info)]
        for _ in range(steps):
            forward = rng.random(n) < 0.6  # mostly forward: walls, bumps, ends of the world
            actions = np.where(forward, 3, rng.integers(0, 5, n))
            out.append(venv.step(actions))
        return out
    finally:
        venv.close()


def _same(a, b) -> None:
    """Two steps' results equal: arrays exactly, ``info`` key by key (the native env's
    numbers as arrays where ``SyncVectorEnv`` holds tuples and lists)."""
    for x, y in zip(a[:4], b[:4]):
        if x is not None:
            np.testing.assert_array_equal(x, y)
    ia, ib = a[4], b[4]
    assert sorted(ia) == sorted(ib)
    for key in ia:
        if key == "reward_terms":
            for t in ia[key]:
                np.testing.assert_array_equal(ia[key][t], ib[key][t])
        elif ia[key].dtype == object and not isinstance(ia[key][0], str):
            np.testing.assert_array_equal(np.array(list(ia[key]), float), ib[key])
        else:
            np.testing.assert_array_equal(ia[key], ib[key])


@pytest.mark.parametrize(
    ("seed", "kw"),
    [
        (11, {"max_steps": 120}),
        ([3, 1, 4, 1, 5, 9, 2, 6], {"world": "koolio-real-dr", "max_episode_steps": 70}),
        (0, {"config": "paper-memory-qlambda", "goal": "random"}),
    ],
)
def test_the_compiled_vector_env_is_sync_of_gym_make(seed, kw):
    """The same observations, rewards, terminations, truncations and info as
    ``SyncVectorEnv`` of ``gym.make`` envs with the same seeds, through staggered
    autoresets, rescues and both caps (the env's own and ``TimeLimit``'s)."""
    rescue = {"rescue": {"max_steps_before_rescue": 4, "rescue_chance": 0.5}}
    from koolio_pymunk.store.config import load_config

    cfg = load_config(kw.pop("config", None), overrides=rescue)
    sync = _rollout("sync", 8, seed, 300, config=cfg, **kw)
    native = _rollout("vector_entry_point", 8, seed, 300, config=cfg, **kw)
    for a, b in zip(sync, native):
        _same(a, b)
    steps = sync[1:]
    ends = sum(int(s[2].sum() + s[3].sum()) for s in steps)
    rescued = sum(int(s[4]["rescued"].sum()) for s in steps)
    assert ends >= 8 and rescued >= 4  # the premise: autoresets and rescues happened


def test_reset_mask_resets_only_the_masked_envs():
    venv = gym.make_vec(ENV_ID, num_envs=3)
    try:
        venv.reset(seed=4)
        for _ in range(5):
            venv.step(np.array([3, 3, 3]))
        _, info = venv.reset(options={"reset_mask": np.array([False, True, False])})
        assert info["_steps"].tolist() == [False, True, False]
        assert info["steps"][1] == 0 and info["steps"][0] == 5 and info["steps"][2] == 5
        with pytest.raises(ValueError, match="reset_mask"):
            venv.reset(options={"reset_mask": [True, False, True]})
    finally:
        venv.close()


@pytest.mark.parametrize("actions", [[0, 5], [0.5, 1.0], [1, 2, 3], [-1, 0]])
def test_bad_actions_are_refused_before_anything_moves(actions):
    venv = gym.make_vec(ENV_ID, num_envs=2)
    try:
        obs, _ = venv.reset(seed=0)
        with pytest.raises(ValueError, match="actions"):
            venv.step(np.array(actions))
        again, *_ = venv.step(np.array([0, 0]))
        assert again.shape == obs.shape
    finally:
        venv.close()


def test_the_compiled_vector_env_renders_each_env():
    venv = gym.make_vec(ENV_ID, num_envs=2, render_mode="rgb_array")
    try:
        venv.reset(seed=[0, 1])
        frames = venv.render()
        assert len(frames) == 2 and frames[0].dtype == np.uint8 and frames[0].ndim == 3
    finally:
        venv.close()


def test_the_learners_keys_stack_in_vector_envs_of_any_id():
    """``action_mask``, ``observation_before_rescue`` and ``goal_index`` are in every
    ``info`` with one dtype and shape, so both vector modes stack them, through
    autoresets; a configuration given as a dict reaches the async workers (and the
    compiled vector env gives the same keys)."""
    kwargs = {"max_steps": 4, "config": {"learner": {"no_undo": True}}, "observe_goal": True}
    for mode in ("sync", "async", "vector_entry_point"):
        venv = gym.make_vec(
            "koolio_pymunk/HallwayAnyDoor-v0", num_envs=2, vectorization_mode=mode, **kwargs
        )
        try:
            obs, info = venv.reset(seed=[0, 1])
            assert info["action_mask"].dtype == np.int8 and info["action_mask"].shape == (2, 5)
            assert info["action_mask"].tolist() == [[1] * 5] * 2
            np.testing.assert_array_equal(info["observation_before_rescue"], obs)
            for _ in range(5):  # the 5th step autoresets both
                obs, *_, info = venv.step(np.array([1, 3]))
                assert info["observation_before_rescue"].shape == obs.shape == (2, 13)
                assert info["goal_index"].dtype == np.int64
                np.testing.assert_array_equal(obs[:, -1], info["goal_index"])
            assert list(info["event"]) == ["reset", "reset"]
            masks = info["action_mask"].tolist()
            assert masks == [[1] * 5] * 2
            _, _, _, _, info = venv.step(np.array([1, 3]))
            assert info["action_mask"].tolist() == [[1, 1, 0, 1, 1], [1, 1, 1, 1, 0]]
        finally:
            venv.close()
