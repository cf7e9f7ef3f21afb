"""ldv_node: laser Doppler velocimeter, the aircraft's velocity relative to the deck."""
from __future__ import annotations

from geometry_msgs.msg import TwistWithCovarianceStamped
from nav_msgs.msg import Odometry

from alignment_core import pipeline
from alignment_core.sensors import LdvModel
from alignment_ros import convert, node_util, qos, topics
from alignment_ros.params import ScenarioParameters
from alignment_ros.stamped_pairs import StampPairer


class LdvNode(node_util.CountingNode):
    def __init__(self) -> None:
        super().__init__('ldv_node')
        self.sc = ScenarioParameters(self).scenario
        self.model = LdvModel(self.sc.ldv, self.sc.seed, pipeline.plane_of(self.sc))
        self.stream_publisher(TwistWithCovarianceStamped, topics.LDV_TWIST)
        self.pairs = StampPairer()
        self.create_subscription(Odometry, topics.SHIP_ODOM, self.on_ship, qos.STREAM)
        self.create_subscription(Odometry, topics.TRUTH_AIRCRAFT_ODOM, self.on_aircraft, qos.STREAM)

    def on_ship(self, m: Odometry) -> None:
        self.received[topics.SHIP_ODOM] += 1
        self._step(self.pairs.add_a(convert.to_ns(m.header.stamp), m))

    def on_aircraft(self, m: Odometry) -> None:
        self.received[topics.TRUTH_AIRCRAFT_ODOM] += 1
        self._step(self.pairs.add_b(convert.to_ns(m.header.stamp), m))

    def _step(self, pair) -> None:
        if pair is None:
            return
        ship_odom, air_odom = pair
        s = convert.msgs_to_ship(ship_odom)
        meas = self.model.measure(s, convert.msg_to_truth(air_odom))
        self.send(topics.LDV_TWIST, convert.ldv_to_msg(meas))



def main() -> None:
    node_util.run(LdvNode)
