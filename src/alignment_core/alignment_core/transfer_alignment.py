"""The transfer-alignment estimator: slave strapdown + 12-state error-state KF, fed in stamp
order from the slave IMU, the LDV and the master INS (it never sees truth).

Events at equal stamps run IMU first, then LDV, then master: the IMU sample stamped t ends
the interval at t, so the slave solution is at t when the master sample at t is matched.
Initialisation (first master sample): the slave copies the master attitude (times the
nominal mounting), velocity and position at its lever arm. Velocity matching with
computational lever-arm compensation. The aircraft is parked (zero deck velocity, surveyed
spot) until the LDV sees it move; from then on its deck displacement is the integral of the
LDV velocity. Closed loop: each update is fed back into the strapdown.

Published misalignment: mu_hat = log(C_m^n^T C_a^n_hat), the aircraft IMU axes relative to
the master's (aircraft FLU axes), evaluated at each matching update and held once matching
stops (aircraft off the deck); its 1-sigma is from P_phi rotated to aircraft axes.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from scipy.spatial.transform import Rotation

from . import earth
from .attitude import ARCMIN, DEG, DPH, cross3, dcm_to_rotvec_small, rotvec_to_dcm_small
from .config import require
from .filters import CarlsonFilter, FadingMemoryFilter, KalmanFilter, SqrtFadingFilter, StrongTrackingFilter, UDFilter
from .models import velocity_matching as vm
from .samples import ImuSample, LdvSample, MasterSample
from .sensors import UG
from .strapdown import NavState, Strapdown, quat_mul, quat_to_dcm, rotvec_to_quat
from .sync import StampMerger

STREAMS = ('imu', 'ldv', 'master')


@dataclass(frozen=True)
class FilterConfig:
    """Alignment filter tuning and geometry (all known to the user, none from truth)."""
    lever_arm_m: tuple[float, float, float] = (40.0, -10.0, 15.0)
    lever_arm_compensation: bool = True
    init_attitude_sigma_deg: float = 1.0
    init_velocity_sigma_mps: float = 0.1
    gyro_bias_sigma_dph: float = 0.01
    accel_bias_sigma_ug: float = 100.0
    arw_dpsh: float = 0.001
    vrw_ugpshz: float = 10.0
    gyro_bias_rw_dphps: float = 0.0
    accel_bias_rw_ugps: float = 0.0
    ldv_sigma_mps: float = 0.01
    master_velocity_sigma_mps: float = 0.001
    parked_velocity_sigma_mps: float = 0.005
    launch_detect_mps: float = 0.05
    master_attitude_states: bool = True
    algorithm: Literal['kf', 'stf', 'stf_multiple', 'fading', 'fading_tested', 'carlson', 'ud',
                       'combined'] = 'kf'
    float32: bool = False
    stf_rho: float = 0.95
    stf_beta: float = 3.0      # at 100 Hz V0 (about 20 samples) scatters +-30 % around R: beta < ~2.5 fades on noise
    stf_alpha: tuple[float, float, float, float, float] = (1.0, 1.0, 1.0, 1.0, 1.0)
    fading_factor: float = 1.0
    fading_gamma: float = 10.0
    master_tilt_sigma_arcmin: float = 0.2
    master_heading_sigma_arcmin: float = 0.5
    output_rate_hz: float = 10.0
    gate_chi2: float = 0.0
    max_gap_factor: float = 1.5

    def validate(self) -> None:
        for k in ('init_attitude_sigma_deg', 'init_velocity_sigma_mps', 'gyro_bias_sigma_dph',
                  'accel_bias_sigma_ug', 'ldv_sigma_mps', 'output_rate_hz', 'parked_velocity_sigma_mps',
                  'launch_detect_mps'):
            require(getattr(self, k) > 0.0, f"{k} must be > 0, got {getattr(self, k)}")
        for k in ('arw_dpsh', 'vrw_ugpshz', 'gyro_bias_rw_dphps', 'accel_bias_rw_ugps',
                  'master_velocity_sigma_mps', 'gate_chi2'):
            require(getattr(self, k) >= 0.0, f"{k} must be >= 0, got {getattr(self, k)}")
        require(self.max_gap_factor > 1.0, f"max_gap_factor must be > 1, got {self.max_gap_factor}")
        require(0.0 < self.stf_rho <= 1.0, f"stf_rho must be in (0, 1], got {self.stf_rho}")
        require(self.stf_beta >= 1.0, f"stf_beta must be >= 1, got {self.stf_beta}")
        require(all(a >= 1.0 for a in self.stf_alpha), f"stf_alpha must all be >= 1, got {self.stf_alpha}")
        require(self.fading_factor >= 1.0, f"fading_factor must be >= 1, got {self.fading_factor}")
        require(self.fading_gamma >= 1.0, f"fading_gamma must be >= 1, got {self.fading_gamma}")


@dataclass
class Estimate:
    """One output of the filter at a master stamp."""
    t_ns: int
    misalignment: np.ndarray          # (3,) rad, aircraft FLU axes
    misalignment_sigma: np.ndarray    # (3,) rad
    q_nb: np.ndarray                  # (4,) aligned slave attitude
    attitude_cov: np.ndarray          # (3, 3) rad^2, nav frame (phi)
    x: np.ndarray                     # (n,) last a-posteriori error state (before feedback)
    sigma: np.ndarray                 # (n,) 1-sigma of the error state (n = 12 or 15)
    bias_gyro: np.ndarray             # (3,) accumulated gyro bias estimate, rad/s
    bias_accel: np.ndarray            # (3,) accumulated accelerometer bias estimate, m/s^2
    nis: float
    updates: int
    matching: bool


@dataclass
class Counters:
    imu: int = 0
    ldv: int = 0
    master: int = 0
    rejected_nonfinite: int = 0
    rejected_out_of_order: int = 0
    imu_gaps: int = 0
    updates: int = 0
    gated: int = 0
    skipped_before_init: int = 0
    extra: dict = field(default_factory=dict)


def make_filter(cfg: FilterConfig, x0: np.ndarray, p0: np.ndarray):
    """The filter named by cfg.algorithm (alignment_core.filters), in float32 if asked.

    stf_alpha gives the multiple-factor STF's alpha per state block (phi, dV, eps, nabla,
    phi_m): which blocks may change faster than the model says."""
    dtype = np.float32 if cfg.float32 else np.float64
    a = cfg.algorithm
    if a == 'kf':
        return KalmanFilter(x0, p0, dtype=dtype)
    if a == 'stf':
        return StrongTrackingFilter(x0, p0, rho=cfg.stf_rho, beta=cfg.stf_beta, dtype=dtype)
    if a == 'stf_multiple':
        alpha = np.repeat(np.asarray(cfg.stf_alpha), 3)[:len(x0)]
        return StrongTrackingFilter(x0, p0, rho=cfg.stf_rho, beta=cfg.stf_beta, alpha=alpha, dtype=dtype)
    if a == 'fading':
        return FadingMemoryFilter(x0, p0, lam=cfg.fading_factor, dtype=dtype)
    if a == 'fading_tested':
        return FadingMemoryFilter(x0, p0, gamma=cfg.fading_gamma, dtype=dtype)
    if a == 'carlson':
        return CarlsonFilter(x0, p0, dtype=dtype)
    if a == 'ud':
        return UDFilter(x0, p0, dtype=dtype)
    if a == 'combined':
        return SqrtFadingFilter(x0, p0, gamma=cfg.fading_gamma, dtype=dtype)
    raise ValueError(f'unknown filter algorithm {a!r}')


def _finite(*arrays) -> bool:
    """True if every element is finite (a NaN or inf anywhere makes the sum non-finite)."""
    return math.isfinite(sum(map(np.sum, arrays)))


class TransferAlignment:
    """Stamp-ordered transfer-alignment estimator. Push samples; read `outputs`."""

    def __init__(self, cfg: FilterConfig, plane: earth.TangentPlane, imu_rate_hz: float) -> None:
        self.cfg = cfg
        self.plane = plane
        self.merger = StampMerger(STREAMS)
        self.counters = Counters()
        self.imu_dt_nominal = 1.0 / imu_rate_hz
        self.out_period_ns = int(round(1e9 / cfg.output_rate_hz))
        self.r0 = np.asarray(cfg.lever_arm_m, dtype=float)
        self.n = 15 if cfg.master_attitude_states else vm.N
        self.labels = vm.labels(cfg.master_attitude_states)
        self.noise = vm.NoiseDensities(
            arw=cfg.arw_dpsh * DEG / 60.0, vrw=cfg.vrw_ugpshz * UG,
            gyro_bias_rw=cfg.gyro_bias_rw_dphps * DPH, accel_bias_rw=cfg.accel_bias_rw_ugps * UG)
        self.R_moving = np.eye(3) * (cfg.ldv_sigma_mps**2 + cfg.master_velocity_sigma_mps**2)
        self.R_parked = np.eye(3) * (cfg.parked_velocity_sigma_mps**2 + cfg.master_velocity_sigma_mps**2)
        self.moving = False
        self.ins: Strapdown | None = None
        self.kf: KalmanFilter | None = None
        self.t_ins: int | None = None
        self.t0: int | None = None
        self.bg = np.zeros(3)
        self.ba = np.zeros(3)
        self.deck_disp = np.zeros(3)
        self.last_ldv: LdvSample | None = None
        self.mu = np.zeros(3)
        self.mu_sigma = np.full(3, cfg.init_attitude_sigma_deg * DEG)
        self.last_x = np.zeros(self.n)
        self.last_nis = math.nan
        self.matching = False
        self.outputs: list[Estimate] = []
        self._qd: dict[float, np.ndarray] = {}

    # ----- input -----
    def push_imu(self, s: ImuSample) -> bool:
        return self._push('imu', s.t_ns, s, s.gyro, s.accel)

    def push_ldv(self, s: LdvSample) -> bool:
        return self._push('ldv', s.t_ns, s, s.v_s if s.valid else np.zeros(3))

    def push_master(self, s: MasterSample) -> bool:
        return self._push('master', s.t_ns, s, s.p_w, s.q_nb, s.v_b, s.w_b)

    def _push(self, stream: str, t_ns: int, item, *arrays) -> bool:
        if not _finite(*arrays):
            self.counters.rejected_nonfinite += 1
            return False
        if not self.merger.push(stream, t_ns, item):
            self.counters.rejected_out_of_order += 1
            return False
        return True

    def process(self, final: bool = False) -> list[Estimate]:
        """Run every event up to the watermark (all of them if final); return new outputs."""
        n0 = len(self.outputs)
        events = self.merger.flush() if final else self.merger.pop_ready()
        for stream, t, item in events:
            getattr(self, '_on_' + stream)(t, item)
        return self.outputs[n0:]

    # ----- events -----
    def _on_imu(self, t: int, s: ImuSample) -> None:
        self.counters.imu += 1
        if self.ins is None or t <= self.t_ins:
            self.counters.skipped_before_init += 1
            return
        h = (t - self.t_ins) * 1e-9
        if h > self.cfg.max_gap_factor * self.imu_dt_nominal:
            self.counters.imu_gaps += 1
        dth = (s.gyro - self.bg) * h
        dv = (s.accel - self.ba) * h
        f_n = self.ins.update(dth, dv, h)
        phi = vm.transition(self.ins.c_start, f_n, self.ins.w_ie, self.ins.w_en, h, self.n)
        qd = self._qd.get(h)
        if qd is None:
            qd = self._qd[h] = vm.process_noise(self.noise, h, self.n)
        self.kf.predict(phi, qd)
        self.t_ins = t

    def _on_ldv(self, t: int, s: LdvSample) -> None:
        """Parked (held back) until the LDV first reads more than `launch_detect_mps`: until
        then the aircraft's deck velocity is zero and its spot fixed, so LDV noise is neither
        integrated into the lever arm (a random walk of ~2 cm over 300 s, which through
        w' x dr looks like tens of ug) nor added to the reference velocity."""
        self.counters.ldv += 1
        prev = self.last_ldv
        if s.valid and not self.moving and float(np.sqrt(s.v_s @ s.v_s)) > self.cfg.launch_detect_mps:
            self.moving = True
        if self.moving and s.valid and prev is not None and prev.valid:
            self.deck_disp += 0.5 * (prev.v_s + s.v_s) * (t - prev.t_ns) * 1e-9
        self.last_ldv = s

    def _on_master(self, t: int, m: MasterSample) -> None:
        self.counters.master += 1
        c_m = quat_to_dcm(m.q_nb)
        r = self.r0 + self.deck_disp if self.cfg.lever_arm_compensation else self.deck_disp
        ldv = self.last_ldv if (self.last_ldv is not None and self.last_ldv.t_ns == t) else None
        v_rel = ldv.v_s if (ldv is not None and ldv.valid and self.moving) else np.zeros(3)
        u_n = c_m @ (cross3(m.w_b, r) + v_rel)
        v_ref = c_m @ m.v_b + u_n
        if self.ins is None:
            self._initialise(t, m, c_m, r, v_ref)
        elif ldv is not None and ldv.valid and t == self.t_ins:
            self._update(c_m, v_ref, u_n)
            self.matching = True
        else:
            self.matching = False
        if (t - self.t0) % self.out_period_ns == 0:
            self._emit(t)

    def _initialise(self, t, m, c_m, r, v_ref) -> None:
        cfg = self.cfg
        lat, lon, h = self.plane.to_geodetic(m.p_w + self.plane.c_local_to_world(m.p_w) @ (c_m @ r))
        q = Rotation.from_matrix(c_m).as_quat()
        self.ins = Strapdown(NavState(q_nb=q, v_n=v_ref.copy(), lat=float(lat), lon=float(lon),
                                      h=float(h)))
        p0 = np.diag(np.concatenate([
            np.full(3, (cfg.init_attitude_sigma_deg * DEG) ** 2),
            np.full(3, cfg.init_velocity_sigma_mps ** 2),
            np.full(3, (cfg.gyro_bias_sigma_dph * DPH) ** 2),
            np.full(3, (cfg.accel_bias_sigma_ug * UG) ** 2),
            np.array([cfg.master_tilt_sigma_arcmin, cfg.master_tilt_sigma_arcmin,
                      cfg.master_heading_sigma_arcmin]) ** 2 * ARCMIN**2][:self.n // 3]))
        self.kf = make_filter(cfg, np.zeros(self.n), p0)
        self.t_ins = t
        self.t0 = t

    def _update(self, c_m: np.ndarray, v_ref: np.ndarray, u_n: np.ndarray) -> None:
        st = self.ins.s
        z = st.v_n - v_ref
        gate = self.cfg.gate_chi2 if self.cfg.gate_chi2 > 0.0 else None
        r = self.R_moving if self.moving else self.R_parked
        res = self.kf.update(z, vm.measurement(u_n, self.n), r, gate)
        self.last_nis = res.nis
        if not res.accepted:
            self.counters.gated += 1
            return
        self.counters.updates += 1
        x = self.kf.x
        self.last_x = x.copy()
        # feedback: C <- (I + [phi x]) C, V <- V - dV, biases accumulate
        q = quat_mul(rotvec_to_quat(x[0:3]), st.q_nb)
        st.q_nb = q / np.sqrt(q @ q)
        st.v_n = st.v_n - x[3:6]
        self.bg = self.bg + x[6:9]
        self.ba = self.ba + x[9:12]
        x_new = np.zeros(self.n)
        x_new[12:] = x[12:]                 # the master's attitude error is not fed back
        self.kf.x = x_new
        c_na = quat_to_dcm(st.q_nb)
        p = self.kf.P
        if self.n == 15:
            # best estimate of the master's true attitude: C_m = (I + [phi_m x]) C_m,est
            c_m = rotvec_to_dcm_small(x[12:15]) @ c_m
            p_rel = p[0:3, 0:3] - p[0:3, 12:15] - p[12:15, 0:3] + p[12:15, 12:15]
        else:
            p_rel = p[0:3, 0:3]
        self.mu = dcm_to_rotvec_small(c_m.T @ c_na)
        self.mu_sigma = np.sqrt(np.diag(c_na.T @ p_rel @ c_na))

    def _emit(self, t: int) -> None:
        st = self.ins.s
        self.outputs.append(Estimate(
            t_ns=t, misalignment=self.mu.copy(), misalignment_sigma=self.mu_sigma.copy(),
            q_nb=st.q_nb.copy(), attitude_cov=self.kf.P[0:3, 0:3].copy(), x=self.last_x.copy(),
            sigma=np.sqrt(np.diag(self.kf.P)), bias_gyro=self.bg.copy(), bias_accel=self.ba.copy(),
            nis=self.last_nis, updates=self.counters.updates, matching=self.matching))
