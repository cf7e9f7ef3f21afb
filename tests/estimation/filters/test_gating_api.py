"""Common interface of the bank: chi-square gating (rejected and counted, nothing changes),
reset_state() for closed-loop feedback, assignable P, diagnostics, the float32 mode's dtype."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2
from support.filter_problems import random_linear_problem

from alignment_core.estimation.filters import (
    CarlsonFilter,
    CubatureKalmanFilter,
    ExtendedKalmanFilter,
    FadingMemoryFilter,
    Filter,
    KalmanFilter,
    NonlinearFilter,
    SqrtFadingFilter,
    StrongTrackingFilter,
    UDFilter,
    UnscentedKalmanFilter,
)

MAKERS = {
    'kf': KalmanFilter,
    'fading': lambda x, p: FadingMemoryFilter(x, p, lam=1.02),
    'fading tested': lambda x, p: FadingMemoryFilter(x, p, gamma=3.0),
    'stf': StrongTrackingFilter,
    'stf multiple': lambda x, p: StrongTrackingFilter(x, p, alpha=np.arange(1.0, 1.0 + x.size)),
    'carlson': CarlsonFilter,
    'ud': UDFilter,
    'combined': lambda x, p: SqrtFadingFilter(x, p, gamma=3.0),
    'ekf': ExtendedKalmanFilter,
    'ukf': UnscentedKalmanFilter,
    'ckf': CubatureKalmanFilter,
}
NONLINEAR = ('ekf', 'ukf', 'ckf')
GATE = float(chi2.ppf(0.999, 3))      # 16.27 for m = 3


def _setup(name, seed=0):
    rng = np.random.default_rng(seed)
    phi, qd, h, r, p0, x0 = random_linear_problem(rng, 6, 3)
    f = MAKERS[name](x0, p0)
    f.predict(phi, qd)
    return f, h, r


def _update(f, name, z, h, r, gate, nonlinear):
    if nonlinear:
        return f.update_nonlinear(z, lambda x: h @ x, r, gate_chi2=gate)
    return f.update(z, h, r, gate_chi2=gate)


@pytest.mark.parametrize('name,nonlinear', [(k, False) for k in MAKERS] + [(k, True) for k in NONLINEAR])
def test_gate_rejects_outlier_counts_it_and_accepts_normal(name, nonlinear):
    """y = 100 sqrt(lambda_max(S)) v_max: NIS = y^T S^-1 y = 1e4 >> chi2_3(0.999) = 16.3; a zero
    innovation has NIS 0."""
    f, h, r = _setup(name)
    x0, p0 = f.x.copy(), f.P.copy()
    s = h @ p0 @ h.T + r
    w, v = np.linalg.eigh(s)
    z_out = h @ x0 + 100.0 * np.sqrt(w[-1]) * v[:, -1]
    res = _update(f, name, z_out, h, r, GATE, nonlinear)
    assert not res.accepted
    assert res.nis == pytest.approx(1e4, rel=1e-6)
    np.testing.assert_allclose(res.s, s, rtol=1e-12)
    np.testing.assert_array_equal(f.x, x0)
    np.testing.assert_allclose(f.P, p0, rtol=1e-13, atol=1e-15)
    d = f.diagnostics()
    assert d['gated'] == 1 and d['updates'] == 0 and d['nis'] == pytest.approx(1e4, rel=1e-6)
    res = _update(f, name, h @ x0, h, r, GATE, nonlinear)
    assert res.accepted and res.nis == pytest.approx(0.0, abs=1e-20)
    d = f.diagnostics()
    assert d['gated'] == 1 and d['updates'] == 1 and d['predicts'] == 1
    # without a gate the same outlier is used
    res = _update(f, name, z_out, h, r, None, nonlinear)
    assert res.accepted and f.diagnostics()['gated'] == 1


@pytest.mark.parametrize('name', list(MAKERS))
def test_interface_reset_state_and_assignable_p(name):
    f, h, r = _setup(name, seed=1)
    assert isinstance(f, Filter)
    assert isinstance(f, NonlinearFilter) == (name in NONLINEAR)
    f.update(np.ones(3), h, r)
    p = f.P.copy()
    f.reset_state()                                   # feedback: x <- 0, covariance untouched
    np.testing.assert_array_equal(f.x, 0.0)
    np.testing.assert_allclose(f.P, p, rtol=1e-14, atol=1e-16)
    f.reset_state(np.arange(6.0))
    np.testing.assert_array_equal(f.x, np.arange(6.0))
    p_new = np.diag(np.arange(1.0, 7.0))
    f.P = p_new                                      # a factored filter re-factors
    np.testing.assert_allclose(f.P, p_new, rtol=1e-14, atol=1e-15)
    f.predict(np.eye(6), np.zeros((6, 6)))           # (the fixed-factor fading filter fades by lam)
    np.testing.assert_allclose(f.P, getattr(f, 'lam', 1.0) * p_new, rtol=1e-14, atol=1e-15)


@pytest.mark.parametrize('cls', [KalmanFilter, CarlsonFilter, UDFilter, SqrtFadingFilter,
                                 FadingMemoryFilter, StrongTrackingFilter])
def test_float32_mode_keeps_every_array_in_float32(cls):
    rng = np.random.default_rng(2)
    phi, qd, h, r, p0, x0 = random_linear_problem(rng, 6, 3)
    kw = {'gamma': 1.0} if cls in (SqrtFadingFilter,) else {}
    f = cls(x0, p0, dtype=np.float32, **kw)
    for k in range(5):
        f.predict(phi, qd)
        res = f.update(h @ f.x + (3.0 if k % 2 else 0.1) * rng.standard_normal(3), h, r)
    assert res.innovation.dtype == np.float32 and res.s.dtype == np.float32
    arrays = {k: v for k, v in vars(f).items() if isinstance(v, np.ndarray)}
    assert arrays
    for k, v in arrays.items():
        if v.dtype.kind == 'f':
            assert v.dtype == np.float32, k
    assert f.x.dtype == np.float32 and f.P.dtype == np.float32
