"""FADS sensor stage. Expected values come from outside the stage:
- the atmosphere in closed form (hydrostatic equation with the standard's lapse rate
  L = 6.5 K/km to 11 km, isothermal above, geopotential height H = r0 h / (r0 + h)), flow
  angles alpha = atan2(-v_z, v_x), beta = asin(-v_y / V) of the body air velocity (scipy's
  rotation), Mach V / sqrt(gamma R T), and the port model `PortModel.pressures`;
- the first-order lag's closed-form response to a ramp-then-hold input;
- the Gauss-Markov process's stationary variance sigma^2 and lag-1 correlation rho, tested
  within 4 standard deviations of their estimators over N samples of an AR(1) process:
  sd(s^2) = sigma^2 sqrt(2 (1 + rho^2) / (N (1 - rho^2))), sd(r_1) = sqrt((1 - rho^2) / N)
  (Bartlett), divided by sqrt(5) when the 5 independent ports are pooled;
- faults by their definitions against the fault-free run of the same seed (the noise stream
  is the same, so a bias step is an exact offset and a noise factor an exact scaling)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from alignment_core.air_data.day_offsets import DayOffsets
from alignment_core.air_data.ports import PortModel
from alignment_core.aircraft.wind import WindConfig
from alignment_core.sensors.fads import AirDataTruth, FadsStage, simulate_fads
from alignment_core.sensors.fads_config import FadsConfig

R, G0, T0, P0, R0, LAPSE, GAMMA = 287.05287, 9.80665, 288.15, 101325.0, 6356766.0, 0.0065, 1.4
T_NS = 1_000_000_000                 # the stage's t0 (a scenario's start time)
QUIET = dict(sigma_pa=0.0, lag_s_sea_level=0.0)


def atmosphere_by_hand(h: np.ndarray, dt: float = 0.0, dp0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(T, p) at geometric heights h below 20 km geopotential: T = T0 + dT - L H and
    p = (P0 + dp0) (T / (T0 + dT))^(g0 / (R L)) in the troposphere, isothermal above 11 km."""
    H = R0 * np.asarray(h, dtype=float) / (R0 + np.asarray(h, dtype=float))
    t11 = T0 + dt - LAPSE * 11000.0
    p11 = (P0 + dp0) * (t11 / (T0 + dt)) ** (G0 / (R * LAPSE))
    t_trop = T0 + dt - LAPSE * H
    p_trop = (P0 + dp0) * (t_trop / (T0 + dt)) ** (G0 / (R * LAPSE))
    p_strat = p11 * np.exp(-G0 * (H - 11000.0) / (R * t11))
    return np.where(H < 11000.0, t_trop, t11), np.where(H < 11000.0, p_trop, p_strat)


def expected(q: np.ndarray, v_air_enu: np.ndarray, h: np.ndarray, day: tuple[float, float] = (0.0, 0.0)) -> dict:
    """Air data and port pressures by hand (see the module docstring)."""
    vb = Rotation.from_quat(q).inv().apply(v_air_enu)
    speed = np.linalg.norm(vb, axis=-1)
    alpha, beta = np.arctan2(-vb[:, 2], vb[:, 0]), np.arcsin(-vb[:, 1] / speed)
    temp, p = atmosphere_by_hand(h, *day)
    mach = speed / np.sqrt(GAMMA * R * temp)
    qc = p * ((1.0 + 0.2 * mach**2) ** 3.5 - 1.0)            # subsonic isentropic
    alt = T0 / LAPSE * (1.0 - (p / P0) ** (R * LAPSE / G0))   # standard-day inverse, troposphere
    return dict(tas=speed, alpha=alpha, beta=beta, temp=temp, p=p, mach=mach, qc=qc, alt=alt,
                ports=PortModel().pressures(alpha, beta, mach, p))


def flight(n: int, dt_s: float = 0.02, speed=150.0, height=3000.0, yaw_deg=30.0) -> tuple:
    """n truth samples from T_NS: (t_ns, q_nb, v_enu, h); speed and height may be callables of t."""
    t = np.arange(n) * dt_s
    t_ns = T_NS + np.arange(n, dtype=np.int64) * int(round(dt_s * 1e9))
    sp = speed(t) if callable(speed) else np.full(n, speed)
    hh = height(t) if callable(height) else np.full(n, height)
    yaw = np.deg2rad(yaw_deg)
    v = np.c_[sp * np.cos(yaw), sp * np.sin(yaw), np.zeros(n)]
    q = Rotation.from_euler('z', np.full((n, 1), yaw)).as_quat()
    return t_ns, q, v, hh


def pressures(frames) -> np.ndarray:
    return np.array([f.pressures_pa for f in frames])


def times(frames) -> np.ndarray:
    return np.array([f.t_ns for f in frames])


@pytest.mark.parametrize('day', [(0.0, 0.0), (15.0, 1000.0), (-20.0, -1500.0)])
def test_noise_free_lag_free_frames_are_the_port_model_at_the_truth(day):
    n = 501
    t = np.arange(n) * 0.02
    t_ns = T_NS + np.arange(n, dtype=np.int64) * 20_000_000
    euler = np.c_[np.deg2rad(30.0 + 3.0 * t), np.deg2rad(-5.0 - 2.0 * np.sin(0.5 * t)), np.deg2rad(10.0 * np.cos(t))]
    q = Rotation.from_euler('ZYX', euler).as_quat()
    track = np.deg2rad(30.0 + 3.0 * t + 4.0 * np.sin(0.3 * t))
    v = np.c_[150.0 * np.cos(track), 150.0 * np.sin(track), 5.0 + 3.0 * np.sin(0.7 * t)]
    h = 3000.0 + 5.0 * t
    cfg = FadsConfig(rate_hz=10.0, day=DayOffsets(*day), **QUIET)
    frames = simulate_fads(cfg, 1, t_ns, q, v, h)
    k = np.arange(0, n, 5)                                          # frames on every 5th truth sample
    assert np.array_equal(times(frames), t_ns[k])
    e = expected(q[k], v[k], h[k], day)
    np.testing.assert_allclose(pressures(frames), e['ports'], rtol=1e-11)
    tr = [f.truth for f in frames]
    assert all(x.windward for x in tr)
    for name, key in (('mach', 'mach'), ('alpha_rad', 'alpha'), ('beta_rad', 'beta'), ('tas_mps', 'tas'),
                      ('static_pressure_pa', 'p'), ('impact_pressure_pa', 'qc'), ('pressure_altitude_m', 'alt'),
                      ('temperature_k', 'temp')):
        np.testing.assert_allclose([getattr(x, name) for x in tr], e[key], rtol=1e-10, atol=1e-9, err_msg=name)
    np.testing.assert_allclose([x.total_pressure_pa for x in tr], e['p'] + e['qc'], rtol=1e-11)
    np.testing.assert_array_equal([x.wind_enu_mps for x in tr], np.zeros((len(k), 3)))
    assert np.max(np.abs(e['alpha'])) > np.deg2rad(3.0) and np.max(np.abs(e['beta'])) > np.deg2rad(2.0)
    assert AirDataTruth.labels()[:10] == ('mach', 'alpha_rad', 'beta_rad', 'tas_mps', 'static_pressure_pa',
                                          'impact_pressure_pa', 'pressure_altitude_m', 'wind_east_mps',
                                          'wind_north_mps', 'wind_up_mps')
    x = tr[3]
    named = {name: getattr(x, name, None) for name in AirDataTruth.labels()}
    named.update(wind_east_mps=x.wind_enu_mps[0], wind_north_mps=x.wind_enu_mps[1], wind_up_mps=x.wind_enu_mps[2])
    assert list(x.vector()) == [named[name] for name in AirDataTruth.labels()]


def test_frames_between_truth_samples_take_the_interpolated_truth():
    """Frames at 7 Hz between 50 Hz truth samples: the truth of the linearly interpolated air
    velocity (a linear speed ramp stays exact), the port pressures linear between samples."""
    t_ns, q, v, h = flight(501, speed=lambda t: 100.0 + 3.0 * t)
    frames = simulate_fads(FadsConfig(rate_hz=7.0, **QUIET), 1, t_ns, q, v, h)
    tk = times(frames)
    assert np.array_equal(tk, T_NS + np.arange(70) * 142_857_143)       # period rounded up: 70 frames in 10 s
    np.testing.assert_allclose([f.truth.tas_mps for f in frames], 100.0 + 3.0 * (tk - T_NS) * 1e-9, rtol=1e-12)
    ports = expected(q, v, h)['ports']
    j = np.searchsorted(t_ns, tk)
    frac = ((tk - t_ns[j - 1]) / 20e6)[:, None]
    np.testing.assert_allclose(pressures(frames)[1:], (ports[j - 1] + frac * (ports[j] - ports[j - 1]))[1:], rtol=1e-12)


def test_gauss_markov_noise_variance_and_lag1_correlation():
    n = 20000
    t_ns, q, v, h = flight(n, speed=150.0, height=1000.0)
    clean = expected(q[:1], v[:1], h[:1])['ports'][0]
    rho = 0.5
    for kind, cfg in (('additive', FadsConfig(rate_hz=50.0, sigma_pa=20.0, lag_s_sea_level=0.0)),
                      ('multiplicative', FadsConfig(rate_hz=50.0, sigma_pa=0.0, scale_sigma=1e-3,
                                                    lag_s_sea_level=0.0))):
        frames = simulate_fads(cfg, 11, t_ns, q, v, h)
        p = pressures(frames)
        assert p.shape == (n, 5)
        if kind == 'additive':
            r, sigma = p - clean, 20.0
            np.testing.assert_allclose([f.variance_pa2 for f in frames], np.full((n, 5), 400.0))
        else:
            r, sigma = p / clean - 1.0, 1e-3
            np.testing.assert_allclose([f.variance_pa2 for f in frames], (1e-3 * p) ** 2, rtol=1e-12)
        var = np.mean(r**2, axis=0)
        r1 = np.sum(r[1:] * r[:-1], axis=0) / np.sum(r**2, axis=0)
        sd_var = np.sqrt(2.0 * (1 + rho**2) / (n * (1 - rho**2))) / np.sqrt(5.0)
        sd_r1 = np.sqrt((1.0 - rho**2) / n) / np.sqrt(5.0)
        assert abs(var.mean() / sigma**2 - 1.0) < 4.0 * sd_var, (kind, var.mean() / sigma**2)
        assert abs(r1.mean() - rho) < 4.0 * sd_r1, (kind, r1.mean())
        assert np.all(np.abs(r.mean(axis=0)) < 4.0 * sigma * np.sqrt((1 + rho) / ((1 - rho) * n)))
        # independent ports: cross-correlation of two ports within 4 sd of 0
        c = np.corrcoef(r[:, 1], r[:, 2])[0, 1]
        assert abs(c) < 4.0 * np.sqrt((1 + rho**2) / ((1 - rho**2) * n))


@pytest.mark.parametrize('height, dt_s, span_s', [(0.0, 1e-3, 0.1), (20000.0, 1e-2, 2.0)])
def test_lag_step_response_with_the_altitude_time_constant(height, dt_s, span_s):
    """Speed 100 -> 150 m/s over a ramp of T_r = 1 us, then held: tau y' = u - y gives, for
    t >= T_r, y = u1 - (u1 - u0) (tau_r / T_r)(1 - exp(-T_r / tau_r)) exp(-(t - T_r) / tau)
    (-> 1 - exp(-t / tau) of the step), per port tau = tau0 P0 / u1 (the tube holds the port's
    pressure) and tau_r = tau0 P0 / ((u0 + u1) / 2) over the ramp."""
    ramp_ns = 1000
    k = np.arange(int(round(span_s / dt_s)) + 1)
    t_rel = np.concatenate([[0], [ramp_ns], k[1:] * int(round(dt_s * 1e9))]).astype(np.int64)
    t_ns = T_NS + t_rel
    n = len(t_ns)
    speed = np.where(t_rel == 0, 100.0, 150.0)
    v = np.c_[speed, np.zeros(n), np.zeros(n)]
    q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    hh = np.full(n, height)
    frames = simulate_fads(FadsConfig(rate_hz=1.0 / dt_s, sigma_pa=0.0), 1, t_ns, q, v, hh)
    _, p = atmosphere_by_hand(np.array([height]))
    # at rest the tube holds p_inf: 20 ms at sea level, 0.37 s at 20 km
    assert 0.02 * P0 / p[0] == pytest.approx(0.02 if height == 0.0 else 0.3665, rel=1e-3)
    e = expected(q[:2], v[:2], hh[:2])['ports']
    u0, u1 = e[0], e[1]
    tau, tau_r = 0.02 * P0 / u1, 0.02 * P0 / (0.5 * (u0 + u1))
    t = (times(frames) - T_NS) * 1e-9
    assert np.array_equal(times(frames), T_NS + k * int(round(dt_s * 1e9)))
    tr = ramp_ns * 1e-9
    want = u1 - (u1 - u0) * (tau_r / tr) * (1.0 - np.exp(-tr / tau_r)) * np.exp(-(t[:, None] - tr) / tau)
    want[0] = u0
    np.testing.assert_allclose(pressures(frames), want, rtol=0, atol=1e-9 * np.max(u1 - u0))
    # about 63 % of the step after one tau
    i = int(round(tau[0] / dt_s))
    share = (pressures(frames)[i, 0] - u0[0]) / (u1[0] - u0[0])
    assert share == pytest.approx(1 - np.exp(-i * dt_s / tau[0]), abs=1e-4)


def accelerating(n: int = 501):
    return flight(n, speed=lambda t: 100.0 + 5.0 * t)


def test_blocked_port_freezes_at_its_value_at_the_fault_time():
    t_ns, q, v, h = accelerating()
    frames = simulate_fads(FadsConfig(rate_hz=10.0, faults='blocked port=2 at_s=5', **QUIET), 1, t_ns, q, v, h)
    k = np.arange(0, 501, 5)
    want = expected(q[k], v[k], h[k])['ports']
    after = (t_ns[k] - T_NS) >= 5_000_000_000
    want[after, 2] = want[np.flatnonzero(after)[0], 2]
    np.testing.assert_allclose(pressures(frames), want, rtol=1e-12)
    # with the lag: the frozen value is the lagged pressure at the fault time
    lagged = dict(rate_hz=50.0, sigma_pa=0.0)
    free = pressures(simulate_fads(FadsConfig(**lagged), 1, t_ns, q, v, h))
    blocked = pressures(simulate_fads(FadsConfig(faults='blocked port=2 at_s=5', **lagged), 1, t_ns, q, v, h))
    np.testing.assert_array_equal(blocked[:, [0, 1, 3, 4]], free[:, [0, 1, 3, 4]])
    np.testing.assert_array_equal(blocked[:251, 2], free[:251, 2])
    np.testing.assert_array_equal(blocked[250:, 2], free[250, 2])
    between = pressures(simulate_fads(FadsConfig(faults='blocked port=2 at_s=5.013', **lagged), 1, t_ns, q, v, h))
    assert free[250, 2] < between[-1, 2] < free[251, 2] and np.all(between[251:, 2] == between[-1, 2])
    # frames at 100 Hz, between the 50 Hz truth samples: the frame at 5.01 s is already frozen
    fast = dict(rate_hz=100.0, sigma_pa=0.0)
    free = pressures(simulate_fads(FadsConfig(**fast), 1, t_ns, q, v, h))
    mid = pressures(simulate_fads(FadsConfig(faults='blocked port=2 at_s=5.005', **fast), 1, t_ns, q, v, h))
    assert free[500, 2] < mid[-1, 2] < free[501, 2] and np.all(mid[501:, 2] == mid[-1, 2])
    np.testing.assert_array_equal(mid[:501], free[:501])
    # noise and bias still add to a blocked port: the same noise and bias as the unblocked run
    noisy, clean = dict(rate_hz=10.0, sigma_pa=20.0, bias_sigma_pa=50.0), dict(rate_hz=10.0, sigma_pa=0.0)
    added = [pressures(simulate_fads(FadsConfig(faults=f, **noisy), 4, t_ns, q, v, h))
             - pressures(simulate_fads(FadsConfig(faults=f, **clean), 4, t_ns, q, v, h))
             for f in ('', 'blocked port=2 at_s=5')]
    np.testing.assert_allclose(added[1], added[0], rtol=0, atol=1e-9)
    assert np.std(added[1][50:, 2]) > 10.0


def test_bias_constant_random_and_step():
    t_ns, q, v, h = accelerating()
    base = dict(rate_hz=10.0, sigma_pa=20.0)
    ref_frames = simulate_fads(FadsConfig(**base), 2, t_ns, q, v, h)
    ref, t = pressures(ref_frames), (times(ref_frames) - T_NS) * 1e-9
    step = pressures(simulate_fads(FadsConfig(faults='bias_step port=1 at_s=3 pa=200; bias_step port=1 at_s=7 pa=-50',
                                              **base), 2, t_ns, q, v, h))
    want = np.zeros_like(ref)
    want[:, 1] = np.where(t >= 7.0, 150.0, np.where(t >= 3.0, 200.0, 0.0))
    np.testing.assert_allclose(step - ref, want, atol=1e-9)
    const = (1.0, -2.0, 3.0, -4.0, 5.0)
    stage = FadsStage(FadsConfig(bias_pa=const, bias_sigma_pa=30.0, **base), 2, T_NS)
    got = pressures(stage.step_batch(t_ns, q, v, h))
    np.testing.assert_allclose(got - ref, np.tile(stage.bias_pa, (len(ref), 1)), atol=1e-9)
    assert not np.allclose(stage.bias_pa, const)
    draws = np.array([FadsStage(FadsConfig(bias_sigma_pa=30.0), s, 0).bias_pa for s in range(400)]).ravel()
    assert abs(draws.mean()) < 4.0 * 30.0 / np.sqrt(draws.size)
    assert abs(draws.std() - 30.0) < 4.0 * 30.0 / np.sqrt(2.0 * draws.size)


def test_noise_fault_scales_the_ports_noise():
    t_ns, q, v, h = accelerating()
    base = dict(rate_hz=10.0, sigma_pa=20.0, scale_sigma=1e-3)
    clean = pressures(simulate_fads(FadsConfig(rate_hz=10.0, sigma_pa=0.0), 3, t_ns, q, v, h))
    ref = pressures(simulate_fads(FadsConfig(**base), 3, t_ns, q, v, h)) - clean
    got = pressures(simulate_fads(FadsConfig(faults='noise port=3 at_s=2 factor=5', **base), 3, t_ns, q, v, h)) - clean
    want = ref.copy()
    want[20:, 3] *= 5.0                                  # frames from t = 2 s on (10 Hz)
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)
    silent = pressures(simulate_fads(FadsConfig(faults='noise port=0 at_s=0 factor=0', **base), 3, t_ns, q, v, h))
    np.testing.assert_allclose(silent[:, 0], clean[:, 0], rtol=1e-14)


def test_no_frames_below_the_minimum_airspeed_and_the_wind_sign():
    t_ns, q, v, h = flight(1001, speed=lambda t: 24.95 - t, height=100.0)
    frames = simulate_fads(FadsConfig(rate_hz=10.0), 1, t_ns, q, v, h)
    assert np.array_equal(times(frames), T_NS + np.arange(150) * 100_000_000)   # 24.95 - t >= 10 up to 14.9 s
    assert min(f.truth.tas_mps for f in frames) >= 10.0
    # standing still, nose West, in a wind blowing to the East: a 20 m/s airflow from ahead
    n = 101
    t_ns = T_NS + np.arange(n, dtype=np.int64) * 20_000_000
    west = np.tile([0.0, 0.0, 1.0, 0.0], (n, 1))
    cfg = FadsConfig(rate_hz=10.0, wind=WindConfig(mean_enu_mps=(20.0, 0.0, 0.0)), **QUIET)
    frames = simulate_fads(cfg, 1, t_ns, west, np.zeros((n, 3)), np.full(n, 100.0))
    assert len(frames) == 21
    tr = frames[-1].truth
    assert (tr.tas_mps, tr.alpha_rad, tr.beta_rad) == pytest.approx((20.0, 0.0, 0.0), abs=1e-12)
    np.testing.assert_allclose(tr.wind_enu_mps, [20.0, 0.0, 0.0])
    np.testing.assert_allclose(tr.v_air_body_mps, [20.0, 0.0, 0.0], atol=1e-12)
    still = simulate_fads(FadsConfig(rate_hz=10.0, **QUIET), 1, t_ns, west, np.zeros((n, 3)), np.full(n, 100.0))
    assert still == []


def wild(seed_cfg: dict | None = None) -> tuple[FadsConfig, tuple]:
    """Everything on: lag, both noises, random bias, turbulence, faults, a rate off the truth grid."""
    cfg = FadsConfig(rate_hz=7.0, scale_sigma=1e-3, bias_sigma_pa=30.0,
                     wind=WindConfig(mean_enu_mps=(5.0, -3.0, 0.0), severity='moderate'),
                     faults='blocked port=2 at_s=3.013; bias_step port=1 at_s=2 pa=200; noise port=3 at_s=1 factor=5',
                     **(seed_cfg or {}))
    return cfg, accelerating(301)


def test_stepping_equals_batch_and_chunks():
    cfg, (t_ns, q, v, h) = wild()
    t0 = T_NS - 30_000_000                                 # the first grid time precedes the first truth sample
    batch = simulate_fads(cfg, 9, t_ns, q, v, h, t0_ns=t0)
    stage = FadsStage(cfg, 9, t0)
    stepped = [f for k in range(len(t_ns)) for f in stage.step(int(t_ns[k]), q[k], v[k], float(h[k]))]
    chunks = FadsStage(cfg, 9, t0)
    cuts = [0, 1, 2, 40, 41, 160, 301]
    chunked = [f for a, b in zip(cuts, cuts[1:]) for f in chunks.step_batch(t_ns[a:b], q[a:b], v[a:b], h[a:b])]
    assert len(batch) == 42 and times(batch)[0] == t0 + 142_857_143
    for other in (stepped, chunked):
        assert np.array_equal(times(other), times(batch))
        np.testing.assert_allclose(pressures(other), pressures(batch), rtol=1e-13)
        np.testing.assert_allclose([f.truth.vector() for f in other], [f.truth.vector() for f in batch],
                                   rtol=1e-12, atol=1e-10)
        np.testing.assert_allclose([f.variance_pa2 for f in other], [f.variance_pa2 for f in batch], rtol=1e-12)
    with pytest.raises(ValueError, match='increasing'):
        stage.step(int(t_ns[-1]), q[-1], v[-1], float(h[-1]))


def test_deterministic_from_the_seed():
    cfg, (t_ns, q, v, h) = wild()
    a, b, c = (simulate_fads(cfg, s, t_ns, q, v, h) for s in (5, 5, 6))
    np.testing.assert_array_equal(pressures(a), pressures(b))
    np.testing.assert_array_equal([f.truth.wind_enu_mps for f in a], [f.truth.wind_enu_mps for f in b])
    assert not np.allclose(pressures(a), pressures(c))
    assert not np.allclose([f.truth.wind_enu_mps for f in a], [f.truth.wind_enu_mps for f in c])


def test_the_noise_starts_stationary():
    """Over 400 seeds x 5 ports, the first two frames' noise has variance sigma^2 each (a
    zero start would give 0 and (1 - rho^2) sigma^2), within 4 sd = 4 sigma^2 sqrt(2 / 2000)."""
    t_ns, q, v, h = flight(51, speed=150.0, height=1000.0)
    clean = expected(q[:1], v[:1], h[:1])['ports'][0]
    cfg = FadsConfig(rate_hz=1.0, lag_s_sea_level=0.0)
    r = np.array([pressures(simulate_fads(cfg, s, t_ns, q, v, h)) - clean for s in range(400)])   # (400, 2, 5)
    assert r.shape == (400, 2, 5)
    np.testing.assert_allclose(np.mean(r**2, axis=(0, 2)) / 400.0, [1.0, 1.0], atol=4.0 * np.sqrt(2.0 / 2000))
