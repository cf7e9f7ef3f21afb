"""The INS-consistency check shared by the navigation, aircraft and ship tests: noise-free slave
IMU increments (pipeline.SlaveImuStage with the IMU's noise and biases off) integrated by the
strapdown from the true initial state must reproduce the true attitude and velocity."""
from __future__ import annotations

import numpy as np

from alignment_core import evaluation, pipeline
from alignment_core.samples import ShipBatch

NOISE_OFF = {'imu.gyro_bias_dph': 0.0, 'imu.accel_bias_ug': 0.0, 'imu.arw_dpsh': 0.0,
             'imu.vrw_ugpshz': 0.0}
ATT_TOL = 1e-6            # rad
VEL_TOL = 1e-3            # m/s


def simulate(sc) -> tuple[list, dict, list]:
    """Ship samples, aircraft truth dict and ideal IMU samples for the whole scenario."""
    ship_list = pipeline.ship_samples(sc)
    truth, imu = pipeline.SlaveImuStage(sc).run_batch(ShipBatch.of(ship_list))
    return ship_list, truth, imu


def integrate(sc, truth: dict, imu: list) -> tuple[np.ndarray, np.ndarray]:
    """Strapdown from the true initial state: attitude (rad) and velocity (m/s) error norms
    after each IMU sample."""
    return evaluation.strapdown_errors(pipeline.plane_of(sc), sc.t0_ns, truth, imu)


def strapdown_errors(sc) -> tuple[np.ndarray, np.ndarray, dict]:
    """simulate + integrate in one call: (attitude errors, velocity errors, truth dict)."""
    _, truth, imu = simulate(sc)
    att, vel = integrate(sc, truth, imu)
    return att, vel, truth
