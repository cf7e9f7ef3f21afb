"""``player`` (scripts/play.sh) against ``ros2 bag play``'s (Jazzy) semantics: rate, loop, start
offset, playback end, topic selection, remapping, /clock, QoS offers and overrides, usage errors.

The bag (written here with the project's BagWriter) spans 2 s: /a/imu every 100 ms from 1.0 s
to 3.0 s (21 messages), /b/imu from 1.05 s to 2.95 s (20), /clock from 1.0 s to 3.0 s (21).
Expected stamps follow from rosbag2's rules (start = first log time + offset; stop after the
later of start + duration and the until-stamp), not from the player.
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import serialize_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu

from alignment_ros.bag import BagWriter
from alignment_ros.play_options import parse_args
from alignment_ros.qos import STREAM

NS = 1_000_000_000
MS = 1_000_000
A = [NS + k * 100 * MS for k in range(21)]
B = [NS + 50 * MS + k * 100 * MS for k in range(20)]
C = list(A)
BEST_EFFORT = QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.BEST_EFFORT)


def _imu(t_ns: int) -> Imu:
    m = Imu()
    m.header.stamp.sec, m.header.stamp.nanosec = divmod(t_ns, NS)
    return m


@pytest.fixture(scope='module')
def bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp('play') / 'bag'
    with BagWriter(path) as w:
        w.add_topic('/a/imu', 'sensor_msgs/msg/Imu')
        w.add_topic('/b/imu', 'sensor_msgs/msg/Imu')
        w.add_topic('/clock', 'rosgraph_msgs/msg/Clock')
        for t in A:
            w.write('/a/imu', serialize_message(_imu(t)), t)
        for t in B:
            w.write('/b/imu', serialize_message(_imu(t)), t)
        for t in C:
            c = Clock()
            c.clock.sec, c.clock.nanosec = divmod(t, NS)
            w.write('/clock', serialize_message(c), t)
    return path


def stamp(msg) -> int:
    s = msg.clock if isinstance(msg, Clock) else msg.header.stamp
    return s.sec * NS + s.nanosec


class Listener:
    """Subscriptions in the test process: (wall time, stamp) of every message per topic."""

    def __init__(self, ctx: Context, topics: dict[str, type], qos: QoSProfile = STREAM) -> None:
        self.node = Node('test_listener', context=ctx)
        self.got: dict[str, list[tuple[float, int]]] = {t: [] for t in topics}
        for topic, cls in topics.items():
            self.node.create_subscription(
                cls, topic, lambda m, t=topic: self.got[t].append((time.monotonic(), stamp(m))),
                BEST_EFFORT if topic == '/clock' else qos)
        self.executor = SingleThreadedExecutor(context=ctx)
        self.executor.add_node(self.node)

    def reset(self) -> None:
        for v in self.got.values():
            v.clear()

    def stamps(self, topic: str) -> list[int]:
        return [s for _, s in self.got[topic]]

    def span(self, topic: str) -> float:
        return self.got[topic][-1][0] - self.got[topic][0][0]

    def play(self, bag: Path, *args: str, wait: tuple[str, ...] = ('/a/imu',),
             stop_when=None, timeout: float = 20.0) -> tuple[int, dict, str]:
        """Run the player (after our subscriptions matched), spin until it exits (or
        ``stop_when()`` holds: then SIGINT); return (status, stats, stderr)."""
        stats = bag.parent / f'stats{time.monotonic_ns()}.json'
        cmd = [sys.executable, '-m', 'alignment_ros.player', str(bag), *args, '--stats', str(stats)]
        if wait:
            cmd += ['--wait-subscribers', *wait, '--wait-timeout', '15']
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                env=os.environ.copy())
        deadline = time.monotonic() + timeout
        while proc.poll() is None and time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.01)
            if stop_when is not None and stop_when():
                proc.send_signal(signal.SIGINT)
                stop_when = None
        for _ in range(20):   # anything still in flight
            self.executor.spin_once(timeout_sec=0.01)
        if proc.poll() is None:
            proc.kill()
        _out, err = proc.communicate()
        return proc.returncode, (json.loads(stats.read_text()) if stats.exists() else {}), err

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()


@pytest.fixture
def listen(ros_context: Context):
    made: list[Listener] = []

    def make(topics: dict[str, type], qos: QoSProfile = STREAM) -> Listener:
        made.append(Listener(ros_context, topics, qos))
        return made[-1]
    yield make
    for lst in made:
        lst.close()


def test_rate_and_playback_end(bag: Path, listen) -> None:
    """A 2 s bag at -r 2 takes 1 s; --playback-duration 0.6 at the default rate 1.0 plays
    0.6 s of it; --playback-until-sec keeps the message stamped exactly at the limit (the player
    gives its readers a second to take the last messages before it leaves)."""
    lst = listen({'/a/imu': Imu, '/b/imu': Imu})
    rc, stats, err = lst.play(bag, '-r', '2', '--topics', '/a/imu')
    assert rc == 0, err
    assert lst.stamps('/a/imu') == A and lst.stamps('/b/imu') == []
    assert 0.85 < lst.span('/a/imu') < 1.3 and 0.9 < stats['wall_s'] < 1.4

    lst.reset()
    rc, stats, err = lst.play(bag, '--playback-duration', '0.6', '--topics', '/a/imu')
    assert rc == 0, err
    assert lst.stamps('/a/imu') == A[:7]                     # 1.0 ... 1.6 s
    assert 0.5 < lst.span('/a/imu') < 0.9

    lst.reset()
    rc, stats, err = lst.play(bag, '-r', '4', '--playback-until-sec', '1.35',
                              '--exclude-topics', '/clock', wait=('/a/imu', '/b/imu'))
    assert rc == 0, err
    assert lst.stamps('/a/imu') == A[:4] and lst.stamps('/b/imu') == B[:4]  # B[3] = 1.35 s


def test_start_offset_and_loop(bag: Path, listen) -> None:
    lst = listen({'/a/imu': Imu})
    rc, stats, err = lst.play(bag, '--start-offset', '1.5', '-r', '2', '--topics', '/a/imu')
    assert rc == 0, err
    assert lst.stamps('/a/imu') == A[15:]                    # 2.5 ... 3.0 s
    assert stats['wall_s'] < 0.6                             # 0.5 s of bag at rate 2

    lst.reset()
    rc, stats, err = lst.play(bag, '--loop', '-r', '8', '--topics', '/a/imu',
                              stop_when=lambda: lst.stamps('/a/imu').count(A[0]) >= 3)
    assert rc == 0, err                                      # Ctrl-C ends a loop: status 0
    got = lst.stamps('/a/imu')
    assert got[:2 * len(A)] == A + A                         # starts again at the beginning
    assert stats['interrupted'] is True and stats['loops'] >= 3


def test_topic_selection(bag: Path, listen) -> None:
    lst = listen({'/a/imu': Imu, '/b/imu': Imu, '/clock': Clock})
    fast = ('-r', '20')
    rc, stats, err = lst.play(bag, *fast, '--exclude-topics', '/a/imu', wait=('/b/imu', '/clock'))
    assert rc == 0, err
    assert stats['topics'] == {'/b/imu': 20, '/clock': 21}
    assert lst.stamps('/a/imu') == [] and lst.stamps('/b/imu') == B
    # excludes first; the regex selects the rest (full match, like std::regex_match)
    rc, stats, err = lst.play(bag, *fast, '-e', '/.*/imu', '-x', '/b/.*')
    assert stats['topics'] == {'/a/imu': 21}
    rc, stats, err = lst.play(bag, *fast, '-e', 'imu', wait=())
    assert stats['topics'] == {}
    # --topics and --regex together: a topic in either is played
    rc, stats, err = lst.play(bag, *fast, '--topics', '/clock', '-e', '/b/.*',
                              wait=('/b/imu', '/clock'))
    assert stats['topics'] == {'/b/imu': 20, '/clock': 21}


def test_remap_and_clock(bag: Path, listen) -> None:
    lst = listen({'/a/imu': Imu, '/c/imu': Imu, '/clock': Clock})
    rc, stats, err = lst.play(bag, '-r', '20', '--topics', '/a/imu', '--remap', '/a/imu:=/c/imu')
    assert rc == 0, err
    assert lst.stamps('/c/imu') == A and lst.stamps('/a/imu') == []

    lst.reset()
    rc, stats, err = lst.play(bag, '-r', '2', '--clock', '20')
    assert rc == 0, err
    assert '/clock' not in stats['topics']                   # the bag's /clock is not played
    ticks = lst.got['/clock']
    assert len(ticks) >= 12                                  # 20 Hz for about 1 s
    values = [s for _, s in ticks]
    assert values == sorted(values) and A[0] <= values[0] and values[-1] <= A[-1] + 200 * MS
    sim_per_wall = (values[-1] - values[0]) / NS / (ticks[-1][0] - ticks[0][0])
    assert 1.6 < sim_per_wall < 2.4                          # the player's clock runs at -r 2


def _offered(node: Node, topic: str, timeout: float = 15.0) -> QoSProfile:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        infos = node.get_publishers_info_by_topic(topic)
        if infos:
            return infos[0].qos_profile
        time.sleep(0.05)
    pytest.fail(f'no publisher on {topic}')


def test_qos_offers_and_overrides(bag: Path, tmp_path: Path, ros_context: Context) -> None:
    """Recorded offer (RELIABLE, VOLATILE) by default; an overrides file changes one topic;
    a file rosbag2 refuses (a profile without history/depth) ends with status 1."""
    node = Node('test_observer', context=ros_context)
    overrides = tmp_path / 'qos.yaml'
    overrides.write_text('/a/imu:\n  history: keep_last\n  depth: 5\n  reliability: best_effort\n'
                         '  durability: transient_local\n')
    proc = subprocess.Popen([sys.executable, '-m', 'alignment_ros.player', str(bag), '--delay', '3',
                             '--qos-profile-overrides-path', str(overrides)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=os.environ.copy())
    try:
        a, b = _offered(node, '/a/imu'), _offered(node, '/b/imu')
    finally:
        proc.send_signal(signal.SIGINT)
        proc.communicate(timeout=10)
    assert (a.reliability, a.durability) == (ReliabilityPolicy.BEST_EFFORT,
                                             DurabilityPolicy.TRANSIENT_LOCAL)
    assert (b.reliability, b.durability) == (ReliabilityPolicy.RELIABLE, DurabilityPolicy.VOLATILE)
    node.destroy_node()

    overrides.write_text('/a/imu:\n  reliability: best_effort\n')
    res = subprocess.run([sys.executable, '-m', 'alignment_ros.player', str(bag),
                          '--qos-profile-overrides-path', str(overrides)],
                         capture_output=True, text=True, timeout=20)
    assert res.returncode == 1 and res.stderr.startswith('[ERROR] [ros2bag]: ')


def test_lossless_extension(bag: Path, listen) -> None:
    """-r 0 --lossless (what replay.sh uses): as fast as acknowledged, every message, acked."""
    lst = listen({'/a/imu': Imu, '/b/imu': Imu, '/clock': Clock})
    rc, stats, err = lst.play(bag, '-r', '0', '--lossless', wait=('/a/imu', '/b/imu', '/clock'))
    assert rc == 0, err
    assert stats['acked'] is True and stats['wall_s'] < 0.5
    assert (lst.stamps('/a/imu'), lst.stamps('/b/imu'), lst.stamps('/clock')) == (A, B, C)


@pytest.mark.parametrize(('argv', 'message'), [
    (['-r', '-1'], 'argument -r/--rate: -1 is not in the valid range (> 0.0)'),
    (['--start-offset', '-1'], 'argument --start-offset: Value -1 is less than zero.'),
    (['--delay', '0'], "argument -d/--delay: invalid positive_float value: '0'"),
    (['--clock', '-5'], "argument --clock: invalid positive_float value: '-5'"),
    (['--wait-for-all-acked', '-2'], 'argument --wait-for-all-acked: Value -2 is less than zero.'),
    (['--playback-until-sec', '1', '--playback-until-nsec', '1'], 'not allowed with argument'),
    (['--clock', '--clock-topics-all'], 'not allowed with argument'),
])
def test_usage_errors(bag: Path, argv: list[str], message: str,
                      capsys: pytest.CaptureFixture) -> None:
    with pytest.raises(SystemExit) as exc:
        parse_args([str(bag), *argv])
    assert exc.value.code == 2
    assert message in capsys.readouterr().err


def test_defaults_are_ros2s(bag: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    a = parse_args([str(bag)])
    assert (a.rate, a.loop, a.clock, a.delay, a.start_offset, a.playback_duration) == (
        1.0, False, 0, 0.0, 0.0, -1.0)
    assert (a.play_until_ns, a.wait_for_all_acked, a.read_ahead_queue_size) == (-1, -1, 1000)
    assert parse_args([str(bag), '--clock']).clock == 40          # --clock alone: 40 Hz
    assert parse_args([str(bag), '--clock']).exclude_topics == ['/clock']
    assert parse_args([str(bag), '--playback-until-nsec', '7']).play_until_ns == 7
    with pytest.raises(SystemExit):
        parse_args([str(tmp_path / 'missing')])
    assert "Bag path '" in capsys.readouterr().err


def test_progress_line_and_quiet(bag: Path, listen) -> None:
    """Off a terminal the player ends with one plain progress line: the bag time it played of
    the planned span (2.00 s: 1.0 to 3.0 s; --playback-duration 0.6: 0.60 s) and the messages;
    --quiet: none."""
    lst = listen({'/a/imu': Imu})
    rc, _, err = lst.play(bag, '-r', '0', '--topics', '/a/imu')
    assert rc == 0, err
    lines = [x for x in err.splitlines() if x.startswith('play: ')]
    assert len(lines) == 1 and lines[0].startswith('play: t = 2.00 / 2.00 s')
    assert '21 msgs' in lines[0] and lines[0].endswith('(done)')
    lst.reset()
    rc, _, err = lst.play(bag, '-r', '4', '--playback-duration', '0.6', '--topics', '/a/imu')
    assert rc == 0, err
    assert [x for x in err.splitlines() if x.startswith('play: ')][-1].startswith('play: t = 0.60 / 0.60 s')
    lst.reset()
    rc, _, err = lst.play(bag, '-r', '0', '--topics', '/a/imu', '--quiet')
    assert rc == 0 and 'play: ' not in err, err
