"""The alignment filter's configuration (`filter.*`) and its validation: each value's range, and
the model x algorithm x option combinations the engine can run (docs/engine.md)."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from alignment_core.estimation.models import DOPPLER_MODELS, NONLINEAR_MODELS
from alignment_core.estimation.presets import PRESET_NAMES
from alignment_core.validation import require

LINEAR_ALGORITHMS = ('kf', 'stf', 'stf_multiple', 'fading', 'fading_tested', 'carlson', 'ud', 'combined')
NONLINEAR_ALGORITHMS = ('ekf', 'ukf', 'ckf')
ATTITUDE_MODELS = ('seed003_21', 'seed003_24')               # attitude-match rows and mounting states
RATE_MODELS = ('vm12', 'vm15', 'seed003_21', 'seed003_24')   # phi and eps states: rate matching
BEAM_MODELS = ('vm12', 'vm15', 'seed000_6', 'seed003_21', 'seed003_24')   # linear, three velocity rows first
MASTER_ATTITUDE_MODELS = ('vm15', 'seed003_24')              # master attitude states phi_m
# inflate the whole covariance by a fading factor: with a beam LDV's one row the unobserved
# directions grow without bound (fading only when fading_factor > 1, an STF's only when
# stf_lambda_max > 1; docs/engine.md)
FADING_ALGORITHMS = ('stf', 'stf_multiple', 'fading', 'fading_tested', 'combined')
# the lever arm told to the filter: aircraft.lever_arm_m's bounds (200 m, 50 m; aircraft_config.py)
# plus a survey error's 10 sigma of 10 m, so a surveyed arm near the aircraft's bound loads every seed
DECK_SPOT_HORIZONTAL_M = 300.0
DECK_SPOT_VERTICAL_M = 150.0
OUTPUT_RATE_MAX_HZ = 1e9          # an output period of at least 1 ns (engine.py counts it in whole ns)


@dataclass(frozen=True)
class FilterConfig:
    """Alignment filter tuning and geometry (all known to the user, none from truth)."""
    model: Literal['vm15', 'vm12', 'seed000_6', 'seed000_large_angle', 'seed002_10', 'seed003_21',
                   'seed003_24', 'seed001_13'] = 'vm15'
    lever_arm_m: tuple[float, float, float] = (40.0, -10.0, 15.0)
    lever_arm_treatment: Literal['compensation', 'none', 'butterworth'] = 'compensation'
    butterworth_cutoff_hz: float = 0.505      # seed 002: butter(2, 0.0101) at 100 Hz
    lever_arm_states: bool = False
    lever_arm_sigma_m: float = 1.0
    init_attitude_sigma_deg: float = 1.0
    init_yaw_sigma_deg: float = 0.0           # 0: init_attitude_sigma_deg
    init_velocity_sigma_mps: float = 0.1
    gyro_bias_sigma_dph: float = 0.01
    accel_bias_sigma_ug: float = 100.0
    arw_dpsh: float = 0.001
    vrw_ugpshz: float = 10.0
    gyro_bias_rw_dphps: float = 0.0
    accel_bias_rw_ugps: float = 0.0
    ldv_sigma_mps: float = 0.01
    master_velocity_sigma_mps: float = 0.001
    parked_velocity_sigma_mps: float = 0.005
    launch_detect_mps: float = 0.05
    launch_confirm_samples: int = 3           # LDV samples in a row above launch_detect_mps that make a launch
    creep_detect_mps: float = 0.02            # slow deck motion: median LDV speed above this (0 = off)
    creep_window_samples: int = 25            # ... over this many valid samples
    algorithm: Literal['kf', 'stf', 'stf_multiple', 'fading', 'fading_tested', 'carlson', 'ud',
                       'combined', 'ekf', 'ukf', 'ckf'] = 'kf'
    float32: bool = False
    stf_rho: float = 0.95
    stf_beta: float = 3.0      # at 100 Hz V0 (about 20 samples) scatters +-30 % around R: beta < ~2.5 fades on noise
    stf_alpha: tuple[float, float, float, float, float] = (1.0, 1.0, 1.0, 1.0, 1.0)
    fading_factor: float = 1.0
    fading_gamma: float = 10.0
    master_tilt_sigma_arcmin: float = 0.2
    master_heading_sigma_arcmin: float = 0.5
    mounting_sigma_deg: float = 1.0           # seed003: prior of the mounting misalignment
    flexure_sigma_arcmin: tuple[float, float, float] = (3.0, 3.0, 3.0)   # seed003, per axis
    flexure_tau_s: tuple[float, float, float] = (3.0, 3.0, 3.0)
    attitude_match_sigma_arcmin: float = 0.1  # seed003: white noise of the attitude match
    large_angle_feedback_deg: float = 1.0     # seed000_large_angle: feed phi back below this sigma
    doppler_scale_sigma_ppm: float = 1000.0   # seed001_13: priors of the radar's errors
    doppler_bias_sigma_mps: float = 0.05
    doppler_drift_sigma_arcmin: float = 5.0
    output_rate_hz: float = 10.0
    # innovation gate: an update whose NIS exceeds it changes nothing (0 = off). On by default as a
    # gross-outlier gate (1e6: a velocity innovation 1000 sigma off); a statistical threshold (e.g.
    # chi2_3 at 1 - 1e-9 = 45) would gate the aliased-vibration runs, whose NIS reaches ~1e3-1e4
    gate_chi2: float = 1e6
    gate_release_updates: int = 10            # after this many gated updates in a row the next one is taken
    max_gap_factor: float = 1.5               # an IMU interval longer than this many nominal ones is a gap
    gap_bridge_factor: float = 5.0            # ... longer than this many: bridged, never one strapdown step
    gap_error_s: float = 2.0                  # ... longer than this: ERROR until re-converged
    silence_warn_s: float = 1.0               # master or LDV this far behind the newest stream: WARN
    # input plausibility (estimation/plausibility.py): beyond these a sample is rejected
    quaternion_norm_tolerance: float = 1e-3   # master |q| within 1 +- this is normalised, else rejected
    imu_gyro_range_dps: float = 400.0         # full scale of the slave gyros, per axis
    imu_accel_range_g: float = 16.0           # ... of the slave accelerometers, per axis
    master_speed_max_mps: float = 100.0       # ship speed
    master_rate_max_dps: float = 60.0         # ship body rate
    position_max_m: float = 1e7               # |position| in the world tangent plane
    ldv_speed_max_mps: float = 150.0          # aircraft speed relative to the deck
    doppler_speed_max_mps: float = 400.0      # aircraft ground speed
    future_stamp_s: float = 1.0               # a sample this far (+ the largest latency) ahead of every other stream
    launch_felt_fraction: float = 0.5         # an LDV launch needs this fraction of its speed in the IMU's x (0 = off)
    launch_felt_tolerance_mps: float = 0.2    # ... less this (vibration, deck motion)
    # consistency monitor (estimation/consistency.py): NIS summed over windows of updates
    consistency_window_updates: int = 100
    consistency_warn_p: float = 1e-4          # a window whose NIS sum exceeds chi2(dof) at 1 - p fails: WARN
    consistency_error_windows: int = 3        # ... this many failing windows in a row: ERROR (persisting)
    misalignment_max_deg: float = 30.0        # a misalignment or its sigma beyond this is absurd (never published)
    heading_on_deck_deg: float = 0.0          # nominal aircraft heading on deck (from the bow, clockwise)
    master_latency_s: float = 0.0             # known latency: /master/odom data are valid at stamp - latency
    ldv_latency_s: float = 0.0                # the same for /ldv/twist
    doppler_latency_s: float = 0.0            # the same for /doppler/twist (seed001_13)
    stf_lambda_max: float = 1e6               # cap on the strong tracking fading factor(s)
    launch_accel_noise_mps2: float = 0.0      # velocity noise density (m/s^2/sqrt(Hz)) after the launch
    launch_noise_s: float = 1.0               # ... for this long after the LDV detects it
    attitude_match_axes: Literal['all', 'yaw'] = 'all'   # seed003_*: match all three axes or heading only
    rate_matching: bool = False               # + angular-rate rows (models/rate_matching.py)
    rate_match_sigma_dph: float = 1.0         # white noise of the rate match beyond the gyro's ARW
    master_delay_state: bool = False          # + the master's unknown latency as a state (models/master_delay.py)
    master_delay_sigma_ms: float = 20.0       # ... its prior 1-sigma
    # relative velocity of the slave to the master's body (estimation/relative_velocity.py):
    # ldv: from /ldv/twist; zero: rigidly tied (no LDV); auto: zero when no LDV sample comes
    relative_velocity: Literal['auto', 'ldv', 'zero'] = 'auto'
    rigid_velocity_sigma_mps: float = 0.005   # zero: white noise of the zero relative velocity
    ldv_silence_s: float = 30.0               # an LDV this far (stamps) behind the IMU and master: silent
    preset: str = ''                          # tuning grade (estimation/presets.py), resolved on load
    flexure_states: bool = True               # seed003_*: false drops theta, theta' (6 states)
    whiteness_window_updates: int = 500       # innovation whiteness (estimation/whiteness.py)
    whiteness_lags: int = 10                  # ... Ljung-Box lags
    whiteness_p: float = 1e-3                 # ... a window whose p-value is below this fails
    ldv_mode: Literal['vector', 'beam'] = 'vector'   # the LDV installed (follows ldv.mode): beam = one row along it
    # the specific force the error model couples attitude into velocity with (estimation/reference_force.py):
    # slave: the slave's own (carries g x its tilt error); reference: parked, the horizontal part from the
    # deck spot's acceleration fitted to the master samples over reference_force_window_s
    specific_force: Literal['slave', 'reference'] = 'slave'
    reference_force_window_s: float = 1.0
    # the delay state's column (models/master_delay.py): slave: the slave's acceleration parked, two master
    # samples differenced moving; reference: the same fit as specific_force's, parked and moving
    delay_acceleration: Literal['slave', 'reference'] = 'slave'

    def validate(self) -> None:
        for k in ('init_attitude_sigma_deg', 'init_velocity_sigma_mps', 'gyro_bias_sigma_dph',
                  'accel_bias_sigma_ug', 'ldv_sigma_mps', 'output_rate_hz', 'parked_velocity_sigma_mps',
                  'launch_detect_mps'):
            require(getattr(self, k) > 0.0, f"{k} must be > 0, got {getattr(self, k)}")
        for k in ('arw_dpsh', 'vrw_ugpshz', 'gyro_bias_rw_dphps', 'accel_bias_rw_ugps',
                  'master_velocity_sigma_mps', 'gate_chi2'):
            require(getattr(self, k) >= 0.0, f"{k} must be >= 0, got {getattr(self, k)}")
        require(self.creep_detect_mps >= 0.0, f"creep_detect_mps must be >= 0 (0 = off), got {self.creep_detect_mps}")
        require(3 <= self.creep_window_samples <= 10000,
                f"creep_window_samples must be in [3, 10000], got {self.creep_window_samples}")
        require(1 <= self.launch_confirm_samples <= 100,
                f"launch_confirm_samples must be in [1, 100], got {self.launch_confirm_samples}")
        require(0.1 <= self.reference_force_window_s <= 10.0,
                f"reference_force_window_s must be in [0.1, 10] s, got {self.reference_force_window_s}")
        require(self.max_gap_factor > 1.0, f"max_gap_factor must be > 1, got {self.max_gap_factor}")
        require(self.output_rate_hz <= OUTPUT_RATE_MAX_HZ,
                f"output_rate_hz must be <= {OUTPUT_RATE_MAX_HZ:g} Hz (a period of at least 1 ns; outputs come "
                f"at master stamps, so a rate at or above the master's gives one at every master sample), "
                f"got {self.output_rate_hz}")
        r = self.lever_arm_m
        require(math.hypot(r[0], r[1]) <= DECK_SPOT_HORIZONTAL_M and abs(r[2]) <= DECK_SPOT_VERTICAL_M,
                f"lever_arm_m out of range (|horizontal| <= {DECK_SPOT_HORIZONTAL_M:g} m, "
                f"|z| <= {DECK_SPOT_VERTICAL_M:g} m): {self.lever_arm_m}")
        self.validate_monitoring()
        require(-180.0 <= self.heading_on_deck_deg <= 180.0,
                f"heading_on_deck_deg must be in [-180, 180], got {self.heading_on_deck_deg}")
        for k in ('master_latency_s', 'ldv_latency_s', 'doppler_latency_s'):
            require(0.0 <= getattr(self, k) <= 1.0, f"{k} must be in [0, 1] s, got {getattr(self, k)}")
        require(self.stf_lambda_max >= 1.0, f"stf_lambda_max must be >= 1, got {self.stf_lambda_max}")
        require(self.launch_accel_noise_mps2 >= 0.0,
                f"launch_accel_noise_mps2 must be >= 0 (0 = off), got {self.launch_accel_noise_mps2}")
        require(0.0 < self.launch_noise_s <= 600.0, f"launch_noise_s must be in (0, 600], got {self.launch_noise_s}")
        require(0.0 < self.stf_rho <= 1.0, f"stf_rho must be in (0, 1], got {self.stf_rho}")
        require(self.stf_beta >= 1.0, f"stf_beta must be >= 1, got {self.stf_beta}")
        require(all(a >= 1.0 for a in self.stf_alpha), f"stf_alpha must all be >= 1, got {self.stf_alpha}")
        require(self.fading_factor >= 1.0, f"fading_factor must be >= 1, got {self.fading_factor}")
        require(self.fading_gamma >= 1.0, f"fading_gamma must be >= 1, got {self.fading_gamma}")
        for k in ('butterworth_cutoff_hz', 'lever_arm_sigma_m', 'mounting_sigma_deg', 'attitude_match_sigma_arcmin',
                  'large_angle_feedback_deg', 'doppler_scale_sigma_ppm', 'doppler_bias_sigma_mps',
                  'doppler_drift_sigma_arcmin', 'rate_match_sigma_dph', 'master_delay_sigma_ms'):
            require(getattr(self, k) > 0.0, f"{k} must be > 0, got {getattr(self, k)}")
        require(self.init_yaw_sigma_deg >= 0.0, f"init_yaw_sigma_deg must be >= 0, got {self.init_yaw_sigma_deg}")
        for k in ('master_tilt_sigma_arcmin', 'master_heading_sigma_arcmin'):
            if self.model in MASTER_ATTITUDE_MODELS:
                require(getattr(self, k) > 0.0, f"{k} must be > 0 (the prior of {self.model}'s master attitude "
                                                f"states), got {getattr(self, k)}")
            else:
                require(getattr(self, k) >= 0.0, f"{k} must be >= 0, got {getattr(self, k)}")
        require(not self.flexure_states or all(v > 0.0 for v in self.flexure_sigma_arcmin + self.flexure_tau_s),
                f"flexure_sigma_arcmin and flexure_tau_s must be > 0, got {self.flexure_sigma_arcmin}, "
                f"{self.flexure_tau_s}")
        self.validate_combination()
        self.validate_estimator_options()
        self.validate_ldv_mode()

    def validate_estimator_options(self) -> None:
        """Relative velocity, preset, flexure states, whiteness (docs/engine.md)."""
        require(self.relative_velocity in ('auto', 'ldv', 'zero'),
                f"relative_velocity must be auto, ldv or zero, got {self.relative_velocity!r}")
        require(self.rigid_velocity_sigma_mps > 0.0,
                f"rigid_velocity_sigma_mps must be > 0, got {self.rigid_velocity_sigma_mps}")
        require(self.ldv_silence_s > 0.0, f"ldv_silence_s must be > 0, got {self.ldv_silence_s}")
        require(not (self.relative_velocity == 'zero' and self.model in DOPPLER_MODELS),
                f"relative_velocity zero: {self.model} needs the LDV on the deck")
        require(self.preset in ('',) + PRESET_NAMES,
                f"preset must be one of {', '.join(PRESET_NAMES)} (or empty), got {self.preset!r}")
        require(self.flexure_states or self.model in ATTITUDE_MODELS,
                f"flexure_states false: only {', '.join(ATTITUDE_MODELS)} have flexure states, got {self.model}")
        require(10 <= self.whiteness_window_updates <= 100000,
                f"whiteness_window_updates must be in [10, 100000], got {self.whiteness_window_updates}")
        require(1 <= self.whiteness_lags < self.whiteness_window_updates // 2,
                f"whiteness_lags must be in [1, window / 2), got {self.whiteness_lags}")
        require(0.0 < self.whiteness_p < 0.5, f"whiteness_p must be in (0, 0.5), got {self.whiteness_p}")

    def validate_ldv_mode(self) -> None:
        """A beam LDV's one row projects the three velocity rows on the line of sight
        (models/beam.py): a linear model whose first three rows are E, N, U velocity, and no
        fading of the whole covariance (the directions the row leaves unobserved would grow)."""
        require(self.ldv_mode in ('vector', 'beam'), f"ldv_mode must be 'vector' or 'beam', got {self.ldv_mode!r}")
        require(self.ldv_mode == 'vector' or self.model in BEAM_MODELS,
                f"ldv_mode beam projects the three velocity rows on the beam: it needs one of "
                f"{', '.join(BEAM_MODELS)}, got {self.model}")
        a = self.algorithm
        fades = a in FADING_ALGORITHMS and not (a == 'fading' and self.fading_factor == 1.0) \
            and not (a in ('stf', 'stf_multiple') and self.stf_lambda_max == 1.0)
        require(self.ldv_mode == 'vector' or not fades,
                f"algorithm {self.algorithm} cannot run with ldv_mode beam: its fading factor inflates the whole "
                f"covariance while the beam's one row leaves directions unobserved, which then grow without bound "
                f"(the estimate diverges while the level stays OK); use kf, carlson, ud, ekf, ukf or ckf"
                + (f" (or fading_factor 1, got {self.fading_factor})" if a == 'fading' else '')
                + (f" (or stf_lambda_max 1, got {self.stf_lambda_max})" if a in ('stf', 'stf_multiple') else ''))

    def validate_monitoring(self) -> None:
        """Plausibility limits, gap handling, the gate and the consistency monitor."""
        require(self.gap_bridge_factor >= self.max_gap_factor,
                f"gap_bridge_factor must be >= max_gap_factor = {self.max_gap_factor}, got {self.gap_bridge_factor}")
        for k in ('gap_error_s', 'silence_warn_s', 'imu_gyro_range_dps', 'imu_accel_range_g',
                  'master_speed_max_mps', 'master_rate_max_dps', 'position_max_m', 'ldv_speed_max_mps',
                  'doppler_speed_max_mps', 'future_stamp_s', 'misalignment_max_deg'):
            require(getattr(self, k) > 0.0, f"{k} must be > 0, got {getattr(self, k)}")
        require(0.0 < self.quaternion_norm_tolerance < 0.5,
                f"quaternion_norm_tolerance must be in (0, 0.5), got {self.quaternion_norm_tolerance}")
        require(0.0 <= self.launch_felt_fraction <= 1.0,
                f"launch_felt_fraction must be in [0, 1] (0 = off), got {self.launch_felt_fraction}")
        require(self.launch_felt_tolerance_mps >= 0.0,
                f"launch_felt_tolerance_mps must be >= 0, got {self.launch_felt_tolerance_mps}")
        require(self.gate_release_updates >= 1, f"gate_release_updates must be >= 1, got {self.gate_release_updates}")
        require(10 <= self.consistency_window_updates <= 100000,
                f"consistency_window_updates must be in [10, 100000], got {self.consistency_window_updates}")
        require(0.0 < self.consistency_warn_p < 0.5,
                f"consistency_warn_p must be in (0, 0.5), got {self.consistency_warn_p}")
        require(self.consistency_error_windows >= 1,
                f"consistency_error_windows must be >= 1, got {self.consistency_error_windows}")
        require(self.misalignment_max_deg <= 180.0,
                f"misalignment_max_deg must be <= 180, got {self.misalignment_max_deg}")
        prior = max(self.init_attitude_sigma_deg, self.init_yaw_sigma_deg)
        require(prior < self.misalignment_max_deg,
                f"init_attitude_sigma_deg / init_yaw_sigma_deg ({prior}) must be below misalignment_max_deg "
                f"({self.misalignment_max_deg}): an estimate less certain than that is published as absurd")

    def validate_combination(self) -> None:
        """Model x algorithm x options (the matrix in docs/engine.md)."""
        m, a = self.model, self.algorithm
        require(not (m in DOPPLER_MODELS and a in ('stf', 'stf_multiple')),
                f"algorithm {a} cannot run {m}: its innovation recursion would mix the LDV and Doppler "
                f"streams; use kf, fading, fading_tested, carlson, ud, combined, ekf, ukf or ckf")
        require(not (self.lever_arm_states and m in DOPPLER_MODELS),
                f"lever_arm_states is not available with {m} (its Doppler rows have no lever arm)")
        if m in NONLINEAR_MODELS:
            require(a in NONLINEAR_ALGORITHMS,
                    f"model {m} is nonlinear: algorithm must be one of {', '.join(NONLINEAR_ALGORITHMS)}, got {a}")
            require(not self.lever_arm_states, f"lever_arm_states is not available with the nonlinear model {m}")
        require(not (self.float32 and a in NONLINEAR_ALGORITHMS),
                f"algorithm {a} runs in float64 only: set float32 false or pick one of {', '.join(LINEAR_ALGORITHMS)}")
        require(self.attitude_match_axes in ('all', 'yaw'),
                f"attitude_match_axes must be 'all' or 'yaw', got {self.attitude_match_axes!r}")
        require(self.attitude_match_axes == 'all' or m in ATTITUDE_MODELS,
                f"attitude_match_axes yaw needs a model with mounting states and attitude rows "
                f"({', '.join(ATTITUDE_MODELS)}): a heading match without them would pull the slave onto the "
                f"master's heading, off by the unknown mounting yaw; got model {m}")
        require(not self.rate_matching or m in RATE_MODELS,
                f"rate_matching needs attitude and gyro-bias states (models {', '.join(RATE_MODELS)}), got {m}")
        require(not (self.rate_matching and a in ('stf', 'stf_multiple')),
                f"algorithm {a} cannot take rate_matching: its innovation recursion needs the same rows at "
                f"every update, and the rate rows start at the second master sample")
        require(self.specific_force in ('slave', 'reference'),
                f"specific_force must be 'slave' or 'reference', got {self.specific_force!r}")
        require(self.delay_acceleration in ('slave', 'reference'),
                f"delay_acceleration must be 'slave' or 'reference', got {self.delay_acceleration!r}")
        require(self.specific_force == 'slave' or (m not in NONLINEAR_MODELS and m not in DOPPLER_MODELS),
                f"specific_force reference needs a linear model without the Doppler stream, got {m}")
        require(not self.master_delay_state or (m not in NONLINEAR_MODELS and m not in DOPPLER_MODELS),
                f"master_delay_state needs a linear model without the Doppler stream, got {m}")
        require(not (self.lever_arm_states and self.lever_arm_treatment != 'compensation'),
                f"lever_arm_states estimate the error of the compensated lever arm: they need "
                f"lever_arm_treatment compensation, got {self.lever_arm_treatment}")
