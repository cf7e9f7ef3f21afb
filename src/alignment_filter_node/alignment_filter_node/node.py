"""alignment_filter_node: aligns the aircraft INS to the master INS (never reads truth).

Inputs are queued and processed in stamp order by alignment_core's TransferAlignment, so
its outputs do not depend on how the three streams interleave on arrival. A numerical
breakdown of the filter does not stop the node: it keeps publishing the last good estimate
and reports the failure in /diagnostics (level ERROR, `healthy: false`, `numerical_failures`).
"""
from __future__ import annotations

import dataclasses

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseWithCovarianceStamped, TwistWithCovarianceStamped, Vector3Stamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Imu
from std_msgs.msg import Float64MultiArray

from alignment_core import pipeline
from alignment_core.estimation.engine import TransferAlignment
from alignment_ros import convert, node_util, qos, topics
from alignment_ros.params import NODE_SCOPES, ScenarioParameters


class AlignmentFilterNode(node_util.CountingNode):
    def __init__(self) -> None:
        super().__init__('alignment_filter_node')
        self.sc = ScenarioParameters(self, NODE_SCOPES['alignment_filter_node']).scenario
        self.plane = pipeline.plane_of(self.sc)
        self.engine = TransferAlignment(self.sc.filter, self.plane, self.sc.rate_hz)
        self.stream_publisher(Vector3Stamped, topics.ALIGN_MISALIGNMENT)
        self.stream_publisher(PoseWithCovarianceStamped, topics.ALIGN_ATTITUDE)
        self.stream_publisher(Float64MultiArray, topics.ALIGN_STATE)
        self.stream_publisher(DiagnosticArray, topics.DIAGNOSTICS)
        self.create_subscription(Imu, topics.AIRCRAFT_IMU, self.on_imu, qos.STREAM)
        self.create_subscription(Odometry, topics.MASTER_ODOM, self.on_master, qos.STREAM)
        self.create_subscription(TwistWithCovarianceStamped, topics.LDV_TWIST, self.on_ldv, qos.STREAM)
        if self.engine.uses_doppler:
            self.create_subscription(TwistWithCovarianceStamped, topics.DOPPLER_TWIST, self.on_doppler, qos.STREAM)
        self.n_out = 0
        self.reported_failure = False

    def on_imu(self, m: Imu) -> None:
        self._accept(topics.AIRCRAFT_IMU, self.engine.push_imu(convert.msg_to_imu(m)), m)

    def on_master(self, m: Odometry) -> None:
        self._accept(topics.MASTER_ODOM, self.engine.push_master(convert.msg_to_master(m)), m)

    def on_ldv(self, m: TwistWithCovarianceStamped) -> None:
        self._accept(topics.LDV_TWIST, self.engine.push_ldv(convert.msg_to_ldv(m)), m)

    def on_doppler(self, m: TwistWithCovarianceStamped) -> None:
        self._accept(topics.DOPPLER_TWIST, self.engine.push_doppler(convert.msg_to_doppler(m)), m)

    def _accept(self, topic: str, ok: bool, m) -> None:
        self.received[topic] += 1
        if not ok:
            self.rejected[topic] += 1
            self.get_logger().warning(
                f'rejected {topic} message stamped {convert.to_ns(m.header.stamp)} ns '
                f'(non-finite or not after the previous stamp); {self.rejected[topic]} so far',
                throttle_duration_sec=1.0)
        self._publish(self.engine.process())

    def _publish(self, estimates) -> None:
        if not estimates:
            return
        nav = self.engine.solution          # the live slave solution: position of the published pose
        assert nav is not None              # estimates exist only after initialisation
        p_w = self.plane.from_geodetic(nav.lat, nav.lon, nav.h)
        for e in estimates:
            mis, att, st = convert.estimate_to_msgs(e, self.engine.labels, p_w)
            self.send(topics.ALIGN_MISALIGNMENT, mis)
            self.send(topics.ALIGN_ATTITUDE, att)
            self.send(topics.ALIGN_STATE, st)
            if self.n_out % 10 == 0 or (not e.healthy and not self.reported_failure):
                self.send(topics.DIAGNOSTICS, self._diagnostics(e))
            if not e.healthy and not self.reported_failure:
                self.reported_failure = True
                self.get_logger().error(f'numerical breakdown ({self.engine.failure}): the filter stopped; '
                                        f'publishing the last good estimate')
            self.n_out += 1

    def _diagnostics(self, e) -> DiagnosticArray:
        c = self.engine.counters
        d = self.engine.diagnostics()
        bad = c.rejected_nonfinite + c.rejected_out_of_order + c.imu_gaps + c.unmatched_master
        level = DiagnosticStatus.OK if bad == 0 else DiagnosticStatus.WARN
        msg = 'aligning' if e.matching else 'free inertial (no matching)'
        if not e.healthy:
            level = DiagnosticStatus.ERROR
            msg = f'numerical breakdown ({d.failure}): last good estimate held, filter stopped'
        return convert.diagnostics(e.t_ns, 'alignment_filter', level, msg, {
            'nis': f'{e.nis:.4g}', 'updates': c.updates, 'gated': c.gated,
            'rejected_nonfinite': c.rejected_nonfinite,
            'rejected_out_of_order': c.rejected_out_of_order, 'imu_gaps': c.imu_gaps,
            'imu': c.imu, 'master': c.master, 'ldv': c.ldv, 'doppler': c.doppler,
            'doppler_updates': c.doppler_updates, 'unmatched_master': c.unmatched_master,
            'numerical_failures': c.numerical_failures, 'healthy': str(e.healthy).lower(),
            'pending': d.pending,
            'model': self.engine.model_name, 'states': self.engine.n_states, 'algorithm': self.sc.filter.algorithm,
            'lever_arm_treatment': self.sc.filter.lever_arm_treatment,
            **_fading_values(e.fading)})

    def finish(self) -> None:
        # anything still queued (a stream ended early) is processed in stamp order
        self._publish(self.engine.process(final=True))
        self.wait_acked(5.0)

    def stats(self) -> dict:
        d = super().stats()
        d['filter'] = dataclasses.asdict(self.engine.counters)
        return d


def _fading_values(fading) -> dict[str, str]:
    """The fading factor of the last update (1 = none): one number for a single factor, the
    maximum and the per-state list for the multiple-factor STF."""
    lam = np.atleast_1d(np.asarray(fading, dtype=float))
    if lam.size == 1:
        return {'fading': f'{lam[0]:.4g}'}
    return {'fading_max': f'{lam.max():.4g}', 'fading': ' '.join(f'{v:.3g}' for v in lam)}


def main() -> None:
    node_util.run(AlignmentFilterNode)
