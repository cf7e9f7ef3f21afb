"""Seed 004's 3-state airspeed estimator: given the attitude its process and measurement are
linear in the state, so EKF, UKF and CKF must agree to round-off (the CKF's advantage the seed
reports cannot come from this model); and it tracks the truth within its sigma."""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation
from scipy.stats import chi2
from support.air_data_flight import flight

from alignment_core.air_data.ports import PortModel
from alignment_core.estimation.air_data.config import AirDataFilterConfig
from alignment_core.estimation.air_data.paper_form import PaperAirDataFilter
from alignment_core.geometry import earth

IMU_DT = 0.1


def imu_between(a, b):
    """Mean specific force and rate (body) between two INS samples of the synthetic flight, by
    central differences of its truth (gravity, Earth rate and transport rate included)."""
    dt = b.t - a.t
    ca, cb = Rotation.from_quat(a.q_nb), Rotation.from_quat(b.q_nb)
    c_mid = Rotation.from_quat(a.q_nb) * Rotation.from_rotvec(0.5 * (ca.inv() * cb).as_rotvec())
    w_nb = (ca.inv() * cb).as_rotvec() / dt
    v = 0.5 * (a.v_enu + b.v_enu)
    lat, h = a.lat_rad, a.height_m
    w_ie, w_en = earth.omega_ie_n(lat), earth.omega_en_n(lat, h, v)
    f_n = (b.v_enu - a.v_enu) / dt + np.cross(2 * w_ie + w_en, v) - earth.gravity_n(lat, h)
    c = c_mid.as_matrix()
    return c.T @ f_n, w_nb + c.T @ (w_ie + w_en)


def run(algorithm, duration_s=200.0, seed=1):
    frames = flight(duration_s=duration_s, rate_hz=1.0 / IMU_DT, rho=0.0, seed=seed)
    f = PaperAirDataFilter(AirDataFilterConfig(form='paper', algorithm=algorithm), PortModel(), IMU_DT)
    rows = []
    for k, fr in enumerate(frames):
        f.push_ins(fr.ins)
        if k:
            f_b, w_ib = imu_between(frames[k - 1].ins, fr.ins)
            f.push_imu(frames[k - 1].t, fr.t, f_b, w_ib)
        if k % 10 == 0:                          # FADS at 1 Hz
            f.push_frame(fr.t, fr.pressures)
            rows.append((fr, f.estimate()))
    return f, rows, frames[-1]


def test_ekf_ukf_ckf_agree_to_round_off():
    results = {a: run(a, duration_s=60.0)[0].filter for a in ('ekf', 'ukf', 'ckf')}
    for a in ('ukf', 'ckf'):
        np.testing.assert_allclose(results[a].x, results['ekf'].x, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(results[a].P, results['ekf'].P, rtol=1e-6, atol=1e-12)


def test_nees_over_seeds_is_chi_square():
    """The state error x - v_a^b at the end of independent runs, normalised by P: the sum over 6
    seeds of e^T P^-1 e is chi-square with 18 degrees of freedom (two-sided 0.1 % bounds)."""
    total = 0.0
    for seed in range(6):
        f, _, last = run('ckf', duration_s=80.0, seed=seed)
        assert f.counts['gated'] == 0 and f.t == last.t
        e = f.filter.x - last.v_air_body
        total += float(e @ np.linalg.solve(f.filter.P, e))
    assert chi2.ppf(0.0005, 18) < total < chi2.ppf(0.9995, 18)


def test_single_run_errors_stay_inside_their_sigma():
    f, rows, _ = run('ckf', duration_s=120.0)
    assert f.counts['updates'] > 100
    for name, truth in (('alpha_rad', lambda fr: fr.alpha), ('beta_rad', lambda fr: fr.beta),
                        ('mach', lambda fr: fr.mach)):
        z = np.array([(e.get(name) - truth(fr)) / e.sigma_of(name) for fr, e in rows[10:]])
        assert np.max(np.abs(z)) < 4.5, name
