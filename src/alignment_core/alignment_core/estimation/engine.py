"""The transfer-alignment engine: a slave strapdown and an error-state filter, fed in stamp order
from the slave IMU, the LDV and the master INS (never truth). The error model (`filter.model`) and
the filter algorithm (`filter.algorithm`) are chosen at run time; the default (vm15 + kf) is the
15-state velocity-matching Kalman filter. Event by event, and why: docs/engine.md."""
from __future__ import annotations

from collections import deque
from dataclasses import replace

import numpy as np

from alignment_core.estimation import status
from alignment_core.estimation.anchoring import (
    carried_attitude,
    reset_velocity,
    slave_from_master,
)
from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.consistency import NisMonitor
from alignment_core.estimation.deck_run import DeckRun
from alignment_core.estimation.engine_views import EngineViews
from alignment_core.estimation.filter_factory import make_filter
from alignment_core.estimation.health import BREAKDOWN_ERRORS
from alignment_core.estimation.imu_events import ImuEvents
from alignment_core.estimation.input_streams import InputStreams
from alignment_core.estimation.launch_detection import FELT_SPAN_NS, LaunchDetector, LaunchThresholds
from alignment_core.estimation.matching import LiveSolution, Matcher, Reference
from alignment_core.estimation.models import make_model
from alignment_core.estimation.models.base import DV
from alignment_core.estimation.models.beam import track_velocity
from alignment_core.estimation.outputs import Counters, Estimate
from alignment_core.estimation.publication import EstimateMaker, OdometryMaker, PublishGuard, prior_estimate
from alignment_core.estimation.reference_force import SpotAcceleration
from alignment_core.estimation.relative_velocity import ABSENT, LDV, RelativeVelocity
from alignment_core.estimation.whiteness import InnovationWhiteness
from alignment_core.geometry import earth
from alignment_core.navigation.history import LdvHistory, LdvRecord, SlaveHistory
from alignment_core.samples import DopplerSample, ImuSample, LdvSample, MasterSample
from alignment_core.units import DEG

STREAMS = ('imu', 'ldv', 'master')
DOPPLER_STREAMS = ('imu', 'ldv', 'doppler', 'master')   # seed001_13: the Doppler radar too


class TransferAlignment(ImuEvents, EngineViews):
    """Stamp-ordered transfer-alignment estimator: push samples, call `process`, read `outputs`
    (the read-only views: engine_views.py)."""

    def __init__(self, cfg: FilterConfig, plane: earth.TangentPlane, imu_rate_hz: float,
                 keep_history: bool = True) -> None:
        """keep_history False (a node): `outputs` and `published` keep only the latest estimate
        and `whiteness.history` nothing, so memory does not grow with the run (process() returns
        the new ones either way)."""
        self._keep_history = keep_history
        self._cfg = cfg
        self._plane = plane
        self._model = make_model(cfg)
        self._cells = self._model.transition_cells()
        self._rel = RelativeVelocity(cfg)
        streams: tuple[str, ...] = DOPPLER_STREAMS if self._model.uses_doppler else STREAMS
        if not self._rel.takes_ldv:
            streams = tuple(k for k in streams if k != 'ldv')
        self._counters = Counters()
        self._inputs = InputStreams(cfg, self._counters, streams)
        self._imu_rate_hz = imu_rate_hz
        self._imu_dt_nominal = 1.0 / imu_rate_hz
        self._imu_dt_ns = int(round(1e9 / imu_rate_hz))
        self._out_period_ns = int(round(1e9 / cfg.output_rate_hz))
        # time of validity: data valid at stamp - latency
        self._master_lat_ns = int(round(cfg.master_latency_s * 1e9))
        self._ldv_lat_ns = int(round(cfg.ldv_latency_s * 1e9))
        self._doppler_lat_ns = int(round(cfg.doppler_latency_s * 1e9))
        self._span_ns = max(self._master_lat_ns, self._ldv_lat_ns, self._doppler_lat_ns) + int(0.2e9)
        self._max_step_ns = int(cfg.max_gap_factor * self._imu_dt_nominal * 1e9)
        self._bridge_ns = int(cfg.gap_bridge_factor * self._imu_dt_nominal * 1e9)
        self._matcher = Matcher(cfg, self._model, imu_rate_hz, self._span_ns, self._counters)
        self._results = self._matcher.results
        if self._rel.rigid:
            self._matcher.use_rigid_noise()
        self._track_intervals = self._matcher.tracks_intervals
        # the deck spot's acceleration from the master (reference_force.py): parked, the error model's
        # horizontal specific force; the delay state's column
        self._spot_accel = SpotAcceleration(cfg.reference_force_window_s) \
            if 'reference' in (cfg.specific_force, cfg.delay_acceleration) else None
        self._matcher.spot = self._spot_accel
        self._ldv_history = LdvHistory(self._span_ns, cfg.ldv_sigma_mps)
        self._imu_buffer: deque[ImuSample] = deque()       # IMU samples before (re-)anchoring
        self._pending: deque[tuple[int, MasterSample]] = deque()   # (validity time, sample)
        self._t_master: int | None = None          # last master stamp, and the spacing of the last two
        self._master_spacing_ns = 0
        imu_record: deque[tuple[int, float, float]] = deque()     # the IMU along x: the deck run feeds it
        self._launch = LaunchDetector(LaunchThresholds(
            cfg.launch_detect_mps, cfg.launch_confirm_samples, cfg.creep_detect_mps, cfg.creep_window_samples,
            self._ldv_lat_ns, cfg.launch_felt_fraction, cfg.launch_felt_tolerance_mps), imu_record)
        self._t_imu: int | None = None             # the last IMU stamp (the IMU record's intervals)
        # known-event process noise after the launch (velocity states)
        self._launch_ns = int(round(cfg.launch_noise_s * 1e9))
        dv = np.array([k == DV for k in self._model.kinds], dtype=float)
        self._q_launch = np.diag(dv) * cfg.launch_accel_noise_mps2 ** 2 if cfg.launch_accel_noise_mps2 > 0.0 else None
        self._live: LiveSolution | None = None
        self._anchor_from: int | None = None      # after a gap on the deck: re-anchor at the first master from here
        self._imu_start: int | None = None        # where the IMU's data begins: its first stamp less an interval
        self._init_from: int | None = None        # a told latency reaching before it: initialise from here
        self._next_out: int | None = None         # the next output at or after this master stamp
        self._t_first_master: int | None = None   # the IMU cannot have been silent before it
        psi = cfg.heading_on_deck_deg * DEG              # the airframe's x axis on deck, ship axes
        self._deck = DeckRun(self._ldv_lat_ns, np.array([np.cos(psi), -np.sin(psi), 0.0]), imu_record, FELT_SPAN_NS)
        self._matching = False
        self._health = status.Health()
        self._monitor = NisMonitor(cfg.consistency_window_updates, cfg.consistency_warn_p,
                                   cfg.consistency_error_windows, cfg.gate_chi2 if cfg.gate_chi2 > 0.0 else None)
        self._whiteness = InnovationWhiteness(cfg.whiteness_window_updates, cfg.whiteness_lags, cfg.whiteness_p,
                                              keep_history)
        self._maker = EstimateMaker(self._model, OdometryMaker(self._model, plane, self._imu_dt_nominal,
                                                               cfg.arw_dpsh, cfg.gyro_bias_sigma_dph))
        self._guard = PublishGuard(cfg.misalignment_max_deg * DEG)
        self._outputs: list[Estimate] = []
        self._published: list[Estimate] = []

    # ----- input -----
    def push_imu(self, s: ImuSample) -> bool:
        """Queue a sample unless it is implausible (plausibility.py) or not after its stream's
        previous stamp; a rejection is counted by reason (`last_rejection`). So do the others."""
        return self._inputs.push('imu', s)

    def push_ldv(self, s: LdvSample) -> bool:
        """An LDV sample; ignored (counted) under relative velocity zero or once it was silent."""
        if not self._rel.takes_ldv:
            self._counters.ldv_ignored += 1
            return True
        return self._inputs.push('ldv', s)

    def push_master(self, s: MasterSample) -> bool:
        return self._inputs.push('master', s)

    def push_doppler(self, s: DopplerSample) -> bool:
        """A Doppler radar sample (only models that use it take this stream; others ignore it)."""
        if not self._model.uses_doppler:
            return True
        return self._inputs.push('doppler', s)

    def process(self, final: bool = False) -> list[Estimate]:
        """Run every event up to the watermark (all of them if final); return the new outputs as
        published (`published`: the same as `outputs` while the estimates are good)."""
        n0 = len(self._outputs)
        self._check_ldv(final)
        for stream, t, item in self._inputs.events(final):
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
        if len(self._outputs) == n0:                # most calls: no output at this master stamp
            return []
        new = [self._guard.publish(e, self._prior) for e in self._outputs[n0:]]
        self._published.extend(new)
        if not self._keep_history:
            del self._outputs[:-1], self._published[:-1]
        return new

    def _check_ldv(self, final: bool) -> None:
        """Stop waiting for an LDV that is silent or absent (relative_velocity.py)."""
        rel = self._rel
        inputs = self._inputs
        if rel.mode != LDV or not rel.silent(inputs.merger.last, inputs.gate.quiet_since('ldv'), final):
            return
        self._inputs.stop_waiting('ldv', absent=rel.mode == ABSENT)
        if rel.mode == ABSENT:
            self._matcher.use_rigid_noise()
        self._match_pending()

    def _prior(self, e: Estimate) -> Estimate:
        p0 = self._model.initial_covariance()
        return prior_estimate(e, np.full(3, self._cfg.init_attitude_sigma_deg * DEG), p0, self._model.attitude)

    # ----- events (the IMU's: imu_events.py) -----
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
        if decision.not_felt:
            self._counters.launch_not_felt += 1
        if not decision.record:
            return
        for r in decision.record:
            self._record_ldv(r)
        if self._pending:
            self._match_pending()

    def _late_launch_noise(self, t_v: int) -> None:
        """The launch noise (velocity states) of the IMU steps between the launch at t_v and now."""
        live = self._live
        if self._q_launch is not None and live is not None and self._health.running and live.t_ns > t_v:
            late = min(live.t_ns - t_v, self._launch_ns) * 1e-9
            live.kf.P = live.kf.P + self._q_launch * late

    def _record_ldv(self, s: LdvSample) -> None:
        """Keep the sample by validity time with the deck displacement at it (deck_run.py); a beam
        sample, once moving, as the run along the track it implies (models/beam.py)."""
        moving = self._launch.moving
        if moving and s.valid and s.beam is not None:
            s = replace(s, v_s=track_velocity(s.v_s, s.beam, self._cfg.heading_on_deck_deg * DEG))
        disp = self._deck.record(s, moving, self._launch.t_moving_ns)
        self._ldv_history.record(LdvRecord(s.t_ns - self._ldv_lat_ns, s.v_s, s.valid, moving, disp, beam=s.beam))

    def _on_doppler(self, t: int, s: DopplerSample) -> None:
        """Match the radar at its validity time (it is ordered after the IMU sample at t)."""
        self._counters.doppler += 1
        live = self._live
        if live is None or not s.valid or not self._health.running:
            return
        past = None if self._anchor_from is not None else live.history.state_at(
            t - self._doppler_lat_ns, live.ins.s, live.t_ns, self._max_step_ns)
        if past is None:
            self._counters.unmatched_doppler += 1
            return
        try:
            self._matcher.update_doppler(live, t, s, past)
        except BREAKDOWN_ERRORS as e:
            self._fail(f'update: {e}')
            return
        self._monitor_update()

    def _monitor_update(self) -> None:
        """The last update's NIS into the consistency monitor."""
        inn, s = self._results.innovation, self._results.innovation_cov
        if inn is not None and s is not None:
            self._whiteness.add(inn, s)
            self._results.innovation = None
        res = self._monitor.add(self._results.nis, self._results.dof)
        if res is not None:
            if res.failed:
                self._counters.consistency_failures += 1
            self._health.window_done(self._monitor, res.failed)

    def _on_master(self, t: int, m: MasterSample) -> None:
        """Queue the sample at its validity time; match it once the slave and the LDV have
        reached that time (at once when nothing is late); emit at the output rate."""
        self._counters.master += 1
        if self._next_out is None:
            self._next_out = self._t_first_master = t
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
            anchor_from = self._anchor_from
            anchoring = anchor_from is not None
            if anchor_from is not None and t_v < anchor_from:      # inside the gap: no slave solution there
                self._pending.popleft()
                self._counters.unmatched_master += 1
                continue
            if self._live is None and self._before_imu_data(t_v):     # no IMU data there: not a start
                self._pending.popleft()
                self._counters.skipped_before_init += 1
                continue
            if not final:
                latest = self._ldv_history.latest_ns
                if (self._rel.waits() and (latest is None or latest < t_v)) or (
                        self._live is not None and not anchoring and self._live.t_ns < t_v):
                    return
            self._pending.popleft()
            self._match(t_v, m)

    def _match(self, t_v: int, m: MasterSample) -> None:
        """The master sample valid at t_v against the LDV and the slave solution at t_v (the
        first one initialises the slave, the first after a gap on the deck re-anchors it)."""
        ldv = self._ldv_history.at(t_v)
        if self._rel.mode != LDV and (ldv is None or self._rel.rigid):
            ldv = self._rel.stand_in(t_v, self._ldv_history.latest_ns, self._launch.moving, self._deck.displacement)
        live = self._live
        reanchor = live is not None and self._anchor_from is not None
        # matching, the sample also goes into the deck spot's fit (the matcher's spot, reference_force.py)
        ref = self._matcher.reference(m, ldv, self._deck.displacement, surveyed=reanchor,
                                      fit_at=None if live is None or reanchor else t_v)
        if live is None or reanchor:
            self._anchor(t_v, m, ref)
            return
        if ldv is None or not ldv.valid or not self._health.running:
            self._matching = self._health.running and self._results.t_doppler_update == m.t_ns
            return
        past = live.history.find(t_v, live.ins.s, live.t_ns, self._max_step_ns)
        if past is None:
            self._counters.unmatched_master += 1
            self._matching = False
            return
        step = self._matcher.step_in_kernel(live, past) if past.f else None
        if step is None:
            past.state()                                   # the slave there (its errors raised here)
        extras = self._matcher.extras(live, t_v, m, ref) if self._track_intervals else None
        try:
            self._matcher.update_master(live, t_v, m, ref, ldv, past, step, extras, self._ldv_history.spacing_ns,
                                        self._master_spacing_ns)
        except BREAKDOWN_ERRORS as e:
            self._fail(f'update: {e}')
            return
        self._matching = True
        self._monitor_update()

    def _anchor(self, t_v: int, m: MasterSample, ref: Reference) -> None:
        """Slave = master attitude times the nominal mounting (initialisation) or times the relative
        attitude of the last match (after a gap), velocity and position at the lever arm, at the
        master's validity time; the filter starts from the prior, or keeps its covariance with the
        velocity errors reset to the reference's. IMU samples received after t_v are replayed."""
        reanchor = self._live is not None
        c_a = carried_attitude(ref.c_m, self._results.anchor if reanchor else None, self._matcher.c_nom)
        ins = slave_from_master(self._plane, m, ref, c_a)
        if self._live is None:
            kf = make_filter(self._cfg, np.zeros(self._model.n), self._model.initial_covariance(), self._model.kinds)
            self._live = LiveSolution(ins, kf, t_v, SlaveHistory(self._span_ns))
        else:
            self._live.ins, self._live.t_ns, self._live.history = ins, t_v, SlaveHistory(self._span_ns)
            self._anchor_from = None
            if self._health.running:
                cfg = self._cfg
                reset_velocity(self._live.kf, self._model, cfg.parked_velocity_sigma_mps ** 2
                               + cfg.master_velocity_sigma_mps ** 2)
        live = self._live
        buffered, self._imu_buffer = self._imu_buffer, deque()
        for s in buffered:
            if s.t_ns > live.t_ns:
                self._propagate(live, s.t_ns, s)
            else:
                self._counters.skipped_before_init += 1

    def _valid_at(self, t: int) -> int:
        """The time the misalignment published at master stamp t refers to: its last master
        update's validity time (a held match stays valid where it was made), else t less the
        master latency the filter is told."""
        t_mu = self._results.t_mu
        return t - self._master_lat_ns if t_mu is None else t_mu

    def _emit(self, t: int, live: LiveSolution) -> None:
        """One output at master stamp t, valid at t less the master latency; after a breakdown,
        the last good one with healthy=False."""
        odo = None
        if self._health.running:
            odo = self._maker.keep(live, self._results)
            if odo is None:
                self._fail('output not finite (covariance, misalignment or odometry)')
        # the IMU's silence: since the slave's time, or the data's start for a slave initialised
        # before it (at a told master latency), which is no silence
        since = live.t_ns if self._t_first_master is None else max(live.t_ns, self._t_first_master)
        level, flags = status.with_lag(*status.level_and_flags(self._health, self._monitor), t - since,
                                       self._bridge_ns, int(self._cfg.gap_error_s * 1e9))
        e = self._maker.make(t, live, self._results, self._counters.updates, self._matching, level, flags,
                             t_valid=self._valid_at(t), odometry=odo)
        e.report = self.report(level, flags)
        self._outputs.append(e)
