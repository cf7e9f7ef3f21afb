"""The airframe on its landing gear (aircraft/landing_gear.py, gear_response.py).

Expected values come from hand derivations, not from the model's matrices: the lever rule and
the polytropic slope for the static deflections, the closed-form eigenvalues of the 2-DOF
heave-pitch model, the log decrement of a single-degree-of-freedom oscillator, conservation
of energy, the statics of the hold-back pull, the Dryden intensities; and the wiring: disabled
gear leaves every number as it was, stepping equals batch, the IMU's increments integrate back
to the truth, the LDV reads the gear's motion."""
from __future__ import annotations

import dataclasses
import hashlib

import numpy as np
import pytest
from scipy.integrate import simpson
from support.ins_consistency import ATT_TOL, NOISE_OFF, VEL_TOL, integrate

from alignment_core import pipeline
from alignment_core.air_data.turbulence_spec import dryden_parameters
from alignment_core.aircraft.gear_config import GearConfig
from alignment_core.aircraft.gear_response import DeckGust, GearResponse
from alignment_core.aircraft.landing_gear import N_DOF, GearModel
from alignment_core.config import scenario
from alignment_core.samples import ShipBatch
from alignment_core.units import G0
from alignment_core.validation import ConfigError

CFG = GearConfig(enabled=True)
LINEAR = dataclasses.replace(CFG, strut_spring='linear')     # the tangent model, for the linear closed forms


def leg_loads(cfg: GearConfig) -> np.ndarray:
    """Lever rule: the nose leg carries nose_load_fraction of the weight, each main half the rest."""
    w = cfg.mass_kg * G0
    return np.array([cfg.nose_load_fraction * w, 0.5 * (1 - cfg.nose_load_fraction) * w,
                     0.5 * (1 - cfg.nose_load_fraction) * w])


def test_static_deflection_is_load_over_stiffness():
    m = GearModel(CFG)
    q = -m.settling()                                        # static point relative to the unloaded gear
    f = leg_loads(CFG)
    gas = np.array([CFG.nose_gas_length_m, CFG.main_gas_length_m, CFG.main_gas_length_m])
    k_strut = CFG.polytropic_index * f / gas                 # slope of F0 (V0 / (V0 - A s))^n at s = 0
    np.testing.assert_allclose(m.strut_compression(q), f / k_strut, rtol=1e-9)
    np.testing.assert_allclose(m.strut_compression(q), gas / CFG.polytropic_index, rtol=1e-9)
    k_tyre = np.array([CFG.nose_tyre_kz_npm, CFG.main_tyre_kz_npm, CFG.main_tyre_kz_npm])
    unsprung = np.array([CFG.nose_unsprung_kg, CFG.main_unsprung_kg, CFG.main_unsprung_kg])
    np.testing.assert_allclose(-q[6:], (f + unsprung * G0) / k_tyre, rtol=1e-9)   # axles sink by the tyres'
    assert q[2] < -0.15                                       # the CG settles by strut + tyre, about 0.2 m


def test_heave_pitch_roll_surge_frequencies_against_closed_form():
    # CG on the contact plane and near-massless axles: heave-pitch, roll and surge decouple and the
    # legs act as strut and tyre in series
    cfg = dataclasses.replace(CFG, cg_height_m=0.0, nose_unsprung_kg=1e-3, main_unsprung_kg=1e-3)
    f = leg_loads(cfg)
    gas = np.array([cfg.nose_gas_length_m, cfg.main_gas_length_m, cfg.main_gas_length_m])
    ks = cfg.polytropic_index * f / gas
    kt = np.array([cfg.nose_tyre_kz_npm, cfg.main_tyre_kz_npm, cfg.main_tyre_kz_npm])
    k = ks * kt / (ks + kt)
    x = np.array([(1 - cfg.nose_load_fraction) * cfg.wheelbase_m, -cfg.nose_load_fraction * cfg.wheelbase_m,
                  -cfg.nose_load_fraction * cfg.wheelbase_m])
    y = np.array([0.0, 0.5 * cfg.main_track_m, -0.5 * cfg.main_track_m])
    m, ixx, iyy = cfg.mass_kg, cfg.inertia_kgm2[0], cfg.inertia_kgm2[1]
    kzz, kzt, ktt = k.sum(), -(k * x).sum(), (k * x * x).sum()       # heave z, pitch theta (nose-down +)
    a, b, c = m * iyy, -(kzz * iyy + ktt * m), kzz * ktt - kzt**2
    w2 = np.array([(-b - s * np.sqrt(b * b - 4 * a * c)) / (2 * a) for s in (1, -1)])
    roll = (k * y * y).sum() / ixx
    kx = np.array([cfg.nose_tyre_kx_npm, cfg.main_tyre_kx_npm, cfg.main_tyre_kx_npm])
    surge = kx.sum() / m
    got = GearModel(cfg).natural_frequencies_hz()
    for w2_expected in (*w2, roll, surge):
        f_expected = np.sqrt(w2_expected) / (2 * np.pi)
        assert np.min(np.abs(got / f_expected - 1)) < 1e-5, (f_expected, got)


def test_free_decay_matches_the_damping_ratio():
    # equal gas columns: every leg's k / m_leg = n g / L, so c = 2 zeta sqrt(k m) is proportional to
    # k and the heave mode (a uniform drop) is a single oscillator of ratio zeta at sqrt(n g / L)
    zeta = 0.1
    cfg = dataclasses.replace(CFG, nose_gas_length_m=0.2, main_gas_length_m=0.2, strut_damping_ratio=zeta,
                              tyre_damping_ratio=0.0, nose_tyre_kz_npm=1e9, main_tyre_kz_npm=1e9,
                              nose_unsprung_kg=1.0, main_unsprung_kg=1.0)
    model = GearModel(cfg)
    dt = 1e-3
    phi, _, _ = model.discretise(dt)
    x = np.zeros(2 * N_DOF)
    x[2] = 0.01
    z = np.empty(6000)
    for j in range(len(z)):
        z[j] = x[2]
        x = phi @ x
    peaks = [j for j in range(1, len(z) - 1) if z[j] > z[j - 1] and z[j] >= z[j + 1] and z[j] > 1e-5]
    t_pk, v_pk = [], []
    for j in peaks:                                          # parabola through the three samples
        a, b, c = z[j - 1], z[j], z[j + 1]
        off = 0.5 * (a - c) / (a - 2 * b + c)
        t_pk.append((j + off) * dt)
        v_pk.append(b - 0.25 * (a - c) * off)
    delta = np.log(v_pk[0] / v_pk[1])
    assert delta / np.sqrt(4 * np.pi**2 + delta**2) == pytest.approx(zeta, rel=0.01)
    wn = np.sqrt(cfg.polytropic_index * G0 / 0.2)
    assert t_pk[1] - t_pk[0] == pytest.approx(2 * np.pi / (wn * np.sqrt(1 - zeta**2)), rel=2e-3)


def _simulate(model: GearModel, x0: np.ndarray, load: np.ndarray, dt: float, n: int):
    phi, g0, g1 = model.discretise(dt)
    xs = np.empty((n, 2 * N_DOF))
    x = x0
    for j in range(n):
        xs[j] = x
        x = phi @ x + (g0 + g1) @ load
    return xs[:, :N_DOF], xs[:, N_DOF:]


def test_energy_balance_with_and_without_damping():
    rng = np.random.default_rng(5)
    x0 = np.concatenate([rng.normal(0, 0.01, N_DOF), rng.normal(0, 0.05, N_DOF)])
    dt, n = 2e-4, 15000
    undamped = GearModel(dataclasses.replace(LINEAR, strut_damping_ratio=0.0, tyre_damping_ratio=0.0))
    q, qd = _simulate(undamped, x0, np.zeros(N_DOF), dt, n)
    e = undamped.energy(q, qd)
    assert np.ptp(e) < 1e-9 * e[0]
    # damped, under a constant load switched on at t = 0: the load's work = energy gained + dissipated
    model = GearModel(LINEAR)
    load = 5e4 * model.holdback_load() + rng.normal(0, 1e3, N_DOF)
    q, qd = _simulate(model, x0, load, dt, n)
    e = model.energy(q, qd)
    dissipated = simpson(np.einsum('ki,ij,kj->k', qd, model.C, qd), dx=dt)
    work = load @ (q[-1] - q[0])
    assert dissipated > 0.5 * e[0]                           # the dampers really act
    assert e[-1] - e[0] + dissipated == pytest.approx(work, rel=1e-5, abs=1e-6 * e[0])


def test_holdback_offset_and_kneel_statics():
    tension = 1e5
    # pulled at the deck level with the CG on it: no moment, the airframe moves T / sum(k_x)
    flat = dataclasses.replace(LINEAR, cg_height_m=0.0, holdback_height_m=0.0)
    q = GearModel(flat).static(tension * GearModel(flat).holdback_load())
    kx = CFG.nose_tyre_kx_npm + 2 * CFG.main_tyre_kx_npm
    assert q[0] == pytest.approx(tension / kx, rel=1e-9)
    assert abs(q[4]) < 1e-12 and abs(q[2]) < 1e-12
    # the default: pulled at holdback_height_m, the nose kneels. Statics by hand: the contact points
    # all move u_x = T / sum(k_x); moments about the CG: T z_hb + sum(x_i k_i u_iz) + m g h theta = 0
    # with u_iz = d_z - theta x_i and sum(k_i u_iz) = 0 (k_i: strut and tyre in series, linear springs)
    model = GearModel(LINEAR)
    q = model.static(tension * model.holdback_load())
    f = leg_loads(CFG)
    gas = np.array([CFG.nose_gas_length_m, CFG.main_gas_length_m, CFG.main_gas_length_m])
    ks = CFG.polytropic_index * f / gas
    kt = np.array([CFG.nose_tyre_kz_npm, CFG.main_tyre_kz_npm, CFG.main_tyre_kz_npm])
    k = ks * kt / (ks + kt)
    x = np.array([(1 - CFG.nose_load_fraction) * CFG.wheelbase_m, -CFG.nose_load_fraction * CFG.wheelbase_m,
                  -CFG.nose_load_fraction * CFG.wheelbase_m])
    h = CFG.cg_height_m
    theta = CFG.holdback_height_m * tension / ((k * x * x).sum() - (k * x).sum()**2 / k.sum()
                                               - CFG.mass_kg * G0 * h)
    d_z = theta * (k * x).sum() / k.sum()
    assert q[4] == pytest.approx(theta, rel=1e-9)             # nose down
    assert q[2] == pytest.approx(d_z, rel=1e-9)
    assert q[0] - h * q[4] == pytest.approx(tension / kx, rel=1e-9)
    kneel = -(d_z - theta * x[0])
    assert kneel > 0.03                                       # the nose leg shortens by centimetres
    leg_z = q[2] - q[4] * x[0]
    assert -leg_z == pytest.approx(kneel, rel=1e-9)


def test_holdback_ramp_reaches_the_static_kneel_then_rings_down():
    rate = 100.0
    resp = GearResponse(dataclasses.replace(CFG, gust_severity='none'), 1, rate, np.array([0.0, 0.0, G0]),
                        holdback=(1.0, 11.0))
    n = int(20 * rate) + 1
    resp.feed(np.arange(n), np.tile([0.0, 0.0, G0], (n, 1)), np.zeros((n, 3)))
    q, _, _ = resp.states(np.arange(n))
    t = resp.holdback_tension(np.array([0.99, 6.0, 10.99, 11.0]))
    assert t[0] == 0.0 and t[1] == pytest.approx(0.5 * CFG.holdback_tension_n) and t[2] > 0.99 * t[1] * 2
    assert t[3] == 0.0                                        # released at the launch sample
    expected = resp.model.static(CFG.holdback_tension_n * resp.model.holdback_load())
    k_end = int(11.0 * rate) - 1
    np.testing.assert_allclose(q[k_end, [0, 2, 4]], expected[[0, 2, 4]], rtol=0.02)
    assert np.all(np.abs(q[:int(rate)]) < 1e-15)              # nothing before the tensioning
    # released at 11 s: it rings down (the slowest mode, pitch-surge at 0.5 Hz, decays as e^(-0.27 t))
    assert np.abs(q[-1]).max() < 0.1 * np.abs(expected).max()
    assert np.abs(q[int(11.5 * rate):]).max() < 1.5 * np.abs(expected).max()


def test_a_heeled_deck_leans_the_aircraft_by_the_closed_form():
    # a deck heeled by phi tilts the specific force: the airframe is pushed sideways by m g sin(phi)
    # at its CG, the lateral tyres hold it at the deck, and the moment h m g sin(phi) about the CG
    # is balanced by the main legs (k: strut and tyre in series) less gravity's m g h:
    # theta_x = h m g sin(phi) / (sum k_i y_i^2 - m g h)
    phi = 0.01
    f = np.array([0.0, G0 * np.sin(phi), G0 * np.cos(phi)])
    resp = GearResponse(dataclasses.replace(LINEAR, gust_severity='none'), 1, 100.0, np.array([0.0, 0.0, G0]))
    resp.feed(np.arange(3), np.tile(f, (3, 1)), np.zeros((3, 3)))
    q = resp.states(np.arange(3))[0]
    loads = leg_loads(CFG)
    ks = CFG.polytropic_index * loads[1] / CFG.main_gas_length_m
    k = ks * CFG.main_tyre_kz_npm / (ks + CFG.main_tyre_kz_npm)
    m, h = CFG.mass_kg, CFG.cg_height_m
    lean = h * m * G0 * np.sin(phi) / (2 * k * (0.5 * CFG.main_track_m) ** 2 - m * G0 * h)
    np.testing.assert_allclose(q[:, 3], lean, rtol=1e-6)          # settled from the first sample on
    assert lean > 0                                                # towards the low side (-y)
    # the lateral tyres carry the whole side force: their stiffness-weighted mean slide is F / sum k_y
    # (the slides differ by a yaw: the nose and main tyres' stiffness is not balanced about the CG)
    ky = np.array([CFG.nose_tyre_ky_npm, CFG.main_tyre_ky_npm, CFG.main_tyre_ky_npm])
    x = np.array([(1 - CFG.nose_load_fraction) * CFG.wheelbase_m, -CFG.nose_load_fraction * CFG.wheelbase_m,
                  -CFG.nose_load_fraction * CFG.wheelbase_m])
    slide = q[:, 1:2] + q[:, 5:6] * x + h * q[:, 3:4]               # u_iy = d_y + theta_z x_i + h theta_x
    np.testing.assert_allclose(slide @ ky / ky.sum(), -m * G0 * np.sin(phi) / ky.sum(), rtol=1e-6)


def test_polytropic_struts_follow_the_gas_law():
    # a weight increase dW on rigid tyres, CG on the contact plane, equal gas columns: every strut
    # carries its lever-rule share times (1 + dW / W) and, by the polytropic law
    # F = F0 (L / (L - s))^n, shortens by s = L (1 - (W / (W + dW))^(1/n)); the linear spring: L/n dW/W
    cfg = dataclasses.replace(CFG, strut_spring='polytropic', cg_height_m=0.0, nose_gas_length_m=0.2,
                              main_gas_length_m=0.2, nose_tyre_kz_npm=1e12, main_tyre_kz_npm=1e12)
    model = GearModel(cfg)
    w, dw = cfg.mass_kg * G0, 0.6 * cfg.mass_kg * G0
    load = np.zeros(N_DOF)
    load[2] = -dw
    s = model.strut_compression(model.static(load))
    n, gas = cfg.polytropic_index, 0.2
    np.testing.assert_allclose(s, gas * (1 - (w / (w + dw)) ** (1 / n)), rtol=1e-6)
    linear = GearModel(dataclasses.replace(cfg, strut_spring='linear'))
    np.testing.assert_allclose(linear.strut_compression(linear.static(load)), gas / n * dw / w, rtol=1e-6)
    assert s[0] < 0.8 * gas / n * dw / w                          # the air spring stiffens


def test_polytropic_free_motion_conserves_energy():
    # undamped, after a step of the deck's vertical specific force: kinetic + elastic (with the air
    # springs' nonlinear potential) minus the constant load's potential stays constant
    cfg = dataclasses.replace(CFG, strut_spring='polytropic', strut_damping_ratio=0.0, tyre_damping_ratio=0.0,
                              gust_severity='none')
    rate = 2000.0
    resp = GearResponse(cfg, 1, rate, np.array([0.0, 0.0, G0]))
    n = int(4 * rate)
    f = np.tile([0.3, 0.5, G0 + 3.0], (n, 1))
    f[0] = [0.0, 0.0, G0]
    resp.feed(np.arange(n), f, np.zeros((n, 3)))
    q, qd, _ = resp.states(np.arange(2, n))
    load = resp.model.inertial_load(f[2], np.zeros(3), resp.f0)
    e = resp.model.energy(q, qd) - q @ load
    swing = resp.model.energy(q, qd).max()
    assert np.abs(resp.model.strut_compression(q)).max() > 0.02        # large enough to be nonlinear
    assert np.ptp(e) < 1e-5 * swing


def test_a_gear_that_would_tip_over_is_refused():
    with pytest.raises(ConfigError, match='not stable'):
        GearModel(dataclasses.replace(CFG, cg_height_m=5.0, main_track_m=1.0))


def test_gust_intensities_are_drydens():
    cfg = dataclasses.replace(CFG, wind_over_deck_mps=15.0, gust_severity='moderate')
    gust = DeckGust(cfg, seed=3, dt=0.5)
    noise = gust.draw(100_000)
    g = np.array([gust.step(nz) for nz in noise])
    par = dryden_parameters(cfg.gust_height_m, 'moderate')
    np.testing.assert_allclose(g.std(axis=0), [par.sigma_u, par.sigma_v, par.sigma_w], rtol=0.05)


# --- wiring into the aircraft kinematics -----------------------------------------------------------

SHORT = {'duration_s': 8.0, 'aircraft.catapult.launch_time_s': 4.0, 'aircraft.catapult.stroke_s': 2.0}


def _digest(over: dict) -> str:
    sc = scenario.load('catapult_paper', {**SHORT, **over})
    truth, imu = pipeline.SlaveImuStage(sc).run_batch(ShipBatch.of(pipeline.ship_samples(sc)))
    h = hashlib.sha256()
    for a in (truth['p_w'], truth['q_nb'], truth['v_b'], truth['w_b'],
              np.array([s.gyro for s in imu]), np.array([s.accel for s in imu])):
        h.update(np.array([float(f'{x:.10e}') for x in a.ravel()]).tobytes())
    return h.hexdigest()[:16]


@pytest.mark.parametrize('over,expected', [
    ({}, 'f98a16c33dc5cf53'),
    ({'aircraft.flexure.enabled': True, 'aircraft.vibration.enabled': True, 'aircraft.vibration.mode': 'motion'},
     'fee1b6c177d25f42'),
])
def test_disabled_gear_leaves_the_imu_stage_as_it_was(over, expected):
    """Digests (11 significant digits) recorded from the code before the gear existed; setting gear
    keys without enabling it changes nothing either."""
    assert _digest(over) == expected
    assert _digest({**over, 'aircraft.gear.mass_kg': 30000.0, 'aircraft.gear.holdback_tension_n': 2e5}) == expected


GEAR = {'aircraft.gear.enabled': True, 'ship.mode': 'spectral', 'ship.sea_state': 5,
        'aircraft.catapult.holdback_s': 2.0}


@pytest.mark.parametrize('spring', ['linear', 'polytropic'])
def test_gear_stepping_equals_batch_and_increments_integrate_to_truth(spring):
    sc = scenario.load('catapult_paper', {**NOISE_OFF, **SHORT, **GEAR, 'aircraft.flexure.enabled': True,
                                    'aircraft.gear.strut_spring': spring})
    ships = pipeline.ship_samples(sc)
    stage = pipeline.SlaveImuStage(sc)
    truth, imu = stage.run_batch(ShipBatch.of(ships))
    assert stage.kin.gear.response.n == int(6.0 * sc.rate_hz) + 1     # simulated up to the release
    step = pipeline.SlaveImuStage(sc)
    out = [step.step(s) for s in ships]
    assert np.array_equal([o[0].q_nb for o in out], truth['q_nb'])
    assert np.array_equal([o[0].v_b for o in out], truth['v_b'])
    assert np.array_equal([o[1].accel for o in out[1:]], [s.accel for s in imu])
    assert np.array_equal([o[1].gyro for o in out[1:]], [s.gyro for s in imu])
    att, vel = integrate(sc, truth, imu)
    assert att.max() < ATT_TOL and vel.max() < VEL_TOL, (att.max(), vel.max())


def test_truth_and_ldv_see_the_gear():
    over = {**SHORT, **GEAR, 'ldv.noise_mps': 1e-9}
    rigid = pipeline.simulate(scenario.load('catapult_paper', {**over, 'aircraft.gear.enabled': False}))
    sc = scenario.load('catapult_paper', over)
    inp = pipeline.simulate(sc)
    stage = pipeline.SlaveImuStage(sc)
    stage.run_batch(inp.ships)
    kin = stage.kin
    on = inp.truth['on_deck']
    dp = np.linalg.norm(inp.truth['p_w'][on] - rigid.truth['p_w'][on], axis=1)
    assert 1e-3 < dp.max() < 0.5                              # the truth moves with the gear
    # parked, before the tensioning: the LDV reads the IMU point's velocity on the gear, ship axes
    parked = [s for s in inp.ldv if s.valid and s.t_ns < sc.t0_ns + 1.9e9]
    assert len(parked) > 100
    k = np.array([(s.t_ns - sc.t0_ns) // sc.dt_ns for s in parked])
    expected = kin.gear.response.imu_at(k)[1] @ kin.gear.c_ds.T
    got = np.array([s.v_s for s in parked])
    assert np.sqrt((expected**2).mean()) > 1e-4               # mm/s of motion
    np.testing.assert_allclose(got, expected, atol=1e-7)
    rigid_parked = np.array([s.v_s for s in rigid.ldv if s.valid and s.t_ns < sc.t0_ns + 1.9e9])
    assert np.abs(rigid_parked).max() < 1e-7
