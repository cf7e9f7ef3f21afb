"""Monte Carlo statistics against closed forms and published chi-square quantiles."""
import math

import numpy as np
import pytest

from alignment_experiments.statistics import axis_stats, nees, nees_bounds, settling_time


def test_axis_stats_closed_form():
    s = axis_stats(np.array([3.0, -4.0]), np.array([1.0, 2.0]))
    assert s.n == 2
    assert s.mean == pytest.approx(-0.5)
    assert s.rms == pytest.approx(math.sqrt(12.5))
    assert s.std == pytest.approx(math.sqrt(24.5))          # sample std of (3, -4)
    assert s.mean_sigma == pytest.approx(1.5)
    assert s.in_2sigma == 0.0                                # 3 > 2*1, 4 = 2*2 is not inside
    assert s.nees == pytest.approx((9.0 + 4.0) / 2)


def test_nees_bounds_match_chi_square_tables():
    # chi2(3) 2.5 % and 97.5 % quantiles: 0.2158, 9.3484 (any chi-square table)
    lo, hi = nees_bounds(3, 1)
    assert lo == pytest.approx(0.2158, abs=1e-4) and hi == pytest.approx(9.3484, abs=1e-4)
    # N runs of 1 dof: chi2(50) quantiles 32.357, 71.420 divided by 50
    lo, hi = nees_bounds(1, 50)
    assert lo == pytest.approx(32.357 / 50, abs=1e-4) and hi == pytest.approx(71.420 / 50, abs=1e-4)
    with pytest.raises(ValueError):
        nees_bounds(0, 10)


def test_honest_gaussian_errors_pass_the_consistency_checks():
    rng = np.random.default_rng(7)
    n = 4000
    sigma = rng.uniform(0.5, 2.0, n)
    err = rng.standard_normal(n) * sigma
    s = axis_stats(err, sigma)
    # P(|x| < 2 sigma) = erf(sqrt 2) = 0.9545; binomial sd sqrt(p(1-p)/n) = 0.0033
    assert abs(s.in_2sigma - math.erf(math.sqrt(2.0))) < 4 * math.sqrt(0.9545 * 0.0455 / n)
    lo, hi = nees_bounds(1, n)
    assert lo < s.nees < hi
    # three axes at once: the 3-dof NEES has mean 3
    e3 = rng.standard_normal((n, 3)) * 0.3
    assert np.mean(nees(e3, np.full((n, 3), 0.3))) == pytest.approx(3.0, abs=4 * math.sqrt(6.0 / n))


def test_settling_time():
    t = np.arange(10.0)
    err = np.array([5.0, 3.0, 0.5, 2.0, 0.9, 0.5, 0.1, 0.2, 0.1, 0.0])
    assert settling_time(t, err, 1.0) == 4.0          # last excursion above 1 at t = 3
    assert settling_time(t, np.zeros(10), 1.0) == 0.0
    assert math.isnan(settling_time(t, np.full(10, 2.0), 1.0))
