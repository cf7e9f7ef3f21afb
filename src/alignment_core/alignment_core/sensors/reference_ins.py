"""A reference INS: a navigation solution (attitude, ground velocity, position) with first-order
Gauss-Markov errors of stated sigma and correlation time, for scenarios where the aircraft has
no transfer-aligned INS (seed 004 flies from an airborne start; the paper takes its INS
attitude as given). The errors it reports are the ones it simulates (an honest covariance)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from alignment_core.geometry.rotations import quat_mul_batch, rotvec_to_quat_batch
from alignment_core.rng import stage_rng
from alignment_core.units import DEG
from alignment_core.validation import require


@dataclass(frozen=True)
class ReferenceInsConfig:
    """`enabled`; output `rate_hz`; per-axis 1-sigma of the attitude error (nav-frame rotation
    vector, deg), the ENU velocity error (m/s) and the height error (m), all first-order
    Gauss-Markov with `correlation_time_s`."""
    enabled: bool = False
    rate_hz: float = 10.0
    attitude_sigma_deg: float = 0.01
    velocity_sigma_mps: float = 0.05
    height_sigma_m: float = 5.0
    correlation_time_s: float = 300.0

    def validate(self) -> None:
        require(0.0 < self.rate_hz <= 1000.0, f"rate_hz must be in (0, 1000], got {self.rate_hz}")
        for name in ('attitude_sigma_deg', 'velocity_sigma_mps', 'height_sigma_m'):
            require(getattr(self, name) >= 0.0, f"{name} must be >= 0, got {getattr(self, name)}")
        require(self.correlation_time_s > 0.0, f"correlation_time_s must be > 0, got {self.correlation_time_s}")

    @property
    def period_ns(self) -> int:
        return int(round(1e9 / self.rate_hz))


@dataclass(frozen=True)
class ReferenceInsSample:
    """Solution at t_ns: q_nb (4,) body FLU -> local ENU, v_enu (3,), lat, lon (rad), h (m), and
    the error covariances: att_cov (3, 3) rad^2, vel_cov (3, 3), height_var."""
    t_ns: int
    q_nb: np.ndarray
    v_enu: np.ndarray
    lat: float
    lon: float
    h: float
    att_cov: np.ndarray
    vel_cov: np.ndarray
    height_var: float


class ReferenceInsStage:
    """Truth in, solutions out on the stage's own grid (t0_ns + k period_ns), reproducible from
    the seed; batch and sample-by-sample calls give the same numbers."""

    def __init__(self, cfg: ReferenceInsConfig, seed: int, t0_ns: int) -> None:
        cfg.validate()
        self.cfg, self.t0_ns = cfg, int(t0_ns)
        self.rng = stage_rng(seed, 'reference_ins')
        self.sigma = np.array([cfg.attitude_sigma_deg * DEG] * 3 + [cfg.velocity_sigma_mps] * 3 + [cfg.height_sigma_m])
        self.rho = math.exp(-cfg.period_ns * 1e-9 / cfg.correlation_time_s)
        self.err: np.ndarray | None = None
        self.next_k = 0

    def due(self, t_ns: int) -> bool:
        return t_ns >= self.t0_ns + self.next_k * self.cfg.period_ns

    def step(self, t_ns: int, q_nb: np.ndarray, v_enu: np.ndarray, lat: float, lon: float,
             h: float) -> ReferenceInsSample | None:
        """A solution if t_ns is on (or past) the next grid instant: truth plus the error there."""
        if not self.due(t_ns):
            return None
        k = self.next_k
        self.next_k = (t_ns - self.t0_ns) // self.cfg.period_ns + 1
        noise = self.rng.standard_normal(7)
        if self.err is None:
            self.err = self.sigma * noise
        else:
            steps = self.next_k - k
            rho = self.rho ** steps
            self.err = rho * self.err + math.sqrt(1.0 - rho * rho) * self.sigma * noise
        e = self.err
        q = quat_mul_batch(rotvec_to_quat_batch(e[:3]), np.asarray(q_nb, dtype=float))
        var = self.sigma**2
        return ReferenceInsSample(int(t_ns), q, np.asarray(v_enu, dtype=float) + e[3:6], float(lat), float(lon),
                                  float(h) + float(e[6]), np.diag(var[:3]), np.diag(var[3:6]), float(var[6]))
