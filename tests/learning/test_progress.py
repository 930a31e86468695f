"""``train``'s progress lines end with the time left (``eta 0:12``), from the rate of the
recent episodes; a clock given to :class:`Progress` makes the figures exact (no test
here waits or times anything)."""

from __future__ import annotations

import re

from koolio_pymunk.apps import cli
from koolio_pymunk.learning.episodes import EpisodeResult
from koolio_pymunk.learning.training import Progress, clock_time


def episode() -> EpisodeResult:
    return EpisodeResult(0, -5.0, 40, 1, "goal", False, 0.1, "201")


def progress_at(times: list[float]) -> Progress:
    """A Progress whose episodes ended at ``times`` (seconds after its start)."""
    ticks = iter(times)
    p = Progress(started=0.0, clock=lambda: next(ticks))
    for _ in times:
        p.add(episode())
    return p


def test_the_eta_is_the_episodes_left_at_the_recent_rate() -> None:
    p = progress_at([2.0, 4.0, 6.0, 8.0])  # one episode every 2 s
    assert p.eta_seconds(6) == 12.0
    assert p.line(4, 10, 0.1).endswith("  epsilon 0.100  eta 0:12")
    assert p.line(10, 10, 0.1).endswith("  eta 0:00")  # nothing left


def test_no_eta_from_the_first_episode_alone() -> None:
    """The first episode's time holds the start (a first run's 20 s compile): one episode
    gives no rate; two give the rate between their ends, the start left out."""
    assert progress_at([30.0]).eta_seconds(4) is None
    assert progress_at([30.0]).line(1, 5, 0.1).endswith("  eta -:--")
    assert progress_at([30.0, 30.5]).eta_seconds(4) == 2.0


def test_the_rate_is_the_recent_episodes_not_the_whole_run() -> None:
    """200 slow episodes (10 s each), then 100 fast ones (0.5 s): the time left follows
    the last 100, as a run that speeds up once the robot has learned."""
    slow = [10.0 * k for k in range(1, 201)]
    fast = [2000.0 + 0.5 * k for k in range(1, 101)]
    p = progress_at(slow + fast)
    assert p.eta_seconds(1000) == 1000 * 0.5
    assert p.line(300, 1300, 0.05).endswith("  eta 8:20")


def test_no_episode_yet_no_eta() -> None:
    p = Progress(started=0.0, clock=lambda: 0.0)
    assert p.eta_seconds(5) is None and p.line(0, 5, 0.1).endswith("  eta -:--")


def test_clock_time() -> None:
    assert [clock_time(s) for s in (0, 59.6, 61, 3599, 3600, 90061)] == [
        "0:00", "1:00", "1:01", "59:59", "1:00:00", "25:01:01",
    ]  # fmt: skip


def test_train_s_progress_lines_end_with_the_eta(tmp_path, capsys, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "tiny.yaml").write_text("episode: {max_steps: 30}\n")
    argv = ["train", "--arena", "room", "--config", "tiny.yaml", "--episodes", "3"]
    assert cli.main(argv) == 0
    lines = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("episode")]
    assert lines and re.fullmatch(r".*  epsilon \d\.\d{3}  eta \d+:\d\d", lines[-1])
    assert lines[-1].startswith("episode      3/3  training goal rate (exploring; last 3)")
