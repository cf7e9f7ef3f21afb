"""Freed heap back to the operating system. glibc's malloc keeps what a process freed for reuse;
a buffer that peaks and drains (the recorder's reorder buffer behind a lagging stream) then
leaves its high-water mark in the resident set, and each higher peak raises it for the rest of
the run. malloc_trim(0) returns the free pages; elsewhere than glibc it is a no-op.

Large transient arrays (the spectral ship's knot blocks: ~10 arrays of 4.6 MB at a time) are
the other way a long run's resident set creeps: glibc serves an allocation above its mmap
threshold with mmap, but raises the threshold to the size of each such block it frees, so the
next ones come from the heap, where small objects allocated meanwhile pin their pages once they
are freed. :func:`map_large_allocations` fixes the threshold: every large array is its own
mapping, returned whole when it is freed."""
from __future__ import annotations

import ctypes
import ctypes.util

M_MMAP_THRESHOLD = -3        # mallopt parameter (malloc.h)
LARGE_ALLOCATION_B = 256 * 1024

_libc_name = ctypes.util.find_library('c')
try:
    _libc = ctypes.CDLL(_libc_name) if _libc_name else None
    _trim = _libc.malloc_trim if _libc is not None else None
    _mallopt = _libc.mallopt if _libc is not None else None
except (OSError, AttributeError):
    _trim = _mallopt = None


def release_free_heap() -> bool:
    """True if the allocator gave memory back."""
    return bool(_trim(0)) if _trim is not None else False


def map_large_allocations(threshold_b: int = LARGE_ALLOCATION_B) -> bool:
    """Serve every allocation of at least threshold_b bytes with its own mapping for the rest of
    the process (a fixed M_MMAP_THRESHOLD); True if the allocator took it."""
    return bool(_mallopt(M_MMAP_THRESHOLD, threshold_b)) if _mallopt is not None else False
