"""Run the whole node graph for a scenario: recorder, filter, LDV, slave, master, ship.

Each node is a separate process with one params file: the scenario as given (its file's keys
and --set), which each node resolves itself (params.py); the resolved scenario is written next
to it (scenario.yaml). The nodes are forked from this launcher once it has imported their code
(:mod:`alignment_ros.forked`), with the command line scripts/start_node.sh would exec (which
starts them where this process cannot fork), beside the recorder. The ship node starts the clock
once every subscription is matched and runs on past the scenario's end for the run-out
(alignment_core/run_out.py: a sensor with its own rate, latency or jitter would otherwise stop
short of the end, and the filter's outputs with it). When every stream of END_TOPICS has
reached the scenario's end, the recorder says so; then the nodes get SIGINT and stop once every subscriber
has acknowledged every message they sent; their published counts go to the recorder
(stats/published.json), which records until it has all of them (no quiet-period guess: on a
loaded machine a message the transport dropped arrives seconds later, when the reliable
protocol resends it); then the summary is computed from the bag.

Exit status: 0 for a complete run; 1 for any other (a message lost or from a foreign
publisher, a run cut short, a process that failed, a bag that had to be repaired: the table's
last line and summary.json's ``complete``/``problems`` say which); 130/143 when stopped by
SIGINT/SIGTERM (every process stopped, the bag closed, one line); 2 for a bad command line.
The processes of a run never outlive it (:mod:`alignment_ros.launch`).
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

import yaml

from alignment_core import compiled
from alignment_core.config import scenario as core_scenario
from alignment_core.ship import motion
from alignment_core.validation import ConfigError

from . import forked, summary, topics
from .bag import BagError
from .launch import (
    OneLineParser,
    Run,
    domain_id,
    finish_recording,
    guarded_main,
    malformed_inputs,
    number_type,
    published_counts,
    root,
    start_recorder,
    unpaired_drops,
    wait_ready,
    watch_end_time,
)
from .params import given_parameters
from .progress_watch import LiveProgress
from .shm_cleanup import clean_stale
from .signals import Interrupted, SignalGuard

# the nodes (the recorder among them) whose subscriptions each node waits for before it sends on
# a topic: by name, so that another subscriber (echo.sh, a second recorder) cannot stand in for
# one still being discovered, which would miss the start
REC, SHIP, MASTER, SLAVE, LDV, FILTER = ('recorder', 'ship_motion_node', 'master_ins_node', 'slave_ins_node',
                                         'ldv_node', 'alignment_filter_node')
AIR, AIR_FILTER = 'air_data_node', 'air_data_filter_node'
MATCHED: dict[str, dict[str, tuple[str, ...]]] = {
    SHIP: {topics.CLOCK: (REC,), topics.SHIP_ODOM: (REC, MASTER, SLAVE, LDV), topics.SHIP_ACCEL: (REC, SLAVE),
           topics.SHIP_FIX: (REC,)},
    MASTER: {topics.MASTER_ODOM: (REC, FILTER), topics.MASTER_FIX: (REC,), topics.TRUTH_MASTER_ERROR: (REC,)},
    SLAVE: {topics.AIRCRAFT_IMU: (REC, FILTER), topics.TRUTH_AIRCRAFT_ODOM: (REC, LDV, SHIP),   # SHIP: its pacing
            topics.TRUTH_MISALIGNMENT: (REC,), topics.TRUTH_IMU_BIAS: (REC,)},
    LDV: {topics.LDV_TWIST: (REC, FILTER), topics.DOPPLER_TWIST: (REC, FILTER)},
    FILTER: {**{t: (REC,) for t in topics.FILTER_OUTPUT_TOPICS}, topics.ALIGN_MISALIGNMENT: (REC, SHIP)},
}

# the ship runs at most its lead ahead of these (alignment_ros.pacing): of the slave's truth (the
# LDV pairs it with the ship's odometry and would buffer the ship's for as long as the slave lags)
# of the filter's output (the slowest consumer: every queue upstream of it holds at most the lead)
# and of the recorder's progress (the one consumer of every stream: its queues and the writers'
# histories it has not acknowledged hold at most the lead too)
PACE_TOPICS = (topics.TRUTH_AIRCRAFT_ODOM, topics.ALIGN_MISALIGNMENT, topics.RECORDER_PROGRESS)
MAX_LEAD_S = 5.0
NODES = ('alignment_filter_node', 'ldv_node', 'slave_ins_node', 'master_ins_node')
AIR_DATA_TOPICS = (*topics.FADS_PORT_TOPICS, topics.AIR_DATA_VELOCITY, topics.AIR_DATA_STATIC_PRESSURE,
                   topics.AIR_DATA_TOTAL_PRESSURE, topics.AIR_DATA_WIND, topics.AIR_DATA_STATE,
                   topics.TRUTH_AIR_DATA_STATE, topics.TRUTH_WIND)


def nodes_of(sc: core_scenario.Scenario) -> tuple[str, ...]:
    """The nodes of a scenario's run but the ship (started apart, first), consumers before producers."""
    if not sc.fads.enabled:
        return NODES
    return ('air_data_filter_node', 'alignment_filter_node', 'ldv_node', 'air_data_node', 'slave_ins_node',
            'master_ins_node')


def matched_of(sc: core_scenario.Scenario) -> dict[str, dict[str, tuple[str, ...]]]:
    """MATCHED with the subscriptions the scenario's optional nodes add."""
    m = {k: dict(v) for k, v in MATCHED.items()}
    air, ref = sc.fads.enabled, sc.reference_ins.enabled
    paper, aligned = sc.air_data_filter.form == 'paper', sc.air_data_filter.ins_source == 'aligned'
    if air:
        m[AIR] = {**{t: (REC, AIR_FILTER) for t in topics.FADS_PORT_TOPICS}, topics.TRUTH_AIR_DATA_STATE: (REC,),
                  topics.TRUTH_WIND: (REC,)}
        m[AIR_FILTER] = {t: (REC,) for t in (topics.AIR_DATA_VELOCITY, topics.AIR_DATA_STATIC_PRESSURE,
                                             topics.AIR_DATA_TOTAL_PRESSURE, topics.AIR_DATA_WIND,
                                             topics.AIR_DATA_STATE, topics.DIAGNOSTICS)}
        m[AIR_FILTER][topics.AIR_DATA_VELOCITY] += (SHIP,)     # the ship's pacing watcher
        m[SLAVE][topics.TRUTH_AIRCRAFT_ODOM] += (AIR,)
        if paper:
            m[SLAVE][topics.AIRCRAFT_IMU] += (AIR_FILTER,)
        if aligned:
            m[FILTER][topics.ALIGN_ODOM] += (AIR_FILTER,)
    if ref:
        m[SLAVE][topics.REFERENCE_INS_ODOM] = (REC,) if aligned or not air else (REC, AIR_FILTER)
    return m


def pace_topics_of(sc: core_scenario.Scenario) -> tuple[str, ...]:
    """PACE_TOPICS, and the air-data filter's output when the scenario has one."""
    return PACE_TOPICS + ((topics.AIR_DATA_VELOCITY,) if sc.fads.enabled else ())


def max_lead_of(sc: core_scenario.Scenario) -> float:
    """MAX_LEAD_S, or three output periods of a filter publishing more slowly (the ship must be
    able to run past a filter's next output for the filter to reach it)."""
    rates = [sc.filter.output_rate_hz] + ([sc.air_data_filter.output_rate_hz] if sc.fads.enabled else [])
    return max(MAX_LEAD_S, 3.0 / min(rates))


def recorded_of(sc: core_scenario.Scenario) -> list[str]:
    """The topics a run records: every one of the interface, optional sensors' only when enabled
    (no empty topics in the bag)."""
    return [t for t in topics.TOPIC_TYPES
            if (t != topics.DOPPLER_TWIST or sc.doppler.enabled) and (t not in AIR_DATA_TOPICS or sc.fads.enabled)
            and (t != topics.REFERENCE_INS_ODOM or sc.reference_ins.enabled)]


def end_topics_of(sc: core_scenario.Scenario) -> tuple[str, ...]:
    """Stamped topics only: an unstamped one's time is the recorder's /clock when it arrives,
    which lags the stream under load (its last message may be logged before the end)."""
    return END_TOPICS + ((topics.FADS_PORT_TOPICS[-1], topics.AIR_DATA_VELOCITY) if sc.fads.enabled else ())


def _list_param(name: str, items: dict[str, tuple[str, ...]]) -> str:
    return f'{name}:=[' + ','.join(f'"{t}:{"+".join(nodes)}"' for t, nodes in items.items()) + ']'


# the streams whose last stamp marks the end of the run (the filter's output last: it has
# processed everything); the recorder then waits for the publishers' final counts of every topic
END_TOPICS = (topics.SHIP_ODOM, topics.MASTER_ODOM, topics.AIRCRAFT_IMU, topics.LDV_TWIST,
              topics.TRUTH_AIRCRAFT_ODOM, topics.ALIGN_MISALIGNMENT)


def params_yaml(given: dict, sc: core_scenario.Scenario, header: str = '') -> str:
    """A params file for every node: the scenario as given (nested; `sc` its resolution),
    not resolved, so a node's -p has the effect --set has (a key given here stays fixed)."""
    body = yaml.safe_dump({'/**': {'ros__parameters': given_parameters(given, sc)}}, sort_keys=False)
    return header + body


def write_params(given: dict, sc: core_scenario.Scenario, path: Path) -> None:
    path.write_text(params_yaml(given, sc))


def start(run: Run, name: str, params: Path, *args: str,
          matched: dict[str, dict[str, tuple[str, ...]]] = MATCHED,
          fork: bool = False) -> subprocess.Popen | forked.ForkedProcess:
    """Start a node of the run, its output to logs/NAME.log: through scripts/start_node.sh, or
    with `fork` as a fork of this launcher (:mod:`alignment_ros.forked`) with the command line
    start_node.sh would exec."""
    out = run.out
    log = open(out / 'logs' / f'{name}.log', 'w')
    ros_args = ['-p', f'stats_path:={out / "stats" / (name + ".json")}', *args]
    if name in matched and not any('hold_until_matched' in x for x in args):
        ros_args += ['-p', _list_param('hold_until_matched', matched[name])]
    if fork:
        exe = root() / 'ros2_ws' / 'install' / name / 'lib' / name / name
        argv = [str(exe), '--ros-args', '--params-file', str(params), *ros_args]
        with log:
            return run.fork(name, forked.entry_point(name), argv, log)
    cmd = [str(root() / 'scripts' / 'start_node.sh'), name, '--params-file', str(params), '--ros-args', *ros_args]
    return run.spawn(name, cmd, stdout=log, stderr=subprocess.STDOUT)


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    ap = OneLineParser(prog='run_graph.sh', description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--scenario', default='catapult')
    ap.add_argument('--out', type=Path, default=None)
    ap.add_argument('--seed', type=number_type(0, kind=int), default=None)
    ap.add_argument('--set', dest='sets', action='append', default=[], metavar='KEY=VALUE')
    ap.add_argument('--real-time-factor', type=number_type(0.0), default=5.0,
                    help='simulation speed: 1 = real time, 0 = as fast as possible (default 5)')
    ap.add_argument('--timeout', type=number_type(0.0, strict=True), default=None,
                    help='wall seconds before giving up (default 120 + 3 x duration)')
    ap.add_argument('--domain-id', type=domain_id, default=None,
                    help='ROS_DOMAIN_ID for the run (default: the exported ROS_DOMAIN_ID, else a '
                         'free one; printed at the start)')
    ap.add_argument('--quiet', action='store_true', help='no progress line on stderr')
    ap.add_argument('--no-plots', action='store_true', help='no plots nor report.md in DIR')
    return ap.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    return guarded_main('run_graph', _main, parse_args(argv))


def _command_start() -> float:
    """When the user's command started (run_graph.sh exports it), else now (Unix seconds)."""
    ns = os.environ.get('ALIGNMENT_COMMAND_START_NS', '')
    return int(ns) * 1e-9 if ns.isdigit() else time.time()


def _main(a: argparse.Namespace, guard: SignalGuard) -> int:
    started = _command_start()
    try:
        given = core_scenario.given_data(a.scenario, core_scenario.parse_overrides(a.sets), a.seed)
        sc = core_scenario.resolve(given)
    except ConfigError as e:
        print(f'run_graph: {e}', file=sys.stderr)
        return 2
    out = a.out or root() / 'runs' / time.strftime(f'{sc.name}-%Y%m%d-%H%M%S')
    if (out / 'bag').exists():
        print(f'run_graph: {out}/bag already exists; choose another --out', file=sys.stderr)
        return 2
    for d in ('logs', 'stats'):
        (out / d).mkdir(parents=True, exist_ok=True)
    run = Run('run_graph', out, guard)
    run.use_domain(a.domain_id)
    clean_stale(log=lambda m: print(f'run_graph: {m}', file=sys.stderr))   # killed runs' /dev/shm
    (out / 'scenario.yaml').write_text(core_scenario.dump(sc))
    params = out / 'params.yaml'
    write_params(given, sc, params)
    live = LiveProgress('run_graph', sc.duration_s, sc.start_time_s, quiet=a.quiet)
    try:
        wall = _run(run, a, sc, params, live)
        run.end(out / 'bag')
        s = _summary(run, sc, wall, started)
    except BaseException:
        live.watcher.stop()     # a participant left running aborts the interpreter's exit
        raise
    live.close(s if run.interrupted is None else None)
    if not a.no_plots and run.interrupted is None:
        from . import run_report  # matplotlib: loaded for the report, not at start-up
        run_report.write(out, s)
    if run.interrupted is not None:
        print(run.stopped_line(s), file=sys.stderr)
    else:
        if run.failure is not None:
            print(f'run_graph: {run.failure}', file=sys.stderr)
        if s is not None:
            print(summary.table(s))
        print(f'output: {out}')
    return run.exit_code(s is not None and s['complete'])


def _run(run: Run, a: argparse.Namespace, sc: core_scenario.Scenario, params: Path, live: LiveProgress) -> float:
    """Start the recorder and the nodes, wait until every stream reached the end, finish the
    recording; return the wall time to the end (or to the cut: run.interrupted/failure)."""
    out = run.out
    end_s = sc.start_time_s + sc.duration_s
    wall0 = time.monotonic()
    try:
        matched = matched_of(sc)
        expect = out / 'stats' / 'published.json'
        # the recorder's process first and the nodes beside it, all discovering each other from
        # their start (a reader found while data already flows may get a message of a topic out
        # of order), forked while this process runs no other thread (the recorder's reader and
        # the progress line start after them); then the recorder's ready line
        rec = start_recorder(run, out / 'bag', end_s, recorded_of(sc), end_topics_of(sc), expect_counts=expect,
                             progress_topic=topics.RECORDER_PROGRESS, wait=False)
        unsafe = forked.unsafe_reason()
        fork = unsafe is None
        run.node_start = 'fork' if fork else f'start_node.sh ({unsafe})'
        if not fork:
            print(f'run_graph: nodes started through scripts/start_node.sh: {unsafe}', file=sys.stderr)
        # the ship first, once its own code is imported (its ship model's module too, and numba:
        # the spectral sea runs a kernel, which it would otherwise import on the way to the first
        # message): the first message waits for its start-up, which the other nodes' imports and
        # start-up overlap; it publishes nothing before every reader it waits for has matched
        try:
            if fork:
                forked.entry_point('ship_motion_node')
                motion.model_class(sc.ship)
                compiled.activate()            # the slave and the filter run kernels too
            start(run, 'ship_motion_node', params, '-p', f'real_time_factor:={a.real_time_factor}',
                  '-p', _list_param('wait_subscribers', MATCHED['ship_motion_node']),
                  '-p', 'pace_topics:=[' + ','.join(f'"{t}"' for t in pace_topics_of(sc)) + ']',
                  '-p', f'max_lead_s:={max_lead_of(sc)}', fork=fork)
            if fork:
                for n in nodes_of(sc):
                    forked.entry_point(n)      # every other node's imports once, before their forks
            for n in nodes_of(sc):
                start(run, n, params, matched=matched, fork=fork)
        finally:
            if fork:
                forked.thaw_launcher()
        wait_ready(run, rec)
        end_reached = watch_end_time(rec, live.recorded)
        live.start()
        timeout = a.timeout or 120.0 + 3.0 * sc.duration_s
        deadline = time.monotonic() + timeout
        while rec.poll() is None and not end_reached.is_set():
            run.check_running()
            if time.monotonic() > deadline:
                raise RuntimeError(f'run did not finish within {timeout:.0f} s')
            time.sleep(0.2)
        wall = time.monotonic() - wall0
        if not end_reached.is_set():
            raise RuntimeError('the run was cut: the recorder ended before the end time')
        finish_recording(run, expect)
        return wall
    except Interrupted as e:
        run.interrupted = e
    except RuntimeError as e:
        run.failure = str(e)
    finally:
        run.guard.ignore()      # the end is bounded: stop, repair, summarise
    return time.monotonic() - wall0


def _short_of_the_end(stats: dict, end_topics: tuple[str, ...], end_s: float) -> str:
    """Which end topics the recorder had not seen reach the end when the run timed out (their
    last stamps as recorded by the time it stopped, and how many messages it took only then)."""
    last = stats.get('last_stamp_ns', {})
    short = [f'{t} (last {last[t] * 1e-9:.2f} s)' if t in last else f'{t} (none)'
             for t in end_topics if last.get(t, -1) < round(end_s * 1e9)]
    where = ', '.join(short) if short else 'none by the time the recorder stopped'
    return (f'end topics short of t = {end_s:.2f} s: {where}; taken by the recorder only at its stop: '
            f'{stats.get("taken_directly", "unknown")}')


def _summary(run: Run, sc: core_scenario.Scenario, wall: float, started: float) -> dict | None:
    """Write summary.json (for a cut run too: complete false); return it, or None if there is
    no bag to read. ``startup_s``: from the command's start to the first message recorded."""
    bag = run.out / 'bag'
    ours = {n for n in run.procs if n != 'recorder'}
    if run.failure is not None and run.failure.startswith('run did not finish'):
        run.problems.append(_short_of_the_end(run.recorder_stats(), end_topics_of(sc),
                                              sc.start_time_s + sc.duration_s))
    for node, n in unpaired_drops(run.out).items():
        run.problems.append(f'{node} dropped {n} unpaired half-samples (its input fell too far behind)')
    for node, n in malformed_inputs(run.out).items():
        run.problems.append(f'{node} rejected {n} input messages it could not read (malformed)')
    try:
        s = summary.summarise(bag, bag, sc.start_time_s, sc.duration_s, wall,
                              published_counts(run.out, with_held=True),
                              run.foreign_publishers(ours), run.problems,
                              published_known=not run.unknown_counts(),
                              latency_s=sc.filter.master_latency_s)
    except (BagError, OSError) as e:
        summary.write({'complete': False, 'lost_total': None,
                       'problems': [*run.problems, f'no bag to read: {e}'],
                       'scenario': sc.name, 'seed': sc.seed}, run.out)
        return None
    s['scenario'] = sc.name
    s['seed'] = sc.seed
    first = run.recorder_stats().get('first_message_unix_s')
    s['startup_s'] = None if first is None else first - started
    s['node_start'] = run.node_start
    summary.write(s, run.out)
    return s


if __name__ == '__main__':
    sys.exit(main())
