"""The aircraft's run along the deck: the displacement from its spot, integrated from the LDV's
velocity once the aircraft moves, with the LDV's dropouts bridged. A gap in a stroke is bridged
by the speed along the airframe's x axis the IMU felt, pinned to the LDV at both ends; a gap in
slow motion by the trapezoid (docs/engine.md, the deck displacement)."""
from __future__ import annotations

from collections import deque

import numpy as np

from alignment_core.samples import LdvSample

TRAPEZOID_MAX_NS = 1_000_000_000     # a gap bridged whatever the speed change (by the trapezoid without the IMU)
SHAPED_MAX_NS = 10_000_000_000       # the longest gap bridged (a stroke the LDV lost), by the IMU's shape
SHAPED_MIN_MPS = 5.0                 # ... a gap over TRAPEZOID_MAX_NS: the speed changed this much
GRID_SLACK_NS = 1_000                # IMU intervals are contiguous to this (their lengths round-trip through floats)


class DeckRun:
    """The deck displacement (3,), ship axes, m: the trapezoid between consecutive valid LDV
    samples while moving (as fast or slow as the LDV's rate). Across a gap (invalid samples
    between two valid ones, the second one moving) the speed along the airframe's x axis on deck
    (`axis`, ship axes) is the IMU's velocity change along x over the gap, corrected by a line so
    that it meets the LDV's speed along that axis at both ends: exact for an acceleration constant
    over each IMU interval, whatever the constant part of the specific force (gravity on a pitched
    airframe, a bias) and the LDV's times on the IMU's grid, forward, backward or reversing; the
    velocity across the axis (small on a track) by the trapezoid. Its error (the deck's motion
    felt) grows with the square of the gap, so a gap over TRAPEZOID_MAX_NS is bridged only when
    the speed changed across the bridged time by at least SHAPED_MIN_MPS (a stroke the LDV lost),
    up to SHAPED_MAX_NS. A run first seen moving (from a parked sample, the LDV never valid, or
    last valid parked over SHAPED_MAX_NS before) is bridged from rest, from where the launch
    detector dated its start (else as far back as the IMU reaches). Without the IMU's intervals
    a gap of at most TRAPEZOID_MAX_NS from a moving sample is bridged by the trapezoid; nothing
    else is."""

    def __init__(self, ldv_latency_ns: int = 0, axis: np.ndarray | None = None,
                 imu: deque[tuple[int, float, float]] | None = None, span_ns: int = SHAPED_MAX_NS) -> None:
        """axis: the airframe's x axis on deck (3,), ship axes; imu: the record of the IMU's intervals
        to keep (shared with the launch detector), `span_ns` long (at least SHAPED_MAX_NS)."""
        self.displacement = np.zeros(3)
        self._latency = ldv_latency_ns
        self._axis = np.array([1.0, 0.0, 0.0]) if axis is None else np.asarray(axis, dtype=float)
        self._imu = deque() if imu is None else imu   # (t_end, specific force along x, h)
        self._span = max(span_ns, SHAPED_MAX_NS)
        self._last: LdvSample | None = None
        self._last_valid: tuple[LdvSample, bool] | None = None  # (sample, recorded moving)

    def observe_imu(self, t_ns: int, f_x: float, h: float) -> None:
        """One IMU interval ending at t_ns: mean specific force along the aircraft's x axis, length h s."""
        q = self._imu
        q.append((t_ns, f_x, h))
        while q[0][0] < t_ns - self._span:
            q.popleft()

    def record(self, s: LdvSample, moving: bool, t_start_ns: int | None = None) -> np.ndarray:
        """Take the next LDV sample (stamp order; moving: the aircraft moves on the deck at it, its
        velocity along the track for a beam; t_start_ns: the validity time the run from rest began,
        as the launch detector dated it from the IMU) and return the displacement at it."""
        last = self._last_valid
        if moving and s.valid:
            if last is not None and last[0] is self._last:
                prev = last[0]
                self.displacement = self.displacement + 0.5 * (prev.v_s + s.v_s) * (s.t_ns - prev.t_ns) * 1e-9
            elif last is not None and (last[1] or s.t_ns - last[0].t_ns <= SHAPED_MAX_NS):
                prev, prev_moving = last
                gap = s.t_ns - prev.t_ns
                run = self._shaped(prev, s, None if prev_moving else t_start_ns) if gap <= SHAPED_MAX_NS else None
                if run is not None:
                    self.displacement = self.displacement + run
                elif prev_moving and gap <= TRAPEZOID_MAX_NS:
                    self.displacement = self.displacement + 0.5 * (prev.v_s + s.v_s) * gap * 1e-9
            elif self._imu:
                run = self._shaped(self._parked_before(s), s, t_start_ns)     # first seen moving: parked before
                if run is not None:
                    self.displacement = self.displacement + run
        self._last = s
        if s.valid:
            self._last_valid = (s, moving)
        return self.displacement

    def _parked_before(self, s: LdvSample) -> LdvSample:
        """A parked reading (zero velocity) as far before s as the IMU reaches, at most
        SHAPED_MAX_NS: the start of a run first seen moving, the LDV never valid before it or
        last valid parked longer ago."""
        t_imu, _f, h = self._imu[0]
        t0 = max(t_imu - int(round(h * 1e9)), s.t_ns - self._latency - SHAPED_MAX_NS)
        return LdvSample(t_ns=t0 + self._latency, v_s=np.zeros(3), sigma=s.sigma, valid=True)

    def _shaped(self, a: LdvSample, b: LdvSample, t_start: int | None) -> np.ndarray | None:
        """The run (3,) between valid samples a and b by the IMU's shape, or None: over
        TRAPEZOID_MAX_NS with less than SHAPED_MIN_MPS of speed change, or IMU intervals that do
        not cover the time bridged (the last one may end up to an interval before b: its
        acceleration is taken to hold to b). t_start: a was parked and the run began then (validity
        time): at rest before it, the bridge starts there, so the deck's motion felt while parked
        does not enter."""
        x = self._axis
        t0, t1 = a.t_ns - self._latency, b.t_ns - self._latency
        u0, u1 = float(a.v_s @ x), float(b.v_s @ x)
        c0, c1 = a.v_s - u0 * x, b.v_s - u1 * x
        if t_start is not None and t0 < t_start < t1:
            t0, u0, c0 = t_start, 0.0, np.zeros(3)
        if abs(u1 - u0) < SHAPED_MIN_MPS and t1 - t0 > TRAPEZOID_MAX_NS:
            return None
        nodes: list[tuple[int, float]] = [(t0, 0.0)]     # (time, the IMU's velocity change since t0)
        v = 0.0
        covered = None
        f_last = h_last = 0.0
        for t, f, h in self._imu:
            start = t - int(round(h * 1e9))
            if t <= t0 or start >= t1:
                continue
            gap_ns = start - t0 if covered is None else abs(start - covered)
            if gap_ns > GRID_SLACK_NS:
                return None                               # a hole in the IMU's intervals
            end = min(t, t1)
            v += f * (end - max(start, t0)) * 1e-9
            nodes.append((end, v))
            covered, f_last, h_last = end, f, h
        if covered is None or (t1 - covered) * 1e-9 > h_last:
            return None
        if covered < t1:
            v += f_last * (t1 - covered) * 1e-9
            nodes.append((t1, v))
        drift = (v - (u1 - u0)) / ((t1 - t0) * 1e-9)      # the IMU's change beyond the LDV's, per second
        along = 0.0
        t_prev, s_prev = t0, u0
        for t, v_k in nodes[1:]:
            s_k = u0 + v_k - drift * (t - t0) * 1e-9
            along += 0.5 * (s_prev + s_k) * (t - t_prev) * 1e-9
            t_prev, s_prev = t, s_k
        return along * x + 0.5 * (c0 + c1) * (t1 - t0) * 1e-9
