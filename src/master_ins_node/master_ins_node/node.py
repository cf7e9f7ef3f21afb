"""master_ins_node: the ship master INS solution = ship truth + master INS error model, at the
master's own rate, stamped validity time + latency and published when simulation time
reaches the stamp; /master/fix and /truth/master_error (attitude error phi, nav frame) at
10 Hz.

Ship samples are collected and run through the stage in chunks (`MasterInsStage.step_many`: per
sample, a chunk of 50 costs about an eighth of a single `step`), up to CHUNK_MAX samples, or
whatever is pending when the FLUSH_PERIOD_S wall timer fires, and at shutdown. Any split gives
the outputs `step` gives sample by sample, bit for bit, in the same order; only when they go out
changes, by at most a chunk (the ship's lead limit, alignment_ros/pacing.py, is 5 s of simulated
time)."""
from __future__ import annotations

from geometry_msgs.msg import Vector3Stamped
from nav_msgs.msg import Odometry
from rclpy.clock import Clock, ClockType
from sensor_msgs.msg import NavSatFix

from alignment_core import pipeline
from alignment_core.samples import ShipSample
from alignment_core.sensors.master_ins import MasterInsStage
from alignment_core.units import DEG
from alignment_ros import convert, node_util, topics
from alignment_ros.params import NODE_SCOPES, ScenarioParameters

FIX_RATE_HZ = 10.0
CHUNK_MAX = 50                # ship samples per batched stage call (0.5 s at 100 Hz)
FLUSH_PERIOD_S = 0.02         # wall time: a pending chunk is processed at least this often


class MasterInsNode(node_util.CountingNode):
    def __init__(self) -> None:
        super().__init__('master_ins_node')
        self.sc = ScenarioParameters(self, NODE_SCOPES['master_ins_node']).scenario
        m = self.sc.master
        self.stage = MasterInsStage(m, self.sc.seed, self.sc.ship.lat_deg * DEG, self.sc.rate_hz, self.sc.t0_ns)
        self.plane = pipeline.plane_of(self.sc)
        self.stream_publisher(Odometry, topics.MASTER_ODOM)
        self.stream_publisher(NavSatFix, topics.MASTER_FIX)
        self.stream_publisher(Vector3Stamped, topics.TRUTH_MASTER_ERROR)
        self.fix_every = max(1, round((m.rate_hz or self.sc.rate_hz) / FIX_RATE_HZ))
        self.n_out = 0
        self.last_t: int | None = None
        self.pending: list[ShipSample] = []
        self.create_timer(FLUSH_PERIOD_S, self.flush, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.stream_subscription(Odometry, topics.SHIP_ODOM, self.on_ship)

    def on_ship(self, odom: Odometry) -> None:
        self.received[topics.SHIP_ODOM] += 1
        t = convert.to_ns(odom.header.stamp)
        if self.last_t is not None and t <= self.last_t:
            self.rejected['out_of_order'] += 1
            self.get_logger().warning(f'ship sample at {t} ns is not after {self.last_t} ns: dropped')
            return
        self.last_t = t
        self.pending.append(convert.msgs_to_ship(odom))
        if len(self.pending) >= CHUNK_MAX:
            self.flush()

    def flush(self) -> None:
        """Run the pending ship samples through the stage and publish what it releases."""
        if not self.pending:
            return
        samples, self.pending = self.pending, []
        for out in self.stage.step_many(samples):
            m = out.sample
            self.send(topics.MASTER_ODOM, convert.master_to_msg(m))
            if self.n_out % self.fix_every == 0:
                lat, lon, h = self.plane.to_geodetic(m.p_w)
                self.send(topics.MASTER_FIX, convert.navsatfix(m.t_ns, topics.FRAME_SHIP, lat, lon, h))
                self.send(topics.TRUTH_MASTER_ERROR, convert.vector_stamped(m.t_ns, topics.FRAME_WORLD, out.phi))
            self.n_out += 1

    def finish(self) -> None:
        """At shutdown: what is still pending goes out before the acknowledgements are awaited."""
        self.flush()


def main() -> None:
    node_util.run(MasterInsNode)
