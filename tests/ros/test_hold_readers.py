"""What a node waits for before it sends (hold_until_matched, the ship's wait_subscribers):
'topic:count' or 'topic:node+node...'. A count can be met by a subscriber nobody waits for
(echo.sh, a second recorder) while a node that is waited for is still being discovered: a graph
run under load lost the master's first 3.4 s that way. Named nodes cannot be stood in for."""
from __future__ import annotations

import pytest
import rclpy
from std_msgs.msg import UInt64
from support.ros_driving import spin_until

from alignment_core.validation import ConfigError
from alignment_ros import node_util, qos

TOPIC = '/hold_readers/test'


def test_items_parse_to_a_count_and_the_nodes_named():
    got = node_util.parse_readers(['/a:2', '/b:recorder+ldv_node', '', '/ns/c:recorder'])
    assert got == {'/a': (2, ()), '/b': (2, ('recorder', 'ldv_node')), '/ns/c': (1, ('recorder',))}
    for bad in ('/a', '/a:', ':3'):
        with pytest.raises(ConfigError, match='topic:count'):
            node_util.parse_readers([bad])


def test_an_extra_subscriber_meets_a_count_but_not_a_named_node(ros):
    driver, _ = ros
    pub = driver.create_publisher(UInt64, TOPIC, qos.STREAM)
    extra = rclpy.create_node('extra_subscriber', context=driver.context)
    extra.create_subscription(UInt64, TOPIC, lambda m: None, qos.STREAM)
    try:
        spin_until(driver, lambda: pub.get_subscription_count() >= 1
                   and len(driver.get_subscriptions_info_by_topic(TOPIC)) >= 1)
        n = pub.get_subscription_count()
        assert node_util.readers_matched(driver, TOPIC, n, 1, ())                    # the count is met
        assert not node_util.readers_matched(driver, TOPIC, n, 1, ('waited_node',))  # the node is not there
        waited = rclpy.create_node('waited_node', context=driver.context)
        waited.create_subscription(UInt64, TOPIC, lambda m: None, qos.STREAM)
        try:
            spin_until(driver, lambda: node_util.readers_matched(
                driver, TOPIC, pub.get_subscription_count(), 1, ('waited_node',)))
            assert pub.get_subscription_count() == 2
        finally:
            waited.destroy_node()
    finally:
        extra.destroy_node()
