"""One master match of plain velocity matching (vm12, vm15) under the plain Kalman filter,
compiled whole: the measurement matrix, the Kalman update, the health check, the feedback and the
misalignment in one kernel, the same operations in the same order as the calls
Matcher.update_master makes otherwise (models/velocity_matching.py, filters/kalman_kernels.py,
health.py). For a match at the live solution's time (no latency to carry the measurement across).

Why: those five calls cost several times their arithmetic from Python (docs/speed.md)."""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from alignment_core.compiled import as_float64, kernel
from alignment_core.estimation.filters.base import UpdateResult
from alignment_core.estimation.filters.kalman import KalmanFilter
from alignment_core.estimation.filters.kalman_kernels import update
from alignment_core.estimation.health import UNHEALTHY, NumericalBreakdownError, healthy
from alignment_core.estimation.models.base import Corrections
from alignment_core.estimation.models.velocity_matching import feedback_k, measurement_k, misalignment_k
from alignment_core.navigation.strapdown import NavState

_INF = float('inf')


class Fed(NamedTuple):
    """An accepted update fed back: the state before feedback, the one the filter keeps after
    it, and the misalignment and its sigma (aircraft axes, rad)."""
    x: np.ndarray
    x_kept: np.ndarray
    mu: np.ndarray
    mu_sigma: np.ndarray


def update_and_feed_back(kf: KalmanFilter, n: int, z: np.ndarray, u_n: np.ndarray, r: np.ndarray,
                         gate: float | None, nav: NavState, corr: Corrections, c_nominal: np.ndarray
                         ) -> tuple[UpdateResult, Fed | None]:
    """kf.update with velocity matching's measurement of n states (z = z_vel, u_n the lever-arm
    and deck velocity, nav frame, r (3, 3)), then check_health; if accepted, the model's feedback
    into nav and corr (q_nb, v_n, bg, ba replaced) and its misalignment against the nominal
    attitude c_nominal = C_m c_nom (3, 3). Raises as those calls raise."""
    x, p, y, s = kf.arrays_to_update(3)
    try:
        nis, accepted, ok, x_before, q, v, bg, ba, x_kept, mu, sigma = _match(
            x, p, as_float64(z), as_float64(u_n), n, as_float64(r), _INF if gate is None else gate, y, s,
            as_float64(nav.q_nb), as_float64(nav.v_n), as_float64(corr.bg), as_float64(corr.ba),
            np.ascontiguousarray(c_nominal, dtype=np.float64))
    except np.linalg.LinAlgError:           # S singular
        nis, accepted, ok = math.nan, False, True
    upd = kf.account(y, s, nis, accepted)
    if not ok:
        raise NumericalBreakdownError(UNHEALTHY)
    if not accepted:
        return upd, None
    nav.q_nb, nav.v_n, corr.bg, corr.ba = q, v, bg, ba
    return upd, Fed(x_before, x_kept, mu, sigma)


@kernel
def _match(x, p, z, u_n, n, r, gate, y, s, q_nb, v_n, bg, ba, c_nominal):
    """The update (x, P, y, S in place) with velocity matching's H of n states (measurement_k);
    (nis, accepted, healthy, then, if both, x before feedback, q_nb, v_n, bg, ba and the state
    kept after it, mu, sigma; else empty arrays)."""
    nis, accepted = update(x, p, z, measurement_k(u_n, n), r, gate, y, s)
    ok = healthy(x, p)
    if not (accepted and ok):
        e = np.empty(0)
        return nis, accepted, ok, e, e, e, e, e, e, e, e
    x_before = x.copy()
    q, v, bg1, ba1, x_kept = feedback_k(q_nb, v_n, bg, ba, x)
    mu, sigma = misalignment_k(q, c_nominal, x_kept, p, n == 15)
    return nis, accepted, ok, x_before, q, v, bg1, ba1, x_kept, mu, sigma
