"""The landing gear as the aircraft kinematics sees it: the gear's frame on the deck (the deck
turned by the heading on deck, C_d^s), the airframe's CG on the rigid ship, the deck's
excitation there, and the gear's output in ship axes (the IMU point's motion) and in aircraft
axes (the airframe's rotation, C_mu^T theta: the IMU is mounted in the airframe by mu).
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from alignment_core.aircraft.gear_config import GearConfig
from alignment_core.aircraft.gear_response import GearResponse
from alignment_core.geometry import earth
from alignment_core.geometry.rotations import cross, quat_to_dcm_batch, rotvec_to_dcm_batch
from alignment_core.samples import ShipBatch
from alignment_core.units import DEG

ImuFunction = Callable[..., tuple[np.ndarray, np.ndarray]]
"""(C_a^n, omega_na^a, v_p, a_p, p_world) -> (omega_ib^a, f^a): the kinematics' rigid-body IMU."""


class GearOnDeck:
    """The gear's response (`response`, GearResponse) fed from ship samples, and its output."""

    def __init__(self, cfg: GearConfig, heading_on_deck_deg: float, mu: np.ndarray, r0: np.ndarray,
                 plane: earth.TangentPlane, seed: int, rate_hz: float,
                 holdback: tuple[float, float] | None, imu: ImuFunction) -> None:
        """mu: the mounting misalignment (rad); r0: the IMU's deck spot (ship axes, m); holdback:
        (start, launch) of the hold-back tensioning or None; imu: the kinematics' rigid IMU."""
        psi = -heading_on_deck_deg * DEG
        self.c_ds = np.array([[np.cos(psi), -np.sin(psi), 0.0], [np.sin(psi), np.cos(psi), 0.0], [0.0, 0.0, 1.0]])
        self.c_mu = rotvec_to_dcm_batch(np.asarray(mu, dtype=float))
        self.r_cg = np.asarray(r0, dtype=float) - self.c_ds @ np.asarray(cfg.imu_from_cg_m, dtype=float)
        self.plane = plane
        self.imu = imu
        lat0 = plane.to_geodetic(np.zeros(3))[0]
        f0 = np.array([0.0, 0.0, float(earth.gravity(lat0, self.r_cg[2]))])
        self.response = GearResponse(cfg, seed, rate_hz, f0, holdback)

    def feed(self, sb: ShipBatch, tau: np.ndarray, c_nb: np.ndarray | None = None,
             c_lw: np.ndarray | None = None) -> None:
        """Simulate the gear through these deck samples (tau: their scenario times): the specific
        force at the rigidly mounted CG and the deck's angular acceleration, in the gear's axes.
        Samples already simulated are skipped before their loads are computed (the increments
        feed the samples the truth fed before them). c_nb, c_lw (K, 3, 3): the samples' C_b^n and
        plane.c_local_to_world of their positions, if the caller has them."""
        k = self.response.index(tau)
        new = k >= self.response.n
        if not np.any(new):
            return
        if not np.all(new):
            sb, k = sb.slice(new), k[new]
            c_nb = None if c_nb is None else c_nb[new]
            c_lw = None if c_lw is None else c_lw[new]
        if c_nb is None:
            c_nb = quat_to_dcm_batch(sb.q_nb)
        if c_lw is None:
            c_lw = self.plane.c_local_to_world(sb.p_w)
        wxr = cross(sb.w_b, self.r_cg)
        v_p = np.einsum('kij,kj->ki', c_nb, sb.v_b + wxr)
        a_p = np.einsum('kij,kj->ki', c_nb, sb.a_b + cross(sb.wdot_b, self.r_cg) + cross(sb.w_b, wxr))
        p_p = sb.p_w + np.einsum('kij,kj->ki', c_lw, np.einsum('kij,j->ki', c_nb, self.r_cg))
        _, f_s = self.imu(c_nb, sb.w_b, v_p, a_p, p_p)                   # ship axes
        self.response.feed(k, np.einsum('ji,kj->ki', self.c_ds, f_s),
                           np.einsum('ji,kj->ki', self.c_ds, sb.wdot_b))

    def displacement(self, tau) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The IMU point's displacement, velocity and acceleration (..., 3) relative to its deck
        spot, ship axes, at scenario times tau (...)."""
        return tuple(np.einsum('ij,...j->...i', self.c_ds, x) for x in self.response.imu_motion(tau))

    def rotation(self, tau) -> tuple[np.ndarray, np.ndarray]:
        """The airframe's rotation and its rate (..., 3) relative to the deck, aircraft axes, at
        sample instants tau (...)."""
        th, thd = self.response.rotation_at(self.response.index(tau))
        return tuple(np.einsum('ji,...j->...i', self.c_mu, x) for x in (th, thd))
