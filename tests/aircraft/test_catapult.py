"""Catapult stroke profiles, hold-back tensioning and heading on deck, against closed forms.

The aircraft moves along the track u (the aircraft x axis in ship axes) by s(t) from the deck
spot r0; from the truth, its position relative to the master INS in ship axes is r0 + s u and
its velocity relative to the deck is s' u. End speed = int a dt, stroke length = int int a dt
= int_0^T (T - t) a(t) dt:
- constant a = A: v = A T, s = A T^2 / 2.
- linear (knots (0, a0), (T, a1); PCHIP reproduces a straight line): a = a0 + k t,
  v = a0 T + k T^2 / 2, s = a0 T^2 / 2 + k T^3 / 6.
- shape (ramp r, tail tau, tail fraction e, S(x) = 10x^3 - 15x^4 + 6x^5 with int_0^1 S = 1/2,
  int_0^1 x S = 5/14, int_0^1 (1 - x) S = 1/7):
  v = A (T - r/2 - (1 - e) tau / 2),
  s = A (r T / 2 - 5 r^2 / 14 + (T - r)^2 / 2 - (1 - e) tau^2 / 7).
- hold-back creep d over T_h: s = d S(x): at mid-tension s = d / 2 and s' = 1.875 d / T_h.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from support.ins_consistency import ATT_TOL, NOISE_OFF, VEL_TOL, integrate

from alignment_core import pipeline
from alignment_core.aircraft.catapult import stroke_end_speed, stroke_length
from alignment_core.config import scenario
from alignment_core.samples import ShipBatch
from alignment_core.units import ARCMIN, DEG, G0
from alignment_core.validation import ConfigError

LAUNCH, T = 2.0, 3.0
SHORT = {**NOISE_OFF, 'duration_s': 6.0, 'aircraft.catapult.launch_time_s': LAUNCH,
         'aircraft.catapult.stroke_s': T}
A = 2.0 * G0
R_UP, TAIL, E = 0.2, 0.3, 0.6

PROFILES = {
    'constant': ({}, A * T, A * T**2 / 2),
    'linear-knots': ({'aircraft.catapult.profile': 'knots', 'aircraft.catapult.knot_time_s': [0.0, 1.5, 3.0],
                      'aircraft.catapult.knot_accel_g': [1.0, 2.0, 3.0]},
                     G0 * T + (2 * G0 / T) * T**2 / 2, G0 * T**2 / 2 + (2 * G0 / T) * T**3 / 6),
    'shape': ({'aircraft.catapult.profile': 'shape', 'aircraft.catapult.ramp_s': R_UP,
               'aircraft.catapult.tail_s': TAIL, 'aircraft.catapult.tail_fraction': E},
              A * (T - R_UP / 2 - (1 - E) * TAIL / 2),
              A * (R_UP * T / 2 - 5 * R_UP**2 / 14 + (T - R_UP)**2 / 2 - (1 - E) * TAIL**2 / 7)),
}


def run(overrides):
    sc = scenario.load('catapult_paper', {**SHORT, **overrides})
    ship_list = pipeline.ship_samples(sc)
    truth, imu = pipeline.SlaveImuStage(sc).run_batch(ShipBatch.of(ship_list))
    tau = (np.array([s.t_ns for s in ship_list]) - sc.t0_ns) / 1e9
    return sc, ship_list, truth, imu, tau


def relative(sc, ship_list, truth, k):
    """Aircraft position (m) and velocity (m/s) relative to the ship at sample k, ship axes:
    r = C_n^s C_w^l (p_a - p_s), r' = C_n^s (v_a - v_s) - w x r."""
    s = ship_list[k]
    plane = pipeline.plane_of(sc)
    c_ns = Rotation.from_quat(s.q_nb).inv()
    r = c_ns.apply(plane.c_local_to_world(s.p_w).T @ (truth['p_w'][k] - s.p_w))
    v_a = Rotation.from_quat(truth['q_nb'][k]).apply(truth['v_b'][k])
    v_s = Rotation.from_quat(s.q_nb).apply(s.v_b)
    return r, c_ns.apply(v_a - v_s) - np.cross(s.w_b, r)


def track_of(sc):
    mu = np.asarray(sc.aircraft.misalignment_arcmin) * ARCMIN
    return Rotation.from_rotvec(mu).as_matrix()[:, 0]


@pytest.mark.parametrize('name', list(PROFILES))
def test_end_speed_and_stroke_length(name):
    ov, v_end, s_end = PROFILES[name]
    sc, ship_list, truth, _, tau = run(ov)
    assert stroke_end_speed(sc.aircraft.catapult) == pytest.approx(v_end, abs=1e-9)
    assert stroke_length(sc.aircraft.catapult) == pytest.approx(s_end, abs=1e-9)
    u, r0 = track_of(sc), np.asarray(sc.aircraft.lever_arm_m)
    k0, k1 = int(np.argmin(abs(tau - LAUNCH))), int(np.argmin(abs(tau - LAUNCH - T)))
    r, v = relative(sc, ship_list, truth, k0)
    np.testing.assert_allclose(r, r0, atol=1e-6)
    np.testing.assert_allclose(v, 0.0, atol=1e-6)
    r, v = relative(sc, ship_list, truth, k1)
    np.testing.assert_allclose(r - r0, s_end * u, atol=1e-6)
    np.testing.assert_allclose(v, v_end * u, atol=1e-6)
    # the LDV beam covers the creep and the stroke (+ 0.5 m)
    assert sc.ldv.track_length_m == pytest.approx(s_end + 0.5, abs=1e-9)


def test_shape_profile_acceleration_in_the_plateau_and_at_the_release():
    """Plateau: d(s')/dt = A; last interval before the release: s'' -> e A (tail end)."""
    sc, ship_list, truth, _, tau = run(PROFILES['shape'][0])
    u = track_of(sc)
    k = int(np.argmin(abs(tau - LAUNCH - 1.5)))
    v_a, v_b = (relative(sc, ship_list, truth, j)[1] @ u for j in (k, k + 1))
    assert (v_b - v_a) / 0.01 == pytest.approx(A, rel=1e-9)
    k1 = int(np.argmin(abs(tau - LAUNCH - T)))
    v_a, v_b = (relative(sc, ship_list, truth, j)[1] @ u for j in (k1 - 1, k1))
    # mean acceleration over the last 10 ms of the tail: A (1 - (1 - e) S(x)) with x near 1
    assert (v_b - v_a) / 0.01 == pytest.approx(E * A, rel=1e-3)


def test_holdback_creep():
    d, th = 0.05, 1.0
    sc, ship_list, truth, imu, tau = run({'aircraft.catapult.holdback_s': th,
                                          'aircraft.catapult.holdback_stretch_m': d})
    u, r0 = track_of(sc), np.asarray(sc.aircraft.lever_arm_m)
    at = {t: int(np.argmin(abs(tau - t))) for t in (LAUNCH - th, LAUNCH - th / 2, LAUNCH, LAUNCH + T)}
    r, v = relative(sc, ship_list, truth, at[LAUNCH - th])
    np.testing.assert_allclose(r, r0, atol=1e-6)
    r, v = relative(sc, ship_list, truth, at[LAUNCH - th / 2])
    np.testing.assert_allclose(r - r0, 0.5 * d * u, atol=1e-6)
    np.testing.assert_allclose(v, 1.875 * d / th * u, atol=1e-6)
    r, v = relative(sc, ship_list, truth, at[LAUNCH])
    np.testing.assert_allclose(r - r0, d * u, atol=1e-6)
    np.testing.assert_allclose(v, 0.0, atol=1e-6)
    r, v = relative(sc, ship_list, truth, at[LAUNCH + T])
    np.testing.assert_allclose(r - r0, (d + A * T**2 / 2) * u, atol=1e-6)
    assert sc.ldv.track_length_m == pytest.approx(d + A * T**2 / 2 + 0.5, abs=1e-9)


def test_heading_on_deck_turns_the_aircraft_and_the_track():
    """Heading on deck -9 deg (to port, the angled deck), no misalignment, calm sea: the
    aircraft's heading is the ship's minus 9 deg and the stroke runs along (cos 9, sin 9, 0)
    in ship axes (FLU: +y is port)."""
    sc, ship_list, truth, _, tau = run({'aircraft.heading_on_deck_deg': -9.0,
                                        'aircraft.misalignment_arcmin': [0.0, 0.0, 0.0], 'ship.sea_state': 0})
    yaw_a = Rotation.from_quat(truth['q_nb'][0]).as_euler('ZYX')[0]
    yaw_s = Rotation.from_quat(ship_list[0].q_nb).as_euler('ZYX')[0]
    assert (yaw_a - yaw_s) == pytest.approx(9.0 * DEG, abs=1e-12)      # ROS yaw is anticlockwise
    u = np.array([np.cos(9 * DEG), np.sin(9 * DEG), 0.0])
    k1 = int(np.argmin(abs(tau - LAUNCH - T)))
    r, v = relative(sc, ship_list, truth, k1)
    np.testing.assert_allclose(r - np.asarray(sc.aircraft.lever_arm_m), A * T**2 / 2 * u, atol=1e-6)
    np.testing.assert_allclose(v, A * T * u, atol=1e-6)


@pytest.mark.parametrize('ov', [
    {**PROFILES['shape'][0], 'aircraft.catapult.holdback_s': 1.5, 'aircraft.catapult.holdback_stretch_m': 0.08,
     'aircraft.heading_on_deck_deg': -9.0},
    PROFILES['linear-knots'][0],
], ids=['shape-holdback-angled', 'knots'])
def test_ins_consistency_through_holdback_and_profiled_stroke(ov):
    """Noise-free increments integrated from the true initial state reproduce the truth on a
    rolling deck (sea state 5), through tensioning, the stroke and 3 s of free flight."""
    sc, _, truth, imu, _ = run({**ov, 'ship.sea_state': 5})
    att, vel = integrate(sc, truth, imu)
    assert att.max() < ATT_TOL, f'attitude error {att.max():.3g} rad'
    assert vel.max() < VEL_TOL, f'velocity error {vel.max():.3g} m/s'


@pytest.mark.parametrize('ov,msg', [
    ({'aircraft.catapult.profile': 'knots', 'aircraft.catapult.knot_time_s': [0.0, 2.0, 1.0, 3.0],
      'aircraft.catapult.knot_accel_g': [1.0, 2.0, 2.0, 1.0]}, 'increase strictly'),
    ({'aircraft.catapult.profile': 'knots', 'aircraft.catapult.knot_time_s': [0.0, 2.5],
      'aircraft.catapult.knot_accel_g': [1.0, 2.0]}, 'from 0 to stroke_s'),
    ({'aircraft.catapult.profile': 'knots', 'aircraft.catapult.knot_time_s': [0.0, 1.005, 3.0],
      'aircraft.catapult.knot_accel_g': [1.0, 2.0, 2.0]}, 'sample grid'),
    ({'aircraft.catapult.profile': 'shape', 'aircraft.catapult.ramp_s': 2.0, 'aircraft.catapult.tail_s': 1.5},
     'must fit in stroke_s'),
    ({'aircraft.catapult.holdback_s': 3.0}, 'holdback_s'),
    ({'aircraft.catapult.holdback_stretch_m': 0.05}, 'needs holdback_s'),
    ({'aircraft.catapult.profile': 'parabolic'}, 'must be one of'),
    ({'aircraft.heading_on_deck_deg': 200.0}, 'heading_on_deck_deg'),
])
def test_invalid_catapult_settings_fail_clearly(ov, msg):
    with pytest.raises(ConfigError, match=msg):
        scenario.load('catapult_paper', {**SHORT, **ov})
