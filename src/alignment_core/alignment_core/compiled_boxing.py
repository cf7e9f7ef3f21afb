"""How a kernel hands a new array back to Python: numba's boxing of an array, with the array's
Python type read from the function's environment instead of unpickled on every call.

numba 0.68 builds the ndarray it returns with NRT_adapt_ndarray_to_python_acqref, passing the
array's dtype and its Python type (the numba type's `box_type`: np.ndarray, unless an array
subclass registers a numba type of its own). It keeps the dtype among the function's environment
constants, read from that list in C, but embeds the type as a pickle that numba_unpickle turns
back into the object on every call: a call into the interpreter (a memo lookup) for each array
returned, whose new reference to the type is never released. A kernel returning new 3-vectors
hands each back in 0.15 us instead of 0.37 us (docs/speed.md). `install` registers a boxer that
keeps the type among the environment constants too, as numba keeps the dtype: the same C
function, the same arguments, the same array (the function only reads the type: a borrowed
reference is what it needs, and none leaks). The arithmetic is untouched; only what a kernel's
return costs changes. Compiled code keeps the boxer it was compiled with: a cache written before
(in a user's NUMBA_CACHE_DIR; the package's own cache directory is named by its sources' digest)
still returns arrays numba's way.

The dtype a returned array carries is an environment constant too, and the environment is
pickled into the disk cache. numpy's reduce of a dtype rebuilds it as a copy, so an array returned
by a kernel loaded from the cache had a float64 descriptor equal to numpy's but another object,
and as_float64's identity test (compiled.py) fell through to the equality test on every kernel
operand that such an array became. Pickled by numba's copy of cloudpickle (its cache, and
whatever else numba pickles with it; the standard pickler and the cloudpickle package are left as
they are), numpy's own float64 descriptor is rebuilt as itself (`_reduce_dtype`).

It is installed only under the numba it was written against (`NUMBA_VERSION`, the version
requirements.txt pins) and only over numba's own boxer; any other numba keeps its own."""
from __future__ import annotations

from typing import Any

import numpy as np

_FLOAT64 = np.dtype(np.float64)

NUMBA_VERSION = '0.68.1'


def install() -> bool:
    """Register the boxer for numba's array types (before any kernel compiles); True if it was
    registered (now or before), False under another numba or over a boxer not numba's own."""
    import numba
    from numba.core import boxing, pythonapi, types
    boxers = pythonapi._boxers.functions
    current = boxers.get(types.Array)
    if current is _box_array:
        return True
    if numba.__version__ != NUMBA_VERSION or current is not boxing.box_array:
        return False
    from numba.core.serialize import NumbaPickler
    NumbaPickler.dispatch_table[type(_FLOAT64)] = _reduce_dtype
    boxers[types.Array] = _box_array
    return True


def _reduce_dtype(d: Any) -> Any:
    """numpy's own float64 descriptor object (what numba keeps for a float64 array it returns) as
    np.dtype('f8'), numpy's own object again when unpickled; any other descriptor of its class,
    equal to it or not (a copy, byte-swapped, with metadata or fields), as numpy reduces it."""
    if d is _FLOAT64:
        return np.dtype, ('f8',)
    return d.__reduce__()


def _box_array(typ: Any, val: Any, c: Any) -> Any:
    """numba.core.boxing.box_array and PythonAPI.nrt_adapt_ndarray_to_python of numba 0.68, with
    typ.box_type taken from the environment's constants (module docstring)."""
    from llvmlite import ir
    from numba.core import boxing, cgutils, types
    from numba.np import numpy_support
    if not c.context.enable_nrt:
        return boxing.box_array(typ, val, c)
    pyapi, builder = c.pyapi, c.builder
    dtype = c.env_manager.read_const(c.env_manager.add_const(numpy_support.as_dtype(typ.dtype)))
    pytype = c.env_manager.read_const(c.env_manager.add_const(typ.box_type))
    i32 = ir.IntType(32)
    fnty = ir.FunctionType(pyapi.pyobj, [pyapi.voidptr, pyapi.pyobj, i32, i32, pyapi.pyobj])
    fn = pyapi._get_function(fnty, name='NRT_adapt_ndarray_to_python_acqref')
    fn.args[0].add_attribute('captures(none)')
    ndim = c.context.get_constant(types.int32, typ.ndim)
    writable = c.context.get_constant(types.int32, int(typ.mutable))
    aryptr = cgutils.alloca_once_value(builder, val)
    out = builder.call(fn, [builder.bitcast(aryptr, pyapi.voidptr), pytype, ndim, writable, dtype])
    c.context.nrt.decref(builder, typ, val)          # the array's reference, as numba's boxer drops it
    return out
