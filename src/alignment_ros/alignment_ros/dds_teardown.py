"""A ROS process's last step, bounded: its executor, node and context torn down within a deadline
that holds even while a native call holds the GIL.

Destroying a process's last node deletes its DDS participant, and Fast DDS 2.14.5 as the ROS
wheels build it can deadlock there. DomainParticipant::set_listener(nullptr) waits, with no
timeout, for a discovery callback in flight (a peer's endpoint coming or going, as when other
processes stop at the same moment). Its deadline, steady_clock::time_point::max(), becomes an
overflowed system_clock one in a libstdc++ built without pthread_cond_clockwait, so
pthread_cond_timedwait fails (EINVAL) without ever releasing the mutex that callback needs:
the main thread spins for ever, holding the GIL (docs/architecture.md, "A process's end").
No Python code runs then, not even a signal handler, so the deadline is kept by two
threads of C: faulthandler's, which prints every thread's stack, and a POSIX timer's
(timer_create, SIGEV_THREAD), which then ends the process with _exit(status).

A process calls :func:`shut_down` once its output is out (bag closed, stats written, its last
line printed) and gives the status it is about to exit with: what the deadline cuts is the
middleware's cleanup (its shared-memory files are left for shm_cleanup.py), nothing the user
asked for.
"""
from __future__ import annotations

import ctypes
import faulthandler
import signal
import sys
from typing import Any

import rclpy

from .signals import STOP_SIGNALS

TEARDOWN_TIMEOUT_S = 15.0
"""How long a teardown may take before the process ends without it (a healthy one takes well
under a second)."""
EXIT_AFTER_STACKS_S = 1.0
"""From the stacks' dump to the exit: time for faulthandler to write them."""

_CLOCK_MONOTONIC = 1     # <time.h>
_SIGEV_THREAD = 2        # <signal.h>


class _SigEvent(ctypes.Structure):
    """struct sigevent (Linux, 64 bytes): the value handed to the function, then the
    SIGEV_THREAD function and its thread attributes."""
    _fields_ = [('value', ctypes.c_void_p), ('signo', ctypes.c_int), ('notify', ctypes.c_int),
                ('function', ctypes.c_void_p), ('attributes', ctypes.c_void_p),
                ('pad', ctypes.c_byte * 32)]


class _TimeSpec(ctypes.Structure):
    """struct timespec."""
    _fields_ = [('sec', ctypes.c_long), ('nsec', ctypes.c_long)]


class _ITimerSpec(ctypes.Structure):
    """struct itimerspec: no interval (one expiry), then the expiry."""
    _fields_ = [('interval', _TimeSpec), ('value', _TimeSpec)]


class ExitDeadline:
    """Past `seconds`, every thread's stack on stderr, then the process ends with _exit(status):
    both from threads of C, so a main thread stuck in native code holding the GIL cannot stop
    them. `cancel` disarms both. Linux (glibc) only, as the project. faulthandler has one
    watchdog per process: arming this one replaces any other, and cancelling it clears it."""

    def __init__(self, seconds: float, status: int) -> None:
        self._libc = ctypes.CDLL(None, use_errno=True)
        faulthandler.dump_traceback_later(seconds, exit=False, file=sys.stderr)
        event = _SigEvent(value=status, notify=_SIGEV_THREAD,
                          function=ctypes.cast(self._libc._exit, ctypes.c_void_p).value)
        self._timer: ctypes.c_void_p | None = ctypes.c_void_p()
        if self._libc.timer_create(_CLOCK_MONOTONIC, ctypes.byref(event), ctypes.byref(self._timer)) != 0:
            faulthandler.cancel_dump_traceback_later()
            raise OSError(ctypes.get_errno(), 'timer_create failed')
        at = seconds + EXIT_AFTER_STACKS_S
        spec = _ITimerSpec(value=_TimeSpec(int(at), int((at % 1.0) * 1e9)))
        if self._libc.timer_settime(self._timer, 0, ctypes.byref(spec), None) != 0:
            self.cancel()
            raise OSError(ctypes.get_errno(), 'timer_settime failed')

    def cancel(self) -> None:
        """Neither the stacks nor the exit (a notification already under way still exits)."""
        faulthandler.cancel_dump_traceback_later()
        if self._timer is not None:
            self._libc.timer_delete(self._timer)
            self._timer = None


def say_once(exc: BaseException, text: str) -> None:
    """An error's line on stderr, once: printed before a teardown that might not end, and not
    again where the caller catches the error (which prints those raised before any node)."""
    if not getattr(exc, 'said', False):
        sys.stdout.flush()
        print(text, file=sys.stderr, flush=True)
        exc.said = True  # type: ignore[attr-defined]


def shut_down(node: Any, executor: Any = None, *, status: int = 0, signalled: bool = False,
              seconds: float = TEARDOWN_TIMEOUT_S) -> None:
    """executor.shutdown(), node.destroy_node(), rclpy.try_shutdown() within `seconds`, else the
    process ends with `status` (the one it is about to end with) after its stacks are printed.
    After a stop signal (`signalled`) a second SIGINT/SIGTERM ends the process at once: their
    default action, which needs no Python handler to run."""
    if signalled:
        for s in STOP_SIGNALS:
            signal.signal(s, signal.SIG_DFL)
    sys.stdout.flush()
    sys.stderr.flush()
    deadline: ExitDeadline | None = None
    try:
        deadline = ExitDeadline(seconds, status)
    except (OSError, ValueError, RuntimeError, AttributeError) as e:     # no stderr file, no timer
        print(f'teardown not bounded ({e})', file=sys.stderr, flush=True)
    try:
        if executor is not None:
            executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
    finally:
        if deadline is not None:
            deadline.cancel()
