"""Rotations: skew matrices, rotation vectors, quaternions (scipy x, y, z, w order), Euler.

Conventions: the navigation frame n is local-level East-North-Up; bodies are
forward-left-up (REP-103). `C_b^n` maps body vectors to the nav frame. Euler angles are
ROS roll (x), pitch (y, positive nose-down), yaw (z, from East, counter-clockwise),
composed as C_b^n = Rz(yaw) Ry(pitch) Rx(roll).
"""
from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.spatial.transform import Rotation


def skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrix [v x], shape (3, 3)."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rotvec_to_dcm(v) -> np.ndarray:
    return Rotation.from_rotvec(v).as_matrix()


def dcm_to_rotvec(c) -> np.ndarray:
    return Rotation.from_matrix(c).as_rotvec()














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



def right_jacobian(theta: np.ndarray) -> np.ndarray:
    """J_r(theta) (…, 3, 3): body rate of exp([theta x]) is J_r(theta) theta'."""
    a2 = np.sum(theta * theta, axis=-1)
    small = a2 < 1e-8
    a = np.sqrt(np.where(small, 1.0, a2))
    b = np.where(small, 0.5 - a2 / 24.0, (1.0 - np.cos(a)) / np.where(small, 1.0, a2))
    c = np.where(small, 1.0 / 6.0 - a2 / 120.0, (a - np.sin(a)) / (np.where(small, 1.0, a2) * a))
    k = np.zeros(theta.shape[:-1] + (3, 3))
    k[..., 0, 1], k[..., 0, 2], k[..., 1, 2] = -theta[..., 2], theta[..., 1], -theta[..., 0]
    k[..., 1, 0], k[..., 2, 0], k[..., 2, 1] = theta[..., 2], -theta[..., 1], theta[..., 0]
    return np.eye(3) - b[..., None, None] * k + c[..., None, None] * (k @ k)



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



def quat_conj(q: np.ndarray) -> np.ndarray:
    x, y, z, w = floats(q)
    return np.array([-x, -y, -z, w])


def _quat_to_rotvec_f(q) -> tuple[float, float, float]:
    x, y, z, w = q
    if w < 0.0:
        x, y, z, w = -x, -y, -z, -w
    s = math.sqrt(x * x + y * y + z * z)
    k = 2.0 if s < 1e-12 else 2.0 * math.atan2(s, w) / s
    return (x * k, y * k, z * k)


def quat_to_rotvec(q: np.ndarray) -> np.ndarray:
    """Rotation vector of a unit (x, y, z, w) quaternion (the shorter rotation)."""
    return np.array(_quat_to_rotvec_f(floats(q)))


def slerp(q0: np.ndarray, q1: np.ndarray, f: float) -> np.ndarray:
    """Attitude a fraction f of the way from q0 to q1 (rotation about a fixed body axis)."""
    a = floats(q0)
    rx, ry, rz = _quat_to_rotvec_f(quat_mul_f((-a[0], -a[1], -a[2], a[3]), floats(q1)))
    return np.array(normalized_f(quat_mul_f(a, rotvec_to_quat_f(f * rx, f * ry, f * rz))))
