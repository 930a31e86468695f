"""What a training run reports as scalars, for TensorBoard (``koolio-pm train --tensorboard DIR``).

:class:`RunScalars` writes, through :class:`~koolio_pymunk.store.tensorboard.EventWriter`
(a new event file in ``DIR`` per run), one record per finished episode and one per
periodic check, each at the environment step its episode ended on, counted from the
table's first episode (the steps of the episodes its log already holds), so a resumed
run continues the curves where they stopped:

* ``episode/return``, ``episode/steps``, ``episode/bumps``, ``episode/goal`` (1 at the
  goal, else 0), ``episode/epsilon``, ``episode/rescued``;
* ``train/goal_rate``: the share at the goal of the last 100 training episodes (with
  exploration: ``train``'s progress line), ``train/episodes`` (the table's count);
* with ``--eval-every``: ``check/goal_rate``, ``check/end_of_world_rate``,
  ``check/wrong_door_rate``, ``check/truncated_rate``, ``check/mean_steps``,
  ``check/mean_return`` (the greedy checks).

The records are written at most once a second (and at the end): a killed run loses at
most the last second of them; the table and the log lose nothing (their own rules).

>>> import tempfile
>>> from koolio_pymunk.store.tensorboard import read_scalars
>>> from koolio_pymunk.learning.episodes import EpisodeResult
>>> run = RunScalars(tempfile.mkdtemp(), start_steps=100)
>>> run.episode(EpisodeResult(4, -12.5, 30, 1, "goal", False, 0.15, "311"))
>>> run.close()
>>> sorted((s.tag, s.step, s.value) for s in read_scalars(run.writer.path))[:2]
[('episode/bumps', 130, 1.0), ('episode/epsilon', 130, 0.15000000596046448)]
"""

from __future__ import annotations

import time
from collections import deque
from pathlib import Path

from ..store.episode_log import log_rows
from ..store.tensorboard import EventWriter
from .episodes import EpisodeResult
from .evaluation import Check


def logged_steps(log_path: str | Path | None) -> int:
    """The environment steps of the episodes a log holds (0: no log, or none yet)."""
    if log_path is None or str(log_path) == "":
        return 0
    return sum(int(row["steps"]) for row in log_rows(log_path) if row["steps"].isdigit())


class RunScalars:
    """A run's scalars into a new event file in ``logdir`` (module doc); ``start_steps``:
    the environment steps before the run's first episode."""

    def __init__(self, logdir: str | Path, start_steps: int = 0) -> None:
        self.writer = EventWriter(logdir)
        self.steps = start_steps
        """Environment steps so far: the step of the next record."""
        self._recent: deque[bool] = deque(maxlen=100)
        self._flushed = time.monotonic()

    def episode(self, res: EpisodeResult) -> None:
        """A finished episode (its row)."""
        self.steps += res.steps
        goal = res.outcome == "goal"
        self._recent.append(goal)
        self.writer.scalars(
            {
                "episode/return": res.reward,
                "episode/steps": res.steps,
                "episode/bumps": res.bumps,
                "episode/goal": float(goal),
                "episode/epsilon": res.epsilon,
                "episode/rescued": float(res.rescued),
                "train/goal_rate": sum(self._recent) / len(self._recent),
                "train/episodes": res.episode + 1,
            },
            step=self.steps,
        )
        self._maybe_flush()

    def check(self, c: Check) -> None:
        """A periodic greedy check."""
        r = c.result
        self.writer.scalars(
            {
                "check/goal_rate": r.goal_rate,
                "check/end_of_world_rate": r.end_of_world_rate,
                "check/wrong_door_rate": r.wrong_door_rate,
                "check/truncated_rate": r.truncated_rate,
                "check/mean_steps": r.mean_steps,
                "check/mean_return": r.mean_reward,
            },
            step=self.steps,
        )

    def _maybe_flush(self) -> None:
        now = time.monotonic()
        if now - self._flushed >= 1.0:
            self.writer.flush()
            self._flushed = now

    def close(self) -> None:
        """Write what waits and close the file."""
        self.writer.close()
