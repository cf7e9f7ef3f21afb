"""Units and physical constants, defined once: angles, rates, gravity for unit conversions, knots."""
from __future__ import annotations

import numpy as np

ARCMIN = np.pi / (180.0 * 60.0)


ARCSEC = ARCMIN / 60.0


DEG = np.pi / 180.0


DPH = DEG / 3600.0                  # degree per hour, in rad/s


G0 = 9.80665                        # standard gravity for unit conversions (mg, ug)



UG = 1e-6 * G0



KNOT = 0.514444
