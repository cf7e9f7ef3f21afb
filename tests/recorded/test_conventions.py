"""Each axis and attitude convention of a log's layout against a closed form: a known rotation
written out by hand in the log's own frames, its image in the project's (FLU body in ENU)."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core.recorded import conventions as cv
from alignment_core.recorded.column_units import LogError

D = np.pi / 180.0
E, N, U = np.eye(3)


def one(c: np.ndarray) -> np.ndarray:
    return c[0]


def test_body_axes_and_nav_frames_map_vectors():
    assert cv.BODY_TO_FLU['FRD'] @ [1.0, 2.0, 3.0] == pytest.approx([1.0, -2.0, -3.0])
    assert cv.BODY_TO_FLU['RFU'] @ [1.0, 2.0, 3.0] == pytest.approx([2.0, -1.0, 3.0])   # right = -left
    assert cv.NAV_TO_ENU['NED'] @ [1.0, 2.0, 3.0] == pytest.approx([2.0, 1.0, -3.0])


def test_aerospace_321_heading_east_level_is_the_identity():
    # nose East, right wing South, belly down: in FLU/ENU that is x East, y North, z Up
    assert one(cv.euler_dcm('ned_frd_321', [0.0], [0.0], [90 * D], 'x')) == pytest.approx(np.eye(3), abs=1e-15)


def test_aerospace_321_pitch_and_roll_on_a_north_heading():
    th, ph = 30 * D, 20 * D
    c = one(cv.euler_dcm('ned_frd_321', [0.0], [th], [0.0], 'x'))
    assert c[:, 0] == pytest.approx([0.0, np.cos(th), np.sin(th)], abs=1e-15)      # nose up
    c = one(cv.euler_dcm('ned_frd_321', [ph], [0.0], [0.0], 'x'))
    # positive roll: right wing down; the left wing (FLU y) points West and up
    assert c[:, 1] == pytest.approx([-np.cos(ph), 0.0, np.sin(ph)], abs=1e-15)


def test_aerospace_321_composed_matches_the_textbook_matrix():
    ph, th, ps = 10 * D, -20 * D, 135 * D
    cf, sf, ct, st, cp, sp = np.cos(ph), np.sin(ph), np.cos(th), np.sin(th), np.cos(ps), np.sin(ps)
    c_ned_frd = np.array([[ct * cp, sf * st * cp - cf * sp, cf * st * cp + sf * sp],
                          [ct * sp, sf * st * sp + cf * cp, cf * st * sp - sf * cp],
                          [-st, sf * ct, cf * ct]])
    p = np.array([[0, 1, 0], [1, 0, 0], [0, 0, -1.0]])
    want = p @ c_ned_frd @ np.diag([1.0, -1.0, -1.0])
    assert one(cv.euler_dcm('ned_frd_321', [ph], [th], [ps], 'x')) == pytest.approx(want, abs=1e-15)


def test_ros_321_yaw_is_from_east_counter_clockwise():
    c = one(cv.euler_dcm('enu_flu_321', [0.0], [0.0], [90 * D], 'x'))
    assert c[:, 0] == pytest.approx(N, abs=1e-15)


def test_papers_312_yaw_from_north_counter_clockwise_pitch_about_the_right_axis():
    c = one(cv.euler_dcm('enu_rfu_312', [0.0], [0.0], [90 * D], 'x'))
    assert c[:, 0] == pytest.approx(-E, abs=1e-15)           # yaw +90 deg: nose West
    th, ga = 25 * D, 15 * D
    c = one(cv.euler_dcm('enu_rfu_312', [0.0], [th], [0.0], 'x'))
    assert c[:, 0] == pytest.approx([0.0, np.cos(th), np.sin(th)], abs=1e-15)
    c = one(cv.euler_dcm('enu_rfu_312', [ga], [0.0], [0.0], 'x'))
    assert c[:, 1] == pytest.approx([-np.cos(ga), 0.0, np.sin(ga)], abs=1e-15)   # right wing down


def test_papers_312_composed_matches_the_strapdown_textbook_matrix():
    # C_b^n of the right-forward-up body, yaw psi (north-west positive), pitch theta, roll gamma
    ga, th, ps = 5 * D, 12 * D, -40 * D
    cg, sg, ct, st, cp, sp = np.cos(ga), np.sin(ga), np.cos(th), np.sin(th), np.cos(ps), np.sin(ps)
    c_rfu = np.array([[cp * cg - sp * st * sg, -sp * ct, cp * sg + sp * st * cg],
                      [sp * cg + cp * st * sg, cp * ct, sp * sg - cp * st * cg],
                      [-ct * sg, st, ct * cg]])
    flu_from_rfu = np.array([[0, 1.0, 0], [-1.0, 0, 0], [0, 0, 1.0]])
    want = c_rfu @ flu_from_rfu.T
    assert one(cv.euler_dcm('enu_rfu_312', [ga], [th], [ps], 'x')) == pytest.approx(want, abs=1e-15)


def test_quaternions_in_either_order_and_frame():
    h = np.sqrt(0.5)
    # 90 deg about up, FLU in ENU: the nose turns from East to North
    for q, order in (([h, 0, 0, h], 'wxyz'), ([0, 0, h, h], 'xyzw')):
        c = one(cv.quaternion_dcm(np.array([q]), order, 'ENU', 'FLU', 'x'))
        assert c[:, 0] == pytest.approx(N, abs=1e-15)
    # 90 deg about down, FRD in NED: heading East, which is the FLU/ENU identity
    c = one(cv.quaternion_dcm(np.array([[h, 0, 0, h]]), 'wxyz', 'NED', 'FRD', 'x'))
    assert c == pytest.approx(np.eye(3), abs=1e-15)
    c = one(cv.quaternion_dcm(np.array([[h, 0, 0, h]]), 'wxyz', 'ENU', 'FLU', 'x', inverse=True))
    assert c[:, 0] == pytest.approx(-N, abs=1e-15)


def test_bad_conventions_are_named():
    with pytest.raises(LogError, match='unit quaternion'):
        cv.quaternion_dcm(np.array([[1.0, 0.1, 0, 0]]), 'wxyz', 'ENU', 'FLU', 'x')
    with pytest.raises(LogError, match="Euler convention 'zyx'"):
        cv.euler_dcm('zyx', [0.0], [0.0], [0.0], 'x')
    with pytest.raises(LogError, match="body axes 'FRU'"):
        cv.body_to_flu('FRU', 'x')
    with pytest.raises(LogError, match="quaternion order 'wzyx'"):
        cv.quaternion_dcm(np.array([[1.0, 0, 0, 0]]), 'wzyx', 'ENU', 'FLU', 'x')
