"""Fast sensing backend vs the pymunk reference on random poses in every shipped arena.

For each arena and world (``--worlds``: the ideal world and ``koolio-real`` by default),
``--poses`` random free poses (noise off unless ``--noise``): counts the poses whose
noise-free distances differ in any bit (or whose camera markers differ; with
realism models on, also each ray's incidence and the other plates in view), the poses
whose encoded state or readings after the realism models differ, and the poses whose
every distance is bit-identical (:func:`sensing_agreement.compare_backends`);
then, in the ideal world, how often the exact-cone sonar model (``sensors.backend:
cone``) encodes differently from the paper's sub-arcs
(:func:`sensing_agreement.cone_disagreement`). Arena/world pairs run in parallel,
one process each (``--jobs``). Exits 1 on any fast/reference mismatch.

``--moves N`` also checks the compiled swept move (``koolio_pymunk.world.swept_move``)
against the pymunk world's (``World.move``) on ``N`` random moves per shipped arena and
per generated arena (``--generated K``, default 4: jittered and turned shipped arenas,
star-shaped rooms with obstacles; ``tools/move_agreement.py``): the moves
whose end positions differ in any bit (exit 1 if any), the moves that met a wall or
started touching one, and the smallest clearance to a wall after a move. ``--poses 0``
skips the sensors.

``--shared K`` makes the pose and move checks in a shared arena with ``K`` other robots
(``World(..., shared=True)``): the poses with ``K`` robots round the reader
(:func:`sensing_agreement.compare_backends` with ``others``: the robot each
ray and sonar met compared too, and the poses where a sonar read a robot counted), the
moves of ``K + 1`` robots walking among each other
(:func:`move_agreement.compare_shared_moves`: the moves a robot
changed, the starts touching a robot, the smallest clearance between two robots).

``--episodes N`` also trains ``N`` seeded episodes of the hallway in each world
(``--worlds``) with each learner (``--algorithms``: one-step Q and Q(lambda), those that
run compiled) and each robot count (``--robots``: 1 and 8) twice, on the Python loop
(the reference: ``koolio_pymunk.learning.episodes.Robots``) and on the compiled step
engine (:func:`compare_robots`), and counts the episodes after which the log row, any
robot's pose, state, memory, generators or learner, or the Q-table differ in any bit
(exit 1 if any).

    .venv/bin/python tools/agreement.py --poses 100000 --out agreement.json
    .venv/bin/python tools/agreement.py --poses 0 --moves 100000
    .venv/bin/python tools/agreement.py --poses 0 --episodes 3000
    .venv/bin/python tools/agreement.py --poses 20000 --moves 100000 --shared 7

About 1 ms per pose (the pymunk reference is most of it; 1 to 3 ms with koolio-real's
models): 100k poses x 3 arenas take about 3 minutes per world on 2 cores. A move
comparison is 0.15 to 0.35 ms (the clearance checks are most of it): ``--moves 100000``
takes 2 to 4 minutes on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor

ARENAS = ("hallway", "room", "obstacles")


IDEAL = "ideal"


def one(arena: str, poses: int, seed: int, noise: str, world: str, others: int = 0) -> dict:
    from sensing_agreement import compare_backends, cone_disagreement

    t = time.perf_counter()
    laid = None if world == IDEAL else world
    out = compare_backends(
        arena, poses, seed=seed, noise=noise, world=laid, others=others
    ).as_dict()
    out["world"] = world
    out["others"] = others
    out["seconds"] = round(time.perf_counter() - t, 1)
    if world == IDEAL:
        out["cone"] = cone_disagreement(arena, poses, seed=seed, others=others).as_dict()
    return out


def one_moves(arena: str | int, moves: int, seed: int, generated: int, others: int = 0) -> dict:
    """Move agreement in a shipped arena (a name) or generated arena number ``arena``,
    alone or among ``others`` robots."""
    from move_agreement import (
        compare_moves,
        compare_shared_moves,
        generated_arenas,
    )

    laid = arena if isinstance(arena, str) else generated_arenas(generated, seed)[arena]
    if others:
        return compare_shared_moves(laid, moves, seed=seed, others=others).as_dict()
    return compare_moves(laid, moves, seed=seed).as_dict()


def run_moves(
    moves: int, seed: int = 0, jobs: int = 2, generated: int = 4, others: int = 0
) -> list[dict]:
    """Move agreement figures per shipped and generated arena (a list of dicts)."""
    arenas: list[str | int] = [*ARENAS, *range(generated)]
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        futures = [pool.submit(one_moves, a, moves, seed, generated, others) for a in arenas]
        return [f.result() for f in futures]


def _side(
    arena: str,
    world: str | None,
    overrides: dict,
    seed: int,
    robots: int,
    compiled: bool,
    shared: bool = False,
    own_tables: bool = False,
):
    """One side of :func:`compare_robots`: an env, a table, the robots' learners, the loop
    (``shared``: the robots in one arena; ``own_tables``: each robot its own rows)."""
    from koolio_pymunk.learning.algorithms import make_learner
    from koolio_pymunk.learning.engine import robots as make_robots
    from koolio_pymunk.store.config import load_config
    from koolio_pymunk.store.keyword import own_tables as own_layout
    from koolio_pymunk.store.qtable import QTable
    from koolio_pymunk.task.env import KoolioEnv
    from koolio_pymunk.task.shared_arena import SharedArena

    cfg = load_config(overrides=overrides, world=world)
    envs = SharedArena.envs(robots, arena, cfg) if shared else KoolioEnv(arena, config=cfg)
    layout = envs[0].layout if shared else envs.layout
    if own_tables:
        layout = own_layout(layout, robots)
    table = QTable(layout, {}, cfg.learner.q_init)
    agents = [make_learner(table, cfg.learner, None) for _ in range(robots)]
    loop = make_robots(envs, agents, seed, compiled=compiled)
    if compiled and loop.python_reason is not None:
        raise ValueError(f"this configuration does not run compiled: {loop.python_reason}")
    return table, loop


def _snapshot(loop) -> list:
    """What must be the same on both sides after an episode: every robot's pose, state,
    memory, generators' states and learner (its last action, its traces)."""
    loop.sync()
    out = []
    for env, agent in zip(loop.envs, loop.agents):
        out.append(
            (
                env.world.pose(env.robot),
                bool(env.world.present[env.robot]) if env.share is not None else True,
                env.waiting,
                env.state_key,
                env.codes,
                (env.steps, env.bumps, env.episode_reward, env.has_been_rescued),
                env.np_random.bit_generator.state,
                agent.rng.bit_generator.state,
                agent.last,
                getattr(agent, "traces", None),
            )
        )
    return out


def compare_robots(
    arena: str = "hallway",
    world: str | None = None,
    episodes: int = 10,
    seed: int = 0,
    robots: int = 1,
    overrides: dict | None = None,
    max_steps: int | None = None,
    shared: bool = False,
    own_tables: bool = False,
) -> dict:
    """Train ``episodes`` seeded episodes of ``robots`` robots in ``arena`` (in ``world``,
    ``overrides`` laid over the configuration, ``max_steps`` the step cap; ``shared``: all
    in one arena, :mod:`koolio_pymunk.task.shared_arena`; ``own_tables``: each robot
    learns into its own rows, ``train --tables each``) twice, on the
    Python loop (:class:`koolio_pymunk.learning.episodes.Robots`, the reference) and on the
    compiled step engine, and compare after every finished episode its log row, the whole
    Q-table and every robot's pose, state, counters, memory, generators and learner, bit
    for bit. Returns the figures (``mismatches``: episodes after which anything differed).

    >>> r = compare_robots("room", episodes=3, robots=2, max_steps=40)
    >>> r["episodes"], r["mismatches"], r["steps"] > 0
    (3, 0, True)
    """
    over = dict(overrides or {})
    if max_steps is not None:
        over["episode"] = {**over.get("episode", {}), "max_steps": max_steps}
    t = time.perf_counter()
    sides = [
        _side(arena, world, over, seed, robots, compiled, shared, own_tables)
        for compiled in (False, True)
    ]
    started = [0, 0]
    for (_, loop), k in zip(sides, range(2)):
        for r in range(min(robots, episodes)):
            loop.begin(r, started[k])
            started[k] += 1
    steps = mismatches = 0
    first = -1
    for e in range(episodes):
        rows, snaps = [], []
        for k, (table, loop) in enumerate(sides):
            r = loop.advance()
            rows.append((r, loop.result(r, episode=e).row()))
            snaps.append((_snapshot(loop), dict(table.rows)))
            if started[k] < episodes:
                loop.begin(r, started[k])
                started[k] += 1
            else:
                loop.release(r)
        steps += int(rows[0][1][2])
        if rows[0] != rows[1] or snaps[0] != snaps[1]:
            mismatches += 1
            first = e if first < 0 else first
    return {
        "arena": arena,
        "world": world or IDEAL,
        "robots": robots,
        "episodes": episodes,
        "steps": steps,
        "mismatches": mismatches,
        "first_mismatch": first,
        "states": len(sides[1][0].rows),
        "seconds": round(time.perf_counter() - t, 1),
    }


def one_episodes(world: str, episodes: int, seed: int, algorithm: str = "q", robots: int = 1):
    laid = None if world == IDEAL else world
    over = {"learner": {"algorithm": algorithm}}
    out = compare_robots("hallway", laid, episodes, seed, robots, overrides=over)
    return {"algorithm": algorithm, **out}


def run_episodes(
    episodes: int,
    seed: int,
    jobs: int,
    worlds: tuple[str, ...],
    algorithms: tuple[str, ...],
    robots: tuple[int, ...] = (1,),
) -> list[dict]:
    """Step-engine agreement figures per world, algorithm and robot count (dicts)."""
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        futures = [
            pool.submit(one_episodes, w, episodes, seed, a, n)
            for n in robots
            for a in algorithms
            for w in worlds
        ]
        return [f.result() for f in futures]


def print_episodes(rows: list[dict]) -> None:
    print("step engine vs the Python loop (rows, robots, tables, bit for bit):")
    print(
        f"{'algorithm':>9} {'world':>12} {'robots':>6} {'episodes':>9} {'steps':>10} "
        f"{'mismatches':>11} {'states':>7} {'s':>6}"
    )
    for r in rows:
        print(
            f"{r['algorithm']:>9} {r['world']:>12} {r['robots']:>6} {r['episodes']:>9} "
            f"{r['steps']:>10} {r['mismatches']:>11} {r['states']:>7} {r['seconds']:>6}"
        )


def print_poses(rows: list[dict]) -> None:
    shared = any(r.get("others") for r in rows)
    if shared:
        print(f"among {rows[0]['others']} other robots (a shared arena):")
    extra = f" {'read a robot':>13}" if shared else ""
    print(
        f"{'arena':>10} {'world':>12} {'poses':>8} {'dist. mismatch':>15} "
        f"{'state mismatch':>15} {'bit-identical':>14} {'max |diff| in':>14}{extra} {'s':>6}"
    )
    for r in rows:
        extra = f" {r['robot_readings']:>13}" if shared else ""
        print(
            f"{r['arena']:>10} {r['world']:>12} {r['poses']:>8} {r['distance_mismatches']:>15} "
            f"{r['state_mismatches']:>15} {r['bit_identical']:>14} "
            f"{r['max_abs_diff']:>14.3g}{extra} {r['seconds']:>6}"
        )
    cones = [r for r in rows if "cone" in r]
    if cones:
        print("exact-cone sonar model (backend: cone) vs the paper's sub-arcs, after encoding:")
    for r in cones:
        c = r["cone"]
        print(
            f"{r['arena']:>10}: state differs on {c['state_differs']:.1%} of poses; per sonar "
            f"group {', '.join(f'{g:.1%}' for g in c['group_differs'])}; "
            f"cone farther than sub-arcs: {c['cone_not_nearer']}"
        )


def print_shared_moves(rows: list[dict]) -> None:
    print(
        f"compiled swept move among {rows[0]['robots'] - 1} other robots vs the pymunk "
        "world's (end positions, bit for bit):"
    )
    print(
        f"{'arena':>12} {'moves':>8} {'mismatches':>11} {'met a robot':>12} "
        f"{'touching one':>13} {'min clearance: wall':>20} {'robot':>10} {'s':>6}"
    )
    for r in rows:
        print(
            f"{r['arena']:>12} {r['moves']:>8} {r['mismatches']:>11} {r['robot_contacts']:>12} "
            f"{r['touching_robot']:>13} {r['min_clearance']:>20.3g} "
            f"{r['min_robot_clearance']:>10.3g} {r['seconds']:>6}"
        )


def print_moves(rows: list[dict]) -> None:
    if rows and "robots" in rows[0]:
        print_shared_moves(rows)
        return
    print("compiled swept move vs the pymunk world's (end positions, bit for bit):")
    print(
        f"{'arena':>12} {'moves':>8} {'mismatches':>11} {'met a wall':>11} "
        f"{'touching':>9} {'min clearance in':>17} {'s':>6}"
    )
    for r in rows:
        print(
            f"{r['arena']:>12} {r['moves']:>8} {r['mismatches']:>11} {r['contacts']:>11} "
            f"{r['touching']:>9} {r['min_clearance']:>17.3g} {r['seconds']:>6}"
        )


def run(
    poses: int,
    seed: int = 0,
    jobs: int = 2,
    noise: str = "none",
    worlds: tuple[str, ...] = (IDEAL, "koolio-real"),
    others: int = 0,
) -> list[dict]:
    """Agreement figures per shipped arena and world (a list of dicts), alone or among
    ``others`` robots."""
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        futures = [
            pool.submit(one, a, poses, seed, noise, w, others) for w in worlds for a in ARENAS
        ]
        return [f.result() for f in futures]


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--poses", type=int, default=100_000, help="poses per arena (100000)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--jobs", type=int, default=2, help="processes (2)")
    p.add_argument("--noise", default="none", help="noise model for the state check (none)")
    p.add_argument(
        "--worlds",
        nargs="+",
        default=[IDEAL, "koolio-real"],
        help="worlds to check: 'ideal' and world profiles or files (ideal koolio-real)",
    )
    p.add_argument("--moves", type=int, default=0, help="moves per arena, the motion (0)")
    p.add_argument("--generated", type=int, default=4, help="generated arenas for --moves (4)")
    p.add_argument(
        "--shared",
        type=int,
        default=0,
        metavar="K",
        help="--poses and --moves in a shared arena with K other robots (0: alone)",
    )
    p.add_argument(
        "--episodes", type=int, default=0, help="training episodes per world, the episode (0)"
    )
    p.add_argument(
        "--algorithms",
        nargs="+",
        default=["q", "qlambda"],
        help="learner.algorithm of the --episodes runs (q qlambda: those that run compiled)",
    )
    p.add_argument(
        "--robots",
        nargs="+",
        type=int,
        default=[1, 8],
        help="robot counts of the --episodes runs (1 8)",
    )
    p.add_argument("--out", default=None, help="write the figures as JSON here")
    args = p.parse_args(argv)
    rows, moves, episodes = [], [], []
    if args.poses:
        rows = run(args.poses, args.seed, args.jobs, args.noise, tuple(args.worlds), args.shared)
        print_poses(rows)
    if args.moves:
        moves = run_moves(args.moves, args.seed, args.jobs, args.generated, args.shared)
        print_moves(moves)
    if args.episodes:
        episodes = run_episodes(
            args.episodes,
            args.seed,
            args.jobs,
            tuple(args.worlds),
            tuple(args.algorithms),
            tuple(args.robots),
        )
        print_episodes(episodes)
    if args.out:
        out: object = rows
        if args.moves or args.episodes:
            out = {"poses": rows, "moves": moves, "episodes": episodes}
        with open(args.out, "w", encoding="utf-8") as fh:
            json.dump(out, fh, indent=2)
    bad = sum(r["distance_mismatches"] + r["state_mismatches"] for r in rows)
    bad += sum(r["mismatches"] for r in moves) + sum(r["mismatches"] for r in episodes)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
