"""The transfer-alignment engine: a slave strapdown and an error-state filter, fed in stamp order
from the slave IMU, the LDV and the master INS (never truth). The error model (`filter.model`) and
the filter algorithm (`filter.algorithm`) are chosen at run time; the default (vm15 + kf) is the
15-state velocity-matching Kalman filter. Event by event, and why: docs/engine.md."""
from __future__ import annotations

import dataclasses
from collections import deque
from typing import cast

import numpy as np
from scipy.spatial.transform import Rotation

from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.filter_factory import make_filter
from alignment_core.estimation.filters.base import NonlinearFilter
from alignment_core.estimation.health import BREAKDOWN_ERRORS, finite
from alignment_core.estimation.launch_detection import LaunchDetector, LaunchThresholds
from alignment_core.estimation.matching import LiveSolution, Matcher, Reference
from alignment_core.estimation.models import Corrections, Propagation, make_model
from alignment_core.estimation.models.base import DV
from alignment_core.estimation.outputs import Counters, DeckMotion, Diagnostics, Estimate
from alignment_core.geometry import earth
from alignment_core.navigation.history import LdvHistory, LdvRecord, SlaveHistory
from alignment_core.navigation.ordering import StampMerger
from alignment_core.navigation.strapdown import NavState, Strapdown
from alignment_core.samples import DopplerSample, ImuSample, LdvSample, MasterSample

STREAMS = ('imu', 'ldv', 'master')
DOPPLER_STREAMS = ('imu', 'ldv', 'doppler', 'master')   # seed001_13: the Doppler radar too


class TransferAlignment:
    """Stamp-ordered transfer-alignment estimator: push samples, call `process`, read `outputs`."""

    def __init__(self, cfg: FilterConfig, plane: earth.TangentPlane, imu_rate_hz: float) -> None:
        self._cfg = cfg
        self._plane = plane
        self._model = make_model(cfg)
        self._merger = StampMerger(DOPPLER_STREAMS if self._model.uses_doppler else STREAMS)
        self._counters = Counters()
        self._imu_dt_nominal = 1.0 / imu_rate_hz
        self._out_period_ns = int(round(1e9 / cfg.output_rate_hz))
        # time of validity: data valid at stamp - latency
        self._master_lat_ns = int(round(cfg.master_latency_s * 1e9))
        self._ldv_lat_ns = int(round(cfg.ldv_latency_s * 1e9))
        self._doppler_lat_ns = int(round(cfg.doppler_latency_s * 1e9))
        self._span_ns = max(self._master_lat_ns, self._ldv_lat_ns, self._doppler_lat_ns) + int(0.2e9)
        self._max_step_ns = int(cfg.max_gap_factor * self._imu_dt_nominal * 1e9)
        self._matcher = Matcher(cfg, self._model, imu_rate_hz, self._span_ns, self._counters)
        self._results = self._matcher.results
        self._track_intervals = self._matcher.tracks_intervals
        self._ldv_history = LdvHistory(self._span_ns, cfg.ldv_sigma_mps)
        self._imu_buffer: deque[ImuSample] = deque()       # IMU samples before initialisation
        self._pending: deque[tuple[int, MasterSample]] = deque()   # (validity time, sample)
        self._t_master: int | None = None          # last master stamp, and the spacing of the last two
        self._master_spacing_ns = 0
        self._launch = LaunchDetector(LaunchThresholds(
            cfg.launch_detect_mps, cfg.launch_confirm_samples, cfg.creep_detect_mps, cfg.creep_window_samples,
            self._ldv_lat_ns))
        # known-event process noise after the launch (velocity states)
        self._launch_ns = int(round(cfg.launch_noise_s * 1e9))
        dv = np.array([k == DV for k in self._model.kinds], dtype=float)
        self._q_launch = np.diag(dv) * cfg.launch_accel_noise_mps2 ** 2 if cfg.launch_accel_noise_mps2 > 0.0 else None
        self._live: LiveSolution | None = None
        self._next_out: int | None = None         # the next output at or after this master stamp
        self._deck_disp = np.zeros(3)
        self._last_ldv: LdvSample | None = None
        self._matching = False
        self._healthy = True
        self._failure = ''
        self._held: tuple[np.ndarray, np.ndarray, dict] | None = None   # (attitude cov, sigma, diagnostics)
        self._outputs: list[Estimate] = []

    # ----- what the engine shows -----
    @property
    def outputs(self) -> tuple[Estimate, ...]:
        """Every estimate so far, one per output instant."""
        return tuple(self._outputs)

    @property
    def latest(self) -> Estimate | None:
        return self._outputs[-1] if self._outputs else None

    @property
    def counters(self) -> Counters:
        """A copy of the counters."""
        return dataclasses.replace(self._counters)

    def diagnostics(self) -> Diagnostics:
        """The filter's diagnostics as of the last output, health, failure and queued samples."""
        if self._held is not None:
            filt = dict(self._held[2])
        else:
            filt = {} if self._live is None else self._live.kf.diagnostics()
        return Diagnostics(filt, self._healthy, self._failure, self._merger.pending())

    @property
    def solution(self) -> NavState | None:
        """A copy of the live slave solution (None before initialisation)."""
        if self._live is None:
            return None
        st = self._live.ins.s
        return dataclasses.replace(st, q_nb=st.q_nb.copy(), v_n=st.v_n.copy(), prev_dtheta=st.prev_dtheta.copy(),
                                   prev_dv=st.prev_dv.copy())

    @property
    def corrections(self) -> Corrections:
        """A copy of what feedback accumulated outside the strapdown (sensor biases, lever arm)."""
        c = self._results.corr
        return Corrections(bg=c.bg.copy(), ba=c.ba.copy(), dr=c.dr.copy(), mu=c.mu.copy())

    @property
    def deck_motion(self) -> DeckMotion:
        d = self._launch
        return DeckMotion(d.moving, d.t_moving_ns, d.t_launch_ns, self._deck_disp.copy())

    @property
    def labels(self) -> tuple[str, ...]:
        return self._model.labels

    @property
    def n_states(self) -> int:
        return self._model.n

    @property
    def model_name(self) -> str:
        return self._model.name

    @property
    def uses_doppler(self) -> bool:
        return self._model.uses_doppler

    @property
    def healthy(self) -> bool:
        return self._healthy

    @property
    def failure(self) -> str:
        """Why the filter stopped ('' while healthy)."""
        return self._failure

    # ----- input -----
    def push_imu(self, s: ImuSample) -> bool:
        return self._push('imu', s.t_ns, s, s.gyro, s.accel)

    def push_ldv(self, s: LdvSample) -> bool:
        return self._push('ldv', s.t_ns, s, s.v_s if s.valid else np.zeros(3))

    def push_master(self, s: MasterSample) -> bool:
        return self._push('master', s.t_ns, s, s.p_w, s.q_nb, s.v_b, s.w_b)

    def push_doppler(self, s: DopplerSample) -> bool:
        """A Doppler radar sample (only models that use it take this stream; others ignore it)."""
        if not self._model.uses_doppler:
            return True
        return self._push('doppler', s.t_ns, s, s.v_b if s.valid else np.zeros(3), np.array([s.sigma]))

    def _push(self, stream: str, t_ns: int, item: object, *arrays: np.ndarray) -> bool:
        """Queue a sample unless it is non-finite or not after its stream's previous stamp."""
        if not finite(*arrays):
            self._counters.rejected_nonfinite += 1
            return False
        if not self._merger.push(stream, t_ns, item):
            self._counters.rejected_out_of_order += 1
            return False
        return True

    def process(self, final: bool = False) -> list[Estimate]:
        """Run every event up to the watermark (all of them if final); return the new outputs."""
        n0 = len(self._outputs)
        events = self._merger.flush() if final else self._merger.pop_ready()
        for stream, t, item in events:
            if stream == 'imu':
                self._on_imu(t, item)
            elif stream == 'ldv':
                self._on_ldv(t, item)
            elif stream == 'master':
                self._on_master(t, item)
            else:
                self._on_doppler(t, item)
        if final:
            for h in self._launch.release():         # an unconfirmed run at the end: parked
                self._record_ldv(h)
            self._match_pending(final=True)
        return self._outputs[n0:]

    def _fail(self, why: str) -> None:
        """Stop filtering after a breakdown: keep the last good estimate (published with
        healthy=False) and let the slave run free inertial."""
        self._counters.numerical_failures += 1
        if self._healthy:
            self._healthy = False
            self._failure = why
            self._matching = False

    # ----- events -----
    def _on_imu(self, t: int, s: ImuSample) -> None:
        self._counters.imu += 1
        live = self._live
        if live is None:
            self._imu_buffer.append(s)
            while self._imu_buffer and self._imu_buffer[0].t_ns < t - self._span_ns:
                self._imu_buffer.popleft()
                self._counters.skipped_before_init += 1
            return
        if t <= live.t_ns:
            self._counters.skipped_before_init += 1
            return
        self._propagate(live, t, s)
        if self._pending:
            self._match_pending()

    def _propagate(self, live: LiveSolution, t: int, s: ImuSample) -> None:
        """The strapdown over the IMU interval ending at t, then the filter's predict."""
        h = (t - live.t_ns) * 1e-9
        if h > self._cfg.max_gap_factor * self._imu_dt_nominal:
            self._counters.imu_gaps += 1
        corr = self._results.corr
        dth = (s.gyro - corr.bg) * h
        dv = (s.accel - corr.ba) * h
        ins = live.ins
        snap = live.history.record(live.t_ns, ins.s)
        v_start = ins.s.v_n
        f_n = ins.update(dth, dv, h)
        st = ins.s
        if self._track_intervals:
            self._matcher.record_interval(t, h, s.gyro, st.v_n - v_start)
        live.t_ns = t
        live.history.prune(t - self._span_ns, t)
        if not self._healthy:
            return
        p = Propagation(ins.c_start, f_n, ins.w_ie, ins.w_en, st.v_n, st.lat, st.h, h)
        qd = self._model.process_noise(h)
        t_launch = self._launch.t_launch_ns
        if self._q_launch is not None and t_launch is not None and t - t_launch <= self._launch_ns \
                and t > t_launch:
            qd = qd + self._q_launch * h
        try:
            if self._model.nonlinear:
                fun, jac = self._model.propagator(p)
                cast(NonlinearFilter, live.kf).predict_nonlinear(fun, qd, jac)
            else:
                phi = self._model.transition(p)
                snap.phi = phi
                live.kf.predict(phi, qd)
        except (np.linalg.LinAlgError, FloatingPointError, ValueError) as e:
            self._fail(f'predict: {e}')

    def _on_ldv(self, t: int, s: LdvSample) -> None:
        """The launch detector decides which samples to record now (none while it holds a fast
        run back: the master matches wait); a launch it confirms puts the launch noise of the IMU
        steps already propagated past it into P at once. Each sample is kept by its validity time."""
        self._counters.ldv += 1
        decision = self._launch.observe(s)
        if decision.launch_ns is not None:
            self._late_launch_noise(decision.launch_ns)
        if decision.creep:
            self._counters.creep_detected += 1
        if not decision.record:
            return
        for r in decision.record:
            self._record_ldv(r)
        if self._pending:
            self._match_pending()

    def _late_launch_noise(self, t_v: int) -> None:
        """The launch noise (velocity states) of the IMU steps between the launch at t_v and now."""
        live = self._live
        if self._q_launch is not None and live is not None and self._healthy and live.t_ns > t_v:
            late = min(live.t_ns - t_v, self._launch_ns) * 1e-9
            live.kf.P = live.kf.P + self._q_launch * late

    def _record_ldv(self, s: LdvSample) -> None:
        """Integrate the deck displacement (when moving) and keep the sample by validity time."""
        t = s.t_ns
        moving = self._launch.moving
        prev = self._last_ldv
        if moving and s.valid and prev is not None and prev.valid:
            self._deck_disp = self._deck_disp + 0.5 * (prev.v_s + s.v_s) * (t - prev.t_ns) * 1e-9
        self._last_ldv = s
        self._ldv_history.record(LdvRecord(t - self._ldv_lat_ns, s.v_s, s.valid, moving, self._deck_disp))

    def _on_doppler(self, t: int, s: DopplerSample) -> None:
        """Match the radar at its validity time (it is ordered after the IMU sample at t)."""
        self._counters.doppler += 1
        live = self._live
        if live is None or not s.valid or not self._healthy:
            return
        past = live.history.state_at(t - self._doppler_lat_ns, live.ins.s, live.t_ns, self._max_step_ns)
        if past is None:
            self._counters.unmatched_doppler += 1
            return
        try:
            self._matcher.update_doppler(live, t, s, past)
        except BREAKDOWN_ERRORS as e:
            self._fail(f'update: {e}')

    def _on_master(self, t: int, m: MasterSample) -> None:
        """Queue the sample at its validity time; match it once the slave and the LDV have
        reached that time (at once when nothing is late); emit at the output rate."""
        self._counters.master += 1
        if self._next_out is None:
            self._next_out = t
        if self._t_master is not None:
            self._master_spacing_ns = t - self._t_master
        self._t_master = t
        self._pending.append((t - self._master_lat_ns, m))
        self._match_pending()
        if self._live is not None and t >= self._next_out:
            self._emit(t, self._live)
            self._next_out += self._out_period_ns * (1 + (t - self._next_out) // self._out_period_ns)

    def _match_pending(self, final: bool = False) -> None:
        while self._pending:
            t_v, m = self._pending[0]
            if not final:
                latest = self._ldv_history.latest_ns
                if latest is None or latest < t_v or (self._live is not None and self._live.t_ns < t_v):
                    return
            self._pending.popleft()
            self._match(t_v, m)

    def _match(self, t_v: int, m: MasterSample) -> None:
        """The master sample valid at t_v against the LDV and the slave solution at t_v (the
        first one initialises the slave)."""
        ldv = self._ldv_history.at(t_v)
        ref = self._matcher.reference(m, ldv, self._deck_disp)
        live = self._live
        if live is None:
            self._initialise(t_v, m, ref)
            return
        if ldv is None or not ldv.valid or not self._healthy:
            self._matching = self._healthy and self._results.t_doppler_update == m.t_ns
            return
        past = live.history.state_at(t_v, live.ins.s, live.t_ns, self._max_step_ns)
        if past is None:
            self._counters.unmatched_master += 1
            self._matching = False
            return
        extras = self._matcher.extras(live, t_v, m, ref) if self._track_intervals else None
        try:
            self._matcher.update_master(live, t_v, m, ref, ldv, past, extras, self._ldv_history.spacing_ns,
                                        self._master_spacing_ns)
        except BREAKDOWN_ERRORS as e:
            self._fail(f'update: {e}')
            return
        self._matching = True

    def _initialise(self, t_v: int, m: MasterSample, ref: Reference) -> None:
        """Slave = master attitude (times the nominal mounting), velocity and position at the lever
        arm, at the master's validity time; IMU samples already received after it are replayed."""
        c_m = ref.c_m
        lat, lon, h = self._plane.to_geodetic(m.p_w + self._plane.c_local_to_world(m.p_w) @ (c_m @ ref.r))
        c_nom = self._matcher.c_nom
        c_a = c_m if c_nom is None else c_m @ c_nom
        q = Rotation.from_matrix(c_a).as_quat()
        ins = Strapdown(NavState(q_nb=q, v_n=ref.v_ref.copy(), lat=float(lat), lon=float(lon), h=float(h)))
        kf = make_filter(self._cfg, np.zeros(self._model.n), self._model.initial_covariance(), self._model.kinds)
        live = self._live = LiveSolution(ins, kf, t_v, SlaveHistory(self._span_ns))
        buffered, self._imu_buffer = self._imu_buffer, deque()
        for s in buffered:
            if s.t_ns > live.t_ns:
                self._propagate(live, s.t_ns, s)
            else:
                self._counters.skipped_before_init += 1

    def _emit(self, t: int, live: LiveSolution) -> None:
        """One output at master stamp t; after a breakdown, the last good one with healthy=False."""
        res = self._results
        fading: float | np.ndarray = 1.0
        if self._healthy:
            diag = live.kf.diagnostics()
            fading = diag.get('fading', 1.0)
            att = self._model.attitude
            p = live.kf.P
            cov, sigma = p[att, att].copy(), np.sqrt(np.diag(p))
            if not (finite(cov, sigma) and finite(res.mu, res.mu_sigma)):
                self._fail('covariance not finite at the output')
            else:
                self._held = (cov, sigma, diag)
        if not self._healthy:
            if self._held is None:
                att = self._model.attitude
                p0 = self._model.initial_covariance()
                self._held = (p0[att, att].copy(), np.sqrt(np.diag(p0)), {})
            cov, sigma, diag = self._held
            fading = diag.get('fading', 1.0)
        corr = res.corr
        self._outputs.append(Estimate(
            t_ns=t, misalignment=res.mu.copy(), misalignment_sigma=res.mu_sigma.copy(),
            q_nb=live.ins.s.q_nb.copy(), attitude_cov=cov, x=res.x.copy(),
            sigma=sigma, bias_gyro=corr.bg.copy(), bias_accel=corr.ba.copy(),
            nis=res.nis, updates=self._counters.updates, matching=self._matching, fading=fading,
            healthy=self._healthy))
