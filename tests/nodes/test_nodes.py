"""Nodes started alone (scripts/start_node.sh) give the same records as their alignment_core
stage, reject bad input with counts in /diagnostics, and refuse invalid parameters."""
from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import TwistWithCovarianceStamped, Vector3Stamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Imu
from support.ros_driving import spin_until

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.sensors.master_ins import MasterInsModel
from alignment_core.units import DEG
from alignment_ros import convert, qos, topics

ROOT = Path(__file__).resolve().parents[2]
PARAMS = ROOT / 'config/params/catapult_paper.yaml'
SC = scenario.load('catapult_paper')


def test_master_node_equals_its_core_stage(ros):
    node, start = ros
    got: list[Odometry] = []
    pub = node.create_publisher(Odometry, topics.SHIP_ODOM, qos.STREAM)
    node.create_subscription(Odometry, topics.MASTER_ODOM, got.append, qos.STREAM)
    start('master_ins_node')
    spin_until(node, lambda: pub.get_subscription_count() >= 1 and node.count_publishers(topics.MASTER_ODOM) >= 1)
    time.sleep(1.0)
    ships = pipeline.ship_samples(SC)[:200]
    for s in ships:
        pub.publish(convert.ship_to_msgs(s)[0])
    spin_until(node, lambda: len(got) == len(ships))
    model = MasterInsModel(SC.master, SC.seed, SC.ship.lat_deg * DEG)
    for s, m in zip(ships, got):
        want = model.measure(convert.msgs_to_ship(convert.ship_to_msgs(s)[0]))
        have = convert.msg_to_master(m)
        assert have.t_ns == want.t_ns
        for f in ('p_w', 'q_nb', 'v_b', 'w_b'):
            np.testing.assert_allclose(getattr(have, f), getattr(want, f), rtol=0, atol=1e-12)


def test_a_node_started_by_the_scripts_does_not_read_the_clock(ros):
    """The nodes run on their inputs' stamps and never read ROS time: started as start_node.sh
    (and the launcher) start them, without use_sim_time, they keep no /clock subscription (rclpy's
    reader costs an idle node 1-1.6 CPU s per default run); with use_sim_time set, one would
    subscribe (the check's control)."""
    node, start = ros
    start('master_ins_node')
    start('ldv_node', '-p', 'use_sim_time:=true')

    def readers() -> list[str]:
        return [i.node_name for i in node.get_subscriptions_info_by_topic(topics.CLOCK)]

    spin_until(node, lambda: node.count_publishers(topics.MASTER_ODOM) >= 1 and 'ldv_node' in readers())
    time.sleep(1.0)                  # a node's endpoints are announced together
    assert 'master_ins_node' not in readers()


def test_filter_node_rejects_bad_input_and_reports_it(ros):
    node, start = ros
    sc = scenario.load('catapult_paper')
    inp = pipeline.simulate(sc)
    n = 301                                   # 3 s of data
    pubs = {t: node.create_publisher(ty, t, qos.STREAM) for t, ty in
            ((topics.AIRCRAFT_IMU, Imu), (topics.MASTER_ODOM, Odometry),
             (topics.LDV_TWIST, TwistWithCovarianceStamped))}
    mis: list[Vector3Stamped] = []
    diag: list[DiagnosticArray] = []
    node.create_subscription(Vector3Stamped, topics.ALIGN_MISALIGNMENT, mis.append, qos.STREAM)
    node.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, diag.append, qos.STREAM)
    start('alignment_filter_node', '-p', 'hold_until_matched:=["/alignment/misalignment:1","/diagnostics:1"]')
    spin_until(node, lambda: all(p.get_subscription_count() >= 1 for p in pubs.values()))
    time.sleep(1.0)
    gyro_var = accel_var = 0.0
    for k in range(n):
        if k > 0:
            imu = inp.imu[k - 1]
            pubs[topics.AIRCRAFT_IMU].publish(convert.imu_to_msg(imu, gyro_var, accel_var))
            if k == 150:   # a corrupted copy between two good samples, and a stale repeat
                bad = dataclasses.replace(imu, t_ns=imu.t_ns + 1, gyro=np.array([np.nan, 0.0, 0.0]))
                pubs[topics.AIRCRAFT_IMU].publish(convert.imu_to_msg(bad, gyro_var, accel_var))
                pubs[topics.AIRCRAFT_IMU].publish(convert.imu_to_msg(inp.imu[k - 5], gyro_var, accel_var))
        pubs[topics.LDV_TWIST].publish(convert.ldv_to_msg(inp.ldv[k]))
        pubs[topics.MASTER_ODOM].publish(convert.master_to_msg(inp.master[k]))
    spin_until(node, lambda: len(mis) == 31 and len(diag) >= 4)
    # the good data give exactly the batch filter's estimates
    ref = pipeline.align(sc, dataclasses.replace(
        inp, ships=inp.ships.slice(slice(0, n)), imu=inp.imu[:n - 1], master=inp.master[:n], ldv=inp.ldv[:n]))
    want = np.array([e.misalignment for e in ref.outputs])
    have = np.array([convert.vec_msg_to_array(m)[1] for m in mis])
    assert np.max(np.abs(have - want)) < 1e-12
    last = {kv.key: kv.value for kv in diag[-1].status[0].values}
    assert last['rejected_nonfinite'] == '1'
    assert last['rejected_out_of_order'] == '1'
    assert diag[-1].status[0].level == b'\x01'          # WARN


def test_invalid_parameter_fails_at_startup_with_the_key(ros):
    _, start = ros
    p = start('slave_ins_node', '-p', 'imu.gyro_bias_dph:=-1.0')
    out, _ = p.communicate(timeout=30)
    assert p.returncode == 2
    assert 'gyro_bias_dph' in out


def test_parameters_are_frozen_while_running(ros):
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    from rcl_interfaces.srv import SetParameters
    node, start = ros
    start('ldv_node')
    cli = node.create_client(SetParameters, '/ldv_node/set_parameters')
    assert cli.wait_for_service(timeout_sec=30)
    req = SetParameters.Request(parameters=[Parameter(
        name='ldv.noise_mps', value=ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=0.5))])
    fut = cli.call_async(req)
    spin_until(node, fut.done)
    res = fut.result().results[0]
    assert not res.successful
    assert 'fixed while the node runs' in res.reason
