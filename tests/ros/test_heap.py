"""alignment_ros.heap: a large array freed below a small live allocation goes back to the OS."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

PROBE = r"""
import ctypes, ctypes.util, sys
import numpy as np
from alignment_ros import heap
if sys.argv[1] == 'mapped':
    assert heap.map_large_allocations()
libc = ctypes.CDLL(ctypes.util.find_library('c'))
libc.malloc.restype = ctypes.c_void_p

def rss_mib():
    for line in open('/proc/self/status'):
        if line.startswith('VmRSS:'):
            return int(line.split()[1]) / 1024

a = np.ones(1 << 20)          # 8 MiB: above glibc's default threshold, a mapping of its own
del a                         # ... whose release raises the default threshold to its size
libc.malloc_trim(0)           # free heap left by start-up (or by a, if the threshold was already above it) goes back
base = rss_mib()
pins = []
for _ in range(8):
    b = np.ones(1 << 20)      # 8 MiB again: from the heap unless the threshold is fixed
    pins.append(libc.malloc(64))   # a small live allocation after it
    del b
print(rss_mib() - base)
"""


def _growth_mib(mode: str) -> float:
    # glibc's defaults: a MALLOC_TRIM_THRESHOLD_ (Dask's nanny exports one) or a tunable also fixes the threshold
    env = {k: v for k, v in os.environ.items() if not k.startswith('MALLOC_') and k != 'GLIBC_TUNABLES'}
    res = subprocess.run([sys.executable, '-c', PROBE, mode], capture_output=True, text=True, timeout=60, env=env)
    assert res.returncode == 0, res.stderr
    return float(res.stdout)


@pytest.mark.skipif(not sys.platform.startswith('linux'), reason='glibc malloc')
def test_a_freed_large_array_leaves_no_resident_memory_once_large_allocations_are_mapped():
    mapped, default = _growth_mib('mapped'), _growth_mib('default')
    assert mapped < 2.0, f'{mapped:.2f} MiB still resident with the threshold fixed ({default:.2f} MiB without)'
    # the probe shows what the fixed threshold prevents
    assert default > 6.0, f'{default:.2f} MiB resident without the fixed threshold ({mapped:.2f} MiB with it)'
