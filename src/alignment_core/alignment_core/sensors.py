"""Sensor error models: slave IMU, master INS, laser Doppler velocimeter.

Slave IMU: random-constant gyro and accelerometer biases (1-sigma per axis, drawn once from
the seed), angle and velocity random walk added to the integrated increments, output as
mean rate and mean specific force over each interval (increment / interval).

Master INS: a ship INS in steady state (damped by log/GNSS for hours) has its tilt balancing
its accelerometer bias and its heading at the gyrocompass equilibrium, so its velocity error
does not grow: phi_E = -bias_N/g, phi_N = bias_E/g, phi_U = (Omega_U phi_N - eps_E)/Omega_N
(biases resolved in the nav frame at the start); plus white velocity noise and the gyro bias
on its body rate. Attitude convention: C_est = (I - [phi x]) C_true.

LDV: aircraft velocity relative to the deck in ship axes plus white noise; no measurement
(valid = False) when the aircraft is outside the beam along the catapult track.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from . import earth
from .attitude import DPH, G0, cross
from .config import require
from .rng import stage_rng
from .samples import AircraftTruth, ImuSample, LdvSample, MasterSample, ShipBatch, ShipSample

UG = 1e-6 * G0


@dataclass(frozen=True)
class ImuConfig:
    """Slave IMU grade (defaults: seed 000's slave, 0.01 deg/h and 100 ug, 1-sigma per axis)."""
    gyro_bias_dph: float = 0.01
    accel_bias_ug: float = 100.0
    arw_dpsh: float = 0.001           # angle random walk, deg/sqrt(h)
    vrw_ugpshz: float = 10.0          # velocity random walk, ug/sqrt(Hz)

    def validate(self) -> None:
        for k in ('gyro_bias_dph', 'accel_bias_ug', 'arw_dpsh', 'vrw_ugpshz'):
            v = getattr(self, k)
            require(0.0 <= v <= 1e6, f"{k} must be >= 0, got {v}")

    @property
    def arw(self) -> float:
        """Angle random walk, rad/sqrt(s)."""
        return self.arw_dpsh * np.pi / 180.0 / 60.0

    @property
    def vrw(self) -> float:
        """Velocity random walk, (m/s)/sqrt(s)."""
        return self.vrw_ugpshz * UG


class ImuErrorModel:
    """Adds the slave IMU's errors to ideal increments, sample by sample (deterministic)."""

    def __init__(self, cfg: ImuConfig, seed: int) -> None:
        self.cfg = cfg
        self.rng = stage_rng(seed, 'slave_imu')
        self.gyro_bias = self.rng.standard_normal(3) * cfg.gyro_bias_dph * DPH
        self.accel_bias = self.rng.standard_normal(3) * cfg.accel_bias_ug * UG

    def measure(self, t_ns: int, dtheta: np.ndarray, dv: np.ndarray, h: float) -> ImuSample:
        g, a = self.measure_batch(dtheta[None], dv[None], np.array([h]))
        return ImuSample(t_ns=t_ns, gyro=g[0], accel=a[0])

    def measure_batch(self, dtheta: np.ndarray, dv: np.ndarray, h: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray]:
        """Mean rate and specific force (K, 3) from K ideal increments over intervals h (K,);
        the noise sequence is the same whether drawn sample by sample or all at once."""
        n = self.rng.standard_normal((len(h), 6))
        hh = h[:, None]
        sh = np.sqrt(hh)
        dth = dtheta + self.gyro_bias * hh + n[:, :3] * self.cfg.arw * sh
        dvv = dv + self.accel_bias * hh + n[:, 3:] * self.cfg.vrw * sh
        return dth / hh, dvv / hh


@dataclass(frozen=True)
class MasterConfig:
    """Master ship INS grade (defaults: seed 000, 0.001 deg/h and 50 ug, 1-sigma per axis)."""
    gyro_bias_dph: float = 0.001
    accel_bias_ug: float = 50.0
    velocity_noise_mps: float = 0.001

    def validate(self) -> None:
        for k in ('gyro_bias_dph', 'accel_bias_ug', 'velocity_noise_mps'):
            require(getattr(self, k) >= 0.0, f"{k} must be >= 0, got {getattr(self, k)}")


class MasterInsModel:
    """Master INS solution = ship truth + steady-state INS errors."""

    def __init__(self, cfg: MasterConfig, seed: int, lat: float) -> None:
        self.cfg = cfg
        self.rng = stage_rng(seed, 'master_ins')
        eps = self.rng.standard_normal(3) * cfg.gyro_bias_dph * DPH        # nav axes
        nab = self.rng.standard_normal(3) * cfg.accel_bias_ug * UG
        g = float(earth.gravity(lat, 0.0))
        w_ie = earth.omega_ie_n(lat)
        phi_e = -nab[1] / g
        phi_n = nab[0] / g
        phi_u = (w_ie[2] * phi_n - eps[0]) / w_ie[1]
        self.phi = np.array([phi_e, phi_n, phi_u])
        self.err_rot = Rotation.from_rotvec(-self.phi)                    # C_est = exp(-phi) C
        self.gyro_bias_b = self.rng.standard_normal(3) * cfg.gyro_bias_dph * DPH

    def measure(self, s: ShipSample) -> MasterSample:
        return self.measure_batch(ShipBatch.of([s]))[0]

    def measure_batch(self, sb: ShipBatch) -> list[MasterSample]:
        c_true = Rotation.from_quat(sb.q_nb)
        v_n = c_true.apply(sb.v_b) + self.rng.standard_normal((len(sb), 3)) * self.cfg.velocity_noise_mps
        c_est = self.err_rot * c_true
        q = c_est.as_quat()
        v_b = c_est.inv().apply(v_n)
        w_b = sb.w_b + self.gyro_bias_b
        return [MasterSample(t_ns=int(sb.t_ns[k]), p_w=sb.p_w[k].copy(), q_nb=q[k], v_b=v_b[k],
                             w_b=w_b[k]) for k in range(len(sb))]


@dataclass(frozen=True)
class LdvConfig:
    """Laser Doppler velocimeter (seed 000: 0.01 m/s). Its beam runs along the catapult track
    (ship x axis) from `origin_m` (the aircraft's start spot, ship axes); it measures while the
    aircraft is within `track_length_m` along the track and `beam_halfwidth_m` across it."""
    noise_mps: float = 0.01
    origin_m: tuple[float, float, float] = (40.0, -10.0, 15.0)
    track_length_m: float = 95.0
    beam_halfwidth_m: float = 2.0

    def validate(self) -> None:
        require(0.0 < self.noise_mps <= 10.0, f"noise_mps must be in (0, 10], got {self.noise_mps}")
        require(self.track_length_m > 0.0, f"track_length_m must be > 0, got {self.track_length_m}")
        require(self.beam_halfwidth_m > 0.0, f"beam_halfwidth_m must be > 0, got {self.beam_halfwidth_m}")


class LdvModel:
    """Relative velocity of the aircraft w.r.t. the deck, from ship and aircraft truth."""

    def __init__(self, cfg: LdvConfig, seed: int, plane: earth.TangentPlane) -> None:
        self.cfg = cfg
        self.rng = stage_rng(seed, 'ldv')
        self.plane = plane

    def measure(self, s: ShipSample, a: AircraftTruth) -> LdvSample:
        return self.measure_batch(ShipBatch.of([s]), a.p_w[None], a.q_nb[None], a.v_b[None])[0]

    def measure_batch(self, sb: ShipBatch, p_a: np.ndarray, q_a: np.ndarray, v_a_b: np.ndarray
                      ) -> list[LdvSample]:
        """K measurements from ship samples and aircraft truth (positions, attitudes, body
        velocities, each (K, ...))."""
        cfg = self.cfg
        n = self.rng.standard_normal((len(sb), 3)) * cfg.noise_mps
        c_ns = Rotation.from_quat(sb.q_nb).inv()                           # C_n^s
        c_lw = np.swapaxes(self.plane.c_local_to_world(sb.p_w), -1, -2)  # world -> local ENU
        r = c_ns.apply(np.einsum('kij,kj->ki', c_lw, p_a - sb.p_w))
        d = r - np.asarray(cfg.origin_m)
        valid = ((d[:, 0] >= -cfg.beam_halfwidth_m) & (d[:, 0] <= cfg.track_length_m)
                 & (np.hypot(d[:, 1], d[:, 2]) <= cfg.beam_halfwidth_m))
        v_a_n = Rotation.from_quat(q_a).apply(v_a_b)
        v_s_n = Rotation.from_quat(sb.q_nb).apply(sb.v_b)
        v_rel = c_ns.apply(v_a_n - v_s_n) - cross(sb.w_b, r) + n
        zero = np.zeros(3)
        return [LdvSample(t_ns=int(sb.t_ns[k]), v_s=v_rel[k] if valid[k] else zero,
                          sigma=cfg.noise_mps, valid=bool(valid[k])) for k in range(len(sb))]
