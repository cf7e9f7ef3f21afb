"""Seed 004's air-data estimator, as published: the state is the air-relative velocity in body
axes, x = v_a^b (3), driven by the IMU's specific force and the INS attitude (the wind held
constant),
    v_a^b' = f^b + C_n^b g^n - C_n^b (2 w_ie + w_en) x v_g - w_nb^b x v_a^b,
    w_nb^b = w_ib^b - C_n^b (w_ie + w_en),
and measured by the FADS solve of each frame (the triples for alpha and beta with the seed's
alpha > 45 deg branch test, the pseudo-inverse for qc and p_inf with its fixed-point eps(M)
iteration), converted to v_a^b with the standard temperature at the solved pressure altitude
(the paper has no temperature sensor: a non-standard day biases its speed), with the solve's
covariance R = J Sigma J^T. Given the attitude the model is linear in x (so is the measurement):
EKF, UKF and CKF then agree to round-off, whatever the seed reports. The specific-force and
rate noises are white per IMU sample, the seed's "accuracy" figures."""
from __future__ import annotations

import math
from typing import Literal

import numpy as np

from alignment_core.air_data import standard_day
from alignment_core.air_data.atmosphere import G0, GAMMA, R_AIR
from alignment_core.air_data.fads_solver import FadsSolver
from alignment_core.air_data.flow_angles import air_angles, air_velocity
from alignment_core.air_data.pitot import impact_pressure_ratio
from alignment_core.air_data.ports import PortModel
from alignment_core.estimation.air_data.algorithms import NonlinearFilter, linearised_covariance, make_nonlinear_filter
from alignment_core.estimation.air_data.config import AirDataFilterConfig
from alignment_core.estimation.air_data.inputs import INS_SPAN_S, InsHistory, InsSample
from alignment_core.estimation.air_data.outputs import AIR_DATA_LABELS, AirDataEstimate
from alignment_core.geometry import earth
from alignment_core.geometry.rotations import quat_to_dcm, skew
from alignment_core.units import DEG

STATE_LABELS = ('v_air_x_mps', 'v_air_y_mps', 'v_air_z_mps')


def _identity(x: np.ndarray) -> np.ndarray:
    return x


_identity.vectorized = True         # type: ignore[attr-defined]


def _rotation_step(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For x' = d - w x x over dt with w and d constant (theta = w dt): x1 = Phi x0 + dt Gamma d,
    Phi = exp(-[theta x]), Gamma = int_0^1 exp(-u [theta x]) du
        = I - (1 - cos t) / t^2 [theta x] + (t - sin t) / t^3 [theta x]^2   (t = |theta|)."""
    t = float(np.linalg.norm(theta))
    k = skew(theta)
    if t < 1e-6:
        a, b, c, d = 1.0 - t * t / 6.0, 0.5 - t * t / 24.0, 0.5 - t * t / 24.0, 1.0 / 6.0 - t * t / 120.0
    else:
        a, b, c, d = math.sin(t) / t, (1.0 - math.cos(t)) / t**2, (1.0 - math.cos(t)) / t**2, (t - math.sin(t)) / t**3
    k2 = k @ k
    return np.eye(3) - a * k + b * k2, np.eye(3) - c * k + d * k2


class PaperAirDataFilter:
    """Push INS solutions, IMU intervals (`push_imu`: mean specific force and rate over (t0, t1])
    and port frames, in time order; read `estimate()`."""

    def __init__(self, cfg: AirDataFilterConfig, model: PortModel, imu_interval_s: float) -> None:
        cfg.validate()
        self.cfg, self.model = cfg, model
        branch: Literal['paper', 'atan2'] = 'paper' if cfg.paper_branch else 'atan2'
        self.solver = FadsSolver(model, alpha_branch=branch, epsilon_iteration='fixed_point')
        # the solve's Jacobian: the root form of the same equations has the same fixed point
        # and so the same derivative, at a fraction of the iteration's cost
        self.jacobian_solver = FadsSolver(model, alpha_branch=branch, epsilon_iteration='root')
        n = model.geometry.count
        self.port_cov = np.eye(n) * (cfg.port_sigma_pa**2 + cfg.port_white_sigma_pa**2)
        self.imu_interval_s = float(imu_interval_s)
        self.ins = InsHistory(span_s=INS_SPAN_S)
        self.filter: NonlinearFilter | None = None
        self.t = -math.inf
        self.p_inf = math.nan
        self.p_inf_var = math.nan
        self.temperature = math.nan
        self.counts = {'frames': 0, 'updates': 0, 'gated': 0, 'no_ins': 0, 'not_finite': 0, 'unsolved': 0}
        self.last_nis = math.nan
        self.failure = ''

    def push_ins(self, s: InsSample) -> bool:
        return s.finite() and self.ins.push(s)

    def push_imu(self, t0: float, t1: float, f_b: np.ndarray, w_ib: np.ndarray) -> None:
        """Propagate over an IMU interval ending at t1 with the mean specific force f_b (3,) and
        rate w_ib (3,) (body FLU) and the INS at the interval's middle."""
        f = self.filter
        if f is None or t1 <= self.t or self.failure:
            return
        dt = t1 - max(t0, self.t)
        ins = self.ins.sample(0.5 * (t0 + t1))
        c_bn = quat_to_dcm(ins.q_nb)
        w_ie, w_en = earth.omega_ie_n(ins.lat_rad), earth.omega_en_n(ins.lat_rad, ins.height_m, ins.v_enu)
        drive = (np.asarray(f_b, dtype=float) + c_bn.T @ earth.gravity_n(ins.lat_rad, ins.height_m)
                 - c_bn.T @ np.cross(2.0 * w_ie + w_en, ins.v_enu))
        w_nb = np.asarray(w_ib, dtype=float) - c_bn.T @ (w_ie + w_en)
        phi, gamma = _rotation_step(w_nb * dt)
        offset = dt * gamma @ drive

        def step(x: np.ndarray) -> np.ndarray:
            return x @ phi.T + offset
        step.vectorized = True      # type: ignore[attr-defined]

        x = f.x
        per_sample = (dt / self.imu_interval_s) * self.imu_interval_s**2
        g_n = earth.gravity_n(ins.lat_rad, ins.height_m)
        tilt = np.cross(c_bn.T @ g_n, np.eye(3)) @ c_bn.T        # d(C_n^b g) / d(phi): C^T [g x]
        qd = (per_sample * (self.cfg.accel_sigma_mps2**2 * np.eye(3)
                            + (self.cfg.gyro_sigma_dps * DEG) ** 2 * (x @ x * np.eye(3) - np.outer(x, x)))
              + 2.0 * self.cfg.ins_error_time_s * dt * tilt @ ins.att_cov @ tilt.T)
        f.predict_nonlinear(step, qd)
        self.t = t1

    def _measure(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, float, float] | None:
        """(v_a^b, its covariance, p_inf, its variance, temperature) of one frame's solve."""
        sol = self.solver.solve(p)
        if not bool(sol.converged):
            return None
        cov = self.jacobian_solver.covariance(p, self.port_cov)

        def velocity(s: np.ndarray) -> np.ndarray:
            _, temp = standard_day.pressure_altitude(s[:, 3])
            return air_velocity(s[:, 2] * np.sqrt(GAMMA * R_AIR * temp), s[:, 0], s[:, 1])
        v, r = linearised_covariance(velocity, sol.vector(), cov)
        _, temp = standard_day.pressure_altitude(float(sol.p_inf))
        return v, r, float(sol.p_inf), float(cov[3, 3]), float(temp)

    def push_frame(self, t: float, pressures: np.ndarray) -> bool:
        p = np.asarray(pressures, dtype=float)
        self.counts['frames'] += 1
        if self.failure:
            return False
        if p.shape != (self.model.geometry.count,) or not np.all(np.isfinite(p)) or np.any(p <= 0.0):
            self.counts['not_finite'] += 1
            return False
        if not self.ins.covers(t, 0.5):
            self.counts['no_ins'] += 1
            return False
        m = self._measure(p)
        if m is None or not np.all(np.isfinite(m[1])):
            self.counts['unsolved'] += 1
            return False
        z, r, p_inf, p_inf_var, temperature = m
        if self.filter is None and np.linalg.norm(z) < self.cfg.start_mach * math.sqrt(GAMMA * R_AIR * temperature):
            return False
        self.p_inf, self.p_inf_var, self.temperature = p_inf, p_inf_var, temperature
        if self.filter is None:
            self.filter = make_nonlinear_filter(self.cfg.algorithm, z, r)
            self.t = t
            return True
        try:
            res = self.filter.update_nonlinear(z, _identity, r, gate_chi2=self.cfg.gate_chi2,
                                               jac=lambda x: np.eye(3))
        except np.linalg.LinAlgError as e:
            self.failure = f'update failed: {e}'
            return False
        if not np.all(np.isfinite(self.filter.x)):
            self.failure = 'the state is no longer finite'
            return False
        self.last_nis = res.nis
        self.counts['updates' if res.accepted else 'gated'] += 1
        return res.accepted

    @property
    def initialised(self) -> bool:
        return self.filter is not None

    def state_labels(self) -> tuple[str, ...]:
        return STATE_LABELS

    def estimate(self, t: float | None = None) -> AirDataEstimate | None:
        f = self.filter
        if f is None:
            return None
        t = self.t if t is None else t
        ins = self.ins.sample(t)
        c_bn = quat_to_dcm(ins.q_nb)
        a = math.sqrt(GAMMA * R_AIR * self.temperature)
        x, p = f.x, f.P

        def outputs(xs: np.ndarray) -> np.ndarray:
            speed, alpha, beta = air_angles(xs)
            return np.column_stack([speed / a, alpha, beta, speed, ins.v_enu[None, :] - xs @ c_bn.T])
        y, cov = linearised_covariance(outputs, x, p)
        mach, p_inf = y[0], self.p_inf
        dp = 1e-3 * max(math.sqrt(self.p_inf_var), 1e-3)          # the speed of sound from the solved p_inf
        dtemp = float(np.diff(standard_day.pressure_altitude(np.array([p_inf - dp, p_inf + dp]))[1])[0]) / (2 * dp)
        cov[0, 0] += (0.5 * mach / self.temperature * dtemp) ** 2 * self.p_inf_var
        qc = float(impact_pressure_ratio(mach)) * p_inf
        sig_p = math.sqrt(self.p_inf_var)
        alt, t_alt = (float(v) for v in standard_day.pressure_altitude(p_inf))
        sig = np.sqrt(np.clip(np.diagonal(cov), 0.0, None))
        wind_cov = cov[4:7, 4:7] + ins.vel_cov
        values = [mach, y[1], y[2], y[3], p_inf, qc, alt, *y[4:7]]
        sigmas = [sig[0], sig[1], sig[2], sig[3], sig_p, qc / p_inf * sig_p, R_AIR * t_alt / (G0 * p_inf) * sig_p,
                  *np.sqrt(np.clip(np.diagonal(wind_cov), 0.0, None))]
        value = np.concatenate([values, x])
        sigma = np.concatenate([sigmas, np.sqrt(np.clip(np.diagonal(p), 0.0, None))])
        ok = not self.failure and bool(np.all(np.isfinite(value)))
        return AirDataEstimate(t, AIR_DATA_LABELS + STATE_LABELS, value, sigma, x.copy(), p.copy(), y[4:7], wind_cov,
                               p_inf + qc, math.hypot(sig_p, qc / p_inf * sig_p), healthy=ok)
