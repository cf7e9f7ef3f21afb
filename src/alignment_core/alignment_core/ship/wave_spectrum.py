"""Wave spectra, directional spreading, and a sea as a sum of random-phase components.

Spectra are one-sided in circular frequency omega (rad/s), m^2 s/rad; S(f) = 2 pi S(omega).
- ITTC / two-parameter Bretschneider with T0 = Tp (Pierson-Moskowitz family):
  S(w) = 5/16 Hs^2 wp^4 w^-5 exp(-5/4 (wp/w)^4), wp = 2 pi/Tp; m0 = Hs^2/16, Tz = 0.710 Tp.
- JONSWAP: C(gamma) S_ITTC(w) gamma^exp(-(w - wp)^2 / (2 s^2 wp^2)), s = 0.07 (w <= wp),
  0.09 above; C normalises m0 to Hs^2/16 exactly (numerical quadrature, not 1 - 0.287 ln g).
Spreading: long-crested, or D(mu) = 2/pi cos^2(mu) on |mu| <= pi/2, discretised at the
midpoints of n equal direction bins (the discrete weights D(mu_k) dmu sum to 1 exactly).

The sea is a sum over frequency bins j and directions k of
  zeta(x, y, t) = sum A_jk cos(w_jk t - k_jk (x cos chi_jk + y sin chi_jk) + eps_jk),
  A_jk = sqrt(2 S(w_jk) dw_j D(mu_k) dmu),
with w_jk drawn uniformly inside bin j (independently for each direction, so no two
components share a frequency and the record never repeats) and eps_jk ~ U[0, 2 pi).
The frequency bins are equally spaced in log(omega): the bins are narrowest at low
frequency, where a carrier's roll resonance (half-power width 2 zeta w4 ~ 0.03 rad/s) needs
them, and widest in the tail, which only the wave elevation's statistics (Tz) need.
Deep water: k = w^2/g. Nav frame ENU; chi is the direction the waves travel towards,
counter-clockwise from East.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

G_WAVE = 9.81                       # gravity for the dispersion relation (MSS uses 9.81)
JONSWAP_GAMMA = 3.3


def ittc(omega, hs: float, tp: float) -> np.ndarray:
    """ITTC / Bretschneider spectrum S(omega), m^2 s/rad."""
    w = np.asarray(omega, dtype=float)
    if hs <= 0.0:
        return np.zeros_like(w)
    wp = 2.0 * np.pi / tp
    with np.errstate(divide='ignore', over='ignore', invalid='ignore'):
        s = 5.0 / 16.0 * hs**2 * wp**4 / w**5 * np.exp(-1.25 * (wp / w) ** 4)
    return np.where(w > 0.0, s, 0.0)


def _jonswap_shape(w: np.ndarray, tp: float, gamma: float) -> np.ndarray:
    wp = 2.0 * np.pi / tp
    sig = np.where(w <= wp, 0.07, 0.09)
    return gamma ** np.exp(-((w - wp) ** 2) / (2.0 * sig**2 * wp**2))


@lru_cache(maxsize=64)
def jonswap_norm(tp: float, gamma: float = JONSWAP_GAMMA) -> float:
    """C(gamma): m0 of C S_ITTC gamma^r equals Hs^2/16 (quadrature in u = (wp/w)^4)."""
    # with u = 1.25 (wp/w)^4: integral of S_ITTC d omega = Hs^2/16 * integral e^-u du
    x, wx = np.polynomial.legendre.leggauss(400)
    u = 0.5 * (x + 1.0) * 60.0                       # e^-60 is negligible
    w = (2.0 * np.pi / tp) * (1.25 / np.where(u > 0, u, 1e-300)) ** 0.25
    val = np.sum(0.5 * 60.0 * wx * np.exp(-u) * _jonswap_shape(w, tp, gamma))
    return 1.0 / val


def jonswap(omega, hs: float, tp: float, gamma: float = JONSWAP_GAMMA) -> np.ndarray:
    """JONSWAP spectrum S(omega), m^2 s/rad, normalised so that m0 = Hs^2/16."""
    w = np.asarray(omega, dtype=float)
    return jonswap_norm(float(tp), float(gamma)) * ittc(w, hs, tp) * _jonswap_shape(w, tp, gamma)


def spectrum(name: str, omega, hs: float, tp: float, gamma: float = JONSWAP_GAMMA) -> np.ndarray:
    if name == 'ittc':
        return ittc(omega, hs, tp)
    if name == 'jonswap':
        return jonswap(omega, hs, tp, gamma)
    raise ValueError(f"unknown spectrum {name!r} (ittc, jonswap)")


def spreading_directions(spreading: str, n: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Direction offsets mu_k (rad), weights D(mu_k) dmu (sum 1) and dmu."""
    if spreading == 'none' or n == 1:
        return np.zeros(1), np.ones(1), 1.0
    if spreading != 'cos2':
        raise ValueError(f"unknown spreading {spreading!r} (none, cos2)")
    dmu = np.pi / n
    mu = -0.5 * np.pi + (np.arange(n) + 0.5) * dmu
    w = 2.0 / np.pi * np.cos(mu) ** 2 * dmu
    return mu, w / w.sum(), dmu                       # sum is 1 to rounding; make it exact


def default_band(tp: float) -> tuple[float, float]:
    """Frequency band (rad/s): 0.15-2.5 rad/s widened to 0.55-6 wp (ITTC energy outside:
    below 0.55 wp < 1e-6; above 6 wp 0.1 % of m0 and 3.5 % of m2, i.e. Tz 1.8 % long)."""
    wp = 2.0 * np.pi / tp
    return min(0.15, 0.55 * wp), max(2.5, 6.0 * wp)


@dataclass(frozen=True)
class WaveComponents:
    """A sea as M components (flattened over frequency bins j and directions k, j major)."""
    omega: np.ndarray          # wave (absolute) frequency, rad/s
    k: np.ndarray              # wave number, rad/m
    chi: np.ndarray            # propagation direction in ENU, CCW from East, rad
    mu: np.ndarray             # offset from the mean direction, rad
    amp: np.ndarray            # amplitude A_jk, m
    phase: np.ndarray          # eps_jk, rad
    d_omega: np.ndarray        # width of the frequency bin, rad/s
    weight: np.ndarray         # D(mu_k) dmu
    s: np.ndarray              # S(omega_jk), m^2 s/rad
    hs: float
    tp: float

    def __len__(self) -> int:
        return len(self.omega)

    def variance(self) -> float:
        """Variance of the synthesised elevation, sum A^2/2 (m^2)."""
        return float(np.sum(self.amp**2) / 2.0)

    def elevation(self, t, x: float = 0.0, y: float = 0.0) -> np.ndarray:
        """Elevation (m) at a fixed nav point (x East, y North; m) at times t (s)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        ph = self.phase - self.k * (x * np.cos(self.chi) + y * np.sin(self.chi))
        out = np.empty(len(t))
        for a in range(0, len(t), 2048):
            z = np.exp(1j * (np.outer(t[a:a + 2048], self.omega) + ph))
            out[a:a + 2048] = (z @ self.amp.astype(complex)).real
        return out


def synthesize(name: str, hs: float, tp: float, chi0: float, rng: np.random.Generator, *,
               n_frequencies: int = 150, n_directions: int = 15, spreading: str = 'cos2',
               omega_min: float = 0.0, omega_max: float = 0.0,
               gamma: float = JONSWAP_GAMMA) -> WaveComponents:
    """Random-phase components of a sea with mean propagation direction chi0 (ENU, rad).

    Draws, in this order, the in-bin frequency positions (n_frequencies x n_directions) and
    the phases (same shape), whatever Hs is, so a seed gives the same phases for any Hs."""
    lo_d, hi_d = default_band(tp)
    lo = omega_min if omega_min > 0.0 else lo_d
    hi = omega_max if omega_max > 0.0 else hi_d
    if not 0.0 < lo < hi:
        raise ValueError(f"frequency band must satisfy 0 < omega_min < omega_max, got {lo}, {hi}")
    mu, wdir, _ = spreading_directions(spreading, n_directions)
    nd = len(mu)
    edges = np.exp(np.linspace(np.log(lo), np.log(hi), n_frequencies + 1))
    u = rng.uniform(size=(n_frequencies, nd))
    phase = rng.uniform(0.0, 2.0 * np.pi, size=(n_frequencies, nd))
    lle = np.log(edges)
    omega = np.exp(lle[:-1, None] + u * (lle[1:] - lle[:-1])[:, None])
    dw = np.broadcast_to(np.diff(edges)[:, None], omega.shape)
    s = spectrum(name, omega, hs, tp, gamma)
    weight = np.broadcast_to(wdir[None, :], omega.shape)
    amp = np.sqrt(2.0 * s * dw * weight)
    mu2 = np.broadcast_to(mu[None, :], omega.shape)
    def flat(a):
        return np.ascontiguousarray(a).reshape(-1)
    om = flat(omega)
    return WaveComponents(omega=om, k=om**2 / G_WAVE, chi=flat(chi0 + mu2), mu=flat(mu2),
                          amp=flat(amp), phase=flat(phase), d_omega=flat(dw), weight=flat(weight),
                          s=flat(s), hs=float(hs), tp=float(tp))


def regular(omega: float, amplitude: float, chi: float, phase: float = 0.0) -> WaveComponents:
    """One regular wave component (for regular-wave tests)."""
    a = np.array
    return WaveComponents(omega=a([omega]), k=a([omega**2 / G_WAVE]), chi=a([chi]), mu=a([0.0]),
                          amp=a([amplitude]), phase=a([phase]), d_omega=a([0.0]), weight=a([1.0]),
                          s=a([0.0]), hs=2.0 * amplitude, tp=2.0 * np.pi / omega)
