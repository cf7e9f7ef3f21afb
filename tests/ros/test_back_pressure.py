"""Back-pressure: a STREAM publisher (RELIABLE, KEEP_ALL) far ahead of a slow subscriber waits
for it (CountingNode.send) instead of failing, and the subscriber gets every message in order.

Why it is exercised: Fast DDS holds at most resource_limits.max_samples = 5000 unacknowledged
messages in the writer's KEEP_ALL history and 5000 in the reader's. The subscriber sleeps 3 s in
its first callback, longer than the writers' max_blocking_time (1 s, config/dds/fastdds.xml;
100 ms without it), so with 12000 messages the publisher's write is refused at least once
(rmw: "cannot publish data"; before send waited for it, the node died of it).
"""
from __future__ import annotations

import json
import os
import subprocess
import sys

from std_msgs.msg import UInt64
from support.ros_driving import spin_until

from alignment_ros import node_util, qos

TOPIC = '/back_pressure/test'
N = 12000          # > 5000 (writer history) + 5000 (reader history): the writer has to wait
STALL_S = 3.0      # > max_blocking_time: at least one write is refused

SLOW_SUBSCRIBER = f'''
import json, sys, time
import rclpy
from std_msgs.msg import UInt64
from alignment_ros import qos
rclpy.init()
node = rclpy.create_node('slow_subscriber')
got = []
def on_msg(m):
    got.append(m.data)
    if len(got) == 1:
        time.sleep({STALL_S})
node.create_subscription(UInt64, {TOPIC!r}, on_msg, qos.STREAM)
print('ready', flush=True)
deadline = time.monotonic() + 120.0
while len(got) < {N} and time.monotonic() < deadline:
    rclpy.spin_once(node, timeout_sec=0.1)
print(json.dumps({{'n': len(got), 'in_order': got == list(range(len(got)))}}), flush=True)
'''


def test_publisher_waits_for_a_slow_subscriber_and_loses_nothing(ros):
    driver, _ = ros
    dom = driver.context.get_domain_id()
    sub = subprocess.Popen([sys.executable, '-c', SLOW_SUBSCRIBER], stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True,
                           env=dict(os.environ, ROS_DOMAIN_ID=str(dom)))
    try:
        assert sub.stdout.readline().strip() == 'ready'
        node = node_util.CountingNode('fast_publisher')
        pub = node.stream_publisher(UInt64, TOPIC)
        assert pub.qos_profile == qos.STREAM
        spin_until(node, lambda: pub.get_subscription_count() >= 1)
        for i in range(N):
            node.send(TOPIC, UInt64(data=i))            # an RCLError here fails the test
        assert node.published[TOPIC] == N
        assert node.publish_waits[TOPIC] >= 1, 'the subscriber never held the writer back'
        assert node.wait_acked(60.0)
        out, _ = sub.communicate(timeout=120)
        result = json.loads(out.strip().splitlines()[-1])
        assert result == {'n': N, 'in_order': True}
        assert node.stats()['publish_waits'] == {TOPIC: node.publish_waits[TOPIC]}
        node.destroy_node()
    finally:
        if sub.poll() is None:
            sub.kill()
            sub.wait()
