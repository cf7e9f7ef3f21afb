"""Doppler radar (seed 001): the aircraft's ground velocity in its body axes (FLU).

A Doppler navigation radar measures the ground speed along the track and the drift angle
(track relative to the aircraft's x axis). Error model, all random constants drawn once
per seed (stream stage_rng(seed, 'doppler'); 1-sigma values in DopplerConfig) except the
noise (stream 'doppler_noise'):
    u = Rz(a) Ry(e) v_b                          boresight: azimuth a, pitch e (antenna axes)
    s = |u_xy|, D = atan2(u_y, u_x)              horizontal speed and drift angle
    s' = (1 + k) s + b,  D' = D + dD             scale factor k, speed bias b, drift-angle error dD
    v_meas = (s' cos D', s' sin D', (1 + k) u_z) + n,   n ~ N(0, sigma^2 I),
    sigma = noise_mps + noise_per_speed |v_b|    (speed-dependent noise)
As constants, the azimuth boresight and the drift-angle error act alike in level flight; they
differ once the aircraft banks or climbs. Own rate and latency: sensors/timing.py.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from alignment_core.rng import stage_rng
from alignment_core.samples import AircraftTruth, DopplerSample
from alignment_core.sensors.timing import SensorTiming
from alignment_core.units import ARCMIN
from alignment_core.validation import require


@dataclass(frozen=True)
class DopplerConfig:
    """Doppler radar (off by default). Seed 001 gives a total speed error of about 0.1 %:
    the defaults are scale 0.1 %, bias 0.05 m/s, boresight and drift-angle errors of a few
    arcminutes, noise 0.02 m/s + 0.1 % of speed (1-sigma)."""
    enabled: bool = False
    rate_hz: float = 10.0              # a divisor of the scenario rate (0 = the scenario rate)
    latency_s: float = 0.0
    scale_factor_ppm: float = 1000.0
    bias_mps: float = 0.05
    boresight_azimuth_arcmin: float = 3.0
    boresight_pitch_arcmin: float = 3.0
    drift_angle_arcmin: float = 2.0
    noise_mps: float = 0.02
    noise_per_speed: float = 0.001

    def validate(self) -> None:
        require(0.0 <= self.rate_hz <= 2000.0, f"rate_hz must be in [0, 2000], got {self.rate_hz}")
        require(0.0 <= self.latency_s <= 1.0, f"latency_s must be in [0, 1] s, got {self.latency_s}")
        require(0.0 <= self.scale_factor_ppm <= 1e5,
                f"scale_factor_ppm must be in [0, 1e5], got {self.scale_factor_ppm}")
        require(0.0 <= self.bias_mps <= 10.0, f"bias_mps must be in [0, 10], got {self.bias_mps}")
        for k in ('boresight_azimuth_arcmin', 'boresight_pitch_arcmin', 'drift_angle_arcmin'):
            v = getattr(self, k)
            require(0.0 <= v <= 600.0, f"{k} must be in [0, 600], got {v}")
        require(0.0 < self.noise_mps <= 10.0, f"noise_mps must be in (0, 10], got {self.noise_mps}")
        require(0.0 <= self.noise_per_speed <= 0.1,
                f"noise_per_speed must be in [0, 0.1], got {self.noise_per_speed}")




def rot_z(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rot_y(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


class DopplerRadarModel:
    """Body-frame ground velocity with the radar's errors (random constants per seed)."""

    def __init__(self, cfg: DopplerConfig, seed: int) -> None:
        self.cfg = cfg
        r = stage_rng(seed, 'doppler')
        z = r.standard_normal(5)
        self.scale = z[0] * cfg.scale_factor_ppm * 1e-6
        self.bias = z[1] * cfg.bias_mps
        self.azimuth = z[2] * cfg.boresight_azimuth_arcmin * ARCMIN
        self.pitch = z[3] * cfg.boresight_pitch_arcmin * ARCMIN
        self.drift = z[4] * cfg.drift_angle_arcmin * ARCMIN
        self.boresight = rot_z(self.azimuth) @ rot_y(self.pitch)
        self.rng = stage_rng(seed, 'doppler_noise')

    def reading(self, v_b: np.ndarray) -> np.ndarray:
        """Noise-free readings (K, 3) of true body velocities v_b (K, 3)."""
        u = np.asarray(v_b, dtype=float) @ self.boresight.T
        s = (1.0 + self.scale) * np.hypot(u[:, 0], u[:, 1]) + self.bias
        d = np.arctan2(u[:, 1], u[:, 0]) + self.drift
        return np.c_[s * np.cos(d), s * np.sin(d), (1.0 + self.scale) * u[:, 2]]

    def sigma(self, v_b: np.ndarray) -> np.ndarray:
        """Noise 1-sigma (K,) at true body velocities v_b (K, 3)."""
        return self.cfg.noise_mps + self.cfg.noise_per_speed * np.linalg.norm(v_b, axis=1)

    def measure_batch(self, t_ns: np.ndarray, v_b: np.ndarray) -> list[DopplerSample]:
        v_b = np.asarray(v_b, dtype=float).reshape(-1, 3)
        sig = self.sigma(v_b)
        out = self.reading(v_b) + self.rng.standard_normal((len(v_b), 3)) * sig[:, None]
        return [DopplerSample(t_ns=int(t_ns[k]), v_b=out[k], sigma=float(sig[k]), valid=True)
                for k in range(len(v_b))]

    def measure(self, a: AircraftTruth) -> DopplerSample:
        return self.measure_batch(np.array([a.t_ns]), a.v_b[None])[0]


class DopplerStage:
    """Aircraft truth in -> Doppler samples at the radar's rate, stamped t + latency and
    released when simulation time reaches the stamp (node: `step`; batch: `run_batch`)."""

    def __init__(self, cfg: DopplerConfig, seed: int, base_rate_hz: float, t0_ns: int) -> None:
        self.model = DopplerRadarModel(cfg, seed)
        self.timing = SensorTiming(cfg.rate_hz, cfg.latency_s, base_rate_hz, t0_ns)

    def _stamped(self, samples: list[DopplerSample]) -> list[DopplerSample]:
        lat = self.timing.latency_ns
        if not lat:
            return samples
        return [DopplerSample(t_ns=s.t_ns + lat, v_b=s.v_b, sigma=s.sigma, valid=s.valid) for s in samples]

    def step(self, a: AircraftTruth) -> list[DopplerSample]:
        new = self._stamped([self.model.measure(a)]) if self.timing.due(a.t_ns) else []
        return self.timing.release(a.t_ns, new)

    def run_batch(self, t_ns: np.ndarray, v_b: np.ndarray) -> list[DopplerSample]:
        idx = np.flatnonzero(self.timing.due_mask(t_ns))
        out = self.model.measure_batch(t_ns[idx], v_b[idx]) if len(idx) else []
        return self.timing.release_batch(self._stamped(out), int(t_ns[-1]))
