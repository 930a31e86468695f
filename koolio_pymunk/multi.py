"""Many robots learning into one shared Q-table (``koolio-pm train --robots N``).

All ``N`` robots live in one pymunk :class:`~koolio_pymunk.world.World` (one space, one
non-colliding shape group: each robot is alone in its own copy of the arena) and run
their own episodes of the single-robot task (same actions, sensors, rewards, rescue, step
cap). Their experience goes into one :class:`~koolio_pymunk.qtable.QTable`.

**A tick** (every robot takes one step):

1. every active robot chooses an action epsilon-greedily from the table as it stands;
2. all robots act together (one set of pymunk sub-steps for the whole space);
3. all robots are sensed in two compiled calls (:func:`raycast.sense_batch`,
   :func:`readout.readout_batch`: robots x rays x walls);
4. **in robot index order**, each robot's step is judged (reward, end of episode),
   rescued if auto rescue fires, and its Table 11 update applied to the shared table
   (so robot ``r`` bootstraps from values robots ``< r`` updated in the same tick);
   a finished episode is logged, and the robot starts a new one if the budget allows.

**Numbering.** Episodes are numbered in completion order (robot index order within a
tick), continuing from the table's ``episodes`` count, and logged in the usual CSV
format. Episode *starts* are numbered too (0, 1, ... from the same count, robot order):
the epsilon schedule uses the start number, since an episode's completion number is not
known while it runs. Exactly ``episodes`` episodes are started and finished; robots
without a new episode to start stand still.

**Randomness** (a seeded run is reproducible for a given seed and N):

* per tick, from one run generator ``default_rng([seed, N, 2])``: the exploration draws,
  random actions and tie-breaks (``N`` each), then every robot's sensor noise
  (``N x readings``), in that order;
* per episode start ``k``, ``default_rng(episode_seeds(seed, k)[0])``: the random goal
  (``--goal random``), the start heading, the first reading's noise, and every auto-rescue
  draw of that episode.

**Saving.** The table is written (file + backup, as :func:`training.train` does) each
time ``save_every`` more episodes have finished (default ``N``: about once per round of
episodes rather than at every episode end, because N robots finish episodes N times as
often and every save is two fsynced file writes), and always at the end and on Ctrl-C.
``save_every=1`` is the paper's cadence. Ctrl-C folds every unfinished episode into the
table (logged ``interrupted``); with ``discard_unfinished`` the table file is left as last
saved.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pymunk.batch

from .env import KoolioEnv
from .qtable import QTableStore, load_qtable
from .raycast import new_trig, sense_batch, sense_one
from .readout import readout, readout_batch
from .rescue import rescue_robot, wants_rescue
from .training import (
    EpisodeResult,
    LogWriter,
    Progress,
    TrainResult,
    episode_seeds,
    sensor_signature,
)
from .world import Action, World

STOP = int(Action.STOP)
FORWARD = int(Action.FORWARD)
REVERSE = int(Action.REVERSE)


class PoseReader:
    """Every robot's position in one pymunk batch call (``pymunk.batch``).

    Chipmunk lists bodies in its own order (sleeping robots move to the end), so each
    call reads the body ids too and puts the rows back in robot order; each robot's
    arena-copy offset is then removed.
    """

    def __init__(self, world: World) -> None:
        self.world = world
        self.n = world.n_robots
        ids = np.array([b.id for b in world.bodies], dtype=np.intp)
        self.order = np.argsort(ids)
        self.sorted_ids = ids[self.order]
        self.offsets = np.asarray(world.offsets, dtype=np.float64)
        self.buffer = pymunk.batch.Buffer()
        self.fields = pymunk.batch.BodyFields.BODY_ID | pymunk.batch.BodyFields.POSITION

    def xy(self) -> np.ndarray:
        """``(N, 2)`` positions in robot order, arena coordinates (as ``World.pose``)."""
        self.buffer.clear()
        pymunk.batch.get_space_bodies(self.world.space, self.fields, self.buffer)
        ids = np.frombuffer(self.buffer.int_buf(), dtype=np.intp)
        pos = np.frombuffer(self.buffer.float_buf()).reshape(-1, 2)
        at = np.minimum(np.searchsorted(self.sorted_ids, ids), self.n - 1)
        robot = self.sorted_ids[at] == ids  # drops the static body
        out = np.empty((self.n, 2))
        out[self.order[at[robot]]] = pos[robot]
        out[:, 0] -= self.offsets
        return out


class Fleet:
    """Sensing of N robots: the single-robot sensor suite's kernel inputs, N-row buffers."""

    def __init__(self, env: KoolioEnv, world: World) -> None:
        self.k = env.sensors._kernel
        self.suite = env.sensors
        n, m = world.n_robots, self.k.n_raw
        self.world = world
        self.goals = np.tile(self.k.goal, (n, 1))
        self.raw = np.empty((n, m))
        self.rays = np.empty((n,) + self.k.ray_offsets.shape)
        self.eow_k = np.empty((n, self.suite.n_camera), np.int64)
        self.out = np.empty((n, m))
        self.codes = np.empty((n, len(self.k.bits)), np.int64)
        self.keys = np.empty(n, np.int64)
        self.flags = np.empty((n, 2), np.bool_)
        self.walls = self.suite.engine.walls
        self.trig = new_trig(self.k.ray_offsets.size, n)

    def _args(self) -> tuple:
        k = self.k
        return (
            k.fracs,
            self.suite.n_sonar,
            k.limits,
            self.suite.sonar_thresholds,
            self.suite.camera_thresholds,
            k.group_members,
            k.group_sizes,
            k.bits,
            k.compass_in_state,
        )

    def sense_all(
        self, xy: np.ndarray, headings: list[float], draws: np.ndarray
    ) -> tuple[list[int], list[bool], list[bool]]:
        """State key, Bump and goal-close of every robot."""
        k = self.k
        sense_batch(
            np.ascontiguousarray(xy[:, 0]),
            np.ascontiguousarray(xy[:, 1]),
            np.asarray(headings, dtype=np.float64),
            k.ray_offsets,
            k.params,
            k.camera_dirs,
            self.goals,
            k.markers,
            self.walls,
            self.raw,
            self.rays,
            self.eow_k,
            self.trig,
        )
        readout_batch(
            self.raw, draws, *self._args(), self.out, self.eow_k, self.codes, self.keys, self.flags
        )
        return self.keys.tolist(), self.flags[:, 0].tolist(), self.flags[:, 1].tolist()

    def sense_one(self, r: int, rng: np.random.Generator) -> tuple[int, bool, bool]:
        """Robot ``r`` alone (after a reset or a rescue), noise from ``rng``."""
        k = self.k
        x, y, h = self.world.pose(r)
        sense_one(
            x,
            y,
            h,
            k.ray_offsets,
            k.params,
            k.camera_dirs,
            self.goals[r],
            k.markers,
            self.walls,
            self.raw[r],
            self.rays[r],
            self.eow_k[r],
            self.trig[r],
        )
        draws = self.suite.draw_noise(rng, k.n_raw)
        return readout(self.raw[r], draws, *self._args(), self.out[r], self.eow_k[r], self.codes[r])


class _Episode:
    """The running episode of one robot."""

    __slots__ = ("bumps", "epsilon", "goal", "key", "rescued", "reward", "rng", "start", "steps")

    def __init__(self, start: int, rng: np.random.Generator, epsilon: float, goal: str) -> None:
        self.start = start
        self.rng = rng
        self.epsilon = epsilon
        self.goal = goal
        self.key = 0
        self.steps = 0
        self.bumps = 0
        self.reward = 0.0
        self.rescued = False


def train_many(
    env: KoolioEnv,
    store: QTableStore,
    episodes: int,
    seed: int,
    log_path: str | Path | None = None,
    robots: int = 2,
    discard_unfinished: bool = False,
    report: Callable[[str], None] | None = print,
    report_every: float = 1.0,
    save_every: int | None = None,
) -> TrainResult:
    """Train ``robots`` robots for ``episodes`` more episodes into one table (module doc)."""
    return _Run(env, store, episodes, seed, log_path, robots, save_every).run(
        discard_unfinished, report, report_every
    )


class _Run:
    def __init__(
        self,
        env: KoolioEnv,
        store: QTableStore,
        episodes: int,
        seed: int,
        log_path: str | Path | None,
        robots: int,
        save_every: int | None,
    ) -> None:
        cfg = env.config
        self.env, self.cfg, self.store = env, cfg, store
        self.table = store.open(env.layout, sensor_signature(cfg), cfg.learner.q_init)
        self.first = int(self.table.meta.get("episodes", 0))
        self.budget = episodes
        self.seed = seed
        self.n = robots
        self.save_every = max(1, save_every if save_every is not None else robots)
        self.world = World.from_arena(env.arena, cfg.robot.radius, robots)
        self.poses = PoseReader(self.world)
        self.fleet = Fleet(env, self.world)
        self.log = LogWriter(log_path)
        self.progress = Progress()
        self.results: list[EpisodeResult] = []
        self.tick_rng = np.random.default_rng([seed, robots, 2])
        self.started = 0
        self.finished = 0
        self.unsaved = 0
        self.eps: list[_Episode | None] = [None] * robots

    # -- episodes ---------------------------------------------------------------------
    def _start(self, r: int) -> None:
        """Start episode number ``first + started`` on robot ``r`` (or idle it)."""
        if self.started >= self.budget:
            self.eps[r] = None
            return
        k = self.first + self.started
        self.started += 1
        env, world = self.env, self.world
        rng = np.random.default_rng(episode_seeds(self.seed, k)[0])
        names = env.world_arena.goal_names()
        goal = names[int(rng.integers(len(names)))] if env.random_goal else env.goal_name
        self.fleet.goals[r] = env.world_arena.goal(goal).at
        ep = _Episode(k, rng, self.cfg.learner.epsilon.at(k), goal)
        start = env.world_arena.start
        heading = (
            np.radians(start.heading_deg)
            if start.heading_deg is not None
            else float(rng.uniform(0.0, 2.0 * np.pi))
        )
        world.place(r, start.at, float(heading))
        ep.key = self.fleet.sense_one(r, rng)[0]
        self.eps[r] = ep

    def _finish(self, r: int, outcome: str) -> None:
        ep = self.eps[r]
        assert ep is not None
        e = self.first + self.finished
        self.finished += 1
        res = EpisodeResult(
            e, ep.reward, ep.steps, ep.bumps, outcome, ep.rescued, ep.epsilon, ep.goal
        )
        self.table.meta["episodes"] = e + 1
        self.log.write(res)
        self.results.append(res)
        self.progress.add(res)
        self.unsaved += 1
        if self.unsaved >= self.save_every or self.finished == self.budget:
            self.store.save(self.table)
            self.unsaved = 0
        self._start(r)

    # -- the loop -----------------------------------------------------------------------
    def run(
        self,
        discard_unfinished: bool,
        report: Callable[[str], None] | None,
        report_every: float,
    ) -> TrainResult:
        interrupted = False
        last_report = time.perf_counter()
        try:
            for r in range(self.n):
                self._start(r)
            while self.finished < self.budget:
                self._tick()
                now = time.perf_counter()
                if report and now - last_report >= report_every:
                    eps = [ep.epsilon for ep in self.eps if ep is not None]
                    report(self._line(eps[0] if eps else 0.0))
                    last_report = now
            if report:
                report(self._line(self.cfg.learner.epsilon.at(self.first + self.budget - 1)))
        except KeyboardInterrupt:
            interrupted = True
            self._interrupt(discard_unfinished, report)
        finally:
            self.log.close()
        p = self.progress
        return TrainResult(
            self.table,
            p.episodes,
            p.goals,
            p.steps,
            time.perf_counter() - p.started,
            interrupted,
            self.results,
        )

    def _line(self, epsilon: float) -> str:
        done = self.first + self.finished
        return self.progress.line(done, self.first + self.budget, epsilon) + f"  robots {self.n}"

    def _interrupt(self, discard: bool, report: Callable[[str], None] | None) -> None:
        if discard:
            self.table = load_qtable(self.store.path)
            if report:
                report("interrupted: unfinished episodes discarded (Exit Without Save)")
            return
        for ep in self.eps:
            if ep is not None:
                res = EpisodeResult(
                    self.first + self.finished,
                    ep.reward,
                    ep.steps,
                    ep.bumps,
                    "interrupted",
                    ep.rescued,
                    ep.epsilon,
                    ep.goal,
                )
                self.log.write(res)
                self.results.append(res)
        self.store.save(self.table)
        if report:
            report("interrupted: unfinished episodes folded into the Q-table and saved (Exit)")

    def _tick(self) -> None:
        n, eps, rows = self.n, self.eps, self.table.rows
        rng = self.tick_rng
        n_actions = self.table.layout.n_actions
        explore = rng.random(n).tolist()
        random_action = rng.integers(n_actions, size=n).tolist()
        tie = rng.random(n).tolist()
        draws = self.fleet.suite.draw_noise(rng, n * self.fleet.k.n_raw).reshape(n, -1)
        actions = [STOP] * n
        for r in range(n):
            ep = eps[r]
            if ep is None:
                continue
            if explore[r] < ep.epsilon:
                actions[r] = random_action[r]
                continue
            row = rows.get(ep.key)
            if row is None:
                actions[r] = random_action[r]
                continue
            best = max(row)
            count = row.count(best)
            if count == 1:
                actions[r] = row.index(best)
            else:
                ties = [a for a, q in enumerate(row) if q == best]
                actions[r] = ties[int(tie[r] * count)]
        world = self.world
        world.act(actions, self.env._distance, self.env._arc)
        xy = self.poses.xy()
        keys, bumps, closes = self.fleet.sense_all(xy, world.heading, draws)
        self._learn(actions, keys, bumps, closes, xy.tolist())

    def _learn(
        self,
        actions: list[int],
        keys: list[int],
        bumps: list[bool],
        closes: list[bool],
        xy: list[list[float]],
    ) -> None:
        cfg = self.cfg
        rw = cfg.rewards
        by_action = (rw.stop, rw.turn, rw.turn, rw.forward, rw.reverse)
        alpha, gamma = cfg.learner.alpha, cfg.learner.gamma
        q_init = self.table.q_init
        rows = self.table.rows
        row_of = self.table.row
        contains = self.env.zones.contains
        rescue, cap = cfg.rescue, cfg.episode.max_steps
        for r in range(self.n):
            ep = self.eps[r]
            if ep is None:
                continue
            a, bump = actions[r], bumps[r]
            terminal = True
            if a == STOP and closes[r]:
                event, reward = "goal", rw.goal
            elif contains(xy[r][0], xy[r][1]):
                event, reward = "end_of_world", rw.end_of_world
            elif bump:
                event, reward, terminal = "bump", rw.bump, False
            else:
                event, reward, terminal = "", by_action[a], False
            ep.steps += 1
            ep.bumps += bump
            ep.reward += reward
            nxt = keys[r]
            if not terminal and wants_rescue(rescue, ep.steps, bump, ep.rng):
                rescue_robot(self.world, r, rescue, self.env._distance, ep.rng)
                nxt = self.fleet.sense_one(r, ep.rng)[0]
                ep.rescued = True
            row = row_of(ep.key)
            if terminal:
                target = reward
            else:
                nrow = rows.get(nxt)
                target = reward + gamma * (max(nrow) if nrow is not None else q_init)
            row[a] += alpha * (target - row[a])
            ep.key = nxt
            if terminal:
                self._finish(r, event)
            elif cap > 0 and ep.steps >= cap:
                self._finish(r, "truncated")
