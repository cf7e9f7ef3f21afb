"""Rotations: skew matrices, rotation vectors, quaternions (scipy x, y, z, w order), Euler.

Conventions: the navigation frame n is local-level East-North-Up; bodies are
forward-left-up (REP-103). `C_b^n` maps body vectors to the nav frame. Euler angles are
ROS roll (x), pitch (y, positive nose-down), yaw (z, from East, counter-clockwise),
composed as C_b^n = Rz(yaw) Ry(pitch) Rx(roll).
"""
from __future__ import annotations

import math

import numpy as np
from scipy.spatial.transform import Rotation

ARCMIN = np.pi / (180.0 * 60.0)
ARCSEC = ARCMIN / 60.0
DEG = np.pi / 180.0
DPH = DEG / 3600.0                  # degree per hour, in rad/s
G0 = 9.80665                        # standard gravity for unit conversions (mg, ug)


def skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrix [v x], shape (3, 3)."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rotvec_to_dcm(v) -> np.ndarray:
    return Rotation.from_rotvec(v).as_matrix()


def dcm_to_rotvec(c) -> np.ndarray:
    return Rotation.from_matrix(c).as_rotvec()


def euler_to_dcm(roll, pitch, yaw) -> np.ndarray:
    """C_b^n for ROS Euler angles (rad); vectorised over leading dimensions."""
    return Rotation.from_euler('ZYX', np.stack([yaw, pitch, roll], axis=-1)).as_matrix()


def heading_to_yaw(heading):
    """Navigational heading (from North, clockwise) to ROS yaw (from East, counter-clockwise)."""
    return np.pi / 2.0 - heading


def euler_rates_to_body_rate(euler, euler_dot) -> np.ndarray:
    """Body angular rate omega_nb^b from ROS Euler angles and their rates, shape (..., 3).

    omega = Rx(-roll) Ry(-pitch) [0, 0, yaw_dot] + Rx(-roll) [0, pitch_dot, 0] + [roll_dot, 0, 0].
    """
    r, p = euler[..., 0], euler[..., 1]
    rd, pd, yd = euler_dot[..., 0], euler_dot[..., 1], euler_dot[..., 2]
    sr, cr, sp, cp = np.sin(r), np.cos(r), np.sin(p), np.cos(p)
    return np.stack([rd - yd * sp, pd * cr + yd * cp * sr, -pd * sr + yd * cp * cr], axis=-1)


def euler_acc_to_body_acc(euler, euler_dot, euler_ddot) -> np.ndarray:
    """Time derivative of `euler_rates_to_body_rate` (angular acceleration), shape (..., 3)."""
    r, p = euler[..., 0], euler[..., 1]
    rd, pd, yd = euler_dot[..., 0], euler_dot[..., 1], euler_dot[..., 2]
    rdd, pdd, ydd = euler_ddot[..., 0], euler_ddot[..., 1], euler_ddot[..., 2]
    sr, cr, sp, cp = np.sin(r), np.cos(r), np.sin(p), np.cos(p)
    wx = rdd - ydd * sp - yd * pd * cp
    wy = (pdd * cr - pd * rd * sr + ydd * cp * sr - yd * pd * sp * sr + yd * rd * cp * cr)
    wz = (-pdd * sr - pd * rd * cr + ydd * cp * cr - yd * pd * sp * cr - yd * rd * cp * sr)
    return np.stack([wx, wy, wz], axis=-1)


def rfu_to_flu(v) -> np.ndarray:
    """Vector from right-forward-up axes (the seed papers' bodies) to forward-left-up (ROS)."""
    v = np.asarray(v, dtype=float)
    return np.stack([v[..., 1], -v[..., 0], v[..., 2]], axis=-1)


def flu_to_rfu(v) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    return np.stack([-v[..., 1], v[..., 0], v[..., 2]], axis=-1)


def quat_to_dcm_batch(q: np.ndarray) -> np.ndarray:
    """(..., 4) unit quaternions (x, y, z, w) -> (..., 3, 3) rotation matrices."""
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz, xw, yw, zw = x * y, x * z, y * z, x * w, y * w, z * w
    m = np.stack([1 - 2 * (yy + zz), 2 * (xy - zw), 2 * (xz + yw),
                  2 * (xy + zw), 1 - 2 * (xx + zz), 2 * (yz - xw),
                  2 * (xz - yw), 2 * (yz + xw), 1 - 2 * (xx + yy)], -1)
    return m.reshape(q.shape[:-1] + (3, 3))


def rotvec_to_dcm_batch(v: np.ndarray) -> np.ndarray:
    """(..., 3) rotation vectors -> (..., 3, 3) by Rodrigues' formula (series near zero)."""
    a2 = np.sum(v * v, axis=-1)
    small = a2 < 1e-12
    a = np.sqrt(np.where(small, 1.0, a2))
    s = np.where(small, 1.0 - a2 / 6.0, np.sin(a) / a)
    c = np.where(small, 0.5 - a2 / 24.0, (1.0 - np.cos(a)) / np.where(small, 1.0, a2))
    k = np.zeros(v.shape[:-1] + (3, 3))
    k[..., 0, 1], k[..., 0, 2], k[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    k[..., 1, 0], k[..., 2, 0], k[..., 2, 1] = v[..., 2], -v[..., 1], v[..., 0]
    return np.eye(3) + s[..., None, None] * k + c[..., None, None] * (k @ k)


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b for two 3-vectors (np.cross costs ~40 us a call; this ~1 us: the components
    as Python floats, whose arithmetic is far cheaper than numpy scalars')."""
    a0, a1, a2 = a.tolist() if type(a) is np.ndarray else a
    b0, b1, b2 = b.tolist() if type(b) is np.ndarray else b
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def dcm_to_rotvec_small(c: np.ndarray) -> np.ndarray:
    """Rotation vector of a rotation matrix whose angle is well below pi (a misalignment)."""
    (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = c.tolist()   # floats: ~5x cheaper
    x, y, z = 0.5 * (c21 - c12), 0.5 * (c02 - c20), 0.5 * (c10 - c01)
    s = math.sqrt(x * x + y * y + z * z)
    if s < 1e-300:
        return np.array([x, y, z])
    k = math.atan2(s, 0.5 * (c00 + c11 + c22 - 1.0)) / s
    return np.array([x * k, y * k, z * k])


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b over the last axis (broadcasting); several times cheaper than np.cross."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def quat_mul_batch(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product of (..., 4) quaternions (x, y, z, w), broadcasting."""
    ax, ay, az, aw = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    bx, by, bz, bw = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    return np.stack([aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw,
                     aw * bw - ax * bx - ay * by - az * bz], axis=-1)


def rotvec_to_dcm_small(v: np.ndarray) -> np.ndarray:
    """Rotation matrix of one rotation vector: Rodrigues' formula I + s [v x] + c [v x]^2 as
    rotvec_to_dcm_batch (series near zero), in float arithmetic (~10x cheaper for one vector)."""
    x, y, z = v.tolist() if type(v) is np.ndarray else (float(e) for e in v)
    a2 = x * x + y * y + z * z
    if a2 < 1e-12:
        s, c = 1.0 - a2 / 6.0, 0.5 - a2 / 24.0
    else:
        a = math.sqrt(a2)
        s, c = math.sin(a) / a, (1.0 - math.cos(a)) / a2
    # [v x]^2 = v v^T - |v|^2 I
    xx, yy, zz, xy, xz, yz = x * x, y * y, z * z, x * y, x * z, y * z
    return np.array([[1.0 + c * (-yy - zz), -s * z + c * xy, s * y + c * xz],
                     [s * z + c * xy, 1.0 + c * (-xx - zz), -s * x + c * yz],
                     [-s * y + c * xz, s * x + c * yz, 1.0 + c * (-xx - yy)]])
