"""Stale Fast DDS shared-memory files: those of a killed participant are removed, those of a live
one (locked, mapped) and anything else are kept."""
from __future__ import annotations

import fcntl
import gc
import mmap
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from alignment_ros import domain, shm_cleanup

OLD = time.time() - 3600.0


def _touch(path: Path, mtime: float = OLD, size: int = 0) -> Path:
    path.write_bytes(b'\0' * size)
    os.utime(path, (mtime, mtime))
    return path


def test_only_unlocked_unmapped_old_groups_are_removed(tmp_path: Path):
    stale = [_touch(tmp_path / n) for n in
             ('fastrtps_port12345', 'fastrtps_port12345_el', 'sem.fastrtps_port12345_mutex',
              'fastrtps_0123456789abcdef', 'fastrtps_0123456789abcdef_el',
              'fastrtps_port23456', 'sem.fastrtps_port23456_mutex')]      # its lock file already gone
    locked = [_touch(tmp_path / n) for n in ('fastrtps_port34567', 'fastrtps_port34567_sl')]
    mapped = _touch(tmp_path / 'fastrtps_fedcba9876543210', size=4096)   # no lock file, but in use
    young = [_touch(tmp_path / n, mtime=time.time()) for n in ('fastrtps_port45678', 'fastrtps_port45678_el')]
    other = [_touch(tmp_path / n) for n in ('lttng-ust-wait-6', 'fastrtps_notasegment', 'sem.other')]
    holder = open(locked[1], 'rb')
    fcntl.flock(holder, fcntl.LOCK_SH)              # a shared listener of the port, alive
    with open(mapped, 'r+b') as f, mmap.mmap(f.fileno(), 4096):
        removed = shm_cleanup.clean_stale(tmp_path)
    holder.close()
    assert sorted(removed) == sorted(stale)
    for p in [*locked, mapped, *young, *other]:
        assert p.exists(), p.name
    assert shm_cleanup.clean_stale(tmp_path / 'missing') == []


PARTICIPANT = '''
import rclpy
from std_msgs.msg import UInt64
rclpy.init()
node = rclpy.create_node('shm_probe')
pub = node.create_publisher(UInt64, '/shm_probe', 10)
print('ready', flush=True)
while True:
    pub.publish(UInt64())
    rclpy.spin_once(node, timeout_sec=0.1)
'''


def _participant() -> tuple[subprocess.Popen, int]:
    dom = domain.claim()
    p = subprocess.Popen([sys.executable, '-c', PARTICIPANT], stdout=subprocess.PIPE, text=True,
                         env=dict(os.environ, ROS_DOMAIN_ID=str(dom)))
    assert p.stdout.readline().strip() == 'ready'
    return p, dom


def _shm_files(pid: int) -> set[Path]:
    """The Fast DDS files a process maps or holds open (its segment, its ports, their locks)."""
    names = {line.split(None, 5)[-1].strip() for line in Path(f'/proc/{pid}/maps').read_text().splitlines()
             if '/dev/shm/' in line}
    for fd in Path(f'/proc/{pid}/fd').iterdir():
        try:
            names.add(os.readlink(fd))
        except OSError:
            pass
    return {Path(n) for n in names if n.startswith('/dev/shm/') and 'fastrtps' in n}


def _holders(paths: list[Path]) -> str:
    """Which processes map the paths (for a failure's message: who kept a dead one's file)."""
    out = []
    for proc in Path('/proc').iterdir():
        try:
            maps = (proc / 'maps').read_text() if proc.name.isdigit() else ''
            who = (proc / 'cmdline').read_bytes().replace(b'\0', b' ').decode(errors='replace')[:120]
        except OSError:
            continue
        hit = [p.name for p in paths if str(p) in maps]
        if hit:
            out.append(f'pid {proc.name} ({"this test" if int(proc.name) == os.getpid() else who}) maps {hit}')
    return f'kept {[p.name for p in paths]}; ' + ('; '.join(out) or 'mapped by none (locked?)')


def test_files_of_a_killed_participant_go_those_of_a_live_one_stay():
    # a port's file keeps its name across owners: a participant that once wrote to port N keeps
    # N's file mapped, and a later owner of N (the killed one here) shares that file; such a
    # file is in use and stays. The suite's own participants awaiting collection go first.
    gc.collect()
    dead, d1 = _participant()
    live, d2 = _participant()
    try:
        time.sleep(1.0)
        dead_files, live_files = _shm_files(dead.pid), _shm_files(live.pid)
        assert any(p.name.endswith('_el') for p in dead_files), dead_files
        dead.send_signal(signal.SIGKILL)
        dead.wait()
        left = {p for p in dead_files if p.exists()}
        used = shm_cleanup.mapped_files()
        in_use = {shm_cleanup.group_of(p.name) for p in left if str(p) in used}
        stale = {p for p in left if shm_cleanup.group_of(p.name) not in in_use}
        # its own segment, which no other process maps, at least
        assert any(not p.name.startswith('fastrtps_port') for p in stale), (left, _holders(sorted(left)))
        groups = {shm_cleanup.group_of(p.name) for p in left | live_files}
        for p in shm_cleanup.SHM_DIR.iterdir():       # old, both: only locks and maps tell them apart
            if shm_cleanup.group_of(p.name) in groups:
                os.utime(p, (OLD, OLD))
        shm_cleanup.clean_stale()
        kept = [p for p in stale if p.exists()]
        assert not kept, _holders(kept)
        assert all(p.exists() for p in left - stale), _holders(sorted(left - stale))
        assert all(p.exists() for p in live_files), live_files
        assert live.poll() is None
    finally:
        for p in (dead, live):
            if p.poll() is None:
                p.kill()
                p.wait()
        domain.release(d1)
        domain.release(d2)
