"""A random mounting misalignment: drawn once per seed around the given value, with the
stated 1-sigma, and what the truth reports."""
import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.units import ARCMIN

RANDOM = {'aircraft.misalignment_random_arcmin': 20.0, 'aircraft.misalignment_arcmin': [0.0, 0.0, 0.0]}


def test_random_mounting_is_a_per_seed_constant_with_the_stated_sigma():
    d = np.array([pipeline.SlaveImuStage(scenario.load('catapult_paper', RANDOM, seed=s)).kin.mu / ARCMIN
                  for s in range(1, 41)])
    # 120 draws of N(0, 20'^2): sample std within ~3 standard errors (20 / sqrt(240) ~ 1.3')
    assert np.std(d) == pytest.approx(20.0, abs=4.0)
    assert abs(np.mean(d)) < 3 * 20.0 / np.sqrt(d.size)
    again = pipeline.SlaveImuStage(scenario.load('catapult_paper', RANDOM, seed=1)).kin.mu / ARCMIN
    np.testing.assert_array_equal(again, d[0])


def test_truth_reports_the_drawn_mounting():
    sc = scenario.load('catapult_paper', {'aircraft.misalignment_random_arcmin': 20.0, 'duration_s': 2.0,
                                    'aircraft.catapult.enabled': False}, seed=3)
    res = pipeline.run(sc)
    mu = pipeline.SlaveImuStage(sc).kin.mu
    assert not np.allclose(mu, np.asarray(sc.aircraft.misalignment_arcmin) * ARCMIN)
    np.testing.assert_allclose(res.truth[0].misalignment, mu, rtol=0, atol=1e-12)   # via the attitudes: rounding
