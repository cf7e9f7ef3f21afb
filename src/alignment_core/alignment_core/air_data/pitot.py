"""Impact pressure qc = p_t - p_inf of a stagnation port, its inverse, and airspeeds.

qc is not the dynamic pressure q = (gamma/2) p_inf M^2: it is what a pitot port feels.
- Subsonic (isentropic compression to rest):
      qc / p_inf = (1 + (gamma-1)/2 M^2)^(gamma/(gamma-1)) - 1          ((1 + 0.2 M^2)^3.5 - 1)
- Supersonic (a normal shock stands ahead of the port, then isentropic compression: the
  Rayleigh pitot formula):
      (qc + p_inf) / p_inf = K M^(2 gamma/(gamma-1)) (2 gamma M^2 - (gamma-1))^(-1/(gamma-1)),
      K = ((gamma+1)^2 / 2)^(gamma/(gamma-1)) / (gamma+1)  (gamma 1.4: 166.92158 M^7 / (7 M^2 - 1)^2.5)
Both branches give 0.892929 and the same slope at M = 1, so qc/p_inf is C1 and increasing in
M; the inverse is closed form below M = 1 and a bracketing root (bisection) above.
"""
from __future__ import annotations

import numpy as np

from alignment_core.air_data.atmosphere import A0, GAMMA, P0, R_AIR

MACH_MAX = 30.0       # upper bracket of the supersonic inverse


def _sonic_ratio(gamma: float) -> float:
    """qc / p_inf at M = 1."""
    return float((1.0 + 0.5 * (gamma - 1.0)) ** (gamma / (gamma - 1.0)) - 1.0)


def impact_pressure_ratio(mach: np.ndarray | float, gamma: float = GAMMA) -> np.ndarray:
    """qc / p_inf at Mach `mach` (any shape, M >= 0)."""
    m = np.asarray(mach, dtype=float)
    e = gamma / (gamma - 1.0)
    sub = (1.0 + 0.5 * (gamma - 1.0) * m**2) ** e - 1.0
    k = ((gamma + 1.0) ** 2 / 2.0) ** e / (gamma + 1.0)
    ms = np.maximum(m, 1.0)
    sup = k * ms ** (2.0 * e) * (2.0 * gamma * ms**2 - (gamma - 1.0)) ** (-1.0 / (gamma - 1.0)) - 1.0
    return np.where(m < 1.0, sub, sup)


def impact_pressure_ratio_slope(mach: np.ndarray | float, gamma: float = GAMMA) -> np.ndarray:
    """d(qc/p_inf)/dM (for Jacobians)."""
    m = np.asarray(mach, dtype=float)
    sub = gamma * m * (1.0 + 0.5 * (gamma - 1.0) * m**2) ** (1.0 / (gamma - 1.0))
    ms = np.maximum(m, 1.0)
    dlog = (2.0 * gamma / (gamma - 1.0)) / ms \
        - (4.0 * gamma * ms / (gamma - 1.0)) / (2.0 * gamma * ms**2 - (gamma - 1.0))
    sup = (impact_pressure_ratio(ms, gamma) + 1.0) * dlog
    return np.where(m < 1.0, sub, sup)


def impact_pressure(mach: np.ndarray | float, p_inf: np.ndarray | float, gamma: float = GAMMA) -> np.ndarray:
    """qc (Pa) at Mach `mach` and static pressure `p_inf` (Pa)."""
    return impact_pressure_ratio(mach, gamma) * np.asarray(p_inf, dtype=float)


def mach_from_impact_ratio(ratio: np.ndarray | float, gamma: float = GAMMA) -> np.ndarray:
    """The Mach number whose qc/p_inf is `ratio` (any shape). Non-positive ratios give 0 (no
    flow); subsonic in closed form, supersonic by 8 bisection steps on [1, MACH_MAX] (the
    Rayleigh ratio increases with M) then Newton steps kept inside the bracket, all elements
    at once, to round-off."""
    r = np.asarray(ratio, dtype=float)
    e = gamma / (gamma - 1.0)
    out = np.sqrt(np.maximum((np.maximum(r, 0.0) + 1.0) ** (1.0 / e) - 1.0, 0.0) * 2.0 / (gamma - 1.0))
    sup = r > _sonic_ratio(gamma)
    if not np.any(sup):
        return out
    target = r[sup]
    if np.any(target >= float(impact_pressure_ratio(MACH_MAX, gamma))):
        raise ValueError(f"qc/p_inf = {float(np.max(target))} is beyond Mach {MACH_MAX}")
    lo, hi = np.ones_like(target), np.full_like(target, MACH_MAX)
    for _ in range(8):
        mid = 0.5 * (lo + hi)
        up = impact_pressure_ratio(mid, gamma) > target
        hi, lo = np.where(up, mid, hi), np.where(up, lo, mid)
    m = 0.5 * (lo + hi)
    for _ in range(30):
        step = (impact_pressure_ratio(m, gamma) - target) / impact_pressure_ratio_slope(m, gamma)
        m_new = np.clip(m - step, lo, hi)
        if np.all(np.abs(m_new - m) <= 4e-16 * m_new):
            m = m_new
            break
        m = m_new
    out = np.array(out, dtype=float)
    out[sup] = m
    return out


def dynamic_pressure(mach: np.ndarray | float, p_inf: np.ndarray | float, gamma: float = GAMMA) -> np.ndarray:
    """q = rho V^2 / 2 = (gamma/2) p_inf M^2 (Pa)."""
    return 0.5 * gamma * np.asarray(p_inf, dtype=float) * np.asarray(mach, dtype=float) ** 2


def true_airspeed(mach: np.ndarray | float, temperature: np.ndarray | float, gamma: float = GAMMA) -> np.ndarray:
    """TAS = M a(T) (m/s), T the static air temperature (K)."""
    return np.asarray(mach, dtype=float) * np.sqrt(gamma * R_AIR * np.asarray(temperature, dtype=float))


def mach_from_airspeed(tas: np.ndarray | float, temperature: np.ndarray | float, gamma: float = GAMMA) -> np.ndarray:
    """M = TAS / a(T)."""
    return np.asarray(tas, dtype=float) / np.sqrt(gamma * R_AIR * np.asarray(temperature, dtype=float))


def calibrated_airspeed(qc: np.ndarray | float) -> np.ndarray:
    """CAS (m/s): the speed that gives impact pressure qc at standard sea level, a0 M(qc/p0)
    (the subsonic closed form below 340.3 m/s, the Rayleigh formula above)."""
    return A0 * mach_from_impact_ratio(np.asarray(qc, dtype=float) / P0)
