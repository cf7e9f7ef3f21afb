"""The scenario's checks across sections: stamps that fit, and the filter's options against the
sensors and the aircraft it runs with (each refused at load, naming the keys, what would happen
instead: an overflow, every LDV sample rejected, a rigid mount on a moving aircraft, rate rows
never formed, a low-pass at the wrong cutoff)."""
from __future__ import annotations

import pytest

from alignment_core.config import scenario
from alignment_core.validation import ConfigError


def test_stamps_must_fit_int64_nanoseconds_and_ros_seconds():
    """start_time_s 1e12 overflowed int64 ns in the ship's stamps (OverflowError)."""
    with pytest.raises(ConfigError, match=r"^start_time_s \+ duration_s must be <= 2e\+09 s \(stamps in int64 ns and "
                                          r"a ROS header's int32 seconds, up to 2\^31 s\), got 1e\+12 \+ 68 s$"):
        scenario.load('catapult_paper', {'start_time_s': 1e12})
    with pytest.raises(ConfigError, match=r"got 2e\+09 \+ 10 s$"):
        scenario.load('deck_paper', {'start_time_s': 2e9, 'duration_s': 10.0})
    assert scenario.load('deck_paper', {'start_time_s': 1.7e9}).t0_ns == 1_700_000_000_000_000_000   # a Unix time


def test_a_filter_ldv_mode_contradicting_the_installed_ldv_is_refused():
    """Every LDV sample would be rejected as of the wrong kind (plausibility reason ldv_mode)."""
    with pytest.raises(ConfigError, match=r"^filter\.ldv_mode = beam contradicts ldv\.mode = vector: the filter "
                                          r"would reject every LDV sample"):
        scenario.load('catapult_paper', {'filter.ldv_mode': 'beam'})
    with pytest.raises(ConfigError, match=r"^filter\.ldv_mode = vector contradicts ldv\.mode = beam"):
        scenario.load('deck', {'filter.ldv_mode': 'vector'})
    assert scenario.load('deck', {'filter.ldv_mode': 'beam'}).filter.ldv_mode == 'beam'
    assert scenario.load('deck_paper', {'ldv.mode': 'beam'}).filter.ldv_mode == 'beam'    # it follows


def test_a_rigid_mount_on_an_aircraft_launched_in_the_run_is_refused():
    with pytest.raises(ConfigError, match=r"^filter\.relative_velocity zero takes the slave as rigidly tied to the "
                                          r"master's body, but the catapult moves the aircraft from 60 s "
                                          r"\(aircraft\.catapult\.launch_time_s = 60 s\), inside duration_s = 68 s: "
                                          r"use auto or ldv$"):
        scenario.load('catapult_paper', {'filter.relative_velocity': 'zero'})
    with pytest.raises(ConfigError, match=r"moves the aircraft from 55 s \(aircraft\.catapult\.launch_time_s = 60 s\)"):
        scenario.load('catapult_paper', {'filter.relative_velocity': 'zero', 'duration_s': 58.0,
                                         'aircraft.catapult.holdback_s': 5.0,
                                         'aircraft.catapult.holdback_stretch_m': 0.1})
    with pytest.raises(ConfigError, match=r"but aircraft\.flight\.start is airborne"):
        scenario.load('catapult_paper', {'filter.relative_velocity': 'zero', 'aircraft.flight.start': 'airborne',
                                         'aircraft.catapult.enabled': False})


def test_a_rigid_mount_is_kept_where_the_aircraft_stays_put():
    assert scenario.load('rigid').filter.relative_velocity == 'zero'
    assert scenario.load('deck_paper', {'filter.relative_velocity': 'zero'}).filter.relative_velocity == 'zero'
    parked = scenario.load('catapult_paper', {'filter.relative_velocity': 'zero', 'duration_s': 60.0})
    assert parked.moves_on_deck() == ''         # the launch at the run's last sample: it has not moved yet


@pytest.mark.parametrize('overrides,words', [
    ({'master.rate_hz': 50.0}, r"needs the master at the IMU rate: master\.rate_hz = 50 Hz is not rate_hz = 100 Hz"),
    ({'master.latency_jitter_s': 0.004}, r"needs master stamps on the IMU grid: master\.latency_jitter_s = 0\.004 s"),
    ({'master.latency_s': 0.015},
     r"master\.latency_s = 0\.015 s less filter\.master_latency_s = 0 s is 15000000 ns, not a multiple of the IMU "
     r"interval 10000000 ns"),
    ({'master.latency_s': 0.02, 'filter.master_latency_s': 0.025}, r"is -5000000 ns, not a multiple"),
])
def test_rate_matching_is_refused_where_its_rows_are_never_formed(overrides, words):
    """matching.py forms rate rows only for a master valid at the end of an IMU interval whose
    previous sample is one IMU interval earlier (else counted rate_unmatched, every update)."""
    with pytest.raises(ConfigError, match=rf"^filter\.rate_matching .*{words}.*\(its rate rows need the master valid"):
        scenario.load('deck_paper', {'filter.rate_matching': True, **overrides})


@pytest.mark.parametrize('overrides', [{}, {'master.rate_hz': 100.0}, {'master.latency_s': 0.02},
                                       {'master.latency_s': 0.025, 'filter.master_latency_s': 0.025}])
def test_rate_matching_on_the_imu_grid_loads(overrides):
    assert scenario.load('deck_paper', {'filter.rate_matching': True, **overrides}).filter.rate_matching


def test_a_butterworth_low_pass_stepped_slower_than_designed_is_refused():
    with pytest.raises(ConfigError, match=r"^filter\.lever_arm_treatment butterworth: its low-pass is designed at "
                                          r"the IMU rate \(rate_hz = 100 Hz\) but stepped once per master match, so "
                                          r"master\.rate_hz = 25 Hz would move its cutoff from 0\.505 Hz to "
                                          r"0\.12625 Hz"):
        scenario.load('catapult_paper', {'filter.lever_arm_treatment': 'butterworth', 'master.rate_hz': 25.0})
    sc = scenario.load('catapult_paper', {'filter.lever_arm_treatment': 'butterworth', 'master.rate_hz': 100.0})
    assert sc.filter.lever_arm_treatment == 'butterworth'
