"""The LDV sample as the wire carries it (/ldv/twist, TwistWithCovarianceStamped): the velocity,
and a 3x3 linear covariance that says what was measured. A vector LDV: sigma^2 I. A beam LDV:
sigma^2 u u^T (rank 1: the unit line of sight u, the other two directions unmeasured). No
measurement: covariance[0] = -1.

A beam's u and sigma come back from the covariance (the eigenvector of its one non-zero
eigenvalue, the square root of its trace) to within rounding, and the sign of u may flip (immaterial:
the measurement is a projection). So that a run through the graph and the batch pipeline feed
the filter the same bits, the batch feeds it `transmitted(s)`: the sample after this encoding and
decoding, exactly what the filter node decodes from the message."""
from __future__ import annotations

import math
from collections.abc import Iterator, Sequence

import numpy as np

from alignment_core.samples import LdvSample

BEAM_RANK_TOLERANCE = 1e-9
"""A linear covariance block whose second eigenvalue is below this fraction of its trace is a
beam's (rank 1)."""


def encode(s: LdvSample) -> tuple[np.ndarray, np.ndarray]:
    """(linear velocity (3,), linear covariance (3, 3)) of a sample; covariance[0, 0] = -1 and
    zeros elsewhere when it is not valid."""
    cov = np.zeros((3, 3))
    if not s.valid:
        cov[0, 0] = -1.0
        return np.array(s.v_s, dtype=float), cov
    if s.beam is None:
        cov[0, 0] = cov[1, 1] = cov[2, 2] = s.sigma**2
    else:
        cov = s.sigma**2 * np.outer(s.beam, s.beam)
    return np.array(s.v_s, dtype=float), cov


def decode(t_ns: int, linear: np.ndarray, cov: np.ndarray) -> LdvSample:
    """The LdvSample of a velocity (3,) and its linear covariance (3, 3) (`encode`): decode_all's
    steps on one sample, with Python floats where it takes whole columns (the filter node decodes
    each message as it comes: the stack's overhead was most of the cost); the same bits."""
    cov = np.asarray(cov, dtype=float)
    v = np.array(linear, dtype=float)
    cells = cov.ravel().tolist()
    c0 = cells[0]
    if not c0 >= 0.0:                                   # NaN: not valid
        return LdvSample(t_ns=t_ns, v_s=v, sigma=math.nan, valid=False)
    trace = cells[0] + cells[4] + cells[8]
    if all(map(math.isfinite, cells)) and trace > 0.0 and not _isotropic(cells):
        w1, beam = _eigh_one(0.5 * (cov + cov.T))
        if w1 <= BEAM_RANK_TOLERANCE * trace:
            return LdvSample(t_ns=t_ns, v_s=v, sigma=math.sqrt(trace), valid=True, beam=beam)
    return LdvSample(t_ns=t_ns, v_s=v, sigma=math.sqrt(c0), valid=True)


def _eigh_one(a: np.ndarray) -> tuple[float, np.ndarray]:
    """(the middle eigenvalue, the eigenvector of the largest (3,)) of a symmetric 3 x 3, or (NaN,
    zeros) when LAPACK does not converge (cells near the end of the float range): NaN compares
    false, so not a beam."""
    try:
        w, vec = np.linalg.eigh(a)
    except np.linalg.LinAlgError:
        return math.nan, np.zeros(3)
    return float(w[1]), vec[:, 2].copy()


def decode_all(t_ns: list[int], linear: np.ndarray, cov: np.ndarray) -> list[LdvSample]:
    """The LdvSamples of velocities (N, 3) and their linear covariances (N, 3, 3), the
    covariances that could be a beam's (valid, finite, a positive trace, not sigma^2 I) decomposed
    as one stack (eigh solves each matrix on its own: the same bits as one by one; a stack with
    one that does not converge, each on its own)."""
    c0 = cov[:, 0, 0]
    valid = c0 >= 0.0                                   # NaN: not valid
    trace = cov[:, 0, 0] + cov[:, 1, 1] + cov[:, 2, 2]
    candidate = valid & np.isfinite(cov).all(axis=(1, 2)) & (trace > 0.0) & ~_isotropic_stack(cov)
    w1, beam = np.full(len(cov), math.nan), np.zeros((len(cov), 3))     # NaN: not a beam
    if candidate.all():                                 # the usual case: no masks
        w1, beam = _eigh_stack(0.5 * (cov + cov.transpose(0, 2, 1)))
    elif candidate.any():
        sub = cov[candidate]
        w1[candidate], beam[candidate] = _eigh_stack(0.5 * (sub + sub.transpose(0, 2, 1)))
    out = []
    linear = np.array(linear, dtype=float)           # one copy; each sample's v_s a row of it
    rows = zip(t_ns, valid.tolist(), trace.tolist(), w1.tolist(), c0.tolist())
    for i, (t, ok, tr, w, var) in enumerate(rows):
        v = linear[i]
        if not ok:
            out.append(LdvSample(t_ns=t, v_s=v, sigma=math.nan, valid=False))
        elif w <= BEAM_RANK_TOLERANCE * tr:
            out.append(LdvSample(t_ns=t, v_s=v, sigma=math.sqrt(tr), valid=True, beam=beam[i]))
        else:
            out.append(LdvSample(t_ns=t, v_s=v, sigma=math.sqrt(var), valid=True))
    return out


def _isotropic(cells: list[float]) -> bool:
    """The 9 cells are sigma^2 I (a vector LDV's): its middle eigenvalue is sigma^2, within
    rounding of the cells (LAPACK's eigenvalues are backward stable), far above a beam's
    BEAM_RANK_TOLERANCE of the trace, and one that does not converge is no beam either: so it
    is not a beam without solving for the eigenvalues."""
    c = cells[0]
    return cells[4] == c and cells[8] == c and not (cells[1] or cells[2] or cells[3] or cells[5] or cells[6]
                                                     or cells[7])


def _isotropic_stack(cov: np.ndarray) -> np.ndarray:
    """(N,) `_isotropic` of each of the covariances (N, 3, 3)."""
    c = cov[:, 0, 0]
    off = cov.reshape(-1, 9)[:, [1, 2, 3, 5, 6, 7]]
    return (cov[:, 1, 1] == c) & (cov[:, 2, 2] == c) & ~off.any(axis=1)


def _eigh_stack(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(middle eigenvalues (N,), eigenvectors of the largest (N, 3)) of symmetric matrices (N, 3, 3),
    `_eigh_one`'s (NaN, zeros) for one that does not converge."""
    try:
        w, vec = np.linalg.eigh(a)
    except np.linalg.LinAlgError:
        each = [_eigh_one(m) for m in a]
        return np.array([w for w, _ in each]), np.array([b for _, b in each]).reshape(len(a), 3)
    return np.ascontiguousarray(w[:, 1]), np.ascontiguousarray(vec[:, :, 2])


def transmitted(s: LdvSample) -> LdvSample:
    """The sample the filter decodes from the message of `s`."""
    return decode(s.t_ns, *encode(s))


def encode_all(samples: Sequence[LdvSample]) -> tuple[np.ndarray, np.ndarray]:
    """`encode` of every sample as stacks: velocities (N, 3) and linear covariances (N, 3, 3),
    the same bits (each variance is sigma**2 of a Python float, as `encode` squares it: the C
    library's pow, which rounds differently from x * x now and then)."""
    n = len(samples)
    linear = np.array([s.v_s for s in samples], dtype=float).reshape(n, 3)
    cov = np.zeros((n, 3, 3))
    var = np.array([s.sigma**2 if s.valid else -1.0 for s in samples])
    kind = np.array([0 if not s.valid else 1 if s.beam is None else 2 for s in samples], dtype=np.int8)
    cov[kind == 0, 0, 0] = -1.0
    vector = kind == 1
    for i in range(3):
        cov[vector, i, i] = var[vector]
    beam = kind == 2
    if beam.any():
        u = np.array([s.beam for s, b in zip(samples, beam.tolist()) if b], dtype=float).reshape(-1, 3)
        cov[beam] = var[beam, None, None] * (u[:, :, None] * u[:, None, :])      # sigma^2 np.outer(u, u)
    return linear, cov


def transmitted_all(samples: Sequence[LdvSample]) -> list[LdvSample]:
    """`transmitted` of every sample (encoded and decoded as one stack)."""
    if not samples:
        return []
    return decode_all([s.t_ns for s in samples], *encode_all(samples))


def transmitted_stream(samples: Sequence[LdvSample], batch: int) -> Iterator[LdvSample]:
    """`transmitted` of every sample in turn, decoded `batch` at a time (each sample is decoded
    on its own, so the batch size changes no bit): a batch run's whole LDV stream without a
    decoded copy of all of it in memory."""
    for a in range(0, len(samples), batch):
        yield from transmitted_all(samples[a:a + batch])
