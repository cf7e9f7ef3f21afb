"""The ship's lead over the streams downstream of it: the ship node publishes a sample only when
every watched stream has reached within `max_lead_ns` of its stamp. A node that pairs two
streams (the LDV: the ship's odometry with the slave's aircraft truth) otherwise buffers the
faster one for as long as the slower lags, and every DDS reader queue between the ship and the
slowest consumer (the filter) fills up to the lag; a reader keeps the memory of its deepest queue,
so at an unpaced real-time factor the nodes' resident size crept up with the run. With the lead
bounded, every such buffer and queue holds at most the lead's samples. Stamps are untouched: the
numbers are the same at any lead.

A watched stream that stays silent for `release_s` wall seconds while the ship waits on it (a
filter that publishes nothing: every input rejected, a node that died) is released: the ship no
longer waits on it until it advances again, so a silent stream never hangs a run."""
from __future__ import annotations

import time
from collections.abc import Callable, Iterable


class LeadLimit:
    """Latest stamp (ns) seen on each watched stream, against the sample about to be sent."""

    def __init__(self, topics: Iterable[str], max_lead_ns: int, t0_ns: int, release_s: float = 10.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        if max_lead_ns <= 0:
            raise ValueError(f'max_lead_ns must be > 0, got {max_lead_ns}')
        if not release_s > 0:
            raise ValueError(f'release_s must be > 0, got {release_s}')
        self.max_lead_ns = max_lead_ns
        self.t0_ns = t0_ns
        self.release_s = release_s
        self.clock = clock
        self.latest: dict[str, int | None] = dict.fromkeys(topics)
        self.advanced: dict[str, float] = dict.fromkeys(self.latest, -float('inf'))   # wall s
        self.released: set[str] = set()
        self.releases = 0

    def note(self, topic: str, t_ns: int) -> None:
        last = self.latest.get(topic)
        if last is None or t_ns > last:
            self.latest[topic] = t_ns
            self.advanced[topic] = self.clock()
            self.released.discard(topic)

    def behind(self, t_ns: int) -> list[str]:
        """The watched streams more than the lead behind t_ns (one that has sent nothing yet
        counts as at t0)."""
        floor = t_ns - self.max_lead_ns
        return [t for t, last in self.latest.items() if (self.t0_ns if last is None else last) < floor]

    def unheard(self) -> list[str]:
        """The watched streams that have sent nothing yet."""
        return [t for t, last in self.latest.items() if last is None]

    def holding(self, t_ns: int, waiting_since: float) -> list[str]:
        """The streams behind t_ns the sample still waits for: a stream silent for release_s
        (counted from its last advance or from `waiting_since`, the wall time the wait began,
        whichever is later) is released instead, until it advances."""
        now = self.clock()
        out = []
        for t in self.behind(t_ns):
            if t in self.released:
                continue
            if now - max(self.advanced[t], waiting_since) > self.release_s:
                self.released.add(t)
                self.releases += 1
                continue
            out.append(t)
        return out
