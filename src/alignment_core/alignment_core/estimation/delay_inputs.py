"""What a master match gives the master-delay state and rate matching (models/master_delay.py,
rate_matching.py) besides the reference: the master's nav-frame body rate, the deck spot's
acceleration and the gyro's and the master's rates over the IMU interval ending at the match's
validity time. Kept here: the IMU intervals the slave stepped over and the previous master sample
they are taken from (docs/engine.md, matching options)."""
from __future__ import annotations

from collections import deque
from typing import Protocol

import numpy as np

from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.models.base import RateInputs
from alignment_core.estimation.outputs import Counters
from alignment_core.estimation.reference_force import SpotAcceleration
from alignment_core.estimation.reference_velocity import Reference
from alignment_core.geometry.rotations import cross3
from alignment_core.navigation.strapdown import Strapdown
from alignment_core.samples import MasterSample

Extras = tuple[np.ndarray, np.ndarray | None, RateInputs | None]   # (w_n, a_n, rate) of a Match
Interval = tuple[int, float, np.ndarray, np.ndarray]                 # (t_end ns, h s, raw gyro rate, dv_n)


class Live(Protocol):
    """What `at_match` reads of the live solution (matching.py's LiveSolution): its strapdown,
    for the nav frame's own rate under rate matching."""
    ins: Strapdown


def interval_containing(intervals: deque[Interval], t_v: int) -> Interval | None:
    """The IMU interval with t_end - h < t_v < t_end: the deck spot's acceleration for a validity
    time between IMU samples (a master stamp with transport jitter)."""
    for item in reversed(intervals):
        if item[0] - item[1] * 1e9 < t_v < item[0]:
            return item
        if item[0] < t_v:
            return None
    return None


class DelayInputs:
    """The IMU intervals of the last `span_ns` and the previous master sample; `at_match` makes a
    match's extras from them."""

    def __init__(self, cfg: FilterConfig, imu_rate_hz: float, span_ns: int, counters: Counters) -> None:
        self._cfg = cfg
        self._counters = counters
        self.intervals: deque[Interval] = deque(maxlen=int(span_ns / (1e9 / imu_rate_hz)) + 8)
        self._prev_master: tuple[int, np.ndarray, np.ndarray, np.ndarray] | None = None   # t_v, C_m, v_b, w_b

    def record_interval(self, t_ns: int, h: float, gyro: np.ndarray, dv_n: np.ndarray) -> None:
        """An IMU interval ending at t_ns (length h s, raw gyro rate, nav-frame velocity change)."""
        self.intervals.append((t_ns, h, gyro, dv_n))

    def restart(self) -> None:
        """Forget the intervals and the previous master sample (after a bridged IMU gap)."""
        self.intervals.clear()
        self._prev_master = None

    def at_match(self, live: Live, t_v: int, m: MasterSample, ref: Reference, spot: SpotAcceleration | None,
                 bg: np.ndarray) -> Extras:
        """(w_n, a_n, rate inputs) of the match of m at t_v with reference ref: the master's
        nav-frame body rate; the deck spot's acceleration, from the slave's velocity change over
        the IMU interval ending at t_v while parked, else from the master's last two samples with
        today's lever arm and LDV velocity (the undelayed parts); the gyro (less its bias
        estimate bg) and master rates over that interval when the previous master sample started
        it. Under delay_acceleration reference the spot's acceleration is the quadratic fit to the
        master samples (`spot`, reference_force.py) whenever it has one: the slave's carries the
        airframe's own motion on its gear, and two master samples 20 ms apart their velocity noise
        times 70 per m/s (both errors in the regressor pull the delay toward zero)."""
        c_m, r, v_rel = ref.c_m, ref.r, ref.v_rel
        w_m = m.w_b             # the kernel's product is numpy's where numpy's would be BLAS's
        w_n = ref.w_n if ref.w_n is not None and type(w_m) is np.ndarray and w_m.flags.c_contiguous \
            and w_m.flags.aligned else c_m @ w_m
        prev, self._prev_master = self._prev_master, (t_v, c_m, m.v_b, m.w_b)
        a_n = None
        if self._cfg.delay_acceleration == 'reference' and spot is not None:
            a_n = spot.acceleration()                       # the fit, when it has one
        iv = None                                           # the IMU interval ending at t_v, where needed
        if a_n is None or self._cfg.rate_matching:
            for item in reversed(self.intervals):
                if item[0] == t_v:
                    iv = item
                    break
                if item[0] < t_v:
                    break
        if a_n is None:
            parked_iv = iv if iv is not None else interval_containing(self.intervals, t_v)
            if not ref.moving and parked_iv is not None:
                a_n = parked_iv[3] / parked_iv[1]
            elif ref.moving and prev is not None and prev[0] < t_v:
                fixed = cross3(m.w_b, r) + v_rel
                a_n = (c_m @ (m.v_b + fixed) - prev[1] @ (prev[2] + cross3(prev[3], r) + v_rel)) \
                    / ((t_v - prev[0]) * 1e-9)
        rate = None
        if self._cfg.rate_matching and iv is not None and prev is not None \
                and t_v - prev[0] == int(round(iv[1] * 1e9)):
            w_in = live.ins.w_ie + live.ins.w_en
            w_prev = prev[1] @ prev[3]
            w_mean = 0.5 * (w_n + w_prev)
            w_b = iv[2] - bg
            rate = RateInputs(w_b=w_b, dtheta=w_b * iv[1], omega_n=w_mean + w_in, w_n=w_mean,
                              w_dot_n=(w_n - w_prev) / iv[1], h=iv[1])
        if rate is None and self._cfg.rate_matching:
            self._counters.rate_unmatched += 1
        return w_n, a_n, rate
