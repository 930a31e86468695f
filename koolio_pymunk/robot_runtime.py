"""Koolio robot runtime: run and keep learning an exported policy on the real robot.

This one file is all the robot's computer needs: it uses **only the Python standard
library** (Python 3.10 or newer) and imports nothing from ``koolio_pymunk``, so it can be copied
onto the robot on its own. It reads the policy file written by ``koolio-pm export``
(format ``koolio-policy``, version 1; every field is described in
:func:`validate_document` and in ``docs/handoff.md``), and:

* encodes raw sensor readings into the state exactly as the simulator does (Tables 6, 7
  and 12 of the paper, with the thresholds stored in the file): :meth:`Policy.encode`;
* chooses actions, greedy or epsilon-greedy: :meth:`Policy.greedy`, :meth:`Policy.act`;
* applies the Table 11 update from real transitions: :meth:`Policy.update`, with the
  same floating-point operations as the simulator's learner; or, when the file's
  ``learner.algorithm`` says so, Watkins's Q(lambda) (:class:`Traces`) or Dyna-Q
  (:class:`Model`), the same computations as the simulator's ``qlambda.py`` and
  ``dyna.py`` given the same transitions and random draws;
* saves the table atomically in the same format (temporary file, fsync, rename; the
  previous file is kept as ``<file>.bak``), so ``koolio-pm train --init-qtable`` can
  continue learning in simulation from what the robot learned;
* writes the same per-episode CSV log as ``koolio-pm train``
  (``episode,reward,steps,bumps,outcome,rescued,epsilon,goal``), so ``koolio-pm plot``
  draws real-robot learning curves too: :class:`EpisodeLog`.

A learning loop on the robot (``robot.*`` stands for the robot's own driver code)::

    from robot_runtime import Policy, RobotLearner

    policy = Policy.load("policy.json")
    learner = RobotLearner(policy, save_path="policy.json", log_path="robot.csv",
                           epsilon=0.05, seed=1, goal="302")
    sonar, goal_cam, eow_cam = robot.read()          # inches from the robot's edge
    learner.begin(policy.encode(sonar, goal_cam, eow_cam))
    while True:
        action = learner.choose()                    # 0 Stop .. 4 Reverse
        robot.perform(action)
        sonar, goal_cam, eow_cam = robot.read()
        event, reward, terminal = policy.judge(action, sonar, goal_cam,
                                               end_of_world=robot.off_the_end())
        learner.step(action, reward, policy.encode(sonar, goal_cam, eow_cam), terminal,
                     bump=policy.bump(sonar))
        if terminal:
            learner.end(event)                       # log row + atomic save
            break

Raw readings: ``sonar`` is one distance per sonar (inches from the robot's edge, in the
order of ``sensors.sonar_sensors_deg``); ``goal_cam`` and ``eow_cam`` are one distance per
camera to the goal's plate and to the nearest end-of-world marker, ``None`` (or
``float("inf")``) when the camera does not see one. A policy learned with several pings
per sonar (``policy.encoder.sonar_pings`` > 1, ``sensors.sonar.pings`` in the simulator)
expects each sonar's reading to be the median of that many pings
(``Encoder.median([robot.ping(s) for _ in range(policy.encoder.sonar_pings)])``).

``python robot_runtime.py POLICY`` prints a summary of a policy file.
"""

from __future__ import annotations

import bisect
import contextlib
import csv
import io
import itertools
import json
import math
import os
import random
import shutil
import stat
import sys
from collections.abc import Callable, Sequence
from typing import Any

FORMAT = "koolio-policy"
VERSION = 1
#: Largest policy file read (a table of a million states is about 300 MiB of JSON).
MAX_POLICY_BYTES = 1 << 30
#: Learning algorithms (``learner.algorithm``; absent means ``q``) and their parameters.
ALGORITHMS = {"q": (), "qlambda": ("trace_decay", "trace_cutoff"), "dyna": ("planning_steps",)}
#: By action index: the action that undoes it (-1: none), for the no-undo rule of a policy
#: whose ``learner.no_undo`` is true (the simulator's ``task.action_rules.UNDO``).
UNDO = (-1, 2, 1, 4, 3)
#: Most simulated updates per real step (``learner.planning_steps``; the simulator's
#: configuration has the same limit): 1e12 made every step last for days.
MAX_PLANNING_STEPS = 10_000
#: The paper's five actions; an action's index is the low bits of the keyword.
ACTION_NAMES = ("Stop", "RotateLeft", "RotateRight", "Forward", "Reverse")
STOP = 0
#: Columns of the per-episode log: ``koolio-pm train`` writes the same (it reads them here).
LOG_FIELDS = ("episode", "reward", "steps", "bumps", "outcome", "rescued", "epsilon", "goal")
#: Events of :meth:`Policy.judge`, in the paper's order of priority (first wins).
EVENTS = ("goal", "end_of_world", "bump", "stop", "reverse", "turn", "forward")
_ACTION_EVENTS = ("stop", "turn", "turn", "forward", "reverse")


class PolicyError(ValueError):
    """A malformed policy file or a bad argument: one line, ``source: item: problem``."""


def _err(source: str, item: str, problem: str) -> PolicyError:
    return PolicyError(f"{source}: {item}: {problem}" if item else f"{source}: {problem}")


def field_bits(levels: int) -> int:
    """Bits of a state field with ``levels`` codes: ``max(1, ceil(log2(levels)))``.

    >>> [field_bits(n) for n in (1, 2, 3, 4, 5, 8, 9)]
    [1, 1, 2, 2, 3, 3, 4]
    """
    return max(1, (int(levels) - 1).bit_length())


class Layout:
    """The Table 12 keyword: state fields most significant first, the action lowest.

    >>> lay = Layout([("A", 3), ("B", 4)], n_actions=5)
    >>> lay.shifts, lay.action_bits, lay.keyword((2, 1), 3)
    ((5, 3), 3, 75)
    >>> lay.decode(75)
    ((2, 1), 3)
    """

    def __init__(self, fields: Sequence[tuple[str, int]], n_actions: int) -> None:
        self.names = tuple(str(n) for n, _ in fields)
        self.levels = tuple(int(lv) for _, lv in fields)
        self.n_actions = int(n_actions)
        self.bits = tuple(field_bits(lv) for lv in self.levels)
        self.action_bits = field_bits(self.n_actions)
        shifts, pos = [], self.action_bits
        for b in reversed(self.bits):
            shifts.append(pos)
            pos += b
        self.shifts = tuple(reversed(shifts))
        self.total_bits = pos

    def state_key(self, codes: Sequence[int]) -> int:
        """The keyword without its action bits (``keyword >> action_bits``)."""
        key = 0
        for code, b in zip(codes, self.bits):
            key = (key << b) | int(code)
        return key

    def keyword(self, codes: Sequence[int], action: int) -> int:
        return (self.state_key(codes) << self.action_bits) | int(action)

    def decode(self, keyword: int) -> tuple[tuple[int, ...], int]:
        """``(codes, action)`` of a keyword."""
        action = keyword & ((1 << self.action_bits) - 1)
        key = keyword >> self.action_bits
        codes = []
        for b in reversed(self.bits):
            codes.append(key & ((1 << b) - 1))
            key >>= b
        return tuple(reversed(codes)), action

    def to_json(self) -> dict[str, Any]:
        return {
            "fields": [
                {"name": n, "levels": lv, "bits": b, "shift": s}
                for n, lv, b, s in zip(self.names, self.levels, self.bits, self.shifts)
            ],
            "action_bits": self.action_bits,
            "n_actions": self.n_actions,
            "total_bits": self.total_bits,
        }


def compass_code(units: float) -> int:
    """Compass units 0..255 -> East 0, North 1, West 2, South 3 (boundaries NE/NW/SW/SE).

    >>> [compass_code(u) for u in (0, 31.9, 32.1, 100, 159, 160, 224.1, 255)]
    [0, 0, 1, 2, 2, 3, 0, 0]
    """
    deg = (units / 256.0 * 360.0) % 360.0
    return int(((deg + 45.0) % 360.0) // 90.0)


class Encoder:
    """Raw readings -> state codes, in keyword order: goal cameras, end-of-world cameras,
    sonar groups (then the compass when it is in the state).

    A code is the number of thresholds at or below the reading (``bisect_right``): with
    the paper's sonar thresholds ``[6, 24, 60]``, 5.9 -> 0 Bump, 6 -> 1 Close, 59 -> 2
    Medium, 60 -> 3 Far. A sonar group's reading is the mean of its sonars. A camera that
    sees nothing (``None``, infinity) or reads beyond ``max_camera_view`` encodes Far.
    """

    def __init__(self, enc: dict[str, Any]) -> None:
        self.sonar_thresholds = [float(t) for t in enc["thresholds"]["sonar"]]
        self.camera_thresholds = [float(t) for t in enc["thresholds"]["camera"]]
        self.sonar_groups = [[int(i) for i in g] for g in enc["sonar_groups"]]
        self.n_sonar = int(enc["n_sonar"])
        self.n_camera = int(enc["n_camera"])
        self.max_camera_view = float(enc["max_camera_view"])
        self.compass_in_state = bool(enc["compass_in_state"])
        self.sonar_pings = int(enc.get("sonar_pings", 1))
        """Pings per sonar and reading the policy was learned with (``encoding.sonar_pings``,
        1 when absent): the driver pings each sonar this many times and passes the median
        (:meth:`median`) as the sonar's reading."""
        mem = enc.get("memory") or {}
        self.memory = {k: mem.get(k, v) for k, v in NO_MEMORY.items()}
        """The memory's settings (``encoding.memory``; all off when absent)."""
        if self.memory["goal_bearing"]:
            self.memory["turn_deg"] = float(mem["turn_deg"])
            self.memory["camera_deg"] = [float(d) for d in mem["camera_deg"]]

    def fields(self) -> list[tuple[str, int]]:
        """``(name, levels)`` of the state fields: the sensors', then the memory's."""
        cam = len(self.camera_thresholds) + 1
        son = len(self.sonar_thresholds) + 1
        out = [(f"GoalCam{c}", cam) for c in range(self.n_camera)]
        out += [(f"EoWCam{c}", cam) for c in range(self.n_camera)]
        out += [("Sonar" + "-".join(str(i) for i in g), son) for g in self.sonar_groups]
        if self.compass_in_state:
            out.append(("Compass", 4))
        mem = self.memory
        out += [("GoalMemory", self.n_camera + 1)] if mem["goal_camera"] else []
        out += [("EoWMemory", self.n_camera + 1)] if mem["eow_camera"] else []
        out += [("LastAction", len(ACTION_NAMES) + 1)] if mem["previous_action"] else []
        out += [("GoalBearing", len(BEARINGS))] if mem["goal_bearing"] else []
        return out

    @property
    def remembers(self) -> bool:
        """The state holds memory fields (:class:`Memory`)."""
        m = self.memory
        return bool(
            m["goal_camera"] or m["eow_camera"] or m["previous_action"] or m["goal_bearing"]
        )

    def encode(
        self,
        sonar: Sequence[float],
        goal_cam: Sequence[float | None],
        eow_cam: Sequence[float | None],
        compass: float | None = None,
    ) -> tuple[int, ...]:
        """The state codes of one set of raw readings (inches from the robot's edge)."""
        sonar = _numbers(sonar, self.n_sonar, "sonar", allow_none=False)
        goal = _numbers(goal_cam, self.n_camera, "goal_cam", allow_none=True)
        eow = _numbers(eow_cam, self.n_camera, "eow_cam", allow_none=True)
        codes = [self._camera(v) for v in goal] + [self._camera(v) for v in eow]
        for g in self.sonar_groups:
            total = 0.0
            for i in g:
                total += sonar[i]
            codes.append(bisect.bisect_right(self.sonar_thresholds, total / len(g)))
        if self.compass_in_state:
            if compass is None:
                raise PolicyError("compass: a reading is needed (the compass is in the state)")
            codes.append(compass_code(float(compass)))
        return tuple(codes)

    @staticmethod
    def median(pings: Sequence[float]) -> float:
        """The reading of one sonar from an odd number of pings: their median.

        >>> Encoder.median([40.2, 3.1, 118.0])
        40.2
        """
        values = sorted(float(v) for v in pings)
        if len(values) % 2 == 0:
            raise PolicyError(f"sonar: {len(values)} pings (the median needs an odd number)")
        return values[len(values) // 2]

    def _camera(self, v: float | None) -> int:
        if v is None or v > self.max_camera_view:
            return len(self.camera_thresholds)
        return bisect.bisect_right(self.camera_thresholds, v)

    def sees(self, v: float | None) -> bool:
        """A camera reading that saw its target (not nothing, within ``max_camera_view``)."""
        return v is not None and v <= self.max_camera_view

    def bump(self, sonar: Sequence[float]) -> bool:
        """Any single sonar reads Bump (below the first sonar threshold)."""
        return any(float(v) < self.sonar_thresholds[0] for v in sonar)

    def goal_close(self, goal_cam: Sequence[float | None]) -> bool:
        """The front camera (camera 0) reads the goal Close."""
        v = goal_cam[0]
        return v is not None and v <= self.max_camera_view and v < self.camera_thresholds[0]


def _numbers(values: Sequence[Any], n: int, name: str, allow_none: bool) -> list[Any]:
    vals = list(values)
    if len(vals) != n:
        raise PolicyError(f"{name}: expected {n} readings, got {len(vals)}")
    out: list[Any] = []
    for i, v in enumerate(vals):
        if v is None and allow_none:
            out.append(None)
            continue
        try:
            f = float(v)
        except (TypeError, ValueError):
            raise PolicyError(f"{name}[{i}]: not a number: {v!r}") from None
        if math.isnan(f):
            raise PolicyError(f"{name}[{i}]: not a number (NaN)")
        out.append(None if (allow_none and math.isinf(f)) else f)
    return out


#: ``encoding.memory`` of a policy whose state holds no memory.
NO_MEMORY: dict[str, Any] = {
    "goal_camera": False,
    "eow_camera": False,
    "forget_after": 0,
    "previous_action": False,
    "goal_bearing": False,
}
#: ``encoding.memory``'s keys when ``goal_bearing`` is on: the rotation's arc and the
#: cameras' angles, degrees (the bearing turns with the commanded turns).
BEARING_KEYS = ("turn_deg", "camera_deg")
#: ``GoalBearing``'s codes (the simulator's ``store.config.BEARINGS``).
BEARINGS = ("none", "ahead", "left", "behind", "right")


class Memory:
    """What the robot remembers in its state: the simulator's ``sensing.memory.Memory``,
    standard-library copy (the same fields, the same updates).

    ``GoalMemory`` / ``EoWMemory``: the camera that last saw the goal plate / an
    end-of-world marker (0: none; ``1 + camera``; the nearest reading when several see it,
    ties to the lower camera), forgotten after ``forget_after`` steps without a sighting
    (0: never); ``LastAction``: 0 at the start of an episode, then ``1 + action``;
    ``GoalBearing``: where the goal plate was last seen, turned with the commanded turns
    (:func:`bearing_code` of the millidegrees; 0: none, forgotten like the sightings). Call
    :meth:`reset` at the start of every episode; :meth:`Policy.encode` updates it with each
    reading (``action`` None after a reset or a rescue: sightings are recorded, nothing
    ages, the last action stays).
    """

    def __init__(self, encoder: Encoder) -> None:
        self.encoder = encoder
        mem = encoder.memory
        self.camera_mdeg = [millidegrees(d) for d in mem.get("camera_deg", [])]
        self.turn_mdeg = millidegrees(mem.get("turn_deg", 0.0))
        self.reset()

    def reset(self) -> None:
        """A new episode: nothing seen, no action yet."""
        self.goal = self.eow = self.action = self.bearing = 0
        self.goal_age = self.eow_age = self.bearing_age = self.bearing_mdeg = 0

    def update(self, goal: Sequence[Any], eow: Sequence[Any], action: int | None) -> None:
        """Remember one reading made after ``action``."""
        moved = action is not None
        seen = self._nearest(goal)
        self.goal, self.goal_age = self._sighting(seen, self.goal, self.goal_age, moved)
        self.eow, self.eow_age = self._sighting(self._nearest(eow), self.eow, self.eow_age, moved)
        if self.encoder.memory["goal_bearing"]:
            if seen:
                self.bearing_mdeg = self.camera_mdeg[seen - 1]
            elif moved and self.bearing:
                self.bearing_mdeg = turned(self.bearing_mdeg, int(action), self.turn_mdeg)  # type: ignore[arg-type]
            held, self.bearing_age = self._sighting(seen, self.bearing, self.bearing_age, moved)
            self.bearing = bearing_code(self.bearing_mdeg) if held else 0
        if moved:
            self.action = 1 + int(action)  # type: ignore[arg-type]

    def _nearest(self, readings: Sequence[Any]) -> int:
        best, best_d = 0, math.inf
        for c, d in enumerate(readings):
            if self.encoder.sees(d) and d < best_d:
                best, best_d = 1 + c, d
        return best

    def _sighting(self, seen: int, held: int, age: int, moved: bool) -> tuple:
        if seen:
            return seen, 0
        if not moved or not held:
            return held, age
        age += 1
        k = int(self.encoder.memory["forget_after"])
        return (0, 0) if k > 0 and age >= k else (held, age)

    def codes(self) -> tuple[int, ...]:
        """The memory's codes, in keyword order (only the fields that are on)."""
        mem = self.encoder.memory
        out = [self.goal] if mem["goal_camera"] else []
        out += [self.eow] if mem["eow_camera"] else []
        out += [self.action] if mem["previous_action"] else []
        out += [self.bearing] if mem["goal_bearing"] else []
        return tuple(out)


def millidegrees(deg: float) -> int:
    """An angle in whole millidegrees (the bearing's unit in every copy)."""
    return round(deg * 1000.0)


def turned(bearing: int, action: int, turn: int) -> int:
    """``bearing`` (millidegrees, left positive) after ``action`` (RotateLeft subtracts
    ``turn``, RotateRight adds it), in [-180, 180) degrees.

    >>> turned(90_000, 1, 30_000), turned(170_000, 2, 30_000)
    (60000, -160000)
    """
    if action == ACTION_NAMES.index("RotateLeft"):
        bearing -= turn
    elif action == ACTION_NAMES.index("RotateRight"):
        bearing += turn
    return (bearing + 180_000) % 360_000 - 180_000


def bearing_code(bearing: int) -> int:
    """The quarter of ``bearing`` (millidegrees): 1 ahead (within 45 degrees of the
    front), 2 left (45 to 135), 3 behind, 4 right.

    >>> [bearing_code(b) for b in (0, 44_999, 45_000, 134_999, 135_000, -135_000, -45_000)]
    [1, 1, 2, 2, 3, 3, 4]
    """
    if -45_000 < bearing < 45_000:
        return 1
    if 45_000 <= bearing < 135_000:
        return 2
    if -135_000 < bearing <= -45_000:
        return 4
    return 3


class Policy:
    """A loaded policy: layout, encoder, Q rows, learning settings and metadata.

    ``rows`` maps a state key to its list of ``n_actions`` Q values (as the simulator's
    sparse table); states never visited have every value at ``q_init``.
    """

    def __init__(self, doc: dict[str, Any], source: str = "<policy>") -> None:
        validate_document(doc, source)
        self.source = source
        lay = doc["layout"]
        self.layout = Layout([(f["name"], f["levels"]) for f in lay["fields"]], lay["n_actions"])
        self.encoder = Encoder(doc["encoding"])
        self.sensors: dict[str, Any] = doc["sensors"]
        self.learner: dict[str, Any] = dict(doc.get("learner") or {})
        self.algorithm = str(self.learner.get("algorithm", "q"))
        """``q``, ``qlambda`` or ``dyna`` (the file's ``learner.algorithm``)."""
        self.no_undo = self.learner.get("no_undo") is True
        """The file's ``learner.no_undo``: never choose the action that undoes the last."""
        self.model = (
            Model.from_json(doc.get("model"), self.layout) if self.algorithm == "dyna" else None
        )
        """Dyna-Q's model of the real transitions (``dyna`` only; saved in the file)."""
        self.rewards: dict[str, float] = dict(doc.get("rewards") or {})
        self.q_init = float(doc["q_init"])
        self.episodes = int(doc["episodes"])
        names = doc.get("actions") or list(ACTION_NAMES)
        self.actions = [str(n) for n in names][: self.layout.n_actions]
        self.extra = {k: v for k, v in doc.items() if k not in _KNOWN_KEYS}
        self.rows: dict[int, list[float]] = {}
        ab = self.layout.action_bits
        for e in doc["entries"]:
            kw = e["keyword"]
            self.row(kw >> ab)[kw & ((1 << ab) - 1)] = float(e["q"])

    # -- files --------------------------------------------------------------------------
    @classmethod
    def load(cls, path: str) -> Policy:
        """Read and validate a policy file; PolicyError (one line) when it is bad."""
        data = read_regular(str(path), MAX_POLICY_BYTES + 1)
        if len(data) > MAX_POLICY_BYTES:
            raise _err(str(path), "", f"larger than {MAX_POLICY_BYTES >> 20} MiB: not a policy")
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError:
            raise _err(str(path), "", "not a policy file (not UTF-8 text)") from None
        return cls.loads(text, str(path))

    @classmethod
    def loads(cls, text: str, source: str = "<policy>") -> Policy:
        try:
            doc = json.loads(text, parse_constant=_reject_constant)
        except ValueError as exc:
            problem = str(exc).split(";")[0][:120]
            raise _err(source, "", f"not a policy file (invalid JSON: {problem})") from None
        except RecursionError:
            raise _err(source, "", "not a policy file (JSON nested too deeply)") from None
        return cls(doc, source)

    def to_document(self, written_by: str = "robot_runtime") -> dict[str, Any]:
        """The policy as a version-1 document (entries and greedy actions rebuilt)."""
        doc: dict[str, Any] = {
            "format": FORMAT,
            "version": VERSION,
            "written_by": written_by,
            "layout": self.layout.to_json(),
            "actions": self.actions,
            "encoding": encoding_json(self.encoder),
            "sensors": self.sensors,
            "learner": self.learner,
            "rewards": self.rewards,
            "q_init": self.q_init,
            "episodes": self.episodes,
        }
        doc.update(self.extra)
        doc.update(rows_json(self.rows, self.layout.action_bits))
        if self.model is not None and self.model.pairs:
            doc["model"] = self.model.to_json()
        return doc

    def save(self, path: str, written_by: str = "robot_runtime", backup: bool = True) -> None:
        """Write the policy atomically; the previous file becomes ``<path>.bak``."""
        text = dump_document(self.to_document(written_by))
        check_regular(path)
        if backup and os.path.exists(path):
            _atomic(path + ".bak", lambda tmp: shutil.copyfile(path, tmp))
        atomic_write_text(path, text)

    # -- acting and learning ----------------------------------------------------------
    def encode(
        self,
        sonar: Sequence[float],
        goal_cam: Sequence[float | None],
        eow_cam: Sequence[float | None],
        compass: float | None = None,
        memory: Memory | None = None,
        action: int | None = None,
    ) -> tuple[int, ...]:
        """Raw readings -> state codes (see :class:`Encoder`). A policy whose state holds
        memory fields needs the episode's ``memory`` (:meth:`new_memory`), which this
        updates with the reading and ``action``, the action just taken (None after a reset
        or a rescue); its codes follow the sensors'."""
        codes = self.encoder.encode(sonar, goal_cam, eow_cam, compass)
        if not self.encoder.remembers:
            return codes
        if memory is None:
            raise PolicyError("memory: this policy's state remembers (encoding.memory): pass "
                              "the episode's Memory (Policy.new_memory)")  # fmt: skip
        n = self.encoder.n_camera
        if action is not None and not (_is_int(action) and 0 <= action < self.layout.n_actions):
            raise PolicyError(
                f"action: {action!r} is not an action (0..{self.layout.n_actions - 1}, or None "
                "after a reset or a rescue)"
            )
        memory.update(_numbers(goal_cam, n, "goal_cam", True),
                      _numbers(eow_cam, n, "eow_cam", True), action)  # fmt: skip
        return codes + memory.codes()

    def new_memory(self) -> Memory:
        """An empty memory for this policy's encoding (reset it at every episode start)."""
        return Memory(self.encoder)

    def state_key(self, codes: Sequence[int]) -> int:
        if len(codes) != len(self.layout.levels):
            raise PolicyError(f"state: expected {len(self.layout.levels)} codes, got {len(codes)}")
        return self.layout.state_key(codes)

    def row(self, state: int) -> list[float]:
        """The (mutable) Q row of ``state``, created at ``q_init`` when missing."""
        r = self.rows.get(state)
        if r is None:
            r = [self.q_init] * self.layout.n_actions
            self.rows[state] = r
        return r

    def q(self, state: int) -> list[float]:
        """A copy of the Q values of ``state`` (``q_init`` everywhere if never visited)."""
        r = self.rows.get(state)
        return list(r) if r is not None else [self.q_init] * self.layout.n_actions

    def barred(self, last: int) -> int:
        """The action the policy's no-undo rule bars after the action ``last`` (-1: none;
        none when the rule is off or ``last`` is -1, no action yet)."""
        return UNDO[last] if self.no_undo and 0 <= last < len(UNDO) else -1

    def greedy_actions(self, state: int, bar: int = -1) -> list[int]:
        """Every action of highest Q but ``bar`` (all of them for a state never visited)."""
        r = self.q(state)
        best = max(v for a, v in enumerate(r) if a != bar)
        return [a for a, v in enumerate(r) if v == best and a != bar]

    def greedy(self, state: int, rng: random.Random | None = None, bar: int = -1) -> int:
        """An action of highest Q but ``bar``; ties broken uniformly at random (as the
        simulator), or the lowest index when ``rng`` is None."""
        ties = self.greedy_actions(state, bar)
        if len(ties) == 1 or rng is None:
            return ties[0]
        return ties[rng.randrange(len(ties))]

    def act(self, state: int, epsilon: float, rng: random.Random, last: int = -1) -> int:
        """epsilon-greedy: a uniform random action with probability ``epsilon``; with the
        no-undo rule, never the one that undoes ``last`` (the action taken before)."""
        bar = self.barred(last)
        if epsilon > 0.0 and rng.random() < epsilon:
            if bar < 0:
                return rng.randrange(self.layout.n_actions)
            k = rng.randrange(self.layout.n_actions - 1)
            return k + 1 if k >= bar else k
        return self.greedy(state, rng, bar)

    def update(
        self,
        state: int,
        action: int,
        reward: float,
        next_state: int,
        terminal: bool,
        alpha: float | None = None,
        gamma: float | None = None,
    ) -> float:
        """Table 11: ``Q += alpha * (reward + gamma * max(NextQ) - Q)``; returns new Q.

        ``max(NextQ)`` is 0 after a terminal step (goal, end of world). ``alpha`` and
        ``gamma`` default to the file's ``learner`` values.
        """
        alpha = self._setting("alpha", alpha)
        gamma = self._setting("gamma", gamma)
        if not 0 <= action < self.layout.n_actions:
            raise PolicyError(
                f"action: {action!r} is not an action (0..{self.layout.n_actions - 1})"
            )
        row = self.row(state)
        nxt = self.rows.get(next_state)
        row[action] += td_step(row[action], reward, nxt, self.q_init, terminal, alpha, gamma)
        return row[action]

    def _setting(self, name: str, value: float | None) -> float:
        if value is not None:
            return float(value)
        if name not in self.learner:
            raise PolicyError(f"learner.{name}: not in the policy file (pass {name}=...)")
        return float(self.learner[name])

    # -- rewards (paper §5.4.7) -------------------------------------------------------
    def bump(self, sonar: Sequence[float]) -> bool:
        return self.encoder.bump(sonar)

    def judge(
        self,
        action: int,
        sonar: Sequence[float],
        goal_cam: Sequence[float | None],
        end_of_world: bool = False,
    ) -> tuple[str, float, bool]:
        """``(event, reward, terminal)`` of a step, first rule that applies: goal (Stop
        with the front camera reading the goal Close) > end_of_world > bump > by action."""
        if action == STOP and self.encoder.goal_close(goal_cam):
            event = "goal"
        elif end_of_world:
            event = "end_of_world"
        elif self.encoder.bump(sonar):
            event = "bump"
        else:
            event = _ACTION_EVENTS[action]
        if event not in self.rewards:
            raise PolicyError(f"rewards: no value for {event!r} in the policy file")
        return event, float(self.rewards[event]), event in ("goal", "end_of_world")


_SPECIAL = (
    (stat.S_ISDIR, "a folder"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)


def _not_regular(path: str, mode: int) -> PolicyError:
    kind = next((words for test, words in _SPECIAL if test(mode)), "a special file")
    return _err(path, "", f"is {kind}, not a regular file")


def check_regular(path: str) -> None:
    """Refuse an existing ``path`` that is not a regular file (a FIFO would block a
    writer for ever); a missing one is fine. The simulator's ``files.check_regular``."""
    try:
        mode = os.stat(path).st_mode
    except OSError:  # the write that follows says why it fails
        return
    if not stat.S_ISREG(mode):
        raise _not_regular(path, mode)


def read_regular(path: str, limit: int) -> bytes:
    """At most ``limit`` bytes of the regular file ``path``, opened without blocking
    (a FIFO is refused, not waited on): the simulator's ``files.read_bytes``."""
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
    try:
        fd = os.open(path, flags)
    except OSError as exc:  # e.g. a socket cannot be opened (ENXIO): say what it is
        check_regular(path)
        raise _err(path, "", f"cannot read: {exc.strerror}") from None
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            raise _not_regular(path, mode)
        with os.fdopen(fd, "rb") as fh:
            fd = -1
            return fh.read(limit)
    except OSError as exc:
        raise _err(path, "", f"cannot read: {exc.strerror}") from None
    finally:
        if fd >= 0:
            os.close(fd)


def _reject_constant(name: str) -> float:
    raise ValueError(f"{name} is not allowed")


_KNOWN_KEYS = frozenset(
    (
        "format",
        "version",
        "written_by",
        "layout",
        "actions",
        "encoding",
        "sensors",
        "learner",
        "rewards",
        "q_init",
        "episodes",
        "n_states",
        "entries",
        "greedy",
        "model",
    )
)


def memory_json(mem: dict[str, Any]) -> dict[str, Any]:
    """``encoding.memory`` of a document: ``goal_bearing`` and its keys only when on (the
    documents written before the bearing existed keep their bytes)."""
    out = {k: v for k, v in mem.items() if k not in ("goal_bearing", *BEARING_KEYS)}
    if mem["goal_bearing"]:
        out |= {"goal_bearing": True} | {k: mem[k] for k in BEARING_KEYS}
    return out


def encoding_json(enc: Encoder) -> dict[str, Any]:
    """The ``encoding`` section of a document."""
    return {
        "thresholds": {"sonar": enc.sonar_thresholds, "camera": enc.camera_thresholds},
        "sonar_groups": enc.sonar_groups,
        "n_sonar": enc.n_sonar,
        "n_camera": enc.n_camera,
        "max_camera_view": enc.max_camera_view,
        "compass_in_state": enc.compass_in_state,
        **({"sonar_pings": enc.sonar_pings} if enc.sonar_pings != 1 else {}),
        **({"memory": memory_json(enc.memory)} if enc.remembers else {}),
        "levels": {
            "sonar": list(_level_names(("Bump", "Close", "Medium", "Far"), enc.sonar_thresholds)),
            "camera": list(_level_names(("Close", "Medium", "Far"), enc.camera_thresholds)),
        },
    }


def _level_names(names: tuple[str, ...], thresholds: list[float]) -> tuple[str, ...]:
    n = len(thresholds) + 1
    return names if len(names) == n else tuple(f"L{i}" for i in range(n))


def rows_json(rows: dict[int, list[float]], action_bits: int) -> dict[str, Any]:
    """``n_states``, ``entries`` (every Q entry by ascending keyword) and ``greedy`` (one
    action of highest Q per state, the lowest index among equal values)."""
    entries = []
    greedy = []
    for state in sorted(rows):
        r = rows[state]
        for a, q in enumerate(r):
            entries.append({"keyword": (state << action_bits) | a, "q": float(q)})
        greedy.append({"state": state, "action": r.index(max(r))})
    return {"n_states": len(rows), "entries": entries, "greedy": greedy}


def validate_document(doc: Any, source: str = "<policy>") -> None:
    """Check a version-1 ``koolio-policy`` document; PolicyError naming the bad item.
    Every number anywhere in it is finite (JSON's ``1e400`` reads as infinity, which the
    next save could not write).

    Fields (JSON object):

    * ``format`` ``"koolio-policy"``; ``version`` ``1`` (an integer; a reader refuses
      versions it does not know); ``written_by`` free text.
    * ``layout``: ``fields`` (state fields, most significant first, each ``name``,
      ``levels`` = number of codes, ``bits`` = max(1, ceil(log2 levels)), ``shift`` =
      its position in the keyword), ``action_bits``, ``n_actions``, ``total_bits``.
      ``keyword = sum(code_i << shift_i) | action`` (paper Table 12).
    * ``actions``: action names by index (``Stop, RotateLeft, RotateRight, Forward,
      Reverse``).
    * ``encoding``: ``thresholds.sonar`` / ``thresholds.camera`` (inches, increasing; a
      code is the number of thresholds at or below the reading), ``sonar_groups``
      (sonar indices averaged into one field, in keyword order), ``n_sonar``,
      ``n_camera``, ``max_camera_view`` (a camera reading beyond it encodes Far, as does
      "not seen"), ``compass_in_state``, ``levels`` (names of the codes).
    * ``sensors``: the simulator's sensor signature (angles, arcs, ranges, thresholds):
      what the table was learned with; ``koolio-pm train --init-qtable`` refuses a file
      whose signature differs from the run's.
    * ``learner``: ``alpha`` in (0, 1], ``gamma`` and ``epsilon`` in [0, 1]: defaults
      for the robot; for a learner other than one-step Q its ``algorithm`` (``qlambda``:
      with ``trace_decay`` in [0, 1] and ``trace_cutoff`` in [1e-6, 1); ``dyna``: with
      ``planning_steps``, an integer in 0..:data:`MAX_PLANNING_STEPS`); ``no_undo``
      (``true`` or ``false``, absent: false): never choose the action that undoes the
      last one (:data:`UNDO`); ``rewards``: the
      reward of each event (``goal, end_of_world, bump, stop, reverse, turn, forward``),
      each within +-:data:`MAX_REWARD`.
    * ``model`` (``dyna`` only, optional): the robot's model of its real transitions,
      ``{"pairs": [[state, action, [[next_state, reward, terminal, count], ...]], ...]}``
      in first-seen order (:class:`Model`; states inside the layout, actions in the
      action set, rewards within +-:data:`MAX_REWARD`, counts in 1..2**53).
      ``koolio-pm export`` writes none: the robot builds its own from real steps.
    * ``q_init``: the value of a Q entry never visited; ``episodes``: episodes learned so
      far (simulation + robot); ``n_states``: number of visited states.
    * ``entries``: ``[{"keyword": K, "q": Q}, ...]``, ascending keywords, every action of
      every visited state, every Q (and ``q_init``) within +-:data:`MAX_Q`; ``greedy``:
      ``[{"state": S, "action": A}, ...]`` with ``S = K >> action_bits``, one per visited
      state, ascending, ``A`` the action of highest Q (the lowest index among equal
      values).

    ``n_states``, ``greedy`` and ``layout.total_bits`` (and each field's ``bits`` and
    ``shift``, ``layout.action_bits``) are derived data, rebuilt on every save; each may
    be left out, and one given must be what ``entries`` and ``layout.fields`` make it (a
    reader may act on it alone).
    """
    if not isinstance(doc, dict):
        raise _err(source, "", "not a policy file (not a JSON object)")
    if doc.get("format") != FORMAT:
        raise _err(source, "format", f"not a {FORMAT} file (format {_show(doc.get('format'))})")
    version = doc.get("version")
    if not _is_int(version) or version > VERSION or version < 1:
        raise _err(
            source, "version", f"unsupported version {_show(version)} (this reader knows {VERSION})"
        )
    for key in ("layout", "encoding", "sensors", "q_init", "episodes", "entries"):
        if key not in doc:
            raise _err(source, key, "missing")
    _check_layout(doc["layout"], source)
    _check_encoding(doc, source)
    if not isinstance(doc["sensors"], dict):
        raise _err(source, "sensors", f"must be a mapping, got {_show(doc['sensors'])}")
    actions = doc.get("actions")
    if actions is not None and (
        not isinstance(actions, list)
        or not all(isinstance(a, str) for a in actions)
        or len(actions) < doc["layout"]["n_actions"]
    ):
        raise _err(
            source, "actions", f"must be a list of {doc['layout']['n_actions']} action names"
        )
    if not is_number(doc["q_init"]) or abs(doc["q_init"]) > MAX_Q:
        raise _err(source, "q_init", f"must be a finite number within +-{MAX_Q:g}")
    if not _is_int(doc["episodes"]) or not 0 <= doc["episodes"] < 1 << 63:
        raise _err(source, "episodes", "must be an integer >= 0")
    sec = doc.get("rewards") or {}
    if not isinstance(sec, dict) or not all(
        is_number(v) and abs(v) <= MAX_REWARD for v in sec.values()
    ):
        raise _err(source, "rewards", f"must map names to finite numbers within +-{MAX_REWARD:g}")
    missing = [e for e in EVENTS if e not in sec]
    if missing:  # else the step that needs it fails, on the robot, mid-episode
        raise _err(source, f"rewards.{missing[0]}", f"missing (the rewards of {', '.join(EVENTS)})")
    _check_learner(doc.get("learner") or {}, source)
    _check_entries(doc, source)
    if "model" in doc:
        if (doc.get("learner") or {}).get("algorithm") != "dyna":
            raise _err(source, "model", "only a dyna policy has a model")
        lay = doc["layout"]
        layout = Layout([(f["name"], f["levels"]) for f in lay["fields"]], lay["n_actions"])
        try:
            Model.from_json(doc["model"], layout)
        except PolicyError as exc:
            raise _err(source, "model", str(exc)) from None
    bad = nonfinite_item(doc)  # anywhere else (sensors, extra keys): JSON's 1e400
    if bad is not None:
        raise _err(source, bad, "not a finite number (JSON could not write it back)")


#: The range of each ``learner`` number a policy may hold (the simulator's configuration
#: has the same): name -> (test, problem).
LEARNER_RANGES = {
    "alpha": (lambda v: 0 < v <= 1, "must be in (0, 1]"),
    "gamma": (lambda v: 0 <= v <= 1, "must be in [0, 1]"),
    "epsilon": (lambda v: 0 <= v <= 1, "must be in [0, 1]"),
    "trace_decay": (lambda v: 0 <= v <= 1, "must be in [0, 1]"),
    "trace_cutoff": (lambda v: 1e-6 <= v < 1, "must be in [1e-06, 1)"),
    "planning_steps": (
        lambda v: _is_int(v) and 0 <= v <= MAX_PLANNING_STEPS,
        f"must be an integer in 0..{MAX_PLANNING_STEPS:,} (simulated updates per real step)",
    ),
}
_PARAMETER_NAMES = frozenset(n for names in ALGORITHMS.values() for n in names)


def _check_learner(sec: Any, source: str) -> None:
    if not isinstance(sec, dict):
        raise _err(source, "learner", "must map names to finite numbers")
    algorithm = sec.get("algorithm", "q")
    if not isinstance(algorithm, str) or algorithm not in ALGORITHMS:
        raise _err(
            source,
            "learner.algorithm",
            f"unknown algorithm {_show(algorithm)} (valid: {', '.join(ALGORITHMS)})",
        )
    if "no_undo" in sec and not isinstance(sec["no_undo"], bool):
        raise _err(source, "learner.no_undo", "must be true or false")
    for name, v in sec.items():
        if name not in ("algorithm", "no_undo") and not is_number(v):
            raise _err(source, f"learner.{name}", "must be a finite number")
    for name, (ok, problem) in LEARNER_RANGES.items():
        if name in sec and name not in _PARAMETER_NAMES and not ok(sec[name]):
            raise _err(source, f"learner.{name}", problem)
    ranges = LEARNER_RANGES
    for name in ALGORITHMS[algorithm]:
        if name not in sec:
            raise _err(source, f"learner.{name}", f"missing (needed by {algorithm})")
        ok, problem = ranges[name]
        if not ok(sec[name]):
            raise _err(source, f"learner.{name}", problem)


#: Bounds of a policy's integers (a 64-bit keyword, at most 64 actions, sensors, levels).
MAX_KEYWORD_BITS = 64
MAX_ACTIONS = 64
MAX_LEVELS = 1 << 16
MAX_SENSORS = 1024
#: Largest magnitude of a reward (in ``rewards`` and in a model): the simulator's bound on
#: every number of a configuration. Rewards of 1e308 overflowed Q values to infinity,
#: which JSON cannot write.
MAX_REWARD = 1e15
#: Largest magnitude of a Q value or ``q_init``: far above anything learned from rewards
#: of at most 1e15 (1e285 updates away), far enough below the float range (1.8e308) that
#: an update ``reward + gamma * Q' - Q`` never overflows to infinity.
MAX_Q = 1e300
#: Largest count of one outcome, and total of one pair, in a Dyna-Q model: counts and
#: their sums stay exact in floats (2**53 real steps are centuries of driving).
MAX_COUNT = 1 << 53


def state_problem(state: Any, layout: Layout) -> str | None:
    """What is wrong with ``state`` as a state key of ``layout`` (None: nothing): an
    integer >= 0 within the state bits, every field's code below its levels. The
    simulator's Q-table, Dyna-Q model and policy readers use this one.

    >>> lay = Layout([("A", 3), ("B", 4)], n_actions=5)
    >>> state_problem(9, lay) is None, state_problem(16, lay), state_problem(13, lay)
    (True, 'state 16 beyond the 4-bit layout', 'state 13: code 3 of A beyond its 3 levels')
    """
    if not _is_int(state) or state < 0:
        return f"state {_show(state)} is not an integer >= 0"
    bits = layout.total_bits - layout.action_bits
    if state >> bits:
        return f"state {_show(state)} beyond the {bits}-bit layout"
    codes, _ = layout.decode(state << layout.action_bits)
    for name, code, levels in zip(layout.names, codes, layout.levels):
        if code >= levels:
            return f"state {state}: code {code} of {name} beyond its {levels} levels"
    return None


def action_problem(action: Any, layout: Layout) -> str | None:
    """What is wrong with ``action`` as an action of ``layout`` (None: nothing)."""
    if not _is_int(action) or not 0 <= action < layout.n_actions:
        return f"action {_show(action)} is not an action (0..{layout.n_actions - 1})"
    return None


def outcome_problem(reward: Any, terminal: Any, count: Any) -> str | None:
    """What is wrong with a Dyna-Q outcome's reward, terminal flag and count (None:
    nothing): a finite reward of at most :data:`MAX_REWARD` in size, a bool, an integer
    count in 1..:data:`MAX_COUNT`."""
    if not is_number(reward) or abs(reward) > MAX_REWARD:
        return f"reward {_show(reward)} is not a finite number within +-{MAX_REWARD:g}"
    if not isinstance(terminal, bool):
        return f"terminal {_show(terminal)} is not true or false"
    if not _is_int(count) or not 1 <= count <= MAX_COUNT:
        return f"count {_show(count)} is not an integer in 1..2**53"
    return None


def _check_layout(lay: Any, source: str) -> None:
    if not isinstance(lay, dict) or not isinstance(lay.get("fields"), list) or not lay["fields"]:
        raise _err(source, "layout.fields", "must be a non-empty list")
    na = lay.get("n_actions")
    if not _is_int(na) or not 1 <= na <= MAX_ACTIONS:
        raise _err(source, "layout.n_actions", f"must be an integer 1..{MAX_ACTIONS}")
    if len(lay["fields"]) > MAX_KEYWORD_BITS:
        raise _err(source, "layout.fields", f"more than {MAX_KEYWORD_BITS} fields")
    fields = []
    for i, f in enumerate(lay["fields"]):
        if (
            not isinstance(f, dict)
            or not isinstance(f.get("name"), str)
            or not _is_int(f.get("levels"))
            or not 1 <= f["levels"] <= MAX_LEVELS
        ):
            raise _err(source, f"layout.fields[{i}]", f"needs a name and levels 1..{MAX_LEVELS}")
        fields.append((f["name"], f["levels"]))
    expect = Layout(fields, na)
    if expect.total_bits > MAX_KEYWORD_BITS:
        raise _err(
            source,
            "layout",
            f"a {expect.total_bits}-bit keyword does not fit {MAX_KEYWORD_BITS} bits",
        )
    for i, f in enumerate(lay["fields"]):
        for key, want in (("bits", expect.bits[i]), ("shift", expect.shifts[i])):
            if key in f and f[key] != want:
                raise _err(source, f"layout.fields[{i}].{key}", f"{_show(f[key])}, expected {want}")
    for key in ("action_bits", "total_bits"):
        want = getattr(expect, key)
        if key in lay and (not _is_int(lay[key]) or lay[key] != want):
            raise _err(source, f"layout.{key}", f"{_show(lay[key])}, expected {want}")


def _check_encoding(doc: dict[str, Any], source: str) -> None:
    enc = doc["encoding"]
    if not isinstance(enc, dict):
        raise _err(source, "encoding", "must be a mapping")
    ths = enc.get("thresholds")
    if not isinstance(ths, dict):
        raise _err(source, "encoding.thresholds", "must map sonar and camera to lists")
    for name in ("sonar", "camera"):
        values = ths.get(name)
        if not isinstance(values, list) or not all(is_number(v) for v in values):
            raise _err(source, f"encoding.thresholds.{name}", "must be a list of finite numbers")
        if len(values) > MAX_SENSORS:
            raise _err(source, f"encoding.thresholds.{name}", "too many thresholds")
    for name in ("n_sonar", "n_camera"):
        value = enc.get(name)
        if not _is_int(value) or not 0 <= value <= MAX_SENSORS:
            raise _err(source, f"encoding.{name}", f"must be an integer 0..{MAX_SENSORS}")
    groups = enc.get("sonar_groups")
    if (
        not isinstance(groups, list)
        or len(groups) > MAX_SENSORS
        or not all(isinstance(g, list) and all(_is_int(i) for i in g) for g in groups)
    ):
        raise _err(source, "encoding.sonar_groups", "must be a list of lists of sonar indices")
    if not is_number(enc.get("max_camera_view")):
        raise _err(source, "encoding.max_camera_view", "must be a finite number")
    if not isinstance(enc.get("compass_in_state"), bool):
        raise _err(source, "encoding.compass_in_state", "must be true or false")
    pings = enc.get("sonar_pings", 1)
    if not _is_int(pings) or pings not in SONAR_PINGS:
        raise _err(source, "encoding.sonar_pings", "must be odd, 1 to 9 (the median is read)")
    _check_memory(enc.get("memory", NO_MEMORY), source, enc["n_camera"])
    encoder = Encoder(enc)
    for name, ts in (("sonar", encoder.sonar_thresholds), ("camera", encoder.camera_thresholds)):
        if not ts or any(b <= a for a, b in itertools.pairwise(ts)):
            raise _err(source, f"encoding.thresholds.{name}", "must be increasing, non-empty")
    for g in encoder.sonar_groups:
        if not g or any(not 0 <= i < encoder.n_sonar for i in g):
            raise _err(source, "encoding.sonar_groups", f"bad group {_show(g)}")
    lay = doc["layout"]
    got = [(str(f["name"]), f["levels"]) for f in lay["fields"]]
    if got != encoder.fields():
        raise _err(
            source, "layout.fields", f"do not match the encoding (expected {encoder.fields()!r})"
        )


#: Pings a sonar may take per reading (``encoding.sonar_pings``; the simulator's
#: ``sensors.sonar.pings``).
SONAR_PINGS = (1, 3, 5, 7, 9)

#: Largest ``encoding.memory.forget_after`` (steps; more than any episode's cap).
MAX_FORGET_AFTER = 10_000


def _check_memory(mem: Any, source: str, n_camera: int) -> None:
    """``encoding.memory``: the memory's settings (:data:`NO_MEMORY`'s keys)."""
    if not isinstance(mem, dict) or set(mem) - set(NO_MEMORY) - set(BEARING_KEYS):
        raise _err(source, "encoding.memory", f"must map {', '.join((*NO_MEMORY, *BEARING_KEYS))}")
    for key in ("goal_camera", "eow_camera", "previous_action", "goal_bearing"):
        if not isinstance(mem.get(key, False), bool):
            raise _err(source, f"encoding.memory.{key}", "must be true or false")
    if mem.get("goal_bearing", False):
        turn = mem.get("turn_deg")
        if not is_number(turn) or not 0 < turn < 360:
            raise _err(source, "encoding.memory.turn_deg", "must be a number in (0, 360)")
        cams = mem.get("camera_deg")
        if (
            not isinstance(cams, list)
            or len(cams) != n_camera
            or not all(is_number(d) and abs(d) <= 360 for d in cams)
        ):
            raise _err(
                source,
                "encoding.memory.camera_deg",
                f"must be a list of {n_camera} angles in [-360, 360] (one per camera)",
            )
    k = mem.get("forget_after", 0)
    if not _is_int(k) or not 0 <= k <= MAX_FORGET_AFTER:
        raise _err(
            source, "encoding.memory.forget_after", f"must be an integer 0..{MAX_FORGET_AFTER}"
        )


def _check_entries(doc: dict[str, Any], source: str) -> None:
    lay = doc["layout"]
    layout = Layout([(f["name"], f["levels"]) for f in lay["fields"]], lay["n_actions"])
    entries = doc["entries"]
    if not isinstance(entries, list):
        raise _err(source, "entries", "must be a list")
    limit = 1 << layout.total_bits
    amask = (1 << layout.action_bits) - 1
    seen = set()
    for i, e in enumerate(entries):
        item = f"entries[{i}]"
        if not isinstance(e, dict) or not _is_int(e.get("keyword")) or not is_number(e.get("q")):
            raise _err(source, item, "needs an integer keyword and a finite number q")
        if abs(e["q"]) > MAX_Q:
            raise _err(source, item, f"q {_show(e['q'])} beyond +-{MAX_Q:g}")
        kw = e["keyword"]
        if not 0 <= kw < limit or (kw & amask) >= layout.n_actions:
            raise _err(source, item, f"keyword {_show(kw)} out of range for the layout")
        codes, _ = layout.decode(kw)
        if any(c >= lv for c, lv in zip(codes, layout.levels)):
            raise _err(source, item, f"keyword {kw} has a code beyond its field's levels")
        if kw in seen:
            raise _err(source, item, f"keyword {kw} repeated")
        seen.add(kw)
    rows: dict[int, list[float]] = {}
    for e in entries:
        kw = e["keyword"]
        row = rows.setdefault(kw >> layout.action_bits, [doc["q_init"]] * layout.n_actions)
        row[kw & amask] = e["q"]
    if "n_states" in doc and (not _is_int(doc["n_states"]) or doc["n_states"] != len(rows)):
        problem = f"{_show(doc['n_states'])}, expected {len(rows)} (the states of entries)"
        raise _err(source, "n_states", problem)
    if "greedy" in doc:
        _check_greedy(doc["greedy"], rows, layout, source)


def _check_greedy(greedy: Any, rows: dict[int, list[float]], layout: Layout, source: str) -> None:
    """``greedy``, derived data: one ``{"state", "action"}`` per visited state, ascending,
    each the action of highest Q (the lowest index among equal values), as
    :func:`rows_json` writes it. A reader in another language may act on it alone."""
    if not isinstance(greedy, list):
        raise _err(source, "greedy", "must be a list")
    states = sorted(rows)
    if len(greedy) != len(states):
        problem = f"{len(greedy)} items, expected {len(states)} (one per state of entries)"
        raise _err(source, "greedy", problem)
    for i, (g, state) in enumerate(zip(greedy, states)):
        item = f"greedy[{i}]"
        if not isinstance(g, dict) or not _is_int(g.get("state")) or not _is_int(g.get("action")):
            raise _err(source, item, "needs an integer state and an integer action")
        problem = action_problem(g["action"], layout)
        if problem is not None:
            raise _err(source, f"{item}.action", problem)
        if g["state"] != state:
            problem = f"{_show(g['state'])}, expected {state} (the states of entries, ascending)"
            raise _err(source, f"{item}.state", problem)
        row = rows[state]
        best = row.index(max(row))
        if g["action"] != best:
            problem = f"{g['action']} is not the greedy action of state {state} (expected {best})"
            raise _err(source, f"{item}.action", problem)


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def nonfinite_item(value: Any) -> str | None:
    """The path of the first float in ``value`` (nested lists and mappings) that is not
    finite, or None. JSON's ``1e400`` reads as infinity, which no JSON can write back: a
    policy (or a table's header) holding one would fail at its next save. The
    simulator's table reader uses this one too.

    >>> nonfinite_item({"a": [1.0, {"b": float("inf")}]}), nonfinite_item([1, 2.5]) is None
    ('a[1].b', True)
    """
    stack: list[tuple[str, Any]] = [("", value)]
    while stack:
        path, v = stack.pop()
        if isinstance(v, float) and not math.isfinite(v):
            return path or "(top level)"
        if isinstance(v, dict):
            stack.extend((f"{path}.{k}" if path else str(k), x) for k, x in v.items())
        elif isinstance(v, list):
            stack.extend((f"{path}[{i}]", x) for i, x in enumerate(v))
    return None


def is_number(v: Any) -> bool:
    """A finite int or float, not a bool (an integer beyond the float range is not).
    The simulator's readers use this one too.

    >>> [is_number(v) for v in (1, 2.5, True, float("inf"), 10**400, "1")]
    [True, True, False, False, False, False]
    """
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return False
    try:
        return math.isfinite(v)
    except OverflowError:
        return False


def _show(value: Any, limit: int = 40) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def dump_document(doc: dict[str, Any]) -> str:
    """JSON text of a document: short values on one line, one entry per line."""
    return _pretty(doc, "") + "\n"


def _pretty(value: Any, pad: str, width: int = 96) -> str:
    flat = json.dumps(value, allow_nan=False)
    if not isinstance(value, (dict, list)) or not value or len(pad) + len(flat) <= width:
        return flat
    inner = pad + "  "
    if isinstance(value, dict):
        items = [f"{inner}{json.dumps(k)}: {_pretty(v, inner, width)}" for k, v in value.items()]
        return "{\n" + ",\n".join(items) + f"\n{pad}}}"
    items = [inner + _pretty(v, inner, width) for v in value]
    return "[\n" + ",\n".join(items) + f"\n{pad}]"


def _remove_stale_temps(directory: str, base: str) -> None:
    """Remove ``.<base>.tmp<pid>`` files of processes that no longer run (a write cut
    short by a crash or SIGKILL)."""
    if sys.platform == "win32":  # os.kill(pid, 0) would terminate the process there
        return
    prefix = f".{base}.tmp"
    try:
        names = os.listdir(directory)
    except OSError:
        return
    for name in names:
        pid = name[len(prefix) :]
        if not name.startswith(prefix) or not pid.isdigit() or int(pid) == os.getpid():
            continue
        try:
            os.kill(int(pid), 0)
        except ProcessLookupError:  # no such process: its file is stale
            with contextlib.suppress(OSError):
                os.unlink(os.path.join(directory, name))
        except OSError:  # it runs, as another user
            pass


def _atomic(path: str, write) -> None:
    directory = os.path.dirname(os.path.abspath(path))
    _remove_stale_temps(directory, os.path.basename(path))
    tmp = os.path.join(directory, f".{os.path.basename(path)}.tmp{os.getpid()}")
    try:
        write(tmp)
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def atomic_write_text(path: str, text: str) -> None:
    """Write ``text`` so that a crash leaves either the old or the new file."""

    def write(tmp: str) -> None:
        with open(tmp, "w", encoding="utf-8", newline="\n") as fh:
            fh.write(text)

    _atomic(path, write)


class EpisodeLog:
    """Appends one CSV row per episode, in ``koolio-pm train``'s log format. A file that
    exists must already be such a log (its first line the header): anything else is
    refused with a :class:`PolicyError` and left untouched."""

    def __init__(self, path: str) -> None:
        self.path = path
        check_regular(path)  # a FIFO would block the first row for ever
        new = not os.path.exists(path) or os.path.getsize(path) == 0
        if new:
            self._write(list(LOG_FIELDS))
            return
        head = read_regular(path, 1000)
        first = head.split(b"\n", 1)[0].rstrip(b"\r")
        if first != ",".join(LOG_FIELDS).encode():
            raise _err(path, "line 1", "not a training log (its first line is not the header)")

    def _write(self, row: list[str]) -> None:
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerow(row)
        with open(self.path, "a", encoding="utf-8", newline="", opener=open_append) as fh:
            fh.write(buf.getvalue())
            fh.flush()
            os.fsync(fh.fileno())

    def write(
        self,
        episode: int,
        reward: float,
        steps: int,
        bumps: int,
        outcome: str,
        rescued: bool,
        epsilon: float,
        goal: str,
    ) -> None:
        self._write(
            [
                str(episode),
                format(reward, ".6g"),
                str(steps),
                str(bumps),
                outcome,
                str(int(rescued)),
                format(epsilon, ".6g"),
                goal,
            ]
        )


def open_append(
    path: str, flags: int, refuse: Callable[[str, int], Exception] = _not_regular
) -> int:
    """``open()``'s opener of a log (the robot's, and the simulator's
    ``store.episode_log``): never waiting (a FIFO with no reader is an error, not a
    hang), a regular file only: ``refuse(path, mode)`` is raised for anything else (a
    :class:`PolicyError` here)."""
    fd = os.open(path, flags | getattr(os, "O_NONBLOCK", 0), 0o666)
    mode = os.fstat(fd).st_mode
    if not stat.S_ISREG(mode):
        os.close(fd)
        raise refuse(path, mode)
    return fd


class RobotLearner:
    """One learning episode at a time on the robot: choose, update, log, save.

    ``epsilon`` (default: the file's ``learner.epsilon``) sets exploration; ``learn``
    False runs the greedy policy without updates (``epsilon`` then defaults to 0).
    Outcomes for :meth:`end`: ``goal``, ``end_of_world``, ``truncated`` or
    ``interrupted``, as in the simulator's log.

    The file's ``learner.algorithm`` chooses the learning (:meth:`learn_step`): one-step
    Q, Q(lambda) with :class:`Traces` (cleared at :meth:`begin` and after a non-greedy
    choice), or Dyna-Q with the policy's :class:`Model` (saved in the policy file by
    :meth:`end`, so the next session continues from it).
    """

    def __init__(
        self,
        policy: Policy,
        save_path: str | None = None,
        log_path: str | None = None,
        epsilon: float | None = None,
        seed: int | None = None,
        learn: bool = True,
        goal: str = "",
    ) -> None:
        self.policy = policy
        self.save_path = save_path
        self.log = EpisodeLog(log_path) if log_path else None
        default_eps = float(policy.learner.get("epsilon", 0.0)) if learn else 0.0
        self.epsilon = default_eps if epsilon is None else float(epsilon)
        self.rng = random.Random(seed)
        self.learn = learn
        self.goal = goal
        self.state: int | None = None
        self.last = -1
        """The action chosen last in this episode (-1: none yet, or a rescue since)."""
        self.traces: Traces | None = None
        """Q(lambda)'s traces (``qlambda`` only); they live within an episode."""
        if policy.algorithm == "qlambda":
            gamma = policy._setting("gamma", None)
            lam = float(policy.learner["trace_decay"])
            self.traces = Traces(gamma * lam, float(policy.learner["trace_cutoff"]))

    def begin(self, codes: Sequence[int]) -> None:
        """Start an episode from the first state's codes."""
        self.state = self.policy.state_key(codes)
        self.last = -1
        if self.traces is not None:
            self.traces.clear()
        self.reward = 0.0
        self.steps = 0
        self.bumps = 0
        self.rescued = False

    def choose(self) -> int:
        if self.state is None:
            raise PolicyError("choose: call begin() first")
        bar = self.policy.barred(self.last)
        action = self.policy.act(self.state, self.epsilon, self.rng, self.last)
        if self.traces is not None and action not in self.policy.greedy_actions(self.state, bar):
            self.traces.clear()  # Watkins's cut: an exploratory, non-greedy action
        self.last = action
        return action

    def step(
        self,
        action: int,
        reward: float,
        next_codes: Sequence[int],
        terminal: bool,
        bump: bool = False,
        rescued: bool = False,
    ) -> None:
        """Record one real transition (and learn from it)."""
        if self.state is None:
            raise PolicyError("step: call begin() first")
        nxt = self.policy.state_key(next_codes)
        if self.learn:
            self.learn_step(self.state, action, reward, nxt, terminal)
        self.state = nxt
        self.reward += reward
        self.steps += 1
        self.bumps += int(bump)
        self.rescued = self.rescued or rescued

    def moved(self, codes: Sequence[int]) -> None:
        """The robot was moved by hand (a rescue, after :meth:`step`): the episode goes
        on from the state of ``codes``, with no update (a person's move is no action of
        the policy), Q(lambda)'s traces cleared when it is not the state the last step
        led to (as ``QLambda`` clears them when a step does not start where the last one
        ended), and is logged as rescued."""
        if self.state is None:
            raise PolicyError("moved: call begin() first")
        moved_to = self.policy.state_key(codes)
        if self.traces is not None and moved_to != self.state:
            self.traces.clear()  # the next step does not start where the last one ended
        self.state = moved_to
        self.last = -1  # the next action undoes nothing
        self.rescued = True

    def learn_step(self, state: int, action: int, reward: float, nxt: int, terminal: bool) -> None:
        """The file's learning algorithm on one transition: Table 11 (``q``), Q(lambda)
        traces (``qlambda``), or Table 11 then ``planning_steps`` updates drawn from the
        model with ``2 * planning_steps`` calls of ``rng.random()`` (``dyna``)."""
        p = self.policy
        if self.traces is not None:
            alpha, gamma = p._setting("alpha", None), p._setting("gamma", None)
            self.traces.update(p, state, action, reward, nxt, terminal, alpha, gamma)
            return
        p.update(state, action, reward, nxt, terminal)
        if p.model is None:
            return
        p.model.record(state, action, reward, nxt, terminal)
        n = int(p.learner["planning_steps"])
        draws = [self.rng.random() for _ in range(2 * n)]
        for k in range(0, 2 * n, 2):
            p.update(*p.model.sample(draws[k], draws[k + 1]))

    def end(self, outcome: str) -> None:
        """Finish the episode: count it, write its log row, save the table atomically."""
        episode = self.policy.episodes
        self.policy.episodes += 1
        if self.log is not None:
            self.log.write(
                episode,
                self.reward,
                self.steps,
                self.bumps,
                outcome,
                self.rescued,
                self.epsilon,
                self.goal,
            )
        if self.save_path and self.learn:
            self.policy.save(self.save_path)
        self.state = None


def td_step(
    q: float,
    reward: float,
    next_row: list[float] | None,
    q_init: float,
    terminal: bool,
    alpha: float,
    gamma: float,
) -> float:
    """Table 11's change of a Q value ``q``: ``alpha * (target - q)``, the target
    ``reward + gamma * max(NextQ)`` (the reward alone after a terminal step, ``q_init``
    for a next state never visited: ``next_row`` None). The simulator's
    ``qlearning.td_target`` and ``td_step``, the same operations; :meth:`Policy.update`
    and :class:`Traces` use it.

    >>> td_step(0.0, -1.0, [0.0, 4.0], -30.0, False, 0.5, 0.9)
    1.3
    """
    if terminal:
        target = reward
    else:
        target = reward + gamma * (max(next_row) if next_row is not None else q_init)
    return alpha * (target - q)


class Traces:
    """Watkins's Q(lambda) eligibility traces: the simulator's ``qlambda.py``, stdlib copy.

    ``entries`` maps a state to ``[action, e]`` (replacing traces: one traced action per
    state), first traced first. :meth:`update` computes the TD error of one step, sets
    the step's trace to 1, moves every traced entry by ``alpha * delta * e``, decays the
    traces by ``decay`` (gamma * lambda) and drops those below ``cutoff``.

    >>> p = {0: [0.0] * 5, 1: [0.0] * 5}
    >>> class Rows:
    ...     rows, q_init = p, 0.0
    ...     def row(self, s): return p[s]
    >>> t = Traces(0.5, 0.01)
    >>> t.update(Rows(), 0, 3, 0.0, 1, False, 0.5, 1.0)
    >>> t.update(Rows(), 1, 3, 8.0, 1, True, 0.5, 1.0)
    >>> p[1][3], p[0][3]
    (4.0, 2.0)
    """

    def __init__(self, decay: float, cutoff: float) -> None:
        self.decay = decay
        self.cutoff = cutoff
        self.entries: dict[int, list] = {}

    def clear(self) -> None:
        self.entries.clear()

    def update(
        self,
        policy: Any,
        state: int,
        action: int,
        reward: float,
        nxt: int,
        terminal: bool,
        alpha: float,
        gamma: float,
    ) -> None:
        rows = policy.rows
        row = policy.row(state)
        step = td_step(row[action], reward, rows.get(nxt), policy.q_init, terminal, alpha, gamma)
        entries = self.entries
        entries[state] = [action, 1.0]
        dropped = []
        for s, tr in entries.items():
            rows[s][tr[0]] += step * tr[1]
            tr[1] *= self.decay
            if tr[1] < self.cutoff:
                dropped.append(s)
        for s in dropped:
            del entries[s]


class Model:
    """Dyna-Q's model, the simulator's too (its ``dyna_model.Model`` adds the Q-table
    file's section): every (state, action) pair seen, first seen first, with every
    distinct outcome ``[next_state, reward, terminal, count]``. :meth:`sample` draws a
    pair uniformly (``int(u1 * n_pairs)``) and an outcome in proportion to its count (the
    first whose cumulative count exceeds ``u2 * total``).

    >>> m = Model()
    >>> m.record(5, 3, -0.5, 6, False); m.record(5, 3, -5.0, 7, False)
    >>> m.sample(0.0, 0.2), m.sample(0.0, 0.9)
    ((5, 3, -0.5, 6, False), (5, 3, -5.0, 7, False))
    """

    def __init__(self) -> None:
        self.pairs: list[tuple[int, int]] = []
        """``(state, action)`` in first-seen order."""
        self.outcomes: list[list[list]] = []
        """Per pair: ``[next_state, reward, terminal, count]`` in first-seen order."""
        self.totals: list[int] = []
        """Per pair: the sum of its counts."""
        self._index: dict[tuple[int, int], int] = {}
        self._outcome: list[dict[tuple[int, float, bool], list]] = []

    def __len__(self) -> int:
        return len(self.pairs)

    def __contains__(self, pair: tuple[int, int]) -> bool:
        return pair in self._index

    def record(self, state: int, action: int, reward: float, nxt: int, terminal: bool) -> None:
        """Count one real transition."""
        i = self._index.get((state, action))
        if i is None:
            i = self.add(state, action, [])
        key = (nxt, reward, terminal)
        out = self._outcome[i].get(key)
        if out is None:
            out = [nxt, reward, terminal, 0]
            self._outcome[i][key] = out
            self.outcomes[i].append(out)
        out[3] += 1
        self.totals[i] += 1

    def add(self, state: int, action: int, outcomes: list[list]) -> int:
        """Append a pair not in the model with its ``outcomes`` (a file's, in order); its
        index."""
        i = len(self.pairs)
        self._index[(state, action)] = i
        self.pairs.append((state, action))
        self.outcomes.append(outcomes)
        self.totals.append(sum(o[3] for o in outcomes))
        self._outcome.append({(o[0], o[1], o[2]): o for o in outcomes})
        return i

    def sample(self, u1: float, u2: float) -> tuple[int, int, float, int, bool]:
        i = int(u1 * len(self.pairs))
        x = u2 * self.totals[i]
        seen = 0
        for out in self.outcomes[i]:
            seen += out[3]
            if x < seen:
                break
        state, action = self.pairs[i]
        return state, action, out[1], out[0], out[2]

    def to_json(self) -> dict[str, Any]:
        return {
            "pairs": [
                [s, a, [[o[0], o[1], o[2], o[3]] for o in outs]]
                for (s, a), outs in zip(self.pairs, self.outcomes)
            ]
        }

    @classmethod
    def from_json(cls, data: Any, layout: Layout | None = None) -> Model:
        """A model from its JSON form (None: an empty model); PolicyError when malformed.

        Checked as the simulator's ``dyna_model.Model.from_bytes`` checks its section: states
        inside ``layout`` (:func:`state_problem`), actions in its action set, rewards,
        flags and counts by :func:`outcome_problem`, each pair's total at most
        :data:`MAX_COUNT`, no pair or outcome twice.
        """
        model = cls()
        if data is None:
            return model
        pairs = data.get("pairs") if isinstance(data, dict) else None
        if not isinstance(pairs, list):
            raise PolicyError("pairs: must be a list")
        for i, item in enumerate(pairs):
            ok = isinstance(item, list) and len(item) == 3 and isinstance(item[2], list)
            ok = ok and _is_int(item[0]) and _is_int(item[1]) and bool(item[2])
            if not ok or (item[0], item[1]) in model:
                raise PolicyError(f"pairs[{i}]: expected a new [state, action, [outcome, ...]]")
            problem = None
            if layout is not None:
                problem = state_problem(item[0], layout) or action_problem(item[1], layout)
            if problem:
                raise PolicyError(f"pairs[{i}]: {problem}")
            outs = []
            seen = set()
            for o in item[2]:
                if not isinstance(o, list) or len(o) != 4 or not _is_int(o[0]):
                    raise PolicyError(
                        f"pairs[{i}]: an outcome is [next_state, reward, terminal, count >= 1]"
                    )
                problem = outcome_problem(o[1], o[2], o[3])
                if layout is not None and problem is None:
                    problem = state_problem(o[0], layout)
                if problem is None and (o[0], float(o[1]), o[2]) in seen:
                    problem = f"outcome {_show(o)} repeated"
                if problem:
                    raise PolicyError(f"pairs[{i}]: {problem}")
                seen.add((o[0], float(o[1]), o[2]))
                outs.append([o[0], float(o[1]), o[2], o[3]])
            total = sum(o[3] for o in outs)
            if total > MAX_COUNT:
                raise PolicyError(f"pairs[{i}]: counts sum to {total}, more than 2**53")
            model.add(item[0], item[1], outs)
        return model


_USAGE = """usage: python robot_runtime.py [--] POLICY
Check a koolio-policy file (koolio-pm export) and print a summary: version, states,
episodes, keyword layout, thresholds, learner. Exit 0 when the robot can run it, 2 with one
line 'robot_runtime: error: <file>: <item>: <problem>' when it cannot."""


def main(argv: Sequence[str] | None = None) -> int:
    """``python robot_runtime.py POLICY``: check a policy file and print a summary (exit
    0; 2 with one line when the robot cannot run it). A reader that leaves early
    (``| head -2``) ends it quietly, with 0, as ``koolio-pm``."""
    try:
        code = _check_command(argv)
        sys.stdout.flush()  # here, not at exit: a closed pipe is seen inside the try
    except BrokenPipeError:
        # Python's documented recipe: stdout pointed at devnull, so the exit flush is quiet
        with contextlib.suppress(OSError, ValueError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    return code


def _check_command(argv: Sequence[str] | None) -> int:
    """:func:`main`'s work: the arguments, the check and the summary."""
    args = list(sys.argv[1:] if argv is None else argv)
    if args in (["-h"], ["--help"]):
        print(_USAGE)
        return 0
    if args[:1] == ["--"]:  # a file name that starts with '-'
        args = args[1:]
    elif args[:1] and args[0].startswith("-"):
        args = []
    if len(args) != 1:
        print(f"robot_runtime: error: {_USAGE.splitlines()[0]}", file=sys.stderr)
        return 2
    try:
        p = Policy.load(args[0])
    except PolicyError as exc:
        print(f"robot_runtime: error: {exc}", file=sys.stderr)
        return 2
    lay = p.layout
    keyword = " | ".join(f"{n}<<{s}" for n, s in zip(lay.names, lay.shifts))
    enc = p.encoder
    print(f"{args[0]}: {FORMAT} version {VERSION}, {len(p.rows)} states, {p.episodes} episodes")
    print(f"keyword ({lay.total_bits} bits): {keyword} | Action")
    print(f"sonar thresholds {enc.sonar_thresholds}, camera thresholds {enc.camera_thresholds}")
    if enc.sonar_pings != 1:
        print(f"each sonar read as the median of {enc.sonar_pings} pings (Encoder.median)")
    params = ", ".join(f"{k} {p.learner[k]}" for k in ALGORITHMS[p.algorithm])
    model = f", model of {len(p.model.pairs)} pairs" if p.model is not None else ""
    print(f"learner: {p.algorithm}" + (f" ({params})" if params else "") + model)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
