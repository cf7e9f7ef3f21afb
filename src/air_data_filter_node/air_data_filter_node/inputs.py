"""The air-data filter node's input handling, free of ROS: port messages assembled into frames,
IMU samples into the blocks the paper form propagates over, and the streams released in stamp
order (so the estimates do not depend on how the topics interleave on arrival)."""
from __future__ import annotations

import heapq
from collections import Counter
from typing import Any

import numpy as np


class FrameAssembler:
    """Port pressures in (each port's messages in stamp order), whole frames out: a frame is
    complete when all n ports of one stamp have arrived. Dropped and counted in `rejected`:
    a port message not newer than that port's last one or than the last frame ('duplicate' at
    the same stamp, 'out_of_order' before it), an unknown port ('unknown_port'), and a stamp
    left incomplete ('incomplete') when a later frame completes (every port has gone past it)
    or when it is more than max_wait_ns older than the newest port stamp (a port fell silent).
    A port that trails the others (as fast as possible, a reliable stream can be thousands of
    messages behind another) is waited for: a bound on the count of open stamps (16, once)
    dropped frames whose last port was merely late."""

    def __init__(self, n_ports: int, max_wait_ns: int) -> None:
        self.n = int(n_ports)
        self.max_wait_ns = int(max_wait_ns)
        self.newest_ns: int | None = None
        self.pending: dict[int, tuple[np.ndarray, np.ndarray]] = {}   # t_ns -> (pressures (n,), have (n,))
        self.last_port_ns: list[int | None] = [None] * self.n
        self.last_frame_ns: int | None = None
        self.rejected: Counter = Counter()

    def _refuse(self, t_ns: int, last: int | None) -> bool:
        if last is None or t_ns > last:
            return False
        self.rejected['duplicate' if t_ns == last else 'out_of_order'] += 1
        return True

    def add(self, port: int, t_ns: int, pressure_pa: float) -> tuple[int, np.ndarray] | None:
        """One port message; the frame (t_ns, pressures (n,)) it completes, or None."""
        if not 0 <= port < self.n:
            self.rejected['unknown_port'] += 1
            return None
        if self._refuse(t_ns, self.last_frame_ns) or self._refuse(t_ns, self.last_port_ns[port]):
            return None
        self.last_port_ns[port] = t_ns
        if self.newest_ns is None or t_ns > self.newest_ns:
            self.newest_ns = t_ns
            for t in [t for t in self.pending if t_ns - t > self.max_wait_ns]:
                del self.pending[t]
                self.rejected['incomplete'] += 1
        if t_ns not in self.pending:
            self.pending[t_ns] = (np.full(self.n, np.nan), np.zeros(self.n, dtype=bool))
        p, have = self.pending[t_ns]
        p[port], have[port] = pressure_pa, True
        if not have.all():
            return None
        for t in [t for t in self.pending if t <= t_ns]:
            if t < t_ns:
                self.rejected['incomplete'] += 1
            del self.pending[t]
        self.last_frame_ns = t_ns
        return t_ns, p


class ImuBlocks:
    """IMU samples (mean specific force and rate over the interval ending at their stamp) into
    blocks of `block` samples, as air_data_run does: each block's (t0_ns, t1_ns, mean f_b,
    mean w_ib); the first block starts one sample interval (dt_ns) before the first sample."""

    def __init__(self, block: int, dt_ns: int) -> None:
        self.block, self.dt_ns = max(1, int(block)), int(dt_ns)
        self.start_ns: int | None = None
        self.last_ns: int | None = None
        self.n = 0
        self.f = np.zeros(3)
        self.w = np.zeros(3)
        self.rejected = 0

    def add(self, t_ns: int, accel: np.ndarray, gyro: np.ndarray) -> tuple[int, int, np.ndarray, np.ndarray] | None:
        """One sample (stamps must increase; others are counted in `rejected`); the block it ends."""
        if self.last_ns is not None and t_ns <= self.last_ns:
            self.rejected += 1
            return None
        if not (np.all(np.isfinite(accel)) and np.all(np.isfinite(gyro))):
            self.rejected += 1
            return None
        if self.start_ns is None:
            self.start_ns = t_ns - self.dt_ns
        self.last_ns = t_ns
        self.f, self.w, self.n = self.f + accel, self.w + gyro, self.n + 1
        return self.close() if self.n == self.block else None

    def close(self) -> tuple[int, int, np.ndarray, np.ndarray] | None:
        """The block so far (also a partial one: at the end of the stream), or None if empty."""
        if self.n == 0 or self.start_ns is None or self.last_ns is None:
            return None
        out = (self.start_ns, self.last_ns, self.f / self.n, self.w / self.n)
        self.start_ns, self.f, self.w, self.n = self.last_ns, np.zeros(3), np.zeros(3), 0
        return out


class StampOrder:
    """Events of several streams (each in stamp order) released in stamp order: an event goes
    once every other stream has reached its stamp (ties in the order `streams` lists them), or
    once it is more than max_wait_ns older than the newest stamp seen (a stream fell silent)."""

    def __init__(self, streams: tuple[str, ...], max_wait_ns: int) -> None:
        self.rank = {s: i for i, s in enumerate(streams)}
        self.reached: dict[str, int | None] = {s: None for s in streams}
        self.max_wait_ns = int(max_wait_ns)
        self._heap: list[tuple[int, int, int, str, Any]] = []
        self._seq = 0

    def __len__(self) -> int:
        return len(self._heap)

    def advance(self, stream: str, t_ns: int) -> None:
        """The stream has reached t_ns (nothing earlier will come from it)."""
        r = self.reached[stream]
        self.reached[stream] = t_ns if r is None else max(r, t_ns)

    def add(self, stream: str, t_ns: int, item: Any) -> None:
        self.advance(stream, t_ns)
        heapq.heappush(self._heap, (t_ns, self.rank[stream], self._seq, stream, item))
        self._seq += 1

    def ready(self, final: bool = False) -> list[tuple[str, int, Any]]:
        """(stream, t_ns, item) of every event that may go now (all with final=True), in order."""
        seen = [r for r in self.reached.values() if r is not None]
        newest = max(seen) if seen else None
        out = []
        while self._heap:
            t, _, _, stream, item = self._heap[0]
            others = [r for s, r in self.reached.items() if s != stream]
            go = (final or all(r is not None and r >= t for r in others)
                  or (newest is not None and newest - t > self.max_wait_ns))
            if not go:
                break
            heapq.heappop(self._heap)
            out.append((stream, t, item))
        return out
