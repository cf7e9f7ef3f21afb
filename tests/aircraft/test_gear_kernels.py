"""The gear's compiled kernels (landing_gear.air_spring_excess_rows, gear_response.gust_series and
step_samples) against the numpy code they replaced, written out here step by step."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from alignment_core.aircraft.gear_config import GearConfig
from alignment_core.aircraft.gear_response import DeckGust, GearResponse, gust_series, quintic_hermite
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


def _motion_reference(resp: GearResponse, tau: np.ndarray) -> tuple[np.ndarray, ...]:
    """The numpy form GearResponse.imu_motion had: each node's samples read and interpolated alone."""
    x = tau * resp.rate_hz
    k = np.floor(x + 1e-9).astype(np.int64)
    u = x - k
    at_sample = np.abs(u) < 1e-9
    u = np.where(at_sample, 0.0, u)[..., None]
    d0, v0, a0 = resp.imu_at(k)
    d1, v1, a1 = resp.imu_at(np.where(at_sample, k, k + 1))
    h = resp.dt
    u2, u3, u4, u5 = u * u, u**3, u**4, u**5
    pos = ((1 - 10*u3 + 15*u4 - 6*u5) * d0 + (u - 6*u3 + 8*u4 - 3*u5) * h * v0
           + 0.5 * (u2 - 3*u3 + 3*u4 - u5) * h * h * a0 + (10*u3 - 15*u4 + 6*u5) * d1
           + (-4*u3 + 7*u4 - 3*u5) * h * v1 + 0.5 * (u3 - 2*u4 + u5) * h * h * a1)
    vel = ((-30*u2 + 60*u3 - 30*u4) * d0 / h + (1 - 18*u2 + 32*u3 - 15*u4) * v0
           + 0.5 * (2*u - 9*u2 + 12*u3 - 5*u4) * h * a0 + (30*u2 - 60*u3 + 30*u4) * d1 / h
           + (-12*u2 + 28*u3 - 15*u4) * v1 + 0.5 * (3*u2 - 8*u3 + 5*u4) * h * a1)
    acc = ((-60*u + 180*u2 - 120*u3) * d0 / (h * h) + (-36*u + 96*u2 - 60*u3) * v0 / h
           + 0.5 * (2 - 18*u + 36*u2 - 20*u3) * a0 + (60*u - 180*u2 + 120*u3) * d1 / (h * h)
           + (-24*u + 84*u2 - 60*u3) * v1 / h + 0.5 * (6*u - 24*u2 + 20*u3) * a1)
    s = at_sample[..., None]
    return np.where(s, d0, pos), np.where(s, v0, vel), np.where(s, a0, acc)


def test_imu_motion_is_the_per_node_numpy_form_bit_for_bit():
    """imu_motion reads each row's samples once and interpolates in gear_response.quintic_hermite:
    the numbers of the per-node numpy form, for Gauss nodes inside intervals (the increments'),
    rows mixing sample instants and nodes, nodes of different intervals in one row, and scalars."""
    resp = GearResponse(CFG, seed=2, rate_hz=100.0, f0=np.array([0.0, 0.0, G0]))
    rng = np.random.default_rng(8)
    n = 300
    resp.feed(np.arange(n), np.array([0.0, 0.0, G0]) + rng.normal(0.0, 0.3, (n, 3)), rng.normal(0.0, 0.05, (n, 3)))
    k = np.arange(1, n - 2)
    nodes = (k[:, None] + np.array([0.1127016653792583, 0.5, 0.8872983346207417])) / 100.0
    mixed = np.stack([k / 100.0, (k + 0.25) / 100.0], axis=1)
    spread = np.stack([(k + 0.5) / 100.0, (k + 1.5) / 100.0], axis=1)
    for tau in (nodes, mixed, spread, np.array(1.234), k / 100.0):
        got, want = resp.imu_motion(tau), _motion_reference(resp, tau)
        for g, w in zip(got, want):
            assert g.shape == w.shape and g.tobytes() == w.tobytes()


def test_the_quintic_hermite_refuses_shapes_that_do_not_agree():
    """numba checks no bounds: fractions or ends of other counts raise before any read."""
    u, ends = np.zeros((4, 3)), [np.zeros((4, 3))] * 6
    with pytest.raises(ValueError):
        quintic_hermite(u, u, u[:3], u, u > 0, *ends, 0.01)
    with pytest.raises(ValueError):
        quintic_hermite(u, u, u, u, u > 0, *ends[:5], np.zeros((3, 3)), 0.01)
