"""Strapdown mechanisation in the local-level ENU frame (quaternion attitude).

Per interval of length h with increments (dtheta, dv) in body axes: two-sample coning and
sculling corrections (using the previous interval's increments), rotation of the nav frame
by zeta = omega_in h, velocity with gravity and Coriolis at mid-interval (predictor-corrector),
trapezoidal position.
C_b^n(k) = exp(-[zeta x]) C_b^n(k-1) exp([phi x]).
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from . import earth

# Speed: the per-step work is on 3-vectors and quaternions, where one numpy operation costs
# ~1 us of call overhead against ~30 ns for a Python float operation. The helpers below work on
# plain floats (tuples/lists); arrays are built only for what callers keep or use as arrays.

Floats = Sequence[float]


def floats(a) -> list[float]:
    """The elements of a small 1-D array (or sequence) as Python floats."""
    return a.tolist() if type(a) is np.ndarray else [float(x) for x in a]


def cross_f(a: Floats, b: Floats) -> tuple[float, float, float]:
    """a x b for two 3-vectors of floats."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def quat_mul_f(a: Floats, b: Floats) -> tuple[float, float, float, float]:
    """Hamilton product of two (x, y, z, w) quaternions of floats."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def rotvec_to_quat_f(x: float, y: float, z: float) -> tuple[float, float, float, float]:
    """(x, y, z, w) quaternion of the rotation vector (x, y, z); series near zero."""
    a2 = x * x + y * y + z * z
    if a2 < 1e-12:
        s = 0.5 - a2 / 48.0
        c = 1.0 - a2 / 8.0 + a2 * a2 / 384.0
    else:
        a = math.sqrt(a2)
        s = math.sin(0.5 * a) / a
        c = math.cos(0.5 * a)
    return (x * s, y * s, z * s, c)


def normalized_f(q: Floats) -> tuple[float, float, float, float]:
    """q / |q| for a quaternion of floats."""
    x, y, z, w = q
    n = math.sqrt(x * x + y * y + z * z + w * w)
    return (x / n, y / n, z / n, w / n)


def quat_to_dcm_f(q: Floats) -> tuple[float, ...]:
    """The rotation matrix of a unit (x, y, z, w) quaternion, row-major as 9 floats."""
    x, y, z, w = q
    return (1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
            2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
            2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y))


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product of (x, y, z, w) quaternions."""
    return np.array(quat_mul_f(floats(a), floats(b)))


def rotvec_to_quat(v: np.ndarray) -> np.ndarray:
    """(x, y, z, w) quaternion of rotation vector v; series near zero."""
    x, y, z = floats(v)
    return np.array(rotvec_to_quat_f(x, y, z))


def quat_to_dcm(q: np.ndarray) -> np.ndarray:
    """Rotation matrix (3, 3) of a unit (x, y, z, w) quaternion."""
    return np.array(quat_to_dcm_f(floats(q))).reshape(3, 3)


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
        th = floats(dtheta)
        dvl = floats(dv)
        pth = floats(s.prev_dtheta)
        # coning: phi = dtheta + prev_dtheta x dtheta / 12
        c = cross_f(pth, th)
        phi_x, phi_y, phi_z = th[0] + c[0] / 12.0, th[1] + c[1] / 12.0, th[2] + c[2] / 12.0
        # rotation compensation and sculling:
        # dv_b = dv + rot / 2 + dtheta x rot / 6 + (prev_dtheta x dv + prev_dv x dtheta) / 12,
        # rot = dtheta x dv
        rot = cross_f(th, dvl)
        rr = cross_f(th, rot)
        s1 = cross_f(pth, dvl)
        s2 = cross_f(floats(s.prev_dv), th)
        bx = dvl[0] + 0.5 * rot[0] + rr[0] / 6.0 + (s1[0] + s2[0]) / 12.0
        by = dvl[1] + 0.5 * rot[1] + rr[1] / 6.0 + (s1[1] + s2[1]) / 12.0
        bz = dvl[2] + 0.5 * rot[2] + rr[2] / 6.0 + (s1[2] + s2[2]) / 12.0
        q0 = floats(s.q_nb)
        c = quat_to_dcm_f(q0)
        self.c_start = np.array(c).reshape(3, 3)
        # dv_sf = C_b^n(start) dv_b
        fx = c[0] * bx + c[1] * by + c[2] * bz
        fy = c[3] * bx + c[4] * by + c[5] * bz
        fz = c[6] * bx + c[7] * by + c[8] * bz
        v0x, v0y, v0z = floats(s.v_n)
        lat0, h0 = s.lat, s.h
        # predictor at the start of the interval: v1 = v0 + dv_sf + (g^n - (2 w_ie + w_en) x v0) h
        r_m, r_n, ien, ieu, ene, enn, enu, g = earth.local_terms(lat0, h0, v0x, v0y)
        wx, wy, wz = ene, 2.0 * ien + enn, 2.0 * ieu + enu
        v1x = v0x + fx + (0.0 - (wy * v0z - wz * v0y)) * h
        v1y = v0y + fy + (0.0 - (wz * v0x - wx * v0z)) * h
        v1z = v0z + fz + (-g - (wx * v0y - wy * v0x)) * h
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
        wx, wy, wz = ene, 2.0 * ien + enn, 2.0 * ieu + enu
        vx = v0x + dnx + (0.0 - (wy * vmz - wz * vmy)) * h
        vy = v0y + dny + (0.0 - (wz * vmx - wx * vmz)) * h
        vz = v0z + dnz + (-g - (wx * vmy - wy * vmx)) * h
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
