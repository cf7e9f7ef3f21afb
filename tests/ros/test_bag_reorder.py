"""The bag writer streams: a bounded reorder buffer puts the streams' messages in log-time order
as they arrive (each stream in its own stamp order, the streams lagging each other), and the
writer's memory does not grow with the recording's length."""
from __future__ import annotations

import gc
import random
import tracemalloc

import pytest

from alignment_ros import bag_writer
from alignment_ros.bag import BagReader, BagWriter
from alignment_ros.bag_reorder import ENTRY_OVERHEAD_B, ReorderBuffer

MS = 1_000_000


def lagging_arrivals(n: int, lag: int, seed: int = 3) -> list[tuple[str, int]]:
    """Three streams at 1 ms ('a', 'b') and 10 ms ('c'); 'b' arrives up to `lag` ms late
    (a random walk of its delay), 'c' on time: (stream, log time) in arrival order."""
    rng = random.Random(seed)
    events = []
    delay = 0
    for i in range(n):
        events.append((i, 0, 'a', i * MS))
        delay = min(lag, max(0, delay + rng.choice((-1, 1))))
        events.append((i + delay, 1, 'b', i * MS))
        if i % 10 == 0:
            events.append((i, 2, 'c', i * MS))
    events.sort()
    return [(s, t) for _, _, s, t in events]


def test_lagging_streams_come_out_in_log_time_order_then_arrival():
    arrivals = lagging_arrivals(5000, lag=40)
    buf = ReorderBuffer(max_bytes=1 << 30)
    for s in 'abc':
        buf.add_stream(s)
    out = []
    for k, (s, t) in enumerate(arrivals):
        buf.push(s, t, k.to_bytes(4, 'little'))
        out += buf.release()
    out += buf.drain()
    expected = sorted((t, k, s) for k, (s, t) in enumerate(arrivals))
    assert [(t, int.from_bytes(d, 'little'), s) for t, s, d in out] == expected
    assert buf.late == 0
    # held: what arrived while 'b' lagged (at most 40 ms of 'a', 'b' and 'c'), not the run
    assert buf.peak_messages <= 2 * 41 + 5


def test_a_silent_stream_holds_no_more_than_the_bound():
    """'quiet' never sends: the watermark stays back, and the bound releases the oldest."""
    buf = ReorderBuffer(max_bytes=100 * (100 + ENTRY_OVERHEAD_B))
    buf.add_stream('a')
    buf.add_stream('quiet')
    out = []
    for i in range(1000):
        buf.push('a', i * MS, bytes(100))
        out += buf.release()
        assert len(buf) <= 100
    assert [t for t, _, _ in out] == [i * MS for i in range(900)]
    buf.push('quiet', 5 * MS, b'late')          # older than what was released: late, kept
    out += buf.drain()
    assert len(out) == 1001 and buf.late == 1
    assert [t for t, _, _ in out[900:]] == [5 * MS] + [i * MS for i in range(900, 1000)]



def test_a_held_buffer_lets_a_stream_subscribed_late_come_out_in_order():
    """A recorder still discovering holds the buffer: a stream added while held, whose first
    message is older than what the other stream sent meanwhile, comes out in log-time order with
    nothing late; without the hold the same arrivals release one message late."""
    outs = {}
    for hold in (True, False):
        buf = ReorderBuffer(max_bytes=1 << 30)
        buf.add_stream('ship')
        buf.hold = hold
        out = []
        for k in range(5):                                  # the ship alone: 0-4 ms
            buf.push('ship', k * MS, b'x')
            out += [t for t, _, _ in buf.release()]
        buf.add_stream('filter')                            # discovered now, its output lags
        buf.push('filter', 1 * MS, b'y')
        out += [t for t, _, _ in buf.release()]
        buf.hold = False                                    # discovery settled
        buf.push('ship', 5 * MS, b'x')
        buf.push('filter', 5 * MS, b'y')
        out += [t for t, _, _ in buf.release()] + [t for t, _, _ in buf.drain()]
        outs[hold] = (out, buf.late)
    assert outs[True] == ([0, 1 * MS, 1 * MS, 2 * MS, 3 * MS, 4 * MS, 5 * MS, 5 * MS], 0)
    assert outs[False][1] == 1 and outs[False][0] != sorted(outs[False][0])


def test_a_held_buffer_still_keeps_to_its_bound():
    buf = ReorderBuffer(max_bytes=10 * (100 + ENTRY_OVERHEAD_B))
    buf.add_stream('a')
    buf.hold = True
    released = []
    for k in range(50):
        buf.push('a', k * MS, b'z' * 100)
        released += [t for t, _, _ in buf.release()]
    assert len(buf) == 10 and released == [k * MS for k in range(40)]


def test_the_bound_must_be_positive():
    with pytest.raises(ValueError):
        ReorderBuffer(0)


def test_messages_beyond_the_bound_are_kept_and_read_back_in_order(tmp_path):
    """A stream lagging more than the bound: its messages are written late (the file is not in
    log-time order there), counted, and every message reads back in log-time order."""
    from rclpy.serialization import serialize_message
    from std_msgs.msg import Float64MultiArray
    data = serialize_message(Float64MultiArray(data=[0.0] * 8))
    bag = tmp_path / 'bag'
    w = BagWriter(bag, reorder_bytes=200 * (len(data) + ENTRY_OVERHEAD_B))
    w.add_topic('/fast', 'std_msgs/msg/Float64MultiArray')
    w.add_topic('/slow', 'std_msgs/msg/Float64MultiArray')
    sent = []
    for i in range(3000):
        w.write('/fast', data, i * MS)
        sent.append(('/fast', i * MS))
        if i >= 1000:                      # /slow: 1000 ms behind, five times the bound
            w.write('/slow', data, (i - 1000) * MS)
            sent.append(('/slow', (i - 1000) * MS))
    w.close()
    assert w.reorder.late > 0
    got = [(m.topic, m.t_ns) for m in BagReader(bag).messages()]
    assert [t for _, t in got] == sorted(t for _, t in sent)
    assert sorted(got) == sorted(sent)
    assert BagReader(bag).counts() == {'/fast': 3000, '/slow': 2000}


def test_the_writers_memory_does_not_grow_with_the_recording(tmp_path, monkeypatch):
    """100 000 messages, two streams 50 ms apart, 16 kB chunks (about 1800: the Python memory
    of a chunk in progress stays below 16 kB): the memory the writer holds after 20 000 and
    after 100 000 messages differs by less than 64 kB. A whole-run index of 22 bytes per
    message (what the writer once kept for its sort at close) would be 1.7 MB, mcap's list of
    chunk indexes 2.7 MB."""
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import Imu
    monkeypatch.setattr(bag_writer, 'CHUNK_SIZE', 16 << 10)
    data = serialize_message(Imu())
    w = BagWriter(tmp_path / 'bag')
    w.add_topic('/a', 'sensor_msgs/msg/Imu')
    w.add_topic('/b', 'sensor_msgs/msg/Imu')
    tracemalloc.start()
    try:
        held = {}
        for i in range(50_000):
            w.write('/a', data, i * MS)
            if i >= 50:
                w.write('/b', data, (i - 50) * MS)
            if i in (10_000, 49_999):
                gc.collect()
                held[i] = tracemalloc.get_traced_memory()[0]
    finally:
        tracemalloc.stop()
        w.close()
    assert held[49_999] - held[10_000] < 64_000, held
    assert BagReader(tmp_path / 'bag').counts() == {'/a': 50_000, '/b': 49_950}


def _recorder(topic_filter, graph_topics=()):
    """A Recorder without a node: its writer's reorder buffer, its filter and a fake graph."""
    from types import SimpleNamespace

    from alignment_ros.recorder import Recorder

    rec = object.__new__(Recorder)
    rec.writer = SimpleNamespace(reorder=ReorderBuffer(1 << 20))
    rec.filter, rec.subscriptions, rec._unusable = topic_filter, {}, set()
    rec.node = SimpleNamespace(get_topic_names_and_types=lambda: list(graph_topics),
                               get_publishers_info_by_topic=lambda topic: [])
    rec.subscribe = lambda topic, type_name, qos: rec.subscriptions.setdefault(topic, type_name)
    return rec


def test_the_recorder_holds_its_bag_while_discovery_adds_topics():
    """Held from a newly subscribed topic until DISCOVERY_SETTLE_S without another; never held
    by a recorder that does not discover (its topics were all subscribed at its start)."""
    from alignment_ros.record_options import TopicFilter
    from alignment_ros.recorder import DISCOVERY_SETTLE_S

    rec = _recorder(TopicFilter(regex='^/ship/'))
    rec.last_new_topic = 100.0
    held = []
    for discovering, now in ((True, 100.0), (True, 100.0 + 0.5 * DISCOVERY_SETTLE_S),
                             (True, 100.0 + DISCOVERY_SETTLE_S), (False, 100.0)):
        rec.settle(discovering, now)
        held.append(rec.writer.reorder.hold)
    assert held == [True, True, False, False]


def test_the_recorder_holds_its_bag_while_a_named_topic_is_missing():
    """Topics named on the command line (no discovery beyond them): held however long the named
    topic takes to appear, released once it is subscribed; discovery dates the new subscription."""
    from alignment_ros.record_options import TopicFilter
    from alignment_ros.recorder import DISCOVERY_SETTLE_S

    rec = _recorder(TopicFilter(topics=['/a', '/b']), [('/a', ['std_msgs/msg/String'])])
    rec.filter.include_unpublished = True
    assert rec.discover() == 1 and rec.pending_topics() == ['/b']
    rec.settle(True, rec.last_new_topic + 10 * DISCOVERY_SETTLE_S)
    assert rec.writer.reorder.hold
    rec.node.get_topic_names_and_types = lambda: [('/a', ['std_msgs/msg/String']), ('/b', ['std_msgs/msg/String'])]
    before = rec.last_new_topic
    assert rec.discover() == 1 and not rec.pending_topics() and rec.last_new_topic > before
    rec.settle(True, rec.last_new_topic + 0.1)
    assert not rec.writer.reorder.hold
    dated = rec.last_new_topic
    assert rec.discover() == 0 and rec.last_new_topic == dated        # nothing new: not dated again
