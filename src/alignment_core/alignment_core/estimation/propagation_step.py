"""One IMU interval compiled whole, for a model whose Phi is velocity matching's transition and
the plain Kalman filter: the strapdown step (navigation/strapdown.py), the transition
(models/velocity_matching.py) and the filter's predict (filters/kalman_kernels.py) in one
kernel, the same operations in the same order as the three calls the engine otherwise makes.

Why: each of the three costs about as much to call from Python (argument checks, dispatch, the
arrays it returns) as its arithmetic; one call instead of three saves a third of the interval's
time (docs/speed.md)."""
from __future__ import annotations

import numpy as np

from alignment_core.compiled import as_float64, kernel
from alignment_core.estimation.filters.kalman import KalmanFilter
from alignment_core.estimation.filters.kalman_kernels import predict
from alignment_core.estimation.models.velocity_matching import phi_from_cells
from alignment_core.navigation.strapdown import Strapdown, step

_NO_SPOT = np.zeros(3)


def strapdown_and_predict(ins: Strapdown, kf: KalmanFilter, cells: tuple[np.ndarray, int], gyro: np.ndarray,
                          bg: np.ndarray, accel: np.ndarray, ba: np.ndarray, h: float, qd: np.ndarray,
                          a_spot: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """Strapdown.update of ins with the increments (gyro - bg) h and (accel - ba) h (3,), then
    KalmanFilter.predict of kf with the interval's Phi and qd (size, size); cells: the model's
    `transition_cells` (F h's cell indices, n). Phi takes the slave's specific force, or with the
    deck spot's acceleration a_spot (3,) `reference_specific_force`'s (reference_force.py).
    Returns (that specific force (3,), Phi (size, size))."""
    idx, n = cells
    x, p = kf.arrays_to_predict()
    s = ins.s
    (ins.c_start, ins.w_ie, ins.w_en, s.v_n, s.q_nb, f_model, s.lat, s.lon, s.h, s.prev_dtheta, s.prev_dv,
     phi) = _interval(as_float64(gyro), as_float64(bg), as_float64(accel), as_float64(ba), float(h),
                      as_float64(s.prev_dtheta), as_float64(s.prev_dv), as_float64(s.q_nb), as_float64(s.v_n),
                      float(s.lat), float(s.lon), float(s.h), idx, n, x, p, qd,
                      _NO_SPOT if a_spot is None else as_float64(a_spot), a_spot is not None)
    kf.n_predicts += 1
    return f_model, phi


@kernel
def _interval(gyro, bg, accel, ba, h, prev_dtheta, prev_dv, q_nb, v_n, lat, lon, height, idx, n, x, p, qd,
              a_spot, reference):
    """The strapdown step over h from the biased rates gyro, accel (3,) less bg, ba, Phi of
    its start attitude, mean specific force (reference: the spot's, from a_spot) and rates (F h's
    cells idx of the first n states, in a (size, size) identity, size = len(x)), and x, P
    predicted in place. Returns step's nine values (the force Phi took for its sixth), the two
    increments (3,) and Phi."""
    dtheta = np.empty(3)
    dv = np.empty(3)
    for i in range(3):
        dtheta[i] = (gyro[i] - bg[i]) * h
        dv[i] = (accel[i] - ba[i]) * h
    c_start, w_ie, w_en, v, q, f_n, lat1, lon1, h1 = step(dtheta, dv, prev_dtheta, prev_dv, q_nb, v_n,
                                                          lat, lon, height, h)
    if reference:                       # reference_specific_force's floats, in its order
        ax, ay, az = 2.0 * w_ie[0] + w_en[0], 2.0 * w_ie[1] + w_en[1], 2.0 * w_ie[2] + w_en[2]
        f_n = np.array([a_spot[0] + (ay * v[2] - az * v[1]), a_spot[1] + (az * v[0] - ax * v[2]), f_n[2]])
    phi = phi_from_cells(c_start, f_n, w_ie, w_en, h, idx, n, x.shape[0])
    predict(x, p, phi, qd)
    return c_start, w_ie, w_en, v, q, f_n, lat1, lon1, h1, dtheta, dv, phi
