"""The gear's compiled kernels (landing_gear.air_spring_excess_rows, gear_response.gust_series and
step_samples) against the numpy code they replaced, written out here step by step."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from alignment_core.aircraft.gear_config import GearConfig
from alignment_core.aircraft.gear_response import DeckGust, GearResponse, gust_series
from alignment_core.aircraft.landing_gear import N_DOF, GearModel, air_spring_excess_rows
from alignment_core.units import G0

CFG = dataclasses.replace(GearConfig(), enabled=True, wind_over_deck_mps=15.0, gust_severity='moderate')


def test_excess_is_the_gas_law_and_compiled_equals_interpreted():
    model = GearModel(CFG)
    rng = np.random.default_rng(1)
    s = rng.uniform(-0.3, 0.8, (500, 3)) * model.gas
    n = CFG.polytropic_index
    got = air_spring_excess_rows(s, model.gas, model.leg_load_n, n)
    assert np.array_equal(got, air_spring_excess_rows.py_func(s, model.gas, model.leg_load_n, n))
    x = s / model.gas
    # numpy's own power may round the last bit differently (its SIMD pow): a relative 1e-15 of F0
    np.testing.assert_allclose(got, model.leg_load_n * ((1.0 - x) ** -n - 1.0 - n * x),
                               rtol=0, atol=1e-15 * model.leg_load_n.max() * 10)
    small = 1e-4 * model.gas                              # Taylor: F0 n (n + 1) / 2 (s / L)^2
    np.testing.assert_allclose(model.air_spring_excess(small), model.leg_load_n * n * (n + 1) / 2 * 1e-8, rtol=1e-3)
    assert model.air_spring_excess(np.zeros((4, 2, 3))).shape == (4, 2, 3)


def test_a_bottomed_strut_is_refused():
    model = GearModel(CFG)
    with pytest.raises(ValueError, match='bottoming out'):
        model.air_spring_excess(np.array([0.0, 0.96, 0.0]) * model.gas)


def test_gust_series_is_the_dryden_recursion():
    gust = DeckGust(CFG, seed=3, dt=0.01)
    noise = gust.draw(300)
    b = GearModel(CFG).gust_matrix()
    g, load = gust.series(noise[:100], b)
    g2, load2 = gust.series(noise[100:], b)
    x = noise[0] * np.array([1.0, 0.5, 0.5, 0.5, 0.5])
    want, want_load = [], []
    for j, nz in enumerate(noise):
        if j:
            x = gust.phi @ x + gust.root @ nz
        want.append(gust.sigma * (gust.out @ x))
        want_load.append(b @ want[-1])
    assert np.array_equal(np.vstack([g, g2]), np.array(want))
    assert np.array_equal(np.vstack([load, load2]), np.array(want_load))
    fresh = DeckGust(CFG, seed=3, dt=0.01)
    py = gust_series.py_func(noise, np.zeros(0), fresh.phi, fresh.root, fresh.sigma, fresh.out, b)
    assert np.array_equal(py[0], np.array(want))


def _reference(resp: GearResponse, load: np.ndarray) -> np.ndarray:
    """The step-by-step numpy loop the kernel replaced: q, q', q'' (K, 27) from loads (K, 9)."""
    m = resp.model
    x = np.concatenate([m.static(load[0]), np.zeros(N_DOF)])
    prev, excess, out = load[0], None, []
    for j, f in enumerate(load):
        if j and excess is None:
            x = resp.phi @ x + resp.g0 @ prev + resp.g1 @ f
        elif j:
            base = resp.phi @ x + resp.g0 @ (prev + excess)
            pred = base + resp.g1 @ (f + excess)
            x = base + resp.g1 @ (f + m.nonlinear_load(pred[:N_DOF]))
        prev = f
        if m.polytropic:
            excess = m.nonlinear_load(x[:N_DOF])
        q, qd = x[:N_DOF], x[N_DOF:]
        out.append(np.concatenate([q, qd, m.acceleration(q, qd, f)]))
    return np.array(out)


@pytest.mark.parametrize('spring', ['linear', 'polytropic'])
def test_stepping_is_the_numpy_loop_bit_for_bit(spring):
    cfg = dataclasses.replace(CFG, strut_spring=spring, gust_severity='none')
    resp = GearResponse(cfg, seed=2, rate_hz=100.0, f0=np.array([0.0, 0.0, G0]))
    rng = np.random.default_rng(4)
    n = 400
    f = np.array([0.0, 0.0, G0]) + np.cumsum(rng.normal(0.0, 0.05, (n, 3)), axis=0)
    wdot = rng.normal(0.0, 0.01, (n, 3))
    for lo, hi in ((0, 1), (1, 150), (150, 151), (151, n)):         # chunks of any size, one at a time
        resp.feed(np.arange(lo, hi), f[lo:hi], wdot[lo:hi])
    q, qd, qdd = resp.states(np.arange(n))
    want = _reference(resp, resp.model.inertial_load(f, wdot, resp.f0))
    assert np.array_equal(np.hstack([q, qd, qdd]), want)
    assert np.abs(resp.model.strut_compression(q)).max() > 1e-3          # the springs were worked
