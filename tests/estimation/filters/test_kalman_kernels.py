"""The compiled Kalman predict and update give their interpreted form's numbers bit for bit
(the same operations: numpy's BLAS and LAPACK calls, the Joseph form's loops), in float64,
float32 and the mixed float32 / float64 the engine's feedback makes; and the Joseph form,
evaluated in O(m n^2), is the textbook (I - K H) P (I - K H)^T + K R K^T for any gain K."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core.estimation.filters import kalman_kernels as kk
from alignment_core.estimation.filters.kalman import KalmanFilter

N, M = 15, 3


def _problem(rng, dtype_x=np.float64, dtype_p=np.float64, selecting=True):
    a = rng.standard_normal((N, N))
    p = (a @ a.T + np.eye(N) * rng.uniform(0.01, 10.0)).astype(dtype_p)
    x = rng.standard_normal(N).astype(dtype_x)
    h = np.zeros((M, N))
    h[:, 3:6] = np.eye(M)
    if not selecting:
        h[:, 12:15] = rng.standard_normal((M, M))
    dt = np.float32 if dtype_p == np.float32 else np.float64
    z = rng.standard_normal(M).astype(dt)
    r = np.diag(rng.uniform(1e-3, 1e-1, M)).astype(dt)
    return x, p, z, h.astype(dt), r


def _in_place(kernel, x, p, *rest) -> tuple:
    """What kernel returns, then the x and P it wrote (into copies of x and p)."""
    x, p = x.copy(), p.copy()
    out = kernel(x, p, *rest)
    return (*(() if out is None else out), x, p)


def _update(kernel, x, p, z, h, r, gate) -> tuple:
    """(y, S, nis, accepted, x+, P+) of one update kernel call, y and S in z - H x's and S's
    dtypes as the filter allocates them."""
    y, s = np.empty(z.shape, np.result_type(z, x)), np.empty(r.shape, np.result_type(p, r))
    nis, accepted, x_new, p_new = _in_place(kernel, x, p, z, h, r, gate, y, s)
    return y, s, nis, accepted, x_new, p_new


def _same(a, b) -> bool:
    return type(a) is type(b) and (a == b or (a != a and b != b)) if not isinstance(a, np.ndarray) else \
        a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


@pytest.mark.parametrize('selecting', [True, False])
@pytest.mark.parametrize('dtypes', [(np.float64, np.float64), (np.float32, np.float32), (np.float64, np.float32)])
def test_update_compiled_equals_interpreted(selecting, dtypes):
    rng = np.random.default_rng(7)
    for _ in range(200):
        args = _problem(rng, *dtypes, selecting=selecting)
        x, p, z, h, r = args
        for gate in (np.inf, 2.0):
            got = _update(kk.update, x, p, z, h, r, gate)
            want = _update(kk.update.py_func, x, p, z, h, r, gate)
            assert all(_same(a, b) for a, b in zip(got, want))
            y, s, *_ = got
            inn = kk.innovation(x, p, z, h, r)
            assert _same(y, inn[0]) and _same(s, inn[2])


@pytest.mark.parametrize('selecting', [True, False])
@pytest.mark.parametrize('dtypes', [(np.float64, np.float64), (np.float32, np.float32), (np.float64, np.float32)])
def test_innovation_compiled_equals_interpreted_and_a_selection_is_indexing(selecting, dtypes):
    """The fading filters' innovation; for a selecting H, P H^T, H x and H P H^T are P's columns,
    x's and P's entries exactly (the skipped cells are zeros)."""
    rng = np.random.default_rng(12)
    for _ in range(50):
        x, p, z, h, r = _problem(rng, *dtypes, selecting=selecting)
        got = kk.innovation(x, p, z, h, r)
        want = kk.innovation.py_func(x, p, z, h, r)
        assert all(_same(a, b) for a, b in zip(got, want))
        if selecting:
            y, ph, s = got
            assert np.array_equal(ph, p[:, 3:6]) and np.array_equal(s, p[3:6, 3:6] + r)
            assert np.array_equal(y, z - x[3:6])


@pytest.mark.parametrize('dtypes', [(np.float64, np.float64), (np.float32, np.float32), (np.float64, np.float32)])
def test_predict_compiled_equals_interpreted(dtypes):
    rng = np.random.default_rng(8)
    dt = dtypes[1]
    for _ in range(100):
        x, p, *_ = _problem(rng, *dtypes)
        phi = (np.eye(N) + 0.01 * rng.standard_normal((N, N))).astype(dt)
        qd = np.diag(rng.uniform(1e-8, 1e-6, N)).astype(dt)
        got, want = _in_place(kk.predict, x, p, phi, qd), _in_place(kk.predict.py_func, x, p, phi, qd)
        assert all(_same(a, b) for a, b in zip(got, want))


@pytest.mark.parametrize('dtypes', [(np.float64, np.float64), (np.float32, np.float32), (np.float64, np.float32)])
def test_joseph_compiled_equals_interpreted(dtypes):
    """The subclasses' update (fading, nonlinear) after they changed the prior."""
    rng = np.random.default_rng(6)
    for _ in range(100):
        x, p, z, h, r = _problem(rng, *dtypes, selecting=False)
        ph = kk.dot(p, h.T)
        s_inv = kk.inverse(kk.dot(h, ph) + r)
        y = z - kk.dot(h, x)
        got = _in_place(kk.joseph, x, p, ph, s_inv, y, h, r)
        want = _in_place(kk.joseph.py_func, x, p, ph, s_inv, y, h, r)
        assert all(_same(a, b) for a, b in zip(got, want))


def test_the_filter_equals_the_textbook_update_it_replaced():
    """The Joseph form written out with numpy's @ and inv, selecting and full H: the same to
    rounding, which for matrix products is bounded relative to the matrix's norm, not to each
    element (the bit-for-bit checks are the compiled-against-interpreted ones above)."""
    rng = np.random.default_rng(9)
    for selecting in (True, False):
        x, p, z, h, r = _problem(rng, selecting=selecting)
        eye = np.eye(N)
        kf = KalmanFilter(x, p)
        kf.update(z, h, r)
        s = h @ p @ h.T + r
        s_inv = np.linalg.inv(s)
        k = p @ h.T @ s_inv
        ikh = eye - k @ h
        a = ikh @ p @ ikh.T + k @ r @ k.T
        want = a + a.T
        want *= 0.5
        assert np.allclose(kf.x, x + k @ (z - h @ x), rtol=1e-13, atol=1e-15)
        np.testing.assert_allclose(kf.P, want, rtol=0.0, atol=1e-13 * np.abs(want).max())


@pytest.mark.parametrize('m', [1, 3, 6])
def test_the_joseph_form_holds_for_any_gain(m):
    """The Joseph form's point: (I - K H) P (I - K H)^T + K R K^T is the covariance of the
    updated error for any gain K, not only the optimal one. The kernel's O(m n^2) evaluation,
    given ph and S^-1 whose product is a perturbed gain, against the dense products written out
    (in float64 to 1e-13 of |P|; in float32 to its own rounding, 1e-5 of |P|), for dense and
    for sparse (selecting) H."""
    rng = np.random.default_rng(11)
    for dense in (True, False):
        a = rng.standard_normal((N, N))
        p = a @ a.T + np.eye(N)
        h = rng.standard_normal((m, N)) if dense else np.eye(N)[rng.choice(N, m, replace=False)]
        r = np.diag(rng.uniform(0.1, 1.0, m))
        s_inv = np.linalg.inv(h @ p @ h.T + r)
        ph = p @ h.T * (1.0 + 0.3 * rng.standard_normal((N, m)))       # K = ph S^-1, not optimal
        x, y = rng.standard_normal(N), rng.standard_normal(m)
        k = ph @ s_inv
        ikh = np.eye(N) - k @ h
        want = ikh @ p @ ikh.T + k @ r @ k.T
        want = 0.5 * (want + want.T)
        x_new, p_new = _in_place(kk.joseph, x, p, ph, s_inv, y, h, r)
        np.testing.assert_allclose(x_new, x + k @ y, rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(p_new, want, rtol=0.0, atol=1e-13 * np.abs(want).max())
        f32 = [v.astype(np.float32) for v in (x, p, ph, s_inv, y, h, r)]
        _, p32 = _in_place(kk.joseph, *f32)
        assert p32.dtype == np.float32
        np.testing.assert_allclose(p32, want, rtol=0.0, atol=1e-5 * np.abs(want).max())


def test_a_scalar_measurement_is_one_row():
    """numpy broadcast a scalar z against a (1, n) H; the filter still takes it."""
    x, p = np.zeros(3), np.eye(3)
    a, b = KalmanFilter(x, p), KalmanFilter(x, p)
    h, r = np.array([[1.0, 0.0, 0.0]]), np.array([[1.0]])
    a.update(np.float64(1.0), h, r)
    b.update(np.array([1.0]), h, r)
    assert np.array_equal(a.x, b.x) and np.array_equal(a.P, b.P) and a.x[0] == 0.5


def test_a_non_finite_s_is_not_accepted_and_a_singular_one_raises():
    rng = np.random.default_rng(10)
    x, p, z, h, r = _problem(rng, selecting=False)
    bad = r.copy()
    bad[0, 0] = np.nan
    y, s, nis, accepted, x1, p1 = _update(kk.update, x, p, z, h, bad, np.inf)
    assert np.isnan(nis) and not accepted and np.array_equal(x1, x) and np.array_equal(p1, p)
    assert np.isnan(s[0, 0]) and np.allclose(y, z - h @ x, rtol=1e-14, atol=1e-14)
    kf = KalmanFilter(x, p)
    with pytest.raises(np.linalg.LinAlgError):
        kf.update(z, np.zeros_like(h), np.zeros_like(r))      # S = 0: singular
    assert kf.n_updates == 0 and np.array_equal(kf.x, x) and np.array_equal(kf.P, p)


@pytest.mark.parametrize('compiled', [True, False])
@pytest.mark.parametrize('bad', ['h_rows', 'r', 'z'])
def test_measurement_sizes_that_do_not_agree_are_refused_before_any_write(bad, compiled):
    """An H of other rows, an R of another size or a z of another length than the y and S the
    filter allocated: ValueError, with x, P, y and S untouched (the kernel reads no memory
    beyond its arrays)."""
    rng = np.random.default_rng(11)
    x, p, z, h, r = _problem(rng, selecting=False)
    y, s = np.full(3, 7.0), np.full((3, 3), 7.0)
    if bad == 'h_rows':
        h = h[:2]
    elif bad == 'r':
        r = np.ascontiguousarray(r[:2, :2])
    else:
        z = z[:2]
    x1, p1 = x.copy(), p.copy()
    with pytest.raises(ValueError, match='measurement size'):
        (kk.update if compiled else kk.update.py_func)(x1, p1, z, h, r, np.inf, y, s)
    assert np.array_equal(x1, x) and np.array_equal(p1, p)
    assert np.all(y == 7.0) and np.all(s == 7.0)
