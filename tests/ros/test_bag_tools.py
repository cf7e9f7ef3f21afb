"""Tests of the bag tools: echo formatting, bag writing/reading, recorder, player, echo CLI.

Run in a shell that sourced scripts/env.sh. Each test that touches DDS gets its own
ROS_DOMAIN_ID (also exported to the subprocesses it starts) so parallel runs do not interfere.
"""
from __future__ import annotations

import json
import logging
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from nav_msgs.msg import Odometry
from rclpy.context import Context
from rclpy.duration import Duration
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.serialization import deserialize_message, serialize_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu
from std_msgs.msg import Float64MultiArray

from alignment_ros.bag import BagError, BagReader, BagWriter, read_bag, topic_counts
from alignment_ros.echo_format import to_csv_header, to_csv_row, to_yaml
from alignment_ros.qos import STREAM

IMU = 'sensor_msgs/msg/Imu'
CLOCK = 'rosgraph_msgs/msg/Clock'
STATE = 'std_msgs/msg/Float64MultiArray'
NS = 1_000_000_000


# --- fixtures and helpers -------------------------------------------------------------------



def imu(i: int, frame: str = 'aircraft') -> Imu:
    """An Imu numbered i: stamp i ms (+1 s), distinctive values."""
    m = Imu()
    m.header.stamp.sec = 1 + i // 1000
    m.header.stamp.nanosec = (i % 1000) * 1_000_000
    m.header.frame_id = frame
    m.orientation_covariance[0] = -1.0
    m.angular_velocity.x = 1e-3 * i
    m.linear_acceleration.z = 9.8 + i
    return m


def stamp_ns(msg) -> int:
    return msg.header.stamp.sec * NS + msg.header.stamp.nanosec


def tool(name: str, *args: str, **kw) -> subprocess.Popen:
    """Start one of our executables (recorder, player, echo) as a subprocess."""
    return subprocess.Popen(
        [sys.executable, '-m', f'alignment_ros.{name}', *args],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=os.environ.copy(), **kw)


def wait_line(proc: subprocess.Popen, text: str, timeout: float = 10.0) -> None:
    """Read proc's stdout until a line equals ``text``."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if line.strip() == text:
            return
        if not line and proc.poll() is not None:
            break
    proc.kill()
    out, err = proc.communicate()
    pytest.fail(f'no {text!r} line from subprocess; stdout={out!r} stderr={err!r}')


def wait_matched(pub, n: int = 1, timeout: float = 10.0) -> None:
    deadline = time.monotonic() + timeout
    while pub.get_subscription_count() < n:
        assert time.monotonic() < deadline, 'subscriber not matched in time'
        time.sleep(0.02)


def make_bag(path: Path, n_imu: int = 300, n_clock: int = 100, n_state: int = 50) -> dict:
    """Write a small bag with three topics; return the messages written per topic."""
    msgs = {'/aircraft/imu': [imu(i) for i in range(n_imu)], '/clock': [], '/alignment/state': []}
    for i in range(n_clock):
        c = Clock()
        c.clock.sec, c.clock.nanosec = 1 + i // 100, (i % 100) * 10_000_000
        msgs['/clock'].append(c)
    for i in range(n_state):
        msgs['/alignment/state'].append(Float64MultiArray(data=[float(i), 0.5 * i, -1.0]))
    with BagWriter(path) as w:
        w.add_topic('/clock', CLOCK)
        w.add_topic('/aircraft/imu', IMU)
        w.add_topic('/alignment/state', STATE)
        for m in msgs['/clock']:
            w.write('/clock', serialize_message(m), m.clock.sec * NS + m.clock.nanosec)
        for m in msgs['/aircraft/imu']:
            w.write('/aircraft/imu', serialize_message(m), stamp_ns(m))
        for i, m in enumerate(msgs['/alignment/state']):
            w.write('/alignment/state', serialize_message(m), NS + i * 20_000_000)
    return msgs


# --- (a) echo formatting --------------------------------------------------------------------

ZEROS9 = '- 0.0\n' * 9

IMU_YAML = (
    'header:\n'
    '  stamp:\n'
    '    sec: 1\n'
    '    nanosec: 500\n'
    '  frame_id: aircraft\n'
    'orientation:\n'
    '  x: 0.0\n'
    '  y: 0.0\n'
    '  z: 0.0\n'
    '  w: 1.0\n'
    'orientation_covariance:\n'
    '- -1.0\n'
    '- 0.0\n'
    '- 0.0\n'
    '- 0.0\n'
    '- 0.0\n'
    '- 0.0\n'
    '- 0.0\n'
    '- 0.0\n'
    '- 0.0\n'
    'angular_velocity:\n'
    '  x: 0.001\n'
    '  y: -2.5e-05\n'
    '  z: 0.1\n'
    'angular_velocity_covariance:\n'
    + ZEROS9 +
    'linear_acceleration:\n'
    '  x: 0.0\n'
    '  y: -0.5\n'
    '  z: 9.80665\n'
    'linear_acceleration_covariance:\n'
    + ZEROS9
)


def test_echo_yaml_imu() -> None:
    m = Imu()
    m.header.stamp.sec, m.header.stamp.nanosec = 1, 500
    m.header.frame_id = 'aircraft'
    m.orientation_covariance[0] = -1.0
    m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z = 0.001, -2.5e-05, 0.1
    m.linear_acceleration.y, m.linear_acceleration.z = -0.5, 9.80665
    assert to_yaml(m) == IMU_YAML


def test_echo_yaml_odometry() -> None:
    m = Odometry()
    m.header.stamp.sec, m.header.stamp.nanosec = 12, 250000000
    m.header.frame_id = 'world'
    m.child_frame_id = ''
    m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z = 1e17, -0.1, 1.5e-07
    m.pose.covariance[0] = 0.25
    m.twist.twist.linear.x = 12.5
    m.twist.twist.angular.z = float('nan')
    m.twist.covariance[35] = float('inf')
    expected = (
        'header:\n'
        '  stamp:\n'
        '    sec: 12\n'
        '    nanosec: 250000000\n'
        '  frame_id: world\n'
        "child_frame_id: ''\n"
        'pose:\n'
        '  pose:\n'
        '    position:\n'
        '      x: 1.0e+17\n'
        '      y: -0.1\n'
        '      z: 1.5e-07\n'
        '    orientation:\n'
        '      x: 0.0\n'
        '      y: 0.0\n'
        '      z: 0.0\n'
        '      w: 1.0\n'
        '  covariance:\n'
        '  - 0.25\n'
        + '  - 0.0\n' * 35 +
        'twist:\n'
        '  twist:\n'
        '    linear:\n'
        '      x: 12.5\n'
        '      y: 0.0\n'
        '      z: 0.0\n'
        '    angular:\n'
        '      x: 0.0\n'
        '      y: 0.0\n'
        '      z: .nan\n'
        '  covariance:\n'
        + '  - 0.0\n' * 35 +
        '  - .inf\n'
    )
    assert to_yaml(m) == expected


def test_echo_yaml_strings_bytes_sequences_and_truncation() -> None:
    d = DiagnosticArray()
    d.header.frame_id = '1.5'
    d.status = [DiagnosticStatus(level=DiagnosticStatus.OK, name='filter', message='',
                                 values=[KeyValue(key='converged', value='yes')])]
    assert to_yaml(d) == (
        'header:\n'
        '  stamp:\n'
        '    sec: 0\n'
        '    nanosec: 0\n'
        "  frame_id: '1.5'\n"
        'status:\n'
        '- level: "\\0"\n'
        '  name: filter\n'
        "  message: ''\n"
        "  hardware_id: ''\n"
        '  values:\n'
        '  - key: converged\n'
        "    value: 'yes'\n"
    )
    f = Float64MultiArray(data=[0.0, 1.0, 2.0, 3.0])
    assert to_yaml(f, truncate_length=2) == (
        'layout:\n'
        '  dim: []\n'
        '  data_offset: 0\n'
        'data:\n'
        '- 0.0\n'
        '- 1.0\n'
        "- '...'\n"
    )


def test_echo_csv() -> None:
    m = Imu()
    m.header.stamp.sec, m.header.stamp.nanosec = 1, 500
    m.header.frame_id = 'aircraft'
    m.orientation_covariance[0] = -1.0
    m.linear_acceleration.z = 9.80665
    row = to_csv_row(m).split(',')
    head = to_csv_header(m).split(',')
    assert len(row) == len(head) == 3 + 4 + 9 + 3 + 9 + 3 + 9
    assert row[:8] == ['1', '500', 'aircraft', '0.0', '0.0', '0.0', '1.0', '-1.0']
    assert head[:8] == ['header.stamp.sec', 'header.stamp.nanosec', 'header.frame_id',
                        'orientation.x', 'orientation.y', 'orientation.z', 'orientation.w',
                        'orientation_covariance[0]']
    assert dict(zip(head, row))['linear_acceleration.z'] == '9.80665'
    f = Float64MultiArray(data=[1.5, 2.0])
    assert to_csv_row(f) == ',0,1.5,2.0'  # ros2 prints an empty cell for the empty layout.dim
    assert to_csv_header(f) == 'layout.dim,layout.data_offset,data[0],data[1]'


# --- (b) bag writing, read back independently -----------------------------------------------

def test_bag_writer_standard_layout(tmp_path: Path) -> None:
    bag = tmp_path / 'bag'
    msgs = make_bag(bag)
    meta = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['version'] == 9
    assert meta['storage_identifier'] == 'mcap'
    assert meta['message_count'] == 450
    topics = meta['topics_with_message_count']
    counts = {t['topic_metadata']['name']: t['message_count'] for t in topics}
    assert counts == {'/clock': 100, '/aircraft/imu': 300, '/alignment/state': 50}
    types = {t['topic_metadata']['name']: t['topic_metadata']['type'] for t in topics}
    assert types['/aircraft/imu'] == IMU
    hashes = [t['topic_metadata']['type_description_hash'] for t in topics]
    assert all(h.startswith('RIHS01_') for h in hashes)
    mcap_file = bag / meta['relative_file_paths'][0]

    # independent reader: mcap + mcap_ros2 decoder (not our code)
    seen: dict[str, list] = {t: [] for t in counts}
    with mcap_file.open('rb') as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        assert reader.get_header().profile == 'ros2'
        summary = reader.get_summary()
        assert {s.encoding for s in summary.schemas.values()} == {'ros2msg'}
        assert {c.message_encoding for c in summary.channels.values()} == {'cdr'}
        for _schema, channel, message, decoded in reader.iter_decoded_messages():
            seen[channel.topic].append((message.log_time, decoded))
    assert {t: len(v) for t, v in seen.items()} == counts
    for (log_time, dec), orig in zip(seen['/aircraft/imu'], msgs['/aircraft/imu']):
        assert log_time == stamp_ns(orig)
        assert dec.header.frame_id == 'aircraft'
        assert dec.header.stamp.nanosec == orig.header.stamp.nanosec
        assert dec.angular_velocity.x == orig.angular_velocity.x
        assert dec.linear_acceleration.z == orig.linear_acceleration.z
        assert list(dec.orientation_covariance) == list(orig.orientation_covariance)
    assert [list(d.data) for _, d in seen['/alignment/state']] == [
        list(m.data) for m in msgs['/alignment/state']]
    assert [d.clock.sec * NS + d.clock.nanosec for _, d in seen['/clock']] == [t for t, _ in seen['/clock']]

    # our reader: log-time order across topics (written topic by topic), same counts
    out = list(read_bag(bag))
    assert [m.t_ns for m in out] == sorted(m.t_ns for m in out)
    assert topic_counts(bag) == counts
    imus = [deserialize_message(m.data, Imu) for m in read_bag(bag, topics=['/aircraft/imu'])]
    assert [stamp_ns(m) for m in imus] == [stamp_ns(m) for m in msgs['/aircraft/imu']]
    assert {m.type_name for m in out if m.topic == '/clock'} == {CLOCK}


# --- (c) truncated bag, non-bag path --------------------------------------------------------

def test_truncated_bag_and_non_bag(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    bag = tmp_path / 'full'
    n = 8000  # about 3 MB: several 1 MiB chunks
    with BagWriter(bag) as w:
        w.add_topic('/aircraft/imu', IMU)
        for i in range(n):
            m = imu(i)
            w.write('/aircraft/imu', serialize_message(m), stamp_ns(m))
    cut = tmp_path / 'cut'
    cut.mkdir()
    src = next(bag.glob('*.mcap'))
    data = src.read_bytes()
    (cut / src.name).write_bytes(data[:int(0.6 * len(data))])  # no metadata.yaml, no footer

    with caplog.at_level(logging.WARNING, logger='alignment_ros.bag'):
        reader = BagReader(cut)
        got = list(reader.messages())
    assert reader.truncated
    assert 'truncated' in caplog.text and 'metadata.yaml' in caplog.text
    assert 0.5 * n < len(got) < 0.65 * n  # the file ends with its index: a bit over 60 %
    stamps = [stamp_ns(deserialize_message(m.data, Imu)) for m in got]
    assert stamps == [stamp_ns(imu(i)) for i in range(len(got))]  # exactly the prefix
    assert topic_counts(cut) == {'/aircraft/imu': len(got)}

    (tmp_path / 'empty').mkdir()
    (tmp_path / 'notes.txt').write_text('not a bag')
    (tmp_path / 'fake').mkdir()
    (tmp_path / 'fake' / 'fake.mcap').write_bytes(b'definitely not mcap')
    for bad in ('missing', 'empty', 'notes.txt', 'fake'):
        with pytest.raises(BagError):
            read_bag(tmp_path / bad)


# --- (d) recorder across processes ----------------------------------------------------------

def test_recorder_records_every_message(tmp_path: Path, ros_context: Context) -> None:
    n = 2000
    bag, stats = tmp_path / 'rec', tmp_path / 'stats.json'
    end_s = stamp_ns(imu(n - 1)) / NS
    rec = tool('recorder', '--out', str(bag), '--topics', '/aircraft/imu', '/clock',
               '--end-time', repr(end_s), '--idle-timeout', '5', '--stats', str(stats))
    try:
        wait_line(rec, 'recorder ready')
        node = Node('test_publisher', context=ros_context)
        pub = node.create_publisher(Imu, '/aircraft/imu', STREAM)
        wait_matched(pub)
        msgs = [imu(i) for i in range(n)]
        for m in msgs:
            pub.publish(m)
        assert pub.wait_for_all_acked(Duration(seconds=10))
        out, err = rec.communicate(timeout=10)
    finally:
        if rec.poll() is None:
            rec.kill()
            rec.communicate()
    assert rec.returncode == 0, err
    st = json.loads(stats.read_text())
    assert st['end_reason'] == 'end_time'
    assert st['topics'] == {'/aircraft/imu': n, '/clock': 0}
    assert 0.0 < st['cpu_s'] < 60.0        # the recorder's own CPU time, as a node's stats give it
    assert st['last_stamp_ns']['/aircraft/imu'] == stamp_ns(msgs[-1])
    assert (bag / 'metadata.yaml').is_file()
    assert topic_counts(bag) == {'/aircraft/imu': n, '/clock': 0}
    got = [m for m in read_bag(bag)]
    assert [m.t_ns for m in got] == [stamp_ns(m) for m in msgs]
    last = deserialize_message(got[-1].data, Imu)
    assert last.linear_acceleration.z == msgs[-1].linear_acceleration.z


def imu_bias(i: int) -> Imu:
    """A /truth/imu_bias message numbered i: stamp 1 s + 100 ms * i."""
    m = Imu()
    m.header.stamp.sec = 1 + i // 10
    m.header.stamp.nanosec = (i % 10) * 100_000_000
    m.header.frame_id = 'aircraft'
    m.angular_velocity.x = 1e-6 * i
    return m


def test_recorder_waits_for_expected_counts(tmp_path: Path, ros_context: Context) -> None:
    """With --expect-counts, end-time is not the end: a topic outside --wait-topics whose
    messages arrive long after every wait-topic reached end-time (much later than --drain, as a
    message the transport dropped and the reliable protocol resends at the next heartbeat) is
    still recorded in full; the recorder stops once every topic has its published count."""
    n, k = 200, 12
    bag, stats, expect = tmp_path / 'rec', tmp_path / 'stats.json', tmp_path / 'published.json'
    rec = tool('recorder', '--out', str(bag), '--topics', '/aircraft/imu', '/truth/imu_bias',
               '--end-time', repr(stamp_ns(imu(n - 1)) / NS), '--wait-topics', '/aircraft/imu',
               '--drain', '0.1', '--expect-counts', str(expect), '--expect-timeout', '30',
               '--stats', str(stats))
    try:
        wait_line(rec, 'recorder ready')
        node = Node('test_publisher', context=ros_context)
        pub_imu = node.create_publisher(Imu, '/aircraft/imu', STREAM)
        pub_bias = node.create_publisher(Imu, '/truth/imu_bias', STREAM)
        wait_matched(pub_imu)
        wait_matched(pub_bias)
        for i in range(n):
            pub_imu.publish(imu(i))
        wait_line(rec, 'recorder end-time reached')
        time.sleep(1.0)       # ten quiet periods (--drain): the drain rule would have stopped
        assert rec.poll() is None, 'the recorder stopped before it had the expected counts'
        for i in range(k):
            pub_bias.publish(imu_bias(i))
        assert pub_bias.wait_for_all_acked(Duration(seconds=10))
        expect.write_text(json.dumps({'/aircraft/imu': n, '/truth/imu_bias': k}))
        out, err = rec.communicate(timeout=20)
    finally:
        if rec.poll() is None:
            rec.kill()
            rec.communicate()
    assert rec.returncode == 0, err
    st = json.loads(stats.read_text())
    assert st['end_reason'] == 'end_time'
    assert st['missing'] == {}
    assert st['topics'] == {'/aircraft/imu': n, '/truth/imu_bias': k}
    assert topic_counts(bag) == {'/aircraft/imu': n, '/truth/imu_bias': k}
    got = [m.t_ns for m in read_bag(bag, ['/truth/imu_bias'])]
    assert got == [stamp_ns(imu_bias(i)) for i in range(k)]


def test_recorder_reports_a_shortfall(tmp_path: Path, ros_context: Context) -> None:
    """Expected counts that never arrive: the recorder gives up after --expect-timeout, says
    'incomplete' and names the shortfall (the launcher then reports the loss)."""
    n = 20
    bag, stats, expect = tmp_path / 'rec', tmp_path / 'stats.json', tmp_path / 'published.json'
    expect.write_text(json.dumps({'/aircraft/imu': n, '/truth/imu_bias': 3}))
    rec = tool('recorder', '--out', str(bag), '--topics', '/aircraft/imu', '/truth/imu_bias',
               '--end-time', repr(stamp_ns(imu(n - 1)) / NS), '--wait-topics', '/aircraft/imu',
               '--expect-counts', str(expect), '--expect-timeout', '1', '--stats', str(stats))
    try:
        wait_line(rec, 'recorder ready')
        node = Node('test_publisher', context=ros_context)
        pub_imu = node.create_publisher(Imu, '/aircraft/imu', STREAM)
        pub_bias = node.create_publisher(Imu, '/truth/imu_bias', STREAM)
        wait_matched(pub_imu)
        wait_matched(pub_bias)
        pub_bias.publish(imu_bias(0))
        for i in range(n):
            pub_imu.publish(imu(i))
        out, err = rec.communicate(timeout=20)
    finally:
        if rec.poll() is None:
            rec.kill()
            rec.communicate()
    assert rec.returncode == 0, err
    st = json.loads(stats.read_text())
    assert st['end_reason'] == 'incomplete'
    assert st['missing'] == {'/truth/imu_bias': 2}
    assert st['topics'] == {'/aircraft/imu': n, '/truth/imu_bias': 1}


def test_recorder_takes_what_the_executor_did_not_dispatch(tmp_path: Path,
                                                             ros_context: Context) -> None:
    """take_pending() records messages already in the reader although no executor ran (the
    recorder's safety net when a topic is short of its expected count)."""
    from alignment_ros.recorder import Recorder
    n = 50
    rec_node = Node('recorder_under_test', context=ros_context)
    writer = BagWriter(tmp_path / 'bag')
    rec = Recorder(rec_node, writer, {'/aircraft/imu': IMU}, None, [])
    node = Node('test_publisher', context=ros_context)
    pub = node.create_publisher(Imu, '/aircraft/imu', STREAM)
    wait_matched(pub)
    for i in range(n):
        pub.publish(imu(i))
    assert pub.wait_for_all_acked(Duration(seconds=10))
    assert rec.counts['/aircraft/imu'] == 0
    assert rec.missing({'/aircraft/imu': n}) == {'/aircraft/imu': n}
    assert rec.take_pending(['/aircraft/imu']) == n
    assert rec.missing({'/aircraft/imu': n}) == {}
    assert rec.take_pending(['/aircraft/imu']) == 0
    writer.close()
    assert [m.t_ns for m in read_bag(tmp_path / 'bag')] == [stamp_ns(imu(i)) for i in range(n)]


# --- (e) player -----------------------------------------------------------------------------

def test_player_publishes_every_message(tmp_path: Path, ros_context: Context) -> None:
    bag, stats = tmp_path / 'bag', tmp_path / 'play.json'
    msgs = make_bag(bag)
    node = Node('test_subscriber', context=ros_context)
    got: dict[str, list] = {t: [] for t in msgs}
    for topic, cls in (('/aircraft/imu', Imu), ('/clock', Clock), ('/alignment/state', Float64MultiArray)):
        node.create_subscription(cls, topic, got[topic].append, STREAM)
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(node)
    play = tool('player', str(bag), '-r', '0', '--lossless', '--wait-subscribers', '/aircraft/imu=1', '/clock=1',
                '/alignment/state=1', '--wait-timeout', '10', '--stats', str(stats))
    deadline = time.monotonic() + 15
    try:
        while time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
            if play.poll() is not None and all(len(got[t]) >= len(msgs[t]) for t in msgs):
                break
        for _ in range(10):  # anything still in flight
            executor.spin_once(timeout_sec=0.02)
        out, err = play.communicate(timeout=5)
    finally:
        if play.poll() is None:
            play.kill()
            play.communicate()
        executor.shutdown()
    assert play.returncode == 0, err
    assert {t: len(v) for t, v in got.items()} == {t: len(v) for t, v in msgs.items()}
    st = json.loads(stats.read_text())
    assert st['topics'] == {t: len(v) for t, v in msgs.items()}
    assert st['truncated'] is False and st['acked'] is True
    assert [stamp_ns(m) for m in got['/aircraft/imu']] == [stamp_ns(m) for m in msgs['/aircraft/imu']]
    assert [list(m.data) for m in got['/alignment/state']] == [list(m.data) for m in msgs['/alignment/state']]
    assert 'published 450 messages' in out


def test_player_truncated_bag_and_errors(tmp_path: Path, domain_id: int) -> None:
    bag = tmp_path / 'bag'
    make_bag(bag, n_imu=6000, n_clock=0, n_state=0)
    cut = tmp_path / 'cut'
    cut.mkdir()
    src = next(bag.glob('*.mcap'))
    data = src.read_bytes()
    (cut / src.name).write_bytes(data[:int(0.6 * len(data))])
    stats = tmp_path / 'p.json'
    res = subprocess.run([sys.executable, '-m', 'alignment_ros.player', str(cut), '-r', '0', '--stats', str(stats)],
                         capture_output=True, text=True, timeout=15)
    assert res.returncode == 0, res.stderr
    st = json.loads(stats.read_text())
    assert st['truncated'] is True
    assert 0 < st['topics']['/aircraft/imu'] < 6000
    assert 'truncated' in res.stderr
    res = subprocess.run([sys.executable, '-m', 'alignment_ros.player', str(bag),
                          '--wait-subscribers', '/aircraft/imu=1', '--wait-timeout', '0.5'],
                         capture_output=True, text=True, timeout=15)
    assert res.returncode == 1 and 'waiting for subscribers' in res.stderr
    res = subprocess.run([sys.executable, '-m', 'alignment_ros.player', str(tmp_path)],
                         capture_output=True, text=True, timeout=15)
    assert res.returncode == 1 and 'not a rosbag2' in res.stderr


# --- (f) echo CLI ---------------------------------------------------------------------------

def test_echo_once_prints_yaml_doc(ros_context: Context) -> None:
    node = Node('test_talker', context=ros_context)
    pub = node.create_publisher(Imu, '/aircraft/imu', STREAM)
    echo = tool('echo', '/aircraft/imu', '--once', '--timeout', '10')
    try:
        deadline = time.monotonic() + 12
        i = 0
        while echo.poll() is None and time.monotonic() < deadline:
            if pub.get_subscription_count() > 0:
                pub.publish(imu(i))
                i += 1
            time.sleep(0.05)
        out, err = echo.communicate(timeout=5)
    finally:
        if echo.poll() is None:
            echo.kill()
            echo.communicate()
    assert echo.returncode == 0, err
    assert out.endswith('---\n') and out.count('---\n') == 1
    doc = out[:-len('---\n')]
    assert doc.startswith('header:\n  stamp:\n    sec: 1\n')
    first = yaml.safe_load(doc)
    assert first['header']['frame_id'] == 'aircraft'
    assert first['orientation_covariance'][0] == -1.0
    assert doc == to_yaml(imu(first['header']['stamp']['nanosec'] // 1_000_000))


def test_echo_timeout_without_messages(domain_id: int) -> None:
    res = subprocess.run([sys.executable, '-m', 'alignment_ros.echo', '/aircraft/imu', '--timeout', '0.5'],
                         capture_output=True, text=True, timeout=15)
    assert res.returncode == 0             # ros2 topic echo: a timeout with nothing received is not an error
    assert res.stdout == '' and res.stderr == ''
