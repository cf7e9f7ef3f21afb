"""Pair messages of two topics by header stamp (for nodes that need both halves of a sample)."""
from __future__ import annotations


class StampPairer:
    """Holds unmatched halves; returns (a, b) when both messages of a stamp have arrived.
    Pairs must complete in stamp order: a pair older than the last one is rejected."""

    def __init__(self, max_pending: int = 10000) -> None:
        self.a: dict[int, object] = {}
        self.b: dict[int, object] = {}
        self.last: int | None = None
        self.max_pending = max_pending
        self.rejected = 0
        self.dropped = 0

    def _done(self, t: int, a, b):
        if self.last is not None and t <= self.last:
            self.rejected += 1
            return None
        self.last = t
        return a, b

    def add_a(self, t: int, msg):
        if t in self.b:
            return self._done(t, msg, self.b.pop(t))
        self.a[t] = msg
        self._trim()
        return None

    def add_b(self, t: int, msg):
        if t in self.a:
            return self._done(t, self.a.pop(t), msg)
        self.b[t] = msg
        self._trim()
        return None

    def counts(self) -> dict[str, int]:
        """What never became a pair, by reason (a node's stats 'rejected'; the launcher reports
        any 'unpaired_dropped' as a problem: a simulated sample was lost)."""
        return {'out_of_order': self.rejected, 'unpaired_dropped': self.dropped}

    def _trim(self) -> None:
        for d in (self.a, self.b):
            while len(d) > self.max_pending:
                d.pop(min(d))
                self.dropped += 1
