"""Master (ship) INS: its solution = ship truth + a navigation error model.

Attitude convention: C_est = (I - [phi x]) C_true (phi in the local-level ENU frame);
velocity error dv = v_est - v_true (ENU). Position is GNSS-aided and not corrupted (its
error does not enter transfer alignment). Two models (`master.model`):

- 'constant' (default, today's numbers): the steady state of a ship INS damped for hours:
  tilt balancing the accelerometer bias and heading at the gyrocompass equilibrium,
  phi_E = -nabla_N/g, phi_N = nabla_E/g, phi_U = (Omega_U phi_N - eps_E)/Omega_N,
  no velocity error (biases resolved in the nav frame).
- 'schuler': the linear error-state system of a stationary-base INS (transport rate and the
  ship's wave accelerations neglected: at 10 kn the transport rate is 1 % of Earth rate),
  x = [phi_E, phi_N, phi_U, dv_E, dv_N] (vertical channel damped by GNSS/baro, not modelled):
      phi' = -Omega x phi + d(omega_en) - eps,     dv' = f x phi + nabla - 2 Omega x dv,
  f = (0, 0, g). Free (`damping: none`): Schuler oscillation at 2 pi sqrt(R/g) = 84.4 min
  (Foucault-modulated), heading error growing as -eps_U t. Damped (`damping: velocity`,
  default): the ship's log / GNSS velocity reference (error neglected) is fed back:
      east channel:  dv_E' -= K1e dv_E                    (Schuler loop, zeta, omega_s)
      north channel: dv_N' -= K1n dv_N, phi_E' -= K2n dv_N / R_M, phi_U' += K3 dv_N
  a third-order gyrocompass loop whose poles are -1/tau and the Schuler pair with damping
  ratio zeta (`damping_ratio`, default 0.5; `gyrocompass_tau_s`, default 3600 s):
      K1e = 2 zeta w_s, K1n = s + 2 zeta w_s, K2n = (2 zeta w_s s - W_N^2)/w_s^2,
      K3 = (s w_s^2 - K1n W_N^2)/(g W_N)   (s = 1/tau, w_s^2 = g/R, W_N = Omega cos L).
  Its steady state is the 'constant' model's (tilt nabla/g, heading -eps_E/(Omega cos L))
  plus small velocity-feedback terms; `initial: settled` starts there (plus the stationary
  noise), `initial: aligned` starts from zero error `aligned_ago_s` before the run and
  settles with the loop's time constants. Gyro drift and accelerometer bias are random
  constants in the nav frame (straight course); optional white noise (arw_dpsh, vrw_ugpshz)
  drives the loop. Propagated exactly between master samples: Phi = expm(F dt), bias input
  by the augmented expm, process noise by Van Loan (stream stage_rng(seed, 'master_ins_process')).

Both models add white velocity noise and the gyro bias on the body rate (stream 'master_ins').
Output rate and latency: sensors/timing.py (`rate_hz`, 0 = scenario rate; `latency_s`; a
transport jitter `latency_jitter_s`, uniform per sample, stream 'master_ins_jitter').
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.linalg import expm, solve_continuous_lyapunov
from scipy.spatial.transform import Rotation

from alignment_core.compiled import kernel
from alignment_core.geometry import earth
from alignment_core.geometry.rotations import rotate_rows
from alignment_core.rng import stage_rng
from alignment_core.samples import MasterSample, ShipBatch, ShipSample
from alignment_core.sensors.timing import SensorTiming
from alignment_core.units import DEG, DPH, UG
from alignment_core.validation import ConfigError, require

STATE_LABELS = ('phi_E', 'phi_N', 'phi_U', 'dv_E', 'dv_N')
VAN_LOAN_MAX_EXPONENT = 18.0
"""The largest a t the Van Loan form serves an `initial: aligned` covariance (a: the damped loop's
fastest decay rate): its block holds expm(-F t), which grows as exp(a t), and Qd = Phi times it
cancels that growth, losing about a t / ln 10 of float64's 16 digits. Measured (lat 0-70 deg,
damping_ratio 0.1-2, tau 60 s - 1e6 s) against P_inf - Phi P_inf Phi^T: within 1e-4 at a t = 18,
every digit lost by a t ~ 35, overflow (LinAlgError) at ~ 710. Older ages take the stable form
(`aligned_since`)."""


@dataclass(frozen=True)
class MasterConfig:
    """Master ship INS grade (defaults: seed 000, 0.001 deg/h and 50 ug, 1-sigma per axis)
    and error model ('constant': today's steady state; 'schuler': damped error dynamics)."""
    preset: str = ''
    gyro_bias_dph: float = 0.001
    accel_bias_ug: float = 50.0
    velocity_noise_mps: float = 0.001
    model: Literal['constant', 'schuler'] = 'constant'
    damping: Literal['velocity', 'none'] = 'velocity'
    damping_ratio: float = 0.5
    gyrocompass_tau_s: float = 3600.0
    initial: Literal['settled', 'aligned'] = 'settled'
    aligned_ago_s: float = 0.0
    arw_dpsh: float = 0.0
    vrw_ugpshz: float = 0.0
    rate_hz: float = 0.0               # 0 = the scenario rate; else a divisor of it
    latency_s: float = 0.0             # data valid at t are stamped (and arrive at) t + latency
    latency_jitter_s: float = 0.0      # + a uniform random delay in [0, jitter) per sample (timing.py)
    noise_change_at_s: float = 0.0     # 0 = never; from then on velocity noise x noise_change_factor
    noise_change_factor: float = 1.0   # (seed 003's model-error case: variance x 50 after 100 s)

    def validate(self) -> None:
        from alignment_core.sensors.presets import MASTER_PRESETS, check_preset
        check_preset('master', self.preset, MASTER_PRESETS)
        for k in ('gyro_bias_dph', 'accel_bias_ug', 'velocity_noise_mps', 'arw_dpsh', 'vrw_ugpshz'):
            require(getattr(self, k) >= 0.0, f"{k} must be >= 0, got {getattr(self, k)}")
        require(0.0 < self.damping_ratio <= 2.0,
                f"damping_ratio must be in (0, 2], got {self.damping_ratio}")
        require(60.0 <= self.gyrocompass_tau_s <= 1e6,
                f"gyrocompass_tau_s must be in [60, 1e6] s, got {self.gyrocompass_tau_s}")
        require(0.0 <= self.aligned_ago_s <= 30 * 86400.0,
                f"aligned_ago_s must be in [0, 30 days], got {self.aligned_ago_s}")
        require(not (self.model == 'schuler' and self.damping == 'none' and self.initial == 'settled'),
                "initial: 'settled' needs damping 'velocity' (a free INS has no steady "
                "state); use initial: aligned")
        require(0.0 <= self.rate_hz <= 2000.0, f"rate_hz must be in [0, 2000], got {self.rate_hz}")
        require(0.0 <= self.latency_s <= 1.0, f"latency_s must be in [0, 1] s, got {self.latency_s}")
        require(0.0 <= self.latency_jitter_s <= 1.0,
                f"latency_jitter_s must be in [0, 1] s, got {self.latency_jitter_s}")
        require(self.noise_change_at_s >= 0.0,
                f"noise_change_at_s must be >= 0 (0 = never), got {self.noise_change_at_s}")
        require(0.0 <= self.noise_change_factor <= 1000.0,
                f"noise_change_factor must be in [0, 1000], got {self.noise_change_factor}")

    def validate_at(self, lat_deg: float) -> None:
        """The 'schuler' model at the ship's latitude (the scenario's check, which knows it): the
        error dynamics exist there (error_dynamics' own test)."""
        if self.model != 'schuler':
            return
        try:
            error_dynamics(lat_deg * DEG, self.damping, self.damping_ratio, self.gyrocompass_tau_s)
        except ValueError as e:
            raise ConfigError(f"ship.lat_deg = {lat_deg} is out of range for master.model schuler with damping "
                              f"{self.damping}: {e}") from None


def error_dynamics(lat: float, damping: str = 'velocity', zeta: float = 0.5,
                   tau_s: float = 3600.0) -> tuple[np.ndarray, np.ndarray]:
    """(F, B) of the 5-state master INS error model at latitude `lat` (rad); inputs
    u = [eps_E, eps_N, eps_U, nabla_E, nabla_N] (nav-frame gyro drift, accelerometer bias)."""
    r_m, r_n = (float(x) for x in earth.radii(lat))
    g = float(earth.gravity(lat, 0.0))
    w_n, w_u = earth.OMEGA_IE * np.cos(lat), earth.OMEGA_IE * np.sin(lat)
    f = np.array([
        [0.0, w_u, -w_n, 0.0, -1.0 / r_m],
        [-w_u, 0.0, 0.0, 1.0 / r_n, 0.0],
        [w_n, 0.0, 0.0, np.tan(lat) / r_n, 0.0],
        [0.0, -g, 0.0, 0.0, 2.0 * w_u],
        [g, 0.0, 0.0, -2.0 * w_u, 0.0]])
    b = np.zeros((5, 5))
    b[:3, :3] = -np.eye(3)
    b[3, 3] = b[4, 4] = 1.0
    if damping == 'velocity':
        if abs(np.cos(lat)) < 0.2:
            raise ValueError(f'a gyrocompassing master INS needs |latitude| < 78 deg, got {lat / DEG:.1f}')
        ws_e2, ws_n2 = g / r_n, g / r_m
        s = 1.0 / tau_s
        k1e = 2.0 * zeta * np.sqrt(ws_e2)
        k1n = s + 2.0 * zeta * np.sqrt(ws_n2)
        k2n = (2.0 * zeta * np.sqrt(ws_n2) * s - w_n**2) / ws_n2
        k3 = (s * ws_n2 - k1n * w_n**2) / (g * w_n)
        f[3, 3] -= k1e
        f[4, 4] -= k1n
        f[0, 4] -= k2n / r_m
        f[2, 4] += k3
    return f, b


def transition(f: np.ndarray, b: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact (Phi, Gamma) over dt: x+ = Phi x + Gamma u."""
    n, m = f.shape[0], b.shape[1]
    a = np.zeros((n + m, n + m))
    a[:n, :n] = f
    a[:n, n:] = b
    e = expm(a * dt)
    return e[:n, :n], e[:n, n:]


def discretise(f: np.ndarray, b: np.ndarray, qc: np.ndarray, dt: float
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact (Phi, Gamma, Qd) over dt: x+ = Phi x + Gamma u + w, w ~ N(0, Qd) (Van Loan)."""
    n = f.shape[0]
    phi, gam = transition(f, b, dt)
    vl = np.zeros((2 * n, 2 * n))
    vl[:n, :n] = -f
    vl[:n, n:] = qc
    vl[n:, n:] = f.T
    ev = expm(vl * dt)
    qd = phi @ ev[:n, n:]
    return phi, gam, 0.5 * (qd + qd.T)


def aligned_since(f: np.ndarray, b: np.ndarray, qc: np.ndarray, t: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Phi, Gamma, P) t after a perfect alignment: discretise's, or for a damped loop past
    VAN_LOAN_MAX_EXPONENT the same covariance as P_inf - Phi P_inf Phi^T (P_inf the settled one,
    from the Lyapunov equation), where Phi has decayed and nothing cancels."""
    rates = -np.linalg.eigvals(f).real
    if not (rates.min() > 0.0 and rates.max() * t > VAN_LOAN_MAX_EXPONENT):
        return discretise(f, b, qc, t)
    phi, gam = transition(f, b, t)
    p_inf = solve_continuous_lyapunov(f, -qc)
    p = p_inf - phi @ p_inf @ phi.T
    return phi, gam, 0.5 * (p + p.T)


def _sqrt_psd(q: np.ndarray) -> np.ndarray:
    w, v = np.linalg.eigh(q)
    return v * np.sqrt(np.clip(w, 0.0, None))


class SchulerErrorModel:
    """The 'schuler' master INS error state, propagated exactly from sample to sample."""

    def __init__(self, cfg: MasterConfig, lat: float, u: np.ndarray, rng: np.random.Generator) -> None:
        self.f, self.b = error_dynamics(lat, cfg.damping, cfg.damping_ratio, cfg.gyrocompass_tau_s)
        self.u = np.asarray(u, dtype=float)
        arw = cfg.arw_dpsh * DEG / 60.0
        vrw = cfg.vrw_ugpshz * UG
        self.qc = np.diag([arw**2] * 3 + [vrw**2] * 2)
        self.noisy = bool(np.any(self.qc > 0.0))
        self.rng = rng
        self._cache: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        if cfg.initial == 'settled':
            x = -np.linalg.solve(self.f, self.b @ self.u)
            p = solve_continuous_lyapunov(self.f, -self.qc) if self.noisy else None
        else:
            x = np.zeros(5)
            p = None
            if cfg.aligned_ago_s > 0.0:
                phi, gam, p = aligned_since(self.f, self.b, self.qc, cfg.aligned_ago_s)
                x = gam @ self.u
        if self.noisy and p is not None:     # aligned at the run's start (aligned_ago_s 0): no error yet
            x = x + _sqrt_psd(0.5 * (p + p.T)) @ self.rng.standard_normal(5)
        self.x = x
        self.t_ns: int | None = None

    def step(self, t_ns: int) -> np.ndarray:
        """Error state at t_ns (the first call returns the initial state)."""
        if self.t_ns is not None:
            d = self._over(t_ns - self.t_ns)
            self.x = d[0] @ self.x + d[1]
            if self.noisy:
                self.x = self.x + d[2] @ self.rng.standard_normal(5)
        self.t_ns = t_ns
        return self.x.copy()

    def step_many(self, t_ns: np.ndarray) -> np.ndarray:
        """(K, 5) `step` at each of the stamps t_ns (K,) in turn: the same states bit for bit and
        the same state and noise stream afterwards, each run of equal intervals in one compiled
        loop (the same BLAS products; the noise drawn as one block, the same stream)."""
        t = np.asarray(t_ns, dtype=np.int64)
        out = np.empty((len(t), 5))
        i = 0
        if self.t_ns is None and len(t):
            out[0] = self.x
            self.t_ns, i = int(t[0]), 1
        if i == len(t):
            return out
        dt = np.diff(t[i - 1:] if i else np.r_[self.t_ns, t])
        ends = np.r_[np.flatnonzero(np.diff(dt)) + 1, len(dt)]
        for a, b in zip(np.r_[0, ends[:-1]].tolist(), ends.tolist()):
            d = self._over(int(dt[a]))
            noise = self.rng.standard_normal((b - a, 5)) if self.noisy else _NO_NOISE
            self.x = schuler_steps(d[0], d[1], d[2], self.x, noise, out[i + a:i + b])
            self.t_ns = int(t[i + b - 1])          # where step would be if the next run's interval fails
        return out

    def _over(self, dt_ns: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(Phi, Gamma u, Qd's square root) over dt_ns, made once per interval; Phi C-ordered (the
        same BLAS product whether numpy or a kernel takes it)."""
        d = self._cache.get(dt_ns)
        if d is None:
            phi, gam, qd = discretise(self.f, self.b, self.qc, dt_ns * 1e-9)
            d = self._cache[dt_ns] = (np.ascontiguousarray(phi), gam @ self.u, np.ascontiguousarray(_sqrt_psd(qd)))
        return d


_NO_NOISE = np.zeros((0, 5))


@kernel
def schuler_steps(phi, gu, sq, x, noise, out):
    """x <- Phi x + Gamma u (+ sq noise[k] when noise is given) for each row k of out (K, 5),
    which takes the states; returns the last. numpy's products: the same BLAS calls."""
    for k in range(out.shape[0]):
        x = np.dot(phi, x) + gu
        if noise.shape[0]:
            x = x + np.dot(sq, noise[k])
        for j in range(5):
            out[k, j] = x[j]
    return x


class MasterInsModel:
    """Master INS solution = ship truth + INS errors ('constant' or 'schuler'). After each
    call, `last_phi` (K, 3) and `last_dv` (K, 3) hold the attitude and velocity errors (nav
    frame) of the samples returned: the truth for scoring the filter's master states."""

    def __init__(self, cfg: MasterConfig, seed: int, lat: float, t0_ns: int = 0) -> None:
        self.cfg = cfg
        self.t_change_ns = (t0_ns + int(round(cfg.noise_change_at_s * 1e9))
                            if cfg.noise_change_at_s > 0.0 and cfg.noise_change_factor != 1.0 else None)
        self.rng = stage_rng(seed, 'master_ins')
        eps = self.rng.standard_normal(3) * cfg.gyro_bias_dph * DPH        # nav axes
        nab = self.rng.standard_normal(3) * cfg.accel_bias_ug * UG
        self.eps_n, self.nabla_n = eps, nab
        g = float(earth.gravity(lat, 0.0))
        w_ie = earth.omega_ie_n(lat)
        phi_e = -nab[1] / g
        phi_n = nab[0] / g
        phi_u = (w_ie[2] * phi_n - eps[0]) / w_ie[1]
        self.phi = np.array([phi_e, phi_n, phi_u])
        self.err_rot = Rotation.from_rotvec(-self.phi)                    # C_est = exp(-phi) C
        self.gyro_bias_b = self.rng.standard_normal(3) * cfg.gyro_bias_dph * DPH
        self.schuler = None
        if cfg.model == 'schuler':
            self.schuler = SchulerErrorModel(cfg, lat, np.r_[eps, nab[:2]],
                                             stage_rng(seed, 'master_ins_process'))
        self.last_phi = np.zeros((0, 3))
        self.last_dv = np.zeros((0, 3))

    def measure(self, s: ShipSample) -> MasterSample:
        return self.measure_batch(ShipBatch.of([s]))[0]

    def measure_batch(self, sb: ShipBatch, delay_ns: np.ndarray | int = 0) -> list[MasterSample]:
        """The solutions at the ship samples, stamped t + delay_ns (each sample's transport delay,
        sensors/timing.py; 0: the data's validity time)."""
        c_true = Rotation.from_quat(sb.q_nb)
        noise = self.rng.standard_normal((len(sb), 3)) * self.cfg.velocity_noise_mps
        if self.t_change_ns is not None:
            noise[sb.t_ns >= self.t_change_ns] *= self.cfg.noise_change_factor
        v_n = rotate_rows(c_true.as_matrix(), sb.v_b) + noise
        if self.schuler is None:
            c_est = self.err_rot * c_true
            self.last_phi = np.broadcast_to(self.phi, (len(sb), 3)).copy()
            self.last_dv = np.zeros((len(sb), 3))
        else:
            x = self.schuler.step_many(sb.t_ns)
            self.last_phi = x[:, :3]
            self.last_dv = np.c_[x[:, 3:], np.zeros(len(sb))]
            v_n = v_n + self.last_dv
            c_est = Rotation.from_rotvec(-self.last_phi) * c_true
        q = c_est.as_quat()
        v_b = rotate_rows(c_est.as_matrix(), v_n, inverse=True)
        w_b = sb.w_b + self.gyro_bias_b
        stamps = (sb.t_ns + delay_ns).tolist()
        return [MasterSample(*rows) for rows in zip(stamps, sb.p_w.copy(), q, v_b, w_b)]


@dataclass(frozen=True)
class MasterOutput:
    """A released master sample and its truth errors (nav frame phi, dv) for /truth."""
    sample: MasterSample
    phi: np.ndarray
    dv: np.ndarray

    @property
    def t_ns(self) -> int:
        return self.sample.t_ns


class MasterInsStage:
    """Ship samples in -> master samples at the master's rate, stamped t + latency and
    released when simulation time reaches the stamp (node: `step`; batch: `run_batch`)."""

    def __init__(self, cfg: MasterConfig, seed: int, lat: float, base_rate_hz: float, t0_ns: int) -> None:
        self.model = MasterInsModel(cfg, seed, lat, t0_ns)
        jitter = stage_rng(seed, 'master_ins_jitter') if cfg.latency_jitter_s > 0.0 else None
        self.timing = SensorTiming(cfg.rate_hz, cfg.latency_s, base_rate_hz, t0_ns, cfg.latency_jitter_s, jitter)

    def _outputs(self, sb: ShipBatch) -> list[MasterOutput]:
        ms = self.model.measure_batch(sb, self.timing.delays_ns(len(sb)))
        return [MasterOutput(*rows) for rows in zip(ms, self.model.last_phi, self.model.last_dv)]

    def step(self, s: ShipSample) -> list[MasterOutput]:
        new = self._outputs(ShipBatch.of([s])) if self.timing.due(s.t_ns) else []
        return self.timing.release(s.t_ns, new)

    def step_many(self, ships: Sequence[ShipSample]) -> list[MasterOutput]:
        """`step` on each of K ship samples in turn, as one batched call: the same outputs, bit for
        bit, and the same state afterwards (noise and jitter streams, the Schuler error state,
        pending releases); what `step` releases on the way comes out at the last sample's time."""
        if not ships:
            return []
        due = [s for s in ships if self.timing.due(s.t_ns)]
        new = self._outputs(ShipBatch.of(due)) if due else []
        return self.timing.release(ships[-1].t_ns, new)

    def run_batch(self, sb: ShipBatch) -> list[MasterOutput]:
        idx = np.flatnonzero(self.timing.due_mask(sb.t_ns))
        outs = self._outputs(sb.slice(idx)) if len(idx) else []
        return self.timing.release_batch(outs, int(sb.t_ns[-1]))
