"""The aircraft truth and its ideal IMU increments (pipeline.SlaveImuStage, noise off) must be
one consistent motion: integrating the increments with the strapdown from the true initial
state reproduces the true attitude and velocity at a point 60 m from the master INS on a
rolling deck, and through the catapult stroke and free flight. Catapult kinematics are
checked against s = a T^2 / 2 and v = a T with a noise-free LDV.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from support.ins_consistency import ATT_TOL, NOISE_OFF, VEL_TOL, integrate, simulate

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.samples import AircraftTruth, ShipBatch
from alignment_core.sensors.ldv import LdvConfig, LdvModel
from alignment_core.units import ARCMIN, G0

LEVER_ARM = [60.0, -15.0, 20.0]


@pytest.mark.parametrize('name,overrides', [
    ('deck_paper', {}),
    # the same rolling deck with a catapult that never fires within the run
    ('catapult_paper', {'aircraft.catapult.launch_time_s': 1000.0}),
], ids=['deck_paper', 'catapult-never-fires'])
def test_lever_arm_point_on_rolling_deck(name, overrides):
    sc = scenario.load(name, {**NOISE_OFF, 'ship.sea_state': 5, 'aircraft.lever_arm_m': LEVER_ARM,
                              'duration_s': 300.0, **overrides})
    assert sc.rate_hz == 100.0 and sc.ship.mode == 'paper'
    _, truth, imu = simulate(sc)
    assert len(imu) == 30000
    assert np.all(truth['on_deck'])
    att, vel = integrate(sc, truth, imu)
    assert att.max() < ATT_TOL, f'attitude error {att.max():.3g} rad'
    assert vel.max() < VEL_TOL, f'velocity error {vel.max():.3g} m/s'


@pytest.fixture(scope='module')
def catapult_run():
    sc = scenario.load('catapult_paper', NOISE_OFF)
    ship_list, truth, imu = simulate(sc)
    return sc, ship_list, truth, imu


def test_ins_through_catapult_stroke_and_free_flight(catapult_run):
    sc, _, truth, imu = catapult_run
    cat = sc.aircraft.catapult
    assert cat.enabled and sc.duration_s > cat.launch_time_s + cat.stroke_s
    assert truth['on_deck'][0] and not truth['on_deck'][-1]
    att, vel = integrate(sc, truth, imu)
    assert att.max() < ATT_TOL, f'attitude error {att.max():.3g} rad'
    assert vel.max() < VEL_TOL, f'velocity error {vel.max():.3g} m/s'


def test_catapult_stroke_kinematics(catapult_run):
    """Constant acceleration a = 2 g along the aircraft x axis for T = 3 s from rest relative to
    the deck: displacement a T^2 / 2 = 88.26 m and end speed a T = 58.84 m/s along the track."""
    sc, ship_list, truth, _ = catapult_run
    cat = sc.aircraft.catapult
    a, t_stroke = cat.accel_g * G0, cat.stroke_s
    assert a == pytest.approx(2.0 * 9.80665) and t_stroke == 3.0
    s_end, v_end = 0.5 * a * t_stroke**2, a * t_stroke
    # the track is the aircraft x axis in ship axes: C_a^s e_x with C_a^s = exp([mu x])
    mu = np.asarray(sc.aircraft.misalignment_arcmin) * ARCMIN
    track = Rotation.from_rotvec(mu).as_matrix()[:, 0]
    r0 = np.asarray(sc.aircraft.lever_arm_m)
    tau = (np.array([s.t_ns for s in ship_list]) - sc.t0_ns) / 1e9
    k_launch = int(np.flatnonzero(np.isclose(tau, cat.launch_time_s))[0])
    k_rel = int(np.flatnonzero(np.isclose(tau, cat.launch_time_s + t_stroke))[0])
    assert truth['on_deck'][k_rel] and not truth['on_deck'][k_rel + 1]

    # from truth: aircraft position relative to the master INS, in ship axes (world positions
    # are in the tangent plane at the origin: rotate the difference into the local level first)
    plane = pipeline.plane_of(sc)

    def rel(k):
        s = ship_list[k]
        d_local = plane.c_local_to_world(s.p_w).T @ (truth['p_w'][k] - s.p_w)
        return Rotation.from_quat(s.q_nb).inv().apply(d_local)
    np.testing.assert_allclose(rel(k_launch), r0, atol=1e-6)
    np.testing.assert_allclose(rel(k_rel) - r0, s_end * track, atol=1e-6)

    # from a noise-free LDV: integrate the relative velocity over the stroke (trapezoid is
    # exact for a velocity linear in time)
    ldv = LdvModel(LdvConfig(noise_mps=1e-9, origin_m=tuple(r0)), sc.seed, pipeline.plane_of(sc))
    samples = []
    for k in range(k_launch, k_rel + 1):
        tr = AircraftTruth(t_ns=ship_list[k].t_ns, p_w=truth['p_w'][k], q_nb=truth['q_nb'][k],
                           v_b=truth['v_b'][k], w_b=truth['w_b'][k], misalignment=mu,
                           on_deck=bool(truth['on_deck'][k]))
        samples.append(ldv.measure(ship_list[k], tr))
    assert all(s.valid for s in samples)
    v_s = np.array([s.v_s for s in samples])
    np.testing.assert_allclose(v_s[0], 0.0, atol=1e-6)
    np.testing.assert_allclose(v_s[-1], v_end * track, atol=1e-6)
    # speed grows linearly: v(t) = a t along the track
    t_rel = tau[k_launch:k_rel + 1] - cat.launch_time_s
    np.testing.assert_allclose(v_s, np.outer(a * t_rel, track), atol=1e-6)
    disp = np.sum(0.5 * (v_s[1:] + v_s[:-1]) * np.diff(t_rel)[:, None], axis=0)
    assert disp @ track == pytest.approx(s_end, abs=1e-6)
    np.testing.assert_allclose(disp - (disp @ track) * track, 0.0, atol=1e-6)


def test_release_off_exact_float_sum():
    """Launch 1.1 s and a 2.2 s stroke are both on the 100 Hz grid (validated), but
    1.1 + 2.2 != 3.3 in floating point. The run must still go through the release: on deck up to
    3.3 s with the deck-relative speed a T = 2 g x 2.2 s along the track, then free flight at
    the release velocity (constant in the nav frame)."""
    sc = scenario.load('catapult_paper', {'duration_s': 5.0, 'aircraft.catapult.launch_time_s': 1.1,
                                    'aircraft.catapult.stroke_s': 2.2})
    res = pipeline.run(sc)
    tau = np.array([(t.t_ns - sc.t0_ns) / 1e9 for t in res.truth])
    on = np.array([t.on_deck for t in res.truth])
    np.testing.assert_array_equal(on, tau <= 3.3 + 1e-9)
    k_rel = int(np.flatnonzero(on)[-1])
    mu = np.asarray(sc.aircraft.misalignment_arcmin) * ARCMIN
    track = Rotation.from_rotvec(mu).as_matrix()[:, 0]
    ldv = LdvModel(LdvConfig(noise_mps=1e-9, origin_m=tuple(sc.aircraft.lever_arm_m)), sc.seed, pipeline.plane_of(sc))
    ld = ldv.measure(pipeline.ship_samples(sc)[k_rel], res.truth[k_rel])
    np.testing.assert_allclose(ld.v_s, 2.0 * G0 * 2.2 * track, atol=1e-6)
    v_n = np.array([Rotation.from_quat(t.q_nb).apply(t.v_b) for t in res.truth])
    np.testing.assert_allclose(v_n[k_rel:], np.broadcast_to(v_n[k_rel], v_n[k_rel:].shape), atol=1e-9)


def test_batch_equals_step():
    """run_batch promises the same numbers as calling step sample by sample (checked across
    the launch and the release of a short catapult run)."""
    sc = scenario.load('catapult_paper', {'duration_s': 4.0, 'aircraft.catapult.launch_time_s': 1.0,
                                    'aircraft.catapult.stroke_s': 2.0})
    ship_list = pipeline.ship_samples(sc)
    truth_b, imu_b = pipeline.SlaveImuStage(sc).run_batch(ShipBatch.of(ship_list))
    stage = pipeline.SlaveImuStage(sc)
    out = [stage.step(s) for s in ship_list]
    for k, (tr, imu) in enumerate(out):
        np.testing.assert_allclose(tr.p_w, truth_b['p_w'][k], rtol=0, atol=1e-9)
        np.testing.assert_allclose(tr.v_b, truth_b['v_b'][k], rtol=0, atol=1e-12)
        assert tr.on_deck == bool(truth_b['on_deck'][k])
        if k > 0:
            assert imu.t_ns == imu_b[k - 1].t_ns
            np.testing.assert_allclose(imu.gyro, imu_b[k - 1].gyro, rtol=0, atol=1e-15)
            np.testing.assert_allclose(imu.accel, imu_b[k - 1].accel, rtol=0, atol=1e-12)
