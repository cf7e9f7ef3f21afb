"""The cubic Hermite of an IMU interval at its quadrature nodes (aircraft/interval_hermite.py)."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core.aircraft.interval_hermite import hermite_nodes
from alignment_core.aircraft.kinematics import GL_NODES, HERMITE


def _bits(a: np.ndarray) -> bytes:
    return np.ascontiguousarray(a, dtype=float).tobytes()


def _numpy_form(x0, dx0, x1, dx1, h):
    """The numpy form hermite_nodes replaced in the increments: value, rate and integral."""
    hk, uu = h[:, None, None], GL_NODES[None, :, None]
    basis = [[2*uu**3 - 3*uu**2 + 1, uu**3 - 2*uu**2 + uu, -2*uu**3 + 3*uu**2, uu**3 - uu**2],
             [6*uu**2 - 6*uu, 3*uu**2 - 4*uu + 1, -6*uu**2 + 6*uu, 3*uu**2 - 2*uu],
             [uu**4/2 - uu**3 + uu, uu**4/4 - 2*uu**3/3 + uu**2/2, -uu**4/2 + uu**3, uu**4/4 - uu**3/3]]

    def herm(b0, b1, b2, b3):
        return b0 * x0[:, None] + b1 * hk * dx0[:, None] + b2 * x1[:, None] + b3 * hk * dx1[:, None]
    with np.errstate(divide='ignore', invalid='ignore'):
        return [herm(*basis[0]), herm(*basis[1]) / hk, hk * herm(*basis[2])]


def test_the_compiled_hermite_is_numpys_bit_for_bit():
    """hermite_nodes against the numpy form it replaced in the increments: the cubic
    Hermite's value, rate and integral at the Gauss nodes, each node's sums in the same order."""
    rng = np.random.default_rng(7)
    x0, dx0, x1, dx1 = (rng.standard_normal((300, 3)) for _ in range(4))
    h = rng.uniform(0.005, 0.02, 300)
    want = _numpy_form(x0, dx0, x1, dx1, h)
    got = hermite_nodes(x0, dx0, x1, dx1, h, HERMITE)
    for i in range(3):
        assert _bits(got[i]) == _bits(want[i])
    assert _bits(hermite_nodes(x0, dx0, x1, dx1, h, HERMITE[:2])) == _bits(got[:2])
    assert _bits(hermite_nodes.py_func(x0, dx0, x1, dx1, h, HERMITE)) == _bits(got)


def test_the_hermite_refuses_ends_that_do_not_agree():
    """numba checks no bounds: ends or interval lengths of other counts raise before any read."""
    x = np.zeros((4, 3))
    with pytest.raises(ValueError):
        hermite_nodes(x, x, x[:3], x, np.ones(4), HERMITE)
    with pytest.raises(ValueError):
        hermite_nodes(x, x, x, x, np.ones(3), HERMITE)


def test_a_zero_length_interval_gives_numpys_infinities_and_nans():
    """The rate divides by the interval's length: at h = +0 and -0, numpy's bits (infinities of
    the quotient's sign, the CPU's NaN for 0 / 0, a NaN passed on with its sign), where a
    kernel's own division raises; ends of any memory layout, zeros and NaNs among them."""
    rng = np.random.default_rng(3)
    x = rng.standard_normal((12, 3))
    x0, dx0, x1, dx1 = x[::2], np.asfortranarray(x[1::2]), rng.standard_normal((6, 3)), np.zeros((6, 3))
    x0[3], x1[3] = 0.0, 0.0                          # 0 / 0
    x0[4, 0], x1[5, 1] = np.nan, -np.nan             # NaNs of either sign
    h = np.array([0.01, 0.0, -0.0, 0.0, -0.0, 0.0])
    got = hermite_nodes(x0, dx0, x1, dx1, h, HERMITE)
    want = _numpy_form(x0, dx0, x1, dx1, h)
    for i in range(3):
        assert got[i].tobytes() == want[i].tobytes()
    rate = got[1, 1:]
    assert np.any(np.isinf(rate)) and np.any(np.isnan(rate))
