"""The flush-port pressure model of a blunt nose (potential flow on a sphere blended with
modified Newtonian flow), shared by the sensor truth and the estimators:

    p_i = qc (cos^2 sigma_i + eps sin^2 sigma_i) + p_inf,   cos sigma_i = n_i . v_a / |v_a|

sigma_i is the incidence of the flow on port i: the angle between the port's outward surface
normal n_i and the air-relative velocity (the stagnation point is where n = v_a / |v_a|).
- eps = 0 is modified Newtonian flow: (p - p_inf) / q = Cp_max cos^2 sigma, Cp_max = qc / q.
- eps = -1.25 is incompressible potential flow over a sphere: (p - p_inf) / qc = 1 - 9/4 sin^2 sigma.
- eps is a calibration function of Mach (`EpsilonCalibration`), the same table for the truth
  and the filter (the filter may add an error state on top of it). The default table is
  illustrative, not a wind-tunnel calibration of a real nose: -0.1 subsonic, a rise through
  the transonic range, the Newtonian 0 from Mach 4 on, and flat there, because at hypersonic
  speed a slope of eps(M) would leave M undetermined (fads_solver.epsilon_loop_gain).
- The model holds for sigma_i < 90 deg only: a port on the lee side is in the flow's shadow.

Port geometry (`PortGeometry`): port i sits at cone angle lambda_i from the nose axis and clock
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
from functools import cached_property

import numpy as np
from scipy.interpolate import PchipInterpolator

from alignment_core.air_data.flow_angles import air_direction, air_direction_partials
from alignment_core.air_data.pitot import impact_pressure_ratio, impact_pressure_ratio_slope
from alignment_core.validation import require


@dataclass(frozen=True)
class PortGeometry:
    """Cone and clock angles (deg) of the ports, one entry per port."""
    cone_deg: tuple[float, ...] = (0.0, 30.0, 30.0, 30.0, 30.0)
    clock_deg: tuple[float, ...] = (0.0, 0.0, 90.0, 180.0, 270.0)

    def validate(self) -> None:
        require(len(self.cone_deg) == len(self.clock_deg) >= 3,
                f"cone_deg and clock_deg need the same length (>= 3), got {len(self.cone_deg)}, {len(self.clock_deg)}")
        require(all(0.0 <= c < 90.0 for c in self.cone_deg), f"cone angles must be in [0, 90) deg: {self.cone_deg}")

    @property
    def count(self) -> int:
        return len(self.cone_deg)

    @cached_property
    def normals(self) -> np.ndarray:
        """Outward unit normals (n, 3) in FLU body axes."""
        lam, phi = np.deg2rad(self.cone_deg), np.deg2rad(self.clock_deg)
        return np.stack([np.cos(lam), -np.sin(lam) * np.sin(phi), -np.sin(lam) * np.cos(phi)], axis=-1)


@dataclass(frozen=True)
class EpsilonCalibration:
    """eps(M): a monotone cubic (PCHIP) through the table, held constant beyond its ends."""
    mach: tuple[float, ...] = (0.0, 0.6, 0.9, 1.1, 1.5, 2.5, 4.0)
    eps: tuple[float, ...] = (-0.10, -0.10, -0.05, 0.02, 0.05, 0.02, 0.0)

    def validate(self) -> None:
        require(len(self.mach) == len(self.eps) >= 2, "mach and eps need the same length (>= 2)")
        require(all(b > a for a, b in zip(self.mach, self.mach[1:])), f"mach must increase: {self.mach}")
        require(all(e < 1.0 for e in self.eps), f"eps must be < 1 (eps = 1 erases the angles): {self.eps}")

    @classmethod
    def constant(cls, eps: float) -> EpsilonCalibration:
        return cls(mach=(0.0, 1.0), eps=(eps, eps))

    @cached_property
    def _curve(self) -> PchipInterpolator:
        return PchipInterpolator(np.asarray(self.mach), np.asarray(self.eps), extrapolate=False)

    def _clamped(self, mach: np.ndarray | float) -> np.ndarray:
        return np.clip(np.asarray(mach, dtype=float), self.mach[0], self.mach[-1])

    def __call__(self, mach: np.ndarray | float) -> np.ndarray:
        return np.asarray(self._curve(self._clamped(mach)), dtype=float)

    def slope(self, mach: np.ndarray | float) -> np.ndarray:
        """d eps / dM (0 beyond the table's ends)."""
        m = np.asarray(mach, dtype=float)
        inside = (m > self.mach[0]) & (m < self.mach[-1])
        return np.where(inside, self._curve.derivative()(self._clamped(m)), 0.0)


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
