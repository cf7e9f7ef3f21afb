"""SIGINT/SIGTERM for the processes of a run: a flag a node's or the recorder's main loop polls;
an exception that ends a launcher's run (once, and never inside its bookkeeping); and children
that die with their launcher. No heavy imports: the recorder and the player start in well
under a second."""
from __future__ import annotations

import os
import signal
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
PR_SET_PDEATHSIG = 1    # <linux/prctl.h>


def stop_on_signals() -> dict[str, bool]:
    """SIGINT/SIGTERM set the returned dict's 'signal' flag (for a main loop to poll)."""
    stop = {'signal': False}

    def on_signal(signum: int, frame: object) -> None:
        stop['signal'] = True
    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)
    return stop


class Interrupted(BaseException):
    """A launcher got SIGINT or SIGTERM; its exit status is 128 + the signal number (130, 143).
    A BaseException, as KeyboardInterrupt: no `except Exception` on the way swallows it."""

    def __init__(self, signum: int) -> None:
        self.signum = signum
        self.name = signal.Signals(signum).name
        self.exit_code = 128 + signum
        super().__init__(f'stopped by {self.name}')


class SignalGuard:
    """The first SIGINT/SIGTERM raises :class:`Interrupted` in the main thread, at once or, inside
    :meth:`deferred` (starting a process and registering it), on leaving it; later ones are
    ignored, so the launcher's stopping of its processes is never cut short."""

    def __init__(self) -> None:
        self.signum: int | None = None
        self._depth = 0
        self._pending = False
        self._ignoring = False
        self._old: dict[int, Any] = {}

    def _on_signal(self, signum: int, frame: object) -> None:
        if self.signum is not None or self._ignoring:
            return
        self.signum = signum
        if self._depth:
            self._pending = True
            return
        raise Interrupted(signum)

    def install(self) -> SignalGuard:
        for s in STOP_SIGNALS:
            self._old[s] = signal.signal(s, self._on_signal)
        return self

    def restore(self) -> None:
        for s, h in self._old.items():
            signal.signal(s, h)
        self._old.clear()

    def ignore(self) -> None:
        """From now on signals do nothing (the launcher's bounded end of a run goes on)."""
        self._ignoring = True

    @contextmanager
    def deferred(self) -> Iterator[None]:
        self._depth += 1
        try:
            yield
        finally:
            self._depth -= 1
            if not self._depth and self._pending:
                self._pending = False
                raise Interrupted(self.signum or signal.SIGINT)

    def __enter__(self) -> SignalGuard:
        return self.install()

    def __exit__(self, *exc: object) -> None:
        self.restore()


def die_with_parent(sig: int = signal.SIGTERM) -> Callable[[], None]:
    """A ``preexec_fn`` for subprocess.Popen: the child gets `sig` when its parent dies, even by
    SIGKILL (Linux ``prctl(PR_SET_PDEATHSIG)``, kept across exec). The kernel sends it when the
    *thread* that started the child ends: start children from the main thread only. A parent
    that died before the call (the child would be orphaned already) fails the start."""
    import ctypes
    prctl = ctypes.CDLL(None, use_errno=True).prctl
    parent = os.getpid()

    def preexec() -> None:
        if prctl(PR_SET_PDEATHSIG, int(sig), 0, 0, 0) != 0:
            raise OSError(ctypes.get_errno(), 'prctl(PR_SET_PDEATHSIG) failed')
        if os.getppid() != parent:
            raise OSError('the launcher died while starting this process')
    return preexec
