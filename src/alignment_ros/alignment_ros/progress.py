"""Live progress of a long job over simulation time (a graph run, a replay, play, record, an
import): one updating line on a terminal (tqdm), a plain line every ``interval_s`` wall seconds
otherwise (CI logs), nothing when quiet. It shows the simulation time reached of the planned
duration, the real-time factor, the messages so far, the ETA and, when given, the filter's
misalignment estimate with its 1-sigma. The final line (:meth:`Progress.close`) carries the
simulation time the job reached. It never touches the data: callers feed it what they saw.

API (stable; the importer calls it too)::

    from alignment_ros.progress import Progress
    p = Progress('import', total_s=600.0, start_s=t0_s, quiet=args.quiet)   # stream: sys.stderr
    for ...:
        p.update(sim_s, messages=n)                          # as often as you like: rate-limited
        p.update(sim_s, estimate=(mu_rad, sigma_rad))        # (3,) and (3,) arrays, rad
        p.update(sim_s, note='Mach 0.81 \u00b1 0.01')            # any short text, shown last
    p.close(sim_s, messages=n)                               # the final line

``mode`` ('auto' default: 'tty' when the stream is a terminal, else 'plain'; 'quiet' when
``quiet``) can be forced. ``total_s`` None: no percentage nor ETA. Time arguments are absolute
simulation seconds; shown relative to ``start_s``.
"""
from __future__ import annotations

import math
import sys
import threading
import time
from typing import TextIO

import numpy as np
from tqdm import tqdm

from .state_layout import ARCMIN_PER_RAD

PLAIN_INTERVAL_S = 10.0
TTY_INTERVAL_S = 0.2
MODES = ('auto', 'tty', 'plain', 'quiet')


def choose_mode(stream: TextIO, quiet: bool = False, mode: str = 'auto') -> str:
    if mode not in MODES:
        raise ValueError(f'progress mode {mode!r} is not one of {", ".join(MODES)}')
    if quiet:
        return 'quiet'
    if mode != 'auto':
        return mode
    isatty = getattr(stream, 'isatty', None)
    return 'tty' if isatty is not None and isatty() else 'plain'


def _duration(seconds: float) -> str:
    if not math.isfinite(seconds):
        return '?'
    s = int(round(seconds))
    return f'{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}' if s >= 3600 else f'{s // 60}:{s % 60:02d}'


class Progress:
    """Progress of one job; thread-safe (a subscriber thread may feed it)."""

    def __init__(self, label: str, total_s: float | None = None, start_s: float = 0.0, *,
                 quiet: bool = False, mode: str = 'auto', stream: TextIO | None = None,
                 interval_s: float | None = None) -> None:
        self.label = label
        self.total_s = total_s
        self.start_s = start_s
        self.stream = stream if stream is not None else sys.stderr
        self.mode = choose_mode(self.stream, quiet, mode)
        self.interval_s = interval_s if interval_s is not None else (
            TTY_INTERVAL_S if self.mode == 'tty' else PLAIN_INTERVAL_S)
        self.sim_s: float | None = None
        self.messages: int | None = None
        self.estimate: tuple[np.ndarray, np.ndarray | None] | None = None
        self.note: str | None = None
        self._first: tuple[float, float] | None = None     # (wall, sim) of the first update
        self._advanced = 0.0                                # wall time sim_s last moved on
        self._last_shown = -math.inf
        self._lock = threading.Lock()
        self._closed = False
        self._bar: tqdm | None = None
        if self.mode == 'tty':
            self._bar = tqdm(total=total_s, file=self.stream, desc=label, dynamic_ncols=True,
                             bar_format='{percentage:3.0f}%|{bar:20}| {desc}' if total_s else '{desc}',
                             mininterval=0, leave=True)

    # ----- feeding ---------------------------------------------------------------------------

    def update(self, sim_s: float | None = None, messages: int | None = None,
               estimate: tuple | None = None, note: str | None = None) -> None:
        """Note what the job reached (absolute sim seconds, messages so far, (mu, sigma) rad, a
        short text); shown at most every interval_s."""
        with self._lock:
            if self._closed:
                return
            now = time.monotonic()
            if sim_s is not None and math.isfinite(sim_s):
                if self.sim_s is None or sim_s > self.sim_s:
                    self.sim_s, self._advanced = sim_s, now
                if self._first is None:
                    self._first = (now, sim_s)
            if messages is not None:
                self.messages = messages
            if note is not None:
                self.note = note
            if estimate is not None:
                mu, sig = estimate
                self.estimate = (np.asarray(mu, dtype=float), None if sig is None else np.asarray(sig, dtype=float))
            if now - self._last_shown >= self.interval_s:
                self._show(now)

    def close(self, sim_s: float | None = None, messages: int | None = None) -> None:
        """The final line: what the job reached (sim_s given: exactly that)."""
        with self._lock:
            if self._closed:
                return
            if sim_s is not None:
                if self.sim_s is None or sim_s > self.sim_s:
                    self._advanced = time.monotonic()
                self.sim_s = sim_s
            if messages is not None:
                self.messages = messages
            self._closed = True
            self._show(time.monotonic(), final=True)
            if self._bar is not None:
                self._bar.close()

    def abandon(self) -> None:
        """End without a final line (a job stopped by a signal says where in its own line)."""
        with self._lock:
            self._closed = True
            if self._bar is not None:
                self._bar.close()

    # ----- what is shown ---------------------------------------------------------------------

    def rtf(self, now: float | None = None) -> float | None:
        """Simulated seconds per wall second from the first update to the latest advance of the
        simulation time (the simulation's own pace, not the set-up and shutdown around it)."""
        if self._first is None or self.sim_s is None:
            return None
        wall = self._advanced - self._first[0]
        return (self.sim_s - self._first[1]) / wall if wall > 0.5 else None

    def fields(self, now: float | None = None) -> list[str]:
        """The parts of a line: 't = T / D s', 'rtf R', 'N msgs', 'ETA', the estimate."""
        out = []
        t = None if self.sim_s is None else self.sim_s - self.start_s
        shown = '-' if t is None else f'{t:.2f}'
        out.append(f't = {shown} / {self.total_s:.2f} s' if self.total_s else f't = {shown} s')
        rtf = self.rtf(now)
        if rtf is not None:
            out.append(f'rtf {rtf:.2f}')
        if self.messages is not None:
            out.append(f'{self.messages} msgs')
        if self.total_s and rtf and t is not None and rtf > 0 and not self._closed:
            out.append(f'ETA {_duration(max(0.0, self.total_s - t) / rtf)}')
        if self.estimate is not None:
            mu, sig = self.estimate
            text = 'misalignment ' + ' '.join(f'{v * ARCMIN_PER_RAD:.2f}' for v in mu)
            if sig is not None:
                text += ' \u00b1 ' + ' '.join(f'{v * ARCMIN_PER_RAD:.2f}' for v in sig)
            out.append(text + ' arcmin')
        if self.note:
            out.append(self.note)
        return out

    def line(self, now: float | None = None) -> str:
        return f'{self.label}: ' + ', '.join(self.fields(now))

    def _show(self, now: float, final: bool = False) -> None:
        if self.mode == 'quiet' or (self.sim_s is None and not final):
            return              # nothing to say yet
        self._last_shown = now
        if self._bar is not None:
            if self.sim_s is not None and self.total_s:
                self._bar.n = min(max(0.0, self.sim_s - self.start_s), self.total_s)
            self._bar.set_description_str(self.line(now), refresh=False)
            self._bar.refresh()
            return
        print(self.line(now) + (' (done)' if final else ''), file=self.stream, flush=True)
