"""The project's compiler for hot numerical kernels: numba's nopython mode, cached on disk.

A kernel is written once, as plain Python on floats and numpy arrays; `kernel` compiles it.
Compiled and interpreted runs give the same numbers bit for bit (tests/test_compiled.py):
  - no fast-math, so LLVM neither reorders nor fuses (no FMA) the float operations;
  - numba's np.dot and np.linalg.solve call the same BLAS and LAPACK routines as numpy
    (OpenBLAS, with the kernels scripts/env.sh pins);
  - math.sin, cos, atan2 and sqrt are the C library's, as in Python.
A kernel uses no numpy reduction (sum, mean, norm, ...): numpy sums pairwise, numba in order,
and the two round differently; a sum is written as the loop the interpreted code also runs.
The interpreted form stays reachable as `f.py_func` (and everywhere under NUMBA_DISABLE_JIT=1).

The machine code is cached on disk: the first process compiles (about 20 s for all kernels),
the next ones load it. numba checks only a kernel's own source file for changes, not the files
of the kernels it calls, so the cache lives in a directory named after a digest of this
package's sources: any change to them compiles afresh. `warm_up()` compiles (or loads) every
kernel in one go: the filter node calls it once its subscriptions exist (while DDS matches
them), so it does not compile on its first message."""
from __future__ import annotations

import hashlib
import os
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import numba

F = TypeVar('F', bound=Callable[..., Any])

PACKAGE = Path(__file__).resolve().parent
CACHE_PREFIX = 'kernels-'


def _source_digest() -> str:
    """sha256 (12 hex digits) of every .py file of the package, by relative path."""
    h = hashlib.sha256()
    for path in sorted(PACKAGE.rglob('*.py')):
        h.update(str(path.relative_to(PACKAGE)).encode() + b'\0' + path.read_bytes() + b'\0')
    return h.hexdigest()[:12]


def cache_dir() -> Path:
    """Where the kernels' machine code is cached: NUMBA_CACHE_DIR if the user set it, else
    __pycache__/kernels-<digest> in this package (or in ~/.cache/alignment_core where the
    package is not writable); older kernels-* directories there are removed."""
    given = os.environ.get('NUMBA_CACHE_DIR')
    if given:
        return Path(given)
    digest = _source_digest()
    for root in (PACKAGE / '__pycache__', Path.home() / '.cache' / 'alignment_core'):
        try:
            root.mkdir(parents=True, exist_ok=True)
            if not os.access(root, os.W_OK):
                continue
            for old in root.glob(CACHE_PREFIX + '*'):
                if old.name != CACHE_PREFIX + digest:
                    shutil.rmtree(old, ignore_errors=True)
            path = root / (CACHE_PREFIX + digest)
            path.mkdir(exist_ok=True)
            return path
        except OSError:
            continue
    raise OSError('no writable directory for the compiled kernels: set NUMBA_CACHE_DIR')


numba.config.CACHE_DIR = str(cache_dir())   # type: ignore[attr-defined]  # read when a kernel is made

_WARM_UPS: list[Callable[[], None]] = []
KERNELS: list[Any] = []
"""Every kernel made so far (numba Dispatchers; the interpreted function is `.py_func`)."""


def kernel(fun: F) -> F:
    """fun compiled in nopython mode (Python's error model: a float division by zero raises
    ZeroDivisionError as it does interpreted), cached on disk."""
    k = numba.njit(cache=True, nogil=True)(fun)
    KERNELS.append(k)
    return k   # type: ignore[return-value]  # a Dispatcher calls as fun


def on_warm_up(call: Callable[[], None]) -> Callable[[], None]:
    """Register `call` (it runs the module's kernels once on typical arguments) for warm_up()."""
    _WARM_UPS.append(call)
    return call


def warm_up() -> None:
    """Compile or load every registered kernel now (each module registers on import)."""
    for call in _WARM_UPS:
        call()
