"""The compiled float forms of the rotations (and the strapdown's Earth terms) equal the
interpreted functions bit for bit, on both sides of their small-angle branches."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

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


def test_rotate_attitude_turns_the_nav_frame():
    # exp([phi x]) C_b^n: the nav-frame rotation applied on the left (scipy's composition)
    q = Rotation.from_euler('ZYX', [40.0, -3.0, 7.0], degrees=True)
    phi = np.array([2e-3, -1e-3, 4e-2])
    got = rc.rotate_attitude(q.as_quat(), phi)
    np.testing.assert_allclose(rotations.quat_to_dcm(got), (Rotation.from_rotvec(phi) * q).as_matrix(), atol=1e-15)
    assert np.linalg.norm(got) == pytest.approx(1.0, abs=1e-15)


def test_rotate_attitude_is_the_float_forms_composition():
    """Bit for bit the interpreted float forms, for float32 operands too (taken exactly)."""
    rng = np.random.default_rng(6)
    for v in _vectors(rng):
        q = rng.standard_normal(4)
        q /= np.linalg.norm(q)
        want = rotations.normalized_f(rotations.quat_mul_f(rotations.rotvec_to_quat_f(*v), tuple(q.tolist())))
        assert tuple(rc.rotate_attitude(q, np.array(v)).tolist()) == want
        assert tuple(rc.rotate_attitude_k.py_func(q, np.array(v)).tolist()) == want
    q32, v32 = np.array([0.1, -0.2, 0.3, 0.9], np.float32), np.array([1e-3, 2e-3, -3e-3], np.float32)
    assert np.array_equal(rc.rotate_attitude(q32, v32), rc.rotate_attitude(q32.astype(float), v32.astype(float)))
