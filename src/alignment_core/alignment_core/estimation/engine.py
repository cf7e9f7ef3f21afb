"""The transfer-alignment estimator: slave strapdown + error-state filter, fed in stamp order
from the slave IMU, the LDV and the master INS (it never sees truth). The error model
(`filter.model`, models/) and the filter algorithm (`filter.algorithm`, filters/) are chosen at
run time; the default (vm15 + kf) is the 15-state velocity-matching Kalman filter.

Events at equal stamps run IMU first, then LDV, then master: the IMU sample stamped t ends
the interval at t, so the slave solution is at t when the master sample at t is matched.

Time of validity (validity_time.py): master data stamped t are valid at t_v = t -
`master_latency_s`, LDV data at their stamp - `ldv_latency_s` (the latencies the user
knows; sensor_timing.py stamps data valid at t as t + latency). A master sample waits until
the slave has reached t_v and the LDV has a sample at or after t_v, then is matched against
the slave solution at t_v (kept for the last IMU steps, interpolated between them) and the
LDV at t_v (interpolated between its samples, so master and LDV may run at different rates;
an LDV slower than the master has its noise weighted once per LDV interval). With zero
latencies and equal rates this is today's match at equal stamps, operation for operation.
The update at a past time: the innovation uses the slave at t_v, while the filter's error
state is the live one at t_ins; over the few IMU steps in between x(t_ins) = Phi x(t_v) (the
product of the stored transitions; process noise over the latency neglected), so the
measurement matrix is H Phi^-1 (delay-aware H). Phi differs from I by ~ f h (g 20 ms phi:
2e-5 m/s per 0.3' of tilt at 20 ms), so applying H itself would also do at these latencies;
H Phi^-1 stays right at larger ones. The correction is fed back into the live solution and,
identically, into the stored past ones. The Doppler radar is matched the same way at its
stamp - `doppler_latency_s`.

Initialisation (first master sample): the slave copies the master attitude times the
nominal mounting on the deck (`heading_on_deck_deg`: C_a^s = Rz(-heading)), velocity and
position at its lever arm, at the master's validity time; IMU samples already received
after it are replayed. Lever-arm treatment
(`lever_arm_treatment`, seed 002): `compensation` (default) puts C_m (w_m x r) into the
reference; `none` leaves it out; `butterworth` leaves it out and low-pass filters the velocity
difference (filters/lowpass.py: a lag the error model does not contain). The aircraft is
parked (zero deck velocity, surveyed spot) until the LDV sees it move; from then on its deck
displacement is the integral of the LDV velocity. It moves when `launch_confirm_samples` LDV
samples in a row exceed `launch_detect_mps` (the launch, dated at the first of them: one noisy
sample is not a launch) or when the median of the last `creep_window_samples` exceeds
`creep_detect_mps` (hold-back creep, taxiing: slow motion that is not the launch); the master
matches wait for the confirmation. Known limitation: a nonlinear model (seed000_large_angle) has
no transition matrices, so a match made after the slave moved on (a latency, or the two matches
that wait for the launch confirmation) meets the live error state without H Phi^-1. Closed loop:
each update is fed back into the strapdown (the model's `feedback`).

Published misalignment (the model's `misalignment`): mu_hat = log((C_m^n C_nom)^T C_a^n_hat),
the aircraft IMU axes relative to the master's turned by the nominal heading on deck
(aircraft FLU axes), or the mounting state for seed003; evaluated at each matching update
(master and slave at the same validity time) and held once matching stops (aircraft off the
deck); its 1-sigma from the covariance, in aircraft axes. Outputs are emitted at master
stamps, every `output_rate_hz` period from the first.

Numerical breakdown (a LinAlgError or non-finite value in predict or update, a non-finite or
non-positive variance after an update, or a non-finite output): counted
(`numerical_failures`), and the filter stops; the last good estimate is published from then
on with healthy=False while the slave runs free inertial (a node keeps running).

Known-event process noise (`launch_accel_noise_mps2`, off by default): white velocity noise of
that density on the velocity states for `launch_noise_s` after the LDV detects the launch,
so the covariance covers the release shock and nose-gear vibration the model lacks.
`stf_lambda_max` caps the strong tracking factor(s).

Algorithms x models (config validation rejects the other combinations with a message):

    model                 kf stf stf_multiple fading fading_tested carlson ud combined | ekf ukf ckf | float32
    vm15, vm12             x  x      x          x         x          x     x     x     |  x   x   x  | linear algs
    seed000_6              x  x      x          x         x          x     x     x     |  x   x   x  | linear algs
    seed002_10             x  x      x          x         x          x     x     x     |  x   x   x  | linear algs
    seed003_21, _24        x  x      x          x         x          x     x     x     |  x   x   x  | linear algs
    seed000_large_angle    -  -      -          -         -          -     -     -     |  x   x   x  | no
    seed001_13             x  -      -          x         x          x     x     x     |  x   x   x  | linear algs

On a linear model EKF = KF and UKF/CKF compute the KF's result (their linear predict/update are
exact). The strong tracking filter's innovation recursion V0 assumes one measurement stream:
seed001_13 alternates LDV/Doppler innovations of different noise levels, which drives its
fading factor up without bound, so stf/stf_multiple are refused there. float32 is accepted for
every linear algorithm, but on the 21/24-state seed003 models the non-square-root ones (kf,
stf, fading) can break down in single precision (seed 003's own finding); carlson, ud and
combined do not. ekf/ukf/ckf run in float64 only. `lever_arm_states` needs `lever_arm_treatment:
compensation` (the states are the error of the compensated arm) and a linear model other
than seed001_13; seed001_13 needs `doppler.enabled` (checked by the scenario).

Matching options (models/__init__.py): `attitude_match_axes: yaw` (seed003_* only: a heading
match needs the mounting states), `rate_matching` (vm12, vm15, seed003_*; not with stf /
stf_multiple, whose V0 recursion needs the same rows at every update: the rate rows need the
previous master sample on the IMU grid, so they start at the second), `master_delay_state` (any
linear model but seed001_13). The engine hands them the IMU interval ending at the match (raw
gyro rate, velocity change) and the previous master sample (`_match_extras`).

Doppler (seed001_13): a fourth input stream, /doppler/twist, ordered before the master at
equal stamps; each valid sample is matched at its validity time (models/seed001.py).
"""
from __future__ import annotations

import math
from collections import deque

import numpy as np
from scipy.spatial.transform import Rotation

from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.filter_factory import make_filter
from alignment_core.estimation.filters import (
    KalmanFilter,
)
from alignment_core.estimation.filters.base import solve
from alignment_core.estimation.filters.lowpass import ButterworthLowPass
from alignment_core.estimation.models import (
    Corrections,
    Match,
    Propagation,
    make_model,
)
from alignment_core.estimation.models.base import DV, RateInputs
from alignment_core.estimation.outputs import Counters, Estimate
from alignment_core.geometry import earth
from alignment_core.geometry.rotations import cross3, quat_conj, quat_mul, quat_to_dcm
from alignment_core.navigation.history import LdvHistory, LdvRecord, SlaveHistory
from alignment_core.navigation.ordering import StampMerger
from alignment_core.navigation.strapdown import NavState, Strapdown
from alignment_core.samples import DopplerSample, ImuSample, LdvSample, MasterSample
from alignment_core.units import DEG
from alignment_core.validation import ConfigError

STREAMS = ('imu', 'ldv', 'master')
DOPPLER_STREAMS = ('imu', 'ldv', 'doppler', 'master')   # seed001_13: the Doppler radar too










_reduce = np.add.reduce
_min = np.minimum.reduce


def _finite(*arrays) -> bool:
    """True if every element is finite (a NaN or inf anywhere makes the sum non-finite). Small
    vectors (the samples' 3- and 4-vectors) are summed as Python floats (~0.3 us); larger arrays
    by the ufunc's reduce directly (~1.5 us; np.sum's wrapper costs ~4 us a call)."""
    t = 0.0
    for a in arrays:
        if type(a) is np.ndarray and a.ndim == 1 and a.size <= 16:
            t += sum(a.tolist())
        else:
            t += float(_reduce(a, axis=None))
    return math.isfinite(t)


class NumericalBreakdownError(Exception):
    """The filter's covariance or state stopped being finite and positive definite."""


class TransferAlignment:
    """Stamp-ordered transfer-alignment estimator. Push samples; read `outputs`."""

    def __init__(self, cfg: FilterConfig, plane: earth.TangentPlane, imu_rate_hz: float) -> None:
        self.cfg = cfg
        self.plane = plane
        self.model = make_model(cfg)
        self.streams = DOPPLER_STREAMS if self.model.uses_doppler else STREAMS
        self.merger = StampMerger(self.streams)
        self.counters = Counters()
        self.imu_dt_nominal = 1.0 / imu_rate_hz
        self.out_period_ns = int(round(1e9 / cfg.output_rate_hz))
        self.r0 = np.asarray(cfg.lever_arm_m, dtype=float)
        self.n = self.model.n
        self.labels = self.model.labels
        self.compensate = cfg.lever_arm_treatment == 'compensation'
        self.lowpass = None
        if cfg.lever_arm_treatment == 'butterworth':
            if not cfg.butterworth_cutoff_hz < 0.5 * imu_rate_hz:
                raise ConfigError(f"filter.butterworth_cutoff_hz = {cfg.butterworth_cutoff_hz} must be below the "
                                  f"Nyquist frequency {0.5 * imu_rate_hz} Hz of the {imu_rate_hz} Hz matching rate")
            self.lowpass = ButterworthLowPass(cfg.butterworth_cutoff_hz, imu_rate_hz)
        self.R_moving = np.eye(3) * (cfg.ldv_sigma_mps**2 + cfg.master_velocity_sigma_mps**2)
        self.R_parked = np.eye(3) * (cfg.parked_velocity_sigma_mps**2 + cfg.master_velocity_sigma_mps**2)
        # nominal mounting on the deck: C_a^s = Rz(-heading on deck) (None: the identity)
        psi = cfg.heading_on_deck_deg * DEG
        self.c_nom = None if psi == 0.0 else Rotation.from_rotvec([0.0, 0.0, -psi]).as_matrix()
        # time of validity (validity_time.py): data valid at stamp - latency
        self.master_lat_ns = int(round(cfg.master_latency_s * 1e9))
        self.ldv_lat_ns = int(round(cfg.ldv_latency_s * 1e9))
        self.doppler_lat_ns = int(round(cfg.doppler_latency_s * 1e9))
        span = max(self.master_lat_ns, self.ldv_lat_ns, self.doppler_lat_ns) + int(0.2e9)
        self.span_ns = span
        self.max_step_ns = int(cfg.max_gap_factor * self.imu_dt_nominal * 1e9)
        self.history = SlaveHistory(span)
        self.ldv_history = LdvHistory(span, cfg.ldv_sigma_mps)
        self.imu_buffer: deque[ImuSample] = deque()       # IMU samples before initialisation
        self.pending: deque[tuple[int, MasterSample]] = deque()
        self.t_master: int | None = None          # last master stamp, and the spacing of the last two
        self.master_spacing_ns = 0
        # known-event process noise after the launch (velocity states)
        self.t_launch: int | None = None
        self.launch_ns = int(round(cfg.launch_noise_s * 1e9))
        dv = np.array([k == DV for k in self.model.kinds], dtype=float)
        self.q_launch = np.diag(dv) * cfg.launch_accel_noise_mps2 ** 2 if cfg.launch_accel_noise_mps2 > 0.0 else None
        # rate matching / delay state: the last IMU intervals and the previous master sample
        self.track_intervals = cfg.rate_matching or cfg.master_delay_state
        self.intervals: deque[tuple[int, float, np.ndarray, np.ndarray]] = deque(
            maxlen=int(span / (self.imu_dt_nominal * 1e9)) + 8)     # (t_end, h, raw gyro rate, dv_n)
        self.prev_master: tuple[int, np.ndarray, np.ndarray, np.ndarray] | None = None   # t_v, C_m, v_b, w_b
        self.moving = False
        self.held_ldv: list[LdvSample] = []       # LDV samples above the launch threshold, not yet confirmed
        self.held_fast = 0
        self.t_moving: int | None = None          # validity time from which the aircraft moves on the deck
        self.fast_run: list[int] = []             # stamps of fast samples in a row while creeping
        self.recent_ldv: deque[np.ndarray] = deque(maxlen=max(cfg.creep_window_samples, 1))
        self.recent_sum = np.zeros(3)             # running sum of recent_ldv (a cheap trigger for the median)
        self.ins: Strapdown | None = None
        self.kf: KalmanFilter | None = None
        self.t_ins: int | None = None
        self.t0: int | None = None
        self.next_out: int | None = None
        self.corr = Corrections()
        self.deck_disp = np.zeros(3)
        self.last_ldv: LdvSample | None = None
        self.mu = np.zeros(3)
        self.mu_sigma = np.full(3, cfg.init_attitude_sigma_deg * DEG)
        self.last_x = np.zeros(self.n)
        self.last_nis = math.nan
        self.matching = False
        self.t_doppler_update: int | None = None
        self.healthy = True
        self.failure: str = ''
        self.held: tuple[np.ndarray, np.ndarray, dict] | None = None   # (attitude cov, sigma, diagnostics)
        self.outputs: list[Estimate] = []

    @property
    def bg(self) -> np.ndarray:
        """Accumulated gyro bias estimate (body axes, rad/s)."""
        return self.corr.bg

    @property
    def ba(self) -> np.ndarray:
        """Accumulated accelerometer bias estimate (body axes, m/s^2)."""
        return self.corr.ba

    # ----- input -----
    def push_imu(self, s: ImuSample) -> bool:
        return self._push('imu', s.t_ns, s, s.gyro, s.accel)

    def push_ldv(self, s: LdvSample) -> bool:
        return self._push('ldv', s.t_ns, s, s.v_s if s.valid else np.zeros(3))

    def push_master(self, s: MasterSample) -> bool:
        return self._push('master', s.t_ns, s, s.p_w, s.q_nb, s.v_b, s.w_b)

    def push_doppler(self, s: DopplerSample) -> bool:
        """A Doppler radar sample (only models that use it take this stream; others ignore it)."""
        if not self.model.uses_doppler:
            return True
        return self._push('doppler', s.t_ns, s, s.v_b if s.valid else np.zeros(3), [s.sigma])

    def _push(self, stream: str, t_ns: int, item, *arrays) -> bool:
        if not _finite(*arrays):
            self.counters.rejected_nonfinite += 1
            return False
        if not self.merger.push(stream, t_ns, item):
            self.counters.rejected_out_of_order += 1
            return False
        return True

    def process(self, final: bool = False) -> list[Estimate]:
        """Run every event up to the watermark (all of them if final); return new outputs."""
        n0 = len(self.outputs)
        events = self.merger.flush() if final else self.merger.pop_ready()
        for stream, t, item in events:
            getattr(self, '_on_' + stream)(t, item)
        if final:
            held, self.held_ldv, self.held_fast = self.held_ldv, [], 0
            for h in held:                         # an unconfirmed run at the end: parked
                self._record_ldv(h)
            self._match_pending(final=True)
        return self.outputs[n0:]

    def filter_diagnostics(self) -> dict:
        """The filter's own diagnostics (nis, updates, gated, fading factor(s) if it fades)."""
        if self.held is not None:
            return dict(self.held[2])
        return {} if self.kf is None else self.kf.diagnostics()

    # ----- numerical health -----
    def _fail(self, why: str) -> None:
        """Stop filtering after a breakdown: keep the last good estimate (published with
        healthy=False) and let the slave run free inertial."""
        self.counters.numerical_failures += 1
        if self.healthy:
            self.healthy = False
            self.failure = why
            self.matching = False

    def _check_health(self) -> None:
        """Raise NumericalBreakdownError unless x is finite and P has a finite, positive diagonal
        (a Cholesky of every P would cost more than the update; a negative or non-finite
        variance is how single-precision breakdowns show first)."""
        d = np.diagonal(self.kf.P)
        if not (_finite(self.kf.x, d) and float(_min(d)) > 0.0):
            raise NumericalBreakdownError('covariance not positive definite or not finite')

    # ----- events -----
    def _on_imu(self, t: int, s: ImuSample) -> None:
        self.counters.imu += 1
        if self.ins is None:
            self.imu_buffer.append(s)
            while self.imu_buffer and self.imu_buffer[0].t_ns < t - self.span_ns:
                self.imu_buffer.popleft()
                self.counters.skipped_before_init += 1
            return
        if t <= self.t_ins:
            self.counters.skipped_before_init += 1
            return
        self._propagate(t, s)
        if self.pending:
            self._match_pending()

    def _propagate(self, t: int, s: ImuSample) -> None:
        h = (t - self.t_ins) * 1e-9
        if h > self.cfg.max_gap_factor * self.imu_dt_nominal:
            self.counters.imu_gaps += 1
        bg, ba = self.corr.bg, self.corr.ba
        dth = (s.gyro - bg) * h
        dv = (s.accel - ba) * h
        ins = self.ins
        snap = self.history.record(self.t_ins, ins.s)
        v_start = ins.s.v_n
        f_n = ins.update(dth, dv, h)
        st = ins.s
        if self.track_intervals:
            self.intervals.append((t, h, s.gyro, st.v_n - v_start))
        self.t_ins = t
        self.history.prune(t - self.span_ns, t)
        if not self.healthy:
            return
        p = Propagation(ins.c_start, f_n, ins.w_ie, ins.w_en, st.v_n, st.lat, st.h, h)
        qd = self.model.process_noise(h)
        if self.q_launch is not None and self.t_launch is not None and t - self.t_launch <= self.launch_ns \
                and t > self.t_launch:
            qd = qd + self.q_launch * h
        try:
            if self.model.nonlinear:
                fun, jac = self.model.propagator(p)
                self.kf.predict_nonlinear(fun, qd, jac)
            else:
                phi = self.model.transition(p)
                snap.phi = phi
                self.kf.predict(phi, qd)
        except (np.linalg.LinAlgError, FloatingPointError, ValueError) as e:
            self._fail(f'predict: {e}')

    def _on_ldv(self, t: int, s: LdvSample) -> None:
        """Parked (held back) until the LDV reads more than `launch_detect_mps` on
        `launch_confirm_samples` valid samples in a row: until then the aircraft's deck velocity
        is zero and its spot fixed, so LDV noise is neither integrated into the lever arm (a
        random walk of ~2 cm over 300 s, which through w' x dr looks like tens of ug) nor added
        to the reference velocity. One noisy sample is not a launch (a 1 cm/s LDV exceeds 5 cm/s
        in |v| about once a minute at 100 Hz): samples above the threshold are held back (the
        master matches wait for them) until the run is confirmed, then recorded as moving from
        the first of them, or released as parked when a slower one breaks the run. Each sample
        is kept by its validity time (stamp - ldv_latency_s) for the master's lookup."""
        self.counters.ldv += 1
        speed = float(np.sqrt(s.v_s @ s.v_s)) if s.valid else 0.0
        fast = speed > self.cfg.launch_detect_mps
        if s.valid:
            rl = self.recent_ldv
            if len(rl) == rl.maxlen:
                self.recent_sum -= rl[0]
            rl.append(s.v_s)
            self.recent_sum += s.v_s
        if self.moving and self.t_launch is None:     # creeping: watch for the stroke (launch noise)
            if s.valid and speed > self.cfg.launch_detect_mps + self._median_speed():
                self.fast_run.append(s.t_ns)
                if len(self.fast_run) >= self.cfg.launch_confirm_samples:
                    self._launch(self.fast_run[0] - self.ldv_lat_ns)
            elif s.valid:
                self.fast_run.clear()
        if not self.moving:
            if fast or (self.held_ldv and not s.valid):
                self.held_ldv.append(s)
                self.held_fast += fast
                if self.held_fast < self.cfg.launch_confirm_samples:
                    return
                self._launch(self.held_ldv[0].t_ns - self.ldv_lat_ns)
            elif self._creeping():
                self.moving = True
                self.t_moving = t - self.ldv_lat_ns
                self.counters.creep_detected += 1
            if self.held_ldv:
                held, self.held_ldv, self.held_fast = self.held_ldv, [], 0
                for h in held:
                    self._record_ldv(h)
                if fast:
                    if self.pending:
                        self._match_pending()
                    return
        self._record_ldv(s)
        if self.pending:
            self._match_pending()

    def _creeping(self) -> bool:
        """Slow deck motion (hold-back creep, taxiing): the per-axis median of the last
        `creep_window_samples` valid LDV samples exceeds `creep_detect_mps` in norm (the median
        ignores single spikes; for a 1 cm/s LDV and 25 samples its noise is ~2.5 mm/s per axis)."""
        w = self.cfg.creep_window_samples
        if self.cfg.creep_detect_mps <= 0.0 or len(self.recent_ldv) < w:
            return False
        mean = self.recent_sum / w           # the median is only worth computing when the mean moves
        if float(np.sqrt(mean @ mean)) <= 0.5 * self.cfg.creep_detect_mps:
            return False
        return self._median_speed() > self.cfg.creep_detect_mps

    def _median_speed(self) -> float:
        """|per-axis median| of the recent valid LDV samples (0 with none)."""
        if not self.recent_ldv:
            return 0.0
        med = np.median(np.asarray(self.recent_ldv), axis=0)
        return float(np.sqrt(med @ med))

    def _launch(self, t_v: int) -> None:
        """The launch, first seen at validity time t_v: moving from then on; the launch noise
        of the IMU steps already propagated past t_v goes into P at once (velocity noise)."""
        if not self.moving:
            self.moving = True
            self.t_moving = t_v
        self.t_launch = t_v
        if self.q_launch is not None and self.kf is not None and self.healthy and self.t_ins > t_v:
            late = min(self.t_ins - t_v, self.launch_ns) * 1e-9
            self.kf.P = self.kf.P + self.q_launch * late

    def _record_ldv(self, s: LdvSample) -> None:
        """Integrate the deck displacement (when moving) and keep the sample by validity time."""
        t = s.t_ns
        t_v = t - self.ldv_lat_ns
        prev = self.last_ldv
        if self.moving and s.valid and prev is not None and prev.valid:
            self.deck_disp = self.deck_disp + 0.5 * (prev.v_s + s.v_s) * (t - prev.t_ns) * 1e-9
        self.last_ldv = s
        self.ldv_history.record(LdvRecord(t_v, s.v_s, s.valid, self.moving, self.deck_disp))

    def _on_doppler(self, t: int, s: DopplerSample) -> None:
        """Match the slave velocity to the radar's, resolved with the slave's own attitude, at
        the radar's validity time t - doppler_latency_s (the slave solution there, H Phi^-1 as
        for the master; the IMU sample at t has been processed: the radar is ordered after it)."""
        self.counters.doppler += 1
        if self.ins is None or not s.valid or not self.healthy:
            return
        t_v = t - self.doppler_lat_ns
        past = self.history.state_at(t_v, self.ins.s, self.t_ins, self.max_step_ns)
        if past is None:
            self.counters.unmatched_doppler += 1
            return
        nav, phi_acc = past
        v_d = quat_to_dcm(nav.q_nb) @ s.v_b
        r = np.eye(2) * s.sigma ** 2
        meas = self.model.doppler_measurement(nav.v_n, (nav.v_n - v_d)[0:2], r)
        h = meas.h if phi_acc is None else solve(phi_acc.T, meas.h.T).T
        gate = self.cfg.gate_chi2 if self.cfg.gate_chi2 > 0.0 else None
        try:
            res = self.kf.update(meas.z, h, meas.r, gate)
            self._check_health()
        except (np.linalg.LinAlgError, FloatingPointError, ValueError, NumericalBreakdownError) as e:
            self._fail(f'update: {e}')
            return
        self.last_nis = res.nis
        if not res.accepted:
            self.counters.gated += 1
            return
        self.counters.doppler_updates += 1
        x = self.kf.x
        self.last_x = x.copy()
        zero = np.zeros(3)
        match = Match(c_m=np.eye(3), w_m=zero, r=zero, u_n=zero, v_ref=v_d, z_vel=zero, r_vel=np.eye(3), ins=nav)
        self.kf.x, _ = self._feed_back(x, self.kf.P, match, nav)
        self.t_doppler_update = t

    def _lever_arm(self, deck_disp: np.ndarray) -> np.ndarray:
        """The lever arm put into the reference (ship axes): the surveyed spot (plus the
        estimated correction) under compensation, and the LDV-integrated deck displacement."""
        if not self.compensate:
            return deck_disp
        if self.cfg.lever_arm_states:
            return self.r0 + self.corr.dr + deck_disp
        return self.r0 + deck_disp

    def _on_master(self, t: int, m: MasterSample) -> None:
        """Queue the sample at its validity time; match it once the slave and the LDV have
        reached that time (at once when nothing is late); emit at the output rate."""
        self.counters.master += 1
        if self.t0 is None:
            self.t0 = self.next_out = t
        if self.t_master is not None:
            self.master_spacing_ns = t - self.t_master
        self.t_master = t
        self.pending.append((t - self.master_lat_ns, m))
        self._match_pending()
        if self.ins is not None and t >= self.next_out:
            self._emit(t)
            self.next_out += self.out_period_ns * (1 + (t - self.next_out) // self.out_period_ns)

    def _match_pending(self, final: bool = False) -> None:
        while self.pending:
            t_v, m = self.pending[0]
            if not final:
                latest = self.ldv_history.latest_ns
                if latest is None or latest < t_v or (self.ins is not None and self.t_ins < t_v):
                    return
            self.pending.popleft()
            self._match(t_v, m)

    def _match(self, t_v: int, m: MasterSample) -> None:
        """The master sample valid at t_v against the LDV and the slave solution at t_v."""
        c_m = quat_to_dcm(m.q_nb)
        ldv = self.ldv_history.at(t_v)
        moving = ldv is not None and ldv.moving
        r = self._lever_arm(ldv.disp if ldv is not None else self.deck_disp)
        v_rel = ldv.v_s if (ldv is not None and ldv.valid and moving) else np.zeros(3)
        u_n = c_m @ (cross3(m.w_b, r) + v_rel)
        v_ref = c_m @ m.v_b + u_n
        if self.ins is None:
            self._initialise(t_v, m, c_m, r, v_ref)
            return
        if ldv is None or not ldv.valid or not self.healthy:
            self.matching = self.healthy and self.t_doppler_update == m.t_ns
            return
        past = self.history.state_at(t_v, self.ins.s, self.t_ins, self.max_step_ns)
        if past is None:
            self.counters.unmatched_master += 1
            self.matching = False
            return
        extras = self._match_extras(t_v, c_m, m, r, v_rel, moving, past[0]) if self.track_intervals else None
        try:
            r_vel = self.R_moving if moving else self.R_parked
            if moving:
                # an LDV slower than the master enters several matches with the same noise:
                # weight it as one sample per LDV interval (variance times the matches per sample)
                ratio = self.ldv_history.spacing_ns / self.master_spacing_ns if self.master_spacing_ns else 1.0
                extra = ldv.var + (ratio - 1.0) * self.cfg.ldv_sigma_mps ** 2 if ratio > 1.0 else ldv.var
                if extra > 0.0:
                    r_vel = r_vel + np.eye(3) * extra
            self._update(t_v, c_m, m, r, v_ref, u_n, past, r_vel, extras)
        except (np.linalg.LinAlgError, FloatingPointError, ValueError, NumericalBreakdownError) as e:
            self._fail(f'update: {e}')
            return
        self.matching = True

    def _match_extras(self, t_v: int, c_m: np.ndarray, m: MasterSample, r: np.ndarray, v_rel: np.ndarray,
                      moving: bool, nav: NavState) -> tuple[np.ndarray, np.ndarray | None, RateInputs | None]:
        """(w_n, a_n, rate inputs) for the delay state and rate matching (models/master_delay.py,
        rate_matching.py): the master's nav-frame body rate; the deck spot's acceleration, from the
        slave's velocity change over the IMU interval ending at t_v while parked, else from the
        master's last two samples with today's lever arm and LDV velocity (the undelayed parts);
        the gyro and master rates over that interval when the previous master sample started it."""
        w_n = c_m @ m.w_b
        prev, self.prev_master = self.prev_master, (t_v, c_m, m.v_b, m.w_b)
        iv = None
        for item in reversed(self.intervals):
            if item[0] == t_v:
                iv = item
                break
            if item[0] < t_v:
                break
        a_n = None
        if not moving and iv is not None:
            a_n = iv[3] / iv[1]
        elif moving and prev is not None and prev[0] < t_v:
            fixed = cross3(m.w_b, r) + v_rel
            a_n = (c_m @ (m.v_b + fixed) - prev[1] @ (prev[2] + cross3(prev[3], r) + v_rel)) / ((t_v - prev[0]) * 1e-9)
        rate = None
        if self.cfg.rate_matching and iv is not None and prev is not None \
                and t_v - prev[0] == int(round(iv[1] * 1e9)):
            w_in = self.ins.w_ie + self.ins.w_en
            w_prev = prev[1] @ prev[3]
            w_mean = 0.5 * (w_n + w_prev)
            w_b = iv[2] - self.corr.bg
            rate = RateInputs(w_b=w_b, dtheta=w_b * iv[1], omega_n=w_mean + w_in, w_n=w_mean,
                              w_dot_n=(w_n - w_prev) / iv[1], h=iv[1])
        if rate is None and self.cfg.rate_matching:
            self.counters.rate_unmatched += 1
        return w_n, a_n, rate

    def _initialise(self, t_v: int, m: MasterSample, c_m: np.ndarray, r: np.ndarray, v_ref: np.ndarray) -> None:
        """Slave = master attitude (times the nominal mounting), velocity and position at the lever
        arm, at the master's validity time; IMU samples already received after it are replayed."""
        lat, lon, h = self.plane.to_geodetic(m.p_w + self.plane.c_local_to_world(m.p_w) @ (c_m @ r))
        c_a = c_m if self.c_nom is None else c_m @ self.c_nom
        q = Rotation.from_matrix(c_a).as_quat()
        self.ins = Strapdown(NavState(q_nb=q, v_n=v_ref.copy(), lat=float(lat), lon=float(lon),
                                      h=float(h)))
        self.kf = make_filter(self.cfg, np.zeros(self.n), self.model.initial_covariance(), self.model.kinds)
        self.t_ins = t_v
        buffered, self.imu_buffer = self.imu_buffer, deque()
        for s in buffered:
            if s.t_ns > self.t_ins:
                self._propagate(s.t_ns, s)
            else:
                self.counters.skipped_before_init += 1

    def _update(self, t_v: int, c_m: np.ndarray, m: MasterSample, r: np.ndarray, v_ref: np.ndarray,
                u_n: np.ndarray, past: tuple[NavState, np.ndarray | None], r_vel: np.ndarray,
                extras: tuple | None = None) -> None:
        """Velocity (+ attitude) match at t_v. The innovation is formed against the slave solution
        at t_v; the error state is the live one (at t_ins), related to the one at t_v by the
        transitions in between, x(t_ins) = Phi x(t_v) (process noise over the latency neglected),
        so the measurement matrix is H Phi^-1 (identity at zero latency). The estimate is fed
        back into the live solution, and the same correction into the stored past ones."""
        nav, phi_acc = past
        z_vel = nav.v_n - v_ref
        if self.lowpass is not None:
            z_vel = self.lowpass.step(z_vel)
        match = Match(c_m=c_m, w_m=m.w_b, r=r, u_n=u_n, v_ref=v_ref, z_vel=z_vel,
                      r_vel=r_vel, ins=nav, c_nom=self.c_nom)
        if extras is not None:
            match.w_n, match.a_n, match.rate = extras
        meas = self.model.measurement(match, self.corr)
        gate = self.cfg.gate_chi2 if self.cfg.gate_chi2 > 0.0 else None
        if meas.h is None:
            res = self.kf.update_nonlinear(meas.z, meas.hfun, meas.r, gate)
        else:
            h = meas.h if phi_acc is None else solve(phi_acc.T, meas.h.T).T
            res = self.kf.update(meas.z, h, meas.r, gate)
        self._check_health()
        self.last_nis = res.nis
        if not res.accepted:
            self.counters.gated += 1
            return
        self.counters.updates += 1
        x = self.kf.x
        self.last_x = x.copy()
        p = self.kf.P
        # no later master match needs the solutions before t_v (a later Doppler sample may)
        self.history.prune(min(t_v, self.t_ins - self.doppler_lat_ns), self.t_ins)
        x_new, nav = self._feed_back(x, p, match, nav)
        self.kf.x = x_new
        self.mu, self.mu_sigma = self.model.misalignment(x_new, p, match, nav, self.corr)

    def _feed_back(self, x: np.ndarray, p: np.ndarray, match: Match, nav: NavState) -> tuple[np.ndarray, NavState]:
        """Apply the estimate to the live solution (the model's feedback) and the same correction
        to the stored past ones; return the state the filter keeps and `nav` (the solution at the
        match's validity time) corrected."""
        live = self.ins.s
        q0, v0, pos0 = live.q_nb, live.v_n, (live.lat, live.lon, live.h)
        x_new = self.model.feedback(x, p, match, live, self.corr)
        if self.lowpass is not None:
            self.lowpass.shift(live.v_n - v0)
        if self.history.items or nav is not live:
            q_corr = quat_mul(live.q_nb, quat_conj(q0))
            dv = live.v_n - v0
            dpos = (live.lat - pos0[0], live.lon - pos0[1], live.h - pos0[2])
            self.history.correct(q_corr, dv, *dpos)
            if nav is not live:
                q = quat_mul(q_corr, nav.q_nb)
                nav = NavState(q_nb=q / np.sqrt(q @ q), v_n=nav.v_n + dv, lat=nav.lat + dpos[0],
                               lon=nav.lon + dpos[1], h=nav.h + dpos[2])
        return x_new, nav

    def _emit(self, t: int) -> None:
        st = self.ins.s
        if self.healthy:
            att = self.model.attitude
            diag = self.kf.diagnostics()
            fading = diag.get('fading', 1.0)
            p = self.kf.P
            cov, sigma = p[att, att].copy(), np.sqrt(np.diag(p))
            if not (_finite(cov, sigma) and _finite(self.mu, self.mu_sigma)):
                self._fail('covariance not finite at the output')
            else:
                self.held = (cov, sigma, diag)
        if not self.healthy:
            if self.held is None:
                att = self.model.attitude
                p0 = self.model.initial_covariance()
                self.held = (p0[att, att].copy(), np.sqrt(np.diag(p0)), {})
            cov, sigma, diag = self.held
            fading = diag.get('fading', 1.0)
        self.outputs.append(Estimate(
            t_ns=t, misalignment=self.mu.copy(), misalignment_sigma=self.mu_sigma.copy(),
            q_nb=st.q_nb.copy(), attitude_cov=cov, x=self.last_x.copy(),
            sigma=sigma, bias_gyro=self.bg.copy(), bias_accel=self.ba.copy(),
            nis=self.last_nis, updates=self.counters.updates, matching=self.matching, fading=fading,
            healthy=self.healthy))
