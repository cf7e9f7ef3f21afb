"""Stacks of rotations compiled with numpy's bits (geometry/rotation_stacks.py)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from alignment_core.geometry.rotation_stacks import _product, fma, products, right_jacobians, rotated
from alignment_core.geometry.rotations import right_jacobian, rotvec_to_dcm_batch


def _bits(a: np.ndarray) -> bytes:
    return np.ascontiguousarray(a, dtype=float).tobytes()


def test_the_compiled_rotations_are_numpys_bit_for_bit():
    """rotated, products and right_jacobians against the numpy they replaced (their
    3 x 3 products are BLAS's fused multiply-adds), on both sides of the small-angle series and
    with zero components; interpreted (exact fma by fractions), the same bits."""
    rng = np.random.default_rng(5)
    v = rng.standard_normal((400, 3, 3)) * np.logspace(-9, 0.5, 400)[:, None, None]
    v[:5, 0] = 0.0
    v[5:10, 1, 1:] = 0.0
    c = Rotation.random(400, random_state=6).as_matrix()
    want = c[:, None] @ rotvec_to_dcm_batch(v)
    assert _bits(rotated(c, v)) == _bits(want)
    assert _bits(rotated(c[:1], v.reshape(1, -1, 3))) == _bits(c[:1] @ rotvec_to_dcm_batch(v))
    assert _bits(right_jacobians(v)) == _bits(right_jacobian(v))
    assert _bits(products(want, rotvec_to_dcm_batch(v))) == _bits(want @ rotvec_to_dcm_batch(v))
    assert _bits(rotated.py_func(c[:20], v[:20])) == _bits(want[:20])
    assert _bits(right_jacobians.py_func(v[:20])) == _bits(right_jacobian(v[:20]))


def test_the_rotation_stacks_refuse_shapes_that_do_not_agree():
    """numba checks no bounds: stacks whose shapes do not agree raise before any read."""
    c, v = np.tile(np.eye(3), (4, 1, 1)), np.zeros((4, 2, 3))
    with pytest.raises(ValueError):
        rotated(c[:3], v)
    with pytest.raises(ValueError):
        products(c, c[:3])


def test_fma_interpreted_is_the_compiled_fused_multiply_add():
    """The interpreted fma (exact by fractions) gives the CPU's fused multiply-add, bit for bit:
    a product whose rounding the sum exposes, signed zeros, infinities, NaN and overflow (each
    case as fma(x, y, z) in a 3 x 3 product's chain, compiled and interpreted)."""
    big, tiny = 1.7e308, 5e-324
    a = 1.0 + 2.0**-30
    cases = [(a, a, -1.0), (-0.0, 1.0, -0.0), (0.0, -1.0, 0.0), (-0.0, 1.0, 0.0), (1.0, 1.0, -1.0),
             (-2.0, 3.0, 6.0), (big, 2.0, 0.0), (big, -2.0, 0.0), (big, 2.0, -big), (tiny, 0.5, 0.0),
             (np.inf, 0.0, 1.0), (np.inf, 1.0, -np.inf), (np.nan, 1.0, 1.0), (1.0, 2.0, np.inf),
             (3.0, 1.0 / 3.0, -1.0)]
    assert fma(a, a, -1.0) != a * a - 1.0              # the case the single rounding shows
    for x, y, z in cases:
        ma, mb = np.zeros((3, 3)), np.zeros((3, 3))
        ma[0] = -0.0, 1.0, x                            # out[0, 0] = fma(x, y, fma(1, z, -0 * 0)) = fma(x, y, z)
        mb[:, 0] = 0.0, z, y
        compiled, interpreted = np.empty((3, 3)), np.empty((3, 3))
        _product(ma, mb, compiled)
        with np.errstate(invalid='ignore', over='ignore'):   # numpy's scalars warn of inf * 0
            _product.py_func(ma, mb, interpreted)
        got, want = interpreted[0, 0], compiled[0, 0]
        assert (np.isnan(got) and np.isnan(want)) or got.tobytes() == want.tobytes(), (x, y, z)


def test_a_zero_or_underflowed_product_has_numpys_sign():
    """An entry whose terms are all zero or underflow to negative values is +0, as numpy's BLAS
    gives it (the zeroed output added after the chain), compiled and interpreted; products of
    tiny and huge matrices are numpy's bit for bit."""
    tiny = np.full((2, 3, 3), 1e-170)
    for a, b in ((np.full((2, 3, 3), -1.0), np.zeros((2, 3, 3))), (tiny, -tiny),
                 (0.5 * np.eye(3)[None].repeat(2, axis=0), np.full((2, 3, 3), -5e-324))):
        assert products(a, b).tobytes() == (a @ b).tobytes() and not np.signbit(products(a, b)).any()
        assert products.py_func(a, b).tobytes() == (a @ b).tobytes()
    rng = np.random.default_rng(9)
    for scale in (1e-300, 1e-162, 1e300):
        a, b = rng.standard_normal((500, 3, 3)) * scale, rng.standard_normal((500, 3, 3)) * scale
        with np.errstate(over='ignore', under='ignore'):
            assert products(a, b).tobytes() == (a @ b).tobytes()
