"""The experiments score a misalignment estimate against the truth at its time of validity (its
stamp less the master latency the filter is told), not at its stamp (docs/carrier.md)."""
from __future__ import annotations

import numpy as np

from alignment_core.estimation.outputs import Estimate
from alignment_experiments.monte_carlo import misalignment_errors

MS = 1_000_000
W_RADPS = 3.0e-3          # the gear's roll rate relative to the deck (docs/carrier.md), rad/s
LAT_NS = 30 * MS          # the carrier master's transport latency


def _truth(t_ns: np.ndarray) -> np.ndarray:
    """A relative attitude turning at a constant rate about x: rel(t) = W t x."""
    rel = np.zeros((len(t_ns), 3))
    rel[:, 0] = W_RADPS * t_ns * 1e-9
    return rel


def _estimate(t_ns: int, mu: np.ndarray, t_valid_ns: int | None) -> Estimate:
    z = np.zeros(3)
    return Estimate(t_ns=t_ns, misalignment=mu, misalignment_sigma=np.full(3, 1e-4), q_nb=np.array([0, 0, 0, 1.0]),
                    attitude_cov=np.eye(3), x=z, sigma=z, bias_gyro=z, bias_accel=z, nis=1.0, updates=1,
                    matching=True, t_valid_ns=t_valid_ns)


def test_an_exact_estimate_under_a_latency_scores_zero_not_the_rate_times_the_latency():
    """Truth at 100 Hz; estimates stamped t = t_v + 30 ms, each the exact relative attitude at
    its validity time t_v. Scored at t_v the error is zero; scored at the stamp it would be
    -W x 30 ms = -0.31' (the rotation in between), which this scorer must not report."""
    truth_t = np.arange(0, 20_000 * MS, 10 * MS, dtype=np.int64)
    rel = _truth(truth_t)
    t_v = np.arange(1_000 * MS, 19_000 * MS, 100 * MS, dtype=np.int64)
    est = [_estimate(int(t) + LAT_NS, _truth(np.array([t]))[0], int(t)) for t in t_v]
    err, sig = misalignment_errors(est, truth_t, rel)
    np.testing.assert_array_equal(err, np.zeros_like(err))
    np.testing.assert_array_equal(sig, np.full((len(est), 3), 1e-4))
    # the same estimates scored at their stamps: the closed-form rate x latency
    at_stamp = [_estimate(e.t_ns, e.misalignment, None) for e in est]
    err_s, _ = misalignment_errors(at_stamp, truth_t, rel)
    np.testing.assert_allclose(err_s[:, 0], -W_RADPS * LAT_NS * 1e-9, rtol=1e-9)


def test_without_latency_validity_is_the_stamp_and_the_score_is_unchanged():
    """t_valid = t_ns (no latency told) and an estimate without t_valid_ns both take the first
    truth sample at or after the stamp, as the scorer always did (off the grid: the next one)."""
    truth_t = np.arange(0, 2_000 * MS, 10 * MS, dtype=np.int64)
    rel = _truth(truth_t)
    mu = np.array([1e-3, -2e-3, 5e-3])
    for t in (500 * MS, 503 * MS):
        k = int(np.searchsorted(truth_t, t))
        for tv in (t, None):
            err, _ = misalignment_errors([_estimate(t, mu, tv)], truth_t, rel)
            np.testing.assert_array_equal(err[0], mu - rel[k])
