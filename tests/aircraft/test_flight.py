"""Post-launch flight (seed 001's climb, level flight and coordinated turn) against closed forms.

- Coordinated level turn at speed V and bank phi: heading rate omega = g tan(phi) / V
  (centripetal V omega = g tan phi); the specific force lies in the aircraft's x-z plane
  (ball centred) up to the Earth-rate terms, which are f_y = y_b . ((2 w_ie + w_en) x v) here;
  |f| = sqrt(g^2 + (V omega)^2) to the same order. 30 deg at 60 m/s: 5.4 deg/s; 10 deg/s at
  60 m/s: 46.9 deg.
- Climb at rate c from level with a transition T (smoothstep, int_0^1 S = 1/2): height gain
  after duration D is c (D - T / 2); pitch = asin(c / V) + alpha.
- Straight and level at V along track chi: lat' = V sin(chi) / (R_M + h) (ENU yaw chi),
  lon' = V cos(chi) / ((R_N + h) cos lat).
- Strapdown consistency: noise-free increments integrated from the true initial state
  reproduce the truth (attitude < 1e-6 rad, velocity < 1e-3 m/s) through deck, stroke,
  climb, turns (transitions off the sample grid included) and the roll-out.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from support.ins_consistency import ATT_TOL, NOISE_OFF, VEL_TOL, integrate

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.geometry import earth
from alignment_core.samples import ShipBatch
from alignment_core.units import DEG
from alignment_core.validation import ConfigError

LAUNCH, STROKE = 2.0, 3.0
RELEASE = LAUNCH + STROKE
V = 60.0
BASE = {**NOISE_OFF, 'aircraft.catapult.launch_time_s': LAUNCH, 'aircraft.catapult.stroke_s': STROKE}


def run(segments, duration, **ov):
    sc = scenario.load('catapult_paper', {**BASE, 'duration_s': duration, 'aircraft.flight.segments': segments,
                                    **{k.replace('__', '.'): v for k, v in ov.items()}})
    ship_list = pipeline.ship_samples(sc)
    truth, imu = pipeline.SlaveImuStage(sc).run_batch(ShipBatch.of(ship_list))
    tau = (np.array([s.t_ns for s in ship_list]) - sc.t0_ns) / 1e9
    return sc, truth, imu, tau


def euler(truth):
    """(roll, pitch, yaw) in ROS convention (pitch positive nose-down, yaw from East)."""
    return Rotation.from_quat(truth['q_nb']).as_euler('ZYX')[:, ::-1]


def geodetic(sc, truth):
    return pipeline.plane_of(sc).to_geodetic(truth['p_w'])


@pytest.fixture(scope='module')
def turn30():
    """Level at 60 m/s, then a right turn at 30 deg bank (roll-in 3 s), on a calm sea."""
    return run(f'level duration_s=10 speed_mps={V}; turn bank_deg=30', 40.0, ship__sea_state=0)


def test_coordinated_turn_rate_and_bank(turn30):
    sc, truth, _, tau = turn30
    lat, _, h = geodetic(sc, truth)
    e = euler(truth)
    steady = tau > RELEASE + 10.0 + 3.0 + 0.05
    np.testing.assert_allclose(e[steady, 0], 30.0 * DEG, atol=1e-6)        # right wing down
    np.testing.assert_allclose(e[steady, 1], 0.0, atol=1e-9)
    yaw = np.unwrap(e[:, 2])
    rate = -(yaw[2:] - yaw[:-2]) / (tau[2:] - tau[:-2])                     # clockwise positive, at tau[1:-1]
    expect = earth.gravity(lat, h) * np.tan(30.0 * DEG) / V
    mid = steady[1:-1]
    np.testing.assert_allclose(rate[mid], expect[1:-1][mid], rtol=1e-5)
    assert np.degrees(expect[steady].mean()) == pytest.approx(5.41, abs=0.01)   # docs/references.md: ~5.4 deg/s
    speed = np.linalg.norm(truth['v_b'], axis=1)
    np.testing.assert_allclose(speed[tau > RELEASE + 3.0], V, atol=1e-9)
    np.testing.assert_allclose(h[steady], h[steady][0], atol=1e-6)


def test_ball_centred_in_the_steady_turn(turn30):
    sc, truth, imu, tau = turn30
    lat, _, h = geodetic(sc, truth)
    f = np.array([s.accel for s in imu])                   # mean over (tau[k], tau[k+1]]
    c = Rotation.from_quat(truth['q_nb']).as_matrix()
    v_n = np.einsum('kij,kj->ki', c, truth['v_b'])
    w = earth.omega_ie_n(lat)
    coriolis = np.cross(2.0 * w + earth.omega_en_n(lat, h, v_n), v_n)
    y_b = c[:, :, 1]
    expect_y = np.einsum('ki,ki->k', y_b, coriolis)        # Earth-rate terms only
    steady = np.flatnonzero(tau[1:] > RELEASE + 13.05)
    f_y_mid = f[steady, 1]
    e_mid = 0.5 * (expect_y[steady] + expect_y[steady + 1])
    np.testing.assert_allclose(f_y_mid, e_mid, atol=1e-4)
    assert np.abs(f_y_mid).max() < 0.01                     # ball centred to ~1 mg
    g = earth.gravity(lat[steady], h[steady])
    omega = g * np.tan(30.0 * DEG) / V
    np.testing.assert_allclose(np.linalg.norm(f[steady], axis=1), np.hypot(g, V * omega), atol=0.01)
    np.testing.assert_allclose(f[steady, 0], 0.0, atol=0.01)


def test_turn_rate_given_derives_the_bank():
    """turn_rate_dps = 10 at 60 m/s: bank atan(V omega / g) = 46.9 deg (docs/references.md)."""
    sc, truth, _, tau = run(f'turn duration_s=8 turn_rate_dps=10 speed_mps={V}; level', 20.0, ship__sea_state=0)
    lat, _, h = geodetic(sc, truth)
    steady = (tau > RELEASE + 3.05) & (tau < RELEASE + 8.0)
    bank = np.arctan(V * 10.0 * DEG / earth.gravity(lat[steady], h[steady]))
    np.testing.assert_allclose(euler(truth)[steady, 0], bank, atol=1e-5)
    assert np.degrees(bank.mean()) == pytest.approx(46.9, abs=0.05)
    yaw = np.unwrap(euler(truth)[:, 2])
    k = np.flatnonzero(steady)
    assert -(yaw[k[-1]] - yaw[k[0]]) / (tau[k[-1]] - tau[k[0]]) == pytest.approx(10.0 * DEG, rel=1e-9)


def test_climb_height_gain_and_pitch():
    c, D, Tt, alpha = 5.0, 20.0, 3.0, 4.0
    sc, truth, _, tau = run(f'level duration_s=5 speed_mps={V}; climb duration_s={D} climb_rate_mps={c}; level',
                            RELEASE + 5 + D + 5, ship__sea_state=0, aircraft__flight__alpha_deg=alpha)
    _, _, h = geodetic(sc, truth)
    k0, k1 = (int(np.argmin(abs(tau - t))) for t in (RELEASE + 5.0, RELEASE + 5.0 + D))
    assert h[k1] - h[k0] == pytest.approx(c * (D - Tt / 2), abs=1e-6)
    e = euler(truth)
    climbing = (tau > RELEASE + 5.0 + Tt) & (tau < RELEASE + 5.0 + D)
    np.testing.assert_allclose(-e[climbing, 1], np.arcsin(c / V) + alpha * DEG, atol=1e-9)
    np.testing.assert_allclose(e[climbing, 0], 0.0, atol=1e-9)
    level = tau > RELEASE + 3.0 + 0.01                     # after the settle and the first transition
    level = level & ((tau < RELEASE + 5.0) | (tau > RELEASE + 5.0 + D + Tt))
    np.testing.assert_allclose(-e[level, 1], alpha * DEG, atol=1e-9)


def test_straight_level_flight_follows_the_ellipsoid():
    sc, truth, _, tau = run(f'level speed_mps={V}', 60.0, ship__sea_state=0)
    lat, lon, h = geodetic(sc, truth)
    k = np.flatnonzero(tau > RELEASE + 3.0)
    chi = euler(truth)[k[0], 2]
    np.testing.assert_allclose(euler(truth)[k, 2], chi, atol=1e-12)       # constant track (nav frame)
    np.testing.assert_allclose(h[k], h[k[0]], atol=1e-6)                  # constant height
    r_m, r_n = earth.radii(lat[k])
    np.testing.assert_allclose(np.diff(lat[k]) / 0.01, (V * np.sin(chi) / (r_m + h[k]))[1:], rtol=1e-6)
    np.testing.assert_allclose(np.diff(lon[k]) / 0.01, (V * np.cos(chi) / ((r_n + h[k]) * np.cos(lat[k])))[1:],
                               rtol=1e-6)


def test_release_is_continuous_in_attitude_velocity_and_rate():
    sc, truth, _, tau = run(f'climb duration_s=10 climb_rate_mps=5 speed_mps={V}', 10.0, ship__sea_state=5)
    k = int(np.argmin(abs(tau - RELEASE)))
    assert truth['on_deck'][k] and not truth['on_deck'][k + 1]
    q = Rotation.from_quat(truth['q_nb'])
    step = [np.linalg.norm((q[j].inv() * q[j + 1]).as_rotvec()) for j in (k - 1, k)]
    assert step[1] == pytest.approx(step[0], abs=2e-5)     # ~ rate x 10 ms on both sides
    c = q.as_matrix()
    v_n = np.einsum('kij,kj->ki', c, truth['v_b'])
    assert np.linalg.norm(v_n[k + 1] - v_n[k]) < 0.25      # the 2 g stroke ends at the release
    assert np.linalg.norm(truth['w_b'][k + 1] - truth['w_b'][k]) < 1e-3


@pytest.mark.parametrize('segments,sea,alpha', [
    (f'climb duration_s=20 climb_rate_mps=5 speed_mps={V}; level duration_s=5; turn duration_s=20 bank_deg=30; '
     'turn duration_s=10 bank_deg=-45 transition_s=2.345 climb_rate_mps=-3; level transition_s=1.111', 4, 3.0),
    (f'climb duration_s=20 climb_rate_mps=5 speed_mps={V} alpha_deg=12 beta_deg=4; '
     'turn duration_s=20 bank_deg=30 alpha_deg=-6 beta_deg=-8 transition_s=2.345; '
     'level transition_s=1.111 alpha_deg=2 beta_deg=0', 4, 3.0),
], ids=['climb-turns-rollout', 'air-angle-sweeps'])
def test_ins_consistency_through_the_flight(segments, sea, alpha):
    sc, truth, imu, tau = run(segments, RELEASE + 70.0, ship__sea_state=sea, aircraft__flight__alpha_deg=alpha)
    att, vel = integrate(sc, truth, imu)
    assert att.max() < ATT_TOL, f'attitude error {att.max():.3g} rad'
    assert vel.max() < VEL_TOL, f'velocity error {vel.max():.3g} m/s'


def test_batch_equals_step_in_flight():
    """The node steps the stage sample by sample: the same numbers as the batch (the position
    grid is extended in fixed chunks, so the call pattern does not matter)."""
    sc = scenario.load('catapult_paper', {**BASE, 'duration_s': 9.0, 'aircraft.flight.segments':
                                    'turn duration_s=2 turn_rate_dps=8 transition_s=1.23; level transition_s=0.7'})
    ship_list = pipeline.ship_samples(sc)
    truth_b, imu_b = pipeline.SlaveImuStage(sc).run_batch(ShipBatch.of(ship_list))
    stage = pipeline.SlaveImuStage(sc)
    for k, s in enumerate(ship_list):
        tr, imu = stage.step(s)
        np.testing.assert_allclose(tr.p_w, truth_b['p_w'][k], rtol=0, atol=1e-9)
        np.testing.assert_array_equal(tr.q_nb, truth_b['q_nb'][k])
        np.testing.assert_array_equal(tr.v_b, truth_b['v_b'][k])
        if k > 0:
            np.testing.assert_array_equal(imu.gyro, imu_b[k - 1].gyro)
            np.testing.assert_array_equal(imu.accel, imu_b[k - 1].accel)


@pytest.mark.parametrize('segments,msg', [
    ('level duration_s=-5', 'duration_s must be >= 0'),
    ('turn duration_s=10 bank_deg=90', r'bank_deg must be within \(-90, 90\)'),
    ('turn duration_s=10 bank_deg=-95', r'bank_deg must be within'),
    ('loop duration_s=10', "unknown segment type 'loop'"),
    ('climb duration_s=10', 'a climb needs exactly one of'),
    ('turn duration_s=10 bank_deg=30 turn_rate_dps=5', 'exactly one of bank_deg, turn_rate_dps'),
    ('level duration_s=10 bank_deg=30', "unknown key 'bank_deg' for level"),
    ('level duration_s=ten', 'must be a number'),
    ('level; level duration_s=10', 'only the last segment may be open-ended'),
    ('level duration_s=2; level', r'transition \(3.0 s\) must fit'),
    ('climb duration_s=10 climb_rate_mps=80 speed_mps=60', 'must be below'),
    ('climb duration_s=10 climb_rate_mps=80', 'must be below the speed'),     # at the release (64 m/s)
    ('level duration_s=10 speed_mps=2501', r'speed_mps must be in \[1, 2500\]'),
    ('level duration_s=10 alpha_deg=-61', r'alpha_deg must be within \[-60, 60\]'),
    ('climb duration_s=10 pitch_deg=5 beta_deg=30.5', r'beta_deg must be within \[-30, 30\]'),
    ('level duration_s=10 alpha_deg=big', 'alpha_deg must be a number'),
])
def test_invalid_segments_fail_clearly(segments, msg):
    with pytest.raises(ConfigError, match=msg) as e:
        run(segments, 8.0)
    assert 'aircraft.flight' in str(e.value)


def test_inflight_scenario_flies_seed_001():
    """config/scenarios/inflight.yaml through pipeline.simulate: release at 13 s, then climb
    50 s at 5 m/s (from the release's vertical speed w0 over the 3 s transition: gain
    50 w0 + (5 - w0)(50 - 1.5)), level 50 s (5 m/s x 1.5 s more in the level-off), 300 s
    right turn at 30 deg bank, level; 60 m/s. Noise-free, the increments integrate back to the
    truth over the whole 420 s."""
    sc = scenario.load('inflight', {**NOISE_OFF, 'imu.gyro_bias_instability_dph': 0.0,
                                    'imu.accel_bias_instability_ug': 0.0})
    assert sc.duration_s == 420.0 and sc.aircraft.catapult.profile == 'shape'
    inp = pipeline.simulate(sc)
    truth = inp.truth
    tau = (inp.ships.t_ns - sc.t0_ns) / 1e9
    rel = 13.0
    k = {t: int(np.argmin(abs(tau - t))) for t in (rel, rel + 50, rel + 100, rel + 120, rel + 400, 420.0)}
    assert truth['on_deck'][k[rel]] and not truth['on_deck'][k[rel] + 1]
    lat, _, h = geodetic(sc, truth)
    c = Rotation.from_quat(truth['q_nb']).as_matrix()
    v_n = np.einsum('kij,kj->ki', c, truth['v_b'])
    w0 = v_n[k[rel], 2]
    assert h[k[rel + 50]] - h[k[rel]] == pytest.approx(50 * w0 + (5.0 - w0) * (50 - 1.5), abs=1e-6)
    assert h[k[rel + 100]] - h[k[rel + 50]] == pytest.approx(5.0 * 1.5, abs=1e-6)    # the level-off
    speed = np.linalg.norm(v_n, axis=1)
    steady = (tau > rel + 3.0) & ((tau <= rel + 50) | (tau >= rel + 53))
    np.testing.assert_allclose(speed[steady], 60.0, atol=1e-9)
    # V_h and v_U blend separately in the level-off: speed >= V_h >= 60 cos(gamma), gamma = asin(5 / 60)
    assert np.abs(speed[tau > rel + 3.0] - 60.0).max() < 60.0 * (1.0 - np.cos(np.arcsin(5.0 / 60.0)))
    e = euler(truth)
    turning = (tau > rel + 100 + 3.0) & (tau <= rel + 400)
    np.testing.assert_allclose(e[turning, 0], 30.0 * DEG, atol=1e-6)
    np.testing.assert_allclose(e[k[420.0], 0], 0.0, atol=1e-9)
    att, vel = integrate(sc, truth, inp.imu)
    assert att.max() < ATT_TOL, f'attitude error {att.max():.3g} rad'
    assert vel.max() < VEL_TOL, f'velocity error {vel.max():.3g} m/s'
