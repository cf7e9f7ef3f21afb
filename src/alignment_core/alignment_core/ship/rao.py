"""Motion response amplitude operators (RAOs): closed-form for a carrier, or an MSS table.

An RAO here is `rao(omega, beta, U) -> (M, 6) complex`: the response per metre of wave
amplitude of (surge, sway, heave, roll, pitch, yaw) at the ship's reference point, to a wave
component of absolute frequency omega (rad/s) travelling at beta relative to the ship, at
speed U (m/s). Conventions (shared with the MSS tables after conversion):
- beta is the direction the waves travel towards, from the bow, clockwise seen from above
  (towards starboard): 0 following seas, 90 deg waves from port travelling to starboard,
  180 deg head seas. (MSS: same.)
- Axes and angles are ROS: surge forward, sway to port (left), heave up (m/m); roll about x
  (starboard down positive), pitch about y (bow down positive), yaw about z (bow to port
  positive), rad/m. MSS uses x forward, y starboard, z down: sway, heave, pitch, yaw change
  sign; surge and roll do not.
- Phase: the response is Re{H a e^{i phi}} when the wave elevation at the reference point is
  Re{a e^{i phi}} and phi grows at the (positive) encounter frequency |omega_e|,
  omega_e = omega - k U cos(beta). (MSS: cos(w_e t + angle(H) + eps), same.)

Closed form (when no table is given), for a carrier (defaults: `CarrierParams`):
- heave H3 = F D3(w_e), pitch H5 = i sgn(cos beta) G D5(w_e), with F and G from Jensen,
  Mansour & Olsen (2004) (Froude-Krylov excitation over the length with their Smith and
  damping correction f, beam replaced by Cb B) and, in place of their resonance factor,
  D_i(w) = w_i^2 / (w_i^2 - w^2 + 2 i zeta_i w_i w) with T3 = T5 = 9.5 s, zeta 0.25;
  long waves give H3 -> 1 and pitch -> the wave slope k cos(beta).
- roll H4 = i k sin(beta) r(k, beta) D4(w_e): wave-slope excitation of a damped oscillator,
  T4 = 20 s, zeta4 = 0.05 at 0 kn rising linearly to 0.10 at 30 kn; r is an effective
  wave-slope coefficient, exp(-k T/2) sinc(k L cos(beta)/2) sinc(k B sin(beta)/2) (depth
  decay, and the slope averaged over the length and across the beam).
- surge, sway: the horizontal displacement of the water particles (a sin(phi) along the
  propagation direction) with the same depth decay and averaging; yaw: the least-squares
  slope along the hull of that lateral displacement (as Jensen's G is for heave). These
  are quasi-static (no speed or mass effects): small for a carrier, reasonable, not exact.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import RegularGridInterpolator

from alignment_core.ship.wave_spectrum import G_WAVE
from alignment_core.units import KNOT
from alignment_core.validation import ConfigError

MSS_TO_ROS = np.array([1.0, -1.0, -1.0, 1.0, -1.0, -1.0])


@dataclass(frozen=True)
class CarrierParams:
    """A ~310 m aircraft carrier (defaults: docs/ship-motion.md)."""
    lpp: float = 310.0
    beam: float = 40.5                  # waterline beam, m
    draft: float = 11.3
    cb: float = 0.62
    heave_period_s: float = 9.5
    pitch_period_s: float = 9.5
    heave_zeta: float = 0.25
    pitch_zeta: float = 0.25
    roll_period_s: float = 20.0
    roll_zeta: float = 0.0              # 0: 0.05 at 0 kn to 0.10 at 30 kn (and above)

    def zeta4(self, speed: float) -> float:
        if self.roll_zeta > 0.0:
            return self.roll_zeta
        return 0.05 + 0.05 * min(max(speed, 0.0) / (30.0 * KNOT), 1.0)


def _sinc(x):
    """sin(x)/x."""
    return np.sinc(np.asarray(x) / np.pi)


def _g5(x):
    """3 (sin x - x cos x) / x^3 (-> 1 at 0): least-squares slope weight over the length."""
    x = np.abs(np.asarray(x, dtype=float))
    small = x < 1e-3
    xs = np.where(small, 1.0, x)
    full = 3.0 * (np.sin(xs) - xs * np.cos(xs)) / xs**3
    return np.where(small, 1.0 - x**2 / 10.0, full)


def _osc(wn: float, zeta: float, we):
    return wn**2 / (wn**2 - we**2 + 2j * zeta * wn * we)


class ClosedFormRao:
    """Closed-form RAOs of a carrier (see the module docstring)."""

    def __init__(self, p: CarrierParams | None = None) -> None:
        self.p = p or CarrierParams()
        self.name = 'closed_form'

    def __call__(self, omega, beta, speed: float) -> np.ndarray:
        p = self.p
        w = np.asarray(omega, dtype=float)
        b = np.asarray(beta, dtype=float)
        c, s = np.cos(b), np.sin(b)
        L, B, T = p.lpp, p.beam, p.draft
        be = p.cb * B
        k = np.maximum(w**2 / G_WAVE, 1e-12)
        we = np.abs(w - k * speed * c)
        # Jensen et al. (2004): F (heave) and G (pitch) with the correction f
        fn = speed / np.sqrt(G_WAVE * L)
        alpha = 1.0 - fn * np.sqrt(k * L) * c                      # = omega_e / omega
        a = 2.0 * np.sin(0.5 * k * be * alpha**2) * np.exp(-k * T * alpha**2)
        tiny = np.abs(alpha) < 1e-9
        ratio = np.where(tiny, k * be * alpha, a**2 / (k * be * np.where(tiny, 1.0, alpha) ** 3))
        f = np.sqrt((1.0 - k * T) ** 2 + ratio**2)
        kappa = np.exp(-k * T)
        ke = np.abs(k * c)
        x = 0.5 * ke * L
        F = kappa * f * _sinc(x)
        G = kappa * f * ke * _g5(x)
        h3 = F * _osc(2.0 * np.pi / p.heave_period_s, p.heave_zeta, we)
        h5 = 1j * np.sign(c) * G * _osc(2.0 * np.pi / p.pitch_period_s, p.pitch_zeta, we)
        # roll: wave-slope excitation of a damped oscillator
        kh = np.exp(-0.5 * k * T)
        avg = _sinc(0.5 * k * c * L) * _sinc(0.5 * k * s * B)
        h4 = 1j * k * s * kh * avg * _osc(2.0 * np.pi / p.roll_period_s, p.zeta4(speed), we)
        # surge, sway: water-particle displacement; yaw: its slope along the hull
        h1 = -1j * c * kh * avg
        h2 = 1j * s * kh * avg
        h6 = (k * s * c * kh * _g5(x) * _sinc(0.5 * k * s * B)).astype(complex)
        return np.stack([h1, h2, h3.astype(complex), h4, h5, h6], axis=-1)


class TableRao:
    """Tabulated RAOs (MSS `vessel.motionRAO`), interpolated linearly in wave frequency,
    heading (periodic) and speed on their real and imaginary parts (as MSS does). Outside
    the table: frequency clamped below its first value (long-wave limit) and zero above its
    last; speed clamped to the tabulated range."""

    def __init__(self, w: np.ndarray, headings: np.ndarray, speeds: np.ndarray, h: np.ndarray,
                 name: str = 'table', main: dict | None = None) -> None:
        """w (nw,) rad/s, headings (nh,) rad in [0, 2 pi), speeds (nv,) m/s, h (nw, nh, nv, 6)
        complex in ROS axes."""
        order = np.argsort(headings)
        headings = np.asarray(headings, dtype=float)[order]
        h = np.asarray(h)[:, order]
        hd = np.concatenate([headings, [headings[0] + 2.0 * np.pi]])
        h = np.concatenate([h, h[:, :1]], axis=1)
        if len(speeds) == 1:
            speeds = np.array([speeds[0], speeds[0] + 1.0])
            h = np.concatenate([h, h], axis=2)
        self.w, self.headings, self.speeds = np.asarray(w, dtype=float), hd, np.asarray(speeds, dtype=float)
        self.h = h
        self.name = name
        self.main = main or {}
        vals = np.concatenate([h.real, h.imag], axis=-1)
        self._interp = RegularGridInterpolator((self.w, hd, self.speeds), vals, method='linear')
        self._h0 = hd[0]

    def __call__(self, omega, beta, speed: float) -> np.ndarray:
        w = np.asarray(omega, dtype=float)
        b = np.mod(np.asarray(beta, dtype=float) - self._h0, 2.0 * np.pi) + self._h0
        b = np.minimum(b, self.headings[-1])
        wc = np.clip(w, self.w[0], self.w[-1])
        u = np.full(w.shape, np.clip(speed, self.speeds[0], self.speeds[-1]))
        pts = np.stack(np.broadcast_arrays(wc, b, u), axis=-1)
        v = self._interp(pts.reshape(-1, 3)).reshape(pts.shape[:-1] + (12,))
        out = v[..., :6] + 1j * v[..., 6:]
        return np.where((w <= self.w[-1])[..., None], out, 0.0)


def load_mss(path: str) -> TableRao:
    """Motion RAOs from an MSS vessel file (`vessel.motionRAO.amp/phase/w`, `headings` rad,
    `velocities` m/s); amplitudes per metre (rad/m for rotations), MSS axes -> ROS axes."""
    import scipy.io

    p = os.path.expandvars(os.path.expanduser(path))
    if not os.path.isfile(p):
        raise ConfigError(f"RAO file not found: {path}")
    try:
        v = scipy.io.loadmat(p, squeeze_me=True, struct_as_record=False)['vessel']
        m = v.motionRAO
        w = np.atleast_1d(np.asarray(m.w, dtype=float))
        hd = np.atleast_1d(np.asarray(v.headings, dtype=float))
        sp = np.atleast_1d(np.asarray(v.velocities, dtype=float))
        h = np.empty((len(w), len(hd), len(sp), 6), dtype=complex)
        for i in range(6):
            amp = np.asarray(m.amp[i], dtype=float).reshape(len(w), len(hd), -1)[:, :, :len(sp)]
            ph = np.asarray(m.phase[i], dtype=float).reshape(len(w), len(hd), -1)[:, :, :len(sp)]
            h[..., i] = MSS_TO_ROS[i] * amp * np.exp(1j * ph)
        main = {f: getattr(v.main, f) for f in v.main._fieldnames} if hasattr(v, 'main') else {}
    except (KeyError, AttributeError, ValueError, IndexError) as e:
        raise ConfigError(f"{path}: not an MSS vessel file with motion RAOs ({e})") from None
    if np.max(hd) > 2.0 * np.pi + 1e-6:
        hd = np.deg2rad(hd)
    return TableRao(w, hd, sp, h, name=os.path.basename(p), main=main)


def make(source: str, params: CarrierParams | None = None):
    """'closed_form' -> ClosedFormRao(params); anything else is a path to an MSS .mat file."""
    if source == 'closed_form':
        return ClosedFormRao(params)
    return load_mss(source)
