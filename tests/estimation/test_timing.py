"""Time-of-validity matching: master and LDV data valid at stamp - latency are compared with the
slave solution at that time (navigation/history.py, docs/engine.md), at their own rates."""
from __future__ import annotations

import numpy as np
import pytest
from support.engine_feed import feed_in_order, random_interleaving

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.geometry.rotations import quat_mul, quat_to_rotvec, rotvec_to_quat
from alignment_core.navigation.history import LdvHistory, LdvRecord, SlaveHistory
from alignment_core.navigation.strapdown import NavState
from alignment_core.units import ARCMIN

# without the catapult's known-event launch noise: the engine's delay-aware update neglects the
# process noise over the latency (two IMU steps here), which that noise makes large for 0.3 s
SHORT = {'duration_s': 12.0, 'aircraft.catapult.launch_time_s': 8.0, 'filter.launch_accel_noise_mps2': 0.0}
MS = 1_000_000


# ----- the history buffers -----
def _slave_history(w: np.ndarray, a: np.ndarray, step_ns: int, n: int):
    """Snapshots of a body turning at the constant rate w about a fixed axis and accelerating at
    a (nav frame): attitude exp(w t), velocity a t, both exact."""
    hist = SlaveHistory(10**9)
    states = []
    for k in range(n):
        t = k * step_ns * 1e-9
        states.append(NavState(q_nb=rotvec_to_quat(w * t), v_n=a * t, lat=0.1 + 1e-7 * t, lon=0.2, h=t))
    for k in range(n - 1):
        s = hist.record(k * step_ns, states[k])
        s.phi = np.eye(2) + (k + 1) * np.array([[0.0, 1e-3], [0.0, 0.0]])
    return hist, states[-1], (n - 1) * step_ns


def test_slave_history_interpolates_a_constant_rate_turn_and_acceleration_exactly():
    w, a = np.array([0.01, -0.02, 0.3]), np.array([20.0, -3.0, 0.5])
    hist, live, t_live = _slave_history(w, a, 10 * MS, 5)
    t = 17 * MS                                        # 0.7 of the step from 10 ms to 20 ms
    nav, phi = hist.state_at(t, live, t_live, 15 * MS)
    err = quat_to_rotvec(quat_mul(rotvec_to_quat(-w * t * 1e-9), nav.q_nb))
    assert np.linalg.norm(err) < 1e-14
    np.testing.assert_allclose(nav.v_n, a * t * 1e-9, rtol=0, atol=1e-13)
    # Phi from t to the live state: the last 0.3 of step 1, then steps 2 and 3 (k + 1 = 2, 3, 4)
    d = np.array([[0.0, 1e-3], [0.0, 0.0]])
    expect = (np.eye(2) + 4 * d) @ (np.eye(2) + 3 * d) @ (np.eye(2) + 0.3 * 2 * d)
    np.testing.assert_allclose(phi, expect, rtol=0, atol=1e-15)
    assert hist.state_at(t_live, live, t_live, 15 * MS) == (live, None)
    assert hist.state_at(t_live + 1, live, t_live, 15 * MS) is None         # not reached yet
    assert hist.state_at(t, live, t_live, 5 * MS) is None                   # step longer than allowed


def test_a_feedback_correction_commutes_with_interpolation():
    """Correcting the stored solutions, then interpolating, equals correcting the interpolated
    solution: the geodesic between two attitudes is invariant under a common nav-frame rotation."""
    w, a = np.array([0.2, 0.1, -0.3]), np.array([1.0, 2.0, 3.0])
    hist, live, t_live = _slave_history(w, a, 10 * MS, 4)
    q_corr, dv = rotvec_to_quat(np.array([1e-3, -2e-3, 5e-3])), np.array([0.01, -0.02, 0.03])
    before, _ = hist.state_at(13 * MS, live, t_live, 15 * MS)
    hist.correct(np.array([0.0, 0.0, 0.0, 1.0]), q_corr, np.zeros(3), dv, 0.0, 0.0, 0.0)    # from the identity
    live_c = NavState(q_nb=quat_mul(q_corr, live.q_nb), v_n=live.v_n + dv, lat=live.lat, lon=live.lon, h=live.h)
    after, _ = hist.state_at(13 * MS, live_c, t_live, 15 * MS)
    expect = quat_mul(q_corr, before.q_nb)
    assert np.linalg.norm(quat_to_rotvec(quat_mul(np.array([-expect[0], -expect[1], -expect[2], expect[3]]),
                                                  after.q_nb))) < 1e-14
    np.testing.assert_allclose(after.v_n, before.v_n + dv, rtol=0, atol=1e-15)



def test_the_matchers_carry_is_the_float_forms_bit_for_bit():
    """Matcher._carry after a feedback took the live solution from (q0, v0, pos0) to its state
    now: every stored solution and a past one (`nav`) corrected by the nav-frame rotation q q0^-1
    (the stored ones renormalised by the float forms, `nav` by numpy), the velocity change and
    the position changes, the same bits as the lines the kernel replaced."""
    from types import SimpleNamespace

    from alignment_core.estimation.matching import Matcher
    from alignment_core.geometry.rotations import floats, normalized_f, quat_mul_f

    rng = np.random.default_rng(4)
    hist, live, _ = _slave_history(np.array([0.2, 0.1, -0.3]), np.array([1.0, 2.0, 3.0]), 10 * MS, 4)
    stored = [(s.q_nb, s.v_n, s.lat, s.lon, s.h) for s in hist.items]
    q0, v0, pos0 = live.q_nb, live.v_n, (live.lat, live.lon, live.h)
    q1 = quat_mul(rotvec_to_quat(rng.normal(size=3) * 1e-3), q0)
    st = NavState(q_nb=q1, v_n=v0 + rng.normal(size=3) * 0.01, lat=live.lat + 1e-8, lon=live.lon - 2e-8, h=live.h + 0.1)
    past = NavState(q_nb=stored[1][0], v_n=stored[1][1], lat=0.1, lon=0.2, h=3.0)
    matcher = object.__new__(Matcher)
    matcher._lowpass = None
    got = matcher._carry(SimpleNamespace(ins=SimpleNamespace(s=st), history=hist), q0, v0, pos0, past)
    cx, cy, cz, cw = floats(q0)
    q_corr = quat_mul_f(floats(q1), (-cx, -cy, -cz, cw))
    dv, dpos = st.v_n - v0, (st.lat - pos0[0], st.lon - pos0[1], st.h - pos0[2])
    for s, (q, v, lat, lon, h) in zip(hist.items, stored, strict=True):
        assert s.q_nb.tobytes() == np.array(normalized_f(quat_mul_f(q_corr, floats(q)))).tobytes()
        assert s.v_n.tobytes() == (v + dv).tobytes()
        assert (s.lat, s.lon, s.h) == (lat + dpos[0], lon + dpos[1], h + dpos[2])
    q = np.array(quat_mul_f(q_corr, floats(past.q_nb)))
    assert got.q_nb.tobytes() == (q / np.sqrt(q @ q)).tobytes()
    assert got.v_n.tobytes() == (past.v_n + dv).tobytes()
    assert (got.lat, got.lon, got.h) == (past.lat + dpos[0], past.lon + dpos[1], past.h + dpos[2])

def _ldv(t_ms: list[float], v_of_t, valid=None, moving=None) -> LdvHistory:
    h = LdvHistory(10**9, 0.01)
    disp = np.zeros(3)
    prev = None
    for i, t in enumerate(t_ms):
        v = v_of_t(t * 1e-3)
        mv = True if moving is None else moving[i]
        ok = True if valid is None else valid[i]
        if prev is not None and mv and ok and prev[2]:
            disp = disp + 0.5 * (prev[1] + v) * (t - prev[0]) * 1e-3
        h.record(LdvRecord(int(t * MS), v, ok, mv, disp))
        prev = (t, v, ok)
    return h


def test_ldv_interpolation_is_exact_at_constant_acceleration():
    """2 g along x sampled at 25 Hz: velocity linear, displacement quadratic; the trapezoid of the
    linear velocity is exact, so both come out exact between samples, with no added variance."""
    acc = np.array([19.6, 0.0, 0.0])
    h = _ldv([0, 40, 80, 120], lambda t: acc * t)
    r = h.at(100 * MS)
    np.testing.assert_allclose(r.v_s, acc * 0.1, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r.disp, 0.5 * acc * 0.1**2, rtol=0, atol=1e-12)
    assert r.valid and r.moving and r.var == 0.0
    assert h.at(121 * MS) is None and h.at(120 * MS) is h.items[-1]


def test_ldv_interpolation_across_the_launch_carries_its_error_bound():
    """The launch at 70 ms inside [40, 80] ms: linear interpolation is off by up to |Delta| f
    (Delta = v_80 minus its extrapolation from 0 and 40 ms); the variance added covers the
    actual error wherever it exceeds three noise sigmas (Delta's noise: sigma^2 (1 + 2^2 + 1) per
    axis at equal spacing, so |e|^2 <= var + 27 (6 sigma^2) f^2, with equality for f <= 0.75)."""
    acc, t_l = np.array([19.6, 0.0, 0.0]), 0.07
    h = _ldv([0, 40, 80], lambda t: acc * max(0.0, t - t_l), moving=[False, False, True])
    for t_ms in (50, 60, 70, 75):
        r = h.at(t_ms * MS)
        err = np.linalg.norm(r.v_s - acc * max(0.0, t_ms * 1e-3 - t_l))
        f = (t_ms - 40) / 40
        assert err ** 2 <= r.var + 27 * 6e-4 * f * f + 1e-12
        assert r.var > 0.0


def test_ldv_nearest_valid_sample_only_while_parked():
    still = lambda t: np.zeros(3)   # noqa: E731
    parked = _ldv([0, 40, 80], still, valid=[True, True, False], moving=[False] * 3)
    assert parked.at(50 * MS).valid and not parked.at(70 * MS).valid      # within / beyond half the spacing
    moving = _ldv([0, 40, 80], still, valid=[True, True, False], moving=[True] * 3)
    assert not moving.at(50 * MS).valid


# ----- the engine on the catapult scenario -----
def _final(**ov):
    sc = scenario.load('catapult_paper', {**SHORT, **ov})
    res = pipeline.run(sc, keep_truth=False)
    e = res.estimates[-1]                     # held since the release (matching stopped)
    assert not e.matching
    mu = np.asarray(sc.aircraft.misalignment_arcmin) * ARCMIN
    return e.misalignment - mu, e.misalignment_sigma, res.filter.counters


@pytest.fixture(scope='module')
def zero_latency():
    return _final()


def test_known_latency_recovers_the_zero_latency_result(zero_latency):
    """Master data 20 ms late, the latency known: the filter makes the same matches (master and
    slave at the same validity times), 20 ms later, so its result equals the zero-latency one
    (the delay-aware H differs from H by Phi^-1 over two IMU steps: ~g 20 ms phi, negligible).
    Unknown, the 20 ms shift costs arcminutes (lever-arm velocity of the rolling deck, a dt)."""
    err0, sig0, c0 = zero_latency
    err, sig, c = _final(**{'master.latency_s': 0.02, 'filter.master_latency_s': 0.02})
    assert c.updates == c0.updates and c.unmatched_master == 0
    assert np.all(np.abs(err) <= 1.5 * np.abs(err0) + 0.01 * ARCMIN)
    np.testing.assert_allclose(err, err0, rtol=0, atol=0.05 * sig0.min())
    np.testing.assert_allclose(sig, sig0, rtol=1e-3)
    err_u, _, _ = _final(**{'master.latency_s': 0.02})
    assert np.max(np.abs(err_u)) > 10 * np.max(np.abs(err))


def test_off_grid_latency(zero_latency):
    """13 ms is off the 10 ms IMU grid: stamps fall between IMU samples. Known, the validity times
    are back on the grid and the result is the zero-latency one; unknown, the validity times
    are off the grid, the slave solution is interpolated and the filter still updates at every
    sample (it used to make no update at all)."""
    err0, sig0, c0 = zero_latency
    err, sig, c = _final(**{'master.latency_s': 0.013, 'filter.master_latency_s': 0.013})
    assert c.updates == c0.updates
    np.testing.assert_allclose(err, err0, rtol=0, atol=0.05 * sig0.min())
    _, _, cu = _final(**{'master.latency_s': 0.013})
    assert cu.updates >= c0.updates - 2 and cu.unmatched_master == 0


def test_master_50hz_ldv_25hz_with_latencies(zero_latency):
    """Master at 50 Hz, LDV at 25 Hz, latencies 13 and 7 ms known: one update per master sample
    (half as many), the LDV interpolated to the master's validity times. Half the samples: on
    the deck sigma grows by sqrt(2); the LDV's noise enters four matches per sample in the
    stroke, weighted as one. Errors within 3 sigma."""
    err0, sig0, c0 = zero_latency
    err, sig, c = _final(**{'master.rate_hz': 50.0, 'ldv.rate_hz': 25.0, 'master.latency_s': 0.013,
                            'ldv.latency_s': 0.007, 'filter.master_latency_s': 0.013, 'filter.ldv_latency_s': 0.007})
    assert abs(c.updates - c0.updates / 2) <= 2 and c.unmatched_master == 0
    assert np.all(np.abs(err) < 3.0 * sig)
    assert np.all(sig < 2.0 * sig0) and np.all(sig > sig0)


def test_ldv_later_than_master_defers_the_match(zero_latency):
    """LDV 30 ms late, master on time: each master sample waits for its LDV sample, then matches
    exactly what it would have matched with no latency (the same result)."""
    err0, sig0, c0 = zero_latency
    err, sig, c = _final(**{'ldv.latency_s': 0.03, 'filter.ldv_latency_s': 0.03})
    assert c.updates == c0.updates
    np.testing.assert_allclose(err, err0, rtol=0, atol=0.05 * sig0.min())


def test_outputs_do_not_depend_on_arrival_order_with_latencies_and_rates():
    """Deferred matches (LDV later than the master, master at half the IMU rate, off-grid
    latencies) still depend only on the streams' contents, not on how they interleave."""
    sc = scenario.load('catapult_paper', {'duration_s': 5.0, 'aircraft.catapult.launch_time_s': 3.0,
                                          'master.rate_hz': 50.0, 'master.latency_s': 0.013, 'ldv.latency_s': 0.03,
                                          'filter.master_latency_s': 0.013, 'filter.ldv_latency_s': 0.03})
    inp = pipeline.simulate(sc)
    ref = pipeline.align(sc, inp)
    f = feed_in_order(sc, random_interleaving(inp, np.random.default_rng(5)))
    out = [np.concatenate([e.misalignment, e.sigma, e.q_nb]) for e in f.outputs]
    assert ref.counters.updates > 100
    assert np.array_equal(np.array(out), np.array([np.concatenate([e.misalignment, e.sigma, e.q_nb])
                                                   for e in ref.outputs]))


def test_doppler_known_latency_recovers_the_zero_latency_result():
    """seed 001's Doppler radar 50 ms late, the latency known: the filter matches each radar sample
    against the slave solution 50 ms back (H Phi^-1), keeps every sample, and ends where the
    zero-latency run ends (to a small part of its sigma)."""
    base = {'duration_s': 45.0, 'doppler.enabled': True, 'filter.model': 'seed001_13',
            'aircraft.flight.segments': 'climb duration_s=20 climb_rate_mps=5 speed_mps=60; level duration_s=10'}

    def final(**ov):
        sc = scenario.load('inflight', {**base, **ov}, seed=2)
        inp = pipeline.simulate(sc)
        f = pipeline.align(sc, inp)
        e = f.outputs[-1]
        k = int(np.searchsorted(inp.ships.t_ns, e.t_ns))
        q_true = inp.truth['q_nb'][k]
        err = quat_to_rotvec(quat_mul(e.q_nb, np.array([-q_true[0], -q_true[1], -q_true[2], q_true[3]])))
        return err, np.sqrt(np.diag(e.attitude_cov)), f.counters

    err0, sig0, c0 = final()
    err, sig, c = final(**{'doppler.latency_s': 0.05, 'filter.doppler_latency_s': 0.05})
    assert c.doppler_updates == c0.doppler_updates > 400 and c.unmatched_doppler == 0
    np.testing.assert_allclose(err, err0, rtol=0, atol=0.1 * sig0.min())
    np.testing.assert_allclose(sig, sig0, rtol=1e-2)


def test_outputs_carry_their_validity_time():
    """Each output's misalignment refers to the stamp less the master latency the filter is told
    (the matches' validity time); without a latency told, the stamp itself."""
    for told_ns in (0, 20 * MS):
        sc = scenario.load('catapult_paper', {**SHORT, 'duration_s': 3.0, 'master.latency_s': 0.02,
                                        'filter.master_latency_s': told_ns * 1e-9})
        est = pipeline.run(sc, keep_truth=False).estimates
        assert len(est) > 10
        assert all(e.t_valid_ns == e.t_ns - told_ns and e.validity_ns == e.t_ns - told_ns for e in est)
