"""Timing of the tools' measurements: wall and CPU seconds of a block, and the rates."""

from __future__ import annotations

import time


class Timer:
    """Wall and CPU seconds of a block."""

    def __enter__(self) -> Timer:
        self.w0, self.c0 = time.perf_counter(), time.process_time()
        return self

    def __exit__(self, *exc: object) -> None:
        self.wall = time.perf_counter() - self.w0
        self.cpu = time.process_time() - self.c0


def rates(steps: int, t: Timer) -> dict:
    return {
        "steps": steps,
        "wall_s": round(t.wall, 3),
        "cpu_s": round(t.cpu, 3),
        "per_wall_s": round(steps / max(t.wall, 1e-9)),
        "per_cpu_s": round(steps / max(t.cpu, 1e-9)),
    }
