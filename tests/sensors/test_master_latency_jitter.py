"""The master INS's transport jitter (master.latency_jitter_s, sensors/timing.py): each sample's
delay is the latency plus a uniform draw in [0, J); stamps stay strictly increasing; the node
(one sample at a time) and the batch pipeline stamp alike; a jitter as long as the sample
interval is refused."""
from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.samples import ShipBatch
from alignment_core.sensors.master_ins import MasterInsStage
from alignment_core.units import DEG
from alignment_core.validation import ConfigError

REAL = {'master.model': 'schuler', 'master.rate_hz': 50.0, 'master.latency_s': 0.03, 'master.latency_jitter_s': 0.012}


def _stages(sc):
    ships = ShipBatch.of(pipeline.ship_samples(sc))
    lat = sc.ship.lat_deg * DEG
    batch = MasterInsStage(sc.master, sc.seed, lat, sc.rate_hz, sc.t0_ns).run_batch(ships)
    stage = MasterInsStage(sc.master, sc.seed, lat, sc.rate_hz, sc.t0_ns)
    stepped = [o for k in range(len(ships)) for o in stage.step(ships.sample(k))]
    return ships, batch, stepped


def test_jittered_delays_are_uniform_monotone_and_the_same_stepped_or_batched():
    sc = scenario.load('deck_paper', {'duration_s': 60.0, **REAL}, seed=5)
    ships, batch, stepped = _stages(sc)
    stamps = np.array([o.t_ns for o in batch], dtype=np.int64)
    assert [o.t_ns for o in stepped] == list(stamps)
    valid = sc.t0_ns + np.arange(len(stamps), dtype=np.int64) * 20_000_000       # 50 Hz on the 100 Hz grid
    delay = (stamps - valid) * 1e-9 - 0.03
    assert np.all(np.diff(stamps) > 0)
    assert delay.min() >= 0.0 and delay.max() < 0.012
    # uniform on [0, J): Kolmogorov-Smirnov at 1e-4, mean J/2 within 4 standard errors
    assert stats.kstest(delay / 0.012, 'uniform').pvalue > 1e-4
    assert abs(delay.mean() - 0.006) < 4.0 * 0.012 / np.sqrt(12.0 * len(delay))
    # the jitter draws from a stream of its own: the solution itself is unchanged
    plain = _stages(scenario.load('deck_paper', {'duration_s': 60.0, **REAL, 'master.latency_jitter_s': 0.0},
                                  seed=5))[1]
    for a, b in zip(batch, plain):
        np.testing.assert_array_equal(a.sample.v_b, b.sample.v_b)
        np.testing.assert_array_equal(a.phi, b.phi)
    # released once simulation time reaches the stamp: none after the last ship sample
    assert stamps[-1] <= ships.t_ns[-1]


def test_a_jitter_as_long_as_the_sample_interval_is_refused():
    with pytest.raises(ConfigError, match='latency_jitter_s'):
        scenario.load('deck_paper', {**REAL, 'master.latency_jitter_s': 0.02})     # 50 Hz: 20 ms apart
    scenario.load('deck_paper', {**REAL, 'master.latency_jitter_s': 0.019})
