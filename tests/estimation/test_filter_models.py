"""filter.model selects the error model at run time; invalid model x algorithm x option
combinations are refused at validation with a message naming the conflict; lever-arm states
and treatments behave as their physics says; fading factors reach the outputs."""
from __future__ import annotations

import typing

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.engine import TransferAlignment
from alignment_core.estimation.models import MODELS
from alignment_core.sensors.doppler_radar import DopplerRadarModel
from alignment_core.units import ARCMIN
from alignment_core.validation import ConfigError

SHORT = {'duration_s': 3.0, 'aircraft.catapult.enabled': False}


def test_default_is_the_15_state_velocity_matching_kf():
    cfg = FilterConfig()
    assert (cfg.model, cfg.algorithm, cfg.lever_arm_treatment, cfg.lever_arm_states) == ('vm15', 'kf', 'compensation',
                                                                                         False)
    sc = scenario.load('catapult_paper')
    f = TransferAlignment(sc.filter, pipeline.plane_of(sc), 100.0)
    assert f.n_states == 15 and f.labels[-3:] == ('phim_E', 'phim_N', 'phim_U') and f.model_name == 'vm15'


def test_model_names_are_the_config_choices():
    assert set(typing.get_args(typing.get_type_hints(FilterConfig)['model'])) == set(MODELS)


@pytest.mark.parametrize('model', MODELS)
def test_every_model_runs_in_the_engine_and_labels_its_state(model):
    algorithm = 'ekf' if model == 'seed000_large_angle' else 'kf'
    sc = scenario.load('deck_paper', {**SHORT, 'filter.model': model, 'filter.algorithm': algorithm,
                                'doppler.enabled': model == 'seed001_13'})
    res = pipeline.run(sc, keep_truth=False)
    n = res.filter.n_states
    assert len(res.filter.labels) == n == len(set(res.filter.labels))
    e = res.estimates[-1]
    assert e.x.shape == (n,) and e.sigma.shape == (n,) and e.attitude_cov.shape == (3, 3)
    assert np.all(np.isfinite(e.misalignment)) and np.all(e.misalignment_sigma > 0)
    assert e.updates > 200


@pytest.mark.parametrize('overrides,message', [
    ({'filter.model': 'seed000_large_angle'}, 'nonlinear: algorithm must be one of ekf, ukf, ckf'),
    ({'filter.model': 'seed000_large_angle', 'filter.algorithm': 'stf'}, 'nonlinear'),
    ({'filter.algorithm': 'ukf', 'filter.float32': True}, 'float64 only'),
    ({'filter.algorithm': 'ekf', 'filter.float32': True}, 'float64 only'),
    ({'filter.lever_arm_states': True, 'filter.lever_arm_treatment': 'butterworth'},
     'lever_arm_treatment compensation'),
    ({'filter.model': 'seed000_large_angle', 'filter.algorithm': 'ckf', 'filter.lever_arm_states': True},
     'lever_arm_states is not available'),
    ({'filter.model': 'seed001_13'}, 'doppler.enabled'),
    ({'filter.model': 'seed001_13', 'doppler.enabled': True, 'filter.lever_arm_states': True}, 'Doppler rows'),
    ({'filter.model': 'seed001_13', 'doppler.enabled': True, 'filter.algorithm': 'stf_multiple'},
     'mix the LDV and Doppler'),
    ({'filter.model': 'seed004'}, 'model'),
    ({'filter.lever_arm_treatment': 'magic'}, 'lever_arm_treatment'),
    ({'filter.flexure_tau_s': [3.0, 0.0, 3.0]}, 'flexure'),
    ({'filter.butterworth_cutoff_hz': 0.0}, 'butterworth_cutoff_hz'),
])
def test_invalid_combinations_are_refused_with_a_message(overrides, message):
    with pytest.raises(ConfigError, match=message) as err:
        scenario.load('catapult_paper', overrides)
    assert 'filter' in str(err.value)


SEED001_FLIGHT = ('climb duration_s=20 climb_rate_mps=5 speed_mps=60; level duration_s=10; '
                  'turn duration_s=60 bank_deg=30')


@pytest.mark.parametrize('seed', [1, 2, 3])
def test_seed001_doppler_matching_in_flight_estimates_the_radar_errors(seed):
    """inflight scenario (10 s on deck with LDV matching, launch, 20 s climb and 10 s level at
    60 m/s), seed001_13 with the Doppler radar: after the release the Doppler keeps matching,
    and by the end of the level segment (before any turn) the radar's speed offset, scale factor
    (separated by the speed change from the deck's 5 m/s to 60 m/s) and track-angle error (its
    azimuth boresight plus drift-angle error: they act alike in level flight) are within 3 sigma
    of the radar's true errors."""
    sc = scenario.load('inflight', {'duration_s': 45.0, 'doppler.enabled': True, 'filter.model': 'seed001_13',
                                    'aircraft.flight.segments': SEED001_FLIGHT}, seed=seed)
    res = pipeline.run(sc, keep_truth=False)
    e = res.estimates[-1]
    assert e.matching and res.filter.counters.doppler_updates == 450       # 45 s at 10 Hz
    radar = DopplerRadarModel(sc.doppler, seed)
    truth = np.array([radar.bias, radar.azimuth + radar.drift, radar.scale])
    assert res.filter.labels[10:13] == ('dVd', 'eps_D', 'dC')
    assert np.all(np.abs(e.x[10:13] - truth) < 3.0 * e.sigma[10:13]), (e.x[10:13], truth, e.sigma[10:13])


def test_butterworth_cutoff_above_nyquist_is_refused_by_the_engine():
    sc = scenario.load('catapult_paper', {'filter.lever_arm_treatment': 'butterworth',
                                          'filter.butterworth_cutoff_hz': 60.0})
    with pytest.raises(ConfigError, match='Nyquist'):
        TransferAlignment(sc.filter, pipeline.plane_of(sc), sc.rate_hz)


def test_lever_arm_states_recover_a_surveying_error():
    """The filter is told an arm 1.5 m off: dr = r_true - r_used = (-1, 1, -0.5) m. The ship's
    rotation (|w| ~ 0.01-0.02 rad/s at sea state 4) makes it a 1-3 cm/s velocity signal against
    5 mm/s of matching noise, so 30 s resolve it to centimetres, and the misalignment error
    returns inside 3 sigma; without the states that arm error costs tens of arcminutes."""
    ov = {'duration_s': 30.0, 'filter.lever_arm_m': [41.0, -11.0, 15.5], 'filter.lever_arm_sigma_m': 2.0}
    sc = scenario.load('deck_paper', {**ov, 'filter.lever_arm_states': True})
    res = pipeline.run(sc, keep_truth=False)
    e = res.estimates[-1]
    truth_dr = np.array([-1.0, 1.0, -0.5])
    sig_dr = e.sigma[-3:]
    assert res.filter.labels[-3:] == ('dr_x', 'dr_y', 'dr_z')
    assert np.all(np.abs(res.filter.corrections.dr - truth_dr) < 3.0 * sig_dr) and np.all(sig_dr < 0.05)
    err = e.misalignment - np.array(sc.aircraft.misalignment_arcmin) * ARCMIN
    assert np.all(np.abs(err) < 3.0 * e.misalignment_sigma)
    e0 = pipeline.run(scenario.load('deck_paper', ov), keep_truth=False).estimates[-1]
    err0 = e0.misalignment - np.array(sc.aircraft.misalignment_arcmin) * ARCMIN
    assert np.max(np.abs(err0)) > 10.0 * ARCMIN


def test_lever_arm_treatments():
    """Lever arm (40, -10, 15) m at sea state 4: C_m (w x r) is ~0.5-0.8 m/s, a hundred times the
    matching noise. Compensated, the deck alignment is within arcminutes; left in (none), it is
    read as attitude and velocity error: tens of arcminutes or worse. Seed 002's Butterworth
    (0.505 Hz) passes the ship's 0.06-0.15 Hz motion with gain > 0.99 and adds a lag: no better
    than none."""
    err = {}
    for tr in ('compensation', 'none', 'butterworth'):
        sc = scenario.load('deck_paper', {'duration_s': 10.0, 'filter.lever_arm_treatment': tr})
        e = pipeline.run(sc, keep_truth=False).estimates[-1]
        err[tr] = np.max(np.abs(e.misalignment - np.array(sc.aircraft.misalignment_arcmin) * ARCMIN))
    assert err['compensation'] < 1.0 * ARCMIN
    assert err['none'] > 10.0 * ARCMIN and err['butterworth'] > 10.0 * ARCMIN


@pytest.mark.parametrize('algorithm,shape', [('stf', ()), ('stf_multiple', (15,)), ('fading_tested', ()),
                                              ('combined', ())])
def test_fading_factors_reach_the_outputs(algorithm, shape):
    sc = scenario.load('catapult_paper', {'duration_s': 12.0, 'aircraft.catapult.launch_time_s': 8.0,
                                    'filter.algorithm': algorithm, 'filter.fading_gamma': 2.0, 'filter.stf_beta': 1.0})
    res = pipeline.run(sc, keep_truth=False)
    lam = [np.asarray(e.fading) for e in res.estimates]
    assert all(x.shape == shape and np.all(x >= 1.0) for x in lam)
    assert 'fading' in res.filter.diagnostics().filter
    assert max(float(np.max(x)) for x in lam) > 1.0          # low beta / gamma: they fade at least once
