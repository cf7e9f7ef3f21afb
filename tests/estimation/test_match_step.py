"""One master match of velocity matching and its delay and lever-arm layers compiled whole
(estimation/match_step.py) against the calls it replaces, bit for bit: the model's measurement, a
beam's projection, H Phi^-1, KalmanFilter.update, check_health, the model's feedback, the carry
of the slave's past attitude (Matcher._carry) and the misalignment; accepted, gated, with a
singular innovation covariance or Phi, with a broken covariance; and engine runs through it
against the same runs through the calls."""
from __future__ import annotations

import contextlib
import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest
from support.estimates import run_both_ways

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation import matching
from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.filters.base import solve
from alignment_core.estimation.filters.kalman import KalmanFilter
from alignment_core.estimation.health import BREAKDOWN_ERRORS, NumericalBreakdownError, check_health
from alignment_core.estimation.match_step import (
    Layers,
    _match,
    _match_in_step,
    _measurement,
    layers_of,
    update_and_feed_back,
)
from alignment_core.estimation.models import Corrections, Match, make_model
from alignment_core.estimation.models.beam import project_on_beam
from alignment_core.estimation.models.lever_arm import LeverArmStates
from alignment_core.estimation.models.master_delay import MasterDelayState
from alignment_core.estimation.models.velocity_matching import VelocityMatching
from alignment_core.estimation.outputs import Counters
from alignment_core.navigation.history import Past, SlaveHistory, SlaveSnapshot
from alignment_core.navigation.strapdown import NavState, Strapdown

MS = 1_000_000
C_NOM = np.array([[0.8, 0.6, 0.0], [-0.6, 0.8, 0.0], [0.0, 0.0, 1.0]])
MODELS = {  # name: FilterConfig options
    'vm15': {}, 'vm12': {'model': 'vm12'},
    'vm15+delay+lever': {'master_delay_state': True, 'lever_arm_states': True},
    'vm12+delay+lever': {'model': 'vm12', 'master_delay_state': True, 'lever_arm_states': True},
    'vm15+delay': {'master_delay_state': True}, 'vm12+lever': {'model': 'vm12', 'lever_arm_states': True},
    'vm12+delay': {'model': 'vm12', 'master_delay_state': True}, 'vm15+lever': {'lever_arm_states': True}}


def _nav(rng: np.random.Generator) -> NavState:
    q = rng.normal(size=4)
    return NavState(q_nb=q / np.linalg.norm(q), v_n=rng.normal(size=3), lat=0.7, lon=0.2, h=10.0)


def _case(rng: np.random.Generator, n: int, extras: int = 0, c_nom: bool = True):
    """A live solution, corrections, a filter of n states and a match: the delay's w_n and a_n
    with extras 1, w_n alone with extras 2 (no spot acceleration known), neither with 0; the
    nominal mounting C_NOM, or none."""
    nav = _nav(rng)
    corr = Corrections(bg=rng.normal(size=3) * 1e-6, ba=rng.normal(size=3) * 1e-4, dr=rng.normal(size=3) * 1e-2)
    a = rng.normal(size=(n, n)) * 1e-2
    p0 = a @ a.T + np.eye(n) * 1e-4
    c_m = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    match = Match(c_m=c_m, w_m=rng.normal(size=3) * 0.02, r=rng.normal(size=3) * 10.0, u_n=rng.normal(size=3),
                  v_ref=rng.normal(size=3), z_vel=rng.normal(size=3) * 0.05, r_vel=np.eye(3) * 1e-4, ins=nav,
                  c_nom=C_NOM if c_nom else None)
    w_n, a_n = rng.normal(size=3) * 0.02, rng.normal(size=3) * 0.3
    if extras:
        match.w_n, match.a_n = w_n, (a_n if extras == 1 else None)
    return nav, corr, KalmanFilter(rng.normal(size=n) * 1e-3, p0), match


def _past(rng: np.random.Generator, n: int) -> tuple[NavState, np.ndarray]:
    """The slave a few steps back and Phi from there to now."""
    return _nav(rng), np.eye(n) + rng.normal(size=(n, n)) * 1e-3


def _calls(model, kf, match, nav, corr, gate, beam_n=None, past=None):
    """What Matcher.update_master does, call by call; the slave's attitude at the validity time
    after feedback is the past one carried as Matcher._carry carries it, else the live one."""
    meas = model.measurement(match, corr)
    if beam_n is not None:
        meas = project_on_beam(meas, beam_n)
    h = meas.h if past is None else solve(past[1].T, meas.h.T).T
    upd = kf.update(meas.z, h, meas.r, gate)
    check_health(kf.x, kf.P)
    if not upd.accepted:
        return upd, None
    x = kf.x
    x_before, p = x.copy(), kf.P
    q0, v0, pos0 = nav.q_nb, nav.v_n, (nav.lat, nav.lon, nav.h)
    x_kept = model.feedback(x, p, match, nav, corr)
    at = nav
    if past is not None:
        history = SimpleNamespace(items=[], correct=lambda *a, **k: None)
        live = SimpleNamespace(ins=SimpleNamespace(s=nav), history=history)
        at = matching.Matcher._carry(SimpleNamespace(_lowpass=None), live, q0, v0, pos0, past[0])
    return upd, (x_before, x_kept) + model.misalignment(x_kept, p, match, at, corr) + (at.q_nb,)


def _one_call(model, kf, match, nav, corr, gate, beam_n=None, past=None):
    layers = layers_of(model)
    assert layers is not None
    return update_and_feed_back(kf, layers, match.z_vel, match.u_n, match.r_vel, gate, nav, corr, match.c_m,
                                match.c_nom, match.w_m, match.a_n, match.w_n, beam_n,
                                None if past is None else past[0].q_nb, None if past is None else past[1])


def _same(a, b) -> bool:
    """The same bits (a signed zero differs from its opposite), shape and dtype, or equal scalars."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return (isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.dtype == b.dtype
                and a.shape == b.shape and a.tobytes() == b.tobytes())
    return type(a) is type(b) and np.float64(a).tobytes() == np.float64(b).tobytes()


def test_layers_are_those_of_velocity_matching_only():
    """Velocity matching with its delay and lever-arm layers has them, at the columns the layers
    fill; any other model, or a subclass of a layer or of velocity matching, has none."""
    cfg = FilterConfig()
    assert layers_of(make_model(cfg)) == Layers(15)
    assert layers_of(make_model(FilterConfig(model='vm12'))) == Layers(12)
    assert layers_of(make_model(FilterConfig(master_delay_state=True, lever_arm_states=True))) == Layers(15, 15, 16)
    assert layers_of(make_model(FilterConfig(model='vm12', lever_arm_states=True))) == Layers(12, -1, 12)
    assert layers_of(LeverArmStates(MasterDelayState(LeverArmStates(VelocityMatching(cfg, True), 0.1), 0.1), 0.1)) \
        is None
    for name in ('seed003_24', 'seed002_10', 'seed000_6'):
        assert layers_of(make_model(FilterConfig(model=name))) is None
    assert layers_of(make_model(FilterConfig(rate_matching=True))) is None

    class OwnRows(LeverArmStates):
        pass

    class OwnModel(VelocityMatching):
        pass

    assert layers_of(OwnRows(VelocityMatching(cfg, True), 0.1)) is None
    assert layers_of(MasterDelayState(OwnModel(cfg, True), 0.1)) is None


@pytest.mark.parametrize('model_name', list(MODELS))
@pytest.mark.parametrize('where', ['live', 'past', 'beam', 'past+beam'])
@pytest.mark.parametrize('gate', [None, 1e-9, 2.0])
def test_one_call_is_the_calls(model_name, where, gate):
    """Twelve matches each way from the same state (the delay's inputs, both, w_n alone or
    none; the nominal mounting or none): the update's result, the filter's state and counts, the
    fed-back solution and corrections, the misalignment and the attitude at the validity time;
    gated (gate 1e-9) nothing fed back; a gate of 2 takes some and rejects others."""
    model = make_model(FilterConfig(**MODELS[model_name]))
    n = model.n
    outcomes = set()
    for seed in range(12):
        args = []
        for _ in range(2):
            rng = np.random.default_rng(seed)
            nav, corr, kf, match = _case(rng, n, extras=seed % 3, c_nom=seed % 4 != 3)
            beam = rng.normal(size=3) if 'beam' in where else None
            if beam is not None:
                beam /= np.linalg.norm(beam)
            args.append((model, kf, match, nav, corr, gate, beam, _past(rng, n) if 'past' in where else None))
        want_upd, want = _calls(*args[0])
        got_upd, got = _one_call(*args[1])
        for f in ('innovation', 's', 'nis', 'accepted'):
            assert _same(getattr(got_upd, f), getattr(want_upd, f)), f
        assert (got is None) == (want is None)
        assert gate != 1e-9 or got is None
        assert gate is not None or got is not None
        outcomes.add(got is None)
        if got is not None:
            for g, w in zip(got, want):
                assert _same(g, w)
        (_, kf_a, _, nav_a, corr_a, *_), (_, kf_b, _, nav_b, corr_b, *_) = args
        assert _same(kf_b.x, kf_a.x) and _same(kf_b.P, kf_a.P)
        assert kf_b.diagnostics() == kf_a.diagnostics() and kf_b.last_nis == kf_a.last_nis
        for f in dataclasses.fields(NavState):
            assert _same(getattr(nav_b, f.name), getattr(nav_a, f.name)), f.name
        for f in dataclasses.fields(Corrections):
            assert _same(getattr(corr_b, f.name), getattr(corr_a, f.name)), f.name
    if gate == 2.0:
        assert outcomes == {True, False}


def _singular_s(kf, match, past):
    kf.P = np.zeros_like(kf.P)
    match.r_vel = np.zeros((3, 3))
    return past


def _broken_p(kf, match, past):
    kf.P[10, 10] = -1.0
    return past


def _singular_phi(kf, match, past):
    return past[0], np.zeros_like(past[1])


@pytest.mark.parametrize('broken, error', [(_singular_s, np.linalg.LinAlgError), (_broken_p, NumericalBreakdownError),
                                           (_singular_phi, np.linalg.LinAlgError)])
def test_a_singular_or_broken_update_raises_as_the_calls_do(broken, error):
    """S singular (R zero and P zero) or Phi singular: np.linalg.LinAlgError, nothing fed back (the
    calls' singular Phi with numpy's RuntimeWarning, as filters/base.py's solve says); a covariance
    whose diagonal turns negative: NumericalBreakdownError after the update, nothing fed back."""
    model = make_model(FilterConfig(**MODELS['vm15+delay+lever']))
    done = []
    for call in (_calls, _one_call):
        rng = np.random.default_rng(1)
        nav, corr, kf, match = _case(rng, model.n, extras=1)
        past = broken(kf, match, _past(rng, model.n))
        q0, bg0, dr0 = nav.q_nb, corr.bg, corr.dr
        # the calls' solve of a singular Phi returns NaN with numpy's warning (filters/base.py); the kernel's raises
        warns = pytest.warns(RuntimeWarning, match='invalid value encountered in solve') \
            if broken is _singular_phi and call is _calls else contextlib.nullcontext()
        with pytest.raises(error), warns:
            call(model, kf, match, nav, corr, None, None, past)
        assert nav.q_nb is q0 and corr.bg is bg0 and corr.dr is dr0              # nothing fed back
        done.append(kf)
    kf_a, kf_b = done
    assert kf_b.diagnostics() == kf_a.diagnostics() or (np.isnan(kf_b.last_nis) and np.isnan(kf_a.last_nis)
                                                       and kf_b.n_updates == kf_a.n_updates
                                                       and kf_b.n_gated == kf_a.n_gated)
    assert _same(kf_b.x, kf_a.x) and _same(kf_b.P, kf_a.P)


@pytest.mark.parametrize('model_name', ['vm12', 'vm15+delay+lever', 'vm12+delay+lever'])
@pytest.mark.parametrize('in_step', [False, True])
def test_the_kernels_compiled_are_the_kernels_interpreted(model_name, in_step):
    """The kernels' own code (the measurement matrix, the layers' columns, the beam, the
    branches; inside the slave's last step, its interpolation and carry) compiled and
    interpreted."""
    model = make_model(FilterConfig(**MODELS[model_name]))
    layers = layers_of(model)
    assert layers is not None
    n = model.n
    outs = []
    for run, measure in (((_match_in_step if in_step else _match), _measurement),
                         ((_match_in_step if in_step else _match).py_func, _measurement.py_func)):
        rng = np.random.default_rng(4)
        nav, corr, kf, match = _case(rng, n, extras=1)
        past = _past(rng, n)
        beam = np.array([0.6, 0.0, 0.8])
        x, p, y, s = kf.arrays_to_update(1)
        args = (match.z_vel, match.u_n, match.r_vel, layers.nb, n, layers.delay, layers.lever, match.c_m,
                match.w_m, match.a_n, beam, past[1])
        common = (x, p, y, s, match.z_vel, match.u_n, match.r_vel, np.inf, layers.nb, layers.delay, layers.lever,
                  match.c_m, C_NOM, match.w_m, match.a_n, match.w_n, beam, past[1], nav.q_nb, nav.v_n, corr.bg,
                  corr.ba, corr.dr, past[0].q_nb)
        got = run(*common, past[0].v_n, 0.3) if in_step else run(*common)
        outs.append(got + (x, p, y, s) + measure(*args))
    assert len(outs[0]) == len(outs[1]) == (22 if in_step else 20)
    assert outs[0][3] is not None and (not in_step or outs[0][13] is not None)      # fed back
    for a, b in zip(*outs):
        assert _same(a, b)


def _history(rng: np.random.Generator, n: int, t_live: int) -> tuple[SlaveHistory, SlaveSnapshot]:
    """A slave history of three stored solutions 10 ms apart, the last (returned) 10 ms before the
    live one's time, each with its step's transition."""
    hist = SlaveHistory(100 * MS)
    for k in range(3):
        snap = hist.record(t_live - (3 - k) * 10 * MS, _nav(rng))
        snap.phi = np.eye(n) + rng.normal(size=(n, n)) * 1e-3
    return hist, hist.items[-1]


@pytest.mark.parametrize('model_name', list(MODELS))
@pytest.mark.parametrize('beam', [False, True])
@pytest.mark.parametrize('gate', [None, 1e-9, 2.0])
def test_a_match_inside_the_last_step_is_the_solution_made_first(model_name, beam, gate):
    """A validity time inside the slave's last step, interpolated by the kernel (update_and_feed_back's
    step) against the solution there made first (history.Past.state) and matched with its
    attitude and Phi: the update, the filter, the fed-back solution and corrections, the
    misalignment, the attitude at the validity time, and the stored solutions after the carry
    (SlaveHistory.correct, the kernel's carry of the last one taken), bit for bit."""
    model = make_model(FilterConfig(**MODELS[model_name]))
    layers = layers_of(model)
    assert layers is not None
    t_live = 1_000 * MS
    outcomes = set()
    for seed in range(12):
        got = []
        for kernel_steps in (False, True):
            rng = np.random.default_rng(seed)
            nav, corr, kf, match = _case(rng, model.n, extras=seed % 3, c_nom=seed % 4 != 3)
            hist, last = _history(rng, model.n, t_live)
            beam_n = rng.normal(size=3) if beam else None
            if beam_n is not None:
                beam_n /= np.linalg.norm(beam_n)
            t_v = t_live - int(rng.integers(1, 10 * MS))
            past = hist.find(t_v, nav, t_live, 20 * MS)
            assert past is not None and past.into_live() is last
            at, phi_acc = past.state()
            match.v_ref = at.v_n - match.z_vel * (0.1 + 0.4 * seed)      # innovations small to large
            q0, v0 = nav.q_nb, nav.v_n
            common = (kf, layers)
            tail = (match.u_n, match.r_vel, gate, nav, corr, match.c_m, match.c_nom, match.w_m, match.a_n,
                    match.w_n, beam_n)
            if kernel_steps:
                upd, fed = update_and_feed_back(*common, match.v_ref, *tail, step=(last, past.f))
            else:
                upd, fed = update_and_feed_back(*common, at.v_n - match.v_ref, *tail, q_past=at.q_nb,
                                                phi_acc=phi_acc)
            if fed is not None:
                assert (fed.carried is not None) == kernel_steps
                hist.correct(q0, nav.q_nb, v0, nav.v_n, 0.0, 0.0, 0.0, carried=fed.carried)
            stored = [(s.q_nb, s.v_n, s.lat) for s in hist.items]
            got.append((upd, None if fed is None else fed[:5], kf, nav, corr, stored))
        (upd_a, fed_a, kf_a, nav_a, corr_a, stored_a), (upd_b, fed_b, kf_b, nav_b, corr_b, stored_b) = got
        for f in ('innovation', 's', 'nis', 'accepted'):
            assert _same(getattr(upd_b, f), getattr(upd_a, f)), f
        assert (fed_a is None) == (fed_b is None)
        outcomes.add(fed_a is None)
        if fed_a is not None:
            for g, w in zip(fed_b, fed_a):
                assert _same(g, w)
        assert _same(kf_b.x, kf_a.x) and _same(kf_b.P, kf_a.P) and kf_b.diagnostics() == kf_a.diagnostics()
        for f in dataclasses.fields(NavState):
            assert _same(getattr(nav_b, f.name), getattr(nav_a, f.name)), f.name
        for f in dataclasses.fields(Corrections):
            assert _same(getattr(corr_b, f.name), getattr(corr_a, f.name)), f.name
        for sb, sa in zip(stored_b, stored_a, strict=True):
            for g, w in zip(sb, sa):
                assert _same(g, w)
    assert outcomes == ({True} if gate == 1e-9 else {False} if gate is None else {True, False})


def test_only_a_time_inside_the_last_step_goes_to_the_kernel_as_a_step():
    """Past.into_live: the stored solution a time inside the step into the live one starts from;
    not a stored solution's own time, a time inside an earlier step, the live time, a step without
    its transition or one kept in float32."""
    rng = np.random.default_rng(2)
    live = _nav(rng)
    t_live = 1_000 * MS
    hist, last = _history(rng, 15, t_live)

    def into(t_v):
        past = hist.find(t_v, live, t_live, 20 * MS)
        assert past is not None
        return past.into_live()

    assert into(t_live - 3 * MS) is last
    assert into(t_live - 10 * MS) is None                  # the stored solution's own time
    assert into(t_live - 13 * MS) is None                  # inside the step before
    assert into(t_live) is None
    last.phi = last.phi.astype(np.float32)
    assert into(t_live - 3 * MS) is None
    last.phi = None
    assert into(t_live - 3 * MS) is None


@pytest.mark.parametrize('name, options', [
    ('deck_paper', {}), ('catapult_paper', {}),
    ('deck_paper', {'filter.model': 'vm12', 'filter.gate_chi2': 3.0, 'filter.gate_release_updates': 3}),
    ('deck_paper', {'filter.lever_arm_treatment': 'butterworth'}), ('deck', {}), ('catapult', {}),
    ('deck', {'ldv.mode': 'vector', 'filter.model': 'vm12', 'filter.master_delay_state': False,
              'filter.gate_chi2': 3.0, 'filter.gate_release_updates': 3})])
def test_an_engine_run_is_the_same_through_the_calls(name, options, monkeypatch):
    """Short runs of the papers' deck and catapult (plain vm15), of vm12 with a gate tight enough
    to reject and release, of the low-pass lever-arm treatment, of the carrier's deck and
    catapult (the delay and lever-arm states, a beam LDV, matches in the slave's past) and of a
    vector LDV with the lever arm on vm12: every published estimate and counter the same when the
    matcher takes the calls one by one."""
    sc = scenario.load(name, {'duration_s': 12.0, 'aircraft.catapult.launch_time_s': 8.0, **options}, seed=5)
    inp = pipeline.simulate(sc)
    filt, calls = run_both_ways(monkeypatch, sc, inp, matching, 'update_and_feed_back', matching.Matcher,
                                lambda m: setattr(m, '_layers', None))
    assert calls > 500
    if 'filter.gate_chi2' in options:
        assert filt.counters.gated > 0 and filt.counters.gate_released > 0


def _matcher_case(rng: np.random.Generator, huge: bool):
    """A matcher of vm15 with the delay and lever-arm states, its live solution with a slave
    history whose last step the validity time t_v falls inside, and a reference; huge: the
    slave's east velocity 1.5e308 m/s and the reference's -1.5e308 m/s (their difference
    overflows)."""
    cfg = FilterConfig(**MODELS['vm15+delay+lever'])
    model = make_model(cfg)
    matcher = matching.Matcher(cfg, model, 100.0, int(0.2e9), Counters())
    nav, corr, kf, match = _case(rng, model.n, extras=1)
    t_live = 1_000 * MS
    hist, _ = _history(rng, model.n, t_live)
    v_ref = match.v_ref.copy()
    if huge:
        for s in [*hist.items, nav]:
            s.v_n = s.v_n.copy()
            s.v_n[0] = 1.5e308
        v_ref[0] = -1.5e308
    live = matching.LiveSolution(Strapdown(nav), kf, t_live, hist)
    ref = matching.Reference(match.c_m, match.r, np.zeros(3), match.u_n, v_ref, False, None, match.w_n)
    m = SimpleNamespace(w_b=match.w_m, t_ns=t_live)
    ldv = SimpleNamespace(var=0.0)
    return matcher, live, t_live - 4 * MS, m, ref, ldv, (match.w_n, match.a_n, None)


@pytest.mark.parametrize('huge', [False, True])
def test_a_step_whose_innovation_numpy_would_warn_of_goes_the_way_before(huge):
    """A validity time inside the slave's last step goes to the kernel whole (step_in_kernel);
    where numpy's z_vel = v - v_ref would overflow, the kernel declines (nothing done) and the
    match goes the way it went before, numpy's warning included: the filter, the solution and
    the results are the same, bit for bit, as without the step."""
    import warnings
    got = []
    for use_step in (True, False):
        matcher, live, t_v, m, ref, ldv, extras = _matcher_case(np.random.default_rng(3), huge)
        past = live.history.find(t_v, live.ins.s, live.t_ns, 20 * MS)
        step = matcher.step_in_kernel(live, past)
        assert step is live.history.items[-1]
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter('always')
            try:
                matcher.update_master(live, t_v, m, ref, ldv, past, step if use_step else None, extras, 0, 0)
            except BREAKDOWN_ERRORS:
                pass
        assert any('overflow encountered in subtract' in str(w.message) for w in caught) == huge
        st = live.ins.s
        got.append((live.kf.x, live.kf.P, st.q_nb, st.v_n, matcher.results.nis, matcher.results.mu,
                    [(s.q_nb, s.v_n) for s in live.history.items]))
    for a, b in zip(*got):
        if isinstance(a, list):
            assert all(_same(x, y) for pa, pb in zip(a, b) for x, y in zip(pa, pb))
        else:
            assert _same(a, b)


def test_the_solution_before_the_last_step_is_made_where_state_at_was(monkeypatch):
    """A validity time the kernel does not interpolate: the engine makes the slave's solution there
    before the delay's inputs and outside the update's breakdown handling, as state_at was
    made (an error there ends processing, not the filter)."""
    sc = scenario.load('deck', {'duration_s': 3.0}, seed=5)
    inp = pipeline.simulate(sc)

    def broken(self):
        raise FloatingPointError('underflow in the product of the transitions')
    monkeypatch.setattr(SlaveHistory, 'find', lambda self, *a: Past(self, 0, 0.0, a[0]))
    monkeypatch.setattr(Past, '_make_state', broken)
    monkeypatch.setattr(matching.Matcher, 'extras', lambda *a: pytest.fail('extras before the solution'))
    with pytest.raises(FloatingPointError, match='underflow'):
        pipeline.align(sc, inp)
