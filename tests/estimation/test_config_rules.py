"""FilterConfig refuses at load what would otherwise break a run deep in the engine: an output
period below 1 ns, a master attitude prior of zero, a lever arm off any ship, and a fading
filter with a beam LDV (docs/engine.md's matrix)."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.config import FilterConfig
from alignment_core.validation import ConfigError, build


def _filter(**values: object) -> FilterConfig:
    return build(FilterConfig, values, 'filter')


def test_an_output_period_below_one_nanosecond_is_refused():
    """engine.py counts the output period in whole ns: 1e12 Hz rounded it to 0 (ZeroDivisionError
    at the first master sample); a rate above the master's is kept (every master sample)."""
    with pytest.raises(ConfigError, match=r"^filter: output_rate_hz must be <= 1e\+09 Hz .*got 1000000000000.0$"):
        _filter(output_rate_hz=1e12)
    assert _filter(output_rate_hz=1e9).output_rate_hz == 1e9


@pytest.mark.parametrize('key', ['master_tilt_sigma_arcmin', 'master_heading_sigma_arcmin'])
@pytest.mark.parametrize('model', ['vm15', 'seed003_24'])
def test_master_attitude_priors_must_be_positive_where_the_model_has_those_states(key, model):
    for value in (0.0, -0.5):
        with pytest.raises(ConfigError, match=rf"^filter: {key} must be > 0 \(the prior of {model}'s master "
                                              rf"attitude states\), got {value}$"):
            _filter(model=model, **{key: value})


def test_master_attitude_priors_unused_may_be_zero_but_not_negative():
    assert _filter(model='vm12', master_tilt_sigma_arcmin=0.0).master_tilt_sigma_arcmin == 0.0
    with pytest.raises(ConfigError, match=r"master_heading_sigma_arcmin must be >= 0, got -1.0"):
        _filter(model='vm12', master_heading_sigma_arcmin=-1.0)


@pytest.mark.parametrize('arm', [[1e4, 0.0, 0.0], [250.0, 250.0, 0.0], [0.0, 0.0, -160.0]])
def test_the_filter_lever_arm_is_bounded_as_the_aircraft_lever_arm_plus_a_survey_error(arm):
    """The aircraft's arm is bounded at 200 m horizontally and 50 m vertically; the filter is told
    that arm plus a survey error (sigma up to 10 m), so its bound is 100 m wider: an arm near the
    aircraft's bound loads whatever the seed, one far beyond it (1e4 m diverged) does not."""
    with pytest.raises(ConfigError, match=r"^filter: lever_arm_m out of range \(\|horizontal\| <= 300 m, "
                                          r"\|z\| <= 150 m\)"):
        scenario.load('catapult_paper', {'filter.lever_arm_m': arm})
    with pytest.raises(ConfigError, match=r"^aircraft: lever_arm_m out of range"):
        scenario.load('catapult_paper', {'aircraft.lever_arm_m': arm})
    assert _filter(lever_arm_m=(230.0, 0.0, 90.0)).lever_arm_m == (230.0, 0.0, 90.0)


@pytest.mark.parametrize('algorithm', ['stf', 'stf_multiple', 'fading_tested', 'combined'])
def test_fading_filters_with_a_beam_ldv_are_refused(algorithm):
    """deck_paper, ldv.mode beam, 30 s, seeds 1-3: these diverge (tens of degrees, stf 57 deg at
    0.5 s on seed 1) with the level OK, where kf, carlson, ud, ekf, ukf, ckf end within 0.04 deg."""
    with pytest.raises(ConfigError, match=rf"^filter: algorithm {algorithm} cannot run with ldv_mode beam: its "
                                          rf"fading factor inflates the whole covariance"):
        scenario.load('deck_paper', {'ldv.mode': 'beam', 'filter.algorithm': algorithm})
    assert scenario.load('deck_paper', {'filter.algorithm': algorithm}).filter.algorithm == algorithm


def test_a_fixed_fading_factor_above_one_with_a_beam_ldv_is_refused():
    """fading_factor 1 is the kf; 1.01 diverges within 30 s, 1.001 reaches 1 deg at 300 s."""
    with pytest.raises(ConfigError, match=r"algorithm fading cannot run with ldv_mode beam.*\(or fading_factor 1, "
                                          r"got 1.001\)$"):
        scenario.load('deck_paper', {'ldv.mode': 'beam', 'filter.algorithm': 'fading', 'filter.fading_factor': 1.001})
    assert scenario.load('deck_paper', {'ldv.mode': 'beam', 'filter.algorithm': 'fading'}).filter.fading_factor == 1.0


@pytest.mark.parametrize('algorithm', ['stf', 'stf_multiple'])
def test_a_strong_tracking_filter_that_never_fades_runs_a_beam_ldv(algorithm):
    """stf_lambda_max 1 caps the fading factor at 1: the STF is then the Kalman filter (its factor is
    what sets them apart), so a beam LDV is no reason to refuse it; 30 s of deck_paper on a beam give
    the kf's estimate bit for bit. A cap above 1 is refused, naming the way out."""
    with pytest.raises(ConfigError, match=rf"algorithm {algorithm} cannot run with ldv_mode beam.*"
                                          r"\(or stf_lambda_max 1, got 1.2\)$"):
        scenario.load('deck_paper', {'ldv.mode': 'beam', 'filter.algorithm': algorithm, 'filter.stf_lambda_max': 1.2})
    base = {'ldv.mode': 'beam', 'duration_s': 30.0}
    kf = scenario.load('deck_paper', {**base, 'filter.algorithm': 'kf'})
    stf = scenario.load('deck_paper', {**base, 'filter.algorithm': algorithm, 'filter.stf_lambda_max': 1.0})
    inp = pipeline.simulate(kf)
    a, b = pipeline.align(kf, inp).outputs[-1], pipeline.align(stf, inp).outputs[-1]
    np.testing.assert_array_equal(a.misalignment, b.misalignment)
    np.testing.assert_array_equal(a.misalignment_sigma, b.misalignment_sigma)


@pytest.mark.parametrize('algorithm', ['kf', 'carlson', 'ud', 'ekf', 'ukf', 'ckf'])
def test_the_other_algorithms_run_a_beam_ldv(algorithm):
    assert scenario.load('deck_paper', {'ldv.mode': 'beam', 'filter.algorithm': algorithm}).filter.ldv_mode == 'beam'


@pytest.mark.parametrize('key', ['init_attitude_sigma_deg', 'init_yaw_sigma_deg'])
def test_a_prior_less_certain_than_the_absurd_bound_is_refused(key):
    """The published view holds any estimate whose misalignment sigma exceeds misalignment_max_deg
    (publication.py): a prior at or above it would hold every output from the start."""
    with pytest.raises(ConfigError, match=r"^filter: init_attitude_sigma_deg / init_yaw_sigma_deg \(30.0\) must be "
                                          r"below misalignment_max_deg \(30.0\)"):
        _filter(**{key: 30.0})
    assert _filter(**{key: 29.0}).misalignment_max_deg == 30.0
