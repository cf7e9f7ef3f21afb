"""The atmosphere of a day: US Standard Atmosphere 1976 (the `ambiance` package; identical to
the ICAO atmosphere below 32 km) with a temperature offset and a sea-level pressure offset.

Heights. `Atmosphere(h)` takes the geometric height h above mean sea level (m); the layers are
defined in geopotential height H = r0 h / (r0 + h), r0 = 6 356 766 m, in which gravity is the
constant g0 and the hydrostatic equation reads dp/dH = -g0 p / (R T). Pressure altitude
(`pressure_altitude`) is, as for an altimeter, the standard-day *geopotential* height of a
pressure: "20 km" is 5474.9 Pa as a pressure altitude and 5529.3 Pa at 20 km geometric.

A non-standard day (`DayOffsets`):
- the temperature is T(H) = T_std(H) + dT at every geopotential height (ISA + dT);
- the sea-level pressure is p0 + dp0, and the pressure aloft follows from the hydrostatic
  equation integrated upwards with that temperature (not the standard pressure at the same
  height: a warm day's air column is taller):
      p(H) = (p0 + dp0) exp(-(g0 / R) I(H; dT)),   I(H; dT) = int_0^H dH' / (T_std(H') + dT),
  I in closed form in each layer of the standard's table: (1 / b) ln(1 + b (H - H_b) / (T_b + dT))
  for a lapse rate b != 0, (H - H_b) / (T_b + dT) in an isothermal layer. With dT = 0 the
  pressure is the standard one scaled by 1 + dp0/p0 at every height.
The standard day is the same formula with dT = dp0 = 0 over the package's layer table: it is
continuous, where the package's own pressure, built on the six-digit layer-base pressures of
the ICAO tables, steps by up to 1.8e-6 of itself at the layer bases (the two agree to that).
The inverse (`Atmosphere.from_pressure`) starts from the package's standard-day inverse and
refines it by Newton steps on ln p(H), whose slope is -g0 / (R T(H)).
"""
from __future__ import annotations

import ambiance
import numpy as np

from alignment_core.air_data.day_offsets import STANDARD_DAY, DayOffsets

R_AIR = float(ambiance.CONST.R)          # specific gas constant of dry air, J/(kg K)
GAMMA = float(ambiance.CONST.kappa)      # ratio of specific heats, 1.4
G0 = float(ambiance.CONST.g_0)           # gravity of the geopotential height, m/s^2
P0 = float(ambiance.CONST.P_0)           # standard sea-level pressure, Pa
T0 = float(ambiance.CONST.T_0)           # standard sea-level temperature, K
A0 = float(np.sqrt(GAMMA * R_AIR * T0))  # standard sea-level speed of sound, m/s
EARTH_RADIUS_GEOPOTENTIAL = float(ambiance.CONST.r)

# the package's layer table: (base geopotential height m, base temperature K, lapse rate K/m)
_LAYERS = tuple((float(d['H_base']), float(d['T']), float(d['beta']))
                for d in ambiance.CONST.LAYER_DICTS.values())
_H_MIN, _H_MAX = _LAYERS[0][0], float(ambiance.CONST.LAYER_DICTS[len(_LAYERS)]['H_top'])


def geopotential_height(h: np.ndarray | float) -> np.ndarray:
    """Geopotential height H = r0 h / (r0 + h) of geometric height h (m)."""
    h = np.asarray(h, dtype=float)
    return EARTH_RADIUS_GEOPOTENTIAL * h / (EARTH_RADIUS_GEOPOTENTIAL + h)


def geometric_height(H: np.ndarray | float) -> np.ndarray:
    """Geometric height h = r0 H / (r0 - H) of geopotential height H (m)."""
    H = np.asarray(H, dtype=float)
    return EARTH_RADIUS_GEOPOTENTIAL * H / (EARTH_RADIUS_GEOPOTENTIAL - H)


def _inverse_temperature_integral(H: np.ndarray, delta_t: float) -> np.ndarray:
    """I(H; dT) = int_0^H dH' / (T_std(H') + dT), layer by layer in closed form."""
    def from_bottom(x: np.ndarray) -> np.ndarray:
        total = np.zeros_like(x)
        tops = [layer[0] for layer in _LAYERS[1:]] + [_H_MAX]
        for (base, t_base, lapse), top in zip(_LAYERS, tops):
            seg = np.clip(x, base, top) - base
            t_b = t_base + delta_t
            if lapse == 0.0:
                total += seg / t_b
            else:
                total += np.log1p(lapse * seg / t_b) / lapse
        return total
    return from_bottom(H) - from_bottom(np.zeros(1))


def _pressure(H: np.ndarray, day: DayOffsets) -> np.ndarray:
    """The day's pressure (Pa) at geopotential heights H (any shape)."""
    flat = np.asarray(H, dtype=float).reshape(-1)
    integral = _inverse_temperature_integral(flat, day.delta_t_k).reshape(np.shape(H))
    return (P0 + day.delta_p0_pa) * np.exp(-G0 / R_AIR * integral)


class Atmosphere:
    """Temperature, pressure, density and speed of sound of a day at geometric heights `h`
    (m above mean sea level, any shape; outputs have the shape of `h`)."""

    def __init__(self, h: np.ndarray | float, day: DayOffsets = STANDARD_DAY) -> None:
        self.h = np.asarray(h, dtype=float)
        self.day = day
        std = ambiance.Atmosphere(self.h.reshape(-1))
        self.geopotential = std.H.reshape(self.h.shape)
        self.temperature = std.temperature.reshape(self.h.shape) + day.delta_t_k
        self.pressure = _pressure(self.geopotential, day)

    @classmethod
    def from_pressure(cls, p: np.ndarray | float, day: DayOffsets = STANDARD_DAY) -> Atmosphere:
        """The atmosphere at the geometric height(s) where the day's pressure is `p` (Pa)."""
        p = np.asarray(p, dtype=float)
        scale = 1.0 + day.delta_p0_pa / P0
        H = ambiance.Atmosphere.from_pressure((p / scale).reshape(-1)).H.reshape(p.shape)
        for _ in range(30):
            t_day = ambiance.Atmosphere(geometric_height(H).reshape(-1)).temperature.reshape(p.shape) + day.delta_t_k
            step = (np.log(_pressure(H, day)) - np.log(p)) * R_AIR * t_day / G0    # d ln p / dH = -g0/(R T)
            H = H + step
            if np.all(np.abs(step) < 1e-9):
                break
        return cls(geometric_height(H), day)

    @property
    def density(self) -> np.ndarray:
        return self.pressure / (R_AIR * self.temperature)

    @property
    def speed_of_sound(self) -> np.ndarray:
        return np.sqrt(GAMMA * R_AIR * self.temperature)


def pressure_altitude(p: np.ndarray | float) -> np.ndarray:
    """Pressure altitude (m): the standard-day geopotential height at which the pressure is p."""
    return Atmosphere.from_pressure(p).geopotential


def pressure_altitude_slope(p: np.ndarray | float) -> np.ndarray:
    """dH/dp of the pressure altitude (m/Pa, negative): -R T / (g0 p), T the standard
    temperature at that pressure altitude; it converts a static-pressure error to height."""
    p = np.asarray(p, dtype=float)
    return -R_AIR * Atmosphere.from_pressure(p).temperature / (G0 * p)
