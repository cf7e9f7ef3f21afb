"""Slave IMU error model: what the aircraft's strapdown IMU adds to the ideal increments.

Per interval (t_{k-1}, t_k] of length h, with ideal increments (dtheta, dv) from aircraft/kinematics.py:
    dtheta_out = Q_a[ (I + S_g) dtheta + (b_g + b_gm + b_rw) h + G dv + arw sqrt(h) n ]
    dv_out     = Q_v[ (I + S_a) dv     + (b_a + b_am + b_arw) h      + vrw sqrt(h) n ]
and the output is increment / interval (mean rate, mean specific force).
- b: random-constant biases (1-sigma per axis, drawn once from stage_rng(seed, 'slave_imu'),
  which also gives the white noise: today's numbers);
- b_gm: first-order Gauss-Markov bias instability (stream 'slave_imu_gm');
- b_rw: rate random walk / acceleration random walk, a bias random walk starting at zero,
  variance sigma^2 t (stream 'slave_imu_rrw');
- S: scale factor and non-orthogonality (stream 'slave_imu_scale');
- G: g-sensitivity of the gyro bias (rad/s per m/s^2 of specific force, a full 3x3 matrix,
  1-sigma per element, stream 'slave_imu_gsens'); over an interval it adds G dv exactly;
- Q: quantisation of the output increments to an LSB, the residual carried to the next
  sample (the running sum of the output equals the running sum of the input rounded to the
  LSB, so the error never accumulates beyond half an LSB and does not bias).
The time-varying biases hold their value at the start of each interval. Each effect has its
own random stream and is off (zero) by default, so the default numbers never change.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from alignment_core.geometry.rotations import rows_matmul
from alignment_core.rng import stage_rng
from alignment_core.samples import ImuSample
from alignment_core.units import ARCSEC, DPH, G0, UG
from alignment_core.validation import require


@dataclass(frozen=True)
class ImuConfig:
    """Slave IMU grade (defaults: seed 000's slave, 0.01 deg/h and 100 ug, 1-sigma per axis).
    `preset` names a grade in sensors/presets.py IMU_PRESETS; it fills the keys a scenario does
    not give (resolved when the scenario is loaded; explicit keys win)."""
    preset: str = ''
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
    # rate random walk (bias random walk, variance sigma^2 t): gyro deg/h per sqrt(s), accel
    # ug per sqrt(s) (the units of the filter's gyro_bias_rw_dphps / accel_bias_rw_ugps). 0 = off.
    gyro_bias_rw_dphps: float = 0.0
    accel_bias_rw_ugps: float = 0.0
    # quantisation of the output increments (LSB of delta-theta, arcsec; of delta-v, m/s). 0 = off.
    angle_quantum_arcsec: float = 0.0
    velocity_quantum_mps: float = 0.0
    # g-sensitive gyro bias, deg/h per g of specific force, 1-sigma per matrix element. 0 = off.
    gyro_g_sensitivity_dphpg: float = 0.0

    NONNEGATIVE = ('gyro_bias_dph', 'accel_bias_ug', 'arw_dpsh', 'vrw_ugpshz',
                   'gyro_bias_instability_dph', 'accel_bias_instability_ug', 'gyro_scale_ppm',
                   'accel_scale_ppm', 'gyro_nonorth_arcsec', 'accel_nonorth_arcsec',
                   'gyro_bias_rw_dphps', 'accel_bias_rw_ugps', 'gyro_g_sensitivity_dphpg')

    def validate(self) -> None:
        from alignment_core.sensors.presets import IMU_PRESETS, check_preset
        check_preset('imu', self.preset, IMU_PRESETS)
        for k in self.NONNEGATIVE:
            v = getattr(self, k)
            require(0.0 <= v <= 1e6, f"{k} must be in [0, 1e6], got {v}")
        require(0.0 < self.bias_corr_time_s <= 1e6,
                f"bias_corr_time_s must be in (0, 1e6], got {self.bias_corr_time_s}")
        require(0.0 <= self.angle_quantum_arcsec <= 3600.0,
                f"angle_quantum_arcsec must be in [0, 3600], got {self.angle_quantum_arcsec}")
        require(0.0 <= self.velocity_quantum_mps <= 1.0,
                f"velocity_quantum_mps must be in [0, 1], got {self.velocity_quantum_mps}")

    @property
    def arw(self) -> float:
        """Angle random walk, rad/sqrt(s)."""
        return self.arw_dpsh * np.pi / 180.0 / 60.0

    @property
    def vrw(self) -> float:
        """Velocity random walk, (m/s)/sqrt(s)."""
        return self.vrw_ugpshz * UG


class Quantiser:
    """Rounds increments to an LSB per channel, carrying the residual (running sums)."""

    def __init__(self, lsb: np.ndarray) -> None:
        self.lsb = np.asarray(lsb, dtype=float)
        self.on = self.lsb > 0.0
        self.total_in = np.zeros(len(self.lsb))      # running sum of the input
        self.total_out = np.zeros(len(self.lsb))     # running sum of the output (LSB multiples)

    def __call__(self, d: np.ndarray) -> np.ndarray:
        """Quantised increments (K, C) of d (K, C); sequential sums, so stepping = batch."""
        s = np.cumsum(np.vstack([self.total_in, d]), axis=0)[1:]
        e = np.where(self.on, np.round(s / np.where(self.on, self.lsb, 1.0)) * self.lsb, s)
        out = np.diff(np.vstack([self.total_out, e]), axis=0)
        out[:, ~self.on] = d[:, ~self.on]
        self.total_in, self.total_out = s[-1].copy(), e[-1].copy()
        return out


class ImuErrorModel:
    """Adds the slave IMU's errors to ideal increments, sample by sample (deterministic).
    After each call `last_bias` (K, 6) holds the additive gyro (rad/s) and accelerometer
    (m/s^2) bias of each interval: constant + instability + random walk + g-sensitivity
    (mean over the interval); the truth for scoring a filter's bias states."""

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
        self.gm: np.ndarray | None = None
        if np.any(self.gm_sigma > 0.0):
            self.gm_rng = stage_rng(seed, 'slave_imu_gm')
            self.gm = self.gm_rng.standard_normal(6) * self.gm_sigma       # stationary start
        self.rw_sigma = np.r_[np.full(3, cfg.gyro_bias_rw_dphps * DPH),
                              np.full(3, cfg.accel_bias_rw_ugps * UG)]
        self.rw: np.ndarray | None = None
        if np.any(self.rw_sigma > 0.0):
            self.rw_rng = stage_rng(seed, 'slave_imu_rrw')
            self.rw = np.zeros(6)                                          # starts at zero
        self.g_sens = None
        if cfg.gyro_g_sensitivity_dphpg > 0.0:
            self.g_sens = (stage_rng(seed, 'slave_imu_gsens').standard_normal((3, 3))
                           * cfg.gyro_g_sensitivity_dphpg * DPH / G0)     # rad/s per m/s^2
        self.quant = None
        if cfg.angle_quantum_arcsec > 0.0 or cfg.velocity_quantum_mps > 0.0:
            self.quant = Quantiser(np.r_[np.full(3, cfg.angle_quantum_arcsec * ARCSEC),
                                         np.full(3, cfg.velocity_quantum_mps)])
        self.last_bias = np.zeros((0, 6))

    def _gm_batch(self, h: np.ndarray) -> np.ndarray:
        """Bias-instability state over each interval (K, 6); advanced sample by sample."""
        n = self.gm_rng.standard_normal((len(h), 6))
        phi = np.exp(-h / self.cfg.bias_corr_time_s)
        q = np.sqrt(1.0 - phi**2)
        out = np.empty((len(h), 6))
        b = self.gm
        assert b is not None                            # called only with the bias instability on
        for k in range(len(h)):
            out[k] = b
            b = phi[k] * b + q[k] * self.gm_sigma * n[k]
        self.gm = b
        return out

    def _rw_batch(self, h: np.ndarray) -> np.ndarray:
        """Bias random-walk state over each interval (K, 6): b_k+1 = b_k + sigma sqrt(h) n."""
        steps = self.rw_rng.standard_normal((len(h), 6)) * self.rw_sigma * np.sqrt(h)[:, None]
        assert self.rw is not None                      # called only with the bias random walk on
        walk = np.cumsum(np.vstack([self.rw, steps]), axis=0)
        self.rw = walk[-1].copy()
        return walk[:-1]

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
        dv_ideal = dv
        if self.scale is not None:
            dtheta = rows_matmul(dtheta, self.scale[0].T)
            dv = rows_matmul(dv, self.scale[1].T)
        dth = dtheta + self.gyro_bias * hh + n[:, :3] * self.cfg.arw * sh
        dvv = dv + self.accel_bias * hh + n[:, 3:] * self.cfg.vrw * sh
        bias = np.broadcast_to(np.r_[self.gyro_bias, self.accel_bias], (len(h), 6))
        if self.gm is not None:
            b = self._gm_batch(h)
            dth = dth + b[:, :3] * hh
            dvv = dvv + b[:, 3:] * hh
            bias = bias + b
        if self.rw is not None:
            b = self._rw_batch(h)
            dth = dth + b[:, :3] * hh
            dvv = dvv + b[:, 3:] * hh
            bias = bias + b
        if self.g_sens is not None:
            gs = rows_matmul(dv_ideal, self.g_sens.T)
            dth = dth + gs
            bias = bias + np.c_[gs / hh, np.zeros((len(h), 3))]
        if self.quant is not None:
            q = self.quant(np.c_[dth, dvv])
            dth, dvv = q[:, :3], q[:, 3:]
        self.last_bias = np.array(bias)
        return dth / hh, dvv / hh
