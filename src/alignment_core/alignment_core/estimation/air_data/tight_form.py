"""The tightly coupled air-data estimator: the five port pressures are the measurements, the
aligned INS gives the flight (attitude, ground velocity, height), and the state is what the
ports and the INS together determine: the air mass's velocity (wind random walk plus
first-order turbulence), the day's static-pressure ratio and temperature offsets, the ports'
biases and their correlated (first-order Gauss-Markov) noise. h(x) is the port model, genuinely
nonlinear in the state, so EKF, UKF and CKF differ here. Each port is compared with the flight
through its pneumatic lag tau_i = tau0 p0 / p_i: the lag-weighted mean of the model pressure
over the flight's recent past (port_prediction.py). A port whose innovations stay large is
excluded and the filter carries on with the others."""
from __future__ import annotations

import math

import numpy as np

from alignment_core.air_data import standard_day
from alignment_core.air_data.atmosphere import G0, GAMMA, P0, R_AIR
from alignment_core.air_data.fads_solver import FadsSolver
from alignment_core.air_data.flow_angles import air_velocity
from alignment_core.air_data.ports import PortModel
from alignment_core.estimation.air_data import turbulence_model
from alignment_core.estimation.air_data.algorithms import NonlinearFilter, linearised_covariance, make_nonlinear_filter
from alignment_core.estimation.air_data.config import AirDataFilterConfig
from alignment_core.estimation.air_data.fault_detection import PortFaultDetector
from alignment_core.estimation.air_data.inputs import INS_SPAN_S, InsHistory
from alignment_core.estimation.air_data.outputs import AIR_DATA_LABELS, AirDataEstimate
from alignment_core.estimation.air_data.port_prediction import (
    PortPrediction,
    StateLayout,
    air_data_of,
    air_mass_velocity,
    lag_instants,
)
from alignment_core.estimation.air_data.turbulence_model import TurbulenceModel
from alignment_core.geometry.rotations import quat_to_dcm, skew

MIN_PORTS = 4          # fewer cannot separate alpha, beta, Mach and p_inf


class TightAirDataFilter:
    """Push INS solutions (`push_ins`) and port frames (`push_frame`, in time order); read
    `estimate()`. `frame_interval_s` is the FADS sample interval (the noise correlation is per
    frame)."""

    def __init__(self, cfg: AirDataFilterConfig, model: PortModel, frame_interval_s: float) -> None:
        cfg.validate()
        self.cfg, self.model = cfg, model
        self.n_ports = model.geometry.count
        self.layout = StateLayout(self.n_ports, cfg.turbulence_severity != 'none')
        self.turbulence = TurbulenceModel(cfg.turbulence_severity) if self.layout.turbulence else None
        self.frame_interval_s = float(frame_interval_s)
        self.ins = InsHistory(span_s=INS_SPAN_S)
        self.filter: NonlinearFilter | None = None
        self.t = -math.inf
        self.used = np.ones(self.n_ports, dtype=bool)
        self.detector = PortFaultDetector(self.n_ports, cfg.fault_window_s, cfg.fault_false_alarm)
        self.counts = {'frames': 0, 'updates': 0, 'gated': 0, 'no_ins': 0, 'not_finite': 0}
        self.last_nis = math.nan
        self.failure = ''

    # ----- inputs -----
    def push_ins(self, s) -> bool:
        return s.finite() and self.ins.push(s)

    def push_frame(self, t: float, pressures: np.ndarray) -> bool:
        """One frame of absolute port pressures (n,) sensed at t; False if it was not used."""
        p = np.asarray(pressures, dtype=float)
        self.counts['frames'] += 1
        if self.failure:
            return False
        if p.shape != (self.n_ports,) or not np.all(np.isfinite(p)) or np.any(p <= 0.0):
            self.counts['not_finite'] += 1
            return False
        if not self.ins.covers(t, 0.5):
            self.counts['no_ins'] += 1
            return False
        if self.filter is None:
            return self._initialise(t, p)
        if t <= self.t:
            return False
        self._predict(t)
        return self._update(t, p)

    # ----- the filter -----
    def _initialise(self, t: float, p: np.ndarray) -> bool:
        sol = FadsSolver(self.model).solve(p)
        if not bool(sol.converged) or float(sol.mach) < self.cfg.start_mach:
            return False
        ins = self.ins.sample(t)
        t_std = float(standard_day.temperature_pressure(ins.height_m)[0])
        p_std = float(standard_day.day_pressure(ins.height_m, 0.0)[0, 0])
        speed = float(sol.mach) * math.sqrt(GAMMA * R_AIR * t_std)
        v_air_n = quat_to_dcm(ins.q_nb) @ air_velocity(speed, sol.alpha, sol.beta)
        lay, cfg = self.layout, self.cfg
        x0 = np.zeros(lay.size)
        x0[lay.wind] = ins.v_enu - v_air_n
        x0[lay.static] = float(sol.p_inf) / p_std - 1.0
        var = np.zeros(lay.size)
        var[lay.wind] = cfg.wind_sigma_mps**2
        var[lay.turb] = np.diagonal(turbulence_model.STATIONARY) if lay.turbulence else ()
        var[lay.static] = cfg.static_offset_sigma**2
        var[lay.temperature] = cfg.temperature_sigma_k**2
        var[lay.bias] = cfg.bias_sigma_pa**2
        var[lay.noise] = cfg.port_sigma_pa**2
        self.filter = make_nonlinear_filter(cfg.algorithm, x0, np.diag(var))
        self.t = t
        return True

    def _predict(self, t: float) -> None:
        cfg, lay, f = self.cfg, self.layout, self.filter
        assert f is not None
        dt = t - self.t
        phi = np.ones(self.layout.size)
        q = np.zeros(self.layout.size)
        q[lay.wind] = cfg.wind_walk_mps_per_sqrt_s**2 * dt
        phi_full, q_full = np.diag(phi), np.diag(q)
        if lay.turbulence:
            _, rates = self._turbulence_at(t)
            phi_t, q_t = turbulence_model.transition(rates * dt)
            phi_full[lay.turb, lay.turb], q_full[lay.turb, lay.turb] = phi_t, q_t
        q[lay.static] = cfg.static_offset_walk_per_sqrt_s**2 * dt
        q[lay.temperature] = cfg.temperature_walk_k_per_sqrt_s**2 * dt
        rho = cfg.port_correlation ** (dt / self.frame_interval_s)
        phi[lay.noise], q[lay.noise] = rho, cfg.port_sigma_pa**2 * (1.0 - rho * rho)
        for k in (lay.static, lay.temperature, *range(lay.noise.start, lay.noise.stop)):
            phi_full[k, k], q_full[k, k] = phi[k], q[k]
        q_full[lay.wind, lay.wind] = np.diag(q[lay.wind])
        f.predict(phi_full, q_full)
        self.t = t

    def _update(self, t: float, p: np.ndarray) -> bool:
        f = self.filter
        assert f is not None
        ports = np.flatnonzero(self.used)
        taus = self.cfg.lag_s_sea_level * P0 / p[ports]
        instants = lag_instants(t, taus) if self.cfg.lag_s_sea_level > 0.0 else np.full(ports.size, t)
        turb_maps = None
        r = np.eye(ports.size) * self.cfg.port_white_sigma_pa**2
        if self.layout.turbulence:
            m, rates = self._turbulence_at(t)
            turb_maps = m[None, :, :] @ turbulence_model.looking_back(rates, t - instants)
        h = PortPrediction(self.model, self.layout, ports, self.ins.at(instants), turb_maps)
        if self.layout.turbulence and self.cfg.lag_s_sea_level > 0.0:
            r = r + self._lag_noise(h, f.x, m, rates, taus)
        try:
            res = f.update_nonlinear(p[ports], h, r, gate_chi2=self.cfg.gate_chi2)
        except np.linalg.LinAlgError as e:
            self.failure = f'update failed: {e}'
            return False
        if not (np.all(np.isfinite(f.x)) and np.all(np.isfinite(f.P))):
            self.failure = 'the state is no longer finite'
            return False
        self.last_nis = res.nis
        normalised = res.innovation**2 / np.diagonal(res.s)
        worst = self.detector.add(t, ports, normalised)
        if res.accepted:
            self.detector.clear()
        elif worst is None and ports.size > MIN_PORTS:
            worst = self.detector.leave_one_out(t, ports, res.innovation, res.s)
        if worst is not None and ports.size > MIN_PORTS:
            self.used[worst] = False
            self._after_exclusion(f)
        if res.accepted:
            self.counts['updates'] += 1
        else:
            self.counts['gated'] += 1
        return res.accepted

    def _after_exclusion(self, f) -> None:
        """The failed port may have pulled the air-mass states before it was caught: their
        covariance goes back to the start's (correlations with them dropped), so the healthy
        ports set them again within a few frames."""
        lay, cfg = self.layout, self.cfg
        air = np.r_[np.arange(lay.wind.start, lay.wind.stop), np.arange(lay.turb.start, lay.turb.stop)]
        p = f.P.copy()
        p[air, :] = 0.0
        p[:, air] = 0.0
        p[lay.wind, lay.wind] = np.eye(3) * cfg.wind_sigma_mps**2
        if lay.turbulence:
            p[lay.turb, lay.turb] = turbulence_model.STATIONARY
        f.P = p

    def _lag_noise(self, h: PortPrediction, x: np.ndarray, m: np.ndarray, rates: np.ndarray,
                   taus: np.ndarray) -> np.ndarray:
        """R of the gusts inside the ports' lag windows (turbulence_model.lag_covariance), through
        each port's sensitivity to the air-mass velocity, dp_i / dw (central differences)."""
        step = 0.01
        pts = np.repeat(x[None, :], 6, axis=0)
        for k in range(3):
            pts[2 * k, self.layout.wind.start + k] += step
            pts[2 * k + 1, self.layout.wind.start + k] -= step
        y = h(pts)
        jac = np.stack([(y[2 * k] - y[2 * k + 1]) / (2 * step) for k in range(3)], axis=-1)    # (m, 3)
        cov = turbulence_model.lag_covariance(m, rates, taus)                                  # (m, m, 3, 3)
        return np.einsum('ia,ijab,jb->ij', jac, cov, jac)

    def _turbulence_at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(state -> ENU turbulence map (3, 5), rates V / L (3,)) at the INS flight at t."""
        assert self.filter is not None and self.turbulence is not None
        ins = self.ins.sample(t)
        airspeed = float(np.linalg.norm(ins.v_enu - self.filter.x[self.layout.wind]))
        return self.turbulence.at(ins.height_m, ins.v_enu, airspeed)

    # ----- outputs -----
    @property
    def initialised(self) -> bool:
        return self.filter is not None

    @property
    def excluded_ports(self) -> tuple[int, ...]:
        return tuple(int(i) for i in np.flatnonzero(~self.used))

    def state_labels(self) -> tuple[str, ...]:
        return self.layout.labels()

    def estimate(self, t: float | None = None) -> AirDataEstimate | None:
        """Air data at t (default: the last frame) from the state and the INS at t."""
        if self.filter is None:
            return None
        t = self.t if t is None else t
        ins = self.ins.sample(t)
        c_bn = quat_to_dcm(ins.q_nb)
        t_std = float(standard_day.temperature_pressure(ins.height_m)[0])
        lay = self.layout

        turb_map = self._turbulence_at(t)[0] if lay.turbulence else None

        def outputs(x: np.ndarray) -> np.ndarray:
            a = air_data_of(x, lay, c_bn, ins.v_enu, t_std, ins.height_m, turb_map)
            wind = air_mass_velocity(x, lay, turb_map)
            return np.column_stack([a['mach'], a['alpha'], a['beta'], a['speed'], a['p_inf'], a['qc'],
                                    wind, a['v_air_body'], a['p_inf'] + a['qc']])

        x, p = self.filter.x, self.filter.P
        y, cov = linearised_covariance(outputs, x, p)
        wind, v_air = y[6:9], y[9:12]
        wind_cov = cov[6:9, 6:9] + ins.vel_cov + skew(c_bn @ v_air) @ ins.att_cov @ skew(c_bn @ v_air).T
        p_inf, sig_p = y[4], math.sqrt(max(cov[4, 4], 0.0))
        alt, t_alt = (float(v) for v in standard_day.pressure_altitude(p_inf))
        sig = np.sqrt(np.clip(np.diagonal(cov), 0.0, None))
        values = [y[0], y[1], y[2], y[3], p_inf, y[5], alt, *wind]
        sigmas = [sig[0], sig[1], sig[2], sig[3], sig_p, sig[5], R_AIR * t_alt / (G0 * p_inf) * sig_p,
                  *np.sqrt(np.clip(np.diagonal(wind_cov), 0.0, None))]
        value = np.concatenate([values, x])
        sigma = np.concatenate([sigmas, np.sqrt(np.clip(np.diagonal(p), 0.0, None))])
        ok = not self.failure and bool(np.all(np.isfinite(value)))
        return AirDataEstimate(t, AIR_DATA_LABELS + lay.labels(), value, sigma, v_air, cov[9:12, 9:12],
                               wind, wind_cov, float(y[12]), math.sqrt(max(cov[12, 12], 0.0)),
                               healthy=ok, excluded_ports=self.excluded_ports)
