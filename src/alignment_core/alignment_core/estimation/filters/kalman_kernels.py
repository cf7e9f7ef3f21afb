"""The Kalman filter's predict and Joseph-form update as compiled kernels (compiled.py).

They are the operations KalmanFilter ran in numpy, in the same order, through the same BLAS and
LAPACK routines, so the numbers are unchanged bit for bit; one call replaces about twenty numpy
calls. `dot` and `inverse` are numpy's np.dot and base.inv when interpreted; compiled, they call
the same routines with the same types (numba's own np.dot takes one dtype, and np.linalg.solve
interpreted would solve a float32 S in float64).

Shapes: x (n,), P (n, n), z (m,), H (m, n), R (m, m), sel (m,) int64 or (0,) (see update).
Arrays are float64 or float32; mixed operands are promoted as numpy would (`dot`)."""
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
    """(Phi x, Phi P Phi^T + Qd)."""
    return dot(phi, x), dot(dot(phi, p), phi.T) + qd


@kernel
def update(x, p, z, h, r, sel, gate, eye):
    """One measurement update: (y, S, nis, accepted, x+, P+); eye: the filter's identity (n, n).

    sel: the state indices H selects when every row of H is a unit row (then P H^T, H x and
    H P H^T are taken by indexing: the products would only add exact zeros), else empty.
    Not accepted (x+, P+ are x, P) when nis > gate, or when S is not finite (nis is then NaN).
    A singular S raises np.linalg.LinAlgError."""
    n = x.shape[0]
    m = z.shape[0]
    if sel.shape[0] == m:
        ph = np.empty((n, m), p.dtype)
        for i in range(n):
            for j in range(m):
                ph[i, j] = p[i, sel[j]]
        hx = np.empty(m, x.dtype)
        hph = np.empty((m, m), p.dtype)
        for j in range(m):
            hx[j] = x[sel[j]]
            for k in range(m):
                hph[j, k] = ph[sel[j], k]
    else:
        ph = dot(p, h.T)
        hx = dot(h, x)
        hph = dot(h, ph)
    y = z - hx
    s = hph + r
    if not np.all(np.isfinite(s)):
        return y, s, np.nan, False, x, p
    s_inv = inverse(s)
    nis = float(dot(dot(y, s_inv), y))
    if not nis < np.inf or nis > gate:
        return y, s, nis, False, x, p
    x_new, p_new = joseph(x, p, ph, s_inv, y, h, r, eye)
    return y, s, nis, True, x_new, p_new


@kernel
def joseph(x, p, ph, s_inv, y, h, r, eye):
    """(x + K y, sym((I - K H) P (I - K H)^T + K R K^T)) with K = P H^T S^-1; ph = P H^T,
    sym(A) = (A + A^T) / 2."""
    k = dot(ph, s_inv)
    x_new = x + dot(k, y)
    ikh = eye - dot(k, h)
    a = dot(dot(ikh, p), ikh.T) + dot(dot(k, r), k.T)
    p_new = a + a.T
    p_new *= 0.5
    return x_new, p_new


NO_SELECTION = np.zeros(0, np.int64)
