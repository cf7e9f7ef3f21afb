"""Nose-gear vibration at the hold-back release (seed 000).

From the stroke start (t = tau - launch > 0) the aircraft's forward (x) and vertical (z) axes
see a(t) = A e^{-t/tau_d} sin(2 pi f t + phi) (A peak, m/s^2; f 100 Hz; tau_d 0.1 s so it is
~0 after 0.5 s); `axes` weights the signal per aircraft axis (default x and z, 1, 0, 1).

With s = -1/tau_d + i omega and a(t) = A Im(e^{i phi} e^{s t}) everything is closed form:
  v(t) = int_0^t a = A Im(e^{i phi} (e^{s t} - 1) / s)
  p(t) = int_0^t v = A Im(e^{i phi} ((e^{s t} - 1) / s^2 - t / s))
so an interval's velocity increment is exactly v(t1) - v(t0) (no quadrature: 3-point
Gauss-Legendre cannot resolve 100 Hz at 100 Hz).

Modes: 'accelerometer' - a disturbance on the accelerometers only (truth unchanged);
'motion' - real airframe motion along the mounted aircraft axes (C_a^s(mu) axes): p, v, a
are added to the deck-relative r, r', r'' so truth position and velocity carry it (note the
damped sinusoid leaves a net velocity v(inf) = A Im(-e^{i phi}/s) ~ A cos(phi)/omega, a few
cm/s; it ends at the release because free flight continues from the release state).
Point-sampling at 100 Hz a 100 Hz vibration gives a(t_k) = A e^{-t_k/tau_d} sin(phi): an
aliased, nearly constant error integrating to ~A tau_d sin(phi) (0.7 m/s at 10 m/s^2, 45 deg).
The vibration needs the catapult (it starts at its launch instant).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from alignment_core.validation import require


@dataclass(frozen=True)
class VibrationConfig:
    """Nose-gear vibration after the hold-back release (off by default; presets 5/10/20)."""
    enabled: bool = False
    peak_mps2: float = 10.0
    frequency_hz: float = 100.0
    decay_s: float = 0.1
    phase_deg: float = 45.0
    axes: tuple[float, float, float] = (1.0, 0.0, 1.0)
    mode: Literal['accelerometer', 'motion'] = 'accelerometer'

    def validate(self) -> None:
        require(0.0 <= self.peak_mps2 <= 1000.0, f"peak_mps2 must be in [0, 1000], got {self.peak_mps2}")
        require(0.0 < self.frequency_hz <= 10000.0,
                f"frequency_hz must be in (0, 10000], got {self.frequency_hz}")
        require(0.0 < self.decay_s <= 10.0, f"decay_s must be in (0, 10], got {self.decay_s}")
        require(all(abs(a) <= 10.0 for a in self.axes), f"axes weights must be within +-10: {self.axes}")


class Vibration:
    """Closed-form acceleration, velocity and displacement along the aircraft axes (…, 3)."""

    def __init__(self, cfg: VibrationConfig, start: float) -> None:
        self.cfg = cfg
        self.start = start
        self.a = cfg.peak_mps2
        self.s = complex(-1.0 / cfg.decay_s, 2.0 * np.pi * cfg.frequency_hz)
        self.e = np.exp(1j * np.deg2rad(cfg.phase_deg))
        self.axes = np.asarray(cfg.axes, dtype=float)

    def _t(self, tau):
        t = np.asarray(tau, dtype=float) - self.start
        return np.where(t > 0.0, t, 0.0)

    def acc_scalar(self, tau):
        t = np.asarray(tau, dtype=float) - self.start
        on = t > 0.0
        t = np.where(on, t, 0.0)
        return np.where(on, self.a * np.imag(self.e * np.exp(self.s * t)), 0.0)

    def vel_scalar(self, tau):
        t = self._t(tau)
        return self.a * np.imag(self.e * np.expm1(self.s * t) / self.s)

    def pos_scalar(self, tau):
        t = self._t(tau)
        s = self.s
        return self.a * np.imag(self.e * (np.expm1(s * t) / s**2 - t / s))

    def acc(self, tau):
        return self.acc_scalar(tau)[..., None] * self.axes

    def vel(self, tau):
        return self.vel_scalar(tau)[..., None] * self.axes

    def pos(self, tau):
        return self.pos_scalar(tau)[..., None] * self.axes

    def dv(self, tau0, tau1):
        """Exact integral of the acceleration over (tau0, tau1], (…, 3)."""
        return (self.vel_scalar(tau1) - self.vel_scalar(tau0))[..., None] * self.axes
