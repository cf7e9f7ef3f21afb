"""Rows of a sampled process by sample index, of which only the recent ones are kept.

A simulation stage that a node runs for hours (the landing gear's response, the deck flexure,
the ship's track) appends one row per sample and reads back rows near the newest (the IMU
increments between the previous sample and this one). Keeping every row would grow with the
run; `RecentRows` keeps the rows from the oldest a reader may still ask for: `forget_before(k)`
lets the rows below k go, and their memory is reused (the live rows are moved down once the
dead ones fill half the buffer, so a stream of any length holds about twice what is live). A
batch run that appends everything before reading forgets nothing and reads any row.

The buffer is written through (NaN) when it is made or grown: its pages are resident from the
start. Left unwritten, they would become resident one by one as rows first land on them, and a
large buffer's resident set would rise for as long as its first fill takes (the ship's track:
1.5 MiB over its first 68 simulated minutes), a growth a memory soak cannot tell from a leak."""
from __future__ import annotations

import numpy as np


class RecentRows:
    """Rows (width,) at sample indices 0, 1, ...: appended in order, read back by index."""

    def __init__(self, width: int, capacity: int = 1024) -> None:
        self._a = np.full((capacity, width), np.nan)
        self._base = 0          # the sample index of self._a[0]
        self._keep = 0          # rows below this index are forgotten
        self.n = 0              # rows appended (indices 0 .. n - 1)

    @property
    def capacity(self) -> int:
        """Rows the buffer holds (live, forgotten not yet reused, and free)."""
        return len(self._a)

    def append(self, row: np.ndarray) -> None:
        if self.n - self._base == len(self._a):
            self._make_room(1)
        self._a[self.n - self._base] = row
        self.n += 1

    def extend(self, rows: np.ndarray) -> None:
        """Append rows (m, width) in order."""
        m = len(rows)
        if self.n - self._base + m > len(self._a):
            self._make_room(m)
        self._a[self.n - self._base:self.n - self._base + m] = rows
        self.n += m

    def _make_room(self, m: int) -> None:
        """Room for m more rows: the live rows moved down over the dead ones when those fill half
        the buffer, else the buffer doubled (until m fit)."""
        dead = self._keep - self._base
        if dead >= len(self._a) // 2:
            live = self._a[dead:self.n - self._base]
            self._a[:len(live)] = live
            self._base = self._keep
        while self.n - self._base + m > len(self._a):
            self._a = np.concatenate([self._a, np.full_like(self._a, np.nan)])

    def forget_before(self, k: int) -> None:
        """Rows below index k are no longer read (a later read of one raises)."""
        self._keep = max(self._keep, min(int(k), self.n))

    def __getitem__(self, k) -> np.ndarray:
        """The rows at indices k (an int or an integer array, any shape): (..., width)."""
        k = np.asarray(k, dtype=np.int64)
        if k.size:
            lo, hi = int(k.min()), int(k.max())
            if lo < self._keep or hi >= self.n:
                raise IndexError(f'row {lo if lo < self._keep else hi} is not kept: rows {self._keep} .. '
                                 f'{self.n - 1} are (older ones were forgotten, newer not yet made)')
        return self._a[k - self._base]
