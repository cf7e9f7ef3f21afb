"""Observability the physics predicts, seen through the models.

seed002_10 (horizontal velocity matching, the paper's P0 and R0 = (0.1 m/s)^2), 10 s on the deck:
* static deck (calm sea, straight course at constant speed): the horizontal specific force is
  only the Coriolis term (~1e-3 m/s^2), so heading enters the velocity only through
  gyrocompassing, phi_E' = -Omega_N phi_U: a velocity signal (g Omega_N / 2) phi_U t^2. Its
  information over T with noise sigma at rate fs (after the tilt/bias ramps are fitted out) is
  about (g Omega_N / 2)^2 fs T^5 / (180 sigma^2) = 0.4 rad^-2 at T = 10 s, against the prior's
  1 / (1.5 deg)^2 = 1459 rad^-2: the yaw sigma must stay at its prior within 1 % (0.01 %).
* sea state 4: the lever arm (40, -10, 15) m turns the ship's yaw (1.9 deg at 8.5 s: 0.7 m/s^2
  peak at 40 m) and roll into horizontal accelerations of a_h >= 0.2 m/s^2 rms;
  sigma_psi ~ sigma_v sqrt(12 / N) / (a_h T) = 0.1 * 0.11 / 2 = 5.5e-3 rad = 0.21 of the prior:
  the yaw sigma falls below a quarter of its prior and the error is inside 3 sigma.

seed001_13 (Doppler), a covariance analysis along a flight (straight 50 s, then a 30 deg bank
turn). The radar's body-frame velocity is resolved with the SINS's own attitude: rotating the
SINS's attitude and velocity together about the vertical (phi_U = psi, dV = psi V x e_U) changes
neither z (H x = 0) nor the SINS's kinematics (gravity is vertical), so heading is invisible
except through gyrocompassing (Earth rate: ~3 % of the prior information in 110 s), turn or
not. The drift-angle error is different: it rotates only the radar's velocity, so in straight
flight it is confounded with the cross-track velocity error, and a turn separates it."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.models import Propagation
from alignment_core.estimation.models.seed001 import DopplerTuning, Seed001Doppler
from alignment_core.units import ARCMIN, DEG

PAPER = {'duration_s': 10.0, 'filter.model': 'seed002_10', 'filter.ldv_sigma_mps': 0.1,
         'filter.parked_velocity_sigma_mps': 0.1, 'filter.init_attitude_sigma_deg': 1.0,
         'filter.init_yaw_sigma_deg': 1.5, 'filter.accel_bias_sigma_ug': 10.0,
         'aircraft.misalignment_arcmin': [60.0, 60.0, 60.0]}
PHI_U = 4          # phi_U in seed002_10's state


@pytest.mark.parametrize('seed', [1, 2])
def test_seed002_yaw_unobservable_on_a_static_deck(seed):
    sc = scenario.load('deck_paper', {**PAPER, 'ship.sea_state': 0}, seed=seed)
    e = pipeline.run(sc, keep_truth=False).estimates[-1]
    assert abs(e.sigma[PHI_U] / (1.5 * DEG) - 1.0) < 0.01


@pytest.mark.parametrize('seed', [1, 2])
def test_seed002_yaw_converges_with_ship_motion(seed):
    sc = scenario.load('deck_paper', {**PAPER, 'ship.sea_state': 4}, seed=seed)
    e = pipeline.run(sc, keep_truth=False).estimates[-1]
    assert e.sigma[PHI_U] < 0.25 * 1.5 * DEG
    err = e.misalignment - np.array(sc.aircraft.misalignment_arcmin) * ARCMIN
    assert abs(err[2]) < 3.0 * e.misalignment_sigma[2]


def _doppler_covariance(turn_s: float, straight_s: float = 50.0, rate_hz: float = 10.0):
    """P of seed001_13 after straight flight north at 60 m/s, then a coordinated 30 deg bank turn."""
    m = Seed001Doppler(DopplerTuning(yaw_sigma_arcmin=10.0, drift_angle_sigma_arcmin=10.0))
    p = m.initial_covariance()
    g, v, h = 9.8, 60.0, 1.0 / rate_hz
    w_turn = g * np.tan(30.0 * DEG) / v                     # 0.094 rad/s
    lat = 30.0 * DEG
    w_ie = 7.292115e-5 * np.array([0.0, np.cos(lat), np.sin(lat)])
    r = np.eye(2) * 0.1 ** 2
    chi = 0.0                                               # track angle from North, clockwise
    for k in range(int(round((straight_s + turn_s) / h))):
        turning = k * h >= straight_s
        if turning:
            chi += w_turn * h
        vel = v * np.array([np.sin(chi), np.cos(chi), 0.0])
        right = np.array([np.cos(chi), -np.sin(chi), 0.0])
        f_n = np.array([0.0, 0.0, g]) + (v * w_turn * right if turning else 0.0)
        yaw = np.pi / 2.0 - chi
        c = np.array([[np.cos(yaw), -np.sin(yaw), 0.0], [np.sin(yaw), np.cos(yaw), 0.0], [0.0, 0.0, 1.0]])
        w_en = np.array([-vel[1], vel[0], vel[0] * np.tan(lat)]) / 6.38e6
        phi = m.transition(Propagation(c, f_n, w_ie, w_en, vel, lat, 3000.0, h))
        p = phi @ p @ phi.T + m.process_noise(h)
        hm = m.measurement_matrix(vel)
        s = hm @ p @ hm.T + r
        k_gain = p @ hm.T @ np.linalg.inv(s)
        ikh = np.eye(13) - k_gain @ hm
        p = ikh @ p @ ikh.T + k_gain @ r @ k_gain.T
    return m, p


def test_seed001_heading_rotation_is_invisible_to_the_doppler_match():
    v = np.array([-52.0, 30.0, 0.0])
    x = np.zeros(13)
    x[2] = 1e-3
    x[3:5] = (1e-3 * np.cross(v, [0.0, 0.0, 1.0]))[0:2]
    np.testing.assert_allclose(Seed001Doppler.measurement_matrix(v) @ x, 0.0, atol=1e-15)


def test_seed001_straight_flight_confounds_drift_angle_and_a_turn_separates_it():
    _, p_straight = _doppler_covariance(0.0)
    _, p_turn = _doppler_covariance(60.0)
    prior = 10.0 * ARCMIN
    assert np.sqrt(p_straight[11, 11]) > 0.9 * prior
    assert np.sqrt(p_turn[11, 11]) < 0.1 * prior
    # heading: neither straight flight nor the turn (gyrocompassing only)
    assert np.sqrt(p_straight[2, 2]) > 0.9 * prior and np.sqrt(p_turn[2, 2]) > 0.9 * prior
