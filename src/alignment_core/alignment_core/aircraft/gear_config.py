"""Configuration of the aircraft on its landing gear (scenario section `aircraft.gear`).

The defaults describe a generic 20 t carrier fighter of the F/A-18C/D class on a tricycle gear
(one nose leg with twin wheels, two main legs); docs/landing-gear.md gives the reasoning behind
every number. Off by default: with `enabled: false` the aircraft rides the deck rigidly, as it
always has, and no number changes.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from alignment_core.air_data.turbulence_spec import Severity
from alignment_core.validation import require


@dataclass(frozen=True)
class GearConfig:
    """Airframe, gear geometry, struts, tyres, wind over the deck and hold-back tension.

    Geometry in aircraft axes (FLU) about the centre of gravity (CG): the nose leg is
    `wheelbase_m` ahead of the main legs, which stand `main_track_m` apart; the CG lies
    `nose_load_fraction * wheelbase_m` ahead of the main legs (the lever rule: that fraction
    of the weight rests on the nose leg) and `cg_height_m` above the tyre contact plane. The
    IMU sits at `imu_from_cg_m` from the CG. Nose values are for the leg (both wheels), main
    values for one leg.

    Struts: oleo-pneumatic, linearised about the static point. A polytropic air spring
    F = F0 (V0 / (V0 - A s))^n has the stiffness k = n F0 / L at the static point, L = V0 / A
    the gas column's length there (`*_gas_length_m`); damping: an equivalent viscous
    coefficient c = 2 zeta sqrt(k m_leg), m_leg the sprung mass the leg carries.
    `strut_spring`: 'polytropic' keeps the air spring's full law (it stiffens as it compresses),
    'linear' its tangent at the static point.
    Tyres: vertical, longitudinal and lateral springs (`*_tyre_k*_npm`) with damping
    2 zeta_t sqrt(k m_leg); the vertical tyre carries the unsprung mass (`*_unsprung_kg`).

    Wind over the deck (`wind_over_deck_mps`, from ahead of the aircraft) with Dryden gusts of
    `gust_severity` at `gust_height_m` ('none': no gusts) acts through linear aerodynamic
    derivatives (magnitudes, per radian of gust angle; signs are fixed by physics).

    Hold-back: a forward pull of `holdback_tension_n` at `holdback_height_m` above the deck at
    the nose leg, restrained by the tyres, ramped in over the catapult's hold-back tensioning
    (`aircraft.catapult.holdback_s`, none when 0) and released at the launch.
    """
    enabled: bool = False
    mass_kg: float = 20000.0
    inertia_kgm2: tuple[float, float, float] = (4.0e4, 3.0e5, 3.3e5)
    cg_height_m: float = 1.9
    wheelbase_m: float = 5.42
    main_track_m: float = 3.11
    nose_load_fraction: float = 0.12
    imu_from_cg_m: tuple[float, float, float] = (2.5, 0.0, 0.3)
    strut_spring: Literal['linear', 'polytropic'] = 'polytropic'
    polytropic_index: float = 1.35
    nose_gas_length_m: float = 0.15
    main_gas_length_m: float = 0.20
    strut_damping_ratio: float = 0.3
    nose_unsprung_kg: float = 70.0
    main_unsprung_kg: float = 180.0
    nose_tyre_kz_npm: float = 7.0e5
    nose_tyre_kx_npm: float = 5.0e5
    nose_tyre_ky_npm: float = 4.0e5
    main_tyre_kz_npm: float = 1.5e6
    main_tyre_kx_npm: float = 1.0e6
    main_tyre_ky_npm: float = 8.0e5
    tyre_damping_ratio: float = 0.05
    wind_over_deck_mps: float = 15.0
    gust_severity: Severity = 'moderate'
    gust_height_m: float = 20.0
    wing_area_m2: float = 37.16
    wing_span_m: float = 11.43
    mean_chord_m: float = 3.51
    lift_coefficient: float = 0.3
    drag_coefficient: float = 0.08
    lift_slope_per_rad: float = 3.8
    side_force_slope_per_rad: float = 0.75
    roll_moment_slope_per_rad: float = 0.08
    pitch_moment_slope_per_rad: float = 0.2
    yaw_moment_slope_per_rad: float = 0.1
    air_density_kgpm3: float = 1.225
    holdback_tension_n: float = 1.0e5
    holdback_height_m: float = 0.6

    def validate(self) -> None:
        require(1000.0 <= self.mass_kg <= 100000.0, f"mass_kg must be in [1000, 100000], got {self.mass_kg}")
        require(all(1e2 <= i <= 1e7 for i in self.inertia_kgm2),
                f"inertia_kgm2 must be in [1e2, 1e7] per axis, got {self.inertia_kgm2}")
        require(0.0 <= self.cg_height_m <= 5.0, f"cg_height_m must be in [0, 5], got {self.cg_height_m}")
        require(1.0 <= self.wheelbase_m <= 20.0, f"wheelbase_m must be in [1, 20], got {self.wheelbase_m}")
        require(1.0 <= self.main_track_m <= 15.0, f"main_track_m must be in [1, 15], got {self.main_track_m}")
        require(0.02 <= self.nose_load_fraction <= 0.5,
                f"nose_load_fraction must be in [0.02, 0.5], got {self.nose_load_fraction}")
        require(all(abs(x) <= 20.0 for x in self.imu_from_cg_m),
                f"imu_from_cg_m must be within +-20 m per axis, got {self.imu_from_cg_m}")
        require(1.0 <= self.polytropic_index <= 1.4,
                f"polytropic_index must be in [1, 1.4] (isothermal to adiabatic), got {self.polytropic_index}")
        for k in ('nose_gas_length_m', 'main_gas_length_m'):
            require(0.01 <= getattr(self, k) <= 2.0, f"{k} must be in [0.01, 2], got {getattr(self, k)}")
        for k in ('strut_damping_ratio', 'tyre_damping_ratio'):
            require(0.0 <= getattr(self, k) <= 2.0, f"{k} must be in [0, 2], got {getattr(self, k)}")
        for k in ('nose_unsprung_kg', 'main_unsprung_kg'):
            require(0.0 < getattr(self, k) <= 2000.0, f"{k} must be in (0, 2000], got {getattr(self, k)}")
        for k in ('nose_tyre_kz_npm', 'nose_tyre_kx_npm', 'nose_tyre_ky_npm',
                  'main_tyre_kz_npm', 'main_tyre_kx_npm', 'main_tyre_ky_npm'):
            require(1e3 <= getattr(self, k) <= 1e12, f"{k} must be in [1e3, 1e12] N/m, got {getattr(self, k)}")
        require(0.0 <= self.wind_over_deck_mps <= 40.0,
                f"wind_over_deck_mps must be in [0, 40], got {self.wind_over_deck_mps}")
        require(3.0 <= self.gust_height_m <= 100.0, f"gust_height_m must be in [3, 100], got {self.gust_height_m}")
        for k in ('wing_area_m2', 'wing_span_m', 'mean_chord_m', 'air_density_kgpm3'):
            require(0.0 < getattr(self, k) <= 1000.0, f"{k} must be in (0, 1000], got {getattr(self, k)}")
        for k in ('lift_coefficient', 'drag_coefficient', 'lift_slope_per_rad', 'side_force_slope_per_rad',
                  'roll_moment_slope_per_rad', 'pitch_moment_slope_per_rad', 'yaw_moment_slope_per_rad'):
            require(0.0 <= getattr(self, k) <= 10.0, f"{k} must be in [0, 10], got {getattr(self, k)}")
        require(0.0 <= self.holdback_tension_n <= 1e6,
                f"holdback_tension_n must be in [0, 1e6], got {self.holdback_tension_n}")
        require(0.0 <= self.holdback_height_m <= 3.0,
                f"holdback_height_m must be in [0, 3], got {self.holdback_height_m}")
