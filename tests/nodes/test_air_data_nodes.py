"""The air-data nodes: alignment_ros.air_data_convert's message conversions round-trip, the
filter node's input handling (frames, IMU blocks, stamp order), and air_data_filter_node started
alone on a straight level flight (FADS frames from the core's FadsStage, a reference INS) gives
finite estimates with alpha within 5 sigma of the flight's."""
from __future__ import annotations

import math
import time

import numpy as np
import pytest
import yaml
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from nav_msgs.msg import Odometry
from scipy.spatial.transform import Rotation
from sensor_msgs.msg import FluidPressure
from std_msgs.msg import Float64MultiArray
from support.ros_driving import spin_until

from air_data_filter_node.inputs import FrameAssembler, ImuBlocks, StampOrder
from alignment_core import pipeline
from alignment_core.air_data_run import make_estimator
from alignment_core.config import scenario
from alignment_core.estimation.air_data.outputs import AirDataEstimate
from alignment_core.sensors.fads import FadsStage
from alignment_core.sensors.reference_ins import ReferenceInsSample, ReferenceInsStage
from alignment_core.units import DEG
from alignment_ros import air_data_convert as adc
from alignment_ros import qos, topics
from alignment_ros.air_data_topics import REFERENCE_INS_ODOM
from alignment_ros.params import given_parameters

SEED004 = scenario.load('seed004')
PLANE = pipeline.plane_of(SEED004)
LAT, LON = SEED004.ship.lat_deg * DEG, SEED004.ship.lon_deg * DEG
T0_NS = SEED004.t0_ns
PITCH = 3.0 * DEG           # level flight, no wind: alpha = pitch, beta = 0
SPEED, HEIGHT = 250.0, 10000.0


def level_flight(seconds: float, rate_hz: float = 10.0):
    """(t_ns, q_nb, v_enu, lat, lon, h) of a straight level flight east at SPEED, HEIGHT, nose
    up by PITCH (body FLU -> ENU: yaw 0 is east, nose-up is a negative turn about body y)."""
    q = Rotation.from_euler('ZYX', [0.0, -PITCH, 0.0]).as_quat()
    v = np.array([SPEED, 0.0, 0.0])
    r_east = 6378137.0 * math.cos(LAT) + HEIGHT
    for k in range(int(seconds * rate_hz) + 1):
        t = k / rate_hz
        yield T0_NS + int(round(t * 1e9)), q, v, LAT, LON + SPEED * t / r_east, HEIGHT


def fads_frames(seconds: float):
    stage = FadsStage(SEED004.fads, SEED004.seed, T0_NS)
    return [f for t_ns, q, v, _, _, h in level_flight(seconds) for f in stage.step(t_ns, q, v, h)]


# ----- conversions -----------------------------------------------------------------------

def test_port_and_truth_messages_round_trip():
    f = fads_frames(2.0)[0]
    msgs = adc.frame_to_msgs(f)
    assert [m.header.frame_id for m in msgs] == [f'fads_port_{k}' for k in range(5)]
    for k, m in enumerate(msgs):
        assert adc.msg_to_port(m) == (f.t_ns, k, f.pressures_pa[k], f.variance_pa2[k])
    m = FluidPressure()
    m.header.frame_id = 'nose'
    assert adc.msg_to_port(m)[1] == -1
    st, wind = adc.air_truth_to_msgs(f)
    rows, labels, data = adc.msg_to_labelled(st)
    assert rows == ('value',) and labels == f.truth.labels()
    np.testing.assert_array_equal(data[0], f.truth.vector())
    assert wind.header.frame_id == 'world'
    np.testing.assert_array_equal([wind.vector.x, wind.vector.y, wind.vector.z], f.truth.wind_enu_mps)
    # the flight's own numbers: no wind, alpha = pitch, beta = 0
    assert f.truth.alpha_rad == pytest.approx(PITCH, abs=1e-12)
    assert f.truth.beta_rad == pytest.approx(0.0, abs=1e-12)


def test_reference_ins_odometry_round_trips_and_uses_body_axes():
    # yaw 90 deg (nose north): a northward ground velocity is all forward in body axes
    q = Rotation.from_euler('z', 90.0, degrees=True).as_quat()
    s = ReferenceInsSample(T0_NS + 5, q, np.array([0.0, 100.0, 1.0]), LAT + 1e-3, LON + 2e-3, 5000.0,
                           np.diag([1e-8, 2e-8, 3e-8]), np.diag([0.01, 0.04, 0.09]), 25.0)
    m = adc.reference_ins_to_msg(s, PLANE)
    assert (m.header.frame_id, m.child_frame_id) == ('world', 'aircraft')
    v = m.twist.twist.linear
    np.testing.assert_allclose([v.x, v.y, v.z], [100.0, 0.0, 1.0], atol=1e-12)
    twist = np.reshape(m.twist.covariance, (6, 6))
    np.testing.assert_allclose(np.diagonal(twist)[:3], [0.04, 0.01, 0.09], atol=1e-15)   # east and north swap
    assert list(np.diagonal(twist)[3:]) == [-1.0] * 3
    pose = np.reshape(m.pose.covariance, (6, 6))
    assert pose[2, 2] == 25.0 and pose[0, 0] == pose[1, 1] == 0.0
    ins = adc.msg_to_ins(m, PLANE, T0_NS)
    assert ins.t == pytest.approx(5e-9, abs=1e-18)
    np.testing.assert_allclose(ins.q_nb, q, atol=1e-15)
    np.testing.assert_allclose(ins.v_enu, s.v_enu, atol=1e-12)
    assert ins.lat_rad == pytest.approx(s.lat, abs=1e-12) and ins.height_m == pytest.approx(s.h, abs=1e-6)
    np.testing.assert_allclose(ins.att_cov, s.att_cov, atol=1e-20)
    np.testing.assert_allclose(ins.vel_cov, s.vel_cov, atol=1e-15)
    assert ins.height_var == 25.0


def test_not_provided_odometry_covariances_read_as_zero():
    s = ReferenceInsSample(T0_NS, np.array([0.0, 0.0, 0.0, 1.0]), np.zeros(3), LAT, LON, 0.0,
                           np.eye(3) * 1e-6, np.eye(3), 4.0)
    m = adc.reference_ins_to_msg(s, PLANE)
    pose = np.reshape(m.pose.covariance, (6, 6)).copy()
    twist = np.reshape(m.twist.covariance, (6, 6)).copy()
    pose[2, 2] = twist[1, 1] = -1.0                 # as /alignment/odom marks axes it does not estimate
    m.pose.covariance, m.twist.covariance = list(pose.ravel()), list(twist.ravel())
    ins = adc.msg_to_ins(m, PLANE)
    assert ins.height_var == 0.0
    np.testing.assert_array_equal(ins.vel_cov, np.diag([1.0, 0.0, 1.0]))


def test_estimate_messages_round_trip():
    labels = ('mach', 'alpha_rad', 'static_pressure_pa', 'wind_east_mps')
    e = AirDataEstimate(2.0, labels, np.array([0.8, 0.05, 26500.0, 3.0]), np.array([0.01, 0.002, 30.0, 1.5]),
                        np.array([240.0, 1.0, -12.0]), np.diag([1.0, 2.0, 3.0]), np.array([3.0, -1.0, 0.0]),
                        np.diag([2.25, 4.0, 1.0]), 40000.0, 50.0)
    assert adc.estimate_finite(e)
    msgs = adc.air_data_to_msgs(2_000_000_000, e)
    t, v, cov = adc.msg_to_twist(msgs.velocity)
    assert t == 2_000_000_000 and msgs.velocity.header.frame_id == 'aircraft'
    np.testing.assert_array_equal(v, e.v_air_body)
    np.testing.assert_array_equal(cov, e.v_air_cov)
    assert list(np.diagonal(np.reshape(msgs.velocity.twist.covariance, (6, 6)))[3:]) == [-1.0] * 3
    _, w, wcov = adc.msg_to_twist(msgs.wind)
    assert msgs.wind.header.frame_id == 'world'
    np.testing.assert_array_equal(w, e.wind_enu)
    np.testing.assert_array_equal(wcov, e.wind_cov)
    assert adc.msg_to_pressure(msgs.static_pressure) == (2_000_000_000, 26500.0, 900.0)
    assert adc.msg_to_pressure(msgs.total_pressure) == (2_000_000_000, 40000.0, 2500.0)
    rows, lab, data = adc.msg_to_labelled(msgs.state)
    assert rows == ('value', 'sigma') and lab == labels
    np.testing.assert_array_equal(data, [e.value, e.sigma])
    bad = AirDataEstimate(**{**e.__dict__, 'wind_cov': np.full((3, 3), np.nan)})
    assert not adc.estimate_finite(bad)


# ----- the filter node's inputs ----------------------------------------------------------

def test_frames_assemble_per_stamp_and_bad_ones_are_counted():
    fa = FrameAssembler(3, max_wait_ns=1000)
    assert fa.add(0, 10, 1.0) is None and fa.add(1, 10, 2.0) is None
    assert fa.add(1, 10, 9.0) is None                       # port 1 twice at one stamp
    assert fa.add(0, 20, 4.0) is None                       # stamp 20 begun; 10 still open
    t, p = fa.add(2, 10, 3.0)
    assert t == 10 and list(p) == [1.0, 2.0, 3.0]
    assert fa.add(2, 5, 3.0) is None                        # before the last frame
    for port in (1, 2):
        fa.add(port, 30, 1.0)
    assert fa.add(0, 30, 1.0)[0] == 30                      # 20 never completed
    assert fa.add(7, 40, 1.0) is None
    assert dict(fa.rejected) == {'duplicate': 1, 'out_of_order': 1, 'incomplete': 1, 'unknown_port': 1}


def test_a_trailing_port_is_waited_for_and_a_silent_one_is_not():
    """Port 2 trails the others by 100 stamps (a reliable stream behind the rest): every frame
    still completes, in stamp order. Then port 2 falls silent: its open stamps are dropped as
    incomplete once the newest port stamp is more than max_wait_ns past them."""
    fa = FrameAssembler(3, max_wait_ns=1500)                # 150 stamps
    frames = []
    for k in range(200):
        for port in (0, 1):
            assert fa.add(port, 10 * k, float(k)) is None
        if k >= 100:
            frames.append(fa.add(2, 10 * (k - 100), float(k - 100)))
    for k in range(100, 200):
        frames.append(fa.add(2, 10 * k, float(k)))
    assert [f[0] for f in frames] == [10 * k for k in range(200)] and not fa.rejected
    for k in range(200, 370):                               # port 2 silent from 2000 on
        for port in (0, 1):
            fa.add(port, 10 * k, 1.0)
    assert fa.rejected == {'incomplete': 19} and min(fa.pending) == 2190    # 3690 - t > 1500


def test_imu_blocks_average_over_block_samples():
    b = ImuBlocks(block=2, dt_ns=10)
    assert b.add(100, np.array([1.0, 0, 0]), np.array([0, 0, 2.0])) is None
    t0, t1, f, w = b.add(110, np.array([3.0, 0, 0]), np.array([0, 0, 4.0]))
    assert (t0, t1) == (90, 110) and list(f) == [2.0, 0, 0] and list(w) == [0, 0, 3.0]
    assert b.add(110, np.ones(3), np.ones(3)) is None and b.rejected == 1
    b.add(120, np.ones(3), np.ones(3))
    assert b.close()[:2] == (110, 120)


def test_stamp_order_waits_for_every_stream_and_breaks_ties_in_stream_order():
    so = StampOrder(('ins', 'frame'), max_wait_ns=100)
    so.add('frame', 10, 'f10')
    assert so.ready() == []                                 # the INS has not reached 10
    so.add('ins', 5, 'i5')
    assert so.ready() == [('ins', 5, 'i5')]
    so.add('ins', 10, 'i10')
    so.add('ins', 15, 'i15')
    assert [x[2] for x in so.ready()] == ['i10', 'f10']     # equal stamps: INS first; i15 waits
    so.add('ins', 200, 'i200')                              # the frames fell silent: i15 goes after 100
    assert [x[2] for x in so.ready()] == ['i15']
    assert [x[2] for x in so.ready(final=True)] == ['i200']


# ----- the node on a level flight --------------------------------------------------------

def test_air_data_filter_node_estimates_alpha_on_a_level_flight(ros, tmp_path):
    node, start = ros
    given = scenario.given_data('seed004')
    params = tmp_path / 'params.yaml'
    params.write_text(yaml.safe_dump({'/**': {'ros__parameters': given_parameters(given, SEED004)}}))
    ports = [node.create_publisher(FluidPressure, t, qos.STREAM) for t in topics.FADS_PORT_TOPICS]
    ins_pub = node.create_publisher(Odometry, REFERENCE_INS_ODOM, qos.STREAM)
    states: list[Float64MultiArray] = []
    diags: list[DiagnosticArray] = []
    node.create_subscription(Float64MultiArray, topics.AIR_DATA_STATE, states.append, qos.STREAM)
    node.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, diags.append, qos.STREAM)
    proc = start('air_data_filter_node', '--params-file', str(params))
    spin_until(node, lambda: all(p.get_subscription_count() >= 1 for p in (*ports, ins_pub))
               and node.count_publishers(topics.AIR_DATA_STATE) >= 1, timeout=20.0)
    time.sleep(1.0)
    seconds = 20.0
    ref = ReferenceInsStage(SEED004.reference_ins, SEED004.seed, T0_NS)
    fads = FadsStage(SEED004.fads, SEED004.seed, T0_NS)
    est = make_estimator(SEED004.air_data_filter, SEED004)     # the core estimator fed in stamp order
    want = []
    for t_ns, q, v, lat, lon, h in level_flight(seconds):
        s = ref.step(t_ns, q, v, lat, lon, h)
        if s is not None:
            m = adc.reference_ins_to_msg(s, PLANE)
            ins_pub.publish(m)
            est.push_ins(adc.msg_to_ins(m, PLANE))
        for f in fads.step(t_ns, q, v, h):
            for pub, m in zip(ports, adc.frame_to_msgs(f)):
                pub.publish(m)
            est.push_frame(f.t_ns * 1e-9, f.pressures_pa)
            e = est.estimate(f.t_ns * 1e-9)
            want.append(np.stack([e.value, e.sigma]))
        rclpy_spin(node)
    n_frames = len(want)
    assert n_frames == int(seconds) + 1
    spin_until(node, lambda: len(diags) >= n_frames or proc.poll() is not None, timeout=20.0)
    assert proc.poll() is None, proc.stdout.read() if proc.stdout else ''
    assert len(states) == n_frames                          # the first frame initialises and is estimated
    for m in states:
        rows, labels, data = adc.msg_to_labelled(m)
        assert rows == ('value', 'sigma') and np.all(np.isfinite(data))
        a = labels.index('alpha_rad')
        assert abs(data[0, a] - PITCH) < 5.0 * data[1, a], (data[0, a], data[1, a])
    np.testing.assert_array_equal([adc.msg_to_labelled(m)[2] for m in states], want)
    last = diags[-1].status[0]
    assert last.level == DiagnosticStatus.OK, last.message
    values = {kv.key: kv.value for kv in last.values}
    assert values['initialised'] == 'true' and values['excluded_ports'] == ''


def rclpy_spin(node) -> None:
    import rclpy
    rclpy.spin_once(node, timeout_sec=0.0)
