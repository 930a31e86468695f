"""koolio-pymunk's speed benchmark: steps/s, time to competence, memory, where time goes.

Every episode, one robot or many, training or evaluation, runs on one compiled step engine
(``learning/engine.py`` over ``task/step_kernel.py``); its Python reference is the loop
of ``learning/episodes.py`` (``compiled=False``). Sections, in the order they run (each
prints its rows; all go to ``--out`` as JSON; ``--only NAME ...`` runs some of them):

* ``one-robot``: one robot learning in the hallway, without file I/O: the Python loop on
  the pymunk reference sensors (``reference``), the engine (what ``koolio-pm train``
  runs) and the Python loop on the same fast backend, with the default learner (Q(lambda)
  and the no-undo rule) and with ``--config one-step-q`` (one-step Q, all five actions);
  steps per second and the ratios;
* ``koolio-real``: the engine in the realistic world (``--world koolio-real``: every
  realism model on) and its ratio to the ideal world; then the same world with one family
  of its models off (:func:`realism_without`: the motion errors; the sonar's beam model),
  which says where its extra cost per step goes;
* ``paper-memory``: the engine and the Python loop with ``--config paper-memory`` (the
  paper's learner; the goal camera and the last action remembered in the state);
* ``train``: :func:`training.train` as ``koolio-pm train`` runs it, end to end (the table
  and the log written): ``--fsync second`` (the default: the table written whole at most
  once a second, each episode's changes to its journal), ``--fsync episode`` (the paper's
  rule: written and fsynced at every episode end) and ``--save-every 100`` with each; then
  IR-SIM (``ir-sim``, the ``compare`` extra) stepping the same hallway with an 88-beam
  lidar (``tools/irsim_compare.py``, collision mode ``stop``) and the default row's ratio
  to it, skipped with a note when ir-sim is not installed;
* ``eval``: :func:`evaluation.evaluate` (``koolio-pm eval``, the checks of ``train
  --eval-every``), greedy, of a table trained for 300 episodes: on the engine with one
  robot (what ``eval`` runs), with 64 robots, and in the Python loop; episodes and steps
  per second;
* ``checks``: ``koolio-pm train --episodes 3000 --eval-every 250``: the share of the run
  spent in its checks (:class:`~koolio_pymunk.learning.evaluation.PeriodicCheck`, timed
  around each check; and the seconds ``train`` writes in the evaluations file), and the
  bound a share of 15 % puts on a greedy step: the CPU time per greedy step of the checks
  against per training step, and the most that ratio may be for 15 %;
* ``robots``: ``koolio-pm train --robots 64`` end to end, robot-steps per second: with
  ``--config one-step-q``, with the default learner, and with the default learner in
  ``--world koolio-real``; then where a robot-step's time goes (CPU timers around the
  compiled steps and the Python between episodes, :func:`many_where`) and a cProfile of
  the same run;
* ``vector``: ``gymnasium.make_vec("koolio_pymunk/Hallway-v0", num_envs=64)`` (the
  compiled vector env, ``task/vector_env.py``) stepped with random actions, against
  Gymnasium's ``SyncVectorEnv`` of 64 ``KoolioEnv`` (``vectorization_mode="sync"``);
  env-steps per second;
* ``motion``: the cost of one 12-inch move from the same seeded random free poses of the
  hallway (near a wall: within 12 in of one): the pymunk world's (``World.move``), the
  compiled move (``swept_move.move``) called from Python, and per move inside one
  compiled loop;
* ``algorithms``: the engine with each ``learner.algorithm`` in the default configuration
  (one-step Q and Q(lambda) on the engine and in the Python loop, Dyna-Q with its default
  ``planning_steps``, which runs the Python loop), the same number of steps from an empty
  table in this one run: the cost per step and its ratio to the engine's one-step Q;
* ``shared-arena``: the cost of one 12-inch move and of one reading of a robot among 7
  others in one hallway (``World(..., shared=True)``: :func:`shared_costs`), next to the
  same robot alone, each in a compiled loop over the same poses: the compiled move
  (``swept_move.move_among`` against ``move``) and the whole reading with its draws
  (``reading_kernel.sense_reading_among`` against ``sense_reading``), in the ideal world
  and in ``koolio-real`` (the shared arena's world and sensing; its episodes do not run
  on the engine yet);
* ``step-costs``: one step of the engine taken apart, each part timed in a compiled loop
  over the same recorded poses (:func:`step_costs`, one-step Q), in the ideal world and
  in ``koolio-real``;
* ``competence``, per seed: ``koolio-pm train`` (hallway) with the default learner and
  with ``--config one-step-q``, a greedy evaluation of 100 episodes after every
  ``--check-every`` episodes, until at least 90 % reach the goal; each seed runs in its
  own process, which also reports its own peak RSS (:func:`peak_rss_mib`) and its
  Q-table's size next to the paper's dense 113.9 MiB;
* ``profile``: cProfile of one robot learning on the engine, top 10 functions by own time;
* ``arena-check``: validating an arena whose walls are a 5,000-point ring, and a
  5,000-point star (random radii, so that many edges' bounding boxes overlap), as
  ``koolio-pm check-arena`` does after parsing (``docs/robustness.md``);
* ``agreement``: fast vs reference sensing on a sample of random poses per arena
  (``tools/agreement.py`` runs the full 100k);
* ``baseline`` (only with ``--baseline DIR``, a checkout of an earlier commit whose
  ``tools/bench.py`` has ``learning_loop`` and ``many``): the one-robot rows (the default
  learner's settings, ``--config qlambda-no-undo`` in both trees, and one-step Q) and the
  64-robot one-step Q row, each tree in its own process, alternately, and the ratios.

Every rate is given twice: per wall-clock second and per CPU second of the process
(``time.process_time``). On an idle machine they agree; on a shared one other processes
stretch wall time, and the CPU figure is the one to compare between runs.

    .venv/bin/python tools/bench.py --out bench.json         # about 15 minutes
    .venv/bin/python tools/bench.py --quick                   # about 3 minutes
    .venv/bin/python tools/bench.py --only robots vector      # some sections
    .venv/bin/python tools/bench.py --quick --scale 0.02 --seeds 0 --max-episodes 50
                                                              # every section, a smoke test
"""

from __future__ import annotations

import argparse
import cProfile
import json
import os
import platform
import pstats
import resource
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

if str(Path(__file__).resolve().parent) not in sys.path:  # the tools' own modules
    sys.path.insert(0, str(Path(__file__).resolve().parent))

from timing import Timer, rates

ROOT = Path(__file__).resolve().parent.parent
PAPER_DENSE_MIB = 113.9
ENV_ID = "koolio_pymunk/Hallway-v0"


def make_env(
    backend: str,
    arena: str = "hallway",
    world: str | None = None,
    algorithm: str | None = None,
    config: str | None = None,
):
    """A hallway env of ``config`` (a profile name; None: the default), its sensors'
    ``backend`` and, when given, its ``learner.algorithm``."""
    from koolio_pymunk.store.config import load_config
    from koolio_pymunk.task.env import KoolioEnv

    overrides: dict = {"sensors": {"backend": backend}}
    if algorithm is not None:
        overrides["learner"] = {"algorithm": algorithm}
    return KoolioEnv(arena, config=load_config(config, overrides=overrides, world=world))


def learning_loop(
    backend: str,
    min_steps: int,
    seed: int = 0,
    world: str | None = None,
    algorithm: str | None = None,
    compiled: bool = True,
    config: str | None = None,
    profiler: cProfile.Profile | None = None,
) -> dict:
    """One robot learning as ``train`` does, without file I/O, for at least ``min_steps``
    steps (``compiled`` False: the Python loop; True: the step engine where the
    configuration allows, as ``train``); ``profiler`` runs during the timed steps."""
    from koolio_pymunk.learning.algorithms import make_learner
    from koolio_pymunk.learning.engine import robots
    from koolio_pymunk.store.qtable import QTable

    def loop_of(env):
        table = QTable(env.layout, {}, env.config.learner.q_init)
        return robots(env, [make_learner(table, env.config.learner, None)], seed, compiled=compiled)

    warm = loop_of(make_env(backend, world=world, algorithm=algorithm, config=config))
    warm.begin(0, 0)  # compile / warm up the kernels on a copy
    warm.advance()
    loop = loop_of(make_env(backend, world=world, algorithm=algorithm, config=config))
    steps, e = 0, 0
    if profiler is not None:
        profiler.enable()
    with Timer() as t:
        while steps < min_steps:
            loop.begin(0, e)
            loop.advance()
            steps += loop.result(0).steps
            e += 1
    if profiler is not None:
        profiler.disable()
    out = rates(steps, t)
    out["episodes"] = e
    out["compiled"] = loop.python_reason is None
    return out


def best_cpu_us(fn: Callable[[], object], repeats: int, count: int) -> float:
    """Microseconds of CPU per item: the best of ``repeats`` calls of ``fn``, which does
    ``count`` items."""
    times = []
    for _ in range(repeats):
        t0 = time.process_time()
        fn()
        times.append(time.process_time() - t0)
    return round(1e6 * min(times) / count, 3)


def ratio(a: dict, b: dict, key: str = "per_cpu_s", digits: int = 2) -> float:
    """``a[key] / b[key]``, rounded."""
    return round(a[key] / max(1e-9, b[key]), digits)


def table_line(name: str, r: dict, extra: str = "") -> str:
    return (
        f"  {name:<44} {r['per_wall_s']:>10,} {r['per_cpu_s']:>10,}   "
        f"{r['steps']:>9,} steps {r['cpu_s']:>7.2f} CPU s  {extra}"
    )


def algorithms(min_steps: int) -> dict:
    """Each learning algorithm in the default configuration; cost per step and ratio to
    one-step Q on the engine (``q-python``, ``qlambda-python``: in the Python loop)."""
    out = {}
    for name in ("q", "q-python", "qlambda", "qlambda-python", "dyna"):
        algo = name.removesuffix("-python")
        r = learning_loop("fast", min_steps, seed=0, algorithm=algo, compiled=name == algo)
        r["us_per_step_cpu"] = round(1e6 * r["cpu_s"] / max(1, r["steps"]), 2)
        out[name] = r
    base = out["q"]["us_per_step_cpu"]
    for r in out.values():
        r["ratio_to_q_cpu"] = round(r["us_per_step_cpu"] / base, 2)
    return out


def end_to_end(
    episodes: int,
    folder: Path,
    save_every: int | None = None,
    fsync: str = "second",
    config: str | None = None,
) -> dict:
    """``koolio-pm train`` end to end, one robot (the table, its journal or backup, the
    log): steps per second."""
    from koolio_pymunk.learning.training import train
    from koolio_pymunk.store.qtable import QTableStore

    env = make_env("fast", config=config)
    name = f"e2e-{fsync}-{save_every}-{config}"
    with Timer() as t:
        res = train(
            env,
            QTableStore(folder / f"{name}.qtable"),
            episodes,
            0,
            folder / f"{name}.csv",
            report=None,
            save_every=save_every,
            fsync=fsync,
        )
    out = rates(res.steps, t)
    out.update(episodes=episodes, save_every=save_every or 1, fsync=fsync, config=config)
    return out


def irsim_row(steps: int, e2e: dict, folder: Path) -> dict | None:
    """IR-SIM stepping the hallway (``tools/irsim_compare.py``, collision ``stop``) and
    the ratio of ``e2e``'s CPU rate to it; None, with a printed note, without ir-sim."""
    if str(ROOT / "tools") not in sys.path:
        sys.path.insert(0, str(ROOT / "tools"))
    import irsim_world

    missing = irsim_world.irsim_missing()
    if missing:
        print(f"  IR-SIM row skipped: {missing}")
        return None
    path = folder / "hallway_irsim.yaml"
    path.write_text(irsim_world.world_yaml(irsim_world.hallway_world("stop")))
    out = irsim_world.drive_irsim(path, steps)
    out["ratio_train_to_irsim_cpu"] = round(e2e["per_cpu_s"] / max(1, out["per_cpu_s"]), 1)
    return out


def many(
    robots: int,
    episodes: int,
    folder: Path,
    config: str | None = None,
    world: str | None = None,
    profiler: cProfile.Profile | None = None,
    shared: bool = False,
) -> dict:
    """``koolio-pm train --robots N`` end to end (the table saved every N episodes, the
    log): robot-steps per second; ``profiler`` runs during the timed run; ``shared``: the
    robots share one hallway (``--shared-arena``, start spots within 200 in)."""
    from koolio_pymunk.learning.training import train
    from koolio_pymunk.store.config import load_config
    from koolio_pymunk.store.qtable import QTableStore
    from koolio_pymunk.task.env import KoolioEnv

    over = {"shared": {"start_spread": 200}} if shared else None

    def env():
        return KoolioEnv("hallway", config=load_config(config, world=world, overrides=over))

    tag = f"many-{robots}-{episodes}-{config}-{world}-{profiler is not None}-{shared}"
    tag = tag.replace("/", "_")
    warm = QTableStore(folder / f"{tag}-warm.qtable")
    train(env(), warm, 2, 0, None, report=None, robots=2, shared_arena=shared)  # compile
    first, store = env(), QTableStore(folder / f"{tag}.qtable")
    if profiler is not None:
        profiler.enable()
    with Timer() as t:
        res = train(
            first,
            store,
            episodes,
            0,
            folder / f"{tag}.csv",
            report=None,
            robots=robots,
            shared_arena=shared,
        )
    if profiler is not None:
        profiler.disable()
    out = rates(res.steps, t)
    out.update(robots=robots, episodes=episodes, states=len(res.table), config=config, world=world)
    return out


class CpuTimers:
    """CPU seconds and calls of some functions while a block runs: each ``(owner,
    name)`` attribute is replaced by a timed wrapper, and put back at the end."""

    def __init__(self, targets: list[tuple[object, str, str]]) -> None:
        self.targets = targets
        self.cpu: dict[str, float] = {label: 0.0 for _, _, label in targets}
        self.calls: dict[str, int] = {label: 0 for _, _, label in targets}
        self._saved: list[tuple[object, str, object]] = []

    def __enter__(self) -> CpuTimers:
        for owner, name, label in self.targets:
            original = getattr(owner, name)
            self._saved.append((owner, name, original))
            setattr(owner, name, self._wrap(original, label))
        return self

    def _wrap(self, fn: Callable, label: str) -> Callable:
        cpu, calls, clock = self.cpu, self.calls, time.process_time

        def timed(*args, **kwargs):
            t0 = clock()
            try:
                return fn(*args, **kwargs)
            finally:
                cpu[label] += clock() - t0
                calls[label] += 1

        return timed

    def __exit__(self, *exc: object) -> None:
        for owner, name, original in reversed(self._saved):
            setattr(owner, name, original)


def many_where(robots: int, episodes: int, folder: Path, config: str | None = None) -> dict:
    """Where a robot-step of ``train --robots N`` goes: CPU timers around the engine's
    compiled call (:func:`engine.run`, which returns at every finished episode) and the
    Python between episodes (the episode start: the env seed's ``SeedSequence``, the two
    generator states, one for the env and one for the learner, the env's reset and the
    load into the arrays; the log row and the save), µs per robot-step and per episode."""
    from koolio_pymunk.learning import engine, training
    from koolio_pymunk.store import run_files
    from koolio_pymunk.store.config import load_config
    from koolio_pymunk.store.qtable import QTableStore
    from koolio_pymunk.task import batch
    from koolio_pymunk.task.env import KoolioEnv

    def env():
        return KoolioEnv("hallway", config=load_config(config))

    train = training.train
    train(env(), QTableStore(folder / "where-warm.qtable"), 2, 0, None, report=None, robots=2)
    parts = [
        (engine, "run", "compiled steps (engine.run)"),
        (engine.Engine, "begin", "episode start (Engine.begin)"),
        (engine, "env_seed", "  env seed (SeedSequence)"),
        (batch, "pcg64_state", "  2 generator states (SeedSequence, PCG64)"),
        (KoolioEnv, "reset_key", "  env reset (KoolioEnv.reset_key)"),
        (batch.EnvBatch, "load", "  load into the arrays (EnvBatch.load)"),
        (engine.Engine, "result", "episode row (Engine.result)"),
        (run_files.RunFiles, "finished", "log row and saves (RunFiles.finished)"),
    ]
    with CpuTimers(parts) as timers, Timer() as t:
        res = train(
            env(),
            QTableStore(folder / "where.qtable"),
            episodes,
            0,
            folder / "where.csv",
            report=None,
            robots=robots,
        )
    steps, n_ep = max(1, res.steps), max(1, res.episodes_run)
    out: dict = {
        "robots": robots,
        "episodes": res.episodes_run,
        "steps": res.steps,
        "cpu_s": round(t.cpu, 3),
        "us_per_step": round(1e6 * t.cpu / steps, 3),
        "parts": {},
    }
    top = 0.0
    for _, _, label in parts:
        cpu = timers.cpu[label]
        if not label.startswith(" "):
            top += cpu
        out["parts"][label] = {
            "calls": timers.calls[label],
            "us_per_step": round(1e6 * cpu / steps, 3),
            "us_per_call": round(1e6 * cpu / max(1, timers.calls[label]), 2),
        }
    out["parts"]["the rest (train's loop, progress, Python around the calls)"] = {
        "calls": 0,
        "us_per_step": round(1e6 * (t.cpu - top) / steps, 3),
        "us_per_call": 0.0,
    }
    kernel = timers.cpu["compiled steps (engine.run)"]
    out["python_us_per_step"] = round(1e6 * (t.cpu - kernel) / steps, 3)
    out["python_us_per_episode"] = round(1e6 * (t.cpu - kernel) / n_ep, 1)
    return out


def vector_rows(n: int, vec_steps: int, sync_steps: int) -> dict:
    """``gymnasium.make_vec(ENV_ID, num_envs=n)`` (the compiled vector env) and its
    ``vectorization_mode="sync"`` (Gymnasium's ``SyncVectorEnv`` of ``n`` ``KoolioEnv``)
    stepped with seeded random actions: env-steps per second."""
    import gymnasium as gym
    import numpy as np

    import koolio_pymunk  # noqa: F401 (registers the env)

    out = {}
    for key, mode, steps in (("compiled", None, vec_steps), ("sync", "sync", sync_steps)):
        kw = {} if mode is None else {"vectorization_mode": mode}
        envs = gym.make_vec(ENV_ID, num_envs=n, **kw)
        actions = np.random.default_rng(0).integers(0, 5, (steps + 1, n))
        envs.reset(seed=0)
        envs.step(actions[0])  # compile / warm up
        with Timer() as t:
            for a in actions[1:]:
                envs.step(a)
        envs.close()
        out[key] = rates(steps * n, t)
        out[key].update(num_envs=n, class_name=type(envs).__name__)
    out["ratio_cpu"] = ratio(out["compiled"], out["sync"], digits=1)
    return out


def evaluation_rows(folder: Path, episodes: int, python_episodes: int, robots: int) -> dict:
    """``evaluate`` (greedy) of a table trained by default ``train`` for 300 episodes
    (seed 0): on the engine with one robot, with ``robots``, and in the Python loop."""
    from koolio_pymunk.learning.evaluation import evaluate
    from koolio_pymunk.learning.training import train
    from koolio_pymunk.store.qtable import QTableStore
    from koolio_pymunk.task.env import KoolioEnv

    table = train(
        KoolioEnv("hallway"), QTableStore(folder / "eval.qtable"), 300, 0, None, report=None
    ).table
    evaluate(KoolioEnv("hallway"), table, 2, 1, robots=2)  # compile / warm up
    out = {}
    rows = (
        ("engine", {}, episodes),
        (f"engine_{robots}", {"robots": robots}, episodes),
        ("python", {"compiled": False}, python_episodes),
    )
    for key, kw, n in rows:
        with Timer() as t:
            ev = evaluate(KoolioEnv("hallway"), table, n, 1, **kw)
        row = rates(round(ev.mean_steps * ev.episodes), t)
        row.update(
            episodes=n,
            goal_rate=ev.goal_rate,
            mean_steps=round(ev.mean_steps, 1),
            episodes_per_cpu_s=round(n / max(1e-9, t.cpu), 1),
            episodes_per_wall_s=round(n / max(1e-9, t.wall), 1),
            **kw,
        )
        out[key] = row
    out["ratio_engine_to_python_cpu"] = ratio(out["engine"], out["python"], digits=1)
    return out


def check_share(folder: Path, episodes: int, every: int) -> dict:
    """``train --episodes E --eval-every N`` (one robot, default learner, seed 0): CPU
    time in the checks (``PeriodicCheck.check``: the greedy evaluation of 100 episodes,
    keeping the best table, the evaluations file's row) against the whole run."""
    from koolio_pymunk.learning.evaluation import PeriodicCheck
    from koolio_pymunk.learning.training import train
    from koolio_pymunk.store.qtable import QTableStore
    from koolio_pymunk.task.env import KoolioEnv

    label = "checks"
    with CpuTimers([(PeriodicCheck, "check", label)]) as timers, Timer() as t:
        res = train(
            KoolioEnv("hallway"),
            QTableStore(folder / "checks.qtable"),
            episodes,
            0,
            folder / "checks.csv",
            report=None,
            eval_every=every,
        )
    check_cpu = timers.cpu[label]
    greedy = sum(round(c.result.mean_steps * c.result.episodes) for c in res.checks)
    train_cpu = t.cpu - check_cpu
    out = rates(res.steps, t)
    out.update(
        episodes=episodes,
        eval_every=every,
        checks=len(res.checks),
        check_cpu_s=round(check_cpu, 3),
        training_cpu_s=round(t.cpu - check_cpu, 3),
        check_share_cpu=round(check_cpu / max(1e-9, t.cpu), 3),
        greedy_steps=greedy,
        us_per_greedy_step=round(1e6 * check_cpu / max(1, greedy), 3),
        us_per_training_step=round(1e6 * train_cpu / max(1, res.steps), 3),
        # a share of 15 %: check_cpu <= 0.15 / 0.85 * train_cpu
        greedy_to_training_cost=round(
            (check_cpu / max(1, greedy)) / max(1e-12, train_cpu / max(1, res.steps)), 3
        ),
        greedy_to_training_cost_for_15=round(0.15 / 0.85 * res.steps / max(1, greedy), 3),
        check_seconds_reported=round(sum(c.seconds for c in res.checks), 3),
        train_seconds_reported=round(res.seconds, 3),
        last_goal_rate=res.checks[-1].result.goal_rate if res.checks else None,
    )
    out["check_share_reported"] = round(
        out["check_seconds_reported"] / max(1e-9, out["train_seconds_reported"]), 3
    )
    return out


def motion(poses: int, repeats: int = 5) -> dict:
    """Microseconds per 12-inch move from ``poses`` seeded random free poses of the
    hallway (best of ``repeats``): ``World.move`` (placing the robot not counted), the
    compiled move from Python, and the compiled move inside one compiled loop; ``near``
    rows: poses within 12 in of a wall."""
    import math

    import numba
    import numpy as np
    from move_agreement import free_points

    from koolio_pymunk.world.arena import load_arena
    from koolio_pymunk.world.physics import World
    from koolio_pymunk.world.segment_query import wall_array
    from koolio_pymunk.world.swept_move import move

    @numba.njit
    def loop(walls: np.ndarray, pts: np.ndarray, hs: np.ndarray, out: np.ndarray) -> None:
        for i in range(pts.shape[0]):
            out[i, 0], out[i, 1] = move(walls, pts[i, 0], pts[i, 1], hs[i], 12.0, 10.0)

    arena = load_arena("hallway")
    world = World.from_arena(arena, 10.0)
    walls = wall_array(world)
    rng = np.random.default_rng(0)
    pts = free_points(arena, 10.0, poses, rng)
    hs = rng.uniform(0.0, 2.0 * math.pi, poses)
    near = np.array([_near_wall(world, x, y) for x, y in pts])
    out = np.empty_like(pts)
    loop(walls, pts[:1], hs[:1], out[:1])  # compile

    def best(fn, sel: np.ndarray) -> float:
        """Best of ``repeats`` (the time ``fn`` returns, else its whole call's)."""
        times = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            inner = fn(sel)
            times.append(time.perf_counter() - t0 if inner is None else inner)
        return round(1e6 * min(times) / max(1, int(sel.sum())), 3)

    def pymunk_moves(sel: np.ndarray) -> float:
        t = 0.0
        for (x, y), h in zip(pts[sel], hs[sel]):
            world.place(0, (x, y), h)
            t0 = time.perf_counter()
            world.move(0, 12.0)
            t += time.perf_counter() - t0
        return t

    def compiled_calls(sel: np.ndarray) -> None:
        for (x, y), h in zip(pts[sel], hs[sel]):
            move(walls, x, y, h, 12.0, 10.0)

    def compiled_loop(sel: np.ndarray) -> None:
        loop(walls, pts[sel], hs[sel], out[: int(sel.sum())])

    out_rows: dict = {"poses": poses, "near_wall": int(near.sum())}
    for label, sel in (("all", np.ones(poses, bool)), ("near", near)):
        out_rows[f"pymunk_us_{label}"] = best(pymunk_moves, sel)
        out_rows[f"compiled_call_us_{label}"] = best(compiled_calls, sel)
        out_rows[f"compiled_loop_us_{label}"] = best(compiled_loop, sel)
    return out_rows


def shared_costs(poses: int, robots: int = 8, repeats: int = 5) -> dict:
    """Microseconds (CPU, best of ``repeats``) per 12-inch move and per reading of a robot
    among ``robots - 1`` others in the first 400 in of the hallway (poses and robots there,
    overlapping nobody: they meet often), against the same robot alone: the compiled move
    and the whole compiled reading (draws, rays, cameras, read-out), in the ideal world and
    in ``koolio-real``; each in one compiled loop."""
    import math

    import numba
    import numpy as np
    from move_agreement import free_points

    from koolio_pymunk.sensing.reading_kernel import (
        ReadingArrays,
        reading_group,
        robot_group,
        robot_others,
        sense_reading,
        sense_reading_among,
    )
    from koolio_pymunk.sensing.suite import SensorSuite
    from koolio_pymunk.store.config import Config, apply_world
    from koolio_pymunk.world.arena import load_arena
    from koolio_pymunk.world.physics import World
    from koolio_pymunk.world.segment_query import wall_array
    from koolio_pymunk.world.swept_move import move, move_among

    @numba.njit
    def moves_alone(walls, pts, hs, out):
        for i in range(pts.shape[0]):
            out[i, 0], out[i, 1] = move(walls, pts[i, 0], pts[i, 1], hs[i], 12.0, 10.0)

    @numba.njit
    def moves_among(walls, robots, present, pts, hs, out):
        for i in range(pts.shape[0]):
            robots[0, 0], robots[0, 1] = pts[i, 0], pts[i, 1]
            out[i, 0], out[i, 1] = move_among(walls, robots, present, 0, pts[i, 0], pts[i, 1],
                                              hs[i], 12.0, 10.0)  # fmt: skip

    @numba.njit
    def reads_alone(pts, hs, rng, sense, keys):
        for i in range(pts.shape[0]):
            keys[i] = sense_reading(pts[i, 0], pts[i, 1], hs[i], rng, sense)[0]

    @numba.njit
    def reads_among(pts, hs, rng, shared, rows, robots, present, robot_rows, keys):
        sense = robot_group(0, shared, rows)
        others = robot_others(0, robots, present, robot_rows)
        for i in range(pts.shape[0]):
            robots[0, 0], robots[0, 1] = pts[i, 0], pts[i, 1]
            keys[i] = sense_reading_among(pts[i, 0], pts[i, 1], hs[i], rng, sense, others)[0]

    def best(fn) -> float:
        return best_cpu_us(fn, repeats, poses)

    arena = load_arena("hallway")
    laid = arena.to_world()
    rng = np.random.default_rng(0)
    spots = [p for p in free_points(arena, 10.0, 4000, rng) if p[0] < 400.0]
    alone = World(laid.segments(), 10.0)
    crowd = World(laid.segments(), 10.0, robots, shared=True)
    k = 1
    for p in spots:
        if k < robots and crowd.robot_clearance(k, p) > 0.0:
            crowd.place(k, p, 0.0)
            k += 1
    crowd.place(0, spots[0], 0.0)
    pts = np.array([p for p in spots if crowd.robot_clearance(0, p) > 0.0][:poses])
    pts = np.resize(pts, (poses, 2))
    hs = rng.uniform(0.0, 2.0 * math.pi, poses)
    walls = wall_array(alone)
    out = np.empty_like(pts)
    keys = np.empty(poses, np.int64)
    xy, present = crowd.xy, crowd.present
    row = {"poses": poses, "robots": robots}
    moves_alone(walls, pts[:1], hs[:1], out[:1])  # compile
    moves_among(walls, xy, present, pts[:1], hs[:1], out[:1])
    row["move_us_alone"] = best(lambda: moves_alone(walls, pts, hs, out))
    row["move_us_among"] = best(lambda: moves_among(walls, xy, present, pts, hs, out))
    met = np.empty_like(pts)
    moves_alone(walls, pts, hs, met)
    moves_among(walls, xy, present, pts, hs, out)
    row["moves_met_a_robot"] = int((met != out).any(axis=1).sum())
    for world in (None, "koolio-real"):
        cfg = Config() if world is None else apply_world(Config(), world)
        tag = "ideal" if world is None else world
        kw = dict(goal=laid.goal().at, markers=[m.at for m in laid.end_of_world],
                  realism=cfg.realism)  # fmt: skip
        mine = SensorSuite(cfg.sensors, crowd, robot=0, **kw)
        them = ReadingArrays([mine])
        them.load(0, mine)
        sense = reading_group(SensorSuite(cfg.sensors, alone, **kw))
        args = (them.shared, them.rows, xy, present, them.robot_rows)
        reads_alone(pts[:1], hs[:1], rng, sense, keys[:1])
        reads_among(pts[:1], hs[:1], rng, *args, keys[:1])
        row[f"read_us_alone_{tag}"] = best(
            lambda sense=sense: reads_alone(pts, hs, rng, sense, keys)
        )
        row[f"read_us_among_{tag}"] = best(lambda args=args: reads_among(pts, hs, rng, *args, keys))
    crowd.place(0, spots[0], 0.0)
    return row


def print_shared(sc: dict) -> None:
    print(
        f"  shared hallway, {sc['robots']} robots, us per robot (CPU, {sc['poses']} poses; "
        f"alone / among {sc['robots'] - 1} others): 12-inch move {sc['move_us_alone']:.3f} / "
        f"{sc['move_us_among']:.3f} ({sc['moves_met_a_robot']} moves met a robot); reading "
        f"{sc['read_us_alone_ideal']:.2f} / {sc['read_us_among_ideal']:.2f}, in koolio-real "
        f"{sc['read_us_alone_koolio-real']:.2f} / {sc['read_us_among_koolio-real']:.2f}"
    )


def step_costs(
    poses: int,
    step_us: float,
    repeats: int = 3,
    world: str | None = None,
    config: str | None = "one-step-q",
) -> dict:
    """Microseconds per robot-step of the step engine's parts, each in a compiled
    loop (best of ``repeats``) replaying ``poses`` steps of a seeded learning run in the
    hallway (the poses before each step, in order, so the ray directions' cache works as
    in a run): the reading (rays, cameras, noise draws, encoding; in ``world``, e.g.
    ``koolio-real``, with its realism models), the move of each step's action (with the
    world's motion errors), epsilon-greedy and the Table 11 update on the states read
    (one-step Q: ``config`` is the learner's profile, ``one-step-q``); ``step_us`` is the
    whole step (the engine's CPU time per step with the same learner) and the rest is
    judge, rescue check, the loop and Python between episodes."""
    import numba
    import numpy as np

    from koolio_pymunk.learning.algorithms import make_learner
    from koolio_pymunk.learning.episodes import Episodes
    from koolio_pymunk.learning.table_kernel import SharedTable, choose, new_journal, update
    from koolio_pymunk.sensing.reading_kernel import reading_group, sense_reading
    from koolio_pymunk.store.qtable import QTable
    from koolio_pymunk.world.segment_query import wall_array
    from koolio_pymunk.world.swept_move import act, world_group

    @numba.njit
    def sensing(pts, hs, rng, sense, keys):
        for i in range(pts.shape[0]):
            keys[i] = sense_reading(pts[i, 0], pts[i, 1], hs[i], rng, sense)[0]

    @numba.njit
    def moving(pts, hs, actions, rng, world, motion):
        s = 0.0
        for i in range(pts.shape[0]):
            s += act(actions[i], pts[i, 0], pts[i, 1], hs[i], rng, world, motion)[0]
        return s

    @numba.njit
    def learning(keys, rewards, arng, index, table, journal):
        for i in range(keys.shape[0] - 1):
            a = choose(keys[i], 0.15, arng, 5, index, table[0])[0]
            update(index, table, 0.2, 0.9, keys[i], a, rewards[i], keys[i + 1], False, 0, journal)

    env = make_env("fast", world=world, config=config)
    table = QTable(env.layout, {}, env.config.learner.q_init)
    agent = make_learner(table, env.config.learner, None)
    run = Episodes(env, agent, 0)  # record a learning run's steps (the Python loop)
    pts, hs, actions, episode = np.empty((poses, 2)), np.empty(poses), np.empty(poses, int), 0
    for i in range(poses):
        if i == 0 or run.outcome is not None:
            run.begin(episode)
            episode += 1
        x, y, h = env.world.pose(0)
        pts[i], hs[i] = (x, y), h
        run.step()
        actions[i] = env.last_action
    sense = reading_group(env.sensors)
    world = world_group(wall_array(env.world), env.world.radius, env.move_distance, env.turn_arc)
    m = env.motion
    motion = (
        np.zeros(5)
        if m is None
        else np.array([1.0, m.drift, m.drift_sigma, m.slip_sigma, m.turn_sigma])
    )
    rng = np.random.default_rng(0)
    rewards = rng.uniform(-10.0, 0.0, poses)
    keys = np.empty(poses, np.int64)

    def best(fn) -> float:
        return best_cpu_us(fn, repeats, poses)

    sensing(pts[:1], hs[:1], rng, sense, keys[:1])
    moving(pts[:1], hs[:1], actions[:1], rng, world, motion)

    def learn() -> None:
        sh = SharedTable(QTable(env.layout, {}, env.config.learner.q_init), poses + 1)
        learning(keys, rewards, np.random.default_rng(1), sh.index, sh.args(), new_journal(1, 0))

    out = {
        "poses": poses,
        "sense_us": best(lambda: sensing(pts, hs, rng, sense, keys)),
        "move_us": best(lambda: moving(pts, hs, actions, rng, world, motion)),
    }
    out["act_learn_us"] = best(learn)
    out["step_us"] = round(step_us, 3)
    out["rest_us"] = round(step_us - out["sense_us"] - out["move_us"] - out["act_learn_us"], 3)
    return out


def _near_wall(world, x: float, y: float) -> bool:
    """A wall within 12 in of the robot's edge at ``(x, y)``."""
    world.place(0, (x, y), 0.0)
    return world.wall_clearance() < 12.0


def profile_rows(pr: cProfile.Profile, top: int = 10) -> list[dict]:
    """The ``top`` functions by own time in ``pr``'s profile."""
    st = pstats.Stats(pr)
    total = sum(v[2] for v in st.stats.values())
    rows = sorted(st.stats.items(), key=lambda kv: kv[1][2], reverse=True)[:top]
    out = []
    for (file, line, name), (_cc, nc, tt, ct, _callers) in rows:
        where = f"{Path(file).name}:{line}({name})" if line else name
        out.append(
            {
                "function": where,
                "calls": nc,
                "tottime_s": round(tt, 3),
                "share": round(tt / total, 3),
                "cumtime_s": round(ct, 3),
            }
        )
    return out


def peak_rss_mib() -> float:
    """This process's peak resident memory, MiB: Linux's ``VmHWM`` (the peak of this
    program alone), else ``getrusage``'s ``ru_maxrss``, which on Linux keeps the parent's
    peak across ``exec``: a competence child started by a bench that had grown bigger
    reported the bench's memory, not its own."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return round(int(line.split()[1]) / 1024, 1)
    except OSError:
        pass
    return round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1)


def agreement_sample(poses: int) -> list[dict]:
    from sensing_agreement import compare_backends

    return [compare_backends(a, poses, seed=9).as_dict() for a in ("hallway", "room", "obstacles")]


def arena_check(points: int) -> dict:
    """Seconds to validate a ``points``-point ring and star arena (parsing excluded)."""
    import math
    import random

    from koolio_pymunk.world.arena import parse_arena

    rng = random.Random(1)
    out = {"points": points}
    for kind in ("ring", "star"):
        radii = [1000.0 if kind == "ring" else rng.uniform(300, 1000) for _ in range(points)]
        walls = [
            [r * math.cos(2 * math.pi * k / points), r * math.sin(2 * math.pi * k / points)]
            for k, r in enumerate(radii)
        ]
        data = {
            "name": kind,
            "walls": walls,
            "goals": [{"name": "g", "at": [0, 100]}],
            "start": {"at": [0, 0]},
        }
        with Timer() as t:
            parse_arena(data, kind)
        out[f"{kind}_s"] = round(t.wall, 3)
    return out


def machine() -> dict:
    return {
        "cpus": os.cpu_count(),
        "python": platform.python_version(),
        "platform": platform.platform(),
        "load_average": [round(x, 2) for x in os.getloadavg()],
    }


def realism_without(folder: Path) -> dict[str, Path]:
    """World files: ``koolio-real`` with its motion errors off, and with its sonar beam
    model off (every reading exact; the echo, incidence and range models stay)."""
    import yaml

    from koolio_pymunk.store.config import PROFILE_DIR

    parts = {  # name -> (file name's part, what to take out of the realism section)
        "motion errors": ("motion", lambda r: r.pop("motion")),
        "sonar beam model": (
            "beam",
            lambda r: r["sonar"].update(
                z_hit=1.0, z_short=0.0, z_max=0.0, z_rand=0.0, sigma_hit=0.0
            ),
        ),
    }
    text = (PROFILE_DIR / "koolio-real.yaml").read_text()
    out = {}
    for name, (slug, cut) in parts.items():
        doc = yaml.safe_load(text)
        cut(doc["realism"])
        out[name] = folder / f"koolio-real-without-{slug}.yaml"
        out[name].write_text(yaml.safe_dump(doc))
    return out


def competence(
    seed: int,
    check_every: int,
    max_episodes: int,
    eval_episodes: int,
    folder: Path,
    config: str | None = None,
) -> dict:
    """``train`` (``config``; None: the default learner) until 90 % of greedy evaluation
    episodes reach the goal, a check every ``check_every`` episodes."""
    from koolio_pymunk.learning.evaluation import evaluate
    from koolio_pymunk.learning.training import train
    from koolio_pymunk.store.qtable import QTableStore, human_bytes

    env = make_env("fast", config=config)
    tag = f"{config or 'default'}-seed{seed}"
    store = QTableStore(folder / f"{tag}.qtable")
    train_s = train_reported = eval_s = 0.0
    episodes, steps, rate, reached = 0, 0, 0.0, False
    history = []
    while episodes < max_episodes:
        with Timer() as t:
            res = train(env, store, check_every, seed, folder / f"{tag}.csv", report=None)
        train_s += t.wall
        train_reported += res.seconds
        episodes += check_every
        steps += res.steps
        with Timer() as t:
            ev = evaluate(env, res.table, eval_episodes, seed)
        eval_s += t.wall
        rate = ev.goal_rate
        history.append([episodes, round(train_s, 2), rate])
        if rate >= 0.9:
            reached = True
            break
    table = res.table
    return {
        "seed": seed,
        "config": config,
        "reached": reached,
        "episodes": episodes,
        "steps": steps,
        "train_wall_s": round(train_s, 2),
        "train_reported_s": round(train_reported, 2),
        "eval_wall_s": round(eval_s, 2),
        "goal_rate": rate,
        "history": history,
        "peak_rss_mib": peak_rss_mib(),
        "qtable_states": len(table),
        "qtable_entries": table.entries,
        "qtable_file_bytes": table.nbytes(),
        "qtable_file": human_bytes(table.nbytes()),
        "dense_entries": table.layout.n_entries,
        "dense": human_bytes(table.layout.dense_bytes()),
    }


def competence_subprocess(
    seed: int, args: argparse.Namespace, folder: Path, config: str | None
) -> dict:
    cmd = [
        sys.executable,
        __file__,
        "--competence-seed",
        str(seed),
        "--check-every",
        str(args.check_every),
        "--max-episodes",
        str(args.max_episodes),
        "--eval-episodes",
        str(args.eval_episodes),
        "--folder",
        str(folder),
    ]
    if config is not None:
        cmd += ["--competence-config", config]
    done = subprocess.run(cmd, capture_output=True, text=True, check=True, cwd=ROOT)
    return json.loads(done.stdout.strip().splitlines()[-1])


def in_tree(tree: Path, call: str, folder: Path) -> dict:
    """``call`` (an expression over ``bench``, ``Path`` and ``folder``) evaluated in a
    new interpreter on ``tree``'s package and ``tree/tools/bench.py``: its JSON."""
    code = (
        "import json, sys; from pathlib import Path; "
        f"sys.path.insert(0, {str(tree / 'tools')!r}); import bench; "
        f"folder = Path({str(folder)!r}); print(json.dumps({call}))"
    )
    env = dict(os.environ, PYTHONPATH=str(tree))
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=tree, env=env
    )
    return json.loads(done.stdout.strip().splitlines()[-1])


def baseline_rows(
    base: Path, steps: int, robots: int, episodes: int, pairs: int, folder: Path
) -> dict:
    """This tree against ``base`` (module doc), ``pairs`` alternating pairs of runs."""
    one_step = (
        "'one-step-q'" if (base / "koolio_pymunk/profiles/one-step-q.yaml").exists() else None
    )
    rows = {
        "default learner (--config qlambda-no-undo)": (
            f"bench.learning_loop('fast', {steps}, config='qlambda-no-undo')",
        )
        * 2,
        "one-step Q": (
            f"bench.learning_loop('fast', {steps}, config={one_step})",
            f"bench.learning_loop('fast', {steps}, config='one-step-q')",
        ),
        f"{robots} robots, one-step Q (robot-steps)": (
            f"bench.many({robots}, {episodes}, folder"
            + ("" if one_step is None else ", 'one-step-q'")
            + ")",
            f"bench.many({robots}, {episodes}, folder, 'one-step-q')",
        ),
    }
    out: dict = {"base": str(base), "commit": _commit(base), "rows": {}}
    for name, (old_call, new_call) in rows.items():
        old, new = [], []
        for k in range(pairs):
            sub = folder / f"baseline-{len(out['rows'])}-{k}"
            (sub / "old").mkdir(parents=True)
            (sub / "new").mkdir()
            old.append(in_tree(base, old_call, sub / "old")["per_cpu_s"])
            new.append(in_tree(ROOT, new_call, sub / "new")["per_cpu_s"])
        out["rows"][name] = {
            "old_per_cpu_s": old,
            "new_per_cpu_s": new,
            "ratios": [round(n / max(1, o), 3) for o, n in zip(old, new)],
        }
    return out


def _commit(tree: Path) -> str | None:
    try:
        done = subprocess.run(
            ["git", "-C", str(tree), "rev-parse", "--short", "HEAD"],
            capture_output=True,
            text=True,
            check=True,
        )
    except (OSError, subprocess.CalledProcessError):
        return None
    return done.stdout.strip()


class Bench:
    """One run of the benchmark: its arguments, its budgets, its rows so far."""

    def __init__(self, args: argparse.Namespace, folder: Path) -> None:
        self.args, self.folder, self.quick = args, folder, args.quick
        self.report: dict = {
            "machine": machine(),
            "commit": _commit(ROOT),
            "quick": args.quick,
            "scale": args.scale,
        }
        self.loops: dict[str, dict] = {}

    def n(self, full: int, quick: int) -> int:
        """A budget: ``full``, or ``quick`` with ``--quick``, times ``--scale``."""
        return max(1, round((quick if self.quick else full) * self.args.scale))

    def loop(self, key: str, full: int, quick: int, **kw) -> dict:
        """:func:`learning_loop`'s row ``key`` (measured once per run)."""
        if key not in self.loops:
            kw.setdefault("backend", "fast")
            self.loops[key] = learning_loop(min_steps=self.n(full, quick), **kw)
        return self.loops[key]

    def engine(self) -> dict:
        """The engine, one robot, the default learner (the rows' common reference)."""
        return self.loop("engine", 300_000, 60_000)

    def engine_q(self) -> dict:
        """The engine, one robot, ``--config one-step-q``."""
        return self.loop("engine_one_step_q", 300_000, 60_000, config="one-step-q")


def section_one_robot(b: Bench) -> None:
    ref = b.loop("reference", 15_000, 4_000, backend="pymunk")
    print(table_line("reference loop (pymunk queries), default", ref))
    eng, engq = b.engine(), b.engine_q()
    py = b.loop("python", 150_000, 30_000, compiled=False)
    pyq = b.loop("python_one_step_q", 150_000, 30_000, compiled=False, config="one-step-q")
    eng["ratio_to_reference_cpu"] = ratio(eng, ref, digits=1)
    eng["ratio_to_python_loop_cpu"] = ratio(eng, py)
    engq["ratio_to_python_loop_cpu"] = ratio(engq, pyq)
    engq["ratio_to_default_cpu"] = ratio(engq, eng)
    print(
        table_line(
            "engine, 1 robot, default learner",
            eng,
            f"x{eng['ratio_to_reference_cpu']} reference, "
            f"x{eng['ratio_to_python_loop_cpu']} Python loop",
        )
    )
    print(table_line("Python loop, same backend, default learner", py))
    print(
        table_line(
            "engine, 1 robot, --config one-step-q",
            engq,
            f"x{engq['ratio_to_python_loop_cpu']} Python loop, "
            f"x{engq['ratio_to_default_cpu']} default",
        )
    )
    print(table_line("Python loop, --config one-step-q", pyq))
    b.report["one_robot"] = {
        "reference": ref,
        "engine": eng,
        "python_loop": py,
        "engine_one_step_q": engq,
        "python_loop_one_step_q": pyq,
    }


def section_koolio_real(b: Bench) -> None:
    eng = b.engine()
    real = b.loop("koolio_real", 300_000, 60_000, world="koolio-real")
    real["ratio_to_ideal_cpu"] = ratio(real, eng, digits=3)
    real["ratio_to_ideal_wall"] = ratio(real, eng, "per_wall_s", digits=3)
    print(
        table_line(
            "koolio-real world, default learner",
            real,
            f"{real['ratio_to_ideal_cpu']:.0%} of ideal (CPU)",
        )
    )
    real["without"] = {}
    for part, path in realism_without(b.folder).items():
        r = learning_loop("fast", b.n(300_000, 60_000), world=str(path))
        r["ratio_to_ideal_cpu"] = ratio(r, eng, digits=3)
        real["without"][part] = r
        print(
            table_line(
                f"  koolio-real, no {part}", r, f"{r['ratio_to_ideal_cpu']:.0%} of ideal (CPU)"
            )
        )
    b.report["koolio_real"] = real


def section_paper_memory(b: Bench) -> None:
    engq = b.engine_q()
    mem = b.loop("paper_memory", 150_000, 60_000, config="paper-memory")
    mem_py = b.loop("paper_memory_python", 60_000, 30_000, compiled=False, config="paper-memory")
    mem["ratio_to_python_loop_cpu"] = ratio(mem, mem_py)
    mem["ratio_to_one_step_q_cpu"] = ratio(mem, engq, digits=3)
    print(
        table_line(
            "paper-memory, engine",
            mem,
            f"x{mem['ratio_to_python_loop_cpu']} Python loop, "
            f"{mem['ratio_to_one_step_q_cpu']:.0%} of one-step-q",
        )
    )
    print(table_line("paper-memory, Python loop", mem_py))
    b.report["paper_memory"] = {"engine": mem, "python_loop": mem_py}


def section_train(b: Bench) -> None:
    eng = b.engine()
    end_to_end(2, b.folder)  # load the kernels' cache (no-op when a section ran before)
    rows = {}
    for key, label, kw, full, quick in (
        ("fsync_second", "train end to end, --fsync second", {}, 600, 100),
        ("fsync_episode", "train end to end, --fsync episode", {"fsync": "episode"}, 600, 100),
        ("save_every_100", "train --save-every 100", {"save_every": 100}, 1_200, 200),
        (
            "fsync_episode_save_every_100",
            "train --fsync episode --save-every 100",
            {"fsync": "episode", "save_every": 100},
            1_200,
            200,
        ),
    ):
        r = end_to_end(b.n(full, quick), b.folder, **kw)
        r["ratio_to_engine_cpu"] = ratio(r, eng, digits=3)
        rows[key] = r
        print(table_line(label, r, f"{r['ratio_to_engine_cpu']:.0%} of the engine's loop"))
    b.report["train"] = rows
    irs = irsim_row(b.n(10_000, 2_000), rows["fsync_second"], b.folder)
    if irs is not None:
        b.report["irsim"] = irs
        x = irs["ratio_train_to_irsim_cpu"]
        print(table_line("IR-SIM, same hallway", irs, f"train end to end x{x}"))


def section_eval(b: Bench) -> None:
    ev = evaluation_rows(b.folder, b.n(3_000, 300), b.n(300, 50), b.args.robots)
    b.report["eval"] = ev
    for key in ("engine", f"engine_{b.args.robots}", "python"):
        r = ev[key]
        print(
            table_line(
                f"evaluate (greedy), {key}",
                r,
                f"{r['episodes_per_cpu_s']:,} episodes/CPU s, goal rate {r['goal_rate']:.0%}",
            )
        )
    print(f"  evaluate: the engine x{ev['ratio_engine_to_python_cpu']} the Python loop (CPU)")


def section_checks(b: Bench) -> None:
    episodes = b.n(3_000, 300)
    # the target's run: 3,000 episodes, a 100-episode check every 250 (12 checks)
    c = check_share(b.folder, episodes, max(1, episodes // 12))
    b.report["checks"] = c
    print(
        table_line(
            f"train --episodes {episodes} --eval-every {c['eval_every']}",
            c,
            f"checks {c['check_share_cpu']:.0%} of the CPU time ({c['checks']} "
            f"checks, {c['check_cpu_s']:.2f} s; the evaluations file: "
            f"{c['check_seconds_reported']:.2f} s of {c['train_seconds_reported']:.2f})",
        )
    )
    print(
        f"    a greedy step of the checks {c['us_per_greedy_step']:.2f} µs "
        f"({c['greedy_steps']:,} steps), a training step {c['us_per_training_step']:.2f} µs "
        f"({c['steps']:,}): ratio {c['greedy_to_training_cost']:.2f}; a 15 % share needs "
        f"at most {c['greedy_to_training_cost_for_15']:.2f}"
    )


def section_robots(b: Bench) -> None:
    n, episodes = b.args.robots, b.n(3_000, 300)
    rows = {}
    for key, config, world in (
        ("one_step_q", "one-step-q", None),
        ("default", None, None),
        ("default_koolio_real", None, "koolio-real"),
    ):
        rows[key] = many(n, episodes, b.folder, config, world)
        label = f"{n} robots, {config or 'default learner'}" + (f", {world}" if world else "")
        print(table_line(label, rows[key], "robot-steps"))
    where = many_where(n, episodes, b.folder)
    rows["where"] = where
    print(
        f"  {n} robots, default learner, where a robot-step goes (CPU, µs per robot-step; "
        f"{where['us_per_step']:.2f} in all; Python {where['python_us_per_episode']:.0f} µs "
        "per finished episode):"
    )
    for label, part in where["parts"].items():
        per_call = f"  {part['us_per_call']:8.1f} µs x {part['calls']:,}" if part["calls"] else ""
        print(f"    {part['us_per_step']:6.3f}  {label}{per_call}")
    pr = cProfile.Profile()
    many(n, b.n(1_000, 100), b.folder, profiler=pr)
    rows["profile"] = profile_rows(pr, top=12)
    print(f"  cProfile of {n} robots (default learner), own time:")
    for r in rows["profile"]:
        print(f"    {r['share']:>6.1%} {r['calls']:>9,}  {r['function']}")
    b.report["robots"] = rows


def section_vector(b: Bench) -> None:
    v = vector_rows(b.args.robots, b.n(2_000, 300), b.n(200, 30))
    b.report["vector"] = v
    n = b.args.robots
    print(
        table_line(
            f"make_vec(num_envs={n}), {v['compiled']['class_name']}",
            v["compiled"],
            f"env-steps, x{v['ratio_cpu']} SyncVectorEnv",
        )
    )
    print(table_line(f"SyncVectorEnv of {n} KoolioEnv", v["sync"], "env-steps"))


def section_motion(b: Bench) -> None:
    mo = b.report["motion"] = motion(b.n(2_000, 500))
    print(
        f"  one 12-inch move, us (all / near a wall, {mo['poses']} hallway poses): "
        f"pymunk world {mo['pymunk_us_all']:.2f} / {mo['pymunk_us_near']:.2f}; compiled, "
        f"from Python {mo['compiled_call_us_all']:.2f} / {mo['compiled_call_us_near']:.2f}, "
        f"in a compiled loop {mo['compiled_loop_us_all']:.3f} / "
        f"{mo['compiled_loop_us_near']:.3f}"
    )


def section_algorithms(b: Bench) -> None:
    algos = b.report["algorithms"] = algorithms(b.n(150_000, 30_000))
    print("  cost per step of each learner.algorithm (default configuration, same steps):")
    for name, r in algos.items():
        loop = "engine" if r["compiled"] else "Python loop"
        print(
            f"    {name:<15} x{r['ratio_to_q_cpu']:.2f} one-step Q  "
            f"{r['us_per_step_cpu']:6.1f} us/step  {r['per_cpu_s']:>8,} steps/CPU s  "
            f"({r['steps']:,} steps, {r['episodes']} episodes, {loop})"
        )


def section_step_costs(b: Bench) -> None:
    real_q = b.loop(
        "koolio_real_one_step_q", 300_000, 60_000, world="koolio-real", config="one-step-q"
    )
    for key, row, world in (
        ("step_costs", b.engine_q(), None),
        ("step_costs_koolio_real", real_q, "koolio-real"),
    ):
        step_us = 1e6 * row["cpu_s"] / max(1, row["steps"])
        sc = b.report[key] = step_costs(b.n(20_000, 5_000), step_us, world=world)
        print(
            f"  one step of the engine (one-step Q){' in koolio-real' if world else ''}, us "
            f"per robot-step (CPU): {sc['step_us']:.2f} = reading {sc['sense_us']:.2f} + move "
            f"{sc['move_us']:.2f} + act and learn {sc['act_learn_us']:.2f} + judge, "
            f"rescue, the loop and Python between episodes {sc['rest_us']:.2f}"
        )


def section_shared_arena(b: Bench) -> None:
    b.report["shared_arena"] = shared_costs(b.n(10_000, 2_000))
    print_shared(b.report["shared_arena"])
    episodes = b.n(3_000, 300)
    alone = many(8, episodes, b.folder)
    shared = many(8, episodes, b.folder, shared=True)
    b.report["shared_arena"]["train_8_alone"] = alone
    b.report["shared_arena"]["train_8_shared"] = shared
    print(table_line("train --robots 8 (each alone), default learner", alone))
    print(
        table_line(
            "train --robots 8 --shared-arena (one hallway)",
            shared,
            f"  {ratio(shared, alone)}x alone (target >= 150,000 robot-steps/s)",
        )
    )


def section_competence(b: Bench) -> None:
    args = b.args
    seeds = args.seeds if args.seeds is not None else ([0] if b.quick else [0, 1, 2])
    out = {}
    for config in (None, "one-step-q"):
        comp = []
        for s in seeds:
            c = competence_subprocess(s, args, b.folder, config)
            comp.append(c)
            got = (
                f"{c['episodes']} episodes, {c['train_wall_s']:.1f} s of training"
                if c["reached"]
                else f"not reached in {c['episodes']} episodes "
                f"({c['train_wall_s']:.1f} s, last goal rate {c['goal_rate']:.0%})"
            )
            print(
                f"  time to competence, {config or 'default learner'}, seed {s}: {got}; "
                f"peak RSS {c['peak_rss_mib']} MiB; Q-table {c['qtable_entries']:,} entries, "
                f"{c['qtable_file']} (dense: {c['dense_entries']:,} entries, {c['dense']})"
            )
        out[config or "default"] = comp
    b.report["competence"] = out


def section_profile(b: Bench) -> None:
    pr = cProfile.Profile()
    learning_loop("fast", b.n(60_000, 20_000), seed=1, profiler=pr)
    prof = profile_rows(pr)
    b.report["profile"] = prof
    print("  where the time goes (one robot on the engine, default learner; cProfile own time):")
    for r in prof:
        print(f"    {r['share']:>6.1%} {r['calls']:>9,}  {r['function']}")


def section_arena_check(b: Bench) -> None:
    check = arena_check(5_000)
    b.report["arena_check"] = check
    print(
        f"  check-arena, {check['points']:,}-point walls (validation only): ring "
        f"{check['ring_s']:.2f} s, star {check['star_s']:.2f} s"
    )


def section_agreement(b: Bench) -> None:
    agree = agreement_sample(b.n(2_000, 300))
    b.report["agreement_sample"] = agree
    print(
        "  agreement sample (tools/agreement.py runs 100k per arena): "
        + ", ".join(
            f"{a['arena']} {a['poses']} poses: {a['distance_mismatches']} distance / "
            f"{a['state_mismatches']} state mismatches"
            for a in agree
        )
    )


def section_baseline(b: Bench) -> None:
    base = Path(b.args.baseline).resolve()
    bl = baseline_rows(
        base, b.n(300_000, 60_000), b.args.robots, b.n(3_000, 300), 2 if b.quick else 3, b.folder
    )
    b.report["baseline"] = bl
    print(f"  against {bl['commit'] or base} (per CPU s, alternate runs, each in its process):")
    for name, r in bl["rows"].items():
        print(
            f"    {name}: before {r['old_per_cpu_s']}, now {r['new_per_cpu_s']}, "
            f"now/before {r['ratios']}"
        )


#: The sections in the order they run (``--only`` picks some; ``baseline`` runs only with
#: ``--baseline``).
SECTIONS: dict[str, Callable[[Bench], None]] = {
    "one-robot": section_one_robot,
    "koolio-real": section_koolio_real,
    "paper-memory": section_paper_memory,
    "train": section_train,
    "eval": section_eval,
    "checks": section_checks,
    "robots": section_robots,
    "shared-arena": section_shared_arena,
    "vector": section_vector,
    "motion": section_motion,
    "algorithms": section_algorithms,
    "step-costs": section_step_costs,
    "competence": section_competence,
    "profile": section_profile,
    "arena-check": section_arena_check,
    "agreement": section_agreement,
    "baseline": section_baseline,
}


def _write(report: dict, out: str | None) -> int:
    if out:
        Path(out).write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
        print(f"wrote {out}")
    return 0


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="short budgets (about 3 minutes)")
    p.add_argument(
        "--scale",
        type=float,
        default=1.0,
        help="multiply every budget by this (e.g. 0.02 for a smoke test)",
    )
    p.add_argument(
        "--only",
        nargs="+",
        choices=list(SECTIONS),
        default=None,
        metavar="SECTION",
        help=f"run these sections only: {', '.join(SECTIONS)}",
    )
    p.add_argument("--out", default=None, help="write the figures as JSON here")
    p.add_argument(
        "--robots",
        type=int,
        default=64,
        help="robots of the N-robot rows and envs of the vector env (64)",
    )
    p.add_argument("--seeds", type=int, nargs="*", default=None, help="competence seeds")
    p.add_argument(
        "--check-every",
        type=int,
        default=25,
        help="competence: episodes between greedy checks (25)",
    )
    p.add_argument("--max-episodes", type=int, default=3000)
    p.add_argument("--eval-episodes", type=int, default=100)
    p.add_argument(
        "--baseline",
        default=None,
        metavar="DIR",
        help="a checkout of an earlier commit to compare with (section baseline)",
    )
    p.add_argument("--competence-seed", type=int, default=None, help=argparse.SUPPRESS)
    p.add_argument("--competence-config", default=None, help=argparse.SUPPRESS)
    p.add_argument("--folder", default=None, help=argparse.SUPPRESS)
    args = p.parse_args(argv)

    if args.competence_seed is not None:  # child process of the competence section
        out = competence(
            args.competence_seed,
            args.check_every,
            args.max_episodes,
            args.eval_episodes,
            Path(args.folder),
            args.competence_config,
        )
        print(json.dumps(out))
        return 0

    names = args.only or [s for s in SECTIONS if s != "baseline" or args.baseline]
    if "baseline" in names and not args.baseline:
        p.error("section baseline needs --baseline DIR")
    scratch = ROOT / "scratch"  # the checkout's disk (saves are fsynced), ignored by git
    scratch.mkdir(exist_ok=True)
    with tempfile.TemporaryDirectory(dir=scratch, prefix="bench-") as tmp:
        b = Bench(args, Path(tmp))
        m = b.report["machine"]
        print(
            f"koolio-pymunk bench ({'quick' if args.quick else 'full'}"
            f"{f', scale {args.scale}' if args.scale != 1 else ''}) at {b.report['commit']}, "
            f"{m['cpus']} CPUs, load average {m['load_average']}"
        )
        print(f"  {'':<44} {'per wall s':>10} {'per CPU s':>10}")
        for name in names:
            with Timer() as t:
                SECTIONS[name](b)
            b.report.setdefault("section_seconds", {})[name] = round(t.wall, 1)
    b.report["load_average_end"] = [round(x, 2) for x in os.getloadavg()]
    b.report["peak_rss_bench_mib"] = round(
        resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1
    )
    print(f"load average at the end {b.report['load_average_end']}")
    return _write(b.report, args.out)


if __name__ == "__main__":
    sys.exit(main())
