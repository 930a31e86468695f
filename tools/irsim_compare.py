"""IR-SIM in koolio-pymunk's hallway, timed in the same run as ``koolio-pm train``.

IR-SIM (``pip install ir-sim``, shapely-based) is an open 2D robot simulator configured
by a YAML world file. This tool writes the world file equivalent to the built-in
``hallway`` into a temporary folder (:func:`hallway_world`: the arena's walls, one
differential-drive robot of koolio's radius at the arena's start, an 88-beam 2D lidar
all round reaching as far as koolio's sonar), drives the robot with random picks of
koolio's five actions for ``--steps`` steps headless (``headless=True``: no figure),
reading the lidar scan after every step, and times it per wall second and per CPU second
of this process (``time.process_time``). In the same process, first, it times
``koolio-pm train`` end to end (the default save at every episode) with
``tools/bench.py``'s :func:`end_to_end`, and prints the rates and their ratio. Figures
only: nothing is asserted.

Units: IR-SIM takes metres; the arena's inches are converted (1 in = 0.0254 m). One
IR-SIM step is one action: ``step_time`` 1 s, Forward / Reverse at 12 in/s, RotateLeft /
RotateRight at 30 degrees/s, Stop at 0 (``actions`` in the default configuration).

Two collision modes, both timed unless ``--collision`` names one:

* ``stop`` (IR-SIM's default): the walls as drawn, one closed line; a robot that
  touches one stops for good, so the run resets the world then (an episode end) and
  counts the resets;
* ``contact``: the wall pushes the robot back out and it drives on, as koolio's robot
  does; each wall is a slab (:data:`SLAB`) behind its line, since a robot whose centre
  steps past a wall that is only a line is pushed out on the far side.

    .venv/bin/pip install -e '.[compare]'     # ir-sim 2.12.0
    .venv/bin/python tools/irsim_compare.py                      # about 40 s
    .venv/bin/python tools/irsim_compare.py --collision stop --out irsim.json
    .venv/bin/python tools/irsim_compare.py --write-world hallway_irsim.yaml  # the file only

Without ir-sim it says in one line how to install it and exits 2 (``--write-world``
needs only koolio-pymunk).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import sys
import tempfile
from pathlib import Path

import yaml

TOOLS = Path(__file__).resolve().parent
if str(TOOLS) not in sys.path:
    sys.path.insert(0, str(TOOLS))

from bench import Timer, end_to_end, machine, rates  # noqa: E402

INCH = 0.0254
"""Metres per inch."""
IRSIM_VERSION = "2.12.0"
INSTALL = "pip install -e '.[compare]'"
"""The command that installs ir-sim (the ``compare`` extra)."""
COLLISIONS = ("stop", "contact")
SLAB = 24.0
"""Thickness of a wall in ``contact`` mode, inches: more than a move (12 in), so that a
robot touching a wall cannot step its centre past the wall's line and be pushed out on
the far side, as it is through a wall that is only a line."""


def hallway_world(collision: str = "stop", arena: str = "hallway") -> dict:
    """The IR-SIM world (the YAML file's mapping, in metres) equivalent to ``arena``.

    >>> w = hallway_world()
    >>> w["robot"][0]["shape"], w["robot"][0]["sensors"][0]["number"]
    ({'name': 'circle', 'radius': 0.254}, 88)
    """
    from koolio_pymunk.store.config import load_config
    from koolio_pymunk.world.arena import load_arena

    config = load_config(None)
    radius = config.robot.radius
    sonar = config.sensors.sonar
    a = load_arena(arena, radius).to_world()
    xmin, ymin, xmax, ymax = a.bounds()
    margin = 2 * radius
    if collision == "stop":  # the walls as drawn: one closed line
        obstacles = [_line([*a.walls, a.walls[0]])]
        obstacles += [_line([*poly, poly[0]]) for poly in a.obstacles]
    else:  # a wall the robot is pushed out of: a slab behind each segment
        obstacles = [_polygon(q) for q in wall_slabs(a.walls, SLAB)]
        obstacles += [_polygon(poly) for poly in a.obstacles]
    for ob in obstacles:  # IR-SIM places an object at [1, 1, 0] unless told
        ob.update(kinematics={"name": "static"}, state=[0.0, 0.0, 0.0])
    heading = math.radians(a.start.heading_deg or 0.0)
    beams = sonar.sub_arcs * len(sonar.sonar_sensors_deg)
    move = round(config.actions.move_action_distance * INCH, 6)
    turn = round(math.radians(config.actions.rotate_action_arc_deg), 9)
    lidar = {
        "name": "lidar2d",
        "range_min": 0.0,
        "range_max": round((sonar.max_range + radius) * INCH, 6),  # from the centre
        "angle_range": round(2 * math.pi * (beams - 1) / beams, 9),  # 88 beams, 360/88 deg apart
        "number": beams,
        "noise": False,
    }
    robot = {
        "kinematics": {"name": "diff"},
        "shape": {"name": "circle", "radius": round(radius * INCH, 6)},
        "state": [*_metres([a.start.at])[0], heading],
        "vel_min": [-move, -turn],
        "vel_max": [move, turn],
        "sensors": [lidar],
    }
    world = {
        "width": round((xmax - xmin + 2 * margin) * INCH, 6),
        "height": round((ymax - ymin + 2 * margin) * INCH, 6),
        "offset": _metres([(xmin - margin, ymin - margin)])[0],
        "step_time": 1.0,
        "sample_time": 1.0,
        "collision_mode": collision,
    }
    return {"world": world, "robot": [robot], "obstacle": obstacles}


def wall_slabs(ring, thickness: float) -> list[list[tuple[float, float]]]:
    """A quadrilateral of ``thickness`` behind each edge of the closed ``ring`` (on the
    side away from the inside).

    >>> wall_slabs([(0, 0), (10, 0), (10, 10), (0, 10)], 2)[0]
    [(0, 0), (0.0, -2.0), (10.0, -2.0), (10, 0)]
    """
    from koolio_pymunk.world.geometry import is_ccw

    n = len(ring)
    side = 1.0 if is_ccw(tuple(ring)) else -1.0  # counter-clockwise: outside on the right
    out = []
    for i in range(n):
        (x0, y0), (x1, y1) = ring[i], ring[(i + 1) % n]
        length = math.hypot(x1 - x0, y1 - y0)
        nx, ny = side * (y1 - y0) / length * thickness, -side * (x1 - x0) / length * thickness
        out.append([(x0, y0), (x0 + nx, y0 + ny), (x1 + nx, y1 + ny), (x1, y1)])
    return out


def _line(points) -> dict:
    return {"shape": {"name": "linestring", "vertices": _metres(points)}}


def _polygon(points) -> dict:
    return {"shape": {"name": "polygon", "vertices": _metres(points)}}


def _metres(points) -> list[list[float]]:
    return [[round(x * INCH, 6), round(y * INCH, 6)] for x, y in points]


def world_yaml(world: dict, name: str = "hallway") -> str:
    """The world file's text."""
    head = f"# Generated by tools/irsim_compare.py from koolio-pymunk's {name} (metres).\n"
    return head + yaml.safe_dump(world, sort_keys=False, default_flow_style=None)


def actions(world: dict) -> list:
    """Koolio's five actions as IR-SIM velocity commands (one step each): Stop,
    RotateLeft, RotateRight, Forward, Reverse."""
    import numpy as np

    move, turn = world["robot"][0]["vel_max"]
    pairs = [(0.0, 0.0), (0.0, turn), (0.0, -turn), (move, 0.0), (-move, 0.0)]
    return [np.array([[v], [w]]) for v, w in pairs]


def irsim_missing() -> str | None:
    """None if ir-sim imports, else the one line saying how to install it."""
    try:
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            import irsim  # noqa: F401  (prints its matplotlib back-end attempts)
    except ImportError:
        return f"tools/irsim_compare.py: ir-sim is not installed: {INSTALL}"
    return None


def drive_irsim(path: Path, steps: int, seed: int = 0, warm: int = 50) -> dict:
    """Random actions for ``steps`` steps in the world file ``path``, headless, reading the
    lidar scan after each step; a robot stopped by a collision resets the world."""
    import irsim
    import numpy as np

    world = yaml.safe_load(path.read_text())
    acts = actions(world)
    env = irsim.make(str(path), headless=True, log_level="ERROR", seed=seed)
    rng = np.random.default_rng(seed)
    picks = rng.integers(0, len(acts), warm + steps)
    resets = 0
    for k in picks[:warm]:  # first calls (imports, caches) not timed
        env.step(acts[k])
        if env.done():
            env.reset()
    env.reset()
    with Timer() as t:
        for k in picks[warm:]:
            env.step(acts[k])
            env.get_lidar_scan()
            if env.done():
                env.reset()
                resets += 1
    out = rates(steps, t)
    out.update(resets=resets, collision=world["world"]["collision_mode"], version=_version())
    env.end(0)
    return out


def _version() -> str:
    import irsim

    return irsim.__version__


def koolio_train(episodes: int, folder: Path) -> dict:
    """``koolio-pm train`` end to end (bench.py's row), after a short warm-up run in its
    own folder (the compiled kernels' first calls)."""
    (folder / "warm").mkdir()
    (folder / "timed").mkdir()
    end_to_end(2, folder / "warm")
    return end_to_end(episodes, folder / "timed")


def compare(steps: int, episodes: int, collisions: list[str], folder: Path) -> dict:
    """Both timings in this process, and the ratio of their per-CPU-second rates:
    ``koolio-pm train`` first, then IR-SIM in each collision mode."""
    out: dict = {"koolio_train": koolio_train(episodes, folder), "irsim": []}
    for collision in collisions:
        path = folder / f"hallway_irsim_{collision}.yaml"
        path.write_text(world_yaml(hallway_world(collision)))
        r = drive_irsim(path, steps)
        r["ratio_cpu"] = round(out["koolio_train"]["per_cpu_s"] / max(1, r["per_cpu_s"]), 1)
        out["irsim"].append(r)
    return out


def row(name: str, r: dict, extra: str = "") -> str:
    return (
        f"  {name:<40} {r['per_wall_s']:>10,} {r['per_cpu_s']:>10,}   "
        f"{r['steps']:>8,} steps {r['cpu_s']:>6.2f} CPU s  {extra}"
    )


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=10_000, help="IR-SIM steps (10,000)")
    p.add_argument("--episodes", type=int, default=600, help="koolio-pm train episodes (600)")
    p.add_argument(
        "--collision",
        choices=COLLISIONS,
        nargs="+",
        default=list(COLLISIONS),
        help="IR-SIM's collision modes to time (both)",
    )
    p.add_argument("--out", help="write the figures as JSON here")
    p.add_argument("--write-world", metavar="FILE", help="write the world file and stop")
    args = p.parse_args(argv)
    if args.write_world:
        world = hallway_world(args.collision[0])
        Path(args.write_world).write_text(world_yaml(world))
        return 0
    missing = irsim_missing()
    if missing:
        print(missing, file=sys.stderr)
        return 2
    m = machine()
    print(f"IR-SIM and koolio-pm train, same run: {m['cpus']} CPUs, load {m['load_average']}")
    with tempfile.TemporaryDirectory() as tmp:
        out = compare(args.steps, args.episodes, args.collision, Path(tmp))
    k = out["koolio_train"]
    print(f"  {'':<40} {'per wall s':>10} {'per CPU s':>10}")
    print(row("koolio-pm train end to end (saves)", k, f"{k['episodes']} episodes"))
    for i in out["irsim"]:
        resets = f", {i['resets']} resets" if i["collision"] == "stop" else ""
        name = f"IR-SIM {i['version']}, collision {i['collision']}"
        print(row(name, i, f"koolio-pm train x{i['ratio_cpu']} (CPU){resets}"))
    if args.out:
        out["machine"] = m
        Path(args.out).write_text(json.dumps(out, indent=2) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
