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
import json
import sys
import tempfile
from pathlib import Path

TOOLS = Path(__file__).resolve().parent
if str(TOOLS) not in sys.path:
    sys.path.insert(0, str(TOOLS))

from bench import end_to_end, machine  # noqa: E402
from irsim_world import (  # noqa: E402
    COLLISIONS,
    drive_irsim,
    hallway_world,
    irsim_missing,
    world_yaml,
)


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
