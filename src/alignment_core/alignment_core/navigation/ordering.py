"""Stamp-ordered merging of several input streams, independent of arrival interleaving.

Each stream must be in stamp order on its own (later duplicates or regressions are rejected
and counted). Events are released in (stamp, stream priority) order once every stream has
delivered a stamp at least as late (the watermark), so the output depends only on the
streams' contents, never on how they interleaved on arrival. `flush()` releases the rest.
"""
from __future__ import annotations

import heapq
import itertools
from typing import Any, cast

Event = tuple[str, int, Any]


class StampMerger:
    def __init__(self, streams: tuple[str, ...]) -> None:
        self.priority = {name: i for i, name in enumerate(streams)}
        self.last: dict[str, int | None] = {name: None for name in streams}
        self.heap: list[tuple[int, int, int, str, Any]] = []
        self.seq = itertools.count()
        self.rejected_out_of_order = {name: 0 for name in streams}
        self._silent = len(streams)          # streams that have not delivered yet (no watermark)

    def push(self, stream: str, t_ns: int, item: Any) -> bool:
        """Queue an item; False (and counted) if its stamp does not advance its stream."""
        last = self.last[stream]
        if last is None:
            self._silent -= 1
        elif t_ns <= last:
            self.rejected_out_of_order[stream] += 1
            return False
        self.last[stream] = t_ns
        heapq.heappush(self.heap, (t_ns, self.priority[stream], next(self.seq), stream, item))
        return True

    def drop(self, stream: str) -> None:
        """Stop waiting for a stream (it fell silent): the watermark is the other streams'; its
        queued events stay; later pushes to it are refused (KeyError)."""
        if self.last.pop(stream) is None:
            self._silent -= 1
        del self.priority[stream]

    def watermark(self) -> int | None:
        """The least recent stamp of all streams (None until every stream has delivered)."""
        if self._silent:
            return None
        return min(cast('dict[str, int]', self.last).values())     # none is None once all delivered

    def pop_ready(self) -> list[Event]:
        """(stream, stamp, item) of every queued event up to the watermark, in order."""
        wm = self.watermark()
        heap = self.heap
        out: list[Event] = []
        if wm is None:
            return out
        pop = heapq.heappop
        while heap and heap[0][0] <= wm:
            t, _, _, stream, item = pop(heap)
            out.append((stream, t, item))
        return out

    def flush(self) -> list[Event]:
        """Every queued event, in order."""
        heap, out = self.heap, []
        while heap:
            t, _, _, stream, item = heapq.heappop(heap)
            out.append((stream, t, item))
        return out

    def pending(self) -> int:
        return len(self.heap)
