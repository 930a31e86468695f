"""Many robots learning into one shared Q-table (``koolio-pm train --robots N``).

All ``N`` robots live in one pymunk :class:`~koolio_pymunk.world.physics.World` (one space, one
non-colliding shape group: each robot is alone in its own copy of the arena) and run
their own episodes of the single-robot task (same actions, sensors, rewards, rescue, step
cap). Their experience goes into one :class:`~koolio_pymunk.learning.qtable.QTable`.

**A tick** (every robot takes one step):

1. every active robot chooses an action epsilon-greedily from the table as it stands
   (:func:`qkernel.choose`);
2. all robots act in one compiled call (:func:`fleet_kernel.move_all`: turns, and each
   Forward or Reverse a :func:`~koolio_pymunk.world.swept_move.sweep` against the robot's
   own copy of the walls, in its copy's coordinates, as the pymunk world moves it, bit
   for bit); the pymunk bodies are set from those positions before a rescue (which moves
   through pymunk) and at the end of the run;
3. all robots are sensed in two compiled calls (:func:`raycast.sense_batch`,
   :func:`readout.readout_batch`: robots x rays x walls; always the compiled kernel,
   which reads what the pymunk reference reads);
4. **in robot index order**, each robot's step is judged (reward, end of episode),
   its Table 11 update applied to the shared table (so robot ``r`` bootstraps from values
   robots ``< r`` updated in the same tick), then rescued if auto rescue fires;
   a finished episode is logged, and the robot starts a new one if the budget allows.
   :func:`qkernel.learn` does this compiled and hands each rescue draw and episode end
   to Python in that same order.

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
often and every save is an fsynced file write), and always at the end and on Ctrl-C.
``save_every=1`` is the paper's cadence. Each finished episode's row is logged when it
finishes, so after a SIGKILL the log may be ahead of the table by up to ``save_every - 1``
rows: resuming removes them (:mod:`koolio_pymunk.store.episode_log`).

**Ctrl-C** (taken between ticks) folds every unfinished episode into the table and logs
it ``interrupted``, numbered ``first + finished``, ``+ 1``, ... in robot order (the numbers
those episodes get when training resumes). With ``discard_unfinished`` only the unfinished
episodes are discarded: every finished episode stays in the table and the log. The robots
share one table, so an unfinished episode's writes are interleaved with those of
episodes that finished; each robot journals its own writes (:func:`qkernel.undo_writes`),
and the discard takes back, newest first, every write of an unfinished episode that no
other robot has written over since (and drops the rows only they created), then saves.

**Algorithm.** One-step Q only (``learner.algorithm: q``): Q(lambda) and Dyna-Q
(``docs/learning.md``) are refused with a one-line error, since the compiled loop has
neither per-robot traces nor a model.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import numba
import numpy as np
import pymunk.batch

from ..sensing.encoding_kernel import readout, readout_batch
from ..sensing.ray_kernel import new_trig, sense_batch, sense_one
from ..sensing.sensor_arrays import GEOMETRY, bundle
from ..store.errors import ConfigError, KoolioError, located
from ..store.interrupts import SafeInterrupt
from ..store.realism_config import realism_on
from ..task.env import KoolioEnv
from ..task.rescue import rescue_robot
from ..world.physics import Action, World
from ..world.segment_query import wall_array
from .episodes import INTERRUPTED, TRUNCATED, EpisodeResult, episode_seeds
from .fleet_kernel import (
    AT_CAP,
    EVENTS,
    RESCUE_DRAW,
    TERMINAL,
    SharedTable,
    choose,
    learn,
    move_all,
    new_journal,
    reward_array,
    undo_writes,
    update_logged,
    zone_arrays,
)
from .qtable import QTableStore
from .training import Progress, RunFiles, TrainResult

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
        pos = np.frombuffer(self.buffer.float_buf())
        out = np.empty((self.n, 2))
        _robot_order(ids, pos, self.sorted_ids, self.order, self.offsets, out)
        return out


@numba.njit(cache=True)
def _robot_order(
    ids: np.ndarray,
    pos: np.ndarray,
    sorted_ids: np.ndarray,
    order: np.ndarray,
    offsets: np.ndarray,
    out: np.ndarray,
) -> None:
    """Row ``order[k]`` of ``out`` = the position listed with ``sorted_ids[k]``, minus its
    robot's x offset; bodies that are no robot (the static body) are skipped."""
    for j in range(ids.shape[0]):
        k = np.searchsorted(sorted_ids, ids[j])
        if k < sorted_ids.shape[0] and sorted_ids[k] == ids[j]:
            r = order[k]
            out[r, 0] = pos[2 * j] - offsets[r]
            out[r, 1] = pos[2 * j + 1]


class Fleet:
    """Sensing of N robots: the single-robot sensor suite's kernel inputs, N-row buffers.

    Always the compiled kernel (batched over robots), whatever ``sensors.backend`` says:
    with ``pymunk`` the readings are the same numbers (see ``docs/speed.md``); ``cone``
    keeps its cone sonar.
    """

    def __init__(self, env: KoolioEnv, world: World) -> None:
        self.k = env.sensors.kernel
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
        self.walls = wall_array(world)  # any backend: the kernel reads robot 0's copy
        self.trig = new_trig(self.k.ray_offsets.size, n)
        self.geometry = bundle(GEOMETRY, self.k, walls=self.walls)
        """The sensing kernel's geometry group, with this world's walls."""

    def sense_all(
        self, xy: np.ndarray, headings: list[float], draws: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """State key of every robot, and their Bump and goal-close flags (``N x 2``)."""
        k = self.k
        xs, ys = np.ascontiguousarray(xy[:, 0]), np.ascontiguousarray(xy[:, 1])
        hs = np.asarray(headings, dtype=np.float64)
        sense_batch(xs, ys, hs, self.geometry, self.goals, self.raw, self.rays, self.eow_k,
                    self.trig)  # fmt: skip
        readout_batch(self.raw, draws, k.encoding, self.out, self.eow_k, self.codes, self.keys,
                      self.flags)  # fmt: skip
        return self.keys, self.flags

    def sense_one(self, r: int, rng: np.random.Generator) -> tuple[int, bool, bool]:
        """Robot ``r`` alone (after a reset or a rescue), noise from ``rng``."""
        k = self.k
        x, y, h = self.world.pose(r)
        buffers = (self.raw[r], self.rays[r], self.eow_k[r], self.trig[r], k.ray_cos, k.decoy)
        sense_one(x, y, h, self.geometry, self.goals[r], k.plates, buffers)
        draws = self.suite.draw_noise(rng, k.n_raw)
        return readout(self.raw[r], draws, k.encoding, self.out[r], self.eow_k[r], self.codes[r])


class _Episode:
    """What Python keeps of one robot's running episode (counters live in arrays)."""

    __slots__ = ("epsilon", "goal", "rescued", "rng", "start")

    def __init__(self, start: int, rng: np.random.Generator, epsilon: float, goal: str) -> None:
        self.start = start
        self.rng = rng
        self.epsilon = epsilon
        self.goal = goal
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
    save_seconds: float | None = None,
) -> TrainResult:
    """Train ``robots`` robots for ``episodes`` more episodes into one table (module doc);
    ``save_seconds``: also save when that many seconds passed since the last save."""
    run = _Run(env, store, episodes, seed, log_path, robots, save_every, discard_unfinished)
    run.files.save_seconds = save_seconds
    return run.run(discard_unfinished, report, report_every)


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
        journal: bool = False,
    ) -> None:
        cfg = env.config
        if realism_on(cfg.realism):
            raise KoolioError(
                "--robots: the many-robot loop runs the ideal world only (its compiled tick "
                "has no realism models) and this configuration turns realism on: use --robots 1"
            )
        mem = cfg.sensors.memory
        if mem.goal_camera or mem.eow_camera or mem.previous_action:
            raise ConfigError(
                located(
                    f"--robots {robots}",
                    "sensors.memory",
                    "the many-robot loop has no memory in its state yet (use --robots 1)",
                )
            )
        if cfg.learner.algorithm != "q":
            raise ConfigError(
                located(
                    f"--robots {robots}",
                    "learner.algorithm",
                    f"{cfg.learner.algorithm} learns with one robot only: the compiled "
                    "many-robot loop (qkernel) has one-step Q only (use --robots 1)",
                )
            )
        self.env, self.cfg = env, cfg
        self.files = RunFiles.open(env, store, log_path, "koolio-pm train")
        self.table = self.files.table
        self.shared = SharedTable(self.table)
        self.files.save_every = max(1, save_every if save_every is not None else robots)
        self.files.before_save = self.shared.sync
        self.first = self.files.first
        self.budget = episodes
        self.seed = seed
        self.n = robots
        self.world = World.from_arena(env.arena, cfg.robot.radius, robots)
        self.copy_walls = np.stack([wall_array(self.world, k) for k in range(robots)])
        """Every robot's copy of the walls (``move_all``)."""
        self.offsets = np.asarray(self.world.offsets, dtype=np.float64)
        self.copy_xy = np.array([self.world.copy_position(k) for k in range(robots)])
        """Every robot's body position in its copy (the compiled moves keep it; the pymunk
        bodies are set from it before a rescue and at the end)."""
        self.motion = (float(env.move_distance), float(env.turn_arc), float(cfg.robot.radius))
        self.fleet = Fleet(env, self.world)
        self.progress = Progress()
        self.results: list[EpisodeResult] = []
        self.tick_rng = np.random.default_rng([seed, robots, 2])
        self.started = 0
        self.finished = 0
        self.eps: list[_Episode | None] = [None] * robots
        # Per robot, for the compiled loop (qkernel): state key, activity, epsilon,
        # this episode's steps, bumps, return, and the last step's event code.
        self.state = np.zeros(robots, np.int64)
        self.active = np.zeros(robots, np.bool_)
        self.epsilon = np.zeros(robots)
        self.steps = np.zeros(robots, np.int64)
        self.bumps = np.zeros(robots, np.int64)
        self.total = np.zeros(robots)
        self.event = np.zeros(robots, np.int64)
        self.actions = np.zeros(robots, np.int64)
        self.xy = np.zeros((robots, 2))
        """Every robot's position as of its last move, reset or rescue."""
        self.reward = reward_array(cfg.rewards)
        rescue = cfg.rescue
        self.rescue_after = rescue.max_steps_before_rescue if rescue.auto_rescue_toggle else -1
        self.zones = zone_arrays(env.zones)
        cap = cfg.episode.max_steps
        self.journal = new_journal(robots, (cap + 1 if cap > 0 else 1024) if journal else 0)
        """Every robot's writes in its running episode (:func:`qkernel.update_logged`)."""

    # -- episodes ---------------------------------------------------------------------
    def _start(self, r: int) -> None:
        """Start episode number ``first + started`` on robot ``r`` (or idle it)."""
        if self.started >= self.budget:
            self.eps[r] = None
            self.active[r] = False
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
        self.xy[r] = world.pose(r)[:2]
        self.copy_xy[r] = world.copy_position(r)
        self.state[r] = self.fleet.sense_one(r, rng)[0]
        self.active[r] = True
        self.epsilon[r] = ep.epsilon
        self.steps[r] = self.bumps[r] = 0
        self.total[r] = 0.0
        self.journal[2][r] = 0
        self.eps[r] = ep

    def _finish(self, r: int, outcome: str) -> None:
        ep = self.eps[r]
        assert ep is not None
        e = self.first + self.finished
        self.finished += 1
        res = EpisodeResult(
            e,
            float(self.total[r]),
            int(self.steps[r]),
            int(self.bumps[r]),
            outcome,
            ep.rescued,
            ep.epsilon,
            ep.goal,
        )
        self.files.finished(res, save=self.finished == self.budget)
        self.results.append(res)
        self.progress.add(res)
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
            with SafeInterrupt() as guard:
                try:
                    for r in range(self.n):
                        self._start(r)
                    while self.finished < self.budget:
                        guard.check()
                        self._tick()
                        now = time.perf_counter()
                        if report and now - last_report >= report_every:
                            eps = [ep.epsilon for ep in self.eps if ep is not None]
                            report(self._line(eps[0] if eps else 0.0))
                            last_report = now
                    if report:
                        last = self.first + self.budget - 1
                        report(self._line(self.cfg.learner.epsilon.at(last)))
                except KeyboardInterrupt:
                    interrupted = True
                    self._interrupt(discard_unfinished, report)
        finally:
            self.files.close()
            for k in range(self.n):  # the pymunk bodies where the compiled moves left them
                self.world.set_copy_position(k, *self.copy_xy[k])
        self.shared.sync()
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
        running = [r for r, ep in enumerate(self.eps) if ep is not None]
        if discard:
            self._discard(running)
            if report:
                report(
                    f"interrupted: {len(running)} unfinished episodes discarded, "
                    f"{self.finished} finished ones kept (Exit Without Save)"
                )
            return
        for k, r in enumerate(running):
            ep = self.eps[r]
            assert ep is not None
            res = EpisodeResult(
                self.first + self.finished + k,
                float(self.total[r]),
                int(self.steps[r]),
                int(self.bumps[r]),
                INTERRUPTED,
                ep.rescued,
                ep.epsilon,
                ep.goal,
            )
            self.files.log.write(res)
            self.results.append(res)
        self.files.save()
        if report:
            report("interrupted: unfinished episodes folded into the Q-table and saved (Exit)")

    def _discard(self, running: list[int]) -> None:
        """Exit Without Save: take back the unfinished episodes' writes, save the rest."""
        jn = self.journal[2]
        if any(int(jn[r]) > self.journal[0].shape[1] for r in running):  # pragma: no cover
            raise AssertionError("journal overflow")  # _tick grows it before it can happen
        dropped = undo_writes(self.shared, self.journal, running)
        self.shared.sync()
        for key in dropped:
            self.table.rows.pop(key, None)
        self.files.save()

    def _tick(self) -> None:
        n, rng, sh = self.n, self.tick_rng, self.shared
        self._grow_journal()
        explore = rng.random(n)
        random_action = rng.integers(self.table.layout.n_actions, size=n)
        tie = rng.random(n)
        draws = self.fleet.suite.draw_noise(rng, n * self.fleet.k.n_raw).reshape(n, -1)
        sh.reserve(2 * n)
        choose(sh.index, sh.q, self.state, self.active, self.epsilon, explore, random_action,
               tie, self.actions)  # fmt: skip
        world = self.world
        headings = np.array(world.heading)
        move_all(self.actions, self.copy_xy, headings, self.copy_walls, self.offsets,
                 self.motion, self.xy)  # fmt: skip
        world.heading[:] = headings.tolist()
        xy = self.xy
        keys, flags = self.fleet.sense_all(xy, headings, draws)
        lc = self.cfg.learner
        tick = (self.active, self.actions, self.state, keys, flags[:, 0], flags[:, 1], xy)
        rules = (self.reward, lc.alpha, lc.gamma, self.zones, self.rescue_after,
                 self.cfg.episode.max_steps)  # fmt: skip
        counters = (self.steps, self.bumps, self.total, self.event)
        table = sh.args()
        r = 0
        while r < n:
            r, why = learn(r, tick, rules, counters, self.journal, sh.index, table)
            if why == RESCUE_DRAW:
                self._rescue_step(r, int(keys[r]))
            elif why == TERMINAL:
                self._finish(r, EVENTS[self.event[r]])
            elif why == AT_CAP:
                self._finish(r, TRUNCATED)
            r += 1

    def _grow_journal(self) -> None:
        """Room for one more entry per robot (one update per robot per tick)."""
        jint, jf, jn, seq = self.journal
        cap = jint.shape[1]
        if cap == 0 or int(jn.max()) < cap:
            return
        grown = new_journal(self.n, 2 * cap)
        grown[0][:, :cap] = jint
        grown[1][:, :cap] = jf
        self.journal = (grown[0], grown[1], jn, seq)

    def _rescue_step(self, r: int, nxt: int) -> None:
        """Robot ``r`` bumped past ``max_steps_before_rescue``: its update (from the state
        the action led to), then the rescue draw, maybe a rescue (new reading), and the
        step cap, in the paper's order (§5.4.8) as in ``KoolioEnv``."""
        ep = self.eps[r]
        assert ep is not None
        lc = self.cfg.learner
        code = int(self.event[r])
        update_logged(self.shared.index, self.shared.args(), lc.alpha, lc.gamma, int(self.state[r]),
                      int(self.actions[r]), float(self.reward[code]), nxt, False, r,
                      self.journal)  # fmt: skip
        if ep.rng.random() < self.cfg.rescue.rescue_chance:
            self.world.set_copy_position(r, *self.copy_xy[r])
            rescue_robot(self.world, r, self.cfg.rescue, self.env.move_distance, ep.rng)
            self.xy[r] = self.world.pose(r)[:2]
            self.copy_xy[r] = self.world.copy_position(r)
            nxt = self.fleet.sense_one(r, ep.rng)[0]
            ep.rescued = True
        self.state[r] = nxt
        cap = self.cfg.episode.max_steps
        if cap > 0 and self.steps[r] >= cap:
            self._finish(r, TRUNCATED)
