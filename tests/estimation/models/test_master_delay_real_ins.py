"""The delay state (filter.master_delay_state) against a real ship INS: Schuler / velocity-damped
errors, 50 Hz output, a 30 ms transport latency the filter is not told (filter.master_latency_s
stays 0), with and without a per-sample jitter."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.units import ARCMIN

REAL = {'duration_s': 60.0, 'master.model': 'schuler', 'master.rate_hz': 50.0, 'master.latency_s': 0.03,
        'filter.master_delay_state': True}


def _run(extra: dict, seed: int):
    sc = scenario.load('deck_paper', {**REAL, **extra}, seed=seed)
    res = pipeline.run(sc, keep_truth=False)
    i = res.filter.labels.index('dt_master')
    return sc, res, res.estimates[-1], i


@pytest.mark.parametrize('seed', [1, 3])
def test_delay_state_converges_to_a_constant_unknown_latency(seed):
    """Constant 30 ms: the estimate within 3 sigma of it, that sigma far below the prior's 20 ms,
    and the misalignment error inside 3 sigma."""
    sc, res, e, i = _run({}, seed)
    assert sc.filter.master_latency_s == 0.0
    assert abs(e.x[i] - 0.03) < 3.0 * e.sigma[i] and e.sigma[i] < 1e-4
    err = e.misalignment - np.array(sc.aircraft.misalignment_arcmin) * ARCMIN
    assert np.all(np.abs(err) < 3.0 * e.misalignment_sigma)


def test_with_jitter_the_delay_state_finds_the_mean_delay():
    """30 ms + U(0, 10 ms): the state is a constant, so it can only find the mean delay, 35 ms. The
    filter does not model the jitter (its sigma, ~0.02 ms, ignores it), so the yardstick is the
    jitter's own: the mean of N delays of standard deviation J/sqrt(12) is known to
    J/sqrt(12 N), N = 3000 master samples in 60 s: 0.05 ms; the estimate within 3 of those."""
    sc, res, e, i = _run({'master.latency_jitter_s': 0.01}, 3)
    n = res.filter.counters.updates
    assert n > 2900
    assert abs(e.x[i] - 0.035) < 3.0 * 0.01 / np.sqrt(12.0 * n)
