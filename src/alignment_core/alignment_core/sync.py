"""Stamp-ordered merging of several input streams, independent of arrival interleaving.

Each stream must be in stamp order on its own (later duplicates or regressions are rejected
and counted). Events are released in (stamp, stream priority) order once every stream has
delivered a stamp at least as late (the watermark), so the output depends only on the
streams' contents, never on how they interleaved on arrival. `flush()` releases the rest.
"""
from __future__ import annotations

import heapq
import itertools
from collections.abc import Iterator
from typing import Any


class StampMerger:
    def __init__(self, streams: tuple[str, ...]) -> None:
        self.priority = {name: i for i, name in enumerate(streams)}
        self.last: dict[str, int | None] = {name: None for name in streams}
        self.heap: list[tuple[int, int, int, str, Any]] = []
        self.seq = itertools.count()
        self.rejected_out_of_order = {name: 0 for name in streams}

    def push(self, stream: str, t_ns: int, item: Any) -> bool:
        """Queue an item; False (and counted) if its stamp does not advance its stream."""
        last = self.last[stream]
        if last is not None and t_ns <= last:
            self.rejected_out_of_order[stream] += 1
            return False
        self.last[stream] = t_ns
        heapq.heappush(self.heap, (t_ns, self.priority[stream], next(self.seq), stream, item))
        return True

    def watermark(self) -> int | None:
        stamps = self.last.values()
        return None if any(s is None for s in stamps) else min(stamps)

    def pop_ready(self) -> Iterator[tuple[str, int, Any]]:
        wm = self.watermark()
        while self.heap and wm is not None and self.heap[0][0] <= wm:
            t, _, _, stream, item = heapq.heappop(self.heap)
            yield stream, t, item

    def flush(self) -> Iterator[tuple[str, int, Any]]:
        while self.heap:
            t, _, _, stream, item = heapq.heappop(self.heap)
            yield stream, t, item

    def pending(self) -> int:
        return len(self.heap)
