"""alignment_core.compiled_boxing: an array a kernel returns is the array numba's own boxer builds,
without its per-call unpickling, and the boxer is installed only under the numba it was written for."""
from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pytest

from alignment_core import compiled, compiled_boxing

ROOT = Path(__file__).resolve().parents[1]


def _numba():
    compiled.activate()
    import numba
    from numba.core import boxing, pythonapi, types
    return numba, boxing, pythonapi._boxers.functions, types.Array


def _returns(a, b):
    """New arrays of each layout and several dtypes, views of an argument (b read-only), the
    arguments themselves, empty arrays."""
    c = a * 2.0
    return (c, c.T, np.asfortranarray(c), a[1], a, b, (a[0, 0] + c)[:0], np.zeros(0, np.float32),
            (a > 1.0), a.astype(np.complex128), np.arange(3), c.reshape(-1)[::2], b[1:])


def _args() -> tuple[np.ndarray, np.ndarray]:
    """_returns' arguments: a (2, 3) and a read-only b (4,)."""
    a, b = np.arange(6.0).reshape(2, 3), np.arange(4.0)
    b.flags.writeable = False
    return a, b


def _compile(boxer, fn=_returns, args=None):
    """fn compiled (not cached, for the types of args, default _args()) with `boxer` registered
    for arrays while it compiles."""
    numba, _, boxers, array = _numba()
    from numba.core.compiler_lock import global_compiler_lock
    with global_compiler_lock:              # no other thread compiles with the swapped boxer
        saved = boxers[array]
        boxers[array] = boxer
        try:
            f = numba.njit(cache=False)(fn)
            f(*(_args() if args is None else args))
        finally:
            boxers[array] = saved
    return f


def test_installed_under_the_pinned_numba():
    numba, _, boxers, array = _numba()
    pin = re.search(r'^numba==(\S+)', (ROOT / 'requirements.txt').read_text(), re.M)
    assert pin is not None and numba.__version__ == pin.group(1) == compiled_boxing.NUMBA_VERSION
    assert boxers[array] is compiled_boxing._box_array
    assert compiled_boxing.install()                          # again: already there


def test_the_arrays_are_numbas_own():
    """Against numba's boxer compiled in the same process: the same type, dtype, shape, strides,
    flags, base and values for every kind of array a kernel returns, including the argument it
    returns as itself and the read-only one it was given."""
    _, boxing, _, _ = _numba()
    ours, theirs = _compile(compiled_boxing._box_array), _compile(boxing.box_array)
    a, b = _args()
    got, want = ours(a, b), theirs(a, b)
    assert len(got) == len(want) == 13
    for g, w in zip(got, want):
        assert type(g) is type(w) is np.ndarray
        assert (g.dtype, g.shape, g.strides) == (w.dtype, w.shape, w.strides)
        assert (g.flags.c_contiguous, g.flags.f_contiguous, g.flags.writeable, g.flags.owndata) == \
            (w.flags.c_contiguous, w.flags.f_contiguous, w.flags.writeable, w.flags.owndata)
        assert type(g.base) is type(w.base)
        np.testing.assert_array_equal(g, w)
    assert got[4] is a and got[5] is b and not got[5].flags.writeable      # arguments come back as themselves
    assert not got[12].flags.writeable                                      # a view of a read-only one is read-only


def test_the_type_is_borrowed_not_taken_or_dropped():
    """The C function only reads the type: many calls leave np.ndarray's reference count as it was
    (a reference dropped per call would free the type; one taken per call would leak)."""
    ours = _compile(compiled_boxing._box_array)
    a, b = _args()
    ours(a, b)
    before = sys.getrefcount(np.ndarray)
    for _ in range(2000):
        ours(a, b)
    assert abs(sys.getrefcount(np.ndarray) - before) < 50


def test_every_array_is_released():
    """The runtime's allocations and frees balance over many calls, the returned arrays dropped
    (a boxer that kept the array's reference would leak its memory on every call)."""
    from numba.core.runtime import _nrt_python, rtsys
    ours = _compile(compiled_boxing._box_array)
    a, b = _args()
    was = _nrt_python.memsys_stats_enabled()
    _nrt_python.memsys_enable_stats()
    try:
        before = rtsys.get_allocation_stats()
        for _ in range(200):
            out = ours(a, b)
            del out
        after = rtsys.get_allocation_stats()
    finally:
        if not was:
            _nrt_python.memsys_disable_stats()
    assert after.alloc - before.alloc >= 200 * 8                       # the new arrays were counted
    assert after.alloc - before.alloc == after.free - before.free
    assert after.mi_alloc - before.mi_alloc == after.mi_free - before.mi_free


class Tagged(np.ndarray):
    """An array subclass with a numba type of its own, whose box_type is this class."""
    __numba_array_subtype_dispatch__ = True


def _register_tagged() -> None:
    """TaggedType (types.Array with box_type Tagged; its views keep the type) as Tagged's numba
    type, registered once."""
    _numba()
    from numba.core import types
    from numba.core.datamodel.models import ArrayModel
    from numba.core.extending import register_model, typeof_impl
    from numba.np import numpy_support
    if hasattr(Tagged, 'numba_type'):
        return

    class TaggedType(types.Array):
        def __init__(self, dtype, ndim, layout, readonly=False, aligned=True):
            super().__init__(dtype, ndim, layout, readonly=readonly, aligned=aligned,
                             name=f'Tagged({dtype}, {ndim}, {layout}, {readonly})')

        def copy(self, dtype=None, ndim=None, layout=None, readonly=None):
            return TaggedType(self.dtype if dtype is None else dtype, self.ndim if ndim is None else ndim,
                              self.layout if layout is None else layout,
                              not self.mutable if readonly is None else readonly)

        @property
        def box_type(self):
            return Tagged

    @typeof_impl.register(Tagged)
    def _typeof(val, c):
        return TaggedType(numpy_support.from_dtype(val.dtype), val.ndim, numpy_support.map_layout(val),
                          readonly=not val.flags.writeable)

    register_model(TaggedType)(ArrayModel)
    Tagged.numba_type = TaggedType


def _reversed(a):
    return a[::-1]


def test_the_python_type_is_the_numba_types_box_type():
    """A view of a Tagged argument is a new array object of type Tagged, from both boxers: the type
    the boxer reads from the environment is the numba type's box_type, not always np.ndarray."""
    _, boxing, _, _ = _numba()
    _register_tagged()
    a = np.arange(4.0).view(Tagged)
    got = {name: _compile(boxer, _reversed, (a,))(a)
           for name, boxer in (('ours', compiled_boxing._box_array), ('numba', boxing.box_array))}
    for r in got.values():
        assert type(r) is Tagged and r is not a and np.shares_memory(r, a)
        np.testing.assert_array_equal(r, [3.0, 2.0, 1.0, 0.0])


@pytest.mark.parametrize('case', ['version', 'foreign boxer'])
def test_not_installed_over_another_numba_or_another_boxer(case, monkeypatch):
    numba, boxing, boxers, array = _numba()
    if case == 'version':
        monkeypatch.setitem(boxers, array, boxing.box_array)
        monkeypatch.setattr(numba, '__version__', '0.69.0')
        expect = boxing.box_array
    else:
        def foreign(typ, val, c):
            return boxing.box_array(typ, val, c)
        monkeypatch.setitem(boxers, array, foreign)
        expect = foreign
    assert compiled_boxing.install() is False
    assert boxers[array] is expect


def test_numbas_pickler_rebuilds_numpys_own_float64_descriptor():
    """A cached kernel's environment (the dtypes of the arrays it returns) is pickled by numba's
    pickler: numpy's native float64 comes back as numpy's own descriptor, any other dtype as numpy
    rebuilds it, and the standard pickler is left as it is."""
    import copyreg
    import pickle

    _numba()
    from numba.core.serialize import dumps
    f8 = np.dtype(np.float64)
    assert pickle.loads(dumps(f8)) is f8
    swapped = pickle.loads(dumps(f8.newbyteorder()))
    assert swapped == f8.newbyteorder() and swapped != f8
    tagged = pickle.loads(dumps(np.dtype(np.float64, metadata={'unit': 'm'})))
    assert tagged is not f8 and tagged.metadata == {'unit': 'm'}
    halves = np.dtype((np.float64, [('lo', '<i4'), ('hi', '<i4')]))      # equal to f8, with fields
    assert pickle.loads(dumps(halves)).fields == halves.fields
    copy = pickle.loads(pickle.dumps(f8))                                  # equal, another object
    assert pickle.loads(dumps(copy)) == f8
    for d in (np.dtype(np.float32), np.dtype(np.int64), np.dtype([('a', 'f8')])):
        assert pickle.loads(dumps(d)) == d
    assert type(f8) not in copyreg.dispatch_table


CACHED_KERNEL = '''
import numpy as np
from alignment_core.compiled import FLOAT64, kernel

@kernel
def doubled(a):
    return a * 2.0

out = doubled(np.arange(3.0))
print(out.dtype is FLOAT64, len(doubled.stats.cache_hits))
'''


def test_an_array_from_a_kernel_loaded_from_the_cache_has_numpys_own_float64(tmp_path):
    """Compiled in one process and loaded from the disk cache in the next, a kernel's new float64
    array carries numpy's own descriptor (as_float64 takes it by its identity test)."""
    import os
    import subprocess
    (tmp_path / 'cached_kernel.py').write_text(CACHED_KERNEL)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / 'cache'))
    env['PYTHONPATH'] = os.pathsep.join(filter(None, [str(tmp_path), env.get('PYTHONPATH')]))
    runs = [subprocess.run([sys.executable, '-c', 'import cached_kernel'], env=env, capture_output=True,
                           text=True, timeout=120, check=True).stdout.split() for _ in range(2)]
    assert runs[0] == ['True', '0']           # compiled here
    assert runs[1][0] == 'True' and runs[1][1] != '0'          # loaded from the cache
