"""The MIL-F-8785C Dryden turbulence specification: intensities and scale lengths by height and
severity. Physics of the atmosphere shared by the wind truth (aircraft/wind.py, its docstring
gives the formulas) and the air-data estimator's turbulence model."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from alignment_core.units import KNOT

FT = 0.3048
Severity = Literal['none', 'light', 'moderate', 'severe']
SEVERITIES = ('none', 'light', 'moderate', 'severe')
W20_KNOTS = {'light': 15.0, 'moderate': 30.0, 'severe': 45.0}
# MIL-F-8785C Figure 7: sigma (ft/s) against height (ft) for each probability of exceedance
_POE_HEIGHT_FT = np.array([500.0, 1750.0, 3750.0, 7500.0, 15000.0, 25000.0, 35000.0, 45000.0,
                           55000.0, 65000.0, 75000.0, 80000.0])
_POE_SIGMA_FTPS = {
    'light': np.array([6.6, 6.9, 7.4, 6.7, 4.6, 2.7, 0.4, 0.0, 0.0, 0.0, 0.0, 0.0]),          # 1e-2
    'moderate': np.array([8.6, 9.6, 10.6, 10.1, 8.0, 6.6, 5.0, 4.2, 2.7, 0.0, 0.0, 0.0]),     # 1e-3
    'severe': np.array([15.6, 17.6, 23.0, 23.6, 22.1, 20.0, 16.0, 15.1, 12.1, 7.9, 6.2, 5.1]),  # 1e-5
}
HIGH_ALTITUDE_SCALE_FT = 1750.0
MIN_AIRSPEED = 1.0



@dataclass(frozen=True)
class DrydenParameters:
    """Intensities (m/s) and scale lengths (m), each of the heights' shape."""
    sigma_u: np.ndarray
    sigma_v: np.ndarray
    sigma_w: np.ndarray
    length_u: np.ndarray
    length_v: np.ndarray
    length_w: np.ndarray


def dryden_parameters(height_m: np.ndarray | float, severity: Severity, w20_mps: float = 0.0) -> DrydenParameters:
    """MIL-F-8785C intensities and scale lengths at heights (m) for a severity (severity
    'none': zero intensities, unit scale lengths as placeholders)."""
    h_ft = np.clip(np.asarray(height_m, dtype=float) / FT, 10.0, 80000.0)
    if severity == 'none':
        zero = np.zeros_like(h_ft)
        one = np.ones_like(h_ft)
        return DrydenParameters(zero, zero, zero, one, one, one)
    w20_ftps = (w20_mps if w20_mps > 0.0 else W20_KNOTS[severity] * KNOT) / FT

    def low(h: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        d = 0.177 + 0.000823 * h
        sigma_w = np.full_like(h, 0.1 * w20_ftps)
        return sigma_w / d**0.4, sigma_w, h / d**1.2, h                     # sigma_uv, sigma_w, L_uv, L_w

    def high(h: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        sigma = np.interp(h, _POE_HEIGHT_FT, _POE_SIGMA_FTPS[severity])
        scale = np.full_like(h, HIGH_ALTITUDE_SCALE_FT)
        return sigma, sigma, scale, scale

    lo_h, hi_h = low(np.minimum(h_ft, 1000.0)), high(np.maximum(h_ft, 2000.0))
    f = np.clip((h_ft - 1000.0) / 1000.0, 0.0, 1.0)
    lo_ref, hi_ref = low(np.full_like(h_ft, 1000.0)), high(np.full_like(h_ft, 2000.0))
    out = []
    for lo, hi, lo1000, hi2000 in zip(lo_h, hi_h, lo_ref, hi_ref):
        blend = lo1000 + f * (hi2000 - lo1000)
        out.append(FT * np.where(h_ft < 1000.0, lo, np.where(h_ft > 2000.0, hi, blend)))
    sigma_uv, sigma_w, length_uv, length_w = out
    return DrydenParameters(sigma_uv, sigma_uv, sigma_w, length_uv, length_uv, length_w)
