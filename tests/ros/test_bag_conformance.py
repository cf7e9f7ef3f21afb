"""Bags as rosbag2 Jazzy's MCAP storage writes them, checked with the mcap library and the
installed interface files (not with our reader): ros_distro, RIHS01 hashes in the channel
metadata, schema text = the installed .msg definitions, messages in log-time order in every
file, summary CRC, counts in metadata.yaml = summary statistics = messages. On a short graph
run's bag, and on two bags recorded from the same run with record.sh: split by duration with
file compression, split by size with message compression. Then bag_info on them.
"""
from __future__ import annotations

import io
import json
import os
import signal
import struct
import subprocess
import time
import zlib
from collections import Counter
from datetime import UTC, datetime
from pathlib import Path

import pytest
import yaml
import zstandard
from ament_index_python.packages import get_package_share_directory
from mcap.reader import make_reader
from mcap.records import Channel, ChunkIndex, Message, Metadata, Schema
from mcap.stream_reader import StreamReader

from alignment_ros.bag import BagReader, BagWriter

ROOT = Path(__file__).resolve().parents[2]
SETS = ['duration_s=12.0', 'aircraft.catapult.launch_time_s=8.0', 'seed=7']
DELIM = '\n' + '=' * 80 + '\nMSG: '
SIZE_LIMIT = 300_000
# rosbag2's order of the dependency blocks (sorted per level, depth first, each type once),
# written out by hand from the installed .msg files
DEPENDENCIES = {
    'rosgraph_msgs/msg/Clock': ['builtin_interfaces/Time'],
    'nav_msgs/msg/Odometry': [
        'geometry_msgs/PoseWithCovariance', 'geometry_msgs/Pose', 'geometry_msgs/Point',
        'geometry_msgs/Quaternion', 'geometry_msgs/TwistWithCovariance', 'geometry_msgs/Twist',
        'geometry_msgs/Vector3', 'std_msgs/Header', 'builtin_interfaces/Time'],
    'geometry_msgs/msg/AccelStamped': ['geometry_msgs/Accel', 'geometry_msgs/Vector3',
                                       'std_msgs/Header', 'builtin_interfaces/Time'],
    'sensor_msgs/msg/NavSatFix': ['sensor_msgs/NavSatStatus', 'std_msgs/Header',
                                  'builtin_interfaces/Time'],
    'sensor_msgs/msg/Imu': ['geometry_msgs/Quaternion', 'geometry_msgs/Vector3',
                            'std_msgs/Header', 'builtin_interfaces/Time'],
    'geometry_msgs/msg/TwistWithCovarianceStamped': [
        'geometry_msgs/TwistWithCovariance', 'geometry_msgs/Twist', 'geometry_msgs/Vector3',
        'std_msgs/Header', 'builtin_interfaces/Time'],
    'geometry_msgs/msg/Vector3Stamped': ['geometry_msgs/Vector3', 'std_msgs/Header',
                                         'builtin_interfaces/Time'],
    'geometry_msgs/msg/PoseWithCovarianceStamped': [
        'geometry_msgs/PoseWithCovariance', 'geometry_msgs/Pose', 'geometry_msgs/Point',
        'geometry_msgs/Quaternion', 'std_msgs/Header', 'builtin_interfaces/Time'],
    'std_msgs/msg/Float64MultiArray': ['std_msgs/MultiArrayLayout', 'std_msgs/MultiArrayDimension'],
    'diagnostic_msgs/msg/DiagnosticArray': ['diagnostic_msgs/DiagnosticStatus',
                                            'diagnostic_msgs/KeyValue', 'std_msgs/Header',
                                            'builtin_interfaces/Time'],
}


def installed(kind: str, type_name: str) -> str:
    """share/PKG/msg/Type.<kind> of 'pkg/Type' or 'pkg/msg/Type'."""
    parts = type_name.split('/')
    return (Path(get_package_share_directory(parts[0])) / 'msg' / f'{parts[-1]}.{kind}').read_text()


def installed_hash(type_name: str) -> str:
    doc = json.loads(installed('json', type_name))
    return next(h['hash_string'] for h in doc['type_hashes'] if h['type_name'] == type_name)


def file_bytes(path: Path) -> bytes:
    data = path.read_bytes()
    if path.name.endswith('.zstd'):
        return zstandard.ZstdDecompressor().stream_reader(io.BytesIO(data)).read()
    return data


def check_summary_crc(data: bytes) -> None:
    """MCAP spec: the footer's CRC covers the summary section and the footer up to the CRC."""
    footer = len(data) - 8 - 29          # magic; footer record = opcode + length + 8 + 8 + 4
    assert data[footer] == 0x02 and struct.unpack_from('<Q', data, footer + 1)[0] == 20
    summary_start, _, crc = struct.unpack_from('<QQI', data, footer + 9)
    assert crc != 0
    assert crc == zlib.crc32(data[summary_start:footer + 25])


def check_bag(bag: Path) -> dict[str, list[tuple[int, bytes]]]:
    """Assert a bag conforms; return {topic: [(log time, CDR bytes)]} in file order."""
    info = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert (info['version'], info['storage_identifier'], info['ros_distro']) == (9, 'mcap', 'jazzy')
    meta = {t['topic_metadata']['name']: t for t in info['topics_with_message_count']}
    mode = info['compression_mode']
    messages: dict[str, list[tuple[int, bytes]]] = {t: [] for t in meta}
    last_time = -1
    assert len(info['files']) == len(info['relative_file_paths'])
    for rel, finfo in zip(info['relative_file_paths'], info['files']):
        data = file_bytes(bag / rel)
        check_summary_crc(data)
        assert make_reader(io.BytesIO(data)).get_header().profile == 'ros2'
        summary = make_reader(io.BytesIO(data)).get_summary()
        records = list(StreamReader(io.BytesIO(data)).records)
        schemas = {r.id: r for r in records if isinstance(r, Schema)}
        channels = {r.id: r for r in records if isinstance(r, Channel)}
        assert {c.topic for c in channels.values()} == set(meta)      # every topic in every file
        for ch in channels.values():
            m = meta[ch.topic]['topic_metadata']
            schema = schemas[ch.schema_id]
            assert (schema.name, schema.encoding, ch.message_encoding) == (m['type'], 'ros2msg', 'cdr')
            assert ch.metadata['topic_type_hash'] == m['type_description_hash'] == installed_hash(m['type'])
            assert yaml.safe_load(ch.metadata['offered_qos_profiles']) == m['offered_qos_profiles']
            check_schema_text(m['type'], schema.data.decode())
        records_meta = [r for r in records if isinstance(r, Metadata) and r.name == 'rosbag2']
        assert len(records_meta) == 1
        serialized = yaml.safe_load(records_meta[0].metadata['serialized_metadata'])
        assert (serialized['version'], serialized['ros_distro']) == (9, 'jazzy')
        times = []
        for r in records:
            if isinstance(r, Message):
                times.append(r.log_time)
                payload = zstandard.ZstdDecompressor().decompress(r.data) if mode == 'MESSAGE' else r.data
                messages[channels[r.channel_id].topic].append((r.log_time, payload))
        assert times == sorted(times) and (not times or times[0] >= last_time)
        last_time = times[-1] if times else last_time
        chunks = sorted((r for r in records if isinstance(r, ChunkIndex)),
                        key=lambda c: c.chunk_start_offset)
        assert all(a.message_end_time <= b.message_start_time for a, b in zip(chunks, chunks[1:]))
        stats = summary.statistics
        assert stats.message_count == len(times) == finfo['message_count']
        assert finfo['starting_time']['nanoseconds_since_epoch'] == times[0]
        assert finfo['duration']['nanoseconds'] == times[-1] - times[0]
        per_topic = Counter(channels[r.channel_id].topic for r in records if isinstance(r, Message))
        assert {summary.channels[c].topic: n for c, n in stats.channel_message_counts.items() if n} == dict(per_topic)
    counts = {t: len(v) for t, v in messages.items()}
    assert counts == {t: m['message_count'] for t, m in meta.items()}
    assert info['message_count'] == sum(counts.values())
    all_times = [t for v in messages.values() for t, _ in v]
    assert info['starting_time']['nanoseconds_since_epoch'] == min(all_times)
    assert info['duration']['nanoseconds'] == max(all_times) - min(all_times)
    return messages


def check_schema_text(type_name: str, text: str) -> None:
    """The root's installed .msg, then one block per dependency with its installed .msg."""
    root, *blocks = text.split(DELIM)
    assert root == installed('msg', type_name)
    names = []
    for b in blocks:
        name, _, body = b.partition('\n')
        assert body == installed('msg', name), name
        names.append(name)
    assert len(names) == len(set(names))
    if type_name in DEPENDENCIES:
        assert names == DEPENDENCIES[type_name]


@pytest.fixture(scope='module')
def bags(tmp_path_factory) -> dict[str, Path]:
    """A short catapult graph run (its bag), and record.sh recordings of the same run."""
    out = tmp_path_factory.mktemp('conformance')
    env = {k: v for k, v in os.environ.items() if k != 'ROS_DOMAIN_ID'}
    cmd = [str(ROOT / 'scripts/run_graph.sh'), '--scenario', 'catapult_paper', '--out', str(out / 'run'),
           '--real-time-factor', '2']
    for s in SETS:
        cmd += ['--set', s]
    graph = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    first = graph.stdout.readline()
    while first.startswith('setup.sh:'):   # a rebuild after a package file changed
        first = graph.stdout.readline()
    assert first.startswith('ROS_DOMAIN_ID='), first + graph.stderr.read()
    renv = dict(env, ROS_DOMAIN_ID=first.split()[0].split('=')[1])
    extra = {
        'file_split': ['-a', '-d', '3', '--compression-mode', 'file', '--compression-format', 'zstd'],
        'message_split': ['-e', '^/(aircraft|alignment|ship)/', '-b', str(SIZE_LIMIT),
                          '--compression-mode', 'message', '--compression-format', 'zstd'],
    }
    recs = {name: subprocess.Popen([str(ROOT / 'scripts/record.sh'), *args, '-o', str(out / name),
                                    '--node-name', f'rec_{name}'], env=renv, text=True,
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE)
            for name, args in extra.items()}
    try:
        stdout, stderr = graph.communicate(timeout=400)
        assert graph.returncode == 0, stdout + stderr
        time.sleep(0.5)
        for p in recs.values():
            p.send_signal(signal.SIGINT)
        for name, p in recs.items():
            _, err = p.communicate(timeout=120)
            assert p.returncode == 0, f'{name}: {err}'
    finally:
        for p in (graph, *recs.values()):
            if p.poll() is None:
                p.kill()
                p.communicate()
    return {'graph': out / 'run' / 'bag', **{name: out / name for name in extra}}


def test_graph_bag_conforms(bags):
    msgs = check_bag(bags['graph'])
    files = list(bags['graph'].glob('*.mcap'))
    assert len(files) == 1 and msgs['/aircraft/imu']
    assert set(DEPENDENCIES) <= set(_types(bags['graph']).values())  # every type checked in order
    with files[0].open('rb') as fh:
        imu = next(s for s in make_reader(fh).get_summary().schemas.values()
                   if s.name == 'sensor_msgs/msg/Imu').data.decode()
    assert 'MSG: geometry_msgs/Quaternion\n' in imu and '\nfloat64 w 1\n' in imu   # defaults kept
    assert imu.startswith('# This is a message to hold data from an IMU')         # comments kept


def _types(bag: Path) -> dict[str, str]:
    info = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    return {t['topic_metadata']['name']: t['topic_metadata']['type'] for t in info['topics_with_message_count']}


@pytest.mark.parametrize('name', ['file_split', 'message_split'])
def test_compressed_split_bags_conform_and_hold_the_graph_messages(bags, name):
    """Each topic a recording shares with the graph's bag holds the same messages from some
    point on (a late subscription misses the first ones, nothing after), at the same log times
    and in the same order for stamped types. An unstamped message's log time is the latest
    simulation time that recorder knew when it arrived (bag.py): a recording started mid-run
    dates the ones it got before its first /clock by the latest stamp it had seen, which may run
    ahead of /clock, so they may sort after a few later ones: the same messages, not always in
    the graph bag's order. Our reader yields them in log-time order, decompressed, across the
    files."""
    msgs = check_bag(bags[name])
    graph = check_bag(bags['graph'])
    types = _types(bags['graph'])
    shared = set(msgs) & set(graph)
    assert {'/aircraft/imu', '/alignment/misalignment', '/alignment/state'} <= shared
    for topic in shared:
        ours, ref = msgs[topic], graph[topic]
        ref = ref[len(ref) - len(ours):]
        if types[topic] == 'std_msgs/msg/Float64MultiArray':  # no stamp: the same messages
            ours, ref = sorted(d for _, d in ours), sorted(d for _, d in ref)
        assert ours and ours == ref, topic
    ours = [(m.topic, m.t_ns, bytes(m.data)) for m in BagReader(bags[name]).messages()]
    assert [t for _, t, _ in ours] == sorted(t for _, t, _ in ours)
    assert Counter(t for t, _, _ in ours) == Counter({t: len(v) for t, v in msgs.items() if v})
    assert sorted(ours) == sorted((t, lt, d) for t, v in msgs.items() for lt, d in v)


def test_split_rules(bags):
    info = yaml.safe_load((bags['file_split'] / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert (info['compression_format'], info['compression_mode']) == ('zstd', 'FILE')
    files = info['files']
    assert len(files) >= 4   # 12 s of simulation in files of at most 3 s
    assert info['relative_file_paths'] == [f'file_split_{k}.mcap.zstd' for k in range(len(files))]
    assert [f['path'] for f in files] == [f'file_split_{k}.mcap' for k in range(len(files))]
    starts = [f['starting_time']['nanoseconds_since_epoch'] for f in files]
    assert all(f['duration']['nanoseconds'] <= 3_000_000_000 for f in files)
    assert all(b - a > 3_000_000_000 for a, b in zip(starts, starts[1:]))
    info = yaml.safe_load((bags['message_split'] / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert (info['compression_format'], info['compression_mode']) == ('zstd', 'MESSAGE')
    sizes = [(bags['message_split'] / p).stat().st_size for p in info['relative_file_paths']]
    assert len(sizes) >= 2 and all(s >= SIZE_LIMIT for s in sizes[:-1])


# --- bag_info -------------------------------------------------------------------------------

def info_text(bag: Path) -> str:
    res = subprocess.run([str(ROOT / 'scripts/bag_info.sh'), str(bag)], capture_output=True,
                         text=True, timeout=120, env=dict(os.environ, TZ='UTC'))
    assert res.returncode == 0, res.stderr
    return res.stdout


def utc(ns: int) -> str:
    d = datetime.fromtimestamp(ns // 10**9, tz=UTC)
    return f'{d:%b} {d.day:2d} {d:%Y %H:%M:%S}.{ns % 10**9:09d} ({ns // 10**9}.{ns % 10**9:09d})'


def test_bag_info_of_a_synthetic_bag(tmp_path):
    """Hand-computed: three messages at 1.0, 2.0 and 3.5 s on two topics."""
    from rclpy.serialization import serialize_message
    from std_msgs.msg import Float64MultiArray
    bag = tmp_path / 'bag'
    with BagWriter(bag) as w:
        w.add_topic('/b', 'std_msgs/msg/Float64MultiArray')
        w.add_topic('/a', 'std_msgs/msg/Float64MultiArray')
        data = serialize_message(Float64MultiArray(data=[1.0]))
        w.write('/a', data, 3_500_000_000)
        w.write('/b', data, 1_000_000_000)
        w.write('/a', data, 2_000_000_000)
    size = sum(p.stat().st_size for p in bag.iterdir())
    assert 1024 <= size < 1024 * 1024
    assert info_text(bag) == (
        '\n'
        'Files:             bag_0.mcap\n'
        f'Bag size:          {size / 1024:.1f} KiB\n'
        'Storage id:        mcap\n'
        'ROS Distro:        jazzy\n'
        'Duration:          2.500000000s\n'
        'Start:             Jan  1 1970 00:00:01.000000000 (1.000000000)\n'
        'End:               Jan  1 1970 00:00:03.500000000 (3.500000000)\n'
        'Messages:          3\n'
        'Topic information: Topic: /b | Type: std_msgs/msg/Float64MultiArray | Count: 1 | '
        'Serialization Format: cdr\n'
        '                   Topic: /a | Type: std_msgs/msg/Float64MultiArray | Count: 2 | '
        'Serialization Format: cdr\n'
        'Service:           0\n'
        'Service information: \n')


def test_bag_info_of_recorded_bags(bags):
    for name in ('graph', 'file_split'):
        bag = bags[name]
        info = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
        start, dur = info['starting_time']['nanoseconds_since_epoch'], info['duration']['nanoseconds']
        files = info['relative_file_paths']
        lines = info_text(bag).split('\n')
        assert lines[0] == '' and lines[1] == f'Files:             {files[0]}'
        assert lines[2:1 + len(files)] == [' ' * 19 + f for f in files[1:]]
        rest = lines[1 + len(files):]
        assert rest[0].startswith('Bag size:          ') and rest[0].endswith('iB')
        assert rest[1:7] == [
            'Storage id:        mcap', 'ROS Distro:        jazzy',
            f'Duration:          {dur // 10**9}.{dur % 10**9:09d}s',
            f'Start:             {utc(start)}', f'End:               {utc(start + dur)}',
            f'Messages:          {info["message_count"]}']
        topics = [f'Topic: {t["topic_metadata"]["name"]} | Type: {t["topic_metadata"]["type"]} | '
                  f'Count: {t["message_count"]} | Serialization Format: cdr'
                  for t in info['topics_with_message_count']]
        assert rest[7] == 'Topic information: ' + topics[0]
        assert rest[8:7 + len(topics)] == [' ' * 19 + t for t in topics[1:]]
        assert rest[7 + len(topics):] == ['Service:           0', 'Service information: ', '']


def test_bag_info_of_a_lone_mcap_file(bags):
    """Without metadata.yaml: the MCAP summary and its rosbag2 record (as rosbag2 reads it)."""
    f = next(bags['graph'].glob('*.mcap'))
    text = info_text(f)
    info = yaml.safe_load((bags['graph'] / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert f'Files:             {f}\n' in text
    assert 'ROS Distro:        jazzy\n' in text
    assert f'Messages:          {info["message_count"]}\n' in text
    for t in info['topics_with_message_count']:
        md = t['topic_metadata']
        assert f'Topic: {md["name"]} | Type: {md["type"]} | Count: {t["message_count"]} |' in text


# --- reading compressed bags back -----------------------------------------------------------

def _imu_bag(path: Path, n: int, **kw) -> list[tuple[int, bytes]]:
    """n IMU messages 1 ms apart, written in reverse order; returns them in log-time order."""
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import Imu
    msgs = []
    for i in range(n):
        m = Imu()
        m.header.stamp.sec, m.header.stamp.nanosec = 1 + i // 1000, (i % 1000) * 1_000_000
        m.linear_acceleration.z = float(i)
        msgs.append((1_000_000_000 + i * 1_000_000, serialize_message(m)))
    with BagWriter(path, **kw) as w:
        w.add_topic('/aircraft/imu', 'sensor_msgs/msg/Imu')
        for t, d in reversed(msgs):
            w.write('/aircraft/imu', d, t)
    return msgs


@pytest.mark.parametrize('mode', ['file', 'message'])
def test_compressed_bags_read_back(tmp_path, mode):
    msgs = _imu_bag(tmp_path / 'bag', 3000, max_bag_duration_s=1, compression_mode=mode,
                    compression_format='zstd')
    check_bag(tmp_path / 'bag')
    got = [(m.t_ns, bytes(m.data)) for m in BagReader(tmp_path / 'bag').messages()]
    assert got == msgs
    assert BagReader(tmp_path / 'bag').counts() == {'/aircraft/imu': 3000}


def test_a_cut_compressed_file_yields_its_prefix(tmp_path, caplog):
    msgs = _imu_bag(tmp_path / 'bag', 6000, compression_mode='file', compression_format='zstd')
    (src,) = (tmp_path / 'bag').glob('*.mcap.zstd')
    cut = tmp_path / 'cut.mcap.zstd'
    data = src.read_bytes()
    cut.write_bytes(data[:len(data) // 2])
    reader = BagReader(cut)
    got = [(m.t_ns, bytes(m.data)) for m in reader.messages()]
    assert reader.truncated and 'truncated MCAP file' in caplog.text
    assert 0 < len(got) < len(msgs) and got == msgs[:len(got)]
