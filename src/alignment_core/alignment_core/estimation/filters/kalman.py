"""Linear Kalman filter with the Joseph-form covariance update."""
from __future__ import annotations

import math

import numpy as np

from alignment_core.estimation.filters import kalman_kernels as kernels
from alignment_core.estimation.filters.base import Counters, UpdateResult, as_dtype, check_nis

__all__ = ['KalmanFilter', 'UpdateResult']

_INF = float('inf')


_NDARRAY = np.ndarray
_empty = np.empty


def _ready(a, dtype: np.dtype) -> np.ndarray:
    """a in dtype, in one block of memory (C or Fortran order): a kernel's BLAS call would copy
    any other layout itself, with a performance warning. The methods test the usual case (the
    first line) inline before calling it: the call costs as much as the test."""
    if type(a) is _NDARRAY and (a.dtype is dtype or a.dtype == dtype) and a.flags.c_contiguous:     # the usual case
        return a
    a = as_dtype(a, dtype)
    flags = a.flags
    return a if flags.c_contiguous or flags.f_contiguous else np.ascontiguousarray(a)


class KalmanFilter(Counters):
    """x (n,), P (n, n). predict(Phi, Qd); update(z, H, R) in Joseph form (P stays SPD).

    dtype: float64 (default) or float32; in float32 every internal array and every operation
    (matrix products, the inverse of S) is single precision.

    Speed: predict and update run as compiled kernels (kalman_kernels.py): the products with H
    over its non-zero cells only, the Joseph form in O(m n^2) operations instead of O(n^3).
    They write x and P in place, copy on write: an array the filter has handed out (read as
    `x` or `P`) or been given (assigned) is never changed by it; the next step first copies it.
    The one exception is an array given to `adopt_x`, which the caller gives up.
    A filter stepped without being read allocates nothing for x and P, and a kernel's returned
    array costs more than its arithmetic at this size (numba builds a Python object for it)."""

    def __init__(self, x0: np.ndarray, p0: np.ndarray, dtype=np.float64) -> None:
        self.dtype = np.dtype(dtype)
        self._x = np.array(x0, dtype=self.dtype)
        self._P = np.array(p0, dtype=self.dtype)
        self._x_out = self._p_out = False         # handed out or given: copy before writing
        self._init_counters()

    @property
    def x(self) -> np.ndarray:
        """The state (n,). Assigned from outside (the engine's feedback) it is kept in the filter's
        dtype: a float32 filter stays single precision (an array of its dtype is kept as it is)."""
        self._x_out = True
        return self._x

    @x.setter
    def x(self, value: np.ndarray) -> None:
        self._x = as_dtype(value, self.dtype)
        self._x_out = True

    @property
    def P(self) -> np.ndarray:
        """The covariance (n, n); assigned from outside (launch noise, a bridged gap, a velocity
        reset) it is kept in the filter's dtype, as x."""
        self._p_out = True
        return self._P

    @P.setter
    def P(self, value: np.ndarray) -> None:
        self._P = as_dtype(value, self.dtype)
        self._p_out = True

    def adopt_x(self, x: np.ndarray) -> None:
        """Set the state to x (n,), a C-ordered array of the filter's dtype that nothing else holds
        (a kernel's new result): kept as it is, without the copy an assignment to `x` makes
        before the next step writes it."""
        if not (type(x) is _NDARRAY and x.dtype == self.dtype and x.flags.c_contiguous and x.shape == self._x.shape):
            raise ValueError(f'adopt_x: a C-ordered {self.dtype} array of shape {self._x.shape} expected')
        self._x = x
        self._x_out = False

    def reset_state(self, x: np.ndarray | None = None) -> None:
        """Closed-loop feedback: x <- 0 (or x); P is untouched."""
        self._x = np.zeros_like(self._x) if x is None else np.array(x, dtype=self.dtype)
        self._x_out = False

    def __copy__(self) -> KalmanFilter:
        """A shallow copy (copy.copy) shares x and P: both filters copy them before their next
        write, so stepping one never changes the other."""
        other = object.__new__(type(self))
        other.__dict__.update(self.__dict__)
        self._x_out = self._p_out = other._x_out = other._p_out = True
        return other

    def _own(self) -> None:
        """Make x and P the filter's own C-ordered arrays, which the kernels may overwrite."""
        if self._x_out:
            self._x = np.array(self._x, dtype=self.dtype, order='C')
            self._x_out = False
        if self._p_out:
            self._P = np.array(self._P, dtype=self.dtype, order='C')
            self._p_out = False

    def predict(self, phi: np.ndarray, qd: np.ndarray) -> None:
        """x <- Phi x, P <- Phi P Phi^T + Qd (symmetric by construction up to round-off, which
        the next update's symmetrisation removes)."""
        dt = self.dtype
        if self._x_out or self._p_out:
            self._own()
        if not (type(phi) is _NDARRAY and (phi.dtype is dt or phi.dtype == dt) and phi.flags.c_contiguous):   # _ready
            phi = _ready(phi, dt)
        if not (type(qd) is _NDARRAY and (qd.dtype is dt or qd.dtype == dt) and qd.flags.c_contiguous):
            qd = _ready(qd, dt)
        kernels.predict(self._x, self._P, phi, qd)
        self.n_predicts += 1

    def arrays_to_predict(self) -> tuple[np.ndarray, np.ndarray]:
        """(x, P) as the filter's own C-ordered arrays, for a compiled step that predicts them in
        place as `predict` does (estimation/propagation_step.py; it counts the predict once done)."""
        if self._x_out or self._p_out:
            self._own()
        return self._x, self._P

    def _innovation(self, z, h, r, x, p):
        """(y = z - H x, P H^T, S = H P H^T + R) for the subclasses that change the prior."""
        return kernels.innovation(x, p, z.reshape(1) if z.ndim == 0 else z, h, r)

    def update(self, z: np.ndarray, h: np.ndarray, r: np.ndarray,
               gate_chi2: float | None = None) -> UpdateResult:
        dt = self.dtype
        if not (type(z) is _NDARRAY and (z.dtype is dt or z.dtype == dt) and z.flags.c_contiguous):    # _ready inline
            z = _ready(z, dt)
        if not (type(h) is _NDARRAY and (h.dtype is dt or h.dtype == dt) and h.flags.c_contiguous):
            h = _ready(h, dt)
        if not (type(r) is _NDARRAY and (r.dtype is dt or r.dtype == dt) and r.flags.c_contiguous):
            r = _ready(r, dt)
        if z.ndim == 0:                       # one measurement given as a scalar
            z = z.reshape(1)
        if self._x_out or self._p_out:
            self._own()
        m = z.shape[0]
        y, s = _empty(m, dt), _empty((m, m), dt)      # x, P, z, h, r are all in dt
        try:
            nis, accepted = kernels.update(self._x, self._P, z, h, r, _INF if gate_chi2 is None else gate_chi2,
                                           y, s)
        except np.linalg.LinAlgError:           # S singular
            nis, accepted = math.nan, False
        return self.account(y, s, nis, accepted)

    def arrays_to_update(self, m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(x, P) as the filter's own C-ordered arrays and new arrays for y (m,) and S (m, m), for
        a kernel that updates them in place as kalman_kernels.update does (estimation/
        match_step.py); the caller then hands its outcome to `account`."""
        if self._x_out or self._p_out:
            self._own()
        dt = self.dtype
        return self._x, self._P, _empty(m, dt), _empty((m, m), dt)

    def account(self, y: np.ndarray, s: np.ndarray, nis: float, accepted: bool) -> UpdateResult:
        """An update's outcome counted (NaN nis: S was singular or not finite; raises
        np.linalg.LinAlgError unless 0 <= nis < inf)."""
        if not 0.0 <= nis < _INF:
            check_nis(nis)
        self.last_nis = nis
        if not accepted:
            self.n_gated += 1
            return UpdateResult(y, s, nis, False)
        self.n_updates += 1
        return UpdateResult(y, s, nis, True)

    def _joseph(self, y, ph, s_inv, h, r) -> None:
        """x += K y, P <- (I - K H) P (I - K H)^T + K R K^T, symmetrised (the same operations as
        update(), for the subclasses that change the prior before updating)."""
        dt = self.dtype
        h, r = _ready(h, dt), _ready(r, dt)
        if self._x_out or self._p_out:
            self._own()
        kernels.joseph(self._x, self._P, ph, s_inv, y, h, r)
