"""scripts/record.sh against live publishers: ros2 bag record's topic selection (-a, positional
topics, -e, -x, --exclude-topics, hidden topics), types from the graph, --max-bag-duration
splitting, SIGINT finalising, a killed recording still readable, and the option errors.

Five recorders run at once on one set of publishers (module fixture); each test checks one.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import rclpy
import yaml
from rclpy.context import Context
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import Imu, Temperature
from std_msgs.msg import String

from alignment_ros.bag import BagReader

ROOT = Path(__file__).resolve().parents[2]
N = 40                      # messages per topic, stamped 1.0 s + 0.1 s * i
RELIABLE = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
RECORDERS = {               # name -> record.sh arguments
    'all': ['-a'],
    'positional': ['/cli/chatter', '/sensors/temp', '--quiet'],
    'regex': ['-e', '^/sensors/'],
    'exclude': ['-a', '-x', 'imu', '--exclude-topics', '/cli/chatter'],
    'split': ['--topics', '/sensors/temp', '-d', '1'],
    'killed': ['--topics', '/sensors/temp'],
}
# topic -> recorders that must subscribe to it
SUBSCRIBERS = {'/cli/chatter': 2, '/cli/imu': 1, '/sensors/temp': 6, '/_hidden/thing': 0}


def stamp(i: int) -> tuple[int, int]:
    return 1 + i // 10, (i % 10) * 100_000_000


def wait_count(pub, n: int, timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    while pub.get_subscription_count() < n:
        assert time.monotonic() < deadline, f'{pub.topic_name}: {pub.get_subscription_count()} < {n}'
        time.sleep(0.05)


@pytest.fixture(scope='module')
def recorded(tmp_path_factory) -> dict[str, Path]:
    from alignment_ros import domain
    dom = domain.claim()
    env = dict(os.environ, ROS_DOMAIN_ID=str(dom), ROS_AUTOMATIC_DISCOVERY_RANGE='SYSTEM_DEFAULT')
    out = tmp_path_factory.mktemp('record')
    ctx = Context()
    rclpy.init(context=ctx, domain_id=dom)
    procs: dict[str, subprocess.Popen] = {}
    try:
        node = Node('cli_talker', context=ctx)
        pubs = {
            '/cli/chatter': node.create_publisher(String, '/cli/chatter', RELIABLE),
            '/cli/imu': node.create_publisher(Imu, '/cli/imu', qos_profile_sensor_data),
            '/sensors/temp': node.create_publisher(Temperature, '/sensors/temp', RELIABLE),
            '/_hidden/thing': node.create_publisher(String, '/_hidden/thing', RELIABLE),
        }
        for name, extra in RECORDERS.items():
            procs[name] = subprocess.Popen(
                [str(ROOT / 'scripts/record.sh'), *extra, '-o', str(out / name),
                 '--node-name', f'rec_{name}'],
                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
        for topic, n in SUBSCRIBERS.items():
            wait_count(pubs[topic], n)
        time.sleep(1.0)  # ten polling intervals: a recorder that would wrongly subscribe has
        for topic, n in SUBSCRIBERS.items():
            assert pubs[topic].get_subscription_count() == n, topic
        for i in range(N):
            sec, nsec = stamp(i)
            imu = Imu()
            imu.header.stamp.sec, imu.header.stamp.nanosec = sec, nsec
            temp = Temperature(temperature=20.0 + i)
            temp.header.stamp.sec, temp.header.stamp.nanosec = sec, nsec
            pubs['/cli/chatter'].publish(String(data=f'hello {i}'))
            pubs['/cli/imu'].publish(imu)
            pubs['/sensors/temp'].publish(temp)
            pubs['/_hidden/thing'].publish(String(data='hidden'))
            time.sleep(0.005)
        for topic in ('/cli/chatter', '/sensors/temp'):
            assert pubs[topic].wait_for_all_acked(Duration(seconds=10))
        time.sleep(1.5)  # the best-effort imu in flight; the spool flushed (FLUSH_INTERVAL_S)
        procs['killed'].kill()
        for name, p in procs.items():
            if name != 'killed':
                p.send_signal(signal.SIGINT)
        for name, p in procs.items():
            _, err = p.communicate(timeout=60)
            assert name == 'killed' or p.returncode == 0, f'{name}: {err}'
            (out / f'{name}.stderr').write_text(err)
    finally:
        for p in procs.values():
            if p.poll() is None:
                p.kill()
                p.communicate()
        rclpy.try_shutdown(context=ctx)
        domain.release(dom)
    return {name: out / name for name in RECORDERS}


def meta_topics(bag: Path) -> dict[str, dict]:
    info = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    return {t['topic_metadata']['name']: t for t in info['topics_with_message_count']}


def test_all_records_every_visible_topic_with_graph_types(recorded):
    topics = meta_topics(recorded['all'])
    assert {'/cli/chatter', '/cli/imu', '/sensors/temp'} <= set(topics)
    assert '/_hidden/thing' not in topics
    assert {'/rosout', '/parameter_events'} <= set(topics)  # as ros2 bag record -a does
    types = {t: m['topic_metadata']['type'] for t, m in topics.items()}
    assert types['/cli/chatter'] == 'std_msgs/msg/String'    # not a project topic: from the graph
    assert types['/sensors/temp'] == 'sensor_msgs/msg/Temperature'
    counts = {t: m['message_count'] for t, m in topics.items()}
    assert counts['/cli/chatter'] == counts['/cli/imu'] == counts['/sensors/temp'] == N
    imu_qos = topics['/cli/imu']['topic_metadata']['offered_qos_profiles']
    assert [q['reliability'] for q in imu_qos] == ['best_effort']   # what the publisher offers
    assert [q['reliability'] for q in topics['/cli/chatter']['topic_metadata']['offered_qos_profiles']] == ['reliable']
    got = [deserialize_message(m.data, String).data
           for m in BagReader(recorded['all']).messages(['/cli/chatter'])]
    assert got == [f'hello {i}' for i in range(N)]


def test_progress_line_ends_with_the_recording(recorded):
    """Off a terminal: a final plain line with the latest stamp recorded (4.9 s) and the bag's
    message count; --quiet (the 'positional' recorder): none."""
    err = (recorded['all'].parent / 'all.stderr').read_text()
    last = [x for x in err.splitlines() if x.startswith('record: ')][-1]
    total = sum(m['message_count'] for m in meta_topics(recorded['all']).values())
    assert last.startswith('record: t = 4.90 s') and f'{total} msgs' in last and last.endswith('(done)')
    assert 'record: ' not in (recorded['positional'].parent / 'positional.stderr').read_text()


def test_positional_topics_record_only_those(recorded):
    assert {t: m['message_count'] for t, m in meta_topics(recorded['positional']).items()} == {
        '/cli/chatter': N, '/sensors/temp': N}


def test_regex_selects_by_name(recorded):
    assert set(meta_topics(recorded['regex'])) == {'/sensors/temp'}


def test_exclude_regex_and_exclude_topics(recorded):
    topics = set(meta_topics(recorded['exclude']))
    assert '/sensors/temp' in topics and '/rosout' in topics
    assert not topics & {'/cli/imu', '/cli/chatter', '/_hidden/thing'}


def test_max_bag_duration_splits_by_log_time(recorded):
    """-d 1 on stamps 1.0, 1.1, ..., 4.9 s: a file ends before the first message more than 1 s
    after its first: [1.0, 2.0], [2.1, 3.1], [3.2, 4.2], [4.3, 4.9]."""
    bag = recorded['split']
    info = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert info['relative_file_paths'] == [f'split_{k}.mcap' for k in range(4)]
    assert [f['message_count'] for f in info['files']] == [11, 11, 11, 7]
    assert [f['starting_time']['nanoseconds_since_epoch'] for f in info['files']] == [
        1_000_000_000, 2_100_000_000, 3_200_000_000, 4_300_000_000]
    assert [f['duration']['nanoseconds'] for f in info['files']] == [
        1_000_000_000, 1_000_000_000, 1_000_000_000, 600_000_000]
    assert sorted(p.name for p in bag.iterdir()) == ['metadata.yaml'] + info['relative_file_paths']
    temps = [m.t_ns for m in BagReader(bag).messages()]
    assert temps == [s * 1_000_000_000 + ns for s, ns in map(stamp, range(N))]


def test_a_killed_recording_stays_readable(recorded, caplog):
    bag = recorded['killed']
    assert not (bag / 'metadata.yaml').exists()
    # the spool and the bag file the recorder was streaming to (no summary: never finished)
    assert sorted(p.name for p in bag.iterdir()) == ['killed.recording.mcap', 'killed_0.mcap']
    reader = BagReader(bag)
    assert 'not finalised' in caplog.text
    assert [m.t_ns for m in reader.messages()] == [s * 1_000_000_000 + ns for s, ns in map(stamp, range(N))]


@pytest.mark.parametrize(('args', 'status', 'message'), [
    ([], 2, 'Need to specify at least one option'),
    (['/a', '-x', 'b'], 2, 'require either --all'),
    (['-a', '--compression-format', 'zstd'], 2, 'Cannot specify compression format without'),
    (['-a', '--compression-mode', 'file'], 2, '--compression-format zstd'),
    (['-a', '-s', 'sqlite3'], 2, "invalid choice: 'sqlite3'"),
    (['-a', '-b', '100'], 1, 'Please provide a value greater than 1024'),
])
def test_option_errors(tmp_path, args, status, message):
    res = subprocess.run([sys.executable, '-m', 'alignment_ros.recorder', *args,
                          '-o', str(tmp_path / 'bag')], capture_output=True, text=True, timeout=60)
    assert res.returncode == status, res.stderr
    assert message in res.stderr
    assert not (tmp_path / 'bag').exists()


def test_existing_output_is_refused(tmp_path):
    (tmp_path / 'bag').mkdir()
    res = subprocess.run([sys.executable, '-m', 'alignment_ros.recorder', '-a', '-o',
                          str(tmp_path / 'bag')], capture_output=True, text=True, timeout=60)
    assert res.returncode == 2 and 'already exists' in res.stderr
