"""The filter node's three outputs, as convert.estimate_to_msgs writes them from one Estimate:
/alignment/misalignment (Vector3Stamped), /alignment/attitude (PoseWithCovarianceStamped:
orientation = q_nb, covariance rotation block = attitude_cov, position = the INS position
with its variances -1, not estimated) and /alignment/state (Float64MultiArray, 5 rows of the
model's n states: stamp, estimate, its 1-sigma, misalignment 1-sigma in the first 3, correction)."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.models import make_model
from alignment_core.estimation.outputs import Estimate
from alignment_core.estimation.state_estimate import StateEstimate
from alignment_ros import convert, topics

# the default model (vm15): attitude, velocity error, gyro and accelerometer bias, master attitude
VM15_LABELS = ('phi_E', 'phi_N', 'phi_U', 'dV_E', 'dV_N', 'dV_U', 'eps_x', 'eps_y', 'eps_z',
               'nabla_x', 'nabla_y', 'nabla_z', 'phim_E', 'phim_N', 'phim_U')
T_NS = 12_345_678_901


def _estimate(n: int) -> Estimate:
    """An Estimate whose every entry is distinct, so a swapped or misplaced field shows."""
    rng = np.random.default_rng(3)
    a = rng.standard_normal((3, 3))
    q = rng.standard_normal(4)
    return Estimate(t_ns=T_NS, misalignment=np.array([1e-3, -2e-3, 3e-3]),
                    misalignment_sigma=np.array([4e-4, 5e-4, 6e-4]), q_nb=q / np.linalg.norm(q),
                    attitude_cov=1e-6 * (a @ a.T + np.eye(3)), x=np.arange(1.0, n + 1.0),
                    sigma=np.arange(1.0, n + 1.0) * 1e-2, bias_gyro=np.zeros(3), bias_accel=np.zeros(3),
                    nis=2.5, updates=10, matching=True)


def test_the_default_model_has_the_15_documented_states():
    cfg = FilterConfig()
    assert cfg.model == 'vm15'
    assert make_model(cfg).labels == VM15_LABELS


def test_misalignment_and_attitude_messages():
    e = _estimate(15)
    p_w = np.array([10.0, -20.0, 30.5])
    mis, att, _ = convert.estimate_to_msgs(e, VM15_LABELS, p_w)
    for m in (mis, att):
        assert convert.to_ns(m.header.stamp) == T_NS
    assert mis.header.frame_id == topics.FRAME_AIRCRAFT
    np.testing.assert_array_equal(convert.vec_msg_to_array(mis)[1], e.misalignment)
    assert att.header.frame_id == topics.FRAME_WORLD
    o = att.pose.pose.orientation
    np.testing.assert_array_equal([o.x, o.y, o.z, o.w], e.q_nb)             # ROS and scipy: x, y, z, w
    p = att.pose.pose.position
    np.testing.assert_array_equal([p.x, p.y, p.z], p_w)
    cov = np.array(att.pose.covariance).reshape(6, 6)                       # rows x y z, rot x y z
    np.testing.assert_array_equal(cov[3:, 3:], e.attitude_cov)
    np.testing.assert_array_equal(cov[:3, :3], -np.eye(3))                  # position: not estimated
    np.testing.assert_array_equal(cov[:3, 3:], 0.0)
    np.testing.assert_array_equal(cov[3:, :3], 0.0)


@pytest.mark.parametrize('model', ['vm15', 'vm12', 'seed002_10', 'seed003_21'])
def test_state_message_is_5_rows_of_the_models_states(model):
    labels = StateEstimate(make_model(dataclasses.replace(FilterConfig(), model=model)).labels).labels
    n = len(labels)
    assert n == {'vm15': 15, 'vm12': 12, 'seed002_10': 10, 'seed003_21': 21}[model]
    e = dataclasses.replace(_estimate(n), state=np.arange(n) * 1e-3 + 0.5)
    _, _, st = convert.estimate_to_msgs(e, labels, np.zeros(3))
    rows, cols = st.layout.dim
    assert (rows.label, rows.size, rows.stride) == ('t_s|estimate|sigma|mu_sigma|correction', 5, 5 * n)
    assert (cols.size, cols.stride) == (n, n)
    assert tuple(cols.label.split(',')) == labels
    assert all(lab.rsplit('_', 1)[1] in ('rad', 'mps', 'radps', 'mps2') for lab in labels)   # SI unit in each
    data = np.array(st.data).reshape(5, n)
    np.testing.assert_array_equal(data[0], T_NS * 1e-9)
    np.testing.assert_array_equal(data[1], e.state)
    np.testing.assert_array_equal(data[2], e.sigma)
    np.testing.assert_array_equal(data[3, :3], e.misalignment_sigma)
    np.testing.assert_array_equal(data[3, 3:], 0.0)
    np.testing.assert_array_equal(data[4], e.x)


def test_state_labels_must_match_the_state():
    with pytest.raises(ValueError, match='15 states but 12 labels'):
        convert.estimate_to_msgs(_estimate(15), VM15_LABELS[:12], np.zeros(3))


def test_the_slave_solution_carries_its_own_time():
    """An output made at a jittered master stamp: the misalignment keeps the stamp, the attitude
    and the odometry (the INS solution) the time of the IMU sample they were integrated to."""
    e = dataclasses.replace(_estimate(15), t_nav_ns=T_NS - 3_000_000, p_w=np.zeros(3), v_b=np.zeros(3),
                            w_b=np.zeros(3), pose_cov=np.eye(6), twist_cov=np.eye(6))
    mis, att, _ = convert.estimate_to_msgs(e, VM15_LABELS, np.zeros(3))
    assert convert.to_ns(mis.header.stamp) == T_NS
    assert convert.to_ns(att.header.stamp) == T_NS - 3_000_000
    odom = convert.estimate_to_odometry(e)
    assert odom is not None and convert.to_ns(odom.header.stamp) == T_NS - 3_000_000
