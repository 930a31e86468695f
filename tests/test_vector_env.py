"""Gymnasium vector environments and render_mode="rgb_array"."""

from __future__ import annotations

import os

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

import gymnasium as gym
import numpy as np

import koolio_pymunk  # noqa: F401  (registers koolio_pymunk/Hallway-v0)

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
