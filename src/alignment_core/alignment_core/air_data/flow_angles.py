"""Angle of attack and sideslip of the air-relative velocity, in the aircraft's FLU body axes.

v_a is the aircraft's velocity relative to the air mass (ground velocity minus wind), in body
axes x forward, y left, z up (FLU, as every body vector of the project). With speed V,
    v_a = V (cos(alpha) cos(beta), -sin(beta), -sin(alpha) cos(beta)),
    alpha = atan2(-v_z, v_x),   beta = asin(-v_y / V):
alpha > 0 when the air meets the aircraft from below (nose above the flight path), beta > 0
when it meets it from the right (the textbook definitions, which are written in FRD axes
where v_a = V (cos a cos b, sin b, sin a cos b)).
"""
from __future__ import annotations

import numpy as np


def air_direction(alpha: np.ndarray | float, beta: np.ndarray | float) -> np.ndarray:
    """Unit air-relative velocity (..., 3) in FLU for angles (rad) of shape (...)."""
    a, b = np.broadcast_arrays(np.asarray(alpha, dtype=float), np.asarray(beta, dtype=float))
    return np.stack([np.cos(a) * np.cos(b), -np.sin(b), -np.sin(a) * np.cos(b)], axis=-1)


def air_direction_partials(alpha: np.ndarray | float, beta: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """(d/d alpha, d/d beta) of `air_direction`, each (..., 3)."""
    a, b = np.broadcast_arrays(np.asarray(alpha, dtype=float), np.asarray(beta, dtype=float))
    d_alpha = np.stack([-np.sin(a) * np.cos(b), np.zeros_like(a), -np.cos(a) * np.cos(b)], axis=-1)
    d_beta = np.stack([-np.cos(a) * np.sin(b), -np.cos(b), np.sin(a) * np.sin(b)], axis=-1)
    return d_alpha, d_beta


def air_velocity(speed: np.ndarray | float, alpha: np.ndarray | float, beta: np.ndarray | float) -> np.ndarray:
    """Air-relative velocity (..., 3) in FLU (m/s)."""
    return np.asarray(speed, dtype=float)[..., None] * air_direction(alpha, beta)


def air_angles(v_air: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(speed, alpha, beta) of air-relative velocities (..., 3) in FLU; alpha in (-pi, pi],
    beta in [-pi/2, pi/2]."""
    v = np.asarray(v_air, dtype=float)
    speed = np.linalg.norm(v, axis=-1)
    alpha = np.arctan2(-v[..., 2], v[..., 0])
    beta = np.arcsin(np.clip(-v[..., 1] / np.where(speed > 0.0, speed, 1.0), -1.0, 1.0))
    return speed, alpha, beta
