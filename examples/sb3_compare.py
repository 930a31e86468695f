"""Stable-Baselines3 DQN and PPO on ``koolio_pymunk/Hallway-v0``, scored like ``koolio-pm eval``.

Not part of the package or its tests (PyTorch is large). In an environment with the
package::

    pip install stable-baselines3          # brings PyTorch
    python examples/sb3_compare.py --steps 100000 --seed 0

It checks the registered env with SB3's own ``check_env``, trains each algorithm with
SB3's default hyperparameters for ``--steps`` environment steps (the registered env:
``MultiDiscrete`` observation, which SB3 one-hot encodes; 1500-step ``TimeLimit``), then
runs the greedy policy (``deterministic=True``) for ``--episodes`` episodes from random
start headings and prints the share that reach the goal, end of world or step cap, and
the mean steps: the figures ``koolio-pm eval`` prints for a Q-table. The README compares
them with the tabular learner.
"""

from __future__ import annotations

import argparse
import json
import time

import gymnasium as gym
import numpy as np

import koolio_pymunk  # noqa: F401  (registers koolio_pymunk/Hallway-v0)

ENV_ID = "koolio_pymunk/Hallway-v0"


def evaluate(model, episodes: int, seed: int) -> dict[str, float]:
    """Greedy episodes of ``model``: outcome shares and mean steps."""
    env = gym.make(ENV_ID)
    outcomes, steps = [], []
    for e in range(episodes):
        obs, _ = env.reset(seed=seed + e)
        done = False
        while not done:
            action, _ = model.predict(obs, deterministic=True)
            obs, _, terminated, truncated, info = env.step(int(action))
            done = terminated or truncated
        outcomes.append(info["event"] if terminated else "step_cap")
        steps.append(info["steps"])
    env.close()
    return {
        "goal_rate": outcomes.count("goal") / episodes,
        "end_of_world_rate": outcomes.count("end_of_world") / episodes,
        "step_cap_rate": outcomes.count("step_cap") / episodes,
        "mean_steps": float(np.mean(steps)),
    }


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--algos", nargs="+", default=["dqn", "ppo"], choices=["dqn", "ppo"])
    p.add_argument("--steps", type=int, default=100_000, help="training steps per algorithm")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--episodes", type=int, default=100, help="greedy evaluation episodes")
    p.add_argument("--threads", type=int, default=1, help="torch threads (small networks: 1)")
    args = p.parse_args()

    import torch
    from stable_baselines3 import DQN, PPO

    torch.set_num_threads(args.threads)
    from stable_baselines3.common.env_checker import check_env

    check_env(gym.make(ENV_ID).unwrapped)
    print(f"SB3 check_env({ENV_ID}): ok")
    for name in args.algos:
        algo = {"dqn": DQN, "ppo": PPO}[name]
        model = algo("MlpPolicy", gym.make(ENV_ID), seed=args.seed, device="cpu")
        started = time.perf_counter()
        model.learn(total_timesteps=args.steps)
        seconds = time.perf_counter() - started
        result = {"algo": name, "steps": args.steps, "seed": args.seed, "train_s": seconds}
        result |= evaluate(model, args.episodes, seed=10_000 + args.seed)
        print(json.dumps(result))


if __name__ == "__main__":
    main()
