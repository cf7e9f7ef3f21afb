"""ldv_node: the velocity sensors. Laser Doppler velocimeter (the aircraft's velocity
relative to the deck, /ldv/twist) and, when doppler.enabled, the Doppler radar (the
aircraft's ground velocity in its body axes, /doppler/twist); each at its own rate, stamped
validity time + latency and published when simulation time reaches the stamp.

Paired (ship, aircraft) samples are collected and run through the LDV stage in chunks
(`LdvStage.step_many`), up to CHUNK_MAX pairs, or whatever is pending when the FLUSH_PERIOD_S
wall timer fires, and at shutdown: any split gives the samples `step` gives pair by pair, bit for
bit, so only when they go out changes, by at most a chunk (within the ship's lead,
alignment_ros/pacing.py)."""
from __future__ import annotations

from geometry_msgs.msg import TwistWithCovarianceStamped
from nav_msgs.msg import Odometry
from rclpy.clock import Clock, ClockType

from alignment_core import pipeline
from alignment_core.samples import AircraftTruth, ShipSample
from alignment_core.sensors.doppler_radar import DopplerStage
from alignment_core.sensors.ldv import LdvStage
from alignment_ros import convert, node_util, topics
from alignment_ros.params import NODE_SCOPES, ScenarioParameters
from alignment_ros.stamped_pairs import StampPairer

CHUNK_MAX = 50                # pairs per batched stage call (0.5 s at 100 Hz)
FLUSH_PERIOD_S = 0.02         # wall time: a pending chunk is processed at least this often


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
        self.pending: list[tuple[ShipSample, AircraftTruth]] = []
        self.create_timer(FLUSH_PERIOD_S, self.flush, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.stream_subscription(Odometry, topics.SHIP_ODOM, self.on_ship)
        self.stream_subscription(Odometry, topics.TRUTH_AIRCRAFT_ODOM, self.on_aircraft)

    def on_ship(self, m: Odometry) -> None:
        self.received[topics.SHIP_ODOM] += 1
        self._add(self.pairs.add_a(convert.to_ns(m.header.stamp), m))

    def on_aircraft(self, m: Odometry) -> None:
        self.received[topics.TRUTH_AIRCRAFT_ODOM] += 1
        self._add(self.pairs.add_b(convert.to_ns(m.header.stamp), m))

    def _add(self, pair) -> None:
        if pair is None:
            self.rejected.update(self.pairs.counts())
            return
        ship_odom, air_odom = pair
        self.pending.append((convert.msgs_to_ship(ship_odom), convert.msg_to_truth(air_odom)))
        if len(self.pending) >= CHUNK_MAX:
            self.flush()

    def flush(self) -> None:
        """Run the pending pairs through the sensors and publish what they release."""
        if not self.pending:
            return
        pairs, self.pending = self.pending, []
        for meas in self.ldv.step_many([s for s, _ in pairs], [a for _, a in pairs]):
            self.send(topics.LDV_TWIST, convert.ldv_to_msg(meas))
        if self.doppler is not None:
            for _, aircraft in pairs:
                for d in self.doppler.step(aircraft):
                    self.send(topics.DOPPLER_TWIST, convert.doppler_to_msg(d))

    def finish(self) -> None:
        """At shutdown: what is still pending goes out before the acknowledgements are awaited."""
        self.flush()


def main() -> None:
    node_util.run(LdvNode)
