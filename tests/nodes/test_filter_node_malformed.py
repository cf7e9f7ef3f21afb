"""A message the filter node cannot read (bytes that are not a message of the topic's type, as a
damaged bag or a foreign publisher could send) is rejected, counted and reported in /diagnostics
at once (WARN 'malformed'), and the node goes on."""
from __future__ import annotations

import os
import signal

import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from nav_msgs.msg import Odometry
from rclpy.serialization import serialize_message
from support.ros_driving import spin_until

from alignment_ros import qos, topics


def test_a_malformed_message_is_reported_at_once_and_the_node_goes_on(ros):
    node, start = ros
    proc = start('alignment_filter_node', '-p', 'hold_until_matched:=["/diagnostics:1"]')
    pub = node.create_publisher(Odometry, topics.MASTER_ODOM, qos.STREAM)
    diag: list[DiagnosticArray] = []
    node.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, diag.append, qos.STREAM)
    spin_until(node, lambda: pub.get_subscription_count() >= 1, timeout=60.0)
    raw = serialize_message(Odometry(child_frame_id='ship'))
    pub.publish(raw[:-9])                          # cut short: no reader can take it
    spin_until(node, lambda: len(diag) >= 1, timeout=30.0)
    status = diag[-1].status[0]
    values = {kv.key: kv.value for kv in status.values}
    assert status.level == DiagnosticStatus.WARN
    assert values['flags'] == 'malformed' and values['rejected_malformed'] == '1'
    assert status.message.endswith('; 1 malformed messages rejected')
    pub.publish(raw[:1])                           # the same flag: /diagnostics waits for an output
    assert pub.wait_for_all_acked(rclpy.duration.Duration(seconds=10.0))
    assert proc.poll() is None                     # still running
    os.killpg(proc.pid, signal.SIGINT)
    out, _ = proc.communicate(timeout=30)
    assert proc.returncode == 0, out
    assert 'rejected a malformed message' in out
