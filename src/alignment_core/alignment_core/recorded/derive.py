"""What /master/odom and /aircraft/imu need and a log may lack, derived from what it has.

- Body-axes velocity: v_b = C_b^n^T v_n (the nav-frame ground velocity rotated into the body).
- Body rate w.r.t. the nav frame from attitude differences: the rotation vectors
  theta_j of C_b^n(k)^T C_b^n(j) to the four nearest attitudes j (two each side inside the
  log, one-sided at its ends), a degree-4 polynomial theta(t_j - t_k) through them and zero,
  its slope at 0. The error is of order dt^4 times the fifth derivative of the attitude
  (on the catapult scenario's ship motion at 100 Hz it matches the master's own rate to
  3.2e-9 rad/s, the master's gyro bias, which its attitude does not carry; a central
  difference leaves 3.6e-7 rad/s, which moves the estimate by 9e-6 rad with a 40 m lever arm).
  Attitude noise sigma (rad, white) becomes rate noise sigma sqrt(130) / (12 dt) inside the
  log and sigma sqrt(4490) / (12 dt) at its ends: 0.95 / dt and 5.6 / dt. A stencil does not
  reach across a gap of more than GAP_SPACINGS median spacings.
- Rates sampled at the stamps (`rate_sampling: instant`) -> means over the interval ending at
  the stamp, as the filter takes them: the trapezoid of each sample and the one before it.
- Rates from increments: increment / interval (the interval ending at the stamp, from the
  file's previous row even when that row is skipped: its increment is lost and its interval
  stays a gap in the stamps, which the filter bridges); the first row's interval (and one
  after a row without a time) is the median one (the log does not say when it started).
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

STENCIL = 5                 # attitudes per body-rate estimate
GAP_SPACINGS = 3.0          # a longer spacing (in median spacings) ends a stencil's run


def body_velocity(c_nb: np.ndarray, v_n: np.ndarray) -> np.ndarray:
    """v_b (N, 3) from C_b^n (N, 3, 3) and nav-frame velocity v_n (N, 3)."""
    return np.einsum('nji,nj->ni', c_nb, v_n)


def body_rate_from_attitude(t_ns: np.ndarray, c_nb: np.ndarray) -> np.ndarray:
    """omega_nb^b (N, 3), rad/s, from attitudes C_b^n (N, 3, 3) at stamps t_ns (N,), N >= 2.
    A stencil does not reach across a gap (a spacing over GAP_SPACINGS median spacings): each
    run between gaps has its own; a lone attitude between two gaps takes the difference to its
    nearer neighbour."""
    n = len(t_ns)
    if n < 2:
        raise ValueError('a body rate from attitude differences needs two attitudes or more')
    r = Rotation.from_matrix(c_nb)
    t = (t_ns - t_ns[0]) * 1e-9
    gap = np.flatnonzero(np.diff(t_ns) > GAP_SPACINGS * median_interval_ns(t_ns))
    bounds = np.r_[0, gap + 1, n]
    out = np.empty((n, 3))
    for a, b in zip(bounds[:-1], bounds[1:]):
        if b - a >= 2:
            out[a:b] = _rate_of_run(t[a:b], r[a:b])
        else:                           # alone between gaps: the nearer neighbour
            j = a - 1 if a == n - 1 or (a > 0 and t[a] - t[a - 1] <= t[a + 1] - t[a]) else a + 1
            out[a] = (r[a].inv() * r[j]).as_rotvec() / (t[j] - t[a])
    return out


def _rate_of_run(t: np.ndarray, r: Rotation) -> np.ndarray:
    """The stencil rate (N, 3) of N >= 2 attitudes `r` at times t (N,) s without gaps."""
    n = len(t)
    m = min(STENCIL, n)
    k = np.arange(n)
    window = np.clip(k - STENCIL // 2, 0, n - m)[:, None] + np.arange(m)
    nb = window[window != k[:, None]].reshape(n, m - 1)         # the m - 1 neighbours of each k
    h = t[nb] - t[k][:, None]
    # d/dh at 0 of the polynomial through (0, 0) and (h_j, theta_j): sum_j theta_j L_j'(0),
    # L_j'(0) = (1 / h_j) prod_{i != j} (-h_i) / (h_j - h_i)
    weight = 1.0 / h
    for j in range(m - 1):
        for i in range(m - 1):
            if i != j:
                weight[:, j] *= -h[:, i] / (h[:, j] - h[:, i])
    r_inv = r.inv()
    return sum(weight[:, j, None] * (r_inv * r[nb[:, j]]).as_rotvec() for j in range(m - 1))


def median_interval_ns(t_ns: np.ndarray) -> int:
    """The median stamp spacing (ns) of a stream of two stamps or more."""
    return int(np.median(np.diff(t_ns)))


def rates_from_increments(t_ns: np.ndarray, inc: np.ndarray, interval_ns: np.ndarray | None = None) -> np.ndarray:
    """Mean rates (N, 3) of increments (N, 3) over the intervals ending at t_ns (N,).
    `interval_ns` (N,): each row's own interval (from the file's previous row, kept or not);
    without it, or where it is 0 (unknown), the stamp spacing, and the median one for the first."""
    dt_ns = np.empty(len(t_ns), dtype=np.int64)
    dt_ns[1:] = np.diff(t_ns)
    dt_ns[0] = median_interval_ns(t_ns)
    if interval_ns is not None:
        dt_ns = np.where(np.asarray(interval_ns) > 0, interval_ns, median_interval_ns(t_ns))
    return inc / (dt_ns * 1e-9)[:, None]


def interval_means(x: np.ndarray, previous: np.ndarray) -> np.ndarray:
    """Means (N, 3) over the intervals ending at the stamps of rates x (N, 3) sampled at them:
    the trapezoid (x[k-1] + x[k]) / 2 (exact for a rate linear in time) where `previous` (N,)
    says row k - 1 is the file's previous row; elsewhere x[k] itself."""
    out = np.array(x, dtype=float)
    both = np.flatnonzero(previous)
    out[both] = 0.5 * (x[both - 1] + x[both])
    return out


def rate_hz_of(t_ns: np.ndarray) -> float:
    """The sample rate of a stream from its median spacing: a whole number of Hz when that
    is within 0.1 % and gives a whole number of nanoseconds, else 1e9 / spacing."""
    d = median_interval_ns(t_ns)
    r = round(1e9 / d)
    if r > 0 and 10**9 % r == 0 and abs(10**9 // r - d) <= 1e-3 * d:
        return float(r)
    return 1e9 / d
