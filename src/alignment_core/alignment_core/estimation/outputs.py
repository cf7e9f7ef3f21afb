"""What the alignment engine publishes: one estimate per output instant, and its counters."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Estimate:
    """One output of the filter at a master stamp."""
    t_ns: int
    misalignment: np.ndarray          # (3,) rad, aircraft FLU axes
    misalignment_sigma: np.ndarray    # (3,) rad
    q_nb: np.ndarray                  # (4,) aligned slave attitude
    attitude_cov: np.ndarray          # (3, 3) rad^2, nav frame (phi)
    x: np.ndarray                     # (n,) last a-posteriori error state (before feedback)
    sigma: np.ndarray                 # (n,) 1-sigma of the error state (n = the model's)
    bias_gyro: np.ndarray             # (3,) accumulated gyro bias estimate, rad/s
    bias_accel: np.ndarray            # (3,) accumulated accelerometer bias estimate, m/s^2
    nis: float
    updates: int
    matching: bool
    fading: float | np.ndarray = 1.0  # last fading factor(s) of a fading / strong tracking filter
    healthy: bool = True              # False after a numerical breakdown: the last good estimate, held


@dataclass
class Counters:
    imu: int = 0
    ldv: int = 0
    master: int = 0
    rejected_nonfinite: int = 0
    rejected_out_of_order: int = 0
    imu_gaps: int = 0
    updates: int = 0
    gated: int = 0
    skipped_before_init: int = 0
    doppler: int = 0
    doppler_updates: int = 0
    unmatched_master: int = 0         # master samples with no slave solution at their validity time
    unmatched_doppler: int = 0        # Doppler samples with no slave solution at their validity time
    numerical_failures: int = 0       # breakdowns of the filter (non-finite or non-PD covariance)
    creep_detected: int = 0           # slow deck motion seen before the launch (LDV in the reference from then)
    rate_unmatched: int = 0           # rate matching: matches without a gyro interval / master pair to compare
    extra: dict = field(default_factory=dict)
