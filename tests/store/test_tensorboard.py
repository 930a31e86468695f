"""TensorBoard event files written directly (store/tensorboard.py), read back with
TensorBoard's own reader: a wrong byte of the format (a field number, a checksum, the
record framing) makes the reader refuse or lose the values, and these tests fail."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

from koolio_pymunk.store.errors import KoolioError
from koolio_pymunk.store.tensorboard import EventWriter, crc32c, read_scalars

REPO = Path(__file__).resolve().parents[2]


def tensorboard_scalars(logdir: Path) -> dict[str, list[tuple[int, float, float]]]:
    """Every scalar TensorBoard reads from ``logdir``: tag -> (step, value, wall time)."""
    acc = EventAccumulator(str(logdir), size_guidance={"scalars": 0})
    acc.Reload()
    return {
        tag: [(e.step, e.value, e.wall_time) for e in acc.Scalars(tag)]
        for tag in acc.Tags()["scalars"]
    }


def test_tensorboard_reads_the_scalars_steps_and_times_written(tmp_path) -> None:
    with EventWriter(tmp_path / "tb") as tb:
        for step in range(1, 6):
            tb.scalar("train/return", -12.5 * step, step, wall_time=1_700_000_000.25 + step)
        tb.scalars({"eval/goal_rate": 0.875, "eval/mean_steps": 223.0}, 5, wall_time=7.5)
        tb.scalar("big/step", 1.0, 2**40, wall_time=8.0)
    assert [p.name for p in (tmp_path / "tb").iterdir()] == [tb.path.name]
    assert tb.path.name.startswith("events.out.tfevents.")
    got = tensorboard_scalars(tmp_path / "tb")
    assert got == {
        "train/return": [(s, -12.5 * s, 1_700_000_000.25 + s) for s in range(1, 6)],
        "eval/goal_rate": [(5, 0.875, 7.5)],
        "eval/mean_steps": [(5, 223.0, 7.5)],
        "big/step": [(2**40, 1.0, 8.0)],
    }
    assert [(s.step, s.tag, s.value) for s in read_scalars(tb.path)][-1] == (2**40, "big/step", 1)


def test_values_are_float32_and_out_of_range_ones_are_infinite(tmp_path) -> None:
    with EventWriter(tmp_path) as tb:
        tb.scalar("x", 0.1, 1, wall_time=1.0)
        tb.scalar("x", 1e39, 2, wall_time=1.0)
        tb.scalar("x", -1e39, 3, wall_time=1.0)
    values = [v for _, v, _ in tensorboard_scalars(tmp_path)["x"]]
    assert values[0] == pytest.approx(0.1, rel=1e-7) and values[0] != 0.1  # a float32
    assert values[1:] == [float("inf"), float("-inf")]


def test_a_killed_writer_leaves_every_flushed_record(tmp_path) -> None:
    """The process is killed (``os._exit``: no close, no atexit) with records flushed
    and more waiting: TensorBoard reads the flushed ones, and nothing else."""
    code = (
        "import os, sys\n"
        "from koolio_pymunk.store.tensorboard import EventWriter\n"
        "tb = EventWriter(sys.argv[1])\n"
        "for s in range(3):\n"
        "    tb.scalar('loss', float(s), s, wall_time=1.0)\n"
        "tb.flush()\n"
        "tb.scalar('loss', 99.0, 3, wall_time=1.0)\n"  # waiting in memory: lost
        "os._exit(0)\n"
    )
    subprocess.run([sys.executable, "-c", code, str(tmp_path)], check=True, cwd=REPO)
    assert tensorboard_scalars(tmp_path) == {"loss": [(0, 0.0, 1.0), (1, 1.0, 1.0), (2, 2.0, 1.0)]}


def test_a_record_cut_short_ends_the_file_for_both_readers(tmp_path) -> None:
    with EventWriter(tmp_path) as tb:
        tb.scalar("a", 1.0, 1, wall_time=1.0)
        tb.scalar("a", 2.0, 2, wall_time=1.0)
    data = tb.path.read_bytes()
    tb.path.write_bytes(data[:-5])  # the last record torn, as by a full disk
    assert tensorboard_scalars(tmp_path) == {"a": [(1, 1.0, 1.0)]}
    assert [s.value for s in read_scalars(tb.path)] == [1.0]


def test_a_wrong_checksum_is_refused_in_one_line(tmp_path) -> None:
    with EventWriter(tmp_path) as tb:
        tb.scalar("a", 1.0, 1, wall_time=1.0)
    data = bytearray(tb.path.read_bytes())
    data[-1] ^= 0xFF
    tb.path.write_bytes(bytes(data))
    with pytest.raises(KoolioError, match="record data checksum wrong"):
        read_scalars(tb.path)


def test_crc32c_is_castagnoli_s() -> None:
    # RFC 3720's test vectors: 32 bytes of zeros, of 0xff, ascending
    assert crc32c(bytes(32)) == 0x8A9136AA
    assert crc32c(b"\xff" * 32) == 0x62A8AB43
    assert crc32c(bytes(range(32))) == 0x46DD794E


def test_a_writer_never_writes_over_a_file_and_names_its_errors(tmp_path) -> None:
    first, second = EventWriter(tmp_path), EventWriter(tmp_path)
    assert first.path != second.path  # the same second and process: still two files
    first.close()
    second.close()
    (tmp_path / "file").write_text("in the way")
    with pytest.raises(KoolioError, match=r"cannot create the folder .*file/tb: a part of the"):
        EventWriter(tmp_path / "file" / "tb")
    with pytest.raises(KoolioError, match="empty file name"):
        EventWriter("")
    with pytest.raises(KoolioError, match="closed"):
        first.scalar("a", 1.0, 1)
    with EventWriter(tmp_path) as tb, pytest.raises(KoolioError, match="tag: not a name"):
        tb.scalar("", 1.0, 1)
