"""slave_ins_node: the aircraft's strapdown IMU at its deck spot (lever arm, mounting
misalignment, catapult stroke, sensor errors) and the aircraft truth; when reference_ins.enabled,
a reference INS solution from that truth (/reference_ins/odom).

Paired ship samples are collected and run through the stage in chunks (`SlaveImuStage.step_many`:
per sample, a chunk of 50 costs about a twentieth of a single `step`), up to CHUNK_MAX samples, or
whatever is pending when the FLUSH_PERIOD_S wall timer fires, and at shutdown. Any split gives the
records `step` gives sample by sample, bit for bit, so the messages, their stamps and their order
are those of stepping; only when they go out changes, by at most a chunk (the ship's lead limit,
alignment_ros/pacing.py, is 5 s of simulated time)."""
from __future__ import annotations

from geometry_msgs.msg import AccelStamped, Vector3Stamped
from nav_msgs.msg import Odometry
from rclpy.clock import Clock, ClockType
from sensor_msgs.msg import Imu

from alignment_core import pipeline
from alignment_core.geometry.rotations import quat_to_dcm
from alignment_core.samples import AircraftTruth, ShipSample
from alignment_core.sensors.reference_ins import ReferenceInsStage
from alignment_ros import air_data_convert, convert, node_util, topics
from alignment_ros.air_data_topics import REFERENCE_INS_ODOM
from alignment_ros.params import NODE_SCOPES, ScenarioParameters
from alignment_ros.stamped_pairs import StampPairer

TRUTH_RATE_HZ = 10.0          # /truth/imu_bias: on the 10 Hz grid of the filter's outputs
CHUNK_MAX = 50                # ship samples per batched stage call (0.5 s at 100 Hz)
FLUSH_PERIOD_S = 0.02         # wall time: a pending chunk is processed at least this often


class SlaveInsNode(node_util.CountingNode):
    def __init__(self) -> None:
        super().__init__('slave_ins_node')
        self.sc = ScenarioParameters(self, NODE_SCOPES['slave_ins_node']).scenario
        self.stage = pipeline.SlaveImuStage(self.sc)
        imu = self.sc.imu
        self.gyro_var = imu.arw**2 * self.sc.rate_hz
        self.accel_var = imu.vrw**2 * self.sc.rate_hz
        self.stream_publisher(Imu, topics.AIRCRAFT_IMU)
        self.stream_publisher(Odometry, topics.TRUTH_AIRCRAFT_ODOM)
        self.stream_publisher(Vector3Stamped, topics.TRUTH_MISALIGNMENT)
        self.stream_publisher(Imu, topics.TRUTH_IMU_BIAS)
        self.truth_every = max(1, round(self.sc.rate_hz / TRUTH_RATE_HZ))
        self.plane = pipeline.plane_of(self.sc)
        self.reference: ReferenceInsStage | None = None
        if self.sc.reference_ins.enabled:
            self.reference = ReferenceInsStage(self.sc.reference_ins, self.sc.seed, self.sc.t0_ns)
            self.stream_publisher(Odometry, REFERENCE_INS_ODOM)
        self.pairs = StampPairer()
        self.pending: list[ShipSample] = []
        self.create_timer(FLUSH_PERIOD_S, self.flush, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.stream_subscription(Odometry, topics.SHIP_ODOM, self.on_odom)
        self.stream_subscription(AccelStamped, topics.SHIP_ACCEL, self.on_accel)

    def on_odom(self, m: Odometry) -> None:
        self.received[topics.SHIP_ODOM] += 1
        self._add(self.pairs.add_a(convert.to_ns(m.header.stamp), m))

    def on_accel(self, m: AccelStamped) -> None:
        self.received[topics.SHIP_ACCEL] += 1
        self._add(self.pairs.add_b(convert.to_ns(m.header.stamp), m))

    def _add(self, pair) -> None:
        if pair is None:
            self.rejected.update(self.pairs.counts())
            return
        self.pending.append(convert.msgs_to_ship(*pair))
        if len(self.pending) >= CHUNK_MAX:
            self.flush()

    def flush(self) -> None:
        """Run the pending ship samples through the stage and publish, sample by sample, what
        stepping each would have published (the IMU sample's bias: its row of last_bias)."""
        if not self.pending:
            return
        samples, self.pending = self.pending, []
        results = self.stage.step_many(samples)
        biases = self.stage.errors.last_bias
        j = 0                                                            # IMU samples so far
        for truth, imu in results:
            odom, mis = convert.truth_to_msgs(truth)
            if imu is not None:
                self.send(topics.AIRCRAFT_IMU, convert.imu_to_msg(imu, self.gyro_var, self.accel_var))
                if ((imu.t_ns - self.sc.t0_ns) // self.sc.dt_ns) % self.truth_every == 0:
                    bias = biases[j]
                    self.send(topics.TRUTH_IMU_BIAS, convert.imu_bias_to_msg(imu.t_ns, bias[:3], bias[3:]))
                j += 1
            self.send(topics.TRUTH_AIRCRAFT_ODOM, odom)
            if mis is not None:
                self.send(topics.TRUTH_MISALIGNMENT, mis)
            if self.reference is not None:
                self._reference(truth)

    def finish(self) -> None:
        """At shutdown: what is still pending goes out before the acknowledgements are awaited."""
        self.flush()

    def _reference(self, truth: AircraftTruth) -> None:
        """The reference INS from the truth as air_data_run feeds it: q_nb body -> local ENU,
        v_enu = C v_b, lat, lon, h of the world tangent plane position."""
        assert self.reference is not None
        lat, lon, h = self.plane.to_geodetic(truth.p_w)
        s = self.reference.step(truth.t_ns, truth.q_nb, quat_to_dcm(truth.q_nb) @ truth.v_b,
                                float(lat), float(lon), float(h))
        if s is not None:
            self.send(REFERENCE_INS_ODOM, air_data_convert.reference_ins_to_msg(s, self.plane))


def main() -> None:
    node_util.run(SlaveInsNode)
