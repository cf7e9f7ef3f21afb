"""``echo`` (scripts/echo.sh) against ``ros2 topic echo``'s (Jazzy) semantics: arguments and
their refusals, exit status, what each formatting option prints, and the subscription QoS.

Expected texts are written out by hand from rosidl_runtime_py's rules (field order, PyYAML
quoting, ``<sequence type: ...>`` abbreviations), not produced by the project's formatter.
Several echo processes run at once against one publisher to keep the tests short.
"""
from __future__ import annotations

import ast
import os
import signal
import subprocess
import sys
import time

import pytest
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import Imu, JointState

WAIT = ('--spin-time', '10', '--timeout', '20')   # find the test's publisher; never hang
RELIABLE_10 = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)


def echo(*args: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, '-m', 'alignment_ros.echo', *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=os.environ.copy())


def finish(proc: subprocess.Popen, timeout: float = 20.0) -> tuple[int, str, str]:
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, err = proc.communicate()
    return proc.returncode, out, err


def joints() -> JointState:
    m = JointState(name=['left', 'right'], position=[0.5, -1.0])
    m.header.stamp.sec, m.header.stamp.nanosec = 3, 5
    m.header.frame_id = 'base'
    return m


def counted_imu(i: int) -> Imu:
    m = Imu()
    m.header.stamp.sec = i
    m.header.frame_id = 'probe'
    m.angular_velocity.x, m.angular_velocity.z = 0.5, -1.0
    return m


# --- without a publisher ----------------------------------------------------------------------

def test_negative_truncate_length_is_refused(domain_id: int) -> None:
    rc, out, err = finish(echo('/aircraft/imu', '-l', '-1'))
    assert rc == 2 and out == ''
    assert 'argument --truncate-length/-l: value must be non-negative integer' in err


def test_unknown_topic_fails_at_once(domain_id: int) -> None:
    """No TYPE, not in the graph: ros2 looks once after --spin-time (0.5 s) and fails."""
    t0 = time.monotonic()
    rc, out, err = finish(echo('/no/such/topic'))
    elapsed = time.monotonic() - t0
    assert rc == 1
    assert out == 'WARNING: topic [/no/such/topic] does not appear to be published yet\n'
    assert err.strip() == 'Could not determine the type for the passed topic'
    assert elapsed < 4.0   # interpreter start + 0.5 s; the old echo waited 5 s before failing


def test_timeout_type_and_signal_exit_status(domain_id: int) -> None:
    """--timeout with nothing received: status 0, nothing printed (ros2 returns normally);
    a TYPE needs no publisher; an invalid TYPE: status 1; SIGINT: status 15 (SIGTERM's
    number: rclpy's signal handler shuts the context down and ros2cli reports that)."""
    quiet = echo('/aircraft/imu', '--timeout', '0.5')
    typed = echo('/no/such/topic', 'std_msgs/msg/String', '--timeout', '0.5')
    short = echo('/no/such/topic', 'std_msgs/String', '--timeout', '0.5')
    invalid = echo('/no/such/topic', 'no_pkg/msg/Nothing')
    waiting = echo('/aircraft/imu')
    assert finish(quiet) == (0, '', '')
    assert finish(typed) == (0, '', '')
    assert finish(short) == (0, '', '')
    rc, out, err = finish(invalid)
    assert rc == 1 and err.strip() == 'The passed message type is invalid'
    time.sleep(0.5)
    assert waiting.poll() is None, 'echo without --timeout/--once must keep waiting'
    waiting.send_signal(signal.SIGINT)
    rc, out, err = finish(waiting)
    assert rc == 15 and out == ''


# --- against a live publisher -----------------------------------------------------------------

def _publish_until_done(ctx: Context, procs: list[subprocess.Popen], timeout: float = 30.0) -> None:
    """Publish joints() on /joints and a counted Imu on /probe/imu every 20 ms until every
    process has exited."""
    node = Node('test_talker', context=ctx)
    pub_j = node.create_publisher(JointState, '/joints', RELIABLE_10)
    pub_i = node.create_publisher(Imu, '/probe/imu', RELIABLE_10)
    deadline = time.monotonic() + timeout
    i = 0
    while any(p.poll() is None for p in procs) and time.monotonic() < deadline:
        pub_j.publish(joints())
        pub_i.publish(counted_imu(i))
        i += 1
        time.sleep(0.02)
    node.destroy_node()


JOINTS_HEADER = 'header:\n  stamp:\n    sec: 3\n    nanosec: 5\n'


def test_format_field_and_filter_options(ros_context: Context) -> None:
    cases = {
        'no_arr': echo('/joints', '--once', '--no-arr', *WAIT),
        'no_str': echo('/joints', 'sensor_msgs/msg/JointState', '--once', '--no-str', *WAIT),
        'csv_no_arr': echo('/joints', '--once', '--csv', '--no-arr', *WAIT),
        'flow': echo('/joints', '--once', '--flow-style', *WAIT),
        'truncate': echo('/joints', '--once', '-l', '1', *WAIT),
        'raw': echo('/joints', '--once', '--raw', *WAIT),
        'field': echo('/probe/imu', '--once', '--field', 'angular_velocity', *WAIT),
        'filter': echo('/probe/imu', '--once', '--field', 'header.stamp.sec',
                       '--filter', 'm % 5 == 3', *WAIT),
    }
    _publish_until_done(ros_context, list(cases.values()))
    res = {k: finish(p) for k, p in cases.items()}
    for k, (rc, _out, err) in res.items():
        assert rc == 0, (k, err)
    out = {k: v[1] for k, v in res.items()}
    assert out['no_arr'] == (
        JOINTS_HEADER + '  frame_id: base\n'
        "name: '<sequence type: string, length: 2>'\n"
        "position: '<sequence type: double, length: 2>'\n"
        "velocity: '<sequence type: double, length: 0>'\n"
        "effort: '<sequence type: double, length: 0>'\n---\n")
    assert out['no_str'] == (
        JOINTS_HEADER + "  frame_id: '<string length: <4>>'\n"
        "name:\n- '<string length: <4>>'\n- '<string length: <5>>'\n"
        'position:\n- 0.5\n- -1.0\nvelocity: []\neffort: []\n---\n')
    assert out['csv_no_arr'] == (
        '3,5,base,<sequence type: string, length: 2>,<sequence type: double, length: 2>,'
        '<sequence type: double, length: 0>,<sequence type: double, length: 0>\n')
    # rosidl's mapping representer builds block mappings whatever the style: only the
    # sequences turn to flow style
    assert out['flow'] == (
        JOINTS_HEADER + '  frame_id: base\n'
        'name: [left, right]\nposition: [0.5, -1.0]\nvelocity: []\neffort: []\n---\n')
    # each sequence cut to one element, and each string in it to one character
    assert out['truncate'] == (
        JOINTS_HEADER + '  frame_id: b...\n'
        "name:\n- l...\n- '...'\nposition:\n- 0.5\n- '...'\nvelocity: []\neffort: []\n---\n")
    # the serialized bytes as Python prints them (padding bytes are not defined and the
    # serializer's buffer may be longer: compare what they decode to)
    assert out['raw'].startswith("b'") and out['raw'].endswith("'\n---\n")
    raw = ast.literal_eval(out['raw'][:-len('\n---\n')])
    back = deserialize_message(raw, JointState)
    assert (back.header.frame_id, list(back.name), list(back.position)) == (
        'base', ['left', 'right'], [0.5, -1.0])
    assert out['field'] == 'x: 0.5\ny: 0.0\nz: -1.0\n---\n'
    # the filter sees the selected field (an int), as in ros2
    n = int(out['filter'].split('\n')[0])
    assert out['filter'] == f'{n}\n---\n' and n % 5 == 3


def test_invalid_field_fails_with_status_1(ros_context: Context) -> None:
    bad = echo('/probe/imu', '--once', '--field', 'header.nothing', *WAIT)
    _publish_until_done(ros_context, [bad])
    rc, out, err = finish(bad)
    assert rc == 1 and out == ''
    assert err.startswith("Invalid field 'header.nothing':")


def _subscription_qos(node: Node, topic: str, timeout: float = 15.0) -> QoSProfile:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        infos = node.get_subscriptions_info_by_topic(topic)
        if infos:
            return infos[0].qos_profile
        time.sleep(0.05)
    pytest.fail(f'no subscription on {topic}')


def test_qos_adapts_to_publishers_unless_set(ros_context: Context) -> None:
    """Default: sensor_data (BEST_EFFORT, VOLATILE) made RELIABLE / TRANSIENT_LOCAL when every
    publisher offers it, so a latched message is received; --qos-* options set the profile
    without adaptation: --qos-durability volatile misses the latched message."""
    node = Node('test_qos_talker', context=ros_context)
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
    node.create_publisher(JointState, '/latched', latched).publish(joints())
    node.create_publisher(JointState, '/reliable', RELIABLE_10)
    node.create_publisher(JointState, '/forced', RELIABLE_10)
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(node)
    got_latched = echo('/latched', '--once', '--field', 'name', *WAIT)
    volatile = echo('/latched', '--once', '--qos-durability', 'volatile',
                    '--spin-time', '10', '--timeout', '3')
    adapted = echo('/reliable', '--spin-time', '10', '--timeout', '4')
    forced = echo('/forced', '--qos-reliability', 'best_effort', '--spin-time', '10',
                  '--timeout', '4')
    assert _subscription_qos(node, '/reliable').reliability == ReliabilityPolicy.RELIABLE
    assert _subscription_qos(node, '/forced').reliability == ReliabilityPolicy.BEST_EFFORT
    assert finish(got_latched) == (0, "['left', 'right']\n---\n", '')
    assert finish(volatile) == (0, '', '')
    assert finish(adapted)[0] == 0 and finish(forced)[0] == 0
    executor.shutdown()
    node.destroy_node()
