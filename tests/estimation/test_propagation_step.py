"""One IMU interval compiled whole (estimation/propagation_step.py) against the three calls it
replaces, bit for bit: Strapdown.update, the model's transition and KalmanFilter.predict; the
models that claim velocity matching's compiled transition (`transition_cells`) against their
own transition; and an engine run through it against the same run through the three calls."""
from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest
from support.estimates import run_both_ways

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation import engine as engine_module
from alignment_core.estimation import imu_events
from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.filters.kalman import KalmanFilter
from alignment_core.estimation.models import MODELS, NONLINEAR_MODELS, Propagation, make_model
from alignment_core.estimation.models.velocity_matching import phi_from_cells
from alignment_core.estimation.propagation_step import strapdown_and_predict
from alignment_core.estimation.reference_force import reference_specific_force
from alignment_core.navigation.strapdown import NavState, Strapdown
from alignment_core.validation import ConfigError

OPTIONS = ('lever_arm_states', 'master_delay_state', 'rate_matching')


def _bits(a, b) -> bool:
    """The same bits (a signed zero differs from its opposite), shape and dtype, or equal floats."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return (isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.dtype == b.dtype
                and a.shape == b.shape and a.tobytes() == b.tobytes())
    return type(a) is type(b) and np.float64(a).tobytes() == np.float64(b).tobytes()


def _models():
    """Every model the factory builds, with every combination of the options it accepts."""
    out = []
    for name in MODELS:
        for flags in itertools.product((False, True), repeat=len(OPTIONS)):
            for axes in ('all', 'yaw'):
                cfg = FilterConfig(model=name, attitude_match_axes=axes,
                                   algorithm='ekf' if name in NONLINEAR_MODELS else 'kf',
                                   **dict(zip(OPTIONS, flags)))
                try:
                    cfg.validate_combination()
                except ConfigError:
                    continue
                out.append(cfg)
    return out


def _propagation(rng: np.random.Generator) -> Propagation:
    q = rng.normal(size=4)
    c = Strapdown(NavState(q_nb=q / np.linalg.norm(q), v_n=np.zeros(3), lat=0.6, lon=0.1, h=0.0)).s.c_nb
    return Propagation(c, rng.normal(size=3) + [0.0, 0.0, 9.8], rng.normal(size=3) * 1e-5,
                       rng.normal(size=3) * 1e-6, rng.normal(size=3), 0.6, 12.0, 0.01)


@pytest.mark.parametrize('cfg', _models(), ids=lambda c: '-'.join(
    [c.model, c.attitude_match_axes] + [k for k in OPTIONS if getattr(c, k)]))
def test_a_model_that_claims_the_compiled_transition_has_it(cfg):
    """transition_cells() is a promise: the model's Phi is phi_from_cells of those cells in an
    identity of the model's size. Velocity matching and every option around it keep it; the
    other models make none."""
    model = make_model(cfg)
    cells = model.transition_cells()
    assert (cells is not None) == (cfg.model in ('vm12', 'vm15'))
    if cells is None:
        return
    rng = np.random.default_rng(7)
    for _ in range(20):
        p = _propagation(rng)
        idx, n = cells
        assert _bits(model.transition(p), phi_from_cells(p.c_nb, p.f_n, p.w_ie, p.w_en, p.h, idx, n, model.n))


def _nav(rng: np.random.Generator) -> NavState:
    q = rng.normal(size=4)
    return NavState(q_nb=q / np.linalg.norm(q), v_n=rng.normal(size=3), lat=0.7, lon=-2.1, h=25.0,
                    prev_dtheta=rng.normal(size=3) * 1e-4, prev_dv=rng.normal(size=3) * 1e-2)


@pytest.mark.parametrize('model_name, lever_arm, reference', [
    ('vm15', False, False), ('vm12', False, True), ('vm15', True, True)])
def test_one_call_is_the_three_calls(model_name, lever_arm, reference):
    """Strapdown, Phi (with the reference specific force or the slave's) and predict, stepped 50
    times both ways from the same state: every array and float equal, and an x and P read from
    the filter before a step left as they were (the filter's copy on write)."""
    cfg = FilterConfig(model=model_name, lever_arm_states=lever_arm, master_delay_state=lever_arm)
    model = make_model(cfg)
    cells = model.transition_cells()
    assert cells is not None
    rng = np.random.default_rng(11)
    nav = _nav(rng)
    ins_a, ins_b = Strapdown(dataclasses.replace(nav)), Strapdown(dataclasses.replace(nav))
    a0 = rng.normal(size=(model.n, model.n))
    p0 = a0 @ a0.T
    kf_a, kf_b = KalmanFilter(rng.normal(size=model.n), p0), KalmanFilter(rng.normal(size=model.n), p0)
    kf_b.x = kf_a.x.copy()
    qd = model.process_noise(0.01)
    for k in range(50):
        gyro, accel = rng.normal(size=3) * 0.02, rng.normal(size=3) + [0.0, 0.0, 9.8]
        bg, ba = rng.normal(size=3) * 1e-5, rng.normal(size=3) * 1e-3
        h = 0.01 + 1e-4 * (k % 3)
        a_spot = rng.normal(size=3) * 0.1 if reference else None
        x_read, p_read = kf_b.x, kf_b.P
        x_kept, p_kept = x_read.copy(), p_read.copy()
        f_n = ins_a.update((gyro - bg) * h, (accel - ba) * h, h)
        st = ins_a.s
        if reference:
            f_n = reference_specific_force(f_n, a_spot, st.v_n, ins_a.w_ie, ins_a.w_en)
        phi_a = model.transition(Propagation(ins_a.c_start, f_n, ins_a.w_ie, ins_a.w_en, st.v_n, st.lat, st.h, h))
        kf_a.predict(phi_a, qd)
        f_b, phi_b = strapdown_and_predict(ins_b, kf_b, cells, gyro, bg, accel, ba, h, qd, a_spot)
        assert _bits(f_b, f_n) and _bits(phi_b, phi_a)
        for name in ('c_start', 'w_ie', 'w_en'):
            assert _bits(getattr(ins_b, name), getattr(ins_a, name)), name
        for f in dataclasses.fields(NavState):
            assert _bits(getattr(ins_b.s, f.name), getattr(ins_a.s, f.name)), f.name
        assert _bits(kf_b.x, kf_a.x) and _bits(kf_b.P, kf_a.P)
        assert _bits(x_read, x_kept) and _bits(p_read, p_kept)
    assert kf_b.n_predicts == kf_a.n_predicts == 50


def test_a_subclass_or_wrapper_with_its_own_transition_claims_nothing():
    """A velocity-matching subclass or an option wrapper that computes Phi its own way does not
    get velocity matching's compiled transition."""
    from alignment_core.estimation.models.base import ModelWrapper
    from alignment_core.estimation.models.velocity_matching import VelocityMatching

    class Scaled(VelocityMatching):
        def transition(self, p):
            return 2.0 * super().transition(p)

    class Wrapped(ModelWrapper):
        def transition(self, p):
            return self.base.transition(p)

    class Widened(ModelWrapper):
        def transition_in(self, p, n):
            return self.base.transition_in(p, n)

    cfg = FilterConfig(model='vm15')
    assert VelocityMatching(cfg, True).transition_cells() is not None
    assert Scaled(cfg, True).transition_cells() is None
    assert Wrapped(VelocityMatching(cfg, True), '+w').transition_cells() is None
    assert Widened(VelocityMatching(cfg, True), '+w').transition_cells() is None
    assert ModelWrapper(VelocityMatching(cfg, True), '+w').transition_cells() is not None


def test_the_kernel_compiled_is_the_kernel_interpreted():
    """The kernel's own arithmetic (the increments, the reference specific force) compiled and
    interpreted, on the same arguments: the same arrays and floats."""
    from alignment_core.estimation import propagation_step
    rng = np.random.default_rng(3)
    cfg = FilterConfig(model='vm15', lever_arm_states=True)
    model = make_model(cfg)
    idx, n = model.transition_cells()
    nav = _nav(rng)
    a0 = rng.normal(size=(model.n, model.n))
    gyro = rng.normal(size=3) * 0.02
    outs = []
    for run in (propagation_step._interval, propagation_step._interval.py_func):
        x, p = np.ones(model.n), a0 @ a0.T
        outs.append(run(gyro, np.full(3, 1e-5), np.array([0.3, -0.2, 9.81]), np.full(3, 1e-3), 0.01,
                        nav.prev_dtheta, nav.prev_dv, nav.q_nb, nav.v_n, nav.lat, nav.lon, nav.h, idx, n, x, p,
                        model.process_noise(0.01), np.array([0.05, -0.02, 0.1]), True) + (x, p))
    for a, b in zip(*outs):
        assert _bits(a, b)


@pytest.mark.parametrize('name', ['deck', 'catapult_paper'])
def test_an_engine_run_is_the_same_through_the_three_calls(name, monkeypatch):
    """A short run of the carrier's deck (the reference specific force, the lever-arm and delay
    states) and of the papers' catapult: every published estimate and counter the same when the
    engine takes the three calls (a model without the compiled transition)."""
    sc = scenario.load(name, {'duration_s': 12.0, 'aircraft.catapult.launch_time_s': 8.0}, seed=5)
    inp = pipeline.simulate(sc)
    _, calls = run_both_ways(monkeypatch, sc, inp, imu_events, 'strapdown_and_predict',
                             engine_module.TransferAlignment, lambda e: setattr(e, '_cells', None))
    assert calls > 0.9 * len(inp.imu)
