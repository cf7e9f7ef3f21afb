"""The run summary tells the truth: a lost message, a message nobody of the run published, or
outputs that stop before the end make the run incomplete (summary.json ``complete: false``,
``problems``, the table's last line), and the simulated time claimed is the one the filter's
outputs reached. A small bag written here: truth on deck 1.0..2.0 s, outputs 1.0..3.0 s at
10 Hz (the estimate is truth + 1 mrad on each axis, sigma 2 mrad)."""
from __future__ import annotations

import math
from pathlib import Path

import pytest
from geometry_msgs.msg import Vector3Stamped
from rclpy.serialization import serialize_message
from std_msgs.msg import Float64MultiArray, MultiArrayDimension

from alignment_ros import summary
from alignment_ros.bag import BagWriter

NS = 1_000_000_000
TRUTH = (0.01, -0.02, 0.03)


def vec(t_ns: int, v) -> bytes:
    m = Vector3Stamped()
    m.header.stamp.sec, m.header.stamp.nanosec = t_ns // NS, t_ns % NS
    m.vector.x, m.vector.y, m.vector.z = v
    return serialize_message(m)


def state(t_ns: int, sigma: float = 0.002) -> bytes:
    """/alignment/state of the output at t_ns: its stamp in the first row, the misalignment's
    sigma in the fourth."""
    n = 3
    m = Float64MultiArray(data=[t_ns * 1e-9] * n + [0.0] * (2 * n) + [sigma] * 3)
    m.layout.dim = [MultiArrayDimension(label='rows', size=4), MultiArrayDimension(label='n', size=n)]
    return serialize_message(m)


@pytest.fixture(scope='module')
def bag(tmp_path_factory) -> Path:
    return write_bag(tmp_path_factory.mktemp('s') / 'bag', [TRUTH] * 11, [[x + 1e-3 for x in TRUTH]] * 21)


def write_bag(path: Path, truths: list, estimates: list, more=None) -> Path:
    """Truth and estimates (with a state) at 10 Hz from 1.0 s; more(writer): anything else."""
    with BagWriter(path) as w:
        if more is not None:
            more(w)
        w.add_topic('/truth/misalignment', 'geometry_msgs/msg/Vector3Stamped')
        w.add_topic('/alignment/misalignment', 'geometry_msgs/msg/Vector3Stamped')
        w.add_topic('/alignment/state', 'std_msgs/msg/Float64MultiArray')
        for k, v in enumerate(truths):
            t = NS + k * NS // 10
            w.write('/truth/misalignment', vec(t, v), t)
        for k, v in enumerate(estimates):
            t = NS + k * NS // 10
            w.write('/alignment/misalignment', vec(t, v), t)
            w.write('/alignment/state', state(t), t)
    return path


def attitudes(truth_yaw, estimate, truth_log_delay_ns: int = 0):
    """write_bag's `more`: /truth/aircraft/odom and /alignment/attitude at 10 Hz from 1.0 s, the
    k-th truth level and turned truth_yaw(k) rad about z (logged truth_log_delay_ns after its
    stamp), the estimate turned by yaw and with the attitude variances of estimate(k)."""
    from geometry_msgs.msg import PoseWithCovarianceStamped
    from nav_msgs.msg import Odometry

    def more(w):
        w.add_topic('/alignment/attitude', 'geometry_msgs/msg/PoseWithCovarianceStamped')
        w.add_topic('/truth/aircraft/odom', 'nav_msgs/msg/Odometry')
        for k in range(11):
            t = NS + k * NS // 10
            o = Odometry()
            o.header.stamp.sec, o.header.stamp.nanosec = t // NS, t % NS
            half = truth_yaw(k) / 2
            o.pose.pose.orientation.z, o.pose.pose.orientation.w = math.sin(half), math.cos(half)
            w.write('/truth/aircraft/odom', serialize_message(o), t + truth_log_delay_ns)
            yaw, var = estimate(k)
            a = PoseWithCovarianceStamped()
            a.header.stamp = o.header.stamp
            a.pose.pose.orientation.z, a.pose.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
            cov = [0.0] * 36
            cov[21], cov[28], cov[35] = var
            a.pose.covariance = cov
            w.write('/alignment/attitude', serialize_message(a), t)
    return more


PUBLISHED = {'/truth/misalignment': 11, '/alignment/misalignment': 21, '/alignment/state': 21}


def test_a_complete_run(bag):
    s = summary.summarise(bag, bag, 1.0, 2.0, 4.0, dict(PUBLISHED))
    assert s['complete'] is True and s['problems'] == []
    assert s['sim_time_s'] == 2.0 and s['real_time_factor'] == 0.5
    assert s['scored_at_s'] == pytest.approx(2.0) and s['estimate_stamp_s'] == pytest.approx(2.0)
    assert s['misalignment_error_rad'] == pytest.approx([1e-3] * 3)
    assert s['misalignment_sigma_rad'] == [0.002] * 3
    assert s['lost_total'] == 0 and s['foreign_total'] == 0
    assert summary.table(s).endswith('complete: yes')


def test_lost_and_foreign_messages_make_it_incomplete(bag):
    pub = dict(PUBLISHED, **{'/truth/misalignment': 13, '/alignment/state': 20})
    s = summary.summarise(bag, bag, 1.0, 2.0, 4.0, pub)
    assert s['complete'] is False
    assert s['lost'] == {'/alignment/misalignment': 0, '/alignment/state': 0, '/truth/misalignment': 2}
    assert s['foreign'] == {'/alignment/state': 1}
    assert s['lost_total'] == 2 and s['foreign_total'] == 1
    text = summary.table(s)
    assert 'lost messages: 2' in text and 'foreign messages: 1' in text
    assert text.splitlines()[-1] == 'INCOMPLETE: 2 messages lost; 1 messages more than the run published'


def test_a_foreign_publisher_makes_it_incomplete(bag):
    s = summary.summarise(bag, bag, 1.0, 2.0, 4.0, dict(PUBLISHED),
                          foreign_publishers={'/alignment/state': ['/intruder']})
    assert s['complete'] is False
    assert s['problems'] == ['foreign publisher on /alignment/state: /intruder']


def test_the_time_claimed_is_the_one_the_outputs_reached(bag):
    """Planned 1.0..6.0 s, outputs to 3.0 s: 2.0 s simulated, and the table says of what."""
    s = summary.summarise(bag, bag, 1.0, 5.0, 4.0, dict(PUBLISHED), problems=['stopped by SIGINT'])
    assert s['sim_time_s'] == pytest.approx(2.0) and s['planned_sim_time_s'] == 5.0
    assert s['complete'] is False
    assert s['problems'] == ['stopped by SIGINT',
                             'cut short: the filter outputs reached t = 3.00 s of 6.00 s']
    assert 'sim time 2.00 s of 5.00 s' in summary.table(s)


def test_nothing_to_score_is_said_not_raised(tmp_path, bag):
    empty = tmp_path / 'empty'
    with BagWriter(empty) as w:
        w.add_topic('/alignment/misalignment', 'geometry_msgs/msg/Vector3Stamped')
    s = summary.summarise(empty, empty, 1.0, 2.0, 4.0, {})
    assert s['complete'] is False and s['misalignment_estimate_rad'] is None
    assert s['sim_time_s'] == 0.0
    assert summary.table(s).startswith('misalignment: nothing to score')
    assert f'nothing to score: {empty}: no /truth/misalignment messages' in s['problems']


def test_without_truth_the_last_estimate_and_its_sigma(bag):
    s = summary.summarise(bag, bag, 1.0, 2.0, 4.0, dict(PUBLISHED), truth=False)
    assert s['truth'] is False and s['complete'] is True
    assert s['misalignment_truth_rad'] is None and s['misalignment_error_rad'] is None
    assert s['misalignment_estimate_rad'] == pytest.approx([x + 1e-3 for x in TRUTH])
    assert s['misalignment_sigma_rad'] == [0.002] * 3 and s['estimate_stamp_s'] == pytest.approx(3.0)
    t = summary.table(s)
    assert 'no truth in the input: estimate and 1 sigma only' in t and 'truth' not in t.split('\n')[1]
    assert 'truth' not in summary.summarise(bag, bag, 1.0, 2.0, 4.0, dict(PUBLISHED))   # the key only then


def test_what_comes_after_the_end_is_not_scored(bag):
    # a graph run's run-out: truth and outputs go on past the end (1.55 s here, off the outputs'
    # 10 Hz grid: the first output after it, at 1.6 s, completes the run), the score is the end's
    s = summary.summarise(bag, bag, 1.0, 0.55, 4.0, dict(PUBLISHED))
    assert s['complete'] is True and s['sim_time_s'] == 0.55
    assert s['scored_at_s'] == pytest.approx(1.5) and s['estimate_stamp_s'] == pytest.approx(1.5)
    assert s['topics']['/alignment/misalignment'] == 21     # recorded all the same


def test_a_moving_truth_is_scored_at_the_estimates_time_of_validity(tmp_path):
    """On its gear or a flexing deck the relative attitude moves: the estimate stamped t with a
    master latency L told to the filter is the relative attitude at t - L. Truth here: a ramp of
    1 mrad per 0.1 s; every estimate equals the truth 0.2 s before its stamp, so with L = 0.2 s
    the error is zero and without it -2 mrad on each axis."""
    ramp = [(1e-3 * k, -1e-3 * k, 2e-3 * k) for k in range(11)]
    path = write_bag(tmp_path / 'bag', ramp, [ramp[max(k - 2, 0)] for k in range(11)])
    told = summary.summarise(path, path, 1.0, 1.0, 1.0, latency_s=0.2)
    assert told['misalignment_error_rad'] == pytest.approx([0.0, 0.0, 0.0], abs=1e-12)
    untold = summary.summarise(path, path, 1.0, 1.0, 1.0)
    assert untold['misalignment_error_rad'] == pytest.approx([-2e-3, 2e-3, -4e-3], abs=1e-12)


def _diagnostics(t_ns: int, values: dict) -> bytes:
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
    d = DiagnosticArray()
    d.header.stamp.sec, d.header.stamp.nanosec = t_ns // NS, t_ns % NS
    d.status = [DiagnosticStatus(name='alignment_filter',
                                 values=[KeyValue(key=k, value=str(v)) for k, v in values.items()])]
    return serialize_message(d)


@pytest.mark.parametrize('diagnosed', [True, False])
def test_a_held_estimate_is_scored_where_its_last_match_was(tmp_path, diagnosed):
    """A beam that loses its reflector before the release: the last match (valid at 1.5 s) is
    first published at 1.6 s, then repeated bit for bit while the relative attitude (a ramp of
    1 mrad per 0.1 s) moves on. The filter's /diagnostics say where the held estimate is valid:
    error zero there. Without that report (an older bag) its first output's stamp stands in
    (1.6 s: one step of the ramp off)."""
    ramp = [(1e-3 * k, -1e-3 * k, 2e-3 * k) for k in range(11)]
    def report(w):              # the filter's 1 Hz report after the last match, then a later one
        w.add_topic('/diagnostics', 'diagnostic_msgs/msg/DiagnosticArray')
        for t in (int(1.8 * NS), int(2.0 * NS)):
            w.write('/diagnostics', _diagnostics(t, {'misalignment_valid_ns': int(1.5 * NS)}), t)
    estimates = [ramp[max(k - 1, 0)] if k < 6 else ramp[5] for k in range(11)]
    path = write_bag(tmp_path / 'bag', ramp, estimates, report if diagnosed else None)
    s = summary.summarise(path, path, 1.0, 1.0, 1.0)
    assert s['estimate_stamp_s'] == pytest.approx(2.0)
    assert s['misalignment_valid_s'] == pytest.approx(1.5 if diagnosed else 1.6)
    want = [0.0, 0.0, 0.0] if diagnosed else [-1e-3, 1e-3, -2e-3]
    assert s['misalignment_error_rad'] == pytest.approx(want, abs=1e-12)
    assert 'valid at t = ' in summary.table(s)


def test_the_slave_attitude_is_scored_at_its_own_stamp(tmp_path):
    """/alignment/attitude against /truth/aircraft/odom at the same stamp. The estimate is the
    truth turned by theta = (0, 0, 1 mrad) (C_est = C_true (I + [theta x]) with a level truth);
    from C_est = (I - [phi x]) C_true, phi = -theta; the 1-sigma is the covariance's diagonal."""
    def estimate(k):
        return 1e-3, [1e-8, 4e-8, 9e-8]
    path = write_bag(tmp_path / 'bag', [TRUTH] * 11, [TRUTH] * 11, attitudes(lambda k: 0.0, estimate))
    s = summary.summarise(path, path, 1.0, 1.0, 1.0)
    assert s['attitude_stamp_s'] == pytest.approx(2.0)
    assert s['attitude_error_rad'] == pytest.approx([0.0, 0.0, -1e-3], abs=1e-12)
    assert s['attitude_sigma_rad'] == pytest.approx([1e-4, 2e-4, 3e-4])
    assert 'slave attitude error' in summary.table(s)


def test_a_bag_cut_between_an_outputs_two_messages_pairs_what_it_holds_of_both(tmp_path):
    """A killed recorder can keep an output's misalignment without its state: the estimates are
    the outputs the bag holds both messages of, and the last of them is scored."""
    path = tmp_path / 'bag'
    with BagWriter(path) as w:
        w.add_topic('/truth/misalignment', 'geometry_msgs/msg/Vector3Stamped')
        w.add_topic('/alignment/misalignment', 'geometry_msgs/msg/Vector3Stamped')
        w.add_topic('/alignment/state', 'std_msgs/msg/Float64MultiArray')
        for k in range(11):
            w.write('/truth/misalignment', vec(NS + k * NS // 10, TRUTH), NS + k * NS // 10)
        for k in range(10):
            t = NS + k * NS // 10
            w.write('/alignment/misalignment', vec(t, [x + 1e-3 for x in TRUTH]), t)
            if k < 9:                                  # the last output's state never recorded
                w.write('/alignment/state', state(t), t)
    e = summary.estimates_from_bag(path)
    assert len(e['t_ns']) == len(e['misalignment']) == len(e['sigma']) == 9
    s = summary.summarise(path, path, 1.0, 1.0, 1.0,
                          {'/truth/misalignment': 11, '/alignment/misalignment': 10, '/alignment/state': 9})
    assert s['estimate_stamp_s'] == pytest.approx(1.8)
    assert s['misalignment_sigma_rad'] == pytest.approx([0.002] * 3)


def test_a_state_recorded_out_of_order_is_paired_with_its_own_output(tmp_path):
    """/alignment/state has no header: its log time is when it arrived. Six states recorded
    late (a reader matched while outputs already flowed) still pair with their own outputs."""
    path = tmp_path / 'bag'
    order = [*range(0, 4), *range(10, 16), *range(4, 10), *range(16, 20)]
    with BagWriter(path) as w:
        w.add_topic('/alignment/misalignment', 'geometry_msgs/msg/Vector3Stamped')
        w.add_topic('/alignment/state', 'std_msgs/msg/Float64MultiArray')
        for k in range(20):
            t = NS + k * NS // 10
            w.write('/alignment/misalignment', vec(t, TRUTH), t)
        for i, k in enumerate(order):
            w.write('/alignment/state', state(NS + k * NS // 10, sigma=1e-3 * (k + 1)), NS + i * NS // 10)
    e = summary.estimates_from_bag(path)
    assert list(e['t_ns']) == [NS + k * NS // 10 for k in range(20)]
    assert e['sigma'][:, 0] == pytest.approx([1e-3 * (k + 1) for k in range(20)])


def test_the_truth_attitude_is_found_by_its_header_stamp_not_its_log_time(tmp_path):
    """A bag recorded with receive times (rosbag2's log time) holds /truth/aircraft/odom logged
    5 ms after its stamp: the truth at the attitude's stamp is still the one stamped there (a
    truth of another stamp, turned by 1 rad, would give a 1 rad error)."""
    more = attitudes(lambda k: 0.0 if k == 10 else 1.0, lambda k: (0.0, [0.0] * 3), truth_log_delay_ns=5_000_000)
    path = write_bag(tmp_path / 'bag', [TRUTH] * 11, [TRUTH] * 11, more)
    s = summary.summarise(path, path, 1.0, 1.0, 1.0)
    assert s['attitude_stamp_s'] == pytest.approx(2.0)
    assert s['attitude_error_rad'] == pytest.approx([0.0, 0.0, 0.0], abs=1e-15)


def test_a_bag_is_read_in_one_pass(bag, monkeypatch):
    """Every pass over an MCAP file parses all its chunks: the summary reads the estimate topics
    and the truth's (the same bag) together (/truth/aircraft/odom only when there is an attitude
    to score, in a pass of its own: this bag has none)."""
    from alignment_ros.bag import BagReader
    passes = []
    real = BagReader.messages

    def counted(self, topics=None):
        passes.append(tuple(sorted(topics or ())))
        return real(self, topics)
    monkeypatch.setattr(BagReader, 'messages', counted)
    s = summary.summarise(bag, bag, 1.0, 2.0, 1.0)
    assert s['misalignment_error_rad'] == pytest.approx([1e-3] * 3)
    assert passes == [tuple(sorted(summary.ESTIMATE_TOPICS + summary.TRUTH_TOPICS))]


def test_truth_and_estimates_from_two_bags_as_from_one(tmp_path, bag):
    """A replay scores the estimates of its own bag against the truth of the bag it played: the
    same numbers as both in one bag, and the counts of both bags."""
    from alignment_ros.bag import read_bag
    truth, est = tmp_path / 'truth', tmp_path / 'est'
    for path, keep in ((truth, {'/truth/misalignment'}), (est, {'/alignment/misalignment', '/alignment/state'})):
        with BagWriter(path) as w:
            types = {}
            for m in read_bag(bag):
                if m.topic in keep:
                    if m.topic not in types:
                        w.add_topic(m.topic, m.type_name)
                        types[m.topic] = m.type_name
                    w.write(m.topic, m.data, m.t_ns)
    one = summary.summarise(bag, bag, 1.0, 2.0, 1.0, PUBLISHED)
    two = summary.summarise(truth, est, 1.0, 2.0, 1.0, PUBLISHED)
    for k in summary.SCORE_KEYS + ('topics', 'lost_total', 'complete', 'sim_time_s', 'state_estimate'):
        assert two[k] == one[k], k
    assert two['misalignment_error_rad'] == pytest.approx([1e-3] * 3)
