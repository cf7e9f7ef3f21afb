"""Strong tracking and fading-memory filters: recovery from a sudden bias jump, the delayed
fading of the prediction, the dimensional consistency of the multiple-factor STF, and the
innovation-tested factor of seed 003 (full and square-root forms, float64 and float32)."""
from __future__ import annotations

import numpy as np
import pytest
from support.filter_problems import random_linear_problem

from alignment_core.estimation.filters import (
    CarlsonFilter,
    FadingMemoryFilter,
    KalmanFilter,
    SqrtFadingFilter,
    StrongTrackingFilter,
)

# Random constant x observed directly, z = x + v, var(v) = 1, x jumps by DELTA at step K0.
K0, DELTA, TAU = 200, 20.0, 0.25     # jump after 200 updates, 20 sigma_v; threshold 0.25 DELTA = 5 sigma_v
HOLD = 20                            # "recovered": below the threshold for HOLD consecutive steps


def _recovery_steps(err: np.ndarray) -> int:
    """Steps after the jump until |err| < TAU DELTA holds for HOLD consecutive steps."""
    below = np.abs(err[K0:]) < TAU * DELTA
    for j in range(below.size - HOLD):
        if below[j:j + HOLD].all():
            return j + 1
    return below.size


def _jump_run(make, n_states, jump_state, seed, steps=1200):
    rng = np.random.default_rng(seed)
    x = rng.normal(0.0, 10.0, n_states)
    f = make()
    eye, zero = np.eye(n_states), np.zeros((n_states, n_states))
    err = np.empty(steps)
    for k in range(steps):
        if k == K0:
            x[jump_state] += DELTA
        f.predict(eye, zero)
        f.update(x + rng.standard_normal(n_states), eye, eye)
        err[k] = f.x[jump_state] - x[jump_state]
    return err


@pytest.mark.parametrize('seed', [0, 1, 2])
def test_stf_recovers_from_a_bias_jump_much_sooner_than_the_kf(seed):
    """KF: with Q = 0 the estimate is the running mean of all measurements (P0 = 100 >> R), so
    after the jump its error is DELTA K0 / k (+ noise of sigma 1/sqrt(k) ~ 0.04, negligible
    against the 5-sigma threshold): below TAU DELTA from k = K0 / TAU, i.e. K0 (1/TAU - 1) = 600
    steps after the jump.
    STF (rho = 0.95, beta = 2): at the first update after the jump V0 ~ DELTA^2 / (1 + rho) = 205,
    N = V0 - beta R ~ 203, M = P ~ 1/200, so lam ~ 4e4 and the gain ~ 203/204: the error drops to
    (1 - K) DELTA + K v ~ 0.1 + v, i.e. within one step (the threshold is 5 sigma_v). Expected
    recovery: KF 600 +- 5 %, STF <= 3 steps."""
    p0 = np.array([[100.0]])
    err_kf = _jump_run(lambda: KalmanFilter(np.zeros(1), p0), 1, 0, seed)
    err_stf = _jump_run(lambda: StrongTrackingFilter(np.zeros(1), p0, beta=2.0), 1, 0, seed)
    t_kf, t_stf = _recovery_steps(err_kf), _recovery_steps(err_stf)
    expected_kf = K0 * (1.0 / TAU - 1.0)
    assert abs(t_kf - expected_kf) < 0.05 * expected_kf
    assert t_stf <= 3
    assert t_kf > 100 * t_stf


@pytest.mark.parametrize('alpha', [None, (1.0, 1.0), (1.0, 4.0)], ids=['single', 'multiple 1,1', 'multiple 1,4'])
def test_stf_two_constants_jump_in_one(alpha):
    """Two independent constants observed directly, the second jumps. The same derivation per
    channel: the KF needs ~600 steps, the STF (single or multiple factors) ~1."""
    p0 = 100.0 * np.eye(2)
    err_kf = _jump_run(lambda: KalmanFilter(np.zeros(2), p0), 2, 1, 7)
    stf = []
    err_stf = _jump_run(lambda: stf.append(StrongTrackingFilter(np.zeros(2), p0, beta=2.0, alpha=alpha))
                        or stf[-1], 2, 1, 7)
    assert abs(_recovery_steps(err_kf) - 600) < 30
    assert _recovery_steps(err_stf) <= 3


def test_multiple_factors_follow_alpha_and_are_unit_invariant():
    """lam_i = max(1, alpha_i c): unclipped factors are in the ratio of the alphas. And c is a pure
    number: re-expressing the states in other units (x' = D x) and, with whiten=True, the
    measurement channels too (z' = E z) changes no factor, and the estimates transform as
    x' = D x, P' = D P D. (The paper's sum_i alpha_i M_ii, an n-term sum over an m x m matrix,
    cannot even be evaluated here.)"""
    rng = np.random.default_rng(11)
    n, m = 6, 3
    phi, qd, h, r, p0, x0 = random_linear_problem(rng, n, m)
    alpha = np.array([1.0, 1.0, 2.0, 3.0, 1.5, 1.0])
    d = np.diag([1e3, 1.0, 1e-4, 57.3, 1.0, 1e6])      # e.g. rad -> mrad, rad -> deg, ...
    e = np.diag([1e2, 1.0, 1e-3])
    di = np.linalg.inv(d)
    a = StrongTrackingFilter(x0, p0, beta=1.0, alpha=alpha, whiten=True)
    b = StrongTrackingFilter(d @ x0, d @ p0 @ d, beta=1.0, alpha=alpha, whiten=True)
    fired = 0
    for _ in range(40):
        a.predict(phi, qd)
        b.predict(d @ phi @ di, d @ qd @ d)
        z = h @ a.x + 3.0 * rng.standard_normal(m)       # inflated innovations: the factors fire
        a.update(z, h, r)
        b.update(e @ z, e @ h @ di, e @ r @ e)
        la, lb = a.diagnostics()['fading'], b.diagnostics()['fading']
        np.testing.assert_allclose(la, lb, rtol=1e-8)
        np.testing.assert_allclose(b.x, d @ a.x, rtol=1e-8, atol=1e-10 * np.abs(d @ a.x).max())
        np.testing.assert_allclose(b.P, d @ a.P @ d, rtol=1e-7, atol=1e-10 * np.abs(d @ a.P @ d).max())
        if np.all(la > 1.0):
            fired += 1
            np.testing.assert_allclose(la / la[0], alpha / alpha[0], rtol=1e-12)
    assert fired > 5


def test_delayed_fading_semantics():
    """Between predict and update P is the nominal prediction (what the KF has); the accepted
    update fades the part carried from the last update, P- = lam Phi_acc P+ Phi_acc^T + Q_acc,
    with Phi_acc and Q_acc over all predicts since; a gated measurement leaves everything,
    including the pending fading, untouched; reset_state() keeps it too."""
    rng = np.random.default_rng(12)
    n, m = 5, 2
    phi, qd, h, r, p0, x0 = random_linear_problem(rng, n, m)
    stf, kf = StrongTrackingFilter(x0, p0, beta=1.0), KalmanFilter(x0, p0)
    p_post = stf.P.copy()
    for _ in range(3):
        stf.predict(phi, qd)
        kf.predict(phi, qd)
        np.testing.assert_array_equal(stf.P, kf.P)
    phi_acc = phi @ phi @ phi
    carried = phi_acc @ p_post @ phi_acc.T
    q_acc = kf.P - carried
    res = stf.update(h @ stf.x + 1e6, h, r, gate_chi2=20.0)       # outlier: gated
    assert not res.accepted and stf.diagnostics()['gated'] == 1
    np.testing.assert_array_equal(stf.P, kf.P)
    stf.reset_state(stf.x.copy())
    s0 = h @ kf.P @ h.T + r
    z = h @ stf.x + 5.0 * np.sqrt(np.diag(s0))            # y^T y = 25 tr S0: lam = tr N / tr M > 1
    x_prior = stf.x.copy()
    res = stf.update(z, h, r, gate_chi2=1e9)
    assert res.accepted
    lam = stf.diagnostics()['fading']
    assert lam > 1.0
    # the single-factor formula, evaluated from its definition
    y = z - h @ x_prior
    v0 = np.outer(y, y)                                            # first update: V0 = y y^T
    mm = h @ carried @ h.T
    nn = v0 - r - h @ q_acc @ h.T
    assert lam == pytest.approx(np.trace(nn) / np.trace(mm), rel=1e-10)
    ref = KalmanFilter(x_prior, lam * carried + q_acc)
    ref.update(z, h, r)
    np.testing.assert_allclose(stf.x, ref.x, rtol=1e-10)
    np.testing.assert_allclose(stf.P, ref.P, rtol=1e-9, atol=1e-12)


def _innovation_test_reference(p_post, phis, qds, z, h, r, gamma):
    """Seed 003's rule from its definition: nominal prior P = Phi P Phi^T + Q (all steps), S0 = H P
    H^T + R; if y^T y > gamma tr S0 then lam = y^T y / tr S0, P- = lam Phi_acc P+ Phi_acc^T + Q_acc."""
    p, phi_acc = p_post, np.eye(p_post.shape[0])
    for phi, qd in zip(phis, qds):
        p = phi @ p @ phi.T + qd
        phi_acc = phi @ phi_acc
    carried = phi_acc @ p_post @ phi_acc.T
    return p, carried


@pytest.mark.parametrize('sqrt_form', [False, True], ids=['full', 'carlson'])
def test_innovation_tested_fading_matches_its_definition(sqrt_form):
    rng = np.random.default_rng(13)
    n, m = 7, 3
    phi, qd, h, r, p0, x0 = random_linear_problem(rng, n, m)
    gamma = 2.0
    f = SqrtFadingFilter(x0, p0, gamma=gamma) if sqrt_form else FadingMemoryFilter(x0, p0, gamma=gamma)
    fired = 0
    for k in range(30):
        p_post, x_post = f.P.copy(), f.x.copy()
        for _ in range(2):
            f.predict(phi, qd)
        p_nom, carried = _innovation_test_reference(p_post, [phi, phi], [qd, qd], None, h, r, gamma)
        x_prior = phi @ phi @ x_post
        z = h @ x_prior + (4.0 if k % 3 == 0 else 0.3) * rng.standard_normal(m)
        y = z - h @ x_prior
        s0 = h @ p_nom @ h.T + r
        lam = y @ y / np.trace(s0) if y @ y > gamma * np.trace(s0) else 1.0
        ref = KalmanFilter(x_prior, p_nom + (lam - 1.0) * carried)
        ref.update(z, h, r)
        f.update(z, h, r)
        assert f.diagnostics()['fading'] == pytest.approx(lam, rel=1e-10)
        fired += lam > 1.0
        np.testing.assert_allclose(f.x, ref.x, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(f.P, ref.P, rtol=1e-8, atol=1e-10)
    assert 5 <= fired < 30


def test_fixed_fading_memory_prediction():
    rng = np.random.default_rng(14)
    phi, qd, h, r, p0, x0 = random_linear_problem(rng, 4, 2)
    f = FadingMemoryFilter(x0, p0, lam=1.05)
    f.predict(phi, qd)
    np.testing.assert_allclose(f.P, 1.05 * phi @ p0 @ phi.T + qd, rtol=1e-14)


def test_combined_filter_float32_tracks_float64_through_a_jump():
    """The combined filter's fading path in single precision: same fading decisions, estimate and
    sigma within float32 round-off accumulated over a few hundred steps (1e-3 relative), the factor
    stays triangular with a positive diagonal."""
    rng = np.random.default_rng(15)
    n = 2
    x = np.array([1.0, -2.0])
    eye, q = np.eye(n), 1e-6 * np.eye(n)
    f64 = SqrtFadingFilter(np.zeros(n), 100.0 * eye, gamma=3.0)
    f32 = SqrtFadingFilter(np.zeros(n), 100.0 * eye, gamma=3.0, dtype=np.float32)
    c64 = CarlsonFilter(np.zeros(n), 100.0 * eye)
    fired = 0
    for k in range(400):
        if k == 200:
            x[1] += 20.0
        z = x + rng.standard_normal(n)
        for f in (f64, f32, c64):
            f.predict(eye, q)
            f.update(z, eye, eye)
        l64, l32 = f64.diagnostics()['fading'], f32.diagnostics()['fading']
        assert (l64 > 1.0) == (l32 > 1.0)
        fired += l64 > 1.0
        assert f32.x.dtype == np.float32 and f32.S.dtype == np.float32
        np.testing.assert_allclose(f32.x, f64.x, rtol=1e-3, atol=1e-3 * np.sqrt(f64.P.diagonal()).max())
        np.testing.assert_allclose(np.sqrt(f32.P.diagonal()), np.sqrt(f64.P.diagonal()), rtol=1e-3)
        assert np.all(np.diag(f32.S) > 0) and np.all(np.tril(f32.S, -1) == 0)
    assert fired >= 1
    # and the fading did its job: after the jump the combined filter is back on the constant
    assert abs(f64.x[1] - x[1]) < 1.0 < abs(c64.x[1] - x[1])
