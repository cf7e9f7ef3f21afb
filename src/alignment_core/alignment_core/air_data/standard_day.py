"""The standard day in closed form, layer by layer (the same formula as atmosphere.py's day with
dT = dp0 = 0, without the package's per-call overhead): what an estimator evaluates at every
update. In a layer with base H_b, T_b, p_b and lapse rate b:
    T = T_b + b (H - H_b),  p = p_b (T / T_b)^(-g0 / (R b))   (b != 0),  p = p_b exp(-g0 (H - H_b) / (R T_b))   (b = 0),
and the inverse (the pressure altitude) solves the same relation for H."""
from __future__ import annotations

import numpy as np

from alignment_core.air_data.atmosphere import _LAYERS, G0, P0, R_AIR, _pressure, geopotential_height
from alignment_core.air_data.day_offsets import STANDARD_DAY

_BASE_H = np.array([lay[0] for lay in _LAYERS])
_BASE_T = np.array([lay[1] for lay in _LAYERS])
_LAPSE = np.array([lay[2] for lay in _LAYERS])


_BASE_P = _pressure(_BASE_H, STANDARD_DAY)      # the day formula at the layer bases (H = 0 at p0)


def temperature_pressure(h: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """Standard-day temperature (K) and pressure (Pa) at geometric heights h (m, any shape)."""
    H = geopotential_height(h)
    k = np.clip(np.searchsorted(_BASE_H, H, side='right') - 1, 0, len(_BASE_H) - 1)
    t_b, b, p_b, dh = _BASE_T[k], _LAPSE[k], _BASE_P[k], H - _BASE_H[k]
    temperature = t_b + b * dh
    iso = b == 0.0
    with np.errstate(divide='ignore', invalid='ignore'):
        graded = p_b * (temperature / t_b) ** (-G0 / (R_AIR * np.where(iso, 1.0, b)))
    pressure = np.where(iso, p_b * np.exp(-G0 * dh / (R_AIR * t_b)), graded)
    return temperature, pressure


def pressure_altitude(p: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """(pressure altitude H (m, geopotential), the standard temperature there (K)) of pressures p (Pa)."""
    p = np.asarray(p, dtype=float)
    k = np.clip(len(_BASE_P) - 1 - np.searchsorted(_BASE_P[::-1], p, side='left'), 0, len(_BASE_P) - 1)
    t_b, b, p_b = _BASE_T[k], _LAPSE[k], _BASE_P[k]
    iso = b == 0.0
    with np.errstate(divide='ignore', invalid='ignore'):
        t_graded = t_b * (p / p_b) ** (-R_AIR * np.where(iso, 1.0, b) / G0)
        dh = np.where(iso, -R_AIR * t_b / G0 * np.log(p / p_b), (t_graded - t_b) / np.where(iso, 1.0, b))
    return _BASE_H[k] + dh, np.where(iso, t_b, t_graded)


def day_pressure(h: np.ndarray | float, delta_t: np.ndarray | float) -> np.ndarray:
    """Pressure (Pa) at geometric heights h (m,) on days warmer by delta_t (N,) K with the
    standard sea-level pressure: p0 exp(-(g0 / R) int_0^H dH' / (T_std(H') + dT)), layer by layer
    in closed form (atmosphere.py's day); shape (N, m). A sea-level offset dp0 scales it by
    1 + dp0 / p0 at every height."""
    H = np.atleast_1d(geopotential_height(h))[None, :]
    dt = np.atleast_1d(np.asarray(delta_t, dtype=float))[:, None]

    def from_bottom(x: np.ndarray) -> np.ndarray:
        total = np.zeros(np.broadcast_shapes(x.shape, dt.shape))
        tops = list(_BASE_H[1:]) + [np.inf]
        for base, top, t_b, b in zip(_BASE_H, tops, _BASE_T, _LAPSE):
            seg = np.clip(x, base, top) - base
            t = t_b + dt
            total = total + (seg / t if b == 0.0 else np.log1p(b * seg / t) / b)
        return total
    return P0 * np.exp(-G0 / R_AIR * (from_bottom(H) - from_bottom(np.zeros((1, 1)))))
