"""Freed heap back to the operating system. glibc's malloc keeps what a process freed for reuse;
a buffer that peaks and drains (the recorder's reorder buffer behind a lagging stream) then
leaves its high-water mark in the resident set, and each higher peak raises it for the rest of
the run. malloc_trim(0) returns the free pages; elsewhere than glibc it is a no-op."""
from __future__ import annotations

import ctypes
import ctypes.util

_libc_name = ctypes.util.find_library('c')
try:
    _trim = ctypes.CDLL(_libc_name).malloc_trim if _libc_name else None
except (OSError, AttributeError):
    _trim = None


def release_free_heap() -> bool:
    """True if the allocator gave memory back."""
    return bool(_trim(0)) if _trim is not None else False
