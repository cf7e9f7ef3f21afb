"""IMU gaps in the engine: a gap longer than filter.gap_bridge_factor intervals is never one
strapdown step. The covariance is propagated over it with the process noise, the outputs are
flagged 'gap' (WARN; ERROR beyond filter.gap_error_s, the last good estimate held) until a NIS
window after it passes, and parked on the deck the slave is carried across by the master (the
aircraft rides the ship rigidly: its attitude relative to the master's does not change)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from support.engine_feed import feed_in_order

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.anchoring import bridge_covariance, dead_reckoned
from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.filter_factory import make_filter
from alignment_core.estimation.health import ERROR, OK, WARN
from alignment_core.estimation.models import Propagation, make_model
from alignment_core.geometry import earth
from alignment_core.navigation.strapdown import NavState
from alignment_core.units import ARCMIN, DEG, DPH, UG

SC = scenario.load('catapult_paper', {'duration_s': 12.0, 'aircraft.catapult.launch_time_s': 8.0}, seed=7)
START = 300                      # the gap starts at 3 s


@pytest.fixture(scope='module')
def runs():
    inp = pipeline.simulate(SC)
    return inp, pipeline.align(SC, inp)


def _with_gap(inp, seconds: float):
    """The inputs in the graph's publishing order with `seconds` of IMU samples left out."""
    drop = set(range(START, START + int(round(seconds * SC.rate_hz))))
    events = []
    for k in range(len(inp.ships)):
        if k > 0 and k - 1 not in drop:
            events.append(('imu', inp.imu[k - 1]))
        events += [('ldv', inp.ldv[k]), ('master', inp.master[k])]
    return feed_in_order(SC, events)


def _attitude_error(q, q_true) -> float:
    return float(np.linalg.norm((Rotation.from_quat(q) * Rotation.from_quat(q_true).inv()).as_rotvec()))


def test_a_one_second_gap_is_bridged_flagged_and_recovered(runs):
    inp, ref = runs
    f = _with_gap(inp, 1.0)
    c = f.counters
    assert c.bridged_gaps == 1 and c.imu_gaps == 1 and c.unmatched_master >= 99
    flagged = [e for e in f.outputs if 'gap' in e.flags]
    assert flagged and all(e.level == WARN and e.healthy for e in flagged)
    assert f.outputs[-1].level == OK                     # re-converged: a NIS window passed
    # the slave after the gap, against the truth: carried across by the master it keeps the
    # attitude error it had (tenths of arcmin), where one 1.01 s step left it tens of arcmin off
    t_true = {int(t): k for k, t in enumerate(inp.ships.t_ns)}
    after = [e for e in f.outputs if e.t_ns > flagged[-1].t_ns][:10]
    for e in after:
        assert _attitude_error(e.q_nb, inp.truth['q_nb'][t_true[e.t_ns]]) < 1.0 * ARCMIN
    np.testing.assert_allclose(f.outputs[-1].misalignment, ref.outputs[-1].misalignment, rtol=0, atol=0.3 * ARCMIN)


def test_a_gap_beyond_the_limit_is_an_error_until_re_converged_and_the_last_good_estimate_is_held(runs):
    inp, ref = runs
    f = _with_gap(inp, 2.5)
    err = [i for i, e in enumerate(f.outputs) if e.level == ERROR]
    assert err and all('gap' in f.outputs[i].flags and not f.outputs[i].healthy for i in err)
    assert err == list(range(err[0], err[-1] + 1))       # one stretch, then OK again
    assert f.outputs[-1].level == OK and f.healthy
    last_good = [e for e in f.published[:err[0]] if e.level == OK][-1]      # the last at OK
    for i in err:
        p = f.published[i]
        assert 'held' in p.flags and np.array_equal(p.misalignment, last_good.misalignment)
        assert np.array_equal(p.q_nb, last_good.q_nb) and p.t_ns == f.outputs[i].t_ns
    assert f.published[err[-1] + 1] is f.outputs[err[-1] + 1]
    np.testing.assert_allclose(f.outputs[-1].misalignment, ref.outputs[-1].misalignment, rtol=0, atol=0.3 * ARCMIN)


def test_a_short_gap_is_still_one_step(runs):
    """Up to gap_bridge_factor (5) intervals the step is integrated as before, counted as a gap."""
    inp, _ = runs
    f = _with_gap(inp, 0.03)
    assert f.counters.imu_gaps == 1 and f.counters.bridged_gaps == 0
    assert all(e.level == OK for e in f.outputs)


def test_the_bridged_covariance_grows_by_the_process_noise_of_the_gap():
    """Over h seconds without data, with no specific force and no rates, phi' = -C eps + w_g and
    dV' = C nabla + w_a with random-constant biases: the attitude variance grows by ARW^2 h plus
    sigma_eps^2 h^2, the velocity variance by VRW^2 h plus sigma_nabla^2 h^2 (exact: Phi = I + F h
    when F only couples the biases in)."""
    cfg = FilterConfig()
    model = make_model(cfg)
    kf = make_filter(cfg, np.zeros(model.n), model.initial_covariance(), model.kinds)
    p0 = kf.P.copy()
    zero = np.zeros(3)
    prop = Propagation(np.eye(3), zero, zero, zero, zero, 0.7, 0.0, 0.01)
    bridge_covariance(kf, model, prop, 2.0)
    h = 2.0
    arw = cfg.arw_dpsh * DEG / 60.0                      # deg/sqrt(h) -> rad/sqrt(s)
    vrw = cfg.vrw_ugpshz * UG                            # ug/sqrt(Hz) -> m/s/sqrt(s)
    eps, nabla = cfg.gyro_bias_sigma_dph * DPH, cfg.accel_bias_sigma_ug * UG
    np.testing.assert_allclose(np.diag(kf.P)[:3] - np.diag(p0)[:3], arw ** 2 * h + eps ** 2 * h ** 2, rtol=1e-6)
    np.testing.assert_allclose(np.diag(kf.P)[3:6] - np.diag(p0)[3:6], vrw ** 2 * h + nabla ** 2 * h ** 2, rtol=1e-6)


def test_dead_reckoning_moves_the_position_by_velocity_times_time():
    """Checked in ECEF (geometry.earth's own conversion, not the radii the function uses): at
    60 m/s north-east and 1 m/s up for 2 s the solution moves by |v| 2 s to 1e-5 relative."""
    st = NavState(q_nb=np.array([0.0, 0.0, 0.0, 1.0]), v_n=np.array([60.0, 60.0, 1.0]), lat=0.7, lon=2.0, h=100.0)
    nxt = dead_reckoned(st, 2.0)
    d = earth.geodetic_to_ecef(nxt.lat, nxt.lon, nxt.h) - earth.geodetic_to_ecef(st.lat, st.lon, st.h)
    assert np.linalg.norm(d) == pytest.approx(2.0 * np.linalg.norm(st.v_n), rel=1e-5)
    assert np.array_equal(nxt.q_nb, st.q_nb) and np.array_equal(nxt.v_n, st.v_n)


def test_a_gap_in_flight_is_dead_reckoned_and_flagged(runs):
    """After the release nothing can re-anchor the slave (it no longer rides the ship): it
    dead-reckons across and stays flagged ('gap') to the end, since no NIS window follows."""
    inp, _ = runs
    events = []
    drop = set(range(1050, 1100))                        # 0.5 s, 2 s after the release at 11 s
    for k in range(len(inp.ships)):
        if k > 0 and k - 1 not in drop:
            events.append(('imu', inp.imu[k - 1]))
        events += [('ldv', inp.ldv[k]), ('master', inp.master[k])]
    f = feed_in_order(SC, events)
    assert f.counters.bridged_gaps == 1
    assert 'gap' in f.outputs[-1].flags and f.outputs[-1].level == WARN
    assert all(np.all(np.isfinite(e.q_nb)) and np.all(np.isfinite(e.p_w)) for e in f.outputs)
