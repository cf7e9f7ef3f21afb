"""FADS configuration: the fault syntax parses into its faults, every malformed fault and
out-of-range setting is refused with a message naming it, and the scenario section builds
with its nested day and wind."""
from __future__ import annotations

import pytest

from alignment_core.air_data.day_offsets import DayOffsets
from alignment_core.air_data.port_layout import EpsilonCalibration, PortGeometry
from alignment_core.sensors.fads_config import FadsConfig, FadsFault, parse_faults
from alignment_core.validation import ConfigError, build


def test_the_example_fault_list_parses():
    faults = parse_faults("blocked port=2 at_s=500; bias_step port=1 at_s=300 pa=200\n"
                          "noise port=3 at_s=100 factor=5", 5)
    assert faults == (FadsFault('blocked', 2, 500.0), FadsFault('bias_step', 1, 300.0, pa=200.0),
                      FadsFault('noise', 3, 100.0, factor=5.0))
    assert parse_faults('', 5) == () and parse_faults(' ; ;', 5) == ()


@pytest.mark.parametrize('text, message', [
    ("leak port=1 at_s=3", "unknown fault 'leak'"),
    ("blocked port=1", "blocked needs at_s"),
    ("bias_step port=1 at_s=3", "bias_step needs pa"),
    ("blocked port=1 at_s=3 pa=2", "unknown key 'pa' for blocked"),
    ("blocked port=5 at_s=3", "port must be an integer in [0, 4], got 5"),
    ("blocked port=1.5 at_s=3", "port must be an integer in [0, 4], got 1.5"),
    ("blocked port=-1 at_s=3", "port must be an integer in [0, 4]"),
    ("blocked port=one at_s=3", "port must be a number, got 'one'"),
    ("blocked port=1 at_s", "expected key=value, got 'at_s'"),
    ("blocked port=1 at_s=", "expected key=value"),
    ("blocked port=1 port=2 at_s=3", "port given twice"),
    ("blocked port=1 at_s=-1", "at_s must be in [0, 1e7] s"),
    ("blocked port=1 at_s=nan", "at_s must be finite"),
    ("noise port=1 at_s=3 factor=-2", "factor must be in [0, 1e4]"),
    ("blocked port=1 at_s=3; blocked port=1 at_s=5", "faults[1] ('blocked port=1 at_s=5'): port 1 is blocked twice"),
])
def test_malformed_faults_are_refused_with_their_position(text, message):
    with pytest.raises(ConfigError, match='faults\\[') as err:
        parse_faults(text, 5)
    assert message in str(err.value)


def test_defaults_are_the_port_models_and_valid():
    cfg = FadsConfig()
    cfg.validate()
    assert cfg.geometry == PortGeometry() and cfg.epsilon == EpsilonCalibration()
    assert (cfg.enabled, cfg.rate_hz, cfg.sigma_pa) == (False, 1.0, 20.0)
    assert (cfg.noise_correlation, cfg.scale_sigma) == (0.5, 0.0)
    assert (cfg.lag_s_sea_level, cfg.min_airspeed_mps, cfg.bias_sigma_pa, cfg.bias_pa) == (0.02, 10.0, 0.0, ())
    assert cfg.period_ns == 1_000_000_000


@pytest.mark.parametrize('kwargs, message', [
    (dict(rate_hz=0.0), "rate_hz must be in (0, 1000]"),
    (dict(rate_hz=2000.0), "rate_hz must be in (0, 1000]"),
    (dict(noise_correlation=1.0), "noise_correlation must be in [0, 1)"),
    (dict(sigma_pa=-1.0), "sigma_pa must be in [0, 1e5]"),
    (dict(scale_sigma=0.6), "scale_sigma must be in [0, 0.5]"),
    (dict(bias_pa=(1.0, 2.0)), "bias_pa needs 5 values"),
    (dict(cone_deg=(0.0, 30.0, 30.0)), "cone_deg and clock_deg need the same length"),
    (dict(eps=(0.0,) * 6), "mach and eps need the same length"),
    (dict(lag_s_sea_level=-0.1), "lag_s_sea_level must be in [0, 10]"),
    (dict(day=DayOffsets(delta_t_k=100.0)), "delta_t_k must be in [-80, 80] K"),
    (dict(faults="blocked port=7 at_s=1"), "port must be an integer in [0, 4]"),
])
def test_bad_settings_are_refused(kwargs, message):
    with pytest.raises(ConfigError) as err:
        FadsConfig(**kwargs).validate()
    assert message in str(err.value)


def test_the_scenario_section_builds_nested_day_and_wind():
    cfg = build(FadsConfig, {'enabled': True, 'rate_hz': 10, 'bias_pa': [1, 2, 3, 4, 5],
                             'day': {'delta_t_k': 10}, 'wind': {'mean_enu_mps': [5, 0, 0], 'severity': 'light'},
                             'faults': 'noise port=0 at_s=1 factor=2'}, 'fads')
    assert cfg.rate_hz == 10.0 and cfg.bias_pa == (1.0, 2.0, 3.0, 4.0, 5.0)
    assert cfg.day.delta_t_k == 10.0 and cfg.wind.severity == 'light'
    with pytest.raises(ConfigError, match='fads.wind.severity'):
        build(FadsConfig, {'wind': {'severity': 'awful'}}, 'fads')
    with pytest.raises(ConfigError, match='unknown key.*fads.sigma'):
        build(FadsConfig, {'sigma': 3}, 'fads')
    with pytest.raises(ConfigError, match="fads: faults\\[0\\]"):
        build(FadsConfig, {'faults': 'blocked port=1'}, 'fads')
