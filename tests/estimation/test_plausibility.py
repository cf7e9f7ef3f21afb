"""Input plausibility (estimation/plausibility.py): a master quaternion is normalised within
filter.quaternion_norm_tolerance of unit norm and rejected beyond it; values beyond the sensor's
or the vehicle's range are rejected; a sample stamped far ahead of every other stream is the
outlier (rejected), not the samples after it; each rejection is counted by reason."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.outputs import Counters
from alignment_core.estimation.plausibility import InputGate, Limits, imu_reason, master_check
from alignment_core.samples import DopplerSample, ImuSample, LdvSample, MasterSample
from alignment_core.units import DEG, G0
from alignment_core.validation import ConfigError

CFG = FilterConfig()
LIM = Limits.of(CFG)
Q = Rotation.from_euler('xyz', [0.01, -0.02, 0.5]).as_quat()
Z3 = np.zeros(3)


def _master(q=Q, t=1):
    return MasterSample(t_ns=t, p_w=np.array([100.0, 50.0, 0.0]), q_nb=np.asarray(q, dtype=float),
                        v_b=np.array([5.0, 0.0, 0.0]), w_b=np.array([0.01, 0.0, 0.0]))


def _gate(cfg=CFG):
    c = Counters()
    return InputGate(cfg, c, ('imu', 'ldv', 'master')), c


@pytest.mark.parametrize('scale', [1.0 + 5e-4, 1.0 - 9e-4])
def test_a_quaternion_within_the_tolerance_is_normalised_to_the_same_rotation(scale):
    """q and s q are the same rotation (a quaternion's scale carries none); the normalised one is
    scipy's unit quaternion of that rotation, to rounding."""
    s, why = master_check(_master(Q * scale), LIM)
    assert why == '' and s is not None
    np.testing.assert_allclose(s.q_nb, Rotation.from_quat(Q * scale).as_quat(), rtol=0, atol=1e-15)
    assert abs(np.linalg.norm(s.q_nb) - 1.0) < 1e-15


def test_a_unit_quaternion_is_passed_on_as_given():
    m = _master()
    s, _ = master_check(m, LIM)
    assert s is m                                   # the same object: bit for bit the clean input


@pytest.mark.parametrize('q', [2.0 * Q, np.zeros(4), Q * (1.0 + 2e-3)])
def test_a_quaternion_off_unit_norm_is_rejected(q):
    gate, c = _gate()
    assert gate.check('master', _master(q)) is None
    assert c.rejected_quaternion == 1 and gate.last_rejection == 'quaternion'


def test_imu_beyond_full_scale_is_rejected_per_axis():
    """400 deg/s and 16 g per axis (filter.imu_gyro_range_dps / imu_accel_range_g)."""
    ok = ImuSample(1, np.array([399.0 * DEG, 0.0, 0.0]), np.array([0.0, 0.0, 15.9 * G0]))
    assert imu_reason(ok, LIM) == ''
    assert imu_reason(dataclasses.replace(ok, gyro=np.array([0.0, -401.0 * DEG, 0.0])), LIM) == 'range'
    assert imu_reason(dataclasses.replace(ok, accel=np.array([16.1 * G0, 0.0, 0.0])), LIM) == 'range'
    assert imu_reason(dataclasses.replace(ok, accel=np.array([1e30, 0.0, 0.0])), LIM) == 'range'
    huge = np.array([1e308, 1e308, 0.0])             # finite: out of range, though its sum overflows
    assert imu_reason(dataclasses.replace(ok, accel=huge), LIM) == 'range'
    assert imu_reason(dataclasses.replace(ok, accel=np.array([np.nan, 0.0, 0.0])), LIM) == 'nonfinite'


@pytest.mark.parametrize('field, value', [('v_b', [101.0, 0.0, 0.0]), ('v_b', [1e200, 1e200, 0.0]),
                                          ('w_b', [0.0, 0.0, 61.0 * DEG]), ('p_w', [1e30, 0.0, 0.0])])
def test_master_values_beyond_the_ships_range_are_rejected(field, value):
    """|v| 100 m/s, |w| 60 deg/s, |p| 1e7 m; 1e200 components do not overflow the norm (hypot)."""
    s, why = master_check(dataclasses.replace(_master(), **{field: np.array(value)}), LIM)
    assert s is None and why == 'range'


def test_ldv_and_doppler_ranges_and_invalid_samples():
    assert InputGate(CFG, Counters(), ('ldv',)).check('ldv', LdvSample(1, np.array([151.0, 0, 0]), 0.01, True)) is None
    invalid = LdvSample(1, np.full(3, np.nan), np.nan, False)       # out of the beam: no numbers to check
    assert InputGate(CFG, Counters(), ('ldv',)).check('ldv', invalid) is invalid
    g = InputGate(CFG, Counters(), ('doppler',))
    assert g.check('doppler', DopplerSample(1, np.array([401.0, 0, 0]), 0.1, True)) is None
    radar_off = DopplerSample(2, Z3, np.nan, False)                # invalid: its NaN sigma is no fault
    assert g.check('doppler', radar_off) is radar_off


def _feed(gate, stream, t):
    s = {'imu': ImuSample(t, Z3, Z3), 'master': _master(t=t), 'ldv': LdvSample(t, Z3, 0.01, True)}[stream]
    ok = gate.check(stream, s) is not None
    if ok:
        gate.accepted(stream, t)
    return ok


def test_a_sample_far_ahead_of_every_other_stream_is_the_outlier_not_the_ones_after_it():
    gate, c = _gate()
    ms = 1_000_000
    for k in range(1, 200):
        for st in ('imu', 'ldv', 'master'):
            assert _feed(gate, st, k * 10 * ms)
    assert not _feed(gate, 'imu', 100_000 * ms + 2000 * ms)        # 100 s ahead
    assert c.rejected_future_stamp == 1 and gate.last_rejection == 'future_stamp'
    assert _feed(gate, 'imu', 2000 * ms) and _feed(gate, 'imu', 2010 * ms)   # the stream goes on


def test_a_stream_resuming_after_a_silence_is_not_an_outlier():
    """The other streams moved on meanwhile: the resumed stamp is not ahead of them."""
    gate, c = _gate()
    s = 1_000_000_000
    for st in ('imu', 'ldv', 'master'):
        _feed(gate, st, 1 * s)
    for k in range(2, 8):
        _feed(gate, 'imu', k * s)
        _feed(gate, 'ldv', k * s)
    assert gate.waiting_for() == ('master',)                         # nothing for 6 s of stamps
    assert _feed(gate, 'master', 7 * s) and c.rejected_future_stamp == 0
    assert gate.waiting_for() == ()


def test_a_stream_that_lags_on_arrival_but_keeps_delivering_is_not_waited_for():
    """The LDV arrives 3 s of stamps behind the IMU (more than silence_warn_s) at every step:
    it is behind, not silent. One that stops delivering is waited for once the others ran more
    than silence_warn_s (1 s) of stamps past its last arrival."""
    gate, _ = _gate()
    ms = 1_000_000
    for k in range(1, 600):
        _feed(gate, 'imu', k * 10 * ms)
        _feed(gate, 'master', k * 10 * ms)
        if k > 300:
            _feed(gate, 'ldv', (k - 300) * 10 * ms)
        if k > 300:
            assert gate.waiting_for() == ()
    for k in range(600, 700):
        _feed(gate, 'imu', k * 10 * ms)
        _feed(gate, 'master', k * 10 * ms)
    assert gate.waiting_for() == ()                                 # 1.0 s of stamps: not yet
    _feed(gate, 'imu', 700 * 10 * ms)
    assert gate.waiting_for() == ('ldv',)


def test_the_lead_allowed_grows_by_the_known_latencies():
    cfg = dataclasses.replace(CFG, master_latency_s=0.5)
    assert Limits.of(cfg).future_ns == int(1.5e9)


@pytest.mark.parametrize('key, value', [('quaternion_norm_tolerance', 0.0), ('imu_gyro_range_dps', -1.0),
                                        ('gap_bridge_factor', 1.2), ('consistency_window_updates', 5),
                                        ('launch_felt_fraction', 1.5), ('misalignment_max_deg', 200.0)])
def test_invalid_limits_are_refused_with_their_key(key, value):
    with pytest.raises(ConfigError, match=key):
        dataclasses.replace(CFG, **{key: value}).validate()
