"""The aircraft's run along the deck: the displacement from its spot, integrated from the LDV's
velocity once the aircraft moves, with the LDV's dropouts bridged. A gap in a stroke is bridged
by the speed the IMU felt, pinned to the LDV at both ends; a gap in slow motion by the trapezoid
(docs/engine.md, the deck displacement)."""
from __future__ import annotations

import math
from collections import deque

import numpy as np

from alignment_core.samples import LdvSample

TRAPEZOID_MAX_NS = 1_000_000_000     # a gap bridged whatever the speed change (by the trapezoid without the IMU)
SHAPED_MAX_NS = 10_000_000_000       # the longest gap bridged (a stroke the LDV lost), by the IMU's shape
SHAPED_MIN_MPS = 5.0                 # ... a gap over TRAPEZOID_MAX_NS: the LDV's speed changed this much


class DeckRun:
    """The deck displacement (3,), ship axes, m: the trapezoid between consecutive valid LDV
    samples while moving. Across a gap (invalid samples, or a silence over TRAPEZOID_MAX_NS,
    between two valid samples, the second one moving) the speed is the IMU's velocity change
    along x over the gap, corrected by a line so that it meets the LDV's speed at both ends:
    exact for any profile of acceleration along the track, whatever the constant part of the
    specific force (gravity on a pitched airframe, a bias), with the direction of the two ends'
    mean velocity; its error grows with the square of the gap (the deck's motion felt), so a gap
    over TRAPEZOID_MAX_NS is bridged only when the LDV's speed changed across it by at least
    SHAPED_MIN_MPS (a stroke the LDV lost), up to SHAPED_MAX_NS. A run first seen moving (from a
    parked sample, the LDV never valid, or last valid parked over SHAPED_MAX_NS before) is
    bridged from rest, from where the launch detector dated its start (else as far back as the
    IMU reaches). Without the IMU's intervals a gap of at
    most TRAPEZOID_MAX_NS from a moving sample is bridged by the trapezoid; nothing else is."""

    def __init__(self, ldv_latency_ns: int = 0) -> None:
        self.displacement = np.zeros(3)
        self._latency = ldv_latency_ns
        self._imu: deque[tuple[int, float, float]] = deque()   # (t_end, specific force along x, h)
        self._last: LdvSample | None = None
        self._last_valid: tuple[LdvSample, bool] | None = None  # (sample, recorded moving)

    def observe_imu(self, t_ns: int, f_x: float, h: float) -> None:
        """One IMU interval ending at t_ns: mean specific force along the aircraft's x axis, length h s."""
        q = self._imu
        q.append((t_ns, f_x, h))
        while q[0][0] < t_ns - SHAPED_MAX_NS:
            q.popleft()

    def record(self, s: LdvSample, moving: bool, t_start_ns: int | None = None) -> np.ndarray:
        """Take the next LDV sample (stamp order; moving: the aircraft moves on the deck at it, its
        velocity along the track for a beam; t_start_ns: the validity time the run from rest began,
        as the launch detector dated it from the IMU) and return the displacement at it."""
        last = self._last_valid
        if moving and s.valid and last is not None and not (
                not last[1] and s.t_ns - last[0].t_ns > SHAPED_MAX_NS):
            prev, prev_moving = last
            gap = s.t_ns - prev.t_ns
            if prev is self._last and gap <= TRAPEZOID_MAX_NS:
                self.displacement = self.displacement + 0.5 * (prev.v_s + s.v_s) * gap * 1e-9
            else:
                run = self._shaped(prev, s, None if prev_moving else t_start_ns) if gap <= SHAPED_MAX_NS else None
                if run is not None:
                    self.displacement = self.displacement + run
                elif prev_moving and gap <= TRAPEZOID_MAX_NS:
                    self.displacement = self.displacement + 0.5 * (prev.v_s + s.v_s) * gap * 1e-9
        elif moving and s.valid and self._imu:
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
        """The run (3,) between valid samples a and b by the IMU's shape, or None: a gap over
        TRAPEZOID_MAX_NS in which the speed changed by less than SHAPED_MIN_MPS (the IMU's residuals
        would swamp a slow run), no velocity at either end, or IMU intervals that do not cover it.
        t_start: a was parked and the run began then (validity time): at rest before it, the
        window starts there, so the deck's motion felt while parked does not enter."""
        s0 = math.sqrt(float(a.v_s @ a.v_s))
        s1 = math.sqrt(float(b.v_s @ b.v_s))
        mean = a.v_s + b.v_s
        norm = math.sqrt(float(mean @ mean))
        if norm == 0.0 or (abs(s1 - s0) < SHAPED_MIN_MPS and b.t_ns - a.t_ns > TRAPEZOID_MAX_NS):
            return None
        t0, t1 = a.t_ns - self._latency, b.t_ns - self._latency
        if t_start is not None and t0 < t_start < t1:
            t0, s0 = t_start, 0.0
        ends: list[int] = []
        dv: list[float] = []
        v = 0.0
        h_max = 0.0
        for t, f, h in self._imu:
            if t0 < t <= t1:
                v += f * h
                ends.append(t)
                dv.append(v)
                h_max = max(h_max, h)
        if not ends or (ends[0] - t0) * 1e-9 > h_max or (t1 - ends[-1]) * 1e-9 > h_max:
            return None
        drift = (v - (s1 - s0)) / ((t1 - t0) * 1e-9)     # the IMU's change beyond the LDV's, per second
        dist = 0.0
        t_prev, s_prev = t0, s0
        for t, v_k in zip(ends, dv):
            s_k = s0 + v_k - drift * (t - t0) * 1e-9
            dist += 0.5 * (s_prev + s_k) * (t - t_prev) * 1e-9
            t_prev, s_prev = t, s_k
        dist += 0.5 * (s_prev + s1) * (t1 - t_prev) * 1e-9
        return dist * mean / norm
