"""A run of run_graph.sh ends cleanly however it is ended: SIGINT or SIGTERM stops every process
of the run within seconds, closes the bag (metadata.yaml, MCAP summary and index), prints one
line and exits 130 / 143; a recorder killed mid-run leaves a bag that run_graph repairs, says
so once and exits non-zero; and a process started by a launcher dies with it.

The processes of a run are the launcher's children (from /proc), each the leader of a process
group of its own: gone means the process and its whole group are gone."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from mcap.reader import make_reader

ROOT = Path(__file__).resolve().parents[2]
# still running when signalled: 30 s of deck matching at real time
SETS = ['duration_s=30.0', 'aircraft.catapult.enabled=false', 'seed=7']
N_PROCS = 6        # recorder + five nodes


def children(pid: int) -> list[int]:
    """The processes whose parent is `pid`."""
    out = []
    for d in Path('/proc').iterdir():
        try:
            stat = (d / 'stat').read_text()
        except (OSError, ValueError):
            continue
        if int(stat.rsplit(')', 1)[1].split()[1]) == pid:
            out.append(int(d.name))
    return out


def alive(pid: int) -> bool:
    """Running (not gone, not a zombie waiting for its parent)."""
    try:
        return Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()[0] != 'Z'
    except OSError:
        return False


def cmdline(pid: int) -> str:
    return Path(f'/proc/{pid}/cmdline').read_bytes().replace(b'\0', b' ').decode()


def start_run(out: Path) -> tuple[subprocess.Popen, list[int]]:
    """run_graph.sh on a free domain, once all its processes run and it records messages."""
    cmd = [str(ROOT / 'scripts/run_graph.sh'), '--scenario', 'catapult_paper', '--out', str(out),
           '--real-time-factor', '1']
    for s in SETS:
        cmd += ['--set', s]
    env = {k: v for k, v in os.environ.items() if k != 'ROS_DOMAIN_ID'}
    p = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    first = p.stdout.readline()
    while first.startswith('setup.sh:'):
        first = p.stdout.readline()
    assert first.startswith('ROS_DOMAIN_ID='), first + p.stderr.read()
    spool = out / 'bag' / 'bag.recording.mcap'
    deadline = time.monotonic() + 90
    while time.monotonic() < deadline:
        kids = children(p.pid)
        if len(kids) >= N_PROCS and spool.exists() and spool.stat().st_size > 300_000:
            return p, kids
        assert p.poll() is None, p.stderr.read()
        time.sleep(0.2)
    p.kill()
    pytest.fail('the run did not start recording within 90 s')


def assert_gone(kids: list[int]) -> None:
    for k in kids:
        assert not alive(k), cmdline(k)
        with pytest.raises(ProcessLookupError):
            os.killpg(k, 0)


def assert_indexed(bag: Path) -> int:
    """The bag opens through its MCAP summary and index; return its message count."""
    assert (bag / 'metadata.yaml').is_file()
    assert not list(bag.glob('*.recording.mcap'))
    (f,) = bag.glob('*.mcap')
    with f.open('rb') as fh:
        reader = make_reader(fh)
        summary = reader.get_summary()
        assert summary is not None and summary.chunk_indexes
        n = sum(1 for _ in reader.iter_messages())
    assert n == summary.statistics.message_count > 0
    return n


@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM])
def test_a_signal_stops_every_process_and_closes_the_bag(tmp_path, sig):
    out = tmp_path / 'run'
    p, kids = start_run(out)
    t0 = time.monotonic()
    p.send_signal(sig)
    stdout, stderr = p.communicate(timeout=120)
    took = time.monotonic() - t0
    assert p.returncode == 128 + sig, stdout + stderr
    assert took < 30, f'{took:.1f} s to stop'
    lines = [x for x in stderr.splitlines()
             if x.strip() and 'shared-memory files' not in x and not x.startswith('run_graph: t = ')]
    assert len(lines) == 1 and f'stopped by {sig.name}' in lines[0], stderr
    assert stdout.strip() == ''
    assert_gone(kids)
    assert_indexed(out / 'bag')
    s = json.loads((out / 'summary.json').read_text())
    assert s['complete'] is False
    assert f'stopped by {sig.name}' in s['problems']
    assert s['sim_time_s'] < s['planned_sim_time_s'] == 30.0


def test_a_killed_recorder_is_repaired_and_the_run_fails(tmp_path):
    out = tmp_path / 'run'
    p, kids = start_run(out)
    (rec,) = [k for k in kids if '/alignment_ros/recorder ' in cmdline(k)]
    os.kill(rec, signal.SIGKILL)
    stdout, stderr = p.communicate(timeout=180)
    assert p.returncode == 1, stdout + stderr
    assert 'Traceback' not in stderr
    repaired = [x for x in stderr.splitlines() if 'bag repaired' in x]
    assert len(repaired) == 1, stderr
    assert 'INCOMPLETE' in stdout
    assert_gone(kids)
    n = assert_indexed(out / 'bag')
    s = json.loads((out / 'summary.json').read_text())
    assert s['complete'] is False
    assert 'the recorder was killed by SIGKILL' in s['problems']
    assert sum(s['topics'].values()) == n


def test_a_started_process_dies_with_its_launcher(tmp_path):
    """die_with_parent: a launcher killed by SIGKILL takes its child along (the child gets
    SIGTERM from the kernel), though the child runs in a session of its own."""
    launcher = subprocess.Popen([sys.executable, '-c', (
        'import subprocess, sys, time\n'
        'from alignment_ros.signals import die_with_parent\n'
        'c = subprocess.Popen(["sleep", "60"], start_new_session=True, preexec_fn=die_with_parent())\n'
        'print(c.pid, flush=True)\n'
        'time.sleep(60)\n')], stdout=subprocess.PIPE, text=True)
    child = int(launcher.stdout.readline())
    assert alive(child) and os.getpgid(child) == child
    launcher.kill()
    launcher.wait()
    deadline = time.monotonic() + 5
    while alive(child):
        assert time.monotonic() < deadline, 'the child outlived its launcher'
        time.sleep(0.05)
