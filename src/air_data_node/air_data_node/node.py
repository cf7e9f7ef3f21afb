"""air_data_node: the flush air-data sensor (FADS). From the aircraft truth (/truth/aircraft/odom)
it runs alignment_core's FadsStage and publishes the five port pressures (/fads/port_k), the
air-data truth of each frame (/truth/air_data/state) and the wind (/truth/wind). Nothing
when fads.enabled is false."""
from __future__ import annotations

import numpy as np
from geometry_msgs.msg import Vector3Stamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import FluidPressure
from std_msgs.msg import Float64MultiArray

from alignment_core import pipeline
from alignment_core.geometry.rotations import quat_to_dcm
from alignment_core.sensors.fads import FadsStage
from alignment_core.validation import require
from alignment_ros import air_data_convert, convert, node_util, topics
from alignment_ros.params import NODE_SCOPES, ScenarioParameters


class AirDataNode(node_util.CountingNode):
    def __init__(self) -> None:
        super().__init__('air_data_node')
        sc = self.sc = ScenarioParameters(self, NODE_SCOPES['air_data_node']).scenario
        self.stage: FadsStage | None = None
        if not sc.fads.enabled:             # no sensor: the node idles (graph.py starts it only with one)
            return
        n = sc.fads.geometry.count
        require(n == len(topics.FADS_PORT_TOPICS),
                f'fads: the graph has {len(topics.FADS_PORT_TOPICS)} port topics, the geometry {n} ports')
        self.plane = pipeline.plane_of(sc)
        self.stage = FadsStage(sc.fads, sc.seed, sc.t0_ns)
        self.last_ns: int | None = None
        for t in topics.FADS_PORT_TOPICS:
            self.stream_publisher(FluidPressure, t)
        self.stream_publisher(Float64MultiArray, topics.TRUTH_AIR_DATA_STATE)
        self.stream_publisher(Vector3Stamped, topics.TRUTH_WIND)
        self.stream_subscription(Odometry, topics.TRUTH_AIRCRAFT_ODOM, self.on_truth)

    def on_truth(self, m: Odometry) -> None:
        self.received[topics.TRUTH_AIRCRAFT_ODOM] += 1
        a = convert.msg_to_truth(m)
        if self.last_ns is not None and a.t_ns <= self.last_ns:
            self.rejected['out_of_order'] += 1
            return
        if not (np.all(np.isfinite(a.p_w)) and np.all(np.isfinite(a.q_nb)) and np.all(np.isfinite(a.v_b))):
            self.rejected['not_finite'] += 1
            return
        self.last_ns = a.t_ns
        v_enu = quat_to_dcm(a.q_nb) @ a.v_b             # q_nb: body FLU -> local ENU (convert.msg_to_truth)
        _, _, h = self.plane.to_geodetic(a.p_w)
        assert self.stage is not None
        for f in self.stage.step(a.t_ns, a.q_nb, v_enu, float(h)):
            for topic, msg in zip(topics.FADS_PORT_TOPICS, air_data_convert.frame_to_msgs(f)):
                self.send(topic, msg)
            state, wind = air_data_convert.air_truth_to_msgs(f)
            self.send(topics.TRUTH_AIR_DATA_STATE, state)
            self.send(topics.TRUTH_WIND, wind)


def main() -> None:
    node_util.run(AirDataNode)


if __name__ == '__main__':
    main()
