"""Fault injection (issue 12: a wrong alignment never reports itself healthy): corrupted copies of
a short clean catapult bag, written with the `rosbags` library, replayed into the alignment filter.

The clean bag holds what the graph's sensor nodes publish for a 12 s catapult run (seed 7, launch
at 8 s): /clock, /master/odom, /aircraft/imu and /ldv/twist, each message logged at its stamp.
Each corrupted copy changes messages from 4 s on (parked on the deck), keeping their log times:
a master quaternion of norm 2 or zero for 10 samples, one IMU or master value of 1e30, one IMU
value NaN, one master value Inf, two IMU samples swapped, a master sample twice, one IMU sample
stamped 0, 1 s of IMU samples missing, one IMU sample stamped 100 s ahead, an LDV reading of
10 m/s for 5 samples (a "launch" the accelerometers do not feel), a wrong frame_id on every
input. Most copies are driven
in-process through the filter node's own input path (FilterInputs: frame check, message
conversion, the engine), which is what the node runs in its callbacks; one is replayed through
ROS (scripts/replay.sh, the filter node in its own process). Every case must end within 0.3' of
the clean run with its rejection counted, or at WARN / ERROR, and no output carries a non-finite
value."""
from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.engine import TransferAlignment
from alignment_core.estimation.health import ERROR, OK, WARN
from alignment_core.units import ARCMIN
from alignment_filter_node.node import FilterInputs
from alignment_ros import convert, topics
from alignment_ros.bag import BagReader

ROOT = Path(__file__).resolve().parents[2]
PARAMS = ROOT / 'config/params/catapult_paper.yaml'       # the papers' catapult filter (what the replay runs)
SC = scenario.load('catapult_paper', {'duration_s': 12.0, 'aircraft.catapult.launch_time_s': 8.0}, seed=7)
K = 400                                           # the faults start at the 400th sample (4 s, parked)
TOL = 0.3 * ARCMIN
STORE = get_typestore(Stores.ROS2_JAZZY)
TYPES = {topics.CLOCK: 'rosgraph_msgs/msg/Clock', topics.MASTER_ODOM: 'nav_msgs/msg/Odometry',
         topics.AIRCRAFT_IMU: 'sensor_msgs/msg/Imu', topics.LDV_TWIST: 'geometry_msgs/msg/TwistWithCovarianceStamped',
         topics.TRUTH_MISALIGNMENT: 'geometry_msgs/msg/Vector3Stamped'}
CASES = ('quaternion_norm_2', 'quaternion_zero', 'imu_1e30', 'master_1e30', 'imu_nan', 'master_inf',
         'imu_swapped', 'master_twice', 'imu_stamp_0', 'imu_gap_1s', 'imu_100s_ahead', 'ldv_10mps_on_deck',
         'wrong_frame_id')


def _write_clean(path: Path) -> None:
    """The sensor topics of the simulated run, as the nodes convert them (convert.py), logged at
    their stamps; /clock at every ship sample, and the true mounting on /truth/misalignment while
    on the deck (the replay's summary scores against it)."""
    from rosgraph_msgs.msg import Clock
    inp = pipeline.simulate(SC)
    mu = inp.sensor_truth['mounting']
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conn = {t: w.add_connection(t, ty, typestore=STORE) for t, ty in TYPES.items()}
        for k in range(len(inp.ships)):
            t = int(inp.ships.t_ns[k])
            w.write(conn[topics.CLOCK], t, serialize_message(Clock(clock=convert.stamp(t))))
            if k > 0:
                w.write(conn[topics.AIRCRAFT_IMU], t, serialize_message(convert.imu_to_msg(inp.imu[k - 1], 0.0, 0.0)))
            w.write(conn[topics.LDV_TWIST], t, serialize_message(convert.ldv_to_msg(inp.ldv[k])))
            w.write(conn[topics.MASTER_ODOM], t, serialize_message(convert.master_to_msg(inp.master[k])))
            if inp.truth['on_deck'][k]:
                w.write(conn[topics.TRUTH_MISALIGNMENT], t,
                        serialize_message(convert.vector_stamped(t, topics.FRAME_AIRCRAFT, mu)))


def _corrupt(case: str, m, topic: str, k: int) -> bool:
    """Change message m (a rosbags message, the k-th of its topic) for the case; False: drop it."""
    if case == 'wrong_frame_id' and topic != topics.CLOCK:
        m.header.frame_id = 'base_link'
    if topic == topics.MASTER_ODOM and K <= k < K + 10 and case.startswith('quaternion'):
        o = m.pose.pose.orientation
        f = 2.0 if case == 'quaternion_norm_2' else 0.0
        o.x, o.y, o.z, o.w = f * o.x, f * o.y, f * o.z, f * o.w
    if topic == topics.MASTER_ODOM and k == K and case == 'master_1e30':
        m.twist.twist.linear.x = 1e30
    if topic == topics.AIRCRAFT_IMU and k == K and case == 'imu_1e30':
        m.linear_acceleration.x = 1e30
    if topic == topics.AIRCRAFT_IMU and k == K and case == 'imu_nan':
        m.angular_velocity.y = float('nan')
    if topic == topics.MASTER_ODOM and k == K and case == 'master_inf':
        m.twist.twist.angular.z = float('inf')
    if topic == topics.AIRCRAFT_IMU and k == K and case == 'imu_stamp_0':
        m.header.stamp.sec, m.header.stamp.nanosec = 0, 0
    if topic == topics.AIRCRAFT_IMU and case == 'imu_gap_1s' and K <= k < K + 100:
        return False
    if topic == topics.AIRCRAFT_IMU and k == K and case == 'imu_100s_ahead':
        m.header.stamp.sec += 100
    if topic == topics.LDV_TWIST and K <= k < K + 5 and case == 'ldv_10mps_on_deck':
        m.twist.twist.linear.x = 10.0
    return True


def _write_corrupted(clean: Path, path: Path, case: str) -> None:
    """A copy of the clean bag with the case's corruption (read, changed and written with rosbags;
    every message keeps its log time)."""
    count = dict.fromkeys(TYPES, 0)
    held = None
    with Reader(clean) as r, Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conn = {c.topic: w.add_connection(c.topic, c.msgtype, typestore=STORE) for c in r.connections}
        for c, t, raw in r.messages():
            m = STORE.deserialize_cdr(raw, c.msgtype)
            k = count[c.topic]
            count[c.topic] += 1
            if not _corrupt(case, m, c.topic, k):
                continue
            data = STORE.serialize_cdr(m, c.msgtype)
            if case == 'imu_swapped' and c.topic == topics.AIRCRAFT_IMU and k in (K, K + 1):
                if k == K:
                    held = data                  # the K-th sample goes out after the (K+1)-th
                    continue
                w.write(conn[c.topic], t, data)
                data = held
            w.write(conn[c.topic], t, data)
            if case == 'master_twice' and c.topic == topics.MASTER_ODOM and k == K:
                w.write(conn[c.topic], t, data)


@pytest.fixture(scope='module')
def bags(tmp_path_factory) -> dict[str, Path]:
    base = tmp_path_factory.mktemp('faults')
    out = {'clean': base / 'clean'}
    _write_clean(out['clean'])
    for case in CASES:
        out[case] = base / case
        _write_corrupted(out['clean'], out[case], case)
    return out


def _replay_in_process(bag: Path, cfg=None):
    """The bag's messages in log-time order through the filter node's input path; the engine,
    its input gate and everything it published."""
    from geometry_msgs.msg import TwistWithCovarianceStamped
    from nav_msgs.msg import Odometry
    from sensor_msgs.msg import Imu
    engine = TransferAlignment(cfg or SC.filter, pipeline.plane_of(SC), SC.rate_hz)
    inputs = FilterInputs(engine)
    take = {topics.AIRCRAFT_IMU: (Imu, inputs.imu), topics.MASTER_ODOM: (Odometry, inputs.master),
            topics.LDV_TWIST: (TwistWithCovarianceStamped, inputs.ldv)}
    published = []
    with Reader(bag) as r:
        for c, _t, raw in r.messages():
            if c.topic in take:
                cls, push = take[c.topic]
                push(deserialize_message(bytes(raw), cls))
                published += engine.process()
    published += engine.process(final=True)
    return engine, inputs, published


def _numbers(e, labels) -> np.ndarray:
    """Every float the estimate's four output messages carry."""
    mis, att, st = convert.estimate_to_msgs(e, labels, e.p_w)
    odom = convert.estimate_to_odometry(e)
    assert odom is not None
    p, o = att.pose.pose.position, att.pose.pose.orientation
    op, oq = odom.pose.pose.position, odom.pose.pose.orientation
    tl, ta = odom.twist.twist.linear, odom.twist.twist.angular
    return np.array([mis.vector.x, mis.vector.y, mis.vector.z, p.x, p.y, p.z, o.x, o.y, o.z, o.w, *att.pose.covariance,
                     *st.data, op.x, op.y, op.z, oq.x, oq.y, oq.z, oq.w, tl.x, tl.y, tl.z, ta.x, ta.y, ta.z,
                     *odom.pose.covariance, *odom.twist.covariance])


@pytest.fixture(scope='module')
def clean(bags):
    engine, inputs, published = _replay_in_process(bags['clean'])
    assert inputs.status() == (OK, ()) and engine.counters.gated == 0
    assert len(published) == 121 and all(e.level == OK for e in published)
    return engine, published


# case -> (counter that must count the fault, its count)
COUNTED = {'quaternion_norm_2': ('rejected_quaternion', 10), 'quaternion_zero': ('rejected_quaternion', 10),
           'imu_1e30': ('rejected_range', 1), 'master_1e30': ('rejected_range', 1),
           'imu_nan': ('rejected_nonfinite', 1), 'master_inf': ('rejected_nonfinite', 1),
           'imu_swapped': ('rejected_out_of_order', 1), 'master_twice': ('rejected_out_of_order', 1),
           'imu_stamp_0': ('rejected_out_of_order', 1),
           'imu_gap_1s': ('bridged_gaps', 1), 'imu_100s_ahead': ('rejected_future_stamp', 1),
           'ldv_10mps_on_deck': ('launch_not_felt', 1)}


@pytest.mark.parametrize('case', sorted(COUNTED))
def test_a_fault_is_counted_reported_and_the_estimate_stays_with_the_clean_run(bags, clean, case):
    engine, inputs, published = _replay_in_process(bags[case])
    name, n = COUNTED[case]
    assert getattr(engine.counters, name) == n
    level, _ = inputs.status()
    assert level == WARN                                  # the fault shows in /diagnostics
    ref_engine, ref = clean
    assert len(published) >= len(ref) - 1                 # an output may fall on a rejected master sample
    np.testing.assert_allclose(published[-1].misalignment, ref[-1].misalignment, rtol=0, atol=TOL)
    for e in published:
        assert np.all(np.isfinite(_numbers(e, engine.labels))), (case, e.t_ns)
        assert np.max(np.abs(e.misalignment)) < 2.0 * 60 * ARCMIN
    assert engine.deck_motion.t_launch_ns == ref_engine.deck_motion.t_launch_ns


def test_an_imu_gap_is_bridged_and_flagged_not_integrated_as_one_step(bags, clean):
    """While the second without IMU data is bridged the outputs are flagged 'gap' (WARN), and the
    masters inside it are not matched; the slave re-anchored on the master afterwards is within
    its clean attitude to the arcminute (a single 1.01 s step left it tens of arcmin off)."""
    engine, _, published = _replay_in_process(bags['imu_gap_1s'])
    _, ref = clean
    gap = [e for e in published if 'gap' in e.flags]
    assert gap and all(e.level == WARN for e in gap)
    assert engine.counters.unmatched_master >= 99
    after = next(i for i, e in enumerate(published) if e.t_ns > gap[-1].t_ns)
    for e, r in zip(published[after:], ref[after:]):
        d = np.linalg.norm(convert_rotvec(e.q_nb, r.q_nb))
        assert d < 1.0 * ARCMIN


def convert_rotvec(q1, q2) -> np.ndarray:
    from scipy.spatial.transform import Rotation
    return (Rotation.from_quat(q1) * Rotation.from_quat(q2).inv()).as_rotvec()


def test_wrong_frame_ids_are_rejected_and_reported(bags):
    engine, inputs, published = _replay_in_process(bags['wrong_frame_id'])
    n = 3 * 1201 - 1                                      # every IMU, LDV and master message
    assert inputs.rejected_frame_id == n and engine.counters.imu == 0 and not published
    level, flags = inputs.status()
    assert level == WARN and 'frame_id' in flags
    assert 'wrong frame' in inputs.message(engine.diagnostics())


def test_integrated_as_one_step_the_gap_would_leave_the_slave_far_off(bags, clean):
    """The corruption is a real fault: with bridging pushed out of reach (gap_bridge_factor 1e6)
    the 1.01 s interval is one strapdown step with the next sample's rates, and the slave's
    attitude after it is off its clean value by far more than an arcminute."""
    import dataclasses
    engine, _, published = _replay_in_process(bags['imu_gap_1s'], dataclasses.replace(SC.filter, gap_bridge_factor=1e6))
    _, ref = clean
    assert engine.counters.bridged_gaps == 0 and engine.counters.imu_gaps == 1
    k = next(i for i, e in enumerate(published) if e.t_ns > SC.t0_ns + 5_100_000_000)
    assert np.linalg.norm(convert_rotvec(published[k].q_nb, ref[k].q_nb)) > 5.0 * ARCMIN


def test_a_corrupted_bag_replayed_through_ros(bags, clean, tmp_path):
    """One IMU value of 1e30 through the real graph (scripts/replay.sh plays the rosbags-written
    bag into a filter node process): the node counts it in /diagnostics, ends within 0.3' of the
    clean run and no output topic, /alignment/odom included, carries a non-finite value."""
    from diagnostic_msgs.msg import DiagnosticArray
    out = tmp_path / 'replay'
    p = subprocess.run([str(ROOT / 'scripts/replay.sh'), str(bags['imu_1e30']), '--params-file', str(PARAMS),
                        '--out', str(out)], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout + p.stderr
    reader = BagReader(out / 'bag')
    assert set(topics.FILTER_OUTPUT_TOPICS) <= set(reader.topics())
    from alignment_ros.summary import estimates_from_bag
    est = estimates_from_bag(out / 'bag')
    _, ref = clean
    np.testing.assert_allclose(est['misalignment'][-1], ref[-1].misalignment, rtol=0, atol=TOL)
    for topic in (topics.ALIGN_MISALIGNMENT, topics.ALIGN_ATTITUDE, topics.ALIGN_STATE, topics.ALIGN_ODOM):
        cls = topics.msg_class(topics.TOPIC_TYPES[topic])
        msgs = [deserialize_message(m.data, cls) for m in reader.messages([topic])]
        assert len(msgs) >= len(ref) - 1, topic
        for m in msgs:
            assert np.all(np.isfinite(_floats(m))), topic
    diag = [deserialize_message(m.data, DiagnosticArray) for m in reader.messages([topics.DIAGNOSTICS])]
    last = {kv.key: kv.value for kv in diag[-1].status[0].values}
    assert last['rejected_range'] == '1' and diag[-1].status[0].level == bytes([WARN])
    assert all(s.level != bytes([ERROR]) for d in diag for s in d.status)


def _floats(m) -> list[float]:
    """Every float field of a message, recursively (sequences included)."""
    out: list[float] = []
    for name in m.get_fields_and_field_types():
        v = getattr(m, name)
        if isinstance(v, float):
            out.append(v)
        elif hasattr(v, 'get_fields_and_field_types'):
            out += _floats(v)
        elif hasattr(v, '__len__') and not isinstance(v, (str, bytes)):
            out += [float(x) for x in v if isinstance(x, float)]
    return out
