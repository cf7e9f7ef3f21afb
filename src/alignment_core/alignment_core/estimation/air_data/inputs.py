"""What the air-data estimators read: the aligned INS solution (attitude, ground velocity,
height with their covariance), kept over a short window so a lagged port can be compared with
the flight at the instant its pressure was sensed."""
from __future__ import annotations

import bisect
from dataclasses import dataclass, field

import numpy as np

from alignment_core.geometry.rotations import quat_to_dcm_batch, slerp

INS_SPAN_S = 20.0
"""INS history kept: a graph delivers streams out of step by seconds (and a lagged port looks
back up to ~7 tau)."""


@dataclass(frozen=True)
class InsSample:
    """One INS solution at time t (s): q_nb (4,) x y z w, body FLU -> nav ENU; v_enu (3,) m/s;
    height_m above mean sea level; lat_rad; att_cov (3, 3) of the nav-frame attitude error
    (rotation vector, rad^2); vel_cov (3, 3) (m/s)^2; height_var m^2."""
    t: float
    q_nb: np.ndarray
    v_enu: np.ndarray
    height_m: float
    lat_rad: float
    att_cov: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))
    vel_cov: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))
    height_var: float = 0.0

    def finite(self) -> bool:
        return bool(np.all(np.isfinite(self.q_nb)) and np.all(np.isfinite(self.v_enu))
                    and np.isfinite(self.height_m) and np.isfinite(self.lat_rad))


@dataclass(frozen=True)
class InsAt:
    """INS quantities at a set of instants (k = one per port): C_b^n (k, 3, 3), v_enu (k, 3),
    height (k,)."""
    c_bn: np.ndarray
    v_enu: np.ndarray
    height_m: np.ndarray


class InsHistory:
    """The last `span_s` seconds of INS solutions, in time order; interpolated in between
    (attitude by slerp, velocity and height linearly), held at the ends."""

    def __init__(self, span_s: float = 5.0) -> None:
        self.span_s = float(span_s)
        self._t: list[float] = []
        self._s: list[InsSample] = []

    def __len__(self) -> int:
        return len(self._s)

    def push(self, s: InsSample) -> bool:
        """Append a solution; False (ignored) if it is not newer than the last one."""
        if self._t and s.t <= self._t[-1]:
            return False
        self._t.append(s.t)
        self._s.append(s)
        while self._t[-1] - self._t[0] > self.span_s and len(self._t) > 2:
            del self._t[0], self._s[0]
        return True

    @property
    def latest(self) -> InsSample | None:
        return self._s[-1] if self._s else None

    def covers(self, t: float, tolerance_s: float) -> bool:
        """A solution exists within tolerance_s of t (on either side) and t is not before the window."""
        if not self._t:
            return False
        return self._t[0] - tolerance_s <= t <= self._t[-1] + tolerance_s

    def sample(self, t: float) -> InsSample:
        """The solution at t (interpolated, held beyond the ends)."""
        i = bisect.bisect_right(self._t, t)
        if i == 0:
            return self._s[0]
        if i == len(self._t):
            return self._s[-1]
        a, b = self._s[i - 1], self._s[i]
        f = (t - a.t) / (b.t - a.t)
        return InsSample(t, slerp(a.q_nb, b.q_nb, f), a.v_enu + f * (b.v_enu - a.v_enu),
                         a.height_m + f * (b.height_m - a.height_m), a.lat_rad + f * (b.lat_rad - a.lat_rad),
                         b.att_cov, b.vel_cov, b.height_var)

    def at(self, times: np.ndarray) -> InsAt:
        """INS at each of `times` (k,)."""
        ss = [self.sample(float(t)) for t in times]
        return InsAt(quat_to_dcm_batch(np.array([s.q_nb for s in ss])), np.array([s.v_enu for s in ss]),
                     np.array([s.height_m for s in ss]))
