"""Measure the shared-arena learning targets of ``docs/multi-robot.md``, many seeds.

Two targets (each a multi-seed measurement; nothing here is timed):

* ``four``: 4 robots in the hallway sharing one arena and one table, all delivering to
  311 from the start area, trained for ``--episodes`` (4,000) episodes in all;
* ``crossing``: the shipped ``examples/crossing.yaml`` (robot 0 from the stairs end to
  311, robot 1 from the far end to 302 near the stairs): 2 robots, 10,000 episodes.

Training is :func:`koolio_pymunk.learning.training.train` itself, as ``koolio-pm train
--robots N --shared-arena --eval-every K --eval-episodes 200`` runs it (its table, log and
kept best table in a temporary folder): every ``--every`` episodes a check plays 200
greedy episodes with the N robots in the arena, and the table whose *worst* robot did
best is kept. Then the kept best table and the last table are scored on a fresh
evaluation (:func:`koolio_pymunk.learning.evaluation.evaluate`, as ``koolio-pm eval
--robots N --shared-arena --episodes 200 --seed`` 1,000,000 + the seed: starts no check
used). The target: every robot's greedy goal rate >= 90 % in the fresh evaluation of the
kept best table, seeds 0-2. It prints every check's worst robot, and both fresh
evaluations robot by robot.

    nice .venv/bin/python tools/multi_robot_targets.py four crossing --seeds 0 1 2

``--tables each`` runs the same plans with each robot learning its own rows of the table
(``train --tables each``), for docs/multi-robot.md's comparison.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: Each robot's greedy goal rate to reach.
TARGET = 0.90
#: Greedy episodes of each check and of the fresh evaluations.
EVAL_EPISODES = 200
#: The fresh evaluations' seed is this plus the run's.
FRESH_SEED = 1_000_000
#: target -> (robots, config file or None, episodes in all, episodes between checks).
PLANS = {
    "four": (4, None, 4000, 500),
    "crossing": (2, str(ROOT / "examples" / "crossing.yaml"), 10000, 1000),
}


def run(
    name: str,
    seed: int,
    episodes: int | None = None,
    every: int | None = None,
    tables: str = "shared",
) -> dict:
    """Target ``name``'s run of ``seed`` (module doc; ``tables`` ``each``: each robot
    learns its own rows, ``train --tables each``)."""
    from koolio_pymunk.learning.evaluation import evaluate
    from koolio_pymunk.learning.training import train
    from koolio_pymunk.store.check_files import best_path
    from koolio_pymunk.store.qtable import QTableStore
    from koolio_pymunk.task.env import KoolioEnv

    robots, config, total, chunk = PLANS[name]
    total, chunk = episodes or total, every or chunk
    t = time.process_time()
    with tempfile.TemporaryDirectory() as folder:
        table, log = Path(folder) / "t.qtable", Path(folder) / "t.csv"
        store = QTableStore(table)
        res = train(KoolioEnv("hallway", config=config), store, total, seed, log, report=None,
                    robots=robots, shared_arena=True, eval_every=chunk,
                    eval_episodes=EVAL_EPISODES, own_tables=tables == "each")  # fmt: skip
        store.close()
        fresh = {}
        for which, path in (("best", best_path(table)), ("last", table)):
            scored = evaluate(KoolioEnv("hallway", config=config), QTableStore(path).peek(),
                              EVAL_EPISODES, FRESH_SEED + seed, robots=robots,
                              shared_arena=True)  # fmt: skip
            fresh[which] = {"rates": scored.robot_goal_rates, "goals": scored.robot_goals}
    checks = [{"episodes": c.episode, "worst": c.result.goal_rate} for c in res.checks]
    return {
        "target": name,
        "tables": tables,
        "seed": seed,
        "checks": checks,
        "fresh": fresh,
        "met": min(fresh["best"]["rates"]) >= TARGET,
        "cpu_s": round(time.process_time() - t, 1),
    }


def _rates(f: dict) -> str:
    return "  ".join(
        f"robot {k} ({g}) {v:6.1%}" for k, (g, v) in enumerate(zip(f["goals"], f["rates"]))
    )


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("targets", nargs="+", choices=sorted(PLANS))
    p.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    p.add_argument("--episodes", type=int, default=None, help="episodes in all (the plan's)")
    p.add_argument("--every", type=int, default=None, help="episodes between checks (the plan's)")
    p.add_argument("--out", default=None, help="also write the figures as JSON")
    p.add_argument(
        "--tables",
        choices=("shared", "each"),
        default="shared",
        help="one table all robots learn (the targets') or each robot its own rows",
    )
    args = p.parse_args(argv)
    results = []
    for name in args.targets:
        robots, _, total, _ = PLANS[name]
        print(
            f"{name}: {robots} robots sharing the hallway, up to {args.episodes or total}, "
            f"tables {args.tables}"
        )
        for seed in args.seeds:
            r = run(name, seed, args.episodes, args.every, args.tables)
            results.append(r)
            worst = "  ".join(f"{c['episodes']}: {c['worst']:.0%}" for c in r["checks"])
            print(f"  seed {seed}  checks (worst robot): {worst}")
            print(f"  seed {seed}  best table, fresh: {_rates(r['fresh']['best'])}")
            print(f"  seed {seed}  last table, fresh: {_rates(r['fresh']['last'])}")
            verdict = "met" if r["met"] else "NOT met"
            print(f"  seed {seed}: {verdict}; {r['cpu_s']} s CPU")
        met = all(r["met"] for r in results if r["target"] == name)
        print(f"{name}: {'met' if met else 'NOT met'} for seeds {args.seeds}")
    if args.out:
        Path(args.out).write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
