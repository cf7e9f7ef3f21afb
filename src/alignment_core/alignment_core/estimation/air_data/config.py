"""Configuration of the air-data estimators (scenario section `air_data_filter`). Noise values
are sensor specifications, not fitted to the simulation: the scenario states both the sensor's
truth and what the filter is told."""
from __future__ import annotations

from dataclasses import dataclass

from alignment_core.air_data.turbulence_spec import SEVERITIES
from alignment_core.validation import require

FORMS = ('paper', 'tight')
ALGORITHMS = ('ekf', 'ukf', 'ckf')
INS_SOURCES = ('aligned', 'reference')


@dataclass(frozen=True)
class AirDataFilterConfig:
    """`form`: 'paper' (seed 004: 3 airspeed states driven by the IMU, the FADS solve as the
    measurement) or 'tight' (the five port pressures as measurements; wind, turbulence, the day's
    static-pressure and temperature offsets, port biases and the ports' correlated noise as
    states). `algorithm`: ekf | ukf | ckf.

    Port model: `port_sigma_pa` and `port_correlation` (lag-1 at the frame interval) of the
    ports' Gauss-Markov noise, `port_white_sigma_pa` an independent floor (quantisation),
    `lag_s_sea_level` the pneumatic lag tau = tau0 p0 / p the filter compensates.
    Tight form: wind random walk (`wind_walk_mps_per_sqrt_s`, initial `wind_sigma_mps`);
    turbulence of `turbulence_severity` (none: no turbulence states): first-order Gauss-Markov
    per ENU axis with the MIL-F-8785C intensity and scale length at the INS height (horizontal:
    sigma_u, L_u; up: sigma_w, L_w; time constant L / V); temperature offset dT and
    static-pressure ratio offset s (p_inf = p_day(h_ins; dT) (1 + s): the hydrostatic pressure of
    the warmer day, scaled by the day's sea-level pressure and the INS height error), each with
    initial sigma and random walk; port biases (initial sigma, constant). Fault detection: a
    port whose normalised innovations squared, summed over `fault_window_s` (at least 5 frames),
    exceed the chi-square quantile of probability 1 - `fault_false_alarm` is excluded from then on.
    Paper form: white specific-force and rate noise (the seed's 3-sigma 0.06 m/s^2 and
    0.03 deg/s: 1-sigma 0.02 and 0.01); `paper_branch` uses the seed's alpha > 45 deg test;
    the INS attitude error (its covariance comes with each INS solution) tilts gravity into the
    specific force: a Gauss-Markov error of correlation time `ins_error_time_s` (the INS's
    specification) enters as white noise of the same low-frequency power, 2 sigma^2 tau.
    Frames whose NIS exceeds `gate_chi2` are rejected (both forms). `ins_source`: the INS the
    estimator reads, 'aligned' (the transfer-aligned slave INS, /alignment/odom) or 'reference'
    (a reference INS, /reference_ins/odom: scenarios without a deck phase). The estimator starts
    at the first frame whose solve is windward at Mach >= `start_mach` (on a deck, in the
    ship's airflow, the angles are undefined)."""
    form: str = 'tight'
    algorithm: str = 'ckf'
    ins_source: str = 'aligned'
    port_sigma_pa: float = 20.0
    port_correlation: float = 0.5
    port_white_sigma_pa: float = 0.5
    lag_s_sea_level: float = 0.02
    wind_sigma_mps: float = 20.0
    wind_walk_mps_per_sqrt_s: float = 0.05
    turbulence_severity: str = 'none'
    static_offset_sigma: float = 0.01
    static_offset_walk_per_sqrt_s: float = 2e-5
    temperature_sigma_k: float = 10.0
    temperature_walk_k_per_sqrt_s: float = 0.01
    bias_sigma_pa: float = 1.0
    accel_sigma_mps2: float = 0.02
    gyro_sigma_dps: float = 0.01
    paper_branch: bool = True
    ins_error_time_s: float = 300.0
    gate_chi2: float = 30.0
    fault_window_s: float = 1.0
    fault_false_alarm: float = 1e-7
    output_rate_hz: float = 10.0
    start_mach: float = 0.08

    def validate(self) -> None:
        require(self.form in FORMS, f"form must be one of {', '.join(FORMS)}, got {self.form!r}")
        require(self.ins_source in INS_SOURCES,
                f"ins_source must be one of {', '.join(INS_SOURCES)}, got {self.ins_source!r}")
        require(self.algorithm in ALGORITHMS,
                f"algorithm must be one of {', '.join(ALGORITHMS)}, got {self.algorithm!r}")
        for name in ('port_sigma_pa', 'port_white_sigma_pa', 'wind_sigma_mps', 'static_offset_sigma',
                     'temperature_sigma_k', 'bias_sigma_pa', 'accel_sigma_mps2', 'gyro_sigma_dps',
                     'ins_error_time_s', 'gate_chi2', 'fault_window_s',
                     'output_rate_hz'):
            v = getattr(self, name)
            require(v > 0.0, f"{name} must be > 0, got {v}")
        require(self.turbulence_severity in SEVERITIES,
                f"turbulence_severity must be one of {', '.join(SEVERITIES)}, got {self.turbulence_severity!r}")
        for name in ('lag_s_sea_level', 'wind_walk_mps_per_sqrt_s',
                     'static_offset_walk_per_sqrt_s', 'temperature_walk_k_per_sqrt_s'):
            v = getattr(self, name)
            require(v >= 0.0, f"{name} must be >= 0, got {v}")
        require(0.0 < self.fault_false_alarm < 0.01,
                f"fault_false_alarm must be in (0, 0.01), got {self.fault_false_alarm}")
        require(0.0 <= self.start_mach < 1.0, f"start_mach must be in [0, 1), got {self.start_mach}")
        require(0.0 <= self.port_correlation < 1.0, f"port_correlation must be in [0, 1), got {self.port_correlation}")
        require(self.lag_s_sea_level <= 1.0, f"lag_s_sea_level must be <= 1 s, got {self.lag_s_sea_level}")
