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

from alignment_core.compiled import as_float64, kernel
from alignment_core.geometry import earth
from alignment_core.geometry.rotations import quat_to_dcm
from alignment_core.geometry.rotations_compiled import normalized_k, quat_mul_k, quat_to_dcm_k, rotvec_to_quat_k

# Speed: the per-step work is on 3-vectors and quaternions, where one numpy operation costs
# ~1 us of call overhead: the step is float arithmetic on the elements (with the float forms of
# geometry/rotations.py and earth.local_terms), compiled into one kernel (compiled.py).
_local_terms = kernel(earth.local_terms)


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

        The state's q_nb and v_n are replaced by new arrays, never changed in place (the
        engine's history keeps references to the old ones)."""
        s = self.s
        self.c_start, self.w_ie, self.w_en, s.v_n, s.q_nb, f_n, s.lat, s.lon, s.h = step(
            as_float64(dtheta), as_float64(dv), as_float64(s.prev_dtheta), as_float64(s.prev_dv), as_float64(s.q_nb),
            as_float64(s.v_n), float(s.lat), float(s.lon), float(s.h), float(h))
        s.prev_dtheta = dtheta
        s.prev_dv = dv
        return f_n


@kernel
def step(dtheta, dv, prev_dtheta, prev_dv, q_nb, v_n, lat0, lon0, h0, h):
    """One interval of length h: dtheta, dv (3,) this interval's increments, prev_* the last
    interval's, q_nb (4,), v_n (3,) and (lat0, lon0, h0) the state at its start.
    Returns (C_b^n at the start (3, 3), w_ie^n (3,), w_en^n (3,) at mid-interval, v_n (3,),
    q_nb (4,), mean specific force f^n (3,), lat, lon, h) at its end.

    Two-sample coning and sculling corrections, the nav-frame rotation zeta = omega_in h, gravity
    and Coriolis at mid-interval (predictor-corrector), trapezoidal position."""
    t0, t1, t2 = dtheta[0], dtheta[1], dtheta[2]
    d0, d1, d2 = dv[0], dv[1], dv[2]
    p0, p1, p2 = prev_dtheta[0], prev_dtheta[1], prev_dtheta[2]
    u0, u1, u2 = prev_dv[0], prev_dv[1], prev_dv[2]
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
    q0 = (q_nb[0], q_nb[1], q_nb[2], q_nb[3])
    cnb = quat_to_dcm_k(q0)
    c_start = np.array(cnb).reshape(3, 3)
    # dv_sf = C_b^n(start) dv_b
    fx = cnb[0] * bx + cnb[1] * by + cnb[2] * bz
    fy = cnb[3] * bx + cnb[4] * by + cnb[5] * bz
    fz = cnb[6] * bx + cnb[7] * by + cnb[8] * bz
    v0x, v0y, v0z = v_n[0], v_n[1], v_n[2]
    # predictor at the start of the interval: v1 = v0 + dv_sf + (g^n - (2 w_ie + w_en) x v0) h
    r_m, r_n, ien, ieu, ene, enn, enu, g = _local_terms(lat0, h0, v0x, v0y)
    w0, w1, w2 = ene, 2.0 * ien + enn, 2.0 * ieu + enu
    v1x = v0x + fx + (0.0 - (w1 * v0z - w2 * v0y)) * h
    v1y = v0y + fy + (0.0 - (w2 * v0x - w0 * v0z)) * h
    v1z = v0z + fz + (-g - (w0 * v0y - w1 * v0x)) * h
    vmx, vmy, vmz = 0.5 * (v0x + v1x), 0.5 * (v0y + v1y), 0.5 * (v0z + v1z)
    lat_m = lat0 + 0.5 * h * vmy / (r_m + h0)
    h_m = h0 + 0.5 * h * vmz
    # corrector with mid-interval quantities
    r_m, r_n, ien, ieu, ene, enn, enu, g = _local_terms(lat_m, h_m, vmx, vmy)
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
    lat = lat0 + h * vmy / (r_m + h_m)
    lon = lon0 + h * vmx / ((r_n + h_m) * math.cos(lat_m))
    # C_b^n(k) = exp(-[zeta x]) C_b^n(k-1) exp([phi x])
    q = quat_mul_k(rotvec_to_quat_k(-zx, -zy, -zz), quat_mul_k(q0, rotvec_to_quat_k(phi_x, phi_y, phi_z)))
    qn = normalized_k(q)
    return (c_start, np.array([0.0, ien, ieu]), np.array([ene, enn, enu]), np.array([vx, vy, vz]),
            np.array([qn[0], qn[1], qn[2], qn[3]]), np.array([dnx / h, dny / h, dnz / h]),
            lat, lon, h0 + h * vmz)
