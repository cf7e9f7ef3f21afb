"""Scenario loading: validation names the bad key, --set overrides parse as YAML scalars."""
from __future__ import annotations

import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.validation import ConfigError


def test_catapult_defaults_are_seed_000():
    sc = scenario.load('catapult_paper')
    assert sc.aircraft.misalignment_arcmin == (15.0, -10.0, -30.0)
    assert sc.aircraft.catapult.enabled and sc.aircraft.catapult.accel_g == 2.0
    assert sc.aircraft.catapult.stroke_s == 3.0
    # timing: 68 s at 100 Hz, both ends included; stamps start above zero
    assert sc.dt_ns == 10_000_000
    assert sc.n_samples == 6801
    assert sc.t0_ns == 1_000_000_000


def test_unknown_key_names_dotted_path():
    with pytest.raises(ConfigError, match=r'ship\.sea_stat\b'):
        scenario.load('catapult_paper', {'ship.sea_stat': 5})
    with pytest.raises(ConfigError, match=r'aircraft\.catapult\.acel_g'):
        scenario.load('deck_paper', {'aircraft.catapult.acel_g': 2.0})


def test_out_of_range_sea_state():
    with pytest.raises(ConfigError, match='sea_state'):
        scenario.load('catapult_paper', {'ship.sea_state': 12})


def test_wrong_type_names_key():
    with pytest.raises(ConfigError, match=r'ship\.sea_state'):
        scenario.load('catapult_paper', {'ship.sea_state': 'four'})
    with pytest.raises(ConfigError, match=r'aircraft\.lever_arm_m'):
        scenario.load('catapult_paper', {'aircraft.lever_arm_m': [1.0, 2.0]})


def test_parse_overrides_yaml_scalars():
    ov = scenario.parse_overrides(['ship.sea_state=6', 'aircraft.lever_arm_m=[60.0,-15.0,20.0]',
                                   'aircraft.catapult.enabled=false', ' seed = 7 '])
    assert ov == {'ship.sea_state': 6, 'aircraft.lever_arm_m': [60.0, -15.0, 20.0],
                  'aircraft.catapult.enabled': False, 'seed': 7}
    assert isinstance(ov['ship.sea_state'], int)
    sc = scenario.load('catapult_paper', ov)
    assert sc.ship.sea_state == 6 and sc.seed == 7
    assert sc.aircraft.lever_arm_m == (60.0, -15.0, 20.0)
    # the filter and the LDV follow the deck spot unless told otherwise
    assert sc.filter.lever_arm_m == (60.0, -15.0, 20.0)
    assert sc.ldv.origin_m == (60.0, -15.0, 20.0)
    with pytest.raises(ConfigError):
        scenario.parse_overrides(['ship.sea_state'])


def test_seed_argument_overrides():
    assert scenario.load('deck_paper', seed=42).seed == 42


def test_start_time_zero_rejected():
    with pytest.raises(ConfigError, match='start_time_s'):
        scenario.load('catapult_paper', {'start_time_s': 0.0})


def test_unknown_scenario_name():
    with pytest.raises(ConfigError, match='unknown scenario'):
        scenario.load('no_such_scenario')


@pytest.mark.parametrize('key,value', [('aircraft.catapult.launch_time_s', 60.005),
                                       ('aircraft.catapult.stroke_s', 3.0025)])
def test_catapult_events_off_the_sample_grid_rejected(key, value):
    """The stroke must start and end on a 100 Hz sample (no interval straddles the jump in
    acceleration). Rejected with the key named, before any sample is produced."""
    with pytest.raises(ConfigError, match=r'launch_time_s|launch \+ stroke'):
        sc = scenario.load('catapult_paper', {key: value})
        pipeline.SlaveImuStage(sc)
