"""The tight form's turbulence: the Dryden forms of MIL-F-8785C as the filter's process model
(the same specification as the wind truth, aircraft/wind.py; the filter is told the severity).
State, dimensionless: the along-track unit process u (first order) and the lateral and vertical
pairs (z, z') of z'' + 2 z' + z = n in the dimensionless time s = int V / L dt (second order),
stationary covariance diag(1, 1/4, 1/4, 1/4, 1/4). The turbulence in ENU is
    sigma_u u along the track + sigma_v (z_v + sqrt(3) z_v') to its left + sigma_w (z_w + sqrt(3) z_w') up,
with the intensities and scale lengths at the INS height and the track of the INS ground velocity."""
from __future__ import annotations

import math

import numpy as np

from alignment_core.air_data.turbulence_spec import dryden_parameters

LABELS = ('turbulence_u', 'turbulence_v', 'turbulence_v_rate', 'turbulence_w', 'turbulence_w_rate')
SIZE = len(LABELS)
STATIONARY = np.diag([1.0, 0.25, 0.25, 0.25, 0.25])


def _pair(ds: float) -> np.ndarray:
    e = math.exp(-ds)
    return e * np.array([[1.0 + ds, ds], [-ds, 1.0 - ds]])


def transition(ds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(Phi, Q) (5, 5) over dimensionless steps ds = (u, v, w) (3,): exact for constant V / L,
    Q = P - Phi P Phi^T with P the stationary covariance (the state stays stationary)."""
    phi = np.zeros((SIZE, SIZE))
    phi[0, 0] = math.exp(-float(ds[0]))
    phi[1:3, 1:3] = _pair(float(ds[1]))
    phi[3:5, 3:5] = _pair(float(ds[2]))
    q = STATIONARY - phi @ STATIONARY @ phi.T
    return phi, 0.5 * (q + q.T)


def looking_back(rates: np.ndarray, back_s: np.ndarray) -> np.ndarray:
    """(K, 5, 5): the expected state back_s (K,) seconds earlier given the state now, for a
    stationary process: P Phi(s)^T P^-1 = Phi(s)^T here (P is a multiple of I in each block)."""
    return np.array([transition(rates * float(s))[0].T for s in back_s])


def lag_covariance(m: np.ndarray, rates: np.ndarray, taus: np.ndarray) -> np.ndarray:
    """(k, k, 3, 3): the covariance, given the state now, of the ENU turbulence averaged over each
    port's lag window (weights e^(-s/tau_i) / tau_i over the past), for ports of lags taus (k,).
    At the lag's scale the Dryden velocities diffuse (their spectra fall as 1 / omega^2):
    u by 2 sigma_u^2 V / L_u per second, the second-order v and w by 3 sigma^2 V / L (the
    sqrt(3) z' part); for a diffusion q the two lag averages of ports i and j covary by
    q E[min(S_i, S_j)] = q tau_i tau_j / (tau_i + tau_j), S exponential of mean tau."""
    su, sv, sw = (float(np.linalg.norm(m[:, k])) for k in (0, 1, 3))
    dirs = [m[:, 0] / max(su, 1e-12), m[:, 1] / max(sv, 1e-12), m[:, 3] / max(sw, 1e-12)]
    q = (2.0 * su * su * rates[0] * np.outer(dirs[0], dirs[0]) + 3.0 * sv * sv * rates[1] * np.outer(dirs[1], dirs[1])
         + 3.0 * sw * sw * rates[2] * np.outer(dirs[2], dirs[2]))
    t = np.asarray(taus, dtype=float)
    share = t[:, None] * t[None, :] / np.maximum(t[:, None] + t[None, :], 1e-12)
    return share[:, :, None, None] * q[None, None, :, :]


class TurbulenceModel:
    """The map from the state to ENU turbulence (3, 5) and the rates V / L (3,) at a flight
    condition, for a severity."""

    def __init__(self, severity: str) -> None:
        self.severity = severity

    def at(self, height_m: float, v_ground_enu: np.ndarray, airspeed_mps: float) -> tuple[np.ndarray, np.ndarray]:
        p = dryden_parameters(height_m, self.severity)          # type: ignore[arg-type]
        chi = math.atan2(float(v_ground_enu[1]), float(v_ground_enu[0]))
        along = np.array([math.cos(chi), math.sin(chi), 0.0])
        left = np.array([-math.sin(chi), math.cos(chi), 0.0])
        up = np.array([0.0, 0.0, 1.0])
        su, sv, sw = float(p.sigma_u), float(p.sigma_v), float(p.sigma_w)
        r3 = math.sqrt(3.0)
        m = np.column_stack([su * along, sv * left, r3 * sv * left, sw * up, r3 * sw * up])
        v = max(float(airspeed_mps), 1.0)
        rates = v / np.array([float(p.length_u), float(p.length_v), float(p.length_w)])
        return m, rates
