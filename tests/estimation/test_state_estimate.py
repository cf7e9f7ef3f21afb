"""The whole estimate (estimation/state_estimate.py): every state of every model published
under a name with its SI unit, as the corrections fed back so far plus the filter's state;
in a run, the delay state finds the master's true latency and the biases are the engine's
accumulated corrections."""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.models import MODELS, Corrections, make_model
from alignment_core.estimation.state_estimate import StateEstimate

UNITS = ('rad', 'mps', 'radps', 'mps2', 'm', 's', 'ratio')


@pytest.mark.parametrize('model', MODELS)
def test_every_state_of_every_model_has_a_name_with_its_unit(model):
    cfg = FilterConfig(model=model, algorithm='ekf' if model == 'seed000_large_angle' else 'kf')
    m = make_model(cfg)
    names = StateEstimate(m.labels).labels
    assert len(names) == m.n and len(set(names)) == m.n
    assert all(n.rsplit('_', 1)[1] in UNITS for n in names)


def test_the_options_states_are_named_and_an_unknown_state_is_refused():
    m = make_model(FilterConfig(model='seed003_24', master_delay_state=True, lever_arm_states=True))
    names = StateEstimate(m.labels).labels
    for n in ('mounting_x_rad', 'flexure_z_rad', 'flexure_rate_y_radps', 'master_attitude_error_U_rad',
              'master_delay_s', 'lever_arm_error_z_m', 'gyro_bias_x_radps', 'accel_bias_y_mps2'):
        assert n in names
    with pytest.raises(ValueError, match='no published name'):
        StateEstimate(('phi_E', 'bogus_x'))


@pytest.mark.parametrize('dtype', [np.float64, np.float32])
def test_the_values_are_numpys_sums(dtype):
    """values() sums in Python floats: numpy's float64 sums of x and the corrections, bit for bit,
    whatever their precision (a float32 filter's state and corrections are widened exactly)."""
    m = make_model(FilterConfig(lever_arm_states=True))
    s = StateEstimate(m.labels)
    rng = np.random.default_rng(4)
    x = rng.standard_normal(m.n).astype(dtype)
    corr = Corrections(bg=rng.standard_normal(3).astype(dtype), ba=rng.standard_normal(3).astype(dtype),
                       dr=rng.standard_normal(3).astype(dtype))
    want = np.array(x, dtype=float)
    for i, name, axis in s._fed:
        want[i] += getattr(corr, name)[axis]
    got = s.values(x, corr)
    assert got.dtype == np.float64 and got.tobytes() == want.tobytes()


def _numpys(s: StateEstimate, x, corr: Corrections) -> np.ndarray:
    """values() as numpy's element sums give it (the code before its Python floats)."""
    want = np.array(x, dtype=float)
    for i, name, axis in s._fed:
        want[i] += getattr(corr, name)[axis]
    return want


def test_non_finite_sums_are_numpys_own_nan_warning_and_all():
    """A sum that is not finite is numpy's: which NaN (NaN + NaN keeps one operand's sign and
    payload, Python's float and numpy's scalar add pick differently), and its overflow warning."""
    m = make_model(FilterConfig(lever_arm_states=True))
    s = StateEstimate(m.labels)
    neg_nan = -math.nan                                     # the hardware's NaN: sign set
    x = np.zeros(m.n)
    x[6], x[9], x[10], x[15] = neg_nan, np.inf, 1e308, math.nan
    corr = Corrections(bg=np.array([math.nan, 0.0, 0.0]), ba=np.array([-np.inf, 1e308, 0.0]),
                       dr=np.array([neg_nan, 0.0, 0.0]))
    with warnings.catch_warnings(record=True) as before:
        warnings.simplefilter('always')
        want = _numpys(s, x, corr)
    with warnings.catch_warnings(record=True) as now:
        warnings.simplefilter('always')
        got = s.values(x, corr)
    assert got.tobytes() == want.tobytes()
    said = sorted(str(w.message) for w in now)
    assert said == sorted(str(w.message) for w in before) and any('overflow' in m for m in said)
    with np.errstate(over='raise', invalid='ignore'), pytest.raises(FloatingPointError):
        s.values(x, corr)


def test_other_inputs_are_summed_by_numpy_as_before():
    """A 2-D state, corrections in long double or as lists: numpy's element sums, as before; a
    correction that is not numeric raises as before."""
    m = make_model(FilterConfig(lever_arm_states=True))
    s = StateEstimate(m.labels)
    rng = np.random.default_rng(8)
    x2 = rng.standard_normal((m.n, 1))
    ld = Corrections(bg=rng.standard_normal(3).astype(np.longdouble) / 3, ba=np.zeros(3), dr=np.zeros(3))
    lists = Corrections(bg=[0.1, 0.2, 0.3], ba=[0.0, 1.0, 2.0], dr=[3.0, 4.0, 5.0])
    for x, corr in ((x2, Corrections()), (x2[:, 0], ld), (x2[:, 0], lists)):
        got, want = s.values(x, corr), _numpys(s, x, corr)
        assert got.shape == want.shape and got.tobytes() == want.tobytes()
    with pytest.raises(TypeError):
        s.values(x2[:, 0], Corrections(bg=np.array(['1', '2', '3'])))


def test_fed_back_states_add_their_correction_the_others_do_not():
    """vm15 + lever arm: x has every state 1; corrections bg = 10, 20, 30, ba = 4, 5, 6, dr = 7, 8, 9."""
    m = make_model(FilterConfig(lever_arm_states=True))
    s = StateEstimate(m.labels)
    corr = Corrections(bg=np.array([10.0, 20, 30]), ba=np.array([4.0, 5, 6]), dr=np.array([7.0, 8, 9]))
    v = s.values(np.ones(m.n), corr)
    want = np.ones(m.n)
    want[6:9] += [10, 20, 30]
    want[9:12] += [4, 5, 6]
    want[15:18] += [7, 8, 9]
    np.testing.assert_array_equal(v, want)


def test_a_run_publishes_the_accumulated_biases_and_finds_the_latency():
    """60 s on the deck, master latency 20 ms unknown to the filter but with the delay state: the
    published master_delay_s is 20 ms within 3 sigma (sigma below 1 ms); the bias states are the
    engine's accumulated corrections, not the last update's."""
    sc = scenario.load('deck_paper', overrides={'duration_s': 60.0, 'master.latency_s': 0.02,
                                          'filter.master_delay_state': True})
    f = pipeline.align(sc, pipeline.simulate(sc))
    e = f.outputs[-1]
    names = f.state_labels
    assert e.state is not None and np.all(np.isfinite(e.state))
    k = names.index('master_delay_s')
    assert abs(e.state[k] - 0.02) < 3 * e.sigma[k] and e.sigma[k] < 1e-3
    g = [names.index(f'gyro_bias_{a}_radps') for a in 'xyz']
    a = [names.index(f'accel_bias_{a}_mps2') for a in 'xyz']
    np.testing.assert_array_equal(e.state[g], e.bias_gyro)     # the residual is zero after feedback
    np.testing.assert_array_equal(e.state[a], e.bias_accel)
    assert not np.allclose(e.state[a], e.x[a])                  # the last correction is something else
