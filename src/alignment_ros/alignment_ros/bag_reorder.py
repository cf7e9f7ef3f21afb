"""A bounded reorder buffer: messages in arrival order in, log-time order out, in constant memory.

A bag's log times are message stamps (:mod:`alignment_ros.bag`), and the streams of a graph
arrive out of log-time order: at ``--real-time-factor 0`` the filter's outputs arrive tens of
simulated seconds after the ship samples of the same stamp. Each stream on its own arrives in
stamp order, so a message can be written once every stream has gone past its log time: the
*watermark* is the oldest of the streams' latest log times (a stream that has sent nothing yet
holds it back), and every buffered message older than the watermark is released, in
(log time, arrival) order: the order :class:`~alignment_ros.bag_writer.BagWriter` always wrote.

Memory is bounded by ``max_bytes``: when the buffered messages (payload plus a per-entry
overhead) exceed it, the oldest are released anyway. A stream that lags more than that (or one
that never sends, or sends out of stamp order) can then deliver a message older than one already
released: it is released at once (the file is then not in log-time order there; MCAP readers
that read in log-time order use the chunk index and still get it in order) and counted as
``late``.

A recorder that discovers its topics as they appear *holds* the buffer (``hold``) while new topics
keep appearing: a stream it has not subscribed to yet cannot hold the watermark back, and its
first messages may be older than those already released. Held, the buffer releases only what its
bound forces out.
"""
from __future__ import annotations

import heapq
from collections.abc import Iterable, Iterator
from typing import cast

ENTRY_OVERHEAD_B = 160
"""Python memory of one buffered entry besides its payload (the heap tuple, two ints, the bytes
object's header), counted against ``max_bytes``."""


class ReorderBuffer:
    """Messages of registered streams (``stream`` is any hashable key, e.g. a channel id)."""

    def __init__(self, max_bytes: int) -> None:
        if max_bytes <= 0:
            raise ValueError(f'max_bytes must be > 0, not {max_bytes}')
        self.max_bytes = max_bytes
        self._heap: list[tuple[int, int, object, bytes]] = []
        self._latest: dict[object, int | None] = {}   # stream -> latest log time (None: nothing yet)
        self._seq = 0
        self.bytes = 0
        self.peak_bytes = 0
        self.peak_messages = 0
        self.released_t = -1       # log time of the last message released
        self.late = 0              # messages released after a younger one
        self.hold = False          # release only what the bound forces out (streams still appearing)

    def add_stream(self, stream: object) -> None:
        """A stream that holds the watermark back until its first message (idempotent)."""
        self._latest.setdefault(stream, None)

    def __len__(self) -> int:
        return len(self._heap)

    def _watermark(self) -> int | None:
        latest = self._latest.values()
        if None in latest:
            return None
        return min(cast(Iterable[int], latest), default=None)   # no None left: every stream has sent

    def push(self, stream: object, t_ns: int, data: bytes) -> None:
        """Buffer one message (then take what it released with :meth:`release`)."""
        self._latest[stream] = t_ns
        heapq.heappush(self._heap, (t_ns, self._seq, stream, data))
        self._seq += 1
        self.bytes += len(data) + ENTRY_OVERHEAD_B
        if self.bytes > self.peak_bytes:
            self.peak_bytes = self.bytes
            self.peak_messages = len(self._heap)

    def release(self) -> Iterator[tuple[int, object, bytes]]:
        """Yield (log time, stream, data) of every message older than the watermark, then the
        oldest while the buffer is over its bound (only those while held)."""
        mark = None if self.hold else self._watermark()
        heap = self._heap
        while heap and ((mark is not None and heap[0][0] < mark) or self.bytes > self.max_bytes):
            yield self._pop()

    def drain(self) -> Iterator[tuple[int, object, bytes]]:
        """Release everything still buffered, in order."""
        while self._heap:
            yield self._pop()

    def _pop(self) -> tuple[int, object, bytes]:
        t, _, stream, data = heapq.heappop(self._heap)
        self.bytes -= len(data) + ENTRY_OVERHEAD_B
        if t < self.released_t:
            self.late += 1
        else:
            self.released_t = t
        return t, stream, data
