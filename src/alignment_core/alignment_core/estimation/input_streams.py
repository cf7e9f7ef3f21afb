"""The engine's input streams (docs/engine.md, input plausibility and stamp order): each sample's
plausibility (plausibility.py), its queue in stamp order (navigation/ordering.py), and what the
health report may say of the streams. That report is a function of the stamps processed, never
of arrival timing, so the graph, a replay and the batch agree at any real-time factor:
- a master or LDV is silent when the stamps processed have run `silence_warn_s` past its last
  processed stamp (processing waits for a stream that lags on arrival, so only a gap in its own
  stamps, or a stream the engine stopped waiting for, shows);
- a rejected sample counts in the report from its stream's next accepted sample on (it arrived
  before that one), or from the end of the data.
What the engine waits for now (`waiting_for`) is arrival liveness, for a node to say so."""
from __future__ import annotations

from collections import deque
from collections.abc import Iterator
from typing import Any

from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.outputs import Counters
from alignment_core.estimation.plausibility import InputGate
from alignment_core.navigation.ordering import Event, StampMerger

SILENCE_STREAMS = ('master', 'ldv')       # the streams a silence of is reported (the IMU's: a gap)


class InputStreams:
    """Push samples, then take the events in stamp order (`events`); `silent` and `rejections`
    as of the events taken so far."""

    def __init__(self, cfg: FilterConfig, counters: Counters, streams: tuple[str, ...]) -> None:
        self.gate = InputGate(cfg, counters, streams)
        self.merger = StampMerger(streams)
        self._silence_ns = int(round(cfg.silence_warn_s * 1e9))
        self._processed: dict[str, int | None] = {k: None for k in streams}   # last stamp processed
        self._first_processed: int | None = None
        self._newest_processed: int | None = None
        self._unplaced = {k: 0 for k in streams}           # rejections since the stream's last accepted sample
        self._placed: dict[str, deque[tuple[int, int]]] = {k: deque() for k in streams}   # (stamp, count)
        self.rejections = 0                                # rejections reached by the stamps processed

    def push(self, stream: str, s: Any) -> bool:
        """Queue a sample unless it is implausible or not after its stream's previous stamp (False:
        rejected, counted by reason)."""
        item = self.gate.check(stream, s)
        if item is not None and not self.merger.push(stream, s.t_ns, item):
            self.gate.reject_out_of_order()
            item = None
        if item is None:
            self._unplaced[stream] += 1
            return False
        self.gate.accepted(stream, s.t_ns)
        if self._unplaced[stream]:
            self._placed[stream].append((s.t_ns, self._unplaced[stream]))
            self._unplaced[stream] = 0
        return True

    def events(self, final: bool) -> Iterator[Event]:
        """The events up to the watermark (all of them if final), in stamp order; each counts as
        processed when it is taken."""
        for stream, t, item in (self.merger.flush() if final else self.merger.pop_ready()):
            self._taken(stream, t)
            yield stream, t, item
        if final:
            for k, placed in self._placed.items():
                self.rejections += sum(n for _, n in placed) + self._unplaced[k]
                placed.clear()
                self._unplaced[k] = 0

    def _taken(self, stream: str, t: int) -> None:
        if stream in self._processed:
            self._processed[stream] = t
        if self._first_processed is None:
            self._first_processed = t
        self._newest_processed = t                     # events come in stamp order
        placed = self._placed[stream]
        while placed and placed[0][0] <= t:
            self.rejections += placed.popleft()[1]

    def stop_waiting(self, stream: str, absent: bool) -> None:
        """Stop waiting for a silent stream; an absent one (never delivered) is never reported silent."""
        self.merger.drop(stream)
        if absent:
            self.gate.forget(stream)
            self._processed.pop(stream, None)

    def silent(self) -> tuple[str, ...]:
        """The master or LDV whose last processed stamp lags the newest processed by more than
        silence_warn_s (or none of which was processed while the others ran that long)."""
        newest, first = self._newest_processed, self._first_processed
        if newest is None or first is None:
            return ()
        out = []
        for k in SILENCE_STREAMS:
            if k in self._processed:
                last = self._processed[k]
                if newest - (first if last is None else last) > self._silence_ns:
                    out.append(k)
        return tuple(out)

    def waiting_for(self) -> tuple[str, ...]:
        """Arrival liveness: the master or LDV the stamp order still waits for that has delivered
        nothing while the others ran silence_warn_s of stamps (plausibility.py)."""
        return tuple(k for k in self.gate.waiting_for() if k in self.merger.last)

    @property
    def last_rejection(self) -> str:
        return self.gate.last_rejection

    def pending(self) -> int:
        return self.merger.pending()
