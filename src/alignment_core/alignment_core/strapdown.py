"""Strapdown mechanisation in the local-level ENU frame (quaternion attitude).

Per interval of length h with increments (dtheta, dv) in body axes: two-sample coning and
sculling corrections (using the previous interval's increments), rotation of the nav frame
by zeta = omega_in h, velocity with gravity and Coriolis, trapezoidal position.
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
        leaves the Earth and transport rates used in `w_ie`, `w_en`."""
        s = self.s
        r_m, r_n, w_ie, w_en, g_mag = earth.local_scalar(s.lat, s.h, s.v_n)
        self.w_ie, self.w_en = w_ie, w_en
        w_in = w_ie + w_en
        phi = dtheta + cross3(s.prev_dtheta, dtheta) / 12.0
        dv_b = dv + 0.5 * cross3(dtheta, dv) + (cross3(s.prev_dtheta, dv)
                                                 + cross3(s.prev_dv, dtheta)) / 12.0
        zeta = w_in * h
        c = s.c_nb
        dv_n = c @ dv_b
        dv_n = dv_n - 0.5 * cross3(zeta, dv_n)
        g = np.array([0.0, 0.0, -g_mag])
        v_old = s.v_n
        v_new = v_old + dv_n + (g - cross3(2.0 * w_ie + w_en, v_old)) * h
        vm = 0.5 * (v_old + v_new)
        s.lat = s.lat + h * vm[1] / (r_m + s.h)
        s.lon = s.lon + h * vm[0] / ((r_n + s.h) * math.cos(s.lat))
        s.h = s.h + h * vm[2]
        s.v_n = v_new
        q = quat_mul(rotvec_to_quat(-zeta), quat_mul(s.q_nb, rotvec_to_quat(phi)))
        s.q_nb = q / np.sqrt(q @ q)
        s.prev_dtheta = dtheta
        s.prev_dv = dv
        return dv_n / h
