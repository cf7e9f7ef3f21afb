"""Velocity-matching error model: phi (3), dV (3), gyro bias eps (3), accel bias (3) = 12
states, optionally + the master INS attitude error phi_m (3) = 15 states.

Nav frame ENU, attitude error C_est = (I - [phi x]) C_true, dV = V_est - V_true; biases are
the residuals of the body-frame sensor biases after compensation (random constants with an
optional random walk). Continuous model (Titterton & Weston 10; PSINS):
  phi'  = -[w_in x] phi - C_b^n eps                     + w_g
  dV'   = [f^n x] phi - [(2 w_ie + w_en) x] dV + C_b^n nabla + w_a
Discretised over h as Phi = I + F h + (F h)^2 / 2 and Qd = G Qc G^T h.
Measurement: z = V_slave - (V_master + C_m^n (w_m x r) + C_m^n v_LDV) = dV + v, H = [0 I 0 0].

Master attitude states (random constants, phi_m' = 0): the master reports C_m,est =
(I - [phi_m x]) C_m. Its nav velocity is exact by construction of the message (it is rotated
back with its own attitude), but the lever-arm and LDV terms u = C_m,est (w_m x r + v_LDV)
are rotated with the erroneous attitude, so z = dV - [u x] phi_m + v, H = [0 I 0 0 -[u x]].
The aircraft-vs-master misalignment error is phi - phi_m: without these states the filter
reports the slave's alignment to a master it believes perfect, and its sigma is too small
whenever the master's own attitude error matters (a long deck alignment).

`VelocityMatching` wraps these functions in the ErrorModel interface (models/base.py): model
names `vm12` and `vm15` (the default). Its numbers are the engine's before the interface
existed, operation for operation.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from alignment_core.compiled import as_float64, kernel
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
    relative_misalignment_k,
)
from alignment_core.geometry.rotations import (
    skew_cells,
    skew_into,
)
from alignment_core.geometry.rotations_compiled import quat_to_dcm_k, rotate_attitude_k, rotvec_to_dcm_k
from alignment_core.navigation.strapdown import NavState
from alignment_core.units import ARCMIN, DEG, DPH, UG

LABELS = ('phi_E', 'phi_N', 'phi_U', 'dV_E', 'dV_N', 'dV_U', 'eps_x', 'eps_y', 'eps_z',
          'nabla_x', 'nabla_y', 'nabla_z')
MASTER_LABELS = ('phim_E', 'phim_N', 'phim_U')
N = 12
H = np.hstack([np.zeros((3, 3)), np.eye(3), np.zeros((3, 6))])


def labels(master_states: bool) -> tuple[str, ...]:
    return LABELS + MASTER_LABELS if master_states else LABELS


def measurement(u_n: np.ndarray, n: int = N) -> np.ndarray:
    """H (3, n); for n >= 15 the master-attitude block (columns 12-14) is -[u x] with u the
    rotated lever-arm plus LDV velocity (nav frame), the columns after it zero (states appended to
    vm15)."""
    return H if n == N else measurement_k(as_float64(u_n), n)


@kernel
def measurement_k(u_n, n):
    """measurement(u_n, n) compiled, for any n >= 12: u_n (3,) float64."""
    h = np.zeros((3, n))
    h[0, 3] = 1.0
    h[1, 4] = 1.0
    h[2, 5] = 1.0
    if n >= 15:                          # -[u x] at column 12
        ux, uy, uz = u_n[0], u_n[1], u_n[2]
        h[0, 13], h[0, 14] = uz, -uy
        h[1, 12], h[1, 14] = -uz, ux
        h[2, 12], h[2, 13] = uy, -ux
    return h


@dataclass(frozen=True)
class NoiseDensities:
    """Continuous white-noise densities: arw rad/sqrt(s), vrw m/s/sqrt(s), bias random walks."""
    arw: float
    vrw: float
    gyro_bias_rw: float
    accel_bias_rw: float


def _fh_index(n: int) -> np.ndarray:
    """Flat indices of F h's non-zero cells in an (n, n) array, in the order transition() lists
    their values: [-w_in h x] at (0, 0), -C h at (0, 6), [f h x] at (3, 0),
    [-(2 w_ie + w_en) h x] at (3, 3), C h at (3, 9)."""
    cells = (skew_cells(0, 0) + [(i, 6 + j) for i in range(3) for j in range(3)] + skew_cells(3, 0)
             + skew_cells(3, 3) + [(3 + i, 9 + j) for i in range(3) for j in range(3)])
    return np.array([r * n + c for r, c in cells])


_FH_INDEX: dict[int, np.ndarray] = {}


def fh_index(n: int) -> np.ndarray:
    """_fh_index(n), made once per n (shared: not to be written)."""
    idx = _FH_INDEX.get(n)
    if idx is None:
        idx = _FH_INDEX[n] = _fh_index(n)
    return idx


def transition(c_nb: np.ndarray, f_n: np.ndarray, w_ie: np.ndarray, w_en: np.ndarray,
               h: float, n: int = N, size: int | None = None) -> np.ndarray:
    """Phi (n, n) over an interval h, from the mean attitude, specific force and rates: the
    compiled phi_from_cells (its numbers are those of `continuous(...) * h` written block by block);
    size > n: in the top-left of a (size, size) identity (states appended to the model)."""
    return phi_from_cells(as_float64(c_nb), as_float64(f_n), as_float64(w_ie), as_float64(w_en), float(h),
                          fh_index(n), n, n if size is None else size)


@kernel
def phi_from_cells(c_nb, f_n, w_ie, w_en, h, idx, n, size):
    """I + F h + (F h)^2 / 2 with F h's 36 non-zero entries (in _fh_index's order) in float
    arithmetic, in the top-left of a (size, size) identity; c_nb (3, 3), f_n, w_ie, w_en (3,),
    idx (36,) flat cell indices of an (n, n) array."""
    c = (c_nb[0, 0], c_nb[0, 1], c_nb[0, 2], c_nb[1, 0], c_nb[1, 1], c_nb[1, 2], c_nb[2, 0], c_nb[2, 1], c_nb[2, 2])
    mh = -h
    ax, ay, az = mh * (w_ie[0] + w_en[0]), mh * (w_ie[1] + w_en[1]), mh * (w_ie[2] + w_en[2])
    bx, by, bz = h * f_n[0], h * f_n[1], h * f_n[2]
    dx = mh * (2.0 * w_ie[0] + w_en[0])
    dy = mh * (2.0 * w_ie[1] + w_en[1])
    dz = mh * (2.0 * w_ie[2] + w_en[2])
    # skew_values(x, y, z) = (-z, y, z, -x, -y, x) per skew block
    vals = (-az, ay, az, -ax, -ay, ax,
            mh * c[0], mh * c[1], mh * c[2], mh * c[3], mh * c[4], mh * c[5], mh * c[6], mh * c[7], mh * c[8],
            -bz, by, bz, -bx, -by, bx,
            -dz, dy, dz, -dx, -dy, dx,
            h * c[0], h * c[1], h * c[2], h * c[3], h * c[4], h * c[5], h * c[6], h * c[7], h * c[8])
    fh = np.zeros((n, n))
    flat = fh.reshape(n * n)
    for i in range(36):
        flat[idx[i]] = vals[i]
    half = np.dot(fh, fh)
    half *= 0.5
    phi = np.eye(n) + fh
    phi += half
    if size == n:
        return phi
    out = np.eye(size)
    out[:n, :n] = phi
    return out


def process_noise(q: NoiseDensities, h: float, n: int = N) -> np.ndarray:
    """Qd (n, n) = G Qc G^T h. The sensor noises are white and isotropic per triad, so
    C_b^n Qc C_b^nT = Qc and Qd does not depend on the attitude; phi_m has no process noise."""
    return np.diag(np.repeat([q.arw**2 * h, q.vrw**2 * h, q.gyro_bias_rw**2 * h,
                              q.accel_bias_rw**2 * h, 0.0][:n // 3], 3))


def continuous(c_nb: np.ndarray, f_n: np.ndarray, w_ie: np.ndarray, w_en: np.ndarray, n: int = N) -> np.ndarray:
    """F (n, n) of the continuous model (transition() is I + F h + (F h)^2 / 2 of it)."""
    f = np.zeros((n, n))
    skew_into(f, 0, 0, -(w_ie + w_en))
    f[0:3, 6:9] = -c_nb
    skew_into(f, 3, 0, f_n)
    skew_into(f, 3, 3, -(2.0 * w_ie + w_en))
    f[3:6, 9:12] = c_nb
    return f


def noise_densities(cfg) -> NoiseDensities:
    """The continuous noise densities of a FilterConfig, in SI units."""
    return NoiseDensities(arw=cfg.arw_dpsh * DEG / 60.0, vrw=cfg.vrw_ugpshz * UG,
                          gyro_bias_rw=cfg.gyro_bias_rw_dphps * DPH, accel_bias_rw=cfg.accel_bias_rw_ugps * UG)


def attitude_variances(cfg) -> np.ndarray:
    """(3,) initial attitude variances: init_attitude_sigma_deg, yaw from init_yaw_sigma_deg if > 0."""
    v = np.full(3, (cfg.init_attitude_sigma_deg * DEG) ** 2)
    if cfg.init_yaw_sigma_deg > 0.0:
        v[2] = (cfg.init_yaw_sigma_deg * DEG) ** 2
    return v


def master_variances(cfg) -> np.ndarray:
    """(3,) prior variances of the master INS attitude error (tilt, tilt, heading)."""
    return np.array([cfg.master_tilt_sigma_arcmin, cfg.master_tilt_sigma_arcmin,
                     cfg.master_heading_sigma_arcmin]) ** 2 * ARCMIN**2


class VelocityMatching(ErrorModel):
    """vm12 / vm15: phi, dV, eps, nabla (+ phi_m), velocity matching (module docstring)."""
    velocity_rows = (0, 1, 2)

    def __init__(self, cfg, master_states: bool) -> None:
        self.cfg = cfg
        self.name = 'vm15' if master_states else 'vm12'
        self.labels = labels(master_states)
        self.kinds = (PHI,) * 3 + (DV,) * 3 + (EPS,) * 3 + (NABLA,) * 3 + (OTHER,) * 3 * master_states
        self._n = len(self.labels)
        self.noise = noise_densities(cfg)
        self._qd: dict[float, np.ndarray] = {}

    def initial_covariance(self) -> np.ndarray:
        cfg = self.cfg
        return np.diag(np.concatenate([
            attitude_variances(cfg),
            np.full(3, cfg.init_velocity_sigma_mps ** 2),
            np.full(3, (cfg.gyro_bias_sigma_dph * DPH) ** 2),
            np.full(3, (cfg.accel_bias_sigma_ug * UG) ** 2),
            master_variances(cfg)][:self._n // 3]))

    def continuous(self, p: Propagation) -> np.ndarray:
        return continuous(p.c_nb, p.f_n, p.w_ie, p.w_en, self._n)

    def transition(self, p: Propagation) -> np.ndarray:
        return transition(p.c_nb, p.f_n, p.w_ie, p.w_en, p.h, self._n)

    def transition_in(self, p: Propagation, n: int) -> np.ndarray:
        return transition(p.c_nb, p.f_n, p.w_ie, p.w_en, p.h, self._n, n)

    def transition_cells(self) -> tuple[np.ndarray, int] | None:
        """Its cells, unless a subclass computes Phi its own way."""
        cls = type(self)
        if cls.transition is not VelocityMatching.transition or cls.transition_in is not VelocityMatching.transition_in:
            return None
        return fh_index(self._n), self._n

    def process_noise(self, h: float) -> np.ndarray:
        qd = self._qd.get(h)
        if qd is None:
            qd = self._qd[h] = process_noise(self.noise, h, self._n)
        return qd

    def measurement(self, m: Match, corr: Corrections) -> Measurement:
        return Measurement(m.z_vel, measurement(m.u_n, self._n), m.r_vel)

    def measurement_in(self, m: Match, corr: Corrections, n: int) -> Measurement:
        if self._n == N or n == self._n:               # vm12's H is a constant: widened by the base class
            return super().measurement_in(m, corr, n)
        return Measurement(m.z_vel, measurement(m.u_n, n), m.r_vel)    # vm15's cells, n columns

    def feedback(self, x: np.ndarray, p: np.ndarray, m: Match, nav: NavState, corr: Corrections) -> np.ndarray:
        """C <- (I + [phi x]) C (exactly: exp([phi x]) C), V <- V - dV, biases accumulate;
        the master's attitude error is not fed back (it is the master's)."""
        nav.q_nb, nav.v_n, corr.bg, corr.ba, x_new = feedback_k(
            as_float64(nav.q_nb), as_float64(nav.v_n), as_float64(corr.bg), as_float64(corr.ba), as_float64(x))
        return x_new

    def feedback_in(self, x: np.ndarray, p: np.ndarray, m: Match, nav: NavState, corr: Corrections) -> np.ndarray:
        """feedback() as it is: it keeps every state from the 13th on, the appended ones too."""
        return self.feedback(x, p, m, nav, corr)

    def misalignment(self, x, p, m: Match, nav: NavState, corr: Corrections):
        """log((C_m c_nom)^T C_a) with, for vm15, C_m corrected by phi_m (C_m = (I + [phi_m x]) C_m,est)
        and the sigma of phi - phi_m."""
        return misalignment_k(as_float64(nav.q_nb), np.ascontiguousarray(nominal_attitude(m), dtype=np.float64),
                             as_float64(x), p, self._n == 15)


@kernel
def feedback_k(q_nb, v_n, bg, ba, x):
    """VelocityMatching.feedback compiled: (q_nb turned by phi = x[0:3] (rotate_attitude),
    v_n - x[3:6], bg + x[6:9], ba + x[9:12], the state kept: zero but x[12:]); float64 operands
    (a float32 state taken exactly, as numpy promotes it)."""
    x_new = np.zeros(x.shape[0])
    x_new[12:] = x[12:]
    return rotate_attitude_k(q_nb, x[0:3]), v_n - x[3:6], bg + x[6:9], ba + x[9:12], x_new


@kernel
def misalignment_k(q_nb, c_m, x, p, master_states):
    """VelocityMatching.misalignment compiled: q_nb (4,), C_m c_nom (3, 3), x (n,) float64,
    P (n, n) in the filter's dtype (p_rel is formed in it); master_states: x[12:15] is phi_m."""
    c_na = np.array(quat_to_dcm_k((q_nb[0], q_nb[1], q_nb[2], q_nb[3]))).reshape(3, 3)
    if master_states:
        c_m = np.dot(np.array(rotvec_to_dcm_k(x[12], x[13], x[14])).reshape(3, 3), c_m)
        p_rel = p[0:3, 0:3] - p[0:3, 12:15] - p[12:15, 0:3] + p[12:15, 12:15]
    else:
        p_rel = np.ascontiguousarray(p[0:3, 0:3])
    return relative_misalignment_k(c_m, c_na, p_rel.astype(np.float64))
