"""A digest of everything an engine run published: every field of every published estimate and
the counters, and an engine run taken two ways (for tests that expect the same bits)."""
from __future__ import annotations

import dataclasses
import hashlib
from collections.abc import Callable

import numpy as np


def digest(filt) -> str:
    h = hashlib.sha256()
    for e in filt.published:
        for f in dataclasses.fields(e):
            v = getattr(e, f.name)
            h.update(np.ascontiguousarray(v).tobytes() if isinstance(v, np.ndarray) else repr(v).encode())
    h.update(repr(filt.counters).encode())
    return h.hexdigest()


def run_both_ways(monkeypatch, sc, inp, module, fast: str, cls: type, disable: Callable[[object], None]):
    """`pipeline.align` of sc's inputs counting the calls of `module.fast` (a compiled path), then
    again with `disable` applied to every new `cls` after its __init__ (the path not taken): the
    second run must never call it and must publish the same digest. Returns the first run's
    filter and its number of calls."""
    from alignment_core import pipeline

    calls = []
    compiled = getattr(module, fast)
    monkeypatch.setattr(module, fast, lambda *a: calls.append(1) or compiled(*a))
    filt = pipeline.align(sc, inp)
    n = len(calls)
    init = cls.__init__

    def without(self, *args, **kwargs):
        init(self, *args, **kwargs)
        disable(self)

    monkeypatch.setattr(cls, '__init__', without)
    calls.clear()
    assert digest(pipeline.align(sc, inp)) == digest(filt)
    assert not calls
    return filt, n
