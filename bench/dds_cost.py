"""The DDS transport's CPU per message, and the bound it alone sets on the graph's real-time factor.

    scripts/bench.sh dds_cost [--messages 3000] [--readers 1 2 4] [--repeat 3] [--run RUN_DIR]

One publisher and k subscribers, each a process of its own as the graph's nodes are, on a domain
of their own, with the graph's QoS (RELIABLE, KEEP_ALL: alignment_ros/qos.py) and DDS profile
(config/dds/fastdds.xml, through scripts/env.sh). The publisher sends nav_msgs/Odometry (the
graph's commonest type) in bursts of BURST, as a fast run's nodes do; every subscriber takes the
messages as serialized bytes, as the recorder does; the publisher sends them serialized beforehand
(rclpy's conversion of a Python message, either way, is the nodes' cost, not the transport's).
Measured: each process's CPU time per message, the publisher's from its first message until every
reader acknowledged the last, a subscriber's from its first message to its last; the publisher's
fitted as a + b k (the median of the repeats for each k; their range is kept), a subscriber's c.

It also times the reading of each stream type from its bytes: rclpy's conversion into its Python
message against rosbags' reader (alignment_ros/wire.py), which the nodes use.

With a graph run's directory (--run: its summary.json's message counts per topic) and the readers
of each topic (alignment_ros.graph.MATCHED), it prints the CPU the transport alone takes in that
run, the sum over topics of n (a + (b + c) k), and the real-time factor that would leave on this
machine's CPUs if nothing else cost anything.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

TOPIC = '/dds_cost/odom'
BURST = 100
"""Messages sent back to back before a pause of PAUSE_S (a node at --real-time-factor 0 publishes
whatever its inputs allow at once)."""
PAUSE_S = 0.005
SETTLE_S = 0.5
"""After the readers matched, before the first message."""
TIMEOUT_S = 60.0


def _qos():
    from alignment_ros import qos
    return qos.STREAM


def publisher(messages: int, readers: int, report: Callable[[dict], None]) -> None:
    """Publish `messages` Odometry messages, serialized beforehand (rclpy's conversion of a Python
    message is the node's cost, not the transport's), once `readers` subscribers have matched; CPU
    per message from the first publish until every reader has acknowledged the last, reported
    before the node's teardown (which can hang: the parent then stops the process)."""
    import rclpy
    from nav_msgs.msg import Odometry
    from rclpy.duration import Duration
    from rclpy.experimental import EventsExecutor
    from rclpy.serialization import serialize_message
    rclpy.init()
    node = rclpy.create_node('dds_cost_publisher')
    pub = node.create_publisher(Odometry, TOPIC, _qos())
    executor = EventsExecutor()
    executor.add_node(node)
    deadline = time.monotonic() + TIMEOUT_S
    while pub.get_subscription_count() < readers:
        if time.monotonic() > deadline:
            raise RuntimeError(f'{pub.get_subscription_count()} of {readers} subscribers matched')
        executor.spin_once(timeout_sec=0.05)
    time.sleep(SETTLE_S)                   # the readers' side of the match, before the first message
    msg = Odometry()
    msg.header.frame_id, msg.child_frame_id = 'map', 'base_link'
    payloads = []
    for i in range(messages):
        msg.header.stamp.sec = i
        msg.pose.pose.position.x = float(i)
        payloads.append(serialize_message(msg))
    c0 = time.process_time()
    for i, raw in enumerate(payloads):
        pub.publish(raw)
        if i % BURST == BURST - 1:
            time.sleep(PAUSE_S)
    acked = pub.wait_for_all_acked(Duration(seconds=TIMEOUT_S))
    cpu = time.process_time() - c0
    if not acked:
        raise RuntimeError(f'the readers did not acknowledge every message within {TIMEOUT_S:g} s')
    report({'role': 'pub', 'readers': readers, 'us_per_msg': 1e6 * cpu / messages})
    node.destroy_node()
    rclpy.shutdown()


def subscriber(messages: int, report: Callable[[dict], None]) -> None:
    """Take `messages` messages as bytes; CPU per message from the first to the last, reported
    before the node's teardown."""
    import rclpy
    from nav_msgs.msg import Odometry
    from rclpy.experimental import EventsExecutor
    rclpy.init()
    node = rclpy.create_node('dds_cost_subscriber')
    got = [0]

    def on_message(_: bytes) -> None:
        got[0] += 1
    node.create_subscription(Odometry, TOPIC, on_message, _qos(), raw=True)
    executor = EventsExecutor()
    executor.add_node(node)
    deadline = time.monotonic() + TIMEOUT_S
    while got[0] < 1 and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.01)
    c0 = time.process_time()
    while got[0] < messages and time.monotonic() < deadline + TIMEOUT_S:
        executor.spin_once(timeout_sec=0.01)
    cpu = time.process_time() - c0
    taken = got[0]
    report({'role': 'sub', 'taken': taken, 'us_per_msg': 1e6 * cpu / max(taken - 1, 1)})
    node.destroy_node()
    rclpy.shutdown()


def _result(p: subprocess.Popen, timeout: float) -> tuple[dict | None, bool, str]:
    """(the last line a role process printed, parsed, or None; whether it had to be killed: it did
    not end within `timeout` s, e.g. stuck in its DDS teardown after it reported; its stderr, if
    piped)."""
    killed = False
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        p.kill()
        out, err = p.communicate()
        killed = True
    lines = (out or '').strip().splitlines()
    try:
        return (json.loads(lines[-1]) if lines else None), killed, err or ''
    except json.JSONDecodeError:
        return None, killed, err or ''


def one_setting(messages: int, readers: int) -> tuple[float, list[float], int]:
    """(publisher us per message, each subscriber's, how many processes had to be stopped after
    they reported) with `readers` subscribers, on a free domain. RuntimeError when a process
    reported nothing or a subscriber missed messages."""
    from alignment_ros import domain
    dom = domain.claim()
    try:
        env = {**os.environ, 'ROS_DOMAIN_ID': str(dom)}
        cmd = [sys.executable, __file__, '--messages', str(messages)]
        procs = [subprocess.Popen([*cmd, '--role', 'sub'], env=env, stdout=subprocess.PIPE, text=True)
                 for _ in range(readers)]
        try:
            procs.append(subprocess.Popen([*cmd, '--role', 'pub', '--readers', str(readers)], env=env,
                                          stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True))
            pub_out, pub_killed, pub_err = _result(procs[-1], 4 * TIMEOUT_S)
            got = [_result(s, TIMEOUT_S)[:2] for s in procs[:readers]]   # they end with the publisher's last message
        finally:
            for p in procs:
                if p.poll() is None:
                    p.kill()
                    p.wait()
    finally:
        domain.release(dom)
    if pub_out is None:
        raise RuntimeError(f'the publisher reported nothing: {pub_err.strip()}'.strip())
    missing = [g for g, _ in got if g is None]
    if missing:
        raise RuntimeError(f'{len(missing)} of {readers} subscribers reported nothing')
    short = [g['taken'] for g, _ in got if g['taken'] != messages]      # type: ignore[index]
    if short:
        raise RuntimeError(f'subscribers took {short} of {messages} messages')
    stuck = pub_killed + sum(k for _, k in got)
    return pub_out['us_per_msg'], [g['us_per_msg'] for g, _ in got], stuck     # type: ignore[index]


ATTEMPTS = 3
"""A setting whose processes fail (a subscriber that misses the match, a process that reports
nothing) is run again, up to this many times in all."""


def _setting(messages: int, readers: int, failures: list[str]) -> tuple[float, list[float], int]:
    """one_setting, run again after a failure (each kept in `failures`) up to ATTEMPTS times."""
    for attempt in range(ATTEMPTS):
        try:
            return one_setting(messages, readers)
        except RuntimeError as e:
            failures.append(f'{readers} readers: {e}')
            if attempt == ATTEMPTS - 1:
                raise
    raise AssertionError('unreachable')


def measure(messages: int = 3000, readers: tuple[int, ...] = (1, 2, 4), repeat: int = 3) -> dict:
    """a, b (publisher: a + b k us per message with k readers) and c (a subscriber's us per
    message), each from the medians over `repeat` runs of every k."""
    pub_us, pub_range, sub_us, failures, stuck = [], [], [], [], 0
    for k in readers:
        runs = [_setting(messages, k, failures) for _ in range(repeat)]
        pub_us.append(float(np.median([p for p, _, _ in runs])))
        pub_range.append((min(p for p, _, _ in runs), max(p for p, _, _ in runs)))
        sub_us.extend(s for _, ss, _ in runs for s in ss)
        stuck += sum(n for _, _, n in runs)
    b, a = np.polyfit(np.array(readers, dtype=float), np.array(pub_us), 1)
    return {'a_us': float(a), 'b_us': float(b), 'c_us': float(np.median(sub_us)), 'readers': list(readers),
            'pub_us': pub_us, 'pub_us_range': pub_range, 'sub_us_range': (min(sub_us), max(sub_us)),
            'messages': messages, 'repeat': repeat, 'read_us': read_costs(), 'failures': failures,
            'stopped_after_report': stuck}


def read_costs(repeat: int = 2000) -> dict[str, dict[str, float]]:
    """{type: {'rclpy_us', 'wire_us'}}: reading one message of each stream type from its bytes,
    rclpy's deserialize_message (what a typed subscription does) against alignment_ros.wire's
    reader; the best of five rounds of `repeat`."""
    from geometry_msgs.msg import AccelStamped, TwistWithCovarianceStamped
    from nav_msgs.msg import Odometry
    from rclpy.serialization import deserialize_message, serialize_message
    from sensor_msgs.msg import FluidPressure, Imu

    from alignment_ros import wire
    out = {}
    for cls in (Odometry, Imu, AccelStamped, TwistWithCovarianceStamped, FluidPressure):
        msg = cls()
        msg.header.frame_id = 'aircraft'
        raw = serialize_message(msg)
        read = wire.reader(cls)
        best = {'rclpy_us': float('inf'), 'wire_us': float('inf')}
        for _ in range(5):
            for key, fn, args in (('rclpy_us', deserialize_message, (raw, cls)), ('wire_us', read, (raw,))):
                t = time.perf_counter()
                for _ in range(repeat):
                    fn(*args)
                best[key] = min(best[key], 1e6 * (time.perf_counter() - t) / repeat)
        out[wire.type_name(cls)] = best
    return out


def readers_per_topic(run: Path | None = None) -> dict[str, int]:
    """How many nodes (the recorder included) read each topic of a run's graph (its scenario.yaml:
    the optional nodes' subscriptions too), or of the default graph."""
    from alignment_ros.graph import MATCHED, matched_of
    matched = MATCHED
    if run is not None:
        from alignment_core.config import scenario
        matched = matched_of(scenario.load(str(run / 'scenario.yaml')))
    return {topic: len(names) for sent in matched.values() for topic, names in sent.items()}


def transport_bound(cost: dict, topics: dict[str, int], sim_time_s: float, cpus: int,
                    readers: dict[str, int] | None = None) -> dict:
    """The transport's CPU seconds in a run with `topics` message counts (a topic missing from
    `readers`, default the graph's, has one reader: the recorder), and the real-time factor it
    alone would allow on `cpus` CPUs (the streaming part: start-up not counted)."""
    readers = readers_per_topic() if readers is None else readers
    cpu_us = sum(n * (cost['a_us'] + (cost['b_us'] + cost['c_us']) * readers.get(t, 1)) for t, n in topics.items())
    reads = sum(n * readers.get(t, 1) for t, n in topics.items())
    cpu_s = cpu_us * 1e-6
    return {'transport_cpu_s': cpu_s, 'messages': sum(topics.values()), 'reads': reads,
            'rtf_bound': sim_time_s / (cpu_s / cpus)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--messages', type=int, default=3000)
    ap.add_argument('--readers', type=int, nargs='+', default=[1, 2, 4])
    ap.add_argument('--repeat', type=int, default=3)
    ap.add_argument('--run', type=Path, help="a graph run's output directory (its summary.json)")
    ap.add_argument('--role', choices=('pub', 'sub'), help=argparse.SUPPRESS)
    a = ap.parse_args()
    def report(d: dict) -> None:
        print(json.dumps(d), flush=True)
    if a.role == 'pub':
        publisher(a.messages, a.readers[0], report)
        return
    if a.role == 'sub':
        subscriber(a.messages, report)
        return
    cost = measure(a.messages, tuple(a.readers), a.repeat)
    print(f'{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}; {a.messages} Odometry messages, '
          f'median of {a.repeat} runs per reader count')
    for k, p, (lo, hi) in zip(cost['readers'], cost['pub_us'], cost['pub_us_range']):
        print(f'  publisher with {k} reader(s): {p:6.1f} us CPU per message ({lo:.1f}-{hi:.1f})')
    lo, hi = cost['sub_us_range']
    print(f'  fit: publisher {cost["a_us"]:.1f} + {cost["b_us"]:.1f} us per reader; a subscriber {cost["c_us"]:.1f} us '
          f'({lo:.1f}-{hi:.1f})')
    print('reading a message from its bytes (rclpy against alignment_ros.wire):')
    for name, r in cost['read_us'].items():
        print(f'  {name:45s} {r["rclpy_us"]:6.1f} us  {r["wire_us"]:6.1f} us  ({r["rclpy_us"] / r["wire_us"]:.1f}x)')
    if a.run is not None:
        s = json.loads((a.run / 'summary.json').read_text())
        cpus = os.cpu_count() or 1
        bound = transport_bound(cost, s['topics'], s['sim_time_s'], cpus, readers_per_topic(a.run))
        print(f'run {a.run}: {bound["messages"]} messages, {bound["reads"]} reads; the transport alone '
              f'~{bound["transport_cpu_s"]:.1f} CPU s for {s["sim_time_s"]:g} simulated s, so at most '
              f'{bound["rtf_bound"]:.1f}x real time on {cpus} CPUs if nothing else cost anything')


if __name__ == '__main__':
    main()
