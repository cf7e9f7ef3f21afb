"""Node processes forked from a launcher that has imported their code once.

Started through scripts/start_node.sh, every node's interpreter imports numpy, scipy, rclpy and
the project again, all at once on the machine's cores: on two cores that was about 2 s of a
run's first message. A fork begins where those imports end. The child is the process
start_node.sh would have started: its own session, the run's domain lock, SIGTERM when the
launcher dies, stdout and stderr to its log, the node's console-script command line (what ``ps``
and the benchmarks read), the same arguments and environment, the node's own exit status.

A fork copies one thread and the memory of the others: it is safe only from a process that runs
no other thread, so no DDS participant (:func:`unsafe_reason`).
"""
from __future__ import annotations

import ctypes
import gc
import importlib
import inspect
import io
import os
import signal
import subprocess
import sys
import threading
import time
import traceback
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import IO

import setproctitle

LTTNG_LISTENERS = 2
"""Threads LTTng-UST starts in every process that loads it (rcl's tracepoints: importing rclpy):
its session-daemon listeners. They hold no lock over a fork made between LTTng's own fork hooks
(what its liblttng-ust-fork.so does for a program that forks), and the child starts its own."""


def _lttng() -> ctypes.CDLL | None:
    """The LTTng-UST library this process has loaded, if any."""
    for line in Path('/proc/self/maps').read_text().splitlines():
        path = line.split(None, 5)[-1]
        name = Path(path).name
        if name.startswith('liblttng-ust') and 'tracepoint' not in name and '.so' in name:
            return ctypes.CDLL(path)
    return None


def unsafe_reason() -> str | None:
    """Why this process may not fork a node (None: it may). Any thread but the main one and
    LTTng-UST's listeners (a DDS participant's, a Python thread) would be copied half-way."""
    threads = len(os.listdir('/proc/self/task'))
    allowed = 1 + (LTTNG_LISTENERS if _lttng() is not None else 0)
    if threading.active_count() > 1 or threads > allowed:
        return f'{threads} threads run in the launcher (at most {allowed} may)'
    return None


def entry_point(name: str) -> Callable[[], object]:
    """A node package's console-script function (``NAME = NAME.node:main`` in its setup.py),
    imported here, in the launcher, so that its children inherit the imports."""
    return importlib.import_module(f'{name}.node').main


SIGSET_BYTES = 128    # sizeof(sigset_t), glibc


class ForkedProcess:
    """A forked child, with the part of subprocess.Popen's interface a launcher uses."""

    def __init__(self, pid: int, args: list[str]) -> None:
        self.pid = pid
        self.args = args
        self.returncode: int | None = None

    def poll(self) -> int | None:
        if self.returncode is None:
            pid, status = os.waitpid(self.pid, os.WNOHANG)
            if pid:
                self.returncode = os.waitstatus_to_exitcode(status)
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        deadline = None if timeout is None else time.monotonic() + timeout
        pause = 0.001
        while self.poll() is None:
            if deadline is not None and time.monotonic() >= deadline:
                raise subprocess.TimeoutExpired(self.args, timeout or 0.0)
            time.sleep(pause)
            pause = min(2.0 * pause, 0.05)
        assert self.returncode is not None
        return self.returncode


MODULE_TABLE_PROBE = '<module table probe>'
"""A file name no module has (inspect.getmodule's `_filename`): looking it up walks sys.modules."""


def fill_module_table() -> None:
    """inspect's table of the imported modules' files, filled before a fork for the child to
    inherit: rclpy's logger looks its caller up through inspect at every call, and the first
    lookup in a process walks every module imported (~50 ms of CPU with the nodes' imports, in
    each node at its first log line: the ship's is on the way to the run's first message). A
    lookup of a file the table lacks makes inspect add every module imported since its last walk
    (one of a file it has returns at once, and a child would lack what was imported after the
    first fork)."""
    inspect.getmodule(None, _filename=MODULE_TABLE_PROBE)


def freeze_launcher() -> None:
    """The launcher's objects frozen before a fork: never collected (nor finalized) in the child.
    They are collected before the first fork only, and stay frozen for the next (a collection
    of a launcher that has imported the nodes' code takes ~60 ms, each fork's had been on the
    last node's start-up) until :func:`thaw_launcher`; what a later fork adds is frozen with
    them."""
    if not gc.get_freeze_count():
        gc.collect()
    gc.freeze()


def thaw_launcher() -> None:
    """After the last fork: the launcher's objects collected as any others again."""
    gc.unfreeze()


def fork_node(entry: Callable[[], object], argv: list[str], log: IO, keep_fds: Iterable[int],
              in_child: Callable[[], None]) -> ForkedProcess:
    """Fork a child that runs `entry` as the console script would with command line `argv`
    (argv[0] the script), output to `log`, in a session of its own, keeping only the
    descriptors `keep_fds` (and 0-2); `in_child` runs first in the child (PR_SET_PDEATHSIG)."""
    reason = unsafe_reason()
    if reason is not None:
        raise RuntimeError(f'cannot fork a node: {reason}')
    for stream in (sys.stdout, sys.stderr):
        stream.flush()
    fill_module_table()
    freeze_launcher()
    lttng = _lttng()
    signals = ctypes.create_string_buffer(SIGSET_BYTES)
    if lttng is not None:
        lttng.ust_before_fork(signals)
    pid = os.fork()
    if pid:
        if lttng is not None:
            lttng.ust_after_fork_parent(signals)
        return ForkedProcess(pid, argv)
    code = 1
    try:
        if lttng is not None:
            lttng.ust_after_fork_child(signals)
        for s in (signal.SIGINT, signal.SIGTERM):
            signal.signal(s, signal.SIG_DFL)
        os.setsid()
        in_child()
        os.dup2(log.fileno(), 1)
        os.dup2(log.fileno(), 2)
        _close_fds_except({0, 1, 2, *keep_fds})
        sys.stdout = _text(1)
        sys.stderr = _text(2)
        sys.argv = list(argv)
        setproctitle.setproctitle(' '.join([sys.executable, *argv]))
        setproctitle.setthreadtitle(Path(argv[0]).name)    # comm: what top shows, as for a script
        code = _exit_code(entry())
    except SystemExit as e:
        code = _exit_code(e.code)
    except BaseException:
        traceback.print_exc()
    finally:
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except Exception:  # noqa: BLE001 - nothing left to report it to
                pass
        os._exit(code)     # never back into the launcher's frames, finally blocks or atexit


def _exit_code(value: object) -> int:
    """sys.exit's rule: None is 0, an int itself, anything else printed and 1."""
    if value is None:
        return 0
    if isinstance(value, int):
        return value
    print(value, file=sys.stderr)
    return 1


def _text(fd: int) -> io.TextIOWrapper:
    """An unbuffered-like text stream on fd (PYTHONUNBUFFERED, as the exec'd node has)."""
    return io.TextIOWrapper(io.FileIO(fd, 'w', closefd=False), line_buffering=True,
                            write_through=True)


def _close_fds_except(keep: set[int]) -> None:
    lo = 0
    for fd in sorted(keep):
        if fd > lo:
            os.closerange(lo, fd)
        lo = max(lo, fd + 1)
    os.closerange(lo, os.sysconf('SC_OPEN_MAX'))
