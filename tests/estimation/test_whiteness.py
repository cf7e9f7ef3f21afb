"""Innovation whiteness (estimation/whiteness.py): the Ljung-Box test over windows of normalised
innovations. A white sequence fails at the chosen rate; a correlated one fails; in the engine,
a master latency the filter does not model fails it while the matched filter passes."""
from __future__ import annotations

import math

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.whiteness import InnovationWhiteness, ljung_box


def test_autocorrelation_of_a_cosine_is_the_cosine_of_the_lag():
    """For e_t = cos(w t) over many periods, r_k -> cos(w k) (the mean product over the mean square)."""
    w = 2 * math.pi / 37.0
    e = np.cos(w * np.arange(37 * 200))[:, None]
    _, r = ljung_box(e, 5)
    np.testing.assert_allclose(r[:, 0], np.cos(w * np.arange(1, 6)), atol=2e-3)


def test_a_white_sequence_fails_at_the_chosen_rate():
    """Q of a white sequence is chi2(m K): with p = 0.01, 400 windows fail about 4 times
    (binomial sd 2.0); the lag-1 autocorrelation stays mostly inside +-1.96/sqrt(N)."""
    rng = np.random.default_rng(5)
    w = InnovationWhiteness(500, 10, 0.01)
    for e in rng.standard_normal((400 * 500, 3)):
        w.add(e, np.eye(3))
    assert w.completed == 400 and w.failures <= 4 + 4 * 2.0
    assert w.last is not None and w.last.dof == 30 and w.last.band == pytest.approx(1.96 / math.sqrt(500))


def test_a_correlated_sequence_fails_and_s_normalises():
    """AR(1) with rho 0.3 (r_1 = 0.3, far outside the white band 0.088): every window fails;
    the innovation covariance S only scales the rows (the statistic is scale-free)."""
    rng = np.random.default_rng(6)
    w = InnovationWhiteness(500, 10, 1e-3)
    x = np.zeros(3)
    for n in rng.standard_normal((5 * 500, 3)):
        x = 0.3 * x + n
        w.add(100.0 * x, np.eye(3) * 1e4)
    assert w.completed == w.failures == 5
    assert w.last is not None and abs(w.last.r1_max - 0.3) < 0.1


def test_a_change_of_rows_restarts_the_window():
    w = InnovationWhiteness(20, 2, 0.01)
    for _ in range(15):
        w.add(np.ones(3), np.eye(3))
    for _ in range(19):
        w.add(np.ones(6), np.eye(6))
    assert w.completed == 0
    with pytest.raises(ValueError):
        InnovationWhiteness(20, 10, 0.01)


def _run(latency_s: float, known: bool):
    ov = {'duration_s': 40.0, 'master.latency_s': latency_s}
    if known:
        ov['filter.master_latency_s'] = latency_s
    sc = scenario.load('deck_paper', overrides=ov)
    return pipeline.align(sc, pipeline.simulate(sc))


def test_an_unmodelled_master_latency_fails_whiteness_the_matched_filter_passes():
    """20 ms of master latency: told to the filter, the innovations are white (no window of 7
    fails at p 1e-3); not told, the innovation follows the deck acceleration times 20 ms
    (~4 mm/s against 1 mm/s of noise), strongly correlated: every window fails."""
    matched = _run(0.02, known=True)
    assert matched.whiteness.completed == 7 and matched.whiteness.failures == 0
    assert matched.diagnostics().whiteness['whiteness'] == 'pass'
    lag = _run(0.02, known=False)
    assert lag.whiteness.completed == lag.whiteness.failures == 7
    assert lag.diagnostics().whiteness['whiteness'] == 'fail'


def test_whiteness_sees_a_latency_the_nis_monitor_cannot():
    """1 ms unknown: ~0.2 mm/s of smooth innovation against 1 mm/s of white noise moves the NIS
    by ~4 % (no NIS window fails) but correlates the innovations: windows fail whiteness."""
    f = _run(0.001, known=False)
    assert f.counters.consistency_failures == 0
    assert f.whiteness.failures >= 2


def test_without_history_the_windows_are_counted_but_not_kept():
    """A node's engine (keep_history False) keeps no window: its memory does not grow with the run."""
    rng = np.random.default_rng(3)
    kept, bounded = InnovationWhiteness(20, 2, 0.01), InnovationWhiteness(20, 2, 0.01, keep_history=False)
    for n in rng.standard_normal((60, 3)):
        kept.add(n, np.eye(3))
        bounded.add(n, np.eye(3))
    assert kept.completed == bounded.completed == 3 and len(kept.history) == 3
    assert bounded.history == [] and bounded.last == kept.last


@pytest.mark.parametrize('dtype', [np.float64, np.float32])
def test_the_normalised_innovation_is_numpys_and_refuses_bad_rows(dtype):
    """e = y / sqrt(diag S) bit for bit as numpy computes it (the root in S's precision), compiled
    and interpreted; a non-finite innovation or a variance that is not positive is refused."""
    from alignment_core.estimation.whiteness import normalised
    rng = np.random.default_rng(2)
    for _ in range(200):
        y = rng.standard_normal(3) * 10.0 ** rng.uniform(-6, 3)
        a = rng.standard_normal((3, 3))
        s = (a @ a.T + np.eye(3) * 1e-3).astype(dtype)
        want = y / np.sqrt(s.diagonal())
        for fun in (normalised, normalised.py_func):
            ok, e = fun(y, s)
            assert ok and e.dtype == np.float64 and np.array_equal(e, want)
    s = np.eye(3, dtype=dtype)
    for bad_y in (np.nan, np.inf):
        assert not normalised(np.array([0.0, bad_y, 1.0]), s)[0]
    for bad_v in (0.0, -1.0, np.nan):
        sb = s.copy()
        sb[2, 2] = bad_v
        assert not normalised(np.ones(3), sb)[0]
        assert InnovationWhiteness(20, 3, 0.01).add(np.ones(3), sb) is None
