"""Ctrl-C at a safe point: an interrupt never lands between two writes that belong together.

Training saves the Q-table and then appends the episode's log row; the window does the
same. :class:`SafeInterrupt` turns SIGINT into a flag that the loops check between steps,
so the files are always in step when a run stops. Once a Ctrl-C is taken, the run
handles it (folds the unfinished episode in, saves, logs it): further Ctrl-Cs are
ignored until that is done, so a second one never cuts the handling short. Code that
writes after an interrupt outside a guard (the window's last save) runs under
:func:`deferred`.

SIGTERM (``kill``, a job scheduler's stop) is taken the same way while a guard is active:
the run stops at its next safe point, saves and exits, as on Ctrl-C; also when SIGINT is
ignored (a background job of a script) or someone else's.

Only the first of two quick Ctrl-Cs counts: a second one interrupts at once only when the
first has waited :data:`GRACE_SECONDS` without being taken (a step that does not end),
never while a save and its log row are being written (milliseconds).
"""

from __future__ import annotations

import contextlib
import signal
import threading
import time
from collections.abc import Iterator
from typing import Any

#: Seconds a pending Ctrl-C may wait for the loop before a second one interrupts at once.
GRACE_SECONDS = 2.0
#: The signal of the last interrupt taken (:func:`exit_status`).
_taken = signal.SIGINT


def exit_status() -> int:
    """A stopped command's exit status, as a shell reports a process ended by the
    signal: 128 + the signal of the interrupt taken, 130 for Ctrl-C (SIGINT), 143 for
    SIGTERM.

    >>> exit_status() in (130, 143)
    True
    """
    return 128 + int(_taken)


def forget_signal() -> None:
    """No interrupt taken yet (a command starting: :func:`exit_status` says 130)."""
    _note(signal.SIGINT)


def _note(signum: int) -> None:
    global _taken
    _taken = signal.Signals(signum)


def raise_once(signum: int, frame: Any) -> None:
    """The SIGINT handler of a ``koolio-pm`` process (:func:`command_line`): the first
    Ctrl-C raises ``KeyboardInterrupt``; from then on Ctrl-C is ignored, since that one
    is being handled (the files put in step, one line said, exit status 130)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _note(signum)
    raise KeyboardInterrupt


def command_line() -> None:
    """Make Ctrl-C :func:`raise_once` for this process (main thread only)."""
    main = threading.current_thread() is threading.main_thread()
    if main and signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        signal.signal(signal.SIGINT, raise_once)


@contextlib.contextmanager
def terminate_as_interrupt() -> Iterator[None]:
    """While active, SIGTERM raises ``KeyboardInterrupt`` as a first Ctrl-C does (main
    thread only; elsewhere nothing changes). For a loop whose Ctrl-C path already stops
    cleanly (a sweep: its finished runs saved, its workers stopped)."""
    main = threading.current_thread() is threading.main_thread()
    ours = main and signal.getsignal(signal.SIGTERM) is signal.SIG_DFL
    if ours:
        signal.signal(signal.SIGTERM, _terminate)
    try:
        yield
    finally:
        if ours:  # ours, or ignored by ours once taken
            signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _terminate(signum: int, frame: Any) -> None:
    signal.signal(signal.SIGTERM, signal.SIG_IGN)  # one stop at a time, as raise_once
    _note(signum)
    raise KeyboardInterrupt


def _replaceable(handler: Any) -> bool:
    """Python's own SIGINT handler, or :func:`raise_once` (a guard may stand in for it)."""
    return handler is signal.default_int_handler or handler is raise_once


class SafeInterrupt:
    """Ctrl-C at a safe point: while active, SIGINT only sets :attr:`pending`; the loops
    check it between steps and raise ``KeyboardInterrupt`` there, so an interrupt never
    lands between saving the table and writing the episode's log row.

    After :meth:`check` has raised (the interrupt is being handled: the unfinished episode
    folded in and saved), every further Ctrl-C is ignored while the guard is active. A
    second Ctrl-C before the first is taken interrupts at once only if the first has
    waited :data:`GRACE_SECONDS` (the loop is stuck in a step); sooner, it is ignored.
    Does nothing outside the main thread (signals go there only).

    >>> with SafeInterrupt() as guard:
    ...     guard.pending
    False
    """

    def __init__(self) -> None:
        self.pending = False
        self.taken = False
        """True once an interrupt was raised: it is being handled."""
        self.ignored = 0
        """Ctrl-Cs ignored (while one was pending or being handled)."""
        self._since = 0.0
        self._previous: Any = None
        self._previous_term: Any = None
        self._installed = False
        self.signal = signal.SIGINT
        """The signal of the interrupt taken: SIGINT (Ctrl-C) or SIGTERM."""

    def _handle(self, signum: int, frame: Any) -> None:
        if self.taken:
            self.ignored += 1
            return
        if self.pending:
            if time.monotonic() - self._since < GRACE_SECONDS:
                self.ignored += 1
                return
            self.pending = False
            self.taken = True
            raise KeyboardInterrupt
        # the time first: a second signal can run this handler again before this one
        # returns, and must then find the first one pending since now, not since long ago
        self._since = time.monotonic()
        self.signal = signal.Signals(signum)
        _note(signum)
        self.pending = True

    def check(self) -> None:
        """Raise ``KeyboardInterrupt`` if a Ctrl-C is pending (it is then being handled:
        further Ctrl-Cs are ignored while the guard is active)."""
        if self.pending:
            self.pending = False
            self.taken = True
            raise KeyboardInterrupt

    def __enter__(self) -> SafeInterrupt:
        if threading.current_thread() is threading.main_thread():
            self._previous = signal.getsignal(signal.SIGINT)
            if _replaceable(self._previous):  # only Python's own, or the command line's
                signal.signal(signal.SIGINT, self._handle)
                self._installed = True
            # A stop request takes the same path, whoever handles SIGINT: a job started in
            # the background of a script has SIGINT ignored, and `kill` must still save.
            self._previous_term = signal.getsignal(signal.SIGTERM)
            if self._previous_term is signal.SIG_DFL:
                signal.signal(signal.SIGTERM, self._handle)
        return self

    def __exit__(self, *exc: object) -> None:
        # In a command (SIGINT was raise_once's) the interrupt this guard took is the
        # process's one: what follows (the files closed, the line said) is its handling,
        # and a later Ctrl-C or SIGTERM is ignored, as raise_once ignores its second. A
        # caller of the library gets its own handlers back.
        handled = self.taken and self._previous is raise_once
        if self._installed:
            signal.signal(signal.SIGINT, signal.SIG_IGN if handled else self._previous)
            self._installed = False
        if self._previous_term is signal.SIG_DFL:
            signal.signal(signal.SIGTERM, signal.SIG_IGN if handled else signal.SIG_DFL)
            self._previous_term = None


@contextlib.contextmanager
def deferred() -> Iterator[None]:
    """Run the block without being cut by Ctrl-C (e.g. the last save and its log row
    after an interrupt). A Ctrl-C during the block raises ``KeyboardInterrupt`` after it,
    unless the block is already ending in an exception. Outside the main thread, or when
    SIGINT has a handler of someone else's, the block runs as it is.

    >>> with deferred():
    ...     1 + 1
    2
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.getsignal(signal.SIGINT)
    if not _replaceable(previous):
        yield
        return
    seen: list[int] = []
    signal.signal(signal.SIGINT, lambda signum, frame: seen.append(signum))
    failed = True
    try:
        yield
        failed = False
    finally:
        signal.signal(signal.SIGINT, previous)
    if seen and not failed:
        raise KeyboardInterrupt


def ignore_from_now() -> None:
    """Ignore Ctrl-C for the rest of the process (the command has ended and said so; a
    Ctrl-C while Python shuts down would otherwise end it by the signal, exit status
    -2, instead of the status the command chose). Main thread only."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)
