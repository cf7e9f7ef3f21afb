"""Replay a recorded run's sensor topics (and /clock) into a fresh alignment filter node,
record its outputs to a new bag, and write the same summary.json as run_graph.

Played: /clock, /master/odom, /aircraft/imu, /ldv/twist, and /doppler/twist when the bag has
it (recorded only with doppler.enabled); the player waits for the filter's subscription to it
when the filter's model matches the Doppler radar (filter.model, as the filter node resolves
its parameters from the params file)."""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import rclpy

from alignment_core.estimation.models import DOPPLER_MODELS

from . import summary, topics
from .bag import BagError, BagReader
from .graph import finish_recording, root, start, start_recorder, stop, use_domain, watch_end_time
from .params import NODE_SCOPES, node_scenario, params_file_given
from .topics import FILTER_OUTPUT_TOPICS, SENSOR_TOPICS

HOLD = 'hold_until_matched:=[' + ','.join(f'"{t}:1"' for t in FILTER_OUTPUT_TOPICS) + ']'


def _wait_graph(timeout_s: float = 30.0) -> None:
    """Block until the filter's subscriptions and output publishers are visible."""
    rclpy.init()
    node = rclpy.create_node('replay_wait')
    try:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if (node.count_subscribers(topics.AIRCRAFT_IMU) >= 1
                    and node.count_publishers(topics.ALIGN_MISALIGNMENT) >= 1):
                time.sleep(1.0)
                return
            time.sleep(0.05)
        raise RuntimeError('the filter node did not come up')
    finally:
        node.destroy_node()
        rclpy.shutdown()


def replay_topics(bag_topics, params: Path) -> tuple[list[str], list[str]]:
    """(topics to play, 'TOPIC=N' subscriptions to wait for): the sensor topics, plus the
    Doppler radar's when the bag has it; its subscriber is awaited only if the filter's model
    uses it (the filter node subscribes only then)."""
    play = list(SENSOR_TOPICS)
    wait = [f'{topics.AIRCRAFT_IMU}=1', f'{topics.MASTER_ODOM}=1', f'{topics.LDV_TWIST}=1']
    if topics.DOPPLER_TWIST in bag_topics:
        play.append(topics.DOPPLER_TWIST)
        name = 'alignment_filter_node'
        sc = node_scenario(params_file_given(params, name), NODE_SCOPES[name])
        if sc.filter.model in DOPPLER_MODELS:
            wait.append(f'{topics.DOPPLER_TWIST}=1')
    return play, wait


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog='replay.sh', description=__doc__)
    ap.add_argument('bag', type=Path, help='a bag recorded by run_graph.sh (its run directory or bag/)')
    ap.add_argument('--out', type=Path, default=None)
    ap.add_argument('--params-file', type=Path, default=None,
                    help="filter parameters (default: the run's params.yaml next to the bag)")
    ap.add_argument('--domain-id', type=int, default=None,
                    help='ROS_DOMAIN_ID for the replay (default: the exported ROS_DOMAIN_ID, else a '
                         'free one; printed at the start)')
    a = ap.parse_args(argv)
    bag = a.bag / 'bag' if (a.bag / 'bag').is_dir() else a.bag
    params = a.params_file or bag.parent / 'params.yaml'
    if not params.exists():
        print(f'replay: no parameters at {params}; pass --params-file', file=sys.stderr)
        return 2
    try:
        reader = BagReader(bag)
        end_ns = max(m.t_ns for m in reader.messages([topics.MASTER_ODOM]))
        play_topics, wait = replay_topics(reader.topics(), params)
    except (BagError, ValueError) as e:
        print(f'replay: {e}', file=sys.stderr)
        return 2
    out = a.out or root() / 'runs' / time.strftime('replay-%Y%m%d-%H%M%S')
    if (out / 'bag').exists():
        print(f'replay: {out}/bag already exists', file=sys.stderr)
        return 2
    for d in ('logs', 'stats'):
        (out / d).mkdir(parents=True, exist_ok=True)
    use_domain(a.domain_id, 'replay')
    procs: dict[str, subprocess.Popen] = {}
    wall0 = time.monotonic()
    try:
        expect = out / 'stats' / 'published.json'
        procs['recorder'] = start_recorder(out, out / 'bag', end_ns * 1e-9,
                                           list(topics.FILTER_OUTPUT_TOPICS),
                                           [topics.ALIGN_MISALIGNMENT], expect_counts=expect)
        end_reached = watch_end_time(procs['recorder'])
        procs['alignment_filter_node'] = start('alignment_filter_node', params, out,
                                                '-p', HOLD, '-p', 'hold_for_node:=recorder')
        _wait_graph()
        player = subprocess.run(
            [str(root() / 'ros2_ws/install/alignment_ros/lib/alignment_ros/player'), str(bag),
             '--topics', *play_topics, '--stats', str(out / 'stats' / 'player.json'),
             '--rate', '0', '--lossless',   # as fast as the filter acknowledges, nothing lost
             '--wait-subscribers', *wait],
            stdout=open(out / 'logs' / 'player.log', 'w'), stderr=subprocess.STDOUT)
        if player.returncode != 0:
            raise RuntimeError(f'player failed; see {out}/logs/player.log')
        deadline = time.monotonic() + 120.0
        while not end_reached.is_set() and procs['recorder'].poll() is None:
            if time.monotonic() > deadline:
                raise RuntimeError('the filter outputs did not reach the end time within 120 s')
            time.sleep(0.2)
    except (RuntimeError, subprocess.TimeoutExpired) as e:
        print(f'replay: {e}', file=sys.stderr)
        stop(procs)
        return 1
    wall = time.monotonic() - wall0
    # stop the filter once its subscribers acknowledged everything, then let the recorder
    # record every message the filter reports having published (as run_graph does)
    finish_recording(procs, out, expect)
    pub = json.loads((out / 'stats' / 'alignment_filter_node.json').read_text())['published']
    sim = (end_ns - min(m.t_ns for m in BagReader(bag).messages([topics.MASTER_ODOM]))) * 1e-9
    s = summary.summarise(bag, out / 'bag', sim, wall, pub)
    s['replayed_from'] = str(bag)
    summary.report(s, out)
    return 0


if __name__ == '__main__':
    sys.exit(main())
