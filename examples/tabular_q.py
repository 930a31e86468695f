"""A tabular Q-learner from outside the package: Gymnasium's API and the env's info only.

It learns as `koolio-pm train --config one-step-q` does (Table 11 with that profile's
settings, the update from info["observation_before_rescue"], then the next choice from the
rescued robot's observation; only actions of info["action_mask"]), then scores its greedy
policy as `koolio-pm eval` does (docs/envs.md):  python examples/tabular_q.py --id
koolio_pymunk/Room-v0 --episodes 300 [--no-undo]
"""

import argparse

import gymnasium as gym
import numpy as np

import koolio_pymunk  # noqa: F401  (registers the ids)

ALPHA, GAMMA, Q_INIT = 0.2, 0.98, -30.0  # learner.alpha, gamma, q_init: one-step-q's


def epsilon(episode: int) -> float:  # learner.epsilon: 0.15 -> 0.01 over 600 episodes
    return 0.15 + (0.01 - 0.15) * min(episode, 600) / 600


def choose(q: dict, s: tuple, mask: np.ndarray, eps: float, rng: np.random.Generator) -> int:
    allowed = np.flatnonzero(mask)  # a new state's action, or exploring: any allowed one
    if s not in q or rng.random() < eps:
        return int(allowed[rng.integers(len(allowed))])
    row = q[s][allowed]
    best = allowed[row == row.max()]  # greedy, ties broken at random
    return int(best[rng.integers(len(best))])


def episode(env: gym.Env, q: dict, eps: float, rng: np.random.Generator, learn: bool) -> bool:
    obs, info = env.reset()
    while True:
        s, a = tuple(obs), choose(q, tuple(obs), info["action_mask"], eps, rng)
        obs, reward, terminated, truncated, info = env.step(a)
        if learn:  # the paper's order: update from where the action led, then the rescue
            nxt = q.get(tuple(info["observation_before_rescue"]))
            best = Q_INIT if nxt is None else nxt.max()
            row = q.setdefault(s, np.full(5, Q_INIT))
            row[a] += ALPHA * ((reward if terminated else reward + GAMMA * best) - row[a])
        if terminated or truncated:
            return terminated and info["event"] == "goal"


def run(env_id: str, episodes: int, evals: int, seed: int, no_undo: bool, **kw) -> float:
    """Train for ``episodes``, then the greedy policy's goal rate over ``evals`` (``kw``:
    more of the env's arguments, e.g. ``max_steps``)."""
    rule = {"overrides": {"learner": {"no_undo": no_undo}}}  # what info["action_mask"] says
    env = gym.make(env_id, **rule, **kw)
    q, rng = {}, np.random.default_rng(seed)
    env.reset(seed=seed)
    for e in range(episodes):
        episode(env, q, epsilon(e), rng, learn=True)
    env.reset(seed=seed + 2**32)  # other starts than training's
    return sum(episode(env, q, 0.0, rng, learn=False) for _ in range(evals)) / evals


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--id", default="koolio_pymunk/Room-v0")
    p.add_argument("--episodes", type=int, default=300)
    p.add_argument("--eval-episodes", type=int, default=100)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--no-undo", action="store_true", help="the no-undo rule (learner.no_undo)")
    a = p.parse_args()
    rate = run(a.id, a.episodes, a.eval_episodes, a.seed, a.no_undo)
    print(f"greedy goal rate: {rate:.0%} ({a.eval_episodes} episodes)")
