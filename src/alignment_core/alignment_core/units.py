"""Units and physical constants, defined once: angles, rates, gravity for unit conversions, knots.

G0 is standard gravity (9.80665 m/s^2, exact by definition): the g of mg / ug and of the
catapult's "2 g", and the ship models' weight (manoeuvring/mmg.py, box_ship_waves.py). Two
other gravities are deliberate: navigation uses normal gravity at the position
(geometry/earth.py), and the wave dispersion relation k = omega^2 / g uses G_WAVE = 9.81
(ship/wave_spectrum.py), the value of the MSS toolbox whose spectra and RAOs it follows.
"""
from __future__ import annotations

import numpy as np

DEG = np.pi / 180.0                 # degree, in rad
ARCMIN = np.pi / (180.0 * 60.0)     # arc minute, in rad
ARCSEC = ARCMIN / 60.0              # arc second, in rad
DPH = DEG / 3600.0                  # degree per hour, in rad/s
G0 = 9.80665                        # standard gravity, m/s^2
UG = 1e-6 * G0                      # micro-g, in m/s^2
KNOT = 0.514444                     # knot, in m/s (1852 m / 3600 s, to six digits)
FT = 0.3048                         # international foot, in m (exact by definition)
