"""Wind truth: a mean wind plus Dryden turbulence (MIL-F-8785C), sampled along a flight.

The wind is the velocity of the air mass over the ground in the local-level ENU frame
("blowing to"); the aircraft's air-relative velocity is v_a = v_ground - wind.

Dryden turbulence (MIL-F-8785C, frozen field flown through at the airspeed V). One-sided
spectra in spatial frequency Omega (rad/m), sigma^2 = int_0^inf Phi dOmega:
    Phi_u = sigma_u^2 (2 L_u / pi) / (1 + (L_u Omega)^2)
    Phi_v = sigma_v^2 (L_v / pi) (1 + 3 (L_v Omega)^2) / (1 + (L_v Omega)^2)^2     (w: same form)
and in time, omega = V Omega, Phi(omega) = Phi(Omega) / V. Components: u along the flight
track (horizontal), v horizontal to its left, w up.
Scale lengths and intensities by height above ground h (feet in the specification):
- h < 1000 ft: L_w = h, L_u = L_v = h / (0.177 + 0.000823 h)^1.2, sigma_w = 0.1 W20,
  sigma_u = sigma_v = sigma_w / (0.177 + 0.000823 h)^0.4, W20 the wind at 20 ft: 15, 30 and
  45 kt for light, moderate and severe turbulence;
- h > 2000 ft: L = 1750 ft for all three, sigma_u = sigma_v = sigma_w from the specification's
  probability-of-exceedance chart (Figure 7), interpolated linearly in height: light 1e-2,
  moderate 1e-3, severe 1e-5;
- in between, every sigma and L linearly from its 1000 ft value to its 2000 ft value.
h is clipped to [10 ft, 80 000 ft] and V to at least 1 m/s; the height is taken as the height
above mean sea level (a carrier's deck is at sea level).

Realisation. Each component is sigma(t) times a unit-variance process of the dimensionless
time s = int V/L dt (trapezoid between samples): u' = -u + sqrt(2) n (first order); v and w
from the critically damped pair z'' + 2 z' + z = n, y = z + sqrt(3) z' (d/ds), whose stationary
state covariance is I/4 for every L and V. Over a step Delta s the transition is exact,
Phi = e^{-Delta s} [[1 + Delta s, Delta s], [-Delta s, 1 - Delta s]] (u: e^{-Delta s}), with
process noise Q = P - Phi P Phi^T (P the stationary covariance): exact for constant V/L over
the step, and the state stays stationary when V, L or sigma change. The first sample is drawn
from the stationary distribution. The recursion x_k = Phi_k x_(k-1) + w_k is evaluated by a doubling
scan within chunks of samples and one short loop over the chunks. Random numbers come from
rng.stage_rng(seed, 'wind'); successive calls continue the same process, so sampling in
chunks gives the batch result.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from alignment_core.air_data.turbulence_spec import (  # noqa: F401 (re-exported)
    FT,
    HIGH_ALTITUDE_SCALE_FT,
    MIN_AIRSPEED,
    W20_KNOTS,
    DrydenParameters,
    Severity,
    dryden_parameters,
)
from alignment_core.rng import stage_rng
from alignment_core.validation import require


@dataclass(frozen=True)
class WindConfig:
    """Mean wind (ENU, blowing to, m/s) and Dryden turbulence severity; `w20_mps` > 0
    replaces the severity's wind at 20 ft for the low-altitude intensities."""
    mean_enu_mps: tuple[float, float, float] = (0.0, 0.0, 0.0)
    severity: Severity = 'none'
    w20_mps: float = 0.0

    def validate(self) -> None:
        require(all(abs(v) <= 200.0 for v in self.mean_enu_mps), f"mean wind within +-200 m/s: {self.mean_enu_mps}")
        require(0.0 <= self.w20_mps <= 100.0, f"w20_mps must be in [0, 100], got {self.w20_mps}")


def _transition_second_order(ds: np.ndarray) -> np.ndarray:
    """Phi (N, 2, 2) of z'' + 2 z' + z = n over dimensionless steps ds (N,)."""
    e = np.exp(-ds)
    return e[:, None, None] * np.stack([np.stack([1.0 + ds, ds], -1), np.stack([-ds, 1.0 - ds], -1)], -2)


def _noise_root(phi: np.ndarray, p_stat: np.ndarray) -> np.ndarray:
    """Symmetric square root (N, n, n), n = 1 or 2, of Q = P - Phi P Phi^T, in closed form:
    sqrt(Q) = (Q + sqrt(det Q) I) / sqrt(tr Q + 2 sqrt(det Q)) for 2 x 2 (round-off clipped)."""
    q = p_stat - phi @ p_stat @ np.swapaxes(phi, -1, -2)
    if q.shape[-1] == 1:
        return np.sqrt(np.maximum(q, 0.0))
    q = 0.5 * (q + np.swapaxes(q, -1, -2))
    root_det = np.sqrt(np.maximum(q[:, 0, 0] * q[:, 1, 1] - q[:, 0, 1] ** 2, 0.0))
    norm = np.sqrt(np.maximum(q[:, 0, 0] + q[:, 1, 1] + 2.0 * root_det, 0.0))
    scale = np.divide(1.0, norm, out=np.zeros_like(norm), where=norm > 0.0)
    return (q + root_det[:, None, None] * np.eye(2)) * scale[:, None, None]


def linear_recurrence(phi: np.ndarray, w: np.ndarray, x0: np.ndarray, chunk: int = 128) -> np.ndarray:
    """x_k = Phi_k x_(k-1) + w_k for k = 0..N-1 from x_(-1) = x0: phi (N, n, n), w (N, n),
    x0 (n,) -> (N, n). Within chunks of `chunk` samples a doubling scan composes the affine
    maps (log2(chunk) vectorised passes); the chunks' start states then follow in one loop."""
    n_samples, n = w.shape
    n_chunks = -(-n_samples // chunk)
    pad = n_chunks * chunk - n_samples
    a = np.concatenate([phi, np.broadcast_to(np.eye(n), (pad, n, n))]).reshape(n_chunks, chunk, n, n)
    b = np.concatenate([w, np.zeros((pad, n))]).reshape(n_chunks, chunk, n)
    d = 1
    while d < chunk:
        b[:, d:] = (a[:, d:] @ b[:, :-d, :, None])[..., 0] + b[:, d:]
        a[:, d:] = a[:, d:] @ a[:, :-d]
        d *= 2
    starts = np.empty((n_chunks, n))
    x = np.asarray(x0, dtype=float)
    for c in range(n_chunks):
        starts[c] = x
        x = a[c, -1] @ x + b[c, -1]
    return ((a @ starts[:, None, :, None])[..., 0] + b).reshape(-1, n)[:n_samples]


_BLOCKS = ((slice(0, 1), 1), (slice(1, 3), 2), (slice(3, 5), 2))   # state columns of u, v, w and their order


class WindField:
    """Mean wind plus turbulence along a flight, reproducible from the scenario seed."""

    def __init__(self, cfg: WindConfig, seed: int) -> None:
        self.cfg = cfg
        self.rng = stage_rng(seed, 'wind')
        self._last: tuple[float, np.ndarray, np.ndarray] | None = None     # (t, V/L per component, state)

    def _unit_processes(self, t: np.ndarray, rate: np.ndarray) -> np.ndarray:
        """States (N, 5) of the unit processes [u | z_v, z_v' | z_w, z_w'] at times t for the
        rates V/L (N, 3), continuing the previous call."""
        noise = self.rng.standard_normal((len(t), 5))
        if self._last is None:
            t_prev, prev_rate, x_prev = t[0], rate[0], np.zeros(5)
        else:
            t_prev, prev_rate, x_prev = self._last
        dt = np.diff(t, prepend=t_prev)
        if np.any(dt < 0.0):
            raise ValueError("wind samples must come in increasing time")
        ds = 0.5 * dt[:, None] * (rate + np.concatenate([prev_rate[None, :], rate[:-1]]))   # (N, 3)
        x = np.empty((len(t), 5))
        for k, (cols, order) in enumerate(_BLOCKS):
            if order == 1:
                phi, p_stat = np.exp(-ds[:, k])[:, None, None], np.eye(1)
            else:
                phi, p_stat = _transition_second_order(ds[:, k]), 0.25 * np.eye(2)
            root = _noise_root(phi, p_stat)
            if self._last is None:               # the first sample is drawn from the stationary law
                phi[0], root[0] = 0.0, np.sqrt(p_stat)
            x[:, cols] = linear_recurrence(phi, (root @ noise[:, cols, None])[..., 0], x_prev[cols])
        self._last = (float(t[-1]), rate[-1].copy(), x[-1].copy())
        return x

    def turbulence(self, t: np.ndarray, height_m: np.ndarray | float, airspeed_mps: np.ndarray | float,
                   track_rad: np.ndarray | float = 0.0) -> np.ndarray:
        """Turbulence (N, 3) in ENU at increasing times t (N,) for the aircraft's height (m),
        airspeed (m/s) and track (rad, ROS yaw: from East, counter-clockwise)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        n = len(t)
        if self.cfg.severity == 'none':
            return np.zeros((n, 3))
        h = np.broadcast_to(np.asarray(height_m, dtype=float), (n,))
        speed = np.maximum(np.broadcast_to(np.asarray(airspeed_mps, dtype=float), (n,)), MIN_AIRSPEED)
        track = np.broadcast_to(np.asarray(track_rad, dtype=float), (n,))
        par = dryden_parameters(h, self.cfg.severity, self.cfg.w20_mps)
        x = self._unit_processes(t, np.stack([speed / par.length_u, speed / par.length_v, speed / par.length_w], -1))
        u = par.sigma_u * x[:, 0]
        v = par.sigma_v * (x[:, 1] + np.sqrt(3.0) * x[:, 2])
        w = par.sigma_w * (x[:, 3] + np.sqrt(3.0) * x[:, 4])
        c, s = np.cos(track), np.sin(track)
        return np.stack([c * u - s * v, s * u + c * v, w], axis=-1)

    def wind(self, t: np.ndarray, height_m: np.ndarray | float, airspeed_mps: np.ndarray | float,
             track_rad: np.ndarray | float = 0.0) -> np.ndarray:
        """Mean wind plus turbulence (N, 3), ENU, blowing to."""
        return np.asarray(self.cfg.mean_enu_mps, dtype=float) + self.turbulence(t, height_m, airspeed_mps, track_rad)
