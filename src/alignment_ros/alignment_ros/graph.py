"""Run the whole node graph for a scenario: recorder, filter, LDV, slave, master, ship.

Each node is a separate process started through scripts/start_node.sh with one params file:
the scenario as given (its file's keys and --set), which each node resolves itself (params.py);
the resolved scenario is written next to it (scenario.yaml). The ship node starts the clock
once every subscription is matched. When every stream of END_TOPICS has reached the
scenario's end, the recorder says so; then the nodes get SIGINT and stop once every subscriber
has acknowledged every message they sent; their published counts go to the recorder
(stats/published.json), which records until it has all of them (no quiet-period guess: on a
loaded machine a message the transport dropped arrives seconds later, when the reliable
protocol resends it); then the summary is computed from the bag.
"""
from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import yaml

from alignment_core.config import scenario as core_scenario
from alignment_core.validation import ConfigError

from . import domain, summary, topics
from .params import given_parameters

# matched subscriptions (recorder included) each node waits for before it sends on a topic
MATCHED = {
    'ship_motion_node': {topics.CLOCK: 1, topics.SHIP_ODOM: 4, topics.SHIP_ACCEL: 2, topics.SHIP_FIX: 1},
    'master_ins_node': {topics.MASTER_ODOM: 2, topics.MASTER_FIX: 1, topics.TRUTH_MASTER_ERROR: 1},
    'slave_ins_node': {topics.AIRCRAFT_IMU: 2, topics.TRUTH_AIRCRAFT_ODOM: 2, topics.TRUTH_MISALIGNMENT: 1,
                       topics.TRUTH_IMU_BIAS: 1},
    'ldv_node': {topics.LDV_TWIST: 2, topics.DOPPLER_TWIST: 2},   # filter + recorder
    'alignment_filter_node': {t: 1 for t in topics.FILTER_OUTPUT_TOPICS},
}
NODES = ('alignment_filter_node', 'ldv_node', 'slave_ins_node', 'master_ins_node')


def _list_param(name: str, items: dict[str, int]) -> str:
    return f'{name}:=[' + ','.join(f'"{t}:{n}"' for t, n in items.items()) + ']'


# the streams whose last stamp marks the end of the run (the filter's output last: it has
# processed everything); the recorder then waits for the publishers' final counts of every topic
END_TOPICS = (topics.SHIP_ODOM, topics.MASTER_ODOM, topics.AIRCRAFT_IMU, topics.LDV_TWIST,
              topics.TRUTH_AIRCRAFT_ODOM, topics.ALIGN_MISALIGNMENT)
NODE_STOP_TIMEOUT_S = 60.0    # > node_util.ACK_TIMEOUT_S: nodes wait for acknowledgements
RECORDER_EXPECT_TIMEOUT_S = 120.0


def root() -> Path:
    return Path(os.environ.get('ALIGN_ROOT', Path(__file__).resolve().parents[3]))


def use_domain(given: int | None, prog: str = 'run_graph') -> int:
    """Claim this run's ROS domain (--domain-id, else an exported ROS_DOMAIN_ID, else a free
    one) and export it to the processes it starts; one that cannot be had ends the run (2)."""
    try:
        dom = domain.for_run(given)
    except RuntimeError as e:
        print(f'{prog}: {e}', file=sys.stderr)
        raise SystemExit(2) from None
    os.environ['ROS_DOMAIN_ID'] = str(dom)
    print(f'ROS_DOMAIN_ID={dom}  (to watch: ROS_DOMAIN_ID={dom} scripts/echo.sh TOPIC)', flush=True)
    return dom


def params_yaml(given: dict, sc: core_scenario.Scenario, header: str = '') -> str:
    """A params file for every node: the scenario as given (nested; `sc` its resolution),
    not resolved, so a node's -p has the effect --set has (a key given here stays fixed)."""
    body = yaml.safe_dump({'/**': {'ros__parameters': given_parameters(given, sc)}}, sort_keys=False)
    return header + body


def write_params(given: dict, sc: core_scenario.Scenario, path: Path) -> None:
    path.write_text(params_yaml(given, sc))


def start(name: str, params: Path, out: Path, *args: str) -> subprocess.Popen:
    log = open(out / 'logs' / f'{name}.log', 'w')
    cmd = [str(root() / 'scripts' / 'start_node.sh'), name, '--params-file', str(params),
           '--ros-args', '-p', f'stats_path:={out / "stats" / (name + ".json")}', *args]
    if name in MATCHED and not any('hold_until_matched' in x for x in args):
        cmd += ['-p', _list_param('hold_until_matched', MATCHED[name]), '-p', 'hold_for_node:=recorder']
    return subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)


def start_recorder(out: Path, bag: Path, end_time_s: float, topic_list, wait_topics,
                   name: str = 'recorder', expect_counts: Path | None = None) -> subprocess.Popen:
    """Start the recorder and wait for its ``ready`` line. With expect_counts it records, after
    end-time, until every topic has the count that file gives (see :func:`finish_recording`)."""
    cmd = [str(root() / 'ros2_ws/install/alignment_ros/lib/alignment_ros/recorder'),
           '--output', str(bag), '--node-name', 'recorder', '--idle-timeout', '5',
           '--end-time', repr(end_time_s), '--stats',
           str(out / 'stats' / f'{name}.json'), '--topics', *topic_list,
           '--wait-topics', *wait_topics]
    if expect_counts is not None:
        cmd += ['--expect-counts', str(expect_counts),
                '--expect-timeout', repr(RECORDER_EXPECT_TIMEOUT_S)]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=open(out / 'logs' / f'{name}.log', 'w'),
                         text=True, start_new_session=True)
    deadline = time.monotonic() + 60
    for line in p.stdout:
        if 'ready' in line:
            return p
        if time.monotonic() > deadline:
            break
    raise RuntimeError(f'{name} did not become ready; see {out}/logs/{name}.log')


def watch_end_time(recorder: subprocess.Popen) -> threading.Event:
    """An event set when the recorder prints that end-time is reached (its stdout is read to
    the end in a background thread)."""
    reached = threading.Event()

    def read() -> None:
        for line in recorder.stdout:
            if 'end-time reached' in line:
                reached.set()
    threading.Thread(target=read, daemon=True).start()
    return reached


def write_expected_counts(path: Path, counts: dict[str, int]) -> None:
    """Atomically (the recorder polls for the file)."""
    tmp = path.with_suffix('.tmp')
    tmp.write_text(json.dumps(counts, indent=1, sort_keys=True) + '\n')
    os.replace(tmp, path)


def finish_recording(procs: dict[str, subprocess.Popen], out: Path, expect_counts: Path) -> None:
    """End of a run, in order: stop the nodes (each exits once its subscribers acknowledged
    every message), give the recorder their published counts, wait until it has recorded them."""
    stop({n: p for n, p in procs.items() if n != 'recorder'}, timeout=NODE_STOP_TIMEOUT_S)
    write_expected_counts(expect_counts, published_counts(out))
    rec = procs['recorder']
    try:
        rec.wait(RECORDER_EXPECT_TIMEOUT_S + 30.0)
    except subprocess.TimeoutExpired:
        stop({'recorder': rec})
    stats = out / 'stats' / 'recorder.json'
    if stats.exists():
        st = json.loads(stats.read_text())
        if st.get('missing'):
            print(f'warning: the recorder ended ({st["end_reason"]}) without '
                  f'{st["missing"]}', file=sys.stderr)


def stop(procs: dict[str, subprocess.Popen], timeout: float = 15.0) -> None:
    for p in procs.values():
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGINT)
    deadline = time.monotonic() + timeout
    for name, p in procs.items():
        try:
            p.wait(max(0.1, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            print(f'warning: {name} did not stop in time and was killed', file=sys.stderr)


def published_counts(out: Path, with_held: bool = False) -> dict[str, int]:
    """Messages the nodes sent, per topic (from their stats files); with_held: plus those they
    still held at exit because their subscribers never matched (sent nowhere: lost too)."""
    pub: dict[str, int] = {}
    for f in sorted((out / 'stats').glob('*_node.json')):
        st = json.loads(f.read_text())
        items = list(st.get('published', {}).items())
        if with_held:
            items += list(st.get('held_unsent', {}).items())
        for k, v in items:
            pub[k] = pub.get(k, 0) + v
    return pub


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog='run_graph.sh', description=__doc__)
    ap.add_argument('--scenario', default='catapult')
    ap.add_argument('--out', type=Path, default=None)
    ap.add_argument('--seed', type=int, default=None)
    ap.add_argument('--set', dest='sets', action='append', default=[], metavar='KEY=VALUE')
    ap.add_argument('--real-time-factor', type=float, default=5.0)
    ap.add_argument('--timeout', type=float, default=None, help='wall seconds before giving up')
    ap.add_argument('--domain-id', type=int, default=None,
                    help='ROS_DOMAIN_ID for the run (default: the exported ROS_DOMAIN_ID, else a '
                         'free one; printed at the start)')
    a = ap.parse_args(argv)
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
    use_domain(a.domain_id)
    (out / 'scenario.yaml').write_text(core_scenario.dump(sc))
    params = out / 'params.yaml'
    write_params(given, sc, params)
    end_s = sc.start_time_s + sc.duration_s
    procs: dict[str, subprocess.Popen] = {}
    wall0 = time.monotonic()
    try:
        # optional sensors' topics are recorded only when enabled (no empty topics in the bag)
        recorded = [t for t in topics.TOPIC_TYPES if t != topics.DOPPLER_TWIST or sc.doppler.enabled]
        expect = out / 'stats' / 'published.json'
        procs['recorder'] = start_recorder(out, out / 'bag', end_s, recorded, END_TOPICS,
                                           expect_counts=expect)
        end_reached = watch_end_time(procs['recorder'])
        for n in NODES:
            procs[n] = start(n, params, out)
        procs['ship_motion_node'] = start(
            'ship_motion_node', params, out, '-p', f'real_time_factor:={a.real_time_factor}',
            '-p', _list_param('wait_subscribers', MATCHED['ship_motion_node']))
        timeout = a.timeout or 120.0 + 3.0 * sc.duration_s
        deadline = time.monotonic() + timeout
        while procs['recorder'].poll() is None and not end_reached.is_set():
            for n, p in procs.items():
                if n != 'recorder' and p.poll() not in (None, 0):
                    raise RuntimeError(f'{n} exited with {p.returncode}; see {out}/logs/{n}.log')
            if time.monotonic() > deadline:
                raise RuntimeError(f'run did not finish within {timeout:.0f} s')
            time.sleep(0.2)
        wall = time.monotonic() - wall0
    except RuntimeError as e:
        print(f'run_graph: {e}', file=sys.stderr)
        stop(procs)
        return 1
    finish_recording(procs, out, expect)
    s = summary.summarise(out / 'bag', out / 'bag', sc.duration_s, wall,
                          published_counts(out, with_held=True))
    s['scenario'] = sc.name
    s['seed'] = sc.seed
    summary.report(s, out)
    return 0


if __name__ == '__main__':
    sys.exit(main())
