"""Attitude conventions and Euler kinematics against explicit matrices and numerical
derivatives of the direction-cosine matrix (omega_nb^b = vee(C^T dC/dt))."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from alignment_core import units
from alignment_core.geometry import euler, rotations


def rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def vee(m):
    """Axial vector of the skew-symmetric part of m."""
    a = 0.5 * (m - m.T)
    return np.array([a[2, 1], a[0, 2], a[1, 0]])


def random_euler(rng, n):
    e = np.empty((n, 3))
    e[:, 0] = rng.uniform(-np.pi, np.pi, n)
    e[:, 1] = rng.uniform(-1.3, 1.3, n)           # away from the pitch singularity
    e[:, 2] = rng.uniform(-np.pi, np.pi, n)
    return e


def test_skew_is_cross_product():
    rng = np.random.default_rng(1)
    for _ in range(10):
        v, u = rng.standard_normal(3), rng.standard_normal(3)
        np.testing.assert_allclose(rotations.skew(v) @ u, np.cross(v, u), atol=1e-15)
        np.testing.assert_allclose(vee(rotations.skew(v)), v, atol=1e-15)
    # batch over leading axes
    v, u = rng.standard_normal((4, 2, 3)), rng.standard_normal((4, 2, 3))
    k = rotations.skew(v)
    assert k.shape == (4, 2, 3, 3)
    np.testing.assert_allclose(np.einsum('...ij,...j->...i', k, u), np.cross(v, u), atol=1e-15)


def test_skew_of_one_vector_is_the_batch_cell_for_cell():
    """One float64 vector takes a shorter path: the same cells, signed zeros included, as the same
    vector in a batch; other inputs (a list, float32, ints) as before."""
    rng = np.random.default_rng(2)
    for v in [rng.standard_normal(3), np.array([0.0, -0.0, 2.5]), np.array([-0.0, 1e-300, -np.inf])]:
        k = rotations.skew(v)
        assert k.shape == (3, 3) and k.dtype == np.float64
        assert k.tobytes() == rotations.skew(v[None])[0].tobytes()
    for v in ([1.0, 2.0, 3.0], np.array([1, 2, 3]), np.array([1.0, 2.0, 3.0], dtype=np.float32)):
        assert rotations.skew(v).tobytes() == rotations.skew(np.asarray(v, dtype=float)[None])[0].tobytes()


def test_skew_into_and_its_cells_write_the_skew_block():
    v = np.array([0.3, -1.1, 2.5])
    m = np.full((5, 7), 9.0)
    rotations.skew_into(m, 1, 3, v)
    want = np.full((5, 7), 9.0)
    want[1:4, 3:6] = np.cross(v, np.eye(3)).T + np.diag([9.0, 9.0, 9.0])   # columns: v x e_j; diagonal untouched
    np.testing.assert_array_equal(m, want)
    flat = np.zeros((5, 7))
    flat[tuple(zip(*rotations.skew_cells(1, 3), strict=True))] = rotations.skew_values(*v)
    np.testing.assert_array_equal(flat[1:4, 3:6], np.cross(v, np.eye(3)).T)


def test_unit_constants():
    assert 60 * units.ARCMIN == pytest.approx(np.pi / 180)
    assert 3600 * units.DPH == pytest.approx(np.pi / 180)
    assert units.G0 == 9.80665


def test_euler_to_dcm_is_rz_ry_rx():
    rng = np.random.default_rng(2)
    e = random_euler(rng, 20)
    c = euler.euler_to_dcm(e[:, 0], e[:, 1], e[:, 2])
    for k in range(len(e)):
        np.testing.assert_allclose(c[k], rz(e[k, 2]) @ ry(e[k, 1]) @ rx(e[k, 0]), atol=1e-14)


def test_euler_sign_conventions():
    # positive pitch is nose down; yaw from East counter-clockwise; heading from North clockwise
    c = euler.euler_to_dcm(0.0, np.radians(10.0), 0.0)
    assert (c @ [1.0, 0.0, 0.0])[2] == pytest.approx(-np.sin(np.radians(10.0)))
    c = euler.euler_to_dcm(0.0, 0.0, np.pi / 2)
    np.testing.assert_allclose(c @ [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], atol=1e-15)   # nose North
    assert euler.heading_to_yaw(0.0) == pytest.approx(np.pi / 2)                       # heading N
    assert euler.heading_to_yaw(np.pi / 2) == pytest.approx(0.0)                       # heading E
    # positive roll is right wing (-y in FLU) down
    c = euler.euler_to_dcm(np.radians(10.0), 0.0, 0.0)
    assert (c @ [0.0, -1.0, 0.0])[2] < 0.0


def test_rotvec_dcm_round_trip():
    rng = np.random.default_rng(3)
    for _ in range(10):
        v = rng.standard_normal(3)
        v *= rng.uniform(0.0, 3.0) / np.linalg.norm(v)
        c = rotations.rotvec_to_dcm(v)
        # Rodrigues: I + sin a [u x] + (1 - cos a) [u x]^2
        a = np.linalg.norm(v)
        k = rotations.skew(v / a)
        np.testing.assert_allclose(c, np.eye(3) + np.sin(a) * k + (1 - np.cos(a)) * k @ k, atol=1e-14)
        np.testing.assert_allclose(rotations.dcm_to_rotvec(c), v, atol=1e-12)
        np.testing.assert_allclose(rotations.dcm_to_rotvec(Rotation.from_rotvec(v).as_matrix()), v, atol=1e-12)


def test_scalar_rodrigues_is_the_rotation_of_its_vector():
    for v in (np.array([1e-3, -2e-3, 5e-3]), np.array([0.3, -1.2, 2.0]), np.array([1e-8, 0.0, -3e-9]), np.zeros(3)):
        np.testing.assert_allclose(rotations.rotvec_to_dcm(v), Rotation.from_rotvec(v).as_matrix(), rtol=0, atol=1e-15)


def _dcm_derivative(e0, ed, t_step):
    """d/dt euler_to_dcm(e0 + ed t) at t = 0, fourth-order central difference."""
    def c(t):
        e = e0 + ed * t
        return euler.euler_to_dcm(e[0], e[1], e[2])
    h = t_step
    return (-c(2 * h) + 8 * c(h) - 8 * c(-h) + c(-2 * h)) / (12 * h)


def test_euler_rates_to_body_rate_matches_dcm_derivative():
    rng = np.random.default_rng(4)
    e = random_euler(rng, 50)
    ed = rng.uniform(-0.5, 0.5, (50, 3))
    w = euler.euler_rates_to_body_rate(e, ed)                 # vectorised call
    assert w.shape == (50, 3)
    for k in range(50):
        c = euler.euler_to_dcm(*e[k])
        w_num = vee(c.T @ _dcm_derivative(e[k], ed[k], 1e-3))
        # truncation ~ h^4 |ed|^5 / 30 ~ 1e-15, round-off ~ 1e-16 / h
        np.testing.assert_allclose(w[k], w_num, atol=1e-11)


def test_euler_acc_to_body_acc_matches_dcm_second_derivative():
    # omega' = vee(C^T C'') (C'^T C' is symmetric, so it drops out of the skew part);
    # C(t) = C(e0 + ed t + edd t^2 / 2), C'' by a fourth-order central difference
    rng = np.random.default_rng(5)
    e = random_euler(rng, 30)
    ed = rng.uniform(-0.5, 0.5, (30, 3))
    edd = rng.uniform(-0.3, 0.3, (30, 3))
    wd = euler.euler_acc_to_body_acc(e, ed, edd)
    assert wd.shape == (30, 3)
    h = 1e-2
    for k in range(30):
        def c(t, k=k):
            x = e[k] + ed[k] * t + 0.5 * edd[k] * t * t
            return euler.euler_to_dcm(x[0], x[1], x[2])
        cdd = (-c(2 * h) + 16 * c(h) - 30 * c(0.0) + 16 * c(-h) - c(-2 * h)) / (12 * h * h)
        np.testing.assert_allclose(wd[k], vee(c(0.0).T @ cdd), atol=1e-8)


def test_euler_acc_is_derivative_of_body_rate():
    rng = np.random.default_rng(6)
    e0 = random_euler(rng, 1)[0]
    ed0 = rng.uniform(-0.5, 0.5, 3)
    edd = rng.uniform(-0.3, 0.3, 3)

    def w(t):
        return euler.euler_rates_to_body_rate(e0 + ed0 * t + 0.5 * edd * t * t, ed0 + edd * t)
    h = 1e-3
    w_dot = (-w(2 * h) + 8 * w(h) - 8 * w(-h) + w(-2 * h)) / (12 * h)
    np.testing.assert_allclose(euler.euler_acc_to_body_acc(e0, ed0, edd), w_dot, atol=1e-11)


def test_rfu_to_flu_seed000_misalignment():
    # seed 000 gives (10', 15', -30') about right, forward, up; in forward-left-up that is
    # 15' about forward (roll), -10' about left (pitch), -30' about up (yaw)
    mu_rfu = np.array([10.0, 15.0, -30.0]) * units.ARCMIN
    mu_flu = euler.rfu_to_flu(mu_rfu)
    np.testing.assert_allclose(mu_flu, np.array([15.0, -10.0, -30.0]) * units.ARCMIN, atol=1e-18)
    np.testing.assert_allclose(euler.flu_to_rfu(mu_flu), mu_rfu, atol=1e-18)
    # vectorised
    np.testing.assert_allclose(euler.rfu_to_flu(np.stack([mu_rfu, 2 * mu_rfu])),
                               np.stack([mu_flu, 2 * mu_flu]), atol=1e-18)


def test_rfu_to_flu_is_a_proper_rotation_of_axes():
    # FLU axes are the RFU axes turned +90 deg about up (x_flu = y_rfu, y_flu = -x_rfu), so
    # components transform with Rz(+90 deg)^T = Rz(-90 deg)
    t = np.stack([euler.rfu_to_flu(e) for e in np.eye(3)], axis=1)   # columns: images of RFU axes
    np.testing.assert_allclose(t, rz(-np.pi / 2), atol=1e-15)
    assert np.linalg.det(t) == pytest.approx(1.0)
    # so a rotation expressed in RFU and in FLU axes agree: T exp([mu x]) T^T = exp([T mu x])
    mu_rfu = np.array([10.0, 15.0, -30.0]) * units.ARCMIN
    np.testing.assert_allclose(t @ rotations.rotvec_to_dcm(mu_rfu) @ t.T,
                               rotations.rotvec_to_dcm(euler.rfu_to_flu(mu_rfu)), atol=1e-15)


# ----- fast-path helpers used by the vectorised stages and the filter -----

def test_cross_helpers_match_cross_product():
    rng = np.random.default_rng(7)
    a, b = rng.standard_normal((5, 4, 3)), rng.standard_normal((5, 4, 3))
    # component definition of a x b
    want = np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
                     a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], axis=-1)
    np.testing.assert_allclose(rotations.cross(a, b), want, atol=1e-15)
    np.testing.assert_allclose(rotations.cross3(a[0, 0], b[0, 0]), want[0, 0], atol=1e-15)
    np.testing.assert_allclose(rotations.cross_f(a[0, 0].tolist(), b[0, 0].tolist()), want[0, 0], atol=1e-15)
    np.testing.assert_allclose(rotations.cross(a[0, 0], b)[2, 3], rotations.cross3(a[0, 0], b[2, 3]),
                               atol=1e-15)                               # broadcasting
    np.testing.assert_allclose(rotations.skew(a[0, 0]) @ b[0, 0], rotations.cross3(a[0, 0], b[0, 0]), atol=1e-15)


def test_quat_to_dcm_batch():
    rng = np.random.default_rng(8)
    q = rng.standard_normal((6, 2, 4))
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    c = rotations.quat_to_dcm_batch(q)
    assert c.shape == (6, 2, 3, 3)
    # a unit quaternion (u sin(a/2), cos(a/2)) is the rotation by a about u (Rodrigues)
    for qq, cc in zip(q.reshape(-1, 4), c.reshape(-1, 3, 3)):
        ang = 2.0 * np.arctan2(np.linalg.norm(qq[:3]), qq[3])
        k = rotations.skew(qq[:3] / np.linalg.norm(qq[:3]))
        np.testing.assert_allclose(cc, np.eye(3) + np.sin(ang) * k + (1 - np.cos(ang)) * k @ k,
                                   atol=1e-14)


@pytest.mark.parametrize('angle', [0.0, 1e-9, 9.9e-7, 1.01e-6, 1e-4, 0.3, 2.0, 3.1])
def test_rotvec_dcm_batch_scalar_and_inverse(angle):
    u = np.array([2.0, -1.0, 0.5]) / np.linalg.norm([2.0, -1.0, 0.5])
    v = angle * u
    k = rotations.skew(u)
    want = np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k          # Rodrigues
    c = rotations.rotvec_to_dcm_batch(np.stack([v, v]))
    np.testing.assert_allclose(c[0], want, atol=1e-15)
    np.testing.assert_allclose(rotations.rotvec_to_dcm(v), want, atol=1e-15)
    np.testing.assert_allclose(rotations.dcm_to_rotvec(want), v, atol=1e-14)


@pytest.mark.parametrize('angle', [0.0, 1e-9, 9.9e-7, 1.01e-6, 1e-4, 0.3, 2.0, 3.1])
def test_rotvec_quaternion_forms_against_scipy(angle):
    u = np.array([-0.4, 1.0, 0.7]) / np.linalg.norm([-0.4, 1.0, 0.7])
    v = angle * u
    want = Rotation.from_rotvec(v).as_quat()           # (x, y, z, w), w >= 0 for angle < pi
    np.testing.assert_allclose(rotations.rotvec_to_quat(v), want, rtol=0, atol=1e-15)
    np.testing.assert_allclose(rotations.rotvec_to_quat_batch(np.stack([v, 2 * v, v]))[[0, 2]], [want, want],
                               rtol=0, atol=1e-15)
    np.testing.assert_allclose(rotations.quat_to_rotvec(want), v, rtol=0, atol=1e-14)
    np.testing.assert_allclose(rotations.quat_to_rotvec(-want), v, rtol=0, atol=1e-14)    # the shorter rotation


def test_axis_quaternions_and_products_against_scipy():
    rng = np.random.default_rng(9)
    ang = rng.uniform(-3.0, 3.0, (5, 2))
    for axis in range(3):
        v = np.zeros((5, 2, 3))
        v[..., axis] = ang
        want = Rotation.from_rotvec(v.reshape(-1, 3)).as_quat().reshape(5, 2, 4)
        np.testing.assert_allclose(rotations.axis_quat_batch(ang, axis), want, rtol=0, atol=1e-15)
    a, b = Rotation.random(4, random_state=1), Rotation.random(4, random_state=2)
    np.testing.assert_allclose(rotations.quat_to_dcm_batch(rotations.quat_mul_batch(a.as_quat(), b.as_quat())),
                               (a * b).as_matrix(), atol=1e-15)
    np.testing.assert_allclose(rotations.quat_to_dcm(rotations.quat_mul(a[0].as_quat(), b[0].as_quat())),
                               (a[0] * b[0]).as_matrix(), atol=1e-15)
    np.testing.assert_allclose(rotations.quat_to_dcm(rotations.quat_conj(a[0].as_quat())), a[0].inv().as_matrix(),
                               atol=1e-15)


@pytest.mark.parametrize('k', [1, 2, 3, 7, 25, 1001])
def test_rows_matmul_equals_one_row_at_a_time(k):
    """A (K, 3) batch gives each row's one-row product bit for bit (a plain (K, 3) @ (3, 3) goes
    to BLAS, whose rounding depends on K), for a transposed (Fortran-ordered) matrix too."""
    rng = np.random.default_rng(k)
    m = Rotation.random(random_state=1).as_matrix()
    x = rng.standard_normal((k, 3)) * 1e6
    for mat in (m, m.T):
        rows = np.array([(x[i:i + 1] @ mat)[0] for i in range(k)])
        assert rotations.rows_matmul(x, mat).tobytes() == rows.tobytes()
        assert np.array_equal(rotations.rows_matmul(x[0], mat), x[0] @ mat)
