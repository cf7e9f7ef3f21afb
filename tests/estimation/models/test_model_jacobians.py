"""Each model's continuous F (and H) against numerical Jacobians of the exact nonlinear strapdown
error propagation (tests/support/nav_error_reference.py), at three dissimilar states; blocks that must
coincide between models do; the discrete Phi is the documented second-order expansion.

The velocity-matching models (vm12, seed000_6, seed002_10, seed003) neglect the errors of the
computed Earth and transport rates caused by dV (d(w_en) = dV / R) and by position (no position
states): entries of order 1/R and |V| (1 + |tan L|) / R, below 4e-6 here. They must agree with
the reference to that bound everywhere, and to 1e-6 relative on every entry above 1e-3 (C_b^n,
[f x]; the Coriolis entries, ~1e-4, contain the neglected terms).
Seed 001's model keeps those terms and must agree to 1e-5 relative plus 1e-10 absolute, except
in its latitude column, which also holds the latitude derivatives of the radii that it neglects
(e^2 |V| (|V| + 1) / R, 4e-6 at 60 m/s)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm
from support.nav_error_reference import Point, context, error_rate, jacobian, points

from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.models import velocity_matching as vm
from alignment_core.estimation.models.seed000 import Seed000Linear
from alignment_core.estimation.models.seed001 import Seed001Doppler
from alignment_core.estimation.models.seed002 import Seed002Horizontal
from alignment_core.estimation.models.seed003 import Seed003VelocityAttitude
from alignment_core.gauss_markov import BETA_TAU
from alignment_core.units import ARCMIN

R_EARTH = 6.378e6
CFG = FilterConfig()


def _vm_rate(p: Point):
    def rate(x):
        d = error_rate(p, phi=x[0:3], dv=x[3:6], eps=x[6:9], nabla=x[9:12])
        return np.concatenate([d['phi'], d['dv'], np.zeros(6)])
    return rate


VM_STEPS = np.repeat([1e-4, 1e-2, 1e-6, 1e-3], 3)


def _neglected_bound(p: Point) -> float:
    v = float(np.linalg.norm(p.ins.v))
    return 2.0 * (1.0 + v * (1.0 + abs(np.tan(p.ins.lat)))) / R_EARTH


def _check_velocity_model(f: np.ndarray, j: np.ndarray, p: Point) -> None:
    np.testing.assert_allclose(f, j, rtol=0, atol=_neglected_bound(p))
    big = np.abs(j) > 1e-3
    np.testing.assert_allclose(f[big], j[big], rtol=1e-6)


@pytest.mark.parametrize('k', range(3))
def test_vm12_f_matches_the_nonlinear_error_propagation(k):
    p = points()[k]
    f = vm.continuous(p.ins.c, p.f_n, context(p).w_ie, context(p).w_en)
    _check_velocity_model(f, jacobian(_vm_rate(p), 12, VM_STEPS), p)


def test_vm_transition_is_the_second_order_expansion_of_f():
    p = points()[0]
    c = context(p, h=0.01)
    f = vm.continuous(c.c_nb, c.f_n, c.w_ie, c.w_en, 15)
    fh = f * c.h
    np.testing.assert_allclose(vm.transition(c.c_nb, c.f_n, c.w_ie, c.w_en, c.h, 15),
                               np.eye(15) + fh + fh @ fh / 2, rtol=0, atol=1e-15)
    # and it is expm(F h) to third order: |F h|^3 / 6 ~ (2e-1 * 1e-2)^3 / 6
    np.testing.assert_allclose(vm.transition(c.c_nb, c.f_n, c.w_ie, c.w_en, c.h, 15), expm(fh), atol=1e-8)


@pytest.mark.parametrize('k', range(3))
def test_seed000_6_is_the_phi_dv_block_of_vm12(k):
    """With zero (absent) biases the 6-state model must be vm12's phi/dV block: F, Phi, Qd."""
    c = context(points()[k])
    m = Seed000Linear(CFG)
    big = vm.VelocityMatching(CFG, master_states=False)
    np.testing.assert_array_equal(m.continuous(c), big.continuous(c)[0:6, 0:6])
    np.testing.assert_allclose(m.transition(c), big.transition(c)[0:6, 0:6], rtol=1e-15, atol=1e-18)
    np.testing.assert_array_equal(m.process_noise(0.01), big.process_noise(0.01)[0:6, 0:6])
    np.testing.assert_array_equal(m.initial_covariance(), big.initial_covariance()[0:6, 0:6])


@pytest.mark.parametrize('k', range(3))
def test_seed000_6_f_matches_the_nonlinear_error_propagation(k):
    p = points()[k]

    def rate(x):
        d = error_rate(p, phi=x[0:3], dv=x[3:6])
        return np.concatenate([d['phi'], d['dv']])
    _check_velocity_model(Seed000Linear(CFG).continuous(context(p)), jacobian(rate, 6, VM_STEPS[:6]), p)


@pytest.mark.parametrize('k', range(3))
def test_seed002_10_f_matches_the_nonlinear_error_propagation(k):
    """Horizontal channel only, vertical velocity held (dV_U = 0), accelerometer z bias absent."""
    p = points()[k]

    def rate(x):
        d = error_rate(p, phi=x[2:5], dv=[x[0], x[1], 0.0], nabla=[x[5], x[6], 0.0], eps=x[7:10],
                       hold_vertical=True)
        return np.concatenate([d['dv'][0:2], d['phi'], np.zeros(5)])
    steps = np.array([1e-2, 1e-2, 1e-4, 1e-4, 1e-4, 1e-3, 1e-3, 1e-6, 1e-6, 1e-6])
    _check_velocity_model(Seed002Horizontal(CFG).continuous(context(p)), jacobian(rate, 10, steps), p)


@pytest.mark.parametrize('master', [False, True])
def test_seed003_f_navigation_block_and_flexure(master):
    """Navigation block against the reference (mu, theta do not enter the dynamics: zero
    columns there); flexure block = the second-order Markov process written out from its
    definition theta'' + 2 beta theta' + beta^2 theta = w, and its exact discretisation."""
    cfg = FilterConfig(flexure_sigma_arcmin=(2.0, 3.0, 5.0), flexure_tau_s=(2.0, 4.0, 8.0))
    m = Seed003VelocityAttitude(cfg, master)
    n = 24 if master else 21
    assert m.n == n and len(m.labels) == n
    p = points()[0]
    c = context(p)
    f = m.continuous(c)
    j = jacobian(_vm_rate(p), 12, VM_STEPS)
    _check_velocity_model(f[0:12, 0:12], j, p)
    assert not np.any(f[0:12, 12:]) and not np.any(f[12:15, :])
    beta = BETA_TAU / np.array([2.0, 4.0, 8.0])
    for i in range(3):
        th, thd = 15 + i, 18 + i
        a = np.array([[0.0, 1.0], [-beta[i] ** 2, -2.0 * beta[i]]])
        np.testing.assert_allclose(f[np.ix_([th, thd], [th, thd])], a, rtol=1e-15)
        phi = m.transition(c)
        np.testing.assert_allclose(phi[np.ix_([th, thd], [th, thd])], expm(a * c.h), rtol=1e-12, atol=1e-15)
        # stationary: P = Phi P Phi^T + Qd with P = diag(sigma^2, beta^2 sigma^2)
        s2 = (cfg.flexure_sigma_arcmin[i] * ARCMIN) ** 2
        p_inf = np.diag([s2, beta[i] ** 2 * s2])
        ph = phi[np.ix_([th, thd], [th, thd])]
        qd = m.process_noise(c.h)[np.ix_([th, thd], [th, thd])]
        np.testing.assert_allclose(ph @ p_inf @ ph.T + qd, p_inf, rtol=1e-9, atol=1e-20)


@pytest.mark.parametrize('k', range(3))
def test_seed001_f_matches_the_nonlinear_error_propagation(k):
    """Aircraft speeds (60 m/s): the position terms are kept, so the agreement is tight."""
    p = points(speed=60.0)[k]

    def rate(x):
        d = error_rate(p, phi=x[0:3], dv=[x[3], x[4], 0.0], dlon=x[5], dlat=x[6], eps=x[7:10], hold_vertical=True)
        return np.concatenate([d['phi'], d['dv'][0:2], [d['dlon'], d['dlat']], np.zeros(6)])
    steps = np.array([1e-4, 1e-4, 1e-4, 1e-2, 1e-2, 1e-6, 1e-6, 1e-6, 1e-6, 1e-6, 1.0, 1.0, 1.0])
    j = jacobian(rate, 13, steps)
    f = Seed001Doppler().continuous(context(p))
    dlat = 6
    rest = np.arange(13) != dlat
    np.testing.assert_allclose(f[:, rest], j[:, rest], rtol=1e-5, atol=1e-10)
    # the dlat column also holds the latitude derivatives of the radii the model neglects
    v = float(np.linalg.norm(p.ins.v))
    np.testing.assert_allclose(f[:, dlat], j[:, dlat], rtol=0, atol=0.0067 * v * (v + 1.0) / R_EARTH)
