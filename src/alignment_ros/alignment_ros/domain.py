"""ROS_DOMAIN_ID allocation: every run of this project on a machine gets a domain of its own.

A run claims a domain by holding an exclusive lock on /tmp/alignment_ros_domains/<id>.lock for
its lifetime (released automatically when the process exits, even when killed), so parallel
graph runs, replays and tests never hear each other. A launcher hands the lock's descriptor to
the processes it starts (:func:`lock_fd`, ``Popen(pass_fds=...)``): the lock is one open file
shared by all of them, so the domain stays claimed until the last process of the run is gone.
Which domain (`for_run`): the one asked for (--domain-id), else an exported ROS_DOMAIN_ID, else
a free one of 1..101 (valid for Fast DDS with default ports on Linux), tried in a random order,
those this process has released last and the longest released first.

A participant of the process can outlive the domain's release (rclpy keeps it, after shutdown,
while a node of it exists) and would meet the domain's next user. So `release` lets a domain go
only once no participant made since its claim is left in the process (each maps a Fast DDS
segment of its own); until then the lock is kept, and a later `claim` or `release` lets it go.
"""
from __future__ import annotations

import fcntl
import gc
import os
import random
import re
import time
from pathlib import Path
from typing import TextIO

LOCK_DIR = Path(os.environ.get('ALIGN_DOMAIN_LOCKS', '/tmp/alignment_ros_domains'))
DOMAINS = tuple(range(1, 102))
MAX_DOMAIN = 232    # rmw's limit on any platform (Fast DDS port arithmetic)

_held: dict[int, TextIO] = {}
_released: dict[int, float] = {}      # domain -> when this process released it (monotonic s)
_segments_at_claim: dict[int, frozenset[str]] = {}
_deferred: dict[int, tuple[TextIO, frozenset[str]]] = {}   # released while a newer participant lived


def _participant_segments() -> frozenset[str]:
    """The Fast DDS segments this process maps: one per live participant (ports are shared)."""
    try:
        lines = Path('/proc/self/maps').read_text().splitlines()
    except OSError:
        return frozenset()
    names = (line.split(None, 5)[5] for line in lines if line.count(' ') >= 5 and '/dev/shm/fastrtps_' in line)
    return frozenset(n.strip() for n in names if not n.strip().startswith('/dev/shm/fastrtps_port'))


def _let_go(dom: int, f: TextIO, at_claim: frozenset[str]) -> bool:
    """Unlock `dom` if no participant made since its claim is left; True if it was."""
    if _participant_segments() - at_claim:
        _deferred[dom] = (f, at_claim)
        return False
    _deferred.pop(dom, None)
    f.close()
    _released[dom] = time.monotonic()
    return True


def claim(preferred: int | None = None) -> int:
    """Lock and return a free domain id (the preferred one if free); it stays claimed until
    `release` or the end of the process."""
    LOCK_DIR.mkdir(parents=True, exist_ok=True)
    for dom, (f, at_claim) in list(_deferred.items()):
        _let_go(dom, f, at_claim)
    order = list(DOMAINS)
    random.Random(os.getpid() ^ int.from_bytes(os.urandom(4), 'little')).shuffle(order)
    order.sort(key=lambda d: (d in _released, _released.get(d, 0.0)))
    if preferred is not None:
        order.insert(0, preferred)
    for dom in order:
        if dom in _held or dom in _deferred:
            if dom == preferred:
                raise RuntimeError(f'ROS domain {dom} is already claimed by this process')
            continue
        f = open(LOCK_DIR / f'{dom}.lock', 'w')
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            f.close()
            if preferred is not None and dom == preferred:
                raise RuntimeError(f'ROS domain {dom} is in use by another run of this project') from None
            continue
        _held[dom] = f
        _segments_at_claim[dom] = _participant_segments()
        return dom
    raise RuntimeError('no free ROS domain id in 1..101')


def lock_fd(dom: int) -> int:
    """The descriptor of this process's lock on `dom` (for children to inherit); KeyError if
    this process does not hold it."""
    return _held[dom].fileno()


def release(dom: int) -> None:
    """Give the domain back, once no participant made since its claim is left (module
    docstring); claimed again by this process last."""
    f = _held.pop(dom, None)
    if f is not None:
        gc.collect()                    # a node in a reference cycle keeps its participant
        _let_go(dom, f, _segments_at_claim.pop(dom, frozenset()))


def from_environment() -> int | None:
    """ROS_DOMAIN_ID as rcl reads it (unset or empty: none); a value rcl would refuse is an error."""
    text = os.environ.get('ROS_DOMAIN_ID', '').strip()
    if not text:
        return None
    if not re.fullmatch('[0-9]+', text) or int(text) > MAX_DOMAIN:
        raise RuntimeError(f'ROS_DOMAIN_ID={text!r} is not a domain id (an integer in 0..{MAX_DOMAIN})')
    return int(text)


def for_run(given: int | None) -> int:
    """The domain of a run, claimed: `given` (--domain-id) if not None, else ROS_DOMAIN_ID if
    exported, else a free one. A domain asked for that another run of this project holds is
    refused (two graphs on one domain would exchange messages)."""
    wanted = given if given is not None else from_environment()
    try:
        return claim(wanted)
    except RuntimeError as e:
        if given is None and wanted is not None:
            raise RuntimeError(f'{e} (ROS_DOMAIN_ID is exported: unset it to get a free domain)') from None
        raise
