"""The filter node with no LDV stream at all (a recording without /ldv/twist): under the default
filter.relative_velocity auto it stops waiting for the LDV after ldv_silence_s of IMU and master
stamps, aligns with zero relative velocity, says so in /diagnostics, and publishes the batch
engine's numbers."""
from __future__ import annotations

import dataclasses
import os
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import Vector3Stamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Imu
from support.ros_driving import spin_until

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_ros import convert, domain, qos, topics

ROOT = Path(__file__).resolve().parents[2]
PARAMS = ROOT / 'config/params/graph.yaml'
SILENCE = {'filter.ldv_silence_s': 2.0}


def test_no_ldv_stream_aligns_with_zero_relative_velocity_and_says_so():
    sc = scenario.load('catapult', SILENCE)
    inp = pipeline.simulate(sc)
    n = 601                                   # 6 s of data, all on the deck
    ref = pipeline.align(sc, dataclasses.replace(
        inp, ships=inp.ships.slice(slice(0, n)), imu=inp.imu[:n - 1], master=inp.master[:n], ldv=[]))
    assert ref.relative_velocity == 'zero (no LDV stream)'
    dom = domain.claim()
    rclpy.init(domain_id=dom)
    node = rclpy.create_node('test_driver')
    env = dict(os.environ, ROS_DOMAIN_ID=str(dom))
    proc = subprocess.Popen([str(ROOT / 'scripts/start_node.sh'), 'alignment_filter_node', '--params-file', str(PARAMS),
                             '--ros-args', '-p', 'hold_until_matched:=["/alignment/misalignment:1","/diagnostics:1"]',
                             '-p', 'filter.ldv_silence_s:=2.0'],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            start_new_session=True)
    try:
        pubs = {t: node.create_publisher(ty, t, qos.STREAM) for t, ty in
                ((topics.AIRCRAFT_IMU, Imu), (topics.MASTER_ODOM, Odometry))}
        mis: list[Vector3Stamped] = []
        diag: list[DiagnosticArray] = []
        node.create_subscription(Vector3Stamped, topics.ALIGN_MISALIGNMENT, mis.append, qos.STREAM)
        node.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, diag.append, qos.STREAM)
        spin_until(node, lambda: all(p.get_subscription_count() >= 1 for p in pubs.values()))
        time.sleep(1.0)
        for k in range(n):
            if k > 0:
                pubs[topics.AIRCRAFT_IMU].publish(convert.imu_to_msg(inp.imu[k - 1], 0.0, 0.0))
            pubs[topics.MASTER_ODOM].publish(convert.master_to_msg(inp.master[k]))
        # the node has no end of data: the last master sample waits for its IMU sample
        spin_until(node, lambda: len(mis) >= len(ref.outputs) - 1 and len(diag) >= 3)
        have = np.array([convert.vec_msg_to_array(m)[1] for m in mis])
        want = np.array([e.misalignment for e in ref.published[:len(have)]])
        assert np.array_equal(have, want)
        last = diag[-1].status[0]
        values = {kv.key: kv.value for kv in last.values}
        assert values['relative_velocity'] == 'zero (no LDV stream)'
        assert 'relative velocity zero (no LDV stream)' in last.message
        assert last.level == DiagnosticStatus.OK and 'ldv' not in values['silent']
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGINT)
            try:
                proc.wait(10)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
        node.destroy_node()
        rclpy.shutdown()
        domain.release(dom)
