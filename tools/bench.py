"""koolio-pymunk's speed benchmark: steps/s, time to competence, memory, where time goes.

Sections (each printed as a table row, all written to ``--out`` as JSON):

* **reference / fast**: the single-robot training loop (epsilon-greedy, Q update, same
  code as ``koolio-pm train``) on the hallway with the pymunk reference sensors (the
  Python episode loop) and with the fast backend, without file I/O: the fast row is the
  compiled episode (``learning/episode_kernel.py``, what ``train`` runs), the next row
  the same fast backend in the Python episode loop, with the compiled/Python ratio;
  steps per second, and the fast/reference ratio;
* **koolio-real**: the same compiled loop in the realistic world (``--world
  koolio-real``: every realism model on), next to the ideal world's row above: steps per
  second and the ratio to the ideal world; then the same world with one family of its
  models off (:func:`realism_without`: the motion errors; the sonar's beam model), which
  says where its extra cost per step goes;
* **paper-memory**: the compiled loop and the Python loop with ``--config paper-memory``
  (the goal camera and the last action remembered in the state);
* **train (end to end)**: :func:`training.train` as ``koolio-pm train`` runs it (the
  compiled episode), saving the table (the file written and fsynced, the replaced one
  kept as the backup) and the log at every episode end, then with ``save_every`` 100
  (``--save-every 100``);
* **IR-SIM, same run**: IR-SIM (``ir-sim``, the ``compare`` extra) stepping the same
  hallway with an 88-beam lidar (``tools/irsim_compare.py``, collision mode ``stop``), and
  the end-to-end row's ratio to it; skipped with a note when ir-sim is not installed;
* **N robots**: :func:`multi.train_many` with ``--robots`` robots, robot-steps per second;
* **motion**: the cost of one 12-inch move from the same seeded random free poses of the
  hallway (near a wall: within 12 in of one): the pymunk world's (``World.move``), the
  compiled move (``swept_move.move``) called from Python, and per move inside one
  compiled loop;
* **shared arena**: the cost of one 12-inch move and of one reading of a robot among 7
  others in one hallway (``World(..., shared=True)``: :func:`shared_costs`), next to the
  same robot alone, each in a compiled loop over the same poses: the compiled move
  (``swept_move.move_among`` against ``move``) and the whole reading with its draws
  (``reading_kernel.sense_reading_among`` against ``sense_reading``), in the ideal world
  and in ``koolio-real``;
* **algorithms**: the fast single-robot loop with each ``learner.algorithm`` (one-step Q
  and Q(lambda) compiled and in the Python loop, Dyna-Q with its default
  ``planning_steps``, which runs the Python loop), the same number of steps from an empty
  table in this one run: the cost per step and its ratio to compiled one-step Q's;
* **time to competence**, per seed: default ``koolio-pm train`` (hallway, default
  config), a greedy evaluation of 100 episodes after every ``--check-every`` episodes,
  until at least 90 % reach the goal; each seed runs in its own process, which also
  reports its own peak RSS (:func:`peak_rss_mib`) and its Q-table's size next to the
  paper's dense 113.9 MiB;
* **cost per step**: the compiled episode's step taken apart, each part timed in a
  compiled loop over the same recorded poses (:func:`step_costs`), in the ideal world
  and in ``koolio-real``;
* **profile**: cProfile of the fast single-robot loop (compiled), top 10 functions by own
  time;
* **agreement**: fast vs reference sensing on a sample of random poses per arena
  (``tools/agreement.py`` runs the full 100k);
* **arena check**: validating an arena whose walls are a 5,000-point ring, and a
  5,000-point star (random radii, so that many edges' bounding boxes overlap), as
  ``koolio-pm check-arena`` does after parsing (``docs/robustness.md``).

Every rate is given twice: per wall-clock second and per CPU second of this process
(``time.process_time``). On an idle machine they agree; on a shared one other processes
stretch wall time, and the CPU figure is the one to compare between runs.

    .venv/bin/python tools/bench.py --out bench.json         # a few minutes
    .venv/bin/python tools/bench.py --quick                   # about a minute
    .venv/bin/python tools/bench.py --algorithms-only         # the algorithms section only
    .venv/bin/python tools/bench.py --robots-only             # the N-robot row only
    .venv/bin/python tools/bench.py --shared-only             # the shared-arena rows only
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
from pathlib import Path

if str(Path(__file__).resolve().parent) not in sys.path:  # the tools' own modules
    sys.path.insert(0, str(Path(__file__).resolve().parent))

from timing import Timer, rates

ROOT = Path(__file__).resolve().parent.parent
PAPER_DENSE_MIB = 113.9


def make_env(
    backend: str,
    arena: str = "hallway",
    world: str | None = None,
    algorithm: str = "q",
    config: str | None = None,
):
    from koolio_pymunk.store.config import load_config
    from koolio_pymunk.task.env import KoolioEnv

    overrides = {"sensors": {"backend": backend}, "learner": {"algorithm": algorithm}}
    return KoolioEnv(arena, config=load_config(config, overrides=overrides, world=world))


def learning_loop(
    backend: str,
    min_steps: int,
    seed: int = 0,
    world: str | None = None,
    algorithm: str = "q",
    compiled: bool = True,
    config: str | None = None,
) -> dict:
    """The training loop of ``train`` without file I/O, for at least ``min_steps`` steps
    (``compiled`` False: the Python loop; True: the step engine where the configuration
    allows, as ``train``)."""
    from koolio_pymunk.learning.algorithms import make_learner
    from koolio_pymunk.learning.engine import robots
    from koolio_pymunk.learning.qtable import QTable

    def loop_of(env):
        table = QTable(env.layout, {}, env.config.learner.q_init)
        return robots(env, [make_learner(table, env.config.learner, None)], seed,
                      compiled=compiled)  # fmt: skip

    warm = loop_of(make_env(backend, world=world, algorithm=algorithm, config=config))
    warm.begin(0, 0)  # compile / warm up the kernels on a copy
    warm.advance()
    loop = loop_of(make_env(backend, world=world, algorithm=algorithm, config=config))
    steps, e = 0, 0
    with Timer() as t:
        while steps < min_steps:
            loop.begin(0, e)
            loop.advance()
            steps += loop.result(0).steps
            e += 1
    out = rates(steps, t)
    out["episodes"] = e
    out["compiled"] = loop.python_reason is None
    return out


def algorithms(min_steps: int) -> dict:
    """Each learning algorithm in the fast loop; cost per step and ratio to one-step Q
    (compiled where it runs compiled; ``q-python``, ``qlambda-python``: in the Python
    loop)."""
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


def algorithms_section(quick: bool) -> dict:
    """Run and print the algorithms section."""
    algos = algorithms(30_000 if quick else 150_000)
    print("  cost per step of each learner.algorithm (fast loop, same steps, this run):")
    for name, r in algos.items():
        loop = "compiled" if r["compiled"] else "Python loop"
        print(
            f"    {name:<8} x{r['ratio_to_q_cpu']:.2f} one-step Q  "
            f"{r['us_per_step_cpu']:6.1f} us/step  {r['per_cpu_s']:>8,} steps/CPU s  "
            f"({r['steps']:,} steps, {r['episodes']} episodes, {loop})"
        )
    return algos


def _write(report: dict, out: str | None) -> int:
    if out:
        Path(out).write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
        print(f"wrote {out}")
    return 0


def end_to_end(episodes: int, folder: Path, save_every: int = 1) -> dict:
    from koolio_pymunk.learning.qtable import QTableStore
    from koolio_pymunk.learning.training import train

    env = make_env("fast")
    name = f"e2e{save_every}"
    with Timer() as t:
        res = train(
            env,
            QTableStore(folder / f"{name}.qtable"),
            episodes,
            0,
            folder / f"{name}.csv",
            report=None,
            save_every=save_every,
        )
    out = rates(res.steps, t)
    out.update(episodes=episodes, save_every=save_every)
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
    robots: int, episodes: int, folder: Path, config: str | None = None, world: str | None = None
) -> dict:
    """``koolio-pm train --robots N`` end to end (the table saved every N episodes, the
    log): robot-steps per second."""
    from koolio_pymunk.learning.qtable import QTableStore
    from koolio_pymunk.learning.training import train
    from koolio_pymunk.store.config import load_config
    from koolio_pymunk.task.env import KoolioEnv

    def env():
        return KoolioEnv("hallway", config=load_config(config, world=world))

    tag = f"many-{config}-{world}".replace("/", "_")
    warm = QTableStore(folder / f"{tag}-warm.qtable")
    train(env(), warm, 2, 0, None, report=None, robots=2)  # compile the kernels
    with Timer() as t:
        res = train(
            env(),
            QTableStore(folder / f"{tag}.qtable"),
            episodes,
            0,
            folder / f"{tag}.csv",
            report=None,
            robots=robots,
        )
    out = rates(res.steps, t)
    out.update(robots=robots, episodes=episodes, states=len(res.table), config=config,
               world=world)  # fmt: skip
    return out


def motion(poses: int, repeats: int = 5) -> dict:
    """Microseconds per 12-inch move from ``poses`` seeded random free poses of the
    hallway (best of ``repeats``): ``World.move`` (placing the robot not counted), the
    compiled move from Python, and the compiled move inside one compiled loop; ``near``
    rows: poses within 12 in of a wall."""
    import math

    import numba
    import numpy as np

    from koolio_pymunk.world.arena import load_arena
    from koolio_pymunk.world.move_agreement import free_points
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
    from koolio_pymunk.world.move_agreement import free_points
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
        times = []
        for _ in range(repeats):
            t0 = time.process_time()
            fn()
            times.append(time.process_time() - t0)
        return round(1e6 * min(times) / poses, 3)

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


def step_costs(poses: int, step_us: float, repeats: int = 3, world: str | None = None) -> dict:
    """Microseconds per robot-step of the compiled episode's parts, each in a compiled
    loop (best of ``repeats``) replaying ``poses`` steps of a seeded learning run in the
    hallway (the poses before each step, in order, so the ray directions' cache works as
    in a run): the reading (rays, cameras, noise draws, encoding; in ``world``, e.g.
    ``koolio-real``, with its realism models), the move of each step's action (with the
    world's motion errors), epsilon-greedy and the Table 11 update on the states read;
    ``step_us`` is the whole step (the compiled loop's CPU time per step) and the rest is
    judge, rescue check, the loop and Python between episodes."""
    import numba
    import numpy as np

    from koolio_pymunk.learning.algorithms import make_learner
    from koolio_pymunk.learning.episodes import Episodes
    from koolio_pymunk.learning.qtable import QTable
    from koolio_pymunk.learning.table_kernel import SharedTable, choose, new_journal, update
    from koolio_pymunk.sensing.reading_kernel import reading_group, sense_reading
    from koolio_pymunk.world.segment_query import wall_array
    from koolio_pymunk.world.swept_move import act

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
            update(index, table, 0.2, 0.9, keys[i], a, rewards[i], keys[i + 1], False, 0,
                   journal)  # fmt: skip

    env = make_env("fast", world=world)
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
    world = (wall_array(env.world), env.world.radius, float(env.move_distance), float(env.turn_arc))
    m = env.motion
    motion = np.zeros(5) if m is None else np.array(
        [1.0, m.drift, m.drift_sigma, m.slip_sigma, m.turn_sigma])  # fmt: skip
    rng = np.random.default_rng(0)
    rewards = rng.uniform(-10.0, 0.0, poses)
    keys = np.empty(poses, np.int64)

    def best(fn) -> float:
        times = []
        for _ in range(repeats):
            t0 = time.process_time()
            fn()
            times.append(time.process_time() - t0)
        return round(1e6 * min(times) / poses, 3)

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


def profile(min_steps: int) -> list[dict]:
    """Top 10 functions by own time in the fast single-robot loop."""
    pr = cProfile.Profile()
    pr.enable()
    learning_loop("fast", min_steps, seed=1)
    pr.disable()
    st = pstats.Stats(pr)
    total = sum(v[2] for v in st.stats.values())
    rows = sorted(st.stats.items(), key=lambda kv: kv[1][2], reverse=True)[:10]
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


def competence(
    seed: int, check_every: int, max_episodes: int, eval_episodes: int, folder: Path
) -> dict:
    """Default training until 90 % of greedy evaluation episodes reach the goal."""
    from koolio_pymunk.learning.evaluation import evaluate
    from koolio_pymunk.learning.qtable import QTableStore, human_bytes
    from koolio_pymunk.learning.training import train
    from koolio_pymunk.task.env import KoolioEnv

    env = KoolioEnv("hallway")
    store = QTableStore(folder / f"seed{seed}.qtable")
    train_s = eval_s = 0.0
    episodes, steps, rate, reached = 0, 0, 0.0, False
    history = []
    while episodes < max_episodes:
        with Timer() as t:
            res = train(env, store, check_every, seed, folder / f"seed{seed}.csv", report=None)
        train_s += t.wall
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
        "reached": reached,
        "episodes": episodes,
        "steps": steps,
        "train_wall_s": round(train_s, 2),
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


def competence_subprocess(seed: int, args: argparse.Namespace, folder: Path) -> dict:
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
    done = subprocess.run(cmd, capture_output=True, text=True, check=True, cwd=ROOT)
    return json.loads(done.stdout.strip().splitlines()[-1])


def agreement_sample(poses: int) -> list[dict]:
    from koolio_pymunk.sensing.agreement import compare_backends

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
        data = {"name": kind, "walls": walls, "goals": [{"name": "g", "at": [0, 100]}],
                "start": {"at": [0, 0]}}  # fmt: skip
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


def table_line(name: str, r: dict, extra: str = "") -> str:
    return (
        f"  {name:<34} {r['per_wall_s']:>10,} {r['per_cpu_s']:>10,}   "
        f"{r['steps']:>8,} steps {r['wall_s']:>7.1f} s  {extra}"
    )


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="short budgets (about a minute)")
    p.add_argument("--out", default=None, help="write the figures as JSON here")
    p.add_argument("--robots", type=int, default=64, help="robots for the N-robot row (64)")
    p.add_argument("--seeds", type=int, nargs="*", default=None, help="competence seeds")
    p.add_argument("--check-every", type=int, default=100)
    p.add_argument("--max-episodes", type=int, default=3000)
    p.add_argument("--eval-episodes", type=int, default=100)
    p.add_argument(
        "--algorithms-only", action="store_true", help="only the cost per step of each algorithm"
    )
    p.add_argument(
        "--robots-only", action="store_true", help="only the N-robot row (--robots robots)"
    )
    p.add_argument("--shared-only", action="store_true", help="only the shared-arena rows")
    p.add_argument("--competence-seed", type=int, default=None, help=argparse.SUPPRESS)
    p.add_argument("--folder", default=None, help=argparse.SUPPRESS)
    args = p.parse_args(argv)

    if args.competence_seed is not None:  # child process of the competence section
        out = competence(
            args.competence_seed,
            args.check_every,
            args.max_episodes,
            args.eval_episodes,
            Path(args.folder),
        )
        print(json.dumps(out))
        return 0

    q = args.quick
    seeds = args.seeds if args.seeds is not None else ([0] if q else [0, 1, 2])
    report: dict = {"machine": machine(), "quick": q}
    print(
        f"koolio-pymunk bench ({'quick' if q else 'full'}), {report['machine']['cpus']} CPUs, "
        f"load average {report['machine']['load_average']}"
    )
    if args.algorithms_only:
        report["algorithms"] = algorithms_section(q)

        return _write(report, args.out)
    if args.shared_only:
        report["shared"] = shared_costs(2_000 if q else 10_000)
        print_shared(report["shared"])
        return _write(report, args.out)
    print(f"  {'':<34} {'per wall s':>10} {'per CPU s':>10}")
    if args.robots_only:
        with tempfile.TemporaryDirectory(dir=ROOT) as tmp:
            report["many"] = many(args.robots, 300 if q else 3000, Path(tmp))
        print(table_line(f"{args.robots} robots robot-steps/s", report["many"]))
        return _write(report, args.out)
    with tempfile.TemporaryDirectory(dir=ROOT) as tmp:
        folder = Path(tmp)
        ref = learning_loop("pymunk", 4_000 if q else 15_000)
        print(table_line("reference (pymunk queries) steps/s", ref))
        fast = learning_loop("fast", 60_000 if q else 300_000)
        ratio = fast["per_cpu_s"] / max(1, ref["per_cpu_s"])
        fast["ratio_to_reference_cpu"] = round(ratio, 1)
        print(table_line("fast backend, compiled steps/s", fast, f"x{ratio:.1f} reference"))
        python = learning_loop("fast", 30_000 if q else 150_000, compiled=False)
        gain = fast["per_cpu_s"] / max(1, python["per_cpu_s"])
        fast["ratio_to_python_loop_cpu"] = round(gain, 2)
        print(table_line("fast backend, Python loop steps/s", python, f"compiled x{gain:.2f}"))
        real = learning_loop("fast", 60_000 if q else 300_000, world="koolio-real")
        real_ratio = real["per_cpu_s"] / max(1, fast["per_cpu_s"])
        real["ratio_to_ideal_cpu"] = round(real_ratio, 3)
        real["ratio_to_ideal_wall"] = round(real["per_wall_s"] / max(1, fast["per_wall_s"]), 3)
        print(table_line("koolio-real world steps/s", real, f"{real_ratio:.0%} of ideal (CPU)"))
        real["without"] = {}
        for part, path in realism_without(folder).items():
            r = learning_loop("fast", 60_000 if q else 300_000, world=str(path))
            r["ratio_to_ideal_cpu"] = round(r["per_cpu_s"] / max(1, fast["per_cpu_s"]), 3)
            real["without"][part] = r
            share = f"{r['ratio_to_ideal_cpu']:.0%} of ideal (CPU)"
            print(table_line(f"  koolio-real, no {part}", r, share))
        mem = learning_loop("fast", 60_000 if q else 150_000, config="paper-memory")
        mem_py = learning_loop(
            "fast", 30_000 if q else 60_000, compiled=False, config="paper-memory"
        )
        mem_gain = mem["per_cpu_s"] / max(1, mem_py["per_cpu_s"])
        mem["ratio_to_python_loop_cpu"] = round(mem_gain, 2)
        mem["ratio_to_ideal_cpu"] = round(mem["per_cpu_s"] / max(1, fast["per_cpu_s"]), 3)
        print(table_line("paper-memory, compiled steps/s", mem, f"x{mem_gain:.2f} Python loop"))
        print(table_line("paper-memory, Python loop steps/s", mem_py))
        e2e = end_to_end(100 if q else 600, folder)
        print(table_line("train end to end (saves) steps/s", e2e))
        e2e100 = end_to_end(200 if q else 1_200, folder, save_every=100)
        print(table_line("train, --save-every 100 steps/s", e2e100))
        irs = irsim_row(2_000 if q else 10_000, e2e, folder)
        if irs is not None:
            report["irsim"] = irs
            ratio = irs["ratio_train_to_irsim_cpu"]
            print(table_line("IR-SIM, same hallway steps/s", irs, f"train end to end x{ratio}"))
        multi = many(args.robots, 300 if q else 3000, folder)
        print(table_line(f"{args.robots} robots robot-steps/s", multi))
        report.update(
            reference=ref,
            fast=fast,
            python_loop=python,
            koolio_real=real,
            paper_memory=mem,
            paper_memory_python_loop=mem_py,
            end_to_end=e2e,
            end_to_end_save_every_100=e2e100,
            many=multi,
        )

        mo = report["motion"] = motion(500 if q else 2_000)
        print(
            f"  one 12-inch move, us (all / near a wall, {mo['poses']} hallway poses): "
            f"pymunk world {mo['pymunk_us_all']:.2f} / {mo['pymunk_us_near']:.2f}; compiled, "
            f"from Python {mo['compiled_call_us_all']:.2f} / {mo['compiled_call_us_near']:.2f}, "
            f"in a compiled loop {mo['compiled_loop_us_all']:.3f} / "
            f"{mo['compiled_loop_us_near']:.3f}"
        )

        report["shared"] = shared_costs(2_000 if q else 10_000)
        print_shared(report["shared"])

        report["algorithms"] = algorithms_section(q)

        parts = (("step_costs", fast, None), ("step_costs_koolio_real", real, "koolio-real"))
        for key, row, world in parts:
            step_us = 1e6 * row["cpu_s"] / max(1, row["steps"])
            sc = report[key] = step_costs(5_000 if q else 20_000, step_us, world=world)
            print(
                f"  one compiled step{' in koolio-real' if world else ''}, us per robot-step "
                f"(CPU): {sc['step_us']:.2f} = reading {sc['sense_us']:.2f} + move "
                f"{sc['move_us']:.2f} + act and learn {sc['act_learn_us']:.2f} + judge, "
                f"rescue and the loop {sc['rest_us']:.2f}"
            )

        comp = []
        for s in seeds:
            c = competence_subprocess(s, args, folder)
            comp.append(c)
            got = (
                f"{c['train_wall_s']:.1f} s of training, {c['episodes']} episodes"
                if c["reached"]
                else f"not reached in {c['episodes']} episodes "
                f"({c['train_wall_s']:.1f} s, last goal rate {c['goal_rate']:.0%})"
            )
            print(
                f"  time to competence, seed {s}: {got}; peak RSS {c['peak_rss_mib']} MiB; "
                f"Q-table {c['qtable_entries']:,} entries, {c['qtable_file']} "
                f"(dense: {c['dense_entries']:,} entries, {c['dense']})"
            )
        report["competence"] = comp

        prof = profile(20_000 if q else 60_000)
        report["profile"] = prof
        print("  where the time goes (fast single-robot loop, compiled; cProfile own time):")
        for r in prof:
            print(f"    {r['share']:>6.1%} {r['calls']:>9,}  {r['function']}")

        check = arena_check(5_000)
        report["arena_check"] = check
        print(
            f"  check-arena, {check['points']:,}-point walls (validation only): ring "
            f"{check['ring_s']:.2f} s, star {check['star_s']:.2f} s"
        )

        agree = agreement_sample(300 if q else 2_000)
        report["agreement_sample"] = agree
        print(
            "  agreement sample (tools/agreement.py runs 100k per arena): "
            + ", ".join(
                f"{a['arena']} {a['poses']} poses: {a['distance_mismatches']} distance / "
                f"{a['state_mismatches']} state mismatches"
                for a in agree
            )
        )
    report["peak_rss_bench_mib"] = round(
        resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1
    )
    return _write(report, args.out)


if __name__ == "__main__":
    sys.exit(main())
