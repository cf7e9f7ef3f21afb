"""Sensor error models: slave IMU, master INS, laser Doppler velocimeter.

Slave IMU: random-constant gyro and accelerometer biases (1-sigma per axis, drawn once from
the seed), angle and velocity random walk added to the integrated increments, output as
mean rate and mean specific force over each interval (increment / interval). Optional (off by
default, own RNG streams so the default numbers do not change): first-order Gauss-Markov bias
instability (bias over each interval = the state at its start), scale factor and
non-orthogonality applied to the ideal increments; imu.output = 'sample' makes the ideal part a
point value (aircraft.py).

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
from typing import Literal

import numpy as np
from scipy.spatial.transform import Rotation

from . import earth
from .attitude import ARCSEC, DPH, G0, cross
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
    # 'increment': mean rate / specific force over each interval (integrated increments);
    # 'sample': their point values at the sample instant (aliasing visible; seed 000's model)
    output: Literal['increment', 'sample'] = 'increment'
    # bias instability: first-order Gauss-Markov per axis (1-sigma, correlation time), on top
    # of the random constants; stream stage_rng(seed, 'slave_imu_gm'). 0 = off.
    gyro_bias_instability_dph: float = 0.0
    accel_bias_instability_ug: float = 0.0
    bias_corr_time_s: float = 100.0
    # scale factor (ppm) and non-orthogonality (arcsec, each off-diagonal element), 1-sigma,
    # drawn once from stage_rng(seed, 'slave_imu_scale'); output = (I + S) ideal. 0 = off.
    gyro_scale_ppm: float = 0.0
    accel_scale_ppm: float = 0.0
    gyro_nonorth_arcsec: float = 0.0
    accel_nonorth_arcsec: float = 0.0

    def validate(self) -> None:
        for k in ('gyro_bias_dph', 'accel_bias_ug', 'arw_dpsh', 'vrw_ugpshz',
                  'gyro_bias_instability_dph', 'accel_bias_instability_ug', 'gyro_scale_ppm',
                  'accel_scale_ppm', 'gyro_nonorth_arcsec', 'accel_nonorth_arcsec'):
            v = getattr(self, k)
            require(0.0 <= v <= 1e6, f"{k} must be >= 0, got {v}")
        require(0.0 < self.bias_corr_time_s <= 1e6,
                f"bias_corr_time_s must be in (0, 1e6], got {self.bias_corr_time_s}")

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
        self.scale = None
        if cfg.gyro_scale_ppm or cfg.accel_scale_ppm or cfg.gyro_nonorth_arcsec or cfg.accel_nonorth_arcsec:
            r = stage_rng(seed, 'slave_imu_scale')
            off = ~np.eye(3, dtype=bool)
            m = np.zeros((2, 3, 3))
            for i, (sf, no) in enumerate(((cfg.gyro_scale_ppm, cfg.gyro_nonorth_arcsec),
                                          (cfg.accel_scale_ppm, cfg.accel_nonorth_arcsec))):
                d = r.standard_normal(3) * sf * 1e-6
                o = r.standard_normal(6) * no * ARCSEC
                m[i][np.diag_indices(3)] = 1.0 + d
                m[i][off] = o
            self.scale = m                                                 # (I + S) gyro, accel
        self.gm_sigma = np.r_[np.full(3, cfg.gyro_bias_instability_dph * DPH),
                              np.full(3, cfg.accel_bias_instability_ug * UG)]
        self.gm = None
        if np.any(self.gm_sigma > 0.0):
            self.gm_rng = stage_rng(seed, 'slave_imu_gm')
            self.gm = self.gm_rng.standard_normal(6) * self.gm_sigma       # stationary start

    def _gm_batch(self, h: np.ndarray) -> np.ndarray:
        """Bias-instability state over each interval (K, 6); advanced sample by sample."""
        n = self.gm_rng.standard_normal((len(h), 6))
        phi = np.exp(-h / self.cfg.bias_corr_time_s)
        q = np.sqrt(1.0 - phi**2)
        out = np.empty((len(h), 6))
        b = self.gm
        for k in range(len(h)):
            out[k] = b
            b = phi[k] * b + q[k] * self.gm_sigma * n[k]
        self.gm = b
        return out

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
        if self.scale is not None:
            dtheta = dtheta @ self.scale[0].T
            dv = dv @ self.scale[1].T
        dth = dtheta + self.gyro_bias * hh + n[:, :3] * self.cfg.arw * sh
        dvv = dv + self.accel_bias * hh + n[:, 3:] * self.cfg.vrw * sh
        if self.gm is not None:
            b = self._gm_batch(h)
            dth = dth + b[:, :3] * hh
            dvv = dvv + b[:, 3:] * hh
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
