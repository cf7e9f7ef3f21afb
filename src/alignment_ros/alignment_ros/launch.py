"""The processes of one run of run_graph.sh or replay.sh, and how a run ends.

Each process starts in a session of its own (the terminal's Ctrl-C reaches the launcher only,
which stops them in order: the nodes, once their subscribers acknowledged everything, then the
recorder, which closes the bag), holds the run's domain lock (inherited descriptor: the domain
stays claimed until the last of them is gone) and gets SIGTERM when the launcher dies, even by
SIGKILL (``PR_SET_PDEATHSIG``, set in the child before exec: the kernel delivers it at once, no
node code polls for it, and the nodes stop on SIGTERM as on SIGINT, the recorder closing its
bag). However a run ends, :meth:`Run.end` stops what still runs, notes what went wrong (a
recorder that died or stopped short, a bag that needed repair) and repairs the bag
(:mod:`alignment_ros.bag_reindex`).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import IO

from . import bag_reindex, domain, forked
from .bag import BagError
from .signals import Interrupted, SignalGuard, die_with_parent

NODE_STOP_TIMEOUT_S = 60.0    # > node_util.ACK_TIMEOUT_S: nodes wait for acknowledgements
CUT_NODE_STOP_TIMEOUT_S = 10.0   # a cut run: the subscribers may be gone, their acks with them
RECORDER_EXPECT_TIMEOUT_S = 120.0
RECORDER_CLOSE_TIMEOUT_S = 60.0  # closing writes the reorder buffer's rest and the summary


def root() -> Path:
    return Path(os.environ.get('ALIGN_ROOT', Path(__file__).resolve().parents[3]))


class OneLineParser(argparse.ArgumentParser):
    """argparse whose errors are one line (``prog: error: ...``, exit status 2)."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f'{self.prog}: error: {message}\n')


def number_type(minimum: float, *, strict: bool = False, kind: type = float):
    """An argparse type: a finite number >= minimum (> minimum if strict)."""
    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f'{text!r} is not a number') from None
        if not math.isfinite(value) or value < minimum or (strict and value == minimum):
            raise argparse.ArgumentTypeError(
                f'{text} is not {">" if strict else ">="} {minimum:g}')
        return value
    return parse


def domain_id(text: str) -> int:
    """An argparse type: a ROS domain id (0..domain.MAX_DOMAIN)."""
    value = number_type(0, kind=int)(text)
    if value > domain.MAX_DOMAIN:
        raise argparse.ArgumentTypeError(f'{text} is not a domain id (0..{domain.MAX_DOMAIN})')
    return value


class Run:
    """The processes of one run (by name), what went wrong, and its end."""

    def __init__(self, prog: str, out: Path, guard: SignalGuard) -> None:
        self.prog = prog
        self.out = out
        self.guard = guard
        self.procs: dict[str, subprocess.Popen | forked.ForkedProcess] = {}
        self.problems: list[str] = []
        self.repaired: bag_reindex.Reindexed | None = None
        self.interrupted: Interrupted | None = None
        self.failure: str | None = None
        self._fds: tuple[int, ...] = ()
        self._preexec = die_with_parent(signal.SIGTERM)
        self.node_start = ''             # how the nodes were started: 'fork' or why not

    def use_domain(self, given: int | None) -> int:
        """Claim this run's ROS domain (--domain-id, else an exported ROS_DOMAIN_ID, else a free
        one), export it to the processes it starts, print it; one that cannot be had ends the
        run (2)."""
        try:
            dom = domain.for_run(given)
        except RuntimeError as e:
            print(f'{self.prog}: {e}', file=sys.stderr)
            raise SystemExit(2) from None
        os.environ['ROS_DOMAIN_ID'] = str(dom)
        self._fds = (domain.lock_fd(dom),)
        print(f'ROS_DOMAIN_ID={dom}  (to watch: ROS_DOMAIN_ID={dom} scripts/echo.sh TOPIC)', flush=True)
        return dom

    def spawn(self, name: str, cmd: list[str], **kw) -> subprocess.Popen:
        """Start a process of the run (own session, domain lock, dies with the launcher)."""
        with self.guard.deferred():
            p = subprocess.Popen(cmd, start_new_session=True, pass_fds=self._fds,
                                 preexec_fn=self._preexec, **kw)
            self.procs[name] = p
        return p

    def fork(self, name: str, entry: Callable[[], object], argv: list[str], log: IO) -> forked.ForkedProcess:
        """Start a node of the run as a fork of this process (:mod:`alignment_ros.forked`): what
        :meth:`spawn` gives an exec'd one, without the node's imports."""
        with self.guard.deferred():
            p = forked.fork_node(entry, argv, log, self._fds, self._preexec)
            self.procs[name] = p
        return p

    def stop(self, names: list[str], timeout: float) -> None:
        """SIGINT to these processes' groups; SIGKILL to those still there after `timeout`."""
        procs = [(n, self.procs[n]) for n in names if n in self.procs]
        for _, p in procs:
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGINT)
        deadline = time.monotonic() + timeout
        killed = []
        for name, p in procs:
            try:
                p.wait(max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()
                killed.append(name)
        if killed:
            self.problems.append(f'{", ".join(killed)} did not stop within {timeout:.0f} s: killed')

    def nodes(self) -> list[str]:
        return [n for n in self.procs if n != 'recorder']

    def check_running(self) -> None:
        """RuntimeError if a node exited with an error (the ship node ends by itself: 0)."""
        for n in self.nodes():
            rc = self.procs[n].poll()
            if rc not in (None, 0):
                raise RuntimeError(f'{n} {_status(rc)}; see {self.out}/logs/{n}.log')

    def end(self, bag: Path) -> None:
        """Stop what still runs (nodes, then the recorder), note how the recorder ended, and
        repair the bag if it needs it (one line saying so)."""
        cut = self.interrupted is not None or self.failure is not None
        self.stop(self.nodes(), CUT_NODE_STOP_TIMEOUT_S if cut else NODE_STOP_TIMEOUT_S)
        self.stop(['recorder'], RECORDER_CLOSE_TIMEOUT_S)
        if self.interrupted is not None:
            self.problems.insert(0, f'stopped by {self.interrupted.name}')
        if self.failure is not None:
            self.problems.insert(0, self.failure)
        if self.unknown_counts():
            self.problems.append(f'no stats from {", ".join(self.unknown_counts())}: '
                                 'what they published is unknown')
        rec = self.procs.get('recorder')
        stats = self.recorder_stats()
        if rec is not None and rec.returncode != 0:
            self.problems.append(f'the recorder {_status(rec.returncode)}')
        elif stats.get('end_reason') not in (None, 'end_time', 'signal', 'incomplete'):
            self.problems.append(f'the recorder stopped early ({stats["end_reason"]})')
        if stats.get('missing'):
            self.problems.append(f'the recorder ended without {stats["missing"]}')
        try:
            self.repaired = bag_reindex.repair_if_damaged(bag) if bag.exists() else None
        except (BagError, OSError) as e:
            self.problems.append(f'the bag could not be repaired: {e}')
            return
        if self.repaired is not None:
            self.problems.append(f'bag repaired ({self.repaired.damage})')
            if self.interrupted is None:    # an interrupted run says it in its one line
                print(f'{self.prog}: bag repaired: {self.repaired.line()}', file=sys.stderr)

    def unknown_counts(self) -> list[str]:
        """The nodes that wrote no stats (killed): their published counts are unknown."""
        return [n for n in self.nodes()
                if n.endswith('_node') and not (self.out / 'stats' / f'{n}.json').exists()]

    def recorder_stats(self) -> dict:
        f = self.out / 'stats' / 'recorder.json'
        return json.loads(f.read_text()) if f.exists() else {}

    def foreign_publishers(self, ours: set[str]) -> dict[str, list[str]]:
        """Publishers the recorder saw on its topics that are not this run's nodes (a node
        name of ours with two publishers on one topic: another process of that name)."""
        out: dict[str, list[str]] = {}
        for topic, pubs in self.recorder_stats().get('publishers', {}).items():
            names = sorted(n for n, k in pubs.items() if n.rsplit('/', 1)[-1] not in ours or k > 1)
            if names:
                out[topic] = names
        return out

    def exit_code(self, complete: bool) -> int:
        """128 + the signal if interrupted, else 0 for a complete run, 1 for any other."""
        if self.interrupted is not None:
            return self.interrupted.exit_code
        return 0 if complete and self.failure is None else 1

    def stopped_line(self, s: dict | None) -> str:
        """The one line an interrupted run prints."""
        where = '' if s is None else f" at t = {s['sim_time_s']:.2f} s of {s['planned_sim_time_s']:.2f} s"
        bag = 'bag repaired' if self.repaired is not None else 'bag closed'
        assert self.interrupted is not None
        return (f'{self.prog}: stopped by {self.interrupted.name}{where}; every process stopped, '
                f'{bag}: {self.out}')


def _status(rc: int | None) -> str:
    if rc is not None and rc < 0:
        return f'was killed by {signal.Signals(-rc).name}'
    return f'exited with status {rc}'


def start_recorder(run: Run, bag: Path, end_time_s: float, topic_list, wait_topics,
                   expect_counts: Path | None = None, progress_topic: str | None = None,
                   wait: bool = True) -> subprocess.Popen:
    """Start the recorder (no idle timeout: the run decides when it ends) and wait for its
    ``ready`` line (`wait` False: :func:`wait_ready` later). With expect_counts it records,
    after end-time, until every topic has the count that file gives (see
    :func:`finish_recording`)."""
    out = run.out
    cmd = [str(root() / 'ros2_ws/install/alignment_ros/lib/alignment_ros/recorder'),
           '--output', str(bag), '--node-name', 'recorder', '--idle-timeout', '0',
           '--end-time', repr(end_time_s), '--stats', str(out / 'stats' / 'recorder.json'),
           '--topics', *topic_list, '--wait-topics', *wait_topics, '--quiet', '--progress-lines']
    if progress_topic is not None:
        cmd += ['--progress-topic', progress_topic]
    if expect_counts is not None:
        cmd += ['--expect-counts', str(expect_counts),
                '--expect-timeout', repr(RECORDER_EXPECT_TIMEOUT_S)]
    p = run.spawn('recorder', cmd, stdout=subprocess.PIPE,
                  stderr=open(out / 'logs' / 'recorder.log', 'w'), text=True)
    if wait:
        wait_ready(run, p)
    return p


def wait_ready(run: Run, recorder: subprocess.Popen) -> None:
    """Read the recorder's output up to its ``ready`` line (RuntimeError if it does not come)."""
    assert recorder.stdout is not None
    deadline = time.monotonic() + 60
    for line in recorder.stdout:
        if 'ready' in line:
            return
        if time.monotonic() > deadline:
            break
    raise RuntimeError(f'the recorder did not become ready; see {run.out}/logs/recorder.log')


def watch_end_time(recorder: subprocess.Popen, on_progress=None) -> threading.Event:
    """An event set when the recorder prints that end-time is reached (its stdout is read to
    the end in a background thread); on_progress(messages, stamp_ns) gets its progress lines."""
    reached = threading.Event()

    def read() -> None:
        assert recorder.stdout is not None
        for line in recorder.stdout:
            if 'end-time reached' in line:
                reached.set()
            elif on_progress is not None and line.startswith('recorder progress '):
                messages, stamp_ns = line.split()[2:4]
                on_progress(int(messages), int(stamp_ns))
            elif on_progress is not None and line.startswith('recorder done '):
                on_progress(int(line.split(': ', 1)[1].split()[0]), 0)    # its final count
    threading.Thread(target=read, daemon=True).start()
    return reached


def write_expected_counts(path: Path, counts: dict[str, int]) -> None:
    """Atomically (the recorder polls for the file)."""
    tmp = path.with_suffix('.tmp')
    tmp.write_text(json.dumps(counts, indent=1, sort_keys=True) + '\n')
    os.replace(tmp, path)


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


def unpaired_drops(out: Path) -> dict[str, int]:
    """Per node, the halves of a sample it dropped unpaired (stamped_pairs.StampPairer's bound
    reached: its reader fell that far behind); from the nodes' stats files."""
    drops = {}
    for f in sorted((out / 'stats').glob('*_node.json')):
        n = json.loads(f.read_text()).get('rejected', {}).get('unpaired_dropped', 0)
        if n:
            drops[f.stem] = int(n)
    return drops


def malformed_inputs(out: Path) -> dict[str, int]:
    """Per node, the input messages it could not read (CountingNode.stream_subscription's
    'malformed <topic>' counts); from the nodes' stats files."""
    bad = {}
    for f in sorted((out / 'stats').glob('*_node.json')):
        n = sum(v for k, v in json.loads(f.read_text()).get('rejected', {}).items() if k.startswith('malformed '))
        if n:
            bad[f.stem] = int(n)
    return bad


def finish_recording(run: Run, expect_counts: Path, end_reached: bool = True) -> None:
    """End of a run, in order: stop the nodes (each exits once its subscribers acknowledged
    every message), give the recorder their published counts, wait until it has recorded them.
    If the recorder never reached end-time (it waits for the counts only after it), stop it:
    what its subscriptions acknowledged it still records."""
    run.stop(run.nodes(), NODE_STOP_TIMEOUT_S)
    write_expected_counts(expect_counts, published_counts(run.out))
    rec = run.procs['recorder']
    if not end_reached:
        run.stop(['recorder'], RECORDER_CLOSE_TIMEOUT_S)
        return
    try:
        rec.wait(RECORDER_EXPECT_TIMEOUT_S + 30.0)
    except subprocess.TimeoutExpired:
        run.stop(['recorder'], RECORDER_CLOSE_TIMEOUT_S)


def guarded_main(prog: str, run_main, args) -> int:
    """run_main(args, guard) with SIGINT/SIGTERM turned into Interrupted: a signal before any
    process was started prints one line and gives its exit status (130 / 143)."""
    guard = SignalGuard().install()
    try:
        return run_main(args, guard)
    except Interrupted as e:
        print(f'{prog}: {e}', file=sys.stderr)
        return e.exit_code
    finally:
        guard.restore()
