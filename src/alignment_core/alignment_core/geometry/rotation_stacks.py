"""Stacks of 3 x 3 rotations compiled with numpy's bits: exp([v x]) times a matrix, the right
Jacobian J_r(v), and products of two stacks, for the aircraft's kinematics at many instants
(aircraft/kinematics.py). numpy's 3 x 3 matrix product goes through BLAS's gemm, which rounds
each entry as a chain of fused multiply-adds over the inner index and then adds the zeroed
output; the kernels make the same chain (`fma`: the CPU's fused multiply-add compiled, exact by
fractions interpreted), so they give numpy's numbers without its temporaries. Should a numpy or
BLAS upgrade change that rounding, the tests against numpy (tests/geometry/test_rotation_stacks.py)
say so."""
from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

from alignment_core.compiled import kernel, on_numba


def fma(a: float, b: float, c: float) -> float:
    """a b + c rounded once, as BLAS's 3 x 3 products accumulate (`rotated`); compiled, the
    CPU's fused multiply-add. A non-finite operand, or an exact zero (then a b is exact), gives
    what the unfused a b + c gives; an exact sum beyond the float range, an infinity."""
    if not (math.isfinite(a) and math.isfinite(b) and math.isfinite(c)):
        return a * b + c
    exact = Fraction(a) * Fraction(b) + Fraction(c)
    if exact == 0:
        return a * b + c
    try:
        return float(exact)
    except OverflowError:
        return math.inf if exact > 0 else -math.inf


@on_numba
def _fma_overload() -> None:
    from llvmlite import ir
    from numba import types
    from numba.extending import intrinsic, overload

    @intrinsic
    def fused(typingctx, a, b, c):
        def codegen(context, builder, signature, args):
            d = ir.DoubleType()
            return builder.call(builder.module.declare_intrinsic('llvm.fma', [d], ir.FunctionType(d, [d, d, d])), args)
        return types.float64(types.float64, types.float64, types.float64), codegen

    overload(fma)(lambda a, b, c: lambda a, b, c: fused(a, b, c))    # type: ignore[call-arg]  # numba types it


@kernel
def _entry(x0, y0, x1, y1, x2, y2):
    """x . y of three pairs as OpenBLAS's gemm rounds an entry of a matrix product: a chain of
    fused multiply-adds over the inner index, then the zeroed output added (+0.0: a zero or an
    underflowed sum comes out +0, as numpy gives it)."""
    return fma(x2, y2, fma(x1, y1, x0 * y0)) + 0.0


@kernel
def _product(a, b, out):
    """out <- a @ b (3, 3) as numpy's matmul rounds it (`_entry`)."""
    for i in range(3):
        for j in range(3):
            out[i, j] = _entry(a[i, 0], b[0, j], a[i, 1], b[1, j], a[i, 2], b[2, j])


@kernel
def _skew_terms(x, y, z, s, c, sign, out):
    """out <- I + sign s [v x] + c [v x]^2 (3, 3) of v = (x, y, z), in numpy's order: the identity
    plus (or minus) s [v x], then c times the product [v x] [v x] (as `_product` rounds it)."""
    k = ((0.0, -z, y), (z, 0.0, -x), (-y, x, 0.0))
    for i in range(3):
        for j in range(3):
            kk = _entry(k[i][0], k[0][j], k[i][1], k[1][j], k[i][2], k[2][j])
            e = 1.0 if i == j else 0.0
            out[i, j] = (e + s * k[i][j] if sign > 0 else e - s * k[i][j]) + c * kk


@kernel
def rotated(c, v):
    """c[m] exp([v[m, j] x]) (M, J, 3, 3) of matrices c (M, 3, 3) and rotation vectors v (M, J, 3):
    numpy's c[:, None] @ rotations.rotvec_to_dcm_batch(v), bit for bit, without its temporaries."""
    if c.shape[0] != v.shape[0] or c.shape[1] != 3 or c.shape[2] != 3 or v.shape[2] != 3:
        raise ValueError('rotated: matrices (M, 3, 3) and rotation vectors (M, J, 3)')
    m, n = v.shape[0], v.shape[1]
    out = np.empty((m, n, 3, 3))
    r = np.empty((3, 3))
    for i in range(m):
        for j in range(n):
            x, y, z = v[i, j, 0], v[i, j, 1], v[i, j, 2]
            a2 = x * x + y * y + z * z
            if a2 < 1e-12:
                _skew_terms(x, y, z, 1.0 - a2 / 6.0, 0.5 - a2 / 24.0, 1, r)
            else:
                a = np.sqrt(a2)
                _skew_terms(x, y, z, np.sin(a) / a, (1.0 - np.cos(a)) / a2, 1, r)
            _product(c[i], r, out[i, j])
    return out


@kernel
def products(a, b):
    """a @ b (..., 3, 3) of two stacks of matrices of one shape, as numpy's matmul rounds them."""
    if a.shape != b.shape or a.shape[-2:] != (3, 3):
        raise ValueError('products: two stacks of 3 x 3 matrices of one shape')
    x, y = np.ascontiguousarray(a).reshape(-1, 3, 3), np.ascontiguousarray(b).reshape(-1, 3, 3)
    out = np.empty(x.shape)
    for i in range(x.shape[0]):
        _product(x[i], y[i], out[i])
    return out.reshape(a.shape)


@kernel
def right_jacobians(theta):
    """J_r(theta) (..., 3, 3) of rotation vectors theta (..., 3): rotations.right_jacobian's numbers."""
    v = np.ascontiguousarray(theta).reshape(-1, 3)
    out = np.empty((v.shape[0], 3, 3))
    for i in range(v.shape[0]):
        x, y, z = v[i, 0], v[i, 1], v[i, 2]
        a2 = x * x + y * y + z * z
        if a2 < 1e-8:
            _skew_terms(x, y, z, 0.5 - a2 / 24.0, 1.0 / 6.0 - a2 / 120.0, -1, out[i])
        else:
            a = np.sqrt(a2)
            _skew_terms(x, y, z, (1.0 - np.cos(a)) / a2, (a - np.sin(a)) / (a2 * a), -1, out[i])
    return out.reshape(theta.shape + (3,))
