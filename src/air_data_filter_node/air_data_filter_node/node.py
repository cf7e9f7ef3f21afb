"""air_data_filter_node: the air-data estimator of `air_data_filter` (paper or tight form,
EKF / UKF / CKF); it never reads a /truth topic. It knows the installed sensor's calibration
(port geometry, eps(M)), never its noise truth or faults.

Inputs: the five /fads/port_k (a frame once all five of one stamp are in), the INS odometry of
`ins_source` (/alignment/odom or /reference_ins/odom) and, for the paper form, /aircraft/imu in
blocks of air_data_run.IMU_BLOCK_S. They are released to the estimator in stamp order (INS,
then IMU, then the frame at equal stamps, as air_data_run feeds them), so the estimates do not
depend on how the topics interleave. Times: the stamps in seconds.
Outputs at every frame once initialised: /air_data/velocity, static and total pressure, wind,
state, and /diagnostics (WARN while not initialised or with a port excluded). Nothing
non-finite is published: a failure of the estimator (or a non-finite estimate) is an ERROR in
/diagnostics, and no estimate is published after it."""
from __future__ import annotations

import functools
import math

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import TwistWithCovarianceStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import FluidPressure, Imu
from std_msgs.msg import Float64MultiArray

from alignment_core import pipeline
from alignment_core.air_data_run import IMU_BLOCK_S, make_estimator
from alignment_core.estimation.air_data.outputs import AirDataEstimate
from alignment_core.estimation.air_data.paper_form import PaperAirDataFilter
from alignment_core.validation import require
from alignment_ros import air_data_convert, convert, node_util, topics
from alignment_ros.air_data_topics import INS_TOPICS
from alignment_ros.params import NODE_SCOPES, ScenarioParameters

from .inputs import FrameAssembler, ImuBlocks, StampOrder

MAX_WAIT_S = 300.0
"""An input waits for the other streams at most this long (in stamp time) before it is processed
(then the stream behind is taken as silent). As fast as possible (real-time factor 0) a reliable
stream can trail another by thousands of messages (tens of seconds of stamps): a short wait
would process frames before their INS and break graph == batch."""
INS, IMU, FRAME = 'ins', 'imu', 'frame'


class AirDataFilterNode(node_util.CountingNode):
    def __init__(self) -> None:
        super().__init__('air_data_filter_node')
        sc = self.sc = ScenarioParameters(self, NODE_SCOPES['air_data_filter_node']).scenario
        self.cfg = sc.air_data_filter
        n = sc.fads.geometry.count
        require(n == len(topics.FADS_PORT_TOPICS),
                f'fads: the graph has {len(topics.FADS_PORT_TOPICS)} port topics, the geometry {n} ports')
        self.plane = pipeline.plane_of(sc)
        self.est = make_estimator(self.cfg, sc)
        self.paper = isinstance(self.est, PaperAirDataFilter)
        self.frames = FrameAssembler(n, int(MAX_WAIT_S * 1e9))
        self.imu = ImuBlocks(round(IMU_BLOCK_S * sc.rate_hz), sc.dt_ns)
        self.order = StampOrder((INS, IMU, FRAME) if self.paper else (INS, FRAME), int(MAX_WAIT_S * 1e9))
        self.ins_topic = INS_TOPICS[self.cfg.ins_source]
        self.failure = ''
        self.n_out = 0
        for t in (topics.AIR_DATA_VELOCITY, topics.AIR_DATA_WIND):
            self.stream_publisher(TwistWithCovarianceStamped, t)
        for t in (topics.AIR_DATA_STATIC_PRESSURE, topics.AIR_DATA_TOTAL_PRESSURE):
            self.stream_publisher(FluidPressure, t)
        self.stream_publisher(Float64MultiArray, topics.AIR_DATA_STATE)
        self.stream_publisher(DiagnosticArray, topics.DIAGNOSTICS)
        for k, t in enumerate(topics.FADS_PORT_TOPICS):
            self.stream_subscription(FluidPressure, t, functools.partial(self.on_port, k))
        self.stream_subscription(Odometry, self.ins_topic, self.on_ins)
        if self.paper:
            self.stream_subscription(Imu, topics.AIRCRAFT_IMU, self.on_imu)

    # ----- inputs -----
    def on_port(self, k: int, m: FluidPressure) -> None:
        topic = topics.FADS_PORT_TOPICS[k]
        self.received[topic] += 1
        t_ns, port, p, _ = air_data_convert.msg_to_port(m)
        if port != k:
            self.rejected['frame_id'] += 1
            return
        frame = self.frames.add(k, t_ns, p)
        for why, n in self.frames.rejected.items():       # assignment: Counter.update would add
            self.rejected[why] = n
        if frame is not None:
            self.order.add(FRAME, *frame)
        self._process()

    def on_ins(self, m: Odometry) -> None:
        self.received[self.ins_topic] += 1
        if m.header.frame_id != topics.FRAME_WORLD or m.child_frame_id != topics.FRAME_AIRCRAFT:
            self.rejected['frame_id'] += 1
            return
        s = air_data_convert.msg_to_ins(m, self.plane)
        self.order.add(INS, convert.to_ns(m.header.stamp), s)
        self._process()

    def on_imu(self, m: Imu) -> None:
        self.received[topics.AIRCRAFT_IMU] += 1
        s = convert.msg_to_imu(m)
        before = self.imu.rejected
        block = self.imu.add(s.t_ns, s.accel, s.gyro)
        if self.imu.rejected != before:
            self.rejected['imu'] += 1
            return
        if block is not None:
            self.order.add(IMU, block[1], block)
        else:
            self.order.advance(IMU, s.t_ns)
        self._process()

    def _process(self, final: bool = False) -> None:
        for stream, t_ns, item in self.order.ready(final):
            if stream == INS:
                if not self.est.push_ins(item):
                    self.rejected['ins'] += 1
            elif stream == IMU and isinstance(self.est, PaperAirDataFilter):
                t0_ns, t1_ns, f_b, w_ib = item
                self.est.push_imu(t0_ns * 1e-9, t1_ns * 1e-9, f_b, w_ib)
            elif stream == FRAME:
                self._frame(t_ns, item)

    # ----- estimates -----
    def _frame(self, t_ns: int, pressures: np.ndarray) -> None:
        t = t_ns * 1e-9
        self.est.push_frame(t, pressures)
        e = None
        if not self.failure:
            if self.est.failure:
                self._fail(t, self.est.failure)
            elif self.est.initialised:
                e = self.est.estimate(t)
                if e is not None and not (e.healthy and air_data_convert.estimate_finite(e)):
                    self._fail(t, 'the estimate is not finite')
                    e = None
        if e is not None:
            msgs = air_data_convert.air_data_to_msgs(t_ns, e)
            self.send(topics.AIR_DATA_VELOCITY, msgs.velocity)
            self.send(topics.AIR_DATA_STATIC_PRESSURE, msgs.static_pressure)
            self.send(topics.AIR_DATA_TOTAL_PRESSURE, msgs.total_pressure)
            self.send(topics.AIR_DATA_WIND, msgs.wind)
            self.send(topics.AIR_DATA_STATE, msgs.state)
            self.n_out += 1
        self.send(topics.DIAGNOSTICS, self._diagnostics(t_ns, e))

    def _fail(self, t: float, why: str) -> None:
        self.failure = why
        self.get_logger().error(f'air-data estimator failed at {t:.3f} s: {why}; no further estimates')

    def _diagnostics(self, t_ns: int, e: AirDataEstimate | None) -> DiagnosticArray:
        excluded = tuple(getattr(self.est, 'excluded_ports', ()))
        if self.failure:
            level, text = DiagnosticStatus.ERROR, f'failed: {self.failure}; no estimates are published'
        elif not self.est.initialised:
            level, text = DiagnosticStatus.WARN, 'not initialised: waiting for a frame the FADS solve and the INS cover'
        elif excluded:
            level, text = DiagnosticStatus.WARN, f'estimating without port(s) {", ".join(map(str, excluded))}'
        else:
            level, text = DiagnosticStatus.OK, 'estimating'
        nis = self.est.last_nis
        values = {'form': self.cfg.form, 'algorithm': self.cfg.algorithm, 'ins_source': self.cfg.ins_source,
                  'initialised': str(self.est.initialised).lower(),
                  'healthy': str(not self.failure and (e is None or e.healthy)).lower(),
                  **{k: v for k, v in self.est.counts.items()},
                  'excluded_ports': ' '.join(map(str, excluded)),
                  'nis': f'{nis:.4g}' if math.isfinite(nis) else 'nan',
                  'published': self.n_out, 'pending': len(self.order),
                  **{f'rejected_{k}': v for k, v in sorted(self.rejected.items())}}
        return convert.diagnostics(t_ns, 'air_data_filter', level, text, values)

    def finish(self) -> None:
        # what is still queued (a stream ended first) goes in stamp order
        if self.paper:
            block = self.imu.close()
            if block is not None:
                self.order.add(IMU, block[1], block)
        self._process(final=True)
        self.wait_acked(5.0)

    def stats(self) -> dict:
        d = super().stats()
        d['air_data'] = {**self.est.counts, 'failure': self.failure, 'published': self.n_out}
        return d


def main() -> None:
    node_util.run(AirDataFilterNode)


if __name__ == '__main__':
    main()
