"""The filter node with no LDV stream at all (a recording without /ldv/twist): under the default
filter.relative_velocity auto it stops waiting for the LDV after ldv_silence_s of IMU and master
stamps, aligns with zero relative velocity, says so in /diagnostics, and publishes the batch
engine's numbers."""
from __future__ import annotations

import dataclasses
import time

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import Vector3Stamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Imu
from support.ros_driving import spin_until

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_ros import convert, qos, topics

SILENCE = {'filter.ldv_silence_s': 2.0}


def test_no_ldv_stream_aligns_with_zero_relative_velocity_and_says_so(ros):
    sc = scenario.load('catapult_paper', SILENCE)
    inp = pipeline.simulate(sc)
    n = 601                                   # 6 s of data, all on the deck
    ref = pipeline.align(sc, dataclasses.replace(
        inp, ships=inp.ships.slice(slice(0, n)), imu=inp.imu[:n - 1], master=inp.master[:n], ldv=[]))
    assert ref.relative_velocity == 'zero (no LDV stream)'
    node, start = ros
    start('alignment_filter_node', '-p', 'hold_until_matched:=["/alignment/misalignment:1","/diagnostics:1"]',
          sets=SILENCE)
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
