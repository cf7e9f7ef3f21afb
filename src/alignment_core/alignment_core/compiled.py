"""The project's compiler for hot numerical kernels: numba's nopython mode, cached on disk.

A kernel is written once, as plain Python on floats and numpy arrays; `kernel` compiles it.
Compiled and interpreted runs give the same numbers bit for bit (tests/test_compiled.py):
  - no fast-math, so LLVM neither reorders nor fuses (no FMA) the float operations;
  - numba's np.dot and np.linalg.solve call the BLAS and LAPACK routines numpy calls (gemm,
    gemv, dot, gesv), from scipy's build of OpenBLAS rather than numpy's: with the CPU kernels
    scripts/env.sh pins both round alike (the kernel tests and bench/same_numbers.py check it;
    an upgrade of numpy or scipy must be checked again);
  - math.sin, cos, atan2 and sqrt are the C library's, as in Python.
A kernel uses no numpy reduction (sum, mean, norm, ...): numpy sums pairwise, numba in order,
and the two round differently; a sum is written as the loop the interpreted code also runs.
The interpreted form stays reachable as `f.py_func` (and everywhere under NUMBA_DISABLE_JIT=1).
An array a kernel returns is built as numba builds it, with its Python type read from the
function's environment rather than unpickled on each call (compiled_boxing.py).

numba itself is imported on the first call of any kernel (or by `activate`), not with the
package: a process that never runs one (a bag tool, a node started on its own that runs none)
does not pay its import (~0.2 s). Then every `Kernel` becomes a numba dispatcher, and the module
globals that named one are rebound to it, so a call costs what a dispatcher's costs. Activating
also loads numba's typing and target registries (~0.15 s), which the first kernel call would
otherwise load. The graph's launcher activates before it forks its nodes: the slave's and the
filter's kernels then find numba imported and its registries loaded (the first kernel call in a
forked process 0.2 s of CPU without them, 0.02 s with).

The machine code is cached on disk: the first process compiles (about 35 s for the kernels a
`deck`, `deck_paper` and `catapult` run call), the next ones load it. numba checks only a
kernel's own source file for changes, not the files of the kernels it calls, so the cache lives
in a directory named after a digest of this package's sources: any change to them compiles
afresh. A process loads (or compiles) a kernel on its first call: the filter node on its first
message (about 0.2 s with the cache, once)."""
from __future__ import annotations

import hashlib
import os
import shutil
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar, cast

import numpy as np

F = TypeVar('F', bound=Callable[..., Any])

PACKAGE = Path(__file__).resolve().parent
CACHE_PREFIX = 'kernels-'
STALE_S = 3600.0
"""An older kernels-* directory is removed once unused this long (a process still running the
sources of before an edit may use it)."""


def _source_digest() -> str:
    """sha256 (12 hex digits) of every .py file of the package, by relative path."""
    h = hashlib.sha256()
    for path in sorted(PACKAGE.rglob('*.py')):
        h.update(str(path.relative_to(PACKAGE)).encode() + b'\0' + path.read_bytes() + b'\0')
    return h.hexdigest()[:12]


def cache_dir() -> Path:
    """Where the kernels' machine code is cached: NUMBA_CACHE_DIR if the user set it, else
    __pycache__/kernels-<digest> in this package (or in ~/.cache/alignment_core where the
    package is not writable); other kernels-* directories there unused for STALE_S are removed."""
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
                if old.name != CACHE_PREFIX + digest and time.time() - old.stat().st_mtime > STALE_S:
                    shutil.rmtree(old, ignore_errors=True)
            path = root / (CACHE_PREFIX + digest)
            path.mkdir(exist_ok=True)
            os.utime(path)
            return path
        except OSError:
            continue
    raise OSError('no writable directory for the compiled kernels: set NUMBA_CACHE_DIR')


FLOAT64 = np.dtype(np.float64)
"""numpy's native float64 descriptor. An array's dtype is tested against it with `is`, then ==: an
array a cached kernel made carries a descriptor numba unpickled from its cache, equal to this one
but another object (identity is the cheaper test, equality the one that decides; a byte-swapped
float64 is not equal and is converted)."""


_NDARRAY = np.ndarray


def is_float64_vector(a: Any) -> bool:
    """a is a 1-D float64 numpy array: the operand a compiled check takes as it is."""
    return type(a) is _NDARRAY and (a.dtype is FLOAT64 or a.dtype == FLOAT64) and a.ndim == 1


def as_float64(a: Any) -> np.ndarray:
    """a as a float64 numpy array for a kernel (no copy when it is one already)."""
    return a if type(a) is _NDARRAY and (a.dtype is FLOAT64 or a.dtype == FLOAT64) else np.asarray(a, dtype=np.float64)


def as_float(a: Any) -> np.ndarray:
    """a as a float64 or float32 numpy array for a kernel, a float32 one kept in its precision
    (a filter's single-precision covariance); anything else as float64."""
    return a if type(a) is _NDARRAY and a.dtype.char in 'fd' else np.asarray(a, dtype=np.float64)


class Kernel:
    """A kernel before numba is imported: calling it (or reading a dispatcher attribute such as
    `signatures`) makes every kernel's dispatcher (`activate`)."""

    def __init__(self, fun: Callable[..., Any]) -> None:
        self.py_func = fun
        self.dispatcher: Any = None

    def __call__(self, *args: Any) -> Any:
        if not _active:
            activate()
        return self.dispatcher(*args)

    def __getattr__(self, name: str) -> Any:
        if name == 'dispatcher':
            raise AttributeError(name)
        if not _active:
            activate()
        return getattr(self.dispatcher, name)


KERNELS: list[Kernel] = []
"""Every kernel made so far."""
_ON_NUMBA: list[Callable[[], None]] = []
_active = False
_lock = threading.RLock()


def kernel(fun: F) -> F:
    """fun compiled in nopython mode on its first call (Python's error model: a float division
    by zero raises ZeroDivisionError as it does interpreted), cached on disk."""
    with _lock:
        k = Kernel(fun)
        KERNELS.append(k)
        if _active:
            _make_dispatcher(k)
            return cast(F, k.dispatcher)
        return cast(F, k)


def on_numba(call: Callable[[], None]) -> Callable[[], None]:
    """Register `call` to run once numba is imported, before any kernel compiles (a module's
    numba extensions: the overloads its kernels call)."""
    with _lock:
        _ON_NUMBA.append(call)
        if _active:
            call()
    return call


def _make_dispatcher(k: Kernel) -> None:
    import numba
    k.dispatcher = numba.njit(cache=True, nogil=True, error_model='python')(k.py_func)


def activate() -> None:
    """Import numba, register the project's array boxer (compiled_boxing.py), load numba's typing
    and target registries, make every kernel's dispatcher and rebind the module globals that name
    a Kernel to its dispatcher (a kernel calling another must find a dispatcher)."""
    global _active
    with _lock:             # one thread activates; the others wait for every dispatcher
        if _active:
            return
        import numba
        from numba.core.compiler_lock import global_compiler_lock
        from numba.core.registry import cpu_target

        from alignment_core import compiled_boxing
        numba.config.CACHE_DIR = str(cache_dir())   # type: ignore[attr-defined]  # read when a dispatcher is made
        compiled_boxing.install()
        with global_compiler_lock:                  # as numba itself refreshes (its typing context too)
            cpu_target.target_context.refresh()
        for call in _ON_NUMBA:
            call()
        for k in KERNELS:
            if k.dispatcher is None:
                _make_dispatcher(k)
        for module in list(sys.modules.values()):
            names = getattr(module, '__dict__', None)
            if not isinstance(names, dict):
                continue
            for name, value in list(names.items()):
                if type(value) is Kernel:
                    names[name] = value.dispatcher
        _active = True
