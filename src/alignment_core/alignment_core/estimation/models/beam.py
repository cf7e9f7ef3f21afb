"""A beam LDV's measurement (`filter.ldv_mode: beam`): one velocity row along the line of sight
instead of three.

The LDV measures only s = u_s . v_rel, the aircraft's velocity relative to the deck along its
unit line of sight u_s (ship axes). The reference then knows the slave's velocity along
u_n = C_m u_s alone, so the model's three velocity rows (E, N, U, first in every model that
allows the beam) become one,
    z = u_n^T z_vel,   H = u_n^T H_vel,   R = u_n^T R_vel u_n,
with z_vel = v_slave - (v_master + C_m (w_m x r + s u_s)): its projection is
u_n^T (v_slave - v_master - C_m (w_m x r)) - s. Rows after the velocity rows (attitude, rate)
are kept as they are. To first order the master's attitude error does not change u_n's role:
rotating u_n by phi_m changes z by u_n^T [phi_m x] dV, second order. The beam's direction is
each sample's own, so the row turns as the aircraft moves along the deck.
"""
from __future__ import annotations

import numpy as np

from alignment_core.estimation.models.base import Measurement


def project_on_beam(meas: Measurement, u_n: np.ndarray) -> Measurement:
    """`meas` with its first three (velocity E, N, U) rows replaced by their projection on the
    unit nav-frame line of sight u_n (module docstring); a linear measurement."""
    h = meas.matrix()
    rows = len(meas.z)
    p = np.zeros((rows - 2, rows))
    p[0, 0:3] = u_n
    if rows > 3:
        p[1:, 3:] = np.eye(rows - 3)
    return Measurement(p @ meas.z, p @ h, p @ meas.r @ p.T)


MIN_TRACK_COSINE = 0.5
"""A beam within 60 deg of the track gives the along-track speed s / cos; beyond, 1/cos amplifies
the LDV's noise more than twice and the component along the beam is kept as it is."""


def track_velocity(v_s: np.ndarray, u_s: np.ndarray, heading_on_deck_rad: float) -> np.ndarray:
    """The deck velocity (ship axes) a beam sample v_s = s u_s gives once the aircraft runs along
    its track (heading on deck psi: t = (cos psi, -sin psi, 0)): (s / (u_s . t)) t, so the deck
    displacement integrates the run, not its component along the beam; its projection on the
    beam is still s, so the beam row is unchanged. v_s itself when the beam is more than
    60 deg off the track (MIN_TRACK_COSINE)."""
    t = np.array([np.cos(heading_on_deck_rad), -np.sin(heading_on_deck_rad), 0.0])
    c = float(u_s @ t)
    if abs(c) < MIN_TRACK_COSINE:
        return v_s
    return (float(v_s @ u_s) / c) * t
