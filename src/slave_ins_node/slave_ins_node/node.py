"""slave_ins_node: the aircraft's strapdown IMU at its deck spot (lever arm, mounting
misalignment, catapult stroke, sensor errors) and the aircraft truth."""
from __future__ import annotations

from geometry_msgs.msg import AccelStamped, Vector3Stamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Imu

from alignment_core import pipeline
from alignment_ros import convert, node_util, qos, topics
from alignment_ros.params import NODE_SCOPES, ScenarioParameters
from alignment_ros.stamped_pairs import StampPairer

TRUTH_RATE_HZ = 10.0          # /truth/imu_bias: on the 10 Hz grid of the filter's outputs


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
        self.pairs = StampPairer()
        self.create_subscription(Odometry, topics.SHIP_ODOM, self.on_odom, qos.STREAM)
        self.create_subscription(AccelStamped, topics.SHIP_ACCEL, self.on_accel, qos.STREAM)

    def on_odom(self, m: Odometry) -> None:
        self.received[topics.SHIP_ODOM] += 1
        self._step(self.pairs.add_a(convert.to_ns(m.header.stamp), m))

    def on_accel(self, m: AccelStamped) -> None:
        self.received[topics.SHIP_ACCEL] += 1
        self._step(self.pairs.add_b(convert.to_ns(m.header.stamp), m))

    def _step(self, pair) -> None:
        if pair is None:
            self.rejected['out_of_order'] = self.pairs.rejected
            return
        s = convert.msgs_to_ship(*pair)
        truth, imu = self.stage.step(s)
        odom, mis = convert.truth_to_msgs(truth)
        if imu is not None:
            self.send(topics.AIRCRAFT_IMU, convert.imu_to_msg(imu, self.gyro_var, self.accel_var))
            if ((imu.t_ns - self.sc.t0_ns) // self.sc.dt_ns) % self.truth_every == 0:
                bias = self.stage.errors.last_bias[-1]
                self.send(topics.TRUTH_IMU_BIAS, convert.imu_bias_to_msg(imu.t_ns, bias[:3], bias[3:]))
        self.send(topics.TRUTH_AIRCRAFT_ODOM, odom)
        if mis is not None:
            self.send(topics.TRUTH_MISALIGNMENT, mis)


def main() -> None:
    node_util.run(SlaveInsNode)
