"""Survey error of the filter's lever arm (aircraft.lever_arm_survey_sigma_m, config/given.py):
off by default (the filter's arm is the true one, bit for bit); on, a random constant per axis
drawn once per seed (the filter node resolves the same: tests/ros/test_params.py; the filter
finding it: tests/estimation/test_lever_arm_survey.py); an explicit filter.lever_arm_m still wins."""
from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from alignment_core.config import scenario
from alignment_core.validation import ConfigError

ARM = [30.0, -12.0, 14.0]


def test_default_copies_the_true_arm_exactly():
    sc = scenario.load('deck_paper', {'aircraft.lever_arm_m': ARM})
    assert sc.aircraft.lever_arm_survey_sigma_m == 0.0
    assert list(sc.filter.lever_arm_m) == ARM


def test_survey_error_is_drawn_per_seed_and_reproducible():
    ov = {'aircraft.lever_arm_m': ARM, 'aircraft.lever_arm_survey_sigma_m': 0.05}
    a = scenario.load('deck_paper', ov, seed=4).filter.lever_arm_m
    b = scenario.load('deck_paper', ov, seed=4).filter.lever_arm_m
    c = scenario.load('deck_paper', ov, seed=5).filter.lever_arm_m
    assert a == b and a != c
    assert np.all(np.abs(np.subtract(a, ARM)) > 0.0)
    # the truth's own keys are untouched: the aircraft stays where it is
    assert list(scenario.load('deck_paper', ov, seed=4).aircraft.lever_arm_m) == ARM


def test_survey_error_has_the_stated_sigma():
    """200 seeds x 3 axes of N(0, sigma^2): sum(e^2)/sigma^2 is chi-square with 600 dof; the
    test fails with probability 1e-4 for a right sigma, and surely for one 20 % off."""
    sigma = 0.03
    errs = np.array([np.subtract(scenario.load('deck_paper', {'aircraft.lever_arm_survey_sigma_m': sigma},
                                               seed=s).filter.lever_arm_m, (40.0, -10.0, 15.0))
                     for s in range(200)])
    q = float(np.sum(errs ** 2) / sigma ** 2)
    lo, hi = stats.chi2.ppf([5e-5, 1 - 5e-5], errs.size)
    assert lo < q < hi
    assert abs(float(np.mean(errs))) < 4.0 * sigma / np.sqrt(errs.size)


def test_explicit_filter_arm_wins_and_bad_sigma_is_refused():
    ov = {'aircraft.lever_arm_survey_sigma_m': 0.05, 'filter.lever_arm_m': [1.0, 2.0, 3.0]}
    assert list(scenario.load('deck_paper', ov).filter.lever_arm_m) == [1.0, 2.0, 3.0]
    with pytest.raises(ConfigError, match='lever_arm_survey_sigma_m'):
        scenario.load('deck_paper', {'aircraft.lever_arm_survey_sigma_m': -0.1})

