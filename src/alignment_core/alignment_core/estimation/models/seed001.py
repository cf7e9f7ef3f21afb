"""Seed 001's 13-state in-flight alignment model: SINS velocity matched to a Doppler radar.

    x = [phi_E, phi_N, phi_U, dV_E, dV_N, dlon, dlat, eps_x, eps_y, eps_z, dVd, eps_D, dC]

(the paper's order). Height channel ignored (baro-damped: dh = dV_U = 0). Continuous dynamics
(ENU, C_est = exp(-[phi x]) C_true; PSINS / Titterton & Weston, with the position terms):
    phi'  = -[w_in x] phi + d(w_in) - C_b^n eps
    dV'   = ([f^n x] phi + V x (2 d(w_ie) + d(w_en)) - (2 w_ie + w_en) x dV)_(E,N)
    dlat' = dV_N / (R_M + h)
    dlon' = dV_E / ((R_N + h) cos L) + V_E tan L / ((R_N + h) cos L) dlat
    d(w_ie) = [0, -Omega sin L, Omega cos L] dlat
    d(w_en) = [-dV_N / (R_M + h), dV_E / (R_N + h), tan L dV_E / (R_N + h) + V_E sec^2 L / (R_N + h) dlat]
eps and the Doppler errors are random constants: dVd an along-track velocity offset (m/s),
eps_D a track (drift) angle error about the vertical (rad, positive counter-clockwise seen
from above, i.e. about Up), dC a scale-factor error. (Accelerometer biases are not states in
the paper: their effect is absorbed in the tilt.) Radii and gravity are held constant in
latitude (their derivatives are of order e^2 ~ 0.007 of the terms kept).

Doppler: the radar gives the body-frame ground velocity; the SINS resolves it with its own
attitude, V_D = C_b,est^n v_D^b, where the radar's horizontal velocity is
    v_D = (1 + dC) R_U(eps_D) V_h + dVd u,   u = V_h / |V_h|.
Measurement z = (V_SINS - V_D)_(E,N). With C_est = (I - [phi x]) C, to first order
    z = dV + (phi x V)_h - dC V_h - eps_D (e_U x V)_h - dVd u_h + v
    H_E = [0, V_U, -V_N | 1, 0 | 0, 0 | 0 0 0 | -u_E,  V_N, -V_E]
    H_N = [-V_U, 0, V_E | 0, 1 | 0, 0 | 0 0 0 | -u_N, -V_E, -V_N]
Observability (tested): the radar's velocity is resolved with the SINS's own attitude, so
rotating the SINS's attitude and velocity together about the vertical (phi_U = psi,
dV = psi V x e_U) leaves z unchanged (H x = 0) and the SINS's kinematics too (gravity is
vertical): heading is seen only through gyrocompassing (Earth rate), turn or not -- unless the
SINS velocity is known at the start (a tight dV prior), which the paper seems to assume. The
drift-angle error rotates the radar velocity alone: in straight flight it is confounded with
the cross-track velocity error (and dC |V| with dVd along the track); a turn separates it.

Discretisation as models/base.py (second-order Phi, Qd = diag(arw^2 h, vrw^2 h) on phi, dV).

In the engine (`filter.model: seed001_13`, needs `doppler.enabled`): on the deck the LDV /
master velocity match gives the horizontal rows (z_vel_(E,N), H = [0 | I2 | 0]) with the vertical
velocity held to the reference; every valid Doppler sample (/doppler/twist) is matched as
above, with R = sigma^2 I from the sample and the vertical velocity held to the radar's
(C_est v_D^b)_U. Feedback: phi, dV_E, dV_N, lat/lon, eps; the radar's dVd, eps_D, dC stay in
the state (z uses the raw reading). The position prior is 1 m (the engine starts at the
surveyed deck spot). The radar's latency, if any, is not modelled (its stamp is used).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from alignment_core.estimation.models.base import (
    DV,
    EPS,
    OTHER,
    PHI,
    Corrections,
    ErrorModel,
    Match,
    Measurement,
    Propagation,
    nominal_attitude,
    relative_misalignment,
)
from alignment_core.geometry import earth
from alignment_core.geometry.rotations import quat_to_dcm, skew_into
from alignment_core.geometry.rotations_compiled import rotate_attitude
from alignment_core.navigation.strapdown import NavState
from alignment_core.units import ARCMIN, DEG, DPH, UG

LABELS = ('phi_E', 'phi_N', 'phi_U', 'dV_E', 'dV_N', 'dlon', 'dlat', 'eps_x', 'eps_y', 'eps_z',
          'dVd', 'eps_D', 'dC')


@dataclass(frozen=True)
class DopplerTuning:
    """Priors and noise of the 13-state model (defaults: seed 001's numbers where it gives them;
    the Doppler priors from its 0.1031 % total speed error)."""
    tilt_sigma_arcmin: float = 6.0
    yaw_sigma_arcmin: float = 10.0
    velocity_sigma_mps: float = 0.5
    position_sigma_m: float = 30.0
    gyro_bias_sigma_dph: float = 0.02
    doppler_offset_sigma_mps: float = 0.05
    drift_angle_sigma_arcmin: float = 3.0
    scale_sigma: float = 0.001
    arw_dpsh: float = 0.01
    vrw_ugpshz: float = 50.0
    doppler_noise_mps: float = 0.1

    @staticmethod
    def from_config(cfg) -> DopplerTuning:
        """The engine's tuning from a FilterConfig (attitude, velocity, gyro, noise, radar priors)."""
        yaw = cfg.init_yaw_sigma_deg if cfg.init_yaw_sigma_deg > 0.0 else cfg.init_attitude_sigma_deg
        return DopplerTuning(tilt_sigma_arcmin=cfg.init_attitude_sigma_deg * 60.0, yaw_sigma_arcmin=yaw * 60.0,
                             velocity_sigma_mps=cfg.init_velocity_sigma_mps, position_sigma_m=1.0,
                             gyro_bias_sigma_dph=cfg.gyro_bias_sigma_dph,
                             doppler_offset_sigma_mps=cfg.doppler_bias_sigma_mps,
                             drift_angle_sigma_arcmin=cfg.doppler_drift_sigma_arcmin,
                             scale_sigma=cfg.doppler_scale_sigma_ppm * 1e-6, arw_dpsh=cfg.arw_dpsh,
                             vrw_ugpshz=cfg.vrw_ugpshz)


class Seed001Doppler(ErrorModel):
    """seed001_13 (module docstring). `continuous(p)` / `transition(p)` use p.v_n (V_U may be
    non-zero: it only appears in the coefficients), p.lat, p.height."""
    name = 'seed001_13'
    labels = LABELS
    kinds = (PHI,) * 3 + (DV,) * 2 + (OTHER,) * 2 + (EPS,) * 3 + (OTHER,) * 3
    attitude = slice(0, 3)
    velocity_rows = (0, 1)
    uses_doppler = True

    def __init__(self, tuning: DopplerTuning = DopplerTuning()) -> None:
        self.t = tuning
        self._qd: dict[float, np.ndarray] = {}

    def initial_covariance(self) -> np.ndarray:
        t = self.t
        r = earth.A
        return np.diag(np.concatenate([
            np.array([t.tilt_sigma_arcmin, t.tilt_sigma_arcmin, t.yaw_sigma_arcmin]) ** 2 * ARCMIN ** 2,
            np.full(2, t.velocity_sigma_mps ** 2), np.full(2, (t.position_sigma_m / r) ** 2),
            np.full(3, (t.gyro_bias_sigma_dph * DPH) ** 2),
            [t.doppler_offset_sigma_mps ** 2, (t.drift_angle_sigma_arcmin * ARCMIN) ** 2, t.scale_sigma ** 2]]))

    def continuous(self, p: Propagation) -> np.ndarray:
        lat, hgt, v = p.lat, p.height, p.v_n
        r_m, r_n = (float(x) for x in earth.radii(lat))
        rmh, rnh = r_m + hgt, r_n + hgt
        sl, cl = np.sin(lat), np.cos(lat)
        tl = sl / cl
        om = earth.OMEGA_IE
        w_ie = np.array([0.0, om * cl, om * sl])
        w_en = np.array([-v[1] / rmh, v[0] / rnh, v[0] * tl / rnh])
        # d(w_ie) and d(w_en) as linear maps of [dV_E, dV_N, dlat] (3 x 3)
        d_ie = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -om * sl], [0.0, 0.0, om * cl]])
        d_en = np.array([[0.0, -1.0 / rmh, 0.0], [1.0 / rnh, 0.0, 0.0],
                         [tl / rnh, 0.0, v[0] / (rnh * cl * cl)]])
        cols = [3, 4, 6]                                   # dV_E, dV_N, dlat
        f = np.zeros((13, 13))
        skew_into(f, 0, 0, -(w_ie + w_en))
        f[np.ix_([0, 1, 2], cols)] += d_ie + d_en
        f[0:3, 7:10] = -p.c_nb
        fx = np.zeros((3, 3))
        skew_into(fx, 0, 0, p.f_n)
        f[3:5, 0:3] = fx[0:2]
        vx = np.zeros((3, 3))
        skew_into(vx, 0, 0, v)
        f[np.ix_([3, 4], cols)] += (vx @ (2.0 * d_ie + d_en))[0:2]
        wx = np.zeros((3, 3))
        skew_into(wx, 0, 0, -(2.0 * w_ie + w_en))
        f[3:5, 3:5] += wx[0:2, 0:2]
        f[6, 4] = 1.0 / rmh
        f[5, 3] = 1.0 / (rnh * cl)
        f[5, 6] = v[0] * tl / (rnh * cl)
        return f

    def process_noise(self, h: float) -> np.ndarray:
        qd = self._qd.get(h)
        if qd is None:
            arw = self.t.arw_dpsh * DEG / 60.0
            vrw = self.t.vrw_ugpshz * UG
            q = np.zeros(13)
            q[0:3] = arw ** 2 * h
            q[3:5] = vrw ** 2 * h
            qd = self._qd[h] = np.diag(q)
        return qd

    @staticmethod
    def measurement_matrix(v_n: np.ndarray) -> np.ndarray:
        """H (2, 13) at the nav velocity v_n (module docstring)."""
        ve, vn, vu = v_n
        sp = np.hypot(ve, vn)
        ue, un = (ve / sp, vn / sp) if sp > 0.0 else (0.0, 0.0)
        h = np.zeros((2, 13))
        h[0, [1, 2, 3, 10, 11, 12]] = [vu, -vn, 1.0, -ue, vn, -ve]
        h[1, [0, 2, 4, 10, 11, 12]] = [-vu, ve, 1.0, -un, -ve, -vn]
        return h

    def doppler_measurement(self, v_n: np.ndarray, z: np.ndarray, r: np.ndarray | None = None) -> Measurement:
        """z = (V_SINS - C_est v_D^b)_(E,N); v_n the SINS velocity (the nominal V)."""
        if r is None:
            r = np.eye(2) * self.t.doppler_noise_mps ** 2
        return Measurement(np.asarray(z, dtype=float), self.measurement_matrix(v_n), r)

    def measurement(self, m: Match, corr: Corrections) -> Measurement:
        """The deck's velocity match (LDV + master), horizontal rows: z = dV_(E,N) + v."""
        h = np.zeros((2, 13))
        h[0, 3] = h[1, 4] = 1.0
        return Measurement(m.z_vel[0:2], h, m.r_vel[0:2, 0:2])

    def feedback(self, x, p, m: Match, nav: NavState, corr: Corrections) -> np.ndarray:
        """phi, dV_E, dV_N, position and eps fed back; vertical velocity held to m.v_ref[2];
        the radar's errors kept in the state."""
        nav.q_nb = rotate_attitude(nav.q_nb, x[0:3])
        nav.v_n = np.array([nav.v_n[0] - x[3], nav.v_n[1] - x[4], m.v_ref[2]])
        nav.lon = nav.lon - float(x[5])
        nav.lat = nav.lat - float(x[6])
        corr.bg = corr.bg + x[7:10]
        x_new = np.zeros(13)
        x_new[10:13] = x[10:13]
        return x_new

    def misalignment(self, x, p, m: Match, nav: NavState, corr: Corrections):
        return relative_misalignment(nominal_attitude(m), quat_to_dcm(nav.q_nb), p[0:3, 0:3])
