"""bag_reindex (scripts/bag_reindex.sh, ``ros2 bag reindex``): a bag cut short or left as a
killed recorder's spool gets its MCAP summary/index and metadata.yaml back, with every message
that was completely written and no other.

Which messages were complete is derived from the byte layout of the original file, not from
the salvage code: in an uncompressed MCAP file a Message record ends with its payload, so a
message survives a cut at byte c exactly when its payload (unique here: stamps and values
differ) ends at or before c."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer
from rclpy.serialization import serialize_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu

from alignment_ros import bag_reindex, msg_definitions
from alignment_ros.bag import BagWriter

IMU, CLOCK = 'sensor_msgs/msg/Imu', 'rosgraph_msgs/msg/Clock'
NS = 1_000_000_000
N = 6000        # about 2.5 MB: several 768 KiB chunks, so a cut falls inside one


def imu(i: int) -> Imu:
    m = Imu()
    m.header.stamp.sec, m.header.stamp.nanosec = 1 + i // 1000, (i % 1000) * 1_000_000
    m.header.frame_id = 'aircraft'
    m.angular_velocity.x = 1e-3 * i
    m.linear_acceleration.z = 9.8 + i
    return m


def messages() -> list[tuple[str, int, bytes]]:
    """(topic, log time, CDR) in log-time order: IMU every 1 ms, /clock every 10 ms + 0.5 ms."""
    out = [('/aircraft/imu', NS + i * 1_000_000, serialize_message(imu(i))) for i in range(N)]
    for k in range(N // 10):
        c = Clock()
        t = NS + k * 10_000_000 + 500_000
        c.clock.sec, c.clock.nanosec = t // NS, t % NS
        out.append(('/clock', t, serialize_message(c)))
    return sorted(out, key=lambda m: m[1])


@pytest.fixture(scope='module')
def recorded(tmp_path_factory) -> tuple[Path, list]:
    bag = tmp_path_factory.mktemp('rec') / 'bag'
    msgs = messages()
    with BagWriter(bag) as w:
        w.add_topic('/clock', CLOCK)
        w.add_topic('/aircraft/imu', IMU)
        for topic, t, data in reversed(msgs):       # any arrival order: the writer sorts
            w.write(topic, data, t)
    return bag, msgs


def complete_before(data: bytes, msgs: list, cut: int) -> list:
    """The messages whose payload ends at or before byte `cut` of the file `data` (the file
    holds them in log-time order: each is searched from where the previous one ended)."""
    out, pos = [], 0
    for m in msgs:
        at = data.find(m[2], pos)
        assert at >= 0
        pos = at + len(m[2])
        if pos <= cut:
            out.append(m)
    return out


def indexed(path: Path) -> list[tuple[str, int, bytes]]:
    """Messages read through the file's MCAP summary and index (None summary: fails)."""
    with path.open('rb') as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None and summary.chunk_indexes
        got = [(c.topic, m.log_time, m.data) for _, c, m in reader.iter_messages(log_time_order=True)]
        assert summary.statistics.message_count == len(got)
    return got


def reindex_cli(bag: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, '-m', 'alignment_ros.bag_reindex', str(bag)],
                          capture_output=True, text=True, timeout=120)


@pytest.mark.parametrize('fraction', [0.5, 0.9])
def test_a_bag_cut_mid_chunk_keeps_every_complete_message(recorded, tmp_path, fraction):
    src, msgs = recorded
    bag = tmp_path / 'bag'
    shutil.copytree(src, bag)
    f = bag / 'bag_0.mcap'
    data = f.read_bytes()
    cut = int(fraction * len(data))
    with f.open('rb') as fh:
        chunks = make_reader(fh).get_summary().chunk_indexes
    assert any(c.chunk_start_offset < cut < c.chunk_start_offset + c.chunk_length for c in chunks)
    os.truncate(f, cut)
    (bag / 'metadata.yaml').unlink()
    expected = complete_before(data, msgs, cut)
    assert 0 < len(expected) < len(msgs)
    assert bag_reindex.damage(bag) is not None

    p = reindex_cli(bag)
    assert p.returncode == 0, p.stderr
    assert len(p.stdout.splitlines()) == 1 and f'{len(expected)} complete messages' in p.stdout
    assert indexed(f) == expected
    meta = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['message_count'] == len(expected)
    counts = {t['topic_metadata']['name']: t['message_count'] for t in meta['topics_with_message_count']}
    assert counts == {t: sum(1 for m in expected if m[0] == t) for t in ('/clock', '/aircraft/imu')}
    assert meta['relative_file_paths'] == ['bag_0.mcap']
    assert meta['starting_time']['nanoseconds_since_epoch'] == expected[0][1]
    assert meta['duration']['nanoseconds'] == expected[-1][1] - expected[0][1]
    assert bag_reindex.damage(bag) is None


def test_a_killed_recorders_spool_becomes_the_bag(tmp_path):
    """The spool (arrival order, plain records, the last one cut by the kill) is finalised as
    the writer would have: sorted, indexed, metadata.yaml; every complete record is kept."""
    msgs = messages()[:3000]
    arrival = msgs[::-1]
    w = BagWriter(tmp_path / 'live' / 'bag')
    w.add_topic('/aircraft/imu', IMU)
    w.add_topic('/clock', CLOCK)
    for topic, t, data in arrival:
        w.write(topic, data, t)
    w.flush()
    bag = tmp_path / 'killed' / 'bag'        # what the killed recorder left: its spool
    bag.mkdir(parents=True)
    spool = bag / 'bag.recording.mcap'
    data = (tmp_path / 'live' / 'bag' / spool.name).read_bytes()
    w.close()
    cut = len(data) - len(arrival[-1][2]) // 2      # the kill fell inside the last message
    spool.write_bytes(data[:cut])
    assert bag_reindex.damage(bag).startswith('bag.recording.mcap left')

    r = bag_reindex.reindex(bag)
    assert not spool.exists()
    kept = sorted(complete_before(data, arrival, cut), key=lambda m: m[1])
    assert kept == sorted(arrival[:-1], key=lambda m: m[1])
    assert r.salvaged == r.messages == len(kept)
    assert indexed(bag / 'bag_0.mcap') == kept
    assert bag_reindex.damage(bag) is None


def test_an_intact_bag_is_left_as_it_was(recorded, tmp_path):
    src, _ = recorded
    bag = tmp_path / 'bag'
    shutil.copytree(src, bag)
    assert bag_reindex.damage(bag) is None
    r = bag_reindex.reindex(bag)
    assert r.damage is None and r.rewritten == []
    assert (bag / 'metadata.yaml').read_text() == (src / 'metadata.yaml').read_text()
    assert (bag / 'bag_0.mcap').read_bytes() == (src / 'bag_0.mcap').read_bytes()


def test_a_cut_zstd_chunk_yields_what_its_prefix_decodes_to(tmp_path):
    """A file of another writer with one zstd chunk, cut in its middle: the messages its
    compressed prefix decodes to are kept, in order (a prefix of what was written)."""
    msgs = [m for m in messages() if m[0] == '/aircraft/imu'][:3000]
    bag = tmp_path / 'bag'
    bag.mkdir()
    f = bag / 'bag_0.mcap'
    with f.open('wb') as fh:
        w = Writer(fh, chunk_size=64 << 20, compression=CompressionType.ZSTD)
        w.start(profile='ros2', library='test')
        enc, text = msg_definitions.message_definition(IMU)
        cid = w.register_channel('/aircraft/imu', 'cdr', w.register_schema(IMU, enc, text.encode()))
        for _, t, data in msgs:
            w.add_message(cid, t, data, t)
        w.finish()
    with f.open('rb') as fh:
        (chunk,) = make_reader(fh).get_summary().chunk_indexes
    os.truncate(f, chunk.chunk_start_offset + chunk.chunk_length // 2)
    r = bag_reindex.reindex(bag)
    got = indexed(f)
    assert 0 < len(got) < len(msgs) and r.salvaged == len(got)
    assert got == msgs[:len(got)]


def test_not_a_bag_is_one_line_and_status_1(tmp_path):
    (tmp_path / 'empty').mkdir()
    for bad in (tmp_path / 'missing', tmp_path / 'empty'):
        p = reindex_cli(bad)
        assert p.returncode == 1
        assert len(p.stderr.splitlines()) == 1 and p.stderr.startswith('bag_reindex: ')
