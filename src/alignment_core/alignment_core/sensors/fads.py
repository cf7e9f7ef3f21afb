"""Flush air-data sensor (FADS): port pressures of the nose from the aircraft's truth, with
the air-data truth of each frame.

Truth. The air moves with the wind of a WindField the stage owns (aircraft/wind.py, stream
stage_rng(seed, 'wind'), config `FadsConfig.wind`; or one passed in); v_air = v_ground - wind
(ENU), rotated into body FLU axes by the attitude; flow angles by air_data/flow_angles.py; the
day's atmosphere at the geometric height gives p_inf and T, so M = |v_air| / a(T); the port
pressures u_i are PortModel's (a lee-side port gets its value at sigma = 90 deg).
Pneumatic lag. Per port tau dy/dt = u - y, tau = tau0 P0 / u (the gas in the tube is at the
port's pressure: a stagnation port lags less than a side port); between two truth samples u is
linear in time and tau is held at tau0 P0 / mean(u), and the lag is integrated exactly:
    y(s) = e y0 + (1 - e) u0 + (u1 - u0) (s / h - (tau / h)(1 - e)),   e = exp(-s / tau),
s the time since the earlier sample, h the step. y starts at u (steady) at the first sample.
Frames. On the stage's own grid t0 + k / rate_hz; a frame at t_k between truth samples takes
y(t_k - t_(j-1)) and the truth of the linearly interpolated air velocity, wind and height
(the truth sample itself when t_k falls on one). Measured, per port,
    p = y (1 + F m_k) + F a_k + b(t_k),
a_k, m_k first-order Gauss-Markov, x_k = rho x_(k-1) + sqrt(1 - rho^2) sigma n_k with rho
`noise_correlation`, stationary start, drawn at every grid time (stream stage_rng(seed,
'fads'), 2 n normals per grid time, additive then multiplicative) whether or not a frame is
produced; F the noise fault's factor (1 without), b = bias_pa + random constant (stream
'fads_bias') + the bias steps so far. A blocked port's y stays at its value at the fault
time. No frame where the true airspeed is below min_airspeed_mps. variance_pa2 is the
nominal noise variance sigma_pa^2 + (scale_sigma p)^2 (the sensor's own claim: no faults,
no bias, no lag).
Stepping (`step`, one truth sample) and the batch (`step_batch`, `simulate_fads`) run the same
code on the stage's state, so they give the same frames: bit for bit without turbulence, to
round-off (~1e-15 relative) with it (the Dryden recursion is scanned in chunks).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from alignment_core.air_data.atmosphere import P0, Atmosphere, pressure_altitude
from alignment_core.air_data.day_offsets import DayOffsets
from alignment_core.air_data.flow_angles import air_angles
from alignment_core.air_data.pitot import impact_pressure
from alignment_core.air_data.ports import PortModel, port_pressures
from alignment_core.aircraft.wind import WindField
from alignment_core.rng import stage_rng
from alignment_core.sensors.fads_config import FadsConfig

LABELS = ('mach', 'alpha_rad', 'beta_rad', 'tas_mps', 'static_pressure_pa', 'impact_pressure_pa',
          'pressure_altitude_m', 'wind_east_mps', 'wind_north_mps', 'wind_up_mps', 'total_pressure_pa',
          'temperature_k')
NEVER = np.iinfo(np.int64).max


@dataclass(frozen=True)
class AirDataTruth:
    """Air data of a frame (SI, rad): wind ENU blowing to, v_air_body FLU (aircraft relative
    to the air), port_pressures the model's at this instant (no lag, noise, bias or fault),
    windward False when a port is on the lee side."""
    mach: float
    alpha_rad: float
    beta_rad: float
    tas_mps: float
    static_pressure_pa: float
    impact_pressure_pa: float
    total_pressure_pa: float
    pressure_altitude_m: float
    temperature_k: float
    wind_enu_mps: np.ndarray
    v_air_body_mps: np.ndarray
    port_pressures_pa: np.ndarray
    windward: bool

    @staticmethod
    def labels() -> tuple[str, ...]:
        return LABELS

    def vector(self) -> np.ndarray:
        """(len(LABELS),) in the order of `labels()`."""
        w = self.wind_enu_mps
        return np.array([self.mach, self.alpha_rad, self.beta_rad, self.tas_mps, self.static_pressure_pa,
                         self.impact_pressure_pa, self.pressure_altitude_m, w[0], w[1], w[2],
                         self.total_pressure_pa, self.temperature_k])


@dataclass(frozen=True)
class FadsFrame:
    """One frame: measured port pressures (n,) Pa, their nominal noise variance (n,) Pa^2."""
    t_ns: int
    pressures_pa: np.ndarray
    variance_pa2: np.ndarray
    truth: AirDataTruth


def air_data(model: PortModel, day: DayOffsets, v_air_body: np.ndarray, height_m: np.ndarray) -> dict[str, np.ndarray]:
    """Truth air data of air velocities (N, 3) FLU at geometric heights (N,): arrays (N,),
    'ports' (N, n) and 'windward' (N,)."""
    tas, alpha, beta = air_angles(v_air_body)
    atm = Atmosphere(height_m, day)
    p_inf, temp = atm.pressure, atm.temperature
    mach = tas / atm.speed_of_sound
    qc = impact_pressure(mach, p_inf)
    c = model.cos_incidence(alpha, beta)
    ports = port_pressures(qc, p_inf, np.maximum(c, 0.0), model.epsilon(mach))
    return dict(tas=tas, alpha=alpha, beta=beta, p_inf=p_inf, temp=temp, mach=mach, qc=qc, ports=ports,
                windward=np.all(c > 0.0, axis=-1))


@dataclass
class _Held:
    """The last truth sample: time, lag state y and input u (n,), air velocity, wind, height, p_inf."""
    t_ns: int
    y: np.ndarray
    u: np.ndarray
    v_air_body: np.ndarray
    wind: np.ndarray
    height: float
    p_inf: float


class FadsStage:
    """Aircraft truth in -> FADS frames on the stage's rate grid from t0_ns (module docstring).
    `wind`: the WindField to use (default WindField(cfg.wind, seed)); the stage calls it once
    per truth sample, so it must not be shared with another consumer."""

    def __init__(self, cfg: FadsConfig, seed: int, t0_ns: int, wind: WindField | None = None) -> None:
        cfg.validate()
        self.cfg = cfg
        self.t0_ns = int(t0_ns)
        self.model = PortModel(cfg.geometry, cfg.epsilon)
        self.n_ports = n = cfg.geometry.count
        self.wind = WindField(cfg.wind, seed) if wind is None else wind
        self.rng = stage_rng(seed, 'fads')
        self.bias_pa = np.array(cfg.bias_pa, dtype=float) if cfg.bias_pa else np.zeros(n)
        if cfg.bias_sigma_pa > 0.0:
            self.bias_pa = self.bias_pa + cfg.bias_sigma_pa * stage_rng(seed, 'fads_bias').standard_normal(n)
        self.faults = cfg.parsed_faults()
        at_ns = [self.t0_ns + int(round(f.at_s * 1e9)) for f in self.faults]
        self.block_ns = np.full(n, NEVER, dtype=np.int64)
        for f, t in zip(self.faults, at_ns):
            if f.kind == 'blocked':
                self.block_ns[f.port] = t
        self._bias_steps = [(t, f) for t, f in zip(at_ns, self.faults) if f.kind == 'bias_step']
        self._noise_faults = sorted(((t, f) for t, f in zip(at_ns, self.faults) if f.kind == 'noise'),
                                    key=lambda x: x[0])
        self.frozen = np.full(n, np.nan)            # a blocked port's held pressure (NaN: not yet blocked)
        self.rho = cfg.noise_correlation
        self._gm: np.ndarray | None = None          # unit GM states (2, n): additive, multiplicative
        self._next_k = 0
        self._held: _Held | None = None

    # --- public --------------------------------------------------------------------------
    def step(self, t_ns: int, q_nb: np.ndarray, v_ground_enu: np.ndarray, height_m: float) -> list[FadsFrame]:
        """One truth sample (attitude (4,) xyzw body FLU -> ENU, ground velocity (3,) ENU,
        geometric height m) -> the frames due in (previous sample, t_ns]."""
        return self.step_batch(np.array([t_ns], dtype=np.int64), np.asarray(q_nb, dtype=float)[None],
                               np.asarray(v_ground_enu, dtype=float)[None], np.array([height_m], dtype=float))

    def step_batch(self, t_ns: np.ndarray, q_nb: np.ndarray, v_ground_enu: np.ndarray,
                   height_m: np.ndarray) -> list[FadsFrame]:
        """N truth samples (t_ns (N,) increasing, q_nb (N, 4), v_ground_enu (N, 3), height_m
        (N,)) -> the frames due up to t_ns[-1], continuing the stage's state."""
        t_ns = np.asarray(t_ns, dtype=np.int64).reshape(-1)
        q_nb, v_g = np.asarray(q_nb, dtype=float).reshape(-1, 4), np.asarray(v_ground_enu, dtype=float).reshape(-1, 3)
        height = np.asarray(height_m, dtype=float).reshape(-1)
        if not len(t_ns) == len(q_nb) == len(v_g) == len(height):
            raise ValueError("t_ns, q_nb, v_ground_enu and height_m need the same length")
        if len(t_ns) == 0:
            return []
        if np.any(np.diff(t_ns) <= 0) or (self._held is not None and t_ns[0] <= self._held.t_ns):
            raise ValueError("FADS truth samples must come in strictly increasing time")
        mean = np.asarray(self.wind.cfg.mean_enu_mps, dtype=float)     # Dryden's airspeed: ground - mean wind
        wind = self.wind.wind((t_ns - self.t0_ns) * 1e-9, height, np.linalg.norm(v_g - mean, axis=1),
                              np.arctan2(v_g[:, 1], v_g[:, 0]))
        v_air_b = Rotation.from_quat(q_nb).inv().apply(v_g - wind)
        now = air_data(self.model, self.cfg.day, v_air_b, height)
        h0 = self._held
        if h0 is None:
            t_all, u_all, p_all = t_ns, now['ports'], now['p_inf']
            vb_all, w_all, hh_all = v_air_b, wind, height
            y0 = now['ports'][0].copy()
        else:
            t_all = np.concatenate([[h0.t_ns], t_ns])
            u_all = np.concatenate([h0.u[None], now['ports']])
            p_all = np.concatenate([[h0.p_inf], now['p_inf']])
            vb_all, w_all = np.concatenate([h0.v_air_body[None], v_air_b]), np.concatenate([h0.wind[None], wind])
            hh_all = np.concatenate([[h0.height], height])
            y0 = h0.y
        y_all, tau = self._lag(t_all, u_all, p_all, y0)
        frames = self._frames(t_all, u_all, y_all, tau, vb_all, w_all, hh_all)
        self._held = _Held(int(t_all[-1]), y_all[-1].copy(), u_all[-1].copy(), vb_all[-1].copy(),
                           w_all[-1].copy(), float(hh_all[-1]), float(p_all[-1]))
        return frames

    # --- lag ---------------------------------------------------------------------------
    def _lag(self, t: np.ndarray, u: np.ndarray, p: np.ndarray, y0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lag states (M, n) at the samples t (M,) from y0 at t[0], and tau (M - 1, n) of each
        step and port; blocked ports frozen from their fault time."""
        tau0 = self.cfg.lag_s_sea_level
        tau = tau0 * P0 / (0.5 * (u[:-1] + u[1:]))
        y = np.empty_like(u)
        y[0] = y0
        if tau0 == 0.0:
            y[1:] = u[1:]
        else:
            h = (np.diff(t) * 1e-9)[:, None]
            e = np.exp(-h / tau)
            w = (tau / h) * (1.0 - e)
            g = (1.0 - e) * u[:-1] + (1.0 - w) * (u[1:] - u[:-1])
            for j in range(1, len(t)):
                y[j] = e[j - 1] * y[j - 1] + g[j - 1]
        for port in np.flatnonzero(self.block_ns <= t[-1]):
            j = 0
            if np.isnan(self.frozen[port]):
                j = int(np.searchsorted(t, self.block_ns[port], side='left'))
                if j == 0:
                    self.frozen[port] = y[0, port]
                else:
                    s = np.array([self.block_ns[port] - t[j - 1]], dtype=float)
                    h = np.array([t[j] - t[j - 1]], dtype=float)
                    exact = np.array([t[j] == self.block_ns[port]])
                    self.frozen[port] = self._between(s, h, tau[j - 1:j], y[j - 1:j], u[j - 1:j], u[j:j + 1],
                                                      exact, y[j:j + 1])[0, port]
            y[j:, port] = self.frozen[port]
        return y, tau

    def _between(self, s_ns: np.ndarray, h_ns: np.ndarray, tau: np.ndarray, y0: np.ndarray, u0: np.ndarray,
                 u1: np.ndarray, exact: np.ndarray, y1: np.ndarray) -> np.ndarray:
        """Lag states (K, n) at s_ns (K,) into steps of h_ns from (y0, u0) towards u1; y1 where exact."""
        frac = (s_ns / h_ns)[:, None]
        if self.cfg.lag_s_sea_level == 0.0:
            out = u0 + frac * (u1 - u0)
        else:
            s, tk = s_ns * 1e-9, tau
            e = np.exp(-s[:, None] / tk)
            out = e * y0 + (1.0 - e) * u0 + (u1 - u0) * (frac - tk / (h_ns[:, None] * 1e-9) * (1.0 - e))
        return np.where(exact[:, None], y1, out)

    # --- frames ------------------------------------------------------------------------
    def _noise(self, m: int) -> np.ndarray:
        """Unit Gauss-Markov states (m, 2, n) at the next m grid times."""
        n = self.rng.standard_normal((m, 2, self.n_ports))
        x = np.empty_like(n)
        start = 0
        if self._gm is None:
            x[0], start = n[0], 1                    # stationary start
            self._gm = x[0]
        if m > start:
            # imported here: scipy.signal (and the scipy.stats it pulls in) would add seconds to the
            # start-up of every node that imports this module, most of which never make a frame
            from scipy.signal import lfilter
            c = np.sqrt(1.0 - self.rho**2)
            x[start:], _ = lfilter([c], [1.0, -self.rho], n[start:], axis=0, zi=(self.rho * self._gm)[None])
        self._gm = x[-1].copy()
        return x

    def _frames(self, t: np.ndarray, u: np.ndarray, y: np.ndarray, tau: np.ndarray, vb: np.ndarray,
                wind: np.ndarray, height: np.ndarray) -> list[FadsFrame]:
        cfg, period = self.cfg, self.cfg.period_ns
        if t[-1] < self.t0_ns:
            return []
        k_last = (int(t[-1]) - self.t0_ns) // period
        ks = np.arange(self._next_k, k_last + 1, dtype=np.int64)
        self._next_k = int(k_last) + 1
        if len(ks) == 0:
            return []
        x = self._noise(len(ks))
        grid = self.t0_ns + ks * period
        keep = grid >= t[0]
        grid, x = grid[keep], x[keep]
        if len(grid) == 0:
            return []
        j = np.searchsorted(t, grid, side='left')
        exact = t[j] == grid
        jm = np.maximum(j - 1, 0)
        s_ns, h_ns = (grid - t[jm]).astype(float), np.maximum(t[j] - t[jm], 1).astype(float)
        tau_k = tau[np.minimum(jm, len(tau) - 1)] if len(tau) else np.ones((len(grid), self.n_ports))
        lagged = self._between(s_ns, h_ns, tau_k, y[jm], u[jm], u[j], exact, y[j])
        for port in np.flatnonzero(~np.isnan(self.frozen)):
            lagged[:, port] = np.where(grid >= self.block_ns[port], self.frozen[port], lagged[:, port])
        frac = (s_ns / h_ns)[:, None]

        def at_grid(a: np.ndarray) -> np.ndarray:
            a2 = a.reshape(len(a), -1)
            return np.where(exact[:, None], a2[j], a2[jm] + frac * (a2[j] - a2[jm]))
        vb_k, wind_k, h_k = at_grid(vb), at_grid(wind), at_grid(height)[:, 0]
        truth = air_data(self.model, cfg.day, vb_k, h_k)
        ok = truth['tas'] >= cfg.min_airspeed_mps
        if not np.any(ok):
            return []
        factor = np.ones((len(grid), self.n_ports))
        for at, f in self._noise_faults:
            factor[grid >= at, f.port] = f.factor
        bias = np.tile(self.bias_pa, (len(grid), 1))
        for at, f in self._bias_steps:
            bias[grid >= at, f.port] += f.pa
        p = lagged * (1.0 + factor * cfg.scale_sigma * x[:, 1]) + factor * cfg.sigma_pa * x[:, 0] + bias
        var = cfg.sigma_pa**2 + (cfg.scale_sigma * p) ** 2
        idx = np.flatnonzero(ok)
        alt = pressure_altitude(truth['p_inf'][idx]).tolist()
        scalars = zip(*(truth[key][idx].tolist() for key in ('mach', 'alpha', 'beta', 'tas', 'p_inf', 'qc', 'temp',
                                                              'windward')))
        # rows of fresh arrays (views: nothing else holds these arrays)
        wind_k, vb_k, ports_k, p_k, var_k = (a[idx] for a in (wind_k, vb_k, truth['ports'], p, var))
        out = []
        for i, (mach, alpha, beta, tas, p_inf, qc, temp, windward) in enumerate(scalars):
            tr = AirDataTruth(mach=mach, alpha_rad=alpha, beta_rad=beta, tas_mps=tas, static_pressure_pa=p_inf,
                              impact_pressure_pa=qc, total_pressure_pa=qc + p_inf, pressure_altitude_m=alt[i],
                              temperature_k=temp, wind_enu_mps=wind_k[i], v_air_body_mps=vb_k[i],
                              port_pressures_pa=ports_k[i], windward=windward)
            out.append(FadsFrame(t_ns=int(grid[idx[i]]), pressures_pa=p_k[i], variance_pa2=var_k[i], truth=tr))
        return out


def simulate_fads(cfg: FadsConfig, seed: int, t_ns: np.ndarray, q_nb: np.ndarray, v_ground_enu: np.ndarray,
                  height_m: np.ndarray, t0_ns: int | None = None, wind: WindField | None = None) -> list[FadsFrame]:
    """Batch run for experiments: a new stage from t0_ns (default t_ns[0]) over the truth
    samples (t_ns (N,) int ns, q_nb (N, 4), v_ground_enu (N, 3), height_m (N,)); the same
    frames as stepping the stage sample by sample."""
    t_ns = np.asarray(t_ns, dtype=np.int64)
    stage = FadsStage(cfg, seed, int(t_ns[0]) if t0_ns is None else t0_ns, wind)
    return stage.step_batch(t_ns, q_nb, v_ground_enu, height_m)
