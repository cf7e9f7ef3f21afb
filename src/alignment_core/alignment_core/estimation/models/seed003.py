"""Seed 003's velocity + attitude matching model with mounting misalignment and deck flexure.

`seed003_21`: x = [phi (3), dV (3), eps (3), nabla (3), mu (3), theta (3), theta' (3)];
`seed003_24`: the same + the master INS attitude error phi_m (3, random constants), as in vm15.
`filter.flexure_states: false` drops theta and theta' (15 and 18 states): a mount known to be
rigid (no deck flexure between the master and the slave), H_a = [I 0 0 0 -C (-I)].

Geometry: the aircraft IMU sits on the deck with C_a^n = C_m^n exp([mu x]) exp([theta x]),
mu the static mounting misalignment (aircraft axes, random constant), theta the deck flexure
(aircraft axes), per axis a second-order Markov process
    theta'' + 2 beta theta' + beta^2 theta = w,   beta = 2.146 / tau,   E[w w] = 4 beta^3 sigma^2
(filter parameters `flexure_sigma_arcmin`, `flexure_tau_s`, per axis).

Dynamics: phi, dV, eps, nabla as the velocity-matching model (velocity_matching.py, second-order
Phi); mu' = 0; theta as above, discretised exactly (Van Loan, gauss_markov.gm2_discrete). The
blocks do not couple in F (theta only enters the measurement), so Phi and Qd are block-diagonal.

Measurement (6 rows):
  velocity  z_v = V_slave - V_ref = dV (- [u x] phi_m)                       (as vm12 / vm15)
  attitude  Delta = C_a,est exp(-[mu_est x]) C_m,est^T,  z_a = log(Delta^T) (rotation vector),
            i.e. the slave's attitude against the master's carried through the estimated
            mounting. With C_a,est = exp(-[phi x]) C_a, C_m,est = exp(-[phi_m x]) C_m and
            dmu = mu - mu_est, to first order in the small quantities
                Delta = exp(-[phi x]) C_m exp([(dmu + theta) x]) C_m^T exp([phi_m x])
                      = I - [(phi - C (dmu + theta) - phi_m) x],   C = C_m,est exp([mu_est x])
            so z_a = phi - C dmu - C theta (- phi_m) + v_a and
            H_a = [I  0  0  0  -C  -C  0  (-I)].
            (Second-order terms dropped: the rotation of theta by mu, ~mu theta, and the
            difference between C_m,est exp(mu_est) and the true C_a^n, ~phi dmu.)
  R = diag(r_vel, sigma_a^2 I), sigma_a = `attitude_match_sigma_arcmin` (master attitude noise,
  timing; in seed003_21 the master's attitude error is only this white noise, as in the paper).

Feedback: phi, dV, eps, nabla as vm; mu_est <- mu_est + dmu (first order); theta, theta' and
phi_m stay in the state. The published misalignment is mu_est with the sigma of dmu: the
static mounting, which the truth reports (the flexure is the deck's, not the mounting's).
Separating mu from theta needs time (sigma_mu ~ sigma_theta sqrt(2 tau / T)); separating it
from phi_m (seed003_24) needs attitude change, so on a gently rolling deck the master's prior
attitude sigma stays in sigma_mu.
"""
from __future__ import annotations

import numpy as np

from alignment_core.estimation.models.base import (
    DV,
    EPS,
    NABLA,
    OTHER,
    PHI,
    Corrections,
    ErrorModel,
    Match,
    Measurement,
    Propagation,
    nominal_attitude,
)
from alignment_core.estimation.models.velocity_matching import LABELS as VM_LABELS
from alignment_core.estimation.models.velocity_matching import (
    MASTER_LABELS,
    attitude_variances,
    continuous,
    master_variances,
    noise_densities,
    process_noise,
    transition,
)
from alignment_core.gauss_markov import BETA_TAU, gm2_discrete
from alignment_core.geometry.rotations import (
    dcm_to_rotvec,
    floats,
    quat_to_dcm,
    rotvec_to_dcm,
    skew_cells,
    skew_values,
)
from alignment_core.geometry.rotations_compiled import rotate_attitude
from alignment_core.navigation.strapdown import NavState
from alignment_core.units import ARCMIN, DEG, DPH, UG

MU = slice(12, 15)
THETA = slice(15, 18)
THETA_DOT = slice(18, 21)
PHI_M = slice(21, 24)


class Seed003VelocityAttitude(ErrorModel):
    """seed003_21 / seed003_24 (module docstring)."""
    attitude = slice(0, 3)
    velocity_rows = (0, 1, 2)
    attitude_rows = (0, 1, 2)

    def __init__(self, cfg, master_states: bool) -> None:
        self.cfg = cfg
        self.master = master_states
        self.name = 'seed003_24' if master_states else 'seed003_21'
        self.flexure = getattr(cfg, 'flexure_states', True)
        flex = ('theta_x', 'theta_y', 'theta_z', 'thetadot_x', 'thetadot_y', 'thetadot_z') if self.flexure else ()
        self.labels = VM_LABELS + ('mu_x', 'mu_y', 'mu_z') + flex + (MASTER_LABELS if master_states else ())
        self._phi_m = PHI_M if self.flexure else THETA     # without flexure phi_m follows mu
        self.kinds = (PHI,) * 3 + (DV,) * 3 + (EPS,) * 3 + (NABLA,) * 3 + (OTHER,) * (len(self.labels) - 12)
        self._n = len(self.labels)
        self.noise = noise_densities(cfg)
        self.sigma_flex = np.asarray(cfg.flexure_sigma_arcmin, dtype=float) * ARCMIN
        self.tau_flex = np.asarray(cfg.flexure_tau_s, dtype=float)
        self.beta = BETA_TAU / self.tau_flex if self.flexure else np.zeros(3)
        self.r_att = np.eye(3) * (cfg.attitude_match_sigma_arcmin * ARCMIN) ** 2
        self._flex: dict[float, tuple[np.ndarray, np.ndarray]] = {}
        self._h0 = np.zeros((6, self._n))
        self._h0[0:3, 3:6] = np.eye(3)
        self._h0[3:6, 0:3] = np.eye(3)
        if master_states:
            self._h0[3:6, self._phi_m] = -np.eye(3)
        self._r0 = np.zeros((6, 6))
        self._r0[3:6, 3:6] = self.r_att
        self._qd: dict[float, np.ndarray] = {}
        self._phi0: dict[float, np.ndarray] = {}
        # cells of H the measurement fills each time: -C at (3, MU) and (3, THETA), then (seed003_24)
        # -[u x] at (0, PHI_M), as flat indices for one put()
        cols = (MU.start, THETA.start) if self.flexure else (MU.start,)
        cells = [(3 + i, col + j) for col in cols for i in range(3) for j in range(3)]
        if master_states:
            cells += skew_cells(0, self._phi_m.start)
        self._h_cells = np.array([r * self._n + c for r, c in cells])

    def initial_covariance(self) -> np.ndarray:
        c = self.cfg
        blocks = [attitude_variances(c), np.full(3, c.init_velocity_sigma_mps ** 2),
                  np.full(3, (c.gyro_bias_sigma_dph * DPH) ** 2), np.full(3, (c.accel_bias_sigma_ug * UG) ** 2),
                  np.full(3, (c.mounting_sigma_deg * DEG) ** 2)]
        if self.flexure:
            blocks += [self.sigma_flex ** 2, (self.beta * self.sigma_flex) ** 2]
        if self.master:
            blocks.append(master_variances(c))
        return np.diag(np.concatenate(blocks))

    def continuous(self, p: Propagation) -> np.ndarray:
        f = np.zeros((self._n, self._n))
        f[0:12, 0:12] = continuous(p.c_nb, p.f_n, p.w_ie, p.w_en)
        if not self.flexure:
            return f
        f[THETA, THETA_DOT] = np.eye(3)
        f[THETA_DOT, THETA] = -np.diag(self.beta ** 2)
        f[THETA_DOT, THETA_DOT] = -np.diag(2.0 * self.beta)
        return f

    def _flexure(self, h: float) -> tuple[np.ndarray, np.ndarray]:
        """(Phi, Qd) of the flexure block [theta (3), theta' (3)] over h, exact."""
        fl = self._flex.get(h)
        if fl is None:
            phi = np.zeros((6, 6))
            qd = np.zeros((6, 6))
            for i in range(3):
                ph, q, _ = gm2_discrete(self.sigma_flex[i], self.tau_flex[i], h)
                idx = np.array([i, 3 + i])
                phi[np.ix_(idx, idx)] = ph
                qd[np.ix_(idx, idx)] = q
            fl = self._flex[h] = (phi, qd)
        return fl

    def transition(self, p: Propagation) -> np.ndarray:
        phi0 = self._phi0.get(p.h)
        if phi0 is None:                  # I with the flexure block, per interval length
            phi0 = self._phi0[p.h] = np.eye(self._n)
            if self.flexure:
                phi0[15:21, 15:21] = self._flexure(p.h)[0]
        phi = phi0.copy()
        phi[0:12, 0:12] = transition(p.c_nb, p.f_n, p.w_ie, p.w_en, p.h)
        return phi

    def process_noise(self, h: float) -> np.ndarray:
        qd = self._qd.get(h)
        if qd is None:
            qd = np.zeros((self._n, self._n))
            qd[0:12, 0:12] = process_noise(self.noise, h)
            if self.flexure:
                qd[15:21, 15:21] = self._flexure(h)[1]
            self._qd[h] = qd
        return qd

    def reference_attitude(self, m: Match, corr: Corrections) -> np.ndarray:
        """C = C_m,est c_nom exp([mu_est x]): the aircraft attitude predicted from the master."""
        return nominal_attitude(m) @ rotvec_to_dcm(corr.mu)

    def measurement(self, m: Match, corr: Corrections) -> Measurement:
        c = self.reference_attitude(m, corr)
        c_a = quat_to_dcm(m.ins.q_nb)
        delta = c_a @ c.T
        z = np.concatenate([m.z_vel, dcm_to_rotvec(delta.T)])
        h = self._h0.copy()               # the constant blocks: I (velocity), I (phi), -I (phi_m)
        neg_c = [-e for e in c.ravel().tolist()]
        vals = neg_c + neg_c if self.flexure else neg_c     # H[3:6, MU] = H[3:6, THETA] = -C
        if self.master:                   # H[0:3, PHI_M] = [(-u) x]
            ux, uy, uz = floats(m.u_n)
            vals += skew_values(-ux, -uy, -uz)
        h.put(self._h_cells, vals)
        r = self._r0.copy()
        r[0:3, 0:3] = m.r_vel
        return Measurement(z, h, r)

    def feedback(self, x, p, m: Match, nav: NavState, corr: Corrections) -> np.ndarray:
        nav.q_nb = rotate_attitude(nav.q_nb, x[0:3])
        nav.v_n = nav.v_n - x[3:6]
        corr.bg = corr.bg + x[6:9]
        corr.ba = corr.ba + x[9:12]
        corr.mu = corr.mu + x[MU]
        x_new = np.zeros(self._n)
        x_new[15:] = x[15:]
        return x_new

    def misalignment(self, x, p, m: Match, nav: NavState, corr: Corrections):
        return corr.mu.copy(), np.sqrt(np.diag(p)[MU])
