"""The filter algorithm named by `filter.algorithm`, built for a model."""
from __future__ import annotations

from typing import Any, Protocol

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
from alignment_core.estimation.filters.base import UpdateResult


class EngineFilter(Protocol):
    """What the engine uses of a filter (filters/base.py): x and P it may assign (closed-loop
    feedback, known-event noise), predict, update and diagnostics."""
    x: np.ndarray
    P: np.ndarray

    def predict(self, phi: np.ndarray, qd: np.ndarray) -> None: ...

    def update(self, z: np.ndarray, h: np.ndarray, r: np.ndarray,
               gate_chi2: float | None = None) -> UpdateResult: ...

    def diagnostics(self) -> dict[str, Any]: ...


def make_filter(cfg: FilterConfig, x0: np.ndarray, p0: np.ndarray, kinds: tuple[int, ...]) -> EngineFilter:
    """The filter named by cfg.algorithm (alignment_core.filters), in float32 if asked.

    stf_alpha gives the multiple-factor STF's alpha per kind of state (phi, dV, eps, nabla,
    other: phi_m, mounting, flexure, lever arm): which blocks may change faster than the model
    says. `kinds` (the model's, one per state) maps them."""
    dtype = np.float32 if cfg.float32 else np.float64
    a = cfg.algorithm
    if a == 'kf':
        return KalmanFilter(x0, p0, dtype=dtype)
    if a == 'stf':
        return StrongTrackingFilter(x0, p0, rho=cfg.stf_rho, beta=cfg.stf_beta, lam_max=cfg.stf_lambda_max,
                                    dtype=dtype)
    if a == 'stf_multiple':
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
