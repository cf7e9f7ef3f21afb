"""ship_motion_node: publishes the ship's six-DOF truth and drives simulation time (/clock)."""
from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
from geometry_msgs.msg import AccelStamped
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
from rclpy.parameter import Parameter
from rclpy.subscription import Subscription
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import NavSatFix

from alignment_core import pipeline, run_out
from alignment_core.validation import ConfigError
from alignment_ros import convert, node_util, qos, topics
from alignment_ros.bag import stamp_reader
from alignment_ros.pacing import LeadLimit
from alignment_ros.params import NODE_SCOPES, ScenarioParameters

CHUNK = 100  # ship samples computed at once (1 s at 100 Hz; 0.24 CPU s per default run against 0.37 at 25)


class ShipMotionNode(node_util.CountingNode):
    def __init__(self) -> None:
        super().__init__('ship_motion_node')
        # the source of /clock keeps wall time: with use_sim_time (a user may set it; the scripts
        # start no node with it) it would subscribe to its own /clock, and that subscription's
        # events pile up in the executor between the rare spins of run() (100 per simulated
        # second, ~46 MiB/h)
        self.set_parameters([Parameter('use_sim_time', value=False)])
        self.declare_parameter('real_time_factor', 5.0, ParameterDescriptor(
            description='simulation speed: 1 = real time, 0 = as fast as possible'))
        self.declare_parameter('wait_subscribers', [''], ParameterDescriptor(
            description="'topic:count' or 'topic:node+node...' items to wait for before starting: "
                        "matched subscriptions (or those of the nodes named) for this node's own "
                        "topics, discovered subscriptions for any other"))
        self.declare_parameter('wait_timeout_s', 60.0, ParameterDescriptor(
            description='give up waiting for subscribers after this many wall seconds'))
        self.declare_parameter('fix_decimation', 10, ParameterDescriptor(
            description='publish /ship/fix every N samples'))
        self.declare_parameter('pace_topics', [''], ParameterDescriptor(
            description='stamped streams downstream (e.g. /truth/aircraft/odom, the filter\'s '
                        '/alignment/misalignment) the ship may not run more than max_lead_s ahead of'))
        self.declare_parameter('max_lead_s', 5.0, ParameterDescriptor(
            description='simulated seconds the ship may run ahead of pace_topics (> 0)'))
        self.declare_parameter('pace_release_s', 10.0, ParameterDescriptor(
            description='wall seconds a silent paced stream is waited for before the ship goes on '
                        'without it (until it advances again; > 0)'))
        self.add_on_set_parameters_callback(self._check)
        if self.get_parameter('real_time_factor').value < 0:
            raise ConfigError('real_time_factor must be >= 0')
        if not self.get_parameter('max_lead_s').value > 0:
            raise ConfigError('max_lead_s must be > 0')
        if not self.get_parameter('pace_release_s').value > 0:
            raise ConfigError('pace_release_s must be > 0')
        self.sc = ScenarioParameters(self, NODE_SCOPES['ship_motion_node']).scenario
        self.source = pipeline.ship_source(self.sc)
        self.plane = pipeline.plane_of(self.sc)
        self.clock_pub = self.stream_publisher(Clock, topics.CLOCK)
        self.stream_publisher(Odometry, topics.SHIP_ODOM)
        self.stream_publisher(AccelStamped, topics.SHIP_ACCEL)
        self.stream_publisher(NavSatFix, topics.SHIP_FIX)
        self._watchers: dict[str, Subscription] = {}
        self.lead = self._watch([t for t in self.get_parameter('pace_topics').value if t])
        self.pace_waits = 0
        self.pace_wait_s = 0.0

    def _watch(self, names: list[str]) -> LeadLimit | None:
        """Best-effort, latest-only subscriptions to the paced streams (they hold nothing back)."""
        if not names:
            return None
        types = topics.PACEABLE_TYPES
        unknown = [t for t in names if t not in types or stamp_reader(types[t]) is None]
        if unknown:
            raise ConfigError(f'pace_topics: not stamped topics of the graph: {unknown}')
        lead = LeadLimit(names, round(self.get_parameter('max_lead_s').value * 1e9), self.sc.t0_ns,
                         release_s=self.get_parameter('pace_release_s').value)
        for t in names:
            read = stamp_reader(types[t])
            assert read is not None  # every stream without a stamp reader was refused above
            self._watchers[t] = self.create_subscription(topics.msg_class(types[t]), t,
                                                         _stamp_noter(lead, t, read), qos.WATCH, raw=True)
        return lead

    def _keep_lead(self, t_ns: int, stop) -> None:
        """Wait (spinning) until every paced stream is within the lead of t_ns or released."""
        if self.lead is None or not self.lead.behind(t_ns):
            return
        w0 = time.monotonic()
        released = self.lead.releases
        if not self.lead.holding(t_ns, w0):
            return
        self.pace_waits += 1
        while self.lead.holding(t_ns, w0) and not stop():
            self.flush_held()        # what waits for its subscribers to match may be what is awaited
            self.executor_ref.spin_once(timeout_sec=0.01)
            self.release_heap_if_due()
        self.pace_wait_s += time.monotonic() - w0
        if self.lead.releases > released:
            self.get_logger().warning(
                f'paced streams silent for {self.lead.release_s:g} s, going on without them: '
                f'{sorted(self.lead.released)} (behind t = {t_ns * 1e-9:.3f} s)')

    def stats(self) -> dict:
        return {**super().stats(), 'pace_waits': self.pace_waits, 'pace_wait_s': round(self.pace_wait_s, 3),
                'pace_releases': self.lead.releases if self.lead is not None else 0,
                'paced_on': dict(self.lead.latest) if self.lead is not None else {}}

    def _check(self, params) -> SetParametersResult:
        for p in params:
            if p.name == 'real_time_factor' and not (p.value >= 0.0):
                return SetParametersResult(successful=False, reason='real_time_factor must be >= 0')
            if p.name == 'fix_decimation' and p.value < 1:
                return SetParametersResult(successful=False, reason='fix_decimation must be >= 1')
        return SetParametersResult(successful=True)

    def _wait_for_subscribers(self, stop) -> bool:
        wants = node_util.parse_readers(self.get_parameter('wait_subscribers').value)
        deadline = time.monotonic() + self.get_parameter('wait_timeout_s').value
        while not stop():
            missing = [(t, names or n) for t, (n, names) in wants.items()
                       if not node_util.readers_matched(self, t, self._subscribers(t), n, names)]
            # and every paced stream's publisher matched with its watcher: a publisher that holds
            # its messages until the watcher has matched (hold_until_matched) would otherwise wait
            # for a ship that has finished a short run and gone
            missing += [(t, 1) for t, sub in self._watchers.items() if sub.get_publisher_count() < 1]
            if not missing:
                # matched on this side, as every node's held messages go out: the streams are
                # reliable and keep all, so a reader matching a moment later asks for what it
                # missed (runs under load lost nothing; a fixed 0.5 s wait cost every run 0.5 s)
                return True
            if time.monotonic() > deadline:
                self.get_logger().error(f'timed out waiting for subscribers: {missing}')
                return False
            time.sleep(0.05)
        return False

    def _subscribers(self, topic: str) -> int:
        pub = self._pubs.get(topic)
        return pub.get_subscription_count() if pub is not None else self.count_subscribers(topic)

    def run(self, stop) -> None:
        if not self._wait_for_subscribers(stop):
            return
        sc = self.sc
        rtf = self.get_parameter('real_time_factor').value
        dec = self.get_parameter('fix_decimation').value
        wall0 = time.monotonic()
        n = run_out.simulated_samples(sc)     # on past the end when a stream would fall short of it
        self.get_logger().info(f'scenario {sc.name}: {sc.duration_s} s at {sc.rate_hz} Hz '
                               f'(run-out {n - sc.n_samples} samples), real-time factor {rtf}')
        chunk: list = []
        for k in range(n):
            if stop():
                break
            tau = (k * sc.dt_ns) / 1e9
            if not chunk:
                # evaluated CHUNK samples at a time: the wave sums vectorise (same numbers, a fraction of the cost)
                ks = np.arange(k, min(k + CHUNK, n))
                chunk = self.source.samples((ks * sc.dt_ns) / 1e9, sc.t0_ns, sc.dt_ns, k0=k)[::-1]
            s = chunk.pop()
            self._keep_lead(s.t_ns, stop)
            clk = Clock()
            clk.clock = convert.stamp(s.t_ns)
            self.send(topics.CLOCK, clk)
            odom, acc = convert.ship_to_msgs(s)
            self.send(topics.SHIP_ODOM, odom)
            self.send(topics.SHIP_ACCEL, acc)
            if k % dec == 0:
                lat, lon, h = self.plane.to_geodetic(s.p_w)
                self.send(topics.SHIP_FIX, convert.navsatfix(s.t_ns, topics.FRAME_SHIP, lat, lon, h))
            rtf = self.get_parameter('real_time_factor').value
            if rtf > 0:
                lag = wall0 + tau / rtf - time.monotonic()
                if lag > 0:
                    time.sleep(lag)
            if k % 50 == 0:
                self.executor_ref.spin_once(timeout_sec=0.0)
                self.release_heap_if_due()
        self._hear_paced_streams(stop)
        self.wait_acked(30.0)
        self.get_logger().info(f'done: {dict(self.published)}')

    def _hear_paced_streams(self, stop) -> None:
        """Stay until every paced stream has been heard (or was silent for pace_release_s). Its
        publisher may hold its first messages until this node's watcher has matched it (the
        graph names the ship in hold_until_matched); on a run shorter than the lead the ship
        never waited on them, and leaving at once could leave them held for ever."""
        if self.lead is None:
            return
        w0 = time.monotonic()
        while self.lead.unheard() and not stop() and time.monotonic() - w0 < self.lead.release_s:
            self.flush_held()
            self.executor_ref.spin_once(timeout_sec=0.01)
        if self.lead.unheard():
            self.get_logger().warning(f'paced streams never heard: {self.lead.unheard()}')


def _stamp_noter(lead: LeadLimit, topic: str, read: Callable[[bytes], int]) -> Callable[[bytes], None]:
    """A paced stream's watcher callback: notes the stamp of each raw (CDR) message to the lead."""
    def note(data: bytes) -> None:
        lead.note(topic, read(data))
    return note


def main() -> None:
    node_util.run(ShipMotionNode, spin=False)
