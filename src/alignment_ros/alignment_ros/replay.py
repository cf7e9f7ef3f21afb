"""Replay a recorded run's sensor topics (and /clock) into a fresh alignment filter node,
record its outputs to a new bag, and write the same summary.json as run_graph.

Played: /clock, /master/odom, /aircraft/imu, and /ldv/twist and /doppler/twist when the bag
has them (an imported log may have neither; /doppler/twist is recorded only with
doppler.enabled); the player waits for the filter's subscription to each played input (to
/doppler/twist when the filter's model matches the Doppler radar: filter.model, as the filter
node resolves its parameters).

Parameters: the run's params.yaml next to the bag, or --params-file, with --set KEY=VALUE
overrides (as run_graph's); the world origin and the IMU rate come from the data where none
of them gives them (alignment_ros.replay_params). The parameters used are written to the
output's params.yaml. A bag without /truth/misalignment (a real recording) is summarised
without truth: the estimate and its 1-sigma at the filter's last output, said so.

The recording ends as run_graph's does: once the filter's outputs reached the input's end
(the last /master/odom stamp; for a run of the graph, its scenario's end when earlier: its
run-out after it is played, not judged), the filter is stopped and the recorder records every
message it reports having published (no idle timeout cuts it).

A damaged input bag (its recorder died, a file cut short) is repaired first
(:mod:`alignment_ros.bag_reindex`, one line saying so) and replayed as far as it goes; the
replay is then incomplete. Exit status as run_graph.sh's: 0 complete, 1 incomplete or failed,
130/143 stopped by SIGINT/SIGTERM, 2 for a bad command line or input.
"""
from __future__ import annotations

import argparse
import logging
import subprocess
import sys
import time
from pathlib import Path

import rclpy
from rclpy.signals import SignalHandlerOptions

from alignment_core import run_out
from alignment_core.config import scenario as core_scenario
from alignment_core.estimation.models import DOPPLER_MODELS
from alignment_core.validation import ConfigError

from . import bag_reindex, replay_params, summary, topics
from .bag import BagError, BagReader
from .graph import start
from .launch import (
    OneLineParser,
    Run,
    domain_id,
    finish_recording,
    guarded_main,
    published_counts,
    root,
    start_recorder,
    watch_end_time,
)
from .params import NODE_SCOPES, node_scenario
from .progress_watch import LiveProgress
from .shm_cleanup import clean_stale
from .signals import Interrupted, SignalGuard
from .topics import FILTER_OUTPUT_TOPICS, SENSOR_TOPICS

HOLD = 'hold_until_matched:=[' + ','.join(f'"{t}:recorder"' for t in FILTER_OUTPUT_TOPICS) + ']'
FILTER = 'alignment_filter_node'
END_TIMEOUT_S = 120.0       # after the player: the filter's outputs reach the input's end
DAMAGED_GRACE_S = 10.0      # a repaired input: its cut streams need not bring the outputs there


def _wait_graph(timeout_s: float = 30.0) -> None:
    """Block until the filter's subscriptions and output publishers are visible."""
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)   # the launcher handles signals
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


def replay_topics(bag_topics, given: dict) -> tuple[list[str], list[str]]:
    """(topics to play, 'TOPIC=N' subscriptions to wait for): the sensor topics the bag has,
    plus the Doppler radar's when it has it; its subscriber is awaited only if the filter's
    model uses it (the filter node subscribes only then). `given`: the filter's parameters."""
    play = [t for t in SENSOR_TOPICS if t in bag_topics]
    wait = [f'{t}=1' for t in (topics.AIRCRAFT_IMU, topics.MASTER_ODOM, topics.LDV_TWIST) if t in bag_topics]
    if topics.DOPPLER_TWIST in bag_topics:
        play.append(topics.DOPPLER_TWIST)
        sc = node_scenario(given, NODE_SCOPES[FILTER])
        if sc.filter.model in DOPPLER_MODELS:
            wait.append(f'{topics.DOPPLER_TWIST}=1')
    return play, wait


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    ap = OneLineParser(prog='replay.sh', description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('bag', type=Path, help='a bag recorded by run_graph.sh (its run directory or bag/)')
    ap.add_argument('--out', type=Path, default=None)
    ap.add_argument('--params-file', type=Path, default=None,
                    help="filter parameters (default: the run's params.yaml next to the bag, if any)")
    ap.add_argument('--set', dest='sets', action='append', default=[], metavar='KEY=VALUE',
                    help='a scenario key for the filter, as run_graph.sh --set (repeatable)')
    ap.add_argument('--domain-id', type=domain_id, default=None,
                    help='ROS_DOMAIN_ID for the replay (default: the exported ROS_DOMAIN_ID, else a '
                         'free one; printed at the start)')
    ap.add_argument('--quiet', action='store_true', help='no progress line on stderr')
    ap.add_argument('--no-plots', action='store_true', help='no plots nor report.md in DIR')
    return ap.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    return guarded_main('replay', _main, parse_args(argv))


def _input(bag: Path, params_in: Path | None, sets: list[str]) -> tuple[
        bag_reindex.Reindexed | None, int, int, list, list, bool, dict, list[str]]:
    """(repair done, first and last stamp the replay covers, topics to play, to wait for,
    whether the bag has the misalignment's truth, the filter's parameters, notes on them)."""
    repaired = bag_reindex.repair_if_damaged(bag) if bag.is_dir() else None
    if bag.is_file() and not bag_reindex.file_intact(bag):
        # a lone .mcap file cut short: read as far as it goes (a repair needs a bag directory)
        logging.getLogger('alignment_ros.bag').setLevel(logging.ERROR)   # said once, by main
        repaired = bag_reindex.Reindexed(bag, 'a .mcap file without a valid summary (cut short?)')
    given, notes = replay_params.replay_parameters(bag, params_in, sets)
    reader = BagReader(bag)
    bag_topics = reader.topics()
    if topics.AIRCRAFT_IMU not in bag_topics:
        raise BagError(f'{bag}: no {topics.AIRCRAFT_IMU} topic')
    play, wait = replay_topics(bag_topics, given)
    inputs = {topics.AIRCRAFT_IMU, topics.MASTER_ODOM, topics.LDV_TWIST}
    if f'{topics.DOPPLER_TWIST}=1' in wait:
        inputs.add(topics.DOPPLER_TWIST)
    first: dict[str, int] = {}
    last: dict[str, int] = {}
    for m in reader.messages(sorted(inputs)):
        first.setdefault(m.topic, m.t_ns)
        last[m.topic] = m.t_ns
    if topics.MASTER_ODOM not in last:
        raise BagError(f'{bag}: no {topics.MASTER_ODOM} messages')
    # a cut input: its streams end at different stamps, the filter's outputs at the earliest
    end_ns = min(last.values()) if repaired is not None else last[topics.MASTER_ODOM]
    scenario_file = bag.parent / 'scenario.yaml'     # a run of the graph: its end, not its run-out's
    if bag.is_dir() and scenario_file.exists():
        end_ns = min(end_ns, run_out.end_ns(core_scenario.load(str(scenario_file))))
    return (repaired, first[topics.MASTER_ODOM], end_ns, play, wait, topics.TRUTH_MISALIGNMENT in bag_topics,
            given, notes)


def _main(a: argparse.Namespace, guard: SignalGuard) -> int:
    bag = a.bag / 'bag' if (a.bag / 'bag').is_dir() else a.bag
    params_in = a.params_file or (bag.parent / 'params.yaml' if (bag.parent / 'params.yaml').exists() else None)
    if params_in is not None and not params_in.exists():
        print(f'replay: no parameters at {params_in}', file=sys.stderr)
        return 2
    out = a.out or root() / 'runs' / time.strftime('replay-%Y%m%d-%H%M%S')
    if (out / 'bag').exists():
        print(f'replay: {out}/bag already exists', file=sys.stderr)
        return 2
    try:
        repaired, start_ns, end_ns, play, wait, has_truth, given, notes = _input(bag, params_in, a.sets)
    except (BagError, ConfigError, ValueError, OSError) as e:
        print(f'replay: {e}', file=sys.stderr)
        return 2
    for line in notes:
        print(f'replay: {line}', file=sys.stderr)
    for d in ('logs', 'stats'):
        (out / d).mkdir(parents=True, exist_ok=True)
    params = out / 'params.yaml'
    replay_params.write_params(given, params)
    run = Run('replay', out, guard)
    if repaired is not None and bag.is_dir():
        print(f'replay: input bag repaired: {repaired.line()}', file=sys.stderr)
        run.problems.append(f'the input bag was damaged ({repaired.damage}) and repaired')
    elif repaired is not None:
        print(f'replay: {bag}: {repaired.damage}', file=sys.stderr)
        run.problems.append(f'the input is {repaired.damage}')
    run.use_domain(a.domain_id)
    clean_stale(log=lambda m: print(f'replay: {m}', file=sys.stderr))   # killed runs' /dev/shm
    live = LiveProgress('replay', (end_ns - start_ns) * 1e-9, start_ns * 1e-9, quiet=a.quiet)
    wall = _run(run, bag, params, play, wait, end_ns, damaged=repaired is not None, live=live)
    run.end(out / 'bag')
    s = None
    try:
        s = summary.summarise(bag, out / 'bag', start_ns * 1e-9, (end_ns - start_ns) * 1e-9, wall,
                              published_counts(out, with_held=True),
                              run.foreign_publishers({FILTER}), run.problems,
                              published_known=not run.unknown_counts(), truth=has_truth,
                              latency_s=node_scenario(given, NODE_SCOPES[FILTER]).filter.master_latency_s)
        s['replayed_from'] = str(bag)
        summary.write(s, out)
    except (BagError, OSError) as e:
        summary.write({'complete': False, 'lost_total': None,
                       'problems': [*run.problems, f'no bag to read: {e}'],
                       'replayed_from': str(bag)}, out)
    live.close(s if run.interrupted is None else None)
    if not a.no_plots and run.interrupted is None:
        from . import run_report  # matplotlib: loaded for the report, not at start-up
        run_report.write(out, s, input_bag=bag)
    if run.interrupted is not None:
        print(run.stopped_line(s), file=sys.stderr)
    else:
        if run.failure is not None:
            print(f'replay: {run.failure}', file=sys.stderr)
        if s is not None:
            print(summary.table(s))
        print(f'output: {out}')
    return run.exit_code(s is not None and s['complete'])


def _run(run: Run, bag: Path, params: Path, play: list[str], wait: list[str], end_ns: int,
         damaged: bool, live: LiveProgress) -> float:
    """Recorder, filter, player; wait until the outputs reach the end; finish the recording.
    Return the wall time to the end (or to the cut: run.interrupted/failure)."""
    out = run.out
    wall0 = time.monotonic()
    try:
        expect = out / 'stats' / 'published.json'
        rec = start_recorder(run, out / 'bag', end_ns * 1e-9, list(FILTER_OUTPUT_TOPICS),
                             [topics.ALIGN_MISALIGNMENT], expect_counts=expect)
        end_reached = watch_end_time(rec, live.recorded)
        live.start()
        start(run, FILTER, params, '-p', HOLD)
        _wait_graph()
        player = run.spawn('player', [
            str(root() / 'ros2_ws/install/alignment_ros/lib/alignment_ros/player'), str(bag),
            '--topics', *play, '--stats', str(out / 'stats' / 'player.json'),
            '--rate', '0', '--lossless',   # as fast as the filter acknowledges, nothing lost
            '--wait-subscribers', *wait, '--quiet'],
            stdout=open(out / 'logs' / 'player.log', 'w'), stderr=subprocess.STDOUT)
        while player.poll() is None:
            run.check_running()
            if rec.poll() is not None:
                raise RuntimeError('the recorder ended while the player played')
            time.sleep(0.2)
        run.check_running()
        deadline = time.monotonic() + (DAMAGED_GRACE_S if damaged else END_TIMEOUT_S)
        while not end_reached.is_set() and rec.poll() is None and time.monotonic() < deadline:
            run.check_running()
            time.sleep(0.2)
        wall = time.monotonic() - wall0
        if rec.poll() is not None and not end_reached.is_set():
            raise RuntimeError('the replay was cut: the recorder ended before the end time')
        if not end_reached.is_set() and not damaged:
            raise RuntimeError(f'the filter outputs did not reach the end time within '
                               f'{END_TIMEOUT_S:.0f} s')
        # stop the filter once its subscribers acknowledged everything, then let the recorder
        # record every message the filter reports having published (as run_graph does)
        finish_recording(run, expect, end_reached.is_set())
        return wall
    except Interrupted as e:
        run.interrupted = e
    except RuntimeError as e:
        run.failure = str(e)
    finally:
        run.guard.ignore()      # the end is bounded: stop, repair, summarise
    return time.monotonic() - wall0


if __name__ == '__main__':
    sys.exit(main())
