"""The Kalman filter's predict and Joseph-form update as compiled kernels (compiled.py).

One call replaces about twenty numpy calls. The products with H run over H's non-zero cells
(measurement matrices are sparse: a selection, a skew block) and the Joseph form in O(m n^2)
(joseph); the predict's n x n products, the gain and the inverse of S are BLAS and LAPACK calls.
`dot` and `inverse` are numpy's np.dot and base.inv when interpreted; compiled, they call the
same routines with the same types (numba's own np.dot takes one dtype, and np.linalg.solve
interpreted would solve a float32 S in float64), so compiled and interpreted give the same
numbers bit for bit.

Shapes: x (n,), P (n, n), z (m,), H (m, n), R (m, m). Arrays are float64 or float32; mixed
operands are promoted as numpy would (`dot`); loops accumulate in P's dtype (H x in x's)."""
from __future__ import annotations

import numpy as np

from alignment_core.compiled import kernel, on_numba
from alignment_core.estimation.filters.base import inv


def dot(a, b):
    """np.dot with numpy's type promotion (numba's np.dot takes one dtype only): a float32 and
    a float64 operand are multiplied in float64, as numpy casts them before calling BLAS."""
    return np.dot(a, b)


def _dot_typed(a, b):
    """dot's compiled form for the operand types a, b (numba types)."""
    if a.dtype == b.dtype:
        return lambda a, b: np.dot(a, b)
    return lambda a, b: np.dot(a.astype(np.float64), b.astype(np.float64))


def inverse(s):
    """S^-1 in S's own precision: LAPACK's gesv against the identity (base.inv)."""
    return inv(s)


def _inverse_typed(s):
    """inverse's compiled form."""
    def solve_identity(s):
        eye_m = np.zeros_like(s)
        for j in range(s.shape[0]):
            eye_m[j, j] = 1.0
        return np.ascontiguousarray(np.linalg.solve(s, eye_m))   # base.inv returns C order
    return solve_identity


@on_numba
def _overloads() -> None:
    from numba.extending import overload
    overload(dot)(_dot_typed)
    overload(inverse)(_inverse_typed)


@kernel
def predict(x, p, phi, qd):
    """x <- Phi x, P <- Phi P Phi^T + Qd, in place."""
    x[:] = dot(phi, x)
    pp = dot(dot(phi, p), phi.T)
    n = p.shape[0]
    for i in range(n):                 # p[:] = pp + qd without the temporary
        for j in range(n):
            p[i, j] = pp[i, j] + qd[i, j]


@kernel
def products(x, p, h):
    """(H x, P H^T, H P H^T) over H's non-zero cells only (a selecting H, e.g. velocity
    matching's [0 I 0], costs a copy of P's columns)."""
    n = x.shape[0]
    m = h.shape[0]
    ph = np.zeros((n, m), p.dtype)
    hx = np.zeros(m, x.dtype)
    for j in range(m):
        for l in range(n):
            v = h[j, l]
            if v != 0.0:
                hx[j] += v * x[l]
                for i in range(n):
                    ph[i, j] += p[i, l] * v
    hph = np.zeros((m, m), p.dtype)
    for j in range(m):
        for l in range(n):
            v = h[j, l]
            if v != 0.0:
                for c in range(m):
                    hph[j, c] += v * ph[l, c]
    return hx, ph, hph


@kernel
def innovation(x, p, z, h, r):
    """(y = z - H x, P H^T, S = H P H^T + R) (`products`)."""
    hx, ph, hph = products(x, p, h)
    return z - hx, ph, hph + r


@kernel
def update(x, p, z, h, r, gate, y, s):
    """One measurement update: y <- z - H x and S <- H P H^T + R, written into the caller's
    arrays (of z - H x's and S's dtypes: a kernel's returned array costs more to hand back than
    it costs to allocate in Python); returns (nis, accepted), x <- x+ and P <- P+ in place if
    accepted. Not accepted when nis > gate, when S is not finite (nis is then NaN) or when
    nis < 0 (S not positive definite: the caller raises). A singular S raises
    np.linalg.LinAlgError, shapes that do not agree ValueError; x and P are unchanged unless
    accepted."""
    m = y.shape[0]
    if z.shape[0] != m or h.shape[0] != m or h.shape[1] != x.shape[0] or r.shape[0] != m or r.shape[1] != m \
            or s.shape[0] != m or s.shape[1] != m:
        raise ValueError('update: z, H, R, y and S must agree in the measurement size')
    hx, ph, hph = products(x, p, h)
    finite = True
    for i in range(m):                 # y[:] = z - hx and s[:] = hph + r, element by element
        y[i] = z[i] - hx[i]
        for j in range(m):
            s[i, j] = hph[i, j] + r[i, j]
            if not -np.inf < s[i, j] < np.inf:
                finite = False
    if not finite:
        return np.nan, False
    s_inv = inverse(s)
    nis = float(dot(dot(y, s_inv), y))
    if not 0.0 <= nis < np.inf or nis > gate:
        return nis, False
    joseph(x, p, ph, s_inv, y, h, r)
    return nis, True


@kernel
def joseph(x, p, ph, s_inv, y, h, r):
    """In place: x <- x + K y, P <- sym((I - K H) P (I - K H)^T + K R K^T) with K = P H^T S^-1;
    ph = P H^T, sym(A) = (A + A^T) / 2. The Joseph form is evaluated in O(m n^2), without the
    n x n products of I - K H: A = (I - K H) P = P - K (H P), then
    A (I - K H)^T + K R K^T = A + (K R - A H^T) K^T; H's zero cells are skipped (a selecting
    H costs a copy of its rows). Every element is accumulated in P's dtype."""
    k = dot(ph, s_inv)
    ky = dot(k, y)
    n = p.shape[0]
    m = h.shape[0]
    for i in range(n):                             # x[:] = x + K y
        x[i] = x[i] + ky[i]
    kt = np.ascontiguousarray(k.T)                 # (m, n)
    hp = np.zeros((m, n), p.dtype)                 # H P
    for j in range(m):
        for l in range(n):
            v = h[j, l]
            if v != 0.0:
                for c in range(n):
                    hp[j, c] += v * p[l, c]
    a = p                                          # P - K (H P), in place: H P is taken
    for i in range(n):
        for j in range(m):
            v = kt[j, i]
            for c in range(n):
                a[i, c] -= v * hp[j, c]
    d = dot(k, r)                                  # K R - A H^T (n, m)
    for j in range(m):
        for l in range(n):
            v = h[j, l]
            if v != 0.0:
                for i in range(n):
                    d[i, j] -= a[i, l] * v
    for i in range(n):                             # A + D K^T
        for j in range(m):
            v = d[i, j]
            for c in range(n):
                a[i, c] += v * kt[j, c]
    for i in range(n):                             # P = (A + A^T) / 2 in place, each pair read before written
        for c in range(i, n):
            v = (a[i, c] + a[c, i]) * 0.5
            p[i, c] = v
            p[c, i] = v
