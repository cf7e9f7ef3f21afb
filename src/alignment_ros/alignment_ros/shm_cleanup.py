"""Stale Fast DDS shared-memory files: remove those no live process uses (`fastdds shm clean`).

Fast DDS's shared-memory transport keeps its segments and ports in /dev/shm: a segment
``fastrtps_<16 hex>`` and a port ``fastrtps_port<N>`` (with ``sem.fastrtps_port<N>_mutex``), each
with lock files ``_el`` / ``_sl`` that the owning process holds locked (flock) while it is
alive. A process that is killed (SIGKILL, a crash) leaves them behind; runs that are killed
often fill /dev/shm. A group of files is stale when none of its lock files is locked, no process
maps any of its files and none was touched in the last `MIN_AGE_S` (a participant that is just
starting may not hold its lock yet). That is fastdds shm clean's rule (tools/fastdds/shm/clean.py:
an unlocked lock file means a dead owner) made stricter, and it also covers files whose lock file
is already gone: a port's listener and a segment's owner hold their lock as long as they live,
so files of live runs are never touched.
"""
from __future__ import annotations

import fcntl
import os
import re
import time
from collections.abc import Callable
from pathlib import Path

SHM_DIR = Path('/dev/shm')
MIN_AGE_S = 10.0
_GROUP = re.compile(r'^(?:sem\.)?(fastrtps_(?:port\d{1,5}|[0-9a-z]{16}))(?:_el|_sl|_mutex)?$')


def group_of(name: str) -> str | None:
    """The segment or port a Fast DDS file name belongs to ('fastrtps_port7411' for
    'sem.fastrtps_port7411_mutex'); None for a file that is not Fast DDS's."""
    m = _GROUP.match(name)
    return m.group(1) if m else None


def _groups(shm_dir: Path) -> dict[str, list[Path]]:
    """Fast DDS files by segment or port name."""
    groups: dict[str, list[Path]] = {}
    try:
        names = os.listdir(shm_dir)
    except FileNotFoundError:
        return groups
    for name in names:
        g = group_of(name)
        if g:
            groups.setdefault(g, []).append(shm_dir / name)
    return groups


def _locked(path: Path) -> bool:
    """Whether another process holds a lock on `path` (a lock we can take is released at once)."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        return True
    finally:
        os.close(fd)            # closing releases a lock we got
    return False


def mapped_files(shm_dir: Path = SHM_DIR) -> set[str]:
    """Paths under shm_dir that some process has mapped (/proc/<pid>/maps of every process
    whose maps can be read: those of other users, or outside ptrace's reach, are not seen)."""
    prefix = str(shm_dir).rstrip('/') + '/'
    used: set[str] = set()
    for pid in os.listdir('/proc'):
        if not pid.isdigit():
            continue
        try:
            with open(f'/proc/{pid}/maps') as f:
                for line in f:
                    i = line.find(prefix)
                    if i >= 0:
                        used.add(line[i:].rstrip('\n').removesuffix(' (deleted)'))
        except (FileNotFoundError, ProcessLookupError, PermissionError):   # ended, or not ours
            continue
    return used


def clean_stale(shm_dir: Path = SHM_DIR, min_age_s: float = MIN_AGE_S,
                log: Callable[[str], None] | None = None) -> list[Path]:
    """Remove the stale Fast DDS segment and port files of shm_dir (see the module docstring);
    return the removed paths. With `log`, one line says how many were removed, if any."""
    groups = _groups(shm_dir)
    if not groups:
        return []
    used = mapped_files(shm_dir)
    now = time.time()
    removed: list[Path] = []
    for files in groups.values():
        try:
            newest = max(p.stat().st_mtime for p in files)
        except FileNotFoundError:     # its owner is removing it
            continue
        if now - newest < min_age_s or any(str(p) in used for p in files):
            continue
        if any(_locked(p) for p in files if p.name.endswith(('_el', '_sl'))):
            continue
        for p in files:
            try:
                p.unlink()
                removed.append(p)
            except FileNotFoundError:
                pass
    if removed and log is not None:
        log(f'removed {len(removed)} stale Fast DDS shared-memory files from {shm_dir} '
            f'({len({group_of(p.name) for p in removed})} segments and ports of processes that '
            f'are gone)')
    return removed
