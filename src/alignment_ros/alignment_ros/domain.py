"""ROS_DOMAIN_ID allocation: every run of this project on a machine gets a domain of its own.

A run claims a domain by holding an exclusive lock on /tmp/alignment_ros_domains/<id>.lock for
its lifetime (released automatically when the process exits, even when killed), so parallel
graph runs, replays and tests never hear each other. Domains 1..101 (valid for Fast DDS with
default ports on Linux) are tried in a random order.
"""
from __future__ import annotations

import fcntl
import os
import random
from pathlib import Path

LOCK_DIR = Path(os.environ.get('ALIGN_DOMAIN_LOCKS', '/tmp/alignment_ros_domains'))
DOMAINS = tuple(range(1, 102))

_held: dict[int, object] = {}


def claim(preferred: int | None = None) -> int:
    """Lock and return a free domain id (the preferred one if free); it stays claimed until
    `release` or the end of the process."""
    LOCK_DIR.mkdir(parents=True, exist_ok=True)
    order = list(DOMAINS)
    random.Random(os.getpid() ^ int.from_bytes(os.urandom(4), 'little')).shuffle(order)
    if preferred is not None:
        order.insert(0, preferred)
    for dom in order:
        if dom in _held:
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
        return dom
    raise RuntimeError('no free ROS domain id in 1..101')


def release(dom: int) -> None:
    f = _held.pop(dom, None)
    if f is not None:
        f.close()
