"""Kalman filter against textbook identities and the closed-form posterior of a scalar
random constant."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core.estimation.filters.kalman import KalmanFilter


def random_spd(rng, n, scale=1.0):
    a = rng.standard_normal((n, n))
    return scale * (a @ a.T + n * np.eye(n))


@pytest.mark.parametrize('seed', [1, 2, 3])
def test_joseph_update_equals_textbook_form(seed):
    rng = np.random.default_rng(seed)
    n, m = 8, 3
    p0 = random_spd(rng, n)
    x0 = rng.standard_normal(n)
    h = rng.standard_normal((m, n))
    r = random_spd(rng, m, 0.1)
    z = rng.standard_normal(m)
    kf = KalmanFilter(x0, p0)
    res = kf.update(z, h, r)
    assert res.accepted
    # textbook: S = H P H^T + R, K = P H^T S^-1, x+ = x + K (z - H x), P+ = (I - K H) P
    s = h @ p0 @ h.T + r
    k = p0 @ h.T @ np.linalg.inv(s)
    y = z - h @ x0
    np.testing.assert_allclose(res.innovation, y, atol=1e-12)
    np.testing.assert_allclose(res.s, s, atol=1e-12)
    assert res.nis == pytest.approx(y @ np.linalg.solve(s, y), rel=1e-12)
    np.testing.assert_allclose(kf.x, x0 + k @ y, atol=1e-12)
    np.testing.assert_allclose(kf.P, (np.eye(n) - k @ h) @ p0, atol=1e-12)
    # information form: P+^-1 = P^-1 + H^T R^-1 H
    np.testing.assert_allclose(np.linalg.inv(kf.P), np.linalg.inv(p0) + h.T @ np.linalg.inv(r) @ h,
                               rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(kf.P, kf.P.T)
    assert np.all(np.linalg.eigvalsh(kf.P) > 0.0)


def test_predict_and_repeated_updates_stay_symmetric():
    rng = np.random.default_rng(4)
    n, m = 12, 3
    kf = KalmanFilter(np.zeros(n), random_spd(rng, n))
    phi = np.eye(n) + 0.01 * rng.standard_normal((n, n))
    q = random_spd(rng, n, 1e-4)
    h = np.hstack([np.zeros((m, 3)), np.eye(m), np.zeros((m, n - 6))])
    r = 1e-4 * np.eye(m)
    for _ in range(300):
        p_prev = kf.P.copy()
        kf.predict(phi, q)
        np.testing.assert_allclose(kf.P, phi @ p_prev @ phi.T + q, rtol=1e-12, atol=1e-14)
        kf.update(rng.standard_normal(m) * 1e-2, h, r)
        np.testing.assert_array_equal(kf.P, kf.P.T)
        assert np.linalg.eigvalsh(kf.P).min() > 0.0


def test_gate_rejects_without_changing_state():
    kf = KalmanFilter(np.zeros(2), np.eye(2))
    h = np.array([[1.0, 0.0]])
    r = np.array([[1.0]])
    res = kf.update(np.array([10.0]), h, r, gate_chi2=9.0)       # NIS = 100 / 2 = 50
    assert not res.accepted and res.nis == pytest.approx(50.0)
    np.testing.assert_array_equal(kf.x, 0.0)
    np.testing.assert_array_equal(kf.P, np.eye(2))
    res = kf.update(np.array([1.0]), h, r, gate_chi2=9.0)        # NIS = 0.5
    assert res.accepted


def test_scalar_random_constant_posterior():
    """x ~ N(0, p0), z_i = x + v_i with v_i ~ N(0, r): after n updates
    P_n = 1 / (1/p0 + n/r) and x_n = P_n * sum(z_i) / r (the Bayesian posterior)."""
    rng = np.random.default_rng(5)
    p0, r, n = 4.0, 0.25, 500
    x_true = rng.normal(0.0, np.sqrt(p0))
    z = x_true + rng.normal(0.0, np.sqrt(r), n)
    kf = KalmanFilter(np.zeros(1), np.array([[p0]]))
    for i in range(n):
        kf.predict(np.eye(1), np.zeros((1, 1)))
        kf.update(z[i:i + 1], np.eye(1), np.array([[r]]))
        p_i = 1.0 / (1.0 / p0 + (i + 1) / r)
        assert kf.P[0, 0] == pytest.approx(p_i, rel=1e-12)
        assert kf.x[0] == pytest.approx(p_i * z[:i + 1].sum() / r, rel=1e-9, abs=1e-12)
    # and the estimate is within 4 sigma of the truth
    assert abs(kf.x[0] - x_true) < 4.0 * np.sqrt(kf.P[0, 0])


def test_a_float32_filter_stays_float32_when_its_state_is_assigned_from_outside():
    """The engine assigns x after feedback and P for launch noise or a bridged gap, in float64:
    a float32 filter must keep computing in float32 (it ran with a float64 x before)."""
    kf = KalmanFilter(np.zeros(3), np.eye(3), dtype=np.float32)
    kf.x = np.array([1.0, 2.0, 3.0])
    kf.P = np.eye(3) * 2.0
    assert kf.x.dtype == np.float32 and kf.P.dtype == np.float32
    kf.predict(np.eye(3), np.eye(3) * 0.1)
    kf.update(np.array([1.0]), np.array([[1.0, 0.0, 0.0]]), np.array([[1.0]]))
    assert kf.x.dtype == np.float32 and kf.P.dtype == np.float32


def test_a_negative_nis_is_a_breakdown_not_an_accepted_update():
    """S = H P H^T + R not positive definite (here P with a negative variance) gives a negative
    NIS; the update must fail rather than be taken (and count as a small NIS)."""
    kf = KalmanFilter(np.zeros(2), np.diag([-4.0, 1.0]))
    with pytest.raises(np.linalg.LinAlgError):
        kf.update(np.array([1.0]), np.array([[1.0, 0.0]]), np.array([[1.0]]))
    assert kf.n_updates == 0 and np.array_equal(kf.x, np.zeros(2))


@pytest.mark.parametrize('dtype', [np.float64, np.float32])
def test_arrays_handed_out_or_given_are_never_changed_by_later_steps(dtype):
    """The filter steps x and P in place, copy on write: what `x` and `P` returned, and what was
    assigned to them, keep their values through later predicts and updates (accepted and gated),
    while the state moves as it does in a filter never read (stepped alongside, bit for bit)."""
    rng = np.random.default_rng(5)
    n, m = 6, 2
    phi = np.eye(n) + 0.05 * rng.standard_normal((n, n))
    qd = np.eye(n) * 1e-3
    h, r = rng.standard_normal((m, n)), np.eye(m) * 0.1
    x0, p0 = rng.standard_normal(n), random_spd(rng, n)
    zs = rng.standard_normal((8, m))
    read, unread = KalmanFilter(np.zeros(n), np.eye(n), dtype), KalmanFilter(x0, p0, dtype)
    given_x, given_p = np.array(x0, dtype=dtype), np.array(p0, dtype=dtype)
    read.x, read.P = given_x, given_p
    kept = []
    for k, z in enumerate(zs):
        for f in (read, unread):
            f.predict(phi, qd)
            f.update(z, h, r, gate_chi2=1e-9 if k == 3 else None)       # the fourth is gated
        x_out, p_out = read.x, read.P
        kept.append((x_out, x_out.copy(), p_out, p_out.copy()))
    assert read.n_gated == 1 and read.n_updates == len(zs) - 1
    for x_out, x_then, p_out, p_then in kept:
        assert np.array_equal(x_out, x_then) and np.array_equal(p_out, p_then)
    assert np.array_equal(given_x, np.array(x0, dtype=dtype)) and np.array_equal(given_p, np.array(p0, dtype=dtype))
    assert np.array_equal(read.x, unread.x) and np.array_equal(read.P, unread.P)
    assert not np.array_equal(read.P, kept[0][3])


def test_a_shallow_copy_steps_apart_from_its_original():
    """copy.copy shares x and P; stepping the copy leaves the original where a filter stepped
    alongside it is (neither is read before the end)."""
    import copy
    rng = np.random.default_rng(6)
    n = 4
    x0, p0 = rng.standard_normal(n), random_spd(rng, n)
    a, same = KalmanFilter(x0, p0), KalmanFilter(x0, p0)
    for f in (a, same):
        f.predict(np.eye(n), np.eye(n) * 0.1)
    b = copy.copy(a)
    b.predict(np.eye(n) * 0.9, np.eye(n) * 0.2)
    b.update(np.ones(1), np.ones((1, n)), np.eye(1))
    assert np.array_equal(a.x, same.x) and np.array_equal(a.P, same.P)
    assert not np.array_equal(b.P, same.P)


def test_an_adopted_state_is_stepped_in_place_and_a_foreign_one_is_refused():
    """adopt_x keeps the array it is given (the next predict writes into it: no copy) with the
    numbers an assignment gives; an array of another dtype or shape is refused."""
    rng = np.random.default_rng(4)
    phi = np.eye(4) + 0.01 * rng.standard_normal((4, 4))
    q = np.eye(4) * 1e-3
    a, b = KalmanFilter(np.zeros(4), np.eye(4)), KalmanFilter(np.zeros(4), np.eye(4))
    x = rng.standard_normal(4)
    mine = x.copy()
    a.adopt_x(mine)
    b.x = x.copy()
    a.predict(phi, q)
    b.predict(phi, q)
    assert a.x is mine and np.array_equal(a.x, b.x)
    with pytest.raises(ValueError, match='adopt_x'):
        a.adopt_x(x.astype(np.float32))
    with pytest.raises(ValueError, match='adopt_x'):
        a.adopt_x(np.zeros(5))
