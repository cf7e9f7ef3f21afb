"""Ship truth arrays as the stages exchange them: one ShipBatch stamped t0_ns + k dt_ns, and its
ShipSamples. The batch pipeline takes the batch as it is (no per-sample records to build and
stack again); a node publishes the samples."""
from __future__ import annotations

import numpy as np

from alignment_core.samples import ShipBatch, ShipSample


def stamped_batch(t0_ns: int, dt_ns: int, k0: int, p_w: np.ndarray, q_nb: np.ndarray, v_b: np.ndarray,
                  w_b: np.ndarray, a_b: np.ndarray, wdot_b: np.ndarray) -> ShipBatch:
    """Samples k0 .. k0+K-1 of the truth arrays (K, ...), stamped t0_ns + k dt_ns; each field a
    C-ordered float64 copy, as ShipBatch.of stacks one from the samples."""
    k = k0 + np.arange(len(p_w), dtype=np.int64)
    return ShipBatch(t0_ns + k * dt_ns, *(np.array(a, dtype=float, order='C')
                                          for a in (p_w, q_nb, v_b, w_b, a_b, wdot_b)))


def split(sb: ShipBatch) -> list[ShipSample]:
    """The batch's samples in order."""
    return [sb.sample(k) for k in range(len(sb))]
