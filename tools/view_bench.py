"""Does drawing throttle learning? ``koolio-pm view`` (clockless) against headless ``train``.

Both learn the same episodes on the same arena with the same seed, in one process, one
after the other (interleaved ``--repeat`` times, best run of each kept): ``train`` through
:func:`koolio_pymunk.learning.training.train`, the window through the real window loop
(:meth:`ViewerApp.run`: events, clockless ticks of ``clockless_loop_count`` steps, a full
redraw at most 30 times a second). The two Q-tables must come out byte-identical (same
work), so the ratio of times is the cost of the window. Prints steps/s of each and the
ratio view / train; the issue asks for at least 0.80.

Times are measured twice: wall clock, and this process's CPU time (``time.process_time``,
all threads, so drawing counts). On an idle machine the two agree; on a shared machine
other processes stretch wall times at random, so the ratio is computed on CPU time
(``--clock wall`` to use wall time instead).

    SDL_VIDEODRIVER=dummy .venv/bin/python tools/view_bench.py --arena hallway --episodes 100

Without a display, SDL_VIDEODRIVER defaults to ``dummy`` here (pygame still draws every
frame into the window surface; only the final copy to a screen is skipped).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path


class Timer:
    """Wall and CPU seconds of a block."""

    def __enter__(self) -> Timer:
        self.w0, self.c0 = time.perf_counter(), time.process_time()
        return self

    def __exit__(self, *exc) -> None:
        self.wall = time.perf_counter() - self.w0
        self.cpu = time.process_time() - self.c0


def run_train(arena: str, episodes: int, seed: int, folder: Path) -> tuple[int, Timer, bytes]:
    from koolio_pymunk.learning.training import train
    from koolio_pymunk.store.qtable import QTableStore
    from koolio_pymunk.task.env import KoolioEnv

    env = KoolioEnv(arena)
    store = QTableStore(folder / "train.qtable")
    with Timer() as t:
        res = train(env, store, episodes, seed, folder / "train.csv", report=None)
    return res.steps, t, (folder / "train.qtable").read_bytes()


def run_view(
    arena: str, episodes: int, seed: int, folder: Path, size: tuple[int, int], budget: float
) -> tuple[int, Timer, bytes, int, float]:
    from koolio_pymunk.apps.viewer.app import ViewerApp
    from koolio_pymunk.apps.viewer.session import Session
    from koolio_pymunk.task.env import KoolioEnv

    env = KoolioEnv(arena)
    session = Session(
        env, folder / "view.qtable", seed=seed, episodes=episodes, log=folder / "view.csv"
    )
    app = ViewerApp(session, size=size, clockless=True, running=True, max_steps=None)
    app.headless = True  # stop when the episodes are done, even with a real window
    if budget > 0:
        app.draw_budget = budget
    with Timer() as t:
        app.run()
    frames = app.frames_drawn
    c1 = time.process_time()
    for _ in range(20):
        app.draw()
    draw_ms = (time.process_time() - c1) / 20 * 1000.0  # CPU time per full redraw
    app.finish()
    return session.total_steps, t, (folder / "view.qtable").read_bytes(), frames, draw_ms


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    p.add_argument("--arena", default="hallway")
    p.add_argument("--episodes", type=int, default=100)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--repeat", type=int, default=2, help="interleaved runs of each (best kept)")
    p.add_argument("--size", default="1280x800")
    p.add_argument("--clock", choices=("cpu", "wall"), default="cpu", help="time for the ratio")
    p.add_argument(
        "--budget",
        type=float,
        default=0.0,
        help="share of wall time redraws may take (default: the window's own, 0.05); "
        "1 = a plain 30 frames per second",
    )
    args = p.parse_args(argv)
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    os.environ.setdefault("SDL_AUDIODRIVER", "dummy")
    size = tuple(int(v) for v in args.size.split("x"))
    best_train = best_view = 0.0
    print(
        f"view vs train: arena {args.arena}, {args.episodes} episodes, seed {args.seed}, "
        f"window {args.size}, SDL_VIDEODRIVER={os.environ['SDL_VIDEODRIVER']}, "
        f"draw budget {args.budget or 'default'}"
    )
    for r in range(args.repeat):
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp)
            steps_t, t_train, table_t = run_train(args.arena, args.episodes, args.seed, folder)
            steps_v, t_view, table_v, frames, draw_ms = run_view(
                args.arena, args.episodes, args.seed, folder, size, args.budget
            )
        if steps_t != steps_v or table_t != table_v:
            print("error: view and train did different work (tables differ)", file=sys.stderr)
            return 1
        sec_t = getattr(t_train, args.clock)
        sec_v = getattr(t_view, args.clock)
        rate_t, rate_v = steps_t / sec_t, steps_v / sec_v
        best_train, best_view = max(best_train, rate_t), max(best_view, rate_v)
        print(
            f"  run {r + 1}: {steps_t} steps; train {rate_t:7.0f} steps/s "
            f"(cpu {t_train.cpu:.2f} s, wall {t_train.wall:.2f} s); view {rate_v:7.0f} steps/s "
            f"(cpu {t_view.cpu:.2f} s, wall {t_view.wall:.2f} s; {frames} frames drawn, "
            f"{draw_ms:.1f} ms cpu per frame); ratio {rate_v / rate_t:.3f}"
        )
    ratio = best_view / best_train
    print(
        f"best ({args.clock} time): train {best_train:.0f} steps/s, "
        f"view (clockless) {best_view:.0f} steps/s, "
        f"ratio view/train {ratio:.3f} ({'ok' if ratio >= 0.8 else 'BELOW'} the 0.80 target)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
