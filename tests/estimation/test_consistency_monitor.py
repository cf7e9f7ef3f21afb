"""The consistency monitor (estimation/consistency.py): the NIS summed over a window of updates is
chi-square with the window's degrees of freedom when the filter is consistent; a window above the
1 - warn_p quantile is a WARN, `error_windows` in a row an ERROR that persists."""
from __future__ import annotations

import math

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.consistency import NisMonitor
from alignment_core.estimation.health import ERROR, OK, WARN


def test_the_bound_is_the_chi_square_quantile():
    """Wilson-Hilferty (an independent approximation, good to ~0.1 % at 300 dof):
    chi2_k(1 - p) ~ k (1 - 2/(9k) + z sqrt(2/(9k)))^3 with z the normal quantile (z(1e-4) = 3.719)."""
    k, z = 300, 3.7190164854556804
    wh = k * (1.0 - 2.0 / (9 * k) + z * math.sqrt(2.0 / (9 * k))) ** 3
    assert NisMonitor(100, 1e-4, 3).bound(k) == pytest.approx(wh, rel=2e-3)


def test_a_consistent_filter_fails_windows_at_the_chosen_rate():
    """NIS of a consistent 3-row update is chi2(3): with warn_p = 0.01, 2000 windows fail about
    20 times (binomial sd 4.4), and never 3 in a row often enough to latch (p^3 = 1e-6)."""
    rng = np.random.default_rng(1)
    m = NisMonitor(50, 0.01, 3)
    for nis in rng.chisquare(3, size=2000 * 50):
        m.add(float(nis), 3)
    assert m.completed == 2000 and 20 - 4 * 4.4 < m.failures < 20 + 4 * 4.4
    assert m.level != ERROR


def test_an_optimistic_filter_warns_then_errs_and_the_error_persists():
    """Innovations 1.5 times larger than the filter believes: NIS 2.25 chi2(3), the window mean
    2.25 per dof against a bound of 1.31 (300 dof, p 1e-4)."""
    rng = np.random.default_rng(2)
    m = NisMonitor(100, 1e-4, 3)
    levels = []
    for _ in range(3):
        for nis in 2.25 * rng.chisquare(3, size=100):
            m.add(float(nis), 3)
        levels.append(m.level)
    assert levels == [WARN, WARN, ERROR]
    for nis in rng.chisquare(3, size=500):                # consistent again: the ERROR stays
        m.add(float(nis), 3)
    assert m.level == ERROR and m.fails_in_row == 0


def test_one_failing_window_is_cleared_by_the_next():
    rng = np.random.default_rng(3)
    m = NisMonitor(100, 1e-4, 3)
    for nis in 3.0 * rng.chisquare(3, size=100):
        m.add(float(nis), 3)
    assert m.level == WARN
    for nis in rng.chisquare(3, size=100):
        m.add(float(nis), 3)
    assert m.level == OK


def test_the_cap_bounds_a_single_outlier_and_non_finite_nis_is_skipped():
    """99 updates at their mean (3) and one gated at 1e8: capped at 25 the window's sum is
    297 + 25 = 322, below chi2_300(1 - 1e-4) ~ 390; uncapped it fails."""
    capped, raw = NisMonitor(100, 1e-4, 3, cap=25.0), NisMonitor(100, 1e-4, 3)
    for mon in (capped, raw):
        mon.add(math.nan, 3)
        for _ in range(99):
            mon.add(3.0, 3)
        mon.add(1e8, 3)
    assert capped.last is not None and capped.last.nis_sum == pytest.approx(322.0) and not capped.last.failed
    assert raw.last is not None and raw.last.failed


def test_restart_drops_the_window_in_progress():
    m = NisMonitor(10, 1e-4, 3)
    for _ in range(5):
        m.add(100.0, 3)
    m.restart()
    for _ in range(10):
        m.add(3.0, 3)
    assert m.completed == 1 and m.last is not None and m.last.nis_sum == pytest.approx(30.0)


def test_clean_runs_stay_ok_and_a_wrong_noise_model_is_reported():
    """The catapult filter is consistent with its data: every output OK. Told the master is ten
    times better than it is (0.1 mm/s instead of 1 mm/s, with the 0.1 mm/s parked allowance), its
    NIS is ~50 times too large: ERROR, and the published view holds the last good estimate."""
    over = {'duration_s': 6.0, 'aircraft.catapult.launch_time_s': 4.0}
    good = pipeline.run(scenario.load('catapult_paper', over), keep_truth=False).filter
    assert all(e.level == OK for e in good.outputs) and good.healthy
    bad = pipeline.run(scenario.load('catapult_paper', {**over, 'filter.master_velocity_sigma_mps': 1e-4}),
                       keep_truth=False).filter
    assert not bad.healthy and 'inconsistent' in bad.failure
    err = [i for i, e in enumerate(bad.outputs) if e.level == ERROR]
    assert err and all(bad.outputs[i].level == ERROR for i in range(err[0], len(bad.outputs)))
    held = [e for e in bad.published[:err[0]] if e.level == OK][-1]       # the last at OK
    for e in bad.published[err[0]:]:
        assert 'held' in e.flags and np.array_equal(e.misalignment, held.misalignment)
