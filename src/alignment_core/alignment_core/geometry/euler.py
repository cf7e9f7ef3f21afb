"""Euler angles and axis conventions: ROS roll/pitch/yaw, navigational heading, the seed
papers' right-forward-up bodies, Euler-rate kinematics."""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation


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
