"""alignment_filter_node: aligns the aircraft INS to the master INS (never reads truth).

Inputs are read from their bytes (a message that is not one of its type is rejected and counted
as 'malformed': alignment_ros/wire.py), checked for their frame (a message in another frame is
rejected and counted as 'frame_id'), converted, and queued and processed in stamp order by alignment_core's
TransferAlignment, which rejects implausible samples itself (counted per reason), so its outputs
do not depend on how the streams interleave on arrival. What it publishes is the engine's
published view: never a non-finite or absurd estimate, and from an ERROR on (a numerical
breakdown, an inconsistent filter, a long IMU gap) the last good estimate on every topic, reported
in /diagnostics (level ERROR, `healthy: false`). /diagnostics is published every 10th output and
whenever the level or its reasons change (a master or LDV that falls silent: WARN).
"""
from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseWithCovarianceStamped, TwistWithCovarianceStamped, Vector3Stamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Imu
from std_msgs.msg import Float64MultiArray

from alignment_core import pipeline
from alignment_core.estimation.engine import TransferAlignment
from alignment_core.estimation.health import ERROR, WARN
from alignment_core.estimation.outputs import Diagnostics, Estimate, Report
from alignment_ros import convert, node_util, topics
from alignment_ros.params import NODE_SCOPES, ScenarioParameters

LEVELS = (DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR)


class FilterInputs:
    """Messages into the engine: the frame check, the conversion, the push. Each call returns ''
    if the message was taken, else the reason it was rejected ('frame_id' or the engine's); the
    subscriptions count the messages they could not read (`malformed`).
    wall_silence_s > 0: a stream the engine waits for is only reported while it has also
    delivered nothing for that long on `clock` (a stall, not a scheduling hiccup of a fast run)."""

    def __init__(self, engine: TransferAlignment, wall_silence_s: float = 0.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.engine = engine
        self.rejected_frame_id = 0
        self.rejected_malformed = 0
        self._wall_silence_s = wall_silence_s
        self._clock = clock
        self._delivered: dict[str, float] = {}          # stream -> clock time of its last sample taken
        self._first_taken: float | None = None

    def imu(self, m: Imu) -> str:
        return self._take(topics.AIRCRAFT_IMU, m) or self._pushed(self.engine.push_imu(convert.msg_to_imu(m)), 'imu')

    def master(self, m: Odometry) -> str:
        return self._take(topics.MASTER_ODOM, m) or self._pushed(
            self.engine.push_master(convert.msg_to_master(m)), 'master')

    def ldv(self, m: TwistWithCovarianceStamped) -> str:
        return self._take(topics.LDV_TWIST, m) or self._pushed(self.engine.push_ldv(convert.msg_to_ldv(m)), 'ldv')

    def doppler(self, m: TwistWithCovarianceStamped) -> str:
        return self._take(topics.DOPPLER_TWIST, m) or self._pushed(
            self.engine.push_doppler(convert.msg_to_doppler(m)), 'doppler')

    def malformed(self, topic: str) -> None:
        """A message on `topic` that was not one of its type (never reached the engine)."""
        self.rejected_malformed += 1

    def _rejections(self) -> list[tuple[str, str]]:
        """(flag, text) of the node's own rejections so far: messages in a wrong frame, malformed ones."""
        out = []
        if self.rejected_frame_id:
            out.append(('frame_id', f'{self.rejected_frame_id} messages in a wrong frame rejected'))
        if self.rejected_malformed:
            out.append(('malformed', f'{self.rejected_malformed} malformed messages rejected'))
        return out

    def _take(self, topic: str, m) -> str:
        if convert.frame_mismatch(m, *topics.INPUT_FRAMES[topic]):
            self.rejected_frame_id += 1
            return 'frame_id'
        return ''

    def _pushed(self, ok: bool, stream: str = '') -> str:
        if ok and stream:
            self._delivered[stream] = self._clock()
            if self._first_taken is None:
                self._first_taken = self._delivered[stream]
        return '' if ok else self.engine.last_rejection or 'rejected'

    def waiting_for(self) -> tuple[str, ...]:
        """The master or LDV the engine waits for (engine.waiting_for: silent for silence_warn_s
        of the other streams' stamps), silent for wall_silence_s on the clock too."""
        now, start = self._clock(), self._first_taken
        return tuple(k for k in self.engine.waiting_for() if start is None
                     or now - self._delivered.get(k, start) > self._wall_silence_s)

    def status(self, report: Report | None = None) -> tuple[int, tuple[str, ...]]:
        """The (level, flags) of the engine's report (the given one, an output's, or as of the
        stamps processed so far); WARN and 'waiting_<stream>' while the stamp order waits for a
        master or LDV that delivers nothing (arrival liveness); WARN and 'frame_id' once a message
        in a wrong frame came, 'malformed' once one that was not a message of its type came."""
        level, flags = (report.level, report.flags) if report is not None else self.engine.status()
        waiting = self.waiting_for()
        if waiting:
            level, flags = max(level, WARN), (*flags, *(f'waiting_{k}' for k in waiting))
        own = [flag for flag, _ in self._rejections()]
        return (max(level, WARN), (*flags, *own)) if own else (level, flags)

    def message(self, report: Report | Diagnostics) -> str:
        """The report's message, with what the node waits for and its own rejections."""
        text = report.message
        waiting = self.waiting_for()
        if waiting:
            text += f"; waiting for {', '.join(waiting)}"
        for _, why in self._rejections():
            text += f'; {why}'
        return text


class AlignmentFilterNode(node_util.CountingNode):
    def __init__(self) -> None:
        super().__init__('alignment_filter_node')
        self.sc = ScenarioParameters(self, NODE_SCOPES['alignment_filter_node']).scenario
        self.plane = pipeline.plane_of(self.sc)
        self.engine = TransferAlignment(self.sc.filter, self.plane, self.sc.rate_hz, keep_history=False)
        self.inputs = FilterInputs(self.engine, self.sc.filter.silence_warn_s)
        self.stream_publisher(Vector3Stamped, topics.ALIGN_MISALIGNMENT)
        self.stream_publisher(PoseWithCovarianceStamped, topics.ALIGN_ATTITUDE)
        self.stream_publisher(Float64MultiArray, topics.ALIGN_STATE)
        self.stream_publisher(Odometry, topics.ALIGN_ODOM)
        self.stream_publisher(DiagnosticArray, topics.DIAGNOSTICS)
        self.stream_subscription(Imu, topics.AIRCRAFT_IMU, self.on_imu, self.on_malformed)
        self.stream_subscription(Odometry, topics.MASTER_ODOM, self.on_master, self.on_malformed)
        self.stream_subscription(TwistWithCovarianceStamped, topics.LDV_TWIST, self.on_ldv, self.on_malformed)
        if self.engine.uses_doppler:
            self.stream_subscription(TwistWithCovarianceStamped, topics.DOPPLER_TWIST, self.on_doppler,
                                     self.on_malformed)
        self.n_out = 0
        self.reported: tuple[int, tuple[str, ...]] = (0, ())    # (level, flags) last published in /diagnostics
        self.last: Estimate | None = None

    def on_malformed(self, topic: str) -> None:
        """A message that could not be read: counted, and /diagnostics says so at once (stamped with
        the last output's time, or the scenario's start: the message had no readable stamp)."""
        self.inputs.malformed(topic)
        self._publish([], self.last.t_ns if self.last is not None else self.sc.t0_ns)

    def on_imu(self, m: Imu) -> None:
        self._accept(topics.AIRCRAFT_IMU, self.inputs.imu(m), m)

    def on_master(self, m: Odometry) -> None:
        self._accept(topics.MASTER_ODOM, self.inputs.master(m), m)

    def on_ldv(self, m: TwistWithCovarianceStamped) -> None:
        self._accept(topics.LDV_TWIST, self.inputs.ldv(m), m)

    def on_doppler(self, m: TwistWithCovarianceStamped) -> None:
        self._accept(topics.DOPPLER_TWIST, self.inputs.doppler(m), m)

    def _accept(self, topic: str, why: str, m) -> None:
        self.received[topic] += 1
        if why:
            self.rejected[topic] += 1
            self.get_logger().warning(
                f'rejected {topic} message stamped {convert.to_ns(m.header.stamp)} ns ({why}); '
                f'{self.rejected[topic]} rejected on it so far', throttle_duration_sec=1.0)
        self._publish(self.engine.process(), convert.to_ns(m.header.stamp))

    def _publish(self, estimates: list[Estimate], t_ns: int) -> None:
        for e in estimates:
            p_w = e.p_w if e.p_w is not None else self._position()
            mis, att, st = convert.estimate_to_msgs(e, self.engine.state_labels, p_w)
            self.send(topics.ALIGN_MISALIGNMENT, mis)
            self.send(topics.ALIGN_ATTITUDE, att)
            self.send(topics.ALIGN_STATE, st)
            odom = convert.estimate_to_odometry(e)
            if odom is not None:
                self.send(topics.ALIGN_ODOM, odom)
            self.last = e
            if self.n_out % 10 == 0 or self._changed():
                self._send_diagnostics(e.t_ns)
            self.n_out += 1
        if not estimates and self._changed():     # e.g. waiting for a silent stream, a message in a wrong frame
            self._send_diagnostics(t_ns if self.last is None else max(t_ns, self.last.t_ns))

    def _position(self) -> np.ndarray:
        nav = self.engine.solution
        return np.zeros(3) if nav is None else self.plane.from_geodetic(nav.lat, nav.lon, nav.h)

    def _report(self) -> Report:
        """The report of the last output (a function of the stamps processed up to it, so the
        graph and a replay say the same); before the first output, as of the stamps processed."""
        e = self.last
        if e is not None and e.report is not None:
            return e.report
        return self.engine.report()

    def _changed(self) -> bool:
        return self.inputs.status(self._report()) != self.reported

    def _send_diagnostics(self, t_ns: int) -> None:
        d = self.engine.diagnostics()
        report = self._report()
        level, flags = self.inputs.status(report)
        text = self.inputs.message(report)
        if level == ERROR and self.reported[0] < ERROR:
            self.get_logger().error(text)
        elif (level, flags) != self.reported and flags:
            self.get_logger().warning(f'{text} [{", ".join(flags)}]', throttle_duration_sec=1.0)
        self.reported = (level, flags)
        self.send(topics.DIAGNOSTICS, self._diagnostics(t_ns, d, level, flags, text))

    def _diagnostics(self, t_ns: int, d: Diagnostics, level: int, flags: tuple[str, ...], text: str
                     ) -> DiagnosticArray:
        c = self.engine.counters
        e = self.last
        return convert.diagnostics(t_ns, 'alignment_filter', LEVELS[level], text, {
            'nis': f'{e.nis:.4g}' if e is not None else 'nan', 'updates': c.updates, 'gated': c.gated,
            'rejected_nonfinite': c.rejected_nonfinite, 'rejected_out_of_order': c.rejected_out_of_order,
            'rejected_quaternion': c.rejected_quaternion, 'rejected_range': c.rejected_range,
            'rejected_future_stamp': c.rejected_future_stamp, 'rejected_frame_id': self.inputs.rejected_frame_id,
            'rejected_malformed': self.inputs.rejected_malformed, 'rejected_ldv_mode': c.rejected_ldv_mode,
            'quaternion_normalised': c.quaternion_normalised, 'launch_not_felt': c.launch_not_felt,
            'imu_gaps': c.imu_gaps, 'bridged_gaps': c.bridged_gaps, 'gate_released': c.gate_released,
            'imu': c.imu, 'master': c.master, 'ldv': c.ldv, 'doppler': c.doppler,
            'doppler_updates': c.doppler_updates, 'unmatched_master': c.unmatched_master,
            'numerical_failures': c.numerical_failures, 'healthy': str(d.healthy).lower(),
            'flags': ' '.join(flags), 'silent': ' '.join(f[:-len('_silent')] for f in flags if f.endswith('_silent')),
            'waiting': ' '.join(self.inputs.waiting_for()), 'held': str(
                e is not None and 'held' in e.flags).lower(),
            'misalignment_valid_ns': e.validity_ns if e is not None else '',
            **{k: f'{v:.4g}' if isinstance(v, float) else v for k, v in d.consistency.items()},
            **{k: f'{v:.4g}' if isinstance(v, float) else v for k, v in d.whiteness.items()},
            'relative_velocity': d.relative_velocity, 'ldv_ignored': c.ldv_ignored,
            'consistency_failures': c.consistency_failures, 'pending': d.pending,
            'model': self.engine.model_name, 'states': self.engine.n_states, 'algorithm': self.sc.filter.algorithm,
            'lever_arm_treatment': self.sc.filter.lever_arm_treatment,
            **_fading_values(e.fading if e is not None else 1.0)})

    def finish(self) -> None:
        # anything still queued (a stream ended early) is processed in stamp order
        self._publish(self.engine.process(final=True), self.last.t_ns if self.last is not None else 0)
        self.wait_acked(5.0)

    def stats(self) -> dict:
        d = super().stats()
        d['filter'] = {**dataclasses.asdict(self.engine.counters), 'rejected_frame_id': self.inputs.rejected_frame_id,
                       'rejected_malformed': self.inputs.rejected_malformed}
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
