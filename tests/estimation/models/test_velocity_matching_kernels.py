"""The velocity-matching model's compiled kernels (transition, misalignment) and the shared
relative_misalignment equal their interpreted forms bit for bit, and the transition is still
I + F h + (F h)^2 / 2 of the continuous model."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core.estimation.models import base
from alignment_core.estimation.models import velocity_matching as vm
from alignment_core.geometry.rotations import rotvec_to_dcm


def _dcm(rng, scale=0.5):
    return rotvec_to_dcm(rng.standard_normal(3) * scale)


def _same(a, b):
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


@pytest.mark.parametrize('n', [12, 15])
def test_transition_compiled_equals_interpreted_and_the_series(n):
    rng = np.random.default_rng(21)
    for _ in range(100):
        c, f = _dcm(rng), rng.standard_normal(3) * 10
        w_ie, w_en = rng.standard_normal(3) * 1e-4, rng.standard_normal(3) * 1e-5
        h = float(rng.choice([0.0025, 0.01]))
        idx = vm._fh_index(n)
        got = vm.transition(c, f, w_ie, w_en, h, n)
        assert _same(got, vm.phi_from_cells.py_func(c, f, w_ie, w_en, h, idx, n, n))
        fh = vm.continuous(c, f, w_ie, w_en, n) * h
        assert np.allclose(got, np.eye(n) + fh + fh @ fh / 2, rtol=0.0, atol=1e-15)
        # with states appended (random constants): the same block in an identity, exactly
        wide = vm.transition(c, f, w_ie, w_en, h, n, n + 4)
        assert _same(wide, vm.phi_from_cells.py_func(c, f, w_ie, w_en, h, idx, n, n + 4))
        grown = np.eye(n + 4)
        grown[:n, :n] = got
        assert _same(wide, grown)


@pytest.mark.parametrize('dtype', [np.float64, np.float32])
@pytest.mark.parametrize('master_states', [True, False])
def test_misalignment_compiled_equals_interpreted(dtype, master_states):
    rng = np.random.default_rng(22)
    for _ in range(100):
        q = rng.standard_normal(4)
        q /= np.sqrt(q @ q)
        c_m, x = _dcm(rng), rng.standard_normal(15) * 1e-3
        a = rng.standard_normal((15, 15))
        p = (a @ a.T * 1e-6).astype(dtype)
        got = vm.misalignment_k(q, c_m, x, p, master_states)
        want = vm.misalignment_k.py_func(q, c_m, x, p, master_states)
        assert all(_same(g, w) for g, w in zip(got, want))


def test_relative_misalignment_compiled_equals_interpreted_and_is_the_log():
    rng = np.random.default_rng(23)
    for _ in range(100):
        phi = rng.standard_normal(3) * 0.01
        c_m = _dcm(rng)
        c_na = c_m @ rotvec_to_dcm(phi)                  # C_a = C_m exp([phi x]): mu = phi
        p = np.diag(rng.uniform(1e-8, 1e-6, 3))
        mu, sigma = base.relative_misalignment(c_m, c_na, p)
        want = base.relative_misalignment_k.py_func(c_m, c_na, p)
        assert _same(mu, want[0]) and _same(sigma, want[1])
        assert np.allclose(mu, phi, rtol=0.0, atol=1e-15)
        assert np.allclose(sigma, np.sqrt(np.diag(c_na.T @ p @ c_na)), rtol=1e-14, atol=0.0)


@pytest.mark.parametrize('dtype', [np.float64, np.float32])
@pytest.mark.parametrize('n', [12, 15])
def test_feedback_is_the_numpy_feedback(dtype, n):
    """C <- exp([phi x]) C (scipy's rotation composed on the left), V - dV, the biases plus their
    estimates, the state zeroed but the master's: numpy's arithmetic on the float64 of x, bit for
    bit, compiled and interpreted."""
    import dataclasses

    from scipy.spatial.transform import Rotation

    from alignment_core.estimation.config import FilterConfig
    from alignment_core.estimation.models.base import Corrections
    from alignment_core.geometry.rotations_compiled import rotate_attitude
    from alignment_core.navigation.strapdown import NavState
    model = vm.VelocityMatching(dataclasses.replace(FilterConfig(), model=f'vm{n}'), n == 15)
    rng = np.random.default_rng(23)
    for k in range(100):
        q = Rotation.random(random_state=k).as_quat()
        v, bg, ba = rng.standard_normal(3) * 10, rng.standard_normal(3) * 1e-5, rng.standard_normal(3) * 1e-3
        x = (rng.standard_normal(n) * 1e-3).astype(dtype)
        nav = NavState(q_nb=q.copy(), v_n=v.copy(), lat=0.6, lon=2.0, h=10.0)
        corr = Corrections(bg=bg.copy(), ba=ba.copy())
        x_new = model.feedback(x, np.eye(n), None, nav, corr)
        assert np.array_equal(nav.q_nb, rotate_attitude(q, x[0:3]))
        np.testing.assert_allclose(Rotation.from_quat(nav.q_nb).as_matrix(),
                                   (Rotation.from_rotvec(x[0:3].astype(float)) * Rotation.from_quat(q)).as_matrix(),
                                   atol=1e-15)
        assert np.array_equal(nav.v_n, v - x[3:6]) and np.array_equal(corr.bg, bg + x[6:9])
        assert np.array_equal(corr.ba, ba + x[9:12])
        want = np.zeros(n)
        want[12:] = x[12:]
        assert _same(x_new, want)
        got = vm.feedback_k.py_func(q, v, bg, ba, x.astype(float))
        for a, b in zip(got, (nav.q_nb, nav.v_n, corr.bg, corr.ba, x_new)):
            assert _same(a, b)


@pytest.mark.parametrize('n', [12, 15, 19])
def test_measurement_is_the_velocity_identity_and_minus_u_cross(n):
    """H (3, n): I at the velocity columns, -[u x] at columns 12-14 when the master's attitude
    states are there (written out from the cross product here), zero elsewhere; the compiled
    kernel equal to its interpreted form bit for bit, signed zeros included."""
    rng = np.random.default_rng(n)
    for u in [rng.standard_normal(3), np.array([0.0, -0.0, 1.5]), np.array([np.nan, 2.0, -np.inf])]:
        h = vm.measurement(u, n)
        want = np.zeros((3, n))
        want[:, 3:6] = np.eye(3)
        if n >= 15:
            x, y, z = u
            want[:, 12:15] = -np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
        np.testing.assert_array_equal(h, want)
        assert _same(vm.measurement_k(u, n), vm.measurement_k.py_func(u, n))
