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

from alignment_core.geometry import earth
from alignment_core.geometry.rotations import (
    floats,
    normalized_f,
    quat_mul_f,
    quat_to_dcm,
    quat_to_dcm_f,
    rotvec_to_quat_f,
)

# Speed: the per-step work is on 3-vectors and quaternions, where one numpy operation costs
# ~1 us of call overhead against ~30 ns for a Python float operation: the update works on plain
# floats (the float forms of geometry/rotations.py) and builds arrays only for what callers keep.


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
        compensation to second order in dtheta and two-sample sculling.

        Float arithmetic throughout (see the note at the top of the module); the state's
        q_nb and v_n are replaced by new arrays, never changed in place (the engine's
        history keeps references to the old ones)."""
        s = self.s
        t0, t1, t2 = floats(dtheta)
        d0, d1, d2 = floats(dv)
        p0, p1, p2 = floats(s.prev_dtheta)
        u0, u1, u2 = floats(s.prev_dv)
        # the cross products written out (cross_f's expressions: the calls cost more than the arithmetic)
        # coning: phi = dtheta + prev_dtheta x dtheta / 12
        phi_x = t0 + (p1 * t2 - p2 * t1) / 12.0
        phi_y = t1 + (p2 * t0 - p0 * t2) / 12.0
        phi_z = t2 + (p0 * t1 - p1 * t0) / 12.0
        # rotation compensation and sculling:
        # dv_b = dv + rot / 2 + dtheta x rot / 6 + (prev_dtheta x dv + prev_dv x dtheta) / 12,
        # rot = dtheta x dv
        r0, r1, r2 = t1 * d2 - t2 * d1, t2 * d0 - t0 * d2, t0 * d1 - t1 * d0
        bx = d0 + 0.5 * r0 + (t1 * r2 - t2 * r1) / 6.0 + ((p1 * d2 - p2 * d1) + (u1 * t2 - u2 * t1)) / 12.0
        by = d1 + 0.5 * r1 + (t2 * r0 - t0 * r2) / 6.0 + ((p2 * d0 - p0 * d2) + (u2 * t0 - u0 * t2)) / 12.0
        bz = d2 + 0.5 * r2 + (t0 * r1 - t1 * r0) / 6.0 + ((p0 * d1 - p1 * d0) + (u0 * t1 - u1 * t0)) / 12.0
        q0 = floats(s.q_nb)
        cnb = quat_to_dcm_f(q0)
        self.c_start = np.array(cnb).reshape(3, 3)
        # dv_sf = C_b^n(start) dv_b
        fx = cnb[0] * bx + cnb[1] * by + cnb[2] * bz
        fy = cnb[3] * bx + cnb[4] * by + cnb[5] * bz
        fz = cnb[6] * bx + cnb[7] * by + cnb[8] * bz
        v0x, v0y, v0z = floats(s.v_n)
        lat0, h0 = s.lat, s.h
        # predictor at the start of the interval: v1 = v0 + dv_sf + (g^n - (2 w_ie + w_en) x v0) h
        r_m, r_n, ien, ieu, ene, enn, enu, g = earth.local_terms(lat0, h0, v0x, v0y)
        w0, w1, w2 = ene, 2.0 * ien + enn, 2.0 * ieu + enu
        v1x = v0x + fx + (0.0 - (w1 * v0z - w2 * v0y)) * h
        v1y = v0y + fy + (0.0 - (w2 * v0x - w0 * v0z)) * h
        v1z = v0z + fz + (-g - (w0 * v0y - w1 * v0x)) * h
        vmx, vmy, vmz = 0.5 * (v0x + v1x), 0.5 * (v0y + v1y), 0.5 * (v0z + v1z)
        lat_m = lat0 + 0.5 * h * vmy / (r_m + h0)
        h_m = h0 + 0.5 * h * vmz
        # corrector with mid-interval quantities
        r_m, r_n, ien, ieu, ene, enn, enu, g = earth.local_terms(lat_m, h_m, vmx, vmy)
        self.w_ie = np.array([0.0, ien, ieu])
        self.w_en = np.array([ene, enn, enu])
        # nav-frame rotation zeta = (w_ie + w_en) h; dv_n = dv_sf - zeta x dv_sf / 2
        zx, zy, zz = ene * h, (ien + enn) * h, (ieu + enu) * h
        dnx = fx - 0.5 * (zy * fz - zz * fy)
        dny = fy - 0.5 * (zz * fx - zx * fz)
        dnz = fz - 0.5 * (zx * fy - zy * fx)
        w0, w1, w2 = ene, 2.0 * ien + enn, 2.0 * ieu + enu
        vx = v0x + dnx + (0.0 - (w1 * vmz - w2 * vmy)) * h
        vy = v0y + dny + (0.0 - (w2 * vmx - w0 * vmz)) * h
        vz = v0z + dnz + (-g - (w0 * vmy - w1 * vmx)) * h
        vmx, vmy, vmz = 0.5 * (v0x + vx), 0.5 * (v0y + vy), 0.5 * (v0z + vz)
        s.lat = lat0 + h * vmy / (r_m + h_m)
        s.lon = s.lon + h * vmx / ((r_n + h_m) * math.cos(lat_m))
        s.h = h0 + h * vmz
        s.v_n = np.array([vx, vy, vz])
        # C_b^n(k) = exp(-[zeta x]) C_b^n(k-1) exp([phi x])
        q = quat_mul_f(rotvec_to_quat_f(-zx, -zy, -zz), quat_mul_f(q0, rotvec_to_quat_f(phi_x, phi_y, phi_z)))
        s.q_nb = np.array(normalized_f(q))
        s.prev_dtheta = dtheta
        s.prev_dv = dv
        return np.array([dnx / h, dny / h, dnz / h])
