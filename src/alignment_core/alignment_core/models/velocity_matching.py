"""Velocity-matching error model: phi (3), dV (3), gyro bias eps (3), accel bias (3) = 12
states, optionally + the master INS attitude error phi_m (3) = 15 states.

Nav frame ENU, attitude error C_est = (I - [phi x]) C_true, dV = V_est - V_true; biases are
the residuals of the body-frame sensor biases after compensation (random constants with an
optional random walk). Continuous model (Titterton & Weston 10; PSINS):
  phi'  = -[w_in x] phi - C_b^n eps                     + w_g
  dV'   = [f^n x] phi - [(2 w_ie + w_en) x] dV + C_b^n nabla + w_a
Discretised over h as Phi = I + F h + (F h)^2 / 2 and Qd = G Qc G^T h.
Measurement: z = V_slave - (V_master + C_m^n (w_m x r) + C_m^n v_LDV) = dV + v, H = [0 I 0 0].

Master attitude states (random constants, phi_m' = 0): the master reports C_m,est =
(I - [phi_m x]) C_m. Its nav velocity is exact by construction of the message (it is rotated
back with its own attitude), but the lever-arm and LDV terms u = C_m,est (w_m x r + v_LDV)
are rotated with the erroneous attitude, so z = dV - [u x] phi_m + v, H = [0 I 0 0 -[u x]].
The aircraft-vs-master misalignment error is phi - phi_m: without these states the filter
reports the slave's alignment to a master it believes perfect, and its sigma is too small
whenever the master's own attitude error matters (a long deck alignment).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

LABELS = ('phi_E', 'phi_N', 'phi_U', 'dV_E', 'dV_N', 'dV_U', 'eps_x', 'eps_y', 'eps_z',
          'nabla_x', 'nabla_y', 'nabla_z')
MASTER_LABELS = ('phim_E', 'phim_N', 'phim_U')
N = 12
H = np.hstack([np.zeros((3, 3)), np.eye(3), np.zeros((3, 6))])


def labels(master_states: bool) -> tuple[str, ...]:
    return LABELS + MASTER_LABELS if master_states else LABELS


def measurement(u_n: np.ndarray, n: int = N) -> np.ndarray:
    """H (3, n); for n = 15 the master-attitude block is -[u x] with u the rotated lever-arm
    plus LDV velocity (nav frame)."""
    if n == N:
        return H
    h = np.zeros((3, n))
    h[0, 3] = h[1, 4] = h[2, 5] = 1.0
    _skew_into(h, 0, 12, -u_n)
    return h


@dataclass(frozen=True)
class NoiseDensities:
    """Continuous white-noise densities: arw rad/sqrt(s), vrw m/s/sqrt(s), bias random walks."""
    arw: float
    vrw: float
    gyro_bias_rw: float
    accel_bias_rw: float


_EYE = {12: np.eye(12), 15: np.eye(15)}


def transition(c_nb: np.ndarray, f_n: np.ndarray, w_ie: np.ndarray, w_en: np.ndarray,
               h: float, n: int = N) -> np.ndarray:
    """Phi (n, n) over an interval h, from the mean attitude, specific force and rates."""
    fh = np.zeros((n, n))
    _skew_into(fh, 0, 0, -h * (w_ie + w_en))
    fh[0:3, 6:9] = -h * c_nb
    _skew_into(fh, 3, 0, h * f_n)
    _skew_into(fh, 3, 3, -h * (2.0 * w_ie + w_en))
    fh[3:6, 9:12] = h * c_nb
    return _EYE[n] + fh + 0.5 * (fh @ fh)


def _skew_into(m: np.ndarray, r: int, c: int, v: np.ndarray) -> None:
    """Write [v x] into the 3x3 block of m at (r, c) (faster than building it apart)."""
    x, y, z = v[0], v[1], v[2]
    m[r, c + 1] = -z
    m[r, c + 2] = y
    m[r + 1, c] = z
    m[r + 1, c + 2] = -x
    m[r + 2, c] = -y
    m[r + 2, c + 1] = x


def process_noise(q: NoiseDensities, h: float, n: int = N) -> np.ndarray:
    """Qd (n, n) = G Qc G^T h. The sensor noises are white and isotropic per triad, so
    C_b^n Qc C_b^nT = Qc and Qd does not depend on the attitude; phi_m has no process noise."""
    return np.diag(np.repeat([q.arw**2 * h, q.vrw**2 * h, q.gyro_bias_rw**2 * h,
                              q.accel_bias_rw**2 * h, 0.0][:n // 3], 3))
