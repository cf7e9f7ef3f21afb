"""RecentRows: rows by sample index, appended in order, read back near the newest; the rows a
reader let go are forgotten and their memory reused, so a stream of any length holds a bounded
buffer, while a batch that reads everything keeps everything."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.recent_rows import RecentRows
from alignment_core.ship import track


def test_rows_read_back_by_index_until_forgotten():
    r = RecentRows(2, capacity=4)
    for k in range(10):
        r.append(np.array([k, -k], dtype=float))
    np.testing.assert_array_equal(r[np.array([0, 9, 3])], [[0, 0], [9, -9], [3, -3]])
    np.testing.assert_array_equal(r[5], [5, -5])
    r.forget_before(6)
    np.testing.assert_array_equal(r[np.arange(6, 10)][:, 0], [6, 7, 8, 9])
    with pytest.raises(IndexError, match='row 5 is not kept'):
        r[5]
    with pytest.raises(IndexError, match='row 10 is not kept'):
        r[10]


def test_a_stream_holds_a_bounded_buffer_and_its_values_survive_the_moves():
    r = RecentRows(3, capacity=8)
    for k in range(100_000):
        r.forget_before(k - 5)                     # a reader that needs the last five rows
        r.append(np.full(3, float(k)))
        if k >= 5:
            np.testing.assert_array_equal(r[np.arange(k - 5, k + 1)][:, 1], np.arange(k - 5, k + 1))
    assert r.capacity <= 16                          # twice the live rows, rounded up to the doubling


def test_blocks_of_rows_append_as_rows_do():
    a, b = RecentRows(2, capacity=4), RecentRows(2, capacity=4)
    rows = np.arange(2 * 300, dtype=float).reshape(300, 2)
    for k0 in range(0, 300, 37):
        a.forget_before(k0 - 10)
        b.forget_before(k0 - 10)
        a.extend(rows[k0:k0 + 37])
        for row in rows[k0:k0 + 37]:
            b.append(row)
        np.testing.assert_array_equal(a[np.arange(max(0, k0 - 10), a.n)], rows[max(0, k0 - 10):a.n])
    assert a.n == b.n == 300 and a.capacity <= 128


def test_the_carriers_gear_flexure_and_track_hold_bounded_histories_in_a_long_stepped_run():
    """The slave's stage stepped in node-sized chunks for 10 minutes of the default carrier
    keeps a few hundred samples of the gear and the flexure (not the run's 60 000), and the
    ship's track a few thousand grid steps."""
    sc = scenario.load('deck', {'duration_s': 600.0})
    track.forget_shared_starts()            # a fresh process's track: integrated here, nothing recalled
    src = pipeline.ship_source(sc)
    stage = pipeline.SlaveImuStage(sc)
    n = sc.n_samples
    for k in range(0, n, 50):
        ks = np.arange(k, min(k + 50, n))
        stage.step_many(src.samples((ks * sc.dt_ns) / 1e9, sc.t0_ns, sc.dt_ns, k0=k))
    gear = stage.kin.gear.response
    assert gear.n == n and gear._q.capacity <= 1024
    assert stage.kin.flex._th.capacity <= 1024
    assert src.track._steps * src.track.h >= 600.0 and src.track._coef.capacity <= 8192


_FILL_PROBE = """
import numpy as np
from alignment_core.recent_rows import RecentRows

def anon_kib():
    for line in open('/proc/self/status'):
        if line.startswith('RssAnon:'):
            return int(line.split()[1])

rows = RecentRows(24, capacity=8192)
row = np.ones(24)
before = anon_kib()
for k in range(4000):           # half the buffer: rows land on pages not written before
    rows.append(row)
    rows.forget_before(k - 100)
print(anon_kib() - before)
"""


@pytest.mark.skipif(not Path('/proc/self/status').exists(), reason='needs /proc')
def test_a_buffer_is_resident_when_made_not_page_by_page_as_it_first_fills():
    # 8192 rows of 24 floats are 1.5 MiB: left unwritten until rows reach them, the 4000 rows'
    # 750 KiB would become resident as they land; written when made, none
    env = {k: v for k, v in os.environ.items() if not k.startswith(('MALLOC_', 'GLIBC_TUNABLES'))}
    out = subprocess.run([sys.executable, '-c', _FILL_PROBE], capture_output=True, text=True, env=env, check=True)
    assert int(out.stdout) < 8192 * 24 * 8 / 1024 / 2 / 4
