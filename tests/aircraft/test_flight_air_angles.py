"""Commanded angle of attack and sideslip, hypersonic speeds and the airborne start (aircraft/flight.py).

- Air angles: with no wind the air-relative velocity is the ground velocity, so the angles of
  v_b (air_data.flow_angles.air_angles: alpha = atan2(-v_z, v_x), beta = asin(-v_y / V)) are
  the commanded ones, which blend from the previous value to each segment's target as
  a0 + (a1 - a0) S(x), S(x) = 10x^3 - 15x^4 + 6x^5 (written out here on its own).
- Body rate: dC_a^n/dt = C_a^n [w_na x], so w_na is the central difference
  log(C(t - h)^T C(t + h)) / (2 h) + O(h^2).
- Hypersonic climb (seed 004: Mach 7 at 20 km = 2066 m/s), airborne from 1 km at 33.6 m/s:
  height gain of a climb-rate blend c0 -> c1 over T in a segment of duration D is
  c0 D + (c1 - c0)(D - T / 2) (int_0^1 S = 1/2), so 1000 + 20 (60 - 15) + 20 * 140
  + 160 (140 - 60) + 180 * 30 / 2 = 20200 m. Position: lat' = v_N / (R_M + h),
  lon' = v_E / ((R_N + h) cos lat), integrated here by scipy's DOP853.
- Strapdown consistency as in test_flight.py (attitude < 1e-6 rad, velocity < 1e-3 m/s).
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation
from support.ins_consistency import ATT_TOL, NOISE_OFF, VEL_TOL, integrate

from alignment_core import pipeline
from alignment_core.air_data.flow_angles import air_angles
from alignment_core.config import scenario
from alignment_core.geometry import earth
from alignment_core.samples import ShipBatch
from alignment_core.units import DEG
from alignment_core.validation import ConfigError

AIRBORNE = {**NOISE_OFF, 'aircraft.catapult.enabled': False, 'aircraft.flight.start': 'airborne'}


def run(segments, duration, **ov):
    sc = scenario.load('catapult_paper', {**AIRBORNE, 'duration_s': duration, 'aircraft.flight.segments': segments,
                                    **{k.replace('__', '.'): v for k, v in ov.items()}})
    ship_list = pipeline.ship_samples(sc)
    stage = pipeline.SlaveImuStage(sc)
    truth, imu = stage.run_batch(ShipBatch.of(ship_list))
    tau = (np.array([s.t_ns for s in ship_list]) - sc.t0_ns) / 1e9
    return sc, stage.kin.path, truth, imu, tau


def commanded(tau, start, schedule):
    """Smoothstep blends of one angle: schedule = [(t_start, T, target or None)], from `start`."""
    out = np.full_like(tau, start)
    prev = start
    for t0, T, target in schedule:
        target = prev if target is None else target
        x = np.clip((tau - t0) / T, 0.0, 1.0)
        S = x**3 * (10.0 - 15.0 * x + 6.0 * x * x)
        out = np.where(tau >= t0, prev + (target - prev) * S, out)
        prev = target
    return out


SWEEP = ('level duration_s=10 speed_mps=80; '
         'climb duration_s=20 transition_s=6 climb_rate_mps=10 alpha_deg=12 beta_deg=-5; '
         'turn duration_s=20 transition_s=4.321 bank_deg=40 alpha_deg=-8 beta_deg=15; '
         'level transition_s=3 beta_deg=0')
ALPHA_SCHEDULE = [(0.0, 3.0, None), (10.0, 6.0, 12.0), (30.0, 4.321, -8.0), (50.0, 3.0, None)]
BETA_SCHEDULE = [(0.0, 3.0, None), (10.0, 6.0, -5.0), (30.0, 4.321, 15.0), (50.0, 3.0, 0.0)]


@pytest.fixture(scope='module')
def sweep():
    return run(SWEEP, 60.0, aircraft__flight__alpha_deg=3.0, ship__sea_state=0)


def test_air_angles_of_the_truth_are_the_commanded_ones(sweep):
    _, _, truth, _, tau = sweep
    speed, alpha, beta = air_angles(truth['v_b'])
    np.testing.assert_allclose(alpha, commanded(tau, 3.0 * DEG, [(t, T, a and a * DEG) for t, T, a in ALPHA_SCHEDULE]),
                               rtol=0, atol=1e-9)
    np.testing.assert_allclose(beta, commanded(tau, 0.0, [(t, T, b and b * DEG) for t, T, b in BETA_SCHEDULE]),
                               rtol=0, atol=1e-9)
    assert np.degrees(alpha).max() == pytest.approx(12.0, abs=1e-7)
    assert np.degrees(beta).max() == pytest.approx(15.0, abs=1e-7)


def test_body_rate_is_the_derivative_of_the_attitude(sweep):
    _, path, _, _, _ = sweep
    t = np.linspace(0.05, 59.95, 1201) + 0.0037         # through every transition, off the breakpoints
    h = 1e-4
    c0, c1 = path.state(t - h).c_na, path.state(t + h).c_na
    fd = Rotation.from_matrix(np.einsum('kji,kjl->kil', c0, c1)).as_rotvec() / (2.0 * h)
    w = path.state(t).w_na
    assert np.abs(w).max() > 0.1                         # rad/s: the sweeps really rotate
    np.testing.assert_allclose(w, fd, rtol=0, atol=1e-7)


def test_commanded_angles_after_a_catapult_release():
    """Deck start: once the 2 s settle is over the air angles are the commanded ones."""
    sc = scenario.load('catapult_paper', {**NOISE_OFF, 'duration_s': 14.0, 'aircraft.catapult.launch_time_s': 2.0,
                                    'aircraft.flight.segments': 'level duration_s=4 alpha_deg=6 beta_deg=-4; level'})
    truth, _ = pipeline.SlaveImuStage(sc).run_batch(ShipBatch.of(pipeline.ship_samples(sc)))
    tau = np.arange(len(truth['v_b'])) / sc.rate_hz
    _, alpha, beta = air_angles(truth['v_b'])
    after = tau > 5.0 + 3.0                              # release at 5 s, 3 s transition (> settle)
    np.testing.assert_allclose(alpha[after], 6.0 * DEG, atol=1e-9)
    np.testing.assert_allclose(beta[after], -4.0 * DEG, atol=1e-9)


def test_airborne_start_state():
    """Seed 004's start: 1 km, Mach 0.1 = 33.6 m/s, heading north (ROS yaw 90 deg), at the
    scenario origin; alpha 2 deg: level flight pitches the nose up by alpha."""
    sc, path, truth, imu, tau = run('level', 5.0, aircraft__flight__start_height_m=1000.0,
                                    aircraft__flight__start_speed_mps=33.6, aircraft__flight__start_track_deg=90.0,
                                    aircraft__flight__alpha_deg=2.0)
    deck = scenario.load('catapult_paper', {**NOISE_OFF, 'duration_s': 1.0})
    truth_deck, _ = pipeline.SlaveImuStage(deck).run_batch(ShipBatch.of(pipeline.ship_samples(deck)))
    assert set(truth) == set(truth_deck)
    assert not truth['on_deck'].any() and len(imu) == len(tau) - 1
    lat, lon, h = pipeline.plane_of(sc).to_geodetic(truth['p_w'][0])
    assert (float(lat), float(lon), float(h)) == pytest.approx((sc.ship.lat_deg * DEG, sc.ship.lon_deg * DEG, 1000.0),
                                                             abs=1e-9)
    c = Rotation.from_quat(truth['q_nb']).as_matrix()
    v_n = np.einsum('kij,kj->ki', c, truth['v_b'])
    np.testing.assert_allclose(np.linalg.norm(v_n, axis=1), 33.6, atol=1e-9)
    np.testing.assert_allclose(v_n[:, 2], 0.0, atol=1e-12)
    np.testing.assert_allclose(np.arctan2(v_n[:, 1], v_n[:, 0]), 90.0 * DEG, atol=1e-12)
    roll, pitch, yaw = Rotation.from_quat(truth['q_nb'][0]).as_euler('ZYX')[::-1]
    assert (roll, -pitch, yaw) == pytest.approx((0.0, 2.0 * DEG, 90.0 * DEG), abs=1e-12)
    att, vel = integrate(sc, truth, imu)
    assert att.max() < ATT_TOL and vel.max() < VEL_TOL


HYPER = ('climb duration_s=60 transition_s=30 climb_rate_mps=20 speed_mps=200; '
         'climb duration_s=140 transition_s=120 climb_rate_mps=180 speed_mps=2066; '
         'level duration_s=40 transition_s=30; '
         'level duration_s=20 transition_s=8 alpha_deg=50; '
         'level duration_s=20 transition_s=10 alpha_deg=-50 beta_deg=20; '
         'turn duration_s=20 transition_s=10 bank_deg=45 alpha_deg=10 beta_deg=-20; '
         'level transition_s=5 alpha_deg=2 beta_deg=0')


@pytest.fixture(scope='module')
def hyper():
    return run(HYPER, 330.0, aircraft__flight__start_height_m=1000.0, aircraft__flight__start_speed_mps=33.6,
               aircraft__flight__start_track_deg=90.0, ship__sea_state=0)


def test_hypersonic_climb_reaches_mach_7_at_20_km(hyper):
    sc, _, truth, _, tau = hyper
    _, _, h = pipeline.plane_of(sc).to_geodetic(truth['p_w'])
    k = int(np.argmin(abs(tau - 230.0)))                 # level-off done
    assert h[k] == pytest.approx(20200.0, abs=1e-6)
    np.testing.assert_allclose(h[tau >= 230.0], 20200.0, atol=1e-6)
    steady = ((tau >= 180.0) & (tau <= 200.0)) | (tau >= 230.0)     # V_h and v_U blend apart in the level-off
    np.testing.assert_allclose(np.linalg.norm(truth['v_b'][steady], axis=1), 2066.0, atol=1e-9)
    _, alpha, beta = air_angles(truth['v_b'])
    assert np.degrees(alpha).max() == pytest.approx(50.0, abs=1e-7)
    assert np.degrees(alpha).min() == pytest.approx(-50.0, abs=1e-7)
    assert np.degrees(beta).max() == pytest.approx(20.0, abs=1e-7)
    assert np.degrees(beta).min() == pytest.approx(-20.0, abs=1e-7)


def test_hypersonic_strapdown_round_trip(hyper):
    sc, _, truth, imu, _ = hyper
    att, vel = integrate(sc, truth, imu)
    assert att.max() < ATT_TOL, f'attitude error {att.max():.3g} rad'
    assert vel.max() < VEL_TOL, f'velocity error {vel.max():.3g} m/s'


def test_hypersonic_position_follows_the_ellipsoid(hyper):
    """The 0.05 s RK4 grid with Hermite interpolation against DOP853 on the same velocity:
    ~450 km flown, within 1 mm (1.6e-10 rad)."""
    sc, path, truth, _, tau = hyper
    lat, lon, _ = pipeline.plane_of(sc).to_geodetic(truth['p_w'])

    def rate(t, y):
        st = path.state(np.array([t]))
        r_m, r_n = earth.radii(y[0])
        hh = st.h[0]
        return [st.v_n[0, 1] / (r_m + hh), st.v_n[0, 0] / ((r_n + hh) * np.cos(y[0]))]
    sol = solve_ivp(rate, (0.0, 330.0), [lat[0], lon[0]], method='DOP853', rtol=1e-13, atol=1e-15,
                    t_eval=tau[::500], max_step=1.0)
    assert (lat[-1] - lat[0]) * earth.A > 4e5                # mostly north: ~450 km
    np.testing.assert_allclose(lat[::500], sol.y[0], rtol=0, atol=1.6e-10)
    np.testing.assert_allclose(lon[::500], sol.y[1], rtol=0, atol=1.6e-10)


def test_batch_equals_step_airborne():
    sc = scenario.load('catapult_paper', {**AIRBORNE, 'duration_s': 4.0, 'aircraft.flight.segments':
                                    'level duration_s=2 transition_s=1.23 alpha_deg=20 beta_deg=5; level beta_deg=-5'})
    ship_list = pipeline.ship_samples(sc)
    truth_b, imu_b = pipeline.SlaveImuStage(sc).run_batch(ShipBatch.of(ship_list))
    stage = pipeline.SlaveImuStage(sc)
    for k, s in enumerate(ship_list):
        tr, imu = stage.step(s)
        np.testing.assert_allclose(tr.p_w, truth_b['p_w'][k], rtol=0, atol=1e-9)
        np.testing.assert_array_equal(tr.q_nb, truth_b['q_nb'][k])
        assert not tr.on_deck
        if k > 0:
            np.testing.assert_array_equal(imu.gyro, imu_b[k - 1].gyro)
            np.testing.assert_array_equal(imu.accel, imu_b[k - 1].accel)


def test_airborne_keys_reach_the_flight_config():
    sc = scenario.load('catapult_paper', {'aircraft.flight.start': 'airborne', 'aircraft.catapult.enabled': False,
                                    'aircraft.flight.start_height_m': 1000, 'aircraft.flight.start_speed_mps': 33.6,
                                    'aircraft.flight.start_track_deg': 90})
    f = sc.aircraft.flight
    assert (f.start, f.start_height_m, f.start_speed_mps, f.start_track_deg) == ('airborne', 1000.0, 33.6, 90.0)


@pytest.mark.parametrize('overrides,msg', [
    ({'aircraft.flight.start': 'airborne'}, 'set catapult.enabled false'),
    ({**AIRBORNE, 'aircraft.flight.start': 'air'}, 'must be one of'),
    ({**AIRBORNE, 'aircraft.flight.start_speed_mps': 2600.0}, r'start_speed_mps must be in \[1, 2500\]'),
    ({**AIRBORNE, 'aircraft.flight.start_height_m': 2e5}, 'start_height_m must be in'),
    ({'aircraft.flight.alpha_deg': 61.0}, r'alpha_deg must be within \[-60, 60\]'),
    ({'aircraft.flight.segments': 'level alpha_deg=60.5'}, r'alpha_deg must be within \[-60, 60\]'),
    ({'aircraft.flight.segments': 'turn bank_deg=10 beta_deg=-31'}, r'beta_deg must be within \[-30, 30\]'),
    ({'aircraft.flight.segments': 'level speed_mps=2600'}, r'speed_mps must be in \[1, 2500\]'),
    ({'aircraft.flight.segments': 'level duration_s=9 alpha_deg=50; climb pitch_deg=-45'},
     r'pitch_deg - alpha_deg must be within \(-90, 90\)'),
])
def test_invalid_flight_keys_fail_clearly(overrides, msg):
    with pytest.raises(ConfigError, match=msg) as e:
        scenario.load('catapult_paper', overrides)
    assert 'aircraft' in str(e.value)
