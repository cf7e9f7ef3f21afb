"""/ldv/twist both ways (alignment_ros.convert): a vector LDV's sample as sigma^2 I, a beam's as
s u with the rank-1 covariance sigma^2 u u^T; the filter side reads the kind, the line of sight
(up to its sign, immaterial for a projection) and sigma back; covariance[0] = -1 is no
measurement."""
from __future__ import annotations

import numpy as np

from alignment_core.samples import LdvSample
from alignment_ros import convert


def test_vector_sample_round_trip_is_todays():
    s = LdvSample(t_ns=1_230_000_000, v_s=np.array([0.3, -0.2, 0.01]), sigma=0.01, valid=True)
    m = convert.ldv_to_msg(s)
    cov = np.array(m.twist.covariance).reshape(6, 6)
    np.testing.assert_array_equal(cov[:3, :3], 1e-4 * np.eye(3))
    back = convert.msg_to_ldv(m)
    assert back.beam is None and back.valid and back.t_ns == s.t_ns
    np.testing.assert_array_equal(back.v_s, s.v_s)
    assert back.sigma == 0.01


def test_beam_sample_carries_its_line_of_sight_in_a_rank_one_covariance():
    u = np.array([-0.97, -0.2, -0.1])
    u /= np.linalg.norm(u)
    s = LdvSample(t_ns=5, v_s=-12.5 * u, sigma=0.02, valid=True, beam=u)
    m = convert.ldv_to_msg(s)
    cov = np.array(m.twist.covariance).reshape(6, 6)[:3, :3]
    assert np.linalg.matrix_rank(cov, tol=1e-12) == 1
    np.testing.assert_allclose(cov, 4e-4 * np.outer(u, u), rtol=0, atol=1e-18)
    back = convert.msg_to_ldv(m)
    assert back.valid and back.beam is not None
    assert abs(abs(float(back.beam @ u)) - 1.0) < 1e-12
    np.testing.assert_allclose(float(back.v_s @ back.beam) * back.beam, s.v_s, rtol=0, atol=1e-12)
    assert abs(back.sigma - 0.02) < 1e-15
    # a beam along an axis: still rank 1
    ax = LdvSample(t_ns=6, v_s=np.array([0.0, 0.0, 0.0]), sigma=0.01, valid=True, beam=np.array([0.0, 1.0, 0.0]))
    b2 = convert.msg_to_ldv(convert.ldv_to_msg(ax))
    assert b2.beam is not None and abs(abs(b2.beam[1]) - 1.0) < 1e-15


def test_invalid_sample_is_no_measurement_of_either_kind():
    s = LdvSample(t_ns=7, v_s=np.zeros(3), sigma=0.01, valid=False)
    m = convert.ldv_to_msg(s)
    assert m.twist.covariance[0] == -1.0
    back = convert.msg_to_ldv(m)
    assert not back.valid and back.beam is None


def test_the_batch_feeds_the_filter_what_the_filter_node_decodes_bit_for_bit():
    """The batch pipeline pushes ldv_wire.transmitted(s); the filter node pushes what it decodes
    from the serialized message: the same bits (line of sight, sigma, velocity), so a graph run
    and the batch agree exactly on the beam carrier, as the IMU and master messages do."""
    from geometry_msgs.msg import TwistWithCovarianceStamped
    from rclpy.serialization import deserialize_message, serialize_message

    from alignment_core import pipeline
    from alignment_core.config import scenario
    from alignment_core.sensors import ldv_wire
    sc = scenario.load('catapult', {'duration_s': 6.0, 'aircraft.catapult.launch_time_s': 3.0})
    inp = pipeline.simulate(sc)
    beams = sum(s.beam is not None for s in inp.ldv)
    assert beams > 100 and any(not s.valid for s in inp.ldv)
    for s in inp.ldv:
        node = convert.msg_to_ldv(deserialize_message(serialize_message(convert.ldv_to_msg(s)),
                                                      TwistWithCovarianceStamped))
        batch = ldv_wire.transmitted(s)
        assert (node.t_ns, node.valid, bits(node.v_s), bits(node.beam)) == \
            (batch.t_ns, batch.valid, bits(batch.v_s), bits(batch.beam))
        assert node.sigma == batch.sigma or (np.isnan(node.sigma) and np.isnan(batch.sigma))
    for s in inp.imu:
        back = convert.msg_to_imu(convert.imu_to_msg(s, 0.0, 0.0))
        assert bits(back.gyro) == bits(s.gyro) and bits(back.accel) == bits(s.accel)
    for m in inp.master:
        back = convert.msg_to_master(convert.master_to_msg(m))
        assert all(bits(getattr(back, f)) == bits(getattr(m, f)) for f in ('p_w', 'q_nb', 'v_b', 'w_b'))


def bits(a) -> bytes | None:
    return None if a is None else np.asarray(a).tobytes()
