"""Input plausibility: what a sample must satisfy before the engine queues it (docs/engine.md,
input plausibility). A non-finite value, a master quaternion off unit norm, a value beyond the
sensor's or the vehicle's physical range, or a stamp far ahead of every other stream (the outlier,
not the samples after it) is rejected and counted by reason; a master quaternion within the
tolerance is normalised. The filter node adds 'frame_id' (it never passes such a message on).

A compiled test first accepts the usual sample in one call (`imu_plausible`, `master_plausible`,
`norm_within`, `beam_plausible`): it says yes only where the rules surely do, with a margin on
every norm, and leaves everything else (a rejection, a sample near a limit, a quaternion to
normalise, arrays that are not 1-D float64) to the rules, so the decisions are the rules' own."""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

from alignment_core.compiled import is_float64_vector, kernel
from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.health import finite
from alignment_core.estimation.outputs import Counters
from alignment_core.samples import DopplerSample, ImuSample, LdvSample, MasterSample
from alignment_core.units import DEG, G0

# reasons a sample is rejected (Counters.rejected_<reason>; the node adds 'frame_id')
REASONS = ('nonfinite', 'out_of_order', 'quaternion', 'range', 'future_stamp', 'ldv_mode')
UNIT_ROUNDING = 1e-12      # |norm - 1| below this is rounding: the quaternion is used as given
NORM_MARGIN = 1e-9         # the compiled accept's relative margin on a norm against its limit
UNIT_MARGIN = 1e-14        # ... and on a unit quaternion's or beam's norm (hypot and a plain sqrt differ by ulps)
BEAM_UNIT_TOLERANCE = 1e-6  # a beam's line of sight is a unit vector to this
NORM_RANGE = (1e-150, 1e150)  # limits the compiled norm test takes (squares normal, none overflowing)


@dataclass(frozen=True)
class Limits:
    """The plausibility limits in SI units (rad/s, m/s^2, m/s, m, ns), from filter.*, as floats
    (a configured int or numpy scalar converted: the compiled accepts take floats)."""
    quaternion_tol: float
    gyro_max: float                  # per axis
    accel_max: float                 # per axis
    master_speed: float
    master_rate: float
    position: float
    ldv_speed: float
    doppler_speed: float
    ldv_beam: bool
    future_ns: int                   # lead over every other stream that makes a stamp the outlier
    silence_ns: int

    @classmethod
    def of(cls, cfg: FilterConfig) -> Limits:
        """The streams' known latencies add to the lead a stamp may legitimately have."""
        lead = cfg.future_stamp_s + max(cfg.master_latency_s, cfg.ldv_latency_s, cfg.doppler_latency_s)
        return cls(float(cfg.quaternion_norm_tolerance), float(cfg.imu_gyro_range_dps * DEG),
                   float(cfg.imu_accel_range_g * G0), float(cfg.master_speed_max_mps),
                   float(cfg.master_rate_max_dps * DEG), float(cfg.position_max_m), float(cfg.ldv_speed_max_mps),
                   float(cfg.doppler_speed_max_mps), cfg.ldv_mode == 'beam', int(round(lead * 1e9)),
                   int(round(cfg.silence_warn_s * 1e9)))


def _norm(a: Any) -> float:
    """|a| of a 3-vector without overflow (hypot scales)."""
    x, y, z = a.tolist()
    return math.hypot(x, y, z)


def _max_abs(a: Any) -> float:
    x, y, z = a.tolist()
    return max(abs(x), abs(y), abs(z))


def imu_reason(s: ImuSample, lim: Limits) -> str:
    """'' if plausible, else why not: a rate or specific force beyond the IMU's full scale."""
    g, a = s.gyro, s.accel
    if is_float64_vector(g) and is_float64_vector(a) and imu_plausible(g, a, lim.gyro_max, lim.accel_max):
        return ''
    return imu_rules(s, lim)


def imu_rules(s: ImuSample, lim: Limits) -> str:
    """imu_reason's rules, which decide whatever the compiled accept does not."""
    if not finite(s.gyro, s.accel):
        return 'nonfinite'
    if _max_abs(s.gyro) > lim.gyro_max or _max_abs(s.accel) > lim.accel_max:
        return 'range'
    return ''


def master_check(s: MasterSample, lim: Limits) -> tuple[MasterSample | None, str]:
    """(the sample, '') if plausible, its quaternion normalised when it is off unit norm by more
    than rounding (and by no more than the tolerance), else (None, why not)."""
    if is_float64_vector(s.p_w) and is_float64_vector(s.q_nb) and is_float64_vector(s.v_b) \
            and is_float64_vector(s.w_b) and master_plausible(
                s.p_w, s.q_nb, s.v_b, s.w_b, lim.quaternion_tol, lim.master_speed, lim.master_rate, lim.position):
        return s, ''
    return master_rules(s, lim)


def master_rules(s: MasterSample, lim: Limits) -> tuple[MasterSample | None, str]:
    """master_check's rules, which decide whatever the compiled accept does not."""
    if not finite(s.p_w, s.q_nb, s.v_b, s.w_b):
        return None, 'nonfinite'
    n = math.hypot(*s.q_nb.tolist())
    if abs(n - 1.0) > lim.quaternion_tol:
        return None, 'quaternion'
    if _norm(s.v_b) > lim.master_speed or _norm(s.w_b) > lim.master_rate or _norm(s.p_w) > lim.position:
        return None, 'range'
    if abs(n - 1.0) > UNIT_ROUNDING:
        return dataclasses.replace(s, q_nb=s.q_nb / n), ''
    return s, ''


def ldv_reason(s: LdvSample, lim: Limits) -> str:
    """A valid LDV sample must be finite and slower than the deck run allows, and of the LDV's
    kind (filter.ldv_mode): a beam sample carries a unit line of sight, a vector one none."""
    if s.valid and (s.beam is not None) == lim.ldv_beam and is_float64_vector(s.v_s) and (
            norm_within(s.v_s, 3, lim.ldv_speed) if s.beam is None
            else is_float64_vector(s.beam) and beam_plausible(s.v_s, s.beam, lim.ldv_speed)):
        return ''
    return ldv_rules(s, lim)


def ldv_rules(s: LdvSample, lim: Limits) -> str:
    """ldv_reason's rules, which decide whatever the compiled accept does not."""
    if not s.valid:
        return ''
    if not finite(s.v_s) or (s.beam is not None and not finite(s.beam)):
        return 'nonfinite'
    if (s.beam is not None) != lim.ldv_beam or (
            s.beam is not None and abs(_norm(s.beam) - 1.0) > BEAM_UNIT_TOLERANCE):
        return 'ldv_mode'
    return 'range' if _norm(s.v_s) > lim.ldv_speed else ''


def doppler_reason(s: DopplerSample, lim: Limits) -> str:
    """A valid radar sample must be finite, with a finite sigma, and slower than the aircraft."""
    if not s.valid:
        return ''
    if not (finite(s.v_b) and math.isfinite(s.sigma)):
        return 'nonfinite'
    return 'range' if _norm(s.v_b) > lim.doppler_speed or s.sigma < 0.0 else ''


@kernel
def within(a, limit):
    """True if a (3,) is finite with every |a_i| <= limit (`_max_abs(a) > limit` is False)."""
    if a.shape[0] != 3:
        return False
    for i in range(3):
        if not abs(a[i]) <= limit or not (-math.inf < a[i] < math.inf):
            return False
    return True


@kernel
def norm_within(a, size, limit):
    """True if a (size,) is finite and surely |a| <= limit (a float): |a| from its plain sum of
    squares, within NORM_MARGIN of the limit (hypot's |a| and this one differ by a few ulps;
    nearer the limit the rules decide). Only for a limit in NORM_RANGE, where neither the squares
    nor the bound's can overflow or lose their precision below the normal range (each component
    is first checked against the limit: no square exceeds the limit's)."""
    if a.shape[0] != size or not NORM_RANGE[0] < limit < NORM_RANGE[1]:
        return False
    ss = 0.0
    for i in range(size):
        if not abs(a[i]) <= limit:             # NaN and inf too
            return False
        ss += a[i] * a[i]
    bound = limit * (1.0 - NORM_MARGIN)
    return ss <= bound * bound


@kernel
def near_unit(a, size, tolerance):
    """True if a (size,) is finite and its norm surely within tolerance of 1 (UNIT_MARGIN: a
    plain square root against the rules' hypot); no component of a unit vector exceeds 1, so a
    larger one (NaN and inf included) is no unit vector here, and no square overflows."""
    if a.shape[0] != size:
        return False
    ss = 0.0
    for i in range(size):
        if not abs(a[i]) <= 2.0:
            return False
        ss += a[i] * a[i]
    return abs(math.sqrt(ss) - 1.0) + UNIT_MARGIN <= tolerance


@kernel
def imu_plausible(gyro, accel, gyro_max, accel_max):
    """True if imu_reason's rules surely accept (gyro, accel): finite and within full scale."""
    return within(gyro, gyro_max) and within(accel, accel_max)


@kernel
def master_plausible(p_w, q_nb, v_b, w_b, quaternion_tol, speed, rate, position):
    """True if master_check's rules surely pass the sample on as given: finite, within range, and
    its quaternion's norm within rounding of 1 (and the tolerance), with the margins above."""
    if not (norm_within(v_b, 3, speed) and norm_within(w_b, 3, rate) and norm_within(p_w, 3, position)):
        return False
    return near_unit(q_nb, 4, min(quaternion_tol, UNIT_ROUNDING))


@kernel
def beam_plausible(v_s, beam, speed):
    """True if ldv_reason's rules surely accept a beam sample (v_s, beam): both finite, v_s
    within speed and the line of sight a unit vector to BEAM_UNIT_TOLERANCE (margins as above)."""
    return norm_within(v_s, 3, speed) and near_unit(beam, 3, BEAM_UNIT_TOLERANCE)


class InputGate:
    """The plausibility of every sample pushed, the stamp guard and the rejection counts. A stamp
    is the outlier when it jumps ahead of its own stream's previous one and of every other
    stream's latest by more than `future_ns` (a stream that resumes after a silence does not:
    the others have moved on with it). A stream's first sample is never taken for the outlier."""

    def __init__(self, cfg: FilterConfig, counters: Counters, streams: tuple[str, ...]) -> None:
        self.limits = Limits.of(cfg)
        self._counters = counters
        self._latest: dict[str, int | None] = {k: None for k in streams}
        self._newest: int | None = None          # the newest stamp taken, of any stream
        self._newest_then: dict[str, int | None] = {k: None for k in streams}   # ... when each last delivered
        self._first: int | None = None
        self.last_rejection = ''          # why the last sample was rejected ('' if accepted)

    def check(self, stream: str, s: Any) -> Any:
        """The sample to queue (a master sample possibly normalised) or None (rejected, counted)."""
        lim = self.limits
        given = s
        if stream == 'imu':
            why = imu_reason(s, lim)
        elif stream == 'master':
            s, why = master_check(s, lim)
        elif stream == 'ldv':
            why = ldv_reason(s, lim)
        else:
            why = doppler_reason(s, lim)
        if not why:
            prev = self._latest[stream]                 # _future's first test, inline: most stamps pass it
            if prev is not None and given.t_ns - prev > lim.future_ns and self._future(stream, given.t_ns):
                why = 'future_stamp'
        self.last_rejection = why
        if why:
            name = f'rejected_{why}'
            setattr(self._counters, name, getattr(self._counters, name) + 1)
            return None
        if s is not given:
            self._counters.quaternion_normalised += 1
        return s

    def reject_out_of_order(self) -> None:
        self._counters.rejected_out_of_order += 1
        self.last_rejection = 'out_of_order'

    def accepted(self, stream: str, t_ns: int) -> None:
        """Record a stamp the stream's queue took."""
        self._latest[stream] = t_ns
        if self._first is None:
            self._first = t_ns
        if self._newest is None or t_ns > self._newest:
            self._newest = t_ns
        self._newest_then[stream] = self._newest

    def _future(self, stream: str, t_ns: int) -> bool:
        prev = self._latest[stream]
        fut = self.limits.future_ns
        if prev is None or t_ns - prev <= fut:
            return False
        others = [v for k, v in self._latest.items() if k != stream and v is not None]
        return bool(others) and t_ns - max(others) > fut

    def forget(self, stream: str) -> None:
        """A stream the run does not have (no LDV): never reported silent."""
        self._latest.pop(stream, None)

    def quiet_since(self, stream: str) -> int | None:
        """The newest stamp of any stream when `stream` last delivered (the first stamp of any
        stream if it never did; None before any): how far the others ran since is its silence,
        however far behind the others its own stamps arrive."""
        then = self._newest_then.get(stream)
        return self._first if then is None else then

    def waiting_for(self, streams: tuple[str, ...] = ('master', 'ldv')) -> tuple[str, ...]:
        """Arrival liveness (for a node to say what it waits for; not a function of the stamps
        alone): the streams that delivered nothing while the newest stamp of any stream advanced
        by more than silence_ns (or that never delivered while the others ran that long). A
        stream that runs behind the others but keeps delivering is not one of them."""
        if self._newest is None or self._first is None:
            return ()
        lim = self.limits.silence_ns
        out = []
        for k in streams:
            if k not in self._latest:
                continue
            since = self.quiet_since(k)
            if since is not None and self._newest - since > lim:
                out.append(k)
        return tuple(out)
