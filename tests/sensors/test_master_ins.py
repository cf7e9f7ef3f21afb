"""Master INS error models. Expectations from closed forms: the free INS oscillates at the
Schuler period 2 pi sqrt(R/g) (84.4 min) with tilt (nabla/g)(1 - cos w_s t) and its heading
error grows as -eps_U t; the velocity-damped loop is a second-order system (damping ratio
zeta): tilt settles at nabla/g with overshoot exp(-pi zeta / sqrt(1 - zeta^2)), heading at the
gyrocompass equilibrium -eps_E / (Omega cos L); the exact discretisation composes."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.rng import stage_rng
from alignment_core.samples import ShipBatch
from alignment_core.sensors.master_ins import MasterConfig, MasterInsModel, MasterInsStage, SchulerErrorModel
from alignment_core.units import ARCMIN, ARCSEC, DEG, DPH

UG = 1e-6 * 9.80665
OMEGA = 7.292115e-5                       # WGS-84 Earth rate
A_WGS84, G_EQUATOR = 6378137.0, 9.7803253359


def run(cfg: MasterConfig, lat: float, u, dt_s: float, hours: float) -> tuple[np.ndarray, np.ndarray]:
    m = SchulerErrorModel(cfg, lat, np.asarray(u, dtype=float), stage_rng(0, 'test'))
    n = int(round(hours * 3600.0 / dt_s)) + 1
    t = np.arange(n) * dt_s
    x = np.array([m.step(int(round(tk * 1e9))) for tk in t])
    return t, x


def upward_crossings(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    i = np.flatnonzero((y[:-1] < 0.0) & (y[1:] >= 0.0))
    return t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])


def test_free_ins_oscillates_at_the_schuler_period():
    # equator: no Foucault coupling; east accelerometer bias drives the east channel alone,
    # phi_N = (nabla/g)(1 - cos w_s t) with w_s = sqrt(g/R), R the transverse radius = a
    nabla = 50 * UG
    cfg = MasterConfig(model='schuler', damping='none', initial='aligned')
    t, x = run(cfg, 0.0, [0, 0, 0, nabla, 0], 5.0, 6.0)
    ref = nabla / G_EQUATOR
    periods = np.diff(upward_crossings(t, x[:, 1] - ref))
    expected = 2 * np.pi * np.sqrt(A_WGS84 / G_EQUATOR)
    assert len(periods) >= 3
    np.testing.assert_allclose(periods, expected, rtol=1e-3)
    assert expected / 60 == pytest.approx(84.4, abs=0.3)
    assert np.max(x[:, 1]) == pytest.approx(2 * ref, rel=1e-3)


def test_free_ins_heading_error_grows_with_the_azimuth_drift():
    eps_u = 0.01 * DPH
    cfg = MasterConfig(model='schuler', damping='none', initial='aligned')
    t, x = run(cfg, 40 * DEG, [0, 0, eps_u, 0, 0], 10.0, 1.0)
    # over one hour (a twenty-fourth of the Earth-rate loop) phi_U = -eps_U t to ~1 %
    assert x[-1, 2] == pytest.approx(-eps_u * 3600.0, rel=0.02)


@pytest.mark.parametrize('zeta', [0.5, 0.707])
def test_damped_tilt_settles_at_bias_over_g_with_second_order_overshoot(zeta):
    lat = 40 * DEG
    nabla = 50 * UG
    cfg = MasterConfig(model='schuler', damping='velocity', damping_ratio=zeta, initial='aligned')
    t, x = run(cfg, lat, [0, 0, 0, nabla, 0], 10.0, 8.0)
    steady = nabla / 9.8017                      # normal gravity at 40 deg
    # (the east channel: phi_N / nabla = (1/R) / (s^2 + 2 zeta w_s s + w_s^2), a step response)
    overshoot = np.exp(-np.pi * zeta / np.sqrt(1 - zeta**2))
    assert x[-1, 1] == pytest.approx(steady, rel=0.01)
    assert np.max(x[:, 1]) == pytest.approx(steady * (1 + overshoot), rel=0.02)
    assert np.max(np.abs(x[:, 1])) <= steady * (1 + overshoot) * 1.02


def test_damped_heading_settles_at_the_gyrocompass_equilibrium():
    lat = 45 * DEG
    eps_e = 0.01 * DPH
    cfg = MasterConfig(model='schuler', damping='velocity', gyrocompass_tau_s=3600.0)
    _, x = run(cfg, lat, [eps_e, 0, 0, 0, 0], 60.0, 0.5)
    # docs/alignment.md: 0.01 deg/h at 45 deg -> 3.2' of heading (the 'settled' start is there)
    expected = -eps_e / (OMEGA * np.cos(lat))
    assert expected / ARCMIN == pytest.approx(-3.2, abs=0.05)
    np.testing.assert_allclose(x[:, 2], expected, rtol=0.02)
    # and from a fresh alignment it settles there within a few gyrocompass time constants
    cfg = MasterConfig(model='schuler', damping='velocity', gyrocompass_tau_s=3600.0, initial='aligned')
    _, x = run(cfg, lat, [eps_e, 0, 0, 0, 0], 60.0, 12.0)
    assert abs(x[0, 2]) < 1e-12
    assert x[-1, 2] == pytest.approx(expected, rel=0.03)


def test_damped_north_tilt_and_seed000_grade_stay_arcseconds():
    lat = 40 * DEG
    nabla_n = -50 * UG
    cfg = MasterConfig(model='schuler')
    _, x = run(cfg, lat, [0, 0, 0, 0, nabla_n], 60.0, 2.0)
    # phi_E = -nabla_N / g, up to the gyrocompass loop's and the Foucault couplings' share,
    # of order (Omega_N / w_s)^2 (1 + 2 zeta w_s tau) ~ 1 % at tau = 1 h
    np.testing.assert_allclose(x[:, 0], -nabla_n / 9.8017, rtol=0.025)
    # seed 000's master (0.001 deg/h, 50 ug, 1-sigma per axis), settled: tilt nabla/g = 10.5"
    # RMS per axis; heading sqrt((eps/(Omega cos L))^2 + (tan L nabla/g)^2) = 19.7" RMS
    # (gyrocompass floor and the Omega_U phi_N term); 20 seeds -> +-50 % (3 sigma)
    tilts, heads = [], []
    for seed in range(20):
        m = MasterInsModel(MasterConfig(model='schuler'), seed, lat)
        tilts.append(m.schuler.x[:2])
        heads.append(m.schuler.x[2])
    rms_tilt = np.sqrt(np.mean(np.square(tilts)))
    rms_head = np.sqrt(np.mean(np.square(heads)))
    nab_g = 50 * UG / 9.8017
    eps_w = 0.001 * DPH / (OMEGA * np.cos(lat))
    assert rms_tilt == pytest.approx(nab_g, rel=0.5)
    assert rms_head == pytest.approx(np.hypot(eps_w, np.tan(lat) * nab_g), rel=0.5)
    assert rms_tilt < 1 * ARCMIN and rms_head < 1 * ARCMIN


def test_exact_discretisation_composes():
    cfg = MasterConfig(model='schuler', initial='aligned', aligned_ago_s=600.0)
    u = np.array([0.003, -0.002, 0.004, 0, 0]) * DPH + np.array([0, 0, 0, 40, -30]) * UG
    _, fine = run(cfg, 30 * DEG, u, 0.5, 0.5)
    _, coarse = run(cfg, 30 * DEG, u, 900.0, 0.5)
    np.testing.assert_allclose(coarse[-1], fine[-1], rtol=1e-9, atol=1e-15)


def test_noisy_ins_aligned_at_the_start_starts_without_error():
    # aligned_ago_s 0: the alignment ends at the first sample, so no error has built up yet (the
    # random walks had no time to act); it then grows from zero with the noise
    cfg = MasterConfig(model='schuler', initial='aligned', aligned_ago_s=0.0, arw_dpsh=0.001, vrw_ugpshz=5.0)
    _, x = run(cfg, 30 * DEG, np.zeros(5), 1.0, 0.01)
    assert np.all(x[0] == 0.0)
    assert np.all(np.abs(x[-1]) > 0.0)


def test_published_solution_carries_the_error_state():
    sc = scenario.load('catapult_paper', {'duration_s': 2.0, 'master.model': 'schuler', 'master.arw_dpsh': 0.001,
                                    'master.vrw_ugpshz': 5.0})
    ships = ShipBatch.of(pipeline.ship_samples(sc))
    m = MasterInsModel(sc.master, sc.seed, sc.ship.lat_deg * DEG)
    out = m.measure_batch(ships)
    for k in (0, 100, 200):
        c_true = Rotation.from_quat(ships.q_nb[k])
        c_est = Rotation.from_quat(out[k].q_nb)
        # C_est = (I - [phi x]) C_true, i.e. C_est C_true^T = exp(-phi)
        np.testing.assert_allclose((c_est * c_true.inv()).as_rotvec(), -m.last_phi[k], atol=1e-14)
    # the error state moves (process noise) but stays tiny over 2 s
    assert 0 < np.max(np.abs(m.last_phi[-1] - m.last_phi[0])) < 0.1 * ARCSEC


def test_rate_and_latency_stamps_and_step_equals_batch():
    sc = scenario.load('catapult_paper', {'duration_s': 1.0, 'master.model': 'schuler', 'master.rate_hz': 50.0,
                                    'master.latency_s': 0.025})
    ships = ShipBatch.of(pipeline.ship_samples(sc))
    lat = sc.ship.lat_deg * DEG
    batch = MasterInsStage(sc.master, sc.seed, lat, sc.rate_hz, sc.t0_ns).run_batch(ships)
    stage = MasterInsStage(sc.master, sc.seed, lat, sc.rate_hz, sc.t0_ns)
    stepped = [o for k in range(len(ships)) for o in stage.step(ships.sample(k))]
    # valid at 0, 20, ..., 1000 ms, stamped 25 ms later; those stamped after the last ship
    # sample (1000 ms) never arrive: 0 ... 960 ms
    want = [sc.t0_ns + k * 20_000_000 + 25_000_000 for k in range(49)]
    assert [o.t_ns for o in batch] == want
    assert [o.t_ns for o in stepped] == want
    for a, b in zip(batch, stepped):                             # bit for bit: rows rotated alone
        for f in ('phi', 'dv'):
            assert getattr(a, f).tobytes() == getattr(b, f).tobytes(), f
        for f in ('p_w', 'q_nb', 'v_b', 'w_b'):
            assert getattr(a.sample, f).tobytes() == getattr(b.sample, f).tobytes(), f


def test_the_carriers_master_stepped_equals_batch_bit_for_bit():
    """The default carrier's master (Schuler errors, 50 Hz, latency jitter): a node stepping
    sample by sample publishes what the batch pipeline computes, bit for bit."""
    sc = scenario.load('deck', {'duration_s': 3.0})
    ships = ShipBatch.of(pipeline.ship_samples(sc))
    lat = sc.ship.lat_deg * DEG
    batch = MasterInsStage(sc.master, sc.seed, lat, sc.rate_hz, sc.t0_ns).run_batch(ships)
    stage = MasterInsStage(sc.master, sc.seed, lat, sc.rate_hz, sc.t0_ns)
    stepped = [o for k in range(len(ships)) for o in stage.step(ships.sample(k))]
    assert len(batch) == len(stepped) > 100
    for a, b in zip(batch, stepped):
        assert a.t_ns == b.t_ns
        for f in ('p_w', 'q_nb', 'v_b', 'w_b'):
            assert getattr(a.sample, f).tobytes() == getattr(b.sample, f).tobytes(), f


@pytest.mark.parametrize('arw', [0.0, 0.002], ids=['noise-free', 'noisy'])
def test_schuler_steps_in_blocks_equal_steps_one_by_one(arw):
    """step_many (one compiled loop per run of equal intervals, the noise drawn as a block) gives
    what step gives one stamp at a time, bit for bit: the states, the state after, and the noise
    stream after; over intervals that change (a jittered master), and continued across calls."""
    cfg = MasterConfig(model='schuler', damping='velocity', gyrocompass_tau_s=3600.0, arw_dpsh=arw,
                       vrw_ugpshz=5.0 if arw else 0.0)
    u = np.array([0.01 * DPH, -0.02 * DPH, 0.005 * DPH, 30.0 * UG, -20.0 * UG])
    one, many = (SchulerErrorModel(cfg, 0.6, u, stage_rng(7, 'test')) for _ in range(2))
    gaps = np.r_[np.full(40, 20_000_000), 19_000_000, 21_000_000, np.full(30, 20_000_000), 20_000_001,
                 np.full(5, 10_000_000), 40_000_000]
    t = 5_000_000_000 + np.r_[0, np.cumsum(gaps)]
    blocks = (t[:1], t[1:2], t[2:50], t[50:51], t[51:])
    got = np.concatenate([many.step_many(b) for b in blocks] + [many.step_many(t[:0])])
    want = np.array([one.step(int(k)) for k in t])
    assert got.shape == want.shape == (len(t), 5)
    assert got.tobytes() == want.tobytes()
    assert many.x.tobytes() == one.x.tobytes() and many.t_ns == one.t_ns
    assert many.rng.standard_normal(3).tobytes() == one.rng.standard_normal(3).tobytes()


def test_schuler_steps_in_blocks_stop_where_steps_one_by_one_stop():
    """An interval the discretisation cannot take (years: expm overflows) raises in both, and
    leaves the state and its time where stepping one stamp at a time left them."""
    cfg = MasterConfig(model='schuler')
    u = np.zeros(5)
    one, many = (SchulerErrorModel(cfg, 0.6, u, stage_rng(7, 'test')) for _ in range(2))
    t = np.array([0, 20_000_000, 40_000_000, 40_000_000 + 10**17])
    with np.errstate(over='ignore', invalid='ignore'):          # expm on the way to its failure
        with pytest.raises(np.linalg.LinAlgError):
            for k in t:
                one.step(int(k))
        with pytest.raises(np.linalg.LinAlgError):
            many.step_many(t)
    assert many.t_ns == one.t_ns == 40_000_000 and many.x.tobytes() == one.x.tobytes()


def test_default_master_is_todays_constant_model():
    sc = scenario.load('catapult_paper', {'duration_s': 1.0})
    assert sc.master.model == 'constant' and sc.master.rate_hz == 0.0 and sc.master.latency_s == 0.0
    ships = ShipBatch.of(pipeline.ship_samples(sc))
    outs = MasterInsStage(sc.master, sc.seed, sc.ship.lat_deg * DEG, sc.rate_hz, sc.t0_ns).run_batch(ships)
    assert [o.t_ns for o in outs] == list(ships.t_ns)
