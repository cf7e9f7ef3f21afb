"""alignment_core.compiled: where the kernels' machine code is cached, and how they compile."""
from __future__ import annotations

import os
import pickle
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from alignment_core import compiled


def _package(tmp_path: Path) -> Path:
    pkg = tmp_path / 'pkg'
    (pkg / 'sub').mkdir(parents=True)
    (pkg / 'a.py').write_text('x = 1\n')
    (pkg / 'sub' / 'b.py').write_text('y = 2\n')
    return pkg


def test_the_digest_changes_with_any_source_file_and_only_with_them(tmp_path, monkeypatch):
    pkg = _package(tmp_path)
    monkeypatch.setattr(compiled, 'PACKAGE', pkg)
    d0 = compiled._source_digest()
    (pkg / 'notes.txt').write_text('not code')
    assert compiled._source_digest() == d0
    (pkg / 'sub' / 'b.py').write_text('y = 3\n')            # a callee's file, not the kernel's
    d1 = compiled._source_digest()
    assert d1 != d0
    (pkg / 'sub' / 'b.py').write_text('y = 2\n')
    assert compiled._source_digest() == d0


def test_the_cache_directory_is_named_by_the_digest_and_stale_ones_are_removed(tmp_path, monkeypatch):
    pkg = _package(tmp_path)
    monkeypatch.setattr(compiled, 'PACKAGE', pkg)
    monkeypatch.delenv('NUMBA_CACHE_DIR', raising=False)
    first = compiled.cache_dir()
    assert first.is_dir() and first.parent == pkg / '__pycache__' and first.name.startswith('kernels-')
    (first / 'k.nbi').write_bytes(b'old')
    (pkg / 'a.py').write_text('x = 2\n')
    second = compiled.cache_dir()
    assert second != first and second.is_dir()
    assert first.exists()                                  # recent: a running process may use it
    old = time.time() - compiled.STALE_S - 60.0
    os.utime(first, (old, old))
    assert compiled.cache_dir() == second                  # unchanged sources: the same place
    assert not first.exists()


def test_a_user_cache_directory_wins(tmp_path, monkeypatch):
    monkeypatch.setenv('NUMBA_CACHE_DIR', str(tmp_path / 'mine'))
    assert compiled.cache_dir() == tmp_path / 'mine'


def test_kernels_are_compiled_without_fast_math_and_with_pythons_error_model():
    """Fast math would let LLVM reorder and fuse float operations (the numbers would move);
    numpy's error model would turn a division by zero into inf instead of the exception the
    interpreted code raises."""
    def half(a, b):
        return a / b
    k = compiled.kernel(half)
    assert not k.targetoptions.get('fastmath', False)
    assert k.targetoptions['error_model'] == 'python'
    assert k(1.0, 4.0) == half(1.0, 4.0) == 0.25
    for f in (k, half):
        try:
            f(1.0, 0.0)
        except ZeroDivisionError:
            continue
        raise AssertionError('no ZeroDivisionError')


def _printed(code: str) -> list[str]:
    """The words a fresh Python process running `code` prints."""
    return subprocess.run([sys.executable, '-c', code], capture_output=True, text=True, check=True,
                          env=dict(os.environ)).stdout.split()


def test_numba_is_imported_on_the_first_kernel_call_and_the_kernels_become_dispatchers():
    """Importing the engine (what the graph's launcher and every node do) imports no numba; the
    first call makes every kernel a dispatcher and rebinds the names, also in other modules."""
    code = ('import sys\n'
            'import alignment_core.estimation.engine\n'
            'from alignment_core.estimation.filters import kalman_kernels as k\n'
            'from alignment_core.navigation import strapdown as s\n'
            'before = "numba" in sys.modules, type(k.update).__name__, type(s.quat_mul_k).__name__\n'
            'import numpy as np\n'
            'k.predict(np.zeros(3), np.eye(3), np.eye(3), np.eye(3))\n'
            'print(*before, "numba" in sys.modules, type(k.update).__name__, type(s.quat_mul_k).__name__)\n')
    assert _printed(code) == ['False', 'Kernel', 'Kernel', 'True', 'CPUDispatcher', 'CPUDispatcher']


def test_a_process_forked_after_activating_finds_numba_s_registries_loaded():
    """What the graph's launcher relies on: activate() loads numba's typing and target registries
    (the linalg and array implementations the kernels use), which importing numba does not, so a
    node forked after it does not load them again at its first kernel call."""
    code = ('import os, sys\n'
            'import numba\n'
            'from numba.core.registry import cpu_target\n'
            'before = "numba.np.linalg" in sys.modules, len(cpu_target.target_context._registries)\n'
            'from alignment_core import compiled\n'
            'compiled.activate()\n'
            'pid = os.fork()\n'
            'if pid == 0:\n'
            '    print(*before, "numba.np.linalg" in sys.modules, len(cpu_target.target_context._registries) > 0)\n'
            '    import numpy as np\n'
            '    from alignment_core.estimation.filters.kalman import KalmanFilter\n'
            '    kf = KalmanFilter(np.zeros(3), np.eye(3))\n'
            '    kf.predict(np.eye(3), np.eye(3))\n'
            '    print(kf.P[0, 0])\n'
            '    sys.stdout.flush()\n'
            '    os._exit(0)\n'
            'os.waitpid(pid, 0)\n')
    assert _printed(code) == ['False', '0', 'True', 'True', '2.0']       # and its kernels run: P = I I I + I


def test_compiled_and_interpreted_agree_on_a_kernel_with_blas():
    def gram(a):
        return np.dot(a.T, a) + np.dot(a, a.T)
    k = compiled.kernel(gram)
    a = np.random.default_rng(0).standard_normal((7, 7))
    assert np.array_equal(k(a), gram(a))


def test_no_kernel_uses_a_numpy_reduction():
    """numpy sums pairwise and numba in order: a reduction in a kernel would round differently
    from its interpreted form (compiled.py)."""
    import inspect

    import alignment_core.estimation.engine  # noqa: F401  (imports every kernel of the engine)
    import alignment_core.pipeline  # noqa: F401  (and of the simulator: the landing gear's)
    names = {k.py_func.__qualname__ for k in compiled.KERNELS}
    assert len(names) >= 15 and {'step_samples', 'gust_series', 'spot_slope'} <= names
    for k in compiled.KERNELS:
        src = inspect.getsource(k.py_func)
        for word in ('.sum(', 'np.sum', '.mean(', 'np.mean', 'norm(', '.prod(', 'np.add.reduce'):
            assert word not in src, f'{k.py_func.__qualname__} uses {word}'


def test_an_array_with_an_unpickled_float64_descriptor_is_taken_as_float64():
    """A cached kernel's new arrays carry a float64 descriptor unpickled from the cache: equal to
    numpy's, another object. as_float64 and the filter's conversions take them as they are (no
    copy), as they take numpy's own; a byte-swapped float64 is converted."""
    from alignment_core.estimation.filters.base import as_dtype
    from alignment_core.navigation.history_kernels import slave_between_k

    unpickled = pickle.loads(pickle.dumps(compiled.FLOAT64))
    assert unpickled == compiled.FLOAT64 and unpickled is not compiled.FLOAT64
    a = np.arange(3.0).view(unpickled)
    assert compiled.as_float64(a) is a and as_dtype(a, compiled.FLOAT64) is a
    q = np.array([0.0, 0.0, 0.0, 1.0])
    made = slave_between_k(q, q, np.zeros(3), np.ones(3), 0.5, np.eye(2))[2]
    assert compiled.as_float64(made) is made
    swapped = np.arange(3.0).astype('>f8')
    assert compiled.as_float64(swapped) is not swapped and compiled.as_float64(swapped).dtype == compiled.FLOAT64
