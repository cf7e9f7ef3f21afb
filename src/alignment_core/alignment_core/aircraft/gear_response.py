"""The airframe's motion on its gear at the scenario's samples, driven by the deck, the wind
over the deck and the hold-back tension (the linear model of aircraft/landing_gear.py).

Loads at sample k: the deck's motion (specific force at the CG of the rigidly mounted airframe
and the deck's angular acceleration, airframe axes, from aircraft/gear_on_deck.py), Dryden gusts
of the wind over the deck, and the hold-back pull (ramped in by a smoothstep over the catapult's
tensioning, dropped to zero at the launch sample). The state starts in the quasi-static
equilibrium of the first sample's load (no start transient) and steps exactly between samples
with the load linear in between (first-order hold); with polytropic struts their excess force
over the linear spring is a load of the state, stepped by a predictor-corrector (Heun's
method on top of the exact linear step: second order).

Gusts: MIL-F-8785C Dryden (aircraft/wind.py's forms) for a frozen field carried over the deck
at the wind-over-deck speed V: unit processes of the dimensionless time s = V t / L, exact
transitions over each sample, stationary start; stream stage_rng(seed, 'gear_gust').

Samples are simulated in index order as the ship samples are fed (`feed`, one at a time or
all at once: the same operations, so stepping and batch agree bit for bit). Between samples
the IMU point's displacement is the quintic Hermite through the samples' displacement,
velocity and acceleration (one smooth motion whose derivatives are consistent for the
increments); the rotation is given at the samples (the kinematics interpolates it as it does
the deck flexure). Only the recent samples are kept (recent_rows.py): a feed lets those more
than KEEP samples before its first go, so a node's gear holds a bounded history however long
it runs (a batch that feeds everything at once keeps everything).
"""
from __future__ import annotations

import numpy as np

from alignment_core.air_data.turbulence_spec import MIN_AIRSPEED, dryden_parameters
from alignment_core.aircraft.gear_config import GearConfig
from alignment_core.aircraft.landing_gear import N_DOF, GearModel, air_spring_excess_rows
from alignment_core.compiled import kernel
from alignment_core.recent_rows import RecentRows
from alignment_core.rng import stage_rng

_SAMPLE_TOL = 1e-9
KEEP = 256
"""Samples before a feed's first that stay readable (the increments read the previous one)."""


def _second_order_transition(ds: float) -> np.ndarray:
    """Phi (2, 2) of z'' + 2 z' + z = n (unit time) over ds."""
    return np.exp(-ds) * np.array([[1.0 + ds, ds], [-ds, 1.0 - ds]])


class DeckGust:
    """Dryden gust velocities (u, v, w) over the deck at the samples, m/s (module docstring)."""

    def __init__(self, cfg: GearConfig, seed: int, dt: float) -> None:
        self.on = cfg.gust_severity != 'none'
        if not self.on:
            return
        par = dryden_parameters(cfg.gust_height_m, cfg.gust_severity)
        self.sigma = np.array([float(par.sigma_u), float(par.sigma_v), float(par.sigma_w)])
        speed = max(cfg.wind_over_deck_mps, MIN_AIRSPEED)
        ds = speed * dt / np.array([float(par.length_u), float(par.length_v), float(par.length_w)])
        self.phi = np.zeros((5, 5))
        self.root = np.zeros((5, 5))
        self.phi[0, 0] = np.exp(-ds[0])
        self.root[0, 0] = np.sqrt(1.0 - self.phi[0, 0] ** 2)
        p2 = 0.25 * np.eye(2)
        for j, sl in ((1, slice(1, 3)), (2, slice(3, 5))):
            phi2 = _second_order_transition(ds[j])
            self.phi[sl, sl] = phi2
            self.root[sl, sl] = np.linalg.cholesky(p2 - phi2 @ p2 @ phi2.T)
        self.rng = stage_rng(seed, 'gear_gust')
        self.x: np.ndarray | None = None
        self.out = np.array([[1.0, 0, 0, 0, 0], [0, 1.0, np.sqrt(3.0), 0, 0], [0, 0, 0, 1.0, np.sqrt(3.0)]])

    def draw(self, n: int) -> np.ndarray:
        """Normal numbers (n, 5) for the next n samples."""
        return self.rng.standard_normal((n, 5))

    def series(self, noise: np.ndarray, load_matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The gusts (n, 3) at the next n samples from their noise (n, 5), and the loads (n, 9)
        they make through load_matrix (9, 3)."""
        x = np.zeros(0) if self.x is None else self.x
        gust, load, self.x = gust_series(np.ascontiguousarray(noise, dtype=float), x, self.phi, self.root,
                                         self.sigma, self.out, load_matrix)
        return gust, load

    def step(self, noise: np.ndarray) -> np.ndarray:
        """The gust (3,) at the next sample from its noise (5,)."""
        return self.series(np.asarray(noise, dtype=float).reshape(1, 5), np.zeros((N_DOF, 3)))[0][0]


@kernel
def gust_series(noise, x, phi, root, sigma, out, load_matrix):
    """(gusts (n, 3), their loads load_matrix @ gust (n, 9), the last state (5,)) of the Dryden
    state x (5,; empty before the first sample: its stationary start) driven by noise (n, 5)."""
    n = noise.shape[0]
    gust = np.empty((n, 3))
    load = np.empty((n, load_matrix.shape[0]))
    start = np.array([1.0, 0.5, 0.5, 0.5, 0.5])
    for j in range(n):
        if x.shape[0] == 0:
            x = noise[j] * start
        else:
            x = np.dot(phi, x) + np.dot(root, noise[j])
        g = sigma * np.dot(out, x)
        gust[j] = g
        load[j] = np.dot(load_matrix, g)
    return gust, load, x


class GearResponse:
    """q, q', q'' (9,) of the airframe on its gear at sample indices k = round(tau * rate_hz),
    and the IMU point's motion (airframe axes) at any time on the deck."""

    def __init__(self, cfg: GearConfig, seed: int, rate_hz: float, f0: np.ndarray,
                 holdback: tuple[float, float] | None = None) -> None:
        """f0 (3,): the static point's specific force (airframe axes); holdback: (start, launch)
        of the tensioning in scenario time (s), or None."""
        self.cfg = cfg
        self.model = GearModel(cfg)
        self.rate_hz = rate_hz
        self.dt = 1.0 / rate_hz
        self.dt_ns = int(round(1e9 / rate_hz))              # sample k is at tau = k dt_ns / 1e9, as stamps give it
        self.f0 = np.asarray(f0, dtype=float)
        self.phi, self.g0, self.g1 = (np.ascontiguousarray(a) for a in self.model.discretise(self.dt))
        self.gust = DeckGust(cfg, seed, self.dt)
        self.gust_b = self.model.gust_matrix()
        self.holdback = holdback if cfg.holdback_tension_n > 0.0 else None
        self.holdback_b = self.model.holdback_load()
        self.imu_rows = self.model.point_rows(np.asarray(cfg.imu_from_cg_m, dtype=float))
        self._mass = np.diag(self.model.M).copy()          # M's diagonal (9,), for the stepping kernel
        self._q, self._qd, self._qdd = RecentRows(N_DOF), RecentRows(N_DOF), RecentRows(N_DOF)
        self._n = 0
        self._x: np.ndarray | None = None
        self._load: np.ndarray | None = None
        self._excess: np.ndarray | None = None          # the air springs' load at the last sample

    @property
    def n(self) -> int:
        """Samples simulated so far (indices 0 .. n - 1)."""
        return self._n

    def holdback_tension(self, tau: np.ndarray) -> np.ndarray:
        """Hold-back tension (N) at scenario times tau."""
        tau = np.asarray(tau, dtype=float)
        if self.holdback is None:
            return np.zeros(tau.shape)
        start, launch = self.holdback
        x = np.clip((tau - start) / (launch - start), 0.0, 1.0)
        ramp = x**3 * (10.0 - 15.0 * x + 6.0 * x * x)
        return np.where(tau < launch, self.cfg.holdback_tension_n * ramp, 0.0)

    def feed(self, k: np.ndarray, specific_force: np.ndarray, wdot: np.ndarray) -> None:
        """Simulate the samples k (K,), increasing, with the deck's specific force and angular
        acceleration there (K, 3; airframe axes); samples already simulated are skipped, new
        ones must follow on without a gap."""
        k = np.asarray(k, dtype=np.int64)
        new = k >= self._n
        if not np.any(new):
            return
        k = k[new]
        if k[0] != self._n or np.any(np.diff(k) != 1):
            raise ValueError(f"gear samples must be fed in order without gaps: expected {self._n}, got {k[0]}")
        load = self.model.inertial_load(specific_force[new], wdot[new], self.f0)
        if self.holdback is not None:
            load = load + self.holdback_tension(k * self.dt_ns / 1e9)[:, None] * self.holdback_b
        if self.gust.on:
            load = load + self.gust.series(self.gust.draw(len(k)), self.gust_b)[1]
        for rows in (self._q, self._qd, self._qdd):
            rows.forget_before(self._n - KEEP)
        start = self._x is None            # the first sample starts in equilibrium
        x0 = np.concatenate([self.model.static(load[0]), np.zeros(N_DOF)]) if start else self._x
        m = self.model
        q, qd, qdd, self._x, self._load, self._excess = step_samples(
            np.ascontiguousarray(load), x0, np.zeros(N_DOF) if start else self._load,
            np.zeros(0) if self._excess is None else self._excess, start, m.polytropic, self.phi, self.g0,
            self.g1, m.strut_rows, m.gas, m.leg_load_n, float(m.cfg.polytropic_index), m.C, m.K, self._mass)
        if not m.polytropic:
            self._excess = None
        self._q.extend(q)
        self._qd.extend(qd)
        self._qdd.extend(qdd)
        self._n += len(k)

    def states(self, k: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """q, q', q'' (..., 9) at simulated sample indices k (...)."""
        k = self._simulated(k)
        return self._q[k], self._qd[k], self._qdd[k]

    def _simulated(self, k) -> np.ndarray:
        """Sample indices k as int64, checked to be simulated."""
        k = np.asarray(k, dtype=np.int64)
        if k.size and (k.min() < 0 or k.max() >= self._n):
            raise RuntimeError(f"gear sample {int(k.max())} not simulated yet ({self._n} so far): "
                               "the aircraft truth feeds the gear before the increments use it")
        return k

    def index(self, tau) -> np.ndarray:
        return np.rint(np.asarray(tau, dtype=float) * self.rate_hz).astype(np.int64)

    def rotation_at(self, k: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """theta, theta' (..., 3) of the airframe at sample indices k."""
        k = self._simulated(k)
        return self._q[k][..., 3:6], self._qd[k][..., 3:6]

    def imu_at(self, k: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The IMU point's displacement, velocity and acceleration (..., 3) at sample indices k."""
        q, qd, qdd = self.states(k)
        return tuple(np.einsum('ij,...j->...i', self.imu_rows, x) for x in (q, qd, qdd))

    def imu_motion(self, tau) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The IMU point's displacement, velocity, acceleration (..., 3) at scenario times tau
        (...): the samples' values at sample instants, the quintic Hermite in between. The
        samples' motion is read once per row of tau (the last axis) whose times share a sample."""
        x = np.asarray(tau, dtype=float) * self.rate_hz
        k = np.floor(x + _SAMPLE_TOL).astype(np.int64)
        u = x - k
        at_sample = np.abs(u) < _SAMPLE_TOL
        if np.all(at_sample):
            return self.imu_at(k)
        u = np.where(at_sample, 0.0, u)
        shape = u.shape
        if u.ndim and np.all(k == k[..., :1]):
            k, u, at_sample = k[..., 0].reshape(-1), u.reshape(-1, shape[-1]), at_sample.reshape(-1, shape[-1])
        else:
            k, u, at_sample = k.reshape(-1), u.reshape(-1, 1), at_sample.reshape(-1, 1)
        ends = self.imu_at(k) + self.imu_at(np.where(np.all(at_sample, axis=1), k, k + 1))
        out = quintic_hermite(u, u**3, u**4, u**5, at_sample, *ends, self.dt)
        return out[0].reshape(shape + (3,)), out[1].reshape(shape + (3,)), out[2].reshape(shape + (3,))


@kernel
def quintic_hermite(u, u3, u4, u5, at_sample, d0, v0, a0, d1, v1, a1, h):
    """Position, velocity, acceleration (3, M, J, 3) at the fractions u (M, J) of sample
    intervals h long from the quintic Hermite through the samples' (d, v, a) (M, 3) at their
    start (0) and end (1); at_sample: the start's own values. u3, u4, u5: numpy's powers of u
    (its SIMD power rounds unlike the C library's); each product and sum in numpy's order."""
    m, n = u.shape
    if not (u3.shape == u.shape and u4.shape == u.shape and u5.shape == u.shape and at_sample.shape == u.shape):
        raise ValueError('quintic_hermite: fractions, their powers and at_sample of one shape (M, J)')
    if not (d0.shape == (m, 3) and v0.shape == (m, 3) and a0.shape == (m, 3) and d1.shape == (m, 3)
            and v1.shape == (m, 3) and a1.shape == (m, 3)):
        raise ValueError('quintic_hermite: the ends (M, 3) of M intervals')
    out = np.empty((3, m, n, 3))
    hh = h * h
    for i in range(m):
        for j in range(n):
            if at_sample[i, j]:
                out[0, i, j], out[1, i, j], out[2, i, j] = d0[i], v0[i], a0[i]
                continue
            s1, s3, s4, s5 = u[i, j], u3[i, j], u4[i, j], u5[i, j]
            s2 = s1 * s1
            p0, p1 = 1 - 10*s3 + 15*s4 - 6*s5, (s1 - 6*s3 + 8*s4 - 3*s5) * h
            p2, p3 = 0.5 * (s2 - 3*s3 + 3*s4 - s5) * h * h, 10*s3 - 15*s4 + 6*s5
            p4, p5 = (-4*s3 + 7*s4 - 3*s5) * h, 0.5 * (s3 - 2*s4 + s5) * h * h
            q0, q1 = -30*s2 + 60*s3 - 30*s4, 1 - 18*s2 + 32*s3 - 15*s4
            q2, q3 = 0.5 * (2*s1 - 9*s2 + 12*s3 - 5*s4) * h, 30*s2 - 60*s3 + 30*s4
            q4, q5 = -12*s2 + 28*s3 - 15*s4, 0.5 * (3*s2 - 8*s3 + 5*s4) * h
            r0, r1 = -60*s1 + 180*s2 - 120*s3, -36*s1 + 96*s2 - 60*s3
            r2, r3 = 0.5 * (2 - 18*s1 + 36*s2 - 20*s3), 60*s1 - 180*s2 + 120*s3
            r4, r5 = -24*s1 + 84*s2 - 60*s3, 0.5 * (6*s1 - 24*s2 + 20*s3)
            for c in range(3):
                out[0, i, j, c] = (p0 * d0[i, c] + p1 * v0[i, c] + p2 * a0[i, c] + p3 * d1[i, c]
                                   + p4 * v1[i, c] + p5 * a1[i, c])
                out[1, i, j, c] = (q0 * d0[i, c] / h + q1 * v0[i, c] + q2 * a0[i, c] + q3 * d1[i, c] / h
                                   + q4 * v1[i, c] + q5 * a1[i, c])
                out[2, i, j, c] = (r0 * d0[i, c] / hh + r1 * v0[i, c] / h + r2 * a0[i, c]
                                   + r3 * d1[i, c] / hh + r4 * v1[i, c] / h + r5 * a1[i, c])
    return out


@kernel
def step_samples(load, x, prev_load, excess, start, polytropic, phi, g0, g1, strut_rows, gas, leg_load, n,
                 damping, stiffness, mass):
    """Step the gear over the samples of load (K, 9): from x = [q, q'] (18,) at the sample
    before them with its load prev_load and air-spring excess (9,; empty: none yet), or, with
    start, from x at the first of them. Returns q, q', q'' (K, 9) and the last sample's x, load
    and excess (empty if the springs are linear). Exact linear step with the load linear in
    between; the air springs' excess by Heun's predictor-corrector (module docstring)."""
    k_n = load.shape[0]
    q = np.empty((k_n, 9))
    qd = np.empty((k_n, 9))
    qdd = np.empty((k_n, 9))
    for j in range(k_n):
        f = load[j]
        if j == 0 and start:
            pass
        elif excess.shape[0] == 0:
            x = np.dot(phi, x) + np.dot(g0, prev_load) + np.dot(g1, f)
        else:                                       # air springs: their excess predicted, then corrected
            base = np.dot(phi, x) + np.dot(g0, prev_load + excess)
            pred = base + np.dot(g1, f + excess)
            x = base + np.dot(g1, f + _spring_load(pred[:9], polytropic, strut_rows, gas, leg_load, n))
        prev_load = f
        spring = _spring_load(x[:9], polytropic, strut_rows, gas, leg_load, n)
        if polytropic:
            excess = spring
        q[j] = x[:9]
        qd[j] = x[9:]
        qdd[j] = (f + spring - np.dot(x[9:], damping.T) - np.dot(x[:9], stiffness.T)) / mass
    return q, qd, qdd, x, prev_load.copy(), excess


@kernel
def _spring_load(q, polytropic, strut_rows, gas, leg_load, n):
    """GearModel.nonlinear_load of one q (9,)."""
    if not polytropic:
        return np.zeros(9)
    compression = np.dot(-q, strut_rows.T)
    return np.dot(air_spring_excess_rows(compression.reshape(1, 3), gas, leg_load, n)[0], strut_rows)
