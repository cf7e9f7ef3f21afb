"""The delay state's and rate matching's inputs at a match (estimation/delay_inputs.py): the
spot's acceleration from the slave's velocity change while parked, from two master samples
once moving, or from the spot's fit; the rates over the interval that ends at the match."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.delay_inputs import DelayInputs, interval_containing
from alignment_core.estimation.outputs import Counters
from alignment_core.estimation.reference_force import SpotAcceleration
from alignment_core.estimation.reference_velocity import Reference
from alignment_core.samples import MasterSample

MS = 1_000_000
H = 0.01


def _inputs(**cfg) -> tuple[DelayInputs, Counters]:
    counters = Counters()
    return DelayInputs(FilterConfig(**cfg), 100.0, 300 * MS, counters), counters


def _master(t_ns: int, v_b: np.ndarray, w_b: np.ndarray) -> MasterSample:
    return MasterSample(t_ns=t_ns, p_w=np.zeros(3), q_nb=np.array([0.0, 0.0, 0.0, 1.0]), v_b=v_b, w_b=w_b)


def _ref(c_m: np.ndarray, r: np.ndarray, moving: bool, v_rel: np.ndarray | None = None) -> Reference:
    v_rel = np.zeros(3) if v_rel is None else v_rel
    return Reference(c_m=c_m, r=r, v_rel=v_rel, u_n=np.zeros(3), v_ref=np.zeros(3), moving=moving)


def _live(w_ie: np.ndarray, w_en: np.ndarray) -> SimpleNamespace:
    return SimpleNamespace(ins=SimpleNamespace(w_ie=w_ie, w_en=w_en))


def test_parked_the_spots_acceleration_is_the_slaves_velocity_change_over_its_interval():
    """A constant acceleration a over 10 ms IMU intervals changes the nav velocity by a h in each:
    the match at an interval's end, or at a time inside one (a jittered master stamp), gets a."""
    a = np.array([0.3, -0.2, 0.05])
    d, _ = _inputs(master_delay_state=True)
    for k in range(1, 6):
        d.record_interval(k * 10 * MS, H, np.zeros(3), a * H)
    ref = _ref(np.eye(3), np.zeros(3), moving=False)
    for t_v in (50 * MS, 37 * MS):
        _, a_n, rate = d.at_match(_live(np.zeros(3), np.zeros(3)), t_v, _master(t_v, np.zeros(3), np.zeros(3)), ref,
                                  None, np.zeros(3))
        np.testing.assert_allclose(a_n, a, rtol=1e-14, atol=0.0)
        assert rate is None                     # not rate matching


def test_moving_the_spots_acceleration_is_the_master_velocities_difference():
    """Moving, the spot's velocity C_m (v_b + w_b x r) + v_rel from two master samples 20 ms
    apart: a ship turning steadily (the same C_m here, the same rate and arm) moves the spot by
    the master velocity's change alone, so a_n = C_m (v_b2 - v_b1) / 0.02 s."""
    rng = np.random.default_rng(1)
    d, _ = _inputs(master_delay_state=True)
    c_m = Rotation.from_euler('zyx', [0.4, 0.02, -0.03]).as_matrix()
    r, w_b, v_rel = np.array([12.0, -3.0, 8.0]), np.array([0.01, -0.02, 0.005]), np.array([0.2, 0.0, 0.0])
    v1 = rng.normal(0.0, 5.0, 3)
    dv = np.array([0.02, -0.01, 0.004])
    live = _live(np.zeros(3), np.zeros(3))
    ref = _ref(c_m, r, moving=True, v_rel=v_rel)
    _, first, _ = d.at_match(live, 20 * MS, _master(20 * MS, v1, w_b), ref, None, np.zeros(3))
    assert first is None                         # no previous master sample yet
    _, a_n, _ = d.at_match(live, 40 * MS, _master(40 * MS, v1 + dv, w_b), ref, None, np.zeros(3))
    np.testing.assert_allclose(a_n, c_m @ dv / 0.02, rtol=0.0, atol=1e-12)


def test_the_spots_fit_wins_under_the_reference_option():
    """delay_acceleration 'reference': the fit's acceleration whenever it has one (a spot moving
    at constant acceleration a: its fit returns a), the slave's interval ignored."""
    a = np.array([0.1, 0.2, -0.3])
    spot = SpotAcceleration(0.5)
    for k in range(60):
        t = k * 0.01
        spot.add(k * 10 * MS, np.eye(3), a * t, np.zeros(3), np.zeros(3))
    assert spot.acceleration() is not None
    d, _ = _inputs(master_delay_state=True, delay_acceleration='reference')
    d.record_interval(600 * MS, H, np.zeros(3), np.array([9.0, 9.0, 9.0]) * H)
    _, a_n, _ = d.at_match(_live(np.zeros(3), np.zeros(3)), 600 * MS, _master(600 * MS, a * 0.6, np.zeros(3)),
                           _ref(np.eye(3), np.zeros(3), moving=False), spot, np.zeros(3))
    np.testing.assert_allclose(a_n, a, rtol=0.0, atol=1e-9)


def test_rate_inputs_need_the_previous_master_at_the_intervals_start():
    """Rate matching over the interval [t_v - h, t_v]: the gyro less its bias estimate, its angle
    w_b h, the master's nav rate averaged over the interval and its change per second, and the
    nav frame's own rate added for the inertial rate; none (counted) when the previous master
    sample did not start the interval."""
    rng = np.random.default_rng(2)
    d, counters = _inputs(rate_matching=True)
    c1 = Rotation.from_euler('z', 0.3).as_matrix()
    c2 = Rotation.from_euler('z', 0.3005).as_matrix()
    w1, w2 = rng.normal(0.0, 0.02, 3), rng.normal(0.0, 0.02, 3)
    gyro, bg = rng.normal(0.0, 0.02, 3), np.array([1e-5, -2e-5, 3e-5])
    w_ie, w_en = np.array([0.0, 5e-5, 4e-5]), np.array([-1e-7, 2e-7, 0.0])
    live = _live(w_ie, w_en)
    d.record_interval(20 * MS, H, gyro, np.zeros(3))
    d.at_match(live, 10 * MS, _master(10 * MS, np.zeros(3), w1), _ref(c1, np.zeros(3), False), None, bg)
    assert counters.rate_unmatched == 1          # no interval ends at the first match
    w_n, _, rate = d.at_match(live, 20 * MS, _master(20 * MS, np.zeros(3), w2), _ref(c2, np.zeros(3), False), None, bg)
    assert rate is not None and counters.rate_unmatched == 1
    np.testing.assert_allclose(w_n, c2 @ w2, rtol=0.0, atol=1e-18)
    np.testing.assert_allclose(rate.w_b, gyro - bg, rtol=0.0, atol=0.0)
    np.testing.assert_allclose(rate.dtheta, (gyro - bg) * H, rtol=0.0, atol=0.0)
    mean = 0.5 * (c2 @ w2 + c1 @ w1)
    np.testing.assert_allclose(rate.w_n, mean, rtol=0.0, atol=1e-18)
    np.testing.assert_allclose(rate.omega_n, mean + w_ie + w_en, rtol=0.0, atol=1e-18)
    np.testing.assert_allclose(rate.w_dot_n, (c2 @ w2 - c1 @ w1) / H, rtol=1e-12, atol=1e-18)
    assert rate.h == H
    d.record_interval(40 * MS, 2 * H, gyro, np.zeros(3))      # a 20 ms interval after a 10 ms master step
    d.at_match(live, 30 * MS, _master(30 * MS, np.zeros(3), w2), _ref(c2, np.zeros(3), False), None, bg)
    _, _, rate = d.at_match(live, 40 * MS, _master(40 * MS, np.zeros(3), w2), _ref(c2, np.zeros(3), False), None, bg)
    assert rate is None and counters.rate_unmatched == 3


def test_a_restart_forgets_the_intervals_and_the_previous_master():
    """After a bridged gap nothing ties a match to the slave's past: parked no interval, moving
    no previous master sample, so no acceleration."""
    d, _ = _inputs(master_delay_state=True)
    live = _live(np.zeros(3), np.zeros(3))
    d.record_interval(10 * MS, H, np.zeros(3), np.ones(3) * H)
    d.at_match(live, 10 * MS, _master(10 * MS, np.zeros(3), np.zeros(3)), _ref(np.eye(3), np.zeros(3), True), None,
               np.zeros(3))
    d.restart()
    for moving in (False, True):
        _, a_n, _ = d.at_match(live, 20 * MS, _master(20 * MS, np.ones(3), np.zeros(3)),
                               _ref(np.eye(3), np.zeros(3), moving), None, np.zeros(3))
        assert a_n is None
        d.restart()


@pytest.mark.parametrize('t_v, want', [(5 * MS, 10 * MS), (15 * MS, 20 * MS), (20 * MS, None), (10 * MS, None),
                                       (45 * MS, None), (0, None)])
def test_the_interval_containing_a_time_is_open_at_both_ends(t_v, want):
    """(t_end - h, t_end), open: a time at an interval's end is that interval's own match (found
    by its end), not one inside it."""
    d, _ = _inputs()
    for k in (1, 2, 3, 4):
        d.record_interval(k * 10 * MS, H, np.zeros(3), np.zeros(3))
    got = interval_containing(d.intervals, t_v)
    assert (None if got is None else got[0]) == want
