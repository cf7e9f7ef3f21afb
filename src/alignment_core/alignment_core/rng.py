"""Deterministic random streams: one generator per (scenario seed, stage name)."""
from __future__ import annotations

import zlib

import numpy as np


def stage_rng(seed: int, stage: str) -> np.random.Generator:
    """Generator for `stage`, independent of every other stage, reproducible from `seed`."""
    return np.random.default_rng(np.random.SeedSequence([int(seed), zlib.crc32(stage.encode())]))
