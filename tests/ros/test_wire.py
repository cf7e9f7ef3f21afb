"""alignment_ros/wire.py and CountingNode.stream_subscription: a stream message read from its bytes
has every field rclpy's own conversion gives (each field set to a value of its own), and bytes
that are not a message of the type are rejected, counted and reported, never handed on."""
from __future__ import annotations

import numpy as np
import pytest
from geometry_msgs.msg import AccelStamped, TwistWithCovarianceStamped
from nav_msgs.msg import Odometry
from rclpy.impl.implementation_singleton import rclpy_implementation
from rclpy.serialization import deserialize_message, serialize_message
from rosbags.serde import SerdeError
from sensor_msgs.msg import FluidPressure, Imu
from support.ros_driving import spin_until

from alignment_ros import node_util, wire

RMWError = rclpy_implementation.RMWError
STREAM_TYPES = (Odometry, Imu, AccelStamped, TwistWithCovarianceStamped, FluidPressure)
"""Every type a node of the project takes as a stream."""


def _fill(msg, counter: list[float]) -> None:
    """Give every numeric field of msg a value of its own (strings a text of their own)."""
    for name, kind in msg.get_fields_and_field_types().items():
        value = getattr(msg, name)
        if hasattr(value, 'get_fields_and_field_types'):
            _fill(value, counter)
        elif kind == 'string':
            setattr(msg, name, f'frame_{len(counter)}')
            counter.append(0.0)
        elif kind.startswith('double['):
            n = len(value)
            setattr(msg, name, np.arange(n, dtype=float) * 0.1 + len(counter) + 0.5)
            counter.extend([0.0] * n)
        elif kind in ('double', 'float'):
            setattr(msg, name, len(counter) + 0.25)
            counter.append(0.0)
        else:                                           # integers (the stamp)
            setattr(msg, name, len(counter) + 7)
            counter.append(0.0)


def _fields(msg, prefix: str = '') -> dict:
    """{dotted field name: value} of an rclpy message, walking into nested messages."""
    out = {}
    for name in msg.get_fields_and_field_types():
        value = getattr(msg, name)
        if hasattr(value, 'get_fields_and_field_types'):
            out.update(_fields(value, f'{prefix}{name}.'))
        else:
            out[prefix + name] = value
    return out


def _read_field(msg, dotted: str):
    for part in dotted.split('.'):
        msg = getattr(msg, part)
    return msg


@pytest.mark.parametrize('msg_type', STREAM_TYPES, ids=lambda t: t.__name__)
def test_a_message_read_from_its_bytes_has_every_field_rclpy_gives(msg_type):
    msg = msg_type()
    _fill(msg, [])
    raw = serialize_message(msg)
    expected = _fields(deserialize_message(raw, msg_type))
    got = wire.reader(msg_type)(raw)
    assert len(expected) > 3
    for name, value in expected.items():
        mine = _read_field(got, name)
        if isinstance(value, (str, int, float)):
            assert mine == value and type(mine) is type(value), name
        else:
            assert np.array_equal(np.asarray(mine), np.asarray(value)), name
            assert np.asarray(mine).dtype == np.asarray(value).dtype, name


@pytest.mark.parametrize('damage', ['truncated', 'one_byte', 'string_length', 'empty'])
def test_bytes_that_are_not_a_message_of_the_type_are_malformed(damage):
    """Bytes rclpy cannot read either (a typed subscription dropped them unseen)."""
    raw = serialize_message(Odometry(child_frame_id='aircraft'))
    # after the 4-byte encapsulation header: the stamp (8 bytes), then frame_id's length at byte 12
    bad = {'truncated': raw[:-9], 'one_byte': raw[:1],
           'string_length': raw[:12] + b'\xff\xff\xff\x7f' + raw[16:], 'empty': b''}[damage]
    with pytest.raises(RMWError):
        deserialize_message(bad, Odometry)
    with pytest.raises(wire.MalformedMessageError, match='are not a nav_msgs/msg/Odometry'):
        wire.reader(Odometry)(bad)


@pytest.mark.parametrize('damage', ['extra_bytes', 'not_utf8'])
def test_bytes_rosbags_refuses_but_rclpy_reads_are_read_as_rclpy_reads_them(damage):
    """rosbags refuses more than 3 bytes after the message and a string that is not UTF-8; a
    typed subscription took them (the string with U+FFFD), so the reader does too."""
    msg = Odometry(child_frame_id='aircraft')
    msg.header.frame_id = 'abc'
    msg.pose.pose.position.x = 4.5
    raw = serialize_message(msg)
    bad = {'extra_bytes': raw + bytes(8), 'not_utf8': raw[:16] + b'\xff' + raw[17:]}[damage]
    with pytest.raises((SerdeError, UnicodeDecodeError)):
        wire.TYPESTORE.deserialize_cdr(bad, 'nav_msgs/msg/Odometry')
    got = wire.reader(Odometry)(bad)
    expected = deserialize_message(bad, Odometry)
    assert got.header.frame_id == expected.header.frame_id == ('abc' if damage == 'extra_bytes' else '\ufffdbc')
    assert (got.child_frame_id, got.pose.pose.position.x) == ('aircraft', 4.5)


def test_a_type_rosbags_does_not_know_is_refused_at_subscription():
    class Unknown:
        __module__ = 'no_such_msgs.msg._unknown'
    with pytest.raises(KeyError, match='no_such_msgs/msg/Unknown'):
        wire.reader(Unknown)


def test_a_stream_subscription_hands_on_messages_and_counts_the_malformed(ros):
    driver, _ = ros
    topic = '/wire_test/odom'
    node = node_util.CountingNode('wire_test_reader')
    got, malformed = [], []
    node.stream_subscription(Odometry, topic, got.append, malformed.append)
    pub = driver.create_publisher(Odometry, topic, 10)
    spin_until(node, lambda: pub.get_subscription_count() >= 1)
    good = Odometry(child_frame_id='aircraft')
    good.pose.pose.position.x = 12.5
    raw = serialize_message(good)
    pub.publish(raw)
    pub.publish(raw[:-9])                      # published as bytes: the transport does not check them
    pub.publish(raw)
    spin_until(node, lambda: len(got) + len(malformed) >= 3)
    assert [m.pose.pose.position.x for m in got] == [12.5, 12.5]
    assert [m.child_frame_id for m in got] == ['aircraft', 'aircraft']
    assert malformed == [topic]
    assert node.rejected == {f'malformed {topic}': 1}
    node.destroy_node()


def test_the_launcher_reports_each_nodes_malformed_inputs(tmp_path):
    """graph.py makes a run with any of them incomplete (a problem in summary.json)."""
    import json

    from alignment_ros.launch import malformed_inputs
    (tmp_path / 'stats').mkdir()
    (tmp_path / 'stats' / 'ldv_node.json').write_text(json.dumps(
        {'rejected': {'malformed /ship/odom': 2, 'malformed /truth/aircraft/odom': 1, 'unpaired_dropped': 5}}))
    (tmp_path / 'stats' / 'master_ins_node.json').write_text(json.dumps({'rejected': {'out_of_order': 3}}))
    assert malformed_inputs(tmp_path) == {'ldv_node': 3}
