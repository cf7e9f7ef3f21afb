"""StampMerger: output order depends only on the streams' contents, never on how they
interleaved on arrival."""
from __future__ import annotations

import numpy as np

from alignment_core.navigation.ordering import StampMerger

STREAMS = ('imu', 'ldv', 'master')


def make_streams(rng):
    """Each stream strictly increasing, with many equal stamps across streams."""
    out = {}
    for name, n in zip(STREAMS, (60, 25, 30)):
        stamps = np.sort(rng.choice(np.arange(1, 80) * 10, size=n, replace=False))
        out[name] = [(int(t), f'{name}@{t}') for t in stamps]
    return out


def interleave(rng, streams):
    """A random arrival order that keeps each stream's own order."""
    labels = [name for name in streams for _ in streams[name]]
    rng.shuffle(labels)
    pos = dict.fromkeys(streams, 0)
    order = []
    for name in labels:
        order.append((name, *streams[name][pos[name]]))
        pos[name] += 1
    return order


def expected_order(streams):
    prio = {name: i for i, name in enumerate(STREAMS)}
    ev = [(t, prio[name], name, item) for name in streams for t, item in streams[name]]
    return [(name, t, item) for t, _, name, item in sorted(ev)]


def test_release_order_independent_of_interleaving():
    rng = np.random.default_rng(1)
    streams = make_streams(rng)
    want = expected_order(streams)
    for _ in range(50):
        m = StampMerger(STREAMS)
        got = []
        for name, t, item in interleave(rng, streams):
            assert m.push(name, t, item)
            got.extend(m.pop_ready())
            # nothing released beyond the watermark (the least recent stamp of all streams)
            if got:
                assert got[-1][1] <= m.watermark()
        got.extend(m.flush())
        assert got == want
        assert m.pending() == 0


def test_nothing_released_until_every_stream_has_data():
    m = StampMerger(STREAMS)
    for t in (10, 20, 30):
        m.push('imu', t, t)
        m.push('master', t, t)
    assert m.watermark() is None
    assert list(m.pop_ready()) == []
    assert m.pending() == 6
    m.push('ldv', 20, 'l20')
    assert m.watermark() == 20
    got = list(m.pop_ready())
    assert got == [('imu', 10, 10), ('master', 10, 10), ('imu', 20, 20), ('ldv', 20, 'l20'),
                   ('master', 20, 20)]
    assert m.pending() == 2


def test_flush_releases_everything_in_order():
    m = StampMerger(STREAMS)
    m.push('master', 30, 'm30')
    m.push('imu', 30, 'i30')
    m.push('master', 40, 'm40')
    assert not m.push('imu', 10, 'i10')          # imu is already at 30
    assert [(s, t) for s, t, _ in m.flush()] == [('imu', 30), ('master', 30), ('master', 40)]
    assert m.pending() == 0


def test_out_of_order_within_a_stream_rejected_and_counted():
    m = StampMerger(STREAMS)
    assert m.push('imu', 100, 'a')
    assert not m.push('imu', 100, 'dup')        # equal stamp: does not advance
    assert not m.push('imu', 50, 'late')        # regression
    assert m.push('imu', 110, 'b')
    assert not m.push('imu', 105, 'late2')
    assert m.push('ldv', 5, 'l')
    assert m.rejected_out_of_order == {'imu': 3, 'ldv': 0, 'master': 0}
    assert m.pending() == 3
    items = [item for _, _, item in m.flush()]
    assert items == ['l', 'a', 'b']
