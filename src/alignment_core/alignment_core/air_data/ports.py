"""The flush-port pressure model of a blunt nose (potential flow on a sphere blended with
modified Newtonian flow), shared by the sensor truth and the estimators:

    p_i = qc (cos^2 sigma_i + eps sin^2 sigma_i) + p_inf,   cos sigma_i = n_i . v_a / |v_a|

sigma_i is the incidence of the flow on port i: the angle between the port's outward surface
normal n_i and the air-relative velocity (the stagnation point is where n = v_a / |v_a|).
- eps = 0 is modified Newtonian flow: (p - p_inf) / q = Cp_max cos^2 sigma, Cp_max = qc / q.
- eps = -1.25 is incompressible potential flow over a sphere: (p - p_inf) / qc = 1 - 9/4 sin^2 sigma.
- eps is a calibration function of Mach (`EpsilonCalibration`, air_data/port_layout.py), the same table for the truth
  and the filter (the filter may add an error state on top of it). The default table is
  illustrative, not a wind-tunnel calibration of a real nose: -0.1 subsonic, a rise through
  the transonic range, the Newtonian 0 from Mach 4 on, and flat there, because at hypersonic
  speed a slope of eps(M) would leave M undetermined (fads_solver.epsilon_loop_gain).
- The model holds for sigma_i < 90 deg only: a port on the lee side is in the flow's shadow.

Port geometry (`PortGeometry`, port_layout.py): port i sits at cone angle lambda_i from the nose axis and clock
angle phi_i around it, phi = 0 at the bottom, 90 deg on the starboard (right) side, 180 deg at
the top, 270 deg on the port (left) side. Its normal in FLU body axes is
    n = (cos lambda, -sin lambda sin phi, -sin lambda cos phi)
(in FRD axes the textbook (cos lambda, sin lambda sin phi, sin lambda cos phi)). The default
layout is seed 004's cross of five ports (its table is lost, the cone angle is a choice):
port 0 at the nose centre, ports 1-4 at lambda = 30 deg on the bottom, right, top and left, so
alpha up to +-50 deg and beta up to +-20 deg keep every port windward (sigma <= 80 deg). The
seed numbers the ports 1-5, so its P2 - P4 (used by its alpha > 45 deg test) is p_1 - p_3 here.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from alignment_core.air_data.flow_angles import air_direction, air_direction_partials
from alignment_core.air_data.pitot import impact_pressure_ratio, impact_pressure_ratio_slope
from alignment_core.air_data.port_layout import EpsilonCalibration, PortGeometry


def port_pressures(qc: np.ndarray | float, p_inf: np.ndarray | float, cos_sigma: np.ndarray,
                   eps: np.ndarray | float) -> np.ndarray:
    """p_i (..., n) from qc, p_inf, eps of shape (...) and cos sigma_i (..., n)."""
    c2 = np.asarray(cos_sigma, dtype=float) ** 2
    qc, p_inf, eps = (np.asarray(x, dtype=float)[..., None] for x in (qc, p_inf, eps))
    return qc * (c2 + eps * (1.0 - c2)) + p_inf


@dataclass(frozen=True)
class PortModel:
    """Port pressures of a nose (geometry + eps table) at given air data."""
    geometry: PortGeometry = field(default_factory=PortGeometry)
    epsilon: EpsilonCalibration = field(default_factory=EpsilonCalibration)

    def cos_incidence(self, alpha: np.ndarray | float, beta: np.ndarray | float) -> np.ndarray:
        """cos sigma_i (..., n) at angles (rad) of shape (...)."""
        return air_direction(alpha, beta) @ self.geometry.normals.T

    def in_view(self, alpha: np.ndarray | float, beta: np.ndarray | float) -> np.ndarray:
        """True where every port is windward (sigma_i < 90 deg), shape (...)."""
        return np.all(self.cos_incidence(alpha, beta) > 0.0, axis=-1)

    def pressures(self, alpha: np.ndarray | float, beta: np.ndarray | float, mach: np.ndarray | float,
                  p_inf: np.ndarray | float, strict: bool = True) -> np.ndarray:
        """Port pressures (..., n) in Pa; `strict` refuses a port on the lee side."""
        c = self.cos_incidence(alpha, beta)
        if strict and np.any(c <= 0.0):
            raise ValueError("a port is on the lee side (sigma >= 90 deg): the port model does not hold there")
        qc = impact_pressure_ratio(mach) * np.asarray(p_inf, dtype=float)
        return port_pressures(qc, p_inf, c, self.epsilon(mach))

    def jacobian(self, alpha: np.ndarray | float, beta: np.ndarray | float, mach: np.ndarray | float,
                 p_inf: np.ndarray | float) -> np.ndarray:
        """d p_i / d (alpha, beta, M, p_inf): (..., n, 4), angles in rad."""
        a, b, m, p = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (alpha, beta, mach, p_inf)))
        d_alpha, d_beta = air_direction_partials(a, b)
        normals = self.geometry.normals
        c = air_direction(a, b) @ normals.T
        ratio, eps = impact_pressure_ratio(m), self.epsilon(m)
        qc = (ratio * p)[..., None]
        k = 2.0 * qc * (1.0 - eps[..., None]) * c          # d p / d cos sigma
        c2 = c**2
        shape = c2 + eps[..., None] * (1.0 - c2)
        d_mach = p[..., None] * (impact_pressure_ratio_slope(m)[..., None] * shape
                                 + ratio[..., None] * self.epsilon.slope(m)[..., None] * (1.0 - c2))
        d_p = ratio[..., None] * shape + 1.0
        return np.stack([k * (d_alpha @ normals.T), k * (d_beta @ normals.T), d_mach, d_p], axis=-1)
