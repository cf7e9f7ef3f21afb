"""Every filter algorithm the node offers runs in the transfer-alignment engine; those that
theory says equal the Kalman filter on this linear model do, and the adaptive ones converge."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.units import ARCMIN
from alignment_core.validation import ConfigError

OV = {'duration_s': 12.0, 'aircraft.catapult.launch_time_s': 8.0}


def _final(algorithm: str, **extra) -> tuple[np.ndarray, np.ndarray]:
    sc = scenario.load('catapult_paper', {**OV, 'filter.algorithm': algorithm, **extra})
    res = pipeline.run(sc)
    t_rel = max(t.t_ns for t in res.truth if t.on_deck)
    e = [e for e in res.estimates if e.t_ns <= t_rel][-1]
    return e.misalignment, e.misalignment_sigma


@pytest.fixture(scope='module')
def kf():
    return _final('kf')


@pytest.mark.parametrize('algorithm', ['carlson', 'ud'])
def test_square_root_filters_equal_the_kf(kf, algorithm):
    mu, sig = _final(algorithm)
    np.testing.assert_allclose(mu, kf[0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(sig, kf[1], rtol=1e-6)


@pytest.mark.parametrize('algorithm', ['fading', 'fading_tested', 'combined'])
def test_fading_filters_with_unit_factor_equal_the_kf(kf, algorithm):
    # fading_factor 1 and a reserve factor the innovations never reach make lambda = 1
    mu, sig = _final(algorithm, **{'filter.fading_gamma': 1e6})
    np.testing.assert_allclose(mu, kf[0], rtol=0, atol=1e-9)


@pytest.mark.parametrize('algorithm', ['stf', 'stf_multiple'])
def test_strong_tracking_converges_within_its_sigma(algorithm):
    mu, sig = _final(algorithm)
    truth = np.array([15.0, -10.0, -30.0]) * ARCMIN
    assert np.all(np.abs(mu - truth) < 3.0 * sig + 0.05 * ARCMIN)
    assert np.all(sig < 1.0 * ARCMIN)


def test_float32_kf_runs_and_stays_close():
    mu, _ = _final('kf', **{'filter.float32': True})
    mu64, sig64 = _final('kf')
    assert np.all(np.abs(mu - mu64) < 0.5 * sig64)


def test_unknown_algorithm_is_rejected_with_its_key():
    with pytest.raises(ConfigError, match='algorithm'):
        scenario.load('catapult_paper', {'filter.algorithm': 'magic'})
