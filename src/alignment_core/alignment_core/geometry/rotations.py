"""Rotations: skew matrices, cross products, rotation vectors, quaternions (scipy's x, y, z, w
order). Euler angles and axis conventions are in euler.py.

Conventions: the navigation frame n is local-level East-North-Up; bodies are forward-left-up
(REP-103). `C_b^n` maps body vectors to the nav frame; q_nb is its (Hamilton) quaternion.

One implementation per operation, in up to three forms with the same formula:
    name_batch(...)  numpy over leading axes, (..., 3) or (..., 4) arrays in and out (the
                     vectorised simulation stages)
    name_f(...)      one vector as Python floats, tuples out: a numpy operation on a 3- or
                     4-vector costs ~1 us of call overhead against ~30 ns for a float operation,
                     and the filter's per-step code (strapdown, history, feedback) runs on these
    name(...)        one vector, arrays in and out, by way of name_f (or float arithmetic
                     written out, for the matrices)
The cross product's batch form is `cross` (its one-vector form `cross3`); `skew` takes any
leading axes and `skew_into` writes one [v x] into a block of a larger matrix.
"""
from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.spatial.transform import Rotation

Floats = Sequence[float]


def floats(a) -> list[float]:
    """The elements of a small 1-D array (or sequence) as Python floats."""
    return a.tolist() if type(a) is np.ndarray else [float(x) for x in a]


def rows_matmul(x: np.ndarray, m: np.ndarray) -> np.ndarray:
    """x @ m with each row of a 2-D x (K, n) computed alone: numpy hands a (K, n) @ (n, p)
    product to BLAS, whose rounding depends on K (its kernels tile the rows), so a batch would
    not equal its rows bit for bit; a stack of (1, n) products is the same operation as one
    row's, for any K. Other shapes (one vector, stacks): plain x @ m."""
    x = np.asarray(x)
    if x.ndim != 2:
        return x @ m
    return (x[:, None, :] @ m)[:, 0, :]


# ----- skew matrices and cross products -----

def skew(v) -> np.ndarray:
    """Cross-product matrices [v x]: (..., 3) -> (..., 3, 3)."""
    if type(v) is np.ndarray and v.shape == (3,) and v.dtype.char == 'd':
        x, y, z = v.tolist()                # one vector: its matrix from Python floats (~4x faster)
        return np.array(((0.0, -z, y), (z, 0.0, -x), (-y, x, 0.0)))
    v = np.asarray(v, dtype=float)
    k = np.zeros(v.shape[:-1] + (3, 3))
    k[..., 0, 1], k[..., 0, 2], k[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    k[..., 1, 0], k[..., 2, 0], k[..., 2, 1] = v[..., 2], -v[..., 1], v[..., 0]
    return k


def skew_into(m: np.ndarray, r: int, c: int, v) -> None:
    """Write [v x] (v a 3-vector) into the 3x3 block of m at (r, c); the other cells are left
    as they are (cheaper than building the block apart and copying it)."""
    x, y, z = v[0], v[1], v[2]
    m[r, c + 1] = -z
    m[r, c + 2] = y
    m[r + 1, c] = z
    m[r + 1, c + 2] = -x
    m[r + 2, c] = -y
    m[r + 2, c + 1] = x


def skew_cells(r: int, c: int) -> list[tuple[int, int]]:
    """The non-zero cells of [v x] in the block at (r, c), in skew_into's order (for put())."""
    return [(r, c + 1), (r, c + 2), (r + 1, c), (r + 1, c + 2), (r + 2, c), (r + 2, c + 1)]


def skew_values(x: float, y: float, z: float) -> list[float]:
    """The values of [v x] at skew_cells, v = (x, y, z)."""
    return [-z, y, z, -x, -y, x]


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b over the last axis (broadcasting); several times cheaper than np.cross."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def cross_f(a: Floats, b: Floats) -> tuple[float, float, float]:
    """a x b for two 3-vectors of floats."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def cross3(a, b) -> np.ndarray:
    """a x b for two 3-vectors, (3,) (np.cross costs ~40 us a call; this ~1 us)."""
    return np.array(cross_f(floats(a), floats(b)))


# ----- rotation vectors and matrices -----

def rotvec_to_dcm_batch(v: np.ndarray) -> np.ndarray:
    """exp([v x]): (..., 3) rotation vectors -> (..., 3, 3) by Rodrigues' formula
    I + s [v x] + c [v x]^2, s = sin|v| / |v|, c = (1 - cos|v|) / |v|^2 (series near zero)."""
    a2 = np.sum(v * v, axis=-1)
    small = a2 < 1e-12
    a = np.sqrt(np.where(small, 1.0, a2))
    s = np.where(small, 1.0 - a2 / 6.0, np.sin(a) / a)
    c = np.where(small, 0.5 - a2 / 24.0, (1.0 - np.cos(a)) / np.where(small, 1.0, a2))
    k = skew(v)
    return np.eye(3) + s[..., None, None] * k + c[..., None, None] * (k @ k)


def rotvec_to_dcm(v) -> np.ndarray:
    """exp([v x]) (3, 3) of one rotation vector: rotvec_to_dcm_batch's formula with
    [v x]^2 = v v^T - |v|^2 I, in float arithmetic (~10x cheaper for one vector)."""
    x, y, z = floats(v)
    return np.array(rotvec_to_dcm_f(x, y, z)).reshape(3, 3)


def rotvec_to_dcm_f(x: float, y: float, z: float) -> tuple[float, ...]:
    """exp([v x]) of v = (x, y, z), row-major as 9 floats (rotvec_to_dcm)."""
    a2 = x * x + y * y + z * z
    if a2 < 1e-12:
        s, c = 1.0 - a2 / 6.0, 0.5 - a2 / 24.0
    else:
        a = math.sqrt(a2)
        s, c = math.sin(a) / a, (1.0 - math.cos(a)) / a2
    xx, yy, zz, xy, xz, yz = x * x, y * y, z * z, x * y, x * z, y * z
    return (1.0 + c * (-yy - zz), -s * z + c * xy, s * y + c * xz,
            s * z + c * xy, 1.0 + c * (-xx - zz), -s * x + c * yz,
            -s * y + c * xz, s * x + c * yz, 1.0 + c * (-xx - yy))


def dcm_to_rotvec(c: np.ndarray) -> np.ndarray:
    """log: the rotation vector (3,) of a rotation matrix whose angle is well below pi (a
    misalignment, an attitude difference): the axis from the skew part loses precision
    near pi, where it vanishes."""
    (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = c.tolist()   # floats: ~5x cheaper
    return np.array(dcm_to_rotvec_f(c00, c11, c22, c01, c02, c10, c12, c20, c21))


def dcm_to_rotvec_f(c00: float, c11: float, c22: float, c01: float, c02: float, c10: float,
                    c12: float, c20: float, c21: float) -> tuple[float, float, float]:
    """dcm_to_rotvec of the matrix with these elements (the diagonal first)."""
    x, y, z = 0.5 * (c21 - c12), 0.5 * (c02 - c20), 0.5 * (c10 - c01)
    s = math.sqrt(x * x + y * y + z * z)
    if s < 1e-300:
        return (x, y, z)
    k = math.atan2(s, 0.5 * (c00 + c11 + c22 - 1.0)) / s
    return (x * k, y * k, z * k)


def right_jacobian(theta: np.ndarray) -> np.ndarray:
    """J_r(theta) (..., 3, 3): the body rate of exp([theta x]) is J_r(theta) theta'."""
    a2 = np.sum(theta * theta, axis=-1)
    small = a2 < 1e-8
    a = np.sqrt(np.where(small, 1.0, a2))
    b = np.where(small, 0.5 - a2 / 24.0, (1.0 - np.cos(a)) / np.where(small, 1.0, a2))
    c = np.where(small, 1.0 / 6.0 - a2 / 120.0, (a - np.sin(a)) / (np.where(small, 1.0, a2) * a))
    k = skew(theta)
    return np.eye(3) - b[..., None, None] * k + c[..., None, None] * (k @ k)


# ----- quaternions (x, y, z, w) -----

def quat_mul_batch(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product of (..., 4) quaternions, broadcasting."""
    ax, ay, az, aw = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    bx, by, bz, bw = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    return np.stack([aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw,
                     aw * bw - ax * bx - ay * by - az * bz], axis=-1)


def quat_mul_f(a: Floats, b: Floats) -> tuple[float, float, float, float]:
    """Hamilton product of two quaternions of floats."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product of two quaternions, (4,)."""
    return np.array(quat_mul_f(floats(a), floats(b)))


def quat_conj(q: np.ndarray) -> np.ndarray:
    """Conjugate (the inverse rotation of a unit quaternion), (4,)."""
    x, y, z, w = floats(q)
    return np.array([-x, -y, -z, w])


def normalized_f(q: Floats) -> tuple[float, float, float, float]:
    """q / |q| for a quaternion of floats."""
    x, y, z, w = q
    n = math.sqrt(x * x + y * y + z * z + w * w)
    return (x / n, y / n, z / n, w / n)


def axis_quat_batch(angle, axis: int) -> np.ndarray:
    """Quaternions (..., 4) of rotations by `angle` (any shape, rad) about body axis 0, 1 or 2."""
    q = np.zeros(np.shape(angle) + (4,))
    q[..., axis] = np.sin(0.5 * angle)
    q[..., 3] = np.cos(0.5 * angle)
    return q


def rotvec_to_quat_batch(v: np.ndarray) -> np.ndarray:
    """Quaternions (..., 4) of rotation vectors (..., 3): (v sin(|v|/2) / |v|, cos(|v|/2)),
    series near zero."""
    a2 = np.sum(v * v, axis=-1)
    small = a2 < 1e-12
    a = np.sqrt(np.where(small, 1.0, a2))
    s = np.where(small, 0.5 - a2 / 48.0, np.sin(0.5 * a) / a)
    c = np.where(small, 1.0 - a2 / 8.0, np.cos(0.5 * a))
    return np.concatenate([v * s[..., None], c[..., None]], axis=-1)


def rotvec_to_quat_f(x: float, y: float, z: float) -> tuple[float, float, float, float]:
    """Quaternion of the rotation vector (x, y, z): rotvec_to_quat_batch's formula."""
    a2 = x * x + y * y + z * z
    if a2 < 1e-12:
        s = 0.5 - a2 / 48.0
        c = 1.0 - a2 / 8.0
    else:
        a = math.sqrt(a2)
        s = math.sin(0.5 * a) / a
        c = math.cos(0.5 * a)
    return (x * s, y * s, z * s, c)


def rotvec_to_quat(v) -> np.ndarray:
    """Quaternion (4,) of the rotation vector v."""
    x, y, z = floats(v)
    return np.array(rotvec_to_quat_f(x, y, z))


def quat_to_rotvec_f(q: Floats) -> tuple[float, float, float]:
    """Rotation vector of a unit quaternion of floats (the shorter rotation)."""
    x, y, z, w = q
    if w < 0.0:
        x, y, z, w = -x, -y, -z, -w
    s = math.sqrt(x * x + y * y + z * z)
    k = 2.0 if s < 1e-12 else 2.0 * math.atan2(s, w) / s
    return (x * k, y * k, z * k)


def quat_to_rotvec(q: np.ndarray) -> np.ndarray:
    """Rotation vector (3,) of a unit quaternion (the shorter rotation)."""
    return np.array(quat_to_rotvec_f(floats(q)))


def quat_to_dcm_batch(q: np.ndarray) -> np.ndarray:
    """(..., 4) unit quaternions -> (..., 3, 3) rotation matrices."""
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz, xw, yw, zw = x * y, x * z, y * z, x * w, y * w, z * w
    m = np.stack([1 - 2 * (yy + zz), 2 * (xy - zw), 2 * (xz + yw),
                  2 * (xy + zw), 1 - 2 * (xx + zz), 2 * (yz - xw),
                  2 * (xz - yw), 2 * (yz + xw), 1 - 2 * (xx + yy)], -1)
    return m.reshape(q.shape[:-1] + (3, 3))


def rotate_rows(c: np.ndarray, v: np.ndarray, inverse: bool = False) -> np.ndarray:
    """C v (or C^T v) for K matrices (K, 3, 3) and vectors (K, 3), each row alone: the same bits
    for a row whatever K (scipy's Rotation.apply rounds a batch differently from its rows, so a
    sensor fed in chunks would depend on where they split)."""
    return np.einsum('kji,kj->ki' if inverse else 'kij,kj->ki', c, v)


def rotate_batch(q: np.ndarray, v: np.ndarray, inverse: bool = False) -> np.ndarray:
    """`rotate_rows` by the matrices of K quaternions (K, 4)."""
    return rotate_rows(quat_to_dcm_batch(np.asarray(q)), v, inverse)


def quat_to_dcm_f(q: Floats) -> tuple[float, ...]:
    """The rotation matrix of a unit quaternion of floats, row-major as 9 floats."""
    x, y, z, w = q
    return (1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
            2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
            2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y))


def quat_to_dcm(q: np.ndarray) -> np.ndarray:
    """Rotation matrix (3, 3) of a unit quaternion."""
    return np.array(quat_to_dcm_f(floats(q))).reshape(3, 3)


def slerp(q0: np.ndarray, q1: np.ndarray, f: float) -> np.ndarray:
    """Attitude a fraction f of the way from q0 to q1 (rotation about a fixed body axis)."""
    a = floats(q0)
    rx, ry, rz = quat_to_rotvec_f(quat_mul_f((-a[0], -a[1], -a[2], a[3]), floats(q1)))
    return np.array(normalized_f(quat_mul_f(a, rotvec_to_quat_f(f * rx, f * ry, f * rz))))


def relative_rotvec_batch(q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
    """(..., 3) rotation vector of q_a^-1 q_b, frame b relative to frame a (both (..., 4)): the
    aircraft IMU axes relative to the master's, the misalignment the filter estimates."""
    a, b = np.broadcast_arrays(np.asarray(q_a, dtype=float), np.asarray(q_b, dtype=float))
    shape = a.shape[:-1]
    rel = Rotation.from_quat(a.reshape(-1, 4)).inv() * Rotation.from_quat(b.reshape(-1, 4))
    return rel.as_rotvec().reshape(*shape, 3)
