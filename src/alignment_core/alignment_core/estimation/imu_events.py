"""The transfer-alignment engine's IMU events (docs/engine.md, events and IMU gaps): per IMU
interval the slave strapdown step and the filter's predict (with the launch noise just after the
launch), the IMU samples kept for the (re-)anchoring master, and the bridging of an IMU gap. A
mixin of TransferAlignment (engine.py), which owns the state these use."""
from __future__ import annotations

from collections import deque
from typing import cast

import numpy as np

from alignment_core.compiled import FLOAT64
from alignment_core.estimation import status
from alignment_core.estimation.anchoring import bridge_covariance, dead_reckoned
from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.consistency import NisMonitor
from alignment_core.estimation.deck_run import DeckRun
from alignment_core.estimation.filters.base import NonlinearFilter
from alignment_core.estimation.filters.kalman import KalmanFilter
from alignment_core.estimation.health import BREAKDOWN_ERRORS, ERROR, WARN
from alignment_core.estimation.launch_detection import LaunchDetector
from alignment_core.estimation.matching import LiveSolution, Matcher, MatchResults
from alignment_core.estimation.models import ErrorModel, Propagation
from alignment_core.estimation.outputs import Counters
from alignment_core.estimation.propagation_step import strapdown_and_predict
from alignment_core.estimation.reference_force import SpotAcceleration, reference_specific_force
from alignment_core.estimation.whiteness import InnovationWhiteness
from alignment_core.navigation.history import SlaveHistory
from alignment_core.samples import ImuSample


class ImuEvents:
    """The IMU side of the event loop: propagation, buffering before anchoring, gap bridging."""
    _cfg: FilterConfig
    _model: ErrorModel
    _cells: tuple[np.ndarray, int] | None       # the model's transition_cells()
    _counters: Counters
    _health: status.Health
    _monitor: NisMonitor
    _whiteness: InnovationWhiteness
    _matcher: Matcher
    _results: MatchResults
    _launch: LaunchDetector
    _deck: DeckRun
    _live: LiveSolution | None
    _matching: bool
    _anchor_from: int | None
    _imu_start: int | None
    _init_from: int | None
    _imu_buffer: deque[ImuSample]
    _pending: deque
    _t_imu: int | None
    _imu_rate_hz: float
    _imu_dt_nominal: float
    _imu_dt_ns: int
    _span_ns: int
    _bridge_ns: int
    _launch_ns: int
    _q_launch: np.ndarray | None
    _track_intervals: bool
    _spot_accel: SpotAcceleration | None

    def _match_pending(self, final: bool = False) -> None:
        raise NotImplementedError          # the engine's (engine.py): match the queued master samples

    def _fail(self, why: str) -> None:
        """Stop filtering after a breakdown: keep the last good estimate (published with
        healthy=False) and let the slave run free inertial."""
        self._counters.numerical_failures += 1
        if self._health.running:
            self._health.running = False
            self._health.failure = why
            self._matching = False

    def _on_imu(self, t: int, s: ImuSample) -> None:
        self._counters.imu += 1
        first = self._t_imu is None
        if first:
            self._imu_start = t - self._imu_dt_ns      # the first sample covers (t - dt, t]
        h = self._imu_dt_nominal if self._t_imu is None else (t - self._t_imu) * 1e-9
        f_x = float(s.accel[0])
        self._deck.observe_imu(t, f_x, h)               # the record the deck run and the launch detector read
        self._t_imu = t
        live = self._live
        if live is None or self._anchor_from is not None:
            self._buffer_imu(t, s)
            if live is not None:
                self._match_pending()
            return
        if t <= live.t_ns:
            self._counters.skipped_before_init += 1
            return
        if t - live.t_ns > self._bridge_ns:
            if first:                                  # the slave started before the IMU's data
                self._start_again(t, s)
                return
            self._bridge(live, t)
            if self._anchor_from is not None:
                self._buffer_imu(t, s)
                self._match_pending()
                return
        self._propagate(live, t, s)
        if self._pending:
            self._match_pending()

    def _before_imu_data(self, t_v: int) -> bool:
        """Before initialisation: is the master valid at t_v too early to start the slave? A told
        master latency that puts t_v more than the bridge limit before the IMU's first sample
        would make the slave's first step a gap the IMU stream does not have; then the slave
        starts at the first master valid where the IMU's data begins (docs/engine.md,
        initialisation). Nearer ones start it as before (one longer first step)."""
        start = self._imu_start
        if start is None:
            return False
        if self._init_from is None and start + self._imu_dt_ns - t_v > self._bridge_ns:
            self._init_from = start
        return self._init_from is not None and t_v < self._init_from

    def _start_again(self, t: int, s: ImuSample) -> None:
        """The slave was initialised (before any IMU sample) at a master validity time more than
        the bridge limit before the IMU's first sample, t: no IMU gap to bridge or flag, and no
        step taken yet, so it is dropped and started again at the first master valid where the
        IMU's data begins (`_before_imu_data`); the sample waits in the buffer for it."""
        self._live = None
        self._counters.skipped_before_init += 1        # the master sample that started it
        self._init_from = self._imu_start
        self._buffer_imu(t, s)
        self._match_pending()

    def _buffer_imu(self, t: int, s: ImuSample) -> None:
        """Keep the IMU sample for the (re-)anchoring master; drop those older than the span."""
        self._imu_buffer.append(s)
        while self._imu_buffer and self._imu_buffer[0].t_ns < t - self._span_ns:
            self._imu_buffer.popleft()
            self._counters.skipped_before_init += 1

    def _propagate(self, live: LiveSolution, t: int, s: ImuSample) -> None:
        """The strapdown over the IMU interval ending at t, then the filter's predict (in one
        compiled call where the model and the filter allow: propagation_step.py)."""
        h = (t - live.t_ns) * 1e-9
        if h > self._cfg.max_gap_factor * self._imu_dt_nominal:
            self._counters.imu_gaps += 1
        corr = self._results.corr
        ins = live.ins
        snap = live.history.record(live.t_ns, ins.s)
        v_start = ins.s.v_n
        running = self._health.running
        a_spot = None
        if running and self._spot_accel is not None and self._cfg.specific_force == 'reference' \
                and not self._launch.moving:
            a_spot = self._spot_accel.acceleration()
        kf = live.kf
        cells = self._cells
        if running and cells is not None and type(kf) is KalmanFilter and kf.dtype is FLOAT64:
            f_model, snap.phi = strapdown_and_predict(ins, kf, cells, s.gyro, corr.bg, s.accel, corr.ba, h,
                                                      self._process_noise(t, h), a_spot)
            self._after_step(live, t, s, v_start, h)
            live.prop = Propagation(ins.c_start, f_model, ins.w_ie, ins.w_en, ins.s.v_n, ins.s.lat, ins.s.h, h)
            return
        f_n = ins.update((s.gyro - corr.bg) * h, (s.accel - corr.ba) * h, h)
        self._after_step(live, t, s, v_start, h)
        if not running:
            return
        st = ins.s
        f_model = f_n if a_spot is None else reference_specific_force(f_n, a_spot, st.v_n, ins.w_ie, ins.w_en)
        p = live.prop = Propagation(ins.c_start, f_model, ins.w_ie, ins.w_en, st.v_n, st.lat, st.h, h)
        qd = self._process_noise(t, h)
        try:
            if self._model.nonlinear:
                fun, jac = self._model.propagator(p)
                cast(NonlinearFilter, kf).predict_nonlinear(fun, qd, jac)
            else:
                phi = self._model.transition(p)
                snap.phi = phi
                kf.predict(phi, qd)
        except (np.linalg.LinAlgError, FloatingPointError, ValueError) as e:
            self._fail(f'predict: {e}')

    def _after_step(self, live: LiveSolution, t: int, s: ImuSample, v_start: np.ndarray, h: float) -> None:
        """The live solution's time, rate and history after its strapdown step to t."""
        if self._track_intervals:
            self._matcher.delay_inputs.record_interval(t, h, s.gyro, live.ins.s.v_n - v_start)
        live.t_ns = t
        live.gyro = s.gyro
        live.history.prune(t - self._span_ns, t)

    def _process_noise(self, t: int, h: float) -> np.ndarray:
        """Qd over the interval h ending at t, with the launch noise just after the launch."""
        qd = self._model.process_noise(h)
        t_launch = self._launch.t_launch_ns
        if self._q_launch is not None and t_launch is not None and t - t_launch <= self._launch_ns \
                and t > t_launch:
            qd = qd + self._q_launch * h
        return qd

    def _bridge(self, live: LiveSolution, t: int) -> None:
        """An IMU gap longer than gap_bridge_factor intervals is never one strapdown step: the
        filter's covariance is propagated over the time without data, the solution flagged 'gap'
        (ERROR beyond gap_error_s) until a NIS window after it passes. Parked on the deck, the
        slave is then carried across by the master (anchoring.py) at the first master sample
        from the next sample's interval on; moving, it dead-reckons across at its velocity."""
        start = t - self._imu_dt_ns                   # the next sample covers (start, t]
        gap = max(start - live.t_ns, 0) * 1e-9
        self._counters.imu_gaps += 1
        self._counters.bridged_gaps += 1
        hl = self._health
        hl.gap_level = max(hl.gap_level, ERROR if gap > self._cfg.gap_error_s else WARN)
        hl.gap_s, hl.recover_mark = gap, self._monitor.completed
        self._monitor.restart()
        self._whiteness.restart()
        self._matcher.restart(self._imu_rate_hz)
        if self._spot_accel is not None:
            self._spot_accel.clear()
        if hl.running:
            try:
                bridge_covariance(live.kf, self._model, live.prop, gap)
            except BREAKDOWN_ERRORS as e:
                self._fail(f'predict: {e}')
        live.history = SlaveHistory(self._span_ns)
        if not self._launch.moving and hl.running:
            self._anchor_from = start
            return
        live.ins.s = dead_reckoned(live.ins.s, gap)
        live.t_ns = start
