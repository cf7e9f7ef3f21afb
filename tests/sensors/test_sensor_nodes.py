"""The sensor nodes, started alone with non-default timing and error models, publish exactly
their alignment_core stages' records: master_ins_node (Schuler model, 50 Hz, 25 ms latency,
/truth/master_error) and ldv_node (LDV at 25 Hz with latency and dropouts, Doppler radar on
/doppler/twist)."""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
from geometry_msgs.msg import TwistWithCovarianceStamped, Vector3Stamped
from nav_msgs.msg import Odometry
from support.ros_driving import spin_until

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.sensors.doppler_radar import DopplerStage
from alignment_core.sensors.ldv import LdvStage
from alignment_core.sensors.master_ins import MasterInsStage
from alignment_core.units import DEG
from alignment_ros import convert, qos, topics

ROOT = Path(__file__).resolve().parents[2]
PARAMS = ROOT / 'config/params/catapult_paper.yaml'
MASTER_SETS = {'master.model': 'schuler', 'master.rate_hz': 50.0, 'master.latency_s': 0.025,
               'master.arw_dpsh': 0.001, 'master.vrw_ugpshz': 5.0}
LDV_SETS = {'ldv.rate_hz': 25.0, 'ldv.latency_s': 0.013, 'ldv.dropout_rate_hz': 2.0, 'ldv.dropout_mean_s': 0.05,
            'ldv.bias_mps': 0.01, 'doppler.enabled': True, 'doppler.latency_s': 0.02}


def test_master_node_schuler_rate_latency(ros):
    node, start = ros
    sc = scenario.load('catapult_paper', MASTER_SETS)
    odom: list[Odometry] = []
    err: list[Vector3Stamped] = []
    pub = node.create_publisher(Odometry, topics.SHIP_ODOM, qos.STREAM)
    node.create_subscription(Odometry, topics.MASTER_ODOM, odom.append, qos.STREAM)
    node.create_subscription(Vector3Stamped, topics.TRUTH_MASTER_ERROR, err.append, qos.STREAM)
    start('master_ins_node', sets=MASTER_SETS)
    spin_until(node, lambda: pub.get_subscription_count() >= 1
               and node.count_publishers(topics.TRUTH_MASTER_ERROR) >= 1)
    time.sleep(1.0)
    ships = pipeline.ship_samples(sc)[:101]
    for s in ships:
        pub.publish(convert.ship_to_msgs(s)[0])
    stage = MasterInsStage(sc.master, sc.seed, sc.ship.lat_deg * DEG, sc.rate_hz, sc.t0_ns)
    want = [o for s in ships for o in stage.step(convert.msgs_to_ship(convert.ship_to_msgs(s)[0]))]
    assert len(want) == 49                      # 0 .. 960 ms at 50 Hz; 980 + 25 ms is past the last
    spin_until(node, lambda: len(odom) == len(want) and len(err) == 10)
    for w, m in zip(want, odom):
        have = convert.msg_to_master(m)
        assert have.t_ns == w.t_ns
        for f in ('q_nb', 'v_b', 'w_b'):
            np.testing.assert_allclose(getattr(have, f), getattr(w.sample, f), rtol=0, atol=1e-12)
    for w, m in zip(want[::5], err):             # /truth/master_error at 10 Hz
        t, phi = convert.vec_msg_to_array(m)
        assert t == w.t_ns
        np.testing.assert_array_equal(phi, w.phi)


def test_ldv_node_timing_dropouts_and_doppler(ros):
    node, start = ros
    sc = scenario.load('catapult_paper', LDV_SETS)
    inp = pipeline.simulate(scenario.load('catapult_paper', {'duration_s': 2.0}))
    ldv: list[TwistWithCovarianceStamped] = []
    dop: list[TwistWithCovarianceStamped] = []
    ps = node.create_publisher(Odometry, topics.SHIP_ODOM, qos.STREAM)
    pa = node.create_publisher(Odometry, topics.TRUTH_AIRCRAFT_ODOM, qos.STREAM)
    node.create_subscription(TwistWithCovarianceStamped, topics.LDV_TWIST, ldv.append, qos.STREAM)
    node.create_subscription(TwistWithCovarianceStamped, topics.DOPPLER_TWIST, dop.append, qos.STREAM)
    start('ldv_node', sets=LDV_SETS)
    spin_until(node, lambda: ps.get_subscription_count() >= 1 and pa.get_subscription_count() >= 1
          and node.count_publishers(topics.DOPPLER_TWIST) >= 1)
    time.sleep(1.0)
    st_ldv = LdvStage(sc.ldv, sc.seed, pipeline.plane_of(sc), sc.rate_hz, sc.t0_ns)
    st_dop = DopplerStage(sc.doppler, sc.seed, sc.rate_hz, sc.t0_ns)
    want_ldv, want_dop = [], []
    t = inp.truth
    for k in range(len(inp.ships)):
        s = inp.ships.sample(k)
        a_msg = convert.odometry(s.t_ns, topics.FRAME_WORLD, topics.FRAME_AIRCRAFT, t['p_w'][k], t['q_nb'][k],
                                 t['v_b'][k], t['w_b'][k])
        s_msg = convert.ship_to_msgs(s)[0]
        ps.publish(s_msg)
        pa.publish(a_msg)
        a = convert.msg_to_truth(a_msg)
        want_ldv += st_ldv.step(convert.msgs_to_ship(s_msg), a)
        want_dop += st_dop.step(a)
    assert len(want_ldv) == 50 and len(want_dop) == 20
    assert not all(w.valid for w in want_ldv)            # some dropouts
    spin_until(node, lambda: len(ldv) == len(want_ldv) and len(dop) == len(want_dop))
    for w, m in zip(want_ldv, ldv):
        h = convert.msg_to_ldv(m)
        assert (h.t_ns, h.valid) == (w.t_ns, w.valid)
        np.testing.assert_allclose(h.v_s, w.v_s, rtol=0, atol=1e-12)
    for w, m in zip(want_dop, dop):
        h = convert.msg_to_doppler(m)
        assert m.header.frame_id == topics.FRAME_AIRCRAFT
        assert h.t_ns == w.t_ns and h.valid
        np.testing.assert_allclose(h.v_b, w.v_b, rtol=0, atol=1e-12)
        assert h.sigma == pytest.approx(w.sigma, rel=1e-12)


def test_master_node_jitter_stamps_as_the_stage(ros):
    """With a transport jitter (master.latency_jitter_s) the node stamps each sample with the
    stage's own draw: the same stamps, off the ship's sample grid, in order."""
    sets = {**MASTER_SETS, 'master.latency_jitter_s': 0.008}
    node, start = ros
    sc = scenario.load('catapult_paper', sets)
    odom: list[Odometry] = []
    pub = node.create_publisher(Odometry, topics.SHIP_ODOM, qos.STREAM)
    node.create_subscription(Odometry, topics.MASTER_ODOM, odom.append, qos.STREAM)
    start('master_ins_node', sets=sets)
    spin_until(node, lambda: pub.get_subscription_count() >= 1)
    time.sleep(1.0)
    ships = pipeline.ship_samples(sc)[:101]
    for s in ships:
        pub.publish(convert.ship_to_msgs(s)[0])
    stage = MasterInsStage(sc.master, sc.seed, sc.ship.lat_deg * DEG, sc.rate_hz, sc.t0_ns)
    want = [o for s in ships for o in stage.step(convert.msgs_to_ship(convert.ship_to_msgs(s)[0]))]
    assert 47 <= len(want) <= 49
    spin_until(node, lambda: len(odom) == len(want))
    stamps = [convert.msg_to_master(m).t_ns for m in odom]
    assert stamps == [w.t_ns for w in want]
    assert all(b > a for a, b in zip(stamps, stamps[1:]))
    assert any((t - sc.t0_ns) % 10_000_000 for t in stamps)
