"""What the alignment engine publishes: one estimate per output instant, its counters, its
diagnostics and what it knows of the aircraft's motion on the deck (docs/engine.md)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass(frozen=True)
class Report:
    """What /diagnostics says at an output: level, flags and one line, from the stamps processed
    up to it (so the graph and the batch say the same; estimation/status.py)."""
    level: int = 0
    flags: tuple[str, ...] = ()
    message: str = ''


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
    healthy: bool = True              # False at level ERROR (breakdown, long gap, inconsistent)
    level: int = 0                    # health.OK / WARN / ERROR at this output
    flags: tuple[str, ...] = ()       # why not OK: 'gap', 'inconsistent', 'breakdown', 'held', ...
    # the slave INS solution after the filter's corrections (/alignment/odom); None: not computed
    p_w: np.ndarray | None = None     # (3,) position, world tangent plane (ENU), m
    v_b: np.ndarray | None = None     # (3,) velocity w.r.t. the Earth in body axes (FLU), m/s
    w_b: np.ndarray | None = None     # (3,) body rate w.r.t. the nav frame, body axes, rad/s
    pose_cov: np.ndarray | None = None    # (6, 6) position (m^2), then attitude (rotation vector, rad^2); -1: unknown
    twist_cov: np.ndarray | None = None   # (6, 6) body velocity (m^2/s^2), then body rate ((rad/s)^2); -1: unknown
    # the accumulated estimate of every state (state_estimate.py; labels: the engine's state_labels),
    # SI, its 1-sigma is `sigma`; None: not computed
    state: np.ndarray | None = None   # (n,)
    report: Report | None = None      # what /diagnostics says at this output (set by the engine)
    # the time the misalignment refers to: its last master update's validity time (the stamp less
    # the master latency the filter is told; a held one keeps its last match's; docs/engine.md,
    # time of validity); None: t_ns (an estimate made before this field)
    t_valid_ns: int | None = None
    # the time the slave solution (q_nb, attitude_cov, p_w, v_b, w_b) refers to: the newest IMU
    # sample the INS has integrated when the output is made; None: t_ns
    t_nav_ns: int | None = None

    @property
    def validity_ns(self) -> int:
        """The time of validity of the misalignment (t_ns when not given)."""
        return self.t_ns if self.t_valid_ns is None else self.t_valid_ns

    @property
    def navigation_ns(self) -> int:
        """The time the slave solution refers to (t_ns when not given)."""
        return self.t_ns if self.t_nav_ns is None else self.t_nav_ns


@dataclass
class Counters:
    """Samples seen, rejected and matched, and the events the engine counts, since the start."""
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
    rejected_quaternion: int = 0      # master quaternion off unit norm by more than the tolerance
    rejected_range: int = 0           # a value beyond the sensor's or the vehicle's range
    rejected_future_stamp: int = 0    # a stamp far ahead of every other stream
    quaternion_normalised: int = 0    # master quaternions normalised (off unit norm within the tolerance)
    launch_not_felt: int = 0          # LDV runs the accelerometers did not feel: not a launch
    bridged_gaps: int = 0             # IMU gaps bridged (longer than gap_bridge_factor intervals)
    gate_released: int = 0            # updates taken after gate_release_updates gated ones in a row
    consistency_failures: int = 0     # NIS windows above their chi-square bound
    ldv_ignored: int = 0              # LDV samples under relative velocity zero or after it fell silent
    rejected_ldv_mode: int = 0        # LDV samples not of the kind filter.ldv_mode says (beam / vector)


@dataclass(frozen=True)
class Diagnostics:
    """The engine's state for /diagnostics: the filter's own diagnostics as of the last output
    (nis, updates, gated, predicts, fading factor(s) if it fades; empty before the first), its
    health, the reason it stopped, and the samples queued but not yet processed."""
    filter: dict[str, Any]
    healthy: bool
    failure: str                      # '' while healthy
    pending: int
    level: int = 0                    # health.OK / WARN / ERROR now (the outputs' and the inputs')
    flags: tuple[str, ...] = ()       # what made it WARN or ERROR
    message: str = ''                 # one line for /diagnostics
    silent: tuple[str, ...] = ()      # master or LDV silent (the stamps processed: input_streams.py)
    consistency: dict[str, Any] = field(default_factory=dict)   # the NIS monitor's last window
    relative_velocity: str = 'ldv'    # where the relative velocity comes from (relative_velocity.py)
    whiteness: dict[str, Any] = field(default_factory=dict)     # the whiteness test's last window


@dataclass(frozen=True)
class DeckMotion:
    """The aircraft's motion on the deck as the LDV showed it: moving (creep or launch) from
    t_moving_ns, launched at t_launch_ns (validity times, None: not yet), and the deck
    displacement integrated from the LDV since it moved (ship axes, m)."""
    moving: bool
    t_moving_ns: int | None
    t_launch_ns: int | None
    displacement: np.ndarray          # (3,)
