"""INS consistency check: integrate a slave IMU's increments with the project's strapdown from
the true initial state and compare with the aircraft truth, sample by sample. Noise-free, the
errors measure how faithfully the simulator's increments represent its own truth."""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from alignment_core.geometry.earth import TangentPlane
from alignment_core.navigation.strapdown import NavState, Strapdown
from alignment_core.samples import ImuSample


def strapdown_errors(plane: TangentPlane, t0_ns: int, truth: dict[str, np.ndarray],
                     imu: list[ImuSample]) -> tuple[np.ndarray, np.ndarray]:
    """Attitude (rad) and velocity (m/s) error norms after each IMU sample, shape (K,).

    truth: arrays 'q_nb' (K+1, 4), 'v_b' (K+1, 3), 'p_w' (K+1, 3) at the sample instants
    (SlaveImuStage.run_batch's first output); imu: the K samples ending at instants 1..K."""
    c_true = Rotation.from_quat(truth['q_nb']).as_matrix()
    v_true = np.einsum('kij,kj->ki', c_true, truth['v_b'])
    bad = ~(np.isfinite(v_true).all(axis=1) & np.isfinite(truth['p_w']).all(axis=1))
    if bad.any():
        raise ValueError(f'aircraft truth is not finite at {bad.sum()} of {len(bad)} samples')
    lat, lon, h = plane.to_geodetic(truth['p_w'][0])
    sd = Strapdown(NavState(q_nb=truth['q_nb'][0].copy(), v_n=v_true[0].copy(), lat=float(lat),
                            lon=float(lon), h=float(h)))
    t_prev = t0_ns
    q = np.empty((len(imu), 4))
    v = np.empty((len(imu), 3))
    for k, s in enumerate(imu):
        dt = (s.t_ns - t_prev) * 1e-9
        t_prev = s.t_ns
        # the sample is the mean rate / specific force over its interval: increment = value * dt
        sd.update(s.gyro * dt, s.accel * dt, dt)
        q[k] = sd.s.q_nb
        v[k] = sd.s.v_n
    att = np.linalg.norm((Rotation.from_matrix(c_true[1:]).inv() * Rotation.from_quat(q)).as_rotvec(),
                         axis=-1)
    return att, np.linalg.norm(v - v_true[1:], axis=-1)
