"""Ctrl-C twice (issue #21): a second Ctrl-C while the first is handled never ends in a
KeyboardInterrupt traceback; the table and the log stay in step, one line at most is
said, and the exit status is 130."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from koolio_pymunk.store import interrupts
from koolio_pymunk.store.episode_log import log_rows
from koolio_pymunk.store.interrupts import SafeInterrupt, deferred
from koolio_pymunk.store.qtable import load_qtable

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")


def ctrl_c() -> None:
    os.kill(os.getpid(), signal.SIGINT)
    time.sleep(0.01)  # the handler runs at the next bytecode boundary


def test_a_second_ctrl_c_is_ignored_while_the_first_is_handled():
    with SafeInterrupt() as guard:
        ctrl_c()
        assert guard.pending
        ctrl_c()  # within the grace: ignored, the first stays pending
        assert guard.pending and guard.ignored == 1
        with pytest.raises(KeyboardInterrupt):
            guard.check()
        for _ in range(3):  # being handled: every further Ctrl-C is ignored
            ctrl_c()
        assert guard.taken and guard.ignored == 4 and not guard.pending
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_command_ignores_ctrl_c_after_its_guard_took_one():
    """In a ``koolio-pm`` process (SIGINT is raise_once's) the interrupt a guard took is
    the one being handled: after the guard, closing the files and saying the line are not
    cut by another Ctrl-C or SIGTERM (one landed in a finalizer and printed a traceback)."""
    old_int = signal.signal(signal.SIGINT, interrupts.raise_once)
    old_term = signal.signal(signal.SIGTERM, signal.SIG_DFL)
    try:
        with pytest.raises(KeyboardInterrupt), SafeInterrupt() as guard:
            ctrl_c()
            guard.check()
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        assert signal.getsignal(signal.SIGTERM) is signal.SIG_IGN
        ctrl_c()  # ignored
        signal.signal(signal.SIGINT, interrupts.raise_once)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        with SafeInterrupt():  # a guard that took nothing gives the command's back
            pass
        assert signal.getsignal(signal.SIGINT) is interrupts.raise_once
        assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL
    finally:
        signal.signal(signal.SIGINT, old_int)
        signal.signal(signal.SIGTERM, old_term)


def test_a_second_ctrl_c_after_the_grace_interrupts_a_stuck_step(monkeypatch):
    monkeypatch.setattr(interrupts, "GRACE_SECONDS", 0.0)
    with SafeInterrupt() as guard:
        ctrl_c()
        with pytest.raises(KeyboardInterrupt):
            ctrl_c()  # the loop never checked: a stuck step
        ctrl_c()  # then it is being handled
        assert guard.taken and guard.ignored == 1


def test_a_ctrl_c_arriving_inside_the_first_ones_handler_is_not_a_stuck_step(monkeypatch):
    """Two signals in a row: the second may run the handler before the first one's
    returns; it must see the first pending since now (not raise as after the grace)."""
    guard = SafeInterrupt()
    real = signal.Signals
    nested: list[int] = []

    def signals(signum):
        if not nested:
            nested.append(1)
            guard._handle(signal.SIGINT, None)  # the second signal, inside the first
        return real(signum)

    monkeypatch.setattr(interrupts.signal, "Signals", signals)
    guard._handle(signal.SIGINT, None)
    assert nested and guard.pending and not guard.taken


def test_deferred_runs_the_block_whole_then_interrupts():
    done = []
    with pytest.raises(KeyboardInterrupt), deferred():
        ctrl_c()
        ctrl_c()
        done.append("saved")
    assert done == ["saved"]
    with deferred():
        done.append("quiet")
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_raise_once_ignores_ctrl_c_from_then_on():
    old = signal.signal(signal.SIGINT, interrupts.raise_once)
    try:
        with pytest.raises(KeyboardInterrupt):
            ctrl_c()
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        ctrl_c()  # ignored
    finally:
        signal.signal(signal.SIGINT, old)


def _in_step(folder: Path) -> None:
    """The log holds each of the table's episodes once, in order (interrupted rows aside)."""
    rows = log_rows(folder / "q.csv")
    done = [int(r["episode"]) for r in rows if r["outcome"] != "interrupted"]
    assert done == list(range(load_qtable(folder / "q.qtable").meta["episodes"]))


def _stopped_run(folder: Path, command: str, signals, extra=(), **popen) -> str:
    """Run ``koolio-pm command`` in ``folder`` until its log has a few rows, send
    ``signals`` (``(signal, seconds to wait before it)``, ...), and return its stderr once
    it has ended (exit status 128 + the first signal: 130 for SIGINT, 143 for SIGTERM; at
    most one line, the table and the log in step)."""
    (folder / "tiny.yaml").write_text("episode: {max_steps: 60}\n")
    argv = [sys.executable, "-m", "koolio_pymunk", command, "--arena", "room"]
    argv += ["--config", "tiny.yaml", "--qtable", "q.qtable", "--log", "q.csv"]
    argv += ["--episodes", "100000"] if command == "train" else ["--steps", "10000000"]
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "PYTHONPATH": str(ROOT)}
    p = subprocess.Popen(
        [*argv, *extra], cwd=folder, env=env, stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE, **popen,
    )  # fmt: skip
    try:
        deadline = time.time() + 120
        log = folder / "q.csv"
        while time.time() < deadline and not (log.exists() and log.stat().st_size > 200):
            time.sleep(0.02)
        assert p.poll() is None, p.communicate()[1]
        for sig, gap in signals:
            time.sleep(gap)
            p.send_signal(sig)
        err = p.communicate(timeout=120)[1].decode()
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 128 + int(signals[0][0]), err
    assert "Traceback" not in err and len(err.strip().splitlines()) <= 1, err
    _in_step(folder)
    return err


@pytest.mark.parametrize(
    ("command", "gaps"),
    [
        ("train", (0.0, 0.002, 0.002, 0.03)),
        ("view", (0.0, 0.01)),
    ],
)
def test_ctrl_c_twice_in_a_real_process(tmp_path, command, gaps):
    _stopped_run(tmp_path, command, [(signal.SIGINT, 0.0)] + [(signal.SIGINT, g) for g in gaps])


def test_terminate_as_interrupt_raises_keyboard_interrupt_and_restores() -> None:
    import os
    import signal

    from koolio_pymunk.store.interrupts import terminate_as_interrupt

    # The premise: SIGTERM's default action (a library run before, Ray's driver for one,
    # may have put its own handler there; the guard then leaves it alone).
    previous = signal.signal(signal.SIGTERM, signal.SIG_DFL)
    try:
        with pytest.raises(KeyboardInterrupt), terminate_as_interrupt():
            os.kill(os.getpid(), signal.SIGTERM)
            for _ in range(1000):  # the handler runs between bytecodes
                pass
        assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL
    finally:
        signal.signal(signal.SIGTERM, previous)


def _ignore_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def test_sigterm_saves_a_background_job_that_ignores_ctrl_c(tmp_path):
    """A job started with ``&`` from a script inherits SIGINT ignored; ``kill`` must still
    stop it at a safe point with the table saved (it ended by the signal, the table at 0
    episodes and the log ahead of it: newcomer audit)."""
    extra = ["--save-every", "100000"]
    _stopped_run(tmp_path, "train", [(signal.SIGTERM, 0.0)], extra, preexec_fn=_ignore_sigint)
    assert load_qtable(tmp_path / "q.qtable").meta["episodes"] > 0
