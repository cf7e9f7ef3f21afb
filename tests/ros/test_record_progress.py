"""The recorder's --progress-topic: the oldest of the --wait-topics streams' latest stamps,
published for a source that paces itself on the recorder, and never recorded."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import rclpy
import yaml
from rclpy.context import Context
from rclpy.duration import Duration
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Temperature

from alignment_ros import qos
from alignment_ros.record_progress import progress_ns

ROOT = Path(__file__).resolve().parents[2]
RELIABLE = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
NS = 1_000_000_000


def test_progress_is_the_oldest_latest_stamp_and_none_until_every_stream_sent():
    assert progress_ns({'/a': 5}, ['/a', '/b']) is None
    assert progress_ns({'/a': 5, '/b': 3, '/c': 1}, ['/a', '/b']) == 3
    assert progress_ns({'/a': 5, '/b': 7}, ['/a', '/b']) == 5


@pytest.mark.parametrize(('args', 'message'), [
    (['-a', '--progress-topic', '/p'], '--progress-topic needs --wait-topics'),
    (['--topics', '/a', '/p', '--wait-topics', '/a', '--progress-topic', '/p'], 'cannot record its own'),
])
def test_progress_option_errors(tmp_path, args, message):
    res = subprocess.run([sys.executable, '-m', 'alignment_ros.recorder', *args, '-o', str(tmp_path / 'bag')],
                         capture_output=True, text=True, timeout=60)
    assert res.returncode == 2 and message in res.stderr, res.stderr


def _temperature(t_ns: int) -> Temperature:
    msg = Temperature()
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(t_ns, NS)
    return msg


def test_the_recorder_publishes_how_far_every_waited_stream_has_reached(tmp_path):
    from alignment_ros import domain
    dom = domain.claim()
    env = dict(os.environ, ROS_DOMAIN_ID=str(dom), ROS_AUTOMATIC_DISCOVERY_RANGE='SYSTEM_DEFAULT')
    ctx = Context()
    rclpy.init(context=ctx, domain_id=dom)
    rec = subprocess.Popen([str(ROOT / 'scripts/record.sh'), '-a', '--wait-topics', '/p/fast', '/p/slow',
                            '--progress-topic', '/p/progress', '--quiet', '-o', str(tmp_path / 'bag')],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    seen: list[int] = []
    try:
        node = Node('progress_talker', context=ctx)
        executor = SingleThreadedExecutor(context=ctx)
        executor.add_node(node)
        node.create_subscription(Clock, '/p/progress', lambda m: seen.append(m.clock.sec * NS + m.clock.nanosec),
                                 qos.WATCH)
        fast = node.create_publisher(Temperature, '/p/fast', RELIABLE)
        slow = node.create_publisher(Temperature, '/p/slow', RELIABLE)

        def spin_until(done, timeout: float = 30.0) -> None:
            deadline = time.monotonic() + timeout
            while not done():
                assert time.monotonic() < deadline, f'progress seen: {seen}'
                executor.spin_once(timeout_sec=0.05)

        spin_until(lambda: fast.get_subscription_count() and slow.get_subscription_count())
        for i in range(1, 31):
            fast.publish(_temperature(i * NS // 10))      # up to 3.0 s
        assert fast.wait_for_all_acked(Duration(seconds=10))
        t_end = time.monotonic() + 1.0
        spin_until(lambda: time.monotonic() > t_end)
        assert seen == []                                  # /p/slow has sent nothing
        for i in range(1, 21):
            slow.publish(_temperature(i * NS // 10))       # up to 2.0 s
        assert slow.wait_for_all_acked(Duration(seconds=10))
        spin_until(lambda: bool(seen) and seen[-1] == 2 * NS)
        assert seen == sorted(set(seen))                    # only when it advanced
        rec.send_signal(signal.SIGINT)
        _, err = rec.communicate(timeout=60)
        assert rec.returncode == 0, err
    finally:
        if rec.poll() is None:
            rec.kill()
            rec.communicate()
        rclpy.try_shutdown(context=ctx)
        domain.release(dom)
    info = yaml.safe_load((tmp_path / 'bag' / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    recorded = {t['topic_metadata']['name'] for t in info['topics_with_message_count']}
    assert {'/p/fast', '/p/slow'} <= recorded and '/p/progress' not in recorded
