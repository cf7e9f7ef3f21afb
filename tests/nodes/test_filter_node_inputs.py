"""The filter node's input path and its /alignment/odom message, in-process (no graph): messages in
a frame other than the one expected are rejected and counted as 'frame_id' (a WARN in
/diagnostics), the rest reach the engine; odometry carries the slave solution per REP-105."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.engine import TransferAlignment
from alignment_core.estimation.health import OK, WARN
from alignment_core.units import G0, KNOT
from alignment_filter_node.node import FilterInputs
from alignment_ros import convert, topics

SC = scenario.load('catapult_paper', {'duration_s': 3.0, 'aircraft.catapult.launch_time_s': 2.0})


@pytest.fixture(scope='module')
def inp():
    return pipeline.simulate(SC)


def _inputs():
    return FilterInputs(TransferAlignment(SC.filter, pipeline.plane_of(SC), SC.rate_hz))


def test_expected_frames_pass_and_others_are_rejected(inp):
    f = _inputs()
    assert f.imu(convert.imu_to_msg(inp.imu[0], 0.0, 0.0)) == ''
    assert f.ldv(convert.ldv_to_msg(inp.ldv[0])) == ''
    assert f.master(convert.master_to_msg(inp.master[0])) == ''
    assert f.status() == (OK, ())
    imu = convert.imu_to_msg(inp.imu[1], 0.0, 0.0)
    imu.header.frame_id = 'ship'
    master = convert.master_to_msg(inp.master[1])
    master.child_frame_id = 'aircraft'                      # the master INS is on the ship
    ldv = convert.ldv_to_msg(inp.ldv[1])
    ldv.header.frame_id = ''
    assert f.imu(imu) == f.master(master) == f.ldv(ldv) == 'frame_id'
    assert f.rejected_frame_id == 3 and f.engine.counters.imu == 0
    level, flags = f.status()
    assert level == WARN and flags == ('frame_id',)


def test_malformed_messages_are_reported_with_the_frame_rejections(inp):
    """The subscriptions' malformed messages (alignment_ros/wire.py) never reach the engine; the
    node says how many came, as WARN 'malformed', beside a wrong frame's rejections."""
    f = _inputs()
    assert f.imu(convert.imu_to_msg(inp.imu[0], 0.0, 0.0)) == ''
    f.malformed(topics.MASTER_ODOM)
    f.malformed(topics.LDV_TWIST)
    assert f.rejected_malformed == 2 and f.engine.counters.master == f.engine.counters.ldv == 0
    assert f.status() == (WARN, ('malformed',))
    imu = convert.imu_to_msg(inp.imu[1], 0.0, 0.0)
    imu.header.frame_id = 'ship'
    assert f.imu(imu) == 'frame_id'
    assert f.status() == (WARN, ('frame_id', 'malformed'))
    text = f.message(f.engine.report())
    assert text.endswith('; 1 messages in a wrong frame rejected; 2 malformed messages rejected')


def test_an_engine_rejection_comes_back_with_its_reason(inp):
    f = _inputs()
    m = convert.master_to_msg(inp.master[0])
    m.pose.pose.orientation.w *= 2.0
    assert f.master(m) == 'quaternion'
    assert f.master(convert.master_to_msg(inp.master[0])) == ''
    assert f.master(convert.master_to_msg(inp.master[0])) == 'out_of_order'


@pytest.mark.filterwarnings('ignore:overflow encountered:RuntimeWarning')
def test_an_ldv_covariance_that_cannot_be_decomposed_reaches_the_engine_as_no_beam(inp):
    """Covariance cells near the float range (LAPACK does not converge on them) once raised out
    of the /ldv/twist callback and stopped the node; the message is now read as no beam."""
    f = _inputs()
    m = convert.ldv_to_msg(inp.ldv[0])
    m.twist.covariance[2] = m.twist.covariance[12] = 1.7e308
    assert f.ldv(m) == ''
    assert convert.msg_to_ldv(m).beam is None


def test_odometry_message_per_rep_105(inp):
    """Pose in 'world' (position, attitude, 6x6: position then attitude), twist in the child frame
    'aircraft' (body velocity, body rate), as the estimate gives them."""
    f = pipeline.align(SC, inp)
    e = f.published[-1]
    m = convert.estimate_to_odometry(e)
    assert m is not None
    assert (m.header.frame_id, m.child_frame_id) == (topics.FRAME_WORLD, topics.FRAME_AIRCRAFT)
    assert convert.to_ns(m.header.stamp) == e.t_ns
    p, q = m.pose.pose.position, m.pose.pose.orientation
    np.testing.assert_array_equal([p.x, p.y, p.z], e.p_w)
    np.testing.assert_array_equal([q.x, q.y, q.z, q.w], e.q_nb)
    v, w = m.twist.twist.linear, m.twist.twist.angular
    np.testing.assert_array_equal([v.x, v.y, v.z], e.v_b)
    np.testing.assert_array_equal([w.x, w.y, w.z], e.w_b)
    np.testing.assert_array_equal(np.array(m.pose.covariance).reshape(6, 6), e.pose_cov)
    np.testing.assert_array_equal(np.array(m.twist.covariance).reshape(6, 6), e.twist_cov)
    np.testing.assert_array_equal(np.array(m.pose.covariance).reshape(6, 6)[3:, 3:], e.attitude_cov)
    # 1 s into the 2 g stroke the aircraft moves along its x axis (the ship's bow) at the ship's
    # 10 kn plus 2 g * 1 s relative to the deck (the sea state's surge and the lever arm: ~1 %)
    assert e.v_b[0] == pytest.approx(10.0 * KNOT + 2.0 * G0 * 1.0, rel=0.02)


def test_a_stalled_ldv_is_reported_as_waited_for_only_when_it_stalls_on_the_clock_too(inp):
    """The LDV stops delivering after 0.5 s while the IMU and master run on to 2.5 s: the engine
    waits for it (more than silence_warn_s of their stamps). At a fast replay's pace (1 ms of
    wall time per sample) that is no stall and nothing is reported; once it has also delivered
    nothing for 1 s on the clock, WARN 'waiting_ldv' ('waiting for ldv'); its next sample ends it."""
    now = [0.0]
    f = FilterInputs(TransferAlignment(SC.filter, pipeline.plane_of(SC), SC.rate_hz), 1.0, clock=lambda: now[0])
    t0 = inp.imu[0].t_ns
    ldv = [s for s in inp.ldv if s.t_ns <= t0 + 500_000_000]
    j_ldv = j_m = 0
    for s in inp.imu[:250]:
        now[0] += 1e-3
        assert f.imu(convert.imu_to_msg(s, 0.0, 0.0)) == ''
        while j_ldv < len(ldv) and ldv[j_ldv].t_ns <= s.t_ns:
            assert f.ldv(convert.ldv_to_msg(ldv[j_ldv])) == ''
            j_ldv += 1
        while j_m < len(inp.master) and inp.master[j_m].t_ns <= s.t_ns:
            assert f.master(convert.master_to_msg(inp.master[j_m])) == ''
            j_m += 1
    assert f.engine.waiting_for() == ('ldv',)
    assert f.waiting_for() == () and f.status() == (OK, ())
    now[0] += 1.0
    assert f.imu(convert.imu_to_msg(inp.imu[250], 0.0, 0.0)) == ''
    assert f.waiting_for() == ('ldv',) and f.status() == (WARN, ('waiting_ldv',))
    assert f.message(f.engine.report()).endswith('; waiting for ldv')
    assert f.ldv(convert.ldv_to_msg(inp.ldv[len(ldv)])) == ''
    assert f.waiting_for() == () and f.status() == (OK, ())
