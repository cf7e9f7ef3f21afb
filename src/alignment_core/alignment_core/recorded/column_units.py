"""Units a log's columns may be given in: name -> (quantity, factor to SI)."""
from __future__ import annotations

from alignment_core.units import ARCMIN, ARCSEC, DEG, DPH, FT, G0, KNOT, UG


class LogError(ValueError):
    """A log cannot be read as its layout says (the message names the file, column or rows)."""


UNITS: dict[str, tuple[str, float]] = {
    'rad': ('angle', 1.0), 'mrad': ('angle', 1e-3), 'deg': ('angle', DEG),
    'arcmin': ('angle', ARCMIN), 'arcsec': ('angle', ARCSEC),
    'rad/s': ('rate', 1.0), 'mrad/s': ('rate', 1e-3), 'deg/s': ('rate', DEG), 'deg/h': ('rate', DPH),
    'arcsec/s': ('rate', ARCSEC),
    'm/s^2': ('accel', 1.0), 'ft/s^2': ('accel', FT), 'g': ('accel', G0), 'mg': ('accel', 1e-3 * G0),
    'ug': ('accel', UG),
    'm/s': ('velocity', 1.0), 'ft/s': ('velocity', FT), 'kn': ('velocity', KNOT), 'km/h': ('velocity', 1 / 3.6),
    'm': ('length', 1.0), 'ft': ('length', FT), 'km': ('length', 1e3),
    's': ('time', 1.0), 'ms': ('time', 1e-3), 'us': ('time', 1e-6), 'ns': ('time', 1e-9),
}
"""Every unit a layout may name; `rad/s`, `deg/s`, ... for rates, `rad`, `deg`, ... for angles
and angle increments, `m/s` for velocity increments."""

TIME_NS = {'s': 10**9, 'ms': 10**6, 'us': 10**3, 'ns': 1}


def factor(unit: str, quantity: str, where: str) -> float:
    """The factor from `unit` to SI for a column of `quantity`; LogError naming `where` if
    the unit is unknown or of another quantity."""
    if unit not in UNITS:
        raise LogError(f'{where}: unknown unit {unit!r} (known: {", ".join(UNITS)})')
    q, f = UNITS[unit]
    if q != quantity:
        allowed = ', '.join(u for u, (qq, _) in UNITS.items() if qq == quantity)
        raise LogError(f'{where}: unit {unit!r} is not a unit of {quantity} (one of: {allowed})')
    return f
