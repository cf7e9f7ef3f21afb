"""master_ins_node: the ship master INS solution = ship truth + master INS error model."""
from __future__ import annotations

from nav_msgs.msg import Odometry
from sensor_msgs.msg import NavSatFix

from alignment_core import pipeline
from alignment_core.attitude import DEG
from alignment_core.sensors import MasterInsModel
from alignment_ros import convert, node_util, qos, topics
from alignment_ros.params import ScenarioParameters


class MasterInsNode(node_util.CountingNode):
    def __init__(self) -> None:
        super().__init__('master_ins_node')
        self.sc = ScenarioParameters(self).scenario
        self.model = MasterInsModel(self.sc.master, self.sc.seed, self.sc.ship.lat_deg * DEG)
        self.plane = pipeline.plane_of(self.sc)
        self.stream_publisher(Odometry, topics.MASTER_ODOM)
        self.stream_publisher(NavSatFix, topics.MASTER_FIX)
        self.last_t: int | None = None
        self.create_subscription(Odometry, topics.SHIP_ODOM, self.on_ship, qos.STREAM)

    def on_ship(self, odom: Odometry) -> None:
        self.received[topics.SHIP_ODOM] += 1
        t = convert.to_ns(odom.header.stamp)
        if self.last_t is not None and t <= self.last_t:
            self.rejected['out_of_order'] += 1
            self.get_logger().warning(f'ship sample at {t} ns is not after {self.last_t} ns: dropped')
            return
        s = convert.msgs_to_ship(odom)
        m = self.model.measure(s)
        self.send(topics.MASTER_ODOM, convert.master_to_msg(m))
        if self.received[topics.SHIP_ODOM] % 10 == 1:
            lat, lon, h = self.plane.to_geodetic(m.p_w)
            self.send(topics.MASTER_FIX, convert.navsatfix(t, topics.FRAME_SHIP, lat, lon, h))
        self.last_t = t



def main() -> None:
    node_util.run(MasterInsNode)
