"""A digest of everything an engine run published: every field of every published estimate and
the counters (for tests that run the engine two ways and expect the same bits)."""
from __future__ import annotations

import dataclasses
import hashlib

import numpy as np


def digest(filt) -> str:
    h = hashlib.sha256()
    for e in filt.published:
        for f in dataclasses.fields(e):
            v = getattr(e, f.name)
            h.update(np.ascontiguousarray(v).tobytes() if isinstance(v, np.ndarray) else repr(v).encode())
    h.update(repr(filt.counters).encode())
    return h.hexdigest()
