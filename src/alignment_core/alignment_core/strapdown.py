"""Strapdown mechanisation in the local-level ENU frame (quaternion attitude).

Per interval of length h with increments (dtheta, dv) in body axes: two-sample coning and
sculling corrections (using the previous interval's increments), rotation of the nav frame
by zeta = omega_in h, velocity with gravity and Coriolis at mid-interval (predictor-corrector),
trapezoidal position.
C_b^n(k) = exp(-[zeta x]) C_b^n(k-1) exp([phi x]).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import earth
from .attitude import cross3


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product of (x, y, z, w) quaternions."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array([aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw,
                     aw * bw - ax * bx - ay * by - az * bz])


def rotvec_to_quat(v: np.ndarray) -> np.ndarray:
    """(x, y, z, w) quaternion of rotation vector v; series near zero."""
    a2 = float(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    if a2 < 1e-12:
        s = 0.5 - a2 / 48.0
        c = 1.0 - a2 / 8.0 + a2 * a2 / 384.0
    else:
        a = math.sqrt(a2)
        s = math.sin(0.5 * a) / a
        c = math.cos(0.5 * a)
    return np.array([v[0] * s, v[1] * s, v[2] * s, c])


def quat_to_dcm(q: np.ndarray) -> np.ndarray:
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


@dataclass
class NavState:
    """INS solution: attitude q_nb (x, y, z, w; nav <- body), ENU velocity, geodetic position."""
    q_nb: np.ndarray
    v_n: np.ndarray
    lat: float
    lon: float
    h: float
    prev_dtheta: np.ndarray = field(default_factory=lambda: np.zeros(3))
    prev_dv: np.ndarray = field(default_factory=lambda: np.zeros(3))

    @property
    def c_nb(self) -> np.ndarray:
        return quat_to_dcm(self.q_nb)


class Strapdown:
    """Integrates increments into a NavState; also returns the nav-frame specific force."""

    def __init__(self, state: NavState) -> None:
        self.s = state

    def update(self, dtheta: np.ndarray, dv: np.ndarray, h: float) -> np.ndarray:
        """Advance by one interval; returns the mean nav-frame specific force f^n (3,) and
        leaves the attitude at the start (`c_start`) and the mid-interval Earth and transport
        rates used (`w_ie`, `w_en`).

        Gravity, Coriolis and the nav-frame rotation are evaluated at mid-interval from a
        predictor step (second order); the body-frame velocity increment carries rotation
        compensation to second order in dtheta and two-sample sculling."""
        s = self.s
        phi = dtheta + cross3(s.prev_dtheta, dtheta) / 12.0
        rot = cross3(dtheta, dv)
        dv_b = (dv + 0.5 * rot + cross3(dtheta, rot) / 6.0
                + (cross3(s.prev_dtheta, dv) + cross3(s.prev_dv, dtheta)) / 12.0)
        self.c_start = c = s.c_nb
        dv_sf = c @ dv_b
        v0 = s.v_n
        # predictor at the start of the interval
        r_m, r_n, w_ie, w_en, g = earth.local_scalar(s.lat, s.h, v0)
        v1 = v0 + dv_sf + (np.array([0.0, 0.0, -g]) - cross3(2.0 * w_ie + w_en, v0)) * h
        vm = 0.5 * (v0 + v1)
        lat_m = s.lat + 0.5 * h * vm[1] / (r_m + s.h)
        h_m = s.h + 0.5 * h * vm[2]
        # corrector with mid-interval quantities
        r_m, r_n, w_ie, w_en, g = earth.local_scalar(lat_m, h_m, vm)
        self.w_ie, self.w_en = w_ie, w_en
        zeta = (w_ie + w_en) * h
        dv_n = dv_sf - 0.5 * cross3(zeta, dv_sf)
        v_new = v0 + dv_n + (np.array([0.0, 0.0, -g]) - cross3(2.0 * w_ie + w_en, vm)) * h
        vm = 0.5 * (v0 + v_new)
        s.lat = s.lat + h * vm[1] / (r_m + h_m)
        s.lon = s.lon + h * vm[0] / ((r_n + h_m) * math.cos(lat_m))
        s.h = s.h + h * vm[2]
        s.v_n = v_new
        q = quat_mul(rotvec_to_quat(-zeta), quat_mul(s.q_nb, rotvec_to_quat(phi)))
        s.q_nb = q / math.sqrt(q @ q)
        s.prev_dtheta = dtheta
        s.prev_dv = dv
        return dv_n / h
