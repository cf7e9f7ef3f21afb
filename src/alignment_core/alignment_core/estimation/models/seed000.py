"""Seed 000's error models: 6 states phi (3), dV (3), velocity matching against master + LDV.

`seed000_6` (linear, small angle): the phi/dV block of the velocity-matching model with no bias
states (the paper's X = [phi, dV], H = [0 I]):
    phi' = -[w_in x] phi + w_g,      dV' = [f^n x] phi - [(2 w_ie + w_en) x] dV + w_a
Phi = I + F h + (F h)^2 / 2, Qd = diag(arw^2 h I, vrw^2 h I); z = V_slave - (V_master +
C_m (w_m x r) + C_m v_LDV) = dV + v. Unmodelled sensor biases show up as attitude (tilt = bias/g).

`seed000_large_angle` (nonlinear, for EKF / UKF / CKF): the same states, with phi a rotation
vector of any size, C_est = exp(-[phi x]) C_true (the paper's large-misalignment equations
(2)-(4) use Euler angles; a rotation vector describes the same attitude error with an exact
propagation and no singularity). With the true nav-frame rate equal to the computed one
(position error negligible over an alignment):
    C_err = C_est C_true^T obeys C_err' = -[w_in x] C_err + C_err [w_in x]  =>  over h
    phi_(k+1) = exp(-[w_in h x]) phi_k                               (exact, linear in phi)
    dV_(k+1) = dV_k + (I - exp([phi_k x])) dv^n - h [(2 w_ie + w_en) x] dV_k
where dv^n = f^n h is the strapdown's nav-frame velocity increment (computed with the erroneous
attitude: the true increment is exp([phi x]) dv^n). For small phi this is the linear model.
EKF Jacobian: d/dphi [-exp([phi x]) v] = [(exp([phi x]) v) x] J_l(phi), J_l the left Jacobian.

Feedback: dV at every update. phi (large-angle model only) is kept in the state -- output
correction -- until every attitude sigma is below `large_angle_feedback_deg`, then fed back at
every update (seed 001's "output correction first, feedback once the filter has settled"). An
EKF that fed back a large phi at once would linearise about zero at every step and be the KF.
"""
from __future__ import annotations

import numpy as np

from alignment_core.estimation.models.base import (
    DV,
    PHI,
    Corrections,
    ErrorModel,
    Match,
    Measurement,
    Propagation,
    nominal_attitude,
    relative_misalignment,
)
from alignment_core.estimation.models.velocity_matching import attitude_variances, noise_densities
from alignment_core.geometry.rotations import (
    quat_to_dcm,
    right_jacobian,
    rotvec_to_dcm,
    skew,
    skew_into,
)
from alignment_core.geometry.rotations_compiled import rotate_attitude
from alignment_core.navigation.strapdown import NavState
from alignment_core.units import DEG

LABELS = ('phi_E', 'phi_N', 'phi_U', 'dV_E', 'dV_N', 'dV_U')
H = np.hstack([np.zeros((3, 3)), np.eye(3)])


class Seed000Linear(ErrorModel):
    """seed000_6: phi, dV; small-angle, velocity matching (module docstring)."""
    name = 'seed000_6'
    labels = LABELS
    kinds = (PHI,) * 3 + (DV,) * 3
    attitude = slice(0, 3)
    velocity_rows = (0, 1, 2)

    def __init__(self, cfg) -> None:
        self.cfg = cfg
        self.noise = noise_densities(cfg)
        self._qd: dict[float, np.ndarray] = {}

    def initial_covariance(self) -> np.ndarray:
        return np.diag(np.concatenate([attitude_variances(self.cfg),
                                       np.full(3, self.cfg.init_velocity_sigma_mps ** 2)]))

    def continuous(self, p: Propagation) -> np.ndarray:
        f = np.zeros((6, 6))
        skew_into(f, 0, 0, -(p.w_ie + p.w_en))
        skew_into(f, 3, 0, p.f_n)
        skew_into(f, 3, 3, -(2.0 * p.w_ie + p.w_en))
        return f

    def process_noise(self, h: float) -> np.ndarray:
        qd = self._qd.get(h)
        if qd is None:
            qd = self._qd[h] = np.diag(np.repeat([self.noise.arw ** 2 * h, self.noise.vrw ** 2 * h], 3))
        return qd

    def measurement(self, m: Match, corr: Corrections) -> Measurement:
        return Measurement(m.z_vel, H, m.r_vel)

    def _feed_attitude(self, x: np.ndarray, p: np.ndarray) -> bool:
        return True

    def feedback(self, x, p, m: Match, nav: NavState, corr: Corrections) -> np.ndarray:
        x_new = np.zeros(6)
        nav.v_n = nav.v_n - x[3:6]
        if self._feed_attitude(x, p):
            nav.q_nb = rotate_attitude(nav.q_nb, x[0:3])
        else:
            x_new[0:3] = x[0:3]
        return x_new

    def misalignment(self, x, p, m: Match, nav: NavState, corr: Corrections):
        """log(C_m^T C_a) with C_a = exp([phi x]) C_a,est (phi = the part not yet fed back)."""
        c_na = quat_to_dcm(nav.q_nb)
        if np.any(x[0:3]):
            c_na = rotvec_to_dcm(x[0:3]) @ c_na
        return relative_misalignment(nominal_attitude(m), c_na, p[0:3, 0:3])


class Seed000LargeAngle(Seed000Linear):
    """seed000_large_angle: phi a rotation vector of any size; nonlinear propagation."""
    name = 'seed000_large_angle'
    nonlinear = True

    def __init__(self, cfg) -> None:
        super().__init__(cfg)
        self.settle_sigma = cfg.large_angle_feedback_deg * DEG
        self.feeding_back = False

    def propagator(self, p: Propagation):
        rot = rotvec_to_dcm(-(p.w_ie + p.w_en) * p.h)
        cor = np.eye(3) - p.h * skew(2.0 * p.w_ie + p.w_en)
        dvn = p.f_n * p.h

        def fun(x: np.ndarray) -> np.ndarray:
            phi = x[0:3]
            return np.concatenate([rot @ phi, cor @ x[3:6] + dvn - rotvec_to_dcm(phi) @ dvn])

        def jac(x: np.ndarray) -> np.ndarray:
            phi = x[0:3]
            j = np.zeros((6, 6))
            j[0:3, 0:3] = rot
            j[3:6, 0:3] = skew(rotvec_to_dcm(phi) @ dvn) @ right_jacobian(-phi)   # J_l(phi) = J_r(-phi)
            j[3:6, 3:6] = cor
            return j
        return fun, jac

    def _feed_attitude(self, x, p) -> bool:
        if not self.feeding_back:
            self.feeding_back = bool(np.all(np.sqrt(np.diag(p)[0:3]) < self.settle_sigma))
        return self.feeding_back
