"""Measure the learning targets of ``docs/learning.md``, many seeds, and print them.

Three targets (each a multi-seed measurement; nothing here is timed):

* ``paper``: the ``paper`` profile on the default delivery: train up to ``--paper-episodes``
  (3,000) episodes, a 100-episode greedy evaluation every ``--paper-every`` (250); the
  target is >= 90 % greedy goal rate for every seed 0-4 within the budget. Two
  more targets: the kept best table (``train --eval-every``) scores >= 95 % on a fresh
  ``--fresh-episodes`` (200) episode evaluation, and the last third of the checks never
  falls below 85 %, for every seed.
* ``default``: episodes to competence (>= 90 % of a 100-episode greedy evaluation,
  checked every ``--every`` = K episodes, 25 by default) for seeds 0-9, for the
  configuration measured (the default, Q(lambda) with the no-undo rule; with ``--set``
  or ``--config`` another) and for the ``one-step-q`` profile (the paper's learner with
  the settings that were the default before); the targets: a median of at most 100
  episodes and no seed over 200, its training time to competence under 0.5 s (the CPU
  time of ``train`` without its checks), and 3x fewer episodes than one-step Q.
* ``random``: ``train --goal random`` for ``--random-episodes`` (20,000) episodes with a
  greedy check of ``--random-check-episodes`` (200) random-door episodes every
  ``--random-every`` (1,000), then ``eval --goal all --episodes 100 --seed 7`` of the last
  table and of the kept best one; the target is >= 99 % over all doors.

Training is :func:`koolio_pymunk.learning.training.train` itself, with its table and log files in
a temporary folder (a run checked every K episodes resumes its table, which continues
exactly like an uninterrupted run); the checks are ``train``'s own (``--eval-every K
--eval-episodes 100``: the run's seed, as ``koolio-pm eval`` does, the best table kept);
``--goal all`` evaluates with seed 7.

For every seed of ``paper`` and ``default`` it prints the best check, the final check,
the lowest check in the last third of the checks (the last ``ceil(n / 3)`` of ``n``), and
the goal rates of the kept best table and of the last table on a fresh evaluation of
``--fresh-episodes`` episodes with seed ``1,000,000 + seed`` (starts no check used).

    nice .venv/bin/python tools/learning_targets.py default --set learner.algorithm=qlambda
    nice .venv/bin/python tools/learning_targets.py default --config qlambda-no-undo  # met
    nice .venv/bin/python tools/learning_targets.py paper --set learner.algorithm=dyna
    nice .venv/bin/python tools/learning_targets.py paper --config paper-memory-qlambda  # met
    nice .venv/bin/python tools/learning_targets.py random --workers 2 --out random.json

``--set KEY=VALUE`` (repeatable; VALUE is YAML) overrides the target's configuration;
``--config`` replaces its profile. Runs go to ``--workers`` processes (2 by default).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import yaml

TARGETS = ("paper", "default", "random")
#: Greedy episodes of each check.
CHECK_EPISODES = 100
#: The fresh evaluation of the kept best table uses seed FRESH_SEED_OFFSET + the run's seed.
FRESH_SEED_OFFSET = 1_000_000


def overrides_of(pairs: list[str]) -> dict[str, Any]:
    """``["learner.alpha=0.1"]`` -> ``{"learner": {"alpha": 0.1}}``."""
    from koolio_pymunk.apps.sweep import expand_dotted

    flat = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep:
            raise SystemExit(f"--set {pair}: expected KEY=VALUE")
        flat[key] = yaml.safe_load(value)
    return expand_dotted(flat)


def run_job(job: dict[str, Any]) -> dict[str, Any]:
    """Train one seed with periodic greedy evaluations (see the module doc)."""
    from koolio_pymunk.learning.evaluation import evaluate
    from koolio_pymunk.learning.training import train
    from koolio_pymunk.store.check_files import best_path
    from koolio_pymunk.store.config import load_config
    from koolio_pymunk.store.qtable import QTableStore, load_qtable
    from koolio_pymunk.task.env import KoolioEnv

    cfg = load_config(job["config"], overrides=job["overrides"])
    goal = job["goal"]
    env = KoolioEnv("hallway", config=cfg, goal=goal)
    seed, every, budget = job["seed"], job["every"], job["episodes"]
    checks, reached, done, train_s = [], None, 0, 0.0
    started = time.process_time()
    with tempfile.TemporaryDirectory(prefix="koolio-targets-") as tmp:
        store = QTableStore(Path(tmp) / "t.qtable", warn=lambda msg: None)
        checking = {"eval_every": every, "eval_episodes": CHECK_EPISODES}
        if goal == "random":
            checking = {"eval_every": job["check_every"], "eval_episodes": job["check_episodes"]}
        while done < budget:
            n = min(every, budget - done)
            t0 = time.process_time()
            res = train(env, store, n, seed, Path(tmp) / "t.csv", report=None, **checking)
            train_s += time.process_time() - t0 - sum(c.seconds for c in res.checks)
            done += n
            if goal == "random":
                continue
            if res.checks and res.checks[-1].episode == done:
                rate = res.checks[-1].result.goal_rate
            else:  # a last stretch shorter than K: checked, not kept
                rate = evaluate(env, res.table, CHECK_EPISODES, seed).goal_rate
            checks.append([done, rate])
            if rate >= 0.9 and reached is None:
                reached = done
                if job["stop"]:
                    break
        out: dict[str, Any] = {"checks": checks, "reached": reached, "episodes": done}
        if goal == "random":
            doors = env.arena.goal_names()
            tables = [("last", res.table)]
            best = best_path(store.path)
            if best.exists():  # a check ran
                tables.append(("best", load_qtable(best)))
                out["kept_best"] = tables[-1][1].meta["best"]
            for key, table in tables:
                rates = [evaluate(env, table, 100, 7, goal=g).goal_rate for g in doors]
                out[key] = {"doors": dict(zip(doors, rates)), "mean": sum(rates) / len(rates)}
        else:
            out["final"] = checks[-1][1]
            out.update(summary(checks))
            last = evaluate(env, res.table, job["fresh"], FRESH_SEED_OFFSET + seed)
            out["final_fresh"] = last.goal_rate  # the last table, on the same fresh starts
            best = best_path(store.path)
            if best.exists():
                table = load_qtable(best)
                fresh = evaluate(env, table, job["fresh"], FRESH_SEED_OFFSET + seed)
                out["kept_best"] = dict(table.meta["best"], fresh=fresh.goal_rate)
        out.update(
            states=len(res.table),
            train_cpu_s=round(train_s, 3),
            cpu_s=round(time.process_time() - started, 1),
        )
    return job | out


def summary(checks: list[list]) -> dict[str, Any]:
    """The best check, and the lowest of the last third (``ceil(n / 3)`` of ``n``).

    >>> summary([[1, 0.5], [2, 0.9], [3, 0.7], [4, 0.8]])
    {'best_check': [2, 0.9], 'last_third': 2, 'lowest_last_third': [3, 0.7]}
    """
    k = math.ceil(len(checks) / 3)
    best = max(checks, key=lambda c: c[1])  # the first of equal ones
    low = min(checks[-k:], key=lambda c: c[1])
    return {"best_check": best, "last_third": k, "lowest_last_third": low}


def jobs_for(target: str, args: argparse.Namespace) -> list[dict[str, Any]]:
    extra = overrides_of(args.set)
    base = {"overrides": extra, "goal": None, "stop": False, "fresh": args.fresh_episodes}
    if target == "paper":
        cfg = args.config or "paper"
        return [
            base | {"target": target, "label": "measured", "config": cfg, "seed": s,
                    "every": args.paper_every, "episodes": args.paper_episodes}
            for s in (args.seeds or [0, 1, 2, 3, 4])
        ]  # fmt: skip
    if target == "default":
        out = []
        # the baseline is one-step Q with the earlier default's settings, whatever --config
        labels = [("measured", args.config, extra)]
        labels += [] if args.no_baseline else [("one-step Q", "one-step-q", {})]
        for label, config, ov in labels:
            for s in args.seeds if args.seeds is not None else range(10):
                out.append(
                    base | {"target": target, "label": label, "config": config,
                            "overrides": ov, "seed": s, "every": args.every,
                            "episodes": args.max_episodes, "stop": True}
                )  # fmt: skip
        return out
    return [
        base | {"target": target, "label": "measured", "config": args.config, "goal": "random",
                "seed": s, "every": args.random_episodes, "episodes": args.random_episodes,
                "check_every": args.random_every, "check_episodes": args.random_check_episodes}
        for s in (args.seeds or [0])
    ]  # fmt: skip


def report(target: str, results: list[dict[str, Any]]) -> None:
    print(f"\n== {target} ==  configuration: {results[0]['config'] or 'default'} + "
          f"{json.dumps(results[0]['overrides'])}")  # fmt: skip
    if target == "random":
        for r in results:
            for key, name in (("last", "the last table"), ("best", "the kept best table")):
                got = r.get(key)
                if got is None:
                    print(f"  seed {r['seed']}: no check ran, no best table kept")
                    continue
                worst = min(got["doors"].items(), key=lambda kv: kv[1])
                when = f" (episode {r['kept_best']['episode']})" if key == "best" else ""
                print(
                    f"  seed {r['seed']}, {name}{when}: {got['mean']:.1%} over "
                    f"{len(got['doors'])} doors (worst {worst[0]} {worst[1]:.0%}), "
                    f"{r['episodes']} episodes, {r['train_cpu_s']:.0f} CPU s of training "
                    f"-> target >= 99 %: {'met' if got['mean'] >= 0.99 else 'NOT met'}"
                )
        return
    by_label: dict[str, list[dict[str, Any]]] = {}
    for r in results:
        by_label.setdefault(r["label"], []).append(r)
    for label, rs in by_label.items():
        for r in rs:
            curve = " ".join(f"{e}:{g:.0%}" for e, g in r["checks"])
            got = f"first >= 90 % at {r['reached']}" if r["reached"] else "never >= 90 %"
            print(f"  {label:<10} seed {r['seed']}: {got}; final {r['final']:.0%}; "
                  f"{r['train_cpu_s']:.0f} CPU s; {curve}")  # fmt: skip
            print(f"  {'':<10} {held(r)}")
    if target == "paper":
        ok = all(r["reached"] for r in results)
        print(f"  target (>= 90 % for every seed within the budget): {'met' if ok else 'NOT met'}")
        kept = all(r.get("kept_best", {}).get("fresh", 0.0) >= 0.95 for r in results)
        floor = all(r["lowest_last_third"][1] >= 0.85 for r in results)
        print(
            f"  target (kept best >= 95 % on a fresh evaluation, every seed): "
            f"{'met' if kept else 'NOT met'}; (the last third of the checks never below "
            f"85 %, every seed): {'met' if floor else 'NOT met'}"
        )
        return
    cap = max(r["episodes"] for r in results)

    def episodes(rs: list[dict[str, Any]]) -> list[int]:
        return [r["reached"] or cap for r in rs]

    new = episodes(by_label["measured"])
    median = (
        sorted(new)[len(new) // 2]
        if len(new) % 2
        else sum(sorted(new)[len(new) // 2 - 1 :][:2]) / 2
    )
    slowest = max(r["train_cpu_s"] for r in by_label["measured"])
    ok = median <= 100 and max(new) <= 200
    print(
        f"  episodes to competence: median {median:g}, most {max(new)} -> target (median <= "
        f"100, none over 200): {'met' if ok else 'NOT met'}; training CPU time to "
        f"competence, slowest seed {slowest:.2f} s -> target < 0.5 s: "
        f"{'met' if slowest < 0.5 else 'NOT met'}"
    )
    if "one-step Q" in by_label:
        old = episodes(by_label["one-step Q"])
        ratio = sum(old) / max(1, sum(new))
        print(
            f"  episodes to competence: measured {new}, one-step Q {old} "
            f"(a run that never reached it counts its budget); one-step Q / measured = "
            f"{ratio:.2f} -> target >= 3: {'met' if ratio >= 3 else 'NOT met'}"
        )


def held(r: dict[str, Any]) -> str:
    """A seed's best check, final check, lowest of the last third, kept best table."""
    (be, bg), (le, lg) = r["best_check"], r["lowest_last_third"]
    text = (
        f"best check {bg:.0%} at {be}; final {r['final']:.0%}; lowest of the last "
        f"{r['last_third']} checks {lg:.0%} at {le}"
    )
    kept = r.get("kept_best")
    fresh = f"on a fresh {r['fresh']}-episode evaluation"
    if kept is None:
        return text + f"; no best table kept; the last table {r['final_fresh']:.1%} {fresh}"
    return text + (
        f"; kept best (episode {kept['episode']}, check {kept['goal_rate']:.0%}) "
        f"{kept['fresh']:.1%}, the last table {r['final_fresh']:.1%}, {fresh}"
    )


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    p.add_argument("targets", nargs="*", choices=[*TARGETS, []], default=list(TARGETS))
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    p.add_argument("--config", default=None, help="profile or file instead of the target's")
    p.add_argument("--seeds", type=int, nargs="*", default=None)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--every", type=int, default=25, help="K of the default target (25)")
    p.add_argument("--max-episodes", type=int, default=600, help="default target's budget")
    p.add_argument("--no-baseline", action="store_true", help="default: skip one-step Q")
    p.add_argument("--paper-episodes", type=int, default=3000)
    p.add_argument("--paper-every", type=int, default=250)
    p.add_argument("--random-episodes", type=int, default=20_000)
    p.add_argument("--random-every", type=int, default=1000, help="random: episodes per check")
    p.add_argument(
        "--random-check-episodes", type=int, default=200, help="random: episodes of a check"
    )
    p.add_argument(
        "--fresh-episodes", type=int, default=200, help="fresh evaluation of the kept best table"
    )
    p.add_argument("--out", default=None, help="write every result as JSON here")
    args = p.parse_args(argv)
    jobs = [j for t in args.targets for j in jobs_for(t, args)]
    from koolio_pymunk.store.config import load_config
    from koolio_pymunk.store.errors import KoolioError

    for job in jobs:  # a bad --set or --config: one line now, not a worker's traceback
        try:
            load_config(job["config"], overrides=job["overrides"])
        except KoolioError as exc:
            print(f"learning_targets: error: {exc}", file=sys.stderr)
            return 2
    print(f"{len(jobs)} runs on {args.workers} worker processes")
    with ProcessPoolExecutor(args.workers) as pool:
        results = list(pool.map(run_job, jobs))
    for t in args.targets:
        report(t, [r for r in results if r["target"] == t])
    if args.out:
        Path(args.out).write_text(json.dumps(results, indent=1) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
