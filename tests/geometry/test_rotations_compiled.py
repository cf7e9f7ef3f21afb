"""The compiled float forms of the rotations (and the strapdown's Earth terms) equal the
interpreted functions bit for bit, on both sides of their small-angle branches."""
from __future__ import annotations

import math

import numpy as np
import pytest

from alignment_core.geometry import earth, rotations
from alignment_core.geometry import rotations_compiled as rc
from alignment_core.navigation import strapdown


def _vectors(rng, n=300):
    scales = (1e-9, 1e-7, 1e-5, 1e-2, 1.0, 3.0)        # |v|^2 around the 1e-12 branch and far from it
    return [tuple(float(c) for c in rng.standard_normal(3) * s) for s in scales for _ in range(n // len(scales))]


def test_rotvec_forms():
    rng = np.random.default_rng(1)
    for v in _vectors(rng):
        assert rc.rotvec_to_quat_k(*v) == rotations.rotvec_to_quat_f(*v)
        assert rc.rotvec_to_dcm_k(*v) == rotations.rotvec_to_dcm_f(*v)


def test_quaternion_forms():
    rng = np.random.default_rng(2)
    for _ in range(300):
        a = tuple(float(c) for c in rng.standard_normal(4))
        b = tuple(float(c) for c in rng.standard_normal(4))
        assert rc.quat_mul_k(a, b) == rotations.quat_mul_f(a, b)
        assert rc.normalized_k(a) == rotations.normalized_f(a)
        assert rc.quat_to_dcm_k(a) == rotations.quat_to_dcm_f(a)


def test_dcm_to_rotvec_form():
    rng = np.random.default_rng(3)
    for v in _vectors(rng):
        c = rotations.rotvec_to_dcm_f(*v)
        args = (c[0], c[4], c[8], c[1], c[2], c[3], c[5], c[6], c[7])
        assert rc.dcm_to_rotvec_k(*args) == rotations.dcm_to_rotvec_f(*args)
    assert rc.dcm_to_rotvec_k(1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0) == (0.0, 0.0, 0.0)


def test_earth_terms():
    rng = np.random.default_rng(4)
    for _ in range(300):
        lat, h = float(rng.uniform(-1.5, 1.5)), float(rng.uniform(-100.0, 12000.0))
        ve, vn = (float(c) for c in rng.standard_normal(2) * 100.0)
        assert strapdown._local_terms(lat, h, ve, vn) == earth.local_terms(lat, h, ve, vn)


def test_libm_functions_round_as_pythons():
    """sin, cos, atan2, sqrt: the compiled kernels call the same C library as math."""
    rng = np.random.default_rng(5)
    xs = [float(x) for x in rng.uniform(-10.0, 10.0, 2000)] + [1e-300, 0.5, math.pi / 2]
    k = rc.rotvec_to_quat_k
    for x in xs:
        assert k(x, 0.0, 0.0) == rotations.rotvec_to_quat_f(x, 0.0, 0.0)


@pytest.mark.parametrize('fun', [rc.quat_mul_k, rc.quat_to_dcm_k])
def test_the_interpreted_function_is_kept(fun):
    assert fun.py_func.__module__ == 'alignment_core.geometry.rotations'
