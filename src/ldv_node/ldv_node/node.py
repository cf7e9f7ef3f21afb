"""ldv_node: the velocity sensors. Laser Doppler velocimeter (the aircraft's velocity
relative to the deck, /ldv/twist) and, when doppler.enabled, the Doppler radar (the
aircraft's ground velocity in its body axes, /doppler/twist); each at its own rate, stamped
validity time + latency and published when simulation time reaches the stamp."""
from __future__ import annotations

from geometry_msgs.msg import TwistWithCovarianceStamped
from nav_msgs.msg import Odometry

from alignment_core import pipeline
from alignment_core.sensors.doppler_radar import DopplerStage
from alignment_core.sensors.ldv import LdvStage
from alignment_ros import convert, node_util, qos, topics
from alignment_ros.params import NODE_SCOPES, ScenarioParameters
from alignment_ros.stamped_pairs import StampPairer


class LdvNode(node_util.CountingNode):
    def __init__(self) -> None:
        super().__init__('ldv_node')
        sc = self.sc = ScenarioParameters(self, NODE_SCOPES['ldv_node']).scenario
        self.ldv = LdvStage(sc.ldv, sc.seed, pipeline.plane_of(sc), sc.rate_hz, sc.t0_ns)
        self.doppler = DopplerStage(sc.doppler, sc.seed, sc.rate_hz, sc.t0_ns) if sc.doppler.enabled else None
        self.stream_publisher(TwistWithCovarianceStamped, topics.LDV_TWIST)
        if self.doppler is not None:
            self.stream_publisher(TwistWithCovarianceStamped, topics.DOPPLER_TWIST)
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
            self.rejected.update(self.pairs.counts())
            return
        ship_odom, air_odom = pair
        aircraft = convert.msg_to_truth(air_odom)
        for meas in self.ldv.step(convert.msgs_to_ship(ship_odom), aircraft):
            self.send(topics.LDV_TWIST, convert.ldv_to_msg(meas))
        if self.doppler is not None:
            for d in self.doppler.step(aircraft):
                self.send(topics.DOPPLER_TWIST, convert.doppler_to_msg(d))


def main() -> None:
    node_util.run(LdvNode)
