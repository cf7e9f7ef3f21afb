"""The filter algorithm named by `filter.algorithm`, built for a model."""
from __future__ import annotations

import numpy as np

from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.filters import (
    CarlsonFilter,
    CubatureKalmanFilter,
    ExtendedKalmanFilter,
    FadingMemoryFilter,
    KalmanFilter,
    SqrtFadingFilter,
    StrongTrackingFilter,
    UDFilter,
    UnscentedKalmanFilter,
)


def make_filter(cfg: FilterConfig, x0: np.ndarray, p0: np.ndarray, kinds: tuple[int, ...] | None = None):
    """The filter named by cfg.algorithm (alignment_core.filters), in float32 if asked.

    stf_alpha gives the multiple-factor STF's alpha per kind of state (phi, dV, eps, nabla,
    other: phi_m, mounting, flexure, lever arm): which blocks may change faster than the model
    says. `kinds` (the model's, one per state) maps them; default: blocks of three in that order."""
    dtype = np.float32 if cfg.float32 else np.float64
    a = cfg.algorithm
    if a == 'kf':
        return KalmanFilter(x0, p0, dtype=dtype)
    if a == 'stf':
        return StrongTrackingFilter(x0, p0, rho=cfg.stf_rho, beta=cfg.stf_beta, lam_max=cfg.stf_lambda_max,
                                    dtype=dtype)
    if a == 'stf_multiple':
        if kinds is None:
            alpha = np.repeat(np.asarray(cfg.stf_alpha), 3)[:len(x0)]
        else:
            alpha = np.asarray(cfg.stf_alpha)[np.asarray(kinds)]
        return StrongTrackingFilter(x0, p0, rho=cfg.stf_rho, beta=cfg.stf_beta, alpha=alpha,
                                    lam_max=cfg.stf_lambda_max, dtype=dtype)
    if a == 'fading':
        return FadingMemoryFilter(x0, p0, lam=cfg.fading_factor, dtype=dtype)
    if a == 'fading_tested':
        return FadingMemoryFilter(x0, p0, gamma=cfg.fading_gamma, dtype=dtype)
    if a == 'carlson':
        return CarlsonFilter(x0, p0, dtype=dtype)
    if a == 'ud':
        return UDFilter(x0, p0, dtype=dtype)
    if a == 'combined':
        return SqrtFadingFilter(x0, p0, gamma=cfg.fading_gamma, dtype=dtype)
    if a == 'ekf':
        return ExtendedKalmanFilter(x0, p0)
    if a == 'ukf':
        return UnscentedKalmanFilter(x0, p0)
    if a == 'ckf':
        return CubatureKalmanFilter(x0, p0)
    raise ValueError(f'unknown filter algorithm {a!r}')
