"""When the aircraft starts to move on the deck: the launch (a confirmed run of fast LDV samples
that the accelerometers felt) and slow creep before it (a median of the LDV over a window). The
engine consults it once per LDV sample, feeds it the IMU's specific force along x until the
launch, and applies what it decides (docs/engine.md, launch detection)."""
from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from alignment_core.compiled import as_float64, kernel
from alignment_core.samples import LdvSample


class LdvDecision(NamedTuple):
    """What the engine does with one LDV sample. `record`: the samples to record now, in stamp
    order (empty: the sample is held back and no match may run); `launch_ns`: the validity time
    of a launch confirmed by this sample, if any; `creep`: creep was first seen at this sample.
    (A NamedTuple: one is made per LDV sample, at a third of a frozen dataclass's cost.)"""
    record: tuple[LdvSample, ...] = ()
    launch_ns: int | None = None
    creep: bool = False
    not_felt: bool = False            # a run of fast samples the accelerometers did not feel: no launch


@dataclass(frozen=True)
class LaunchThresholds:
    """The detector's tuning (filter.*): speeds in m/s, counts in samples, latency in ns."""
    launch_mps: float
    confirm_samples: int
    creep_mps: float                  # 0: no creep detection
    creep_window: int
    ldv_latency_ns: int = 0
    felt_fraction: float = 0.0        # the IMU's velocity change along x must reach this fraction of
    felt_tolerance_mps: float = 0.2   # the run's speed, less this (0 fraction: LDV alone decides)


FELT_MARGIN_NS = 100_000_000          # the IMU's velocity change is summed from 0.1 s before the run
FELT_BASE_NS = 1_000_000_000          # against the mean specific force over the second before that
FELT_BLIND_NS = 10_000_000_000        # an LDV blind before a run: the run began at most this long before it
ONSET_WINDOW_NS = 500_000_000         # a blind run: the parked level is the felt speed's lowest over this
ONSET_SLOPE_INTERVALS = 5             # ... and the felt speed's slope where it leaves the level, over these
ONSET_SLOPE_MIN_MPS2 = 1.0            # ... a stroke's (a parked deck's residual motion is a few tenths)
FELT_SPAN_NS = FELT_BLIND_NS + FELT_MARGIN_NS + FELT_BASE_NS + 3_000_000_000   # IMU kept (+ latency, confirmation)


class LaunchDetector:
    """Parked until the LDV shows a launch (`confirm_samples` valid samples in a row faster than
    `launch_mps`, dated at the first of them, or where the IMU felt it begin when the LDV was
    blind before it) or creep (the per-axis median of the last `creep_window` valid samples
    faster than `creep_mps`); after creep, a run of samples faster than the median by
    `launch_mps` is the launch. Samples above the launch threshold are held
    back until their run is confirmed or broken."""

    def __init__(self, limits: LaunchThresholds, imu: deque[tuple[int, float, float]] | None = None) -> None:
        """imu: the record of the IMU's intervals to read (the engine's, shared with the deck run and
        fed by it); by default its own, fed by `observe_imu`."""
        self.limits = limits
        self._moving = False
        self._t_moving: int | None = None      # validity time from which the aircraft moves on the deck
        self._t_launch: int | None = None      # validity time of the launch
        self._held: list[LdvSample] = []       # fast samples (and gaps among them), not yet confirmed
        self._held_fast = 0
        self._fast_run: list[int] = []         # stamps of fast samples in a row while creeping
        self._recent: deque[np.ndarray] = deque(maxlen=max(limits.creep_window, 1))
        self._recent_sum = np.zeros(3)         # running sum of _recent (a cheap trigger for the median)
        self._window_speed = 0.0               # |mean| of a full _recent (take_valid)
        self._imu = deque() if imu is None else imu   # (t_end, specific force along x, h)
        self.felt_margin_mps = np.inf          # the last check's velocity change minus what it needed
        self._t_last_valid: int | None = None  # validity time of the last valid LDV sample (until one is
                                               # valid: a second into the data, so the check has a baseline)
        self._blind = True                     # the last LDV sample was invalid (or none was valid yet)
        self._run_from = 0                     # the earliest validity time the run being checked began
        self._run_speed = 0.0                  # the speed its first sample showed (relative to before)

    @property
    def moving(self) -> bool:
        return self._moving

    @property
    def t_moving_ns(self) -> int | None:
        return self._t_moving

    @property
    def t_launch_ns(self) -> int | None:
        return self._t_launch

    def observe_imu(self, t_ns: int, f_x: float, h: float) -> None:
        """One IMU interval ending at t_ns: mean specific force along the aircraft x axis, length h s."""
        if self.limits.felt_fraction <= 0.0:
            return
        q = self._imu
        q.append((t_ns, f_x, h))
        while q[0][0] < t_ns - FELT_SPAN_NS:
            q.popleft()

    def _start_run(self, t_v: int, was_blind: bool, since: int, speed: float) -> None:
        """A run of fast samples starts with the one valid at t_v. If the LDV saw nothing valid just
        before it (a dropout; out of range at the spot since its first sample), the motion may
        have begun in the blind time: from `since`, at most FELT_BLIND_NS earlier (an LDV never
        valid yet: from a second into its data, the check's baseline the second before)."""
        self._run_from = min(t_v, max(since, t_v - FELT_BLIND_NS)) if was_blind else t_v
        self._run_speed = speed

    def _felt(self, t_v: int, speed: float) -> bool:
        """Did the accelerometers feel a run that started at validity time t_v and reached `speed`
        (relative to the motion before it)? The velocity change along x summed from FELT_MARGIN
        before t_v, less the mean specific force of the second before that (gravity on the pitched
        deck, the deck's own acceleration), must reach felt_fraction speed - felt_tolerance. A run
        the IMU cannot have seen yet (no intervals) is not held against the LDV. t_v is the
        earliest time the run may have begun (`_start_run`): a stroke the LDV first sees halfway
        must not be taken for a reading the IMU never felt."""
        lim = self.limits
        need = lim.felt_fraction * speed - lim.felt_tolerance_mps
        if lim.felt_fraction <= 0.0 or need <= 0.0 or not self._imu:
            return True
        split = t_v - FELT_MARGIN_NS
        dv = h_sum = 0.0
        for t, f, h in self._imu:
            if t > split:
                dv += f * h
                h_sum += h
        if h_sum == 0.0:
            return True
        self.felt_margin_mps = dv - self._baseline(split) * h_sum - need
        return self.felt_margin_mps >= 0.0

    def _baseline(self, split: int) -> float:
        """The mean specific force along x over the second before `split` (0 without intervals)."""
        base_f = base_h = 0.0
        for t, f, h in self._imu:
            if split - FELT_BASE_NS < t <= split:
                base_f += f * h
                base_h += h
        return base_f / base_h if base_h > 0.0 else 0.0

    def _felt_speed(self, t_from: int) -> list[tuple[int, float]]:
        """(t_end, velocity change along x since FELT_MARGIN before t_from, less the baseline) of
        the IMU intervals after that."""
        split = t_from - FELT_MARGIN_NS
        base = self._baseline(split)
        out = []
        dv = 0.0
        for t, f, h in self._imu:
            if t > split:
                dv += (f - base) * h
                out.append((t, dv))
        return out

    def _onset(self, t_v: int) -> int:
        """When a run the LDV first saw at t_v began, if the LDV was blind before it: back from t_v,
        the IMU's felt speed falls by nine tenths of the speed the LDV saw at t_v; back from there
        to the last interval within the felt tolerance of the parked level (its lowest over the
        ONSET_WINDOW_NS before; the window moved back while its lowest sits at its start on a
        stroke's slope: parked, the felt speed is the deck's residual motion about a level); and
        from that interval back along the ramp to the level (2 rise / slope, if the slope is a
        stroke's: an interval early for a step, tens of ms late for a linear ramp). Never before
        the LDV last saw it parked; t_v itself when the LDV saw the run start, the IMU is not
        watched, or the fall is not in the IMU's record."""
        if self._run_from >= t_v or self.limits.felt_fraction <= 0.0 or self._run_speed <= 0.0:
            return t_v
        felt = [(t, dv) for t, dv in self._felt_speed(self._run_from) if t <= t_v]
        if not felt:
            return t_v
        top = felt[-1][1] - 0.9 * self._run_speed
        k = len(felt) - 1
        while k >= 0 and felt[k][1] > top:
            k -= 1
        if k < 0:
            return t_v
        end = k
        while True:                                # the level: a window's lowest, moved back while on the ramp
            low_i = j = end
            while j >= 0 and felt[j][0] >= felt[end][0] - ONSET_WINDOW_NS:
                if felt[j][1] < felt[low_i][1]:
                    low_i = j
                j -= 1
            if low_i == j + 1 > 0 and self._slope(felt, low_i) >= ONSET_SLOPE_MIN_MPS2:
                end = low_i
                continue
            break
        low = felt[low_i][1]
        j = k
        while felt[j][1] > low + self.limits.felt_tolerance_mps:
            j -= 1
        rise, slope = felt[j][1] - low, self._slope(felt, j)
        if rise > 0.0 and slope >= ONSET_SLOPE_MIN_MPS2:     # back along the ramp to the level: 2 rise / slope
            t_on = felt[j][0] - min(2.0 * rise / slope * 1e9, ONSET_WINDOW_NS)
            while j > 0 and felt[j][0] > t_on:
                j -= 1
        return max(felt[j][0], self._run_from)

    @staticmethod
    def _slope(felt: list[tuple[int, float]], j: int) -> float:
        """The felt speed's slope (m/s^2) over the ONSET_SLOPE_INTERVALS after index j (0 at the end)."""
        m = min(ONSET_SLOPE_INTERVALS, len(felt) - 1 - j)
        if m <= 0:
            return 0.0
        return (felt[j + m][1] - felt[j][1]) / ((felt[j + m][0] - felt[j][0]) * 1e-9)

    def observe(self, s: LdvSample) -> LdvDecision:
        """The decision for the next LDV sample (stamp order)."""
        lim = self.limits
        speed = 0.0
        if s.valid:
            rl = self._recent
            full = len(rl) == rl.maxlen
            v = as_float64(s.v_s)
            speed, self._window_speed = take_valid(self._recent_sum, rl[0] if full else v, v, full,
                                                   lim.creep_window)
            rl.append(v)
        fast = speed > lim.launch_mps
        valid_at = s.t_ns - lim.ldv_latency_ns
        if self._t_last_valid is None:
            self._t_last_valid = valid_at + FELT_BASE_NS + FELT_MARGIN_NS
        was_blind, since = self._blind, self._t_last_valid
        self._blind = not s.valid
        if s.valid:
            self._t_last_valid = valid_at
        launch = None
        if self._moving and self._t_launch is None:     # creeping: watch for the stroke
            median = self._median_speed()
            if s.valid and speed > lim.launch_mps + median:
                if not self._fast_run:
                    self._start_run(valid_at, was_blind, since, speed - median)
                self._fast_run.append(s.t_ns)
                if len(self._fast_run) >= lim.confirm_samples:
                    t_v = self._fast_run[0] - lim.ldv_latency_ns
                    if not self._felt(self._run_from, speed - median):
                        self._fast_run.clear()
                        return LdvDecision((s,), None, False, True)
                    launch = self._launch(self._onset(t_v))
            elif s.valid:
                self._fast_run.clear()
        if self._moving:
            return LdvDecision((s,), launch)
        creep = False
        if fast or (self._held and not s.valid):
            if not self._held:
                self._start_run(valid_at, was_blind, since, speed)
            self._held.append(s)
            self._held_fast += fast
            if self._held_fast < lim.confirm_samples:
                return LdvDecision()
            t_v = self._held[0].t_ns - lim.ldv_latency_ns
            top = max(float(np.sqrt(h.v_s @ h.v_s)) for h in self._held if h.valid)
            if not self._felt(self._run_from, top):
                return LdvDecision(self.release(), None, False, True)   # recorded as parked
            launch = self._launch(self._onset(t_v))
        elif self._creeping():
            self._moving = True
            self._t_moving = s.t_ns - lim.ldv_latency_ns
            creep = True
        if not self._held:
            return LdvDecision((s,), launch, creep)
        held = self.release()
        return LdvDecision(held if fast else (*held, s), launch, creep)

    def release(self) -> tuple[LdvSample, ...]:
        """The held samples, forgotten (at the end of the data: an unconfirmed run is parked)."""
        held, self._held, self._held_fast = tuple(self._held), [], 0
        return held

    def _launch(self, t_v: int) -> int:
        if not self._moving:
            self._moving = True
            self._t_moving = t_v
        self._t_launch = t_v
        return t_v

    def _creeping(self) -> bool:
        """The per-axis median of the last `creep_window` valid samples exceeds `creep_mps` in norm
        (the median ignores single spikes; for a 1 cm/s LDV and 25 samples its noise is ~2.5 mm/s
        per axis). The median is only computed when the window's mean is at least half as fast."""
        lim = self.limits
        w = lim.creep_window
        if lim.creep_mps <= 0.0 or len(self._recent) < w:
            return False
        if self._window_speed <= 0.5 * lim.creep_mps:
            return False
        return self._median_speed() > lim.creep_mps

    def _median_speed(self) -> float:
        """|per-axis median| of the recent valid samples (0 with none)."""
        if not self._recent:
            return 0.0
        med = np.median(np.asarray(self._recent), axis=0)
        return float(np.sqrt(med @ med))


@kernel
def norm3(v):
    """|v| of a vector (3,): the square root of v . v, the dot product through BLAS as numpy's
    v @ v (the same number)."""
    return math.sqrt(np.dot(v, v))


@kernel
def slide(total, old, new, full):
    """The running sum total (3,) of a window, in place: less the sample leaving it (old, if the
    window is full), plus the one entering it (new); element by element, as total -= old then
    total += new."""
    for i in range(total.shape[0]):
        if full:
            total[i] -= old[i]
        total[i] += new[i]


@kernel
def mean_speed(total, count):
    """|total / count| of a window's sum (3,) over its count of samples (total / count, then its
    norm as norm3)."""
    mean = total / float(count)
    return math.sqrt(np.dot(mean, mean))


@kernel
def take_valid(total, old, new, full, count):
    """A valid sample (3,) into the window: slide the running sum total (3,) from old to new, and
    return (norm3 of the sample, mean_speed of the window's sum over count samples): the three
    kernels in one call."""
    slide(total, old, new, full)
    return norm3(new), mean_speed(total, count)
