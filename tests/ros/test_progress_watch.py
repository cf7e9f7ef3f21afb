"""The launcher's watcher: a node of its own context that takes the estimate and the simulation
time it reached (its stamp) from /alignment/misalignment, the estimate's 1-sigma from
/alignment/state and Mach and alpha from /air_data/state, all through best-effort subscriptions
(a reliable publisher matches them and never waits for them); it reads no /clock."""
from __future__ import annotations

import io
import math
import time

import pytest
import rclpy
from geometry_msgs.msg import Vector3Stamped
from rclpy.qos import ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Float64MultiArray, MultiArrayDimension

from alignment_ros.progress import Progress
from alignment_ros.progress_watch import GraphWatcher, air_data_note
from alignment_ros.qos import STREAM
from alignment_ros.state_layout import parse


def test_air_data_note():
    st = parse([('value|sigma', 2), ('mach,alpha_rad,beta_rad', 3)], [0.8, 0.05, 0.0, 0.01, 0.002, 0.001])
    assert air_data_note(st) == 'Mach 0.800 \u00b1 0.010, alpha 2.86 \u00b1 0.11 deg'    # 0.05 rad = 2.865 deg
    assert air_data_note(parse([('value', 1), ('tas_mps', 1)], [100.0])) is None


def _state(sigma_rad: float) -> Float64MultiArray:
    labels = ('phi_E', 'phi_N', 'phi_U')
    m = Float64MultiArray(data=[5.0] * 3 + [0.0] * 3 + [1e-3] * 3 + [sigma_rad] * 3)
    m.layout.dim = [MultiArrayDimension(label='t_s|value|sigma|mu_sigma', size=4, stride=12),
                    MultiArrayDimension(label=','.join(labels), size=3, stride=3)]
    return m


def _watchers(node, topic: str) -> list:
    return [i.qos_profile.reliability for i in node.get_subscriptions_info_by_topic(topic)
            if i.node_name == 'progress_watch']


def test_watcher_feeds_the_progress(ros_context):
    node = rclpy.create_node('fake_graph', context=ros_context)
    clock = node.create_publisher(Clock, '/clock', STREAM)
    mis = node.create_publisher(Vector3Stamped, '/alignment/misalignment', STREAM)
    state = node.create_publisher(Float64MultiArray, '/alignment/state', STREAM)
    p = Progress('run_graph', 10.0, 1.0, stream=io.StringIO(), mode='plain', interval_s=0.0)
    w = GraphWatcher(p).start()
    try:
        deadline = time.monotonic() + 20
        while mis.get_subscription_count() < 1 or state.get_subscription_count() < 1 \
                or not _watchers(node, '/alignment/misalignment') or not _watchers(node, '/alignment/state'):
            assert time.monotonic() < deadline, 'the watcher did not subscribe'
            time.sleep(0.05)
        assert _watchers(node, '/alignment/misalignment') == [ReliabilityPolicy.BEST_EFFORT]
        assert _watchers(node, '/alignment/state') == [ReliabilityPolicy.BEST_EFFORT]
        # its subscriptions are made together: with these two discovered, a /clock one would be too
        assert _watchers(node, '/clock') == [] and clock.get_subscription_count() == 0
        arcmin = math.pi / 180 / 60
        deadline = time.monotonic() + 20
        while p.estimate is None or p.estimate[1] is None or p.sim_s != pytest.approx(5.0):
            assert time.monotonic() < deadline, (p.sim_s, p.estimate)
            state.publish(_state(0.5 * arcmin))
            m = Vector3Stamped()
            m.header.stamp.sec = 5
            m.vector.x, m.vector.y, m.vector.z = 15 * arcmin, -10 * arcmin, -30 * arcmin
            mis.publish(m)
            c = Clock()
            c.clock.sec = 6          # ahead of the estimate's stamp: not what the line shows
            clock.publish(c)
            time.sleep(0.1)
    finally:
        w.stop()
        node.destroy_node()
    mu, sig = p.estimate
    assert mu / arcmin == pytest.approx([15, -10, -30]) and sig / arcmin == pytest.approx([0.5] * 3)
    assert 'misalignment 15.00 -10.00 -30.00 \u00b1 0.50 0.50 0.50 arcmin' in p.line()


def test_quiet_starts_no_node():
    p = Progress('run_graph', 10.0, quiet=True)
    w = GraphWatcher(p).start()
    assert w._ctx is None
    w.stop()
