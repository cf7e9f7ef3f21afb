"""ship_motion_node paces simulation time at `real_time_factor` times wall time.

The node sleeps until wall0 + tau / rtf before each sample: an absolute schedule, so a late
sample (its first publications are slow) is caught up, not carried on. A subscriber therefore
sees, after a short start-up burst, a sim-vs-wall slope of exactly rtf up to the jitter of each
receipt (DDS delivery plus this process's spin: tens of ms on a loaded machine). Measured over
the 3.5 s of wall time after the first simulated second of an 8 s run at 2x, a receipt late by
0.1 s at one end moves the endpoint slope by 0.1 / 3.5 = 3 %, and the least-squares slope over
the 700 receipts averages most of that away: 5 %, which still separates 2x from real time (1x)
or the default 5x by far.
"""
from __future__ import annotations

import time

import numpy as np
import pytest
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Empty
from support.ros_driving import spin_until

from alignment_core.config import scenario
from alignment_ros import convert, qos, topics

RTF = 2.0
DURATION_S = 8.0
TOL = 0.05                      # relative, on the slope (see the module docstring)
GO = '/test/start_pacing'       # the node starts once it discovers a subscription here


def test_simulation_time_advances_at_the_real_time_factor(ros):
    node, start = ros
    n = scenario.load('catapult_paper', {'duration_s': DURATION_S}).n_samples
    got: list[tuple[float, float]] = []             # (wall s at receipt, simulation s)
    sub = node.create_subscription(Clock, topics.CLOCK,
                                   lambda m: got.append((time.monotonic(), convert.to_ns(m.clock) * 1e-9)),
                                   qos.STREAM)
    start('ship_motion_node', '-p', f'wait_subscribers:=["{topics.CLOCK}:1","{GO}:1"]',
          sets={'real_time_factor': RTF, 'duration_s': DURATION_S})
    # the node waits until its /clock writer has matched this reader; the reader's own match of
    # the writer can come later, and samples sent before it would arrive late or not at all: let
    # the node start only once this side has matched too
    spin_until(node, lambda: sub.get_publisher_count() >= 1)
    node.create_subscription(Empty, GO, lambda m: None, qos.STREAM)
    spin_until(node, lambda: len(got) == n)
    wall, sim = np.array(got).T
    assert sim[-1] - sim[0] == pytest.approx(DURATION_S, abs=1e-9)
    # the first samples go out late (first publications, first ship chunk) and the node catches
    # up on its absolute schedule: a start-up burst, not a rate; measure after the first 1 s
    steady = sim >= sim[0] + 1.0
    wall, sim = wall[steady], sim[steady]
    slope = np.polyfit(wall, sim, 1)[0]
    assert abs(slope / RTF - 1.0) < TOL, f'simulation advanced at {slope:.3f}x wall time, not {RTF}x'
    span = (sim[-1] - sim[0]) / (wall[-1] - wall[0])
    assert abs(span / RTF - 1.0) < TOL, f'from 1 s to the last sample: {span:.3f}x wall time, not {RTF}x'


def test_the_clock_source_does_not_listen_to_its_own_clock(ros):
    """Started with use_sim_time (a user may set it), ship_motion_node keeps wall time: no
    subscription of its own on /clock, whose events would pile up between its spins (the node's
    memory grew by ~46 MiB per simulated hour that way)."""
    node, start = ros
    start('ship_motion_node', '-p', f'wait_subscribers:=["{GO}:1"]', '-p', 'wait_timeout_s:=60.0',
          '-p', 'use_sim_time:=true')

    def publishers_seen() -> bool:
        return any(i.node_name == 'ship_motion_node'
                   for i in node.get_publishers_info_by_topic(topics.SHIP_ODOM))

    spin_until(node, publishers_seen)
    t_end = time.monotonic() + 1.0     # the node's subscriptions are announced with its publishers
    spin_until(node, lambda: time.monotonic() > t_end)
    readers = [i.node_name for i in node.get_subscriptions_info_by_topic(topics.CLOCK)]
    assert 'ship_motion_node' not in readers


def test_the_ship_runs_no_further_than_its_lead_ahead_of_a_paced_stream(ros):
    """With pace_topics, the ship (even at real_time_factor 0) sends a sample only while the
    paced stream is within max_lead_s of it: nothing on the stream, it stops at t0 + lead; the
    stream at t0 + 1 s lets it on to t0 + 1 s + lead, and no further; the stream then silent for
    pace_release_s of wall time, the ship goes on without it to the end."""
    node, start = ros
    sc, got, paced, _ = _start_paced_ship(node, start, 20.0, max_lead_s=0.5, release_s=4.0)
    t0 = sc.t0_ns * 1e-9
    spin_until(node, lambda: got and got[-1] >= t0 + 0.5 - 1e-9)
    spin_for(node, 1.5)
    assert got[-1] == pytest.approx(t0 + 0.5, abs=1e-9)          # held at the lead
    m = Odometry()
    m.header.stamp = convert.stamp(sc.t0_ns + 1_000_000_000)
    paced.publish(m)
    spin_until(node, lambda: got[-1] >= t0 + 1.5 - 1e-9)
    spin_for(node, 1.5)
    assert got[-1] == pytest.approx(t0 + 1.5, abs=1e-9)
    assert len(got) == 151                                          # every sample once, none skipped
    spin_until(node, lambda: got[-1] >= t0 + 20.0 - 1e-9, timeout=30.0)   # released: on to the end
    assert len(got) == len(set(got)) and len(got) >= 2001


def spin_for(node, seconds: float) -> None:
    import rclpy
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.05)


def test_the_ship_stays_until_a_paced_stream_is_heard(ros):
    """A run shorter than the lead never waits on its paced streams; a publisher holding its
    first messages until the ship's watcher has matched it would hold them for ever if the ship
    left at its last sample. The ship stays until each paced stream has sent something."""
    node, start = ros
    sc, got, paced, proc = _start_paced_ship(node, start, 1.0, max_lead_s=5.0, release_s=60.0)
    spin_until(node, lambda: got and got[-1] >= (sc.t0_ns + sc.n_samples * sc.dt_ns) * 1e-9 - 0.011)
    spin_for(node, 2.0)
    assert proc.poll() is None                  # every sample sent, the stream silent: still there
    m = Odometry()
    m.header.stamp = convert.stamp(sc.t0_ns)
    paced.publish(m)
    end = time.monotonic() + 30.0
    while proc.poll() is None and time.monotonic() < end:
        spin_for(node, 0.1)
    assert proc.poll() == 0                     # heard: the ship finishes


def _start_paced_ship(node, start, duration_s: float, max_lead_s: float, release_s: float):
    """The ship at real_time_factor 0 paced on /truth/aircraft/odom, which this test publishes:
    (scenario, /clock seconds received, the paced publisher, the ship's process), once started."""
    sc = scenario.load('catapult_paper', {'duration_s': duration_s})
    got: list[float] = []
    sub = node.create_subscription(Clock, topics.CLOCK, lambda m: got.append(convert.to_ns(m.clock) * 1e-9),
                                   qos.STREAM)
    paced = node.create_publisher(Odometry, topics.TRUTH_AIRCRAFT_ODOM, qos.STREAM)
    proc = start('ship_motion_node', '-p', f'wait_subscribers:=["{topics.CLOCK}:1","{GO}:1"]',
                 '-p', f'pace_topics:=["{topics.TRUTH_AIRCRAFT_ODOM}"]', '-p', f'max_lead_s:={max_lead_s}',
                 '-p', f'pace_release_s:={release_s}', sets={'real_time_factor': 0.0, 'duration_s': duration_s})
    spin_until(node, lambda: sub.get_publisher_count() >= 1 and paced.get_subscription_count() >= 1)
    node.create_subscription(Empty, GO, lambda m: None, qos.STREAM)
    return sc, got, paced, proc
