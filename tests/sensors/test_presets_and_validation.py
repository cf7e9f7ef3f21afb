"""Sensor presets load by name (explicit keys override them; an unknown name lists the known
ones) and every new sensor parameter is validated with an error that names it."""
from __future__ import annotations

import pytest

from alignment_core.config import scenario
from alignment_core.sensors.imu import ImuConfig
from alignment_core.sensors.master_ins import MasterConfig
from alignment_core.sensors.presets import IMU_PRESETS, MASTER_PRESETS
from alignment_core.validation import ConfigError


def load(**sets):
    return scenario.load('catapult_paper', {k.replace('__', '.'): v for k, v in sets.items()})


@pytest.mark.parametrize('name', sorted(IMU_PRESETS))
def test_every_imu_preset_loads_by_name(name):
    sc = scenario.from_dict({'imu': {'preset': name}})
    assert sc.imu.preset == name
    for k, v in IMU_PRESETS[name].items():
        assert getattr(sc.imu, k) == v


def test_preset_values_are_the_seed_papers():
    s1 = scenario.from_dict({'imu': {'preset': 'seed001'}}).imu
    assert (s1.gyro_bias_dph, s1.gyro_bias_instability_dph, s1.bias_corr_time_s) == (0.02, 0.01, 10800.0)
    assert (s1.accel_bias_ug, s1.accel_bias_instability_ug) == (100.0, 50.0)          # 1e-4 g, 5e-5 g
    s2 = scenario.from_dict({'imu': {'preset': 'seed002'}}).imu
    assert (s2.gyro_scale_ppm, s2.accel_scale_ppm) == (100.0, 100.0)                  # 1e-4
    s3 = scenario.from_dict({'imu': {'preset': 'seed003'}}).imu
    assert (s3.gyro_bias_dph, s3.accel_bias_ug) == (0.2, 2000.0)                      # 0.2 deg/h, 2 mg
    m = scenario.from_dict({'master': {'preset': 'seed000'}}).master
    assert (m.gyro_bias_dph, m.accel_bias_ug) == (0.001, 50.0)


def test_seed000_presets_are_todays_defaults():
    for k, v in IMU_PRESETS['seed000'].items():
        assert getattr(ImuConfig(), k) == v
    for k, v in MASTER_PRESETS['seed000'].items():
        assert getattr(MasterConfig(), k) == v


def test_explicit_keys_override_the_preset():
    sc = scenario.from_dict({'imu': {'preset': 'seed003', 'gyro_bias_dph': 0.5}},
                            {'imu.accel_bias_ug': 10.0})
    assert sc.imu.gyro_bias_dph == 0.5 and sc.imu.accel_bias_ug == 10.0
    assert sc.imu.arw_dpsh == IMU_PRESETS['seed003']['arw_dpsh']
    # a preset given by --set applies to the keys the scenario file leaves out
    sc = scenario.from_dict({'imu': {'gyro_bias_dph': 0.01}}, {'imu.preset': 'mems_store'})
    assert sc.imu.gyro_bias_dph == 0.01 and sc.imu.accel_bias_ug == 1000.0


def test_unknown_preset_lists_the_names():
    with pytest.raises(ConfigError, match=r"imu\.preset.*'seed9'.*mems_store.*seed000"):
        scenario.from_dict({'imu': {'preset': 'seed9'}})
    with pytest.raises(ConfigError, match=r"master\.preset.*ship_medium"):
        scenario.from_dict({'master': {'preset': 'nope'}})
    with pytest.raises(ConfigError, match=r"imu.*unknown preset"):      # also when built directly
        scenario.resolve({'imu': {'preset': 'nope'}})


@pytest.mark.parametrize('key, value, words', [
    ('imu.angle_quantum_arcsec', -1.0, 'angle_quantum_arcsec'),
    ('imu.velocity_quantum_mps', 2.0, 'velocity_quantum_mps'),
    ('imu.gyro_bias_rw_dphps', -0.1, 'gyro_bias_rw_dphps'),
    ('imu.gyro_g_sensitivity_dphpg', -1.0, 'gyro_g_sensitivity_dphpg'),
    ('master.model', 'kalman', "master.model: must be one of"),
    ('master.damping_ratio', 0.0, 'damping_ratio'),
    ('master.gyrocompass_tau_s', 1.0, 'gyrocompass_tau_s'),
    ('master.latency_s', -0.01, 'latency_s'),
    ('master.rate_hz', 30.0, 'master.rate_hz = 30.0 Hz must divide the scenario rate'),
    ('ldv.rate_hz', 300.0, 'ldv.rate_hz'),
    ('ldv.dropout_mean_s', 0.0, 'dropout_mean_s'),
    ('ldv.max_range_m', -5.0, 'max_range_m'),
    ('ldv.scale_ppm', -5.0, 'scale_ppm'),
    ('doppler.noise_per_speed', 0.5, 'noise_per_speed'),
    ('doppler.boresight_pitch_arcmin', 700.0, 'boresight_pitch_arcmin'),
])
def test_new_parameters_are_validated(key, value, words):
    with pytest.raises(ConfigError, match=words.replace('.', r'\.').replace('(', r'\(')):
        load(**{key.replace('.', '__'): value})


def test_damping_and_initial_state_must_agree():
    with pytest.raises(ConfigError, match="settled.*needs damping"):
        load(master__model='schuler', master__damping='none')
    sc = load(master__model='schuler', master__damping='none', master__initial='aligned')
    assert sc.master.damping == 'none'


def test_doppler_rate_checked_only_when_enabled():
    assert load(doppler__rate_hz=30.0).doppler.rate_hz == 30.0
    with pytest.raises(ConfigError, match='doppler.rate_hz'):
        load(doppler__rate_hz=30.0, doppler__enabled=True)
