"""A spectral ship given one edge of its frequency band: the other one is automatic (the default
band of the peak period), and the band must be non-empty for every peak period the sea can have;
refused at load, where the simulation raised 'frequency band must satisfy 0 < omega_min < omega_max'."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core.config import scenario
from alignment_core.rng import stage_rng
from alignment_core.ship import sea_state, wave_spectrum
from alignment_core.validation import ConfigError

SPECTRAL = {'ship.mode': 'spectral'}


def test_omega_min_above_the_automatic_omega_max_is_refused():
    with pytest.raises(ConfigError, match=r"^ship: omega_min = 5\.0 rad/s must be below omega_max, automatic here: "
                                          r"4\.284 rad/s \(the default band's upper edge at Tp 8\.8 s, sea_state 4\); "
                                          r"give omega_max too$"):
        scenario.load('catapult_paper', {**SPECTRAL, 'ship.omega_min': 5.0})


def test_omega_max_below_the_automatic_omega_min_is_refused():
    with pytest.raises(ConfigError, match=r"^ship: omega_max = 0\.1 rad/s must be above omega_min, automatic here: "
                                          r"0\.15 rad/s \(the default band's lower edge at Tp 8\.8 s, sea_state 4\); "
                                          r"give omega_min too$"):
        scenario.load('catapult_paper', {**SPECTRAL, 'ship.omega_max': 0.1})


@pytest.mark.parametrize('key', ['ship.omega_min', 'ship.omega_max'])
@pytest.mark.parametrize('value', [0.05, 0.1, 0.149, 0.151, 2.0, 4.28, 4.29, 6.0])
def test_a_band_loads_exactly_when_the_sea_can_be_synthesised(key, value):
    """The load's verdict is synthesize's, for either edge given alone (no draw: sea state 4)."""
    sea = sea_state.resolve(4)
    lo, hi = (value, 0.0) if key == 'ship.omega_min' else (0.0, value)
    try:
        wave_spectrum.synthesize('ittc', sea.hs_m, sea.tp_s, 0.0, stage_rng(1, 'ship_waves'),
                                 n_frequencies=4, n_directions=1, omega_min=lo, omega_max=hi)
        synthesised = True
    except ValueError:
        synthesised = False
    try:
        scenario.load('catapult_paper', {**SPECTRAL, 'ship.sea_state': 4, key: value})
        loaded = True
    except ConfigError:
        loaded = False
    assert loaded == synthesised


def test_a_drawn_sea_is_checked_over_its_whole_peak_period_range():
    """Sea state 4 draws Tp in [6.1, 15.2] s: the automatic omega_max falls to 2.5 rad/s at the
    longest, so omega_min 3 fails for some seeds and is refused for all."""
    sc = scenario.load('catapult_paper', {**SPECTRAL, 'ship.omega_min': 3.0})
    assert sc.ship.peak_periods() == (8.8, 8.8)
    with pytest.raises(ConfigError, match=r"omega_min = 3\.0 rad/s must be below omega_max, automatic here: 2\.5 "
                                          r"rad/s \(the default band's upper edge at Tp 15\.2 s"):
        scenario.load('catapult_paper', {**SPECTRAL, 'ship.omega_min': 3.0, 'ship.sea_draw': True})
    tp = [sea_state.resolve(4, rng=stage_rng(seed, 'ship_sea')).tp_s for seed in range(1, 200)]
    lo, hi = scenario.load('catapult_paper', {**SPECTRAL, 'ship.sea_draw': True}).ship.peak_periods()
    assert (lo, hi) == (6.1, 15.2) and lo <= min(tp) and max(tp) <= hi
    assert any(wave_spectrum.default_band(t)[1] <= 3.0 for t in tp) and np.ptp(tp) > 5.0


def test_paper_mode_ignores_the_band():
    assert scenario.load('catapult_paper', {'ship.omega_min': 5.0}).ship.omega_min == 5.0
