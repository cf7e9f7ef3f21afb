"""Kalman filters sharing one small interface: predict, update, x, P, reset_state, diagnostics
(base.Filter); the nonlinear ones add predict_nonlinear / update_nonlinear (base.NonlinearFilter).

    KalmanFilter             kalman.py     Joseph form; float32 mode
    FadingMemoryFilter       fading.py     fixed lam, or innovation-tested lam (seed 003)
    StrongTrackingFilter     fading.py     single / multiple fading factors (Zhou; seed 000)
    CarlsonFilter            sqrt.py       upper-triangular square root; float32 mode
    UDFilter                 sqrt.py       Bierman update, Thornton MWGS time update; float32 mode
    SqrtFadingFilter         sqrt.py       Carlson + innovation-tested fading (seed 003); float32
    ExtendedKalmanFilter     nonlinear.py
    UnscentedKalmanFilter    nonlinear.py  scaled unscented transform (alpha, beta, kappa)
    CubatureKalmanFilter     nonlinear.py  third-order spherical-radial rule, 2n points
"""

from alignment_core.estimation.filters.base import Filter, NonlinearFilter, UpdateResult
from alignment_core.estimation.filters.fading import FadingMemoryFilter, StrongTrackingFilter
from alignment_core.estimation.filters.kalman import KalmanFilter
from alignment_core.estimation.filters.nonlinear import (
           CubatureKalmanFilter,
           ExtendedKalmanFilter,
           UnscentedKalmanFilter,
)
from alignment_core.estimation.filters.sqrt import CarlsonFilter, SqrtFadingFilter, UDFilter

__all__ = ['Filter', 'NonlinearFilter', 'UpdateResult', 'KalmanFilter', 'FadingMemoryFilter',
           'StrongTrackingFilter', 'CarlsonFilter', 'UDFilter', 'SqrtFadingFilter', 'ExtendedKalmanFilter',
           'UnscentedKalmanFilter', 'CubatureKalmanFilter']
