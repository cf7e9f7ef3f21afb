"""Monte Carlo statistics per axis: mean, RMS, 95th percentile, settling time, and the
normalised estimation error squared (NEES) with its chi-square acceptance bounds.

NEES of one run at one time: e^T P^-1 e with e the misalignment error and P its covariance
(here diagonal: the filter publishes per-axis 1-sigma in aircraft axes). For N independent
runs of an honest filter, N times the average NEES of d degrees of freedom is chi-square
with N d degrees of freedom (Bar-Shalom, Li & Kirubarajan 2001, 5.4.2), which gives the
two-sided 95 % bounds on the average.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import chi2


@dataclass(frozen=True)
class AxisStats:
    """Statistics over N runs of one error component (same unit as the input)."""
    n: int
    mean: float
    std: float
    rms: float
    p95: float          # 95th percentile of |error|
    mean_sigma: float   # mean of the filter's own 1-sigma
    in_2sigma: float    # fraction of runs with |error| < 2 sigma (0.954 for an honest filter)
    nees: float         # average of error^2 / sigma^2 (1-dof NEES; 1 for an honest filter)


def axis_stats(err: np.ndarray, sigma: np.ndarray) -> AxisStats:
    """err, sigma: (N,) errors and 1-sigma of N runs."""
    err = np.asarray(err, dtype=float)
    sigma = np.asarray(sigma, dtype=float)
    if err.ndim != 1 or err.shape != sigma.shape or len(err) == 0:
        raise ValueError(f'axis_stats needs two (N,) arrays, N > 0; got {err.shape}, {sigma.shape}')
    return AxisStats(
        n=len(err), mean=float(np.mean(err)), std=float(np.std(err, ddof=1)) if len(err) > 1 else 0.0,
        rms=float(np.sqrt(np.mean(err**2))), p95=float(np.percentile(np.abs(err), 95.0)),
        mean_sigma=float(np.mean(sigma)), in_2sigma=float(np.mean(np.abs(err) < 2.0 * sigma)),
        nees=float(np.mean((err / sigma) ** 2)))


def nees(err: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """NEES over the last axis with a diagonal covariance: sum((err / sigma)^2, axis=-1)."""
    return np.sum((np.asarray(err) / np.asarray(sigma)) ** 2, axis=-1)


def nees_bounds(dof: int, n_runs: int, confidence: float = 0.95) -> tuple[float, float]:
    """Two-sided bounds on the N-run average NEES of a `dof`-dimensional error."""
    if dof < 1 or n_runs < 1 or not 0.0 < confidence < 1.0:
        raise ValueError(f'nees_bounds: dof >= 1, n_runs >= 1, 0 < confidence < 1; got {dof}, {n_runs}, {confidence}')
    a = 0.5 * (1.0 - confidence)
    k = dof * n_runs
    return float(chi2.ppf(a, k) / n_runs), float(chi2.ppf(1.0 - a, k) / n_runs)


def settling_time(t: np.ndarray, err: np.ndarray, threshold: float) -> float:
    """First time after which |err| stays at or below `threshold` up to the end of `t`
    (t[0] if it always was, NaN if it never settles). t: (K,), err: (K,)."""
    t = np.asarray(t, dtype=float)
    bad = np.abs(np.asarray(err, dtype=float)) > threshold
    if len(t) == 0 or bad[-1]:
        return float('nan')
    idx = np.flatnonzero(bad)
    return float(t[0]) if len(idx) == 0 else float(t[idx[-1] + 1])
