"""Many robots learning into one shared Q-table (``koolio-pm train --robots N``).

All ``N`` robots live in one pymunk :class:`~koolio_pymunk.world.physics.World` (one space, one
non-colliding shape group: each robot is alone in its own copy of the arena) and run
their own episodes of the single-robot task (same actions, sensors, rewards, rescue, step
cap). Their experience goes into one :class:`~koolio_pymunk.learning.qtable.QTable`.

**A tick** (every robot takes one step):

1. every active robot chooses an action epsilon-greedily from the table as it stands
   (:func:`fleet_kernel.choose`);
2. all robots act (:func:`fleet_kernel.move_all`: turns, and each Forward or Reverse a
   :func:`~koolio_pymunk.world.swept_move.sweep` against the robot's own copy of the
   walls, in its copy's coordinates, as the pymunk world moves it, bit for bit); the
   pymunk bodies are set from those positions at the end of the run;
3. all robots are sensed (:func:`ray_kernel.sense_batch`, :func:`encoding_kernel.readout_batch`:
   robots x rays x walls; always the compiled kernel, which reads what the pymunk
   reference reads);
4. **in robot index order**, each robot's step is judged (reward, end of episode),
   its Table 11 update applied to the shared table (so robot ``r`` bootstraps from values
   robots ``< r`` updated in the same tick), then rescued if auto rescue fires
   (``rescue_robot``'s moves in the robot's copy of the arena); a finished episode is
   logged, and the robot starts a new one if the budget allows.

Ticks run compiled, many in one call (:func:`fleet_tick.run_ticks`, about :data:`CHUNK`
robot-steps); Python prepares episode starts ahead and logs the finished episodes, the
call stopping at the finish that makes a save due (mid-tick if need be) so that every
save holds the table as it stood at that finish.

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

**Resuming** starts N new episodes from the saved table and a new run generator: a
resumed run is seeded (the same commands give the same bytes) but is not the
uninterrupted run's continuation, whose robots were mid-episode at the save
(``docs/robustness.md``; one robot resumes exactly).

**Saving.** The table is written (file + backup, as :func:`training.train` does) each
time ``save_every`` more episodes have finished (default ``N``: about once per round of
episodes rather than at every episode end, because N robots finish episodes N times as
often and every save is an fsynced file write), and always at the end and on Ctrl-C.
``save_every=1`` is the paper's cadence. Each finished episode's row is logged when it
finishes, so after a SIGKILL the log may be ahead of the table by up to ``save_every - 1``
rows: resuming removes them (:mod:`koolio_pymunk.store.episode_log`).

**Ctrl-C** (taken between two compiled calls, so between ticks) folds every unfinished
episode into the table and logs it ``interrupted``, numbered ``first + finished``,
``+ 1``, ... in robot order (the numbers those episodes get when training resumes). With
``discard_unfinished`` only the unfinished episodes are discarded: every finished episode
stays in the table and the log. The robots share one table, so an unfinished episode's
writes are interleaved with those of episodes that finished; each robot journals its own
writes (:func:`fleet_kernel.undo_writes`), and the discard takes back, newest first, every
write of an unfinished episode that no other robot has written over since (and drops the
rows only they created), then saves.

**Algorithm.** One-step Q only (``learner.algorithm: q``): Q(lambda) and Dyna-Q
(``docs/learning.md``) are refused with a one-line error, since the compiled loop has
neither per-robot traces nor a model.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..sensing.ray_kernel import new_trig
from ..sensing.sensor_arrays import GEOMETRY, bundle
from ..store.errors import ConfigError, KoolioError, located
from ..store.interrupts import SafeInterrupt
from ..store.realism_config import realism_on
from ..task.env import KoolioEnv
from ..world.physics import TWO_PI, World
from ..world.segment_query import wall_array
from .episode_kernel import TRUNCATED_CODE
from .episodes import INTERRUPTED, TRUNCATED, EpisodeResult, env_seed
from .fleet_kernel import (
    EVENTS,
    SharedTable,
    new_journal,
    reward_array,
    undo_writes,
    zone_arrays,
)
from .fleet_tick import (
    C_BUDGET,
    C_CURSOR,
    C_PREPARED,
    C_RECORDS,
    C_STARTED,
    C_STOP_AT,
    C_TAIL,
    C_TICKS,
    N_CTL,
    NEED_ROOM,
    R_BUMPS,
    R_OUTCOME,
    R_RESCUED,
    R_START,
    R_STEPS,
    TICKS_DONE,
    generator_list,
    run_ticks,
    set_generator,
)
from .qtable import QTableStore
from .training import Progress, RunFiles, TrainResult

#: Robot-steps per compiled call at most (Python looks for a Ctrl-C and reports between
#: calls): ``CHUNK // N`` ticks.
CHUNK = 4096


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

    def group(self) -> tuple:
        """:func:`fleet_tick.run_ticks`'s ``sensing`` group (the ideal world's reading:
        the realism group is there for its type only)."""
        k = self.k
        flags = np.array([0, int(k.gaussian), k.n_raw, 0], np.int64)
        return (self.geometry, k.encoding, self.goals, self.raw, self.rays, self.eow_k,
                self.trig, self.out, self.codes, self.keys, self.flags, k.plates, k.ray_cos,
                k.decoy, k.realism, k.noise, flags)  # fmt: skip


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


def _generators(n: int):
    """A typed list of ``n`` distinct generators (their states are set before use)."""
    out = generator_list(np.random.default_rng(0), n)
    for i in range(n):
        set_generator(out, i, np.random.Generator(np.random.PCG64(i)))
    return out


def check_fleet(env: KoolioEnv, robots: int) -> None:
    """Refuse, in one line, what the many-robot loop does not run: realism models, a
    memory in the state, a learner other than one-step Q, the no-undo rule (``train``
    asks before it prints or writes anything)."""
    cfg = env.config
    if realism_on(cfg.realism):
        raise KoolioError(
            "--robots: the many-robot loop runs the ideal world only (its compiled tick "
            "has no realism models) and this configuration turns realism on: use --robots 1"
        )
    if cfg.sensors.memory.on:
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
                "many-robot loop (fleet_kernel) has one-step Q only (use --robots 1)",
            )
        )
    if cfg.learner.no_undo:
        raise ConfigError(
            located(
                f"--robots {robots}",
                "learner.no_undo",
                "the many-robot loop chooses among all five actions: it has no no-undo "
                "rule yet (use --robots 1)",
            )
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
        journal: bool = False,
    ) -> None:
        cfg = env.config
        check_fleet(env, robots)
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
        copy_walls = np.stack([wall_array(self.world, k) for k in range(robots)])
        offsets = np.asarray(self.world.offsets, dtype=np.float64)
        self.copy_xy = np.array([self.world.copy_position(k) for k in range(robots)])
        """Every robot's body position in its copy (the compiled moves keep it; the pymunk
        bodies are set from it at the end)."""
        self.headings = np.array(self.world.heading, dtype=np.float64)
        self.xy = np.zeros((robots, 2))
        """Every robot's position as of its last move, start or rescue."""
        motion = (float(env.move_distance), float(env.turn_arc), float(cfg.robot.radius))
        self.motion = (self.copy_xy, self.headings, copy_walls, offsets, motion, self.xy)
        self.fleet = Fleet(env, self.world)
        self.progress = Progress()
        self.results: list[EpisodeResult] = []
        self.finished = 0
        # Per robot, for the compiled ticks (fleet_tick): state key, activity, epsilon,
        # action, rescued, start number; this episode's steps, bumps, return, last event.
        self.state = np.zeros(robots, np.int64)
        self.active = np.zeros(robots, np.bool_)
        self.epsilon = np.zeros(robots)
        self.rescued = np.zeros(robots, np.bool_)
        self.start_of = np.zeros(robots, np.int64)
        self.robots = (self.state, self.active, self.epsilon, np.zeros(robots, np.int64),
                       self.rescued, self.start_of)  # fmt: skip
        self.steps = np.zeros(robots, np.int64)
        self.bumps = np.zeros(robots, np.int64)
        self.total = np.zeros(robots)
        self.counters = (self.steps, self.bumps, self.total, np.zeros(robots, np.int64))
        lc, rescue = cfg.learner, cfg.rescue
        rescue_after = rescue.max_steps_before_rescue if rescue.auto_rescue_toggle else -1
        self.rules = (reward_array(cfg.rewards), float(lc.alpha), float(lc.gamma),
                      zone_arrays(env.zones), int(rescue_after),
                      int(cfg.episode.max_steps))  # fmt: skip
        self.rescue = (float(rescue.rescue_chance), int(rescue.rescue_max_backup))
        cap = cfg.episode.max_steps
        self.journal = new_journal(robots, (cap + 1 if cap > 0 else 1024) if journal else 0)
        """Every robot's writes in its running episode (:func:`fleet_kernel.update_logged`)."""
        self.tick_rng = np.random.default_rng([seed, robots, 2])
        self._starts(robots)

    # -- episodes ---------------------------------------------------------------------
    def _starts(self, robots: int) -> None:
        """The slots of prepared starts (:mod:`.fleet_tick`), the records of finished
        episodes, and every robot waiting for its first start."""
        slots = max(2 * robots, 16)
        self.pool = _generators(slots)
        self.gens = _generators(robots)
        self.slot_goal = np.zeros((slots, 2))
        self.slot_heading = np.zeros(slots)
        self.slot_epsilon = np.zeros(slots)
        start = np.array(self.env.world_arena.start.at, dtype=np.float64)
        self.starts = (self.slot_goal, self.slot_heading, self.slot_epsilon, start)
        self.prepared: dict[int, tuple[str, float]] = {}
        """The goal and epsilon of every start prepared and not yet finished, by start
        number."""
        capacity = max(64, robots)
        self.records = (np.zeros((capacity, 6), np.int64), np.zeros(capacity))
        self.ctl = np.zeros(N_CTL, np.int64)
        self.ctl[C_CURSOR] = robots
        self.ctl[C_BUDGET] = self.budget
        self.pending = np.arange(robots, dtype=np.int64)
        self.ctl[C_TAIL] = robots

    def _prepare(self) -> None:
        """Prepare the starts the next call may make: the episode's generator
        (``default_rng(episode_seeds(seed, k)[0])``'s state), its random goal and start
        heading drawn from it, its epsilon."""
        ctl, env = self.ctl, self.env
        slots = len(self.pool)
        names = env.world_arena.goal_names()
        start = env.world_arena.start
        until = min(int(ctl[C_STARTED]) + slots, self.budget)
        for s in range(int(ctl[C_PREPARED]), until):
            k = self.first + s
            slot = s % slots
            rng = self.pool[slot]  # a finished episode's generator, or one not used yet
            rng.bit_generator.state = np.random.PCG64(env_seed(self.seed, k)).state
            goal = names[int(rng.integers(len(names)))] if env.random_goal else env.goal_name
            heading = (
                np.radians(start.heading_deg)
                if start.heading_deg is not None
                else float(rng.uniform(0.0, 2.0 * np.pi))
            )
            epsilon = self.cfg.learner.epsilon.at(k)
            self.slot_goal[slot] = env.world_arena.goal(goal).at
            self.slot_heading[slot] = float(heading) % TWO_PI  # World.place
            self.slot_epsilon[slot] = epsilon
            self.prepared[s] = (goal, epsilon)
        ctl[C_PREPARED] = max(until, int(ctl[C_PREPARED]))

    def _record(self) -> None:
        """Log the episodes the last call finished (completion order), saving the table
        when due (the call stopped at the finish that makes a save due)."""
        ints, totals = self.records
        n = int(self.ctl[C_RECORDS])
        self.ctl[C_RECORDS] = 0
        outcomes = ints[:n, R_OUTCOME].tolist()
        for k, (start, steps, bumps, rescued) in enumerate(
            ints[:n, [R_START, R_STEPS, R_BUMPS, R_RESCUED]].tolist()
        ):
            code = outcomes[k]
            goal, epsilon = self.prepared.pop(start)
            res = EpisodeResult(
                self.first + self.finished,
                float(totals[k]),
                steps,
                bumps,
                TRUNCATED if code == TRUNCATED_CODE else EVENTS[code],
                bool(rescued),
                epsilon,
                goal,
            )
            self.finished += 1
            self.files.finished(res, save=self.finished == self.budget)
            self.results.append(res)
            self.progress.add(res)

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
                    while self.finished < self.budget:
                        guard.check()
                        self._ticks()
                        now = time.perf_counter()
                        if report and now - last_report >= report_every:
                            running = np.flatnonzero(self.active)
                            eps = float(self.epsilon[running[0]]) if running.size else 0.0
                            report(self._line(eps))
                            last_report = now
                    if report:
                        last = self.first + self.budget - 1
                        report(self._line(self.cfg.learner.epsilon.at(last)))
                except KeyboardInterrupt:
                    interrupted = True
                    self._interrupt(discard_unfinished, report)
        finally:
            self.files.close()
            world = self.world  # the pymunk bodies where the compiled moves left them
            for k in range(self.n):
                world.set_copy_position(k, *self.copy_xy[k])
            world.heading[:] = self.headings.tolist()
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
        running = np.flatnonzero(self.active).tolist()
        if discard:
            self._discard(running)
            if report:
                report(
                    f"interrupted: {len(running)} unfinished episodes discarded, "
                    f"{self.finished} finished ones kept (Exit Without Save)"
                )
            return
        for k, r in enumerate(running):
            goal, epsilon = self.prepared[int(self.start_of[r])]
            res = EpisodeResult(
                self.first + self.finished + k,
                float(self.total[r]),
                int(self.steps[r]),
                int(self.bumps[r]),
                INTERRUPTED,
                bool(self.rescued[r]),
                epsilon,
                goal,
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
            raise AssertionError("journal overflow")  # _ticks grows it before it can happen
        dropped = undo_writes(self.shared, self.journal, running)
        self.shared.sync()
        for key in dropped:
            self.table.rows.pop(key, None)
        self.files.save()

    def _ticks(self) -> None:
        """Compiled ticks (:func:`fleet_tick.run_ticks`), about :data:`CHUNK` robot-steps,
        ending between two ticks (or at the run's last finished episode): each stop on the
        way for Python (finished episodes, starts to prepare, room) is served here."""
        ctl, sh = self.ctl, self.shared
        ctl[C_TICKS] = 0
        ticks = max(1, CHUNK // self.n)
        capacity = self.records[0].shape[0]
        while self.finished < self.budget:
            self._prepare()
            until_save = self.files.save_every - self.files.unsaved
            if self.files.save_seconds is not None:
                until_save = 1  # the clock is looked at every finished episode
            ctl[C_STOP_AT] = max(1, min(until_save, self.budget - self.finished, capacity))
            why = run_ticks(ticks, self.tick_rng, self.gens, self.pool, ctl, self.pending,
                            self.fleet.group(), self.motion, self.robots, self.counters,
                            self.rules, self.rescue, self.starts, self.records, self.journal,
                            sh.index, sh.args())  # fmt: skip
            self._record()
            if why == NEED_ROOM:
                sh.reserve(2 * self.n)
                self._grow_journal()
            elif why == TICKS_DONE:
                return

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
