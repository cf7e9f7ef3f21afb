"""The aircraft's run along the deck: the displacement from its spot, integrated from the LDV's
velocity once the aircraft moves, with the LDV's dropouts bridged. A gap in a stroke is bridged
by the speed the IMU felt, pinned to the LDV at both ends; a gap in slow motion by the trapezoid
(docs/engine.md, the deck displacement)."""
from __future__ import annotations

import math
from collections import deque

import numpy as np

from alignment_core.samples import LdvSample

TRAPEZOID_MAX_NS = 1_000_000_000     # the longest gap in slow motion bridged (by the trapezoid)
SHAPED_MAX_NS = 10_000_000_000       # the longest gap bridged by the IMU's shape (a stroke the LDV lost)
SHAPED_MIN_MPS = 5.0                 # ... when the LDV's speed changed at least this much across it
ONSET_MARGIN_NS = 500_000_000        # a run from rest: from this long before the IMU reached a tenth of its speed


class DeckRun:
    """The deck displacement (3,), ship axes, m: the trapezoid between consecutive valid LDV
    samples while moving. Across a gap (invalid samples, or a silence over TRAPEZOID_MAX_NS,
    between two valid samples, the second one moving) in which the LDV's speed changed by at
    least SHAPED_MIN_MPS, a stroke the LDV lost (or, from a parked sample, first saw halfway),
    the speed is the IMU's velocity change along x over the gap, corrected by a line so that it
    meets the LDV's speed at both ends: exact for any profile of acceleration along the track,
    whatever the constant part of the specific force (gravity on a pitched airframe, a bias),
    with the direction of the two ends' mean velocity. A run first seen moving (the LDV never
    valid, or last valid parked over SHAPED_MAX_NS before) is bridged from rest as far back as
    the IMU reaches. A smaller change (creep, a taxi) is bridged by the trapezoid over at most
    TRAPEZOID_MAX_NS from a moving sample, and not at all beyond."""

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

    def record(self, s: LdvSample, moving: bool) -> np.ndarray:
        """Take the next LDV sample (stamp order; moving: the aircraft moves on the deck at it, its
        velocity along the track for a beam) and return the displacement at it."""
        last = self._last_valid
        if moving and s.valid and last is not None and not (
                not last[1] and s.t_ns - last[0].t_ns > SHAPED_MAX_NS):
            prev, prev_moving = last
            gap = s.t_ns - prev.t_ns
            if prev is self._last and gap <= TRAPEZOID_MAX_NS:
                self.displacement = self.displacement + 0.5 * (prev.v_s + s.v_s) * gap * 1e-9
            else:
                run = self._shaped(prev, s, not prev_moving) if gap <= SHAPED_MAX_NS else None
                if run is not None:
                    self.displacement = self.displacement + run
                elif prev_moving and gap <= TRAPEZOID_MAX_NS:
                    self.displacement = self.displacement + 0.5 * (prev.v_s + s.v_s) * gap * 1e-9
        elif moving and s.valid and self._imu:
            run = self._shaped(self._parked_before(s), s, True)     # first seen moving: parked before
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

    def _shaped(self, a: LdvSample, b: LdvSample, from_rest: bool) -> np.ndarray | None:
        """The run (3,) between valid samples a and b by the IMU's shape, or None: the speed changed
        by less than SHAPED_MIN_MPS, or the IMU's intervals do not cover the gap. from_rest: a was
        parked, so the run starts where the IMU's speed (back from b's) falls under a tenth of b's,
        less ONSET_MARGIN_NS; the parked time before it adds nothing (nor its residuals)."""
        s0 = math.sqrt(float(a.v_s @ a.v_s))
        s1 = math.sqrt(float(b.v_s @ b.v_s))
        if abs(s1 - s0) < SHAPED_MIN_MPS:
            return None
        t0, t1 = a.t_ns - self._latency, b.t_ns - self._latency
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
        if from_rest:
            for k in range(len(ends) - 1, -1, -1):
                if s1 - (v - dv[k]) <= 0.1 * s1:             # the IMU's speed back from b's
                    start = ends[k] - ONSET_MARGIN_NS
                    if start > t0:
                        keep = [j for j, t in enumerate(ends) if t > start]
                        v0 = dv[keep[0] - 1]
                        t0, ends, dv = ends[keep[0] - 1], [ends[j] for j in keep], [dv[j] - v0 for j in keep]
                        v -= v0
                    break
        drift = (v - (s1 - s0)) / ((t1 - t0) * 1e-9)     # the IMU's change beyond the LDV's, per second
        dist = 0.0
        t_prev, s_prev = t0, s0
        for t, v_k in zip(ends, dv):
            s_k = s0 + v_k - drift * (t - t0) * 1e-9
            dist += 0.5 * (s_prev + s_k) * (t - t_prev) * 1e-9
            t_prev, s_prev = t, s_k
        dist += 0.5 * (s_prev + s1) * (t1 - t_prev) * 1e-9
        mean = a.v_s + b.v_s
        return dist * mean / math.sqrt(float(mean @ mean))
