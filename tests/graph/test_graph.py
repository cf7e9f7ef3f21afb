"""Graph integration: a short catapult run through all nodes, its bag, replay, and batch equality."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from alignment_core import pipeline
from alignment_core.config import scenario

ROOT = Path(__file__).resolve().parents[2]
SETS = ['duration_s=12.0', 'aircraft.catapult.launch_time_s=8.0', 'seed=7']


@pytest.fixture(scope='module')
def graph_run(tmp_path_factory) -> Path:
    """One short catapult run through the graph; while it runs, echo.sh prints one live
    /alignment/misalignment message (saved as echo.txt next to the run)."""
    out = tmp_path_factory.mktemp('graph') / 'run'
    cmd = [str(ROOT / 'scripts/run_graph.sh'), '--scenario', 'catapult_paper', '--out', str(out),
           '--real-time-factor', '2']
    for s in SETS:
        cmd += ['--set', s]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    first = p.stdout.readline()
    while first.startswith('setup.sh:'):          # a workspace rebuild after a package file changed
        first = p.stdout.readline()
    assert first.startswith('ROS_DOMAIN_ID='), first + p.stderr.read()
    dom = first.split()[0].split('=')[1]
    echo = subprocess.run([str(ROOT / 'scripts/echo.sh'), '/alignment/misalignment', '--once',
                           '--timeout', '60'], env=dict(os.environ, ROS_DOMAIN_ID=dom),
                          capture_output=True, text=True, timeout=120)
    stdout, stderr = p.communicate(timeout=300)
    assert p.returncode == 0, stdout + stderr
    assert 'lost messages: 0' in stdout
    (out / 'echo.txt').write_text(echo.stdout if echo.returncode == 0 else f'FAILED: {echo.stderr}')
    return out


@pytest.fixture(scope='module')
def replay_run(graph_run, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp('replay') / 'run'
    p = subprocess.run([str(ROOT / 'scripts/replay.sh'), str(graph_run), '--out', str(out)],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout + p.stderr
    return out


def _bag_estimates(bag: Path, sigma: bool = False):
    from alignment_ros.summary import estimates_from_bag
    e = estimates_from_bag(bag)
    return (e['t_ns'], e['misalignment'], e['sigma']) if sigma else (e['t_ns'], e['misalignment'])


def test_summary_has_contract_keys_and_no_losses(graph_run):
    s = json.loads((graph_run / 'summary.json').read_text())
    for k in ('misalignment_truth_rad', 'misalignment_estimate_rad', 'misalignment_sigma_rad'):
        assert len(s[k]) == 3 and all(np.isfinite(s[k]))
    assert s['sim_time_s'] == pytest.approx(12.0)
    assert s['wall_time_s'] > 0
    assert 0 < s['startup_s'] < s['wall_time_s'] + 60    # command -> first message (the wall time starts later)
    assert s['node_start'] == 'fork'          # forked from the launcher (alignment_ros/forked.py)
    assert s['lost_total'] == 0
    for topic, n in s['published'].items():
        assert s['topics'][topic] == n, topic
    # every stream of the contract is present; 12 s at 100 Hz -> 1201 ship samples
    assert s['topics']['/ship/odom'] == 1201
    assert s['topics']['/aircraft/imu'] == 1200
    assert s['topics']['/truth/misalignment'] == 1101    # on deck until the release at 11 s


def test_recorder_waited_for_every_published_message(graph_run):
    """The recorder stopped because it had every message the nodes report they sent (not
    after a quiet period), and every node exited only once its subscribers had acknowledged
    every message it published, without waiting for a reader that had left (its writer would
    have waited for the reader's participant lease, 20 s: node_util.READER_LINGER_S)."""
    rec = json.loads((graph_run / 'stats' / 'recorder.json').read_text())
    assert rec['end_reason'] == 'end_time'
    assert rec['missing'] == {}
    published = json.loads((graph_run / 'stats' / 'published.json').read_text())
    assert rec['expected'] == published
    assert {t: rec['topics'][t] for t in published} == published
    for f in sorted((graph_run / 'stats').glob('*_node.json')):
        st = json.loads(f.read_text())
        assert st['all_acked'] is True, f.name
        assert st['ack_wait_s'] < 5.0, f.name
        assert st['held_unsent'] == {}, f.name


def test_the_ship_kept_its_lead_over_the_filter_and_the_recorder(graph_run):
    """The ship paced itself on the filter's output and the recorder's progress, and never had
    to go on without them: when it sent its last sample (at the end, 13 s, or later) both were
    within its lead (5 s) of it."""
    ship = json.loads((graph_run / 'stats' / 'ship_motion_node.json').read_text())
    rec = json.loads((graph_run / 'stats' / 'recorder.json').read_text())
    assert ship['pace_releases'] == 0
    assert rec['progress_published'] > 0
    for topic in ('/alignment/misalignment', '/recorder/progress'):
        assert ship['paced_on'][topic] >= 8.0e9, topic


def test_bag_reads_with_independent_reader(graph_run):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    bag = graph_run / 'bag'
    meta = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['version'] == 9
    assert meta['storage_identifier'] == 'mcap'
    files = list(bag.glob('*.mcap'))
    assert len(files) == 1
    counts: dict[str, int] = {}
    first_imu = None
    with open(files[0], 'rb') as f:
        for schema, channel, _message, decoded in make_reader(
                f, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
            if channel.topic == '/aircraft/imu' and first_imu is None:
                first_imu = decoded
                assert schema.encoding == 'ros2msg' and channel.message_encoding == 'cdr'
    meta_counts = {t['topic_metadata']['name']: t['message_count'] for t in meta['topics_with_message_count']}
    assert counts == meta_counts
    # REP-145: no orientation; the two decoders agree on the first IMU message
    assert first_imu.orientation_covariance[0] == -1.0
    assert first_imu.header.frame_id == 'aircraft'
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import Imu

    from alignment_ros.bag import read_bag
    ours = deserialize_message(next(read_bag(bag, ['/aircraft/imu'])).data, Imu)
    for f in ('x', 'y', 'z'):
        assert getattr(ours.linear_acceleration, f) == getattr(first_imu.linear_acceleration, f)
        assert getattr(ours.angular_velocity, f) == getattr(first_imu.angular_velocity, f)
    # specific force magnitude: g plus the deck's lever-arm and heave accelerations (< 2.5 m/s^2)
    acc = first_imu.linear_acceleration
    assert abs(np.hypot(np.hypot(acc.x, acc.y), acc.z) - 9.80) < 2.5


def test_graph_equals_batch(graph_run):
    sc = scenario.load(str(graph_run / 'scenario.yaml'))
    batch = pipeline.run(sc, keep_truth=False)
    t_b = np.array([e.t_ns for e in batch.estimates])
    mu_b = np.array([e.misalignment for e in batch.estimates])
    t_g, mu_g, sig_g = _bag_estimates(graph_run / 'bag', sigma=True)
    assert np.array_equal(t_g, t_b)
    assert np.array_equal(mu_g, mu_b)                # bit for bit: the same inputs, in the same order
    sig_b = np.array([e.misalignment_sigma for e in batch.estimates])
    assert np.array_equal(sig_g, sig_b)
    s = json.loads((graph_run / 'summary.json').read_text())
    i = int(np.searchsorted(t_b, round(s['scored_at_s'] * 1e9), side='right')) - 1
    assert s['misalignment_estimate_rad'] == mu_b[i].tolist()


def test_replay_reproduces_the_estimates(graph_run, replay_run):
    t_g, mu_g = _bag_estimates(graph_run / 'bag')
    t_r, mu_r = _bag_estimates(replay_run / 'bag')
    assert np.array_equal(t_g, t_r)
    assert np.max(np.abs(mu_g - mu_r)) < 1e-12
    a = json.loads((graph_run / 'summary.json').read_text())
    b = json.loads((replay_run / 'summary.json').read_text())
    assert b['misalignment_estimate_rad'] == pytest.approx(a['misalignment_estimate_rad'], abs=1e-12)


def test_filter_never_reads_truth(graph_run):
    stats = json.loads((graph_run / 'stats' / 'alignment_filter_node.json').read_text())
    assert set(stats['received']) == {'/aircraft/imu', '/master/odom', '/ldv/twist'}
    src = (ROOT / 'src/alignment_filter_node/alignment_filter_node/node.py').read_text()
    assert '/truth' not in src and 'TRUTH' not in src


def test_echo_prints_a_live_estimate_like_ros2_topic_echo(graph_run):
    text = (graph_run / 'echo.txt').read_text()
    doc, sep, rest = text.partition('\n---\n')
    assert sep and rest == '', text
    msg = yaml.safe_load(doc)
    assert set(msg) == {'header', 'vector'}
    assert msg['header']['frame_id'] == 'aircraft'
    assert set(msg['header']['stamp']) == {'sec', 'nanosec'}
    # the echoed message is one the recorder stored, digit for digit
    t_ns = msg['header']['stamp']['sec'] * 1_000_000_000 + msg['header']['stamp']['nanosec']
    t_g, mu_g = _bag_estimates(graph_run / 'bag')
    i = int(np.flatnonzero(t_g == t_ns)[0])
    assert [msg['vector'][a] for a in 'xyz'] == mu_g[i].tolist()


def test_invalid_scenario_value_fails_with_named_key(tmp_path):
    p = subprocess.run([str(ROOT / 'scripts/run_graph.sh'), '--out', str(tmp_path / 'x'),
                        '--set', 'ship.sea_state=12'], capture_output=True, text=True, timeout=120)
    assert p.returncode == 2
    assert 'sea_state' in p.stderr


@pytest.mark.parametrize('module, args', [
    ('graph', ['--real-time-factor', '-1']),
    ('graph', ['--real-time-factor', 'nan']),
    ('graph', ['--timeout', '0']),
    ('graph', ['--seed', '-3']),
    ('graph', ['--domain-id', '300']),
    ('replay', ['some/bag', '--domain-id', '-1']),
])
def test_impossible_option_values_are_refused_in_one_line(tmp_path, module, args):
    p = subprocess.run([sys.executable, '-m', f'alignment_ros.{module}', '--out', str(tmp_path / 'x'),
                        *args], capture_output=True, text=True, timeout=120)
    assert p.returncode == 2
    assert len(p.stderr.splitlines()) == 1 and f'argument {args[-2]}' in p.stderr, p.stderr
    assert not (tmp_path / 'x').exists()


def test_replay_of_a_cut_bag_repairs_it_and_fails(graph_run, tmp_path):
    """A run's bag file cut at 50 % (metadata.yaml gone too): replay.sh repairs it first (one
    line), replays what it holds, records every output the filter published and exits 1."""
    import shutil

    from mcap.reader import make_reader
    run = tmp_path / 'run'
    shutil.copytree(graph_run, run, ignore=shutil.ignore_patterns('echo.txt'))
    f = run / 'bag' / 'bag_0.mcap'
    os.truncate(f, f.stat().st_size // 2)
    (run / 'bag' / 'metadata.yaml').unlink()
    p = subprocess.run([str(ROOT / 'scripts/replay.sh'), str(run), '--out', str(tmp_path / 'replay')],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 1, p.stdout + p.stderr
    assert [x for x in p.stderr.splitlines() if 'repaired' in x] == [p.stderr.splitlines()[0]]
    assert 'truncated' not in p.stderr and 'Traceback' not in p.stderr
    with f.open('rb') as fh:
        assert make_reader(fh).get_summary() is not None
    s = json.loads((tmp_path / 'replay' / 'summary.json').read_text())
    assert s['complete'] is False and s['lost_total'] == 0
    assert s['topics']['/alignment/misalignment'] == s['published']['/alignment/misalignment'] > 0
