"""One master match of plain velocity matching compiled whole (estimation/match_step.py) against
the calls it replaces, bit for bit: the model's measurement, KalmanFilter.update, check_health, the
model's feedback and misalignment; accepted, gated, with a singular innovation covariance and
with a broken covariance; and an engine run through it against the same run through the calls."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from support.estimates import digest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation import matching
from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.filters.kalman import KalmanFilter
from alignment_core.estimation.health import NumericalBreakdownError, check_health
from alignment_core.estimation.match_step import _match, update_and_feed_back
from alignment_core.estimation.models import Corrections, Match, make_model
from alignment_core.estimation.models.base import nominal_attitude
from alignment_core.navigation.strapdown import NavState

C_NOM = np.array([[0.8, 0.6, 0.0], [-0.6, 0.8, 0.0], [0.0, 0.0, 1.0]])


def _case(rng: np.random.Generator, n: int):
    q = rng.normal(size=4)
    nav = NavState(q_nb=q / np.linalg.norm(q), v_n=rng.normal(size=3), lat=0.7, lon=0.2, h=10.0)
    corr = Corrections(bg=rng.normal(size=3) * 1e-6, ba=rng.normal(size=3) * 1e-4)
    a = rng.normal(size=(n, n)) * 1e-2
    p0 = a @ a.T + np.eye(n) * 1e-4
    c_m = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    match = Match(c_m=c_m, w_m=rng.normal(size=3) * 0.02, r=rng.normal(size=3) * 10.0, u_n=rng.normal(size=3),
                  v_ref=rng.normal(size=3), z_vel=rng.normal(size=3) * 0.05, r_vel=np.eye(3) * 1e-4, ins=nav,
                  c_nom=C_NOM)
    return nav, corr, KalmanFilter(rng.normal(size=n) * 1e-3, p0), match


def _calls(model, kf, match, nav, corr, gate):
    """What Matcher.update_master does for plain velocity matching, call by call."""
    meas = model.measurement(match, corr)
    upd = kf.update(meas.z, meas.h, meas.r, gate)
    check_health(kf.x, kf.P)
    if not upd.accepted:
        return upd, None
    x = kf.x
    x_before, p = x.copy(), kf.P
    x_kept = model.feedback(x, p, match, nav, corr)
    return upd, (x_before, x_kept) + model.misalignment(x_kept, p, match, nav, corr)


def _same(a, b) -> bool:
    """The same bits (a signed zero differs from its opposite), shape and dtype, or equal scalars."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return (isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.dtype == b.dtype
                and a.shape == b.shape and a.tobytes() == b.tobytes())
    return type(a) is type(b) and np.float64(a).tobytes() == np.float64(b).tobytes()


@pytest.mark.parametrize('model_name', ['vm12', 'vm15'])
@pytest.mark.parametrize('gate', [None, 1e6, 1e-9])
def test_one_call_is_the_calls(model_name, gate):
    """Twenty matches each way from the same state: the update's result, the filter's state and
    counts, the fed-back solution and corrections, the misalignment; gated (gate 1e-9) nothing fed
    back either way."""
    model = make_model(FilterConfig(model=model_name))
    n = model.n
    for seed in range(20):
        nav_a, corr_a, kf_a, match_a = _case(np.random.default_rng(seed), n)
        nav_b, corr_b, kf_b, match_b = _case(np.random.default_rng(seed), n)
        want_upd, want = _calls(model, kf_a, match_a, nav_a, corr_a, gate)
        got_upd, got = update_and_feed_back(kf_b, n, match_b.z_vel, match_b.u_n, match_b.r_vel, gate, nav_b,
                                            corr_b, nominal_attitude(match_b))
        for f in ('innovation', 's', 'nis', 'accepted'):
            assert _same(getattr(got_upd, f), getattr(want_upd, f)), f
        assert (got is None) == (want is None) == (gate == 1e-9)
        if got is not None:
            for g, w in zip(got, want):
                assert _same(g, w)
        assert _same(kf_b.x, kf_a.x) and _same(kf_b.P, kf_a.P)
        assert kf_b.diagnostics() == kf_a.diagnostics() and kf_b.last_nis == kf_a.last_nis
        for f in dataclasses.fields(NavState):
            assert _same(getattr(nav_b, f.name), getattr(nav_a, f.name)), f.name
        for f in dataclasses.fields(Corrections):
            assert _same(getattr(corr_b, f.name), getattr(corr_a, f.name)), f.name


def test_a_singular_or_broken_update_raises_as_the_calls_do():
    """S singular (R zero and P zero): np.linalg.LinAlgError, nothing fed back; a covariance
    whose diagonal turns negative: NumericalBreakdownError after the update, nothing fed back."""
    model = make_model(FilterConfig(model='vm15'))
    for broken, error in ((lambda kf, m: (setattr(kf, 'P', np.zeros((15, 15))), setattr(m, 'r_vel', np.zeros((3, 3)))),
                           np.linalg.LinAlgError),
                          (lambda kf, m: kf.P.__setitem__((10, 10), -1.0), NumericalBreakdownError)):
        nav_a, corr_a, kf_a, match_a = _case(np.random.default_rng(1), 15)
        broken(kf_a, match_a)
        with pytest.raises(error):
            _calls(model, kf_a, match_a, nav_a, corr_a, None)
        nav, corr, kf, match = _case(np.random.default_rng(1), 15)
        broken(kf, match)
        q0, bg0 = nav.q_nb, corr.bg
        with pytest.raises(error):
            update_and_feed_back(kf, 15, match.z_vel, match.u_n, match.r_vel, None, nav, corr,
                                 nominal_attitude(match))
        assert nav.q_nb is q0 and corr.bg is bg0              # nothing fed back
        assert _same(nav_a.q_nb, q0) and _same(corr_a.bg, bg0)
        assert kf.diagnostics() == kf_a.diagnostics() or (np.isnan(kf.last_nis) and np.isnan(kf_a.last_nis)
                                                           and kf.n_updates == kf_a.n_updates
                                                           and kf.n_gated == kf_a.n_gated)
        assert _same(kf.x, kf_a.x) and _same(kf.P, kf_a.P)


def test_the_kernel_compiled_is_the_kernel_interpreted():
    """The kernel's own code (the measurement matrix, the branches) compiled and interpreted."""
    for n in (12, 15):
        outs = []
        for run in (_match, _match.py_func):
            nav, corr, kf, match = _case(np.random.default_rng(4), n)
            x, p, y, s = kf.arrays_to_update(3)
            outs.append(run(x, p, match.z_vel, match.u_n, n, match.r_vel, np.inf, y, s, nav.q_nb, nav.v_n,
                            corr.bg, corr.ba, np.ascontiguousarray(nominal_attitude(match))) + (x, p, y, s))
        for a, b in zip(*outs):
            assert _same(a, b)


@pytest.mark.parametrize('name, options', [
    ('deck_paper', {}), ('catapult_paper', {}),
    ('deck_paper', {'filter.model': 'vm12', 'filter.gate_chi2': 3.0, 'filter.gate_release_updates': 3}),
    ('deck_paper', {'filter.lever_arm_treatment': 'butterworth'})])
def test_an_engine_run_is_the_same_through_the_calls(name, options, monkeypatch):
    """Short runs of the papers' deck and catapult (plain vm15), of vm12 with a gate tight enough
    to reject and release, and of the low-pass lever-arm treatment: every published estimate and
    counter the same when the matcher takes the calls one by one."""
    sc = scenario.load(name, {'duration_s': 12.0, 'aircraft.catapult.launch_time_s': 8.0, **options}, seed=5)
    inp = pipeline.simulate(sc)
    calls = []
    compiled = matching.update_and_feed_back
    monkeypatch.setattr(matching, 'update_and_feed_back', lambda *a: calls.append(1) or compiled(*a))
    filt = pipeline.align(sc, inp)
    through_kernel = digest(filt)
    assert len(calls) > 500
    if 'filter.gate_chi2' in options:
        assert filt.counters.gated > 0 and filt.counters.gate_released > 0
    init = matching.Matcher.__init__

    def one_by_one(self, *args, **kwargs):
        init(self, *args, **kwargs)
        self._vm_states = 0

    monkeypatch.setattr(matching.Matcher, '__init__', one_by_one)
    calls.clear()
    assert digest(pipeline.align(sc, inp)) == through_kernel
    assert not calls
